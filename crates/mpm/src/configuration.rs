//! The configuration a load step starts from, which the updated-Lagrangian
//! step measures its increment against: the grid, the step's active nodes
//! and the material points. The stages that build a step's terms (boundary
//! loads, the IBM band, the soft background) take it as one bundle.

use crate::grid::{Basis, Connectivity, Grid};
use crate::particles::{Dim, MaterialPoints, Space};

#[derive(Clone, Copy)]
pub struct Configuration<'a, const D: usize = 2>
where
    Dim<D>: Space<D>,
{
    pub grid: &'a Grid<D>,
    /// The shape functions, which the boundary's quadrature uses too.
    pub basis: Basis,
    /// The grid reset of the step: shape functions on the active nodes.
    pub conn: &'a Connectivity<D>,
    pub points: &'a MaterialPoints<D>,
}
