//! The background grid: an unbounded lattice of square cells; a node is
//! named by its integer coordinates `(i, j)` and sits at `origin + h (i, j)`.
//! Nothing is allocated per cell: the nodes a step uses are the ones the
//! material's shape functions touch ([`connectivity`]).

pub mod basis;
pub mod connectivity;
pub mod quadrilateral_domain;

pub use basis::{Basis, NodeWeight, Support};
pub use connectivity::{Connectivity, Link};

/// A lattice node packed into one integer; ordering is by `i`, then `j`.
pub type NodeKey = u64;

const BIAS: i64 = 1 << 31;

/// How far from the grid's origin, in cells, material may go: node keys
/// hold indices within 2^31 of it, and this leaves room for the nodes
/// around the material.
pub const REACH_CELLS: f64 = (1u64 << 30) as f64;

#[inline]
pub fn node_key(i: i64, j: i64) -> NodeKey {
    (((i + BIAS) as u64) << 32) | ((j + BIAS) as u64 & 0xffff_ffff)
}

#[inline]
pub fn node_indices(key: NodeKey) -> (i64, i64) {
    ((key >> 32) as i64 - BIAS, (key & 0xffff_ffff) as i64 - BIAS)
}

/// Cell size and the position of node (0, 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    pub h: f64,
    pub origin: [f64; 2],
}

impl Grid {
    /// Integer coordinates `(i, j)` of the cell holding `x`: the one whose
    /// lower-left node is `(i, j)`.
    #[inline]
    pub fn cell_of(&self, x: [f64; 2]) -> [i64; 2] {
        [0, 1].map(|d| ((x[d] - self.origin[d]) / self.h).floor() as i64)
    }

    #[inline]
    pub fn node_position(&self, key: NodeKey) -> [f64; 2] {
        let (i, j) = node_indices(key);
        [
            self.origin[0] + self.h * i as f64,
            self.origin[1] + self.h * j as f64,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_keys_round_trip_and_sort_by_i_then_j() {
        for (i, j) in [(0, 0), (-3, 7), (12345, -678), (-1, -1)] {
            assert_eq!(node_indices(node_key(i, j)), (i, j));
        }
        assert!(node_key(-1, 5) < node_key(0, -5));
        assert!(node_key(0, -5) < node_key(0, 4));
    }
}
