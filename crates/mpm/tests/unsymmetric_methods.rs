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
        let (ta, tb) = (
            a.probes[0].displacement.clone(),
            b.probes[0].displacement.clone(),
        );
        let gap = (ta[0] - tb[0]).hypot(ta[1] - tb[1]);
        assert!(gap < 1e-6, "step {}: {ta:?} against {tb:?}", a.step);
    }
    let tip = direct.steps.last().unwrap().probes[0].displacement.clone();
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
        let (ta, tb) = (
            a.probes[0].displacement.clone(),
            b.probes[0].displacement.clone(),
        );
        let gap = (ta[0] - tb[0]).hypot(ta[1] - tb[1]);
        assert!(gap < 1e-6, "step {}: {ta:?} against {tb:?}", a.step);
    }
}

/// By default GMRES on an elastic body's tangent is preconditioned by
/// multigrid from `ELASTIC_GMRES_MULTIGRID_FROM_DOFS` (10,000), where it
/// is faster than the kept factor on GIMP (docs/scale.md), and on a
/// plastic body's by the kept factor, whose symmetric parts multigrid
/// serves badly. The cantilever at 20,480 points (about 11,000 DOFs),
/// elastic, and the same body as von Mises with a yield stress far
/// above any stress it reaches (so the answer is the elastic one): no kept
/// factor made for the first, one for the second, and the tips agree to
/// Newton's tolerance.
#[test]
fn an_elastic_bodys_gmres_takes_multigrid_by_default() {
    let elastic = cantilever(64);
    let mut plastic = mpm::case::builtin::json("cantilever").unwrap();
    plastic["basis"] = "gimp".into();
    plastic["grid"]["cell_size"] = (4.0 / 64.0).into();
    plastic["bodies"][0]["points"] = serde_json::json!({ "count": [320, 64] });
    let material = &mut plastic["bodies"][0]["material"];
    material["model"] = "von_mises".into();
    material["yield_stress"] = 1.0e9.into();
    let plastic = Case::from_json(&plastic.to_string()).unwrap();
    let (a, a_counts) = run_with_settings(&elastic, SolverSettings::default());
    let (b, b_counts) = run_with_settings(&plastic, SolverSettings::default());
    assert!(a.steps[0].active_dofs >= mpm::linsolve::ELASTIC_GMRES_MULTIGRID_FROM_DOFS);
    assert_eq!(a_counts.last_factor_entries, 0, "{a_counts:?}");
    assert!(b_counts.last_factor_entries > 0, "{b_counts:?}");
    for (a, b) in a.steps.iter().zip(&b.steps) {
        assert_eq!(a.newton.factorisation, Some(Factorisation::Gmres));
        assert_eq!(b.newton.factorisation, Some(Factorisation::Gmres));
        let (ta, tb) = (
            a.probes[0].displacement.clone(),
            b.probes[0].displacement.clone(),
        );
        let gap = (ta[0] - tb[0]).hypot(ta[1] - tb[1]);
        assert!(gap < 1e-6, "step {}: {ta:?} against {tb:?}", a.step);
    }
}
