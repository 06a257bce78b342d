//! The 10 m x 2 m cantilever under uniform pressure on its top, against
//! independent finite-element solutions of linear elasticity with the same
//! supports (rollers on x = 0, a single pinned point at (0, 1)), E = 1 MPa,
//! nu = 0.25, plane strain, p = 1500 Pa:
//! - tip horizontal displacement at mid-height: 0.00234375 m, exact: split
//!   the load about y = 1 into bending, which leaves the centre line's u_x
//!   zero, and a uniform compression `sigma_yy = -p/2`, which gives
//!   `u_x = 10 nu (1 + nu) p / (2E)`;
//! - tip deflection relative to the mean vertical displacement of the left
//!   edge: -2.76606576 m, within 4e-8 (the pinned point makes the absolute
//!   deflection depend logarithmically on the support's size; the relative
//!   one converges).
//!
//! `scripts/cantilever_reference.py` computes both with biquadratic (Q9)
//! finite elements on meshes of 20 x 4 to 640 x 128 elements and
//! Richardson extrapolation (its docstring has the table); it also gives
//! the clamped beam's tip deflection used below.
//!
//! Both scale linearly with p. The MPM model here is the small-strain
//! material with p = 1.5 mPa, one load step, results scaled by 1e6. The
//! scale matters for the horizontal displacement: the follower pressure
//! turns with the deflected top and pushes the beam along its axis with a
//! force of about p w_tip, so its relative effect on u_x grows like p; at
//! p = 1.5 Pa it was measured at 0.5%, at 1.5 mPa it is 5e-6.

use crate::common::run;
use mpm::newton::observed_order;
use serde_json::json;

const TIP_X: f64 = 0.00234375;
const RELATIVE_DEFLECTION: f64 = -2.76606576;
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

/// `(tip horizontal, tip deflection relative to the left edge's mean)`
/// at p = 1500 Pa.
fn measure(h: f64, representation: &str) -> (f64, f64) {
    measure_case(cantilever(h, representation), h, [0.0, 0.0])
}

#[test]
fn small_load_cantilever_converges_to_the_finite_element_reference() {
    let mut rows = Vec::new();
    for representation in ["edge", "points"] {
        for h in [1.0, 0.5, 0.25, 0.125] {
            let (ux, rel) = measure(h, representation);
            let e_ux = (ux - TIP_X) / TIP_X;
            let e_rel = (rel - RELATIVE_DEFLECTION) / RELATIVE_DEFLECTION;
            eprintln!(
                "{representation:>6} h {h:<6} tip u_x {ux:.6} ({e_ux:+.2e})  relative deflection {rel:.6} ({e_rel:+.2e})"
            );
            rows.push((representation, h, e_ux.abs(), e_rel.abs()));
        }
    }
    // Measured (edge, h = 1, 0.5, 0.25, 0.125): relative deflection errors
    // 3.5e-2, 9.1e-3, 2.3e-3, 3.8e-4 (second order: the bilinear cells'
    // bending error); u_x within 5e-6 of the exact value at every h (the
    // follower pressure's push along the beam, module docs). Through the
    // points: 9.9e-2 .. 9.0e-3 and u_x 25% .. 2.8% low (first order: the
    // loaded curve is half a spacing short of the edge at each end and half
    // a spacing low).
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
    assert!(edge.iter().all(|r| r.2 < 2e-5), "{rows:?}");
    // The material-edge representation is the more accurate at every size.
    for (e, p) in edge.iter().zip(&points) {
        assert!(e.2 < p.2 && e.3 < p.3, "{rows:?}");
    }
}

/// The same beam with its whole left edge clamped (all grid nodes on x = 0
/// fixed): the reference tip deflection is -2.745340 m at p = 1500 Pa,
/// within 2e-5 (`scripts/cantilever_reference.py`; the corners of the
/// clamped edge are singular, and the Q9 meshes converge at order 1.45).
const CLAMPED_TIP: f64 = -2.745340;

#[test]
fn clamped_cantilever_converges_to_the_finite_element_reference() {
    let clamp = json!([ { "on": { "x": 0.0 }, "fix": "xy" } ]);
    let mut errors = Vec::new();
    for h in [1.0, 0.5, 0.25, 0.125] {
        let (_, report) = run(&with_supports(h, "edge", clamp.clone()));
        let tip = SCALE * report.steps[0].probes[0].displacement[1];
        let e = (tip - CLAMPED_TIP) / CLAMPED_TIP;
        eprintln!("clamped h {h:<6} tip deflection {tip:.5} ({e:+.2e})");
        errors.push(e.abs());
    }
    // Measured: 4.22e-2, 1.28e-2, 3.89e-3, 1.23e-3 (order 1.7, a little below
    // the pinned case's relative deflection).
    for w in errors.windows(2) {
        assert!(w[1] < w[0], "{errors:?}");
    }
    assert!(errors[3] < 2e-3, "{errors:?}");
}

/// The rollers and the mid-height support by the implicit boundary method.
fn ibm_supports() -> serde_json::Value {
    json!([
        { "on": { "x": 0.0 }, "fix": "normal", "method": "ibm" },
        { "on": { "x": 0.0, "y": 1.0 }, "fix": "xy", "method": "ibm" }
    ])
}

/// `measure` for any of these cases, with the grid's origin moved by `shift`
/// cells.
fn measure_case(mut case: serde_json::Value, h: f64, shift: [f64; 2]) -> (f64, f64) {
    case["grid"]["origin"] = json!([shift[0] * h, shift[1] * h]);
    let (_, report) = run(&case);
    let probes = &report.steps[0].probes;
    let tip = probes[0].displacement.clone();
    // Trapezoidal mean of the left edge's vertical displacement.
    let left: Vec<f64> = probes[1..].iter().map(|p| p.displacement[1]).collect();
    let mean = (left[1..8].iter().sum::<f64>() + 0.5 * (left[0] + left[8])) / 8.0;
    (SCALE * tip[0], SCALE * (tip[1] - mean))
}

/// The pinned beam with its supports by the implicit boundary method: the
/// same references as above. With the grid's lines where the body's are
/// not, the IBM is the only way to hold it. Measured (linear basis,
/// h = 1 .. 0.125, relative errors of the relative deflection | tip u_x):
/// - aligned grid: 3.6e-2, 8.5e-3, 1.8e-3, 2.0e-4 | 1.6e-2, 4.5e-3, 1.2e-3,
///   3.0e-4 (grid-node supports: 3.5e-2 .. 3.8e-4 | 5e-6 throughout; the
///   IBM fixes a stretch one point spacing long where the reference pins a
///   point, and its penalty gives a little: 1e-3 of the relative deflection
///   at delta = h/100, see docs/ibm.md);
/// - grid moved by half a cell both ways: 3.0e-2 .. 3.4e-4 | 1.0e-2 ..
///   1.8e-4.
///
/// Moved by 0.21 of a cell vertically, the relative deflection converges
/// alike (5.5e-4 at 0.125) but u_x, a thousandth of the deflection, is
/// first order (2.1e-2 at 0.125): the two point rows of each cell sit
/// unsymmetrically about the neutral axis, and the bilinear basis sampled
/// at points then couples bending into stretching. Moved by 0.37 of a cell
/// horizontally, the point columns sit at 0.12 and 0.62 of every cell and
/// the bilinear basis's deflection stalls 1e-3 from the aligned grid's; GIMP
/// (exact cell integrals of each domain) brings that to 3e-4 and falling.
#[test]
fn ibm_supported_cantilever_converges_to_the_finite_element_reference() {
    for shift in [[0.0, 0.0], [0.5, 0.5], [0.0, 0.21]] {
        let mut errors = Vec::new();
        for h in [1.0, 0.5, 0.25, 0.125] {
            let (ux, rel) = measure_case(with_supports(h, "edge", ibm_supports()), h, shift);
            let e_ux = (ux - TIP_X) / TIP_X;
            let e_rel = (rel - RELATIVE_DEFLECTION) / RELATIVE_DEFLECTION;
            eprintln!(
                "ibm, grid moved {shift:?} cells, h {h:<6} tip u_x {ux:.6} ({e_ux:+.2e})  relative deflection {rel:.6} ({e_rel:+.2e})"
            );
            errors.push((e_ux.abs(), e_rel.abs()));
        }
        for w in errors.windows(2) {
            assert!(w[1].1 < w[0].1 && w[1].0 < w[0].0, "{shift:?}: {errors:?}");
        }
        let finest = errors[3];
        assert!(finest.1 < 1e-3, "{shift:?}: {errors:?}");
        if shift[1] != 0.21 {
            assert!(finest.0 < 1e-3, "{shift:?}: {errors:?}");
        }
    }
}

/// The clamped beam (whole left edge fixed by the IBM) on grids cutting the
/// left edge inside a cell, GIMP, against the reference above (-2.745340 m).
/// Measured, h = 0.5 .. 0.0625: moved (0.37, 0.21) cells 9.6e-3, 2.7e-3,
/// 8.0e-4, 2.8e-4; moved half a cell 1.08e-2, 3.0e-3, 8.3e-4, 2.2e-4
/// (grid-node clamp on the aligned grid: 1.28e-2, 3.9e-3, 1.2e-3 at 0.5 ..
/// 0.125).
#[test]
fn ibm_clamped_cantilever_on_a_cut_grid_converges() {
    let clamp = json!([ { "on": { "x": 0.0 }, "fix": "xy", "method": "ibm" } ]);
    for shift in [[0.37, 0.21], [0.5, 0.0]] {
        let mut errors = Vec::new();
        for h in [0.5, 0.25, 0.125, 0.0625] {
            let mut case = with_supports(h, "edge", clamp.clone());
            case["grid"]["origin"] = json!([shift[0] * h, shift[1] * h]);
            case["basis"] = json!("gimp");
            let (_, report) = run(&case);
            let tip = SCALE * report.steps[0].probes[0].displacement[1];
            let e = (tip - CLAMPED_TIP) / CLAMPED_TIP;
            eprintln!(
                "ibm clamped, gimp, grid moved {shift:?} cells, h {h:<6} tip {tip:.5} ({e:+.2e})"
            );
            errors.push(e.abs());
        }
        for w in errors.windows(2) {
            assert!(w[1] < w[0], "{shift:?}: {errors:?}");
        }
        assert!(errors[3] < 1e-3, "{shift:?}: {errors:?}");
    }
}

/// The paper's case as built in (`mpm example cantilever`): 1500 Pa follower
/// pressure in 5 steps, left edge on IBM rollers and fixed at mid-height.
/// Newton must converge quadratically in every step (the order estimated
/// from the last three residuals; measured 2.6 .. 2.9) and the supports.
/// reactions must balance the pressure's resultant on the deformed top
/// (measured to 3e-15 of it: the material's internal forces sum to zero
/// by the partition of unity, so the imbalance is the sum of the Newton
/// residual; a wrong sign or a missing term in the band's reactions shows).
#[test]
fn papers_cantilever_converges_quadratically_and_its_reactions_balance() {
    let (_, report) = run(&crate::common::example("cantilever"));
    for s in &report.steps {
        let r = &s.newton.residuals;
        let n = r.len();
        let order = observed_order([r[n - 3], r[n - 2], r[n - 1]]);
        let applied = s.applied_load.clone();
        let total = [0, 1].map(|c| s.reactions.iter().map(|f| f[c]).sum::<f64>() + applied[c]);
        let size = applied[0].hypot(applied[1]);
        eprintln!(
            "step {}: residuals {r:?}, order {order:.2}, applied {applied:.3?}, reactions {:.3?}, imbalance {:.1e}",
            s.step,
            s.reactions,
            total[0].hypot(total[1]) / size
        );
        assert!(order > 1.8, "step {}: {r:?}", s.step);
        assert!(
            total[0].hypot(total[1]) < 1e-6 * size,
            "step {}: {total:?}",
            s.step
        );
    }
}

/// Where the grid lies, per basis: the small-load beam on IBM supports at
/// h = 0.5 m over seven grid origins spread over a cell (`(k/7, 3k mod
/// 7 / 7)`). Measured spreads (largest minus smallest, relative to the
/// reference) of tip u_x | relative deflection: GIMP 1.6e-1 | 2.2e-2,
/// bspline2 5.3e-2 | 5.0e-3, bspline3 3.5e-2 | 5.0e-3 (u_x is a thousandth
/// of the deflection, so any coupling of bending into stretching shows in
/// it); worst errors of the relative deflection GIMP 1.3e-2, bspline2 and
/// bspline3 1.6e-2 (at this cell size the B-splines' systematic error is
/// the larger, see the next test). Asserted:
/// the B-splines' spread of the deflection under 6e-3 and under a third of
/// GIMP's. The remaining spread is the boundary's (the supports' anchors
/// and the pressure's quadrature move with the grid), which every basis
/// shares.
#[test]
fn bsplines_depend_less_on_where_the_grid_lies() {
    let h = 0.5;
    let mut spreads = Vec::new();
    for basis in ["gimp", "bspline2", "bspline3"] {
        let mut ux = Vec::new();
        let mut rel = Vec::new();
        for k in 0..7 {
            let shift = [k as f64 / 7.0, (3 * k % 7) as f64 / 7.0];
            let mut case = with_supports(h, "edge", ibm_supports());
            case["basis"] = basis.into();
            let (u, r) = measure_case(case, h, shift);
            ux.push((u - TIP_X) / TIP_X);
            rel.push((r - RELATIVE_DEFLECTION) / RELATIVE_DEFLECTION);
        }
        let spread = |v: &[f64]| {
            v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - v.iter().copied().fold(f64::INFINITY, f64::min)
        };
        let worst = |v: &[f64]| v.iter().map(|e| e.abs()).fold(0.0, f64::max);
        eprintln!(
            "{basis}, h {h}: u_x spread {:.2e} worst {:.2e}; relative deflection spread {:.2e} worst {:.2e}",
            spread(&ux),
            worst(&ux),
            spread(&rel),
            worst(&rel)
        );
        spreads.push(spread(&rel));
    }
    for (basis, s) in ["bspline2", "bspline3"].iter().zip(&spreads[1..]) {
        assert!(*s < 6e-3 && *s < spreads[0] / 3.0, "{basis}: {spreads:?}");
    }
}

/// The small-load beam on IBM supports with the B-splines (aligned grid,
/// h = 1 .. 0.125; relative errors of the relative deflection | tip u_x):
/// bspline2 6.25e-2, 1.64e-2, 4.42e-3, 1.42e-3 | 1.19e-2, 3.83e-3, 1.01e-3,
/// 2.57e-4; bspline3 6.23e-2, 1.64e-2, 4.43e-3, 1.40e-3 | 1.01e-2, 3.44e-3,
/// 9.14e-4, 2.33e-4. Orders 1.6 to 2.0. Asserted: the deflection's error
/// falling at every refinement at an overall order above 1.6, under 2e-3
/// at the finest, u_x under 1e-3. (The bilinear basis on this aligned grid
/// is luckier, 2.0e-4, and loses it when the grid moves; see above.)
#[test]
fn bspline_cantilever_converges_to_the_finite_element_reference() {
    for basis in ["bspline2", "bspline3"] {
        let mut errors = Vec::new();
        for h in [1.0, 0.5, 0.25, 0.125] {
            let mut case = with_supports(h, "edge", ibm_supports());
            case["basis"] = basis.into();
            let (ux, rel) = measure_case(case, h, [0.0, 0.0]);
            let e_ux = (ux - TIP_X) / TIP_X;
            let e_rel = (rel - RELATIVE_DEFLECTION) / RELATIVE_DEFLECTION;
            eprintln!(
                "{basis}, h {h:<6} tip u_x {ux:.6} ({e_ux:+.2e})  relative deflection {rel:.6} ({e_rel:+.2e})"
            );
            errors.push((e_ux.abs(), e_rel.abs()));
        }
        for w in errors.windows(2) {
            assert!(w[1].1 < w[0].1, "{basis}: {errors:?}");
        }
        let overall = (errors[0].1 / errors[3].1).log2() / 3.0;
        assert!(
            overall > 1.6 && errors[3].1 < 2e-3,
            "{basis}: order {overall:.2}, {errors:?}"
        );
        assert!(errors[3].0 < 1e-3, "{basis}: {errors:?}");
    }
}
