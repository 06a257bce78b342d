//! CG preconditioned by a kept factor, and by multigrid, answers as
//! factorising every tangent does, through a whole large-deformation run.
//! Each run chooses its method ([`mpm::linsolve::SolverSettings`]) and
//! counts its own solves, so the tests run side by side.

use mpm::case::solid::SolidCase;
use mpm::linsolve::{Factorisation, SolveCounts, SolverSettings, SymmetricMethod};
use mpm::particles::MaterialPoints;
use mpm::{Case, NoObserver, RunReport, Simulation};

/// `case` run to the end with its symmetric tangents solved by `method`,
/// and its solvers' counts.
fn run_with(case: &Case, method: SymmetricMethod) -> (RunReport, SolveCounts) {
    let mut sim = Simulation::new(case).unwrap();
    sim.solver = SolverSettings {
        symmetric: Some(method),
        ..SolverSettings::default()
    };
    let report = sim.run(&mut NoObserver).unwrap();
    (report, sim.solve_counts())
}

/// AMPLE's self-weight column (`verification/column.rs`: 52% compression
/// in 40 steps, top displacement -25.940 m exactly) with `high` cells over
/// the height and `high / 8` across (GIMP, 2x2 points a cell).
fn column(high: u32) -> Case {
    let mut case = mpm::case::builtin::json("column").unwrap();
    let h = 50.0 / f64::from(high);
    let width = f64::from(high / 8) * h;
    case["grid"]["cell_size"] = h.into();
    case["grid"]["extent"]["max"] = serde_json::json!([width, 50.0]);
    case["bodies"][0]["geometry"]["rectangle"]["max"] = serde_json::json!([width, 50.0]);
    case["supports"][1]["on"]["x"] = width.into();
    case["probes"][0]["at"] = serde_json::json!([width / 2.0, 50.0]);
    Case::from_json(&case.to_string()).unwrap()
}

/// The top displacement of the column solved with `method`, Newton's
/// iterations in each step, what solved each step's last system, the
/// first step's active DOFs, and the run's solve counts.
fn run_column(
    case: &Case,
    method: SymmetricMethod,
) -> (
    f64,
    Vec<usize>,
    Vec<Option<Factorisation>>,
    usize,
    SolveCounts,
) {
    let (report, counts) = run_with(case, method);
    let iterations = report.steps.iter().map(|s| s.newton.iterations).collect();
    let solvers = report
        .steps
        .iter()
        .map(|s| s.newton.factorisation)
        .collect();
    let top = report.steps.last().unwrap().probes[0].displacement[1];
    (
        top,
        iterations,
        solvers,
        report.steps[0].active_dofs,
        counts,
    )
}

/// The column with 64 cells over the height (1,170 DOFs), run with each
/// method. The points cross cells in most steps (new patterns) and keep
/// their cells in some (the last step's analysis taken over; each step
/// makes its own factor). Newton takes the same iterations in every step, and the answers
/// agree to 1e-9 of the top displacement (they differ by 3e-11 m): CG
/// stops at the accuracy Newton's forcing term asks for, and each step
/// ends, either way, with an out-of-balance force within Newton's
/// tolerance (1e-9 of the force scale).
#[test]
fn a_kept_factor_solves_the_column_as_direct_factorisation_does() {
    let case = column(64);
    let (direct_top, direct_iterations, _, _, _) = run_column(&case, SymmetricMethod::Direct);
    let (kept_top, kept_iterations, _, _, counts) =
        run_column(&case, SymmetricMethod::KeptFactorCg);
    let (factorisations, cg_solves) = (counts.fresh_factorisations, counts.cg_solves);
    eprintln!(
        "direct {direct_top}, kept {kept_top}; {factorisations} factorisations, {cg_solves} CG solves"
    );
    assert_eq!(kept_iterations, direct_iterations);
    assert!((kept_top - direct_top).abs() < 1e-9 * direct_top.abs());
    // The exact top displacement, within the discretisation's error at 64
    // cells over the height (0.01%; `verification/column.rs` shows its
    // convergence).
    assert!((direct_top + 25.940).abs() < 1e-3 * 25.940, "{direct_top}");
    // Most solves reuse a factor.
    assert!(
        cg_solves > 2 * factorisations,
        "{factorisations} {cg_solves}"
    );
}

/// A block of Mohr-Coulomb soil with non-associated flow (friction 20,
/// dilation 5 degrees) squeezed 5% past yield in 5 steps, with the kept
/// factor forced on: its tangent is unsymmetric, so no step may try a
/// Cholesky factor (CG on an unsymmetric matrix, or a factor of its upper
/// triangle) and every one is solved by LU.
#[test]
fn an_unsymmetric_tangent_never_meets_the_kept_factor() {
    let case = serde_json::json!({
        "version": 1,
        "analysis": { "load_steps": 5 },
        "grid": { "cell_size": 0.25, "origin": [0.1, 0.07] },
        "basis": "gimp",
        "bodies": [{
            "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [1.0, 1.0] } },
            "points": { "count": [8, 8] },
            "material": { "model": "mohr_coulomb", "youngs_modulus": 1.0e6, "poisson_ratio": 0.3,
                          "density": 0.0, "cohesion": 1.0e3, "friction_angle": 20.0,
                          "dilation_angle": 5.0 }
        }],
        "supports": [
            { "on": { "x": 0.0 }, "fix": "normal", "method": "ibm" },
            { "on": { "y": 0.0 }, "fix": "normal", "method": "ibm" },
            { "on": { "y": 1.0 }, "fix": "y", "method": "ibm", "displacement": [0.0, -0.05] }
        ]
    });
    let case = Case::from_json(&case.to_string()).unwrap();
    let (report, counts) = run_with(&case, SymmetricMethod::KeptFactorCg);
    assert_eq!(
        (counts.fresh_factorisations, counts.cg_solves),
        (0, 0),
        "symmetric solves were tried"
    );
    for step in &report.steps {
        assert_eq!(step.newton.factorisation, Some(Factorisation::Lu));
    }
}

/// The column with 128 cells over the height (4,096 DOFs, more than the
/// multigrid's dense level takes, so the hierarchy has a coarse level
/// below the finest), by multigrid and by factorising every tangent. Newton takes
/// the same iterations in every step and the answers agree to 1e-9 of the
/// top displacement (they differ by 1e-11 m), as the kept factor's do
/// above; every step's last system was multigrid's (none fell back to a
/// factor).
#[test]
fn multigrid_solves_the_column_as_direct_factorisation_does() {
    let case = column(128);
    let (direct_top, direct_iterations, _, dofs, _) = run_column(&case, SymmetricMethod::Direct);
    let (multigrid_top, multigrid_iterations, solvers, _, _) =
        run_column(&case, SymmetricMethod::Multigrid);
    eprintln!("{dofs} DOFs: direct {direct_top}, multigrid {multigrid_top}");
    assert!(dofs > 3000, "{dofs} DOFs: no coarse level below the finest");
    let multigrid = Some(Factorisation::Multigrid);
    assert!(solvers.iter().all(|s| *s == multigrid), "{solvers:?}");
    assert_eq!(multigrid_iterations, direct_iterations);
    assert!((multigrid_top - direct_top).abs() < 1e-9 * direct_top.abs());
    // The exact top displacement, within the discretisation's error.
    assert!((direct_top + 25.940).abs() < 1e-3 * 25.940, "{direct_top}");
}

/// The 3D column (`cases/column3d.json`, AMPLE's column as a prism on
/// rollers) with `high` cells over the height and `high / 8` across both
/// ways, in two load steps, its symmetric tangents solved by `method` (the
/// default's choice when `None`): its points and report.
fn column_3d(high: u32, method: Option<SymmetricMethod>) -> (MaterialPoints<3>, RunReport) {
    let mut case: serde_json::Value =
        serde_json::from_str(include_str!("../cases/column3d.json")).unwrap();
    let h = 50.0 / f64::from(high);
    let width = f64::from(high / 8) * h;
    case["analysis"]["load_steps"] = 2.into();
    case["grid"]["cell_size"] = h.into();
    case["grid"]["extent"]["max"] = serde_json::json!([width, width, 50.0]);
    case["bodies"][0]["geometry"]["box"]["max"] = serde_json::json!([width, width, 50.0]);
    case["supports"][1]["on"]["x"] = width.into();
    case["supports"][3]["on"]["y"] = width.into();
    let case = SolidCase::from_json(&case.to_string()).unwrap();
    let mut sim = Simulation::from_solid_case(&case).unwrap();
    sim.solver = SolverSettings {
        symmetric: method,
        ..SolverSettings::default()
    };
    let report = sim.run(&mut NoObserver).unwrap();
    (sim.points, report)
}

/// In 3D the multigrid aggregates 3 x 3 x 3 blocks of nodes with six rigid
/// body modes (`multigrid.rs`), and is the default from
/// `SOLID_MULTIGRID_FROM_DOFS` (20,000). The 3D column with 80 cells over
/// the height and 10 across (64,000 points, 52% compression in two steps;
/// 25,520 active DOFs in the first step, 15,631 in the second, which the
/// kept factor solves): the default takes the method of each step's size,
/// in the iterations of factorising every tangent, and the
/// points end where the direct solve puts them to 1e-9 of the top's
/// displacement (CG stops at Newton's forcing term). The answer is the
/// column's: the base carries the weight, and sigma_zz = -rho0 g (L - Z)
/// within the discretisation's error (the normalised error of
/// `verification/column3d.rs`, 2.4e-3 here).
#[test]
fn multigrid_solves_the_3d_column_as_direct_factorisation_does() {
    let (direct, direct_report) = column_3d(80, Some(SymmetricMethod::Direct));
    let (multigrid, report) = column_3d(80, None);
    let dofs = report.steps[0].active_dofs;
    assert!(dofs >= mpm::linsolve::SOLID_MULTIGRID_FROM_DOFS, "{dofs}");
    for (step, direct_step) in report.steps.iter().zip(&direct_report.steps) {
        let default = if step.active_dofs >= mpm::linsolve::SOLID_MULTIGRID_FROM_DOFS {
            Factorisation::Multigrid
        } else {
            // The kept factor's CG.
            Factorisation::Cholesky
        };
        assert_eq!(step.newton.factorisation, Some(default), "{}", step.step);
        assert_eq!(step.newton.iterations, direct_step.newton.iterations);
    }
    let moved = direct
        .position
        .iter()
        .zip(&multigrid.position)
        .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    eprintln!("{dofs} DOFs: largest difference in position {moved:e} m");
    assert!(moved < 1e-9 * 25.940, "{moved}");
    let (rho_g, length) = (80.0 * 10.0, 50.0);
    let volume: f64 = multigrid.volume0.iter().sum();
    let error = (0..multigrid.len())
        .map(|p| {
            let exact = -rho_g * (length - multigrid.reference[p][2]);
            (multigrid.stress[p][(2, 2)] - exact).abs() * multigrid.volume0[p]
        })
        .sum::<f64>()
        / (rho_g * length * volume);
    eprintln!("normalised stress error {error:e}");
    assert!(error < 5e-3, "{error}");
}
