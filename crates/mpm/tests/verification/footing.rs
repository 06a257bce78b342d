//! The rigid strip footing on weightless undrained clay against Prandtl's
//! collapse pressure `q = (2 + pi) c` (Prandtl 1920; for a smooth and a
//! rough rigid footing alike on weightless undrained soil, since the rigid
//! wedge under a rough one carries no shear on its base: Chen 1975, Limit
//! analysis and soil plasticity, section 8.4).
//!
//! The case is the built-in `footing` (half model, B = 1 m, soil 5 m x 3 m,
//! von Mises with `sigma_y = sqrt(3) c` so that `k = c` in plane strain,
//! c = 10 kPa, E = 100 MPa, nu = 0.49, F-bar, GIMP, 2 x 2 points per cell),
//! its footing held by the implicit boundary method on average over pieces
//! of about two cells (`"constraint": "averaged"`) and pushed 0.01 B in 40
//! steps, the grid's origin at -0.3 h (the footing's edge at 0.5 / h + 0.3
//! of its cell: 0.3 at h = 0.25, 0.125 and 0.0625) unless a test moves it.
//!
//! The tolerances are the method's own error at these cells, measured
//! (docs/study/footing/footing.md has the study): the velocity jump at the
//! footing's edge is smeared over the cell beside it, which makes the
//! error first order in h, and the ghost penalty, scaled by the clay's
//! elastic stiffness, resists the flow by a few tenths of a percent more
//! (docs/ibm.md, Why the ghost ties). Read at 0.005 B (this clay collapses
//! near 0.003 B, and past it the load rises as the soil heaves, by 0.1-0.6%
//! more at 0.01 B): smooth +1.93%, +0.74% and +0.78% at h = B/4, B/8
//! and B/16; rough +4.67%, +2.24% and +1.40%. Each bound is the measured
//! error and a quarter of it again, within the 5% at B/8 and 2% at B/16
//! the collapse-load issue asks; the error must also fall by at least 1.5
//! times from B/4 to B/8, and stay above Prandtl's load. At B/16 the
//! smooth footing's error has met the ghost penalty's floor and no longer
//! falls (on clay ten times stiffer, where the geometry does not change
//! before collapse: +1.50%, +0.49%, +0.42%).

use std::f64::consts::PI;

use serde_json::json;

use crate::common::{example, run};

const HALF_WIDTH: f64 = 0.5;
const COHESION: f64 = 10e3;

/// The footing case at cell `h` with the grid's origin at `-offset h` in x,
/// pushed 0.01 B in 40 steps, smooth (y held) or rough (both held).
fn footing(h: f64, offset: f64, rough: bool) -> serde_json::Value {
    let mut case = example("footing");
    case["analysis"]["load_steps"] = json!(40);
    case["grid"]["cell_size"] = json!(h);
    case["grid"]["origin"] = json!([-offset * h, -0.3 * h]);
    case["supports"][0]["displacement"] = json!([0.0, -0.01 * 2.0 * HALF_WIDTH]);
    case["supports"][0]["fix"] = json!(if rough { "xy" } else { "y" });
    case
}

/// q / c at the last step: the footing support's reaction over the half
/// width, and that step's report.
fn pressure(case: &serde_json::Value) -> (f64, mpm::StepReport) {
    let (_, report) = run(case);
    let last = report.steps.last().expect("steps").clone();
    (q_over_c(&last), last)
}

fn q_over_c(step: &mpm::StepReport) -> f64 {
    -step.reactions[0][1] / HALF_WIDTH / COHESION
}

#[test]
fn a_rigid_footing_on_undrained_clay_comes_to_prandtls_load_as_the_cells_shrink() {
    let exact = 2.0 + PI;
    // (rough, bounds at B/4, B/8 and B/16), each the measured error + 25%.
    for (rough, bounds) in [
        (false, [0.025, 0.0095, 0.0098]),
        (true, [0.059, 0.028, 0.0175]),
    ] {
        let errors: Vec<f64> = [0.25, 0.125, 0.0625]
            .iter()
            .map(|&h| {
                let (_, report) = run(&footing(h, 0.3, rough));
                // The steps from the first: step 20 of 40 is 0.005 B.
                let curve: Vec<f64> = report.steps.iter().map(q_over_c).collect();
                let q = curve[19];
                let error = q / exact - 1.0;
                eprintln!("rough {rough} h {h}: q/c {q:.4} ({:+.2}%)", 100.0 * error);
                // Past the collapse the load may level off or rise as the
                // soil heaves, but not drop: at B/8 points change cell from
                // 0.006 B, and F-bar's pressure carried across the grid's
                // reset (`FbarCells::carrying`) keeps the curve smooth there
                // (before, rough: 5.526 at 0.005 B, 5.401 at 0.007 B).
                for k in 20..curve.len() {
                    assert!(
                        curve[k] > curve[k - 1] * (1.0 - 1e-3),
                        "rough {rough} h {h}: the load fell in step {}: {curve:?}",
                        k + 1
                    );
                }
                error
            })
            .collect();
        for (error, bound) in errors.iter().zip(bounds) {
            assert!(*error > 0.0 && *error < bound, "rough {rough}: {errors:?}");
        }
        assert!(errors[0] / errors[1] > 1.5, "rough {rough}: {errors:?}");
    }
}

/// Where the footing's edge falls in its cell: at h = B/8, on a grid line
/// (origin offset 0) and at 0.6 of its cell, q / c is 5.2370 and 5.1686,
/// 1.31% apart (held pointwise, 6.96 on the grid line and 6.54 with the
/// edge at 0.3 of its cell; at h = 0.2 m two origins gave 5.54 against
/// 6.30, 15%). At B/16 five placements lie within 0.64% (the study). The
/// bound, 2.5%, is that spread with room for the rounding of where the
/// pieces fall.
#[test]
fn where_the_footings_edge_falls_in_a_cell_moves_its_load_by_little() {
    let q: Vec<f64> = [0.0, 0.6]
        .iter()
        .map(|&offset| pressure(&footing(0.125, offset, false)).0)
        .collect();
    let spread = (q[0] - q[1]).abs() / (0.5 * (q[0] + q[1]));
    eprintln!("q/c {q:?}: spread {:.2}%", 100.0 * spread);
    assert!(spread < 0.025, "{q:?}");
}

/// The contact tractions the step reports along the footing add up to its
/// reaction, and a smooth footing's carry no shear.
#[test]
fn the_footings_contact_tractions_add_up_to_its_reaction() {
    let (_, last) = pressure(&footing(0.25, 0.3, false));
    let along: Vec<_> = (last.support_tractions.iter())
        .filter(|t| t.support == 0)
        .collect();
    assert!(!along.is_empty());
    let total: f64 = along.iter().map(|t| t.traction[1] * t.length).sum();
    let reaction = last.reactions[0][1];
    assert!(
        (total - reaction).abs() < 1e-9 * reaction.abs(),
        "{total} against {reaction}"
    );
    assert!(along.iter().all(|t| t.traction[0] == 0.0));
    let length: f64 = along.iter().map(|t| t.length).sum();
    assert!((length - HALF_WIDTH).abs() < 0.02 * HALF_WIDTH, "{length}");
}

/// A rough rigid footing on weightless Mohr-Coulomb soil (phi = psi = 30
/// degrees, c = 10 kPa, E = 100 MPa, nu = 0.3) pushed 0.02 B in 20 steps,
/// against Prandtl-Reissner's `N_c = (N_q - 1) cot(phi)` = 30.14 with
/// `N_q = exp(pi tan(phi)) tan^2(45 + phi / 2)` (Reissner 1924; exact for
/// weightless soil, smooth or rough: Chen 1975, section 8.4). At h = B/8
/// the points' own strains lock by dilatancy: the flow rule binds each of
/// a cell's four points, and the load is +16.9% without F-bar (the
/// bearing study). The cell-mean strain binds one per cell: at B/16
/// +0.37% and +1.69% with the edge at 0.3 and 0.6 of its cell (+2.45% at
/// B/8).
/// The bound, 5%, is the target at B/16, at two placements.
#[test]
fn the_cell_mean_strain_takes_a_frictional_footing_to_prandtl_reissner() {
    let phi = 30f64.to_radians();
    let n_q = (PI * phi.tan()).exp() * (PI / 4.0 + phi / 2.0).tan().powi(2);
    let n_c = (n_q - 1.0) / phi.tan();
    for offset in [0.3, 0.6] {
        let mut case = footing(0.0625, offset, true);
        case["analysis"]["volumetric"] = json!("cell_mean");
        case["analysis"]["load_steps"] = json!(20);
        case["supports"][0]["displacement"] = json!([0.0, -0.02 * 2.0 * HALF_WIDTH]);
        case["bodies"][0]["material"] = json!({ "model": "mohr_coulomb",
            "youngs_modulus": 1e8, "poisson_ratio": 0.3, "density": 0.0,
            "cohesion": COHESION, "friction_angle": 30.0 });
        let (q, last) = pressure(&case);
        let error = q / n_c - 1.0;
        eprintln!(
            "offset {offset}: q/c {q:.3} against {n_c:.3} ({:+.2}%), {} iterations in the last step",
            100.0 * error,
            last.newton.iterations
        );
        assert!(error.abs() < 0.05, "offset {offset}: {error}");
    }
}

/// A rough rigid footing on heavy cohesionless sand (phi = 30 degrees,
/// c = 0, gamma = 20 kN/m3, E = 100 MPa, nu = 0.3, Mohr-Coulomb) after a
/// geostatic stage (K0 = 0.5), pushed 0.01 B in 8 steps at h = B/8, with
/// dilation angle `psi`: `2 q / (gamma B)` at the end, and the Newton
/// iterations of the run.
fn footing_on_sand(psi: f64) -> (f64, usize) {
    let (curve, iterations) = sand_curve(psi, "standard");
    (*curve.last().unwrap(), iterations)
}

/// [`footing_on_sand`]'s `2 q / (gamma B)` at the end of each step of the
/// push, with `volumetric` the case's `analysis.volumetric`.
fn sand_curve(psi: f64, volumetric: &str) -> (Vec<f64>, usize) {
    let mut case = footing(0.125, 0.3, true);
    case["analysis"] = json!({ "volumetric": volumetric });
    case["bodies"][0]["material"] = json!({ "model": "mohr_coulomb",
        "youngs_modulus": 1e8, "poisson_ratio": 0.3, "density": 2000.0,
        "cohesion": 0.0, "friction_angle": 30.0, "dilation_angle": psi });
    let supports = case["supports"].as_array().unwrap().clone();
    let mut held = supports.clone();
    held[0]["displacement"] = json!([0.0, 0.0]);
    case["stages"] = json!([
        { "name": "geostatic", "load_steps": 1, "geostatic": { "k0": 0.5 },
          "loads": { "gravity": [0.0, -10.0] }, "supports": held },
        { "name": "footing", "load_steps": 8, "supports": supports }
    ]);
    case.as_object_mut().unwrap().remove("supports");
    let (_, report) = run(&case);
    let curve = (report.steps[1..].iter())
        .map(|s| 2.0 * (-s.reactions[0][1] / HALF_WIDTH) / (20e3 * 2.0 * HALF_WIDTH))
        .collect();
    let iterations = report.steps.iter().map(|s| s.newton.iterations).sum();
    (curve, iterations)
}

/// With the cell-mean strain each point keeps working with the stress it
/// ended the last step with across the grid's reset (`CellMean::carrying`,
/// which carries how far that stood from its own), so the load under the
/// footing on sand (psi = phi) rises smoothly through the steps in which
/// the points under it change cell. Had each point taken its new cell's
/// mean at once, the curve would fall by a fifth there (docs/guide.md,
/// Material models). What is left is the path's: the same push in 8, 16
/// and 32 steps, with and without stuck tries given up early
/// (`newton::stuck`), which cut different increments, dips by up to 2.8%
/// in a step (20.8 to 20.3 here, in 301 Newton iterations, to 21.3) and
/// ends at 21.1-22.2. The bound on a fall, 5% a step, is well above
/// those dips and a quarter of the fall it guards against.
#[test]
fn the_cell_means_load_does_not_fall_where_points_change_cell() {
    let (curve, iterations) = sand_curve(30.0, "cell_mean");
    eprintln!("2 q / (gamma B): {curve:.2?} in {iterations} iterations");
    for k in 1..curve.len() {
        assert!(
            curve[k] > curve[k - 1] * (1.0 - 5e-2),
            "the load fell in step {}: {curve:?}",
            k + 1
        );
    }
}

/// Sand without dilation (psi = 0, what users choose for sands) under the
/// footing finishes the push, weaker than the associated soil (a
/// non-associated flow rule lowers the collapse load: Drescher &
/// Detournay 1993; Loukidis & Salgado 2009 for N_gamma), and cheaply:
/// each increment starts from the last (`analysis.newton.predictor`).
/// Measured: 19.45 against 26.64 (Martin's exact associated N_gamma is
/// 14.75; both are high at this cell), in 93 Newton iterations. From no
/// displacement the same run took 1917: the first tangent of every
/// increment was the elastic one, and each of its 8 steps was cut into
/// 20-32 pieces of about 9 iterations. The bound, 400, lies between; the
/// ratio of the loads, 0.73, must lie within 0.5-0.9.
#[test]
fn sand_without_dilation_under_a_footing_finishes_weaker_than_with_it() {
    let (without, iterations) = footing_on_sand(0.0);
    let (with, _) = footing_on_sand(30.0);
    eprintln!("psi = 0: {without:.2} in {iterations} iterations; psi = phi: {with:.2}");
    assert!(
        without > 0.5 * with && without < 0.9 * with,
        "{without} against {with}"
    );
    assert!(iterations < 400, "{iterations}");
}
