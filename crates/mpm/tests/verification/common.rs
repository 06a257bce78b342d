//! Helpers shared by the verification cases.
#![allow(dead_code)]

use mpm::{Case, NoObserver, RunReport, Simulation};

/// A built-in example as an editable JSON value.
pub fn example(name: &str) -> serde_json::Value {
    mpm::case::builtin::json(name).expect("built-in example")
}

/// Parses (validating) and runs a case.
pub fn run(case: &serde_json::Value) -> (Simulation, RunReport) {
    let case = Case::from_json(&case.to_string()).expect("valid case");
    let mut sim = Simulation::new(&case).expect("valid case");
    let report = sim.run(&mut NoObserver).expect("the solve converges");
    (sim, report)
}

/// Observed order of convergence between successive refinements by 2.
pub fn orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}
