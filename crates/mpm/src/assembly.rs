//! Per-step grid data and the assembly of forces and tangent stiffness.
//!
//! At the start of a load step the grid is reset: every point's shape
//! functions are evaluated at its position, the nodes they touch become the
//! step's active nodes (numbered `0..n` in key order), and the sparsity
//! pattern of the stiffness matrix is built once. Every Newton iteration of
//! the step reuses all of it; only the values change.
//!
//! The matrix is stored in compressed sparse columns with a full (both
//! triangles) pattern. Degree of freedom `2a + c` is component `c` of active
//! node `a`. The rows of column `2b + c` are the DOFs of the nodes adjacent to
//! `b` (sharing a point), in node order, both components per node, so the
//! entry `(2a + r, 2b + c)` sits at `col_ptr[2b + c] + 2k + r` where `k` is
//! the position of `a` in `b`'s neighbour list.

use rayon::prelude::*;

use crate::basis::{Basis, Grid, NodeKey, NodeWeight, node_key};
use crate::material::Response;
use crate::points::MaterialPoints;

/// A point's view of one active node.
#[derive(Debug, Clone, Copy)]
pub struct Link {
    /// Active node index.
    pub node: u32,
    /// Shape function value.
    pub n: f64,
    /// Shape function gradient in the step's start configuration.
    pub grad: [f64; 2],
}

/// Shape functions of every point on the active nodes of one load step.
#[derive(Debug, Clone, Default)]
pub struct Connectivity {
    /// Active node keys, sorted.
    pub nodes: Vec<NodeKey>,
    /// `links[offsets[p]..offsets[p + 1]]` are point `p`'s nodes.
    pub offsets: Vec<usize>,
    pub links: Vec<Link>,
}

const CHUNK: usize = 4096;

impl Connectivity {
    /// Evaluates every point's shape functions, keeping the nodes for which
    /// `in_grid` holds: the grid ends there, as a finite mesh would.
    pub fn build(
        grid: &Grid,
        basis: Basis,
        points: &MaterialPoints,
        in_grid: impl Fn(NodeKey) -> bool + Sync,
    ) -> Self {
        let n = points.len();
        let chunks: Vec<(Vec<usize>, Vec<NodeWeight>)> = (0..n)
            .into_par_iter()
            .chunks(CHUNK)
            .map(|idx| {
                let mut counts = Vec::with_capacity(idx.len());
                let mut weights = Vec::with_capacity(idx.len() * 9);
                for p in idx {
                    let before = weights.len();
                    basis.eval(grid, points.position[p], points.half_width(p), &mut weights);
                    let mut k = before;
                    for i in before..weights.len() {
                        if in_grid(weights[i].node) {
                            weights[k] = weights[i];
                            k += 1;
                        }
                    }
                    weights.truncate(k);
                    counts.push(weights.len() - before);
                }
                (counts, weights)
            })
            .collect();
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0);
        let mut weights = Vec::with_capacity(chunks.iter().map(|c| c.1.len()).sum());
        for (counts, w) in chunks {
            for c in counts {
                offsets.push(offsets.last().unwrap() + c);
            }
            weights.extend(w);
        }
        let mut nodes: Vec<NodeKey> = weights.par_iter().map(|w| w.node).collect();
        nodes.par_sort_unstable();
        nodes.dedup();
        let links = weights
            .par_iter()
            .map(|w| Link {
                node: nodes
                    .binary_search(&w.node)
                    .expect("every linked node is active") as u32,
                n: w.n,
                grad: w.grad,
            })
            .collect();
        Self {
            nodes,
            offsets,
            links,
        }
    }

    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    pub fn n_dofs(&self) -> usize {
        2 * self.nodes.len()
    }

    pub fn point_links(&self, p: usize) -> &[Link] {
        &self.links[self.offsets[p]..self.offsets[p + 1]]
    }

    pub fn n_points(&self) -> usize {
        self.offsets.len() - 1
    }
}

/// Sparsity of the stiffness matrix, in faer's compressed-column form.
#[derive(Debug, Clone, Default)]
pub struct Pattern {
    /// Neighbours of node `b` are `neighbours[first[b]..first[b + 1]]`, sorted.
    first: Vec<usize>,
    neighbours: Vec<u32>,
    pub col_ptr: Vec<usize>,
    pub row_idx: Vec<usize>,
}

impl Pattern {
    /// Two nodes are neighbours when some point links to both.
    /// Two nodes are also neighbours when they share one of the `groups`
    /// (couplings that do not come from points, e.g. boundary loads).
    pub fn build(conn: &Connectivity, groups: &[Vec<u32>]) -> Self {
        let n_nodes = conn.n_nodes();
        let mut node_groups: Vec<Vec<u32>> =
            vec![Vec::new(); if groups.is_empty() { 0 } else { n_nodes }];
        for (g, members) in groups.iter().enumerate() {
            for &a in members {
                node_groups[a as usize].push(g as u32);
            }
        }
        // Node -> points incidence, in compressed form.
        let mut start = vec![0usize; n_nodes + 1];
        for l in &conn.links {
            start[l.node as usize + 1] += 1;
        }
        for i in 0..n_nodes {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut incident = vec![0u32; conn.links.len()];
        for p in 0..conn.n_points() {
            for l in conn.point_links(p) {
                incident[fill[l.node as usize]] = p as u32;
                fill[l.node as usize] += 1;
            }
        }
        let lists: Vec<Vec<u32>> = (0..n_nodes)
            .into_par_iter()
            .map(|b| {
                let mut nb: Vec<u32> = incident[start[b]..start[b + 1]]
                    .iter()
                    .flat_map(|&p| conn.point_links(p as usize).iter().map(|l| l.node))
                    .collect();
                if let Some(gs) = node_groups.get(b) {
                    nb.extend(gs.iter().flat_map(|&g| groups[g as usize].iter().copied()));
                }
                nb.sort_unstable();
                nb.dedup();
                nb
            })
            .collect();
        let mut first = Vec::with_capacity(n_nodes + 1);
        first.push(0);
        for l in &lists {
            first.push(first.last().unwrap() + l.len());
        }
        let neighbours: Vec<u32> = lists.into_iter().flatten().collect();
        let mut col_ptr = Vec::with_capacity(2 * n_nodes + 1);
        let mut row_idx = Vec::with_capacity(4 * neighbours.len());
        col_ptr.push(0);
        for b in 0..n_nodes {
            let nb = &neighbours[first[b]..first[b + 1]];
            for _component in 0..2 {
                row_idx.extend(
                    nb.iter()
                        .flat_map(|&a| [2 * a as usize, 2 * a as usize + 1]),
                );
                col_ptr.push(row_idx.len());
            }
        }
        Self {
            first,
            neighbours,
            col_ptr,
            row_idx,
        }
    }

    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Index in the values array of the 2x2 block's entry `(0, 0)` for row
    /// node `a` and column node `b`; entry `(r, c)` is at
    /// `block(a, b) + r + c * 2 * degree(b)`.
    #[inline]
    fn block(&self, a: u32, b: u32) -> (usize, usize) {
        self.try_block(a, b).expect("linked nodes are neighbours")
    }

    fn try_block(&self, a: u32, b: u32) -> Option<(usize, usize)> {
        let nb = &self.neighbours[self.first[b as usize]..self.first[b as usize + 1]];
        let k = nb.binary_search(&a).ok()?;
        Some((self.col_ptr[2 * b as usize] + 2 * k, 2 * nb.len()))
    }

    /// Adds `value` at `(row, col)` (DOF indices); returns false, adding
    /// nothing, if the entry is outside the pattern.
    pub fn add(&self, values: &mut [f64], row: usize, col: usize, value: f64) -> bool {
        match self.try_block((row / 2) as u32, (col / 2) as u32) {
            Some((base, stride)) => {
                values[base + row % 2 + (col % 2) * stride] += value;
                true
            }
            None => false,
        }
    }
}

/// Internal force `f_a = sum_p V0_p P_p g_pa` over all active DOFs.
pub fn internal_force(
    conn: &Connectivity,
    points: &MaterialPoints,
    responses: &[Response],
) -> Vec<f64> {
    scatter_sum(conn.n_points(), conn.n_dofs(), |p, f| {
        let v0 = points.volume0[p];
        let pk = &responses[p].p;
        for l in conn.point_links(p) {
            let a = 2 * l.node as usize;
            f[a] += v0 * (pk[(0, 0)] * l.grad[0] + pk[(0, 1)] * l.grad[1]);
            f[a + 1] += v0 * (pk[(1, 0)] * l.grad[0] + pk[(1, 1)] * l.grad[1]);
        }
    })
}

/// Body force `f_a = sum_p m_p N_pa g`.
pub fn body_force(conn: &Connectivity, points: &MaterialPoints, gravity: [f64; 2]) -> Vec<f64> {
    scatter_sum(conn.n_points(), conn.n_dofs(), |p, f| {
        let m = points.mass[p];
        for l in conn.point_links(p) {
            let a = 2 * l.node as usize;
            f[a] += m * l.n * gravity[0];
            f[a + 1] += m * l.n * gravity[1];
        }
    })
}

/// Values of the tangent stiffness
/// `K_(ai),(bj) = sum_p V0_p g_pa,I A_p[(2i+I),(2j+J)] g_pb,J`
/// in the layout of `pattern`.
pub fn stiffness(
    conn: &Connectivity,
    pattern: &Pattern,
    points: &MaterialPoints,
    responses: &[Response],
) -> Vec<f64> {
    scatter_sum(conn.n_points(), pattern.nnz(), |p, k| {
        let v0 = points.volume0[p];
        let t = &responses[p].tangent;
        let links = conn.point_links(p);
        for lb in links {
            // q[2i+I][j] = V0 sum_J A[(2i+I),(2j+J)] g_b,J
            let mut q = [[0.0; 2]; 4];
            for (row, qr) in q.iter_mut().enumerate() {
                for (j, qrj) in qr.iter_mut().enumerate() {
                    *qrj = v0 * (t[(row, 2 * j)] * lb.grad[0] + t[(row, 2 * j + 1)] * lb.grad[1]);
                }
            }
            for la in links {
                let (base, stride) = pattern.block(la.node, lb.node);
                for i in 0..2 {
                    for j in 0..2 {
                        k[base + i + j * stride] +=
                            la.grad[0] * q[2 * i][j] + la.grad[1] * q[2 * i + 1][j];
                    }
                }
            }
        }
    })
}

/// A soft background material over every cell the material's point domains
/// overlap: small-strain elastic in the step's displacement increment, with
/// moduli `ratio` times the stiffest material's.
///
/// A node that only one or two points reach (a point has just crossed into
/// an empty cell at a free surface) has displacement modes that no point
/// resists: the tangent is singular there and the solve returns garbage along
/// them, which breaks Newton (seen on a cantilever at 0.1 m cells, where the
/// tip corner point crossed into a new cell column). The finite cell method
/// fills the empty part of cut cells with a soft material for the same
/// reason. It enters both the internal force (`K_soft u`) and the tangent, so
/// Newton stays quadratic; the price is a stiffening of relative size
/// `ratio` in each step's increment (the grid forgets it at the next reset).
/// Adding it to the tangent only was tried: modes with small but real
/// stiffness then converge at a rate of about 1, and Newton stalls.
pub struct SoftCells {
    /// Active-node indices of each cell's corners: (i, j), (i+1, j), (i, j+1),
    /// (i+1, j+1).
    cells: Vec<[u32; 4]>,
    /// 8x8 stiffness of one bilinear cell of the soft material (independent
    /// of the cell size in 2D); DOF `2c + i` is component `i` of corner `c`.
    k_cell: [[f64; 8]; 8],
}

impl SoftCells {
    /// The cells overlapped by any point's domain (its containing cell for
    /// the linear basis), with a material of Lame constants `ratio *
    /// (lambda, mu)`.
    pub fn new(
        grid: &Grid,
        conn: &Connectivity,
        points: &MaterialPoints,
        basis: Basis,
        lambda: f64,
        mu: f64,
        ratio: f64,
    ) -> Self {
        let mut keys: Vec<(i64, i64)> = (0..points.len())
            .into_par_iter()
            .flat_map_iter(|p| {
                let x = points.position[p];
                let lp = match basis {
                    Basis::Linear => [0.0, 0.0],
                    // As in `Basis::eval`, which caps the domain at a cell.
                    Basis::Gimp => points.half_width(p).map(|l| l.min(grid.h)),
                };
                let range = |d: usize| {
                    let lo = ((x[d] - lp[d] - grid.origin[d]) / grid.h).floor() as i64;
                    let hi = ((x[d] + lp[d] - grid.origin[d]) / grid.h).floor() as i64;
                    lo..=hi
                };
                let ys = range(1);
                range(0).flat_map(move |i| ys.clone().map(move |j| (i, j)))
            })
            .collect();
        keys.par_sort_unstable();
        keys.dedup();
        let node = |i: i64, j: i64| {
            conn.nodes
                .binary_search(&node_key(i, j))
                .ok()
                .map(|a| a as u32)
        };
        let cells = keys
            .into_iter()
            .filter_map(|(i, j)| {
                Some([
                    node(i, j)?,
                    node(i + 1, j)?,
                    node(i, j + 1)?,
                    node(i + 1, j + 1)?,
                ])
            })
            .collect();
        Self {
            cells,
            k_cell: bilinear_cell_stiffness(ratio * lambda, ratio * mu),
        }
    }

    /// Adds the soft cells' force `K_soft u` to `f`.
    pub fn add_force(&self, u: &[f64], f: &mut [f64]) {
        for corners in &self.cells {
            for (ca, &a) in corners.iter().enumerate() {
                for i in 0..2 {
                    let mut sum = 0.0;
                    for (cb, &b) in corners.iter().enumerate() {
                        for j in 0..2 {
                            sum += self.k_cell[2 * ca + i][2 * cb + j] * u[2 * b as usize + j];
                        }
                    }
                    f[2 * a as usize + i] += sum;
                }
            }
        }
    }

    /// Adds the soft cells' stiffness to tangent values in `pattern`'s
    /// layout. Corners of a cell that a point's domain overlaps all link to
    /// that point, so every block exists in the pattern.
    pub fn add_to(&self, pattern: &Pattern, values: &mut [f64]) {
        for corners in &self.cells {
            for (cb, &b) in corners.iter().enumerate() {
                for (ca, &a) in corners.iter().enumerate() {
                    let (base, stride) = pattern.block(a, b);
                    for i in 0..2 {
                        for j in 0..2 {
                            values[base + i + j * stride] += self.k_cell[2 * ca + i][2 * cb + j];
                        }
                    }
                }
            }
        }
    }
}

/// Plane-strain stiffness of a square bilinear cell, 2x2 Gauss quadrature:
/// `K_(ai),(bj) = int lambda g_ai g_bj + mu (g_aj g_bi + delta_ij g_a . g_b)`.
fn bilinear_cell_stiffness(lambda: f64, mu: f64) -> [[f64; 8]; 8] {
    let mut k = [[0.0; 8]; 8];
    let g = 0.5 / 3f64.sqrt();
    for xi in [0.5 - g, 0.5 + g] {
        for eta in [0.5 - g, 0.5 + g] {
            // Gradients on the unit square; the cell size cancels in 2D.
            let grads = [
                [-(1.0 - eta), -(1.0 - xi)],
                [1.0 - eta, -xi],
                [-eta, 1.0 - xi],
                [eta, xi],
            ];
            for a in 0..4 {
                for b in 0..4 {
                    let dot = grads[a][0] * grads[b][0] + grads[a][1] * grads[b][1];
                    for i in 0..2 {
                        for j in 0..2 {
                            let delta = if i == j { dot } else { 0.0 };
                            k[2 * a + i][2 * b + j] += 0.25
                                * (lambda * grads[a][i] * grads[b][j]
                                    + mu * (grads[a][j] * grads[b][i] + delta));
                        }
                    }
                }
            }
        }
    }
    k
}

/// Sums per-point contributions into a vector of length `len`, in parallel:
/// one accumulator per worker thread, added at the end.
fn scatter_sum(n_points: usize, len: usize, add: impl Fn(usize, &mut [f64]) + Sync) -> Vec<f64> {
    let threads = rayon::current_num_threads().max(1);
    let per = n_points.div_ceil(threads).max(1);
    let parts: Vec<Vec<f64>> = (0..n_points.div_ceil(per))
        .into_par_iter()
        .map(|c| {
            let mut acc = vec![0.0; len];
            for p in c * per..((c + 1) * per).min(n_points) {
                add(p, &mut acc);
            }
            acc
        })
        .collect();
    let mut parts = parts.into_iter();
    let mut total = parts.next().unwrap_or_else(|| vec![0.0; len]);
    for part in parts {
        total
            .par_iter_mut()
            .zip(part.par_iter())
            .for_each(|(t, v)| *t += v);
    }
    total
}

/// Replaces the rows and columns of fixed DOFs by a scaled identity, so the
/// solve returns zero increments there.
pub fn constrain(pattern: &Pattern, values: &mut [f64], fixed: &[bool]) {
    let n = fixed.len();
    let mut diag_sum = 0.0;
    let mut diag_count = 0usize;
    for col in 0..n {
        for k in pattern.col_ptr[col]..pattern.col_ptr[col + 1] {
            if pattern.row_idx[k] == col && !fixed[col] {
                diag_sum += values[k].abs();
                diag_count += 1;
            }
        }
    }
    let scale = if diag_count > 0 {
        diag_sum / diag_count as f64
    } else {
        1.0
    };
    for col in 0..n {
        for k in pattern.col_ptr[col]..pattern.col_ptr[col + 1] {
            let row = pattern.row_idx[k];
            if fixed[row] || fixed[col] {
                values[k] = if row == col { scale } else { 0.0 };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn soft_cell_stiffness_has_exactly_the_three_rigid_modes_as_null_space() {
        // A bilinear element's stiffness is symmetric, annihilates the two
        // translations and the rotation, and has rank 8 - 3 = 5.
        let k = bilinear_cell_stiffness(1.0, 0.5);
        let m = nalgebra::SMatrix::<f64, 8, 8>::from_fn(|r, c| k[r][c]);
        assert!((m - m.transpose()).norm() < 1e-14);
        let corners = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        let modes = [
            nalgebra::SVector::<f64, 8>::from_fn(|r, _| if r % 2 == 0 { 1.0 } else { 0.0 }),
            nalgebra::SVector::<f64, 8>::from_fn(|r, _| if r % 2 == 1 { 1.0 } else { 0.0 }),
            nalgebra::SVector::<f64, 8>::from_fn(|r, _| {
                let c = corners[r / 2];
                if r % 2 == 0 { -c[1] } else { c[0] }
            }),
        ];
        for v in modes {
            assert!((m * v).norm() < 1e-13);
        }
        let rank = m
            .symmetric_eigenvalues()
            .iter()
            .filter(|e| e.abs() > 1e-10)
            .count();
        assert_eq!(rank, 5);
    }
}
