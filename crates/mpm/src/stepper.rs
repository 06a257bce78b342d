//! The load-step loop of implicit quasi-static MPM.
//!
//! For each load step `k` of `n` (load factor `k/n`):
//! 1. reset the grid: shape functions at the points' current positions, the
//!    active nodes and the stiffness pattern ([`Connectivity`], [`Pattern`]);
//! 2. external forces and constrained DOFs on the active nodes; boundary
//!    loads on the B-spline, which move with the trial displacement
//!    ([`BoundaryLoading`]); the soft background of the cells the material
//!    touches ([`SoftCells`]);
//! 3. Newton-Raphson for the incremental nodal displacements ([`newton`]);
//! 4. move the points and probes with the converged grid displacement and
//!    commit their deformation, history and stress.

use std::time::Instant;

use nalgebra::Matrix2;
use rayon::prelude::*;

use crate::assembly::{self, Connectivity, Pattern, SoftCells};
use crate::basis::{Basis, Grid};
use crate::boundary::ibm::{self, Anchor, BandTerms};
use crate::boundary::loading::{BoundaryLoading, LoadedStretch, select};
use crate::boundary::{BoundaryLoop, find_loops, selected_segments, set_offsets};
use crate::case::{Case, CaseError, Support, SupportMethod};
use crate::linsolve::{Factorisation, SparseSolver};
use crate::material::Response;
use crate::newton::{self, Equilibrium, InvertedPoint, NewtonSettings, SolveError};
use crate::observer::{Observer, StepState};
use crate::output::{ProbeReport, RunReport, StepReport, StepTimings};
use crate::points::MaterialPoints;

/// Named reference points that move with the grid displacement.
#[derive(Debug, Clone, Default)]
pub struct Probes {
    pub names: Vec<String>,
    pub reference: Vec<[f64; 2]>,
    pub position: Vec<[f64; 2]>,
}

/// A case made ready to run: points, grid, loads and supports.
pub struct Simulation {
    pub grid: Grid,
    pub basis: Basis,
    /// The grid's extent `(min, max)`, if bounded: nodes outside it do not
    /// exist, and material must stay inside it.
    pub extent: Option<([f64; 2], [f64; 2])>,
    pub points: MaterialPoints,
    /// Boundary loops of the material points, found once (Lagrangian).
    pub loops: Vec<BoundaryLoop>,
    pub probes: Probes,
    gravity: [f64; 2],
    /// `(point, force)`: each point load rides on its nearest material point.
    point_loads: Vec<(usize, [f64; 2])>,
    /// Loads on stretches of the boundary curves.
    boundary_loads: Vec<LoadedStretch>,
    /// Quadrature points of the supports imposed on the boundary curves by
    /// the implicit boundary method, and the band width `delta` they use.
    anchors: Vec<Anchor>,
    band_width: f64,
    supports: Vec<Support>,
    pub settings: NewtonSettings,
    pub load_steps: usize,
}

impl Simulation {
    /// Builds the initial state of a validated case. Fails, naming the
    /// field, when a boundary load selects no stretch of any body's boundary
    /// (which could not be told before the points were generated).
    pub fn new(case: &Case) -> Result<Self, CaseError> {
        let grid = Grid {
            h: case.grid.cell_size,
            origin: case.grid.origin,
        };
        let points = MaterialPoints::from_case(case);
        let extent = case.grid.extent.map(|b| (b.min, b.max));
        let mut loops = find_loops(&points.lattice, &points.material, &points.reference);
        set_offsets(&mut loops, &points, case.boundary.representation);
        let boundary_selectors = (case.loads.boundary.iter().enumerate())
            .map(|(i, l)| (format!("loads.boundary[{i}].on"), &l.on))
            .chain(
                (case.supports.iter().enumerate())
                    .filter(|(_, s)| s.method == SupportMethod::Ibm)
                    .map(|(i, s)| (format!("supports[{i}].on"), &s.on)),
            );
        for (path, on) in boundary_selectors {
            if selected_segments(on, &loops, &points, grid.h).is_empty() {
                return Err(CaseError {
                    path,
                    message:
                        "selects no stretch of any body's boundary (it must pass within about \
                              a point spacing of two neighbouring outer points)"
                            .into(),
                });
            }
        }
        let point_loads = case
            .loads
            .point_loads
            .iter()
            .map(|l| (nearest_point(&points, l.at), l.force))
            .collect();
        Ok(Self {
            grid,
            basis: case.basis.into(),
            extent,
            probes: Probes {
                names: case.probes.iter().map(|p| p.name.clone()).collect(),
                reference: case.probes.iter().map(|p| p.at).collect(),
                position: case.probes.iter().map(|p| p.at).collect(),
            },
            boundary_loads: select(&case.loads.boundary, &loops, &points, grid.h),
            anchors: ibm::anchors(&case.supports, &loops, &points, &grid),
            band_width: case
                .boundary
                .band_width
                .unwrap_or(ibm::DEFAULT_BAND_WIDTH * grid.h),
            loops,
            points,
            gravity: case.loads.gravity.unwrap_or([0.0, 0.0]),
            point_loads,
            supports: case.supports.clone(),
            settings: NewtonSettings {
                tolerance: case.analysis.newton.tolerance,
                max_iterations: case.analysis.newton.max_iterations as usize,
                tangent_regularisation: case.analysis.newton.tangent_regularisation,
                ..Default::default()
            },
            load_steps: case.analysis.load_steps as usize,
        })
    }

    /// Runs every load step, reporting each to `observer`.
    pub fn run(&mut self, observer: &mut dyn Observer) -> Result<RunReport, SolveError> {
        let start = Instant::now();
        let mut steps = Vec::with_capacity(self.load_steps);
        for step in 1..=self.load_steps {
            observer.step_started(step, self.load_steps);
            let report = self.load_step(step, observer)?;
            observer.step_finished(
                &report,
                &StepState {
                    points: &self.points,
                    loops: &self.loops,
                },
            );
            steps.push(report);
        }
        Ok(RunReport {
            points: self.points.len(),
            load_steps: self.load_steps,
            wall_seconds: start.elapsed().as_secs_f64(),
            steps,
        })
    }

    /// One load step, as in the module docs.
    pub fn load_step(
        &mut self,
        step: usize,
        observer: &mut dyn Observer,
    ) -> Result<StepReport, SolveError> {
        let started = Instant::now();
        self.check_inside_extent(step - 1)?;
        let load_factor = step as f64 / self.load_steps as f64;

        let conn = Connectivity::build(&self.grid, self.basis, &self.points, |node| {
            self.node_in_grid(node)
        });
        let (boundary, pattern) = self.boundary_terms(&conn, load_factor);
        let fixed = self.constrained_dofs(&conn);
        let f_ext = self.external_force(&conn, load_factor);
        let soft = self.soft_cells(&conn);
        let grid_seconds = started.elapsed().as_secs_f64();

        let mut eq =
            StepEquilibrium::new(&conn, &pattern, &self.points, &fixed, f_ext, soft, boundary);
        let (u, newton) = newton::solve(&mut eq, &self.settings, step, observer)?;

        let update_start = Instant::now();
        let mut reactions = self.reactions(&conn, &eq.f_int, &eq.f_ext);
        let band_reactions = eq
            .band
            .reactions(&self.anchors, &u, &fixed, self.supports.len());
        for (r, b) in reactions.iter_mut().zip(band_reactions) {
            r[0] += b[0];
            r[1] += b[1];
        }
        let mut timings = eq.timings;
        timings.grid = grid_seconds;
        let applied_load = [0, 1].map(|c| eq.f_ext.iter().skip(c).step_by(2).sum());
        let responses = std::mem::take(&mut eq.responses);
        let band = std::mem::take(&mut eq.band);
        self.update_points(&conn, &u, &responses);
        self.advect_probes(&conn, &u);
        band.advance(&mut self.anchors, &u, |p| {
            increment(conn.point_links(p), &u).0
        });
        timings.update = update_start.elapsed().as_secs_f64();
        timings.total = started.elapsed().as_secs_f64();

        Ok(StepReport {
            step,
            load_factor,
            newton,
            timings,
            active_nodes: conn.n_nodes(),
            active_dofs: conn.n_dofs() - fixed.iter().filter(|f| **f).count(),
            probes: self.probe_reports(),
            reactions,
            applied_load,
        })
    }

    /// The boundary curves' loads and IBM supports in a step, and the
    /// stiffness pattern with the couplings they add.
    fn boundary_terms<'a>(
        &'a self,
        conn: &'a Connectivity,
        load_factor: f64,
    ) -> (BoundaryTerms<'a>, Pattern) {
        let loading = BoundaryLoading::new(
            &self.grid,
            conn,
            &self.points,
            &self.loops,
            &self.boundary_loads,
            load_factor,
        );
        let band = BandTerms::new(
            &self.anchors,
            &self.loops,
            &self.points,
            conn,
            &self.grid,
            self.band_width,
            load_factor,
        );
        let mut groups = loading.coupling_groups();
        groups.extend(band.coupling_groups());
        let pattern = Pattern::build(conn, &groups);
        (BoundaryTerms { loading, band }, pattern)
    }

    /// Whether a node lies in the grid's extent (with a tolerance of 1e-9 h).
    fn node_in_grid(&self, node: crate::basis::NodeKey) -> bool {
        let Some((lo, hi)) = self.extent else {
            return true;
        };
        let x = self.grid.node_position(node);
        let tol = 1e-9 * self.grid.h;
        (0..2).all(|d| x[d] >= lo[d] - tol && x[d] <= hi[d] + tol)
    }

    /// Material must stay inside the extent, or, on an unbounded grid, within
    /// the range of node indices (2^30 cells from the origin).
    fn check_inside_extent(&self, step: usize) -> Result<(), SolveError> {
        let reach = self.grid.h * (1u64 << 30) as f64;
        let o = self.grid.origin;
        let (lo, hi) = self
            .extent
            .unwrap_or(([o[0] - reach, o[1] - reach], [o[0] + reach, o[1] + reach]));
        match self
            .points
            .position
            .iter()
            .position(|x| !(x[0] >= lo[0] && x[0] <= hi[0] && x[1] >= lo[1] && x[1] <= hi[1]))
        {
            Some(point) => {
                let [x, y] = self.points.position[point];
                Err(SolveError::LeftGrid { step, point, x, y })
            }
            None => Ok(()),
        }
    }

    /// DOF mask of the grid-node supports: a node is on a support when the
    /// support's selector contains the node's position (tolerance 1e-9 h).
    fn constrained_dofs(&self, conn: &Connectivity) -> Vec<bool> {
        let tol = 1e-9 * self.grid.h;
        let mut fixed = vec![false; conn.n_dofs()];
        for (a, &key) in conn.nodes.iter().enumerate() {
            let x = self.grid.node_position(key);
            for s in self.grid_supports().filter(|s| s.on.contains(x, tol)) {
                for c in 0..2 {
                    fixed[2 * a + c] |= s.fix.holds(c);
                }
            }
        }
        fixed
    }

    /// The soft background of the tangent, with the stiffest material's
    /// constants scaled by the regularisation ratio.
    fn soft_cells(&self, conn: &Connectivity) -> Option<SoftCells> {
        let ratio = self.settings.tangent_regularisation;
        if ratio == 0.0 {
            return None;
        }
        let stiffest = self
            .points
            .materials
            .iter()
            .map(|m| m.elastic())
            .max_by(|a, b| (a.lambda + 2.0 * a.mu).total_cmp(&(b.lambda + 2.0 * b.mu)))?;
        Some(SoftCells::new(
            &self.grid,
            conn,
            &self.points,
            self.basis,
            stiffest.lambda,
            stiffest.mu,
            ratio,
        ))
    }

    /// The supports imposed on grid nodes.
    fn grid_supports(&self) -> impl Iterator<Item = &Support> {
        self.supports
            .iter()
            .filter(|s| s.method == SupportMethod::Grid)
    }

    /// Body force and point loads, scaled by the load factor.
    fn external_force(&self, conn: &Connectivity, load_factor: f64) -> Vec<f64> {
        let g = self.gravity.map(|g| g * load_factor);
        let mut f = if g == [0.0, 0.0] {
            vec![0.0; conn.n_dofs()]
        } else {
            assembly::body_force(conn, &self.points, g)
        };
        for &(p, force) in &self.point_loads {
            for l in conn.point_links(p) {
                for c in 0..2 {
                    f[2 * l.node as usize + c] += load_factor * l.n * force[c];
                }
            }
        }
        f
    }

    /// Per support: the force the support exerts on the body, summed over its
    /// constrained DOFs, `f_int - f_ext`.
    fn reactions(&self, conn: &Connectivity, f_int: &[f64], f_ext: &[f64]) -> Vec<[f64; 2]> {
        let tol = 1e-9 * self.grid.h;
        self.supports
            .iter()
            .map(|s| {
                let mut r = [0.0; 2];
                if s.method != SupportMethod::Grid {
                    return r; // from the band terms
                }
                for (a, &key) in conn.nodes.iter().enumerate() {
                    if s.on.contains(self.grid.node_position(key), tol) {
                        for (c, rc) in r.iter_mut().enumerate() {
                            if s.fix.holds(c) {
                                *rc += f_int[2 * a + c] - f_ext[2 * a + c];
                            }
                        }
                    }
                }
                r
            })
            .collect()
    }

    /// Moves each point with the grid displacement and commits its state.
    fn update_points(&mut self, conn: &Connectivity, u: &[f64], responses: &[Response]) {
        let mp = &mut self.points;
        (
            &mut mp.position,
            &mut mp.deformation,
            &mut mp.history,
            &mut mp.stress,
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(p, (x, f, history, stress))| {
                let (dx, grad_u) = increment(conn.point_links(p), u);
                let df = Matrix2::identity() + grad_u;
                x[0] += dx[0];
                x[1] += dx[1];
                *f = df * *f;
                *history = responses[p].history;
                *stress = responses[p].cauchy;
            });
    }

    /// Moves each probe with the bilinear interpolation of the grid
    /// displacement over the active nodes of its cell (renormalised if some
    /// are inactive; a probe away from all material stays where it is).
    fn advect_probes(&mut self, conn: &Connectivity, u: &[f64]) {
        let mut weights = Vec::new();
        for x in &mut self.probes.position {
            weights.clear();
            Basis::Linear.eval(&self.grid, *x, [0.0, 0.0], &mut weights);
            let mut sum = 0.0;
            let mut d = [0.0; 2];
            for w in &weights {
                if let Ok(a) = conn.nodes.binary_search(&w.node) {
                    sum += w.n;
                    d[0] += w.n * u[2 * a];
                    d[1] += w.n * u[2 * a + 1];
                }
            }
            if sum > 0.0 {
                x[0] += d[0] / sum;
                x[1] += d[1] / sum;
            }
        }
    }

    fn probe_reports(&self) -> Vec<ProbeReport> {
        let p = &self.probes;
        (0..p.names.len())
            .map(|i| ProbeReport {
                name: p.names[i].clone(),
                position: p.position[i],
                displacement: [
                    p.position[i][0] - p.reference[i][0],
                    p.position[i][1] - p.reference[i][1],
                ],
            })
            .collect()
    }
}

/// Index of the point nearest to `x`.
fn nearest_point(points: &MaterialPoints, x: [f64; 2]) -> usize {
    let d2 = |p: &[f64; 2]| (p[0] - x[0]).powi(2) + (p[1] - x[1]).powi(2);
    (0..points.len())
        .min_by(|&a, &b| d2(&points.position[a]).total_cmp(&d2(&points.position[b])))
        .unwrap_or(0)
}

/// Displacement `sum_a N_a u_a` and displacement gradient
/// `grad_u = sum_a u_a (x) g_a` of a point (`dF = I + grad_u`).
fn increment(links: &[assembly::Link], u: &[f64]) -> ([f64; 2], Matrix2<f64>) {
    let mut dx = [0.0; 2];
    let mut df = Matrix2::zeros();
    for l in links {
        let ua = [u[2 * l.node as usize], u[2 * l.node as usize + 1]];
        for i in 0..2 {
            dx[i] += l.n * ua[i];
            for j in 0..2 {
                df[(i, j)] += ua[i] * l.grad[j];
            }
        }
    }
    (dx, df)
}

/// The equilibrium equations of one load step, as Newton sees them.
struct StepEquilibrium<'a> {
    conn: &'a Connectivity,
    pattern: &'a Pattern,
    points: &'a MaterialPoints,
    fixed: &'a [bool],
    soft: Option<SoftCells>,
    /// Boundary loads, evaluated on the trial boundary.
    loading: BoundaryLoading<'a>,
    /// Implicit-boundary supports.
    band: BandTerms,
    /// `BandTerms::load_norm`, once per step.
    band_load: f64,
    /// The band terms' forces at the last trial state (kept apart from
    /// `f_int`, from which grid supports take their reactions).
    f_band: Vec<f64>,
    /// Loads that do not depend on the displacement (gravity, point loads).
    f_ext_fixed: Vec<f64>,
    /// All external forces at the last trial state.
    f_ext: Vec<f64>,
    /// The last trial increment.
    u: Vec<f64>,
    f_int: Vec<f64>,
    responses: Vec<Response>,
    solver: SparseSolver,
    timings: StepTimings,
}

/// What the boundary curves contribute to a step: loads and IBM supports.
struct BoundaryTerms<'a> {
    loading: BoundaryLoading<'a>,
    band: BandTerms,
}

impl<'a> StepEquilibrium<'a> {
    fn new(
        conn: &'a Connectivity,
        pattern: &'a Pattern,
        points: &'a MaterialPoints,
        fixed: &'a [bool],
        f_ext: Vec<f64>,
        soft: Option<SoftCells>,
        BoundaryTerms { loading, band }: BoundaryTerms<'a>,
    ) -> Self {
        Self {
            conn,
            pattern,
            points,
            fixed,
            soft,
            loading,
            band_load: band.load_norm(conn.n_dofs()),
            f_band: vec![0.0; conn.n_dofs()],
            band,
            f_ext: f_ext.clone(),
            f_ext_fixed: f_ext,
            u: Vec::new(),
            f_int: Vec::new(),
            responses: Vec::new(),
            solver: SparseSolver::new(conn.n_dofs()),
            timings: StepTimings::default(),
        }
    }
}

impl Equilibrium for StepEquilibrium<'_> {
    fn n_dofs(&self) -> usize {
        self.conn.n_dofs()
    }

    /// The point loop: trial stress and tangent of every point, in parallel,
    /// then the internal force.
    fn out_of_balance(&mut self, u: &[f64]) -> Result<(Vec<f64>, f64), InvertedPoint> {
        let t = Instant::now();
        self.u.clear();
        self.u.extend_from_slice(u);
        let (conn, mp) = (self.conn, self.points);
        self.responses = (0..mp.len())
            .into_par_iter()
            .map(|p| {
                let (_, grad_u) = increment(conn.point_links(p), u);
                let j_start = mp.deformation[p].determinant();
                let jacobian = j_start * (Matrix2::identity() + grad_u).determinant();
                if jacobian.is_nan() || jacobian <= 0.0 {
                    return Err(InvertedPoint { point: p, jacobian });
                }
                let material = &mp.materials[mp.material[p] as usize];
                Ok(material.respond(&mp.history[p], &grad_u, j_start))
            })
            .collect::<Result<_, _>>()?;
        self.f_int = assembly::internal_force(conn, mp, &self.responses);
        // Forces are measured against the material's own internal force
        // (which includes the reactions), the loads, and what prescribed
        // displacements ask of the material (`BandTerms::load_norm`); the
        // band forces themselves are a stiff penalty's and would loosen the
        // balance by h / delta.
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let material_norm = norm(&self.f_int);
        if !self.loading.is_empty() {
            self.f_ext.clone_from(&self.f_ext_fixed);
            self.loading.add_forces(u, &mut self.f_ext);
        }
        if let Some(soft) = &self.soft {
            soft.add_force(u, &mut self.f_int);
        }
        self.f_band.fill(0.0);
        self.band.add_forces(u, &mut self.f_band);
        let scale = norm(&self.f_ext)
            .max(material_norm)
            .max(self.band_load)
            .max(f64::MIN_POSITIVE);
        let r = (0..u.len())
            .map(|i| {
                if self.fixed[i] {
                    0.0
                } else {
                    self.f_ext[i] - self.f_int[i] - self.f_band[i]
                }
            })
            .collect();
        self.timings.point_loop += t.elapsed().as_secs_f64();
        Ok((r, scale))
    }

    fn correction(&mut self, r: &[f64]) -> Result<(Vec<f64>, Factorisation), String> {
        let t = Instant::now();
        let mut k = assembly::stiffness(self.conn, self.pattern, self.points, &self.responses);
        if let Some(soft) = &self.soft {
            soft.add_to(self.pattern, &mut k);
        }
        self.band.add_stiffness(self.pattern, &mut k);
        // Boundary loads move with the boundary: their load stiffness makes
        // the tangent non-symmetric. Hyperelastic materials under loads that
        // do not move have a symmetric tangent.
        let symmetric = self.loading.is_empty();
        for (row, col, value) in self.loading.stiffness(&self.u) {
            self.pattern.add(&mut k, row, col, value);
        }
        assembly::constrain(self.pattern, &mut k, self.fixed);
        self.timings.assembly += t.elapsed().as_secs_f64();
        let (du, kind, timing) = self.solver.solve(self.pattern, &k, r, symmetric)?;
        self.timings.factorisation += timing.factorise;
        self.timings.solve += timing.solve;
        if du.iter().any(|v| !v.is_finite()) {
            return Err("the solution has non-finite entries (singular tangent)".into());
        }
        Ok((du, kind))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::newton::Equilibrium;

    /// Condition number (2-norm) of the first step's tangent on the free
    /// DOFs, from the dense inverse built column by column with the
    /// step's own solver.
    fn first_tangent_condition(case: &Case) -> f64 {
        let sim = Simulation::new(case).unwrap();
        let load_factor = 1.0 / sim.load_steps as f64;
        let conn = Connectivity::build(&sim.grid, sim.basis, &sim.points, |n| sim.node_in_grid(n));
        let (boundary, pattern) = sim.boundary_terms(&conn, load_factor);
        let fixed = sim.constrained_dofs(&conn);
        let f_ext = sim.external_force(&conn, load_factor);
        let mut eq = StepEquilibrium::new(
            &conn,
            &pattern,
            &sim.points,
            &fixed,
            f_ext,
            sim.soft_cells(&conn),
            boundary,
        );
        let n = conn.n_dofs();
        eq.out_of_balance(&vec![0.0; n]).unwrap();
        let free: Vec<usize> = (0..n).filter(|&i| !fixed[i]).collect();
        let mut inverse = nalgebra::DMatrix::zeros(free.len(), free.len());
        for (j, &dof) in free.iter().enumerate() {
            let mut e = vec![0.0; n];
            e[dof] = 1.0;
            let (column, _) = eq.correction(&e).unwrap();
            for (i, &row) in free.iter().enumerate() {
                inverse[(i, j)] = column[row];
            }
        }
        let sym = (&inverse + inverse.transpose()) * 0.5;
        let eig = sym.symmetric_eigenvalues();
        let (lo, hi) = eig.iter().fold((f64::INFINITY, 0.0f64), |(a, b), v| {
            (a.min(v.abs()), b.max(v.abs()))
        });
        hi / lo
    }

    /// How the band width conditions the system: the IBM patch test (unit
    /// block, rollers and a prescribed stretch by the IBM, GIMP, grid cut
    /// at (0.1, 0.07), h = 0.25). The penalty is about (4/3) h / delta times
    /// a cell's stiffness, so the condition number should grow tenfold per
    /// decade of delta once the penalty dominates. Measured: 3.1e2, 2.7e3,
    /// 2.6e4, 2.6e5, 2.6e6 for delta = h/10 .. h/10^5; the same block on
    /// grid-node supports (aligned grid): 3.6e1.
    #[test]
    fn band_width_sets_the_conditioning() {
        let case = |delta: Option<f64>| {
            let mut c = serde_json::json!({
                "version": 1,
                "analysis": { "load_steps": 1 },
                "grid": { "cell_size": 0.25, "origin": [0.1, 0.07] },
                "basis": "gimp",
                "bodies": [{
                    "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [1.0, 1.0] } },
                    "points": { "count": [8, 8] },
                    "material": { "model": "linear_elastic", "youngs_modulus": 1e6, "poisson_ratio": 0.3, "density": 0.0 }
                }],
                "supports": [
                    { "on": { "x": 0.0 }, "fix": "normal", "method": "ibm" },
                    { "on": { "y": 0.0 }, "fix": "normal", "method": "ibm" },
                    { "on": { "x": 1.0 }, "fix": "x", "method": "ibm", "displacement": [0.01, 0.0] }
                ]
            });
            if let Some(d) = delta {
                c["boundary"] = serde_json::json!({ "band_width": d });
            }
            Case::from_json(&c.to_string()).unwrap()
        };
        let mut grid = case(None);
        grid.grid.origin = [0.0, 0.0];
        grid.supports = serde_json::from_value(serde_json::json!([
            { "on": { "x": 0.0 }, "fix": "x" },
            { "on": { "y": 0.0 }, "fix": "y" },
            { "on": { "x": 1.0 }, "fix": "x" }
        ]))
        .unwrap();
        let baseline = first_tangent_condition(&grid);
        eprintln!("grid-node supports, aligned grid: condition number {baseline:.2e}");
        let mut conditions = Vec::new();
        for k in 1..=5 {
            let kappa = first_tangent_condition(&case(Some(0.25 / 10f64.powi(k))));
            eprintln!("delta = h/1e{k}: condition number {kappa:.2e}");
            conditions.push(kappa);
        }
        for w in conditions.windows(2).skip(1) {
            let ratio = w[1] / w[0];
            assert!(ratio > 8.0 && ratio < 12.0, "{conditions:?}");
        }
    }
}
