//! The relative-pose error (Kuemmerle et al. 2009) of a run's trajectory files against
//! ground-truth relations.
//!
//! map-sink takes this score at the end of a run, rather than slam-launch after it: map-sink
//! writes `metrics.json` and `map.svg` once, atomically and last, and the score belongs in
//! both; scoring afterwards would mean a second writer rewriting both files after the run
//! had already declared itself finished. It also scores a pipeline started by hand (a live
//! sensor has no relations, but a replay started without slam-launch does).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::EvalError;
use crate::relations::{Relation, read_relations};
use crate::run_files::{DEAD_RECKONING_FILE, TRAJECTORY_FILE, TRAJECTORY_ONLINE_FILE};
use crate::score::score;
use crate::summary::ScoreSummary;
use crate::trajectory::Trajectory;

/// A relations file, read and checked.
#[derive(Debug, Clone, PartialEq)]
pub struct RelationsFile {
    pub path: PathBuf,
    pub relations: Vec<Relation>,
}

impl RelationsFile {
    /// Reads and parses `path`; the error names the file and the first bad line.
    pub fn read(path: &Path) -> Result<Self, EvalError> {
        Ok(Self {
            path: path.to_path_buf(),
            relations: read_relations(path)?,
        })
    }
}

/// The relative-pose error of each trajectory file of a run; a file the run did not write
/// has none.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RelativePoseErrors {
    /// The relations scored against.
    pub relations_file: PathBuf,
    /// Stamps match when they are at most this far apart, nanoseconds.
    pub tolerance_ns: u64,
    /// `trajectory.tum`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trajectory: Option<ScoreSummary>,
    /// `trajectory_online.tum`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trajectory_online: Option<ScoreSummary>,
    /// `dead_reckoning.tum`: the front end's own motion estimate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dead_reckoning: Option<ScoreSummary>,
}

/// Scores the TUM file at `path` against `truth`, as [`score_run`] scores each of a run's
/// trajectory files (map-sink: a trajectory written but not yet renamed into place);
/// `None` when there is no file.
pub fn score_tum_file(
    path: &Path,
    truth: &RelationsFile,
    tolerance_ns: u64,
) -> Result<Option<ScoreSummary>, EvalError> {
    if !path.is_file() {
        return Ok(None);
    }
    let trajectory = Trajectory::read_tum(path)?;
    Ok(Some(ScoreSummary::from(&score(
        &trajectory,
        &truth.relations,
        tolerance_ns,
    ))))
}

/// Scores the trajectory files present in `dir` against `truth`, matching stamps within
/// `tolerance_ns`.
pub fn score_run(
    dir: &Path,
    truth: &RelationsFile,
    tolerance_ns: u64,
) -> Result<RelativePoseErrors, EvalError> {
    let score_file = |name: &str| score_tum_file(&dir.join(name), truth, tolerance_ns);
    Ok(RelativePoseErrors {
        relations_file: truth.path.clone(),
        tolerance_ns,
        trajectory: score_file(TRAJECTORY_FILE)?,
        trajectory_online: score_file(TRAJECTORY_ONLINE_FILE)?,
        dead_reckoning: score_file(DEAD_RECKONING_FILE)?,
    })
}
