//! `mpm study bearing`: the bearing capacity factor `N_c` of a rough rigid
//! strip footing on weightless, associated Mohr-Coulomb soil (phi = psi =
//! 20 and 30 degrees, c = 10 kPa, E = 100 MPa, nu = 0.3), the built-in
//! `footing` case's geometry (half model, soil 5 m x 3 m, B = 1 m, GIMP,
//! 2x2 points a cell, grid origin at -0.3 h), pushed 0.02 B in 20 steps by
//! the implicit boundary method (held on average over pieces of two
//! cells), at three cell sizes, with the points' own strains (`standard`)
//! and with their cells' mean strain (`cell_mean`). The reference is
//! Prandtl-Reissner's `N_c = (N_q - 1) cot(phi)`, exact for weightless
//! soil, smooth or rough (Chen 1975, Limit analysis and soil plasticity,
//! section 8.4).
//!
//! What it shows: the standard points lock by dilatancy (associated flow
//! binds each point's volume change to its shear, four constraints a
//! cell), and the cell mean binds one a cell (docs/guide.md, Material
//! models). Then the phi = 30 cell-mean row at B/8 pushed in 20 to 200
//! steps: how much of its error is the load steps'.
//!
//! Then the self-weight factor `N_gamma`: the same rough footing on heavy
//! cohesionless sand (phi = psi = 30 degrees, c = 0, gamma = 20 kN/m3,
//! E = 100 MPa, nu = 0.3) after a geostatic stage (K0 = 0.5, one step),
//! pushed 0.01 B in 8 steps, `2 q / (gamma B)` against Martin's (2005)
//! exact 14.75 for a rough strip (the method of characteristics, his
//! program ABC; Martin, "Exact bearing capacity calculations using the
//! method of characteristics", IACMAG 11, Turin, table of `N_gamma`).
//! With `gamma B / 2 = c` of the first part, 10 kPa, the curve's `q / c`
//! is `2 q / (gamma B)`.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use serde_json::json;

use crate::LabError;
use crate::footing_study::{
    Curve, Loading, Soil, at_settlement, footing_case, orders, prandtl_reissner, run_curve,
};

/// Cell sizes (m): B/4, B/8, B/16.
const CELLS: [f64; 3] = [0.25, 0.125, 0.0625];
/// Friction angles (degrees).
const ANGLES: [f64; 2] = [20.0, 30.0];
/// The push (m, 0.02 B) and its steps.
const SETTLEMENT: f64 = 0.02;
const STEPS: usize = 20;
/// The strain each point's model answers to.
const FORMULATIONS: [&str; 2] = ["standard", "cell_mean"];
/// The load steps of the steps' table (phi = 30, the cell mean, B/8).
const STEP_COUNTS: [usize; 4] = [20, 50, 100, 200];

/// Martin's (2005) exact `N_gamma` of a rough strip footing, phi = 30
/// degrees.
const MARTIN_N_GAMMA: f64 = 14.75;
/// The sand's push (m, 0.01 B), its steps, and where the table reads the
/// curve besides its end (0.005 B; the curves still rise there).
const SAND_SETTLEMENT: f64 = 0.01;
const SAND_STEPS: usize = 8;
const SAND_READ_AT: f64 = 0.005;
const SAND_LOADING: Loading = Loading::Pushed {
    settlement: SAND_SETTLEMENT,
    rough: true,
};

/// One run: friction angle, formulation, cell, and its curve.
struct Run {
    phi: f64,
    formulation: &'static str,
    h: f64,
    curve: Curve,
}

pub fn bearing(out: &Path, quick: bool) -> Result<(), LabError> {
    fs::create_dir_all(out)?;
    let cells: &[f64] = if quick { &CELLS[..2] } else { &CELLS };
    let loading = Loading::Pushed {
        settlement: SETTLEMENT,
        rough: true,
    };
    let mut runs = Vec::new();
    for phi in ANGLES {
        for formulation in FORMULATIONS {
            for &h in cells {
                let mut case = footing_case(h, Soil::MohrCoulomb(phi), loading, STEPS);
                case["analysis"]["volumetric"] = json!(formulation);
                let curve = run_curve(&case, loading)?;
                let q = curve.points.last().map_or(0.0, |p| p.1);
                eprintln!(
                    "phi {phi} {formulation} h {h}: q/c {q:.3}, {} iterations, {:.0} s{}",
                    curve.newton_iterations,
                    curve.seconds,
                    curve
                        .failure
                        .as_ref()
                        .map_or(String::new(), |f| format!(", stopped at {:.3}", f.carried))
                );
                runs.push(Run {
                    phi,
                    formulation,
                    h,
                    curve,
                });
            }
        }
    }
    let mut sand = Vec::new();
    for formulation in FORMULATIONS {
        for &h in cells {
            let curve = run_curve(&sand_case(h, formulation), SAND_LOADING)?;
            let q = curve.points.last().map_or(0.0, |p| p.1);
            eprintln!(
                "N_gamma {formulation} h {h}: {q:.2}, {} iterations, {:.0} s",
                curve.newton_iterations, curve.seconds
            );
            sand.push(Run {
                phi: 30.0,
                formulation,
                h,
                curve,
            });
        }
    }
    // The same push in more steps: how much of the error is the steps'.
    let counts: &[usize] = if quick {
        &STEP_COUNTS[..2]
    } else {
        &STEP_COUNTS
    };
    let mut stepped = Vec::new();
    for &steps in counts {
        let mut case = footing_case(CELLS[1], Soil::MohrCoulomb(30.0), loading, steps);
        case["analysis"]["volumetric"] = json!("cell_mean");
        let curve = run_curve(&case, loading)?;
        eprintln!(
            "phi 30 cell_mean h {} in {steps} steps: {} iterations, {:.0} s",
            CELLS[1], curve.newton_iterations, curve.seconds
        );
        stepped.push((steps, curve));
    }
    let mut md = markdown(&runs, quick);
    steps_markdown(&mut md, &stepped);
    sand_markdown(&mut md, &sand);
    fs::write(out.join("bearing.md"), md)?;
    Ok(())
}

/// The `N_gamma` case at cell `h` (see the module's doc).
fn sand_case(h: f64, formulation: &str) -> serde_json::Value {
    let mut case = footing_case(h, Soil::MohrCoulomb(30.0), SAND_LOADING, SAND_STEPS);
    case["analysis"] = json!({ "volumetric": formulation });
    case["bodies"][0]["material"]["cohesion"] = json!(0.0);
    case["bodies"][0]["material"]["density"] = json!(2000.0);
    let supports = case["supports"].clone();
    let mut held = supports.clone();
    held[0]["displacement"] = json!([0.0, 0.0]);
    case["stages"] = json!([
        { "name": "geostatic", "load_steps": 1, "geostatic": { "k0": 0.5 },
          "loads": { "gravity": [0.0, -10.0] }, "supports": held },
        { "name": "footing", "load_steps": SAND_STEPS, "supports": supports }
    ]);
    case.as_object_mut()
        .expect("a case object")
        .remove("supports");
    case
}

/// The steps' table: the phi = 30 cell-mean row at B/8 pushed in more
/// steps.
fn steps_markdown(md: &mut String, stepped: &[(usize, Curve)]) {
    let n_c = prandtl_reissner(30.0);
    let _ = writeln!(
        md,
        "## The same push in more steps (phi = psi = 30, cell mean, h = {} m)\n\n\
         `q / c` at the end of the push ({SETTLEMENT} B) and at the curve's peak, against N_c = {n_c:.2}: \
         how much of the table's error is the load steps'.\n\n\
         | steps | at the end | error | peak | error | Newton iterations | seconds |\n\
         |---|---|---|---|---|---|---|",
        CELLS[1]
    );
    for (steps, c) in stepped {
        let end = c.points.last().map_or(f64::NAN, |p| p.1);
        let peak = c.points.iter().map(|p| p.1).fold(f64::NAN, f64::max);
        let _ = writeln!(
            md,
            "| {steps} | {end:.3} | {:+.2}% | {peak:.3} | {:+.2}% | {} | {:.0} |",
            100.0 * (end / n_c - 1.0),
            100.0 * (peak / n_c - 1.0),
            c.newton_iterations,
            c.seconds
        );
    }
    md.push('\n');
}

fn sand_markdown(md: &mut String, sand: &[Run]) {
    let _ = writeln!(
        md,
        "## Self-weight: N_gamma on heavy sand, phi = psi = 30 degrees: Martin's {MARTIN_N_GAMMA}\n\n\
         `2 q / (gamma B)` where the footing's centre has settled {SAND_READ_AT} B (the \
         curves still rise there and after: docs/guide.md), and at the end of the push, {SAND_SETTLEMENT} B \
         (the module's doc gives the case).\n\n\
         | formulation | h (m) | points | at {SAND_READ_AT} B | error | at the end | error | Newton iterations | cut increments | seconds |\n\
         |---|---|---|---|---|---|---|---|---|---|"
    );
    for formulation in FORMULATIONS {
        let mut errors = Vec::new();
        for r in sand.iter().filter(|r| r.formulation == formulation) {
            let c = &r.curve;
            let early = at_settlement(c, SAND_READ_AT).unwrap_or(f64::NAN);
            let end = c.points.last().map_or(0.0, |p| p.1);
            let error = |q: f64| q / MARTIN_N_GAMMA - 1.0;
            errors.push(error(early));
            let _ = writeln!(
                md,
                "| {formulation} | {} | {} | {early:.2} | {:+.1}% | {end:.2} | {:+.1}% | {} | {} | {:.0} |",
                r.h,
                c.n_points,
                100.0 * error(early),
                100.0 * error(end),
                c.newton_iterations,
                c.cutbacks,
                c.seconds
            );
        }
        let _ = writeln!(
            md,
            "| {formulation}: observed orders at {SAND_READ_AT} B | | | | {} | | | | | |",
            orders(&errors)
        );
    }
}

fn markdown(runs: &[Run], quick: bool) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Bearing capacity factors N_c and N_gamma: a rough rigid footing on frictional soil\n\n\
         Generated by `mpm study bearing{}` (`crates/mpm-lab/src/bearing_study.rs`, \
         whose doc gives the case). `q / c` at 0.02 B (or where the run stopped), \
         against Prandtl-Reissner's `N_c`; the observed orders are between \
         successive cells.\n",
        if quick { " --quick" } else { "" }
    );
    for phi in ANGLES {
        let n_c = prandtl_reissner(phi);
        let _ = writeln!(
            md,
            "## phi = psi = {phi} degrees: N_c = {n_c:.3}\n\n\
             | formulation | h (m) | points | q / c | error | Newton iterations | cut increments | seconds | stopped |\n\
             |---|---|---|---|---|---|---|---|---|"
        );
        for formulation in FORMULATIONS {
            let mut errors = Vec::new();
            for r in runs
                .iter()
                .filter(|r| r.phi == phi && r.formulation == formulation)
            {
                let c = &r.curve;
                let q = c.points.last().map_or(0.0, |p| p.1);
                let error = q / n_c - 1.0;
                errors.push(error);
                let stopped = c.failure.as_ref().map_or("no".to_string(), |f| {
                    format!("at {:.3} of the push", f.carried)
                });
                let _ = writeln!(
                    md,
                    "| {formulation} | {} | {} | {q:.3} | {:+.2}% | {} | {} | {:.0} | {stopped} |",
                    r.h,
                    c.n_points,
                    100.0 * error,
                    c.newton_iterations,
                    c.cutbacks,
                    c.seconds
                );
            }
            let _ = writeln!(
                md,
                "| {formulation}: observed orders | | | | {} | | | | |",
                orders(&errors)
            );
        }
        md.push('\n');
    }
    md
}
