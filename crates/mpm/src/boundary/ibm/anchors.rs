//! The anchors of the implicit-boundary supports: quadrature points fixed
//! on the reference curve and carried by the grid's displacement.

use nalgebra::Matrix2;

use crate::boundary::curve::{bezier, bezier_derivative, local_segment};
use crate::boundary::detection::BoundaryLoop;
use crate::boundary::quadrature::gauss_points;
use crate::boundary::reference_ring;
use crate::grid::{Basis, Grid};
use crate::particles::MaterialPoints;
use crate::supports::{Fix, Rotation};

/// A support imposed on the boundary curve by the implicit boundary method.
#[derive(Debug, Clone, PartialEq)]
pub struct IbmSupport {
    /// Its index among the case's supports (for reactions).
    pub index: usize,
    /// The segments of each loop it holds, `(loop index, segments)`.
    pub segments: Vec<(usize, Vec<usize>)>,
    pub fix: Fix,
    /// Prescribed displacement at load factor 1.
    pub displacement: [f64; 2],
    pub rotation: Option<Rotation>,
}

/// A quadrature point of an implicit-boundary support, Lagrangian: fixed on
/// the reference curve, carried by the grid's displacement.
#[derive(Debug, Clone, PartialEq)]
pub struct Anchor {
    /// Index of the support in the case (for reactions).
    pub support: usize,
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
    /// Prescribed displacement and rotation at load factor 1.
    pub(super) prescribed: [f64; 2],
    pub(super) rotation: Option<Rotation>,
    /// Reference position and the displacement since.
    pub(super) reference: [f64; 2],
    pub(super) moved: [f64; 2],
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

    /// The prescribed displacement at load factor `lambda`:
    /// `lambda d + (R(lambda theta) - I)(X - c)`.
    pub(super) fn prescribed_at(&self, lambda: f64) -> [f64; 2] {
        let mut u = [lambda * self.prescribed[0], lambda * self.prescribed[1]];
        if let Some(r) = self.rotation {
            let (sin, cos) = (lambda * r.angle.to_radians()).sin_cos();
            let x = [
                self.reference[0] - r.center[0],
                self.reference[1] - r.center[1],
            ];
            u[0] += (cos - 1.0) * x[0] - sin * x[1];
            u[1] += sin * x[0] + (cos - 1.0) * x[1];
        }
        u
    }

    /// `A_nn[i][j] = A[(2i+K),(2j+L)] n_K n_L` of the anchor's point's
    /// material tangent at the start of the step, for its normal `n`.
    pub(super) fn acoustic_tensor(&self, points: &MaterialPoints) -> Matrix2<f64> {
        let (p, n) = (self.point, self.normal);
        let material = &points.materials[points.material[p] as usize];
        let j = points.deformation[p].determinant();
        let tangent = material
            .respond(&points.history[p], &Matrix2::zeros(), j)
            .tangent;
        Matrix2::from_fn(|i, jj| {
            let mut sum = 0.0;
            for k in 0..2 {
                for l in 0..2 {
                    sum += n[k] * tangent[(2 * i + k, 2 * jj + l)] * n[l];
                }
            }
            sum
        })
    }

    /// Current position.
    pub fn position(&self) -> [f64; 2] {
        [
            self.reference[0] + self.moved[0],
            self.reference[1] + self.moved[1],
        ]
    }
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
    for s in supports {
        for (loop_index, segments) in &s.segments {
            let (loop_index, l) = (*loop_index, &loops[*loop_index]);
            if l.points.len() < 3 {
                continue; // no curve through one or two points
            }
            let n = l.points.len();
            let ring = reference_ring(l, points);
            for &k in segments {
                let segment = local_segment(&ring, k);
                for (t, weight) in gauss_points(&segment, grid, basis) {
                    let d = bezier_derivative(&segment, t);
                    let length = (d[0] * d[0] + d[1] * d[1]).sqrt();
                    out.push(Anchor {
                        normal: [d[1] / length, -d[0] / length],
                        support: s.index,
                        loop_index,
                        segment: k,
                        t,
                        weight,
                        point: l.points[if t < 0.5 { k } else { (k + 1) % n }],
                        fix: s.fix,
                        prescribed: s.displacement,
                        rotation: s.rotation,
                        reference: bezier(&segment, t),
                        moved: [0.0, 0.0],
                    });
                }
            }
        }
    }
    out
}
