//! Material points: the Lagrangian carriers of mass, volume, deformation and
//! stress. Stored as a structure of arrays, one entry per point.

use nalgebra::Matrix2;

pub mod admissible;
pub mod geostatic;
pub mod seeding;
pub mod solid_seeding;

use crate::grid::Support;
use crate::material::{CauchyStress, History, Material};
use seeding::{Domain, SeedPoint};

#[derive(Debug, Clone, Default)]
pub struct MaterialPoints {
    /// Current position.
    pub position: Vec<[f64; 2]>,
    /// Position in the reference (initial) configuration.
    pub reference: Vec<[f64; 2]>,
    /// Reference volume `V0` (area times unit thickness).
    pub volume0: Vec<f64>,
    pub mass: Vec<f64>,
    /// Index into [`MaterialPoints::materials`] (one material per body, so
    /// this is also the body index).
    pub material: Vec<u32>,
    /// Place in the body's generation lattice (see [`seeding::SeedPoint`]).
    pub lattice: Vec<[i64; 2]>,
    /// The point's domain in its own frame, in the reference configuration.
    pub domain: Vec<Domain>,
    /// Total deformation gradient `F` (in-plane block).
    pub deformation: Vec<Matrix2<f64>>,
    /// Constitutive history (see [`Material::respond`]).
    pub history: Vec<History>,
    /// Whether the point flowed plastically in the last step.
    pub yielding: Vec<bool>,
    pub stress: Vec<CauchyStress>,
    /// The stress's slopes across the point's domain, `dsigma_ij/dx_k`
    /// in the order `[xx,x; xx,y; yy,x; yy,y; xy,x; xy,y]`: what a point
    /// of an elastic body seeded one a cell or fewer holds of its bending
    /// (`assembly::lone_points`); zero for the others.
    pub stress_slopes: Vec<[f64; 6]>,
    /// With F-bar, how far the mean pressure each point worked with in the
    /// last step stood from its own model's, which the next carries across
    /// the grid's reset (`assembly::FbarCells::carrying`); empty before the
    /// first.
    pub fbar_pressure: Vec<f64>,
    /// With the cell-mean strain, how far the stress each point worked with
    /// in the last step stood from its own model's (Kirchhoff's, per unit
    /// reference volume), which the next carries across the grid's reset
    /// (`assembly::CellMean::carrying`); empty before the first.
    pub cell_mean_stress: Vec<Matrix2<f64>>,
    /// One material per body of the case.
    pub materials: Vec<Material>,
}

impl MaterialPoints {
    /// Bytes of the points' state on the heap.
    /// The first point whose position, deformation or stress is not a
    /// finite number.
    pub fn first_non_finite(&self) -> Option<usize> {
        (0..self.len()).find(|&p| {
            let s = &self.stress[p];
            !(self.position[p].iter().all(|x| x.is_finite())
                && self.deformation[p].iter().all(|x| x.is_finite())
                && s.plane.iter().all(|x| x.is_finite())
                && s.zz.is_finite())
        })
    }

    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.position.as_slice())
            + size_of_val(self.reference.as_slice())
            + size_of_val(self.volume0.as_slice())
            + size_of_val(self.mass.as_slice())
            + size_of_val(self.material.as_slice())
            + size_of_val(self.lattice.as_slice())
            + size_of_val(self.domain.as_slice())
            + size_of_val(self.deformation.as_slice())
            + size_of_val(self.history.as_slice())
            + size_of_val(self.yielding.as_slice())
            + size_of_val(self.stress.as_slice())
            + size_of_val(self.stress_slopes.as_slice())
            + size_of_val(self.fbar_pressure.as_slice())
            + size_of_val(self.cell_mean_stress.as_slice())
    }

    /// Adds a body's points, seeded in its reference state, with their
    /// material and density; the body's index is the material's.
    pub fn add_body(&mut self, material: Material, density: f64, seeds: &[SeedPoint]) {
        let body = self.materials.len() as u32;
        self.materials.push(material);
        for seed in seeds {
            self.position.push(seed.position);
            self.reference.push(seed.position);
            self.volume0.push(seed.volume);
            self.mass.push(density * seed.volume);
            self.material.push(body);
            self.lattice.push(seed.lattice);
            self.domain.push(seed.domain);
            self.deformation.push(Matrix2::identity());
            self.history.push(material.initial_history());
            self.yielding.push(false);
            self.stress.push(CauchyStress::default());
            self.stress_slopes.push([0.0; 6]);
        }
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

    /// The point's domain for GIMP now. An upright rectangular cell stays
    /// an axis-aligned rectangle, its half-widths scaled by the diagonal of
    /// the right stretch tensor `U = sqrt(F^T F)`, so it follows stretch
    /// but not rotation. Any other cell (turned, mapped, polar) is carried
    /// by `F` as a whole, `x + F (s a + t b + s t c)`, so that neighbouring
    /// cells keep tiling the body under a uniform deformation.
    pub fn support(&self, p: usize) -> Support {
        let Domain {
            axes: [a, b],
            twist,
        } = self.domain[p];
        let f = &self.deformation[p];
        if a[1] == 0.0 && b[0] == 0.0 && twist == [0.0, 0.0] {
            let u = right_stretch(f);
            return Support::Rectangle([a[0].abs() * u[(0, 0)], b[1].abs() * u[(1, 1)]]);
        }
        Support::Quadrilateral([(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(
            |(s, t)| {
                let r = [0, 1].map(|d| s * a[d] + t * b[d] + s * t * twist[d]);
                [
                    f[(0, 0)] * r[0] + f[(0, 1)] * r[1],
                    f[(1, 0)] * r[0] + f[(1, 1)] * r[1],
                ]
            },
        ))
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
