//! Dirichlet conditions on the boundary curve by the implicit boundary
//! method (Burla & Kumar 2008; Kumar et al. 2008; in MPM, Cortis et al.
//! 2018).
//!
//! The trial displacement is `u = D u_h + u_a`: `u_h` the grid
//! interpolation, `u_a` the prescribed values, `D` a D-function of the
//! distance `phi` from the boundary, `D = 1 - (1 - phi/delta)^2` across a
//! band of width `delta` inside the material and 1 beyond. Integrated across
//! the band, the strain energy of `D u_h` has the leading part
//! `1/2 int_Gamma (4 / (3 delta)) (u_h - u_a) . A_nn (u_h - u_a) dGamma`, since
//! `int_0^delta D'(phi)^2 dphi = 4 / (3 delta)`, with `A_nn` the acoustic
//! tensor `A_iKjL n_K n_L` of the material next to the boundary. The band is
//! far thinner than a point spacing, so no point lies in it and the points
//! keep their ordinary integration; the band adds that boundary term,
//! integrated by Gauss quadrature along the B-spline (split at grid lines,
//! as tractions are). A fixed condition holds both components, a roller the
//! normal one (`P = n n` in `P A_nn P`), so inclined and curved rollers are
//! the same code.
//!
//! The band width `delta` trades two errors: the penalty holds the
//! condition to a gap of about `(3/4) delta` times the boundary strain, and
//! a boundary at an angle to the grid locks as `delta` shrinks (the bilinear
//! field cannot meet a stiff constraint at every quadrature point). The
//! default, a hundredth of a cell, keeps both at or below the
//! discretisation error; `docs/ibm.md` has the measurements.
//!
//! Updated-Lagrangian steps reset the grid, so a step's band term sees only
//! that step's increment, while a support must hold the boundary's total
//! displacement. The band's quadrature points are therefore [`Anchor`]s:
//! fixed on the reference curve (Gauss points of its segments, split at
//! the grid lines of the first step) and carried by the grid's own
//! displacement at the end of every step, so that each one knows how far it
//! has moved; the step's target is the prescribed displacement minus that.
//!
//! Nodes just beyond a supported boundary, which GIMP domains reach as the
//! body deforms, get a tiny stiffness but a force proportional to the
//! point's stress; their equilibrium would ask that stress to vanish, which
//! at a support it cannot. They get a ghost tie ([`ghost`]), which makes
//! them follow the linear continuation of the field inside.
//!
//! The stages: [`anchors`] once per run, [`band::BandTerms`] (with the ghost
//! ties) every load step.

pub mod band;
pub mod ghost;

pub use band::{BandTerms, DEFAULT_BAND_WIDTH};

use super::bspline::{bezier, bezier_derivative, local_segment};
use super::detection::BoundaryLoop;
use super::quadrature::gauss_points;
use super::reference_ring;
use crate::grid::Grid;
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
                for (t, weight) in gauss_points(&segment, grid) {
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
