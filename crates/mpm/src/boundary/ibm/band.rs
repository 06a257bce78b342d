//! The band terms of one load step: each anchor's penalty
//! `(4/3) P A_nn P / delta` per unit length, integrated at the anchor with
//! the bilinear shape functions of the step (an averaged support's summed
//! over each piece into one constraint on the piece's mean displacement,
//! each anchor counted for the part of its span under the support), and
//! the ghost ties of the nodes beyond the boundary of pointwise supports.

use std::any::Any;
use std::collections::{BTreeMap, HashMap};

use nalgebra::{SMatrix, SVector};

use super::anchors::{Anchor, Carried, projection};
use super::ghost_ties::{self, GHOST_STENCIL, GhostTie, nodes_beyond};
use crate::assembly::{Pattern, Side, StepTerm};
use crate::boundary::current_ring;
use crate::boundary::curve::{bezier_derivative, local_segment};
use crate::boundary::detection::BoundaryLoop;
use crate::boundary::quadrature::hat_shares;
use crate::configuration::Configuration;
use crate::grid::NodeKey;
use crate::report::SupportTraction;

/// Default band width `delta` in cells (see the module docs).
pub const DEFAULT_BAND_WIDTH: f64 = 1e-2;

/// One constraint of the band in a load step: an anchor's own, or the
/// average over the anchors of one piece of an averaged support.
#[derive(Debug, Clone)]
pub(super) struct BandPoint<const D: usize> {
    /// The case's support it stands for.
    pub(super) support: usize,
    /// Its shares of the active nodes are `shares[first..last]`.
    pub(super) first: usize,
    pub(super) last: usize,
    /// `dGamma * 4 / (3 delta) * P A_nn P`.
    pub(super) stiffness: SMatrix<f64, D, D>,
    /// The length (in 3D, area) of boundary it stands for, `dGamma`
    /// (summed over a piece), and its place there at the step's start
    /// (weighted by it).
    pub(super) length: f64,
    pub(super) at: [f64; D],
    /// Displacement increment the boundary should make in this step.
    pub(super) target: [f64; D],
}

/// The band terms of one load step, on the curves of plane strain or
/// (`D = 3`) the surfaces of 3D ([`super::surface_anchors`]).
#[derive(Debug, Clone, Default)]
pub struct BandTerms<const D: usize = 2> {
    pub(super) points: Vec<BandPoint<D>>,
    pub(super) shares: Vec<(usize, f64)>,
    /// Each anchor with active nodes and its own shares, `(anchor, first,
    /// last)` into `shares`: what carries it at the end of the step.
    pub(super) carriers: Vec<(usize, usize, usize)>,
    pub(super) ghosts: Vec<GhostTie<D>>,
    /// The stiffness of the band points and the ghost ties summed over
    /// those on the same nodes ([`BandTerms::couple`]).
    coupled: Vec<Coupled<D>>,
    /// `3 delta / (4 h)`: turns band forces into a cell's material forces.
    pub(super) material_scale: f64,
}

/// The stiffness `sum N_a N_b K` of the band points (and ghost ties) on
/// one list of nodes: the anchors in a cell share theirs, so the tangent
/// takes a cell's sum once rather than each anchor's (some 64 where a 3D
/// surface crosses a cell).
#[derive(Debug, Clone)]
struct Coupled<const D: usize> {
    nodes: Vec<usize>,
    /// `blocks[i * n + j]` couples row node `nodes[i]` with column node
    /// `nodes[j]`, `n` the nodes' count.
    blocks: Vec<SMatrix<f64, D, D>>,
}

impl BandTerms {
    pub fn new(
        start: &Configuration,
        loops: &[BoundaryLoop],
        anchors: &[Anchor],
        band_width: f64,
        load_factor: f64,
    ) -> Self {
        let Configuration {
            grid, conn, points, ..
        } = *start;
        let mut terms = BandTerms::empty(grid.h, band_width);
        let mut weights = Vec::with_capacity(4);
        // Nodes just beyond a pointwise support's boundary, with the anchor
        // that saw them first.
        let mut beyond: BTreeMap<NodeKey, usize> = BTreeMap::new();
        // The current data points of the loops with anchors.
        let mut rings: BTreeMap<usize, Vec<[f64; 2]>> = BTreeMap::new();
        let mut pieces: BTreeMap<usize, PieceSum<2>> = BTreeMap::new();
        for (i, a) in anchors.iter().enumerate() {
            let current = rings
                .entry(a.loop_index)
                .or_insert_with(|| current_ring(&loops[a.loop_index], points));
            let first = terms.shares.len();
            if !hat_shares(
                start.basis,
                grid,
                a.position(),
                &conn.nodes,
                &mut weights,
                &mut terms.shares,
            ) {
                continue;
            }
            let d = bezier_derivative(&local_segment(current, a.segment), a.t);
            let span = [a.weight * d[0], a.weight * d[1]];
            let inside = a.share_inside(span);
            terms.carriers.push((i, first, terms.shares.len()));
            if inside <= 0.0 {
                continue; // slid out from under an averaged support
            }
            let length = inside * span[0].hypot(span[1]);
            let a_nn = a.acoustic_tensor(points);
            // An averaged support's anchors (a rigid footing's) find no
            // nodes to tie: the ties would resist the soil's flow past its
            // edge (docs/ibm.md, Why the ghost ties). A node also beyond a
            // pointwise support is still tied by that one.
            if a.piece.is_none() {
                let cells = start.basis.reach_beyond_boundary();
                for key in nodes_beyond(grid, a.position(), a.normal, cells) {
                    if conn.nodes.binary_search(&key).is_ok() {
                        beyond.entry(key).or_insert(i);
                    }
                }
            }
            let held = projection(a.fix, a.normal);
            let stiffness = held * a_nn * held * (length * 4.0 / (3.0 * band_width));
            let target = {
                let u = a.prescribed_at(load_factor);
                [u[0] - a.moved[0], u[1] - a.moved[1]]
            };
            let point = BandPoint {
                support: a.support,
                first,
                last: terms.shares.len(),
                stiffness,
                length,
                at: a.position(),
                target,
            };
            terms.add_point(&mut pieces, a.piece, point);
        }
        terms.add_pieces(pieces);
        terms.ghosts = ghost_ties::ties(start, loops, anchors, &beyond, &rings);
        terms.couple();
        terms
    }

    /// The traction each band constraint exerts on the body at the
    /// converged increment `u`, `-K (u_h - target) / dGamma`, where the
    /// constraint's place has moved to. The ghost ties' forces, which
    /// the reactions include, are left out: they stand for no length.
    pub fn tractions(&self, u: &[f64]) -> Vec<SupportTraction> {
        let mut out: Vec<SupportTraction> = (self.points.iter())
            .map(|b| {
                let (v, force) = (self.increment(b, u), self.force(b, u));
                SupportTraction {
                    support: b.support,
                    at: [b.at[0] + v[0], b.at[1] + v[1]],
                    length: b.length,
                    traction: [-force[0] / b.length, -force[1] / b.length],
                }
            })
            .collect();
        out.sort_by_key(|t| t.support);
        out
    }
}

impl<const D: usize> BandTerms<D> {
    /// The grid's displacement increment `u` interpolated with the shares
    /// `shares[first..last]`.
    fn interpolate(&self, first: usize, last: usize, u: &[f64]) -> [f64; D] {
        let mut v = [0.0; D];
        for &(a, n) in &self.shares[first..last] {
            for d in 0..D {
                v[d] += n * u[D * a + d];
            }
        }
        v
    }

    /// The grid's displacement increment `u` at a band point (its average
    /// over the piece, for an averaged one).
    fn increment(&self, b: &BandPoint<D>, u: &[f64]) -> [f64; D] {
        self.interpolate(b.first, b.last, u)
    }

    /// `K (u_h - target)` at a band point: the band's contribution to the
    /// internal force there (the force on the body is its negative).
    fn force(&self, b: &BandPoint<D>, u: &[f64]) -> SVector<f64, D> {
        let v = self.increment(b, u);
        b.stiffness * SVector::<f64, D>::from_fn(|d, _| v[d] - b.target[d])
    }

    /// Moves the anchors with the converged increment `u`. An anchor that
    /// found no active node this step (it has drifted off the cells the
    /// material touches) moves with its material point instead, given as
    /// that point's displacement over the step in `point_moved`.
    pub fn advance(
        &self,
        anchors: &mut [impl Carried<D>],
        u: &[f64],
        point_moved: impl Fn(usize) -> [f64; D],
    ) {
        let mut carried = vec![false; anchors.len()];
        for &(i, first, last) in &self.carriers {
            let v = self.interpolate(first, last, u);
            let moved = anchors[i].moved_mut();
            for d in 0..D {
                moved[d] += v[d];
            }
            carried[i] = true;
        }
        for (a, _) in anchors.iter_mut().zip(carried).filter(|(_, c)| !c) {
            let v = point_moved(a.point());
            let moved = a.moved_mut();
            for d in 0..D {
                moved[d] += v[d];
            }
        }
    }
}

/// The sums that make an averaged band point: the piece's constraint
/// `int (u_h - target) dGamma = 0`, so its shares are `int N dGamma / L`.
#[derive(Debug)]
pub(super) struct PieceSum<const D: usize> {
    support: usize,
    /// Per active node, `sum dGamma N`.
    shares: BTreeMap<usize, f64>,
    stiffness: SMatrix<f64, D, D>,
    /// `sum dGamma target` and `sum dGamma x`.
    target: [f64; D],
    at: [f64; D],
    length: f64,
}

impl<const D: usize> BandTerms<D> {
    /// No terms yet, on cells of size `h` with the band width `band_width`.
    pub(super) fn empty(h: f64, band_width: f64) -> Self {
        BandTerms {
            material_scale: 0.75 * band_width / h,
            ..Default::default()
        }
    }

    /// Adds a constraint whose shares are the last ones pushed: as a band
    /// point of its own, or into the sums of its averaged support's piece.
    pub(super) fn add_point(
        &mut self,
        pieces: &mut BTreeMap<usize, PieceSum<D>>,
        piece: Option<usize>,
        point: BandPoint<D>,
    ) {
        let Some(piece) = piece else {
            self.points.push(point);
            return;
        };
        let sum = pieces.entry(piece).or_insert_with(|| PieceSum {
            support: point.support,
            shares: BTreeMap::new(),
            stiffness: SMatrix::zeros(),
            target: [0.0; D],
            at: [0.0; D],
            length: 0.0,
        });
        let length = point.length;
        for &(node, n) in &self.shares[point.first..point.last] {
            *sum.shares.entry(node).or_insert(0.0) += length * n;
        }
        sum.stiffness += point.stiffness;
        for d in 0..D {
            sum.target[d] += length * point.target[d];
            sum.at[d] += length * point.at[d];
        }
        sum.length += length;
    }

    /// Sums the stiffness of the band points and ghost ties made so far by
    /// the nodes they couple (the step's tangent then adds each sum once).
    pub(super) fn couple(&mut self) {
        let mut index: HashMap<Vec<usize>, usize> = HashMap::new();
        let mut coupled: Vec<Coupled<D>> = Vec::new();
        let mut add = |nodes: Vec<usize>, weights: &[f64], k: &SMatrix<f64, D, D>| {
            let n = nodes.len();
            let g = *index.entry(nodes).or_insert_with_key(|nodes| {
                coupled.push(Coupled {
                    nodes: nodes.clone(),
                    blocks: vec![SMatrix::zeros(); n * n],
                });
                coupled.len() - 1
            });
            let blocks = &mut coupled[g].blocks;
            for (i, wi) in weights.iter().enumerate() {
                for (j, wj) in weights.iter().enumerate() {
                    blocks[i * n + j] += k * (wi * wj);
                }
            }
        };
        for b in &self.points {
            let shares = &self.shares[b.first..b.last];
            let weights: Vec<f64> = shares.iter().map(|s| s.1).collect();
            add(shares.iter().map(|s| s.0).collect(), &weights, &b.stiffness);
        }
        for tie in &self.ghosts {
            add(tie.nodes.to_vec(), &GHOST_STENCIL, &tie.stiffness);
        }
        self.coupled = coupled;
    }

    /// Adds each piece's averaged band point.
    pub(super) fn add_pieces(&mut self, pieces: BTreeMap<usize, PieceSum<D>>) {
        for sum in pieces.into_values() {
            let first = self.shares.len();
            self.shares
                .extend((sum.shares.into_iter()).map(|(node, share)| (node, share / sum.length)));
            self.points.push(BandPoint {
                support: sum.support,
                first,
                last: self.shares.len(),
                stiffness: sum.stiffness,
                length: sum.length,
                at: sum.at.map(|x| x / sum.length),
                target: sum.target.map(|t| t / sum.length),
            });
        }
    }
}

impl<const D: usize> StepTerm<D> for BandTerms<D> {
    fn side(&self) -> Side {
        Side::Support
    }

    /// Node groups the band and the ghost ties couple (for the stiffness
    /// pattern).
    fn coupling_groups(&self) -> Vec<Vec<u32>> {
        (self.coupled.iter())
            .map(|g| g.nodes.iter().map(|&a| a as u32).collect())
            .collect()
    }

    /// Adds the band's internal force `N_a K (u_h - target)` and the ghost
    /// ties' `c_a K (u_I - 2 u_J + u_K)` to `f`.
    fn add_force(&self, u: &[f64], f: &mut [f64]) {
        for b in &self.points {
            let force = self.force(b, u);
            for &(a, n) in &self.shares[b.first..b.last] {
                for d in 0..D {
                    f[D * a + d] += n * force[d];
                }
            }
        }
        for tie in &self.ghosts {
            let force = tie.force(u);
            for (&a, c) in tie.nodes.iter().zip(GHOST_STENCIL) {
                for d in 0..D {
                    f[D * a + d] += c * force[d];
                }
            }
        }
    }

    /// What a prescribed displacement asks of the material next to it: the
    /// norm of the band forces at zero increment, `|N_a K target|`, with the
    /// penalty's `4 / (3 delta)` replaced by a cell's `1 / h`. A yardstick
    /// for residuals when nothing else loads the body; the band forces
    /// themselves are `h / delta` times larger, and measuring against them
    /// would let the material's balance go that much looser.
    fn force_scale(&self, n_dofs: usize) -> f64 {
        let mut f = vec![0.0; n_dofs];
        self.add_force(&vec![0.0; n_dofs], &mut f);
        self.material_scale * f.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// Adds the band's stiffness `N_a N_b K` and the ghost ties' to
    /// tangent values, summed by the nodes they couple.
    fn add_stiffness(&self, _u: &[f64], pattern: &Pattern, values: &mut [f64]) {
        for g in &self.coupled {
            let n = g.nodes.len();
            for (j, &c) in g.nodes.iter().enumerate() {
                for (i, &a) in g.nodes.iter().enumerate() {
                    let (base, stride) = pattern.block(a as u32, c as u32);
                    let k = &g.blocks[i * n + j];
                    for col in 0..D {
                        for row in 0..D {
                            values[base + row + col * stride] += k[(row, col)];
                        }
                    }
                }
            }
        }
    }

    /// Per support of the case (`n` of them), the force the band terms and
    /// ghost ties exert on the body at increment `u`: their nodal forces on
    /// the DOFs that are free. On a DOF a grid support holds, the band
    /// pushes against that support, not the body, and the grid support's
    /// reaction (from the material's forces) is the body's side of it.
    fn reactions(&self, u: &[f64], fixed: &[bool], n: usize) -> Option<Vec<[f64; D]>> {
        let mut out = vec![[0.0; D]; n];
        let mut take = |support: usize, a: usize, share: f64, force: SVector<f64, D>| {
            for c in 0..D {
                if !fixed[D * a + c] {
                    out[support][c] -= share * force[c];
                }
            }
        };
        for b in &self.points {
            let force = self.force(b, u);
            for &(a, share) in &self.shares[b.first..b.last] {
                take(b.support, a, share, force);
            }
        }
        for tie in &self.ghosts {
            let force = tie.force(u);
            for (&a, c) in tie.nodes.iter().zip(GHOST_STENCIL) {
                take(tie.support, a, c, force);
            }
        }
        Some(out)
    }

    fn into_carried(self: Box<Self>) -> Option<Box<dyn Any>> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix2, Vector2};

    use super::*;
    use crate::supports::Fix;

    #[test]
    fn projections_hold_the_right_components() {
        let n = [0.6, 0.8];
        let p = projection(Fix::Normal, n);
        let v = p * Vector2::new(0.8, -0.6); // tangential
        assert!(v.norm() < 1e-15);
        let v = p * Vector2::new(0.6, 0.8);
        assert!((v - Vector2::new(0.6, 0.8)).norm() < 1e-15);
        assert_eq!(projection(Fix::X, n), Matrix2::new(1.0, 0.0, 0.0, 0.0));
    }
}
