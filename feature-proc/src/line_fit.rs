//! Total-least-squares line fit in normal form `x cos(theta) + y sin(theta) = rho`, and the
//! first-order covariance of `(rho, theta)` from the noise of each point.
//!
//! The fit minimises orthogonal distances, so no orientation is special (an `y = a x + b`
//! fit degrades towards vertical lines).

use nalgebra::Matrix2;

use crate::scan::ScanPoint;
use slam_geom::wrap_angle;

/// A fitted line with what its covariance needs.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TlsFit {
    /// Distance of the line from the sensor, >= 0.
    pub rho: f64,
    /// Unit normal from the sensor towards the line, `(cos theta, sin theta)`.
    pub normal: [f64; 2],
    pub centroid: [f64; 2],
    /// Difference of the scatter matrix's eigenvalues (along minus across the line): how
    /// well the points pin the direction down.
    pub spread: f64,
}

impl TlsFit {
    /// Direction of the normal, in `[-pi, pi)`; only the reported lines need it.
    pub fn theta(&self) -> f64 {
        wrap_angle(self.normal[1].atan2(self.normal[0]))
    }

    /// Unit direction along the line, `(-sin theta, cos theta)`.
    pub fn direction(&self) -> [f64; 2] {
        [-self.normal[1], self.normal[0]]
    }

    /// Signed distance of a point from the line.
    pub fn residual(&self, x: f64, y: f64) -> f64 {
        self.normal[0] * x + self.normal[1] * y - self.rho
    }

    /// The foot of the perpendicular from a point onto the line.
    pub fn project(&self, x: f64, y: f64) -> [f64; 2] {
        let r = self.residual(x, y);
        [x - r * self.normal[0], y - r * self.normal[1]]
    }
}

/// Fits a line to at least two distinct points; `None` when they pin no direction down.
pub(crate) fn fit(points: &[ScanPoint]) -> Option<TlsFit> {
    if points.len() < 2 {
        return None;
    }
    let count = points.len() as f64;
    // Moments about the first point, in one pass: offsets are as small as the run, so
    // centring them afterwards loses nothing that matters (raw coordinates up to 30 m
    // would lose the millimetre spread across a far line).
    let origin = points[0];
    let (mut sx, mut sy, mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for p in points {
        let (dx, dy) = (p.x - origin.x, p.y - origin.y);
        sx += dx;
        sy += dy;
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    let (mx, my) = (sx / count, sy / count);
    let (cx, cy) = (origin.x + mx, origin.y + my);
    let sxx = sxx - sx * mx;
    let sxy = sxy - sx * my;
    let syy = syy - sy * my;
    let (difference, sxy2) = (sxx - syy, 2.0 * sxy);
    let spread = (difference * difference + sxy2 * sxy2).sqrt();
    if spread.is_nan() || spread <= 1e-12 {
        return None;
    }
    // The normal is the eigenvector of the smallest eigenvalue of the scatter matrix.
    // The normal is the eigenvector of the smallest eigenvalue of the scatter matrix, at
    // theta = atan2(-2 sxy, syy - sxx) / 2. Half-angle formulas without trigonometry, each
    // dividing by the larger of cos and sin (>= 1/sqrt 2) so no orientation loses precision.
    let (cos2, sin2) = ((syy - sxx) / spread, -2.0 * sxy / spread);
    let (mut cos, mut sin) = if cos2 >= 0.0 {
        let cos = ((1.0 + cos2) / 2.0).sqrt();
        (cos, sin2 / (2.0 * cos))
    } else {
        let sin = ((1.0 - cos2) / 2.0).sqrt().copysign(sin2);
        (sin2 / (2.0 * sin), sin)
    };
    let mut rho = cx * cos + cy * sin;
    if rho < 0.0 {
        rho = -rho;
        sin = -sin;
        cos = -cos;
    }
    Some(TlsFit {
        rho,
        normal: [cos, sin],
        centroid: [cx, cy],
        spread,
    })
}

/// The largest distance of a point from the fitted line.
pub(crate) fn max_residual(points: &[ScanPoint], fit: &TlsFit) -> f64 {
    points
        .iter()
        .map(|p| fit.residual(p.x, p.y).abs())
        .fold(0.0, f64::max)
}

/// Covariance of `(rho, theta)` of `fit`, propagated to first order from independent range
/// noise `range_sigma` along each beam and bearing noise `bearing_sigma` across it, and
/// scaled up when the residuals are too large for that noise (a rough wall, a slightly bent
/// run): the residuals' mean square over the predicted one must stay below the 99 %
/// quantile of chi-square over its degrees of freedom, else it becomes the scale factor.
///
/// Perturbing point `j` (offset `q` from the centroid) changes the scatter matrix by
/// `dp q^T + q dp^T`; eigenvector perturbation gives
/// `dtheta = -((q.n) t + (q.t) n) . dp / spread`, and `rho = n . c` gives
/// `drho = n . dp / N + (t . c) dtheta`, with `n` the normal and `t` the direction.
pub(crate) fn covariance(
    points: &[ScanPoint],
    fit: &TlsFit,
    range_sigma: f64,
    bearing_sigma: f64,
) -> Matrix2<f64> {
    let count = points.len() as f64;
    let inv_spread = 1.0 / fit.spread;
    let n = fit.normal;
    let t = fit.direction();
    // Sums over the points of the terms the covariance is made of; see below.
    let (mut uu, mut u_theta, mut theta_theta) = (0.0, 0.0, 0.0);
    let (mut vv, mut v_theta, mut theta_theta_v) = (0.0, 0.0, 0.0);
    let mut squares = 0.0;
    for p in points {
        let q = [p.x - fit.centroid[0], p.y - fit.centroid[1]];
        // `qn` is also the point's residual.
        let (qn, qt) = (q[0] * n[0] + q[1] * n[1], q[0] * t[0] + q[1] * t[1]);
        // The beam `u` in the line's frame; the direction across it, `v`, has
        // `v.n = -u.t` and `v.t = u.n`.
        let (un, ut) = (p.cos * n[0] + p.sin * n[1], p.cos * t[0] + p.sin * t[1]);
        // How theta moves with the point along the beam and across it.
        let theta_u = -(qn * ut + qt * un) * inv_spread;
        let theta_v = -(qn * un - qt * ut) * inv_spread;
        uu += un * un;
        u_theta += un * theta_u;
        theta_theta += theta_u * theta_u;
        // Bearing noise moves a point by range * bearing_sigma.
        let w = p.range * p.range;
        vv += w * ut * ut;
        v_theta -= w * ut * theta_v;
        theta_theta_v += w * theta_v * theta_v;
        squares += qn * qn;
    }
    // rho = n . centroid moves with a point by `(n . d) / N + (t . centroid) dtheta`, so with
    // `a = un / N` along the beam (`-ut / N` across) and `b = dtheta`:
    // var(rho) = sum (a + tc b)^2, cov = sum (a + tc b) b, var(theta) = sum b^2.
    let tc = t[0] * fit.centroid[0] + t[1] * fit.centroid[1];
    let (range_var, bearing_var) = (range_sigma * range_sigma, bearing_sigma * bearing_sigma);
    let inv_count = 1.0 / count;
    let part = |aa: f64, ab: f64, bb: f64| {
        let rr = aa * inv_count * inv_count + 2.0 * tc * ab * inv_count + tc * tc * bb;
        let rt = ab * inv_count + tc * bb;
        (rr, rt, bb)
    };
    let (r1, c1, t1) = part(uu, u_theta, theta_theta);
    let (r2, c2, t2) = part(vv, v_theta, theta_theta_v);
    let (rr, rt, tt) = (
        range_var * r1 + bearing_var * r2,
        range_var * c1 + bearing_var * c2,
        range_var * t1 + bearing_var * t2,
    );
    let predicted = range_var * uu + bearing_var * vv;
    // Two parameters were fitted; the residuals keep the other degrees of freedom.
    let dof = count - 2.0;
    let mut scale = 1.0;
    if dof >= 1.0 && predicted > 0.0 {
        let ratio = squares / dof / (predicted * inv_count);
        if ratio > chi_square_99(dof) {
            scale = ratio;
        }
    }
    Matrix2::new(rr, rt, rt, tt) * scale
}

/// The 99 % quantile of chi-square with `dof` degrees of freedom, over `dof`
/// (Wilson-Hilferty; within 1 % from 2 degrees of freedom up).
fn chi_square_99(dof: f64) -> f64 {
    let z = 2.326;
    let a = 2.0 / (9.0 * dof);
    (1.0 - a + z * a.sqrt()).powi(3)
}
