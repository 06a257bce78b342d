//! Studies and benchmarks of the solver, offered by the `mpm` command as
//! `mpm study` and `mpm bench`: the paper's convergence study written as
//! tables and SVG plots ([`study`]), the grid bases compared on it
//! ([`basis_study`]), the strip footing on plastic soil
//! ([`footing_study`]) and its bearing capacity factor on frictional
//! soil ([`bearing_study`]), a slope's factor of safety by strength reduction
//! ([`slope_study`]), random valid cases run under the contract every case
//! must keep ([`random_cases`], [`contract`], [`robustness_study`]), and
//! cost against problem size written to BENCHMARKS.md ([`bench`]). They
//! use only the solver crate.
//!
//! [`bench::bench`] measures each row in a child process (for its own peak
//! memory) by running the current executable as `mpm bench-row SCENE
//! POINTS`: a binary that offers `bench` must offer `bench-row` too, as
//! [`bench::bench_row`].

pub mod basis_study;
pub mod bearing_study;
pub mod bench;
pub mod contract;
pub mod footing_study;
pub mod plot;
pub mod random_cases;
pub mod robustness_study;
pub mod slope_study;
pub mod study;

/// Why a study or benchmark stopped.
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    /// What was asked for does not exist (an unknown basis or scene).
    #[error("{0}")]
    Input(String),
    /// A solve, a child process or a file write failed.
    #[error("{0}")]
    Failed(String),
}

impl From<std::io::Error> for LabError {
    fn from(e: std::io::Error) -> Self {
        LabError::Failed(e.to_string())
    }
}
