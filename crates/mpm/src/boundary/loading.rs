//! Boundary loads within a load step: their nodal forces on the trial
//! boundary and the derivative of those forces (the load stiffness).
//!
//! The boundary moves with the trial displacement: a loop's data point is
//! its material point's position plus the grid displacement there (plus its
//! offset to the material's edge, mapped by the trial deformation gradient),
//! and the curve through the data points carries the loads. A follower pressure therefore depends on `u`, and so does a
//! dead traction (through the length it acts on); both enter the Newton
//! tangent as `-df_ext/du`. The local cubic scheme makes `f` depend on each
//! `Q_k` only through the six segments around it, so `df/dQ_k` is computed
//! by central differences on those segments (step 1e-6 h: truncation and
//! round-off both near 1e-10 relative), then chained with `dQ_k/du_b =
//! w_b I` (see [`BoundaryLoading::ring`]).

use rayon::prelude::*;

use super::current_ring;
use super::curve::{DataTangent, MovedPoint, Point, data_tangents, local_segment};
use super::detection::BoundaryLoop;
use super::traction::{SegmentQuadrature, Traction};
use crate::assembly::{Pattern, Side, StepTerm};
use crate::configuration::Configuration;
use crate::grid::{Connectivity, Grid, node_key};
use crate::particles::MaterialPoints;

/// The segments of one loop that a boundary load acts on.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedStretch {
    pub loop_index: usize,
    /// Segment `k` runs from the loop's data point `k` to `k + 1`.
    pub segments: Vec<usize>,
    pub traction: Traction,
    /// Held at its full value through the stage (what the stages before
    /// applied), rather than ramped with the load factor (its change over
    /// this stage).
    pub held: bool,
}

/// The boundary loads of one load step.
pub struct BoundaryLoading<'a> {
    grid: &'a Grid,
    conn: &'a Connectivity,
    points: &'a MaterialPoints,
    loops: &'a [BoundaryLoop],
    stretches: &'a [LoadedStretch],
    load_factor: f64,
    /// Per stretch, per data point of its loop: the quadrature of the
    /// segment starting there, if it is loaded.
    quadrature: Vec<Vec<Option<SegmentQuadrature>>>,
}

/// Segments whose shape depends on data point `k` of an `n`-point loop.
fn segments_touching(k: usize, n: usize) -> impl Iterator<Item = usize> {
    (0..6).map(move |i| (k + n + i - 3) % n)
}

impl<'a> BoundaryLoading<'a> {
    /// Prepares the loads of a step: the loaded segments' quadrature in the
    /// step's start configuration.
    pub fn new(
        start: &Configuration<'a>,
        loops: &'a [BoundaryLoop],
        stretches: &'a [LoadedStretch],
        load_factor: f64,
    ) -> Self {
        let Configuration {
            grid,
            basis: start_basis,
            conn,
            points,
        } = *start;
        let mut loading = Self {
            grid,
            conn,
            points,
            loops,
            stretches,
            load_factor,
            quadrature: Vec::new(),
        };
        let zero = vec![0.0; conn.n_dofs()];
        loading.quadrature = stretches
            .iter()
            .map(|s| {
                let l = &loops[s.loop_index];
                let start = loading.ring(l, &zero);
                let mut q = vec![None; l.points.len()];
                for &k in &s.segments {
                    q[k] = Some(SegmentQuadrature::new(
                        &local_segment(&start, k),
                        grid,
                        start_basis,
                        &conn.nodes,
                    ));
                }
                q
            })
            .collect();
        loading
    }

    /// Whether there are boundary loads at all.
    pub fn is_empty(&self) -> bool {
        self.stretches.is_empty()
    }

    /// Trial positions of a loop's data points for increment `u`: with the
    /// offset `d` of data point `k` of point `p`,
    /// `Q_k = x_p + dF F_n d = x_p + F_n d + sum_b w_b u_b`, linear in `u`
    /// with weights `w_b = N_b(x_p) + g_b . (F_n d)`.
    fn ring(&self, l: &BoundaryLoop, u: &[f64]) -> Vec<Point> {
        let mut ring = current_ring(l, self.points);
        for (k, x) in ring.iter_mut().enumerate() {
            for (node, w) in self.weights(l, k) {
                x[0] += w * u[2 * node];
                x[1] += w * u[2 * node + 1];
            }
        }
        ring
    }

    /// `(node, w_b)`: how data point `k` of loop `l` moves with each node.
    fn weights<'b>(
        &'b self,
        l: &'b BoundaryLoop,
        k: usize,
    ) -> impl Iterator<Item = (usize, f64)> + 'b {
        let p = l.points[k];
        let f = &self.points.deformation[p];
        let d = l.offset[k];
        let fd = [
            f[(0, 0)] * d[0] + f[(0, 1)] * d[1],
            f[(1, 0)] * d[0] + f[(1, 1)] * d[1],
        ];
        self.conn.point_links(p).iter().map(move |link| {
            (
                link.node as usize,
                link.n + link.grad[0] * fd[0] + link.grad[1] * fd[1],
            )
        })
    }

    /// The nodal forces of stretch `i` on its loaded segment `k`, whose
    /// current control points are `segment`, passed to `sink`.
    fn segment_forces(
        &self,
        i: usize,
        segment: &[Point; 4],
        k: usize,
        sink: &mut impl FnMut(usize, [f64; 2]),
    ) {
        let stretch = &self.stretches[i];
        let factor = if stretch.held { 1.0 } else { self.load_factor };
        self.segment_forces_at(i, segment, k, factor, sink);
    }

    /// [`Self::segment_forces`] at `factor` of the stretch's traction.
    fn segment_forces_at(
        &self,
        i: usize,
        segment: &[Point; 4],
        k: usize,
        factor: f64,
        sink: &mut impl FnMut(usize, [f64; 2]),
    ) {
        let q = self.quadrature[i][k]
            .as_ref()
            .expect("loaded segments have a quadrature");
        q.forces(segment, self.stretches[i].traction, factor, sink);
    }

    /// The loaded segments of stretch `i` whose shape depends on data point
    /// `k` of its `n`-point loop.
    fn affected(&self, i: usize, k: usize, n: usize) -> Vec<usize> {
        segments_touching(k, n)
            .filter(|&j| self.quadrature[i][j].is_some())
            .collect()
    }

    /// Adds the derivative of the nodal forces at increment `u` by the
    /// load factor to `f`: the ramped stretches' forces at their full
    /// traction (a force is linear in its factor at a given boundary).
    pub fn add_load_rate(&self, u: &[f64], f: &mut [f64]) {
        self.add_forces_at(u, f, |s| (!s.held).then_some(1.0));
    }

    /// Adds the boundary loads' nodal forces at increment `u` to `f`.
    pub fn add_forces(&self, u: &[f64], f: &mut [f64]) {
        let factor = self.load_factor;
        self.add_forces_at(u, f, |s| Some(if s.held { 1.0 } else { factor }));
    }

    /// Adds each stretch's nodal forces at increment `u`, at `factor` of
    /// its traction (none where `factor` gives none), to `f`.
    fn add_forces_at(
        &self,
        u: &[f64],
        f: &mut [f64],
        factor: impl Fn(&LoadedStretch) -> Option<f64>,
    ) {
        for (i, s) in self.stretches.iter().enumerate() {
            let Some(factor) = factor(s) else {
                continue;
            };
            let ring = self.ring(&self.loops[s.loop_index], u);
            for &k in &s.segments {
                self.segment_forces_at(i, &local_segment(&ring, k), k, factor, &mut |a, force| {
                    f[2 * a] += force[0];
                    f[2 * a + 1] += force[1];
                });
            }
        }
    }

    /// Entries `(row DOF, column DOF, value)` of the load stiffness
    /// `-df_ext/du` at increment `u` (duplicates are to be summed).
    ///
    /// The data points are differenced in parallel (24 segment quadratures
    /// each: a third of the paper's case's assembly), their segments made from
    /// the tangents of the trial ring ([`MovedPoint`]), and their entries
    /// come out in their order.
    pub fn stiffness(&self, u: &[f64]) -> Vec<(usize, usize, f64)> {
        let mut out = Vec::new();
        for (i, s) in self.stretches.iter().enumerate() {
            let l = &self.loops[s.loop_index];
            let n = l.points.len();
            let ring = self.ring(l, u);
            let tangents = data_tangents(&ring);
            let entries: Vec<Vec<(usize, usize, f64)>> = (0..n)
                .into_par_iter()
                .map_init(
                    || ring.clone(),
                    |ring, k| self.data_point_stiffness(i, ring, &tangents, k),
                )
                .collect();
            out.extend(entries.into_iter().flatten());
        }
        out
    }

    /// The entries of the load stiffness that come from moving data point
    /// `k` of stretch `i`'s loop (`ring` is its trial ring, given back as
    /// it came, and `tangents` the ring's [`data_tangents`]).
    fn data_point_stiffness(
        &self,
        i: usize,
        ring: &mut [Point],
        tangents: &[DataTangent],
        k: usize,
    ) -> Vec<(usize, usize, f64)> {
        let l = &self.loops[self.stretches[i].loop_index];
        let eps = 1e-6 * self.grid.h;
        let mut out = Vec::new();
        let affected = self.affected(i, k, l.points.len());
        if affected.is_empty() {
            return out;
        }
        let weights: Vec<(usize, f64)> = self.weights(l, k).collect();
        for c in 0..2 {
            // The contributions summed per node before they are spread
            // over the columns: a few nodes, many quadrature points.
            let mut df: Vec<(usize, [f64; 2])> = Vec::with_capacity(16);
            let at = ring[k][c];
            for (sign, delta) in [(1.0, eps), (-1.0, -eps)] {
                ring[k][c] = at + delta;
                let moved = MovedPoint::new(ring, tangents, k);
                for &j in &affected {
                    self.segment_forces(i, &moved.segment(j), j, &mut |a, force| {
                        let d = [sign * force[0] / (2.0 * eps), sign * force[1] / (2.0 * eps)];
                        match df.iter_mut().find(|e| e.0 == a) {
                            Some(e) => {
                                e.1[0] += d[0];
                                e.1[1] += d[1];
                            }
                            None => df.push((a, d)),
                        }
                    });
                }
            }
            // Put back as it was (`at + delta - delta` may differ from `at`
            // in the last bit): each task's copy of the ring stays the
            // trial ring, however rayon splits the data points.
            ring[k][c] = at;
            df.sort_unstable_by_key(|e| e.0);
            for (a, d) in df {
                for &(node, w) in &weights {
                    let col = 2 * node + c;
                    out.push((2 * a, col, -d[0] * w));
                    out.push((2 * a + 1, col, -d[1] * w));
                }
            }
        }
        out
    }

    /// Groups of active nodes that the load stiffness may couple: for each
    /// data point, its material point's nodes and the active nodes within a
    /// cell of the segments it shapes. The stiffness pattern must contain
    /// every pair within a group.
    fn node_groups(&self) -> Vec<Vec<u32>> {
        let zero = vec![0.0; self.conn.n_dofs()];
        let mut groups = Vec::new();
        for (i, s) in self.stretches.iter().enumerate() {
            let l = &self.loops[s.loop_index];
            let n = l.points.len();
            let ring = self.ring(l, &zero);
            for k in 0..n {
                let affected = self.affected(i, k, n);
                if affected.is_empty() {
                    continue;
                }
                let mut lo = [f64::INFINITY; 2];
                let mut hi = [f64::NEG_INFINITY; 2];
                for &j in &affected {
                    for p in local_segment(&ring, j) {
                        for d in 0..2 {
                            lo[d] = lo[d].min(p[d]);
                            hi[d] = hi[d].max(p[d]);
                        }
                    }
                }
                let first = self.grid.cell_of(lo).map(|c| c - 1);
                let (g, h) = (self.grid, self.grid.h);
                let last = |d: usize| ((hi[d] - g.origin[d]) / h).ceil() as i64 + 1;
                let mut group: Vec<u32> = self
                    .conn
                    .point_links(l.points[k])
                    .iter()
                    .map(|link| link.node)
                    .collect();
                for i in first[0]..=last(0) {
                    for j in first[1]..=last(1) {
                        if let Ok(a) = self.conn.nodes.binary_search(&node_key(i, j)) {
                            group.push(a as u32);
                        }
                    }
                }
                group.sort_unstable();
                group.dedup();
                groups.push(group);
            }
        }
        groups
    }
}

/// The boundary loads as a step term: tractions on the body, whose
/// stiffness is not symmetric once they move with the boundary.
impl StepTerm for BoundaryLoading<'_> {
    fn side(&self) -> Side {
        Side::Load
    }

    fn coupling_groups(&self) -> Vec<Vec<u32>> {
        self.node_groups()
    }

    fn add_force(&self, u: &[f64], f: &mut [f64]) {
        self.add_forces(u, f);
    }

    fn set_load_factor(&mut self, lambda: f64) {
        self.load_factor = lambda;
    }

    fn add_load_rate(&self, u: &[f64], f: &mut [f64]) {
        BoundaryLoading::add_load_rate(self, u, f);
    }

    fn add_stiffness(&self, u: &[f64], pattern: &Pattern, values: &mut [f64]) {
        for (row, col, value) in self.stiffness(u) {
            pattern.add(values, row, col, value);
        }
    }

    fn symmetric(&self) -> bool {
        self.is_empty()
    }
}
