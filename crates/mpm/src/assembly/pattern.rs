//! The stiffness matrix's sparsity pattern (see the parent module for the
//! layout) and the constraint of held DOFs.

use rayon::prelude::*;

use crate::grid::{Connectivity, lattice_coordinates};
use crate::parallel;

/// Sparsity of the stiffness matrix, in compressed columns (faer's form,
/// with 32-bit row indices), in blocks of `D x D` for each pair of
/// neighbouring nodes (`D` = 2 or 3, the nodes' DOFs).
#[derive(Debug, Clone)]
pub struct Pattern {
    /// DOFs per node: the dimension.
    dofs: usize,
    /// Neighbours of node `b` are `neighbours[first[b]..first[b + 1]]`, sorted.
    first: Vec<usize>,
    neighbours: Vec<u32>,
    /// The points in tiles of the grid, the stiffness assembly's schedule.
    pub(crate) tiles: PointTiles,
    pub col_ptr: Vec<usize>,
    /// 32-bit, as the node lists are: half the bytes of faer's `usize`
    /// (95 bytes a point at 1e6 GIMP points) for every product with the
    /// tangent to read. The solver widens them where faer needs it.
    pub row_idx: Vec<u32>,
}

impl Default for Pattern {
    /// The empty 2D pattern.
    fn default() -> Self {
        Self {
            dofs: 2,
            first: Vec::new(),
            neighbours: Vec::new(),
            tiles: PointTiles::default(),
            col_ptr: Vec::new(),
            row_idx: Vec::new(),
        }
    }
}

/// The nodes adjacent to each active node: what determines a [`Pattern`]'s
/// compressed columns.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeAdjacency {
    first: Vec<usize>,
    neighbours: Vec<u32>,
}

impl Pattern {
    /// A pattern of these compressed columns alone (no node lists), for
    /// tests of what reads only the columns.
    #[cfg(test)]
    pub fn from_columns(col_ptr: Vec<usize>, row_idx: Vec<u32>) -> Self {
        Self {
            col_ptr,
            row_idx,
            ..Self::default()
        }
    }

    /// Two nodes are neighbours when some point links to both.
    /// Two nodes are also neighbours when they share one of the `groups`
    /// (couplings that do not come from points, e.g. boundary loads).
    pub fn build<const D: usize>(conn: &Connectivity<D>, groups: &[Vec<u32>]) -> Self {
        let n_nodes = conn.n_nodes();
        assert!(
            D * n_nodes <= u32::MAX as usize,
            "DOFs beyond 32-bit row indices"
        );
        let mut node_groups: Vec<Vec<u32>> =
            vec![Vec::new(); if groups.is_empty() { 0 } else { n_nodes }];
        for (g, members) in groups.iter().enumerate() {
            for &a in members {
                node_groups[a as usize].push(g as u32);
            }
        }
        // Node -> links incidence, in compressed form (for the neighbour
        // lists alone).
        let mut touching = vec![0usize; n_nodes + 1];
        for l in &conn.links {
            touching[l.node as usize + 1] += 1;
        }
        for i in 0..n_nodes {
            touching[i + 1] += touching[i];
        }
        let mut fill = touching.clone();
        let mut incident = vec![(0u32, 0u32); conn.links.len()];
        for p in 0..conn.n_points() {
            for k in conn.offsets[p]..conn.offsets[p + 1] {
                let node = conn.links[k].node as usize;
                incident[fill[node]] = (p as u32, k as u32);
                fill[node] += 1;
            }
        }
        // Each node's neighbours, gathered once each: `seen[a] == b` marks
        // node `a` as a neighbour of `b` already (a node's points share
        // most of their nodes, so a sort of the raw list would be ten
        // times longer).
        let neighbours_of = |seen: &mut [u32], b: usize| {
            let mut nb = Vec::new();
            let mut add = |a: u32| {
                if seen[a as usize] != b as u32 {
                    seen[a as usize] = b as u32;
                    nb.push(a);
                }
            };
            for &(p, _) in &incident[touching[b]..touching[b + 1]] {
                conn.point_links(p as usize)
                    .iter()
                    .for_each(|l| add(l.node));
            }
            if let Some(gs) = node_groups.get(b) {
                for &g in gs {
                    groups[g as usize].iter().for_each(|&a| add(a));
                }
            }
            nb.sort_unstable();
            nb
        };
        // A few runs of nodes a thread, each with its own marks.
        let run = n_nodes
            .div_ceil(4 * rayon::current_num_threads())
            .max(parallel::BOOKKEEPING);
        let lists: Vec<Vec<u32>> = (0..n_nodes.div_ceil(run))
            .into_par_iter()
            .flat_map_iter(|r| {
                let mut seen = vec![u32::MAX; n_nodes];
                (r * run..((r + 1) * run).min(n_nodes)).map(move |b| neighbours_of(&mut seen, b))
            })
            .collect();
        let mut first = Vec::with_capacity(n_nodes + 1);
        first.push(0);
        for l in &lists {
            first.push(first.last().unwrap() + l.len());
        }
        let neighbours: Vec<u32> = lists.into_iter().flatten().collect();
        let mut col_ptr = Vec::with_capacity(D * n_nodes + 1);
        let mut row_idx = Vec::with_capacity(D * D * neighbours.len());
        col_ptr.push(0);
        let dofs = D as u32;
        for b in 0..n_nodes {
            let nb = &neighbours[first[b]..first[b + 1]];
            for _component in 0..D {
                row_idx.extend(
                    nb.iter()
                        .flat_map(|&a| (0..dofs).map(move |i| dofs * a + i)),
                );
                col_ptr.push(row_idx.len());
            }
        }
        drop((touching, incident));
        Self {
            dofs: D,
            first,
            neighbours,
            tiles: PointTiles::build(conn),
            col_ptr,
            row_idx,
        }
    }

    /// Fills every `D x D` block below the diagonal from its mirror above it,
    /// `K(b, a) = K(a, b)^T` for neighbours `a < b`, in parallel over
    /// columns.
    pub(crate) fn mirror_upper(&self, values: &mut [f64]) {
        assert_eq!(values.len(), self.nnz());
        let n_nodes = self.first.len().saturating_sub(1);
        let shared = SharedValues(values.as_mut_ptr());
        (0..n_nodes)
            .into_par_iter()
            .with_min_len(parallel::BOOKKEEPING)
            .for_each(|a| {
                let shared = &shared;
                let nb = &self.neighbours[self.first[a]..self.first[a + 1]];
                let d = self.dofs;
                let stride = d * nb.len();
                let below = nb.partition_point(|&b| b as usize <= a);
                for (k, &b) in nb.iter().enumerate().skip(below) {
                    let (above, stride_b) = self.block(a as u32, b);
                    let at = self.col_ptr[d * a] + d * k;
                    for r in 0..d {
                        for c in 0..d {
                            // SAFETY: both offsets are inside `values` (the
                            // pattern's own places). This task writes only
                            // column a's blocks below the diagonal, which no
                            // other task writes or reads; every task reads
                            // only blocks above it, which none writes.
                            unsafe {
                                *shared.0.add(at + r + c * stride) =
                                    *shared.0.add(above + c + r * stride_b);
                            }
                        }
                    }
                }
            });
    }

    /// The node adjacency the compressed columns are made from, for telling
    /// later whether a pattern is this one ([`Pattern::is`]) without
    /// keeping the columns (eight times its size).
    pub fn adjacency(&self) -> NodeAdjacency {
        NodeAdjacency {
            first: self.first.clone(),
            neighbours: self.neighbours.clone(),
        }
    }

    /// Whether this pattern is the one `adjacency` was taken from (then a
    /// solver's symbolic analysis of one serves the other).
    pub fn is(&self, adjacency: &NodeAdjacency) -> bool {
        self.first == adjacency.first && self.neighbours == adjacency.neighbours
    }

    /// Bytes held on the heap.
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.first.as_slice())
            + size_of_val(self.neighbours.as_slice())
            + self.tiles.heap_bytes()
            + size_of_val(self.col_ptr.as_slice())
            + size_of_val(self.row_idx.as_slice())
    }

    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// DOFs per node.
    pub fn dofs(&self) -> usize {
        self.dofs
    }

    /// Index in the values array of the `D x D` block's entry `(0, 0)` for
    /// row node `a` and column node `b`; entry `(r, c)` is at
    /// `block(a, b) + r + c * D * degree(b)`.
    #[inline]
    pub(crate) fn block(&self, a: u32, b: u32) -> (usize, usize) {
        self.try_block(a, b).expect("linked nodes are neighbours")
    }

    /// Column node `b`'s blocks, for row nodes asked for in ascending order
    /// ([`Column::block`]): a walk along `b`'s sorted neighbours, where
    /// [`Pattern::block`] searches them for each row node anew.
    #[inline]
    pub(crate) fn column(&self, b: u32) -> Column<'_> {
        let neighbours = &self.neighbours[self.first[b as usize]..self.first[b as usize + 1]];
        Column {
            neighbours,
            base: self.col_ptr[self.dofs * b as usize],
            dofs: self.dofs,
            k: 0,
        }
    }

    #[inline]
    fn try_block(&self, a: u32, b: u32) -> Option<(usize, usize)> {
        let nb = &self.neighbours[self.first[b as usize]..self.first[b as usize + 1]];
        let k = nb.binary_search(&a).ok()?;
        let d = self.dofs;
        Some((self.col_ptr[d * b as usize] + d * k, d * nb.len()))
    }

    /// Adds `value` at `(row, col)` (DOF indices); returns false, adding
    /// nothing, if the entry is outside the pattern.
    #[inline]
    pub fn add(&self, values: &mut [f64], row: usize, col: usize, value: f64) -> bool {
        let d = self.dofs;
        match self.try_block((row / d) as u32, (col / d) as u32) {
            Some((base, stride)) => {
                values[base + row % d + (col % d) * stride] += value;
                true
            }
            None => false,
        }
    }
}

/// One column node's blocks in a [`Pattern`] ([`Pattern::column`]).
pub(crate) struct Column<'a> {
    /// The column node's neighbours, sorted.
    neighbours: &'a [u32],
    /// Where its first column starts in the values.
    base: usize,
    /// DOFs per node.
    dofs: usize,
    /// The neighbour the last row node asked for was (the walk's place).
    k: usize,
}

impl Column<'_> {
    /// As [`Pattern::block`] for row node `a`, which must be a neighbour and
    /// no lower than the row node asked for before.
    #[inline]
    pub(crate) fn block(&mut self, a: u32) -> (usize, usize) {
        self.try_block(a).expect("linked nodes are neighbours")
    }

    /// [`Column::block`], or `None` when `a` is not a neighbour.
    #[inline]
    pub(crate) fn try_block(&mut self, a: u32) -> Option<(usize, usize)> {
        while self.neighbours.get(self.k).is_some_and(|&b| b < a) {
            self.k += 1;
        }
        (self.neighbours.get(self.k) == Some(&a)).then(|| {
            (
                self.base + self.dofs * self.k,
                self.dofs * self.neighbours.len(),
            )
        })
    }
}

/// The values of a matrix in a [`Pattern`], shared by tasks that write
/// disjoint places ([`Pattern::mirror_upper`], the stiffness assembly's
/// tiles of one colour).
pub(crate) struct SharedValues(pub(crate) *mut f64);
unsafe impl Sync for SharedValues {}

/// Where one tile's points add to a pattern's values ([`PointTiles::sum_into`]).
pub(crate) struct TileValues<'a> {
    shared: &'a SharedValues,
    len: usize,
}

impl TileValues<'_> {
    /// Adds `value` at `place`.
    #[inline]
    pub(crate) fn add(&mut self, place: usize, value: f64) {
        debug_assert!(place < self.len);
        // SAFETY: `sum_into`'s caller adds only inside the values and in
        // blocks of this tile's points' nodes, which no other tile of this
        // colour has; colours run one after another.
        unsafe { *self.shared.0.add(place) += value }
    }
}

/// The points of a step in tiles of the grid, for an assembly that writes
/// from many points at once without accumulators of its own.
///
/// A point's tile is the square (the cube in 3D) of `side` nodes a side
/// that holds its lowest linked node in each direction, and a tile's
/// colour is the parity of its indices (4 colours in 2D, 8 in 3D). A point's nodes lie within `span` nodes of its
/// lowest ones in each direction (2 for the bilinear basis, 3 for GIMP, 4
/// for cubic B-splines), so the nodes of a tile's points lie within
/// `side + span - 1` nodes of the tile's corner; two tiles of one colour
/// are `2 side` nodes apart, so with `side >= span - 1` their points share
/// no node, and no entry of the tangent. The tiles of one colour can then
/// be summed into in parallel, colour after colour.
#[derive(Debug, Clone, Default)]
pub(crate) struct PointTiles {
    /// The points, tile by tile (in each, in their own order).
    points: Vec<u32>,
    /// Tile `t`'s points are `points[start[t]..start[t + 1]]`.
    start: Vec<usize>,
    /// Colour `c`'s tiles are `colour_start[c]..colour_start[c + 1]`; the
    /// last entry is the count of tiles (`2^D` colours).
    colour_start: Vec<usize>,
}

/// A tile's side in nodes when the points' span is smaller: a few hundred
/// points a tile at four points a cell (enough work a task, and some
/// thousand tiles at a million points to balance over the threads).
const MIN_TILE_SIDE: i64 = 8;

impl PointTiles {
    /// Calls `add_point(p, values)` for every point `p`, the tiles of one
    /// colour in parallel, colour after colour; `values.add(place, value)`
    /// adds to `values` (a pattern's, over the tiles' points).
    ///
    /// # Safety
    ///
    /// `add_point` must add for point `p` only at places inside `values`
    /// in blocks of two of `p`'s linked nodes: two tiles of one colour then
    /// never write the same place (the type's docs).
    pub(crate) unsafe fn sum_into(
        &self,
        values: &mut [f64],
        add_point: impl Fn(usize, &mut TileValues) + Sync,
    ) {
        let shared = SharedValues(values.as_mut_ptr());
        let len = values.len();
        for colour in 0..self.colour_start.len().saturating_sub(1) {
            self.of_colour(colour).into_par_iter().for_each(|t| {
                let mut values = TileValues {
                    shared: &shared,
                    len,
                };
                for &p in self.points(t) {
                    add_point(p as usize, &mut values);
                }
            });
        }
    }

    fn build<const D: usize>(conn: &Connectivity<D>) -> Self {
        let coordinates: Vec<[i64; D]> = conn
            .nodes
            .par_iter()
            .with_min_len(parallel::BOOKKEEPING)
            .map(|&key| lattice_coordinates(key))
            .collect();
        // Each point's lowest node and its span (points that link to no
        // node have none and add nothing).
        let lowest = |p: usize| {
            let links = conn.point_links(p);
            let ends = links
                .iter()
                .fold(([i64::MAX; D], [i64::MIN; D]), |(lo, hi), l| {
                    let c = coordinates[l.node as usize];
                    (
                        std::array::from_fn(|d| lo[d].min(c[d])),
                        std::array::from_fn(|d| hi[d].max(c[d])),
                    )
                });
            (!links.is_empty()).then_some(ends)
        };
        let span = (0..conn.n_points())
            .into_par_iter()
            .with_min_len(parallel::BOOKKEEPING)
            .filter_map(lowest)
            .map(|(lo, hi)| (0..D).map(|d| hi[d] - lo[d] + 1).max().unwrap_or(1))
            .max()
            .unwrap_or(1);
        let side = (span - 1).max(MIN_TILE_SIDE);
        let tile = |p: usize| {
            let (lo, _) = lowest(p)?;
            Some(lo.map(|c| c.div_euclid(side)))
        };
        let tile_min = (0..conn.n_points())
            .into_par_iter()
            .with_min_len(parallel::BOOKKEEPING)
            .filter_map(tile)
            .reduce(
                || [i64::MAX; D],
                |a, b| std::array::from_fn(|d| a[d].min(b[d])),
            );
        // Sorted by colour, then tile, then point: (colour, the tile's
        // places from the lowest, in 60 / D bits each) over the point. A
        // tile's colour is the parity of its places, axis d's bit d.
        let bits = 60 / D as u32;
        let mut keyed: Vec<(u64, u32)> = (0..conn.n_points())
            .into_par_iter()
            .with_min_len(parallel::BOOKKEEPING)
            .filter_map(|p| {
                let t = tile(p)?;
                let mut key = 0u64;
                let mut colour = 0u64;
                for d in 0..D {
                    colour += (t[d].rem_euclid(2) as u64) << d;
                    let place = (t[d] - tile_min[d]) as u64;
                    assert!(place < 1 << bits, "more tiles a side than a key holds");
                    key |= place << (bits * (D - 1 - d) as u32);
                }
                Some((colour << 60 | key, p as u32))
            })
            .collect();
        keyed.par_sort_unstable();
        let colours = 1 << D;
        let mut start = Vec::new();
        let mut colour_start = vec![0; colours + 1];
        for (k, &(key, _)) in keyed.iter().enumerate() {
            if k == 0 || keyed[k - 1].0 != key {
                start.push(k);
                // Colours without tiles start where the next one does.
                for c in &mut colour_start[(key >> 60) as usize + 1..] {
                    *c = start.len();
                }
            }
        }
        colour_start[colours] = start.len();
        start.push(keyed.len());
        Self {
            points: keyed.into_iter().map(|(_, p)| p).collect(),
            start,
            colour_start,
        }
    }

    /// How many tiles there are, of every colour.
    pub(crate) fn count(&self) -> usize {
        self.colour_start.last().copied().unwrap_or(0)
    }

    /// The tiles of colour `colour` (of `2^D`).
    pub(crate) fn of_colour(&self, colour: usize) -> std::ops::Range<usize> {
        self.colour_start[colour]..self.colour_start[colour + 1]
    }

    /// The points of tile `t`.
    pub(crate) fn points(&self, t: usize) -> &[u32] {
        &self.points[self.start[t]..self.start[t + 1]]
    }

    fn heap_bytes(&self) -> usize {
        std::mem::size_of_val(self.points.as_slice()) + std::mem::size_of_val(self.start.as_slice())
    }
}

/// Replaces the rows and columns of fixed DOFs by a scaled identity, so the
/// solve returns zero increments there. Only the fixed DOFs' columns and
/// their rows' blocks are visited (the held nodes are a boundary's few).
pub fn constrain(pattern: &Pattern, values: &mut [f64], fixed: &[bool]) {
    let d = pattern.dofs;
    let diagonal = |dof: usize| {
        let (base, stride) = pattern.block((dof / d) as u32, (dof / d) as u32);
        base + (dof % d) * (1 + stride)
    };
    let mut diag_sum = 0.0;
    let mut diag_count = 0usize;
    for dof in (0..fixed.len()).filter(|&d| !fixed[d]) {
        diag_sum += values[diagonal(dof)].abs();
        diag_count += 1;
    }
    let scale = if diag_count > 0 {
        diag_sum / diag_count as f64
    } else {
        1.0
    };
    for dof in (0..fixed.len()).filter(|&d| fixed[d]) {
        let (a, c) = ((dof / d) as u32, dof % d);
        for k in pattern.col_ptr[dof]..pattern.col_ptr[dof + 1] {
            values[k] = 0.0;
        }
        let nb = &pattern.neighbours[pattern.first[a as usize]..pattern.first[a as usize + 1]];
        for &b in nb {
            let (base, stride) = pattern.block(a, b);
            for column in 0..d {
                values[base + c + column * stride] = 0.0;
            }
        }
        values[diagonal(dof)] = scale;
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::Pattern;
    use crate::fixtures;

    /// The assembly's schedule: every point that links to a node is in one
    /// tile, and no node is linked from two tiles of one colour, for the
    /// widest basis (cubic B-splines, 5 x 5 nodes a point) as for GIMP, on
    /// a body over 6 x 6 tiles cut off-grid (a tile side of 8 nodes
    /// against a span of 5 needs `side >= span - 1`; with a side of 3 the
    /// cubic case fails, checked).
    #[test]
    fn tiles_of_one_colour_share_no_node() {
        for basis in ["gimp", "bspline3"] {
            let mut case = fixtures::block([24.0, 24.0], [96, 96], 0.5, [0.1, 0.13]);
            case["basis"] = basis.into();
            case["bodies"][0]["material"]["density"] = 1.0.into();
            case["supports"] =
                serde_json::json!([ { "on": { "y": 0.0 }, "fix": "xy", "method": "ibm" } ]);
            let sim = fixtures::simulation(&case);
            let conn = sim.reset_grid();
            let tiles = Pattern::build(&conn, &[]).tiles;
            let mut seen = vec![0; conn.n_points()];
            let mut tiles_of_colour = [0; 4];
            for colour in 0..4 {
                let mut owner: HashMap<u32, usize> = HashMap::new();
                for t in tiles.of_colour(colour) {
                    tiles_of_colour[colour] += 1;
                    for &p in tiles.points(t) {
                        seen[p as usize] += 1;
                        for l in conn.point_links(p as usize) {
                            let first = *owner.entry(l.node).or_insert(t);
                            assert_eq!(
                                first, t,
                                "{basis}: node {} in tiles {first} and {t}",
                                l.node
                            );
                        }
                    }
                }
            }
            assert!(
                seen.iter().all(|&n| n == 1),
                "{basis}: a point not in one tile"
            );
            assert!(
                tiles_of_colour.iter().all(|&n| n >= 9),
                "{basis}: {tiles_of_colour:?}"
            );
        }
    }

    /// In 3D: a box of points on GIMP and on quadratic B-splines over an
    /// offset grid. Every pair of nodes a point links holds a 3x3 block
    /// (all nine entries inside the pattern), each column's rows are
    /// sorted, and the tiles of each of the 8 colours share no node while
    /// every point is in exactly one tile.
    #[test]
    fn three_dimensional_patterns_hold_every_block_and_tile_safely() {
        use crate::grid::Basis;
        let (points, grid) = fixtures::solid_box([0.0; 3], [3.0, 2.5, 2.0], 0.125, 0.25);
        for basis in [Basis::Gimp, Basis::BSpline2] {
            let conn = fixtures::solid_links(&points, &grid, basis);
            let pattern = Pattern::build(&conn, &[]);
            assert_eq!(pattern.dofs(), 3);
            assert_eq!(pattern.col_ptr.len(), 3 * conn.n_nodes() + 1);
            for c in 0..3 * conn.n_nodes() {
                let rows = &pattern.row_idx[pattern.col_ptr[c]..pattern.col_ptr[c + 1]];
                assert!(rows.windows(2).all(|w| w[0] < w[1]), "{basis:?} column {c}");
            }
            let mut values = vec![0.0; pattern.nnz()];
            for p in 0..conn.n_points() {
                for la in conn.point_links(p) {
                    for lb in conn.point_links(p) {
                        for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
                            let (row, col) = (3 * la.node as usize + r, 3 * lb.node as usize + c);
                            assert!(pattern.add(&mut values, row, col, 1.0), "{basis:?}");
                        }
                    }
                }
            }
            let tiles = &pattern.tiles;
            let mut seen = vec![0; conn.n_points()];
            let mut owner: HashMap<(usize, u32), usize> = HashMap::new();
            for colour in 0..8 {
                for t in tiles.of_colour(colour) {
                    for &p in tiles.points(t) {
                        seen[p as usize] += 1;
                        for l in conn.point_links(p as usize) {
                            let first = *owner.entry((colour, l.node)).or_insert(t);
                            assert_eq!(first, t, "{basis:?}: node {} in two tiles", l.node);
                        }
                    }
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{basis:?}");
            assert_eq!(tiles.count(), tiles.of_colour(7).end);
        }
    }

    /// In 3D a held DOF's row and column are cleared but for its diagonal,
    /// which takes the mean of the free diagonals' magnitudes, and every
    /// other entry stays (a box on GIMP with the z DOFs of every node
    /// below z = 0.3 held, the values made up).
    #[test]
    fn three_dimensional_held_dofs_become_a_scaled_identity() {
        use super::constrain;
        use crate::grid::Basis;
        let (points, grid) = fixtures::solid_box([0.0; 3], [1.0, 0.75, 0.5], 0.125, 0.25);
        let conn = fixtures::solid_links(&points, &grid, Basis::Gimp);
        let pattern = Pattern::build(&conn, &[]);
        let n = conn.n_dofs();
        let fixed: Vec<bool> = (0..n)
            .map(|dof| dof % 3 == 2 && grid.node_position(conn.nodes[dof / 3])[2] < 0.3)
            .collect();
        assert!(fixed.iter().any(|&f| f) && !fixed.iter().all(|&f| f));
        let before: Vec<f64> = (0..pattern.nnz()).map(|k| 1.0 + (k % 17) as f64).collect();
        let mut after = before.clone();
        constrain(&pattern, &mut after, &fixed);
        let (mut diagonal_sum, mut free) = (0.0, 0.0);
        for col in (0..n).filter(|&c| !fixed[c]) {
            for k in pattern.col_ptr[col]..pattern.col_ptr[col + 1] {
                if pattern.row_idx[k] as usize == col {
                    diagonal_sum += before[k];
                    free += 1.0;
                }
            }
        }
        let scale = diagonal_sum / free;
        for col in 0..n {
            for k in pattern.col_ptr[col]..pattern.col_ptr[col + 1] {
                let row = pattern.row_idx[k] as usize;
                let expected = if row == col && fixed[col] {
                    scale
                } else if fixed[row] || fixed[col] {
                    0.0
                } else {
                    before[k]
                };
                assert_eq!(after[k], expected, "({row}, {col})");
            }
        }
    }
}
