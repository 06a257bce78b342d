//! The soft background of the tangent: a weak material over the cells the
//! points' domains overlap, which keeps a step's system regular when a
//! point alone reaches new nodes.

use rayon::prelude::*;

use super::{Pattern, Side, StepTerm};
use crate::configuration::Configuration;
use crate::grid::{Basis, node_key};
use crate::material::Elastic;
use crate::parallel;

/// A soft background material over every cell the material's point domains
/// overlap: small-strain elastic in the step's displacement increment, with
/// moduli `ratio` times the stiffest material's.
///
/// A node that only one or two points reach (a point has just crossed into
/// an empty cell at a free surface) has displacement modes that no point
/// resists: the tangent is singular there and the solve returns garbage
/// along them, which breaks Newton. The finite cell method fills the empty
/// part of cut cells with a soft material for the same reason. It enters
/// both the internal force (`K_soft u`) and the tangent, so Newton stays
/// quadratic (in the tangent alone, modes with small but real stiffness
/// would converge at a rate of about 1); the price is a stiffening of
/// relative size `ratio` in each step's increment (the grid forgets it at
/// the next reset).
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
    /// the linear basis), with `ratio` times the Lame constants of the
    /// `stiffest` material.
    pub fn new(start: &Configuration, basis: Basis, stiffest: &Elastic, ratio: f64) -> Self {
        let conn = start.conn;
        let keys = overlapped_cells(start, basis);
        let node = |i: i64, j: i64| {
            conn.nodes
                .binary_search(&node_key(i, j))
                .ok()
                .map(|a| a as u32)
        };
        let cells = keys
            .into_iter()
            .filter_map(|[i, j]| {
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
            k_cell: bilinear_cell_stiffness(ratio * stiffest.lambda, ratio * stiffest.mu),
        }
    }
}

impl StepTerm for SoftCells {
    fn side(&self) -> Side {
        Side::Stabilisation
    }

    /// Adds the soft cells' force `K_soft u` to `f`.
    fn add_force(&self, u: &[f64], f: &mut [f64]) {
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
    fn add_stiffness(&self, _u: &[f64], pattern: &Pattern, values: &mut [f64]) {
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

/// The cells (`[i, j]`, sorted) that any point's domain overlaps (its
/// containing cell for the linear basis).
pub(crate) fn overlapped_cells(start: &Configuration, basis: Basis) -> Vec<[i64; 2]> {
    let Configuration { grid, points, .. } = *start;
    // Each run of points' cells sorted and deduplicated first: neighbours
    // reach most of the same cells (16 a point for quadratic B-splines).
    let mut keys: Vec<[i64; 2]> = (0..points.len().div_ceil(parallel::BOOKKEEPING))
        .into_par_iter()
        .flat_map_iter(|run| {
            let first = run * parallel::BOOKKEEPING;
            let mut keys: Vec<[i64; 2]> = (first
                ..(first + parallel::BOOKKEEPING).min(points.len()))
                .flat_map(|p| {
                    let (lo, hi) = basis.cell_range(grid, points.position[p], points.support(p));
                    let range = |d: usize| lo[d]..=hi[d];
                    let ys = range(1);
                    range(0).flat_map(move |i| ys.clone().map(move |j| [i, j]))
                })
                .collect();
            keys.sort_unstable_by(by_rows);
            keys.dedup();
            keys
        })
        .collect();
    keys.par_sort_unstable_by(by_rows);
    keys.dedup();
    keys
}

/// Cells by `i`, then `j`: `[i64; 2]`'s own order, but sorted 5-10%
/// faster (arrays compare as slices).
fn by_rows(a: &[i64; 2], b: &[i64; 2]) -> std::cmp::Ordering {
    (a[0], a[1]).cmp(&(b[0], b[1]))
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
