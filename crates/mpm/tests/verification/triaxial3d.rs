//! Triaxial compression of a cube through the 3D solver: a unit cube on
//! rollers on three faces (x = 0, y = 0, z = 0), a confining pressure `p`
//! held on the two other side faces from the first step, and an axial
//! force on its top ramped in 43 steps to 1.032 times the strength (steps
//! of 2.4% of it: the cube yields in step 42, at 1.008). Its state is
//! homogeneous up to the quadrature's error where its points' boxes
//! straddle the cells as it shortens (4e-4 of the stress before yield:
//! the linear basis, 2 x 2 x 2 points a cell, the tractions' nodal forces
//! the consistent ones, `boundary::face_loads`). The strengths
//! (compression positive) are those of `material::three_dimensional`'s
//! element test:
//! - von Mises, perfectly plastic: `sigma_1 = p + sigma_y`;
//! - Mohr-Coulomb: `sigma_1 = p N + 2 c sqrt(N)`, `N = (1 + sin phi) / (1 -
//!   sin phi)`;
//! - Drucker-Prager (`sqrt(J2) + eta m = xi c`, `m` the mean stress,
//!   tension positive; the plane-strain match to Mohr-Coulomb): `sigma_1 =
//!   (xi c + p (1/sqrt 3 + 2 eta / 3)) / (1/sqrt 3 - eta / 3)`.
//!
//! Checked: the step the cube first yields in brackets the strength; at
//! the end every point has yielded and its Kirchhoff stress `J sigma`
//! (what the return maps bound) lies on the yield surface, whatever its
//! confinement (the dead confining load is on the reference area, so the
//! lateral stress is not quite `p`); and the mean axial stress is the
//! strength at the mean lateral one. A perfectly plastic cube under dead
//! loads is neutrally stable once it flows: its inhomogeneity grows with
//! the plastic steps (to a 65% spread of the lateral stress 8 steps past
//! yield at 1.2 times the strength), so the check stops one step past.

use mpm::grid::{Basis, Grid};
use mpm::material::{DruckerPrager, Elastic, Material, MohrCoulomb, VonMises};
use mpm::model::{SolidRun, face_loads};
use mpm::particles::MaterialPoints;
use mpm::particles::solid_seeding::{Solid, fill};
use mpm::supports::PlaneSupport;
use mpm::{Observer, Simulation, SolidStepState, StepReport};
use nalgebra::Matrix3;

/// The cube of `material` confined by `p` (Pa) and pushed just past
/// `strength` (axial, compression positive): its points at the end, and
/// the step its points first yielded in.
fn push_past_yield(material: Material, p: f64, strength: f64) -> (MaterialPoints<3>, usize) {
    let h = 0.5;
    let mut points = MaterialPoints::<3>::default();
    points.add_solid(
        material,
        0.0,
        &fill(&Solid::cuboid([0.0; 3], [1.0; 3]), h / 2.0),
    );
    let tol = 1e-9;
    let mut faces = face_loads(&points, (0, 1.0, tol), [-p, 0.0, 0.0], true);
    faces.extend(face_loads(&points, (1, 1.0, tol), [0.0, -p, 0.0], true));
    faces.extend(face_loads(
        &points,
        (2, 1.0, tol),
        [0.0, 0.0, -1.032 * strength],
        false,
    ));
    let roller = |index, axis| PlaneSupport {
        index,
        axis,
        at: 0.0,
        fix: std::array::from_fn(|c| c == axis),
        rotation: None,
    };
    let mut sim = Simulation::solid(SolidRun {
        grid: Grid {
            h,
            origin: [0.0; 3],
        },
        basis: Basis::Linear,
        extent: Some(([0.0; 3], [1.0; 3])),
        points,
        gravity: [0.0; 3],
        point_loads: Vec::new(),
        face_loads: faces,
        faces: Vec::new(),
        surface_loads: Vec::new(),
        supports: vec![roller(0, 0), roller(1, 1), roller(2, 2)],
        surface_supports: Vec::new(),
        load_steps: 43,
    });
    let mut first = FirstYield(None);
    sim.run(&mut first).expect("the cube carries its load");
    (sim.points, first.0.expect("the cube yields"))
}

/// The first step in which a point yielded.
struct FirstYield(Option<usize>);

impl Observer for FirstYield {
    fn solid_step_finished(&mut self, report: &StepReport, state: &SolidStepState<'_>) {
        let points = state.points;
        if self.0.is_none() && points.yielding.iter().any(|&y| y) {
            self.0 = Some(report.step);
        }
    }
}

/// Principal values of a symmetric tensor, compression positive, largest
/// first.
fn principal_compressions(s: &Matrix3<f64>) -> [f64; 3] {
    let mut v: Vec<f64> = s.symmetric_eigenvalues().iter().map(|x| -x).collect();
    v.sort_by(|a, b| b.total_cmp(a));
    [v[0], v[1], v[2]]
}

#[test]
fn cubes_yield_at_their_triaxial_strength() {
    let elastic = Elastic::from_young_poisson(1e7, 0.3);
    let (c, phi) = (1e4, 30f64.to_radians());
    let n = (1.0 + phi.sin()) / (1.0 - phi.sin());
    let von_mises = Material::VonMises(VonMises {
        elastic,
        yield_stress: 1e4,
        hardening: 0.0,
    });
    let mohr_coulomb = Material::MohrCoulomb(MohrCoulomb {
        elastic,
        cohesion: c,
        friction: phi,
        dilation: phi,
    });
    let dp = DruckerPrager::plane_strain_match(elastic, c, phi, phi);
    let (eta, xi) = (dp.eta, dp.xi);
    let root3 = 3f64.sqrt();
    // The axial strength at lateral stress `p`, and the yield function of
    // a stress's principal compressions, in units of the stress.
    type Strength = Box<dyn Fn(f64) -> f64>;
    type Surface = Box<dyn Fn([f64; 3]) -> f64>;
    // Two confinements each, the higher below what would yield the cube
    // before any axial load (von Mises: p < sigma_y).
    let cases: [(&str, Material, [f64; 2], Strength, Surface); 3] = [
        (
            "von Mises",
            von_mises,
            [0.0, 5e3],
            Box::new(|p| p + 1e4),
            Box::new(|[a, b, c]| {
                (((a - b).powi(2) + (b - c).powi(2) + (c - a).powi(2)) / 2.0).sqrt() - 1e4
            }),
        ),
        (
            "Mohr-Coulomb",
            mohr_coulomb,
            [0.0, 2e4],
            Box::new(move |p| p * n + 2.0 * c * n.sqrt()),
            Box::new(move |[a, _, s3]| a - s3 * n - 2.0 * c * n.sqrt()),
        ),
        (
            "Drucker-Prager",
            Material::DruckerPrager(dp),
            [0.0, 2e4],
            Box::new(move |p| {
                (xi * c + p * (1.0 / root3 + 2.0 * eta / 3.0)) / (1.0 / root3 - eta / 3.0)
            }),
            Box::new(move |[a, b, s3]| {
                let j2 = ((a - b).powi(2) + (b - s3).powi(2) + (s3 - a).powi(2)) / 6.0;
                j2.sqrt() - eta * (a + b + s3) / 3.0 - xi * c
            }),
        ),
    ];
    for (name, material, confinements, strength, surface) in cases {
        for p in confinements {
            let sigma_1 = strength(p);
            let (points, first) = push_past_yield(material, p, sigma_1);
            // Step 41 ends at 0.984 of the strength, step 42 at 1.008.
            assert_eq!(first, 42, "{name}, p = {p}");
            assert!(points.yielding.iter().all(|&y| y), "{name}, p = {p}");
            let mut off_surface = 0.0f64;
            let (mut axial, mut lateral) = (0.0, 0.0);
            for q in 0..points.len() {
                let tau = points.stress[q] * points.jacobian(q);
                off_surface =
                    off_surface.max(surface(principal_compressions(&tau)).abs() / sigma_1);
                axial -= tau[(2, 2)] / points.len() as f64;
                lateral -= tau[(0, 0)] / points.len() as f64;
            }
            let miss = (axial - strength(lateral)) / sigma_1;
            eprintln!(
                "{name}, p = {p:.0} Pa: mean axial {axial:.1} Pa at lateral {lateral:.1} (strength there {:.1}, miss {miss:+.1e}); every point's stress within {off_surface:.1e} of the surface",
                strength(lateral)
            );
            assert!(off_surface < 1e-8, "{name}, p = {p}: {off_surface:e}");
            assert!(miss.abs() < 1e-3, "{name}, p = {p}: {miss:e}");
        }
    }
}
