//! Tractions on the faces of 3D bodies that lie on grid-aligned planes (a
//! box's faces), the stopgap until the B-spline surfaces carry them (issue
//! 38, part 2). A loaded face is tiled by the faces of its points' box
//! domains; each tile's force (the traction times its area in the
//! reference configuration: a dead load) acts at the tile's centre, where
//! the face's shape functions (the boundary's: the hats for the linear
//! basis and GIMP, the B-splines for theirs) share it among the nodes. On
//! a flat face of a box the tiles' centres are the midpoint rule on every
//! cell's part of the face: the nodal forces of a uniform traction are the
//! consistent ones.

use super::quadrature::hat_shares;
use crate::assembly::{Pattern, Side, StepTerm};
use crate::configuration::Configuration;

/// One tile of a loaded face: the point whose domain's face it is, the
/// tile's centre from the point in the reference configuration, and its
/// force, held at its full value or ramped with the load factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceLoad<const D: usize> {
    pub point: usize,
    pub offset: [f64; D],
    pub force: [f64; D],
    pub held: bool,
}

/// A step's face loads as nodal forces: where the tiles' centres are at
/// the step's start (each carried by its point's deformation gradient).
pub struct FaceLoading {
    held: Vec<f64>,
    ramped: Vec<f64>,
    load_factor: f64,
}

impl FaceLoading {
    pub fn new(start: &Configuration<'_, 3>, loads: &[FaceLoad<3>], load_factor: f64) -> Self {
        let (conn, points) = (start.conn, start.points);
        let mut held = vec![0.0; conn.n_dofs()];
        let mut ramped = vec![0.0; conn.n_dofs()];
        let (mut weights, mut shares) = (Vec::new(), Vec::new());
        for load in loads {
            let f = &points.deformation[load.point];
            let x = points.position[load.point];
            let at: [f64; 3] = std::array::from_fn(|i| {
                x[i] + (0..3).map(|j| f[(i, j)] * load.offset[j]).sum::<f64>()
            });
            shares.clear();
            if !hat_shares(
                start.basis,
                start.grid,
                at,
                &conn.nodes,
                &mut weights,
                &mut shares,
            ) {
                continue;
            }
            let target = if load.held { &mut held } else { &mut ramped };
            for &(a, n) in &shares {
                for c in 0..3 {
                    target[3 * a + c] += n * load.force[c];
                }
            }
        }
        Self {
            held,
            ramped,
            load_factor,
        }
    }
}

impl StepTerm<3> for FaceLoading {
    fn side(&self) -> Side {
        Side::Load
    }

    fn add_force(&self, _u: &[f64], f: &mut [f64]) {
        for ((f, h), r) in f.iter_mut().zip(&self.held).zip(&self.ramped) {
            *f += h + self.load_factor * r;
        }
    }

    fn set_load_factor(&mut self, lambda: f64) {
        self.load_factor = lambda;
    }

    fn add_load_rate(&self, _u: &[f64], f: &mut [f64]) {
        for (f, r) in f.iter_mut().zip(&self.ramped) {
            *f += r;
        }
    }

    /// A dead load: no stiffness.
    fn add_stiffness(&self, _u: &[f64], _pattern: &Pattern, _values: &mut [f64]) {}
}
