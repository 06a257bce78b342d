//! Implicit, quasi-static, updated-Lagrangian material point method in 2D
//! plane strain, after Bing, Cortis, Charlton, Coombs & Augarde (2017).
//!
//! A [`Case`] (JSON, [`case`]) becomes a [`Simulation`] ([`model`]);
//! [`Simulation::run`] solves its load steps ([`stepper`]) with
//! Newton-Raphson ([`newton`], [`equilibrium`]) on the active part of a
//! background grid ([`grid`]) and reports each step ([`report`]) to an
//! [`Observer`]. The crate does no I/O of its own beyond the writers in
//! [`vtk`].
//!
//! The stages of a load step, each in its own module: the grid reset
//! ([`grid::connectivity`]), the material points and their seeding
//! ([`particles`]), constitutive models ([`material`]), the boundary loops,
//! their B-spline, tractions and the implicit boundary method
//! ([`boundary`]), grid-node supports ([`supports`]), assembly
//! ([`assembly`]), the sparse solve ([`linsolve`]) and probes ([`probes`]).

// Index loops mirror the tensor notation of the formulas (i, j, a, b), which
// reads better in numerical code than iterator chains.
#![allow(clippy::needless_range_loop)]

pub mod assembly;
pub mod boundary;
pub mod case;
pub mod checkpoint;
pub mod configuration;
pub mod equilibrium;
#[cfg(test)]
mod fixtures;
pub mod geometry;
pub mod grid;
pub mod krylov;
pub mod linsolve;
pub mod material;
pub mod model;
pub mod multigrid;
pub mod newton;
pub mod observer;
pub mod ordering;
pub mod parallel;
pub mod particles;
pub mod probes;
pub mod reference_edge;
pub mod report;
mod resume;
pub mod settings;
pub mod stages;
pub mod stepper;
pub mod strength_reduction;
pub mod supports;
pub mod triangular;
pub mod triangulation;
pub mod update;
pub mod vtk;

pub use case::{Case, CaseError, CaseErrorKind};
pub use checkpoint::{Checkpoint, CheckpointError, SolidCheckpoint};
pub use newton::{NewtonSettings, SolveError};
pub use observer::{NoObserver, Observer, SolidStepState, StepState};
pub use particles::MaterialPoints;
pub use report::{RunReport, StepReport};
pub use stepper::{Simulation, Substepping};
