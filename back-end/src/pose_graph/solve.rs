//! How [`PoseGraph::optimize`] solves: the annealed robust weighting of the closures, the
//! Gauss-Newton and Newton steps, the line search, and the normal equations they solve.

use nalgebra::{Matrix3, Vector3};
use slam_geom::{Pose2, wrap_angle};

use super::edge::{self, Linearized, chi2, dcs_cost, dcs_curvature, dcs_scale};
use super::sparse::{Equations, Pattern, Slot};
use super::{ACCEPTED_SCALE, PoseGraph, PoseGraphError, SolveReport};

/// Each Gauss-Newton step of the annealing divides the robust threshold by this at least.
const ANNEALING_FACTOR: f64 = 2.0;

/// A closure whose weight (squared scale) is above this holds the annealing back: the
/// threshold falls no further in one step than takes this much weight from it.
const ANNEALING_WEIGHT_STEP: f64 = 0.25;

/// Costs evaluated at most along one step (extrapolation up to 64 times the step).
const LINE_SEARCH_TRIES: usize = 7;

/// The factor's shape for one shape of the graph, kept while no node or closure is added.
#[derive(Debug, Clone)]
pub(super) struct Structure {
    nodes: usize,
    closures: usize,
    /// Node 0 held fixed (no priors) rather than free.
    gauge_fixed: bool,
    pattern: Pattern,
    step_slots: Vec<Option<Slot>>,
    closure_slots: Vec<Option<Slot>>,
    equations: Equations,
}

impl PoseGraph {
    pub(super) fn optimize_from_here(&mut self) -> Result<SolveReport, PoseGraphError> {
        let phi = self.settings.robust_threshold;
        let information: Vec<Matrix3<f64>> = self
            .closures
            .iter()
            .map(|c| c.measurement.information)
            .collect();
        let initial_cost = self.cost(&self.poses, &information, phi);
        // Pass 1, which closures hold. Only the closures new since the last optimization
        // set where the annealing starts: the others are settled, and starting above them
        // would unsettle them at every call.
        let new: Vec<bool> = self.closures.iter().map(|c| c.scale.is_none()).collect();
        let levelled = levelled_information(&information);
        let (mut iterations, mut converged) = self.anneal(&levelled, &new)?;
        // Pass 2, the answer with each closure's own information, when that differs: the
        // new closures the first pass took fully start it in plain least squares.
        if levelled != information {
            let candidates: Vec<bool> = self
                .closure_chi2(&levelled)
                .iter()
                .zip(&new)
                .map(|(&chi2, &new)| new && chi2 <= phi)
                .collect();
            let (more, settled) = self.anneal(&information, &candidates)?;
            iterations += more;
            converged &= settled;
        }
        let scales: Vec<f64> = self
            .closure_chi2(&information)
            .iter()
            .map(|&chi2| dcs_scale(chi2, phi))
            .collect();
        for (closure, scale) in self.closures.iter_mut().zip(&scales) {
            closure.scale = Some(*scale);
        }
        let accepted_closures = scales.iter().filter(|&&s| s >= ACCEPTED_SCALE).count();
        Ok(SolveReport {
            iterations,
            converged,
            initial_cost,
            final_cost: self.cost(&self.poses, &information, phi),
            accepted_closures,
            rejected_closures: scales.len() - accepted_closures,
        })
    }

    /// Steps with the closures' `information`, the robust threshold starting above the
    /// squared error of every `candidate` and lowered each step down to its setting (one
    /// reweighted Gauss-Newton step each, as graduated non-convexity takes), then held
    /// until the poses converge. Gives the steps taken and whether they converged.
    fn anneal(
        &mut self,
        information: &[Matrix3<f64>],
        candidates: &[bool],
    ) -> Result<(usize, bool), PoseGraphError> {
        let target = self.settings.robust_threshold;
        let mut chi2 = self.closure_chi2(information);
        let mut phi = chi2
            .iter()
            .zip(candidates)
            .filter(|(_, candidate)| **candidate)
            .fold(target, |most, (chi2, _)| most.max(*chi2));
        // The robust cost at the current poses, once a settling step has found it.
        let mut cost = None;
        for iteration in 1..=self.settings.max_iterations {
            // A threshold above every closure's error is plain least squares, as the lowest
            // such one is: the annealing goes on from there.
            phi = phi.min(chi2.iter().fold(target, |most, c| most.max(*c)));
            if phi > target {
                let direction = self.direction(information, &chi2, phi, Curvature::Reweighted)?;
                if direction.largest()? >= self.settings.tolerance {
                    self.poses = direction.apply(&self.poses, 1.0);
                }
                chi2 = self.closure_chi2(information);
                phi = next_threshold(&chi2, phi).max(target);
            } else {
                match self.settle(information, &chi2, cost)? {
                    Some(settled) => cost = Some(settled),
                    None => return Ok((iteration, true)),
                }
                chi2 = self.closure_chi2(information);
            }
        }
        Ok((self.settings.max_iterations, false))
    }

    /// One step at the final threshold: Newton's, the robust kernel's curvature included,
    /// when the equations stay positive definite with it (reweighting alone crawls where a
    /// closure is being let go: each step's weights lag behind), else reweighted
    /// Gauss-Newton's; the line search then picks how far to go. `cost` is the robust cost
    /// at the current poses, if known. Gives the cost where the step went, or `None` when
    /// no step moves the poses: they have converged.
    fn settle(
        &mut self,
        information: &[Matrix3<f64>],
        chi2: &[f64],
        cost: Option<f64>,
    ) -> Result<Option<f64>, PoseGraphError> {
        let phi = self.settings.robust_threshold;
        let cost = cost.unwrap_or_else(|| self.cost(&self.poses, information, phi));
        for curvature in [Curvature::Newton, Curvature::Reweighted] {
            let direction = match self.direction(information, chi2, phi, curvature) {
                Err(PoseGraphError::Singular) if curvature == Curvature::Newton => continue,
                other => other?,
            };
            if direction.largest()? < self.settings.tolerance {
                return Ok(None);
            }
            // Newton's step is the right length near the minimum; a reweighted step may
            // be far too short.
            let longer = curvature == Curvature::Reweighted;
            if let Some((poses, lower)) =
                self.line_search(&direction, information, phi, cost, longer)
            {
                self.poses = poses;
                return Ok(Some(lower));
            }
        }
        Ok(None)
    }

    /// The poses moved along `direction` by the multiple of it that lowers the robust cost
    /// below `cost` (the current one) most: the whole step, or half of it and so on if it
    /// does not; twice it and so on while that helps, if `longer`; with their cost. `None` if
    /// none lowers it.
    fn line_search(
        &self,
        direction: &Direction,
        information: &[Matrix3<f64>],
        phi: f64,
        cost: f64,
        longer: bool,
    ) -> Option<(Vec<Pose2>, f64)> {
        let mut best_cost = cost;
        let mut best = None;
        let mut multiple = 1.0;
        for _ in 0..LINE_SEARCH_TRIES {
            let poses = direction.apply(&self.poses, multiple);
            let cost = self.cost(&poses, information, phi);
            if cost < best_cost {
                best_cost = cost;
                best = Some(poses);
                if multiple < 1.0 || !longer {
                    break;
                }
                multiple *= 2.0;
            } else if best.is_some() {
                break;
            } else {
                multiple *= 0.5;
            }
        }
        best.map(|poses| (poses, best_cost))
    }

    /// Each closure's squared error at the current poses under `information`.
    fn closure_chi2(&self, information: &[Matrix3<f64>]) -> Vec<f64> {
        // Fewer closures than nodes: each takes its own frame.
        self.closures
            .iter()
            .zip(information)
            .map(|(c, w)| {
                let from = edge::Frame::new(&self.poses[c.from]);
                chi2(
                    &edge::error(&from, &self.poses[c.to], &c.measurement.seen),
                    w,
                )
            })
            .collect()
    }

    /// The robust cost at `poses`.
    fn cost(&self, poses: &[Pose2], information: &[Matrix3<f64>], phi: f64) -> f64 {
        let frames = edge::frames(poses);
        let steps: f64 = self
            .steps
            .iter()
            .enumerate()
            .map(|(i, m)| {
                chi2(
                    &edge::error(&frames[i], &poses[i + 1], &m.seen),
                    &m.information,
                )
            })
            .sum();
        let priors: f64 = self
            .priors
            .iter()
            .map(|p| chi2(&prior_error(&poses[p.node], &p.pose), &p.information))
            .sum();
        let closures: f64 = self
            .closures
            .iter()
            .zip(information)
            .map(|(c, w)| {
                let e = edge::error(&frames[c.from], &poses[c.to], &c.measurement.seen);
                dcs_cost(chi2(&e, w), phi)
            })
            .sum();
        steps + priors + closures
    }

    /// The step at the current poses, each closure weighted by DCS at threshold `phi`
    /// given its squared error `chi2`.
    fn direction(
        &mut self,
        information: &[Matrix3<f64>],
        chi2: &[f64],
        phi: f64,
        curvature: Curvature,
    ) -> Result<Direction, PoseGraphError> {
        let mut structure = self.take_structure();
        self.fill(&mut structure, information, chi2, phi, curvature);
        let solved = structure.equations.solve(&structure.pattern);
        let fixed = usize::from(structure.gauge_fixed);
        self.structure = Some(structure);
        let update = solved.ok_or(PoseGraphError::Singular)?;
        Ok(Direction { fixed, update })
    }

    /// Fills the normal equations at the current poses.
    fn fill(
        &self,
        structure: &mut Structure,
        information: &[Matrix3<f64>],
        chi2: &[f64],
        phi: f64,
        curvature: Curvature,
    ) {
        let Structure {
            gauge_fixed,
            pattern,
            step_slots,
            closure_slots,
            equations,
            ..
        } = structure;
        equations.clear();
        let node = |i: usize| variable(i, *gauge_fixed);
        let frames = edge::frames(&self.poses);
        for (i, (m, slot)) in self.steps.iter().zip(step_slots.iter()).enumerate() {
            let edge = Linearized::new(&frames[i], &self.poses[i + 1], &m.seen);
            let ends = (node(i), node(i + 1), *slot);
            add_edge(
                pattern,
                equations,
                ends,
                &edge,
                &m.information,
                &m.information,
            );
        }
        for (k, (c, slot)) in self.closures.iter().zip(closure_slots.iter()).enumerate() {
            let m = &c.measurement;
            let edge = Linearized::new(&frames[c.from], &self.poses[c.to], &m.seen);
            let weighted = information[k] * dcs_scale(chi2[k], phi).powi(2);
            let mut hessian = weighted;
            if curvature == Curvature::Newton {
                let pull = information[k] * edge.error;
                hessian += pull * pull.transpose() * dcs_curvature(chi2[k], phi);
            }
            let ends = (node(c.from), node(c.to), *slot);
            add_edge(pattern, equations, ends, &edge, &hessian, &weighted);
        }
        for p in &self.priors {
            // With priors nothing is held fixed: every node is a variable.
            let error = prior_error(&self.poses[p.node], &p.pose);
            let gradient = p.information * error;
            equations.add_diagonal(pattern, p.node, &p.information, &gradient);
        }
    }

    /// The factor's shape for the graph as it is now, built if it changed.
    fn take_structure(&mut self) -> Structure {
        let gauge_fixed = self.priors.is_empty();
        match self.structure.take() {
            Some(s)
                if s.nodes == self.poses.len()
                    && s.closures == self.closures.len()
                    && s.gauge_fixed == gauge_fixed =>
            {
                s
            }
            _ => self.build_structure(gauge_fixed),
        }
    }

    fn build_structure(&self, gauge_fixed: bool) -> Structure {
        let variables = self.poses.len() - usize::from(gauge_fixed);
        let pair =
            |a: usize, b: usize| Some((variable(a, gauge_fixed)?, variable(b, gauge_fixed)?));
        let step_ends: Vec<_> = (0..self.steps.len()).map(|i| pair(i, i + 1)).collect();
        let closure_ends: Vec<_> = self.closures.iter().map(|c| pair(c.from, c.to)).collect();
        let edges = step_ends.iter().chain(&closure_ends).flatten().copied();
        let pattern = Pattern::new(variables, edges);
        let slot = |ends: &Option<(usize, usize)>| ends.and_then(|(a, b)| pattern.slot(a, b));
        let step_slots = step_ends.iter().map(slot).collect();
        let closure_slots = closure_ends.iter().map(slot).collect();
        let equations = Equations::new(&pattern);
        Structure {
            nodes: self.poses.len(),
            closures: self.closures.len(),
            gauge_fixed,
            pattern,
            step_slots,
            closure_slots,
            equations,
        }
    }
}

/// A Gauss-Newton step: the update of every node after the `fixed` first ones.
struct Direction {
    fixed: usize,
    update: Vec<Vector3<f64>>,
}

impl Direction {
    /// The largest component of the step; an error if it is not finite.
    fn largest(&self) -> Result<f64, PoseGraphError> {
        let largest = self
            .update
            .iter()
            .fold(0.0_f64, |most, d| most.max(d.amax()));
        if largest.is_finite() {
            Ok(largest)
        } else {
            Err(PoseGraphError::Diverged)
        }
    }

    /// `poses` moved by `multiple` times the step.
    fn apply(&self, poses: &[Pose2], multiple: f64) -> Vec<Pose2> {
        let (fixed, free) = poses.split_at(self.fixed);
        // The equations give the step that cancels the gradient: it is subtracted.
        fixed
            .iter()
            .copied()
            .chain(free.iter().zip(&self.update).map(|(p, d)| {
                let d = d * multiple;
                Pose2::new(p.x - d.x, p.y - d.y, p.yaw - d.z)
            }))
            .collect()
    }
}

/// The annealing's next threshold after `phi`, the closures' squared errors `chi2`: half
/// of it, or lower as long as no closure loses more than [`ANNEALING_WEIGHT_STEP`] of its
/// weight. Closures already mostly let go no longer hold it back, so it does not crawl
/// through the levels at which only their weight, near nothing, still changes.
fn next_threshold(chi2: &[f64], phi: f64) -> f64 {
    let lowest = chi2
        .iter()
        .filter_map(|&chi2| {
            let weight = dcs_scale(chi2, phi).powi(2);
            // The scale `r` that keeps the weight within the step is reached at
            // `phi' = r chi2 / (2 - r)`.
            let kept = (weight - ANNEALING_WEIGHT_STEP).max(0.0).sqrt();
            (weight > ANNEALING_WEIGHT_STEP).then(|| kept * chi2 / (2.0 - kept))
        })
        .fold(0.0, f64::max);
    (phi / ANNEALING_FACTOR).min(lowest)
}

/// How a closure's robust kernel enters the normal equations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Curvature {
    /// Its information scaled by its weight (iteratively reweighted least squares).
    Reweighted,
    /// And the kernel's own curvature, negative beyond the threshold (Newton's method).
    Newton,
}

/// The variable of node `i`: none for node 0 when it is the fixed gauge.
fn variable(i: usize, gauge_fixed: bool) -> Option<usize> {
    if gauge_fixed {
        i.checked_sub(1)
    } else {
        Some(i)
    }
}

/// Adds a linearised edge to the normal equations: `ends` are its two variables (`None`:
/// the fixed node) and the slot of their coupling; `hessian` weighs its curvature and
/// `gradient` its error (the same matrix but for a robust kernel's Newton step).
fn add_edge(
    pattern: &Pattern,
    equations: &mut Equations,
    ends: (Option<usize>, Option<usize>, Option<Slot>),
    edge: &Linearized,
    hessian: &Matrix3<f64>,
    gradient: &Matrix3<f64>,
) {
    let pull = gradient * edge.error;
    let curved_from = edge.jacobian_from.transpose() * hessian;
    if let Some(a) = ends.0 {
        let block = curved_from * edge.jacobian_from;
        equations.add_diagonal(pattern, a, &block, &edge.jacobian_from.tr_mul(&pull));
    }
    if let Some(b) = ends.1 {
        let block = edge.jacobian_to.transpose() * hessian * edge.jacobian_to;
        equations.add_diagonal(pattern, b, &block, &edge.jacobian_to.tr_mul(&pull));
    }
    if let Some(slot) = ends.2 {
        equations.add_coupling(slot, &(curved_from * edge.jacobian_to));
    }
}

/// A pose's difference from a prior, in the world's `x, y, yaw`.
fn prior_error(pose: &Pose2, prior: &Pose2) -> Vector3<f64> {
    Vector3::new(
        pose.x - prior.x,
        pose.y - prior.y,
        wrap_angle(pose.yaw - prior.yaw),
    )
}

/// The closures' information scaled to the median volume (determinant), each keeping its
/// shape: how sure a closure claims to be is as untrusted as what it says.
fn levelled_information(information: &[Matrix3<f64>]) -> Vec<Matrix3<f64>> {
    let volume = |w: &Matrix3<f64>| w.determinant().cbrt();
    let mut volumes: Vec<f64> = information.iter().map(volume).collect();
    volumes.sort_by(f64::total_cmp);
    let Some(&median) = volumes.get(volumes.len() / 2) else {
        return Vec::new();
    };
    information
        .iter()
        .map(|w| w * (median / volume(w)))
        .collect()
}
