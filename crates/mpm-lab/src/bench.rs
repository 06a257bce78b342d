//! `mpm bench`: cost against problem size, as a markdown report.
//!
//! Two scenes with symmetric tangents are scaled from about 1e3 to 1e6
//! material points (2x2 points per cell, the cell size shrinking): the
//! self-weight column made 10 m wide (GIMP, 52% compression) and the
//! grid-supported cantilever (linear basis, large deflection); four with
//! unsymmetric tangents from 1e4: the paper's cantilever on GIMP and on
//! quadratic B-splines (follower pressure), and the pushed footing with
//! F-bar and with non-associated Mohr-Coulomb. Each runs its first two
//! load steps, which is enough to time a step and its Newton iterations.
//! Separately, the 896-point cantilever runs end to end many times and
//! its median wall time is reported, and the plastic models' return maps
//! are timed in the point loop against Hencky's elasticity
//! ([`return_map_cost`]).

use std::fs;
use std::path::Path;
use std::time::Instant;

use mpm::boundary::surface::Interpolation;
use mpm::case::solid::SolidCase;
use mpm::linsolve::{FillOrdering, SolverSettings, SymmetricMethod, UnsymmetricMethod};
use mpm::particles::Dim;
use mpm::report::{StepMemory, StepTimings};
use mpm::stepper::RunSpace;
use mpm::{Case, NoObserver, Simulation};
use serde_json::{Value, json};

use crate::LabError;

/// A scene scaled so that it has about `points` material points.
struct Scene {
    name: &'static str,
    build: fn(usize) -> Value,
}

/// The scenes: the size, memory and symmetric-solve tables run the first
/// [`SYMMETRIC_SCENES`], whose tangents are symmetric; the unsymmetric
/// table the rest.
const SCENES: [Scene; 9] = [
    Scene {
        name: "column (10 m x 50 m, GIMP, Hencky)",
        build: wide_column,
    },
    Scene {
        name: "cantilever-grid (10 m x 2 m, linear, Hencky)",
        build: cantilever,
    },
    Scene {
        name: "paper's cantilever (10 m x 2 m, GIMP, follower pressure)",
        build: paper_cantilever,
    },
    Scene {
        name: "paper's cantilever (10 m x 2 m, bspline2, follower pressure)",
        build: paper_cantilever_bspline2,
    },
    Scene {
        name: "footing push (von Mises, F-bar, GIMP)",
        build: footing_fbar,
    },
    Scene {
        name: "footing push (Mohr-Coulomb, psi = 0, GIMP)",
        build: footing_mohr_coulomb,
    },
    Scene {
        name: "3D column (10 m x 10 m x 50 m, GIMP, Hencky)",
        build: column_3d,
    },
    Scene {
        name: "3D cantilever (10 m x 2 m x 2 m, GIMP, Hencky, self-weight)",
        build: cantilever_3d,
    },
    Scene {
        name: "3D column on the IBM (10 m x 10 m x 50 m, GIMP, Hencky, cut grid)",
        build: column_3d_ibm,
    },
];
/// The 3D scenes (`analysis.type: "3d"`) of the size table.
const SOLID_SCENES: std::ops::Range<usize> = 6..8;
/// The 3D scene whose supports are on its B-spline surfaces.
const SURFACE_SCENE: usize = 8;
const SYMMETRIC_SCENES: usize = 2;
/// The scenes (from [`SYMMETRIC_SCENES`] on) whose tangents change with
/// plastic flow, measured up to [`PLASTIC_MAX_POINTS`].
const PLASTIC_SCENES: std::ops::Range<usize> = 4..6;

/// Cells across the short side so that 2x2 points per cell give about
/// `points` points on a 1 x 5 domain: points = 4 * m * 5m.
fn cells_across(points: usize) -> usize {
    ((points as f64 / 20.0).sqrt().round() as usize).max(1)
}

/// Cells across the short side so that 2x2x2 points per cell give about
/// `points` points on a 1 x 1 x 5 domain: points = 8 * m * m * 5m.
fn cells_across_3d(points: usize) -> usize {
    ((points as f64 / 40.0).cbrt().round() as usize).max(1)
}

/// The 3D column (`mpm example column3d`) made 10 m x 10 m across with
/// about `points` points: rollers on its four sides, fixed at its base.
fn column_3d(points: usize) -> Value {
    let h = 10.0 / cells_across_3d(points) as f64;
    let mut case = example("column3d");
    case["grid"]["cell_size"] = h.into();
    case["grid"]["extent"] = json!({"min": [0.0, 0.0, 0.0], "max": [10.0, 10.0, 50.0]});
    case["bodies"][0]["geometry"]["box"]["max"] = json!([10.0, 10.0, 50.0]);
    case["supports"][1]["on"]["x"] = 10.0.into();
    case["supports"][3]["on"]["y"] = 10.0.into();
    case
}

/// A 3D cantilever 10 m x 2 m x 2 m clamped by the grid plane x = 0,
/// bent by its weight (Hencky, E = 1 MPa, rho g = 1 kN/m3: a tip
/// deflection of some 2 m), with about `points` points, 2x2x2 a cell.
fn cantilever_3d(points: usize) -> Value {
    let h = 2.0 / cells_across_3d(points) as f64;
    json!({
        "version": 1,
        "analysis": { "type": "3d", "load_steps": 5 },
        "grid": { "cell_size": h },
        "basis": "gimp",
        "bodies": [{
            "geometry": { "box": { "min": [0.0, 0.0, 0.0], "max": [10.0, 2.0, 2.0] } },
            "points": { "per_cell": 2 },
            "material": { "model": "hencky", "youngs_modulus": 1.0e6, "poisson_ratio": 0.3, "density": 100.0 }
        }],
        "loads": { "gravity": [0.0, 0.0, -10.0] },
        "supports": [{ "on": { "x": 0.0 }, "fix": "xyz" }]
    })
}

/// The 3D column of [`column_3d`] held by the implicit boundary method
/// on its B-spline surfaces instead of grid planes (rollers on its four
/// sides, its base fixed) on a grid whose planes cut it (origin at -0.3
/// of a cell): the band is made on the rebuilt surfaces every step. (A
/// traction on its top would make the tangent unsymmetric, which in 3D is
/// solved by GMRES with a direct factor, out of reach at 1e6 points.)
fn column_3d_ibm(points: usize) -> Value {
    let h = 10.0 / cells_across_3d(points) as f64;
    let plane =
        |point: [f64; 3], normal: [f64; 3]| json!({"plane": {"point": point, "normal": normal}});
    let roller = |point, normal| json!({"on": plane(point, normal), "fix": "normal"});
    let mut case = example("column3d");
    let origin = [-0.3 * h; 3];
    case["grid"] = json!({"cell_size": h, "origin": origin});
    case["bodies"][0]["geometry"]["box"]["max"] = json!([10.0, 10.0, 50.0]);
    case["supports"] = json!([]);
    case["surface_supports"] = json!([
        roller([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
        roller([10.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
        roller([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        roller([0.0, 10.0, 0.0], [0.0, 1.0, 0.0]),
        {"on": plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]), "fix": "xyz"},
    ]);
    case
}

fn example(name: &str) -> Value {
    mpm::case::builtin::json(name).expect("built-in example")
}

/// The self-weight column made 10 m wide with about `points` points (the
/// first scene of the size table).
pub fn wide_column(points: usize) -> Value {
    let h = 10.0 / cells_across(points) as f64;
    let mut case = example("column");
    case["grid"]["cell_size"] = h.into();
    case["grid"]["extent"] = json!({"min": [0.0, 0.0], "max": [10.0, 50.0]});
    case["bodies"][0]["geometry"]["rectangle"]["max"] = json!([10.0, 50.0]);
    case["supports"][1]["on"]["x"] = 10.0.into();
    case["probes"][0]["at"] = json!([5.0, 50.0]);
    case
}

/// The paper's cantilever (`mpm example cantilever`: 1500 Pa of follower
/// pressure on its B-spline boundary in 5 steps, supports by the IBM) on
/// GIMP with about `points` points, 2x2 a cell.
fn paper_cantilever(points: usize) -> Value {
    let across = 2 * cells_across(points);
    let mut case = example("cantilever");
    case["basis"] = json!("gimp");
    case["grid"]["cell_size"] = (4.0 / across as f64).into();
    case["bodies"][0]["points"] = json!({ "count": [5 * across, across] });
    case
}

/// [`paper_cantilever`] on quadratic B-splines.
fn paper_cantilever_bspline2(points: usize) -> Value {
    let mut case = paper_cantilever(points);
    case["basis"] = json!("bspline2");
    case
}

/// The built-in footing (`mpm example footing`: a rigid strip footing
/// pushed into weightless undrained clay by the IBM, von Mises with F-bar,
/// 5 m x 3 m half model, 2x2 points a cell) with about `points` points,
/// the grid's origin off the material by 0.3 cells.
fn footing_fbar(points: usize) -> Value {
    let h = (60.0 / points as f64).sqrt();
    let mut case = example("footing");
    case["grid"]["cell_size"] = h.into();
    case["grid"]["origin"] = json!([-0.3 * h, -0.3 * h]);
    case
}

/// [`footing_fbar`] on a Mohr-Coulomb soil with non-associated flow (c =
/// 10 kPa, phi = 20 degrees, psi = 0, E = 100 MPa, nu = 0.3) and no F-bar.
fn footing_mohr_coulomb(points: usize) -> Value {
    let mut case = footing_fbar(points);
    case["analysis"]
        .as_object_mut()
        .expect("an analysis object")
        .remove("volumetric");
    case["bodies"][0]["material"] = json!({
        "model": "mohr_coulomb",
        "youngs_modulus": 1.0e8,
        "poisson_ratio": 0.3,
        "density": 0.0,
        "cohesion": 1.0e4,
        "friction_angle": 20.0,
        "dilation_angle": 0.0
    });
    case
}

fn cantilever(points: usize) -> Value {
    let h = 2.0 / cells_across(points) as f64;
    let mut case = example("cantilever-grid");
    case["grid"]["cell_size"] = h.into();
    case
}

/// The timings of the first load steps of one scene at one size.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Row {
    points: usize,
    dofs: usize,
    steps: usize,
    iterations: usize,
    timings: StepTimings,
    peak_mib: Option<f64>,
    /// Entries of the last Cholesky factor (0: none was computed).
    #[serde(default)]
    factor_entries: usize,
    /// Steps that analysed a new pattern, and steps that reused the last
    /// step's analysis.
    #[serde(default)]
    analysed_steps: usize,
    #[serde(default)]
    reused_steps: usize,
    /// Heap bytes by component at the last step's end.
    #[serde(default)]
    memory: StepMemory,
    /// Symmetric solves by a fresh factorisation, by CG with a kept
    /// factor, and those CG solves' iterations.
    #[serde(default)]
    fresh_factorisations: usize,
    #[serde(default)]
    cg_solves: usize,
    #[serde(default)]
    cg_iterations: usize,
    /// 3D: the surfaces' data points, the supports' anchors, and the
    /// seconds to interpolate every patch once through the data points
    /// where the last step left them (the median of five).
    #[serde(default)]
    surface_points: usize,
    #[serde(default)]
    anchors: usize,
    #[serde(default)]
    surfaces_seconds: f64,
}

/// Sections of BENCHMARKS.md that `mpm bench` keeps: `mpm bench-queue`'s,
/// and the measurements made by hand or too long for it (see the closing
/// notes in docs/).
const KEPT_SECTIONS: [&str; 5] = [
    "## Bending of points one a cell",
    "## Job queue",
    "## Ten million points",
    "## Generic over the dimension",
    "## Before and after",
];

pub fn bench(max_points: usize, out: &Path, repeats: usize) -> Result<(), LabError> {
    let mut report = String::new();
    report.push_str("# Benchmarks\n\n");
    report.push_str(&format!(
        "Written by `mpm bench --max-points {max_points}` ({} threads in rayon's pool; faer's Cholesky on them \
         from 150k DOFs, sequential below, LU sequential; symmetric tangents factorised every Newton iteration \
         below {kept} DOFs, by CG with a kept factor from there and with a multigrid V-cycle from {multigrid}; \
         unsymmetric ones by LU below {gmres} DOFs and by GMRES from there, as the section on them says). \
         Times are wall-clock seconds on this machine; they vary between runs by 10-20%, so compare ratios.\n\n",
        rayon::current_num_threads(),
        kept = mpm::linsolve::KEPT_FACTOR_FROM_DOFS,
        multigrid = mpm::linsolve::MULTIGRID_FROM_DOFS,
        gmres = mpm::linsolve::GMRES_FROM_DOFS,
    ));

    let (median, min, max, points) = end_to_end(repeats)?;
    report.push_str("## Small case end to end\n\n");
    report.push_str(&format!(
        "The paper's cantilever (`mpm example cantilever`: {points} points, 1.5 m cells, 1500 Pa follower \
         pressure on the B-spline boundary in 5 load steps, supports by the implicit boundary method), `Simulation::new` + `run`, no \
         file output: median **{:.1} ms** over {repeats} runs (min {:.1}, max {:.1}).\n\n",
        median * 1e3,
        min * 1e3,
        max * 1e3
    ));

    report.push_str("## Cost against size\n\n");
    report.push_str(
        "First two load steps of each scene. Split: share of the step's wall time in the grid reset \
         (shape functions, active nodes, sparsity pattern, loads), the point loop (stress and tangent of every \
         point, internal force), stiffness assembly, sparse factorisation (symbolic analysis included once per \
         step), triangular solves, the point update, and Newton's own work (vector updates, convergence checks, \
         the line search's bookkeeping). No step of these was cut, so no failed tries. Points/s counts \
         point-steps per second of wall time. \
         Peak memory is the high-water resident set of a process that runs only that row.\n\n",
    );
    report.push_str("| scene | points | active DOFs | s / step | s / iteration | iterations / step | grid | point loop | assembly | factorisation | solve | update | Newton | points/s | peak MiB |\n");
    report
        .push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    let mut largest = Vec::new();
    for (index, scene) in SCENES[..SYMMETRIC_SCENES].iter().enumerate() {
        let mut target = 1_000;
        while target <= max_points {
            let row = measure_in_child(index, target)?;
            let t = &row.timings;
            let per_step = t.total / row.steps as f64;
            let pct = |x: f64| format!("{:.0}%", 100.0 * x / t.total);
            let line = format!(
                "| {} | {} | {} | {:.3} | {:.3} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {:.2e} | {} |\n",
                scene.name,
                row.points,
                row.dofs,
                per_step,
                t.total / row.iterations.max(1) as f64,
                row.iterations as f64 / row.steps as f64,
                pct(t.grid),
                pct(t.point_loop),
                pct(t.assembly),
                pct(t.factorisation),
                pct(t.solve),
                pct(t.update),
                pct(t.newton),
                row.points as f64 * row.steps as f64 / t.total,
                row.peak_mib
                    .map_or("n/a".to_string(), |m| format!("{m:.0}")),
            );
            eprint!("{line}");
            report.push_str(&line);
            if target * 10 > max_points {
                largest.push((scene.name, row));
            }
            target *= 10;
        }
    }
    report.push_str(&memory_by_component(&largest));
    report.push_str(&solid_scenes(max_points)?);
    report.push_str(&surface_costs(max_points)?);
    report.push_str(&symmetric_methods(max_points)?);
    report.push_str(&unsymmetric_methods(max_points)?);
    report.push_str(&ordering_comparison(max_points)?);
    report.push_str(&symbolic_reuse()?);
    report.push_str(&return_map_cost()?);
    // Sections written by other commands or by hand: keep them.
    let earlier = fs::read_to_string(out).unwrap_or_default();
    for heading in KEPT_SECTIONS {
        if let Some(start) = earlier.find(&format!("\n{heading}")) {
            let rest = &earlier[start + 1..];
            let end = rest[3..].find("\n## ").map_or(rest.len(), |i| i + 4);
            // One blank line between sections, however many the file had.
            report.truncate(report.trim_end().len());
            report.push_str("\n\n");
            report.push_str(rest[..end].trim_end());
            report.push('\n');
        }
    }
    fs::write(out, &report)?;
    println!("{report}");
    Ok(())
}

/// The plastic models' return maps in the point loop, against Hencky's
/// elasticity on the same case: a 1 m block of 40,000 points (GIMP, 2x2 a
/// cell) squeezed 5% in 5 steps by the IBM, every point yielding from the
/// first step. The point loop's time (stress, tangent and internal force
/// of every point) per point per residual evaluation (Newton iterations
/// plus the first residual of each step; a line search's extra trials, if
/// any, make it an upper bound).
fn return_map_cost() -> Result<String, LabError> {
    let materials = [
        ("hencky", json!({})),
        ("von_mises", json!({ "yield_stress": 1.0e3 })),
        (
            "drucker_prager",
            json!({ "cohesion": 577.0, "friction_angle": 20.0 }),
        ),
        (
            "mohr_coulomb",
            json!({ "cohesion": 577.0, "friction_angle": 20.0 }),
        ),
    ];
    let mut text = String::from(
        "\n## Return map in the point loop\n\n\
         A 1 m block of 40,000 points (GIMP, 2x2 per cell, E = 1 MPa, nu = 0.3) squeezed 5% in 5 steps by the \
         implicit boundary method, every plastic point yielding from the first step. Point-loop time (stress, \
         tangent and internal force of every point) per point per residual evaluation (Newton iterations plus \
         each step's first residual), median of 3 runs.\n\n\
         | model | iterations | ns / point / evaluation | ratio to Hencky |\n|---|---:|---:|---:|\n",
    );
    let mut hencky = f64::NAN;
    for (name, extra) in materials {
        let mut material =
            json!({ "model": name, "youngs_modulus": 1.0e6, "poisson_ratio": 0.3, "density": 0.0 });
        for (k, v) in extra.as_object().expect("an object") {
            material[k] = v.clone();
        }
        let case = json!({
            "version": 1,
            "analysis": { "load_steps": 5 },
            "grid": { "cell_size": 0.01, "origin": [0.003, 0.003] },
            "basis": "gimp",
            "bodies": [{ "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [1.0, 1.0] } },
                         "points": { "per_cell": 2 }, "material": material }],
            "supports": [
                { "on": { "x": 0.0 }, "fix": "normal", "method": "ibm" },
                { "on": { "y": 0.0 }, "fix": "normal", "method": "ibm" },
                { "on": { "y": 1.0 }, "fix": "y", "method": "ibm", "displacement": [0.0, -0.05] }
            ]
        });
        let case =
            Case::from_json(&case.to_string()).map_err(|e| LabError::Failed(e.to_string()))?;
        let mut costs = Vec::new();
        let mut iterations = 0;
        for _ in 0..3 {
            let mut sim = Simulation::new(&case).map_err(|e| LabError::Failed(e.to_string()))?;
            let run = sim
                .run(&mut NoObserver)
                .map_err(|e| LabError::Failed(format!("return-map block, {name}: {e}")))?;
            iterations = run.steps.iter().map(|s| s.newton.iterations).sum::<usize>();
            let evaluations = iterations + run.steps.len();
            let point_loop: f64 = run.steps.iter().map(|s| s.timings.point_loop).sum();
            costs.push(point_loop / (run.points * evaluations) as f64 * 1e9);
        }
        costs.sort_by(f64::total_cmp);
        let ns = costs[1];
        if name == "hencky" {
            hencky = ns;
        }
        let line = format!("| {name} | {iterations} | {ns:.0} | {:.2} |\n", ns / hencky);
        eprint!("{line}");
        text.push_str(&line);
    }
    Ok(text)
}

/// The environment variable a `bench-row` child reads its fill ordering
/// from: `minimum_degree` or `nested_dissection` (the default).
const ORDERING_VARIABLE: &str = "MPM_BENCH_FILL_ORDERING";
/// `direct`, `kept_factor_cg` or `multigrid`: how the child solves symmetric tangents
/// whatever their size ([`SolverSettings::symmetric`]).
const METHOD_VARIABLE: &str = "MPM_BENCH_SYMMETRIC_METHOD";
/// `direct` or `gmres`: how the child solves tangents that are not
/// symmetric whatever their size ([`SolverSettings::unsymmetric`]).
const UNSYMMETRIC_VARIABLE: &str = "MPM_BENCH_UNSYMMETRIC_METHOD";

/// Heap bytes per point by component at the largest size of each scene,
/// beside the peak resident set per point.
fn memory_by_component(largest: &[(&str, Row)]) -> String {
    let mut text = String::from(
        "\n## Memory per point\n\n\
         Heap bytes per material point by component at the end of the second load step of the largest row \
         of each scene above (`StepMemory`): the points' state; their links to the active nodes (node, shape \
         function value and gradient) with the node keys; the stiffness pattern (node adjacency, the points in \
         tiles for the assembly, compressed columns' pointers and row indices); the tangent's values; what \
         the point loop keeps between iterations (F-bar's cell terms only: the responses are made again where \
         they are used); the Cholesky factor's values and structure; the numeric factorisation's scratch \
         (freed after each: the permuted triangle of the tangent it reads, in the factor's precision, and \
         faer's workspace); the multigrid hierarchy (the default from 150,000 DOFs). Peak is the process's \
         high-water \
         resident set.\n\n\
         | scene | points | points' state | links | pattern | tangent | responses | factor values | factor structure | factorisation scratch | multigrid | sum | peak |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for (name, row) in largest {
        let m = &row.memory;
        let per = |bytes: usize| format!("{:.0}", bytes as f64 / row.points as f64);
        let peak = row.peak_mib.map_or("n/a".to_string(), |mib| {
            format!("{:.0}", mib * 1024.0 * 1024.0 / row.points as f64)
        });
        text.push_str(&format!(
            "| {name} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {peak} |\n",
            row.points,
            per(m.points),
            per(m.links),
            per(m.pattern),
            per(m.tangent),
            per(m.responses),
            per(m.solver.factor_values),
            per(m.solver.factor_structure),
            per(m.solver.scratch),
            per(m.solver.multigrid),
            per(m.total()),
        ));
    }
    text
}

/// The 3D scenes from 1e4 points up: the cost of a step, its split, the
/// memory a point, and how the linear solves' time grows with the DOFs.
fn solid_scenes(max_points: usize) -> Result<String, LabError> {
    let mut text = format!(
        "\n## In 3D\n\n\
         The 3D scenes (issue 38), 2x2x2 points a cell, first two load steps, the default solvers: the \
         tangents are symmetric, solved directly below {kept} DOFs, by CG with a kept factor from there and \
         by CG with multigrid from {multigrid} (`linsolve.rs`). Split as in the size table; bytes a point are the \
         peak resident set's.\n\n",
        kept = mpm::linsolve::SOLID_KEPT_FACTOR_FROM_DOFS,
        multigrid = mpm::linsolve::SOLID_MULTIGRID_FROM_DOFS,
    );
    for index in SOLID_SCENES {
        let scene = &SCENES[index];
        text.push_str(
            "| scene | points | active DOFs | s / step | s / iteration | iterations / step | point loop | assembly | factorisation | solve | other | bytes / point | peak MiB |\n\
             |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        );
        let mut first: Option<(f64, f64)> = None;
        let mut last = None;
        let mut target = 10_000;
        while target <= max_points {
            let row = measure_in_child(index, target)?;
            let t = &row.timings;
            let pct = |x: f64| format!("{:.0}%", 100.0 * x / t.total);
            let solving = (t.factorisation + t.solve) / row.steps as f64;
            first.get_or_insert((row.dofs as f64, solving));
            last = Some((row.dofs as f64, solving));
            let line = format!(
                "| {} | {} | {} | {:.3} | {:.3} | {:.1} | {} | {} | {} | {} | {} | {} | {} |\n",
                scene.name,
                row.points,
                row.dofs,
                t.total / row.steps as f64,
                t.total / row.iterations.max(1) as f64,
                row.iterations as f64 / row.steps as f64,
                pct(t.point_loop),
                pct(t.assembly),
                pct(t.factorisation),
                pct(t.solve),
                pct(t.grid + t.update + t.newton),
                row.peak_mib.map_or("n/a".to_string(), |m| {
                    format!("{:.0}", m * 1024.0 * 1024.0 / row.points as f64)
                }),
                row.peak_mib
                    .map_or("n/a".to_string(), |m| format!("{m:.0}")),
            );
            eprint!("{line}");
            text.push_str(&line);
            target *= 10;
        }
        if let (Some((d0, s0)), Some((d1, s1))) = (first, last)
            && d1 > d0
        {
            text.push_str(&format!(
                "\n{}: the solves' time grows as DOFs^{:.2} from the first row to the last.\n\n",
                scene.name,
                (s1 / s0).ln() / (d1 / d0).ln()
            ));
        }
    }
    Ok(text)
}

/// The boundary's share of a 3D step ([`SURFACE_SCENE`]) from 1e4
/// points up: the surfaces rebuilt (every patch interpolated once), and
/// the boundary's terms (`StepTimings::boundary`: the band made, which
/// rebuilds the patches it is on, and its forces and stiffness in every
/// iteration), against the whole step.
fn surface_costs(max_points: usize) -> Result<String, LabError> {
    let scene = &SCENES[SURFACE_SCENE];
    let mut text = format!(
        "\n## The boundary in 3D\n\n\
         The {name}: the column of the 3D table held by the implicit boundary method on its B-spline surfaces \
         (rollers on its four sides, its base fixed; 4 x 4 anchors a surface cell), on a grid whose planes cut \
         it; first two load steps. Surfaces: every patch \
         interpolated once through its data points (`Interpolation::new`, the median of five, after the second \
         step), what each step does before its loads and supports are integrated. Boundary: the step's \
         boundary terms (`timings.boundary` of the step reports): the band made (the supported patches \
         rebuilt, the anchors' shares of the nodes, the stiffness summed by the nodes it couples), and its \
         forces and stiffness in every Newton iteration. Both against the \
         whole step.\n\n\
         | points | surface data points | anchors | active DOFs | s / step | iterations / step | surfaces s | surfaces % of step | boundary s / step | boundary % of step | CG iterations | peak MiB |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        name = scene.name,
    );
    let mut target = 10_000;
    while target <= max_points {
        let row = measure_in_child(SURFACE_SCENE, target)?;
        let t = &row.timings;
        let per_step = t.total / row.steps as f64;
        let boundary = t.boundary / row.steps as f64;
        let line = format!(
            "| {} | {} | {} | {} | {:.3} | {:.1} | {:.4} | {:.2}% | {:.3} | {:.1}% | {} | {} |\n",
            row.points,
            row.surface_points,
            row.anchors,
            row.dofs,
            per_step,
            row.iterations as f64 / row.steps as f64,
            row.surfaces_seconds,
            100.0 * row.surfaces_seconds / per_step,
            boundary,
            100.0 * boundary / per_step,
            row.cg_iterations,
            row.peak_mib
                .map_or("n/a".to_string(), |m| format!("{m:.0}")),
        );
        eprint!("{line}");
        text.push_str(&line);
        target *= 10;
    }
    Ok(text)
}

/// Symmetric tangents solved by factorising every one (direct) against CG
/// preconditioned by a kept factor and by multigrid, on both scenes from
/// 1e4 points up.
fn symmetric_methods(max_points: usize) -> Result<String, LabError> {
    let mut text = String::from(
        "\n## Symmetric solves: direct, CG with a kept factor, CG with multigrid\n\n\
         Both scenes' tangents are symmetric. Direct: every Newton iteration's tangent factorised in double \
         precision. Kept factor: CG to the accuracy Newton's forcing term asks for (`crates/mpm/src/newton.rs`, \
         1e-3 to 3e-7), preconditioned by the single-precision factor of an earlier tangent of the pattern, \
         refreshed when CG with it reduced the residual by less than 0.15 an iteration \
         (`crates/mpm/src/krylov.rs`, `linsolve.rs`). Multigrid: CG to the same accuracy, preconditioned by a \
         smoothed-aggregation V-cycle (`crates/mpm/src/multigrid.rs`) built on an earlier tangent of the pattern \
         (its 'factorisations' are hierarchies built). The default switches from direct to the kept factor at \
         40,000 DOFs and to multigrid at 150,000. \
         First two load steps; fresh factorisations, CG solves and CG iterations over both.\n\n\
         | scene | points | active DOFs | method | s / step | factorisation s / step | solve s / step | Newton iterations | factorisations | CG solves | CG iterations | peak MiB |\n\
         |---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for (index, scene) in SCENES[..SYMMETRIC_SCENES].iter().enumerate() {
        let mut target = 10_000;
        while target <= max_points {
            for method in ["direct", "kept_factor_cg", "multigrid"] {
                let row = measure_in_child_with(index, target, &[(METHOD_VARIABLE, method)])?;
                let label = match method {
                    "direct" => "direct",
                    "kept_factor_cg" => "kept factor + CG",
                    _ => "multigrid + CG",
                };
                let line = solve_row(scene.name, label, &row);
                eprint!("{line}");
                text.push_str(&line);
            }
            target *= 10;
        }
    }
    Ok(text)
}

/// A row of the solve tables: the scene, the method's label, and the
/// row's times per step, iterations, factorisations, Krylov solves and
/// peak memory.
fn solve_row(scene: &str, label: &str, row: &Row) -> String {
    let steps = row.steps as f64;
    format!(
        "| {scene} | {} | {} | {label} | {:.3} | {:.3} | {:.3} | {} | {} | {} | {} | {} |\n",
        row.points,
        row.dofs,
        row.timings.total / steps,
        row.timings.factorisation / steps,
        row.timings.solve / steps,
        row.iterations,
        row.fresh_factorisations,
        row.cg_solves,
        row.cg_iterations,
        row.peak_mib
            .map_or("n/a".to_string(), |m| format!("{m:.0}")),
    )
}

/// The largest size at which the unsymmetric table factorises every
/// tangent by LU (sequential, COLAMD: about 1 s a factorisation at 26k
/// DOFs, and growing faster than the Cholesky factors).
const UNSYMMETRIC_DIRECT_MAX_POINTS: usize = 100_000;

/// The largest size of the plastic scenes: their symmetric parts are often
/// not positive definite, and LU then solves (hours at 1e6 points). The
/// Mohr-Coulomb footing's nearly always are: it stops at 1e4 (its 1e5 row
/// ran past 30 minutes).
const PLASTIC_MAX_POINTS: usize = 100_000;
const NON_ASSOCIATED_MAX_POINTS: usize = 10_000;

/// Tangents that are not symmetric solved by LU every Newton iteration
/// (direct) against GMRES preconditioned by the symmetric part, from 1e4
/// points up; then the quadratic B-splines' cost against GIMP's.
fn unsymmetric_methods(max_points: usize) -> Result<String, LabError> {
    let mut text = format!(
        "\n## Unsymmetric solves: LU against GMRES\n\n\
         The follower pressure's load stiffness makes the paper's cantilever's tangent unsymmetric; F-bar and \
         plastic flow (non-associated for Mohr-Coulomb with psi = 0) make the pushed footing's. Direct: \
         every Newton iteration's tangent factorised by LU (faer, COLAMD, sequential). GMRES: restarted \
         flexible GMRES (`crates/mpm/src/krylov.rs`) to the accuracy Newton's forcing term asks for, \
         preconditioned on the right by the single-precision Cholesky factor (nested dissection, as for \
         symmetric tangents) of the symmetric part `(K + K^T) / 2` of an earlier tangent of the increment, \
         refreshed as CG's kept factor is, and from {multigrid} DOFs by a multigrid V-cycle of the symmetric \
         part instead (for elastic bodies on GIMP or the linear basis from {elastic} DOFs: the paper's \
         cantilever on GIMP); a tangent whose symmetric part is not positive definite is solved by LU, and after \
         {limit} such in a row, the rest of the increment (`crates/mpm/src/linsolve.rs`). The default \
         switches from LU to GMRES at {gmres} DOFs. First two load steps (the footings' first steps are cut \
         into pieces: their failed tries are in the time); fresh factorisations (Cholesky's of the symmetric \
         part or multigrid set-ups; LU's are not counted), GMRES solves and their iterations over both. The \
         exponent is that of the factorisation and solve time per step against the DOFs, from the row of \
         the same scene and method one size down. The plastic scenes stop at {plastic} points (Mohr-Coulomb's at 10,000), and their LU rows at 10,000.\n\n\
         | scene | points | active DOFs | method | s / step | factorisation s / step | solve s / step | Newton iterations | factorisations | GMRES solves | GMRES iterations | peak MiB | exponent |\n\
         |---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        multigrid = mpm::linsolve::MULTIGRID_FROM_DOFS,
        elastic = mpm::linsolve::ELASTIC_GMRES_MULTIGRID_FROM_DOFS,
        limit = mpm::linsolve::GMRES_INDEFINITE_LIMIT,
        gmres = mpm::linsolve::GMRES_FROM_DOFS,
        plastic = PLASTIC_MAX_POINTS,
    );
    // Per scene and method, the last row's (DOFs, solve seconds a step);
    // and the GMRES rows' seconds a step of the GIMP and bspline2 scenes.
    let mut previous: std::collections::HashMap<(usize, &str), (f64, f64)> = Default::default();
    let mut by_basis: Vec<(usize, usize, f64)> = Vec::new();
    let unsymmetric = SYMMETRIC_SCENES..SOLID_SCENES.start;
    for (index, scene) in SCENES
        .iter()
        .enumerate()
        .skip(unsymmetric.start)
        .take(unsymmetric.len())
    {
        let largest = if index == PLASTIC_SCENES.end - 1 {
            max_points.min(NON_ASSOCIATED_MAX_POINTS)
        } else if PLASTIC_SCENES.contains(&index) {
            max_points.min(PLASTIC_MAX_POINTS)
        } else {
            max_points
        };
        let mut target = 10_000;
        while target <= largest {
            for method in ["direct", "gmres"] {
                // LU on the plastic scenes is compared at the smallest size:
                // larger, it takes minutes a row, and their GMRES rows fall
                // back to it anyway.
                let direct_max = if PLASTIC_SCENES.contains(&index) {
                    10_000
                } else {
                    UNSYMMETRIC_DIRECT_MAX_POINTS
                };
                if method == "direct" && target > direct_max {
                    continue;
                }
                let row = measure_in_child_with(index, target, &[(UNSYMMETRIC_VARIABLE, method)])?;
                let label = if method == "direct" { "LU" } else { "GMRES" };
                let steps = row.steps as f64;
                let solving = (row.timings.factorisation + row.timings.solve) / steps;
                let exponent = previous
                    .insert((index, method), (row.dofs as f64, solving))
                    .map_or(String::new(), |(dofs, seconds)| {
                        format!(
                            "{:.2}",
                            (solving / seconds).ln() / (row.dofs as f64 / dofs).ln()
                        )
                    });
                let line = solve_row(scene.name, label, &row);
                let line = format!("{} {exponent} |\n", line.trim_end());
                eprint!("{line}");
                text.push_str(&line);
                if method == "gmres" && (index == 2 || index == 3) {
                    by_basis.push((index, row.points, row.timings.total / steps));
                }
            }
            target *= 10;
        }
    }
    text.push_str(&basis_cost(&by_basis));
    Ok(text)
}

/// The quadratic B-splines' seconds a step against GIMP's on the paper's
/// cantilever at the same sizes (the GMRES rows of the table above:
/// `(scene, points, s / step)`).
fn basis_cost(rows: &[(usize, usize, f64)]) -> String {
    let mut text = String::from(
        "\n### Quadratic B-splines against GIMP\n\n\
         The paper's cantilever on both bases at the same points (2x2 a cell), default solvers, first two \
         load steps (the rows above). A quadratic B-spline reaches 4x4 nodes a point where GIMP reaches 3x3 \
         (16 against 9 links, 256 against 81 pairs in the stiffness), and its tangent has 7x7 nodes a \
         column against 5x5.\n\n\
         | points | GIMP s / step | bspline2 s / step | ratio |\n|---:|---:|---:|---:|\n",
    );
    for &(_, points, gimp) in rows.iter().filter(|r| r.0 == 2) {
        if let Some(&(_, _, bspline2)) = rows.iter().find(|r| r.0 == 3 && r.1 == points) {
            text.push_str(&format!(
                "| {points} | {gimp:.3} | {bspline2:.3} | {:.2} |\n",
                bspline2 / gimp
            ));
        }
    }
    text
}

/// Load steps that reused the last step's symbolic analysis (the pattern
/// unchanged), over whole runs of the built-in examples.
fn symbolic_reuse() -> Result<String, LabError> {
    let mut text = String::from(
        "\n## Symbolic analysis reused across load steps\n\n\
         A step whose stiffness pattern (node adjacency) equals the last step's takes over its solver: the \
         fill-reducing ordering and symbolic factorisation (and a kept factor). Whole runs of the built-in \
         examples; every increment tried is counted (a load step cut into pieces counts each piece, failed \
         ones too).\n\n\
         | example | points | load steps | increments that analysed | increments that reused | reused |\n\
         |---|---:|---:|---:|---:|---:|\n",
    );
    for name in mpm::case::builtin::NAMES {
        let case = Case::from_json(&example(name).to_string())
            .map_err(|e| LabError::Failed(e.to_string()))?;
        let mut sim = Simulation::new(&case).map_err(|e| LabError::Failed(e.to_string()))?;
        sim.run(&mut NoObserver)
            .map_err(|e| LabError::Failed(format!("{name}: {e}")))?;
        let counts = sim.solve_counts();
        let (analysed, reused) = (counts.analysed, counts.reused);
        text.push_str(&format!(
            "| {name} | {} | {} | {analysed} | {reused} | {:.0}% |\n",
            sim.points.len(),
            sim.load_steps,
            100.0 * reused as f64 / (analysed + reused).max(1) as f64
        ));
    }
    Ok(text)
}

/// Cholesky's fill-reducing orderings compared on the symmetric scene (the
/// column), from 1e4 points up: the factor's entries, the factorisation's
/// time and the peak memory.
fn ordering_comparison(max_points: usize) -> Result<String, LabError> {
    let mut text = String::from(
        "\n## Fill-reducing ordering\n\n\
         The column's tangent is symmetric (Cholesky): faer's approximate minimum degree against nested \
         dissection of the active nodes by grid lines (`crates/mpm/src/ordering.rs`). First two load steps, \
         every tangent factorised (the direct method); factor entries of the last factorisation; \
         factorisation seconds per step (the symbolic analysis included, once a step).\n\n\
         | points | active DOFs | ordering | factor entries | entries / DOF | factorisation s / step | s / step | peak MiB |\n\
         |---:|---:|---|---:|---:|---:|---:|---:|\n",
    );
    // Per ordering, (DOFs, factorisation seconds per step) of each size.
    let mut growth: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
    let mut target = 10_000;
    while target <= max_points {
        for (k, ordering) in ["minimum_degree", "nested_dissection"]
            .into_iter()
            .enumerate()
        {
            let variables = [(ORDERING_VARIABLE, ordering), (METHOD_VARIABLE, "direct")];
            let row = measure_in_child_with(0, target, &variables)?;
            let steps = row.steps as f64;
            growth[k].push((row.dofs as f64, row.timings.factorisation / steps));
            let line = format!(
                "| {} | {} | {} | {} | {:.0} | {:.3} | {:.3} | {} |\n",
                row.points,
                row.dofs,
                ordering.replace('_', " "),
                row.factor_entries,
                row.factor_entries as f64 / row.dofs.max(1) as f64,
                row.timings.factorisation / steps,
                row.timings.total / steps,
                row.peak_mib
                    .map_or("n/a".to_string(), |m| format!("{m:.0}")),
            );
            eprint!("{line}");
            text.push_str(&line);
        }
        target *= 10;
    }
    // The exponent p of factorisation time ~ DOFs^p between the ends.
    let exponent = |rows: &[(f64, f64)]| match (rows.first(), rows.last()) {
        (Some(a), Some(b)) if b.0 > a.0 => format!("{:.2}", (b.1 / a.1).ln() / (b.0 / a.0).ln()),
        _ => "n/a".to_string(),
    };
    text.push_str(&format!(
        "\nFactorisation time against DOFs, first to last row: exponent {} with nested dissection, {} with \
         minimum degree (nested dissection's flops grow as n^1.5 on a 2D mesh).\n",
        exponent(&growth[1]),
        exponent(&growth[0])
    ));
    Ok(text)
}

/// Runs one row in a child process (`mpm bench-row`), so that its peak
/// memory is its own.
fn measure_in_child(scene: usize, target: usize) -> Result<Row, LabError> {
    measure_in_child_with(scene, target, &[])
}

/// [`measure_in_child`] with these environment variables set (the fill
/// ordering, the symmetric method).
fn measure_in_child_with(
    scene: usize,
    target: usize,
    variables: &[(&str, &str)],
) -> Result<Row, LabError> {
    let mut command = std::process::Command::new(std::env::current_exe()?);
    command.args(["bench-row", &scene.to_string(), &target.to_string()]);
    command.envs(variables.iter().copied());
    let output = command.output()?;
    if !output.status.success() {
        return Err(LabError::Failed(
            String::from_utf8_lossy(&output.stderr).trim().to_string(),
        ));
    }
    serde_json::from_slice(&output.stdout)
        .map_err(|e| LabError::Failed(format!("bench-row output: {e}")))
}

/// `mpm bench-row SCENE POINTS`: measures one row and prints it as JSON.
pub fn bench_row(scene: usize, target: usize) -> Result<(), LabError> {
    let scene = SCENES
        .get(scene)
        .ok_or_else(|| LabError::Input(format!("no scene {scene}")))?;
    let ordering = match std::env::var(ORDERING_VARIABLE).as_deref() {
        Ok("minimum_degree") => FillOrdering::MinimumDegree,
        Ok("nested_dissection") | Err(_) => FillOrdering::NestedDissection,
        Ok(other) => {
            return Err(LabError::Input(format!(
                "{ORDERING_VARIABLE}={other}: not minimum_degree or nested_dissection"
            )));
        }
    };
    let symmetric = match std::env::var(METHOD_VARIABLE).as_deref() {
        Ok("direct") => Some(SymmetricMethod::Direct),
        Ok("kept_factor_cg") => Some(SymmetricMethod::KeptFactorCg),
        Ok("multigrid") => Some(SymmetricMethod::Multigrid),
        Err(_) => None,
        Ok(other) => {
            return Err(LabError::Input(format!(
                "{METHOD_VARIABLE}={other}: not direct, kept_factor_cg or multigrid"
            )));
        }
    };
    let unsymmetric = match std::env::var(UNSYMMETRIC_VARIABLE).as_deref() {
        Ok("direct") => Some(UnsymmetricMethod::Direct),
        Ok("gmres") => Some(UnsymmetricMethod::SymmetricPartGmres),
        Err(_) => None,
        Ok(other) => {
            return Err(LabError::Input(format!(
                "{UNSYMMETRIC_VARIABLE}={other}: not direct or gmres"
            )));
        }
    };
    let row = measure(
        scene,
        target,
        SolverSettings {
            ordering,
            symmetric,
            unsymmetric,
        },
    )?;
    println!(
        "{}",
        serde_json::to_string(&row).map_err(|e| LabError::Failed(e.to_string()))?
    );
    Ok(())
}

fn measure(scene: &Scene, target: usize, solver: SolverSettings) -> Result<Row, LabError> {
    let text = (scene.build)(target).to_string();
    let failed = |e: mpm::CaseError| LabError::Failed(e.to_string());
    if mpm::case::solid::is_solid(&text) {
        let case = SolidCase::from_json(&text).map_err(failed)?;
        let mut sim = Simulation::from_solid_case(&case).map_err(failed)?;
        let mut row = first_steps(scene, &mut sim, solver)?;
        row.surface_points = sim.faces.iter().map(|f| f.data.len()).sum();
        row.anchors = sim.surface_anchor_count();
        row.surfaces_seconds = median_seconds(5, || {
            for face in &sim.faces {
                std::hint::black_box(Interpolation::new(face.data_grid(&sim.points)));
            }
        });
        return Ok(row);
    }
    let case = Case::from_json(&text).map_err(failed)?;
    first_steps(scene, &mut Simulation::new(&case).map_err(failed)?, solver)
}

/// The median wall time of `repeats` runs of `f`.
fn median_seconds(repeats: usize, mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..repeats.max(1))
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// The first two load steps of `sim` with `solver`, measured.
fn first_steps<const D: usize>(
    scene: &Scene,
    sim: &mut Simulation<D>,
    solver: SolverSettings,
) -> Result<Row, LabError>
where
    Dim<D>: RunSpace<D>,
{
    sim.solver = solver;
    let steps = 2.min(sim.load_steps);
    let mut timings = StepTimings::default();
    let mut iterations = 0;
    let mut dofs = 0;
    let mut memory = StepMemory::default();
    for step in 1..=steps {
        let r = sim
            .load_step(step, &mut NoObserver)
            .map_err(|e| LabError::Failed(format!("{}: {e}", scene.name)))?;
        iterations += r.newton.iterations;
        dofs = r.active_dofs;
        timings += &r.timings;
        memory = r.memory;
    }
    let counts = sim.solve_counts();
    Ok(Row {
        points: sim.points.len(),
        dofs,
        steps,
        iterations,
        timings,
        peak_mib: peak_memory_mib(),
        factor_entries: counts.last_factor_entries,
        analysed_steps: counts.analysed,
        reused_steps: counts.reused,
        memory,
        fresh_factorisations: counts.fresh_factorisations,
        cg_solves: counts.cg_solves,
        cg_iterations: counts.cg_iterations,
        surface_points: 0,
        anchors: 0,
        surfaces_seconds: 0.0,
    })
}

/// Median, min and max wall time of the paper's 896-point cantilever (the
/// built-in `cantilever`), and its size.
fn end_to_end(repeats: usize) -> Result<(f64, f64, f64, usize), LabError> {
    let case = Case::from_json(&example("cantilever").to_string())
        .map_err(|e| LabError::Failed(e.to_string()))?;
    let mut times = Vec::with_capacity(repeats);
    let mut points = 0;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        let mut sim = Simulation::new(&case).map_err(|e| LabError::Failed(e.to_string()))?;
        sim.run(&mut NoObserver)
            .map_err(|e| LabError::Failed(format!("cantilever: {e}")))?;
        times.push(t.elapsed().as_secs_f64());
        points = sim.points.len();
    }
    times.sort_by(f64::total_cmp);
    Ok((
        times[times.len() / 2],
        times[0],
        times[times.len() - 1],
        points,
    ))
}

/// `VmHWM` of this process in MiB (Linux only).
fn peak_memory_mib() -> Option<f64> {
    let status = fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}
