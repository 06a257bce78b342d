//! The ghost penalty of `ghost_faces.rs` on the faces of 3D cells: the
//! jump of the normal derivative of the step's displacement increment
//! across the faces of the cells at the material's edge, penalised with
//! `1/2 gamma M h int [[du/dn]]^2 dA` per component (the plane-strain
//! penalty per unit thickness is this one's on a prism one cell thick).
//!
//! On a face normal to axis `a`, the trilinear field's jump of normal
//! derivative is bilinear over the face: `(sum_k a_k phi_k) / h` with
//! `a_k` the second difference `u_0 - 2 u_1 + u_2` along the node line
//! through the face's corner `k` (across the face) and `phi_k` the face's
//! bilinear hats. The penalty is `1/2 gamma M h a^T Q a` with `Q` the
//! bilinear mass matrix of the unit square, `Q = (1/9) [[1, 1/2], [1/2,
//! 1]] (x) [[1, 1/2], [1/2, 1]]`: weight `gamma M h / 9` on the Kronecker
//! product. `M` is as in 2D: the mean `2 mu` of the points in the face's
//! two cells, a point that flowed lending
//! [`super::ghost_faces::YIELDED_SHARE`] of it.

use rayon::prelude::*;

use super::ghost_faces::{face_share, point_modulus};
use super::{Pattern, Side, StepTerm};
use crate::configuration::Configuration;
use crate::grid::{Basis, LatticeIndex, lattice_coordinates};
use crate::parallel;

/// The second difference across a face.
const D2: [f64; 3] = [1.0, -2.0, 1.0];

/// The 1D linear mass matrix on a unit interval, times 3.
const LINE: [[f64; 2]; 2] = [[1.0, 0.5], [0.5, 1.0]];

/// The faces of 3D cells to stabilise and the penalty's weight on each.
pub struct SolidGhostFaces {
    /// Per face, its twelve active nodes: the node lines across it (three
    /// nodes each) through its corners `(0, 0)`, `(1, 0)`, `(0, 1)`, `(1,
    /// 1)` in its two tangential axes.
    faces: Vec<[u32; 12]>,
    /// Per face, `gamma M h / 9`.
    weights: Vec<f64>,
}

impl SolidGhostFaces {
    /// The faces between two cells the material overlaps of which at least
    /// one is at the material's edge (a cell with a neighbour, across a
    /// face, an edge or a corner, that no point reaches), as in 2D
    /// ([`super::GhostFaces::new`]).
    pub fn new(start: &Configuration<'_, 3>, basis: Basis, gamma: f64) -> Self {
        let Configuration {
            grid, conn, points, ..
        } = *start;
        let lattice: Vec<[i64; 3]> = conn.nodes.iter().map(|&k| lattice_coordinates(k)).collect();
        let nodes = LatticeIndex::new(&lattice);
        let node = |c: [i64; 3]| nodes.get(c).map(|a| a as u32);
        let mut cells: Vec<[i64; 3]> = (0..points.len())
            .into_par_iter()
            .with_min_len(parallel::BOOKKEEPING)
            .flat_map_iter(|p| {
                let (lo, hi) = basis.cell_range(grid, points.position[p], points.support(p));
                (lo[0]..=hi[0]).flat_map(move |i| {
                    (lo[1]..=hi[1]).flat_map(move |j| (lo[2]..=hi[2]).map(move |k| [i, j, k]))
                })
            })
            .collect();
        cells.par_sort_unstable_by_key(|c| (c[0], c[1], c[2]));
        cells.dedup();
        cells.retain(|&c| corners(c).iter().all(|&n| node(n).is_some()));
        let reached = LatticeIndex::new(&cells);
        let active = |c: [i64; 3]| reached.get(c).is_some();
        let at_edge = |c: [i64; 3]| {
            (-1..=1).any(|di| {
                (-1..=1).any(|dj| (-1..=1).any(|dk| !active([c[0] + di, c[1] + dj, c[2] + dk])))
            })
        };
        let stiffest = points
            .materials
            .iter()
            .map(|m| 2.0 * m.elastic().mu)
            .fold(0.0, f64::max);
        let mut census = vec![(0.0, 0u32); cells.len()];
        for p in 0..points.len() {
            if let Some(c) = reached.get(grid.cell_of(points.position[p])) {
                census[c].0 += point_modulus(points, p) / stiffest;
                census[c].1 += 1;
            }
        }
        let weight = |a: [i64; 3], b: [i64; 3]| {
            let of = |c: [i64; 3]| reached.get(c).map_or((0.0, 0), |c| census[c]);
            gamma * stiffest * face_share(of(a), of(b)) * grid.h / 9.0
        };
        let (faces, weights) = cells
            .par_iter()
            .with_min_len(parallel::BOOKKEEPING)
            .flat_map_iter(|&c| {
                let edge = at_edge(c);
                (0..3).filter_map(move |axis| {
                    let mut next = c;
                    next[axis] += 1;
                    if !(active(next) && (edge || at_edge(next))) {
                        return None;
                    }
                    let (t1, t2) = ((axis + 1) % 3, (axis + 2) % 3);
                    let mut face = [0u32; 12];
                    for (k, (s1, s2)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
                        for m in 0..3 {
                            let mut n = c;
                            n[t1] += s1;
                            n[t2] += s2;
                            n[axis] += m;
                            face[3 * k + m as usize] = node(n)?;
                        }
                    }
                    Some((face, weight(c, next)))
                })
            })
            .unzip();
        Self { faces, weights }
    }
}

/// A cell's eight corner nodes.
fn corners(c: [i64; 3]) -> [[i64; 3]; 8] {
    std::array::from_fn(|k| {
        [
            c[0] + (k & 1) as i64,
            c[1] + ((k >> 1) & 1) as i64,
            c[2] + (k >> 2) as i64,
        ]
    })
}

/// The face's mass coupling between its corner lines `k` and `l`, times 9.
fn coupling(k: usize, l: usize) -> f64 {
    LINE[k & 1][l & 1] * LINE[k >> 1][l >> 1]
}

impl StepTerm<3> for SolidGhostFaces {
    fn side(&self) -> Side {
        Side::Stabilisation
    }

    fn coupling_groups(&self) -> Vec<Vec<u32>> {
        self.faces.iter().map(|f| f.to_vec()).collect()
    }

    /// Adds the penalty's force `K u` to `f`.
    fn add_force(&self, u: &[f64], f: &mut [f64]) {
        for (nodes, &weight) in self.faces.iter().zip(&self.weights) {
            for c in 0..3 {
                let second: [f64; 4] = std::array::from_fn(|k| {
                    (0..3)
                        .map(|m| D2[m] * u[3 * nodes[3 * k + m] as usize + c])
                        .sum()
                });
                for k in 0..4 {
                    let q: f64 = (0..4).map(|l| coupling(k, l) * second[l]).sum();
                    for m in 0..3 {
                        f[3 * nodes[3 * k + m] as usize + c] += weight * D2[m] * q;
                    }
                }
            }
        }
    }

    /// Adds the penalty's stiffness to tangent values in `pattern`'s layout
    /// (which must hold its coupling groups).
    fn add_stiffness(&self, _u: &[f64], pattern: &Pattern, values: &mut [f64]) {
        for (nodes, &weight) in self.faces.iter().zip(&self.weights) {
            for (p, &a) in nodes.iter().enumerate() {
                for (q, &b) in nodes.iter().enumerate() {
                    let k = weight * coupling(p / 3, q / 3) * D2[p % 3] * D2[q % 3];
                    let (base, stride) = pattern.block(a, b);
                    for c in 0..3 {
                        values[base + c + c * stride] += k;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The face's penalty on a field `u` given at its twelve nodes: the
    /// lines through `(y, z)` = (0,0), (1,0), (0,1), (1,1), each at x = 0,
    /// 1, 2 (a face at x = 1 between unit cells).
    fn energy(u: impl Fn([f64; 3]) -> [f64; 3]) -> f64 {
        let faces = SolidGhostFaces {
            faces: vec![std::array::from_fn(|i| i as u32)],
            weights: vec![1.0 / 9.0],
        };
        let flat: Vec<f64> = (0..12)
            .flat_map(|i| {
                let (k, m) = (i / 3, i % 3);
                u([m as f64, (k & 1) as f64, (k >> 1) as f64])
            })
            .collect();
        let mut f = vec![0.0; 36];
        faces.add_force(&flat, &mut f);
        0.5 * f.iter().zip(&flat).map(|(a, b)| a * b).sum::<f64>()
    }

    /// Any field linear over the two cells costs nothing; a kink at the
    /// face, `u_x = max(x - 1, 0)`, costs `1/2 gamma M h int 1^2 dA` = 1/2
    /// with `gamma M h = 1` (weight 1/9); a kink that grows across the
    /// face, `u_x = y max(x - 1, 0)`, costs `1/2 int y^2 dA` = 1/6.
    #[test]
    fn linear_fields_cost_nothing_and_a_kink_costs_its_jump_squared() {
        let linear = |[x, y, z]: [f64; 3]| {
            [
                0.3 + 0.2 * x - 0.7 * y + 0.1 * z,
                -0.1 + 0.5 * x + 0.4 * y,
                0.2 * z - 0.3 * x,
            ]
        };
        assert!(energy(linear).abs() < 1e-14);
        let kink = |[x, _, _]: [f64; 3]| [(x - 1.0).max(0.0), 0.0, 0.0];
        assert!((energy(kink) - 0.5).abs() < 1e-14);
        let growing = |[x, y, _]: [f64; 3]| [0.0, 0.0, y * (x - 1.0).max(0.0)];
        assert!((energy(growing) - 1.0 / 6.0).abs() < 1e-14);
    }

    /// The stiffness is the force's derivative: `K u = f(u)` for the
    /// penalty's quadratic energy, entry by entry on one face.
    #[test]
    fn the_stiffness_is_the_forces_derivative() {
        let (points, grid) = crate::fixtures::solid_box([0.0; 3], [1.0, 1.0, 1.0], 0.25, 0.5);
        let conn = crate::fixtures::solid_links(&points, &grid, Basis::Linear);
        let start = Configuration {
            grid: &grid,
            basis: Basis::Linear,
            conn: &conn,
            points: &points,
        };
        let ghost = SolidGhostFaces::new(&start, Basis::Linear, 0.5);
        assert!(!ghost.faces.is_empty());
        let pattern = Pattern::build(&conn, &ghost.coupling_groups());
        let mut k = vec![0.0; pattern.nnz()];
        ghost.add_stiffness(&[], &pattern, &mut k);
        let n = conn.n_dofs();
        let u: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 17) as f64 / 17.0 - 0.5)
            .collect();
        let mut f = vec![0.0; n];
        ghost.add_force(&u, &mut f);
        let mut ku = vec![0.0; n];
        for col in 0..n {
            for i in pattern.col_ptr[col]..pattern.col_ptr[col + 1] {
                ku[pattern.row_idx[i] as usize] += k[i] * u[col];
            }
        }
        let scale = f.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(scale > 0.0);
        for (a, b) in f.iter().zip(&ku) {
            assert!((a - b).abs() < 1e-12 * scale, "{a} {b}");
        }
    }
}
