//! Issue 14, row 9: two users of one machine. iceoryx2 keeps its node and service files
//! under one root directory for everybody by default, made by the first user with mode
//! 0750, so once one user had run the pipeline another could not ("cannot create node ...
//! InternalError"), and the global management file it left in /dev/shm was writable by
//! everyone. Each user now has a root of their own and a prefix with their uid in
//! /dev/shm, and every file of a run is its user's alone.
//!
//! The second user is `nobody` (uid 65534), through `setpriv`; that needs root. Where the
//! test does not run as root, or setpriv cannot switch users, or `nobody` cannot reach the
//! binaries, it says so and passes without running.

use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use tests::*;

/// `nobody`.
const OTHER_UID: u32 = 65534;
/// Generous for a loaded 2-core machine; a short office run takes seconds.
const LIMIT: Duration = Duration::from_secs(300);

/// `setpriv` arguments that run a command as the other user, or why that is not possible.
fn other_user() -> Result<Vec<String>, String> {
    if !nix::unistd::geteuid().is_root() {
        return Err("not root: no second user to run as".into());
    }
    let setpriv: Vec<String> = vec![
        "setpriv".into(),
        format!("--reuid={OTHER_UID}"),
        format!("--regid={OTHER_UID}"),
        "--clear-groups".into(),
    ];
    let launcher = bin("slam-launch");
    let probe = Command::new(&setpriv[0])
        .args(&setpriv[1..])
        .arg(&launcher)
        .arg("--version")
        .output();
    match probe {
        Ok(output) if output.status.success() => Ok(setpriv),
        Ok(output) => Err(format!(
            "uid {OTHER_UID} cannot run {}: {}",
            launcher.display(),
            String::from_utf8_lossy(&output.stderr).trim()
        )),
        Err(e) => Err(format!("no setpriv here: {e}")),
    }
}

/// A scratch directory the other user may write.
fn scratch_for_other(name: &str) -> PathBuf {
    let dir = scratch(name);
    std::os::unix::fs::chown(&dir, Some(OTHER_UID), Some(OTHER_UID)).expect("chown scratch");
    dir
}

/// slam-launch on a short office run, as the other user when `as_other` holds it.
fn launcher(as_other: Option<&[String]>, domain: &str, out: &Path, frames: &str) -> Command {
    let mut command = match as_other {
        Some(setpriv) => {
            let mut command = Command::new(&setpriv[0]);
            command.args(&setpriv[1..]).arg(bin("slam-launch"));
            command
        }
        None => Command::new(bin("slam-launch")),
    };
    command
        .args(["--quiet", "--domain", domain, "--out"])
        .arg(out)
        .args(["--world", "office", "--frames", frames]);
    command
}

fn run(mut command: Command) -> Output {
    output_within(&mut command, LIMIT).expect("slam-launch ended in time")
}

/// Files of `uid` under `dir` (not following links) that anyone but their owner may write,
/// and files of another owner.
fn open_to_others(dir: &Path, uid: u32) -> Vec<String> {
    let mut found = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return found;
    };
    for entry in entries.filter_map(Result::ok) {
        let Ok(metadata) = std::fs::symlink_metadata(entry.path()) else {
            continue;
        };
        if metadata.uid() != uid || metadata.mode() & 0o022 != 0 {
            found.push(format!(
                "{} (uid {}, mode {:o})",
                entry.path().display(),
                metadata.uid(),
                metadata.mode() & 0o7777
            ));
        }
        if metadata.is_dir() {
            found.extend(open_to_others(&entry.path(), uid));
        }
    }
    found
}

/// The /dev/shm files of `domain` as `uid` names them, with their owners and modes.
fn shm_files_of(uid: u32, domain: &str) -> Vec<(String, u32, u32)> {
    let prefix = format!("slam_u{uid}_{domain}_");
    std::fs::read_dir("/dev/shm")
        .expect("/dev/shm")
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
        .filter_map(|e| {
            let metadata = std::fs::symlink_metadata(e.path()).ok()?;
            Some((
                e.file_name().to_string_lossy().into_owned(),
                metadata.uid(),
                metadata.mode() & 0o7777,
            ))
        })
        .collect()
}

#[test]
fn a_second_user_runs_after_the_first_and_beside_it() {
    let setpriv = match other_user() {
        Ok(setpriv) => setpriv,
        Err(why) => {
            eprintln!("skipped: {why}");
            return;
        }
    };

    // One after the other: root first, so iceoryx2's files of a first user are there.
    let first = scratch("users-first");
    let output = run(launcher(None, &domain("users-first"), &first, "100"));
    assert_success(&output);
    let second = scratch_for_other("users-second");
    let output = run(launcher(
        Some(&setpriv),
        &domain("users-second"),
        &second,
        "100",
    ));
    assert_success(&output);
    assert!(second.join("metrics.json").is_file());

    // At once, under one domain name: each user's run has files of its own.
    let name = domain("users-both");
    let mine = scratch("users-both-root");
    let theirs = scratch_for_other("users-both-other");
    let other = std::thread::spawn({
        let (setpriv, name, theirs) = (setpriv.clone(), name.clone(), theirs.clone());
        move || run(launcher(Some(&setpriv), &name, &theirs, "0"))
    });
    // While the other user's run streams poses (every stage has made its node by then),
    // its files are its own and open to nobody else.
    let online = theirs.join("trajectory_online.tum");
    let deadline = Instant::now() + LIMIT;
    while lines_in(&online) == 0 && !other.is_finished() {
        assert!(
            Instant::now() < deadline,
            "the other user's run never streamed"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let files = shm_files_of(OTHER_UID, &name);
    let root_dir = PathBuf::from(format!("/tmp/slam-iceoryx2-{OTHER_UID}"));
    let root_meta = std::fs::symlink_metadata(&root_dir).expect("the other user's iceoryx2 root");
    let in_root = open_to_others(&root_dir, OTHER_UID);
    let output = run(launcher(None, &name, &mine, "400"));
    assert_success(&output);
    let output = other.join().expect("the other user's run");
    assert_success(&output);

    assert!(
        !files.is_empty(),
        "no file of the other user's run in /dev/shm"
    );
    for (file, uid, mode) in &files {
        assert_eq!(*uid, OTHER_UID, "{file}");
        assert_eq!(mode & 0o077, 0, "{file} has mode {mode:o}");
    }
    assert_eq!(root_meta.uid(), OTHER_UID);
    assert_eq!(root_meta.mode() & 0o077, 0, "mode {:o}", root_meta.mode());
    assert!(in_root.is_empty(), "{in_root:#?}");
    // Both finished whole, and neither left shared memory behind.
    for out in [&mine, &theirs] {
        assert!(metrics(out).frames_processed > 0);
    }
    assert!(shm_files_of(0, &name).is_empty());
    assert!(shm_files_of(OTHER_UID, &name).is_empty());
}
