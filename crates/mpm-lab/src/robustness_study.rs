//! `mpm study robustness`: a batch of random valid cases
//! ([`crate::random_cases`]) run under the contract ([`crate::contract`]),
//! with how many finished, failed cleanly or broke the contract, by class.
//! The failed and broken cases are written beside the table, one JSON
//! file each, to be run again with `mpm run`.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs;
use std::path::Path;
use std::time::Instant;

use crate::LabError;
use crate::contract::{Outcome, Tried, try_case};
use crate::random_cases::{Drawn, draw};

/// The batch's seed: fixed, so that the table can be drawn again.
pub const SEED: u64 = 2026;

/// One case's draw and run.
pub struct Entry {
    pub drawn: Drawn,
    pub tried: Tried,
}

/// Draws and runs cases `0..count` of `seed`, printing a line per case.
pub fn run_batch(seed: u64, count: usize) -> Vec<Entry> {
    (0..count)
        .map(|index| {
            let drawn = draw(seed, index);
            let tried = try_case(&drawn.case.to_string());
            eprintln!(
                "{}: {} in {:.1} s{}",
                drawn.label(),
                tried.outcome.name(),
                tried.seconds,
                match &tried.outcome {
                    Outcome::Finished => String::new(),
                    other => format!(" ({})", detail(other)),
                }
            );
            Entry { drawn, tried }
        })
        .collect()
}

/// What an outcome says beyond its name.
pub fn detail(outcome: &Outcome) -> String {
    match outcome {
        Outcome::Finished => String::new(),
        Outcome::Failed { message, .. } => message.clone(),
        Outcome::Refused(m) | Outcome::Panicked(m) | Outcome::Broken(m) => m.clone(),
        Outcome::TimedOut { seconds } => format!("after {seconds:.0} s"),
    }
}

/// Counts of one class.
#[derive(Default)]
struct Tally {
    cases: usize,
    finished: usize,
    failed: usize,
    broken: usize,
    seconds: Vec<f64>,
}

impl Tally {
    fn add(&mut self, tried: &Tried) {
        self.cases += 1;
        match tried.outcome {
            Outcome::Finished => self.finished += 1,
            Outcome::Failed { .. } => self.failed += 1,
            _ => self.broken += 1,
        }
        self.seconds.push(tried.seconds);
    }

    fn median_seconds(&self) -> f64 {
        let mut s = self.seconds.clone();
        s.sort_by(f64::total_cmp);
        s.get(s.len() / 2).copied().unwrap_or(0.0)
    }
}

/// The classes a case is counted in: (heading, class).
fn classes(d: &Drawn) -> Vec<(&'static str, String)> {
    vec![
        ("scene", d.scene.name().to_string()),
        ("basis", d.basis.to_string()),
        ("material", d.model.to_string()),
        ("load", d.load.to_string()),
        ("support", d.support.to_string()),
        ("points a cell", format!("{0} x {0}", d.per_cell)),
        ("magnitude", d.magnitude.to_string()),
        ("volume treatment", d.volumetric.to_string()),
        ("strength reduction", d.reduction.to_string()),
        (
            "load steps",
            match d.load_steps {
                1..=3 => "1-3",
                4..=10 => "4-10",
                _ => "11-50",
            }
            .to_string(),
        ),
    ]
}

/// The markdown report of a batch.
pub fn markdown(seed: u64, entries: &[Entry], seconds: f64) -> String {
    let mut s = String::new();
    let mut total = Tally::default();
    // The classes the targets name: the smooth bases (GIMP and the
    // B-splines), and those with two or more points a cell.
    let (mut smooth, mut held) = (Tally::default(), Tally::default());
    let mut by: BTreeMap<(&'static str, String), Tally> = BTreeMap::new();
    for e in entries {
        total.add(&e.tried);
        if e.drawn.basis != "linear" {
            smooth.add(&e.tried);
            if e.drawn.per_cell >= 2 {
                held.add(&e.tried);
            }
        }
        for class in classes(&e.drawn) {
            by.entry(class).or_default().add(&e.tried);
        }
    }
    let _ = writeln!(
        s,
        "# Random cases that must finish (`mpm study robustness`)\n\n\
         Written by `crates/mpm-lab/src/robustness_study.rs`: {} cases of seed {seed} drawn by \
         `crates/mpm-lab/src/random_cases.rs` (whose doc gives the scenes and ranges), each run \
         under the contract of `crates/mpm-lab/src/contract.rs`. `finished`: every load step \
         converged. `failed`: a clean failure, the solver's error naming its step and cause. \
         `broken`: the contract broken (a panic, a refused case, a non-finite number or an \
         inverted or exploded point in a finished step, a run past its time limit). \
         {:.0} s in all.\n",
        entries.len(),
        seconds
    );
    let pct = |n: usize, of: usize| 100.0 * n as f64 / of.max(1) as f64;
    let _ = writeln!(
        s,
        "| class | cases | finished | failed | broken | finished (%) | median s |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    let row = |s: &mut String, name: &str, t: &Tally| {
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} | {} | {:.1} | {:.2} |",
            t.cases,
            t.finished,
            t.failed,
            t.broken,
            pct(t.finished, t.cases),
            t.median_seconds()
        );
    };
    row(&mut s, "**all**", &total);
    row(&mut s, "**GIMP and the B-splines**", &smooth);
    row(
        &mut s,
        "**GIMP and the B-splines, 2 or more points a cell**",
        &held,
    );
    let mut heading = "";
    for ((h, class), t) in &by {
        if *h != heading {
            heading = h;
            let _ = writeln!(s, "| *{h}* | | | | | | |");
        }
        row(&mut s, class, t);
    }
    let unfinished: Vec<&Entry> = entries
        .iter()
        .filter(|e| e.tried.outcome != Outcome::Finished)
        .collect();
    if !unfinished.is_empty() {
        let _ = writeln!(
            s,
            "\n## The cases that did not finish\n\nEach is `case_INDEX.json` beside this file.\n"
        );
        let _ = writeln!(s, "| case | outcome | what |");
        let _ = writeln!(s, "|---|---|---|");
        for e in unfinished {
            let _ = writeln!(
                s,
                "| {} | {} | {} |",
                e.drawn.label(),
                e.tried.outcome.name(),
                detail(&e.tried.outcome).replace('|', "/")
            );
        }
    }
    s
}

/// The elastica of the issue that found the 3 x 3 failure: a clamped
/// 10 m x 1 m beam (Hencky, E = 12 MPa, nu = 0.2, EI = 1e6 N m), a dead
/// tip traction of 100 kPa (P L^2 / EI = 10) in 20 steps, clamped by the
/// implicit boundary method. The reference is the continuum's, not the
/// Euler beam's: `scripts/elastica_continuum_reference.py` (Q9 total
/// Lagrangian finite elements, n = 20 to 320, extrapolated) gives the tip's
/// mid-depth point (10, 0.5) at u_x / L = -0.554028 and u_y / L =
/// -0.825415, each to 4e-6 (Mattiasson's inextensible elastica: 0.55500
/// and 0.81061).
fn elastica_case(basis: &str, h: f64, per_cell: u32) -> serde_json::Value {
    serde_json::json!({
        "version": 1,
        "title": format!("elastica, {basis}, h = {h}, {per_cell} x {per_cell} points a cell"),
        "analysis": { "load_steps": 20 },
        "grid": { "cell_size": h },
        "basis": basis,
        "bodies": [ {
            "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [10.0, 1.0] } },
            "points": { "per_cell": per_cell },
            "material": { "model": "hencky", "youngs_modulus": 12e6, "poisson_ratio": 0.2, "density": 0.0 }
        } ],
        "loads": { "boundary": [ { "on": { "x": 10.0 }, "traction": [0.0, -100e3] } ] },
        "supports": [ { "on": { "x": 0.0 }, "fix": "xy", "method": "ibm" } ],
        "probes": [ { "name": "tip", "at": [10.0, 0.5] } ]
    })
}

/// The continuum reference of [`elastica_case`]: tip `(u_x, u_y) / L`.
const ELASTICA: [f64; 2] = [-0.554028, -0.825415];

/// The elastica table: three bases, three cells, two to four points a
/// cell.
fn elastica_table() -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\n## The elastica at 2, 3 and 4 points a cell\n\n\
         A clamped 10 m x 1 m beam (Hencky, E = 12 MPa, nu = 0.2), a dead tip traction of 100 kPa \
         (P L^2 / EI = 10) in 20 steps, clamped by the implicit boundary method, the grid's origin at \
         (0, 0). Reference: the continuum's tip (10, 0.5) at u_x / L = {}, u_y / L = {} \
         (`scripts/elastica_continuum_reference.py`, Q9 finite elements extrapolated, to 4e-6). \
         Errors relative to the reference's.\n",
        ELASTICA[0], ELASTICA[1]
    );
    let _ = writeln!(
        s,
        "| basis | h (m) | points a cell | points | u_x / L | u_y / L | error u_x | error u_y | Newton its | cut | s |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|");
    for basis in ["gimp", "bspline2", "linear"] {
        for h in [0.5, 0.25, 0.125] {
            for per_cell in [2, 3, 4] {
                let case = elastica_case(basis, h, per_cell).to_string();
                let started = Instant::now();
                let run = mpm::Case::from_json(&case)
                    .map_err(|e| e.to_string())
                    .and_then(|c| mpm::Simulation::new(&c).map_err(|e| e.to_string()))
                    .and_then(|mut sim| {
                        let points = sim.points.len();
                        (sim.run(&mut mpm::NoObserver).map_err(|e| e.to_string()))
                            .map(|r| (points, r))
                    });
                let seconds = started.elapsed().as_secs_f64();
                match run {
                    Ok((points, report)) => {
                        let u = &report.steps.last().expect("steps").probes[0].displacement;
                        let (ux, uy) = (u[0] / 10.0, u[1] / 10.0);
                        let error = |v: f64, r: f64| 100.0 * (v - r) / r.abs();
                        let _ = writeln!(
                            s,
                            "| {basis} | {h} | {per_cell} | {points} | {ux:.5} | {uy:.5} | {:+.2}% | {:+.2}% | {} | {} | {seconds:.1} |",
                            error(ux, ELASTICA[0]),
                            error(uy, ELASTICA[1]),
                            report
                                .steps
                                .iter()
                                .map(|s| s.newton.iterations)
                                .sum::<usize>(),
                            report.steps.iter().map(|s| s.cutbacks).sum::<usize>(),
                        );
                    }
                    Err(e) => {
                        let _ = writeln!(
                            s,
                            "| {basis} | {h} | {per_cell} | | failed: {} | | | | | | {seconds:.1} |",
                            e.replace('|', "/")
                        );
                    }
                }
                eprintln!("elastica {basis} h {h} {per_cell}x{per_cell}: {seconds:.1} s");
            }
        }
    }
    s
}

/// Runs the study and writes `robustness.md` (and the cases that did not
/// finish) to `out`: 1,000 cases, or 100 with `quick`, and the elastica
/// table.
pub fn robustness(out: &Path, quick: bool) -> Result<(), LabError> {
    fs::create_dir_all(out)?;
    let count = if quick { 100 } else { 1000 };
    let started = Instant::now();
    let entries = run_batch(SEED, count);
    for e in &entries {
        if e.tried.outcome != Outcome::Finished {
            let path = out.join(format!("case_{}.json", e.drawn.index));
            let text = serde_json::to_string_pretty(&e.drawn.case).expect("JSON");
            fs::write(path, text)?;
        }
    }
    let mut report = markdown(SEED, &entries, started.elapsed().as_secs_f64());
    report += &elastica_table();
    fs::write(out.join("robustness.md"), report)?;
    Ok(())
}
