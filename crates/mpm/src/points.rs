//! Material points: the Lagrangian carriers of mass, volume, deformation and
//! stress. Stored as a structure of arrays, one entry per point.

use nalgebra::Matrix2;

use crate::case::Case;
use crate::fill::fill_body;
use crate::material::{CauchyStress, Elastic, Material};

#[derive(Debug, Clone, Default)]
pub struct MaterialPoints {
    /// Current position.
    pub position: Vec<[f64; 2]>,
    /// Position in the reference (initial) configuration.
    pub reference: Vec<[f64; 2]>,
    /// Reference volume `V0` (area times unit thickness).
    pub volume0: Vec<f64>,
    pub mass: Vec<f64>,
    /// Half-widths of the point's domain in the reference configuration.
    pub half_width0: Vec<[f64; 2]>,
    /// Index into [`MaterialPoints::materials`] (one material per body, so
    /// this is also the body index).
    pub material: Vec<u32>,
    /// Place in the body's generation lattice (see [`crate::fill::SeedPoint`]).
    pub lattice: Vec<[i64; 2]>,
    /// The point's domain in its own frame, in the reference configuration.
    pub domain: Vec<crate::fill::Domain>,
    /// Total deformation gradient `F` (in-plane block).
    pub deformation: Vec<Matrix2<f64>>,
    /// Constitutive history (see [`Material::respond`]).
    pub history: Vec<Matrix2<f64>>,
    pub stress: Vec<CauchyStress>,
    /// One material per body of the case.
    pub materials: Vec<Material>,
}

impl MaterialPoints {
    /// Fills every body of the case with points in its reference state.
    pub fn from_case(case: &Case) -> Self {
        let mut mp = MaterialPoints::default();
        for (b, body) in case.bodies.iter().enumerate() {
            let (e, nu, rho) = body.material.constants();
            let constants = Elastic::from_young_poisson(e, nu);
            let material = match body.material {
                crate::case::MaterialSpec::Hencky { .. } => Material::Hencky(constants),
                crate::case::MaterialSpec::LinearElastic { .. } => {
                    Material::LinearElastic(constants)
                }
            };
            mp.materials.push(material);
            for seed in fill_body(body, case.grid.cell_size, case.grid.origin) {
                mp.position.push(seed.position);
                mp.reference.push(seed.position);
                mp.volume0.push(seed.volume);
                mp.mass.push(rho * seed.volume);
                mp.half_width0.push(seed.half_width);
                mp.material.push(b as u32);
                mp.lattice.push(seed.lattice);
                mp.domain.push(seed.domain);
                mp.deformation.push(Matrix2::identity());
                mp.history.push(material.initial_history());
                mp.stress.push(CauchyStress::default());
            }
        }
        mp
    }

    pub fn len(&self) -> usize {
        self.position.len()
    }

    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Volume ratio `J = det F`.
    pub fn jacobian(&self, p: usize) -> f64 {
        self.deformation[p].determinant()
    }

    /// Current volume `J V0`.
    pub fn volume(&self, p: usize) -> f64 {
        self.jacobian(p) * self.volume0[p]
    }

    /// Displacement from the reference configuration.
    pub fn displacement(&self, p: usize) -> [f64; 2] {
        let (x, x0) = (self.position[p], self.reference[p]);
        [x[0] - x0[0], x[1] - x0[1]]
    }

    /// Current half-widths of the point's domain for GIMP: the reference
    /// half-widths scaled by the diagonal of the right stretch tensor
    /// `U = sqrt(F^T F)`, so the domain follows stretch but not rotation.
    pub fn half_width(&self, p: usize) -> [f64; 2] {
        let u = right_stretch(&self.deformation[p]);
        let h = self.half_width0[p];
        [h[0] * u[(0, 0)], h[1] * u[(1, 1)]]
    }
}

/// `U = sqrt(C)`, `C = F^T F`, by the 2x2 closed form
/// `sqrt(C) = (C + sqrt(det C) I) / sqrt(tr C + 2 sqrt(det C))`.
fn right_stretch(f: &Matrix2<f64>) -> Matrix2<f64> {
    let c = f.transpose() * f;
    let s = c.determinant().max(0.0).sqrt();
    (c + Matrix2::identity() * s) / (c.trace() + 2.0 * s).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn right_stretch_removes_rotation() {
        let (s, c) = 0.7f64.sin_cos();
        let r = Matrix2::new(c, -s, s, c);
        let u = Matrix2::new(1.3, 0.2, 0.2, 0.8);
        assert!((right_stretch(&(r * u)) - u).norm() < 1e-12);
    }
}
