//! Newton-Raphson with the consistent tangent converges quadratically on
//! finite-deformation cases: r_{k+1} <= C r_k^2.

use crate::common::{assert_quadratic_constant, example, run};

/// Quadratic convergence as [`assert_quadratic_constant`] judges it, with
/// `C` = 100 (measured at most 13.6 on the column, 11.9 on the cantilever)
/// above the round-off floor 1e-11 (converged residuals of these cases sit
/// at 1e-13..1e-15, set by the conditioning of K, and say nothing about
/// the rate); and no step takes more than 6 iterations.
fn assert_quadratic(name: &str) {
    let (_, report) = run(&example(name));
    assert_quadratic_constant(&report.steps, name, 100.0, 1e-11);
    for step in &report.steps {
        let r = &step.newton.residuals;
        assert!(step.newton.iterations <= 6, "step {}: {r:?}", step.step);
    }
}

#[test]
fn column_under_self_weight_converges_quadratically() {
    // 52% compression over 40 steps with GIMP: points cross cells.
    assert_quadratic("column");
}

#[test]
fn cantilever_under_self_weight_converges_quadratically() {
    // Large deflection (tip rotation of about 20 degrees) in 5 steps.
    assert_quadratic("cantilever-grid");
}
