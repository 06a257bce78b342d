//! The factor of safety by strength reduction against the collapse load
//! it should give back. A strip of width B under a uniform pressure `q`
//! on weightless undrained clay collapses at Prandtl's `q = (2 + pi) c`
//! (Prandtl 1920; a uniform pressure is the smooth footing's limit load,
//! Chen 1975, Limit analysis and soil plasticity, section 8.4). Loaded to
//! `q = 0.75 (2 + pi) c` and then reduced, the clay (von Mises, `k =
//! c / F`) stands until `c / F = q / (2 + pi)`: the factor of safety is
//! exactly `4 / 3`.
//!
//! The case is the built-in `footing`'s soil (half model, B = 1 m, 5 m x
//! 3 m, c = 10 kPa, E = 100 MPa, nu = 0.49, F-bar, GIMP, 2 x 2 points per
//! cell) at h = B/8, the pressure on the footing's stretch in 6 steps,
//! then the reduction (increment 0.1, tolerance 0.01), the grid's origin
//! at `-offset h` in x (the pressure's edge at that fraction of its cell)
//! and `-0.3 h` in y.
//!
//! Measured (docs/guide.md, "Strength reduction"): with no ghost penalty
//! 1.3375 at offset 0.3 (+0.3%); with the default ghost penalty (1e-3 of
//! the shear modulus, a fifth of it where the soil flows, on each step's
//! increment) 1.35625 (+1.7%) and 1.35 at offset 0.6 (+1.25%): the penalty
//! carries a share of the load that grows with the increment, and a trial
//! near collapse is one large increment. The pressure ramp itself comes to within 1.0% of Prandtl at
//! this cell under arc-length control (docs/study/footing), and the
//! bisection stops within 0.01 above the factor (0.75%): the bound, 2%,
//! is their sum with a quarter again.

use std::f64::consts::PI;

use serde_json::json;

use crate::common::{example, run};

const COHESION: f64 = 10e3;
const EXACT: f64 = 4.0 / 3.0;

/// The footing's soil loaded by `0.75 (2 + pi) c` on its half-width and
/// reduced, at cell `h`, with the grid's origin at `-offset h` in x and the
/// ghost penalty `ghost` (`None`: the default).
pub fn loaded_then_reduced(h: f64, offset: f64, ghost: Option<f64>) -> serde_json::Value {
    let mut case = example("footing");
    case["grid"]["cell_size"] = json!(h);
    case["grid"]["origin"] = json!([-offset * h, -0.3 * h]);
    case["analysis"] = json!({ "volumetric": "fbar" });
    if let Some(g) = ghost {
        case["analysis"]["stabilisation"] = json!({ "ghost_penalty": g });
    }
    let mut supports = case["supports"].as_array().unwrap().clone();
    supports.remove(0);
    case.as_object_mut().unwrap().remove("supports");
    let stretch = json!({ "segment": [[0.0, 3.0], [0.5, 3.0]] });
    let q = 0.75 * (2.0 + PI) * COHESION;
    case["stages"] = json!([
        {
            "name": "load",
            "load_steps": 6,
            "loads": { "boundary": [ { "on": stretch, "pressure": q } ] },
            "supports": supports
        },
        {
            "name": "reduce",
            "load_steps": 40,
            "strength_reduction": { "increment": 0.1, "tolerance": 0.01 }
        }
    ]);
    case
}

/// The factor found, the bracket's failed factor, and the steps.
fn factor_of_safety(case: &serde_json::Value) -> (f64, f64, Vec<mpm::StepReport>) {
    let (_, report) = run(case);
    let last = report.steps.last().expect("steps");
    let found = last
        .strength_reduction
        .clone()
        .expect("a strength-reduction step");
    assert!(found.found, "{found:?}");
    (
        found.factor,
        found.failed.expect("a failed trial"),
        report.steps,
    )
}

#[test]
fn strength_reduction_gives_back_the_collapse_load_at_two_grid_placements() {
    for offset in [0.3, 0.6] {
        let (factor, failed, steps) =
            factor_of_safety(&loaded_then_reduced(0.125, offset, Some(0.0)));
        let error = factor / EXACT - 1.0;
        eprintln!(
            "offset {offset}: F = {factor:.5} ({:+.2}%), failed at {failed:.5}, {} steps",
            100.0 * error,
            steps.len()
        );
        assert!(error.abs() < 0.02, "offset {offset}: {factor}");
        assert!(failed > factor && failed - factor <= 0.01 + 1e-9);
        // The reduction's steps: the factor never falls, the loads stay on.
        let reduce: Vec<_> = steps
            .iter()
            .filter_map(|s| s.strength_reduction.as_ref())
            .collect();
        assert!(reduce.windows(2).all(|w| w[1].factor >= w[0].factor));
        // (A boundary load ends at the last data point in its stretch, so
        // the pressure acts on 15/16 of the half-width here; Prandtl's
        // pressure does not depend on the width.)
        let loaded = steps
            .iter()
            .rfind(|s| s.strength_reduction.is_none())
            .unwrap();
        let last = steps.last().unwrap();
        let held = last.applied_load[1] / loaded.applied_load[1];
        assert!((held - 1.0).abs() < 5e-3, "{held}");
    }
}

/// With the default ghost penalty the factor stays within 3% at both
/// placements: measured 1.35625 (+1.7%) and 1.35 (+1.25%). The penalty
/// lends a fifth of the modulus where the soil flows; at the full modulus
/// it found 1.3875 (+4.1%) at offset 0.6, and this fails.
#[test]
fn the_default_ghost_penalty_keeps_the_factor_within_three_percent() {
    for offset in [0.3, 0.6] {
        let (factor, _, _) = factor_of_safety(&loaded_then_reduced(0.125, offset, None));
        let error = factor / EXACT - 1.0;
        eprintln!(
            "offset {offset}, default ghost: F = {factor:.5} ({:+.2}%)",
            100.0 * error
        );
        assert!(error.abs() < 0.03, "offset {offset}: {factor}");
    }
}

/// With the cell-mean strain (`analysis.volumetric: cell_mean`) each trial
/// starts from the state that held, each point's stress carried across
/// the grid's reset less what the weakening took from its own
/// (`CellMean::carrying`). Carried whole, the stresses of the state that
/// held came back at every trial, and Griffiths and Lane's slope (H/20)
/// stood at every factor up to 9. The hourglass stiffness acts on a
/// trial's whole increment, as the ghost penalty does: at the default
/// (1e-2 of `2 mu`) the factor is 1.45 (+8.75%) at offsets 0.3 and 0.6;
/// at 1e-3, 1.33125 (-0.16%); at 1e-4, 1.30625 (-2.0%). Asked at 1e-3,
/// the bound is the F-bar case's, 2%.
#[test]
fn strength_reduction_with_the_cell_mean_gives_back_the_collapse_load() {
    let mut case = loaded_then_reduced(0.125, 0.3, Some(0.0));
    case["analysis"]["volumetric"] = json!("cell_mean");
    case["analysis"]["stabilisation"]["hourglass"] = json!(1e-3);
    let (factor, failed, _) = factor_of_safety(&case);
    let error = factor / EXACT - 1.0;
    eprintln!(
        "cell mean: F = {factor:.5} ({:+.2}%), failed at {failed:.5}",
        100.0 * error
    );
    assert!(error.abs() < 0.02, "{factor}");
}

/// Griffiths and Lane's (1999) example 1, the built-in `slope`: a 2:1
/// slope, H = 10 m, on a firm base at the toe's level, Mohr-Coulomb c' =
/// 10 kPa, phi' = 20 degrees, psi = 0, gamma = 20 kN/m^3, at h = H/20
/// (GIMP, 2 x 2 points a cell). References: Bishop and Morgenstern's
/// (1960) charts, limit equilibrium on circles, 1.38; Griffiths and
/// Lane's finite elements (non-convergence in 1000 iterations) 1.4.
///
/// Before the flow limit the factor followed the path: 1.5125 rising by
/// 0.1, 1.60 by 0.05 and 1.39 by 0.03, 1.50 with the grid moved, each
/// trial past about 1.4 holding after its crest slid a further 24-212 mm.
/// With it (10, as the built-in sets it): 1.3625 at both placements, 1.35
/// rising by 0.05 (the curve turns up between 1.35 and 1.40 at every
/// placement and increment). Associated flow (psi = phi), which is what limit
/// equilibrium and limit analysis assume: 1.40. The bound is the issue's,
/// 3% of Bishop's; the spread of the three psi = 0 runs at most 0.02, two
/// steps of the bisection's tolerance. Non-associated flow lowers the
/// collapse load of a frictional soil (Drescher and Detournay 1993; by
/// at most cos(phi) = 0.94 in Davis's estimate), and 1.35-1.3625 is
/// 1.3-2.2% below Bishop's, 2.7-3.6% below Griffiths and Lane's.
#[test]
fn griffiths_and_lanes_slope_stands_to_its_factor_of_safety_however_the_factor_rises() {
    const BISHOP: f64 = 1.38;
    let factor = |offset: f64, increment: f64, dilation: f64| {
        let mut case = example("slope");
        case["grid"]["origin"] = json!([-offset * 0.5, -0.15]);
        case["stages"][1]["strength_reduction"]["increment"] = json!(increment);
        case["bodies"][0]["material"]["dilation_angle"] = json!(dilation);
        let (f, failed, _) = factor_of_safety(&case);
        eprintln!(
            "origin -{offset} h, increment {increment}, psi = {dilation}: F = {f:.5} ({:+.2}% against Bishop), failed at {failed:.5}",
            100.0 * (f / BISHOP - 1.0)
        );
        f
    };
    let found = [
        factor(0.3, 0.1, 0.0),
        factor(0.7, 0.1, 0.0),
        factor(0.3, 0.05, 0.0),
    ];
    for f in found {
        assert!((f / BISHOP - 1.0).abs() < 0.03, "{found:?}");
    }
    let spread = found.iter().copied().fold(f64::MIN, f64::max)
        - found.iter().copied().fold(f64::MAX, f64::min);
    assert!(spread <= 0.02 + 1e-9, "{found:?}");
    let associated = factor(0.3, 0.1, 20.0);
    assert!((associated / BISHOP - 1.0).abs() < 0.03, "{associated}");
}
