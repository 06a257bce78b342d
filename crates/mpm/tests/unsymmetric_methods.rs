//! Tangents that are not symmetric solved by LU against GMRES
//! preconditioned by the kept Cholesky factor of their symmetric part
//! (`mpm::linsolve::UnsymmetricMethod`): the same answers, to Newton's
//! tolerance.

use mpm::linsolve::{
    Factorisation, SolveCounts, SolverSettings, SymmetricMethod, UnsymmetricMethod,
};
use mpm::{Case, NoObserver, RunReport, Simulation};

/// The paper's cantilever (`mpm example cantilever`: 1500 Pa of follower
/// pressure on its B-spline boundary in 5 steps, to a tip rotation of
/// about 70 degrees) on GIMP with `across` points over its depth, two a
/// cell: the follower pressure's load stiffness makes its tangent
/// unsymmetric.
fn cantilever(across: u32) -> Case {
    let mut case = mpm::case::builtin::json("cantilever").unwrap();
    case["basis"] = "gimp".into();
    case["grid"]["cell_size"] = (4.0 / f64::from(across)).into();
    case["bodies"][0]["points"] = serde_json::json!({ "count": [5 * across, across] });
    Case::from_json(&case.to_string()).unwrap()
}

fn run_with(case: &Case, method: UnsymmetricMethod) -> (RunReport, SolveCounts) {
    run_with_settings(
        case,
        SolverSettings {
            unsymmetric: Some(method),
            ..SolverSettings::default()
        },
    )
}

fn run_with_settings(case: &Case, settings: SolverSettings) -> (RunReport, SolveCounts) {
    let mut sim = Simulation::new(case).unwrap();
    sim.solver = settings;
    let report = sim.run(&mut NoObserver).unwrap();
    (report, sim.solve_counts())
}

/// At 5,120 points (about 3,000 DOFs) GMRES solves every system (no step
/// falls back to LU) and the tip ends where LU puts it, within Newton's
/// tolerance: the relative residual 1e-9 of forces that move the tip by
/// metres leaves it uncertain by far less than 1e-6 m. Newton takes the
/// same iterations: its forcing term keeps the rate quadratic.
#[test]
fn gmres_preconditioned_by_the_symmetric_part_gives_lus_answer() {
    let case = cantilever(32);
    let (direct, direct_counts) = run_with(&case, UnsymmetricMethod::Direct);
    let (gmres, gmres_counts) = run_with(&case, UnsymmetricMethod::SymmetricPartGmres);
    assert_eq!(direct_counts.cg_solves, 0);
    assert!(gmres_counts.cg_solves >= gmres.steps.len());
    for (a, b) in direct.steps.iter().zip(&gmres.steps) {
        assert_eq!(a.newton.factorisation, Some(Factorisation::Lu));
        assert_eq!(b.newton.factorisation, Some(Factorisation::Gmres));
        assert_eq!(a.newton.iterations, b.newton.iterations, "step {}", a.step);
        let (ta, tb) = (a.probes[0].displacement, b.probes[0].displacement);
        let gap = (ta[0] - tb[0]).hypot(ta[1] - tb[1]);
        assert!(gap < 1e-6, "step {}: {ta:?} against {tb:?}", a.step);
    }
    let tip = direct.steps.last().unwrap().probes[0].displacement;
    assert!(tip[1] < -2.0, "the tip came down by metres: {tip:?}");
}

/// The same with GMRES preconditioned by a multigrid V-cycle of the
/// symmetric part (the default from 150,000 DOFs, forced here at 11,520
/// points, about 6,500 DOFs, where the hierarchy has a coarse level):
/// every system solved by it, no kept factor made (the fallback), the
/// same Newton iterations as LU and its tip within Newton's tolerance.
#[test]
fn gmres_preconditioned_by_multigrid_gives_lus_answer() {
    let case = cantilever(48);
    let (direct, _) = run_with(&case, UnsymmetricMethod::Direct);
    let (gmres, counts) = run_with_settings(
        &case,
        SolverSettings {
            unsymmetric: Some(UnsymmetricMethod::SymmetricPartGmres),
            symmetric: Some(SymmetricMethod::Multigrid),
            ..SolverSettings::default()
        },
    );
    assert!(counts.cg_solves >= gmres.steps.len());
    // Hierarchies are counted as factorisations; a kept factor would
    // record its entries.
    assert_eq!(counts.last_factor_entries, 0, "{counts:?}");
    for (a, b) in direct.steps.iter().zip(&gmres.steps) {
        assert_eq!(b.newton.factorisation, Some(Factorisation::Gmres));
        assert_eq!(a.newton.iterations, b.newton.iterations, "step {}", a.step);
        let (ta, tb) = (a.probes[0].displacement, b.probes[0].displacement);
        let gap = (ta[0] - tb[0]).hypot(ta[1] - tb[1]);
        assert!(gap < 1e-6, "step {}: {ta:?} against {tb:?}", a.step);
    }
}
