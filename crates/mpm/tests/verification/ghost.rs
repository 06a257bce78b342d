//! Ghost stabilisation (`analysis.stabilisation.ghost_penalty`): the answer must
//! not depend on how many load steps reach it, nor on the penalty's value.
//!
//! For a hyperelastic body under loads that depend only on the final load
//! level the exact answer is the same in 1 or 100 steps. With the soft
//! background alone (the default before the penalty) it is not: nodes that
//! only a sliver of
//! material reaches move spuriously, and the points write that motion
//! into their deformation as they cross cells, more with every step.

use crate::common::{example, run};

/// `cantilever-grid` (self-weight, clamped on grid nodes) at 0.25 m cells,
/// GIMP: the tip's deflection.
fn tip(steps: u32, ghost: f64, soft: f64) -> f64 {
    let mut case = example("cantilever-grid");
    case["grid"]["cell_size"] = 0.25.into();
    case["basis"] = "gimp".into();
    case["analysis"]["load_steps"] = steps.into();
    case["analysis"]["stabilisation"] =
        serde_json::json!({"ghost_penalty": ghost, "tangent_regularisation": soft});
    let (_, report) = run(&case);
    report.steps.last().unwrap().probes[0].displacement[1]
}

/// Measured tip deflections (m), 5 and 100 steps: soft background 1e-6,
/// -2.6299 and -2.7396 (4.2% apart); the default ghost penalty 1e-3
/// without the soft background, -2.6209 and -2.6232 (0.09% apart; 1e-2:
/// -2.6201 and -2.6220). The target is 0.5%.
#[test]
fn the_ghost_penalty_removes_the_drift_with_the_number_of_steps() {
    let drift = |ghost: f64, soft: f64| {
        let (five, hundred) = (tip(5, ghost, soft), tip(100, ghost, soft));
        ((hundred - five) / five).abs()
    };
    let soft = drift(0.0, 1e-6);
    let ghost = drift(1e-3, 0.0);
    assert!(soft > 2e-2, "the soft background's drift: {soft}");
    assert!(ghost < 5e-3, "the ghost penalty's drift: {ghost}");
}

/// Over three decades of the penalty (1e-5 to 1e-2) the 5-step deflection
/// moves by 0.09% (measured: -2.6224, -2.6215, -2.6209, -2.6201; 1e-1
/// gives -2.6179); the target is 0.1%. At 100 steps the drift is
/// 0.07% at 1e-2, 0.09% at 1e-3, 0.64% at 1e-4 and 3.7% at 1e-5: below
/// 1e-3 the sliver nodes are held too weakly again.
#[test]
fn the_answer_does_not_hang_on_the_penalty() {
    let tips: Vec<f64> = [1e-5, 1e-4, 1e-3, 1e-2]
        .into_iter()
        .map(|g| tip(5, g, 0.0))
        .collect();
    let (lo, hi) = tips
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), &t| (lo.min(t), hi.max(t)));
    assert!((hi - lo) / hi.abs() < 1e-3, "{tips:?}");
}

/// AMPLE's column (52% compression, GIMP, one cell wide: every cell is at
/// the edge) in 400 load steps, against the exact -25.940 m (column.rs):
/// -25.661 with the soft background (1.1% off), -25.855 with the default
/// ghost penalty 1e-3 (0.33%; -25.886 in 40 steps), -25.888 at 1e-2
/// (0.20%). The target is 0.5%.
#[test]
fn the_column_in_400_steps_stays_on_the_exact_answer() {
    let mut case = example("column");
    case["analysis"]["load_steps"] = 400.into();
    let (_, report) = run(&case);
    let top = report.steps.last().unwrap().probes[0].displacement[1];
    let exact = -25.940;
    assert!(((top - exact) / exact).abs() < 5e-3, "{top}");
}

/// The paper's cantilever (follower pressure, IBM rollers and pin) with
/// GIMP at 0.25 m cells, 2 points per cell: tip u_x in 1 / 5 / 20 / 100
/// steps, measured: soft background -0.4250 / -0.4263 / -0.4296 / -0.4422
/// (100 steps 3.7% from 5); the default ghost penalty 1e-3 -0.4249 /
/// -0.4255 / -0.4259 / -0.4263 (0.19%); 1e-2 -0.4245 / -0.4253 / -0.4257 /
/// -0.4259 (0.14%). The converged reference quoted with the issue is
/// -0.4227.
#[test]
fn the_papers_cantilever_keeps_its_answer_over_100_steps() {
    let tip_ux = |steps: u32| {
        let mut case = example("cantilever");
        case["grid"]["cell_size"] = 0.25.into();
        case["basis"] = "gimp".into();
        case["bodies"][0]["points"] = serde_json::json!({"per_cell": 2});
        case["analysis"]["load_steps"] = steps.into();
        let (_, report) = run(&case);
        report.steps.last().unwrap().probes[0].displacement[0]
    };
    let (five, hundred) = (tip_ux(5), tip_ux(100));
    assert!(
        ((hundred - five) / five).abs() < 5e-3,
        "{five} vs {hundred}"
    );
}
