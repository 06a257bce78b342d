//! The anchors of the implicit-boundary supports: quadrature points fixed
//! on the reference curve and carried by the grid's displacement.

use nalgebra::{Matrix2, SMatrix, Vector2};

use crate::boundary::Piece;
use crate::boundary::curve::{bezier, bezier_derivative, local_segment};
use crate::boundary::detection::BoundaryLoop;
use crate::boundary::quadrature::gauss_points_between;
use crate::boundary::reference_ring;
use crate::geometry::Selector;
use crate::grid::{Basis, Grid};
use crate::particles::{Dim, MaterialPoints, Space};
use crate::supports::{Fix, Rotation};

/// The length of an averaged support's pieces, in cells: one constraint
/// per two cells of stretch, the classical stable choice of a multiplier
/// mesh twice the field's. Pieces of one cell left the load 4% apart
/// between grid origins at h = B/8, against 1.8% (docs/ibm.md).
pub const AVERAGED_PIECE_CELLS: f64 = 2.0;

/// A support imposed on the boundary curve by the implicit boundary method.
#[derive(Debug, Clone, PartialEq)]
pub struct IbmSupport {
    /// Its index among the case's supports (for reactions).
    pub index: usize,
    /// The pieces of each loop's curve it holds, `(loop index, pieces)`.
    pub pieces: Vec<(usize, Vec<Piece>)>,
    pub fix: Fix,
    /// Prescribed displacement at load factor 1.
    pub displacement: [f64; 2],
    pub rotation: Option<Rotation>,
    /// Held on average over pieces of about this length (m) rather than at
    /// every quadrature point ([`AVERAGED_PIECE_CELLS`]), on the part of
    /// the boundary within these ranges (the case's selector, moved with
    /// the prescribed displacement); `None`: at every point, wherever the
    /// anchors go.
    pub averaged: Option<(f64, Selector)>,
}

/// A quadrature point of an implicit-boundary support, Lagrangian: fixed on
/// the reference curve, carried by the grid's displacement.
#[derive(Debug, Clone, PartialEq)]
pub struct Anchor {
    /// Index of the support among the stage's (for reactions).
    pub support: usize,
    /// The support it belongs to, by its place among the run's
    /// implicit-boundary supports ([`enter_stage`]).
    pub(super) owner: usize,
    pub(super) loop_index: usize,
    pub(super) segment: usize,
    /// Parameter on the segment and Gauss weight in it.
    pub(super) t: f64,
    pub(super) weight: f64,
    /// The material point next to it (the nearer end of the segment): its
    /// tangent stiffness stands for the band's, and it carries the anchor
    /// in a step where the anchor touches no active node.
    pub(super) point: usize,
    pub(super) fix: Fix,
    /// Outward unit normal of the reference curve: the wall a roller slides
    /// on. It stays put while the body deforms (the body's own normal turns
    /// with its shear, and a roller along it would push the body sideways).
    pub(super) normal: [f64; 2],
    /// Prescribed displacement and rotation at load factor 1 of the stage,
    /// on top of where the stages before took it (`start`: a displacement
    /// and an angle in degrees about the rotation's centre).
    pub(super) prescribed: [f64; 2],
    pub(super) rotation: Option<Rotation>,
    pub(super) start: ([f64; 2], f64),
    /// Reference position and the displacement since.
    pub(super) reference: [f64; 2],
    pub(super) moved: [f64; 2],
    /// The piece of an averaged support it belongs to, whose anchors
    /// share one constraint; `None`: a constraint of its own.
    pub(super) piece: Option<usize>,
    /// An averaged support's ranges, where it holds the boundary, and
    /// the share of its span within them at the start
    /// ([`Anchor::share_inside`]).
    pub(super) ranges: Option<(Selector, f64)>,
}

impl Anchor {
    /// Its displacement since the reference configuration (what a
    /// checkpoint keeps of it).
    pub fn moved(&self) -> [f64; 2] {
        self.moved
    }

    pub(crate) fn set_moved(&mut self, moved: [f64; 2]) {
        self.moved = moved;
    }

    /// The prescribed displacement at load factor `lambda` of the stage:
    /// `d0 + lambda d + (R(theta0 + lambda theta) - I)(X - c)`, `d0` and
    /// `theta0` where the stages before took it.
    pub(super) fn prescribed_at(&self, lambda: f64) -> [f64; 2] {
        let (d0, theta0) = self.start;
        let mut u = [
            d0[0] + lambda * self.prescribed[0],
            d0[1] + lambda * self.prescribed[1],
        ];
        if let Some(r) = self.rotation {
            let (sin, cos) = (theta0.to_radians() + lambda * r.angle.to_radians()).sin_cos();
            let x = [
                self.reference[0] - r.center[0],
                self.reference[1] - r.center[1],
            ];
            u[0] += (cos - 1.0) * x[0] - sin * x[1];
            u[1] += sin * x[0] + (cos - 1.0) * x[1];
        }
        u
    }

    /// Moves on to the next stage's motion: where this stage ends is
    /// where the next starts.
    fn continue_with(&mut self, motion: &IbmMotion) {
        let (d0, theta0) = self.start;
        let angle = self.rotation.map_or(0.0, |r| r.angle);
        self.start = (
            [d0[0] + self.prescribed[0], d0[1] + self.prescribed[1]],
            theta0 + angle,
        );
        self.support = motion.index;
        self.prescribed = motion.displacement;
        self.rotation = match (motion.rotation, self.rotation) {
            (Some(r), _) => Some(r),
            (None, Some(r)) => Some(Rotation { angle: 0.0, ..r }),
            (None, None) => None,
        };
    }

    /// The acoustic tensor of the anchor's point for its normal
    /// ([`acoustic_tensor`]).
    pub(super) fn acoustic_tensor(&self, points: &MaterialPoints) -> Matrix2<f64> {
        acoustic_tensor(points, self.point, self.normal)
    }

    /// The share of the boundary it stands for, `span` (its length along
    /// the current tangent), that lies within its support's ranges: 1 for a
    /// support without ranges. The anchor is placed relative to the support
    /// by the reference position plus the part of its motion the support
    /// does not hold (a smooth footing's soil sliding beneath it; a rough
    /// footing's soil moves with it and stays put). So a rigid footing holds
    /// the soil that is under it, on its exact width; the share goes
    /// linearly from 1 to 0 as the anchor's span crosses the edge, so the
    /// footing's load does not jump as an anchor leaves.
    pub(super) fn share_inside(&self, span: [f64; 2]) -> f64 {
        let Some((ranges, at_start)) = &self.ranges else {
            return 1.0;
        };
        let free = (Matrix2::identity() - projection(self.fix, self.normal))
            * Vector2::new(self.moved[0], self.moved[1]);
        let p = [self.reference[0] + free[0], self.reference[1] + free[1]];
        // Relative to the start, whose quadrature ends at the edge exactly.
        (overlap_share(ranges, p, span) / at_start.max(f64::MIN_POSITIVE)).min(1.0)
    }

    /// Current position.
    pub fn position(&self) -> [f64; 2] {
        [
            self.reference[0] + self.moved[0],
            self.reference[1] + self.moved[1],
        ]
    }
}

/// The components a support holds, as a projection.
pub(super) fn projection(fix: Fix, n: [f64; 2]) -> Matrix2<f64> {
    let held = match fix {
        Fix::Xy => Some([true, true]),
        Fix::X => Some([true, false]),
        Fix::Y => Some([false, true]),
        Fix::Normal => None,
    };
    held_projection(held, n)
}

/// The projection on the components `held`, or (`None`) on the normal
/// `n`: `n n`.
pub(super) fn held_projection<const D: usize>(
    held: Option<[bool; D]>,
    n: [f64; D],
) -> SMatrix<f64, D, D> {
    match held {
        Some(held) => SMatrix::from_fn(|i, j| if i == j && held[i] { 1.0 } else { 0.0 }),
        None => SMatrix::from_fn(|i, j| n[i] * n[j]),
    }
}

/// `A_nn[i][j] = A[(D i + K), (D j + L)] n_K n_L` of point `p`'s material
/// tangent at the start of the step, for the normal `n`.
pub(super) fn acoustic_tensor<const D: usize>(
    points: &MaterialPoints<D>,
    p: usize,
    n: [f64; D],
) -> SMatrix<f64, D, D>
where
    Dim<D>: Space<D>,
{
    let material = &points.materials[points.material[p] as usize];
    let j = <Dim<D> as Space<D>>::determinant(&points.deformation[p]);
    let response =
        <Dim<D> as Space<D>>::respond(material, &points.history[p], &SMatrix::zeros(), j, true);
    let tangent = <Dim<D> as Space<D>>::tangent_of(&response);
    SMatrix::from_fn(|i, jj| {
        let mut sum = 0.0;
        for k in 0..D {
            for l in 0..D {
                sum += n[k] * tangent[(D * i + k, D * jj + l)] * n[l];
            }
        }
        sum
    })
}

/// What the band moves at the end of a step: an anchor's displacement
/// since the reference configuration, and the point that carries it when
/// it touches no active node (the curve's anchors and the surface's).
pub trait Carried<const D: usize> {
    fn point(&self) -> usize;
    fn moved_mut(&mut self) -> &mut [f64; D];
}

impl Carried<2> for Anchor {
    fn point(&self) -> usize {
        self.point
    }

    fn moved_mut(&mut self) -> &mut [f64; 2] {
        &mut self.moved
    }
}

/// The share of a span `span` centred at `p` that lies within the ranges
/// of `ranges` (1 for a selector without ranges): the overlap of
/// `[c - |dc| / 2, c + |dc| / 2]` with each range, over `|dc|`, for the
/// coordinate `c` each range measures.
fn overlap_share(ranges: &Selector, p: [f64; 2], span: [f64; 2]) -> f64 {
    let overlap = |c: f64, dc: f64, [lo, hi]: [f64; 2]| {
        let (lo, hi, half) = (lo.min(hi), lo.max(hi), 0.5 * dc.abs());
        if half <= 1e-12 * (hi - lo).max(1.0) {
            return if c >= lo && c <= hi { 1.0 } else { 0.0 };
        }
        if c - half >= lo && c + half <= hi {
            return 1.0;
        }
        ((c + half).min(hi) - (c - half).max(lo)).max(0.0) / (2.0 * half)
    };
    let mut share = 1.0;
    if let Some(r) = ranges.x_between {
        share *= overlap(p[0], span[0], r);
    }
    if let Some(r) = ranges.y_between {
        share *= overlap(p[1], span[1], r);
    }
    if let Some([a, b]) = ranges.segment {
        let length = (b[0] - a[0]).hypot(b[1] - a[1]);
        let e = [(b[0] - a[0]) / length, (b[1] - a[1]) / length];
        let along = (p[0] - a[0]) * e[0] + (p[1] - a[1]) * e[1];
        share *= overlap(along, span[0] * e[0] + span[1] * e[1], [0.0, length]);
    }
    share
}

/// What an implicit-boundary support does in a stage after the first: its
/// index among the stage's supports, and its displacement and rotation over
/// the stage (increments; a rotation keeps its centre).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IbmMotion {
    pub index: usize,
    pub displacement: [f64; 2],
    pub rotation: Option<Rotation>,
}

/// Moves the anchors on to a stage: each continues with its support's
/// `motions[owner]`, or is dropped with its released support (`None`).
pub fn enter_stage(anchors: &mut Vec<Anchor>, motions: &[Option<IbmMotion>]) {
    anchors.retain_mut(|a| match &motions[a.owner] {
        Some(m) => {
            a.continue_with(m);
            true
        }
        None => false,
    });
}

/// The anchors of the implicit-boundary supports: Gauss points of the
/// reference-curve segments each support holds.
pub fn anchors(
    supports: &[IbmSupport],
    loops: &[BoundaryLoop],
    points: &MaterialPoints,
    grid: &Grid,
    basis: Basis,
) -> Vec<Anchor> {
    let mut out = Vec::new();
    let mut pieces_so_far = 0;
    for (owner, s) in supports.iter().enumerate() {
        for (loop_index, pieces) in &s.pieces {
            let first = out.len();
            let (loop_index, l) = (*loop_index, &loops[*loop_index]);
            if l.points.len() < 3 {
                continue; // no curve through one or two points
            }
            let n = l.points.len();
            let ring = reference_ring(l, points);
            for &Piece {
                segment: k,
                t: range,
            } in pieces
            {
                let segment = local_segment(&ring, k);
                for (t, weight) in gauss_points_between(&segment, grid, basis, range) {
                    let d = bezier_derivative(&segment, t);
                    let length = (d[0] * d[0] + d[1] * d[1]).sqrt();
                    out.push(Anchor {
                        normal: [d[1] / length, -d[0] / length],
                        support: s.index,
                        owner,
                        loop_index,
                        segment: k,
                        t,
                        weight,
                        point: l.points[if t < 0.5 { k } else { (k + 1) % n }],
                        fix: s.fix,
                        prescribed: s.displacement,
                        rotation: s.rotation,
                        start: ([0.0, 0.0], 0.0),
                        reference: bezier(&segment, t),
                        moved: [0.0, 0.0],
                        piece: None,
                        ranges: None,
                    });
                    if let Some((_, ranges)) = s.averaged {
                        let a = out.last_mut().expect("just pushed");
                        let span = [weight * d[0], weight * d[1]];
                        let at_start = overlap_share(&ranges, a.reference, span);
                        a.ranges = Some((ranges, at_start));
                    }
                }
            }
            if let Some((length, _)) = s.averaged {
                pieces_so_far = into_pieces(&mut out[first..], &ring, length, pieces_so_far);
            }
        }
    }
    out
}

/// Puts the anchors of one averaged support on one loop (made in the order
/// of their segments) into pieces of about `length` of arc each, numbered
/// from `next`: each unbroken run of segments, from its first anchor to
/// its last, divided evenly. Returns the next free piece number.
fn into_pieces(anchors: &mut [Anchor], ring: &[[f64; 2]], length: f64, mut next: usize) -> usize {
    let n = ring.len();
    let chord = |k: usize| {
        let (a, b) = (ring[k], ring[(k + 1) % n]);
        (b[0] - a[0]).hypot(b[1] - a[1])
    };
    let mut covered = vec![false; n];
    for a in anchors.iter() {
        covered[a.segment] = true;
    }
    let start = (0..n)
        .find(|&k| covered[k] && !covered[(k + n - 1) % n])
        .unwrap_or(0);
    // Arc position of each segment's start, from `start` along the loop,
    // and the run each segment belongs to.
    let (mut arc, mut run) = (vec![0.0; n], vec![usize::MAX; n]);
    let (mut s, mut runs) = (0.0, Vec::<[f64; 2]>::new());
    for i in 0..n {
        let k = (start + i) % n;
        if covered[k] {
            if i == 0 || !covered[(k + n - 1) % n] {
                runs.push([s, s]);
            }
            run[k] = runs.len() - 1;
            arc[k] = s;
            s += chord(k);
            runs.last_mut().expect("a run was started")[1] = s;
        }
    }
    // Each run's anchors lie between its first and last anchor.
    let mut span = vec![[f64::INFINITY, f64::NEG_INFINITY]; runs.len()];
    let position = |a: &Anchor| arc[a.segment] + a.t * chord(a.segment);
    for a in anchors.iter() {
        let r = &mut span[run[a.segment]];
        r[0] = r[0].min(position(a));
        r[1] = r[1].max(position(a));
    }
    let bases: Vec<(usize, usize, [f64; 2])> = span
        .iter()
        .map(|&[lo, hi]| {
            let m = ((hi - lo) / length).round().max(1.0) as usize;
            let base = next;
            next += m;
            (base, m, [lo, hi])
        })
        .collect();
    for a in anchors.iter_mut() {
        let (base, m, [lo, hi]) = bases[run[a.segment]];
        let x = if hi > lo {
            m as f64 * (position(a) - lo) / (hi - lo)
        } else {
            0.0
        };
        a.piece = Some(base + (x as usize).min(m - 1));
    }
    next
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::curve::bezier_derivative;
    use crate::case::{Case, builtin};
    use crate::stepper::Simulation;

    /// The built-in footing (B / 2 = 0.5 m at h = 0.25 m, two points per
    /// cell): its outer points sit at x = 0.0625 + 0.125 k, so the edge
    /// x = 0.5 lies halfway between the data points 0.4375 and 0.5625. The
    /// stretch its anchors stand for is 0.5 m to round-off, not the 0.4375 m
    /// of the whole segments within the selection.
    #[test]
    fn a_footing_holds_its_exact_width_between_data_points() {
        let case = Case::from_json(builtin::get("footing").unwrap()).unwrap();
        let sim = Simulation::new(&case).unwrap();
        let rings: Vec<_> = (sim.loops.iter())
            .map(|l| reference_ring(l, &sim.points))
            .collect();
        let length: f64 = (sim.anchors.iter())
            .filter(|a| a.support == 0)
            .map(|a| {
                let d = bezier_derivative(&local_segment(&rings[a.loop_index], a.segment), a.t);
                a.weight * d[0].hypot(d[1])
            })
            .sum();
        assert!((length - 0.5).abs() < 1e-9, "{length}");
        let last = (sim.anchors.iter())
            .filter(|a| a.support == 0)
            .map(|a| a.reference[0])
            .fold(0.0, f64::max);
        assert!(last > 0.49 && last < 0.5, "{last}");
        // Pieces of about two cells: one over this half-width of two cells.
        assert!(
            (sim.anchors.iter())
                .filter(|a| a.support == 0)
                .all(|a| a.piece == Some(0))
        );
    }

    /// A span's share within a range: whole inside, half across the edge,
    /// none beyond, and a span across the range's direction counted by its
    /// centre.
    #[test]
    fn an_anchor_leaves_a_range_in_proportion_to_its_span() {
        let ranges = Selector {
            y: Some(3.0),
            x_between: Some([0.0, 0.5]),
            ..Default::default()
        };
        let share = |x: f64, span: [f64; 2]| overlap_share(&ranges, [x, 3.0], span);
        assert_eq!(share(0.25, [0.1, 0.0]), 1.0);
        assert!((share(0.5, [0.1, 0.0]) - 0.5).abs() < 1e-12);
        assert!((share(0.48, [-0.1, 0.0]) - 0.7).abs() < 1e-12);
        assert_eq!(share(0.56, [0.1, 0.0]), 0.0);
        assert_eq!(share(0.49, [0.0, 0.1]), 1.0);
        assert_eq!(share(0.51, [0.0, 0.1]), 0.0);
        let segment = Selector {
            segment: Some([[0.0, 3.0], [0.5, 3.0]]),
            ..Default::default()
        };
        assert!((overlap_share(&segment, [0.5, 3.0], [0.1, 0.0]) - 0.5).abs() < 1e-12);
    }
}
