//! Closures that would move the path are confirmed before they do. A verified closure that
//! agrees with the graph's estimate enters it at once; one that says the robot is somewhere
//! else (a jump: the drift of a loop, or a corridor matched one door along) waits until a
//! closure from another stretch of the path says the same (pairwise consistency, as in
//! Olson's and Mangelson's PCM): two scans taken metres apart that both fit a wrong place
//! with the same error are far less likely than one. A held closure no other confirms
//! within [`HOLD_M`] of path expires.

use nalgebra::Matrix3;
use slam_geom::Pose2;

use crate::pose_graph::PoseGraph;

/// A closure of a node to a submap, as the graph gets it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tie {
    pub node: usize,
    /// The submap's index and its anchor node.
    pub submap: usize,
    pub anchor: usize,
    /// The node's pose in the anchor's frame, and its information.
    pub seen: Pose2,
    pub information: Matrix3<f64>,
    /// Path driven when the node was made, metres.
    pub at_m: f64,
}

/// Closures held for confirmation: the path between two that confirm each other is at
/// least this long, metres, so that they come from different scans of the place...
const APART_M: f64 = 1.0;
/// ...and a held closure waits this far along the path at most, metres.
pub const HOLD_M: f64 = 30.0;

/// The held closures.
#[derive(Debug, Default)]
pub struct Confirmations {
    held: Vec<Tie>,
}

impl Confirmations {
    /// Offers a jump `tie`; returns the closures to add now (it and those it confirms), or
    /// nothing while it waits. `tolerance(d)` is how far apart, in metres and radians, two
    /// closures `d` metres of path apart may put the robot and still agree.
    pub fn offer(
        &mut self,
        tie: Tie,
        graph: &PoseGraph,
        tolerance: impl Fn(f64) -> (f64, f64),
    ) -> Vec<Tie> {
        self.held.retain(|h| tie.at_m - h.at_m <= HOLD_M);
        let (agree, rest): (Vec<Tie>, Vec<Tie>) = self.held.iter().partition(|held| {
            let apart = tie.at_m - held.at_m;
            let (metres, radians) = tolerance(apart);
            apart >= APART_M && {
                let difference = predicted(held, tie.node, graph).between(&implied(&tie, graph));
                difference.translation_norm() <= metres && difference.yaw.abs() <= radians
            }
        });
        if agree.is_empty() {
            self.held.push(tie);
            return Vec::new();
        }
        self.held = rest;
        let mut confirmed = agree;
        confirmed.push(tie);
        confirmed
    }

    /// Closures waiting.
    pub fn len(&self) -> usize {
        self.held.len()
    }

    pub fn is_empty(&self) -> bool {
        self.held.is_empty()
    }
}

/// Where `tie` puts its node in the world, by the graph's pose of its anchor.
fn implied(tie: &Tie, graph: &PoseGraph) -> Pose2 {
    graph.pose(tie.anchor).compose(&tie.seen)
}

/// Where `held` puts `node`: its own node where it says, and the graph's path from there.
fn predicted(held: &Tie, node: usize, graph: &PoseGraph) -> Pose2 {
    let step = graph.pose(held.node).between(&graph.pose(node));
    implied(held, graph).compose(&step)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight path of `n` nodes 0.5 m apart, drifted by nothing.
    fn straight(n: usize) -> PoseGraph {
        let mut graph = PoseGraph::new(Pose2::IDENTITY).unwrap();
        for _ in 1..n {
            graph
                .add_node(Pose2::new(0.5, 0.0, 0.0), Matrix3::identity() * 1e4)
                .unwrap();
        }
        graph
    }

    fn tie(node: usize, correction: Pose2, graph: &PoseGraph) -> Tie {
        // The node is `correction` away from where the graph has it, seen from node 0.
        let truth = graph.pose(node).compose(&correction);
        Tie {
            node,
            submap: 0,
            anchor: 0,
            seen: graph.pose(0).between(&truth),
            information: Matrix3::identity() * 1e4,
            at_m: 0.5 * node as f64,
        }
    }

    fn tolerance(_: f64) -> (f64, f64) {
        (0.3, 0.05)
    }

    #[test]
    fn a_jump_waits_for_another_that_agrees() {
        let graph = straight(40);
        let mut held = Confirmations::default();
        let jump = Pose2::new(2.0, 0.5, 0.1);
        assert!(
            held.offer(tie(10, jump, &graph), &graph, tolerance)
                .is_empty()
        );
        // Too close along the path to count as another view.
        assert!(
            held.offer(tie(11, jump, &graph), &graph, tolerance)
                .is_empty()
        );
        let confirmed = held.offer(tie(16, jump, &graph), &graph, tolerance);
        assert_eq!(
            confirmed.iter().map(|t| t.node).collect::<Vec<_>>(),
            [10, 11, 16]
        );
        assert!(held.is_empty());
    }

    #[test]
    fn jumps_that_disagree_stay_held_and_expire() {
        let graph = straight(200);
        let mut held = Confirmations::default();
        assert!(
            held.offer(
                tie(10, Pose2::new(3.8, 0.0, 0.0), &graph),
                &graph,
                tolerance
            )
            .is_empty()
        );
        assert!(
            held.offer(
                tie(20, Pose2::new(-3.8, 0.0, 0.0), &graph),
                &graph,
                tolerance
            )
            .is_empty()
        );
        assert_eq!(held.len(), 2);
        // Past the hold, the first two are gone: a third like the first confirms nothing.
        let late = 10 + (2.0 * HOLD_M) as usize + 30;
        assert!(
            held.offer(
                tie(late, Pose2::new(3.8, 0.0, 0.0), &graph),
                &graph,
                tolerance
            )
            .is_empty()
        );
        assert_eq!(held.len(), 1);
    }
}
