//! Exact wall outlines of a rectilinear floor plan, for the built-in worlds.
//!
//! A plan is painted like an architect's sketch: free rectangles (rooms, corridors, door
//! openings, alcoves) and solid ones (pillars, cabinets, door surrounds), later ones over
//! earlier ones, on a background of wall. Tracing the boundary of the free region gives
//! closed polygons whose every vertex is a real corner, with no overlapping or abutting wall
//! pieces that would put hidden vertices into the true-corner list.

use std::collections::HashMap;

/// An axis-aligned rectangle `[x0, y0, x1, y1]` with `x0 < x1`, `y0 < y1`.
pub(crate) type Rect = [f64; 4];

/// One stroke of the plan.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Paint {
    Free(Rect),
    Solid(Rect),
}

impl Paint {
    fn rect(&self) -> &Rect {
        match self {
            Paint::Free(r) | Paint::Solid(r) => r,
        }
    }
}

/// Wall thickness around the free space; only the inner faces are kept, so it only has
/// to be positive.
const MARGIN: f64 = 0.5;

/// Snaps plan coordinates to a millimetre so that sums such as `0.2 + 6.0 * k` written in
/// different places land on one grid line.
fn snap(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

/// Boundary polygons (closed, first point repeated) between free space and walls. A cell
/// of the compressed grid takes the paint of the last stroke covering it, wall if none. The
/// outer boundary of the surrounding wall is dropped: it faces nothing.
pub(crate) fn outline(plan: &[Paint]) -> Vec<Vec<[f64; 2]>> {
    let all = || plan.iter().map(Paint::rect);
    let lo = |k: usize| all().map(|r| r[k]).fold(f64::INFINITY, f64::min) - MARGIN;
    let hi = |k: usize| all().map(|r| r[k]).fold(f64::NEG_INFINITY, f64::max) + MARGIN;
    let axis = |k0: usize, k1: usize, lo: f64, hi: f64| {
        let mut v: Vec<f64> = all()
            .flat_map(|r| [r[k0], r[k1]])
            .chain([lo, hi])
            .map(snap)
            .collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    let xs = axis(0, 2, lo(0), hi(2));
    let ys = axis(1, 3, lo(1), hi(3));
    let (nx, ny) = (xs.len() - 1, ys.len() - 1);
    let inside = |r: &Rect, x: f64, y: f64| r[0] < x && x < r[2] && r[1] < y && y < r[3];
    let mut is_solid = vec![false; nx * ny];
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (0.5 * (xs[i] + xs[i + 1]), 0.5 * (ys[j] + ys[j + 1]));
            let last = plan.iter().rev().find(|p| inside(p.rect(), x, y));
            is_solid[j * nx + i] = !matches!(last, Some(Paint::Free(_)));
        }
    }
    let cell = |i: isize, j: isize| {
        i >= 0
            && j >= 0
            && (i as usize) < nx
            && (j as usize) < ny
            && is_solid[j as usize * nx + i as usize]
    };

    // Directed boundary edges between grid vertices, solid on the left.
    let mut edges: Vec<((isize, isize), (isize, isize))> = Vec::new();
    for j in 0..ny as isize {
        for i in 0..nx as isize {
            if !cell(i, j) {
                continue;
            }
            if !cell(i, j - 1) {
                edges.push(((i, j), (i + 1, j)));
            }
            if !cell(i + 1, j) {
                edges.push(((i + 1, j), (i + 1, j + 1)));
            }
            if !cell(i, j + 1) {
                edges.push(((i + 1, j + 1), (i, j + 1)));
            }
            if !cell(i - 1, j) {
                edges.push(((i, j + 1), (i, j)));
            }
        }
    }
    let mut from: HashMap<(isize, isize), Vec<usize>> = HashMap::new();
    for (k, e) in edges.iter().enumerate() {
        from.entry(e.0).or_default().push(k);
    }
    let dir = |k: usize| {
        let (a, b) = edges[k];
        (b.0 - a.0, b.1 - a.1)
    };

    let mut used = vec![false; edges.len()];
    let mut loops = Vec::new();
    for start in 0..edges.len() {
        if used[start] {
            continue;
        }
        let mut vertices = Vec::new();
        let mut k = start;
        loop {
            used[k] = true;
            vertices.push(edges[k].0);
            let d = dir(k);
            // Where two solid cells touch at a vertex only, turning left keeps to the same
            // cell, so the two solids get separate outlines.
            let next = from.get(&edges[k].1).and_then(|out| {
                out.iter()
                    .copied()
                    .filter(|&n| !used[n] || n == start)
                    .max_by_key(|&n| d.0 * dir(n).1 - d.1 * dir(n).0)
            });
            match next {
                Some(n) if n != start => k = n,
                _ => break,
            }
        }
        if vertices.contains(&(0, 0)) {
            continue;
        }
        // Keep only the vertices where the outline turns.
        let m = vertices.len();
        let corners: Vec<[f64; 2]> = (0..m)
            .filter(|&v| {
                let (p, c, n) = (
                    vertices[(v + m - 1) % m],
                    vertices[v],
                    vertices[(v + 1) % m],
                );
                (c.0 - p.0) * (n.1 - c.1) != (c.1 - p.1) * (n.0 - c.0)
            })
            .map(|v| [xs[vertices[v].0 as usize], ys[vertices[v].1 as usize]])
            .collect();
        if let Some(&first) = corners.first() {
            let mut polygon = corners;
            polygon.push(first);
            loops.push(polygon);
        }
    }
    loops
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn room_with_pillar_and_alcove() {
        let loops = outline(&[
            Paint::Free([0.0, 0.0, 4.0, 3.0]),
            Paint::Free([1.0, 3.0, 2.0, 3.5]),
            Paint::Solid([2.0, 1.0, 2.5, 1.5]),
        ]);
        assert_eq!(loops.len(), 2);
        let mut sizes: Vec<usize> = loops.iter().map(Vec::len).collect();
        sizes.sort();
        // Pillar: 4 corners; room: 4 + 4 from the alcove; each closed with its first point.
        assert_eq!(sizes, [5, 9]);
        assert!(loops.iter().all(|l| l.first() == l.last()));
    }
}
