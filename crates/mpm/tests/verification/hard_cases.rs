//! Hard cases: situations that break naive implicit MPM.

use crate::common::example;
use mpm::{Case, NoObserver, Simulation, SolveError};

/// The grid-supported cantilever at 0.1 m cells in 400 load steps: at step
/// 34 the tip's top corner point crosses into an empty cell column, and the
/// two new nodes there are reached by that point alone. Their displacement
/// modes have (almost) no stiffness; without the soft background the linear
/// solve returns metres of garbage along them and Newton stalls ("did not
/// converge in load step 34").
fn tip_corner_crossing(regularisation: f64) -> Result<(), SolveError> {
    let mut case = example("cantilever-grid");
    case["grid"]["cell_size"] = 0.1.into();
    case["analysis"]["load_steps"] = 400.into();
    case["analysis"]["newton"] = serde_json::json!({"tangent_regularisation": regularisation});
    let case = Case::from_json(&case.to_string()).unwrap();
    let mut sim = Simulation::new(&case).unwrap();
    for step in 1..=40 {
        sim.load_step(step, &mut NoObserver)?;
    }
    Ok(())
}

#[test]
fn a_point_alone_in_a_new_cell_does_not_stall_newton() {
    tip_corner_crossing(1e-6).expect("converges with the default soft background");
}

#[test]
fn without_the_soft_background_the_same_case_stalls_at_the_crossing() {
    // Shows that the case above exercises the problem: plain Newton stalls
    // when the corner point crosses (step 34 or 35, depending on round-off
    // in the earlier steps).
    match tip_corner_crossing(0.0) {
        Err(SolveError::NotConverged { step, .. }) if (30..=40).contains(&step) => {}
        other => panic!("expected the stall at the crossing, got {other:?}"),
    }
}
