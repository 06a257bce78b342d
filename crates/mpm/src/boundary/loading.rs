//! Boundary loads within a load step: their nodal forces on the trial
//! boundary and the derivative of those forces (the load stiffness).
//!
//! The boundary moves with the trial displacement: a loop's data point is
//! its material point's position plus the grid displacement there (plus its
//! offset to the material's edge, mapped by the trial deformation gradient),
//! and the curve through the data points carries the loads. A follower pressure therefore depends on `u`, and so does a
//! dead traction (through the length it acts on); both enter the Newton
//! tangent as `-df_ext/du`. The local cubic scheme makes `f` depend on each
//! `Q_k` only through the six segments around it. A segment's forces are
//! differentiated by its control points exactly (the curve's derivative is
//! linear in them), and its control points by `Q_k` by central differences
//! of the curve's geometry ([`CONTROL_POINT_STEP`]); then chained with
//! `dQ_k/du_b = w_b I` (see [`BoundaryLoading::ring`]).

use rayon::prelude::*;

use super::current_ring;
use super::curve::{DataTangent, MovedPoint, Point, data_tangents, local_segment};
use super::detection::BoundaryLoop;
use super::traction::{ControlPointDerivative, SegmentQuadrature, Traction};
use crate::assembly::{Pattern, Side, StepTerm};
use crate::configuration::Configuration;
use crate::grid::{Connectivity, Grid, node_key};
use crate::particles::MaterialPoints;

/// The central differences' step of the control points by the data
/// points, in cells. The tangents of a straight run bend sharply on the
/// scale of their smoothing (`curve::smooth_abs_cross`), so the truncation
/// error grows as the step squared: on the paper's cantilever bent, the
/// load stiffness misses its differences of the forces by 4e-3 of its
/// largest entry at 1e-4, 4e-7 at 1e-6, 3e-9 at 1e-7, and 4e-8 at 1e-8,
/// where round-off takes over.
const CONTROL_POINT_STEP: f64 = 1e-7;

/// The load stiffness's columns from one data point `Q`: the DOFs that
/// move it, and the rows its motion changes. Entry `(2a + r, 2b + c)` is
/// `-d f_(a, r) / d Q_c w_b`, with `w_b` node `b`'s weight in `Q`.
pub struct DataPointColumns {
    /// Per component `c` of `Q`'s motion, `(a, d f_a / d Q_c)` per node `a`
    /// its forces reach, in ascending `a`.
    by_component: [Vec<(usize, [f64; 2])>; 2],
    /// `(b, w_b)` per node that moves `Q`.
    weights: Vec<(usize, f64)>,
}

impl DataPointColumns {
    /// The entries `(row DOF, column DOF, value)`, column by column.
    #[cfg(test)]
    pub(crate) fn entries(&self) -> Vec<(usize, usize, f64)> {
        let mut out = Vec::new();
        for (c, df) in self.by_component.iter().enumerate() {
            for &(b, w) in &self.weights {
                for &(a, d) in df {
                    out.push((2 * a, 2 * b + c, -d[0] * w));
                    out.push((2 * a + 1, 2 * b + c, -d[1] * w));
                }
            }
        }
        out
    }

    /// Adds the entries to `values`, in `pattern`'s layout; entries
    /// outside the pattern are left out.
    fn add_to(&self, pattern: &Pattern, values: &mut [f64]) {
        for (c, df) in self.by_component.iter().enumerate() {
            for &(b, w) in &self.weights {
                let mut column = pattern.column(b as u32);
                for &(a, d) in df {
                    if let Some((base, stride)) = column.try_block(a as u32) {
                        values[base + c * stride] -= d[0] * w;
                        values[base + 1 + c * stride] -= d[1] * w;
                    }
                }
            }
        }
    }
}

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
    /// current control points are `segment`, at `factor` of the stretch's
    /// traction, passed to `sink`.
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
        let mut affected = Vec::with_capacity(6);
        // A loop of fewer than six points meets a segment twice.
        for j in segments_touching(k, n) {
            if self.quadrature[i][j].is_some() && !affected.contains(&j) {
                affected.push(j);
            }
        }
        affected
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

    /// The load stiffness `-df_ext/du` at increment `u`, data point by
    /// data point, in the loops' order ([`DataPointColumns`]).
    ///
    /// Each loaded segment's forces are differentiated by its control
    /// points exactly ([`SegmentQuadrature::derivative`], once a segment),
    /// and the control points by the data points by central differences
    /// of the curve's geometry alone. The data points are taken in
    /// parallel, each task on its own copy of the trial ring.
    pub fn stiffness(&self, u: &[f64]) -> Vec<DataPointColumns> {
        let mut out = Vec::new();
        for (i, s) in self.stretches.iter().enumerate() {
            let l = &self.loops[s.loop_index];
            let n = l.points.len();
            let ring = self.ring(l, u);
            let tangents = data_tangents(&ring);
            let factor = if s.held { 1.0 } else { self.load_factor };
            let derivatives: Vec<Vec<ControlPointDerivative>> = (0..n)
                .into_par_iter()
                .map(|j| {
                    let mut d = Vec::new();
                    if let Some(q) = &self.quadrature[i][j] {
                        q.derivative(&local_segment(&ring, j), s.traction, factor, &mut d);
                    }
                    d
                })
                .collect();
            let columns: Vec<Option<DataPointColumns>> = (0..n)
                .into_par_iter()
                .map_init(
                    || ring.clone(),
                    |ring, k| self.data_point_columns(i, ring, &tangents, &derivatives, k),
                )
                .collect();
            out.extend(columns.into_iter().flatten());
        }
        out
    }

    /// The load stiffness's entries that come from moving data point `k`
    /// of stretch `i`'s loop (`ring` is its trial ring, given back as it
    /// came, `tangents` the ring's [`data_tangents`], and `derivatives`
    /// its segments' [`SegmentQuadrature::derivative`]); none when no
    /// loaded segment depends on it.
    fn data_point_columns(
        &self,
        i: usize,
        ring: &mut [Point],
        tangents: &[DataTangent],
        derivatives: &[Vec<ControlPointDerivative>],
        k: usize,
    ) -> Option<DataPointColumns> {
        let l = &self.loops[self.stretches[i].loop_index];
        let eps = CONTROL_POINT_STEP * self.grid.h;
        let affected = self.affected(i, k, l.points.len());
        if affected.is_empty() {
            return None;
        }
        let by_component = std::array::from_fn(|c| {
            // How each affected segment's control points move with Q_k,c.
            let at = ring[k][c];
            let mut moved_segments = [[[[0.0; 2]; 4]; 6]; 2];
            for (moved, delta) in moved_segments.iter_mut().zip([eps, -eps]) {
                ring[k][c] = at + delta;
                let moved_point = MovedPoint::new(ring, tangents, k);
                for (m, &j) in moved.iter_mut().zip(&affected) {
                    *m = moved_point.segment(j);
                }
            }
            // Put back as it was (`at + delta - delta` may differ from `at`
            // in the last bit): each task's copy of the ring stays the
            // trial ring, however rayon splits the data points.
            ring[k][c] = at;
            // The contributions summed per node: a few segments, each
            // reaching most of the same nodes.
            let mut df: Vec<(usize, [f64; 2])> = Vec::with_capacity(32);
            for (s, &j) in affected.iter().enumerate() {
                let q = self.quadrature[i][j]
                    .as_ref()
                    .expect("an affected segment is loaded");
                let (plus, minus) = (&moved_segments[0][s], &moved_segments[1][s]);
                let dp: [[f64; 2]; 4] = std::array::from_fn(|m| {
                    [0, 1].map(|d| (plus[m][d] - minus[m][d]) / (2.0 * eps))
                });
                for (&a, dfa) in q.nodes().iter().zip(&derivatives[j]) {
                    let mut d = [0.0; 2];
                    for (dfa_m, dp_m) in dfa.iter().zip(&dp) {
                        for (dr, row) in d.iter_mut().zip(dfa_m) {
                            *dr += row[0] * dp_m[0] + row[1] * dp_m[1];
                        }
                    }
                    match df.iter_mut().find(|e| e.0 == a) {
                        Some(e) => {
                            e.1[0] += d[0];
                            e.1[1] += d[1];
                        }
                        None => df.push((a, d)),
                    }
                }
            }
            df.sort_unstable_by_key(|e| e.0);
            df
        });
        Some(DataPointColumns {
            by_component,
            weights: self.weights(l, k).collect(),
        })
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
        for point in self.stiffness(u) {
            point.add_to(pattern, values);
        }
    }

    fn symmetric(&self) -> bool {
        self.is_empty()
    }
}
