//! Data association by Joint Compatibility Branch and Bound (Neira & Tardos 2001).
//!
//! Every observation of a scan is taken to the world with the same uncertain pose, so
//! their innovations are correlated: `C = D + G P G^T` with `D` block diagonal (corner and
//! sensor noise, one 4x4 block per pairing), `G` the stacked pose Jacobians and `P` the
//! pose covariance. A wrong pairing can pass its own gate; it cannot hide in the joint one.
//!
//! By the Woodbury identity the joint NIS of a hypothesis is
//! `sum s_i - b^T (P^-1 + A)^-1 b` with `s_i = nu_i^T D_i^-1 nu_i`,
//! `A = sum G_i^T D_i^-1 G_i`, `b = sum G_i^T D_i^-1 nu_i`: adding a pairing adds three
//! sums and costs one 3x3 solve, whatever the size of the hypothesis. The determinant
//! lemma gives `ln det C` the same way, hence the joint likelihood for the particle weight.

use std::f64::consts::TAU;
use std::ops::Range;

use nalgebra::{Matrix3, Matrix4, Vector3};

use crate::map::corner_map::CornerState;
use crate::math::linalg::{spd_inverse4, spd_log_det3, spd_solve3};
use crate::update::corner_model::{WorldObservation, innovation};

/// The pose uncertainty shared by every observation of a scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PoseUncertainty {
    /// `P`.
    pub covariance: Matrix3<f64>,
    /// `P^-1`.
    pub information: Matrix3<f64>,
    /// `ln det P`.
    pub log_det: f64,
}

impl PoseUncertainty {
    /// From a diagonal covariance `(x, y, yaw)` variances. A zero variance is floored: a
    /// pose known exactly (the first scan) has no finite information.
    pub fn from_variances(x: f64, y: f64, yaw: f64) -> Self {
        let v = Vector3::new(x, y, yaw).map(|v| v.max(1e-12));
        Self {
            covariance: Matrix3::from_diagonal(&v),
            information: Matrix3::from_diagonal(&v.map(|v| 1.0 / v)),
            log_det: v.iter().map(|v| v.ln()).sum(),
        }
    }
}

/// An individually compatible pairing of an observation with a map corner, with the
/// terms the joint test and the joint likelihood need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pairing {
    pub corner: u32,
    /// Individual NIS, the pose uncertainty included.
    pub distance: f64,
    /// `nu^T D^-1 nu`.
    s: f64,
    /// `G^T D^-1 G`.
    a: Matrix3<f64>,
    /// `G^T D^-1 nu`.
    b: Vector3<f64>,
    /// `ln det D`.
    log_det: f64,
    /// `D^-1 = (P_corner + R)^-1`, which the corner's Kalman update needs too.
    pub d_inverse: Matrix4<f64>,
}

impl Pairing {
    /// The pairing of `observation` with `corner`, or `None` when it fails the individual
    /// gate (4 dof).
    #[inline]
    pub fn new(
        observation: &WorldObservation,
        id: u32,
        corner: &CornerState,
        pose: &PoseUncertainty,
        gate: f64,
    ) -> Option<Self> {
        let nu = innovation(&observation.z, &corner.mean);
        let d = corner.covariance + observation.covariance;
        let (gx, gy) = (observation.lever.x, observation.lever.y);
        // One component bounds the 4-D distance from below (its Schur complement is
        // smaller): most wrong corners are rejected on one coordinate before any 4x4
        // algebra. The angle does not depend on the pose; the others do through `G P G^T`,
        // whose diagonal is `P_xx + 2 gx P_x,yaw + gx^2 P_yaw` (and likewise for y).
        let p = &pose.covariance;
        let along =
            |g: f64, axis: usize| p[(axis, axis)] + g * (2.0 * p[(axis, 2)] + g * p[(2, 2)]);
        if nu.w * nu.w > gate * d[(3, 3)]
            || nu.z * nu.z > gate * (d[(2, 2)] + p[(2, 2)])
            || nu.x * nu.x > gate * (d[(0, 0)] + along(gx, 0))
            || nu.y * nu.y > gate * (d[(1, 1)] + along(gy, 1))
        {
            return None;
        }
        let (d_inverse, log_det) = spd_inverse4(&d)?;
        // G = [[1, 0, gx], [0, 1, gy], [0, 0, 1], [0, 0, 0]] (the observation model: x, y
        // and heading move with the pose, the lever arm turns x and y): G^T D^-1 G and
        // G^T D^-1 nu reduce to a few products instead of two dense 4x3 multiplications.
        let w = d_inverse * nu;
        let c2 = d_inverse.column(0) * gx + d_inverse.column(1) * gy + d_inverse.column(2);
        let s = nu.dot(&w);
        let a = Matrix3::new(
            d_inverse[(0, 0)],
            d_inverse[(0, 1)],
            c2[0],
            d_inverse[(1, 0)],
            d_inverse[(1, 1)],
            c2[1],
            c2[0],
            c2[1],
            gx * c2[0] + gy * c2[1] + c2[2],
        );
        let b = Vector3::new(w[0], w[1], gx * w[0] + gy * w[1] + w[2]);
        let distance = joint_nis(s, &a, &b, &pose.information)?;
        (distance <= gate).then_some(Self {
            corner: id,
            distance,
            s,
            a,
            b,
            log_det,
            d_inverse,
        })
    }
}

/// `s - b^T (P^-1 + A)^-1 b`: the NIS of the stacked innovations under `D + G P G^T`.
fn joint_nis(
    s: f64,
    a: &Matrix3<f64>,
    b: &Vector3<f64>,
    pose_information: &Matrix3<f64>,
) -> Option<f64> {
    let x = spd_solve3(&(pose_information + a), b)?;
    Some(s - b.dot(&x))
}

/// Sums over the pairings of a partial hypothesis.
#[derive(Debug, Clone, Copy)]
struct Accumulated {
    pairings: usize,
    s: f64,
    a: Matrix3<f64>,
    b: Vector3<f64>,
    log_det: f64,
}

impl Accumulated {
    const EMPTY: Self = Self {
        pairings: 0,
        s: 0.0,
        a: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        b: Vector3::new(0.0, 0.0, 0.0),
        log_det: 0.0,
    };

    fn with(&self, p: &Pairing) -> Self {
        Self {
            pairings: self.pairings + 1,
            s: self.s + p.s,
            a: self.a + p.a,
            b: self.b + p.b,
            log_det: self.log_det + p.log_det,
        }
    }
}

/// The outcome of one association.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Association {
    /// Observations paired with a corner.
    pub pairings: usize,
    /// Joint NIS of the pairings.
    pub nis: f64,
    /// `ln N(nu; 0, C)` of the stacked innovations of the pairings (0 for none).
    pub log_likelihood: f64,
    /// Whether the node budget ran out (the result is then the best found so far).
    pub truncated: bool,
    /// What the pairings tell about the pose.
    pub evidence: PoseEvidence,
}

/// What a set of pairings tells about the pose, in information form: the pose correction
/// `-(P^-1 + A)^-1 b` fits them best under a prior of covariance `P`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PoseEvidence {
    /// `A = sum G^T D^-1 G` over the pairings.
    pub information: Matrix3<f64>,
    /// `b = sum G^T D^-1 nu`.
    pub gradient: Vector3<f64>,
}

impl PoseEvidence {
    /// No pairings: nothing known.
    pub const NONE: Self = Self {
        information: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        gradient: Vector3::new(0.0, 0.0, 0.0),
    };
}

/// The search, with buffers kept between calls.
#[derive(Debug, Clone, Default)]
pub(crate) struct Jcbb {
    /// Observations with at least one candidate, fewest candidates first.
    order: Vec<usize>,
    current: Vec<Option<usize>>,
    used: Vec<u32>,
    best: Vec<Option<usize>>,
    best_sum: Option<Accumulated>,
    best_nis: f64,
    nodes: usize,
    /// The result per observation: an index into the pairings, or `None`.
    assignment: Vec<Option<usize>>,
}

/// What one search is over.
struct Problem<'a> {
    pairings: &'a [Pairing],
    /// `lists[i]`: the candidates of observation `i` in `pairings`, best first.
    lists: &'a [Range<usize>],
    pose: &'a PoseUncertainty,
    /// Joint thresholds by number of pairings.
    gates: &'a [f64],
    max_nodes: usize,
}

impl Jcbb {
    /// Finds the largest jointly compatible set of pairings (the lowest joint NIS among
    /// equals found first). `lists[i]` ranges over `pairings`: the individually compatible
    /// candidates of observation `i`, sorted by `distance`. `gates[k]` is the chi-square
    /// threshold of `k` pairings; searches stop growing where it ends.
    pub fn solve(
        &mut self,
        pairings: &[Pairing],
        lists: &[Range<usize>],
        pose: &PoseUncertainty,
        gates: &[f64],
        max_nodes: usize,
    ) -> Association {
        self.order.clear();
        self.order
            .extend((0..lists.len()).filter(|&i| !lists[i].is_empty()));
        // Observations with fewer candidates first: they fix the pose correlation early,
        // and the joint gate then prunes the ambiguous ones.
        self.order.sort_by_key(|&i| (lists[i].len(), i));
        self.current.clear();
        self.current.resize(self.order.len(), None);
        self.best.clear();
        self.best.resize(self.order.len(), None);
        self.used.clear();
        self.best_sum = None;
        self.best_nis = 0.0;
        self.nodes = 0;
        let problem = Problem {
            pairings,
            lists,
            pose,
            gates,
            max_nodes,
        };
        self.descend(&problem, 0, Accumulated::EMPTY, 0.0);

        self.assignment.clear();
        self.assignment.resize(lists.len(), None);
        for (level, &observation) in self.order.iter().enumerate() {
            self.assignment[observation] = self.best[level];
        }
        let truncated = self.nodes > max_nodes;
        let Some(sum) = self.best_sum else {
            return Association {
                pairings: 0,
                nis: 0.0,
                log_likelihood: 0.0,
                truncated,
                evidence: PoseEvidence::NONE,
            };
        };
        // ln det C = sum ln det D_i + ln det P + ln det(P^-1 + A) (matrix determinant lemma).
        let log_det_m = spd_log_det3(&(pose.information + sum.a)).unwrap_or(f64::INFINITY);
        let log_det = sum.log_det + pose.log_det + log_det_m;
        let dims = 4.0 * sum.pairings as f64;
        Association {
            pairings: sum.pairings,
            nis: self.best_nis,
            log_likelihood: -0.5 * (self.best_nis + log_det + dims * TAU.ln()),
            truncated,
            evidence: PoseEvidence {
                information: sum.a,
                gradient: sum.b,
            },
        }
    }

    /// The pairing chosen for each observation, as an index into the pairings.
    pub fn assignment(&self) -> &[Option<usize>] {
        &self.assignment
    }

    fn best_pairings(&self) -> usize {
        self.best_sum.map_or(0, |s| s.pairings)
    }

    fn descend(&mut self, problem: &Problem<'_>, level: usize, sum: Accumulated, nis: f64) {
        self.nodes += 1;
        if self.nodes > problem.max_nodes {
            return;
        }
        let remaining = self.order.len() - level;
        // The bound: even pairing every remaining observation cannot beat the best.
        if sum.pairings + remaining <= self.best_pairings() {
            return;
        }
        if remaining == 0 {
            self.best.copy_from_slice(&self.current);
            self.best_sum = Some(sum);
            self.best_nis = nis;
            return;
        }
        let observation = self.order[level];
        if let Some(&gate) = problem.gates.get(sum.pairings + 1) {
            for index in problem.lists[observation].clone() {
                let pairing = &problem.pairings[index];
                if self.used.contains(&pairing.corner) {
                    continue;
                }
                let next = sum.with(pairing);
                let Some(next_nis) = joint_nis(next.s, &next.a, &next.b, &problem.pose.information)
                else {
                    continue;
                };
                if next_nis > gate {
                    continue;
                }
                self.used.push(pairing.corner);
                self.current[level] = Some(index);
                self.descend(problem, level + 1, next, next_nis);
                self.current[level] = None;
                self.used.pop();
            }
        }
        // Leave this observation unpaired (a new corner, or noise), if that can still win.
        if sum.pairings + remaining - 1 > self.best_pairings() {
            self.descend(problem, level + 1, sum, nis);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filter::observation::Prepared;
    use crate::update::corner_model::to_world;
    use nalgebra::{Matrix4, Vector4};
    use slam_geom::Pose2;

    fn corner(x: f64, y: f64) -> CornerState {
        CornerState {
            mean: Vector4::new(x, y, 0.5, 1.4),
            covariance: Matrix4::from_diagonal(&Vector4::new(1e-4, 1e-4, 1e-4, 1e-4)),
            observations: 3,
        }
    }

    fn observation(x: f64, y: f64) -> Prepared {
        Prepared {
            z: Vector4::new(x, y, 0.5, 1.4),
            covariance: Matrix4::from_diagonal(&Vector4::new(1e-4, 1e-4, 1e-4, 1e-4)),
        }
    }

    /// Individually compatible candidates of each observation, best first.
    fn candidates(
        observations: &[WorldObservation],
        corners: &[CornerState],
        pose: &PoseUncertainty,
        gate: f64,
    ) -> (Vec<Pairing>, Vec<Range<usize>>) {
        let mut pairings = Vec::new();
        let mut lists = Vec::new();
        for o in observations {
            let start = pairings.len();
            for (id, c) in corners.iter().enumerate() {
                pairings.extend(Pairing::new(o, id as u32, c, pose, gate));
            }
            pairings[start..].sort_by(|a, b| a.distance.total_cmp(&b.distance));
            lists.push(start..pairings.len());
        }
        (pairings, lists)
    }

    /// The baseline: each observation takes its nearest unused candidate.
    fn nearest_neighbour(pairings: &[Pairing], lists: &[Range<usize>]) -> Vec<Option<u32>> {
        let mut used = Vec::new();
        lists
            .iter()
            .map(|list| {
                let chosen = pairings[list.clone()]
                    .iter()
                    .find(|p| !used.contains(&p.corner))?;
                used.push(chosen.corner);
                Some(chosen.corner)
            })
            .collect()
    }

    #[test]
    fn jcbb_sees_a_common_pose_error_that_nearest_neighbour_does_not() {
        // Two corners 0.4 m apart on a line. The robot believes it is 0.25 m behind where
        // it is (its pose is uncertain by 0.2 m), so both observations land 0.25 m beyond
        // their corners: the first is then nearer the second corner, and the second is
        // still within the gate of the first.
        let corners = [corner(0.0, 0.0), corner(0.4, 0.0)];
        let pose = Pose2::IDENTITY;
        let uncertainty = PoseUncertainty::from_variances(0.04, 0.04, 1e-6);
        let observations: Vec<_> = [observation(0.25, 0.0), observation(0.65, 0.0)]
            .iter()
            .map(|o| to_world(&pose, o))
            .collect();
        let gates = crate::math::chi2::Gates::new(0.999);
        let (pairings, lists) =
            candidates(&observations, &corners, &uncertainty, gates.individual());
        // Both observations are individually compatible with both corners.
        assert!(lists.iter().all(|l| l.len() == 2));
        assert_eq!(nearest_neighbour(&pairings, &lists), vec![Some(1), Some(0)]);

        let mut jcbb = Jcbb::default();
        let result = jcbb.solve(&pairings, &lists, &uncertainty, gates.joint(), 1000);
        let chosen: Vec<_> = jcbb
            .assignment()
            .iter()
            .map(|a| a.map(|i| pairings[i].corner))
            .collect();
        assert_eq!(chosen, vec![Some(0), Some(1)]);
        assert_eq!(result.pairings, 2);
        assert!(!result.truncated);
        // The common offset is explained by the pose: a small joint NIS.
        assert!(result.nis < 3.0, "{}", result.nis);
    }

    #[test]
    fn joint_terms_match_the_dense_computation() {
        let corners = [corner(1.0, 2.0), corner(-3.0, 0.5), corner(2.0, -2.0)];
        let pose = Pose2::new(0.2, -0.1, 0.3);
        let uncertainty = PoseUncertainty::from_variances(0.01, 0.02, 0.001);
        let inverse = pose.inverse();
        let observations: Vec<_> = corners
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let p = inverse.transform(nalgebra::Vector2::new(c.mean.x, c.mean.y));
                let noise = 0.005 * (i as f64 + 1.0);
                let mut o = observation(p.x + noise, p.y - noise);
                o.z.z = slam_geom::wrap_angle(c.mean.z - pose.yaw + 0.01);
                to_world(&pose, &o)
            })
            .collect();
        let gates = crate::math::chi2::Gates::new(0.999999);
        let (pairings, lists) =
            candidates(&observations, &corners, &uncertainty, gates.individual());
        let mut jcbb = Jcbb::default();
        let result = jcbb.solve(&pairings, &lists, &uncertainty, gates.joint(), 1000);
        assert_eq!(result.pairings, 3);

        // Dense: stack the innovations, build C = D + G P G^T, evaluate N(nu; 0, C).
        let p = Matrix3::from_diagonal(&Vector3::new(0.01, 0.02, 0.001));
        let mut nu = nalgebra::DVector::zeros(12);
        let mut c = nalgebra::DMatrix::zeros(12, 12);
        let mut g = nalgebra::DMatrix::zeros(12, 3);
        for (i, (o, k)) in observations.iter().zip(corners.iter()).enumerate() {
            nu.rows_mut(4 * i, 4).copy_from(&innovation(&o.z, &k.mean));
            c.view_mut((4 * i, 4 * i), (4, 4))
                .copy_from(&(o.covariance + k.covariance));
            g.view_mut((4 * i, 0), (4, 3)).copy_from(&o.pose_jacobian());
        }
        // What the pairings say about the pose: G^T D^-1 G and G^T D^-1 nu.
        let d_inverse = c.clone().try_inverse().unwrap();
        let information = g.transpose() * &d_inverse * &g;
        let gradient = g.transpose() * &d_inverse * &nu;
        assert!(
            (result.evidence.information - &information).abs().max()
                < 1e-6 * information.abs().max()
        );
        assert!((result.evidence.gradient - &gradient).abs().max() < 1e-6 * gradient.abs().max());
        c += &g * p * g.transpose();
        let chol = nalgebra::Cholesky::new(c).unwrap();
        let nis = nu.dot(&chol.solve(&nu));
        let log_det = 2.0 * chol.l().diagonal().iter().map(|v| v.ln()).sum::<f64>();
        let log_likelihood = -0.5 * (nis + log_det + 12.0 * TAU.ln());
        assert!(
            (result.nis - nis).abs() < 1e-9 * nis.max(1.0),
            "{} vs {nis}",
            result.nis
        );
        assert!(
            (result.log_likelihood - log_likelihood).abs() < 1e-9 * log_likelihood.abs().max(1.0)
        );
    }

    #[test]
    fn the_node_budget_bounds_the_search() {
        // Ten identical observations of ten identical corners: 10! perfect hypotheses.
        let corners: Vec<_> = (0..10).map(|_| corner(0.0, 0.0)).collect();
        let observations: Vec<_> = (0..10)
            .map(|_| to_world(&Pose2::IDENTITY, &observation(0.0, 0.0)))
            .collect();
        let uncertainty = PoseUncertainty::from_variances(0.01, 0.01, 0.001);
        let mut gates = crate::math::chi2::Gates::new(0.99);
        gates.ensure(10);
        let (pairings, lists) =
            candidates(&observations, &corners, &uncertainty, gates.individual());
        let mut jcbb = Jcbb::default();
        let result = jcbb.solve(&pairings, &lists, &uncertainty, gates.joint(), 500);
        // The first branch pairs everything: found at once, and the bound stops the rest.
        assert_eq!(result.pairings, 10);
        assert!(!result.truncated);
        let result = jcbb.solve(&pairings, &lists, &uncertainty, gates.joint(), 5);
        assert!(result.truncated);
        assert!(result.pairings < 10);
    }
}
