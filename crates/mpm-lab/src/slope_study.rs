//! `mpm study slope`: the factor of safety of a homogeneous slope by
//! strength reduction, Griffiths and Lane's (1999) example 1 (Geotechnique
//! 49(3), 387-403): a 2:1 slope (26.57 degrees) of height H = 10 m on a
//! firm base at the toe's level (depth factor D = 1), the crest running
//! 1.5 H beyond the slope's top; Mohr-Coulomb with c' / (gamma H) = 0.05
//! (c' = 10 kPa, gamma = 20 kN/m^3), phi' = 20 degrees, psi = 0, E = 100
//! MPa, nu = 0.3. Their finite elements (8-node quadrilaterals, reduced
//! integration, elastic-viscoplastic, failure as no convergence in 1000
//! iterations) give FS = 1.4; Bishop and Morgenstern's (1960) charts,
//! limit equilibrium on circles, give 1.38, as they report.
//!
//! Each run is the built-in `slope` (`mpm example slope`): gravity on in
//! 4 steps (the base held, the far side on rollers, both by the implicit
//! boundary method), then the reduction (increment 0.1, tolerance 0.01,
//! flow limit 10: a trial that holds only after its points slid on the
//! grid fails, `crate::strength_reduction` in the solver). GIMP, 2x2
//! points a cell, the grid's origin at `-0.3 h` in both directions unless
//! a row moves it. Rows: the cell from H/10 to H/40, and the grid moved;
//! smaller increments of the factor; the flow limit at 20 and off (the
//! factor then follows the increments); the default ghost penalty;
//! associated flow (psi = phi); Drucker-Prager, the smooth cone; and the
//! cell-mean strain.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;
use std::time::Instant;

use mpm::{Case, NoObserver, Simulation};
use serde_json::{Value, json};

use crate::LabError;

/// Slope height (m), as the built-in `slope` has it.
const HEIGHT: f64 = 10.0;
/// The reduction's flow limit unless a row says, as the built-in `slope`
/// has it.
const FLOW_LIMIT: f64 = 10.0;
/// Griffiths and Lane's finite-element factor, and Bishop and
/// Morgenstern's.
const GRIFFITHS_LANE: f64 = 1.4;
const BISHOP_MORGENSTERN: f64 = 1.38;

/// One run of the study.
#[derive(Debug, Clone, Copy)]
struct Row {
    /// Cells per slope height.
    cells: f64,
    ghost: Option<f64>,
    dilation: f64,
    /// The grid's origin, as a fraction of the cell.
    offset: f64,
    /// The reduction's increment.
    increment: f64,
    /// `mohr_coulomb` or `drucker_prager` (matched in plane strain).
    model: &'static str,
    /// The cell-mean strain with this hourglass stiffness, if not the
    /// points' own strains.
    cell_mean: Option<f64>,
    /// The reduction's flow limit (0: none).
    flow_limit: f64,
}

impl Row {
    fn label(&self) -> String {
        let mut label = format!("H/{}", self.cells);
        if self.model != "mohr_coulomb" {
            label += &format!(", {}", self.model.replace('_', "-"));
        }
        if self.ghost.is_none() {
            label += ", default ghost penalty";
        }
        if self.dilation > 0.0 {
            label += &format!(", psi = {}", self.dilation);
        }
        if self.offset != 0.3 {
            label += &format!(", origin -{} h", self.offset);
        }
        if self.increment != 0.1 {
            label += &format!(", increment {}", self.increment);
        }
        if let Some(h) = self.cell_mean {
            label += &format!(", cell mean (hourglass {h:e})");
        }
        if self.flow_limit != FLOW_LIMIT {
            label += &match self.flow_limit {
                0.0 => ", no flow limit".to_string(),
                k => format!(", flow limit {k}"),
            };
        }
        label
    }
}

/// The slope case of a run: the built-in `slope` as the row changes it.
fn slope_case(row: &Row) -> Value {
    let Row {
        cells,
        ghost,
        dilation,
        offset,
        increment,
        model,
        cell_mean,
        flow_limit,
    } = *row;
    let h = HEIGHT / cells;
    let mut case = mpm::case::builtin::json("slope").expect("the built-in slope");
    let analysis = &mut case["analysis"];
    match ghost {
        Some(g) => analysis["stabilisation"]["ghost_penalty"] = json!(g),
        None => {
            analysis
                .as_object_mut()
                .expect("analysis")
                .remove("stabilisation");
        }
    }
    if let Some(hourglass) = cell_mean {
        analysis["volumetric"] = json!("cell_mean");
        analysis["stabilisation"]["hourglass"] = json!(hourglass);
    }
    case["title"] = json!(format!(
        "Griffiths and Lane (1999) example 1: 2:1 slope, H = 10 m, c' = 10 kPa, phi' = 20, psi = {dilation}, h = H/{cells}"
    ));
    case["grid"] = json!({ "cell_size": h, "origin": [-offset * h, -0.3 * h] });
    let material = &mut case["bodies"][0]["material"];
    material["model"] = json!(model);
    material["dilation_angle"] = json!(dilation);
    case["stages"][1]["strength_reduction"] =
        json!({ "increment": increment, "tolerance": 0.01, "flow_limit": flow_limit });
    case
}

/// What a run found.
struct Found {
    row: Row,
    points: usize,
    factor: f64,
    failed: Option<f64>,
    found: bool,
    /// Why the trial that closed the bracket failed.
    failure: String,
    steps: usize,
    iterations: usize,
    failed_iterations: usize,
    crest_settlement: f64,
    /// The flow of the last trial that held, if measured.
    flow: Option<f64>,
    seconds: f64,
}

fn solve(row: Row) -> Result<Found, LabError> {
    let json = slope_case(&row);
    let case = Case::from_json(&json.to_string()).map_err(|e| LabError::Failed(e.to_string()))?;
    let mut sim = Simulation::new(&case).map_err(|e| LabError::Failed(e.to_string()))?;
    let start = Instant::now();
    let report = (sim.run(&mut NoObserver))
        .map_err(|e| LabError::Failed(format!("{}: {e}", row.label())))?;
    let seconds = start.elapsed().as_secs_f64();
    let last = report.steps.last().expect("steps");
    let verdict = (report.steps.iter().rev())
        .find_map(|s| s.strength_reduction.clone())
        .ok_or_else(|| LabError::Failed("no strength-reduction step".into()))?;
    let failure = (report.steps.iter().rev())
        .find_map(|s| {
            s.strength_reduction
                .as_ref()
                .and_then(|r| r.failure.clone())
        })
        .unwrap_or_default();
    Ok(Found {
        row,
        points: report.points,
        factor: verdict.factor,
        failed: verdict.failed,
        found: verdict.found,
        failure,
        steps: report.steps.len(),
        iterations: report.steps.iter().map(|s| s.newton.iterations).sum(),
        failed_iterations: report.steps.iter().map(|s| s.failed_iterations).sum(),
        crest_settlement: -last.probes[0].displacement[1],
        flow: (report.steps.iter().rev())
            .find_map(|s| s.strength_reduction.as_ref().and_then(|r| r.flow)),
        seconds,
    })
}

/// Runs the study and writes `slope.md` and `slope.csv` to `out`.
pub fn slope(out: &Path, quick: bool) -> Result<(), LabError> {
    fs::create_dir_all(out)?;
    let base = Row {
        cells: 10.0,
        ghost: Some(0.0),
        dilation: 0.0,
        offset: 0.3,
        increment: 0.1,
        model: "mohr_coulomb",
        cell_mean: None,
        flow_limit: FLOW_LIMIT,
    };
    let at = |cells: f64| Row { cells, ..base };
    let (refinement, variants, finest): (&[f64], f64, f64) = if quick {
        (&[10.0, 20.0], 10.0, 20.0)
    } else {
        (&[10.0, 20.0, 40.0], 20.0, 40.0)
    };
    let mut rows: Vec<Row> = refinement.iter().map(|&c| at(c)).collect();
    // The grid moved, at the variants' cell and the finest.
    rows.extend([variants, finest].map(|cells| Row {
        offset: 0.7,
        ..at(cells)
    }));
    rows.extend([0.05, 0.03].map(|increment| Row {
        increment,
        ..at(variants)
    }));
    // The flow limit raised, and off: without it the factor follows the
    // increments.
    rows.push(Row {
        flow_limit: 20.0,
        ..at(variants)
    });
    rows.extend([0.1, 0.05, 0.03].map(|increment| Row {
        increment,
        flow_limit: 0.0,
        ..at(variants)
    }));
    rows.push(Row {
        ghost: None,
        ..at(variants)
    });
    // Associated flow, what limit equilibrium and limit analysis assume.
    rows.extend([variants, finest].map(|cells| Row {
        dilation: 20.0,
        ..at(cells)
    }));
    rows.extend([variants, finest].map(|cells| Row {
        model: "drucker_prager",
        ..at(cells)
    }));
    // The cell-mean strain, at its default hourglass stiffness and at the
    // one the strength reduction's check asks for (docs/guide.md).
    rows.extend([1e-2, 1e-3].map(|hourglass| Row {
        cell_mean: Some(hourglass),
        ..at(variants)
    }));
    let mut found = Vec::new();
    for row in rows {
        let f = solve(row)?;
        eprintln!(
            "{}: F = {:.5} (failed {:?}), {:.1} s",
            row.label(),
            f.factor,
            f.failed,
            f.seconds
        );
        found.push(f);
    }
    fs::write(out.join("slope.md"), markdown(&found, quick))?;
    fs::write(out.join("slope.csv"), csv(&found))?;
    Ok(())
}

fn markdown(found: &[Found], quick: bool) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Slope stability by strength reduction: Griffiths and Lane (1999), example 1\n"
    );
    let _ = writeln!(
        s,
        "Written by `mpm study slope{}` (crates/mpm-lab/src/slope_study.rs, which gives the case). \
         A 2:1 slope, H = 10 m, on a firm base at the toe's level; Mohr-Coulomb, c' = 10 kPa \
         (c' / gamma H = 0.05), phi' = 20 degrees, psi = 0, E = 100 MPa, nu = 0.3, gamma = 20 kN/m^3. \
         References: Griffiths and Lane's finite elements FS = {GRIFFITHS_LANE}, Bishop and \
         Morgenstern's charts {BISHOP_MORGENSTERN}. The built-in `slope` (`mpm example slope`): gravity in 4 steps, then the reduction \
         (increment 0.1 unless the row says, tolerance 0.01: the factor is within 0.01 below the first that fails; \
         flow limit 10 unless the row says: a trial whose points move, per unit of the factor's rise, more than 10 times \
         their displacement at the stage's start, once they have moved 1% of a cell, fails). \
         GIMP, 2x2 points a cell, origin at -0.3 h unless the row says, no ghost penalty unless the row says.\n",
        if quick { " --quick" } else { "" }
    );
    let _ = writeln!(
        s,
        "`on the ramp`: the factor is one the increments reached (`1 + k increment`), every \
         bisection above it having failed, so that it follows the increments rather than the slope \
         (docs/guide.md, Strength reduction).\n"
    );
    let _ = writeln!(
        s,
        "| run | points | FS | vs G&L | vs Bishop | first failed | found | on the ramp | crest settlement (mm) | flow of the last that held | steps | iterations (failed) | s | the failure that closed it |"
    );
    let _ = writeln!(
        s,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for f in found {
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} | {:+.1}% | {:+.1}% | {} | {} | {} | {:.1} | {} | {} | {} ({}) | {:.1} | {} |",
            f.row.label(),
            f.points,
            f.factor,
            100.0 * (f.factor / GRIFFITHS_LANE - 1.0),
            100.0 * (f.factor / BISHOP_MORGENSTERN - 1.0),
            f.failed.map_or("none".into(), |v| format!("{v:.4}")),
            f.found,
            on_the_ramp(f),
            1e3 * f.crest_settlement,
            f.flow.map_or("-".into(), |v| format!("{v:.1}")),
            f.steps,
            f.iterations,
            f.failed_iterations,
            f.seconds,
            f.failure.replace('|', "/"),
        );
    }
    s
}

/// Whether the factor found is `1 + k increment` for a whole `k`.
fn on_the_ramp(f: &Found) -> bool {
    let k = (f.factor - 1.0) / f.row.increment;
    (k - k.round()).abs() < 1e-6
}

fn csv(found: &[Found]) -> String {
    let mut s = String::from(
        "run,points,factor,failed,found,crest_settlement_m,steps,iterations,failed_iterations,seconds\n",
    );
    for f in found {
        let _ = writeln!(
            s,
            "\"{}\",{},{},{},{},{},{},{},{},{:.3}",
            f.row.label(),
            f.points,
            f.factor,
            f.failed.map_or(String::new(), |v| v.to_string()),
            f.found,
            f.crest_settlement,
            f.steps,
            f.iterations,
            f.failed_iterations,
            f.seconds
        );
    }
    s
}
