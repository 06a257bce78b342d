//! Cases the solver's unit tests build on: one rectangular body, loaded in
//! one step, which each test adjusts (its grid, basis, material, supports)
//! as a JSON tree before it is read like any other case.

use serde_json::{Value, json};

use crate::case::Case;
use crate::stepper::Simulation;

/// A one-step case of one Hencky block (E = 1e6, nu = 0.3, weightless)
/// from the origin to `max`, seeded with `count` points, on cells of
/// `cell_size` whose grid has a node at `origin`; no supports, no loads.
pub fn block(max: [f64; 2], count: [u32; 2], cell_size: f64, origin: [f64; 2]) -> Value {
    json!({
        "version": 1,
        "analysis": { "load_steps": 1 },
        "grid": { "cell_size": cell_size, "origin": origin },
        "bodies": [{
            "geometry": { "rectangle": { "min": [0.0, 0.0], "max": max } },
            "points": { "count": count },
            "material": { "model": "hencky", "youngs_modulus": 1e6, "poisson_ratio": 0.3, "density": 0.0 }
        }]
    })
}

/// The case `case` describes, read and checked as a submitted one is.
pub fn case(case: &Value) -> Case {
    Case::from_json(&case.to_string()).expect("a valid case")
}

/// The case `case` describes, made ready to run.
pub fn simulation(case: &Value) -> Simulation {
    Simulation::new(&self::case(case)).expect("a case that builds")
}
