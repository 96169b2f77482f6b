//! Split-and-merge: segments are split into straight runs, neighbouring runs on one line are
//! merged again, the points at each shared boundary go to the line they lie on, and stubs
//! left around a corner go to its two walls.

use std::ops::Range;

use crate::config::FeatureConfig;
use crate::line_fit::{TlsFit, fit, max_residual};
use crate::scan::ScanPoint;

/// A run of points is split at the one farthest from its chord when it is farther than this,
/// metres; also the largest residual a merged line may have. Five times a wall's sigma: a
/// real bend, not noise, and small enough that a shallow corner is still cut.
const SPLIT_THRESHOLD: f64 = 0.1;
/// Neighbouring lines whose directions differ by less than this are merged when their union
/// is still straight, radians: far below any corner's angle, so a merge never undoes one.
const MERGE_ANGLE: f64 = 6f64.to_radians();
/// Largest gap between neighbouring lines that a merge may bridge (dropouts, grazing
/// incidence), metres: shorter than a doorway, so two walls either side of one stay two.
const MERGE_MAX_GAP: f64 = 0.5;

/// A straight run of points `points[start..end]` and its fit.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Piece {
    pub start: usize,
    pub end: usize,
    pub fit: TlsFit,
}

impl Piece {
    fn len(&self) -> usize {
        self.end - self.start
    }
}

/// Splits `segment` recursively at the point farthest from the chord of its end points,
/// appending the straight runs of at least `min_line_points` points to `out` in scan order.
pub(crate) fn split(
    points: &[ScanPoint],
    segment: Range<usize>,
    config: &FeatureConfig,
    stack: &mut Vec<Range<usize>>,
    out: &mut Vec<Piece>,
) {
    stack.clear();
    stack.push(segment);
    while let Some(run) = stack.pop() {
        if let Some(at) = split_point(&points[run.clone()], SPLIT_THRESHOLD) {
            let at = run.start + at;
            // Right first so the left half is handled first and `out` stays in scan order.
            stack.push(at..run.end);
            stack.push(run.start..at);
        } else if run.len() >= config.min_line_points
            && let Some(fit) = fit(&points[run.clone()])
        {
            out.push(Piece {
                start: run.start,
                end: run.end,
                fit,
            });
        }
    }
}

/// The index of the point farthest from the chord, if farther than `threshold`.
fn split_point(run: &[ScanPoint], threshold: f64) -> Option<usize> {
    let (first, last) = (run.first()?, run.last()?);
    if run.len() < 3 {
        return None;
    }
    let (dx, dy) = (last.x - first.x, last.y - first.y);
    let chord = (dx * dx + dy * dy).sqrt();
    let inner = run.iter().enumerate().take(run.len() - 1).skip(1);
    let best = if chord > 1e-9 {
        // |cross| = distance * chord: no division per point.
        let mut best = (0, threshold * chord);
        for (i, p) in inner {
            let cross = (dx * (p.y - first.y) - dy * (p.x - first.x)).abs();
            if cross > best.1 {
                best = (i, cross);
            }
        }
        best.0
    } else {
        // A closed run has no chord; the point farthest from its start is a vertex then.
        let mut best = (0, threshold * threshold);
        for (i, p) in inner {
            let (px, py) = (p.x - first.x, p.y - first.y);
            if px * px + py * py > best.1 {
                best = (i, px * px + py * py);
            }
        }
        best.0
    };
    (best > 0).then_some(best)
}

/// Merges neighbouring pieces that lie on one line: directions within [`MERGE_ANGLE`], a
/// gap of at most [`MERGE_MAX_GAP`] and every point of the union, including any stray points
/// between them, within [`SPLIT_THRESHOLD`] of the union's fit.
pub(crate) fn merge(points: &[ScanPoint], pieces: &[Piece], out: &mut Vec<Piece>) {
    out.clear();
    for piece in pieces {
        if let Some(last) = out.last_mut()
            && let Some(union) = merged(points, last, piece)
        {
            *last = union;
            continue;
        }
        out.push(*piece);
    }
}

fn merged(points: &[ScanPoint], a: &Piece, b: &Piece) -> Option<Piece> {
    // The sine of the angle between the normals; its magnitude ignores which way each
    // points, which the sign of rho decides.
    let (na, nb) = (a.fit.normal, b.fit.normal);
    if (na[0] * nb[1] - na[1] * nb[0]).abs() > MERGE_ANGLE.sin() {
        return None;
    }
    if points[a.end - 1].distance(&points[b.start]) > MERGE_MAX_GAP {
        return None;
    }
    let union = &points[a.start..b.end];
    let fit = fit(union)?;
    (max_residual(union, &fit) <= SPLIT_THRESHOLD).then_some(Piece {
        start: a.start,
        end: b.end,
        fit,
    })
}

/// Moves the points at the boundary of two touching pieces to the line they are closer to:
/// the split point is only the one farthest from a chord, and a point of one wall fitted to
/// the other biases that line.
pub(crate) fn refine_boundaries(points: &[ScanPoint], pieces: &mut [Piece], min_points: usize) {
    // A boundary moves by a point or two in practice; the cap only bounds the work.
    const MAX_MOVES: usize = 16;
    for i in 1..pieces.len() {
        let (left, right) = pieces.split_at_mut(i);
        let (a, b) = (&mut left[i - 1], &mut right[0]);
        if a.end != b.start {
            continue;
        }
        for _ in 0..MAX_MOVES {
            let last = points[a.end - 1];
            let first = points[b.start];
            let moved = if a.len() > min_points && closer_to(&b.fit, &a.fit, &last) {
                a.end -= 1;
                b.start -= 1;
                true
            } else if b.len() > min_points && closer_to(&a.fit, &b.fit, &first) {
                a.end += 1;
                b.start += 1;
                true
            } else {
                false
            };
            if !moved {
                break;
            }
            let (Some(fa), Some(fb)) = (fit(&points[a.start..a.end]), fit(&points[b.start..b.end]))
            else {
                break;
            };
            a.fit = fa;
            b.fit = fb;
        }
    }
}

/// Whether `p` lies closer to `other` than to `own`.
fn closer_to(other: &TlsFit, own: &TlsFit, p: &ScanPoint) -> bool {
    other.residual(p.x, p.y).abs() < own.residual(p.x, p.y).abs()
}

/// Hands the points of a piece too short to be a corner's arm, wedged between two touching
/// pieces, to those two when each point lies within `tolerance` of the line it goes to:
/// the recursive split can leave the few points around a corner as a stub of their own,
/// which would stand between the two walls of that corner.
pub(crate) fn absorb_stubs(
    points: &[ScanPoint],
    pieces: &mut Vec<Piece>,
    min_length: f64,
    tolerance: f64,
) {
    let mut i = 1;
    while i + 1 < pieces.len() {
        let (a, stub, b) = (pieces[i - 1], pieces[i], pieces[i + 1]);
        let short = points[stub.start].distance(&points[stub.end - 1]) < min_length;
        if !(short && a.end == stub.start && stub.end == b.start) {
            i += 1;
            continue;
        }
        // The cut giving the stub's points before it to `a` and the rest to `b` with the
        // smallest worst residual.
        let worst = |cut: usize| {
            let to_a = points[stub.start..cut]
                .iter()
                .map(|p| a.fit.residual(p.x, p.y).abs());
            let to_b = points[cut..stub.end]
                .iter()
                .map(|p| b.fit.residual(p.x, p.y).abs());
            to_a.chain(to_b).fold(0.0, f64::max)
        };
        let (cut, residual) = (stub.start..=stub.end).map(|cut| (cut, worst(cut))).fold(
            (stub.start, f64::INFINITY),
            |best, c| {
                if c.1 < best.1 { c } else { best }
            },
        );
        if residual > tolerance {
            i += 1;
            continue;
        }
        match (fit(&points[a.start..cut]), fit(&points[cut..b.end])) {
            (Some(fa), Some(fb)) => {
                pieces[i - 1] = Piece {
                    end: cut,
                    fit: fa,
                    ..a
                };
                pieces[i + 1] = Piece {
                    start: cut,
                    fit: fb,
                    ..b
                };
                pieces.remove(i);
            }
            _ => i += 1,
        }
    }
}
