//! A process's peak resident memory, told to slam-launch on stdout as it ends.
//!
//! The launcher reads each stage's peak (`VmHWM`) from /proc while the stage runs, but
//! only every so often, and /proc tells nothing once the process has gone: a peak reached
//! in a stage's last moments (map-sink draws its picture just before it exits) would be
//! missed, and the same run would read tens of megabytes apart. So, as it ends, a stage
//! started with [`crate::progress::ENV`] set also prints its own peak, the channel it
//! already reports on (`ready`, [`crate::progress`], [`crate::losses`]):
//!
//! ```text
//! peak_resident_kib 41234
//! ```

use std::io::Write;

/// The first word of the line.
pub const PREFIX: &str = "peak_resident_kib";

/// The peak resident memory so far (`VmHWM`) of process `pid`, or of this process for
/// `None`, KiB; `None` where /proc does not tell (another system, a process that ended).
pub fn peak_resident_kib(pid: Option<u32>) -> Option<u64> {
    let path = match pid {
        Some(pid) => format!("/proc/{pid}/status"),
        None => "/proc/self/status".to_owned(),
    };
    parse_vm_hwm(&std::fs::read_to_string(path).ok()?)
}

/// Prints this process's peak on stdout when the launcher asked for reports (and /proc
/// tells it). A launcher that has gone is no reason to fail: the error is ignored.
pub fn report() {
    if std::env::var_os(crate::progress::ENV).is_none() {
        return;
    }
    let Some(kib) = peak_resident_kib(None) else {
        return;
    };
    let mut stdout = std::io::stdout().lock();
    let _ = writeln!(stdout, "{PREFIX} {kib}");
    let _ = stdout.flush();
}

/// The KiB of a line without its first word.
pub fn parse(rest: &str) -> Option<u64> {
    rest.trim().parse().ok()
}

/// `VmHWM` of a /proc status file, KiB.
fn parse_vm_hwm(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_high_water_mark_is_read_from_the_status_file() {
        let status = "Name:\tmap-sink\nVmPeak:\t  200000 kB\nVmHWM:\t   45120 kB\nVmRSS:\t 1 kB\n";
        assert_eq!(parse_vm_hwm(status), Some(45_120));
        assert_eq!(parse_vm_hwm("Name:\tx\n"), None);
        // This process has one.
        assert!(peak_resident_kib(None).is_some_and(|kib| kib > 0));
        assert_eq!(parse(" 45120"), Some(45_120));
        assert_eq!(parse(" lots"), None);
    }
}
