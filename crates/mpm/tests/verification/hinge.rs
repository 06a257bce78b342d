//! The plastic hinge: a von Mises beam (plane strain, `k = sigma_y /
//! sqrt 3`) of depth d bent to collapse, against the plastic moment `M_p =
//! k d^2 / 2` per unit width (the section fully plastic at `sigma_xx =
//! +-2 k`, with `sigma_zz = sigma_xx / 2` from the isochoric flow; Hill
//! 1950, The mathematical theory of plasticity, ch. IV).
//!
//! The beams: d = 1 m, E = 100 MPa, nu = 0.3, k = 10 kPa, GIMP, 2 x 2
//! points a cell, h = d/8, F-bar; the grid's origin at `-offset h` in both
//! directions.

use serde_json::json;

use crate::common::run;

const K: f64 = 1.0e4;
const DEPTH: f64 = 1.0;
const CELLS_OVER_DEPTH: f64 = 8.0;

/// `M_p = k d^2 / 2`.
fn plastic_moment() -> f64 {
    K * DEPTH * DEPTH / 2.0
}

/// A beam from x = 0 to `length`, with `supports`, pushed in `steps`,
/// seeded `per_cell` points a cell each way.
fn beam(
    length: f64,
    offset: f64,
    fbar: bool,
    steps: u32,
    supports: serde_json::Value,
    per_cell: u32,
) -> serde_json::Value {
    let h = DEPTH / CELLS_OVER_DEPTH;
    json!({
        "version": 1,
        "analysis": { "load_steps": steps, "volumetric": if fbar { "fbar" } else { "standard" } },
        "grid": { "cell_size": h, "origin": [-offset * h, -offset * h] },
        "basis": "gimp",
        "bodies": [{
            "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [length, DEPTH] } },
            "points": { "per_cell": per_cell },
            "material": { "model": "von_mises", "youngs_modulus": 1.0e8, "poisson_ratio": 0.3,
                          "density": 0.0, "yield_stress": 3f64.sqrt() * K }
        }],
        "supports": supports,
        "probes": [{ "name": "tip", "at": [length, DEPTH / 2.0] }]
    })
}

/// Half of a beam 4 d long in pure bending: the symmetry plane x = 0 on a
/// roller, the end x = 2 d turned 1 degree about its middle in 20 steps
/// by the implicit boundary method (held in both directions, as a
/// rotation must be). The moment is uniform along the beam, so the
/// sections away from the held end carry the exact fully plastic state
/// (no clamp constrains them). Returns each step's moment over `M_p`, from
/// the end's contact tractions.
pub fn pure_bending(offset: f64, fbar: bool, per_cell: u32) -> Vec<f64> {
    let half = 2.0 * DEPTH;
    let supports = json!([
        { "on": { "x": 0.0 }, "fix": "x", "method": "ibm" },
        { "on": { "x": half }, "fix": "xy", "method": "ibm",
          "rotation": { "angle": -1.0, "center": [half, DEPTH / 2.0] } }
    ]);
    let (_, report) = run(&beam(half, offset, fbar, 20, supports, per_cell));
    report
        .steps
        .iter()
        .map(|s| {
            let moment: f64 = (s.support_tractions.iter())
                .filter(|t| t.support == 1)
                .map(|t| t.traction[0] * (t.at[1] - DEPTH / 2.0) * t.length)
                .sum();
            moment / plastic_moment()
        })
        .collect()
}

/// Bent 1 degree over 2 d (the curvature 20 times the first yield's,
/// where the elastic core leaves 1 - M / M_p = 1e-3), the moment comes to
/// M_p within 1% and stays flat: measured at the two placements 0.9940
/// and 0.9998 at the end, moving by 0.23% and 0.12% over the second half
/// (with F-bar's earlier, unsymmetric form: 0.9939 and 1.0006, and 0.9985
/// at d/16). The tolerance is the d/8 cells' error with room for
/// the placement. Without F-bar the cells lock at offset 0.3 and the
/// moment climbs past M_p (1.038 at the end, still rising), which fails
/// this test; at offset 0.65 the same cells happen not to lock (1.0008).
#[test]
fn a_beam_in_pure_bending_carries_the_plastic_moment_and_no_more() {
    for offset in [0.3, 0.65] {
        let moments = pure_bending(offset, true, 2);
        eprintln!("pure bending, offset {offset}: M / M_p {moments:.4?}");
        let last = *moments.last().expect("steps");
        assert!((last - 1.0).abs() < 0.01, "offset {offset}: {last}");
        let second_half = &moments[moments.len() / 2..];
        let (lo, hi) = second_half
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), &m| (l.min(m), h.max(m)));
        assert!(hi - lo < 0.005, "offset {offset}: not flat, {lo}..{hi}");
    }
}

/// A cantilever of length `L` clamped at x = 0 (the IBM, both directions)
/// and pushed down at its tip face by `0.01 L` in 20 steps (held in y
/// only): the tip load over beam theory's `M_p / L` at the last step.
fn cantilever(length: f64) -> f64 {
    let push = 0.01 * length;
    let supports = json!([
        { "on": { "x": 0.0 }, "fix": "xy", "method": "ibm" },
        { "on": { "x": length }, "fix": "y", "method": "ibm", "displacement": [0.0, -push] }
    ]);
    let (_, report) = run(&beam(length, 0.3, true, 20, supports, 2));
    let last = report.steps.last().expect("steps");
    last.reactions[1][1].abs() / (plastic_moment() / length)
}

/// Beam theory's collapse load `P = M_p / L = k d^2 / (2 L)` is the slender
/// limit. A clamp holds the root section's width (`eps_yy = 0` at the
/// wall, so with isochoric flow `eps_xx = 0` there): the hinge forms a
/// fraction of d out from the wall, and the load exceeds `M_p / L` by
/// about `c d / L`. Measured: `P L / M_p` = 1.0687 at L = 10 d and 1.0367
/// at L = 20 d (`c` = 0.69 and 0.73; d/16 at L = 10 d and 0.02 L, with
/// F-bar's earlier form: 1.067), the excess nearly halving with `d / L`.
/// Extrapolated in `d / L` to the slender limit (Richardson, first
/// order): 1.0047. The tolerance, 2%, is the issue's
/// for the hinge: the d/8 cells' error in pure bending (0.6%) and the
/// second-order remainder of the extrapolation.
#[test]
fn a_clamped_cantilever_tends_to_beam_theorys_collapse_load_as_it_gets_slender() {
    let ten = cantilever(10.0 * DEPTH);
    let twenty = cantilever(20.0 * DEPTH);
    let slender = 2.0 * twenty - ten;
    eprintln!("P L / M_p: L = 10 d {ten:.4}, L = 20 d {twenty:.4}, extrapolated {slender:.4}");
    assert!(ten > twenty && twenty > 1.0, "{ten} {twenty}");
    let halving = (ten - 1.0) / (twenty - 1.0);
    assert!(
        (1.6..2.4).contains(&halving),
        "the excess scales as {halving}"
    );
    assert!((slender - 1.0).abs() < 0.02, "{slender}");
}
