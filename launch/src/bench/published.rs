//! Published relative-pose errors of other systems on the benchmark logs, to print beside
//! ours. Only figures we can cite are here; a log without any simply has none.

use serde::Serialize;

/// Where the figures come from.
pub const SOURCES: &str = "scan matching, RBPF (GMapping, 50 particles) and graph mapping: \
Kuemmerle et al. 2009, \"On measuring the accuracy of SLAM algorithms\", Autonomous Robots 27; \
Cartographer: Hess et al. 2016, \"Real-time loop closure in 2D LIDAR SLAM\", ICRA, Table II";

/// A published error: mean and standard deviation over the relations.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Figure {
    pub mean: f64,
    pub std: f64,
}

const fn figure(mean: f64, std: f64) -> Figure {
    Figure { mean, std }
}

/// The published errors on one log: translational in metres, Cartographer's rotational in
/// degrees (the others' rotational errors are not carried here).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Published {
    pub scan_matching_m: Figure,
    pub rbpf_m: Figure,
    pub graph_mapping_m: Figure,
    pub cartographer_m: Figure,
    pub cartographer_deg: Figure,
}

/// Figures by log name (the file stem), as the shared data's carmen/README.md lists them
/// from the two papers.
const TABLE: [(&str, Published); 2] = [
    (
        "mit-csail",
        Published {
            scan_matching_m: figure(0.106, 0.325),
            rbpf_m: figure(0.049, 0.049),
            graph_mapping_m: figure(0.004, 0.009),
            cartographer_m: figure(0.0319, 0.0363),
            cartographer_deg: figure(0.369, 0.365),
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
        },
    ),
];

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
        assert_eq!(published("intel"), None);
    }
}
