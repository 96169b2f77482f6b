//! The pose graph's normal equations, solved by a sparse Cholesky factorization of 3 x 3
//! blocks (one block row per free node), ordered by minimum degree.
//!
//! A chain's nodes each touch two others, so minimum degree eliminates them first at no
//! cost but a 3 x 3 block between their neighbours: the long chain collapses to a small
//! graph over the closures' ends, factored with the fill its shape needs. The solve is
//! exact, whatever the closures (no iteration to converge or to check), and its cost grows
//! with the chain's length plus that small graph's fill. The ordering depends only on which
//! nodes are joined, so it is computed once per shape of the graph and reused by every
//! Gauss-Newton step.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use nalgebra::{Matrix3, Vector3};

/// The shape of the factor: the elimination order and, for each block column of `L`, the
/// rows of its blocks below the diagonal.
#[derive(Debug, Clone)]
pub(super) struct Pattern {
    /// `position[v]`: the place of variable `v` in the elimination order.
    position: Vec<usize>,
    /// Column `k`'s blocks are `rows[start[k]..start[k + 1]]`, positions in ascending order.
    start: Vec<usize>,
    rows: Vec<usize>,
    /// The block each elimination updates, in the order the factorization visits them
    /// (column `k`, then each pair of its rows `i > j`: the block in row `i` of column
    /// `j`): found once here rather than searched for at every factorization.
    targets: Vec<usize>,
}

/// Where the block coupling two variables is kept: `index` into the blocks below the
/// diagonal, transposed when the first variable is eliminated before the second.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Slot {
    index: usize,
    transposed: bool,
}

impl Pattern {
    /// The pattern of `variables` block rows joined by `edges` (pairs of distinct variables;
    /// repeats are allowed).
    pub(super) fn new(variables: usize, edges: impl IntoIterator<Item = (usize, usize)>) -> Self {
        // Each variable's neighbours, allocated once at their number.
        let edges: Vec<(usize, usize)> = edges.into_iter().filter(|(a, b)| a != b).collect();
        let mut degree = vec![0; variables];
        for &(a, b) in &edges {
            degree[a] += 1;
            degree[b] += 1;
        }
        let mut adjacency: Vec<Vec<usize>> =
            degree.iter().map(|&d| Vec::with_capacity(d)).collect();
        for (a, b) in edges {
            adjacency[a].push(b);
            adjacency[b].push(a);
        }
        for neighbours in &mut adjacency {
            neighbours.sort_unstable();
            neighbours.dedup();
        }
        let (order, columns) = minimum_degree(adjacency);
        let mut position = vec![0; variables];
        for (k, &v) in order.iter().enumerate() {
            position[v] = k;
        }
        let mut start = Vec::with_capacity(variables + 1);
        let mut rows = Vec::new();
        start.push(0);
        for column in columns {
            let first = rows.len();
            rows.extend(column.iter().map(|&v| position[v]));
            rows[first..].sort_unstable();
            start.push(rows.len());
        }
        let mut pattern = Self {
            position,
            start,
            rows,
            targets: Vec::new(),
        };
        pattern.targets = pattern.update_targets();
        pattern
    }

    /// The blocks the factorization updates, in its order (see `targets`).
    fn update_targets(&self) -> Vec<usize> {
        let mut targets = Vec::new();
        for k in 0..self.len() {
            let column = &self.rows[self.start[k]..self.start[k + 1]];
            for (s, &i) in column.iter().enumerate() {
                for &j in &column[..s] {
                    // Every pair of a column's rows is joined in the elimination graph; were
                    // one missing, the factorization would fail on it rather than panic.
                    targets.push(self.find(i, j).unwrap_or(usize::MAX));
                }
            }
        }
        targets
    }

    /// The number of variables.
    pub(super) fn len(&self) -> usize {
        self.position.len()
    }

    /// Where the block of row `a`, column `b` (variables, `a != b`) is kept; `None` when the
    /// two are not joined in the factor.
    pub(super) fn slot(&self, a: usize, b: usize) -> Option<Slot> {
        let (pa, pb) = (self.position[a], self.position[b]);
        let (row, column) = if pa > pb { (pa, pb) } else { (pb, pa) };
        self.find(row, column).map(|index| Slot {
            index,
            transposed: pa < pb,
        })
    }

    /// The index of the block in row `row` of column `column` (positions).
    fn find(&self, row: usize, column: usize) -> Option<usize> {
        let range = self.start[column]..self.start[column + 1];
        self.rows[range.clone()]
            .binary_search(&row)
            .ok()
            .map(|i| range.start + i)
    }
}

/// Eliminates the variable of least degree first, joining its neighbours (exact degrees on
/// the explicit elimination graph: the graphs here are small once the chain is gone). Gives
/// the order and, for each variable eliminated, its neighbours at that moment: the rows of
/// its column of the factor.
fn minimum_degree(mut adjacency: Vec<Vec<usize>>) -> (Vec<usize>, Vec<Vec<usize>>) {
    let n = adjacency.len();
    let mut eliminated = vec![false; n];
    let mut queue: BinaryHeap<Reverse<(usize, usize)>> = adjacency
        .iter()
        .enumerate()
        .map(|(v, neighbours)| Reverse((neighbours.len(), v)))
        .collect();
    let mut order = Vec::with_capacity(n);
    let mut columns = Vec::with_capacity(n);
    let mut merged = Vec::new();
    while let Some(Reverse((degree, v))) = queue.pop() {
        // An entry is stale when its variable went or its degree changed since.
        if eliminated[v] || adjacency[v].len() != degree {
            continue;
        }
        eliminated[v] = true;
        let neighbours = std::mem::take(&mut adjacency[v]);
        for &u in &neighbours {
            let before = adjacency[u].len();
            merge_without(&adjacency[u], &neighbours, u, v, &mut merged);
            std::mem::swap(&mut adjacency[u], &mut merged);
            if adjacency[u].len() != before {
                queue.push(Reverse((adjacency[u].len(), u)));
            }
        }
        order.push(v);
        columns.push(neighbours);
    }
    (order, columns)
}

/// Writes the sorted union of `a` and `b` without `u` and `v` into `out`.
fn merge_without(a: &[usize], b: &[usize], u: usize, v: usize, out: &mut Vec<usize>) {
    out.clear();
    out.reserve(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        let next = match (a.get(i), b.get(j)) {
            (Some(&x), Some(&y)) if x == y => {
                i += 1;
                j += 1;
                x
            }
            (Some(&x), Some(&y)) if x < y => {
                i += 1;
                x
            }
            (Some(&x), None) => {
                i += 1;
                x
            }
            (_, Some(&y)) => {
                j += 1;
                y
            }
            (None, None) => break,
        };
        if next != u && next != v {
            out.push(next);
        }
    }
}

/// Normal equations `H x = g` laid out on a [`Pattern`], filled block by block and then
/// factored in place.
#[derive(Debug, Clone)]
pub(super) struct Equations {
    /// By position: `H`'s diagonal blocks, then `L`'s.
    diagonal: Vec<Matrix3<f64>>,
    /// Parallel to the pattern's rows: the blocks below the diagonal, of `H` then of `L`.
    below: Vec<Matrix3<f64>>,
    /// By position.
    rhs: Vec<Vector3<f64>>,
}

impl Equations {
    /// Zero equations of `pattern`'s shape.
    pub(super) fn new(pattern: &Pattern) -> Self {
        Self {
            diagonal: vec![Matrix3::zeros(); pattern.len()],
            below: vec![Matrix3::zeros(); pattern.rows.len()],
            rhs: vec![Vector3::zeros(); pattern.len()],
        }
    }

    /// Sets every block back to zero, to be filled for the next step.
    pub(super) fn clear(&mut self) {
        self.diagonal.fill(Matrix3::zeros());
        self.below.fill(Matrix3::zeros());
        self.rhs.fill(Vector3::zeros());
    }

    /// Adds `block` to `H`'s diagonal block of variable `v` and `gradient` to its row of `g`.
    pub(super) fn add_diagonal(
        &mut self,
        pattern: &Pattern,
        v: usize,
        block: &Matrix3<f64>,
        gradient: &Vector3<f64>,
    ) {
        let p = pattern.position[v];
        self.diagonal[p] += block;
        self.rhs[p] += gradient;
    }

    /// Adds `block` to `H`'s block in the row of the slot's first variable and the column
    /// of its second (and so its transpose to the mirrored block).
    pub(super) fn add_coupling(&mut self, slot: Slot, block: &Matrix3<f64>) {
        if slot.transposed {
            self.below[slot.index] += block.transpose();
        } else {
            self.below[slot.index] += block;
        }
    }

    /// Factors `H = L L^T` and solves for `x`, by variable; `None` if `H` is not positive
    /// definite (a part of the graph that nothing holds in place).
    pub(super) fn solve(&mut self, pattern: &Pattern) -> Option<Vec<Vector3<f64>>> {
        self.factor(pattern)?;
        let by_position = self.substitute(pattern);
        Some(pattern.position.iter().map(|&p| by_position[p]).collect())
    }

    /// Right-looking block Cholesky: each column, once final, is taken out of the blocks
    /// after it. Every block it updates is in the pattern, which is the elimination graph's.
    fn factor(&mut self, pattern: &Pattern) -> Option<()> {
        let mut targets = pattern.targets.iter();
        for k in 0..pattern.len() {
            let (l, inverse) = cholesky(&self.diagonal[k])?;
            let inverse_transpose = inverse.transpose();
            let range = pattern.start[k]..pattern.start[k + 1];
            for s in range.clone() {
                self.below[s] *= inverse_transpose;
            }
            for s in range.clone() {
                let (i, lik) = (pattern.rows[s], self.below[s]);
                self.diagonal[i] -= lik * lik.transpose();
                for t in range.start..s {
                    let ljk = self.below[t];
                    let target = self.below.get_mut(*targets.next()?)?;
                    *target -= lik * ljk.transpose();
                }
            }
            self.diagonal[k] = l;
        }
        Some(())
    }

    /// Forward and back substitution through the factor; the solution by position.
    fn substitute(&self, pattern: &Pattern) -> Vec<Vector3<f64>> {
        let mut x = self.rhs.clone();
        for k in 0..pattern.len() {
            let l = &self.diagonal[k];
            let y = solve_lower(l, &x[k]);
            x[k] = y;
            for s in pattern.start[k]..pattern.start[k + 1] {
                let carried = self.below[s] * y;
                x[pattern.rows[s]] -= carried;
            }
        }
        for k in (0..pattern.len()).rev() {
            let mut y = x[k];
            for s in pattern.start[k]..pattern.start[k + 1] {
                y -= self.below[s].tr_mul(&x[pattern.rows[s]]);
            }
            x[k] = solve_upper_transposed(&self.diagonal[k], &y);
        }
        x
    }
}

/// The Cholesky factor `L` of a symmetric 3 x 3 block (its lower triangle read) and
/// `L^-1`; `None` unless the block is positive definite.
fn cholesky(a: &Matrix3<f64>) -> Option<(Matrix3<f64>, Matrix3<f64>)> {
    let positive = |v: f64| (v > 0.0 && v.is_finite()).then(|| v.sqrt());
    let l00 = positive(a[(0, 0)])?;
    let l10 = a[(1, 0)] / l00;
    let l20 = a[(2, 0)] / l00;
    let l11 = positive(a[(1, 1)] - l10 * l10)?;
    let l21 = (a[(2, 1)] - l20 * l10) / l11;
    let l22 = positive(a[(2, 2)] - l20 * l20 - l21 * l21)?;
    let l = Matrix3::new(l00, 0.0, 0.0, l10, l11, 0.0, l20, l21, l22);
    // Forward substitution on the identity's columns.
    let (i00, i11, i22) = (1.0 / l00, 1.0 / l11, 1.0 / l22);
    let i10 = -l10 * i00 * i11;
    let i21 = -l21 * i11 * i22;
    let i20 = -(l20 * i00 + l21 * i10) * i22;
    let inverse = Matrix3::new(i00, 0.0, 0.0, i10, i11, 0.0, i20, i21, i22);
    Some((l, inverse))
}

/// `L^-1 b` for a lower-triangular `L` with a positive diagonal.
fn solve_lower(l: &Matrix3<f64>, b: &Vector3<f64>) -> Vector3<f64> {
    let x0 = b.x / l[(0, 0)];
    let x1 = (b.y - l[(1, 0)] * x0) / l[(1, 1)];
    let x2 = (b.z - l[(2, 0)] * x0 - l[(2, 1)] * x1) / l[(2, 2)];
    Vector3::new(x0, x1, x2)
}

/// `L^-T b` for a lower-triangular `L` with a positive diagonal.
fn solve_upper_transposed(l: &Matrix3<f64>, b: &Vector3<f64>) -> Vector3<f64> {
    let x2 = b.z / l[(2, 2)];
    let x1 = (b.y - l[(2, 1)] * x2) / l[(1, 1)];
    let x0 = (b.x - l[(1, 0)] * x1 - l[(2, 0)] * x2) / l[(0, 0)];
    Vector3::new(x0, x1, x2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// A symmetric positive-definite block matrix on `edges`, dense, and the equations.
    fn system(n: usize, edges: &[(usize, usize)]) -> (DMatrix<f64>, DVector<f64>, Equations) {
        let pattern = Pattern::new(n, edges.iter().copied());
        let mut equations = Equations::new(&pattern);
        let mut dense = DMatrix::zeros(3 * n, 3 * n);
        let rhs = DVector::from_fn(3 * n, |i, _| (i as f64 * 0.7).sin());
        for v in 0..n {
            let d = Matrix3::new(9.0, 0.5, 0.2, 0.5, 8.0, 0.3, 0.2, 0.3, 7.0) * (1.0 + v as f64);
            let g = Vector3::new(rhs[3 * v], rhs[3 * v + 1], rhs[3 * v + 2]);
            equations.add_diagonal(&pattern, v, &d, &g);
            dense.fixed_view_mut::<3, 3>(3 * v, 3 * v).copy_from(&d);
        }
        for (e, &(a, b)) in edges.iter().enumerate() {
            let c = Matrix3::new(0.9, 0.1, -0.3, 0.2, -0.8, 0.1, 0.4, 0.2, 0.5)
                * (0.5 + e as f64 * 0.1);
            let slot = pattern.slot(a, b).expect("an edge is in the pattern");
            equations.add_coupling(slot, &c);
            let mut ab = dense.fixed_view_mut::<3, 3>(3 * a, 3 * b);
            ab += c;
            let mut ba = dense.fixed_view_mut::<3, 3>(3 * b, 3 * a);
            ba += c.transpose();
        }
        (dense, rhs, equations)
    }

    #[test]
    fn the_sparse_solve_matches_a_dense_one() {
        // A chain with couplings across it, some of them repeated and reversed.
        let n = 12;
        let mut edges: Vec<(usize, usize)> = (0..n - 1).map(|i| (i, i + 1)).collect();
        edges.extend([(0, 7), (9, 2), (3, 11), (5, 10), (10, 5), (1, 6)]);
        let (dense, rhs, mut equations) = system(n, &edges);
        let pattern = Pattern::new(n, edges.iter().copied());
        let x = equations.solve(&pattern).expect("positive definite");
        let expected = dense.cholesky().expect("positive definite").solve(&rhs);
        for v in 0..n {
            for k in 0..3 {
                assert!((x[v][k] - expected[3 * v + k]).abs() < 1e-10, "{v} {k}");
            }
        }
    }

    #[test]
    fn the_block_cholesky_factors_and_inverts() {
        let a = Matrix3::new(9.0, 0.5, 0.2, 0.5, 8.0, 0.3, 0.2, 0.3, 7.0);
        let (l, inverse) = cholesky(&a).expect("positive definite");
        assert!((l * l.transpose() - a).amax() < 1e-12);
        assert!((l * inverse - Matrix3::identity()).amax() < 1e-12);
        assert!(cholesky(&(a - Matrix3::identity() * 10.0)).is_none());
    }

    #[test]
    fn a_chain_is_factored_without_fill() {
        let n = 50;
        let pattern = Pattern::new(n, (0..n - 1).map(|i| (i, i + 1)));
        assert_eq!(pattern.rows.len(), n - 1);
    }

    #[test]
    fn a_matrix_that_is_not_positive_definite_is_refused() {
        let pattern = Pattern::new(2, [(0, 1)]);
        let mut equations = Equations::new(&pattern);
        let one = Vector3::new(1.0, 1.0, 1.0);
        equations.add_diagonal(&pattern, 0, &Matrix3::identity(), &one);
        equations.add_diagonal(&pattern, 1, &Matrix3::identity(), &one);
        let slot = pattern.slot(0, 1).expect("joined");
        equations.add_coupling(slot, &(Matrix3::identity() * 2.0));
        assert!(equations.solve(&pattern).is_none());
    }
}
