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
//! Each run: gravity on in 4 steps (the base held, the far side on
//! rollers, both by the implicit boundary method), then the reduction
//! (increment 0.1, tolerance 0.01). GIMP, 2x2 points a cell, the grid's
//! origin at `-0.3 h` in both directions unless a row moves it. Rows: the
//! cell from H/10 to H/40 without the ghost penalty; with the default
//! penalty; associated flow (psi = phi); the grid moved; smaller
//! increments of the factor, and the increments again with Newton's
//! limit at 100 iterations; Drucker-Prager, the smooth cone; and the
//! cell-mean strain.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;
use std::time::Instant;

use mpm::{Case, NoObserver, Simulation};
use serde_json::{Value, json};

use crate::LabError;

/// Slope height (m), and the crest's run beyond the slope's top.
const HEIGHT: f64 = 10.0;
const CREST: f64 = 1.5 * HEIGHT;
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
    /// Newton's iteration limit, if not the default.
    max_iterations: Option<u32>,
    /// The cell-mean strain with this hourglass stiffness, if not the
    /// points' own strains.
    cell_mean: Option<f64>,
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
        if let Some(n) = self.max_iterations {
            label += &format!(", {n} Newton iterations");
        }
        if let Some(h) = self.cell_mean {
            label += &format!(", cell mean (hourglass {h:e})");
        }
        label
    }
}

/// The slope case of a run.
fn slope_case(row: &Row) -> Value {
    let Row {
        cells,
        ghost,
        dilation,
        offset,
        increment,
        model,
        max_iterations,
        cell_mean,
    } = *row;
    let h = HEIGHT / cells;
    let length = 2.0 * HEIGHT + CREST;
    let mut analysis = json!({ "type": "plane_strain" });
    if let Some(g) = ghost {
        analysis["stabilisation"] = json!({ "ghost_penalty": g });
    }
    if let Some(n) = max_iterations {
        analysis["newton"] = json!({ "max_iterations": n });
    }
    if let Some(hourglass) = cell_mean {
        analysis["volumetric"] = json!("cell_mean");
        analysis["stabilisation"]["hourglass"] = json!(hourglass);
    }
    json!({
        "version": 1,
        "title": format!("Griffiths and Lane (1999) example 1: 2:1 slope, H = 10 m, c' = 10 kPa, phi' = 20, psi = {dilation}, h = H/{cells}"),
        "analysis": analysis,
        "grid": { "cell_size": h, "origin": [-offset * h, -0.3 * h] },
        "basis": "gimp",
        "bodies": [ {
            "name": "slope",
            "geometry": { "polygon": { "vertices": [[0.0, 0.0], [length, 0.0], [length, HEIGHT], [2.0 * HEIGHT, HEIGHT]] } },
            "points": { "per_cell": 2 },
            "material": { "model": model, "youngs_modulus": 1e8, "poisson_ratio": 0.3,
                "density": 2000.0, "cohesion": 10e3, "friction_angle": 20.0, "dilation_angle": dilation }
        } ],
        "stages": [
            { "name": "gravity", "load_steps": 4, "loads": { "gravity": [0.0, -10.0] },
              "supports": [ { "on": { "y": 0.0 }, "fix": "xy", "method": "ibm" },
                            { "on": { "x": length }, "fix": "normal", "method": "ibm" } ] },
            { "name": "safety", "load_steps": 80,
              "strength_reduction": { "increment": increment, "tolerance": 0.01 } }
        ],
        "probes": [ { "name": "crest", "at": [2.0 * HEIGHT, HEIGHT] } ]
    })
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
        max_iterations: None,
        cell_mean: None,
    };
    let at = |cells: f64| Row { cells, ..base };
    let refinement: &[f64] = if quick {
        &[10.0, 20.0]
    } else {
        &[10.0, 20.0, 40.0]
    };
    let mut rows: Vec<Row> = refinement.iter().map(|&c| at(c)).collect();
    let variants = if quick { 10.0 } else { 20.0 };
    rows.extend([
        Row {
            ghost: None,
            ..at(variants)
        },
        Row {
            dilation: 20.0,
            ..at(variants)
        },
        Row {
            offset: 0.7,
            ..at(variants)
        },
        Row {
            increment: 0.05,
            ..at(variants)
        },
        Row {
            increment: 0.03,
            ..at(variants)
        },
    ]);
    // Newton's limit raised: does the factor still follow the increments?
    rows.extend([0.1, 0.05, 0.03].map(|increment| Row {
        increment,
        max_iterations: Some(100),
        ..at(variants)
    }));
    let smooth: &[f64] = if quick { &[10.0] } else { &[20.0, 40.0] };
    rows.extend(smooth.iter().map(|&cells| Row {
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
         Morgenstern's charts {BISHOP_MORGENSTERN}. Gravity in 4 steps, then the reduction \
         (increment 0.1 unless the row says, tolerance 0.01: the factor is within 0.01 below the first that fails). \
         GIMP, 2x2 points a cell, origin at -0.3 h unless the row says.\n",
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
        "| run | points | FS | vs G&L | vs Bishop | first failed | found | on the ramp | crest settlement (mm) | steps | iterations (failed) | s | the failure that closed it |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for f in found {
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} | {:+.1}% | {:+.1}% | {} | {} | {} | {:.1} | {} | {} ({}) | {:.1} | {} |",
            f.row.label(),
            f.points,
            f.factor,
            100.0 * (f.factor / GRIFFITHS_LANE - 1.0),
            100.0 * (f.factor / BISHOP_MORGENSTERN - 1.0),
            f.failed.map_or("none".into(), |v| format!("{v:.4}")),
            f.found,
            on_the_ramp(f),
            1e3 * f.crest_settlement,
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
