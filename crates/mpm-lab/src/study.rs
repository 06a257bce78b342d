//! `mpm study cantilever`: the paper's convergence study (Bing et al. 2017,
//! Figure 3: mid-tip displacement against the number of material points for
//! several cell sizes) and more, for both ways of imposing the supports.
//!
//! Every run is the built-in paper case (10 m x 2 m, Hencky, E = 1 MPa,
//! nu = 0.25, 1500 Pa follower pressure on the top in 5 steps) with its cell
//! size and point count changed: `3.5 n x n` points, so that 896 = 56 x 16.
//! Supports by the implicit boundary method: rollers on x = 0 and the
//! stretch of boundary around (0, 1) fixed, grid origin (0, 0). Grid-node
//! supports: rollers on the nodes of x = 0 and the node (0, 1) pinned, grid
//! origin (0, 1) so that the node exists at every cell size.
//!
//! The mid-tip's vertical displacement has a logarithmic singularity in the
//! size of the pinned support, which shrinks with the point spacing (IBM)
//! or the cell (grid), so it is reported but not measured as an error. The
//! deflection relative to the mean vertical displacement of the left edge
//! and the horizontal tip displacement converge; their errors are measured
//! against the finest run of the same support method.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;
use std::time::Instant;

use mpm::case::BasisKind;
use mpm::{Case, NoObserver, RunReport, Simulation};
use serde_json::{Value, json};

use crate::LabError;
use crate::basis_study::{FINEST_FE_TIP_UY, REFERENCE_RELATIVE};
use crate::plot::{COLOURS, Plot, Series};

/// Cell sizes of the sweep (m): the paper's three and one finer.
const CELLS: [f64; 4] = [1.5, 0.75, 0.375, 0.1875];
/// Points through the depth; `3.5 n` along the beam.
const ROWS: [usize; 5] = [4, 8, 16, 32, 64];
/// Probes on the left edge for its mean vertical displacement.
const LEFT_PROBES: usize = 9;
/// Runs faster than this are repeated and the median taken.
const QUICK_RUN: f64 = 0.2;

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Method {
    Ibm,
    Grid,
}

impl Method {
    fn name(self) -> &'static str {
        match self {
            Method::Ibm => "ibm",
            Method::Grid => "grid",
        }
    }
}

/// One run of the sweep.
struct Run {
    method: Method,
    h: f64,
    points: usize,
    band_width: Option<f64>,
    outcome: Result<Measured, String>,
}

/// What a converged run gives.
#[derive(Clone, Copy)]
struct Measured {
    tip: [f64; 2],
    /// Tip deflection minus the left edge's mean vertical displacement.
    relative: f64,
    iterations: usize,
    dofs: usize,
    /// Median wall time (s) of the whole run.
    seconds: f64,
}

/// The paper's case at cell size `h` with `3.5 rows x rows` points.
fn case(method: Method, h: f64, rows: usize, band_width: Option<f64>, basis: BasisKind) -> Value {
    let mut case = mpm::case::builtin::json("cantilever").expect("built in");
    case["basis"] = json!(basis);
    case["grid"]["cell_size"] = h.into();
    case["bodies"][0]["points"] = json!({ "count": [rows * 7 / 2, rows] });
    let mut probes = vec![json!({ "name": "tip", "at": [10.0, 1.0] })];
    for i in 0..LEFT_PROBES {
        let y = 2.0 * i as f64 / (LEFT_PROBES - 1) as f64;
        probes.push(json!({ "name": format!("left{i}"), "at": [0.0, y] }));
    }
    case["probes"] = json!(probes);
    if method == Method::Grid {
        case["grid"]["origin"] = json!([0.0, 1.0]);
        case["supports"] = json!([
            { "on": { "x": 0.0 }, "fix": "x" },
            { "on": { "x": 0.0, "y": 1.0 }, "fix": "y" }
        ]);
    }
    if let Some(d) = band_width {
        case["boundary"] = json!({ "band_width": d });
    }
    case
}

fn solve(case: &Case) -> Result<RunReport, String> {
    let mut sim = Simulation::new(case).map_err(|e| e.to_string())?;
    sim.run(&mut NoObserver).map_err(|e| e.to_string())
}

fn measure(
    method: Method,
    h: f64,
    rows: usize,
    band_width: Option<f64>,
    basis: BasisKind,
) -> Result<Run, LabError> {
    let json = case(method, h, rows, band_width, basis);
    let case = Case::from_json(&json.to_string())
        .map_err(|e| LabError::Failed(format!("study case: {e}")))?;
    let mut times = Vec::new();
    let mut outcome = Err(String::new());
    while times.len() < 5 {
        let start = Instant::now();
        let report = solve(&case);
        times.push(start.elapsed().as_secs_f64());
        outcome = report.map(|r| summarise(&r));
        if outcome.is_err() || times[0] > QUICK_RUN {
            break;
        }
    }
    times.sort_by(f64::total_cmp);
    let seconds = times[times.len() / 2];
    Ok(Run {
        method,
        h,
        points: (rows * 7 / 2) * rows,
        band_width,
        outcome: outcome.map(|m| Measured { seconds, ..m }),
    })
}

fn summarise(report: &RunReport) -> Measured {
    let last = report.steps.last().expect("a run has steps");
    let tip = [0, 1].map(|c| last.probes[0].displacement[c]);
    // Trapezoidal mean over the left edge's equally spaced probes.
    let left: Vec<f64> = last.probes[1..].iter().map(|p| p.displacement[1]).collect();
    let n = left.len() - 1;
    let mean = (left[1..n].iter().sum::<f64>() + 0.5 * (left[0] + left[n])) / n as f64;
    Measured {
        tip,
        relative: tip[1] - mean,
        iterations: report.steps.iter().map(|s| s.newton.iterations).sum(),
        dofs: last.active_dofs,
        seconds: 0.0,
    }
}

/// Runs the study and writes `cantilever.{csv,md}` and three SVG plots to
/// `out`. `quick` sweeps the two coarsest cells and three point counts;
/// `basis` names one in the case format's spelling (`linear`, the paper's,
/// or another of [`BasisKind::ALL`]).
pub fn cantilever(out: &Path, quick: bool, basis: &str) -> Result<(), LabError> {
    let basis: BasisKind = basis
        .parse()
        .map_err(|e| LabError::Input(format!("--basis: {e}")))?;
    fs::create_dir_all(out)?;
    let cells = if quick { &CELLS[..2] } else { &CELLS[..] };
    let rows = if quick { &ROWS[..3] } else { &ROWS[..] };
    let methods = methods(basis);
    let mut runs = Vec::new();
    for &method in methods {
        for &h in cells {
            // At least one point per cell through the depth: with fewer,
            // whole cells inside the beam are empty.
            for &n in rows.iter().filter(|&&n| 2.0 / n as f64 <= h) {
                let run = measure(method, h, n, None, basis)?;
                eprintln!("{}", progress_line(&run));
                runs.push(run);
            }
        }
    }
    let delta_runs = band_width_study(quick, basis)?;
    let paper_ibm = paper_case_time(Method::Ibm, basis)?;
    let paper_grid = if methods.contains(&Method::Grid) {
        Some(paper_case_time(Method::Grid, basis)?)
    } else {
        None
    };

    fs::write(out.join("cantilever.csv"), csv(&runs, &delta_runs))?;
    fs::write(
        out.join("cantilever.md"),
        markdown(&runs, &delta_runs, paper_ibm, paper_grid, quick, basis),
    )?;
    write_plots(out, &runs, cells)?;
    eprintln!("wrote {}", out.display());
    Ok(())
}

fn progress_line(run: &Run) -> String {
    let what = format!(
        "{:<4} h {:<6} {:>5} points{}",
        run.method.name(),
        run.h,
        run.points,
        run.band_width
            .map(|d| format!(" delta {d:.1e}"))
            .unwrap_or_default()
    );
    match &run.outcome {
        Ok(m) => format!(
            "{what}: tip ({:+.5}, {:+.5}) relative {:+.5}  {} iterations  {:.3} s",
            m.tip[0], m.tip[1], m.relative, m.iterations, m.seconds
        ),
        Err(e) => format!("{what}: failed: {e}"),
    }
}

/// The IBM band width from h / 10 to h / 10^5 on the paper's point count
/// at h = 0.375 m (three points per cell each way).
fn band_width_study(quick: bool, basis: BasisKind) -> Result<Vec<Run>, LabError> {
    let h = if quick { 0.75 } else { 0.375 };
    (1..=5)
        .map(|k| {
            let run = measure(Method::Ibm, h, 16, Some(h / 10f64.powi(k)), basis)?;
            eprintln!("{}", progress_line(&run));
            Ok(run)
        })
        .collect()
}

/// Median wall time of the paper's case itself (896 points, 1.5 m cells)
/// over 21 runs.
fn paper_case_time(method: Method, basis: BasisKind) -> Result<f64, LabError> {
    let case = Case::from_json(&case(method, 1.5, 16, None, basis).to_string())
        .map_err(|e| LabError::Failed(format!("study case: {e}")))?;
    let mut times = Vec::new();
    for _ in 0..21 {
        let start = Instant::now();
        solve(&case).map_err(|e| LabError::Failed(format!("paper case ({method:?}): {e}")))?;
        times.push(start.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    Ok(times[10])
}

/// The support methods a basis can use: grid-node supports only with the
/// bases whose nodal unknowns are the field's values.
fn methods(basis: BasisKind) -> &'static [Method] {
    if matches!(basis, BasisKind::Bspline2 | BasisKind::Bspline3) {
        &[Method::Ibm]
    } else {
        &[Method::Ibm, Method::Grid]
    }
}

/// The finest converged run of a method: the reference for its errors.
fn reference(runs: &[Run], method: Method) -> Option<Measured> {
    runs.iter()
        .filter(|r| r.method == method)
        .filter_map(|r| r.outcome.as_ref().ok().map(|m| (r, *m)))
        .min_by(|a, b| a.0.h.total_cmp(&b.0.h).then(b.0.points.cmp(&a.0.points)))
        .map(|(_, m)| m)
}

/// Relative errors of the relative deflection and of the tip's u_x against
/// the reference.
fn errors(m: &Measured, reference: &Measured) -> (f64, f64) {
    (
        ((m.relative - reference.relative) / reference.relative).abs(),
        ((m.tip[0] - reference.tip[0]) / reference.tip[0]).abs(),
    )
}

fn csv(runs: &[Run], delta_runs: &[Run]) -> String {
    let mut s = String::from(
        "study,method,cell_size,points,band_width,tip_ux,tip_uy,relative_deflection,\
         error_relative_deflection,error_tip_ux,newton_iterations,active_dofs,seconds,failure\n",
    );
    for (study, set) in [("sweep", runs), ("band_width", delta_runs)] {
        let refs = [Method::Ibm, Method::Grid].map(|m| reference(set, m));
        for r in set {
            let delta = r.band_width.map(|d| d.to_string()).unwrap_or_default();
            let _ = write!(
                s,
                "{study},{},{},{},{delta},",
                r.method.name(),
                r.h,
                r.points
            );
            match &r.outcome {
                Ok(m) => {
                    let reference = refs[(r.method == Method::Grid) as usize];
                    let (e_rel, e_ux) = reference.map_or((f64::NAN, f64::NAN), |f| errors(m, &f));
                    let _ = writeln!(
                        s,
                        "{},{},{},{e_rel:.3e},{e_ux:.3e},{},{},{:.6},",
                        m.tip[0], m.tip[1], m.relative, m.iterations, m.dofs, m.seconds
                    );
                }
                Err(e) => {
                    let _ = writeln!(s, ",,,,,,,,\"{}\"", e.replace('"', "'"));
                }
            }
        }
    }
    s
}

fn markdown(
    runs: &[Run],
    delta_runs: &[Run],
    paper_ibm: f64,
    paper_grid: Option<f64>,
    quick: bool,
    basis: BasisKind,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Cantilever convergence study\n");
    let _ = writeln!(
        s,
        "Written by `mpm study cantilever --basis {basis}{}`: the paper's case (10 m x 2 m, \
         Hencky, E = 1 MPa, nu = 0.25, 1500 Pa follower pressure on the top in 5 steps, \
         {basis} basis) with `3.5n x n` points and cells of h. `ibm`: supports by the implicit \
         boundary method (rollers on x = 0, the boundary stretch at (0, 1) fixed, \
         delta = h/100), grid origin (0, 0). `grid`: rollers on the nodes of x = 0 and \
         the node (0, 1) pinned, grid origin (0, 1). Errors are relative, against the \
         finest run of the same method (marked *); the tip's vertical displacement is \
         not converged by design (logarithmic in the pinned support's size) and is \
         reported only. Wall times are medians of up to 5 runs on this machine.\n",
        if quick { " --quick" } else { "" }
    );
    let grid_time = match paper_grid {
        Some(t) => format!("grid-node supports {:.1} ms", t * 1e3),
        None => format!(
            "no grid-node supports with {basis} (its nodes hold coefficients, not the field's \
             values; cases with them are refused)"
        ),
    };
    let _ = writeln!(
        s,
        "The paper's own case (896 points, h = 1.5 m), median of 21 runs: IBM supports \
         {:.1} ms, {grid_time}.\n",
        paper_ibm * 1e3,
    );
    for &method in methods(basis) {
        let reference = reference(runs, method);
        let _ = writeln!(s, "## Supports: {}\n", method.name());
        let _ = writeln!(
            s,
            "| h (m) | points | tip u_x (m) | tip u_y (m) | relative deflection (m) | error rel. defl. | error u_x | Newton its | DOFs | wall (s) |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
        for r in runs.iter().filter(|r| r.method == method) {
            row(&mut s, r, reference.as_ref());
        }
        s.push('\n');
    }
    let _ = writeln!(s, "## Band width (IBM)\n");
    let h = delta_runs.first().map_or(0.0, |r| r.h);
    let _ = writeln!(
        s,
        "h = {h} m, {} points. The penalty per unit length is (4/3) A_nn / delta, about \
         (4/3)(h/delta) times a cell's stiffness, so the system's conditioning grows \
         like h/delta; the gap it leaves falls like delta. Errors against the smallest \
         delta.\n",
        delta_runs.first().map_or(0, |r| r.points)
    );
    let _ = writeln!(
        s,
        "| delta / h | tip u_x (m) | tip u_y (m) | relative deflection (m) | error rel. defl. | error u_x | Newton its | wall (s) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    let finest = delta_runs
        .last()
        .and_then(|r| r.outcome.as_ref().ok().copied());
    for r in delta_runs {
        let ratio = r.band_width.map_or(f64::NAN, |d| d / r.h);
        match &r.outcome {
            Ok(m) => {
                let (e_rel, e_ux) = finest.map_or((f64::NAN, f64::NAN), |f| errors(m, &f));
                let _ = writeln!(
                    s,
                    "| {ratio:.0e} | {:.6} | {:.5} | {:.5} | {e_rel:.2e} | {e_ux:.2e} | {} | {:.3} |",
                    m.tip[0], m.tip[1], m.relative, m.iterations, m.seconds
                );
            }
            Err(e) => {
                let _ = writeln!(s, "| {ratio:.0e} | failed: {e} | | | | | | |");
            }
        }
    }
    s.push_str(
        "\nPlots: `cantilever-tip.svg` (tip deflection against points, the paper's \
         Figure 3, with the tip u_y of the finest Q9 finite-element mesh, which the \
         pin keeps from converging), `cantilever-relative.svg` (relative deflection \
         against points, with the Q9 finite-element reference -2.7597 m of \
         `scripts/papers_cantilever_reference.py`), `cantilever-error.svg` (error of \
         the relative deflection against wall time). A cross on the bottom axis marks \
         a run that failed; lines do not cross it.\n",
    );
    s
}

fn row(s: &mut String, r: &Run, reference: Option<&Measured>) {
    match &r.outcome {
        Ok(m) => {
            let (e_rel, e_ux) = reference.map_or((f64::NAN, f64::NAN), |f| errors(m, f));
            let is_reference = e_rel == 0.0 && e_ux == 0.0;
            let fmt_e = |e: f64| {
                if is_reference {
                    "*".to_string()
                } else {
                    format!("{e:.2e}")
                }
            };
            let _ = writeln!(
                s,
                "| {} | {} | {:.6} | {:.5} | {:.5} | {} | {} | {} | {} | {:.3} |",
                r.h,
                r.points,
                m.tip[0],
                m.tip[1],
                m.relative,
                fmt_e(e_rel),
                fmt_e(e_ux),
                m.iterations,
                m.dofs,
                m.seconds
            );
        }
        Err(e) => {
            let _ = writeln!(s, "| {} | {} | failed: {e} | | | | | | | |", r.h, r.points);
        }
    }
}

/// What a plot shows of a converged run, if anything.
type PlotValue<'a> = dyn Fn(&Run, &Measured) -> Option<(f64, f64)> + 'a;

fn write_plots(out: &Path, runs: &[Run], cells: &[f64]) -> Result<(), LabError> {
    // Each series runs through its runs by point count. A failed run breaks
    // the line (a NaN value): against points it is marked where it would
    // be; against wall time it has no place.
    let series = |value: &PlotValue<'_>, by_points: bool| {
        let mut all = Vec::new();
        for method in [Method::Ibm, Method::Grid] {
            for (k, &h) in cells.iter().enumerate() {
                let mut these: Vec<&Run> = runs
                    .iter()
                    .filter(|r| r.method == method && r.h == h)
                    .collect();
                these.sort_by_key(|r| r.points);
                let points: Vec<(f64, f64)> = these
                    .iter()
                    .filter_map(|r| match &r.outcome {
                        Ok(m) => value(r, m),
                        Err(_) if by_points => Some((r.points as f64, f64::NAN)),
                        Err(_) => Some((f64::NAN, f64::NAN)),
                    })
                    .collect();
                if !points.is_empty() {
                    all.push(Series {
                        label: format!("{} h = {h} m", method.name()),
                        points,
                        colour: COLOURS[k % COLOURS.len()],
                        dashed: method == Method::Grid,
                    });
                }
            }
        }
        all
    };
    let by_points = |title: &str, y_label: &str, reference: (&str, f64)| Plot {
        title: title.into(),
        x_label: "material points".into(),
        y_label: y_label.into(),
        log_x: true,
        log_y: false,
        reference: Some((reference.0.into(), reference.1)),
    };
    let tip = series(&|r, m| Some((r.points as f64, m.tip[1])), true);
    fs::write(
        out.join("cantilever-tip.svg"),
        by_points(
            "Mid-tip deflection (paper's Figure 3)",
            "tip u_y (m)",
            ("Q9 FE 320x64, unconverged", FINEST_FE_TIP_UY),
        )
        .svg(&tip),
    )?;
    let relative = series(&|r, m| Some((r.points as f64, m.relative)), true);
    fs::write(
        out.join("cantilever-relative.svg"),
        by_points(
            "Tip deflection relative to the left edge",
            "relative deflection (m)",
            ("Q9 FE reference", REFERENCE_RELATIVE),
        )
        .svg(&relative),
    )?;
    let refs = [Method::Ibm, Method::Grid].map(|m| reference(runs, m));
    let error = series(
        &|r, m| {
            let f = refs[(r.method == Method::Grid) as usize]?;
            let (e, _) = errors(m, &f);
            (e > 0.0).then_some((m.seconds, e))
        },
        false,
    );
    let plot = Plot {
        title: "Error against cost".into(),
        x_label: "wall time (s)".into(),
        y_label: "relative deflection error (vs finest run)".into(),
        log_x: true,
        log_y: true,
        reference: None,
    };
    fs::write(out.join("cantilever-error.svg"), plot.svg(&error))?;
    Ok(())
}
