//! Ghost ties: the second difference `u_I - 2 u_J + u_K` of a node beyond
//! a supported boundary (`I`) and the next two inward, penalised with a
//! tenth of the band's `A_nn`. It vanishes for linear fields, so the patch
//! tests stay exact, and it makes those nodes follow the linear
//! continuation of the field inside. Only nodes more than a tenth of a
//! cell beyond the boundary and outside the current curve are tied, and
//! only those found by a pointwise support's anchors: an averaged
//! support's (a rigid footing's) find none, so a node beyond both is tied
//! by the pointwise one.

use std::collections::BTreeMap;

use nalgebra::{SMatrix, SVector};

use super::anchors::Anchor;
use crate::boundary::detection::BoundaryLoop;
use crate::configuration::Configuration;
use crate::geometry::inside_ring;
use crate::grid::{Grid, NodeKey, lattice_coordinates, lattice_key};

/// Weight of the ghost ties against the band's material stiffness.
pub(super) const GHOST: f64 = 0.1;

/// An active node beyond a supported boundary (`I`) and the next two
/// inward (`J`, `K`), whose second difference `u_I - 2 u_J + u_K` is
/// penalised (module docs).
#[derive(Debug, Clone)]
pub(super) struct GhostTie<const D: usize = 2> {
    pub(super) nodes: [usize; 3],
    pub(super) stiffness: SMatrix<f64, D, D>,
    /// The support whose anchor found it (its reaction takes the tie's
    /// force where part of it lands on a grid-held node).
    pub(super) support: usize,
}

impl<const D: usize> GhostTie<D> {
    /// `K (u_I - 2 u_J + u_K)`.
    pub(super) fn force(&self, u: &[f64]) -> SVector<f64, D> {
        let mut g = SVector::<f64, D>::zeros();
        for (&a, c) in self.nodes.iter().zip(GHOST_STENCIL) {
            g += c * SVector::<f64, D>::from_fn(|d, _| u[D * a + d]);
        }
        self.stiffness * g
    }

    /// The tie of node `key` inward along the grid axis closest to the
    /// normal `n`, where the next two nodes are active (`nodes`, sorted).
    pub(super) fn inward(
        key: NodeKey,
        n: [f64; D],
        nodes: &[NodeKey],
        a_nn: SMatrix<f64, D, D>,
        support: usize,
    ) -> Option<Self> {
        let axis = (1..D).fold(
            0,
            |best, d| {
                if n[d].abs() > n[best].abs() { d } else { best }
            },
        );
        let c = lattice_coordinates::<D>(key);
        let index = |k: i64| {
            let mut at = c;
            at[axis] -= k * n[axis].signum() as i64;
            nodes.binary_search(&lattice_key(at)).ok()
        };
        Some(GhostTie {
            nodes: [index(0)?, index(1)?, index(2)?],
            stiffness: a_nn * GHOST,
            support,
        })
    }
}

/// The second difference's weights along `[I, J, K]`.
pub(super) const GHOST_STENCIL: [f64; 3] = [1.0, -2.0, 1.0];

/// Grid nodes that GIMP domains reaching just past a supported boundary at
/// `x` (outward normal `n`) can touch: beyond it by more than a tenth of a
/// cell (nearer ones take at least 90% of the band's shares there, and a
/// node on a grid-aligned boundary that has moved a hair is not beyond it)
/// and at most one cell, and within one cell of `x` along it.
pub(super) fn nodes_beyond<const D: usize>(
    grid: &Grid<D>,
    x: [f64; D],
    n: [f64; D],
    cells: f64,
) -> impl Iterator<Item = NodeKey> + '_ {
    let cell = grid.cell_of(x);
    let tol = 1e-9 * grid.h;
    let r = cells.ceil() as i64;
    let side = (2 * r + 2) as usize;
    (0..side.pow(D as u32))
        .map(move |k| {
            let mut rest = k;
            lattice_key::<D>(std::array::from_fn(|d| {
                let i = (rest % side) as i64;
                rest /= side;
                cell[d] - r + i
            }))
        })
        .filter(move |&key| {
            let p = grid.node_position(key);
            let r: [f64; D] = std::array::from_fn(|d| p[d] - x[d]);
            let out: f64 = (0..D).map(|d| r[d] * n[d]).sum();
            let along = (0..D)
                .map(|d| (r[d] - out * n[d]).powi(2))
                .sum::<f64>()
                .sqrt();
            out > 0.1 * grid.h && out <= cells * grid.h + tol && along <= cells * grid.h + tol
        })
}

/// The ghost ties of the active nodes found beyond supported boundaries
/// (`beyond`: node and the anchor that found it). A node beyond the tangent
/// at its anchor but inside the material (a concave stretch, or a curve
/// through the points half a spacing inside the edge) is not tied; the
/// others are tied inward along the grid axis closest to the anchor's
/// normal, where the next two nodes are active. `rings` are the current
/// data points of the loops with anchors.
pub(super) fn ties(
    start: &Configuration,
    loops: &[BoundaryLoop],
    anchors: &[Anchor],
    beyond: &BTreeMap<NodeKey, usize>,
    rings: &BTreeMap<usize, Vec<[f64; 2]>>,
) -> Vec<GhostTie> {
    let Configuration {
        grid, conn, points, ..
    } = *start;
    let mut ties = Vec::new();
    for (&key, &anchor) in beyond {
        let a = &anchors[anchor];
        // Beyond the tangent at the anchor but inside the material (a
        // concave stretch, or a curve through the points half a spacing
        // inside the edge): no tie.
        let inside = inside_ring(&rings[&a.loop_index], grid.node_position(key));
        if inside != loops[a.loop_index].hole {
            continue;
        }
        let a_nn = a.acoustic_tensor(points);
        ties.extend(GhostTie::inward(
            key,
            a.normal,
            &conn.nodes,
            a_nn,
            a.support,
        ));
    }
    ties
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nodes_beyond_a_grid_aligned_side_are_the_next_column_out() {
        let grid = Grid {
            h: 1.0,
            origin: [0.0, 0.0],
        };
        // An anchor on x = 0 that has moved a hair left: the nodes on x = 0
        // are not beyond it, those on x = -1 within a cell along it are.
        let found: Vec<[f64; 2]> = nodes_beyond(&grid, [-1e-4, 2.3], [-1.0, 0.0], 1.0)
            .map(|k| grid.node_position(k))
            .collect();
        assert_eq!(found, vec![[-1.0, 2.0], [-1.0, 3.0]]);
    }
}
