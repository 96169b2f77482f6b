//! The entry point of every process: arguments parsed, Ctrl-C installed and the error handled
//! once, at the top.

use std::process::ExitCode;

use anyhow::Context;

use crate::console::say_err;

/// The `main` of a pipeline stage: parses `A` from the command line (clap prints usage and
/// exits on a bad argument), ties the process to its launcher's life
/// ([`crate::launcher_watch`]), installs the Ctrl-C/SIGTERM flag the stage's loops poll
/// ([`crate::shutdown`]), runs `run`, and on an error prints `name: error` with its whole
/// source chain on stderr and exits with a failing status.
pub fn run_stage<A: clap::Parser>(
    name: &str,
    run: impl FnOnce(A) -> anyhow::Result<()>,
) -> ExitCode {
    run_tool(name, |args| {
        crate::shutdown::install().context("cannot install the Ctrl-C handler")?;
        run(args)
    })
}

/// The `main` of a command-line tool that polls no stop flag: as [`run_stage`] without the
/// Ctrl-C handler, so Ctrl-C ends it at once. (A stage is a tool that installs the handler
/// first.)
pub fn run_tool<A: clap::Parser>(
    name: &str,
    run: impl FnOnce(A) -> anyhow::Result<()>,
) -> ExitCode {
    let args = A::parse();
    report(name, || {
        crate::launcher_watch::stop_with_launcher()?;
        run(args)
    })
}

/// Runs `run`; an error becomes one `name: error` line (`{:#}`) and a failing status. The
/// peak memory is told last either way, for slam-launch ([`ipc_types::peak_memory`]).
fn report(name: &str, run: impl FnOnce() -> anyhow::Result<()>) -> ExitCode {
    let result = run();
    ipc_types::peak_memory::report();
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            say_err(&format!("{name}: {e:#}"));
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_error_is_a_failing_status() {
        assert_eq!(report("t", || Ok(())), ExitCode::SUCCESS);
        assert_eq!(report("t", || anyhow::bail!("no")), ExitCode::FAILURE);
    }
}
