//! Supports on grid nodes (AMPLE's way, exact when the boundary lies on
//! grid lines): the DOFs they hold in a load step and the reactions they
//! exert, from one scan of the step's active nodes. The supports' kinds of
//! hold ([`Fix`]) and prescribed rotations are shared with the implicit
//! boundary method ([`crate::boundary::ibm`]).

use crate::geometry::Selector;
use crate::grid::{Connectivity, Grid};

/// Which displacement components a support holds (the case's
/// `crate::case::Fix`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fix {
    /// Horizontal displacement held (a roller on a wall normal to x).
    X,
    /// Vertical displacement held (a roller on a floor normal to y).
    Y,
    /// Both held.
    Xy,
    /// The component normal to the boundary held (a roller on a boundary at
    /// any angle, or curved). Implicit boundary method only.
    Normal,
}

impl Fix {
    /// Whether a grid support holds Cartesian component `component`
    /// (`Normal` holds none: it is for the implicit boundary method).
    pub fn holds(self, component: usize) -> bool {
        matches!((self, component), (Fix::Xy, _) | (Fix::X, 0) | (Fix::Y, 1))
    }
}

/// A rigid rotation of the boundary it applies to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rotation {
    /// Counter-clockwise angle in degrees at the last load step.
    pub angle: f64,
    /// Centre (m), in the reference configuration.
    pub center: [f64; 2],
}

/// A support on the grid nodes its selector contains.
#[derive(Debug, Clone, PartialEq)]
pub struct GridSupport {
    /// Its index among the case's supports (for reactions).
    pub index: usize,
    pub on: Selector,
    pub fix: Fix,
}

/// The grid supports' hold on one load step's active nodes.
#[derive(Debug, Clone, Default)]
pub struct HeldDofs {
    /// Per DOF of the step: whether a grid support holds it.
    pub fixed: Vec<bool>,
    /// Per grid support: its index in the case and the DOFs it holds, in
    /// node order.
    held: Vec<(usize, Vec<usize>)>,
}

impl HeldDofs {
    /// A node is on a support when the support's selector contains the
    /// node's position (tolerance 1e-9 h).
    pub fn find(supports: &[GridSupport], grid: &Grid, conn: &Connectivity) -> Self {
        let tol = 1e-9 * grid.h;
        let mut fixed = vec![false; conn.n_dofs()];
        let mut held: Vec<(usize, Vec<usize>)> =
            supports.iter().map(|s| (s.index, Vec::new())).collect();
        for (a, &key) in conn.nodes.iter().enumerate() {
            let x = grid.node_position(key);
            for (s, (_, dofs)) in supports.iter().zip(&mut held) {
                if s.on.contains(x, tol) {
                    for c in (0..2).filter(|&c| s.fix.holds(c)) {
                        fixed[2 * a + c] = true;
                        dofs.push(2 * a + c);
                    }
                }
            }
        }
        Self { fixed, held }
    }

    /// The case index of the first grid support that holds no DOF.
    pub fn first_idle(&self) -> Option<usize> {
        self.held
            .iter()
            .find(|(_, dofs)| dofs.is_empty())
            .map(|&(index, _)| index)
    }

    /// Number of held DOFs.
    pub fn count(&self) -> usize {
        self.fixed.iter().filter(|f| **f).count()
    }

    /// Adds to `reactions` (indexed like the case's supports) the force
    /// each grid support exerts on the body: `f_int - f_ext` summed over
    /// its DOFs.
    pub fn add_reactions(&self, f_int: &[f64], f_ext: &[f64], reactions: &mut [[f64; 2]]) {
        for (index, dofs) in &self.held {
            for &dof in dofs {
                reactions[*index][dof % 2] += f_int[dof] - f_ext[dof];
            }
        }
    }
}
