//! The robust pose graph of global SLAM: nodes are robot poses (`world_from_robot`), the
//! front end's steps join each to the next, and loop closures join poses far apart.
//!
//! The steps (and priors) are trusted and fitted by plain least squares. The closures are
//! not: each is weighted by dynamic covariance scaling (DCS, the closed form of switchable
//! constraints), so that a wrong one costs at most a bounded amount instead of bending the
//! path, and each is reported accepted or rejected. DCS alone cannot close a loop that came
//! back metres off (every closure is as far out as a wrong one, and all are switched off),
//! so its threshold is annealed as graduated non-convexity does: it starts above the error
//! of every closure added since the last optimization, where the problem is plain least
//! squares, and falls by half or more each Gauss-Newton step down to its setting, where
//! Newton steps with a line search settle the answer. The annealing runs first with every
//! closure's information scaled to the same volume, so that a wrong closure that claims to
//! be very sure has no more say in which closures survive than any other, then with the
//! true information.
//!
//! Each step is solved exactly by a sparse Cholesky factorization (module `sparse`): the
//! chain is eliminated at linear cost and only the closures' ends fill in.

mod edge;
mod solve;
mod sparse;

use nalgebra::Matrix3;
use slam_geom::Pose2;
use thiserror::Error;

use solve::Structure;

/// A closure whose final DCS scale is at least this is reported accepted (its squared
/// error is below three times the threshold).
pub const ACCEPTED_SCALE: f64 = 0.5;

/// Why a graph refused an input or could not be solved.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PoseGraphError {
    #[error("{what} is not finite")]
    NotFinite { what: &'static str },
    #[error("{what}: the information matrix is not symmetric positive definite")]
    NotPositiveDefinite { what: &'static str },
    #[error("node {index} is not in the graph of {nodes} nodes")]
    NoSuchNode { index: usize, nodes: usize },
    #[error("a closure joins node {0} to itself")]
    SelfClosure(usize),
    #[error("setting {what} is out of range")]
    BadSetting { what: &'static str },
    #[error("the normal equations are not positive definite")]
    Singular,
    #[error("the solve diverged to non-finite poses")]
    Diverged,
}

/// How the graph is solved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseGraphSettings {
    /// DCS's threshold on a closure's squared Mahalanobis error (3 degrees of freedom,
    /// positive): below it a closure counts fully, beyond it less and less; above three
    /// times it the closure is rejected.
    pub robust_threshold: f64,
    /// Steps at most (at least 1), in each of the two passes of an optimization.
    pub max_iterations: usize,
    /// A step that would move no pose by more than this (metres, radians; positive) is
    /// not taken: the poses have converged.
    pub tolerance: f64,
}

impl Default for PoseGraphSettings {
    fn default() -> Self {
        Self {
            // A right closure's squared error is below 7.8 with probability 0.95 and
            // below 24 (scale 0.5) with probability 0.99997.
            robust_threshold: 8.0,
            max_iterations: 100,
            tolerance: 1e-6,
        }
    }
}

/// A closure, as [`PoseGraph::add_closure`] returned it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ClosureId(usize);

impl ClosureId {
    /// The closure's index, in the order they were added.
    pub fn index(self) -> usize {
        self.0
    }
}

/// What an optimization did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveReport {
    /// Gauss-Newton steps, both passes.
    pub iterations: usize,
    /// Whether both passes ended by converging rather than by the iteration limit.
    pub converged: bool,
    /// The robust cost (steps and priors squared, closures through DCS) before and after.
    pub initial_cost: f64,
    pub final_cost: f64,
    pub accepted_closures: usize,
    pub rejected_closures: usize,
}

/// A relative pose with its information (inverse covariance) in `x, y, yaw` of the frame
/// it is measured from.
#[derive(Debug, Clone, Copy)]
struct Measurement {
    seen: Pose2,
    information: Matrix3<f64>,
}

#[derive(Debug, Clone, Copy)]
struct Closure {
    from: usize,
    to: usize,
    measurement: Measurement,
    /// The DCS scale at the end of the last optimization; `None` before one.
    scale: Option<f64>,
}

/// A pose a node should have, information in the world's `x, y, yaw`.
#[derive(Debug, Clone, Copy)]
struct Prior {
    node: usize,
    pose: Pose2,
    information: Matrix3<f64>,
}

/// A robust 2D pose graph; see the module's documentation.
#[derive(Debug, Clone)]
pub struct PoseGraph {
    poses: Vec<Pose2>,
    /// `steps[i]` joins node `i` to node `i + 1`.
    steps: Vec<Measurement>,
    closures: Vec<Closure>,
    priors: Vec<Prior>,
    settings: PoseGraphSettings,
    structure: Option<Structure>,
}

impl PoseGraph {
    /// A graph of one node at `first`, solved with the default settings.
    pub fn new(first: Pose2) -> Result<Self, PoseGraphError> {
        Self::with_settings(first, PoseGraphSettings::default())
    }

    /// A graph of one node at `first`.
    pub fn with_settings(
        first: Pose2,
        settings: PoseGraphSettings,
    ) -> Result<Self, PoseGraphError> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(settings.robust_threshold) {
            return Err(PoseGraphError::BadSetting {
                what: "robust_threshold",
            });
        }
        if !positive(settings.tolerance) {
            return Err(PoseGraphError::BadSetting { what: "tolerance" });
        }
        if settings.max_iterations == 0 {
            return Err(PoseGraphError::BadSetting {
                what: "max_iterations",
            });
        }
        Ok(Self {
            poses: vec![checked_pose(first, "the first pose")?],
            steps: Vec::new(),
            closures: Vec::new(),
            priors: Vec::new(),
            settings,
            structure: None,
        })
    }

    /// Appends a node, `step` after the last one (the pose of the new node in the last
    /// one's frame), and returns its index; its pose starts as the last pose composed with
    /// `step`.
    pub fn add_node(
        &mut self,
        step: Pose2,
        information: Matrix3<f64>,
    ) -> Result<usize, PoseGraphError> {
        let measurement = Measurement {
            seen: checked_pose(step, "a step")?,
            information: checked_information(information, "a step")?,
        };
        let last = self.poses[self.poses.len() - 1];
        self.poses.push(last.compose(&measurement.seen));
        self.steps.push(measurement);
        Ok(self.poses.len() - 1)
    }

    /// Adds a loop closure: node `to` seen at `seen` in the frame of node `from`. It is
    /// weighed by the robust kernel, and may end up rejected.
    pub fn add_closure(
        &mut self,
        from: usize,
        to: usize,
        seen: Pose2,
        information: Matrix3<f64>,
    ) -> Result<ClosureId, PoseGraphError> {
        self.check_node(from)?;
        self.check_node(to)?;
        if from == to {
            return Err(PoseGraphError::SelfClosure(from));
        }
        let measurement = Measurement {
            seen: checked_pose(seen, "a closure")?,
            information: checked_information(information, "a closure")?,
        };
        self.closures.push(Closure {
            from,
            to,
            measurement,
            scale: None,
        });
        Ok(ClosureId(self.closures.len() - 1))
    }

    /// Adds a trusted prior on a node's pose, information in the world's `x, y, yaw`. With
    /// a prior the graph is held by its priors; without, node 0 stays where it is.
    pub fn add_prior(
        &mut self,
        node: usize,
        pose: Pose2,
        information: Matrix3<f64>,
    ) -> Result<(), PoseGraphError> {
        self.check_node(node)?;
        self.priors.push(Prior {
            node,
            pose: checked_pose(pose, "a prior")?,
            information: checked_information(information, "a prior")?,
        });
        Ok(())
    }

    /// The pose of node `i`. Panics if there is no such node, as indexing does.
    pub fn pose(&self, i: usize) -> Pose2 {
        self.poses[i]
    }

    /// Every node's pose, in order.
    pub fn poses(&self) -> &[Pose2] {
        &self.poses
    }

    /// The number of nodes (at least one).
    pub fn node_count(&self) -> usize {
        self.poses.len()
    }

    /// The number of closures added.
    pub fn closure_count(&self) -> usize {
        self.closures.len()
    }

    /// The closure's DCS scale after the last optimization, in `(0, 1]` (the switch of a
    /// switchable constraint: 1 taken fully, near 0 switched off); `None` for a closure
    /// not yet optimized or not of this graph.
    pub fn closure_scale(&self, id: ClosureId) -> Option<f64> {
        self.closures.get(id.0).and_then(|c| c.scale)
    }

    /// Whether the last optimization took the closure ([`ACCEPTED_SCALE`] or more).
    pub fn closure_accepted(&self, id: ClosureId) -> bool {
        self.closure_scale(id).is_some_and(|s| s >= ACCEPTED_SCALE)
    }

    /// Solves the graph, starting from the poses it has. On error the poses are left as
    /// they were.
    pub fn optimize(&mut self) -> Result<SolveReport, PoseGraphError> {
        let before = self.poses.clone();
        let result = self.optimize_from_here();
        if result.is_err() {
            self.poses = before;
        }
        result
    }

    fn check_node(&self, index: usize) -> Result<(), PoseGraphError> {
        if index < self.poses.len() {
            Ok(())
        } else {
            Err(PoseGraphError::NoSuchNode {
                index,
                nodes: self.poses.len(),
            })
        }
    }
}

/// `pose` with its yaw wrapped, or an error if it is not finite.
fn checked_pose(pose: Pose2, what: &'static str) -> Result<Pose2, PoseGraphError> {
    if pose.x.is_finite() && pose.y.is_finite() && pose.yaw.is_finite() {
        Ok(Pose2::new(pose.x, pose.y, pose.yaw))
    } else {
        Err(PoseGraphError::NotFinite { what })
    }
}

/// `information` made exactly symmetric, or an error if it is not finite, not symmetric
/// (beyond rounding) or not positive definite.
fn checked_information(
    information: Matrix3<f64>,
    what: &'static str,
) -> Result<Matrix3<f64>, PoseGraphError> {
    if information.iter().any(|v| !v.is_finite()) {
        return Err(PoseGraphError::NotFinite { what });
    }
    let asymmetry = (information - information.transpose()).amax();
    let symmetric = (information + information.transpose()) * 0.5;
    let positive = symmetric.determinant() > 0.0 && symmetric.cholesky().is_some();
    if asymmetry > 1e-9 * information.amax() || !positive {
        return Err(PoseGraphError::NotPositiveDefinite { what });
    }
    Ok(symmetric)
}
