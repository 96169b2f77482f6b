//! Where a replayed log's ground-truth relations are, when nobody says.

use std::path::{Path, PathBuf};

/// The extension of a relations file (Kuemmerle et al. 2009).
pub const RELATIONS_EXTENSION: &str = "relations";

/// The relations file beside a log, if there is one: for `DIR/NAME.clf`,
/// `DIR/NAME.relations`. The benchmark logs are published this way, so a replay of one is
/// scored without being asked.
pub fn relations_beside(log: &Path) -> Option<PathBuf> {
    let candidate = log.with_extension(RELATIONS_EXTENSION);
    (candidate != log && candidate.is_file()).then_some(candidate)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("launch-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn the_relations_beside_a_log_are_found() {
        let dir = scratch("relations-beside");
        for name in [
            "mit-csail.clf",
            "mit-csail.relations",
            "aces.clf",
            "a.b.clf",
        ] {
            std::fs::write(dir.join(name), "").unwrap();
        }
        std::fs::write(dir.join("a.b.relations"), "").unwrap();
        assert_eq!(
            relations_beside(&dir.join("mit-csail.clf")),
            Some(dir.join("mit-csail.relations"))
        );
        // Only the last extension is the log's.
        assert_eq!(
            relations_beside(&dir.join("a.b.clf")),
            Some(dir.join("a.b.relations"))
        );
        assert_eq!(relations_beside(&dir.join("aces.clf")), None, "none there");
        // A relations file is not its own log, and a directory is not a relations file.
        assert_eq!(relations_beside(&dir.join("mit-csail.relations")), None);
        std::fs::create_dir_all(dir.join("dir.relations")).unwrap();
        assert_eq!(relations_beside(&dir.join("dir.clf")), None);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
