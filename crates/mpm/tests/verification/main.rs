//! The solver's verification cases, each against an answer known from
//! outside the code (analytical solutions, published tables, converged
//! references), in one test binary so that the crate is linked once.

mod common;

mod arc_length;
mod bodies;
mod cantilever;
mod cantilever3d;
mod column;
mod column3d;
mod footing;
mod ghost;
mod hard_cases;
mod hinge;
mod ibm;
mod ibm3d;
mod lame;
mod locking;
mod locking3d;
mod newton_convergence;
mod one_point_cells;
mod plasticity;
mod pressure;
mod slab3d;
mod sphere3d;
mod stages;
mod strength_reduction;
mod triaxial3d;
mod twist3d;
