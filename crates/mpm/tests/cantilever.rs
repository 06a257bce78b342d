//! The 10 m x 2 m cantilever under uniform pressure on its top, against an
//! independent converged finite-element solution of linear elasticity with
//! the same supports (rollers on x = 0, a single pinned point at (0, 1)),
//! E = 1 MPa, nu = 0.25, plane strain, p = 1500 Pa (issue 4's reference):
//! - tip horizontal displacement at mid-height: 0.002344 m,
//! - tip deflection relative to the mean vertical displacement of the left
//!   edge: -2.766066 m (the pinned point makes the absolute deflection
//!   depend logarithmically on the support's size; the relative one
//!   converges).
//!
//! Both scale linearly with p. The MPM model here is the small-strain
//! material with p = 1.5 mPa, one load step, results scaled by 1e6. The
//! scale matters for the horizontal displacement: the follower pressure
//! turns with the deflected top and pushes the beam along its axis with a
//! force of about p w_tip, so its relative effect on u_x grows like p; at
//! p = 1.5 Pa it was measured at 0.5%, at 1.5 mPa it is 5e-6.

mod common;

use common::run;
use serde_json::json;
use std::time::Instant;

const TIP_X: f64 = 0.002344;
const RELATIVE_DEFLECTION: f64 = -2.766066;
const SCALE: f64 = 1.0e6;

fn cantilever(h: f64, representation: &str) -> serde_json::Value {
    with_supports(
        h,
        representation,
        json!([ { "on": { "x": 0.0 }, "fix": "x" }, { "on": { "x": 0.0, "y": 1.0 }, "fix": "y" } ]),
    )
}

fn with_supports(h: f64, representation: &str, supports: serde_json::Value) -> serde_json::Value {
    let mut probes = vec![json!({"name": "tip", "at": [10.0, 1.0]})];
    for i in 0..=8 {
        probes.push(json!({"name": format!("left{i}"), "at": [0.0, 0.25 * i as f64]}));
    }
    json!({
        "version": 1,
        "analysis": { "load_steps": 1 },
        "grid": { "cell_size": h },
        "boundary": { "representation": representation },
        "bodies": [{
            "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [10.0, 2.0] } },
            "points": { "per_cell": 2 },
            "material": { "model": "linear_elastic", "youngs_modulus": 1.0e6, "poisson_ratio": 0.25, "density": 0.0 }
        }],
        "loads": { "boundary": [ { "on": { "y": 2.0 }, "pressure": 1500.0 / SCALE } ] },
        "supports": supports,
        "probes": probes
    })
}

/// `(tip horizontal, tip deflection relative to the left edge's mean, seconds)`
/// at p = 1500 Pa.
fn measure(h: f64, representation: &str) -> (f64, f64, f64) {
    let start = Instant::now();
    let (_, report) = run(&cantilever(h, representation));
    let seconds = start.elapsed().as_secs_f64();
    let probes = &report.steps[0].probes;
    let tip = probes[0].displacement;
    // Trapezoidal mean of the left edge's vertical displacement.
    let left: Vec<f64> = probes[1..].iter().map(|p| p.displacement[1]).collect();
    let mean = (left[1..8].iter().sum::<f64>() + 0.5 * (left[0] + left[8])) / 8.0;
    (SCALE * tip[0], SCALE * (tip[1] - mean), seconds)
}

#[test]
fn small_load_cantilever_converges_to_the_finite_element_reference() {
    let mut rows = Vec::new();
    for representation in ["edge", "points"] {
        for h in [1.0, 0.5, 0.25, 0.125] {
            let (ux, rel, s) = measure(h, representation);
            let e_ux = (ux - TIP_X) / TIP_X;
            let e_rel = (rel - RELATIVE_DEFLECTION) / RELATIVE_DEFLECTION;
            eprintln!(
                "{representation:>6} h {h:<6} tip u_x {ux:.6} ({e_ux:+.2e})  relative deflection {rel:.6} ({e_rel:+.2e})  {s:.3} s"
            );
            rows.push((representation, h, e_ux.abs(), e_rel.abs()));
        }
    }
    // Measured (edge, h = 1, 0.5, 0.25, 0.125): relative deflection errors
    // 3.3e-2, 8.8e-3, 2.2e-3, 3.7e-4 (second order: the bilinear cells'
    // bending error); u_x within 1.1e-4 of the reference, which is given to
    // 4 digits (2e-4). Through the points: 9.7e-2 .. 9.0e-3 and u_x 25% ..
    // 2.8% low (first order: the loaded curve is half a spacing short of
    // the edge at each end and half a spacing low).
    let of = |r: &str| {
        rows.iter()
            .filter(move |row| row.0 == r)
            .collect::<Vec<_>>()
    };
    let (edge, points) = (of("edge"), of("points"));
    for w in edge.windows(2) {
        assert!(
            w[1].3 < w[0].3,
            "relative deflection error does not fall: {rows:?}"
        );
    }
    assert!(edge.last().unwrap().3 < 1e-3, "{rows:?}");
    assert!(edge.iter().all(|r| r.2 < 5e-4), "{rows:?}");
    // The material-edge representation is the more accurate at every size.
    for (e, p) in edge.iter().zip(&points) {
        assert!(e.2 < p.2 && e.3 < p.3, "{rows:?}");
    }
}

/// The same beam with its whole left edge clamped (all grid nodes on x = 0
/// fixed): the reference tip deflection is -2.7452 m at p = 1500 Pa.
#[test]
fn clamped_cantilever_converges_to_the_finite_element_reference() {
    const CLAMPED_TIP: f64 = -2.7452;
    let clamp = json!([ { "on": { "x": 0.0 }, "fix": "xy" } ]);
    let mut errors = Vec::new();
    for h in [1.0, 0.5, 0.25, 0.125] {
        let (_, report) = run(&with_supports(h, "edge", clamp.clone()));
        let tip = SCALE * report.steps[0].probes[0].displacement[1];
        let e = (tip - CLAMPED_TIP) / CLAMPED_TIP;
        eprintln!("clamped h {h:<6} tip deflection {tip:.5} ({e:+.2e})");
        errors.push(e.abs());
    }
    // Measured: 4.0e-2, 1.2e-2, 3.8e-3, 1.2e-3 (order 1.7, a little below
    // the pinned case's relative deflection).
    for w in errors.windows(2) {
        assert!(w[1] < w[0], "{errors:?}");
    }
    assert!(errors[3] < 2e-3, "{errors:?}");
}
