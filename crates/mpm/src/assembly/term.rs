//! A step term: what a load step's system holds besides the material
//! points' own forces and stiffness. The boundary loads, the IBM band, the
//! soft background and the ghost penalty are step terms; the equilibrium
//! of a step (`crate::equilibrium`) holds them as one list and asks each
//! the same questions: which nodes it couples, its force and its stiffness
//! at a trial increment, whether that stiffness is symmetric, and what it
//! reports as reactions.
//!
//! F-bar is not one: it changes each point's stress in the point loop
//! rather than adding a force beside it (`crate::assembly::fbar`).

use std::any::Any;

use super::Pattern;

/// Where a term's force enters a step's balance, `f_ext - f_int - f_support`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// A load on the body (a boundary traction): part of the external
    /// force, and of the force scale the balance is measured against.
    Load,
    /// A stiffness beside the material's (the soft background, the ghost
    /// penalty): added to the internal force once the material's own force
    /// scale is taken, so a grid support's reaction includes it.
    Stabilisation,
    /// A support (the IBM band): its force kept apart, and reported as
    /// the reactions of the case's supports it stands for.
    Support,
}

/// One kind of term in a load step's system, in `D` dimensions. Its
/// stiffness goes into the step's tangent in the step's pattern, which
/// holds its coupling groups.
pub trait StepTerm<const D: usize = 2>: Send + Sync {
    /// Where its force enters the balance.
    fn side(&self) -> Side;

    /// Groups of active nodes it couples, each group every pair of its
    /// nodes (for the stiffness pattern). None beyond the points' own
    /// couplings by default.
    fn coupling_groups(&self) -> Vec<Vec<u32>> {
        Vec::new()
    }

    /// Adds its force at trial increment `u` to `f` (the external force
    /// for a load, the internal force otherwise).
    fn add_force(&self, u: &[f64], f: &mut [f64]);

    /// Sets the load factor its force is at, when the load factor is an
    /// unknown of the step (path following). A load's force follows it;
    /// the other terms' do not depend on it in such a step (a
    /// path-following stage prescribes no motion).
    fn set_load_factor(&mut self, lambda: f64) {
        let _ = lambda;
    }

    /// Adds the derivative of its force at `u` by the load factor to `f`
    /// (nothing by default: a term whose force does not follow it).
    fn add_load_rate(&self, u: &[f64], f: &mut [f64]) {
        let _ = (u, f);
    }

    /// Adds its stiffness at `u` to the tangent's `values` in `pattern`'s
    /// layout (a load's is `-df_ext/du`).
    fn add_stiffness(&self, u: &[f64], pattern: &Pattern, values: &mut [f64]);

    /// Whether its stiffness is symmetric (a load that moves with the
    /// boundary has one that is not).
    fn symmetric(&self) -> bool {
        true
    }

    /// A force the balance is measured against besides the material's and
    /// the loads' (a support's: what its prescribed displacement asks of
    /// the material), on `n_dofs` DOFs. Zero by default.
    fn force_scale(&self, n_dofs: usize) -> f64 {
        let _ = n_dofs;
        0.0
    }

    /// Per support of the case (`n` of them), the force it exerts on the
    /// body at the converged increment `u`, leaving the DOFs a grid support
    /// holds (`fixed`) to that support; `None` for a term that is no
    /// support.
    fn reactions(&self, u: &[f64], fixed: &[bool], n: usize) -> Option<Vec<[f64; D]>> {
        let _ = (u, fixed, n);
        None
    }

    /// What the term carries to the next step once its step converges
    /// (the IBM band: where its anchors moved), for the stage that owns
    /// it to take by its type; `None` for a term that carries nothing.
    fn into_carried(self: Box<Self>) -> Option<Box<dyn Any>> {
        None
    }
}
