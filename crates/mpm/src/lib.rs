//! Implicit, quasi-static, updated-Lagrangian material point method in 2D
//! plane strain, after Bing, Cortis, Charlton, Coombs & Augarde (2017).
//!
//! A [`Case`] (JSON) becomes a [`Simulation`]; [`Simulation::run`] solves its
//! load steps with Newton-Raphson on the active part of a background grid and
//! reports each step to an [`Observer`]. The crate does no I/O of its own
//! beyond the writers in [`output`].

// Index loops mirror the tensor notation of the formulas (i, j, a, b), which
// reads better in numerical code than iterator chains.
#![allow(clippy::needless_range_loop)]

pub mod assembly;
pub mod basis;
pub mod boundary;
pub mod case;
pub mod examples;
pub mod fill;
pub mod linsolve;
pub mod material;
pub mod newton;
pub mod observer;
pub mod output;
pub mod points;
pub mod stepper;

pub use case::{Case, CaseError};
pub use newton::{NewtonSettings, SolveError};
pub use observer::{NoObserver, Observer, StepState};
pub use output::{RunReport, StepReport};
pub use points::MaterialPoints;
pub use stepper::Simulation;
