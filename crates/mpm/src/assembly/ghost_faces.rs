//! Ghost stabilisation of the cut cells at the material's edge: a penalty
//! on the jump of the normal derivative of the step's displacement
//! increment across the faces of those cells (Burman 2010, "Ghost
//! penalty", C. R. Math. 348; for implicit MPM, Coombs 2023, "Ghost
//! stabilisation of the material point method for stable quasi-static and
//! dynamic analysis of large deformation problems", IJNME 124).
//!
//! A node that only a sliver of material reaches has almost no stiffness,
//! and its spurious motion is written into the points as they cross into
//! its cells. The penalty ties such a node to its neighbours through the
//! smoothness of the bilinear grid field across faces: it vanishes for any
//! field linear over the two cells of a face, so it leaves rigid motion and
//! homogeneous deformation alone, and elsewhere it is as small as the jump
//! of the gradient, which is O(h) for a smooth increment.
//!
//! On a face between two cells, with `a` and `b` the second differences
//! `u_0 - 2 u_1 + u_2` of the increment along the two node lines that cross
//! the face (bottom and top for a vertical face), the bilinear field's
//! jump of normal derivative is `(a (1 - eta) + b eta) / h` along it, and
//! the penalty `1/2 gamma M h int [[du/dn]]^2 ds` is
//! `gamma M / 6 (a^2 + a b + b^2)` per component, whatever `h` (2D), with
//! `M` twice the shear modulus (`E` at `nu = 0`) of the material at the
//! face: the jumps are shear-like, and a bulk modulus near
//! incompressibility would lock the edges again.
//!
//! `M` is the mean over the points in the face's two cells of their
//! material's `2 mu`, times [`YIELDED_SHARE`] for a point that flowed
//! plastically in the last step. The penalty acts on the step's increment
//! with an elastic modulus, so where the soil flows at full weight it would
//! carry a load the soil does not, growing with the increment: a footing
//! pushed near collapse, a strength-reduction trial (one large increment).
//! Each material lends its own modulus, so a stiff body does not stiffen
//! the edge of a soft one beside it.

use super::{Pattern, Side, StepTerm};
use crate::configuration::Configuration;
use rayon::prelude::*;

use crate::grid::{Basis, LatticeIndex, node_coordinates};
use crate::parallel;
use crate::particles::{Dim, MaterialPoints, Space};

/// The faces to stabilise and the penalty's weight on each.
pub struct GhostFaces {
    /// Per face, its six active nodes: the node line crossing it on one side
    /// of its midpoint (three nodes across the face), then the other.
    faces: Vec<[u32; 6]>,
    /// Per face, `gamma M / 3`: `K = weight (D D^T (x) [[1, 1/2], [1/2,
    /// 1]])` per component, with `D = (1, -2, 1)`.
    weights: Vec<f64>,
}

/// The share of its material's modulus that a point which flowed
/// plastically in the last step lends the penalty. Not zero: a flowing
/// cell at the edge still needs the tie (at zero, Hill's cylinder under
/// arc-length inverted a point and a Drucker-Prager sample at its apex
/// blew up). Measured (docs/guide.md, Hard cases): the strength reduction
/// of the footing's clay at h = B/8 comes to +2.2% and +1.25% of 4/3 at
/// 0.2 (+2.7% and +4.1% at 1, +1.25% at 0.1), while the worst point of the
/// confined Mohr-Coulomb sample sheared in two stages moves off its
/// confinement by 0.82% (0.33% at 1, 1.02% at 0.1) and off its strength by
/// 0.75%: the largest cut that keeps that sample within 1%.
pub const YIELDED_SHARE: f64 = 0.2;

/// The second difference across a face.
const D: [f64; 3] = [1.0, -2.0, 1.0];

impl GhostFaces {
    /// The faces between two cells the material overlaps of which at least
    /// one is at the material's edge (a cell with a neighbour, sides or
    /// corners, that no point reaches), weighted by `gamma M` with `M` the
    /// modulus of the points in the face's two cells (module docs). A
    /// cell counts as reached when a point's domain overlaps it and its
    /// four corners are active nodes (a domain that ends on a grid line
    /// does not reach the cell beyond).
    pub fn new(start: &Configuration, basis: Basis, gamma: f64) -> Self {
        let Configuration {
            grid, conn, points, ..
        } = *start;
        let lattice: Vec<[i64; 2]> = conn.nodes.iter().map(|&k| node_coordinates(k)).collect();
        let nodes = LatticeIndex::new(&lattice);
        let node = |i: i64, j: i64| nodes.get([i, j]).map(|a| a as u32);
        let mut cells = super::soft_cells::overlapped_cells(start, basis);
        cells.retain(|&[i, j]| {
            [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)]
                .iter()
                .all(|&(a, b)| node(a, b).is_some())
        });
        let reached = LatticeIndex::new(&cells);
        let active = |(i, j): (i64, i64)| reached.get([i, j]).is_some();
        let at_edge =
            |(i, j): (i64, i64)| (-1..=1).any(|di| (-1..=1).any(|dj| !active((i + di, j + dj))));
        let stiffest = points
            .materials
            .iter()
            .map(|m| 2.0 * m.elastic().mu)
            .fold(0.0, f64::max);
        // Per reached cell, the sum of its points' moduli relative to the
        // stiffest (so one elastic material weighs exactly as before), and
        // their count.
        let mut census = vec![(0.0, 0u32); cells.len()];
        for p in 0..points.len() {
            let [i, j] = grid.cell_of(points.position[p]);
            if let Some(c) = reached.get([i, j]) {
                census[c].0 += point_modulus(points, p) / stiffest;
                census[c].1 += 1;
            }
        }
        // A face's weight from its two cells' points (the stiffest
        // material's when neither holds a point's centre).
        let weight = |a: (i64, i64), b: (i64, i64)| {
            let of = |c: (i64, i64)| reached.get([c.0, c.1]).map_or((0.0, 0), |c| census[c]);
            gamma * (stiffest * face_share(of(a), of(b))) / 3.0
        };
        let (faces, weights) = cells
            .par_iter()
            .with_min_len(parallel::BOOKKEEPING)
            .flat_map_iter(|&[i, j]| {
                let edge = at_edge((i, j));
                // The face to the right: node rows j and j + 1, columns i..=i+2.
                let right = (active((i + 1, j)) && (edge || at_edge((i + 1, j))))
                    .then(|| {
                        let row = |r: i64| [node(i, r), node(i + 1, r), node(i + 2, r)];
                        collect(row(j), row(j + 1)).map(|f| (f, weight((i, j), (i + 1, j))))
                    })
                    .flatten();
                // The face above: node columns i and i + 1, rows j..=j+2.
                let above = (active((i, j + 1)) && (edge || at_edge((i, j + 1))))
                    .then(|| {
                        let column = |c: i64| [node(c, j), node(c, j + 1), node(c, j + 2)];
                        collect(column(i), column(i + 1)).map(|f| (f, weight((i, j), (i, j + 1))))
                    })
                    .flatten();
                right.into_iter().chain(above)
            })
            .unzip();
        Self { faces, weights }
    }
}

/// A face's share of the stiffest modulus from its two cells' census (the
/// sum of their points' moduli relative to the stiffest, and their count):
/// the points' mean, or the stiffest's when neither cell holds a point's
/// centre.
pub(super) fn face_share((sa, na): (f64, u32), (sb, nb): (f64, u32)) -> f64 {
    if na + nb == 0 {
        1.0
    } else {
        (sa + sb) / f64::from(na + nb)
    }
}

/// What point `p` lends the penalty: its material's `2 mu`, times
/// [`YIELDED_SHARE`] when it flowed plastically in the last step.
pub(super) fn point_modulus<const D: usize>(points: &MaterialPoints<D>, p: usize) -> f64
where
    Dim<D>: Space<D>,
{
    let m = 2.0 * points.materials[points.material[p] as usize].elastic().mu;
    if points.yielding[p] {
        YIELDED_SHARE * m
    } else {
        m
    }
}

impl StepTerm for GhostFaces {
    fn side(&self) -> Side {
        Side::Stabilisation
    }

    /// The node groups each face couples (for the stiffness pattern).
    fn coupling_groups(&self) -> Vec<Vec<u32>> {
        self.faces.iter().map(|f| f.to_vec()).collect()
    }

    /// Adds the penalty's force `K u` to `f`.
    fn add_force(&self, u: &[f64], f: &mut [f64]) {
        for (nodes, &weight) in self.faces.iter().zip(&self.weights) {
            for c in 0..2 {
                let second = |line: &[u32]| -> f64 {
                    line.iter()
                        .zip(D)
                        .map(|(&n, d)| d * u[2 * n as usize + c])
                        .sum()
                };
                let (a, b) = (second(&nodes[..3]), second(&nodes[3..]));
                for k in 0..3 {
                    f[2 * nodes[k] as usize + c] += weight * D[k] * (a + 0.5 * b);
                    f[2 * nodes[3 + k] as usize + c] += weight * D[k] * (b + 0.5 * a);
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
                    let lines = if (p < 3) == (q < 3) { 1.0 } else { 0.5 };
                    let k = weight * lines * D[p % 3] * D[q % 3];
                    let (base, stride) = pattern.block(a, b);
                    for c in 0..2 {
                        values[base + c + c * stride] += k;
                    }
                }
            }
        }
    }
}

/// Six nodes, if all are active.
fn collect(first: [Option<u32>; 3], second: [Option<u32>; 3]) -> Option<[u32; 6]> {
    let mut out = [0; 6];
    for (o, n) in out.iter_mut().zip(first.into_iter().chain(second)) {
        *o = n?;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures;

    /// Each face weighs `gamma M / 3` with `M` its two cells' points' mean
    /// `2 mu`: one elastic material gives exactly its own (as before the
    /// weights were per face), a point that yielded lends `YIELDED_SHARE`
    /// of it, and a face between two materials their points' mean.
    #[test]
    fn a_face_weighs_the_modulus_of_its_cells_points() {
        let case = fixtures::block([2.0, 1.0], [8, 4], 0.5, [0.1, 0.13]);
        let mut sim = fixtures::simulation(&case);
        let m = 2.0 * sim.points.materials[0].elastic().mu;
        let weights = |sim: &crate::Simulation| {
            let conn = sim.reset_grid();
            let start = sim.configuration(&conn);
            GhostFaces::new(&start, sim.basis, 0.5).weights
        };
        let elastic = weights(&sim);
        assert!(!elastic.is_empty());
        assert!(elastic.iter().all(|&w| w == 0.5 * m / 3.0), "{elastic:?}");
        sim.points.yielding.iter_mut().for_each(|y| *y = true);
        let flowing = weights(&sim);
        assert!(
            flowing
                .iter()
                .all(|&w| (w / (0.5 * YIELDED_SHARE * m / 3.0) - 1.0).abs() < 1e-12)
        );
        // A second material, four times as stiff, for the points right of
        // x = 1: faces of cells wholly on one side weigh its modulus or
        // the first's; faces across mixed cells lie between.
        sim.points.yielding.iter_mut().for_each(|y| *y = false);
        let mut stiff = sim.points.materials[0];
        if let crate::material::Material::Hencky(c) = &mut stiff {
            c.mu *= 4.0;
            c.lambda *= 4.0;
        }
        sim.points.materials.push(stiff);
        for p in 0..sim.points.len() {
            if sim.points.position[p][0] > 1.0 {
                sim.points.material[p] = 1;
            }
        }
        let mixed = weights(&sim);
        let (soft, hard) = (0.5 * m / 3.0, 0.5 * 4.0 * m / 3.0);
        let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-12;
        assert!(mixed.iter().any(|&w| close(w, soft)));
        assert!(mixed.iter().any(|&w| close(w, hard)));
        assert!(mixed.iter().any(|&w| w > 1.01 * soft && w < 0.99 * hard));
        assert!(mixed.iter().all(|&w| w > 0.99 * soft && w < 1.01 * hard));
    }

    /// The face's penalty on a field given at the six nodes.
    fn energy(weight: f64, u: [[f64; 2]; 6]) -> f64 {
        let faces = GhostFaces {
            faces: vec![[0, 1, 2, 3, 4, 5]],
            weights: vec![weight],
        };
        let flat: Vec<f64> = u.iter().flatten().copied().collect();
        let mut f = vec![0.0; 12];
        faces.add_force(&flat, &mut f);
        0.5 * f.iter().zip(&flat).map(|(a, b)| a * b).sum::<f64>()
    }

    /// Nodes of a vertical face at x = 1 between cells [0, 1] and [1, 2]
    /// (unit cells): bottom row (0,0), (1,0), (2,0), then the top row.
    const NODES: [[f64; 2]; 6] = [
        [0.0, 0.0],
        [1.0, 0.0],
        [2.0, 0.0],
        [0.0, 1.0],
        [1.0, 1.0],
        [2.0, 1.0],
    ];

    /// Any field linear over the two cells (rigid motion, homogeneous
    /// strain) costs nothing; a kink at the face costs what the integral
    /// of the jump squared gives: a jump of 1 in du_x/dx all along the
    /// face (u_x = max(x - 1, 0)) costs gamma M / 2 with weight gamma M / 3.
    #[test]
    fn linear_fields_cost_nothing_and_a_kink_costs_its_jump_squared() {
        let linear = NODES.map(|[x, y]| [0.3 + 0.2 * x - 0.7 * y, -0.1 + 0.5 * x + 0.4 * y]);
        assert!(energy(1.0, linear).abs() < 1e-14);
        let kink = NODES.map(|[x, _]| [(x - 1.0).max(0.0), 0.0]);
        // 1/2 gamma M h int_0^1 1^2 ds with h = 1, gamma M = 3 weight.
        assert!((energy(1.0 / 3.0, kink) - 0.5).abs() < 1e-14);
    }
}
