//! The background grid: an unbounded lattice of square (cubic) cells in
//! `D` dimensions, 2 (plane strain) or 3; a node is named by its integer
//! coordinates `(i, j)` (`(i, j, k)`) and sits at `origin + h (i, j)`.
//! Nothing is allocated per cell: the nodes a step uses are the ones the
//! material's shape functions touch ([`connectivity`]).

pub mod basis;
pub mod connectivity;

pub use basis::{Basis, NodeWeight, Support};
pub use connectivity::{Connectivity, Link, increment};

/// A lattice node packed into one integer, `64 / D` bits a coordinate;
/// ordering is by `i`, then `j` (then `k`).
pub type NodeKey = u64;

/// Bits of a node key per coordinate in `D` dimensions.
const fn key_bits(d: usize) -> u32 {
    64 / d as u32
}

/// How far from the grid's origin, in cells, material may go in `d`
/// dimensions: half the span a key's coordinate holds (node keys hold
/// indices within 2^31 of it in 2D, 2^20 in 3D), which leaves room for the
/// nodes around the material.
pub const fn reach_cells(d: usize) -> f64 {
    (1u64 << (key_bits(d) - 2)) as f64
}

/// [`reach_cells`] in 2D: 2^30 cells.
pub const REACH_CELLS: f64 = reach_cells(2);

/// The key of the node at lattice coordinates `c`.
#[inline]
pub fn lattice_key<const D: usize>(c: [i64; D]) -> NodeKey {
    let bits = key_bits(D);
    let (bias, mask) = (1i64 << (bits - 1), u64::MAX >> (64 - bits));
    let mut key = 0;
    for (d, &c) in c.iter().enumerate() {
        key |= ((c + bias) as u64 & mask) << (bits * (D - 1 - d) as u32);
    }
    key
}

/// The lattice coordinates of a node key: [`lattice_key`]'s inverse.
#[inline]
pub fn lattice_coordinates<const D: usize>(key: NodeKey) -> [i64; D] {
    let bits = key_bits(D);
    let (bias, mask) = (1i64 << (bits - 1), u64::MAX >> (64 - bits));
    std::array::from_fn(|d| ((key >> (bits * (D - 1 - d) as u32)) & mask) as i64 - bias)
}

/// The 2D key of node `(i, j)`.
#[inline]
pub fn node_key(i: i64, j: i64) -> NodeKey {
    lattice_key([i, j])
}

/// The 2D coordinates `(i, j)` of a node key.
#[inline]
pub fn node_indices(key: NodeKey) -> (i64, i64) {
    let [i, j] = lattice_coordinates(key);
    (i, j)
}

/// [`node_indices`] as an array.
pub fn node_coordinates(key: NodeKey) -> [i64; 2] {
    lattice_coordinates(key)
}

/// Cell size and the position of node (0, 0) (or (0, 0, 0)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid<const D: usize = 2> {
    pub h: f64,
    pub origin: [f64; D],
}

impl<const D: usize> Grid<D> {
    /// Integer coordinates of the cell holding `x`: the one whose lowest
    /// node is those coordinates.
    #[inline]
    pub fn cell_of(&self, x: [f64; D]) -> [i64; D] {
        std::array::from_fn(|d| ((x[d] - self.origin[d]) / self.h).floor() as i64)
    }

    #[inline]
    pub fn node_position(&self, key: NodeKey) -> [f64; D] {
        let c = lattice_coordinates::<D>(key);
        std::array::from_fn(|d| self.origin[d] + self.h * c[d] as f64)
    }
}

/// The places of a sorted list of lattice coordinates (nodes or cells),
/// looked up in a dense table over their bounding box when it is at most 8
/// times the list's length plus 1024, else by binary search.
pub struct LatticeIndex<'k, const D: usize = 2> {
    keys: &'k [[i64; D]],
    dense: Option<DenseTable<D>>,
}

struct DenseTable<const D: usize> {
    lo: [i64; D],
    extent: [i64; D],
    /// Place + 1 of `lo + c` at `((c_0 extent_1) + c_1) extent_2 + ...`;
    /// 0 for none.
    place: Vec<u32>,
}

/// How much larger than the list a dense table may be.
const DENSE_SLACK: usize = 8;

impl<'k, const D: usize> LatticeIndex<'k, D> {
    /// `keys` sorted (by the first coordinate, then the next), without
    /// repeats.
    pub fn new(keys: &'k [[i64; D]]) -> Self {
        debug_assert!(keys.windows(2).all(|w| w[0] < w[1]), "sorted, no repeats");
        let dense = (|| {
            let (first, last) = (keys.first()?, keys.last()?);
            let mut lo = *first;
            let mut hi = *last;
            for k in keys {
                for d in 1..D {
                    lo[d] = lo[d].min(k[d]);
                    hi[d] = hi[d].max(k[d]);
                }
            }
            let extent: [i64; D] = std::array::from_fn(|d| hi[d] - lo[d] + 1);
            let volume = extent.iter().try_fold(1i64, |v, &e| v.checked_mul(e))?;
            let volume = usize::try_from(volume).ok()?;
            if volume > DENSE_SLACK * keys.len() + 1024 || keys.len() >= u32::MAX as usize {
                return None;
            }
            let mut table = DenseTable {
                lo,
                extent,
                place: vec![0u32; volume],
            };
            for (k, key) in keys.iter().enumerate() {
                let at = table.offset(key).expect("a key is inside its bounding box");
                table.place[at] = k as u32 + 1;
            }
            Some(table)
        })();
        Self { keys, dense }
    }

    /// The place of `c` in the list.
    #[inline]
    pub fn get(&self, c: [i64; D]) -> Option<usize> {
        match &self.dense {
            Some(t) => t.place[t.offset(&c)?].checked_sub(1).map(|k| k as usize),
            None => self.keys.binary_search(&c).ok(),
        }
    }
}

impl<const D: usize> DenseTable<D> {
    /// Where `c` sits in the table, if inside its box.
    #[inline]
    fn offset(&self, c: &[i64; D]) -> Option<usize> {
        let mut at = 0i64;
        for d in 0..D {
            let r = c[d] - self.lo[d];
            if r < 0 || r >= self.extent[d] {
                return None;
            }
            at = at * self.extent[d] + r;
        }
        Some(at as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dense table and the binary search find the same places, inside
    /// and outside the bounding box.
    #[test]
    fn a_lattice_index_finds_what_a_search_finds() {
        let keys: Vec<[i64; 2]> = (-3..7_i64)
            .flat_map(|i| (-5..4).map(move |j| [i, j]))
            .filter(|&[i, j]| (i * 7 + j * 3).rem_euclid(5) != 0)
            .collect();
        let dense = LatticeIndex::new(&keys);
        assert!(dense.dense.is_some());
        // Two far-apart keys: a table would be 1e12 entries.
        let sparse_keys = [[0, 0], [1_000_000, 1_000_000]];
        let sparse = LatticeIndex::new(&sparse_keys);
        assert!(sparse.dense.is_none());
        for i in -6..10 {
            for j in -8..7 {
                assert_eq!(
                    dense.get([i, j]),
                    keys.binary_search(&[i, j]).ok(),
                    "{i} {j}"
                );
            }
        }
        assert_eq!(sparse.get([1_000_000, 1_000_000]), Some(1));
        assert_eq!(sparse.get([5, 5]), None);
    }

    /// In 3D too the dense table finds what a binary search finds.
    #[test]
    fn a_lattice_index_in_three_dimensions_finds_what_a_search_finds() {
        let keys: Vec<[i64; 3]> = (-3..4_i64)
            .flat_map(|i| (-2..3).flat_map(move |j| (-4..2).map(move |k| [i, j, k])))
            .filter(|&[i, j, k]| (i * 7 + j * 3 + k * 5).rem_euclid(4) != 0)
            .collect();
        let index = LatticeIndex::new(&keys);
        assert!(index.dense.is_some());
        for i in -5..6 {
            for j in -4..5 {
                for k in -6..4 {
                    let c = [i, j, k];
                    assert_eq!(index.get(c), keys.binary_search(&c).ok(), "{c:?}");
                }
            }
        }
    }

    /// Keys in 3D round-trip to the reach, and sort by `i`, then `j`,
    /// then `k`, as in 2D; 2D keys round-trip to theirs.
    #[test]
    fn keys_in_three_dimensions_round_trip_and_sort_lexicographically() {
        let reach = reach_cells(3) as i64;
        for c in [[0, 0, 0], [-3, 7, 2], [reach, -reach, 5], [-1, -1, -1]] {
            assert_eq!(lattice_coordinates::<3>(lattice_key(c)), c);
        }
        let order = [
            [-1, 5, 5],
            [0, -5, 9],
            [0, 4, -9],
            [0, 4, 2],
            [3, -reach, -reach],
        ];
        assert!(
            order
                .windows(2)
                .all(|w| lattice_key(w[0]) < lattice_key(w[1]))
        );
        let reach = REACH_CELLS as i64;
        for c in [[reach, -reach], [-reach, reach]] {
            assert_eq!(lattice_coordinates::<2>(lattice_key(c)), c);
        }
    }

    #[test]
    fn node_keys_round_trip_and_sort_by_i_then_j() {
        for (i, j) in [(0, 0), (-3, 7), (12345, -678), (-1, -1)] {
            assert_eq!(node_indices(node_key(i, j)), (i, j));
        }
        assert!(node_key(-1, 5) < node_key(0, -5));
        assert!(node_key(0, -5) < node_key(0, 4));
    }
}
