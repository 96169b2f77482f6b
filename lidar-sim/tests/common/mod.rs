//! The simulator as a process under test, with a subscriber in its domain.

use std::process::{Child, Command, Stdio};

use iceoryx2::prelude::{Node, ipc};
use ipc_types::prelude::*;

/// A running lidar-sim, the domain of its own it publishes in, and a subscriber's node there.
pub struct Sim {
    pub child: Child,
    pub node: Node<ipc::Service>,
    pub domain: Domain,
}

impl Sim {
    /// Starts lidar-sim with `args` in the domain `sim-{tag}-{pid}`, for one subscriber (its
    /// stdout dropped, its stderr to `stderr`), and returns once its scan topic is up.
    pub fn start(tag: &str, args: &[&str], stderr: Stdio) -> Self {
        let domain = Domain::new(&format!("sim-{tag}-{}", std::process::id())).unwrap();
        let child = Command::new(env!("CARGO_BIN_EXE_lidar-sim"))
            .args(args)
            .args(["--domain", domain.name(), "--subscribers", "1"])
            .stdout(Stdio::null())
            .stderr(stderr)
            .spawn()
            .expect("start lidar-sim");
        let node = domain.node("test-subscriber").unwrap();
        wait_for_topic(&node, topic::SCAN).unwrap();
        Self {
            child,
            node,
            domain,
        }
    }
}
