//! Elasto-plastic bodies against answers worked by hand.

use mpm::newton::observed_order;
use serde_json::json;

use crate::common::run;

/// A unit block of von Mises material (E = 1 MPa, nu = 0.3, sigma_y =
/// 1 kPa, perfectly plastic) squeezed by 10% of its height in 10 steps
/// between IBM rollers on x = 0 and y = 0 and an IBM prescribed displacement
/// on its top, its right side free, on a grid cut at (0.1, 0.07) cells.
///
/// Exact, by hand: the state is homogeneous with principal axes x, y, z,
/// `sigma_xx = 0` (free side) and `eps_zz = 0` (plane strain). Once it
/// flows, the plastic strain rate's zz part must vanish, so the deviator's
/// zz part does: `tau_zz = (tau_xx + tau_yy) / 2 = tau_yy / 2`, and on the
/// surface `q = (sqrt(3) / 2) |tau_yy| = sigma_y`: `tau_yy = -2 sigma_y /
/// sqrt(3)`, the plane-strain strength `2k`. The state approaches this
/// exponentially over plastic strains of a few `sigma_y / E` (1e-3), so
/// after 10% it is there to round-off. The Cauchy stress divides by
/// `J = exp(tr e)`, with the elastic volume strain `tr e = tau_m / kappa`,
/// `tau_m = tau_yy / 2`. Newton converges quadratically in every step
/// (the consistent tangent of the return map): order above 1.8 from the
/// last three residuals.
#[test]
fn a_block_squeezed_past_yield_flows_at_the_plane_strain_strength() {
    let (e, nu, sigma_y) = (1.0e6, 0.3, 1.0e3);
    let case = json!({
        "version": 1,
        "analysis": { "load_steps": 10 },
        "grid": { "cell_size": 0.25, "origin": [0.1, 0.07] },
        "basis": "gimp",
        "bodies": [{
            "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [1.0, 1.0] } },
            "points": { "count": [8, 8] },
            "material": { "model": "von_mises", "youngs_modulus": e, "poisson_ratio": nu,
                          "density": 0.0, "yield_stress": sigma_y }
        }],
        "supports": [
            { "on": { "x": 0.0 }, "fix": "normal", "method": "ibm" },
            { "on": { "y": 0.0 }, "fix": "normal", "method": "ibm" },
            { "on": { "y": 1.0 }, "fix": "y", "method": "ibm", "displacement": [0.0, -0.1] }
        ]
    });
    let (sim, report) = run(&case);
    let kappa = e / (3.0 * (1.0 - 2.0 * nu));
    let tau_yy = -2.0 * sigma_y / 3f64.sqrt();
    let j = (tau_yy / 2.0 / kappa).exp();
    let (syy, szz) = (tau_yy / j, tau_yy / 2.0 / j);
    let mut worst = 0.0f64;
    for (s, h) in sim.points.stress.iter().zip(&sim.points.history) {
        let off = [s.plane[0], s.plane[1] - syy, s.plane[2], s.zz - szz];
        worst = off.iter().fold(worst, |w, x| w.max(x.abs()));
        assert!(h.plastic_strain > 0.09, "{}", h.plastic_strain);
    }
    eprintln!(
        "worst stress off the exact state: {:.2e} of sigma_y",
        worst / sigma_y
    );
    assert!(worst < 1e-3 * sigma_y, "{worst:e}");
    assert!(sim.points.yielding.iter().all(|&y| y));
    for s in &report.steps {
        let r = &s.newton.residuals;
        let n = r.len();
        let order = observed_order([r[n - 3], r[n - 2], r[n - 1]]);
        eprintln!("step {}: residuals {r:?}, order {order:.2}", s.step);
        assert!(order > 1.8, "step {}: {r:?}", s.step);
    }
}
