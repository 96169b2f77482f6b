//! Console lines that never panic.
//!
//! slam-launch reads every stage's stdout and stderr through pipes, and when it is killed
//! they break while the stage is still writing its run's results (it gets SIGTERM as the
//! launcher dies). `println!` would panic there and lose them; a line nobody can read is no
//! reason to stop, so these drop it.

use std::io::Write;

/// A line on stdout (what slam-launch shows or parses).
pub fn say(line: &str) {
    let _ = writeln!(std::io::stdout(), "{line}");
}

/// A line on stderr (the stage's log).
pub fn say_err(line: &str) {
    let _ = writeln!(std::io::stderr(), "{line}");
}
