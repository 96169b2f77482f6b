//! Ctrl-C and SIGTERM as a latched flag every loop can poll.
//!
//! iceoryx2's own handler resets its flag when read, so a WaitSet and a process loop reading
//! it would race for one signal. Instead every process installs this handler once and creates
//! its nodes and WaitSets with signal handling disabled.
//!
//! The flag lives here, under the transport, because the transport's blocking waits
//! (discovery, back-pressure, `wait_any`) end on it. A stage installs and reads it through
//! stage-kit (`stage_kit::run_stage`, `stage_kit::shutdown`).

use std::sync::Arc;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();

/// Registers the SIGINT and SIGTERM handlers (idempotent).
pub fn install() -> std::io::Result<()> {
    if FLAG.get().is_some() {
        return Ok(());
    }
    let flag = Arc::new(AtomicBool::new(false));
    signal_hook::flag::register(signal_hook::consts::SIGINT, Arc::clone(&flag))?;
    signal_hook::flag::register(signal_hook::consts::SIGTERM, Arc::clone(&flag))?;
    // A second caller racing us registered its own flag; either one is set by the signal.
    let _ = FLAG.set(flag);
    Ok(())
}

/// True once SIGINT or SIGTERM has arrived (after [`install`]) or [`request`] was called.
pub fn requested() -> bool {
    FLAG.get().is_some_and(|flag| flag.load(Ordering::Relaxed))
}

/// Asks every loop of this process to stop, as a signal would.
pub fn request() {
    let flag = FLAG.get_or_init(|| Arc::new(AtomicBool::new(false)));
    flag.store(true, Ordering::Relaxed);
}
