//! Tractions on a 3D body's surface patches ([`super::face_patches`],
//! [`super::surface`]) within a load step: their nodal forces
//! `f_a = int N_a t dA` on the trial surface, and the load stiffness
//! `-df/du`, as the 2D curve's loads ([`super::loading`]) are.
//!
//! - **Quadrature.** Each loaded Bezier cell of a patch is cut, in its
//!   parameters, into quarters while its image in the step's start
//!   configuration straddles a knot plane of the shape functions (the grid
//!   planes; for quadratic B-splines the cells' middles too), down to an
//!   eighth of the cell a side ([`MAX_DEPTH`]); each piece gets 4 x 4
//!   Gauss points. Pieces that end clear of the planes are integrated as
//!   the curve's are; the last ones across a plane carry the kink of the
//!   shape functions inside them, an error in how a force is shared among
//!   nodes (never in its total, which the partition of unity keeps exact,
//!   nor its moment) of the order of the piece's size squared.
//! - **Densities.** With `a = S_s`, `b = S_t`, a follower pressure `p` has
//!   the density `-p a x b` per unit parameter area (the outward normal
//!   times the area element), a dead traction `t` the density `t |a x b|`.
//! - **Motion.** As in 2D, a data point carried by point `p` at reference
//!   offset `d` is at `Q = x_p + F_n d + sum_b w_b u_b` with
//!   `w_b = N_b(x_p) + grad N_b . (F_n d)` in a step from the
//!   configuration `n`: linear in the increment.
//! - **Stiffness.** A cell's forces are differentiated by its 16 control
//!   points exactly (the derivatives of `S` are linear in them); the
//!   control points by each data point by central differences of the
//!   interpolation, remade locally ([`super::surface::Interpolation`]).

use rayon::prelude::*;

use super::face_patches::{DataPoint, FacePatch};
use super::quadrature::{hat_shares, share_nodes};
use super::surface::{BezierPatch, DataGrid, Interpolation, Point3, bernstein, cross};
use crate::assembly::{Pattern, Side, StepTerm};
use crate::configuration::Configuration;
use crate::grid::{Basis, Grid, NodeKey};

/// Quarterings of a loaded cell where it crosses a knot plane.
pub const MAX_DEPTH: usize = 3;

/// The central differences' step of the control points by the data
/// points, in cells: the 2D loads' ([`super::loading`]).
const CONTROL_POINT_STEP: f64 = 1e-7;

/// Gauss-Legendre nodes on [0, 1] and weights (summing to 1), 4 points.
const GAUSS4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_87, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

/// What acts on a region of surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SurfaceTraction {
    /// A fixed force per unit current area (Pa).
    Dead([f64; 3]),
    /// A pressure (Pa, positive pushes into the material) normal to the
    /// current surface: a follower load.
    Pressure(f64),
}

/// `[v]_x`, the matrix of `w -> v x w`.
fn cross_matrix(v: Point3) -> [[f64; 3]; 3] {
    [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]]
}

impl SurfaceTraction {
    /// Force per unit parameter area, given `S_s` and `S_t`.
    fn density(&self, a: Point3, b: Point3) -> Point3 {
        let n = cross(a, b);
        match *self {
            SurfaceTraction::Dead(t) => {
                let area = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                t.map(|v| v * area)
            }
            SurfaceTraction::Pressure(p) => n.map(|v| -p * v),
        }
    }

    /// The derivatives of [`SurfaceTraction::density`] by `S_s` and by
    /// `S_t`: entry `[r][c]` is `d density_r / d S_c`.
    fn density_derivative(&self, a: Point3, b: Point3) -> [[[f64; 3]; 3]; 2] {
        match *self {
            SurfaceTraction::Dead(t) => {
                let n = cross(a, b);
                let area = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                if area == 0.0 {
                    return [[[0.0; 3]; 3]; 2];
                }
                let unit = n.map(|v| v / area);
                // d|n| = unit . (da x b + a x db) = da . (b x unit) + db . (unit x a)
                let (ga, gb) = (cross(b, unit), cross(unit, a));
                [
                    std::array::from_fn(|r| ga.map(|g| t[r] * g)),
                    std::array::from_fn(|r| gb.map(|g| t[r] * g)),
                ]
            }
            // d(-p a x b) = p b x da - p a x db
            SurfaceTraction::Pressure(p) => {
                let (mb, ma) = (cross_matrix(b), cross_matrix(a));
                [
                    mb.map(|row| row.map(|v| p * v)),
                    ma.map(|row| row.map(|v| -p * v)),
                ]
            }
        }
    }
}

/// The derivative of one node's forces by a cell's 16 control points:
/// entry `[a][b][r][c]` is `d f_r / d P_(a b), c`.
pub type ControlNetDerivative = [[[[f64; 3]; 3]; 4]; 4];

/// The quadrature of one loaded Bezier cell in the step's start
/// configuration: Gauss points with their weights and their shares of the
/// active nodes (fixed for the step, as in 2D: `super::traction`).
#[derive(Debug, Clone, Default)]
pub struct CellQuadrature {
    /// `(s, t, weight)` per Gauss point; its node shares are
    /// `shares[first[q]..first[q + 1]]`.
    points: Vec<(f64, f64, f64)>,
    first: Vec<usize>,
    shares: Vec<(usize, f64)>,
    /// The active nodes the shares are of, sorted, and each share's
    /// node's place among them.
    nodes: Vec<usize>,
    place: Vec<u32>,
}

/// The grid whose planes are the knot planes of `basis`'s shape functions.
fn knot_grid(grid: &Grid<3>, basis: Basis) -> Grid<3> {
    match basis {
        Basis::BSpline2 => Grid {
            h: grid.h / 2.0,
            origin: grid.origin,
        },
        _ => *grid,
    }
}

/// `(s, t, weight)` of the Gauss points of a Bezier cell cut at the knot
/// planes of `basis` on `grid` (module docs), the weights per unit
/// parameter area summing to 1.
pub fn gauss_points(patch: &BezierPatch, grid: &Grid<3>, basis: Basis) -> Vec<(f64, f64, f64)> {
    let mut pieces = Vec::new();
    split(
        patch,
        &knot_grid(grid, basis),
        [0.0, 1.0],
        [0.0, 1.0],
        0,
        &mut pieces,
    );
    let mut out = Vec::with_capacity(16 * pieces.len());
    for (s, t) in pieces {
        out.extend(cell_gauss_points().map(|(u, v, w)| {
            (
                s[0] + u * (s[1] - s[0]),
                t[0] + v * (t[1] - t[0]),
                w * (s[1] - s[0]) * (t[1] - t[0]),
            )
        }));
    }
    out
}

/// `(s, t, weight)` of the 4 x 4 Gauss points of the whole unit square.
pub fn cell_gauss_points() -> impl Iterator<Item = (f64, f64, f64)> {
    GAUSS4
        .into_iter()
        .flat_map(|(s, ws)| GAUSS4.into_iter().map(move |(t, wt)| (s, t, ws * wt)))
}

impl CellQuadrature {
    pub fn new(start: &BezierPatch, grid: &Grid<3>, basis: Basis, nodes: &[NodeKey]) -> Self {
        let mut q = CellQuadrature {
            first: vec![0],
            ..Default::default()
        };
        let mut weights = Vec::with_capacity(8);
        for (u, v, w) in gauss_points(start, grid, basis) {
            let x = start.point(u, v);
            if !hat_shares(basis, grid, x, nodes, &mut weights, &mut q.shares) {
                continue;
            }
            q.points.push((u, v, w));
            q.first.push(q.shares.len());
        }
        (q.nodes, q.place) = share_nodes(&q.shares);
        q
    }

    /// The active nodes the cell's forces reach, sorted.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    /// The nodal forces of `traction` (scaled by `factor`) on the cell
    /// whose current control points are `current`, passed to `sink`.
    pub fn forces(
        &self,
        current: &BezierPatch,
        traction: SurfaceTraction,
        factor: f64,
        sink: &mut impl FnMut(usize, Point3),
    ) {
        for (i, &(s, t, w)) in self.points.iter().enumerate() {
            let (_, a, b) = current.evaluate(s, t);
            let density = traction.density(a, b);
            for &(node, share) in &self.shares[self.first[i]..self.first[i + 1]] {
                let k = factor * w * share;
                sink(node, density.map(|v| k * v));
            }
        }
    }

    /// The derivative of [`CellQuadrature::forces`] by the cell's control
    /// points at `current`, one entry per node of [`CellQuadrature::nodes`]
    /// (written over `out`).
    pub fn derivative(
        &self,
        current: &BezierPatch,
        traction: SurfaceTraction,
        factor: f64,
        out: &mut Vec<ControlNetDerivative>,
    ) {
        out.clear();
        out.resize(self.nodes.len(), [[[[0.0; 3]; 3]; 4]; 4]);
        for (i, &(s, t, w)) in self.points.iter().enumerate() {
            let (_, a, b) = current.evaluate(s, t);
            let [da, db] = traction.density_derivative(a, b);
            let (bs, ds) = bernstein(s);
            let (bt, dt) = bernstein(t);
            let range = self.first[i]..self.first[i + 1];
            for (&(_, share), &place) in self.shares[range.clone()].iter().zip(&self.place[range]) {
                let d = &mut out[place as usize];
                let weight = factor * w * share;
                for (m, dm) in d.iter_mut().enumerate() {
                    for (n, dmn) in dm.iter_mut().enumerate() {
                        // S_s = sum ds_m bt_n P_mn, S_t = sum bs_m dt_n P_mn.
                        let (ka, kb) = (weight * ds[m] * bt[n], weight * bs[m] * dt[n]);
                        for r in 0..3 {
                            for c in 0..3 {
                                dmn[r][c] += ka * da[r][c] + kb * db[r][c];
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Appends to `pieces` the parts of `[s] x [t]` of `patch` that lie
/// between knot planes, quartering those that straddle one (a plane
/// strictly inside the range of a 3 x 3 sample of the part, by more than
/// a billionth of a cell: a face on a grid plane straddles none) down to
/// [`MAX_DEPTH`].
fn split(
    patch: &BezierPatch,
    knots: &Grid<3>,
    s: [f64; 2],
    t: [f64; 2],
    depth: usize,
    pieces: &mut Vec<([f64; 2], [f64; 2])>,
) {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for a in 0..3 {
        for b in 0..3 {
            let (u, v) = (
                s[0] + 0.5 * a as f64 * (s[1] - s[0]),
                t[0] + 0.5 * b as f64 * (t[1] - t[0]),
            );
            let x = patch.point(u, v);
            for d in 0..3 {
                let c = (x[d] - knots.origin[d]) / knots.h;
                lo[d] = lo[d].min(c);
                hi[d] = hi[d].max(c);
            }
        }
    }
    let straddles = (0..3).any(|d| (lo[d] + 1e-9).ceil() <= hi[d] - 1e-9);
    if !straddles || depth == MAX_DEPTH {
        pieces.push((s, t));
        return;
    }
    let (sm, tm) = (0.5 * (s[0] + s[1]), 0.5 * (t[0] + t[1]));
    for ss in [[s[0], sm], [sm, s[1]]] {
        for tt in [[t[0], tm], [tm, t[1]]] {
            split(patch, knots, ss, tt, depth + 1, pieces);
        }
    }
}

/// A loaded region: the cells of one face patch a traction acts on.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedCells {
    /// Index into the run's face patches.
    pub patch: usize,
    /// Cells `k + cells_u l` of the patch.
    pub cells: Vec<usize>,
    pub traction: SurfaceTraction,
    /// Held at its full value through the stage, rather than ramped.
    pub held: bool,
}

/// The load stiffness's columns from one data point: as the 2D loads'
/// (`super::loading::DataPointColumns`) with three components.
pub struct DataPointColumns {
    /// Per component `c` of the data point's motion, `(a, d f_a / d Q_c)`
    /// per node `a` its forces reach, in ascending `a`.
    by_component: [Vec<(usize, Point3)>; 3],
    /// `(b, w_b)` per node that moves the data point.
    weights: Vec<(usize, f64)>,
}

impl DataPointColumns {
    fn add_to(&self, pattern: &Pattern, values: &mut [f64]) {
        for (c, df) in self.by_component.iter().enumerate() {
            for &(b, w) in &self.weights {
                let mut column = pattern.column(b as u32);
                for &(a, d) in df {
                    if let Some((base, stride)) = column.try_block(a as u32) {
                        for (r, dr) in d.iter().enumerate() {
                            values[base + r + c * stride] -= dr * w;
                        }
                    }
                }
            }
        }
    }

    /// The entries `(row DOF, column DOF, value)`.
    #[cfg(test)]
    fn entries(&self) -> Vec<(usize, usize, f64)> {
        let mut out = Vec::new();
        for (c, df) in self.by_component.iter().enumerate() {
            for &(b, w) in &self.weights {
                for &(a, d) in df {
                    for (r, dr) in d.iter().enumerate() {
                        out.push((3 * a + r, 3 * b + c, -dr * w));
                    }
                }
            }
        }
        out
    }
}

/// The surface loads of one load step.
pub struct SurfaceLoading<'a> {
    start: Configuration<'a, 3>,
    patches: &'a [FacePatch],
    regions: &'a [LoadedCells],
    load_factor: f64,
    /// Per region, per cell of its patch: its quadrature's place in
    /// `cells`, if loaded. Loads on the same cell share one quadrature, so
    /// the memory is bounded by the surface whatever the loads.
    quadrature: Vec<Vec<Option<usize>>>,
    cells: Vec<CellQuadrature>,
}

impl<'a> SurfaceLoading<'a> {
    pub fn new(
        start: &Configuration<'a, 3>,
        patches: &'a [FacePatch],
        regions: &'a [LoadedCells],
        load_factor: f64,
    ) -> Self {
        let mut loading = Self {
            start: *start,
            patches,
            regions,
            load_factor,
            quadrature: Vec::new(),
            cells: Vec::new(),
        };
        let zero = vec![0.0; start.conn.n_dofs()];
        let mut made: std::collections::BTreeMap<(usize, usize), usize> = Default::default();
        let mut interpolations: std::collections::BTreeMap<usize, Interpolation> =
            Default::default();
        let mut quadrature = Vec::with_capacity(regions.len());
        for region in regions {
            let interpolation = interpolations
                .entry(region.patch)
                .or_insert_with(|| Interpolation::new(loading.trial_grid(region.patch, &zero)));
            let cells = interpolation.grid().cells();
            let mut q = vec![None; cells[0] * cells[1]];
            for &c in &region.cells {
                let place = *made.entry((region.patch, c)).or_insert_with(|| {
                    loading.cells.push(CellQuadrature::new(
                        &interpolation.patch(c % cells[0], c / cells[0]),
                        start.grid,
                        start.basis,
                        &start.conn.nodes,
                    ));
                    loading.cells.len() - 1
                });
                q[c] = Some(place);
            }
            quadrature.push(q);
        }
        loading.quadrature = quadrature;
        loading
    }

    /// Region `r`'s quadrature of cell `c` of its patch, if it loads it.
    fn cell(&self, r: usize, c: usize) -> Option<&CellQuadrature> {
        self.quadrature[r][c].map(|k| &self.cells[k])
    }

    pub fn is_empty(&self) -> bool {
        self.regions.is_empty()
    }

    /// `(node, w_b)`: how a data point moves with each node.
    fn weights(&self, c: &DataPoint) -> impl Iterator<Item = (usize, f64)> + '_ {
        let f = &self.start.points.deformation[c.point];
        let fd: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| f[(i, j)] * c.offset[j]).sum());
        self.start
            .conn
            .point_links(c.point)
            .iter()
            .map(move |link| {
                let g = link.grad;
                (
                    link.node as usize,
                    link.n + g[0] * fd[0] + g[1] * fd[1] + g[2] * fd[2],
                )
            })
    }

    /// Patch `patch`'s data points at increment `u`.
    fn trial_grid(&self, patch: usize, u: &[f64]) -> DataGrid {
        let face = &self.patches[patch];
        let mut grid = face.data_grid(self.start.points);
        for (x, c) in grid.points.iter_mut().zip(&face.data) {
            for (node, w) in self.weights(c) {
                for d in 0..3 {
                    x[d] += w * u[3 * node + d];
                }
            }
        }
        grid
    }

    fn factor(&self, region: &LoadedCells) -> f64 {
        if region.held { 1.0 } else { self.load_factor }
    }

    /// Adds each region's nodal forces at increment `u`, at `factor` of its
    /// traction (none where `factor` gives none), to `f`.
    fn add_forces_at(
        &self,
        u: &[f64],
        f: &mut [f64],
        factor: impl Fn(&LoadedCells) -> Option<f64>,
    ) {
        for (r, region) in self.regions.iter().enumerate() {
            let Some(factor) = factor(region) else {
                continue;
            };
            let interpolation = Interpolation::new(self.trial_grid(region.patch, u));
            let cu = interpolation.grid().cells()[0];
            for &c in &region.cells {
                let q = self.cell(r, c).expect("loaded cells have a quadrature");
                q.forces(
                    &interpolation.patch(c % cu, c / cu),
                    region.traction,
                    factor,
                    &mut |a, force| {
                        for d in 0..3 {
                            f[3 * a + d] += force[d];
                        }
                    },
                );
            }
        }
    }

    /// The load stiffness `-df_ext/du` at increment `u`, data point by data
    /// point.
    pub fn stiffness(&self, u: &[f64]) -> Vec<DataPointColumns> {
        let mut out = Vec::new();
        for (r, region) in self.regions.iter().enumerate() {
            let interpolation = Interpolation::new(self.trial_grid(region.patch, u));
            let [cu, cv] = interpolation.grid().cells();
            let factor = self.factor(region);
            let derivatives: Vec<Vec<ControlNetDerivative>> = (0..cu * cv)
                .into_par_iter()
                .map(|c| {
                    let mut d = Vec::new();
                    if let Some(q) = self.cell(r, c) {
                        q.derivative(
                            &interpolation.patch(c % cu, c / cu),
                            region.traction,
                            factor,
                            &mut d,
                        );
                    }
                    d
                })
                .collect();
            let [nu, nv] = interpolation.grid().counts;
            let columns: Vec<Option<DataPointColumns>> = (0..nu * nv)
                .into_par_iter()
                .map_init(
                    || interpolation.clone(),
                    |moved, k| self.data_point_columns(r, moved, &derivatives, k % nu, k / nu),
                )
                .collect();
            out.extend(columns.into_iter().flatten());
        }
        out
    }

    /// The loaded cells of region `r` that data point `(i, j)` shapes.
    fn affected(&self, r: usize, interpolation: &Interpolation, i: usize, j: usize) -> Vec<usize> {
        let cu = interpolation.grid().cells()[0];
        interpolation
            .patches_near(i, j)
            .into_iter()
            .map(|(k, l)| k + cu * l)
            .filter(|&c| self.quadrature[r][c].is_some())
            .collect()
    }

    /// The entries that come from moving data point `(i, j)` of region
    /// `r`'s patch (`moved` is the trial interpolation, given back as it
    /// came); none when no loaded cell depends on it.
    fn data_point_columns(
        &self,
        r: usize,
        moved: &mut Interpolation,
        derivatives: &[Vec<ControlNetDerivative>],
        i: usize,
        j: usize,
    ) -> Option<DataPointColumns> {
        let affected = self.affected(r, moved, i, j);
        if affected.is_empty() {
            return None;
        }
        let cu = moved.grid().cells()[0];
        let nu = moved.grid().counts[0];
        let eps = CONTROL_POINT_STEP * self.start.grid.h;
        let at = moved.grid().points[i + nu * j];
        let by_component = std::array::from_fn(|c| {
            let mut nets = [Vec::new(), Vec::new()];
            for (net, delta) in nets.iter_mut().zip([eps, -eps]) {
                let mut to = at;
                to[c] += delta;
                moved.move_point(i, j, to);
                *net = affected
                    .iter()
                    .map(|&cell| moved.patch(cell % cu, cell / cu))
                    .collect::<Vec<_>>();
            }
            moved.move_point(i, j, at);
            let mut df: Vec<(usize, Point3)> = Vec::with_capacity(64);
            for (s, &cell) in affected.iter().enumerate() {
                let q = self.cell(r, cell).expect("an affected cell is loaded");
                let (plus, minus) = (&nets[0][s].control, &nets[1][s].control);
                for (&a, dfa) in q.nodes().iter().zip(&derivatives[cell]) {
                    let mut d = [0.0; 3];
                    for m in 0..4 {
                        for n in 0..4 {
                            let dp: Point3 = std::array::from_fn(|e| {
                                (plus[m][n][e] - minus[m][n][e]) / (2.0 * eps)
                            });
                            for (row, dr) in dfa[m][n].iter().zip(d.iter_mut()) {
                                *dr += row[0] * dp[0] + row[1] * dp[1] + row[2] * dp[2];
                            }
                        }
                    }
                    match df.iter_mut().find(|e| e.0 == a) {
                        Some(e) => (0..3).for_each(|x| e.1[x] += d[x]),
                        None => df.push((a, d)),
                    }
                }
            }
            df.sort_unstable_by_key(|e| e.0);
            df
        });
        let data = &self.patches[self.regions[r].patch].data[i + nu * j];
        Some(DataPointColumns {
            by_component,
            weights: self.weights(data).collect(),
        })
    }

    /// Groups of active nodes the load stiffness couples: per data point
    /// that shapes a loaded cell, its point's nodes and the nodes of those
    /// cells' quadrature.
    fn node_groups(&self) -> Vec<Vec<u32>> {
        let zero = vec![0.0; self.start.conn.n_dofs()];
        let mut groups = Vec::new();
        for (r, region) in self.regions.iter().enumerate() {
            let interpolation = Interpolation::new(self.trial_grid(region.patch, &zero));
            let [nu, nv] = interpolation.grid().counts;
            for j in 0..nv {
                for i in 0..nu {
                    let affected = self.affected(r, &interpolation, i, j);
                    if affected.is_empty() {
                        continue;
                    }
                    let data = &self.patches[region.patch].data[i + nu * j];
                    let mut group: Vec<u32> = self.weights(data).map(|(b, _)| b as u32).collect();
                    for &c in &affected {
                        let q = self.cell(r, c).expect("loaded");
                        group.extend(q.nodes().iter().map(|&a| a as u32));
                    }
                    group.sort_unstable();
                    group.dedup();
                    groups.push(group);
                }
            }
        }
        groups
    }
}

/// The surface loads as a step term: tractions whose stiffness is not
/// symmetric once they move with the surface.
impl StepTerm<3> for SurfaceLoading<'_> {
    fn side(&self) -> Side {
        Side::Load
    }

    fn coupling_groups(&self) -> Vec<Vec<u32>> {
        self.node_groups()
    }

    fn add_force(&self, u: &[f64], f: &mut [f64]) {
        let factor = self.load_factor;
        self.add_forces_at(u, f, |s| Some(if s.held { 1.0 } else { factor }));
    }

    fn set_load_factor(&mut self, lambda: f64) {
        self.load_factor = lambda;
    }

    fn add_load_rate(&self, u: &[f64], f: &mut [f64]) {
        self.add_forces_at(u, f, |s| (!s.held).then_some(1.0));
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

#[cfg(test)]
mod tests {
    use super::super::face_patches::face_patches;
    use super::*;
    use crate::fixtures::{solid_box, solid_links};
    use crate::particles::solid_seeding::Solid;

    /// Every cell of every patch of `patches`.
    fn everywhere(patches: &[FacePatch], traction: SurfaceTraction) -> Vec<LoadedCells> {
        (0..patches.len())
            .map(|patch| {
                let cells = patches[patch].data_grid_cells();
                LoadedCells {
                    patch,
                    cells: (0..cells[0] * cells[1]).collect(),
                    traction,
                    held: false,
                }
            })
            .collect()
    }

    fn resultant_and_moment(f: &[f64], grid: &Grid<3>, nodes: &[NodeKey]) -> (Point3, Point3) {
        let (mut r, mut m) = ([0.0; 3], [0.0; 3]);
        for (a, &key) in nodes.iter().enumerate() {
            let x = grid.node_position(key);
            let fa = [f[3 * a], f[3 * a + 1], f[3 * a + 2]];
            let xf = cross(x, fa);
            for d in 0..3 {
                r[d] += fa[d];
                m[d] += xf[d];
            }
        }
        (r, m)
    }

    /// A uniform pressure on a closed surface has no resultant and no
    /// moment, for any grid placement (the shape functions' partition of
    /// unity and linear reproduction make the nodal sums the integrals of
    /// `n` and `x x n` over the surface, which vanish); on one face of a
    /// box its resultant is `-p A n`.
    #[test]
    fn a_pressure_on_a_closed_surface_has_no_resultant_and_no_moment() {
        for (basis, origin) in [
            (Basis::Linear, 0.0),
            (Basis::Gimp, 0.37),
            (Basis::BSpline2, 0.61),
        ] {
            let (mut points, mut grid) = solid_box([0.1, 0.2, 0.3], [1.1, 0.8, 1.0], 0.1, 0.2);
            grid.origin = [0.1 + origin * 0.2, 0.2, 0.3 - origin * 0.1];
            // Deformed (a homogeneous stretch and shear, so the faces are
            // off the grid planes), except on the aligned grid.
            let f = if origin == 0.0 {
                nalgebra::Matrix3::identity()
            } else {
                nalgebra::Matrix3::new(1.1, 0.2, 0.0, 0.0, 0.95, 0.1, 0.05, 0.0, 1.05)
            };
            for p in 0..points.len() {
                let x = f * nalgebra::Vector3::from(points.reference[p]);
                points.position[p] = [x[0], x[1], x[2]];
                points.deformation[p] = f;
            }
            let conn = solid_links(&points, &grid, basis);
            let start = Configuration {
                grid: &grid,
                basis,
                conn: &conn,
                points: &points,
            };
            let solid = Solid::cuboid([0.1, 0.2, 0.3], [1.1, 0.8, 1.0]);
            let patches = face_patches(&points, 0, &solid, 0.1);
            let regions = everywhere(&patches, SurfaceTraction::Pressure(1000.0));
            let loading = SurfaceLoading::new(&start, &patches, &regions, 1.0);
            let mut forces = vec![0.0; conn.n_dofs()];
            loading.add_force(&vec![0.0; conn.n_dofs()], &mut forces);
            let (r, m) = resultant_and_moment(&forces, &grid, &conn.nodes);
            let scale = 1000.0 * 4.0;
            assert!(
                r.iter().all(|v| v.abs() < 1e-10 * scale),
                "{basis:?}: {r:?}"
            );
            // The moment needs the shape functions' linear reproduction,
            // which holds where every node of a Gauss point's cell is
            // active: on the undeformed box on the aligned grid, whose faces
            // lie on grid planes or inside cells that hold points.
            if origin == 0.0 {
                assert!(
                    m.iter().all(|v| v.abs() < 1e-10 * scale),
                    "{basis:?}: {m:?}"
                );
            }
            // The face x = 1.1 alone: its current area vector is
            // det(F) F^-T (0.6 x 0.7 e_x).
            let face = (0..patches.len())
                .find(|&k| {
                    (0..patches[k].data.len()).all(|d| {
                        let c = &patches[k].data[d];
                        (points.reference[c.point][0] + c.offset[0] - 1.1).abs() < 1e-12
                    })
                })
                .expect("the face x = 1.1");
            let one = vec![LoadedCells {
                patch: face,
                ..regions[face].clone()
            }];
            let loading = SurfaceLoading::new(&start, &patches, &one, 1.0);
            let mut forces = vec![0.0; conn.n_dofs()];
            loading.add_force(&vec![0.0; conn.n_dofs()], &mut forces);
            let (r, _) = resultant_and_moment(&forces, &grid, &conn.nodes);
            let area = f.determinant()
                * f.try_inverse().unwrap().transpose()
                * nalgebra::Vector3::new(0.42, 0.0, 0.0);
            for d in 0..3 {
                assert!(
                    (r[d] + 1000.0 * area[d]).abs() < 1e-10 * scale,
                    "{basis:?}: {r:?} against {area:?}"
                );
            }
        }
    }

    /// Two loads on the same cells share their quadrature (memory bounded
    /// by the surface, whatever the loads), and their forces add.
    #[test]
    fn loads_on_the_same_cells_share_their_quadrature() {
        let (points, grid) = solid_box([0.0, 0.0, 0.0], [0.8, 0.6, 0.4], 0.1, 0.2);
        let solid = Solid::cuboid([0.0, 0.0, 0.0], [0.8, 0.6, 0.4]);
        let conn = solid_links(&points, &grid, Basis::Gimp);
        let start = Configuration {
            grid: &grid,
            basis: Basis::Gimp,
            conn: &conn,
            points: &points,
        };
        let patches = face_patches(&points, 0, &solid, 0.1);
        let once = everywhere(&patches, SurfaceTraction::Pressure(10.0));
        let twice: Vec<LoadedCells> = once.iter().chain(&once).cloned().collect();
        let (one, two) = (
            SurfaceLoading::new(&start, &patches, &once, 1.0),
            SurfaceLoading::new(&start, &patches, &twice, 1.0),
        );
        assert_eq!(one.cells.len(), two.cells.len());
        let u: Vec<f64> = (0..conn.n_dofs())
            .map(|i| 1e-3 * (i as f64).sin())
            .collect();
        let (mut f1, mut f2) = (vec![0.0; conn.n_dofs()], vec![0.0; conn.n_dofs()]);
        one.add_force(&u, &mut f1);
        two.add_force(&u, &mut f2);
        assert!(
            f1.iter()
                .zip(&f2)
                .all(|(a, b)| (2.0 * a - b).abs() <= 1e-12 * a.abs().max(1.0))
        );
    }

    /// A dead traction on a whole sphere's surface: its resultant is the
    /// traction times the area, `4 pi R^2`, to the surface's error
    /// (order 4: the area is off by -3.3e-6 at 0.1 m spacing, R = 0.6 m).
    #[test]
    fn a_dead_traction_integrates_the_area() {
        let solid = Solid::SphericalShell {
            center: [0.05, -0.1, 0.2],
            inner_radius: 0.0,
            outer_radius: 0.6,
        };
        let mut points = crate::particles::MaterialPoints::<3>::default();
        let elastic = crate::material::Elastic::from_young_poisson(1e6, 0.3);
        let seeds = crate::particles::solid_seeding::fill(&solid, 0.1);
        points.add_solid(crate::material::Material::Hencky(elastic), 1000.0, &seeds);
        let grid = Grid {
            h: 0.2,
            origin: [0.03, 0.07, -0.11],
        };
        let conn = solid_links(&points, &grid, Basis::Gimp);
        let start = Configuration {
            grid: &grid,
            basis: Basis::Gimp,
            conn: &conn,
            points: &points,
        };
        let patches = face_patches(&points, 0, &solid, 0.1);
        let regions = everywhere(&patches, SurfaceTraction::Dead([0.0, 2.0, -3.0]));
        let loading = SurfaceLoading::new(&start, &patches, &regions, 1.0);
        let mut forces = vec![0.0; conn.n_dofs()];
        loading.add_force(&vec![0.0; conn.n_dofs()], &mut forces);
        let (r, _) = resultant_and_moment(&forces, &grid, &conn.nodes);
        let area = 4.0 * std::f64::consts::PI * 0.36;
        assert!(r[0].abs() < 1e-10, "{r:?}");
        for (d, t) in [(1, 2.0), (2, -3.0)] {
            assert!(
                (r[d] / (t * area) - 1.0).abs() < 1e-5,
                "{r:?} against {}",
                t * area
            );
        }
    }

    /// The load stiffness is the derivative of the forces: against central
    /// differences of them along a direction, on a deformed trial surface,
    /// for a follower pressure and a dead traction.
    #[test]
    fn the_load_stiffness_is_the_derivative_of_the_forces() {
        let (points, grid) = solid_box([0.0, 0.0, 0.0], [0.8, 0.6, 0.4], 0.1, 0.2);
        let solid = Solid::cuboid([0.0, 0.0, 0.0], [0.8, 0.6, 0.4]);
        for basis in [Basis::Gimp, Basis::BSpline2] {
            let conn = solid_links(&points, &grid, basis);
            let start = Configuration {
                grid: &grid,
                basis,
                conn: &conn,
                points: &points,
            };
            let patches = face_patches(&points, 0, &solid, 0.1);
            let n = conn.n_dofs();
            // A smooth trial increment of a few percent of a cell.
            let u: Vec<f64> = (0..n)
                .map(|dof| {
                    let x = grid.node_position(conn.nodes[dof / 3]);
                    0.01 * ((3.0 * x[0] + dof as f64 % 3.0).sin() + (2.0 * x[1] - x[2]).cos())
                })
                .collect();
            let v: Vec<f64> = (0..n)
                .map(|dof| ((dof * 7919) % 13) as f64 / 13.0 - 0.5)
                .collect();
            for traction in [
                SurfaceTraction::Pressure(1e4),
                SurfaceTraction::Dead([3e3, -1e3, 2e3]),
            ] {
                let regions = everywhere(&patches, traction);
                let loading = SurfaceLoading::new(&start, &patches, &regions, 0.7);
                let force = |u: &[f64]| {
                    let mut f = vec![0.0; n];
                    loading.add_force(u, &mut f);
                    f
                };
                let eps = 1e-6;
                let plus: Vec<f64> = u.iter().zip(&v).map(|(a, b)| a + eps * b).collect();
                let minus: Vec<f64> = u.iter().zip(&v).map(|(a, b)| a - eps * b).collect();
                let (fp, fm) = (force(&plus), force(&minus));
                let mut kv = vec![0.0; n];
                for column in loading.stiffness(&u) {
                    for (row, col, value) in column.entries() {
                        kv[row] += value * v[col];
                    }
                }
                let norm = kv.iter().map(|x| x * x).sum::<f64>().sqrt();
                let miss = (0..n)
                    .map(|i| (kv[i] + (fp[i] - fm[i]) / (2.0 * eps)).powi(2))
                    .sum::<f64>()
                    .sqrt()
                    / norm;
                eprintln!("{basis:?} {traction:?}: miss {miss:e} of |K v| = {norm:e}");
                assert!(miss < 1e-6, "{basis:?} {traction:?}: {miss:e}");
            }
        }
    }
}
