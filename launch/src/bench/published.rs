//! Published relative-pose errors of other systems on the benchmark logs, to print beside
//! ours. Only figures we can cite are here; a log without any simply has none.

use serde::{Deserialize, Serialize};

/// Where the figures come from.
pub const SOURCES: &str = "scan matching, RBPF (GMapping, 50 particles) and graph mapping: \
Kuemmerle et al. 2009, \"On measuring the accuracy of SLAM algorithms\", Autonomous Robots 27; \
Cartographer: Hess et al. 2016, \"Real-time loop closure in 2D LIDAR SLAM\", ICRA, Tables II \
(errors) and V (wall time on one desktop)";

/// A published error: mean and standard deviation over the relations.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Figure {
    pub mean: f64,
    pub std: f64,
}

const fn figure(mean: f64, std: f64) -> Figure {
    Figure { mean, std }
}

/// The published errors on one log: translational in metres, Cartographer's rotational in
/// degrees (the others' rotational errors are not carried here), and Cartographer's wall
/// time for the whole log.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Published {
    pub scan_matching_m: Figure,
    pub rbpf_m: Figure,
    pub graph_mapping_m: Figure,
    pub cartographer_m: Figure,
    pub cartographer_deg: Figure,
    #[serde(default)]
    pub cartographer_wall_s: Option<f64>,
}

/// Figures by log name (the file stem), as the shared data's carmen/README.md lists them
/// from the two papers.
const TABLE: [(&str, Published); 4] = [
    (
        "mit-csail",
        Published {
            scan_matching_m: figure(0.106, 0.325),
            rbpf_m: figure(0.049, 0.049),
            graph_mapping_m: figure(0.004, 0.009),
            cartographer_m: figure(0.0319, 0.0363),
            cartographer_deg: figure(0.369, 0.365),
            cartographer_wall_s: Some(35.0),
        },
    ),
    (
        "aces",
        Published {
            scan_matching_m: figure(0.173, 0.614),
            rbpf_m: figure(0.060, 0.049),
            graph_mapping_m: figure(0.044, 0.044),
            cartographer_m: figure(0.0375, 0.0426),
            cartographer_deg: figure(0.373, 0.469),
            cartographer_wall_s: Some(41.0),
        },
    ),
    (
        "intel",
        Published {
            scan_matching_m: figure(0.220, 0.296),
            rbpf_m: figure(0.070, 0.083),
            graph_mapping_m: figure(0.031, 0.026),
            cartographer_m: figure(0.0229, 0.0239),
            cartographer_deg: figure(0.453, 1.335),
            cartographer_wall_s: Some(179.0),
        },
    ),
    (
        "fr079",
        Published {
            scan_matching_m: figure(0.258, 0.427),
            rbpf_m: figure(0.061, 0.044),
            graph_mapping_m: figure(0.056, 0.042),
            cartographer_m: figure(0.0452, 0.0354),
            cartographer_deg: figure(0.538, 0.718),
            cartographer_wall_s: Some(62.0),
        },
    ),
];

/// The names of the logs with published figures.
pub fn logs() -> impl Iterator<Item = &'static str> {
    TABLE.iter().map(|(name, _)| *name)
}

/// The published figures for the log named `log` (its file stem), if any.
pub fn published(log: &str) -> Option<Published> {
    TABLE
        .iter()
        .find(|(name, _)| *name == log)
        .map(|(_, figures)| *figures)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_logs_have_figures_and_others_none() {
        let mit = published("mit-csail").unwrap();
        assert_eq!(mit.graph_mapping_m, figure(0.004, 0.009));
        assert_eq!(published("aces").unwrap().cartographer_m.mean, 0.0375);
        assert_eq!(published("intel").unwrap().rbpf_m, figure(0.070, 0.083));
        assert_eq!(published("fr079").unwrap().cartographer_wall_s, Some(62.0));
        assert_eq!(published("seed-hall"), None);
        assert_eq!(logs().count(), 4);
    }
}
