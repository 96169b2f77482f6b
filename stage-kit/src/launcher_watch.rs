//! A process started by a launcher dies with it.
//!
//! A launcher (slam-launch for its stages, slam-bench for slam-launch) names itself in the
//! child's environment ([`started_by_this_process`]); the child, first thing in its `main`
//! ([`stop_with_launcher`]), asks the kernel to send it SIGTERM when that launcher dies
//! (`PR_SET_PDEATHSIG`), and refuses to run if the launcher has already gone. SIGTERM, not
//! SIGKILL: every process takes it as Ctrl-C ([`crate::shutdown`]), so map-sink still writes
//! its results and the stages remove their iceoryx2 nodes on the way out. The signal is
//! tied to the launcher's thread that started the child, not its process: a launcher starts
//! children from the thread that lives as long as they should. Linux only; elsewhere a child
//! outlives a killed launcher and still stops on Ctrl-C.

use std::process::Command;

/// The variable that carries the launcher's pid.
pub const LAUNCHER_PID_ENV: &str = "SLAM_LAUNCHER_PID";

/// Why a launched process cannot tie its life to its launcher's.
#[derive(Debug, thiserror::Error)]
pub enum LauncherWatchError {
    #[error("{LAUNCHER_PID_ENV} is {0:?}, not a process id")]
    NotAPid(String),
    #[error("launcher {launcher} has gone (parent is now {parent}): not starting")]
    LauncherGone { launcher: i32, parent: i32 },
    #[cfg(target_os = "linux")]
    #[error("cannot ask for a signal on the launcher's death")]
    DeathSignal(#[source] nix::Error),
}

/// Marks `command` as started by this process: the child dies with it (see the module).
pub fn started_by_this_process(command: &mut Command) {
    command.env(LAUNCHER_PID_ENV, std::process::id().to_string());
}

/// Ties this process's life to the launcher named in its environment, if any: SIGTERM when
/// the launcher dies, an error if it has died already. Without the variable (started by
/// hand), nothing.
pub fn stop_with_launcher() -> Result<(), LauncherWatchError> {
    match std::env::var(LAUNCHER_PID_ENV) {
        Ok(text) => watch(&text),
        Err(_) => Ok(()),
    }
}

#[cfg(target_os = "linux")]
fn watch(text: &str) -> Result<(), LauncherWatchError> {
    use nix::sys::signal::Signal;
    let launcher: i32 = text
        .trim()
        .parse()
        .map_err(|_| LauncherWatchError::NotAPid(text.to_owned()))?;
    nix::sys::prctl::set_pdeathsig(Signal::SIGTERM).map_err(LauncherWatchError::DeathSignal)?;
    // The launcher may have died before the death signal was asked for: the process then
    // has another parent already, and no signal will come.
    let parent = nix::unistd::getppid().as_raw();
    if parent != launcher {
        return Err(LauncherWatchError::LauncherGone { launcher, parent });
    }
    Ok(())
}

#[cfg(not(target_os = "linux"))]
fn watch(text: &str) -> Result<(), LauncherWatchError> {
    text.trim()
        .parse::<i32>()
        .map(|_| ())
        .map_err(|_| LauncherWatchError::NotAPid(text.to_owned()))
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    #[test]
    fn a_child_of_another_process_is_told_its_launcher_has_gone() {
        // This test process's parent is cargo (or a shell), not pid 1.
        let err = watch("1").unwrap_err();
        assert!(
            matches!(err, LauncherWatchError::LauncherGone { launcher: 1, .. }),
            "{err}"
        );
        assert!(matches!(watch("x"), Err(LauncherWatchError::NotAPid(_))));
        let parent = nix::unistd::getppid().as_raw();
        watch(&parent.to_string()).expect("the parent is the launcher");
        // Undo: nothing else in this test binary wants the signal.
        nix::sys::prctl::set_pdeathsig(None).expect("prctl");
    }
}
