//! The `main` of every process: the error handled once, at the top.

use std::process::ExitCode;

use crate::console::say_err;

/// Runs `run`; on an error prints `name: error` with its whole source chain on stderr and
/// exits with a failing status.
pub fn main(name: &str, run: impl FnOnce() -> anyhow::Result<()>) -> ExitCode {
    match run() {
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
        assert_eq!(main("t", || Ok(())), ExitCode::SUCCESS);
        assert_eq!(main("t", || anyhow::bail!("no")), ExitCode::FAILURE);
    }
}
