//! Staged analyses: a load held while another is applied, against the same
//! answers worked by hand as the one-stage cases.

use serde_json::json;

use crate::common::run;

/// A Mohr-Coulomb sample (E = 100 MPa, nu = 0.3, c = 10 kPa, phi = 30,
/// psi = 0; GIMP, h = 0.1 m, 2x2 points a cell, grid cut at `origin`) on
/// IBM rollers at x = 0 and y = 0, its top held by an IBM support: first
/// confined by a 100 kPa pressure on x = 1 over 4 steps with the top held
/// still, then sheared at that confinement by pushing the top 5% down in
/// 20 steps (the second stage lists no loads: the pressure is held).
fn confined_then_sheared(origin: [f64; 2]) -> serde_json::Value {
    let top = |d: f64| json!({ "on": { "y": 1.0 }, "fix": "y", "method": "ibm", "displacement": [0.0, d] });
    let rollers = [
        json!({ "on": { "x": 0.0 }, "fix": "normal", "method": "ibm" }),
        json!({ "on": { "y": 0.0 }, "fix": "normal", "method": "ibm" }),
    ];
    json!({
        "version": 1,
        "analysis": {},
        "grid": { "cell_size": 0.1, "origin": origin },
        "basis": "gimp",
        "bodies": [{
            "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [1.0, 1.0] } },
            "points": { "per_cell": 2 },
            "material": { "model": "mohr_coulomb", "youngs_modulus": 1.0e8, "poisson_ratio": 0.3,
                          "density": 0.0, "cohesion": 1.0e4, "friction_angle": 30.0,
                          "dilation_angle": 0.0 }
        }],
        "stages": [
            { "name": "confine", "load_steps": 4,
              "loads": { "boundary": [{ "on": { "x": 1.0 }, "pressure": 1.0e5 }] },
              "supports": [rollers[0], rollers[1], top(0.0)] },
            { "name": "shear", "load_steps": 20,
              "supports": [rollers[0], rollers[1], top(-0.05)] }
        ]
    })
}

/// The two stages, at two grid placements, against the hand solutions.
///
/// Confined with its top held (`eps_yy = eps_zz = 0`), the sample is
/// elastic (Mohr-Coulomb's main plane: `57 - 143 sin(30) - 2 c cos(30) <
/// 0` kPa) with `sigma_xx = -p` and `sigma_yy = nu / (1 - nu) sigma_xx` =
/// -42.86 kPa, to the Hencky model's departure from linear elasticity at
/// strains of 1e-3 (0.1%; tolerance 0.5%). Sheared, it flows at
/// `-sigma_yy = p N_phi + 2 c sqrt(N_phi)` = 334.64 kPa (`plasticity.rs`)
/// with the confinement held: `sigma_xx = -p` at every point. Tolerance
/// 1%, as the one-stage sample (measured there: 0.02%).
///
/// The steps are numbered across the stages and each names its stage;
/// the load factor runs over each stage.
#[test]
fn a_sample_confined_then_sheared_flows_at_the_strength_of_its_confinement() {
    let (p, c, phi) = (1.0e5, 1.0e4, 30f64.to_radians());
    let n_phi = (1.0 + phi.sin()) / (1.0 - phi.sin());
    let strength = p * n_phi + 2.0 * c * n_phi.sqrt();
    for origin in [[0.1, 0.07], [-0.03, 0.045]] {
        let case = confined_then_sheared(origin);
        let mut confined = case.clone();
        confined["stages"].as_array_mut().unwrap().truncate(1);
        let (sim, report) = run(&confined);
        let lateral = 0.3 / 0.7 * p;
        for s in &sim.points.stress {
            assert!((s.plane[0] + p).abs() < 5e-3 * p, "{origin:?}: {s:?}");
            assert!(
                (s.plane[1] + lateral).abs() < 5e-3 * lateral,
                "{origin:?}: {s:?}"
            );
        }
        assert!(sim.points.yielding.iter().all(|&y| !y), "{origin:?}");
        assert_eq!(report.steps.len(), 4);

        let (sim, report) = run(&case);
        let mut worst = [0.0f64; 2];
        for s in &sim.points.stress {
            worst[0] = worst[0].max((s.plane[0] + p).abs() / p);
            worst[1] = worst[1].max((-s.plane[1] - strength).abs() / strength);
        }
        eprintln!(
            "{origin:?}: confinement off by {:.2e}, strength by {:.2e}",
            worst[0], worst[1]
        );
        assert!(worst[0] < 0.01 && worst[1] < 0.01, "{origin:?}: {worst:?}");
        let numbered: Vec<_> = report
            .steps
            .iter()
            .map(|s| (s.step, s.stage.as_deref().unwrap(), s.load_factor))
            .collect();
        assert_eq!(numbered.len(), 24);
        assert_eq!(numbered[3], (4, "confine", 1.0));
        assert_eq!(numbered[4], (5, "shear", 0.05));
        assert_eq!(numbered[23], (24, "shear", 1.0));
    }
}

/// A heavy block of soil (2 m square, rho = 2000 kg/m^3, g = 9.81;
/// Mohr-Coulomb E = 20 MPa, nu = 0.3, c = 5 kPa, phi = 30, psi = 0; GIMP,
/// h = 0.25 m, 2x2 points a cell, grid cut at `origin`) on IBM rollers at
/// x = 0, x = 2 and y = 0: a geostatic stage with K0 = 0.5, then a 20 kPa
/// pressure on its top over 4 steps.
fn heavy_block(origin: [f64; 2]) -> serde_json::Value {
    json!({
        "version": 1,
        "analysis": {},
        "grid": { "cell_size": 0.25, "origin": origin },
        "basis": "gimp",
        "bodies": [{
            "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [2.0, 2.0] } },
            "points": { "per_cell": 2 },
            "material": { "model": "mohr_coulomb", "youngs_modulus": 2.0e7, "poisson_ratio": 0.3,
                          "density": 2000.0, "cohesion": 5.0e3, "friction_angle": 30.0,
                          "dilation_angle": 0.0 }
        }],
        "stages": [
            { "name": "geostatic", "load_steps": 1, "geostatic": { "k0": 0.5 },
              "loads": { "gravity": [0.0, -9.81] },
              "supports": [
                  { "on": { "x": 0.0 }, "fix": "normal", "method": "ibm" },
                  { "on": { "x": 2.0 }, "fix": "normal", "method": "ibm" },
                  { "on": { "y": 0.0 }, "fix": "normal", "method": "ibm" }
              ] },
            { "name": "surcharge", "load_steps": 4,
              "loads": { "gravity": [0.0, -9.81],
                         "boundary": [{ "on": { "y": 2.0 }, "pressure": 2.0e4 }] } }
        ]
    })
}

/// The geostatic stage leaves the points where they were, in the
/// overburden stress: `sigma_yy = -rho g (H - y)`, `sigma_xx = sigma_zz =
/// K0 sigma_yy` (exact for a uniform block on rollers: it satisfies
/// equilibrium and the supports; it is inside the yield surface, `(s1 -
/// s3) + (s1 + s3) sin(phi) = -0.25 sigma_v < 2 c cos(phi)`). The surcharge
/// then adds one-dimensional elastic compression: `-q` vertically and `-nu
/// / (1 - nu) q` horizontally. Tolerance: 2% of the largest vertical stress
/// at every point, the discrete equilibrium's correction of the initial
/// stresses (MPM's nodal integration of a stress linear in depth, and the
/// band's penalty at the supports). Measured: 0.65% and 0.86% after the
/// geostatic stage, 0.89% and 1.3% after the surcharge, at the two grid
/// placements.
#[test]
fn a_geostatic_stage_starts_a_block_in_its_overburden_stress_without_moving_it() {
    let (rho, g, h, q, k0) = (2000.0, 9.81, 2.0, 2.0e4, 0.5);
    let scale = rho * g * h + q;
    for origin in [[0.1, 0.07], [-0.03, 0.045]] {
        let mut first = heavy_block(origin);
        first["stages"].as_array_mut().unwrap().truncate(1);
        let (sim, report) = run(&first);
        assert_eq!(report.steps[0].stage.as_deref(), Some("geostatic"));
        assert_eq!(sim.points.position, sim.points.reference, "nothing moves");
        let mut worst = 0.0f64;
        for (s, x) in sim.points.stress.iter().zip(&sim.points.position) {
            let v = -rho * g * (h - x[1]);
            worst = worst
                .max((s.plane[1] - v).abs())
                .max((s.plane[0] - k0 * v).abs())
                .max((s.zz - k0 * v).abs());
        }
        eprintln!(
            "{origin:?} geostatic: worst stress off {:.2e} of the scale",
            worst / scale
        );
        assert!(worst < 0.02 * scale, "{origin:?}: {worst}");

        let (sim, report) = run(&heavy_block(origin));
        assert_eq!(report.steps.len(), 5);
        // The stage starts with the geostatic reactions carried: its first
        // residual is its surcharge's increment alone (0.12 of the force
        // scale, against 1.0 at the geostatic stage's start).
        assert!(report.steps[1].newton.residuals[0] < 0.2, "{origin:?}");
        let lateral = 0.3 / 0.7;
        let mut worst = 0.0f64;
        for (s, x) in sim.points.stress.iter().zip(&sim.points.reference) {
            let v = -rho * g * (h - x[1]);
            worst = worst
                .max((s.plane[1] - (v - q)).abs())
                .max((s.plane[0] - (k0 * v - lateral * q)).abs());
        }
        eprintln!(
            "{origin:?} surcharged: worst stress off {:.2e} of the scale",
            worst / scale
        );
        assert!(worst < 0.02 * scale, "{origin:?}: {worst}");
    }
}
