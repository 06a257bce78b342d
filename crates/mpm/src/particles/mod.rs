//! Material points: the Lagrangian carriers of mass, volume, deformation and
//! stress. Stored as a structure of arrays, one entry per point, in `D`
//! dimensions (2: plane strain; 3).

use nalgebra::{Matrix2, Matrix3, SMatrix};

pub mod admissible;
pub mod dimension;
pub mod geostatic;
pub mod seeding;
pub mod solid_seeding;

pub use dimension::{Dim, Space, TangentMatrix};

use crate::grid::Support;
use crate::material::{History3, Material};
use seeding::{Domain, SeedPoint};
use solid_seeding::SolidSeed;

#[derive(Debug, Clone, Default)]
pub struct MaterialPoints<const D: usize = 2>
where
    Dim<D>: Space<D>,
{
    /// Current position.
    pub position: Vec<[f64; D]>,
    /// Position in the reference (initial) configuration.
    pub reference: Vec<[f64; D]>,
    /// Reference volume `V0` (in 2D, area times unit thickness).
    pub volume0: Vec<f64>,
    pub mass: Vec<f64>,
    /// Index into [`MaterialPoints::materials`] (one material per body, so
    /// this is also the body index).
    pub material: Vec<u32>,
    /// Place in the body's generation lattice (see [`seeding::SeedPoint`]).
    pub lattice: Vec<[i64; D]>,
    /// The point's domain in its own frame, in the reference configuration.
    pub domain: Vec<<Dim<D> as Space<D>>::Domain>,
    /// Total deformation gradient `F` (in 2D, the in-plane block).
    pub deformation: Vec<SMatrix<f64, D, D>>,
    /// Constitutive history (see [`Material::respond`]).
    pub history: Vec<<Dim<D> as Space<D>>::History>,
    /// Whether the point flowed plastically in the last step.
    pub yielding: Vec<bool>,
    pub stress: Vec<<Dim<D> as Space<D>>::Stress>,
    /// The stress's slopes across the point's domain, `dsigma_ij/dx_k`
    /// in the order `[xx,x; xx,y; yy,x; yy,y; xy,x; xy,y]`: what a point
    /// of an elastic body seeded one a cell or fewer holds of its bending
    /// (`assembly::lone_points`); zero for the others.
    pub stress_slopes: Vec<<Dim<D> as Space<D>>::Slopes>,
    /// With F-bar, how far the mean pressure each point worked with in the
    /// last step stood from its own model's, which the next carries across
    /// the grid's reset (`assembly::FbarCells::carrying`); empty before the
    /// first.
    pub fbar_pressure: Vec<f64>,
    /// With the cell-mean strain, how far the stress each point worked with
    /// in the last step stood from its own model's (Kirchhoff's, per unit
    /// reference volume), which the next carries across the grid's reset
    /// (`assembly::CellMean::carrying`); empty before the first.
    pub cell_mean_stress: Vec<SMatrix<f64, D, D>>,
    /// One material per body of the case.
    pub materials: Vec<Material>,
}

impl<const D: usize> MaterialPoints<D>
where
    Dim<D>: Space<D>,
{
    pub fn len(&self) -> usize {
        self.position.len()
    }

    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Volume ratio `J = det F`.
    pub fn jacobian(&self, p: usize) -> f64 {
        <Dim<D> as Space<D>>::determinant(&self.deformation[p])
    }

    /// Current volume `J V0`.
    pub fn volume(&self, p: usize) -> f64 {
        self.jacobian(p) * self.volume0[p]
    }

    /// Bytes of the points' state on the heap.
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

    /// Adds a body's points, each `(position, volume, lattice place,
    /// domain)`, unstrained and unstressed with `history`, with their
    /// material and density; the body's index is the material's.
    fn add_seeds(
        &mut self,
        material: Material,
        density: f64,
        seeds: impl Iterator<Item = ([f64; D], f64, [i64; D], <Dim<D> as Space<D>>::Domain)>,
        history: <Dim<D> as Space<D>>::History,
    ) {
        let body = self.materials.len() as u32;
        self.materials.push(material);
        for (position, volume, lattice, domain) in seeds {
            self.position.push(position);
            self.reference.push(position);
            self.volume0.push(volume);
            self.mass.push(density * volume);
            self.material.push(body);
            self.lattice.push(lattice);
            self.domain.push(domain);
            self.deformation.push(SMatrix::identity());
            self.history.push(history);
            self.yielding.push(false);
            self.stress.push(Default::default());
            self.stress_slopes.push(Default::default());
        }
    }

    /// Displacement from the reference configuration.
    pub fn displacement(&self, p: usize) -> [f64; D] {
        let (x, x0) = (self.position[p], self.reference[p]);
        std::array::from_fn(|d| x[d] - x0[d])
    }
}

impl MaterialPoints {
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

    /// Adds a body's points, seeded in its reference state, with their
    /// material and density; the body's index is the material's.
    pub fn add_body(&mut self, material: Material, density: f64, seeds: &[SeedPoint]) {
        let seeds = seeds
            .iter()
            .map(|s| (s.position, s.volume, s.lattice, s.domain));
        self.add_seeds(material, density, seeds, material.initial_history());
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

impl MaterialPoints<3> {
    /// Adds a 3D body's points, seeded in their reference state, with their
    /// material and density; the body's index is the material's.
    pub fn add_solid(&mut self, material: Material, density: f64, seeds: &[SolidSeed]) {
        let seeds = seeds
            .iter()
            .map(|s| (s.position, s.volume, s.lattice, s.half_widths));
        self.add_seeds(material, density, seeds, History3::virgin());
    }

    /// The first point whose position, deformation or stress is not a
    /// finite number.
    pub fn first_non_finite(&self) -> Option<usize> {
        (0..self.len()).find(|&p| {
            !(self.position[p].iter().all(|x| x.is_finite())
                && self.deformation[p].iter().all(|x| x.is_finite())
                && self.stress[p].iter().all(|x| x.is_finite()))
        })
    }

    /// The point's box domain now: its half-widths scaled by the diagonal
    /// of the right stretch tensor `U = sqrt(F^T F)`, as an upright 2D
    /// cell's, so that it follows stretch but not rotation.
    pub fn support(&self, p: usize) -> Support<3> {
        let u = right_stretch_3d(&self.deformation[p]);
        let h = self.domain[p];
        Support::Rectangle(std::array::from_fn(|d| h[d] * u[(d, d)]))
    }
}

/// `U = sqrt(C)`, `C = F^T F`, by the eigen-decomposition of `C`.
fn right_stretch_3d(f: &Matrix3<f64>) -> Matrix3<f64> {
    let eig = nalgebra::SymmetricEigen::new(f.transpose() * f);
    let roots = eig.eigenvalues.map(|l| l.max(0.0).sqrt());
    eig.eigenvectors * Matrix3::from_diagonal(&roots) * eig.eigenvectors.transpose()
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

    /// A 3D body's points carry their seeds' volumes and masses, start
    /// unstrained, and their box domains follow a stretch but not a
    /// rotation (`U` of `F = R U`).
    #[test]
    fn three_dimensional_points_follow_stretch_not_rotation() {
        use solid_seeding::{Solid, fill};
        let mut points = MaterialPoints::<3>::default();
        let seeds = fill(&Solid::cuboid([0.0; 3], [1.0, 0.5, 0.25]), 0.125);
        let elastic = crate::material::Elastic::from_young_poisson(1e6, 0.3);
        points.add_solid(Material::Hencky(elastic), 2000.0, &seeds);
        assert_eq!(points.len(), 8 * 4 * 2);
        let mass: f64 = points.mass.iter().sum();
        assert!((mass - 2000.0 * 0.125).abs() < 1e-9);
        assert_eq!(points.first_non_finite(), None);
        let (s, c) = 0.4f64.sin_cos();
        let rotation = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        let stretch = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.2, 0.9, 1.1));
        points.deformation[5] = rotation * stretch;
        assert!((points.jacobian(5) - 1.2 * 0.9 * 1.1).abs() < 1e-12);
        let Support::Rectangle(h) = points.support(5) else {
            panic!("a box");
        };
        for (d, k) in [1.2, 0.9, 1.1].iter().enumerate() {
            assert!((h[d] - 0.0625 * k).abs() < 1e-12, "{h:?}");
        }
        assert_eq!(points.displacement(5), [0.0; 3]);
    }

    #[test]
    fn right_stretch_removes_rotation() {
        let (s, c) = 0.7f64.sin_cos();
        let r = Matrix2::new(c, -s, s, c);
        let u = Matrix2::new(1.3, 0.2, 0.2, 0.8);
        assert!((right_stretch(&(r * u)) - u).norm() < 1e-12);
    }
}
