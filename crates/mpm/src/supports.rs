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

/// A support on grid nodes, in `D` dimensions.
pub trait NodeHold<const D: usize> {
    /// Its index among the case's supports (for reactions).
    fn index(&self) -> usize;
    /// The components it holds of a node at `x` (none, off the support),
    /// `tol` the distance that counts as on it.
    fn holds_at(&self, x: [f64; D], tol: f64) -> [bool; D];
    /// The increment it prescribes to a node at `x` it holds, in a step
    /// from load factor `from` to `to` (zero: at rest).
    fn moved_at(&self, _x: [f64; D], _factors: (f64, f64)) -> [f64; D] {
        [0.0; D]
    }
}

impl NodeHold<2> for GridSupport {
    fn index(&self) -> usize {
        self.index
    }

    fn holds_at(&self, x: [f64; 2], tol: f64) -> [bool; 2] {
        if self.on.contains(x, tol) {
            [0, 1].map(|c| self.fix.holds(c))
        } else {
            [false; 2]
        }
    }
}

/// A support on the grid nodes of a plane normal to an axis (in 3D, the
/// faces of a box; the B-spline surfaces' supports are the IBM's).
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneSupport<const D: usize> {
    /// Its index among the case's supports (for reactions).
    pub index: usize,
    /// The plane: `x[axis] = at`.
    pub axis: usize,
    pub at: f64,
    /// The components held: all (fixed), or the one along `axis` (a
    /// roller), or any others.
    pub fix: [bool; D],
    /// In 3D, the rotation its nodes are turned by about the plane's
    /// normal through a point (radians at load factor 1, the point), which
    /// the held in-plane components follow; `None`: at rest.
    pub rotation: Option<(f64, [f64; D])>,
}

impl<const D: usize> NodeHold<D> for PlaneSupport<D> {
    fn index(&self) -> usize {
        self.index
    }

    fn holds_at(&self, x: [f64; D], tol: f64) -> [bool; D] {
        if (x[self.axis] - self.at).abs() <= tol {
            self.fix
        } else {
            [false; D]
        }
    }

    /// The material at a node at `x` when the step starts turns with the
    /// plane from `from` to `to` about the axis through `c`: `(R(d theta)
    /// - I)(x - c)`, the in-plane axes in cyclic order after the normal.
    fn moved_at(&self, x: [f64; D], (from, to): (f64, f64)) -> [f64; D] {
        let mut moved = [0.0; D];
        if let (3, Some((angle, c))) = (D, self.rotation) {
            let (sin, cos) = (angle * (to - from)).sin_cos();
            let (a, b) = ((self.axis + 1) % 3, (self.axis + 2) % 3);
            let (ra, rb) = (x[a] - c[a], x[b] - c[b]);
            moved[a] = (cos - 1.0) * ra - sin * rb;
            moved[b] = sin * ra + (cos - 1.0) * rb;
        }
        moved
    }
}

/// The grid supports' hold on one load step's active nodes.
#[derive(Debug, Clone, Default)]
pub struct HeldDofs {
    /// Per DOF of the step: whether a grid support holds it.
    pub fixed: Vec<bool>,
    /// Per grid support: its index in the case and the DOFs it holds, in
    /// node order.
    held: Vec<(usize, Vec<usize>)>,
    /// The held DOFs a support moves in the step, and their increments
    /// ([`HeldDofs::moving`]); empty when every support is at rest.
    pub moved: Vec<(usize, f64)>,
}

impl HeldDofs {
    /// A node is on a support when the support's selector contains the
    /// node's position (tolerance 1e-9 h).
    pub fn find<const D: usize, S: NodeHold<D>>(
        supports: &[S],
        grid: &Grid<D>,
        conn: &Connectivity<D>,
    ) -> Self {
        let tol = 1e-9 * grid.h;
        let mut fixed = vec![false; conn.n_dofs()];
        let mut held: Vec<(usize, Vec<usize>)> =
            supports.iter().map(|s| (s.index(), Vec::new())).collect();
        for (a, &key) in conn.nodes.iter().enumerate() {
            let x = grid.node_position(key);
            for (s, (_, dofs)) in supports.iter().zip(&mut held) {
                let holds = s.holds_at(x, tol);
                for c in (0..D).filter(|&c| holds[c]) {
                    fixed[D * a + c] = true;
                    dofs.push(D * a + c);
                }
            }
        }
        Self {
            fixed,
            held,
            moved: Vec::new(),
        }
    }

    /// The increments the supports prescribe in a step from load factor
    /// `from` to `to`, to the DOFs they hold ([`NodeHold::moved_at`]). A
    /// DOF two moving supports hold takes the last one's.
    pub fn moving<const D: usize, S: NodeHold<D>>(
        mut self,
        supports: &[S],
        grid: &Grid<D>,
        conn: &Connectivity<D>,
        factors: (f64, f64),
    ) -> Self {
        let tol = 1e-9 * grid.h;
        self.moved.clear();
        for (a, &key) in conn.nodes.iter().enumerate() {
            let x = grid.node_position(key);
            for s in supports {
                let (holds, moved) = (s.holds_at(x, tol), s.moved_at(x, factors));
                for c in (0..D).filter(|&c| holds[c] && moved[c] != 0.0) {
                    self.moved.push((D * a + c, moved[c]));
                }
            }
        }
        self
    }

    /// Writes the supports' increments into `u`'s held DOFs.
    pub fn impose(&self, u: &mut [f64]) {
        for &(dof, value) in &self.moved {
            u[dof] = value;
        }
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
    pub fn add_reactions<const D: usize>(
        &self,
        f_int: &[f64],
        f_ext: &[f64],
        reactions: &mut [[f64; D]],
    ) {
        for (index, dofs) in &self.held {
            for &dof in dofs {
                reactions[*index][dof % D] += f_int[dof] - f_ext[dof];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A turning plane moves a node at `x` to where the rotation about
    /// its axis takes it, in any split of the load factor: two half steps
    /// from `x` end where one whole step does (90 degrees about x, y and z
    /// in turn through (0, 1, 1): a node at (2, 1, 3) goes to (2, -1, 1),
    /// (2, 1, -1) and (0, 3, 3)), and a node off the plane is not held.
    #[test]
    fn a_turning_plane_moves_its_nodes_by_the_rotation() {
        let quarter = std::f64::consts::FRAC_PI_2;
        let turning = |axis| PlaneSupport::<3> {
            index: 0,
            axis,
            at: 2.0,
            fix: [true; 3],
            rotation: Some((quarter, [0.0, 1.0, 1.0])),
        };
        let x = [2.0, 1.0, 3.0];
        let whole: Vec<[f64; 3]> = (0..3)
            .map(|axis| turning(axis).moved_at(x, (0.0, 1.0)))
            .collect();
        let expected = [[0.0, -2.0, -2.0], [0.0, 0.0, -4.0], [-2.0, 2.0, 0.0]];
        for axis in 0..3 {
            let s = turning(axis);
            let first = s.moved_at(x, (0.0, 0.5));
            let there: [f64; 3] = std::array::from_fn(|c| x[c] + first[c]);
            let second = s.moved_at(there, (0.5, 1.0));
            for c in 0..3 {
                assert!(
                    (whole[axis][c] - expected[axis][c]).abs() < 1e-14,
                    "{axis}: {:?}",
                    whole[axis]
                );
                assert!(
                    (first[c] + second[c] - whole[axis][c]).abs() < 1e-14,
                    "{axis}"
                );
            }
        }
        assert_eq!(turning(0).holds_at([1.0, 1.0, 3.0], 1e-9), [false; 3]);
    }
}
