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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Basis, lattice_coordinates};

    /// A uniform traction on a box's face gives the consistent nodal forces
    /// of the bilinear face elements: a unit traction on the unit square
    /// face z = 1 of 2 x 2 cells of 0.5 m puts h^2 / 4 on its corner nodes,
    /// twice that on its edges' middles and four times on its centre,
    /// nothing below the face, and the traction times the area in all.
    #[test]
    fn a_uniform_traction_gives_the_consistent_nodal_forces() {
        let (points, mut grid) = crate::fixtures::solid_box([0.0; 3], [1.0; 3], 0.25, 0.5);
        // The face on the grid plane z = 1.
        grid.origin = [0.0; 3];
        let conn = crate::fixtures::solid_links(&points, &grid, Basis::Linear);
        let start = Configuration {
            grid: &grid,
            basis: Basis::Linear,
            conn: &conn,
            points: &points,
        };
        let loads = crate::model::face_loads(&points, (2, 1.0, 1e-9), [0.0, 0.0, -1.0], false);
        assert_eq!(loads.len(), 16);
        let term = FaceLoading::new(&start, &loads, 1.0);
        let mut f = vec![0.0; conn.n_dofs()];
        term.add_force(&[], &mut f);
        let mut total = 0.0;
        for (a, &key) in conn.nodes.iter().enumerate() {
            let [i, j, k] = lattice_coordinates::<3>(key);
            let on_face = k == 2;
            let interior = |c: i64| usize::from(c == 1);
            let expected = if on_face {
                -0.0625 * (1 << (interior(i) + interior(j))) as f64
            } else {
                0.0
            };
            assert!(
                (f[3 * a + 2] - expected).abs() < 1e-15,
                "node {i} {j} {k}: {}",
                f[3 * a + 2]
            );
            assert_eq!((f[3 * a], f[3 * a + 1]), (0.0, 0.0));
            total += f[3 * a + 2];
        }
        assert!((total + 1.0).abs() < 1e-14, "{total}");
    }
}
