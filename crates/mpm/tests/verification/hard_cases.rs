//! Hard cases: situations that break naive implicit MPM.

use crate::common::example;
use mpm::{Case, NoObserver, Simulation, SolveError};

/// The grid-supported cantilever at 0.1 m cells in 400 load steps: at step
/// 34 the tip's top corner point crosses into an empty cell column, and the
/// two new nodes there are reached by that point alone. Their displacement
/// modes have (almost) no stiffness; without the soft background or the
/// ghost penalty the linear solve returns metres of garbage along them and
/// Newton stalls ("did not converge in load step 34").
///
/// Plain Newton here: no line search and no cutting of the step, which
/// would hide the stall behind 40 cut-backs.
fn tip_corner_crossing(regularisation: f64, ghost: f64) -> Result<(), SolveError> {
    let mut case = example("cantilever-grid");
    case["grid"]["cell_size"] = 0.1.into();
    case["analysis"]["load_steps"] = 400.into();
    case["analysis"]["newton"] = serde_json::json!({ "line_search": false });
    case["analysis"]["stabilisation"] = serde_json::json!({
        "tangent_regularisation": regularisation, "ghost_penalty": ghost
    });
    case["analysis"]["substepping"] = serde_json::json!({"min_fraction": 1.0});
    let case = Case::from_json(&case.to_string()).unwrap();
    let mut sim = Simulation::new(&case).unwrap();
    for step in 1..=40 {
        sim.load_step(step, &mut NoObserver)?;
    }
    Ok(())
}

#[test]
fn a_point_alone_in_a_new_cell_does_not_stall_newton() {
    tip_corner_crossing(0.0, 1e-3).expect("converges with the default ghost penalty");
    tip_corner_crossing(1e-6, 0.0).expect("converges with the soft background (the fallback)");
}

#[test]
fn without_stabilisation_the_same_case_stalls_at_the_crossing() {
    // Shows that the case above exercises the problem: plain Newton with
    // neither the ghost penalty nor the soft background fails when the
    // corner point crosses (step 34 or 35, depending on round-off in the
    // earlier steps): it stalls, or its garbage correction explodes the
    // point (J = 11.5 at step 34 since the points keep `b - I`).
    match tip_corner_crossing(0.0, 0.0) {
        Err(SolveError::NotConverged { step, .. } | SolveError::Inadmissible { step, .. })
            if (30..=40).contains(&step) => {}
        other => panic!("expected the stall at the crossing, got {other:?}"),
    }
}

/// AMPLE's self-weight column (52% compression, 16 cells, GIMP) in one load
/// step. A full Newton step from the undeformed state overshoots: the first
/// correction inverts the top point ("material point 0 inverted (J =
/// -2.875)"). The line search halves that step and Newton converges; the
/// answer is the exact one (the quadrature of the exact stretch, -25.940 m,
/// see column.rs) to within the discretisation error of this grid (0.12%
/// in one step, 0.21% in 40 steps: measured).
#[test]
fn the_column_in_one_load_step_reaches_the_exact_answer() {
    let top = |steps: u32, line_search: bool| {
        let mut case = example("column");
        case["analysis"]["load_steps"] = steps.into();
        case["analysis"]["newton"] = serde_json::json!({"line_search": line_search});
        case["analysis"]["substepping"] = serde_json::json!({"min_fraction": 1.0});
        let case = Case::from_json(&case.to_string()).unwrap();
        let mut sim = Simulation::new(&case).unwrap();
        sim.run(&mut NoObserver)
            .map(|r| r.steps.last().unwrap().probes[0].displacement[1])
    };
    match top(1, false) {
        Err(SolveError::Inadmissible { step: 1, .. }) => {}
        other => panic!("plain Newton should invert a point, got {other:?}"),
    }
    let exact = -25.940;
    let one = top(1, true).expect("one step converges with the line search");
    let many = top(40, true).unwrap();
    for (steps, u) in [(1, one), (40, many)] {
        assert!(
            ((u - exact) / exact).abs() < 5e-3,
            "{steps} steps: {u} vs {exact}"
        );
    }
}

/// The paper's cantilever with the `points` boundary representation in one
/// load step inverted a point; with the line search and load-step cutting
/// it finishes, within 3% of the 5-step answer in tip deflection (measured
/// -2.005 m against -2.063 m: on this 1.5 m grid, under two cells through
/// the depth, every cell is at the edge and the ghost penalty's bias on
/// each increment is largest; see ghost.rs).
#[test]
fn the_papers_cantilever_in_one_load_step_finishes() {
    let tip = |steps: u32| {
        let mut case = example("cantilever");
        case["analysis"]["load_steps"] = steps.into();
        case["boundary"] = serde_json::json!({"representation": "points"});
        let case = Case::from_json(&case.to_string()).unwrap();
        let mut sim = Simulation::new(&case).unwrap();
        let report = sim.run(&mut NoObserver).expect("finishes");
        report.steps.last().unwrap().probes[0].displacement.clone()
    };
    let (one, five) = (tip(1), tip(5));
    assert!(
        ((one[1] - five[1]) / five[1]).abs() < 0.03,
        "{one:?} vs {five:?}"
    );
}

/// Load-step cutting, made to happen: the column in one step with Newton
/// allowed 3 iterations fails the whole increment, which is cut until the
/// pieces converge, and the step reports them; the answer is still the
/// exact one to the grid's error (as in the test above), and the failed
/// tries' time is in the step's. With cutting bounded at half the
/// increment it fails, naming the load factor reached.
#[test]
fn a_failed_increment_is_cut_and_the_step_reports_its_pieces() {
    let case_with = |steps: u32, max_iterations: u32, min_fraction: f64| {
        let mut case = example("column");
        case["analysis"]["load_steps"] = steps.into();
        // The ghost penalty (default) keeps the answer independent of the
        // pieces' number (with the soft background instead, many pieces
        // drift as many load steps do: see ghost.rs).
        case["analysis"]["newton"] = serde_json::json!({ "max_iterations": max_iterations });
        case["analysis"]["substepping"] = serde_json::json!({"min_fraction": min_fraction});
        Simulation::new(&Case::from_json(&case.to_string()).unwrap()).unwrap()
    };
    let report = case_with(1, 3, 1.0 / 1024.0)
        .run(&mut NoObserver)
        .expect("cut increments converge");
    let step = &report.steps[0];
    assert!(step.substeps > 1 && step.cutbacks >= 1, "{step:?}");
    assert_eq!(step.load_factor, 1.0);
    // The failed tries' time is in the step's, and its stages add up to it.
    let t = &step.timings;
    let stages = t.grid + t.point_loop + t.assembly + t.factorisation + t.solve;
    let stages = stages + t.update + t.newton + t.failed;
    assert!(t.failed > 0.0, "{t:?}");
    assert!((stages - t.total).abs() <= 1e-9 * t.total, "{t:?}");
    assert_eq!(
        step.newton.step_lengths.len(),
        step.newton.iterations,
        "one step length per solve"
    );
    let top = step.probes[0].displacement[1];
    let exact = -25.940;
    assert!(((top - exact) / exact).abs() < 5e-3, "{top}");

    match case_with(1, 3, 0.5).run(&mut NoObserver) {
        Err(SolveError::SubstepsExhausted {
            step: 1,
            load_factor,
            cause,
            ..
        }) => {
            assert!((0.0..1.0).contains(&load_factor), "{load_factor}");
            assert!(matches!(*cause, SolveError::NotConverged { .. }), "{cause}");
        }
        other => panic!("expected the cut to run out, got {other:?}"),
    }
}

/// Many cell crossings: a 1 m block on 0.25 m cells carried 5 m (20
/// cells) by an IBM prescribed displacement on its left side, in 40 load
/// steps, weightless. A rigid translation: the exact stress is zero and
/// every point moves by (5, 0). Measured: the largest stress component is
/// 2.7e-8 Pa with GIMP and 1.6e-8 Pa bilinear (E = 1 MPa: round-off),
/// and the centre probe moves by 5 to 1e-15. Asserted: stress under
/// 1e-6 Pa (1e-12 E), position to 1e-9 m.
#[test]
fn a_body_carried_across_twenty_cells_stays_unstressed() {
    for basis in ["gimp", "linear"] {
        let case = serde_json::json!({
            "version": 1,
            "analysis": { "load_steps": 40 },
            "grid": { "cell_size": 0.25 },
            "basis": basis,
            "bodies": [{
                "geometry": { "rectangle": { "min": [0.1, 0.1], "max": [1.1, 1.1] } },
                "points": { "per_cell": 2 },
                "material": { "model": "hencky", "youngs_modulus": 1e6, "poisson_ratio": 0.3, "density": 0.0 }
            }],
            "supports": [ { "on": { "x": 0.1 }, "fix": "xy", "method": "ibm", "displacement": [5.0, 0.0] } ],
            "probes": [ { "name": "centre", "at": [0.6, 0.6] } ]
        });
        let case = Case::from_json(&case.to_string()).unwrap();
        let mut sim = Simulation::new(&case).unwrap();
        let report = sim.run(&mut NoObserver).expect("converges");
        let moved = report.steps.last().unwrap().probes[0].displacement.clone();
        assert!(
            (moved[0] - 5.0).abs() < 1e-9 && moved[1].abs() < 1e-9,
            "{basis}: {moved:?}"
        );
        let largest = sim
            .points
            .stress
            .iter()
            .flat_map(|s| s.plane.into_iter().chain([s.zz]))
            .fold(0.0, |m: f64, v| m.max(v.abs()));
        assert!(largest < 1e-6, "{basis}: {largest} Pa");
        for p in 0..sim.points.len() {
            let (x, x0) = (sim.points.position[p], sim.points.reference[p]);
            assert!((x[0] - x0[0] - 5.0).abs() < 1e-9 && (x[1] - x0[1]).abs() < 1e-9);
        }
    }
}

/// The elastica: a clamped slender beam (10 m x 0.2 m, nu = 0, Hencky,
/// EI = 1e6 N m) under a dead end load P = k EI / L^2 with k = 10, in 20
/// load steps, against the elliptic-integral solution tabulated by
/// Mattiasson (1981, IJNME 17, "Numerical results from large deflection
/// beam and frame problems analysed by means of elliptic integrals"),
/// recomputed by `scripts/elastica_reference.py`: tip u/L = 0.55500,
/// v/L = 0.81061. The 2D continuum differs from the Euler beam by shear and
/// stretch, of order (d / L)^2 = 4e-4, and the largest strain (0.1 at the
/// root) bends Hencky's moment-curvature law by about its square, 1%.
///
/// Measured (GIMP; h = 0.1, 0.05, 0.025 m; errors in u/L, v/L):
/// - soft background 1e-6 (the default before the ghost penalty): 8.4%,
///   1.2%; 5.2%, 0.79%; 3.0%, 0.54% (10, 4 and 11 cut-backs; the drift of
///   many cell crossings);
/// - ghost penalty 1e-3 (the default, as run here): 2.6%, 0.51%; 1.1%,
///   0.28%; 0.55%, 0.17% (order about 1.1 in u/L; 155, 139 and 151
///   iterations, 0.8 s, 2.5 s and 17.6 s with `mpm run`; with the monotone
///   line search before its free full steps, 398, 275 and 374 iterations and
///   2.6 s, 7.3 s and 58 s);
/// - ghost penalty 1e-2: 2.1%, 0.44%; 0.82%, 0.24%; 0.38%, 0.15% (9, 14
///   and 15 cut-backs; 1.9 s, 12 s and 58 s);
/// - bilinear: fails at step 3 or 5 however far the increment is cut (the
///   cell-crossing error of its gradient jumps).
///
/// Before the line search and the cutting of increments, every bilinear
/// try and the coarse GIMP ones failed.
#[test]
fn the_elastica_under_a_dead_end_load() {
    let (length, depth, ei, k): (f64, f64, f64, f64) = (10.0, 0.2, 1.0e6, 10.0);
    let tip = |h: f64| {
        // EI = E d^3 / 12 per unit width.
        let e = 12.0 * ei / depth.powi(3);
        let load = k * ei / (length * length);
        let case = serde_json::json!({
            "version": 1,
            "analysis": { "load_steps": 20 },
            "grid": { "cell_size": h },
            "basis": "gimp",
            "bodies": [{
                "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [length, depth] } },
                "points": { "per_cell": 2 },
                "material": { "model": "hencky", "youngs_modulus": e, "poisson_ratio": 0.0, "density": 0.0 }
            }],
            "loads": { "boundary": [ { "on": { "x": length }, "traction": [0.0, -load / depth] } ] },
            "supports": [ { "on": { "x": 0.0 }, "fix": "xy" } ],
            "probes": [ { "name": "tip", "at": [length, depth / 2.0] } ]
        });
        let case = Case::from_json(&case.to_string()).unwrap();
        let mut sim = Simulation::new(&case).unwrap();
        let report = sim.run(&mut NoObserver).expect("the elastica finishes");
        let u = report.steps.last().unwrap().probes[0].displacement.clone();
        let (u_l, v_l) = (-u[0] / length, -u[1] / length);
        (
            ((u_l - 0.55500) / 0.55500).abs(),
            ((v_l - 0.81061) / 0.81061).abs(),
        )
    };
    let (coarse, fine) = (tip(0.1), tip(0.05));
    assert!(
        fine.0 < coarse.0 && fine.0 < 1.5e-2,
        "u/L errors {coarse:?} {fine:?}"
    );
    assert!(fine.1 < 5e-3, "v/L errors {coarse:?} {fine:?}");
}

/// A block strained about 1e-5 by its own weight, in 15 load steps (a
/// Drucker-Prager soil, E = 1.4 MPa, nu = 0.485, on a rough base held by
/// the implicit boundary method; GIMP, 3 x 3 points a cell; found by the
/// random cases, `mpm study robustness`, case 559 of seed 2026). Every step
/// is elastic, so Newton converges in a few iterations. When the points
/// kept `b` rather than `b - I` its first step stalled at a relative
/// residual of 4e-9 against the tolerance 1e-9 (the round-off of one in
/// `b` times E, against a weight of 1e-5 E) and the run failed.
#[test]
fn a_block_strained_1e_5_by_its_weight_converges_in_every_step() {
    let case = serde_json::json!({
        "version": 1,
        "analysis": { "load_steps": 15 },
        "grid": { "cell_size": 0.365, "origin": [-0.116, -0.162] },
        "basis": "gimp",
        "bodies": [{
            "geometry": { "polygon": { "vertices": [[0.0, 0.0], [2.69, 0.0], [2.69, 2.55],
                                                    [1.89, 2.55], [1.89, 4.58], [0.0, 4.58]] } },
            "points": { "per_cell": 3 },
            "material": { "model": "drucker_prager", "youngs_modulus": 1.4e6, "poisson_ratio": 0.485,
                          "density": 1552.0, "cohesion": 3817.0, "friction_angle": 10.0,
                          "dilation_angle": 10.0 }
        }],
        "loads": { "gravity": [0.0, -0.002] },
        "supports": [ { "on": { "y": 0.0 }, "fix": "xy", "method": "ibm" } ]
    });
    let case = Case::from_json(&case.to_string()).unwrap();
    let mut sim = Simulation::new(&case).unwrap();
    let report = sim.run(&mut NoObserver).expect("the block finishes");
    for s in &report.steps {
        assert!(
            s.newton.iterations <= 3 && s.cutbacks == 0,
            "step {}: {} iterations, {:?}",
            s.step,
            s.newton.iterations,
            s.newton.residuals
        );
    }
    // The base carries the block's weight.
    let area = 2.69 * 2.55 + 1.89 * (4.58 - 2.55);
    let weight = 1552.0 * 0.002 * area;
    let last = report.steps.last().unwrap();
    assert!((last.reactions[0][1] - weight).abs() < 1e-6 * weight);
}
