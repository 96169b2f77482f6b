//! How far map-sink got refining the final path, as `trajectory.tum` and the grid hold it.
//!
//! map-sink writes the run's results twice: first from the filter's path as it came (cheap,
//! so that a run killed during the refinement still leaves a whole map), then again from the
//! refined path. `metrics.json` is written last each time and says which of the two the
//! directory holds.

use serde::{Deserialize, Serialize};

/// The refinement of the final path, as the run's files show it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathRefinement {
    /// Passes asked for (`--refine-passes`).
    pub passes_asked: usize,
    /// Passes whose path `trajectory.tum` and the grid hold; 0 is the filter's path as it
    /// came.
    pub passes_done: usize,
    pub state: RefinementState,
}

/// Where the refinement stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RefinementState {
    /// Written before the refinement: the files hold the filter's path. A run whose
    /// metrics.json still says so was killed while refining.
    Pending,
    /// The refined files were being renamed into place, one after the other: each of
    /// `trajectory.tum`, the map files and the picture is whole, but may still be the
    /// filter's path's. Seen only when the process was killed within those milliseconds.
    Replacing,
    /// Every pass done; the files hold the refined path.
    Complete,
    /// The run was stopped and its time to write ran out: the files hold the path after
    /// `passes_done` passes, the passes after them abandoned.
    CutShort,
    /// The path could not be refined (its grid could not be traced) or the refined files
    /// could not be written (see `incomplete_outputs`): the files hold the filter's path.
    NotDone,
}
