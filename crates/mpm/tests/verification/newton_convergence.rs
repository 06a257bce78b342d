//! Newton-Raphson with the consistent tangent converges quadratically on
//! finite-deformation cases: once the relative residual r_k is small,
//! r_{k+1} ~ C r_k^p with p = 2.

use crate::common::{example, run};
use mpm::newton::observed_order;

/// Estimates the order p from three successive residuals
/// (`mpm::newton::observed_order`) wherever they lie in the asymptotic
/// range (r_{k-1} below 5e-2 and falling) and above the round-off floor (r_{k+1} above
/// 1e-11: converged residuals of these cases sit at 1e-13..1e-15, set by the
/// conditioning of K, and say nothing about the rate).
fn assert_quadratic(case: &serde_json::Value) {
    let (_, report) = run(case);
    let mut checked = 0;
    for step in &report.steps {
        let r = &step.newton.residuals;
        for w in r.windows(3) {
            if w[0] < 5e-2 && w[1] < w[0] && w[2] > 1e-11 {
                let order = observed_order([w[0], w[1], w[2]]);
                assert!(
                    order > 1.8,
                    "step {}: residuals {r:?} (order {order:.2})",
                    step.step
                );
                checked += 1;
            }
        }
        assert!(step.newton.iterations <= 6, "step {}: {r:?}", step.step);
    }
    assert!(
        2 * checked >= report.steps.len(),
        "too few iterations in the asymptotic range to judge ({checked})"
    );
}

#[test]
fn column_under_self_weight_converges_quadratically() {
    // 52% compression over 40 steps with GIMP: points cross cells.
    assert_quadratic(&example("column"));
}

#[test]
fn cantilever_under_self_weight_converges_quadratically() {
    // Large deflection (tip rotation of about 20 degrees) in 5 steps.
    assert_quadratic(&example("cantilever-grid"));
}
