//! Sparse direct solves with faer, symbolic analysis once per pattern.
//!
//! The pattern of the tangent is fixed during a step, so the fill-reducing
//! ordering and elimination tree are computed at the first iteration and
//! reused by every later one; only the numeric factorisation is repeated.
//! A step whose pattern equals the last step's (no point crossed into a
//! new cell's reach) takes over the last step's solver and its analysis
//! ([`crate::equilibrium::StepEquilibrium::new`]).
//! A symmetric tangent (elastic or associated plastic materials, loads
//! that do not move, no F-bar) is factorised by Cholesky; LU is used when the tangent is not symmetric, and as a fallback
//! when Cholesky meets a non-positive pivot (an indefinite tangent, e.g. past
//! a limit point). Cholesky orders the unknowns by nested dissection of the
//! grid's active nodes (`ordering.rs`) when it is given them, and runs on
//! rayon's threads for the largest systems; LU keeps faer's COLAMD and
//! sequential mode (faster than its rayon mode where measured). The
//! thresholds below were measured: docs/scale.md, "Measured choices".
//!
//! From [`KEPT_FACTOR_FROM_DOFS`] unknowns up, a symmetric tangent is not
//! factorised at every Newton iteration: CG solves it to the accuracy
//! Newton asks for ([`crate::newton::forcing_term`]), preconditioned by the
//! kept single-precision factor of an earlier tangent of the pattern
//! ([`crate::krylov`]), which is refreshed when CG with it reduced the
//! residual by less than [`REFRESH_RATE`] an iteration, and is kept in
//! double precision if a fresh single one fails to serve. From
//! [`MULTIGRID_FROM_DOFS`] up, CG is preconditioned instead by a multigrid
//! V-cycle ([`crate::multigrid`]), whose memory grows linearly with the
//! unknowns; if no hierarchy serves a tangent, the kept factor does.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering as Atomic};

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
    simplicial, supernodal,
};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::traits::ComplexField;
use faer::{Conj, Mat, MatMut, Par, Side};
use rayon::prelude::*;

use crate::assembly::Pattern;
use crate::krylov;
use crate::multigrid::{self, Hierarchy};
use crate::ordering;
use crate::triangular::SubtreeSchedule;

/// The fill-reducing ordering of a Cholesky factorisation (LU orders its
/// columns by faer's COLAMD, which takes no other).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum FillOrdering {
    /// faer's approximate minimum degree.
    MinimumDegree,
    /// Nested dissection of the active nodes by grid lines (`ordering.rs`),
    /// when the solver is given the nodes.
    #[default]
    NestedDissection,
}

/// How a run's linear systems are solved: a value each run holds, so two
/// runs in one process (two jobs of a service) never share a choice.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SolverSettings {
    /// Cholesky's fill-reducing ordering (nested dissection).
    pub ordering: FillOrdering,
    /// How symmetric tangents are solved whatever their size; `None` (the
    /// default) chooses by size ([`symmetric_method`]). Benchmarks compare
    /// the methods this way.
    pub symmetric: Option<SymmetricMethod>,
    /// How tangents that are not symmetric are solved whatever their
    /// size; `None` (the default) chooses by size ([`unsymmetric_method`]).
    pub unsymmetric: Option<UnsymmetricMethod>,
}

/// What a run's solvers did, summed over them (one per pattern), for
/// benchmarks: read with [`SolveTally::counts`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SolveCounts {
    /// Solvers built for a new pattern (each analysed it), and solvers a
    /// later system of the same pattern took over.
    pub analysed: usize,
    pub reused: usize,
    /// Symmetric systems factorised afresh (or given a fresh multigrid
    /// hierarchy), solved by CG, and CG's iterations.
    pub fresh_factorisations: usize,
    pub cg_solves: usize,
    pub cg_iterations: usize,
    /// Entries (the fill) of the last Cholesky factor; 0 before the first.
    pub last_factor_entries: usize,
}

/// The counts of a run's solvers, shared by them: each solver of the run
/// adds to its run's tally, and nothing else does.
#[derive(Debug, Default)]
pub struct SolveTally {
    analysed: AtomicUsize,
    reused: AtomicUsize,
    fresh_factorisations: AtomicUsize,
    cg_solves: AtomicUsize,
    cg_iterations: AtomicUsize,
    last_factor_entries: AtomicUsize,
}

impl SolveTally {
    pub fn counts(&self) -> SolveCounts {
        let read = |count: &AtomicUsize| count.load(Atomic::Relaxed);
        SolveCounts {
            analysed: read(&self.analysed),
            reused: read(&self.reused),
            fresh_factorisations: read(&self.fresh_factorisations),
            cg_solves: read(&self.cg_solves),
            cg_iterations: read(&self.cg_iterations),
            last_factor_entries: read(&self.last_factor_entries),
        }
    }

    fn add(count: &AtomicUsize, n: usize) {
        count.fetch_add(n, Atomic::Relaxed);
    }

    fn cg_solve(&self, iterations: usize) {
        Self::add(&self.cg_solves, 1);
        Self::add(&self.cg_iterations, iterations);
    }

    fn fresh_factor(&self, entries: Option<usize>) {
        Self::add(&self.fresh_factorisations, 1);
        if let Some(entries) = entries {
            self.last_factor_entries.store(entries, Atomic::Relaxed);
        }
    }
}

/// What produced a solution: a factorisation (of the tangent, or an
/// earlier one preconditioning CG), CG preconditioned by multigrid, or
/// GMRES preconditioned by the Cholesky factor of a symmetric part.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Factorisation {
    Cholesky,
    Lu,
    Multigrid,
    Gmres,
}

/// From this many unknowns up, Cholesky factorises on rayon's threads:
/// the crossover on the GIMP column lies between 48k and 479k DOFs, and
/// this splits the difference.
const PARALLEL_FROM_DOFS: usize = 150_000;

/// A linear solver bound to one sparsity pattern.
pub struct SparseSolver {
    n: usize,
    /// The nested-dissection order of the DOFs, `order[k]` eliminated k-th,
    /// and its inverse.
    order: Option<(Vec<usize>, Vec<usize>)>,
    llt: Option<SymbolicCholesky<usize>>,
    /// The kept factor's supernodes arranged for parallel triangular
    /// solves (`triangular.rs`), made for [`SymmetricMethod::KeptFactorCg`]
    /// and [`UnsymmetricMethod::SymmetricPartGmres`].
    schedule: Option<SubtreeSchedule>,
    lu: Option<SymbolicLu<usize>>,
    /// Whether Cholesky orders by nested dissection (the run's
    /// [`SolverSettings::ordering`]).
    nested_dissection: bool,
    /// The run's counts, which this solver adds to.
    tally: Arc<SolveTally>,
    /// Bytes of the last Cholesky factorisation: its values and its
    /// numeric scratch.
    factor_bytes: usize,
    scratch_bytes: usize,
    /// Later systems (load steps) this solver was reused for.
    reuses: usize,
    /// The last Cholesky factor of an earlier tangent of this increment
    /// (or of its symmetric part), kept to precondition CG when the method
    /// is [`SymmetricMethod::KeptFactorCg`], or GMRES.
    kept: Option<KeptFactor>,
    /// Whether the kept factor is in double precision (a single-precision
    /// one failed to serve).
    double_kept: bool,
    method: SymmetricMethod,
    /// The method chosen for the pattern, to which each increment returns
    /// (`method` falls back from multigrid to the kept factor within one).
    method_choice: SymmetricMethod,
    /// How GMRES's symmetric part is preconditioned: as `method`, or by
    /// multigrid for elastic bodies ([`SparseSolver::with_elastic_tangents`]);
    /// each increment returns to `gmres_method_choice`, as `method` does to
    /// `method_choice`.
    gmres_method: SymmetricMethod,
    gmres_method_choice: SymmetricMethod,
    /// Whether the method was given by the settings rather than chosen.
    forced: bool,
    /// How the last CG or GMRES solve ended.
    last_cg: Option<krylov::CgOutcome>,
    /// Numeric factorisations this solver made.
    factorisations: usize,
    /// Whether the next solve factorises afresh (the last CG or GMRES
    /// solve with a stale factor converged slower than [`REFRESH_RATE`]),
    /// or builds a fresh multigrid hierarchy.
    refresh: bool,
    /// The grid coordinates of the nodes, for the nested-dissection order
    /// and [`SymmetricMethod::Multigrid`]'s aggregates.
    nodes: Option<GridNodes>,
    /// Whether the basis is a B-spline's, whose multigrid smooths more
    /// ([`Hierarchy::new`]).
    wide_stencil: bool,
    /// The multigrid hierarchy of an earlier tangent of this pattern.
    hierarchy: Option<Hierarchy>,
    unsymmetric: UnsymmetricMethod,
    /// The method chosen for the pattern, to which each increment returns
    /// (`unsymmetric` falls back to LU within one).
    unsymmetric_choice: UnsymmetricMethod,
    /// Solves in a row left to LU because the symmetric part was not
    /// positive definite ([`GMRES_INDEFINITE_LIMIT`]).
    indefinite_solves: usize,
    /// Where each entry's transpose lies in the pattern (`K_ji` for the
    /// entry `K_ij`), made at the first GMRES solve; `None` before, and
    /// for a pattern that is not structurally symmetric (then LU solves).
    transpose: Option<Vec<u32>>,
    /// The tangent's symmetric part, GMRES's preconditioners' matrix.
    symmetric_part: Vec<f64>,
}

/// The smallest relative residual (CG's recurrence's) CG is asked to reach
/// with a kept factor, whatever accuracy Newton asks for
/// ([`crate::newton::forcing_term`], 3e-7 and up at its default
/// tolerance). On an ill-conditioned tangent the true residual ends above
/// the recurrence's, and Newton, which measures the true out-of-balance
/// force, judges the answer.
const CG_FLOOR: f64 = 1e-12;
/// CG iterations allowed with a fresh single-precision factor before it
/// is judged too imprecise (then the factor is kept in double).
const CG_MAX_ITERATIONS: usize = 30;
/// CG iterations allowed with a stale factor before the tangent is
/// factorised afresh.
const CG_MAX_ITERATIONS_STALE: usize = 20;
/// A CG solve with a stale factor whose residual fell by less than this
/// factor an iteration (on average) asks for a fresh factor at the next
/// solve. A fresh factor costs as much as 7 (1e5 column points) to 13
/// (1e6) CG iterations; at 0.15 a stale factor needs about 7 iterations
/// to Newton's 1e-6 where a fresh one needs 1 or 2, so over the two or
/// three solves left in a step a refresh about pays for itself.
const REFRESH_RATE: f64 = 0.15;

/// CG's residual reduction per product with `K`, on average: its
/// relative residual to the power of one over its iterations (the
/// reduction by the first preconditioned solve, `x0 = M^-1 b`, is counted
/// in with the others; [`REFRESH_RATE`] was measured with this).
fn contraction(outcome: &krylov::CgOutcome) -> f64 {
    if outcome.iterations == 0 {
        0.0
    } else {
        outcome
            .relative_residual
            .powf(1.0 / outcome.iterations as f64)
    }
}

/// CG iterations allowed with a fresh multigrid hierarchy before it is
/// judged not to serve (it converges by about 0.3 an iteration on the
/// plate of `multigrid.rs`' tests, 1e-10 in about 20; the GIMP column's
/// solves take 7 to 14), and with a stale one before a fresh one is
/// built.
const MULTIGRID_MAX_ITERATIONS: usize = 100;
const MULTIGRID_MAX_ITERATIONS_STALE: usize = 40;
/// A CG solve with a stale hierarchy that reduced the residual by less
/// than this an iteration asks for a fresh one at the next solve.
const MULTIGRID_REFRESH_RATE: f64 = 0.5;

/// The grid coordinates of a step's active nodes: node `k`'s DOFs are
/// `D k` to `D k + D - 1`.
#[derive(Debug, Clone)]
pub enum GridNodes {
    Plane(Vec<[i64; 2]>),
    Solid(Vec<[i64; 3]>),
}

impl GridNodes {
    /// The multigrid hierarchy of `a` over these nodes.
    fn hierarchy(&self, a: multigrid::Operator<'_>, wide: bool) -> Option<Hierarchy> {
        match self {
            GridNodes::Plane(nodes) => Hierarchy::new(a, nodes, wide),
            GridNodes::Solid(nodes) => Hierarchy::new(a, nodes, wide),
        }
        .ok()
    }
}

/// How symmetric tangents are solved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SymmetricMethod {
    /// Every tangent factorised in double precision.
    Direct,
    /// CG preconditioned by a kept factor of an earlier tangent of the
    /// pattern ([`crate::krylov`]), refreshed when CG slows down.
    KeptFactorCg,
    /// CG preconditioned by a smoothed-aggregation multigrid V-cycle
    /// ([`crate::multigrid`]) built on an earlier tangent of the pattern,
    /// rebuilt when CG slows down: no factor, memory linear in the
    /// unknowns. It needs the nodes' grid coordinates
    /// ([`SparseSolver::with_grid`]); without them, or when its hierarchy
    /// fails, the solver takes the kept factor.
    Multigrid,
}

/// From this many unknowns up, symmetric tangents are solved by
/// [`SymmetricMethod::KeptFactorCg`], which takes a fifth to a third off
/// the GIMP column's step from 48k DOFs, ties on the bilinear cantilever,
/// and lowers the peak memory of both. Below it every answer is the direct
/// solve's.
pub const KEPT_FACTOR_FROM_DOFS: usize = 40_000;

/// From this many unknowns up, symmetric tangents are solved by
/// [`SymmetricMethod::Multigrid`], whose memory grows linearly where the
/// kept factor's grows faster (620 bytes a point at 0.5M DOFs, 818 at
/// 4.8M on the GIMP column), and which alone brings 1e6 GIMP column
/// points under 1 GiB. It was faster than the kept factor from about
/// 0.14M DOFs, slower at 0.05M: CG's iterations grow slowly with size
/// where the factorisation grows as DOFs^1.3.
pub const MULTIGRID_FROM_DOFS: usize = 150_000;

/// The method a solver of `n` unknowns uses by default.
pub fn symmetric_method(n: usize) -> SymmetricMethod {
    method_by_size(n, KEPT_FACTOR_FROM_DOFS, MULTIGRID_FROM_DOFS)
}

/// Direct below `kept_from` unknowns, multigrid from `multigrid_from`,
/// the kept factor between.
fn method_by_size(n: usize, kept_from: usize, multigrid_from: usize) -> SymmetricMethod {
    if n >= multigrid_from {
        SymmetricMethod::Multigrid
    } else if n >= kept_from {
        SymmetricMethod::KeptFactorCg
    } else {
        SymmetricMethod::Direct
    }
}

/// In 3D, from this many unknowns up, symmetric tangents are solved by
/// [`SymmetricMethod::KeptFactorCg`], and from
/// [`SOLID_MULTIGRID_FROM_DOFS`] by [`SymmetricMethod::Multigrid`]: a 3D
/// factor fills faster than a plane one, so both come earlier. Measured on
/// the 3D GIMP column (`mpm bench-row 6`, two load steps, seconds a step
/// for direct, kept factor, multigrid): 0.28, 0.18, 0.22 at 3,451 DOFs;
/// 1.46, 0.75, 0.81 at 11,180; 9.7, 3.6, 3.0 at 41,205 (peak 987, 659 and
/// 441 MiB). Below it the built-in example and small cases keep exact
/// solves, at under 0.3 s a step.
pub const SOLID_KEPT_FACTOR_FROM_DOFS: usize = 5_000;
pub const SOLID_MULTIGRID_FROM_DOFS: usize = 20_000;

/// The method a solver of `n` unknowns in 3D uses by default.
pub fn solid_symmetric_method(n: usize) -> SymmetricMethod {
    method_by_size(n, SOLID_KEPT_FACTOR_FROM_DOFS, SOLID_MULTIGRID_FROM_DOFS)
}

/// How tangents that are not symmetric are solved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnsymmetricMethod {
    /// Every tangent factorised by LU.
    Direct,
    /// GMRES ([`krylov::preconditioned_gmres`]) preconditioned by the
    /// kept Cholesky factor of the symmetric part `(K + K^T) / 2` of this
    /// or an earlier tangent of the pattern, refreshed when GMRES slows
    /// down as CG's is. The load stiffness of a follower pressure, F-bar's
    /// averaging and non-associated flow leave `K` close to its symmetric
    /// part. Where the symmetric method is multigrid (from
    /// [`MULTIGRID_FROM_DOFS`]; for elastic bodies on GIMP or the linear
    /// basis from [`ELASTIC_GMRES_MULTIGRID_FROM_DOFS`]), a V-cycle of the
    /// symmetric part preconditions instead, and the kept factor if no
    /// hierarchy serves.
    /// When that part is not positive definite, LU solves that system
    /// ([`GMRES_INDEFINITE_LIMIT`]); when GMRES does not converge with a
    /// fresh double factor, LU solves the rest of the increment.
    SymmetricPartGmres,
}

/// From this many unknowns up, GMRES on the tangents of elastic bodies on
/// GIMP or the linear basis (a follower load's) is preconditioned by a
/// multigrid V-cycle of the symmetric part rather than its kept factor.
/// The paper's cantilever on GIMP, first two steps: 0.20 against 0.13 s a
/// step at 5,410 DOFs, 0.32 against 0.38-0.40 at 16,200 and 1.02 against
/// 1.72 at 52,214. Not for plastic bodies, whose symmetric parts are near
/// indefinite (the F-bar footing at 51,088 DOFs: 182 against 77 s a step),
/// nor the B-splines (2.76 against 2.81 at 53,110, 0.46 against 0.17 at
/// 5,694).
pub const ELASTIC_GMRES_MULTIGRID_FROM_DOFS: usize = 10_000;

/// From this many unknowns up, tangents that are not symmetric are solved
/// by [`UnsymmetricMethod::SymmetricPartGmres`] (BENCHMARKS.md,
/// Unsymmetric solves). Below it every answer is LU's.
pub const GMRES_FROM_DOFS: usize = 2_000;

/// GMRES's Arnoldi steps allowed with a fresh factor of the symmetric
/// part before it is judged not to serve, and with a stale one before a
/// fresh one is made; the basis vectors a cycle holds.
const GMRES_MAX_ITERATIONS: usize = 60;
const GMRES_MAX_ITERATIONS_STALE: usize = 30;
const GMRES_RESTART: usize = 30;

/// The method a solver of `n` unknowns uses by default for tangents that
/// are not symmetric.
pub fn unsymmetric_method(n: usize) -> UnsymmetricMethod {
    if n >= GMRES_FROM_DOFS {
        UnsymmetricMethod::SymmetricPartGmres
    } else {
        UnsymmetricMethod::Direct
    }
}

/// Why GMRES left a system to LU.
enum GmresFailure {
    /// The symmetric part is not positive definite in double precision.
    NotPositiveDefinite,
    /// GMRES did not converge with a fresh double factor of it, or the
    /// pattern is not structurally symmetric.
    NotConverging,
}

/// Systems in a row whose symmetric part was not positive definite, after
/// which LU solves the rest of the increment's (each increment, a load
/// step or a piece of a cut one, tries GMRES again:
/// [`SparseSolver::reused`]).
pub const GMRES_INDEFINITE_LIMIT: usize = 3;

/// What the kept-factor path made of a symmetric system.
enum Kept {
    Solved(Vec<f64>, Timing),
    /// Neither a single nor a double factorisation succeeded.
    NotPositiveDefinite,
}

/// The values of a kept Cholesky factor.
enum KeptFactor {
    Single(Vec<f32>),
    Double(Vec<f64>),
}

impl KeptFactor {
    fn bytes(&self) -> usize {
        match self {
            KeptFactor::Single(v) => std::mem::size_of_val(v.as_slice()),
            KeptFactor::Double(v) => std::mem::size_of_val(v.as_slice()),
        }
    }
}

/// The inverse of a kept factor, applied in place, with its scratch.
struct KeptSolve<'a> {
    symbolic: &'a SymbolicCholesky<usize>,
    kept: &'a KeptFactor,
    /// Parallel triangular solves of a supernodal factor in postorder.
    schedule: Option<&'a SubtreeSchedule>,
    par: Par,
    scratch: MemBuffer,
    single: Vec<f32>,
    permuted: Vec<f64>,
}

impl<'a> KeptSolve<'a> {
    fn new(
        symbolic: &'a SymbolicCholesky<usize>,
        kept: &'a KeptFactor,
        schedule: Option<&'a SubtreeSchedule>,
        par: Par,
    ) -> Self {
        let scratch = MemBuffer::new(
            symbolic
                .solve_in_place_scratch::<f64>(1, par)
                .or(symbolic.solve_in_place_scratch::<f32>(1, par)),
        );
        Self {
            symbolic,
            kept,
            schedule,
            par,
            scratch,
            single: Vec::new(),
            permuted: Vec::new(),
        }
    }

    /// `z <- M^-1 z`, `M` the kept factor's matrix.
    fn apply(&mut self, z: &mut [f64]) {
        let (symbolic, par, n) = (self.symbolic, self.par, z.len());
        let stack = MemStack::new(&mut self.scratch);
        match (self.kept, self.schedule) {
            (KeptFactor::Double(values), Some(schedule)) => {
                schedule.solve(symbolic, values, z, &mut self.permuted);
            }
            (KeptFactor::Single(values), Some(schedule)) => {
                schedule.solve(symbolic, values, z, &mut self.permuted);
            }
            // A simplicial factor, or supernodes out of postorder: faer's
            // sequential solve.
            (KeptFactor::Double(values), None) => {
                let column = MatMut::from_column_major_slice_mut(z, n, 1);
                LltRef::new(symbolic, values).solve_in_place_with_conj(
                    Conj::No,
                    column,
                    par,
                    stack,
                );
            }
            (KeptFactor::Single(values), None) => {
                self.single.clear();
                self.single.extend(z.iter().map(|&v| v as f32));
                let column = MatMut::from_column_major_slice_mut(&mut self.single, n, 1);
                LltRef::new(symbolic, values).solve_in_place_with_conj(
                    Conj::No,
                    column,
                    par,
                    stack,
                );
                for (z, s) in z.iter_mut().zip(&self.single) {
                    *z = f64::from(*s);
                }
            }
        }
    }
}

/// Bytes a solver holds or last needed, by part.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SolverMemory {
    /// The last Cholesky factor's values.
    pub factor_values: usize,
    /// Its structure (row indices and pointers of the factor, the
    /// permutation and the nested-dissection order).
    pub factor_structure: usize,
    /// Scratch of the numeric factorisation (freed after each).
    pub scratch: usize,
    /// The multigrid hierarchy: its coarse operators, prolongators,
    /// smoothers' diagonals, work vectors and dense coarsest factor.
    #[serde(default)]
    pub multigrid: usize,
    /// GMRES's copies of the tangent (its transpose and symmetric part)
    /// and the transpose's places in the pattern.
    #[serde(default)]
    pub gmres: usize,
}

impl SparseSolver {
    /// A solver of `n` unknowns, counting what it does in `tally`;
    /// `order`, when given (and `settings` order by nested dissection), is
    /// the elimination order of Cholesky factorisations.
    pub fn new(
        n: usize,
        order: Option<Vec<usize>>,
        settings: &SolverSettings,
        tally: Arc<SolveTally>,
    ) -> Self {
        faer::set_global_parallelism(faer::Par::Seq);
        SolveTally::add(&tally.analysed, 1);
        let nested_dissection = settings.ordering == FillOrdering::NestedDissection;
        let order = order.filter(|_| nested_dissection).map(with_inverse);
        let method = settings.symmetric.unwrap_or_else(|| symmetric_method(n));
        Self {
            n,
            order,
            nested_dissection,
            tally,
            llt: None,
            schedule: None,
            lu: None,
            factor_bytes: 0,
            scratch_bytes: 0,
            reuses: 0,
            method,
            method_choice: method,
            gmres_method: method,
            gmres_method_choice: method,
            forced: settings.symmetric.is_some(),
            last_cg: None,
            factorisations: 0,
            kept: None,
            double_kept: false,
            refresh: false,
            nodes: None,
            wide_stencil: false,
            hierarchy: None,
            unsymmetric: settings
                .unsymmetric
                .unwrap_or_else(|| unsymmetric_method(n)),
            unsymmetric_choice: settings
                .unsymmetric
                .unwrap_or_else(|| unsymmetric_method(n)),
            indefinite_solves: 0,
            transpose: None,
            symmetric_part: Vec::new(),
        }
    }

    /// This solver, told the grid coordinates of the nodes: the
    /// multigrid's aggregates are blocks of them, and Cholesky's
    /// nested-dissection order, when the solver was given none, is made
    /// from them when first needed. `wide_stencil` for the B-splines, whose
    /// multigrid smooths more. On a 3D grid the default method is
    /// [`solid_symmetric_method`]'s (unless the settings chose one).
    pub fn with_grid(mut self, nodes: GridNodes, wide_stencil: bool) -> Self {
        if !self.forced && matches!(nodes, GridNodes::Solid(_)) {
            let method = solid_symmetric_method(self.n);
            self.method = method;
            self.method_choice = method;
            self.gmres_method = method;
            self.gmres_method_choice = method;
        }
        self.nodes = Some(nodes);
        self.wide_stencil = wide_stencil;
        self
    }

    /// This solver with its symmetric tangents (and GMRES's symmetric
    /// parts) solved by `method`.
    pub fn with_method(mut self, method: SymmetricMethod) -> Self {
        self.method = method;
        self.method_choice = method;
        self.gmres_method = method;
        self.gmres_method_choice = method;
        self.forced = true;
        self
    }

    /// This solver, for a pattern of elastic bodies on GIMP or the linear
    /// basis: GMRES's symmetric part is preconditioned by multigrid from
    /// [`ELASTIC_GMRES_MULTIGRID_FROM_DOFS`] (unless the settings chose a
    /// method). Call after [`SparseSolver::with_grid`].
    pub fn with_elastic_tangents(mut self) -> Self {
        if !self.forced
            && !self.wide_stencil
            && self.nodes.is_some()
            && self.n >= ELASTIC_GMRES_MULTIGRID_FROM_DOFS
        {
            self.gmres_method = SymmetricMethod::Multigrid;
            self.gmres_method_choice = SymmetricMethod::Multigrid;
        }
        self
    }

    /// This solver, for a later system of the same pattern (the caller
    /// checks that it is): counted in its tally.
    pub fn reused(mut self) -> Self {
        SolveTally::add(&self.tally.reused, 1);
        self.reuses += 1;
        // Each increment (a load step, or a piece of a cut one) starts its
        // preconditioners afresh, as a resumed run does (a checkpoint
        // keeps no factor or hierarchy), so that both give the same bits;
        // only the symbolic analysis (a function of the pattern alone) is
        // taken over.
        self.kept = None;
        self.double_kept = false;
        self.hierarchy = None;
        self.refresh = false;
        self.method = self.method_choice;
        self.gmres_method = self.gmres_method_choice;
        self.unsymmetric = self.unsymmetric_choice;
        self.indefinite_solves = 0;
        self
    }

    /// How the last CG solve with a kept factor ended (`None` before one).
    pub fn last_cg(&self) -> Option<krylov::CgOutcome> {
        self.last_cg
    }

    /// Numeric factorisations this solver made.
    pub fn factorisations(&self) -> usize {
        self.factorisations
    }

    /// Systems after the first this solver served.
    pub fn reuses(&self) -> usize {
        self.reuses
    }

    /// What the solver holds, and what its last factorisation needed.
    pub fn memory(&self) -> SolverMemory {
        let index = std::mem::size_of::<usize>();
        let mut structure = self
            .order
            .as_ref()
            .map_or(0, |(o, i)| (o.len() + i.len()) * index);
        if let Some(llt) = &self.llt {
            structure += 2 * llt.nrows() * index;
            structure += match llt.raw() {
                SymbolicCholeskyRaw::Supernodal(s) => {
                    (s.row_idx().len() + s.col_ptr_for_row_idx().len() + s.col_ptr_for_val().len())
                        * index
                }
                SymbolicCholeskyRaw::Simplicial(s) => {
                    (s.row_idx().len() + s.col_ptr().len()) * index
                }
            };
        }
        structure += self
            .schedule
            .as_ref()
            .map_or(0, SubtreeSchedule::heap_bytes);
        SolverMemory {
            factor_values: self.factor_bytes,
            factor_structure: structure,
            scratch: self.scratch_bytes,
            multigrid: self.hierarchy.as_ref().map_or(0, Hierarchy::bytes),
            gmres: std::mem::size_of_val(self.symmetric_part.as_slice())
                + self
                    .transpose
                    .as_ref()
                    .map_or(0, |t| std::mem::size_of_val(t.as_slice())),
        }
    }

    /// Solves the symmetric `K x = rhs` by CG preconditioned by the kept
    /// factor (of this tangent or an earlier one of the pattern). A fresh
    /// factor is made when there is none, when CG with a stale one
    /// converged slower than [`REFRESH_RATE`] last time, or when CG fails
    /// with a stale one. CG stops at the relative residual `accuracy`
    /// (at least [`CG_FLOOR`]). The factor is kept in single precision (half the
    /// memory and bandwidth) until a fresh single one fails to serve; then
    /// in double, whose fresh factor answers directly (the direct method's
    /// answer). [`Kept::NotPositiveDefinite`] when the double factorisation
    /// fails too (then only LU serves).
    fn cg_with_kept_factor(
        &mut self,
        pattern: &Pattern,
        values: &[f64],
        rhs: &[f64],
        accuracy: f64,
        par: Par,
    ) -> Kept {
        let mut timing = Timing::default();
        loop {
            let fresh = self.kept.is_none() || self.refresh;
            if fresh {
                let t = std::time::Instant::now();
                self.refresh = false;
                let factorised = self.factorise_kept(pattern, values, par);
                timing.factorise += t.elapsed().as_secs_f64();
                if !factorised {
                    if self.double_kept {
                        // Not a matter of precision: K is not positive definite.
                        self.double_kept = false;
                        return Kept::NotPositiveDefinite;
                    }
                    self.double_kept = true;
                    continue;
                }
            }
            let Some(symbolic) = self.llt.as_ref() else {
                return Kept::NotPositiveDefinite;
            };
            let Some(kept) = self.kept.as_ref() else {
                return Kept::NotPositiveDefinite;
            };
            let t = std::time::Instant::now();
            let mut inverse = KeptSolve::new(symbolic, kept, self.schedule.as_ref(), par);
            // A fresh double factor is exact: its solve is the answer.
            let direct = fresh && matches!(kept, KeptFactor::Double(_));
            let max_iterations = match (direct, fresh) {
                (true, _) => 0,
                (false, true) => CG_MAX_ITERATIONS,
                (false, false) => CG_MAX_ITERATIONS_STALE,
            };
            let (x, outcome) = krylov::preconditioned_cg(
                |x, y| krylov::symmetric_product(&pattern.col_ptr, &pattern.row_idx, values, x, y),
                |z| inverse.apply(z),
                rhs,
                accuracy.max(CG_FLOOR),
                max_iterations,
            );
            timing.solve += t.elapsed().as_secs_f64();
            self.last_cg = Some(outcome);

            if direct || outcome.converged {
                self.tally.cg_solve(outcome.iterations);
                self.refresh = !fresh && contraction(&outcome) > REFRESH_RATE;
                return Kept::Solved(x, timing);
            }
            if fresh {
                // A fresh single factor is not precise enough for this K.
                self.double_kept = true;
            }
            self.refresh = true;
        }
    }

    /// Solves the symmetric `K x = rhs` by CG preconditioned by a multigrid
    /// V-cycle, to the relative residual `accuracy` (at least
    /// [`CG_FLOOR`]). The hierarchy is built afresh when there is none,
    /// when CG with a stale one converged slower than
    /// [`MULTIGRID_REFRESH_RATE`] last time, or when CG fails with a stale
    /// one. `None` when the solver has no grid, or a fresh hierarchy
    /// cannot be built or does not converge (a tangent that is not
    /// positive definite).
    fn cg_with_multigrid(
        &mut self,
        pattern: &Pattern,
        values: &[f64],
        rhs: &[f64],
        accuracy: f64,
    ) -> Option<(Vec<f64>, Timing)> {
        let op = multigrid::Operator {
            ptr: &pattern.col_ptr,
            col: &pattern.row_idx,
            val: values,
        };
        self.with_multigrid(op, Timing::default(), |hierarchy, limit| {
            krylov::preconditioned_cg(
                |x, y| krylov::symmetric_product(&pattern.col_ptr, &pattern.row_idx, values, x, y),
                |z| hierarchy.apply(op, z),
                rhs,
                accuracy.max(CG_FLOOR),
                limit,
            )
        })
    }

    /// A Krylov solve (`krylov(hierarchy, iteration limit)`) preconditioned
    /// by a multigrid V-cycle of `op`: the kept hierarchy fitted to `op`,
    /// or one built afresh when there is none, when the last solve with a
    /// stale one converged slower than [`MULTIGRID_REFRESH_RATE`], or when
    /// it fails with a stale one. `None` when the solver has no grid, or a
    /// fresh hierarchy cannot be built or does not serve. Times add to
    /// `timing`.
    fn with_multigrid(
        &mut self,
        op: multigrid::Operator<'_>,
        mut timing: Timing,
        mut krylov: impl FnMut(&mut Hierarchy, usize) -> (Vec<f64>, krylov::CgOutcome),
    ) -> Option<(Vec<f64>, Timing)> {
        loop {
            let fresh = self.hierarchy.is_none() || self.refresh;
            self.refresh = false;
            let hierarchy = fitted_hierarchy(
                &mut self.hierarchy,
                op,
                (self.nodes.as_ref(), self.wide_stencil),
                fresh,
                (&self.tally, &mut self.factorisations),
                &mut timing,
            )?;
            let t = std::time::Instant::now();
            let limit = if fresh {
                MULTIGRID_MAX_ITERATIONS
            } else {
                MULTIGRID_MAX_ITERATIONS_STALE
            };
            let (x, outcome) = krylov(hierarchy, limit);
            timing.solve += t.elapsed().as_secs_f64();
            if self.krylov_finished(outcome, fresh, MULTIGRID_REFRESH_RATE) {
                return Some((x, timing));
            }
            if fresh {
                self.hierarchy = None;
                return None;
            }
            self.refresh = true;
        }
    }

    /// Records how a Krylov solve with a kept preconditioner ended, and
    /// whether it converged; if it did with a stale preconditioner that
    /// reduced the residual by less than `rate` an iteration, the next
    /// solve makes a fresh one.
    fn krylov_finished(&mut self, outcome: krylov::CgOutcome, fresh: bool, rate: f64) -> bool {
        self.last_cg = Some(outcome);
        if outcome.converged {
            self.tally.cg_solve(outcome.iterations);
            self.refresh = !fresh && contraction(&outcome) > rate;
        }
        outcome.converged
    }

    /// Makes the symbolic Cholesky analysis of the pattern, once: in
    /// nested-dissection order when the solver has the grid (or was given
    /// an order); and the kept factor's parallel triangular solves, once,
    /// when `schedule`.
    fn analyse_cholesky(&mut self, pattern: &Pattern, schedule: bool) -> Result<(), String> {
        if self.llt.is_none() {
            if self.order.is_none() && self.nested_dissection {
                self.order = self.nodes.as_ref().map(|nodes| {
                    with_inverse(match nodes {
                        GridNodes::Plane(nodes) => ordering::nested_dissection(nodes, pattern),
                        GridNodes::Solid(nodes) => ordering::nested_dissection(nodes, pattern),
                    })
                });
            }
            let (col_ptr, row_idx) = upper_triangle(pattern);
            let structure =
                SymbolicSparseColMatRef::new_checked(self.n, self.n, &col_ptr, None, &row_idx);
            let ordering = match &self.order {
                Some((order, inverse)) => {
                    SymmetricOrdering::Custom(PermRef::new_checked(order, inverse, self.n))
                }
                None => SymmetricOrdering::Amd,
            };
            let llt =
                factorize_symbolic_cholesky(structure, Side::Upper, ordering, Default::default())
                    .map_err(|e| format!("{e:?}"))?;
            self.llt = Some(llt);
        }
        // Made whenever a kept factor may be applied, whichever solve
        // analysed the pattern first: the answer's bits do not depend on
        // the order of the solves.
        if schedule
            && self.schedule.is_none()
            && let Some(llt) = &self.llt
        {
            self.schedule = SubtreeSchedule::new(llt, rayon::current_num_threads());
        }
        Ok(())
    }

    /// Finds, once a pattern, where each entry's transpose lies
    /// (`transpose`), whose places make `K x` from the columns of `K^T`
    /// without a copy of it. An error when the pattern is not structurally
    /// symmetric.
    fn transpose_tangent(&mut self, pattern: &Pattern) -> Result<(), GmresFailure> {
        if self.transpose.is_none() {
            self.transpose = Some(transpose_places(pattern).ok_or(GmresFailure::NotConverging)?);
        }
        Ok(())
    }

    /// `(K + K^T) / 2` into `symmetric_part`, `transpose` found.
    fn make_symmetric_part(&mut self, values: &[f64]) {
        let transpose = self
            .transpose
            .as_ref()
            .expect("the transpose's places are found first");
        self.symmetric_part.resize(values.len(), 0.0);
        (self.symmetric_part.par_iter_mut())
            .zip(values.par_iter().zip(transpose))
            .for_each(|(s, (k, &t))| *s = 0.5 * (k + values[t as usize]));
    }

    /// Solves `K x = rhs` for a `K` that is not symmetric by GMRES
    /// preconditioned by a multigrid V-cycle of its symmetric part (the
    /// method from [`MULTIGRID_FROM_DOFS`] up, where the kept factor's
    /// memory grows faster than the unknowns), built on an earlier tangent
    /// of the increment and fitted to this one, rebuilt as CG's is
    /// ([`MULTIGRID_REFRESH_RATE`]). `None` when no hierarchy serves (no
    /// grid, a setup that fails, or GMRES that does not converge with a
    /// fresh one): then the kept factor does.
    fn gmres_with_multigrid(
        &mut self,
        pattern: &Pattern,
        values: &[f64],
        rhs: &[f64],
        accuracy: f64,
    ) -> Option<(Vec<f64>, Timing)> {
        let mut timing = Timing::default();
        let t = std::time::Instant::now();
        self.transpose_tangent(pattern).ok()?;
        self.make_symmetric_part(values);
        timing.factorise += t.elapsed().as_secs_f64();
        // Out of the solver while it is borrowed whole, and back after.
        let (symmetric_part, transpose) = (
            std::mem::take(&mut self.symmetric_part),
            self.transpose.take().expect("found above"),
        );
        let op = multigrid::Operator {
            ptr: &pattern.col_ptr,
            col: &pattern.row_idx,
            val: &symmetric_part,
        };
        let solved = self.with_multigrid(op, timing, |hierarchy, limit| {
            gmres_on(
                pattern,
                (values, &transpose),
                |z| hierarchy.apply(op, z),
                rhs,
                accuracy,
                limit,
            )
        });
        (self.symmetric_part, self.transpose) = (symmetric_part, Some(transpose));
        solved
    }

    /// Solves `K x = rhs` for a `K` that is not symmetric by GMRES
    /// preconditioned by the kept Cholesky factor of the symmetric part of
    /// this or an earlier tangent of the pattern, to the relative residual
    /// `accuracy` (at least [`CG_FLOOR`]). A fresh factor is made when
    /// there is none, when GMRES with a stale one converged slower than
    /// [`REFRESH_RATE`] last time, or when GMRES fails with a stale one; in
    /// single precision until a fresh single one fails to serve, then in
    /// double. An error when LU must solve: the symmetric part is not
    /// positive definite, GMRES does not converge with a fresh double
    /// factor of it, or the pattern is not structurally symmetric.
    fn gmres_with_kept_factor(
        &mut self,
        pattern: &Pattern,
        values: &[f64],
        rhs: &[f64],
        accuracy: f64,
        par: Par,
    ) -> Result<(Vec<f64>, Timing), GmresFailure> {
        let mut timing = Timing::default();
        self.transpose_tangent(pattern)?;
        loop {
            let fresh = self.kept.is_none() || self.refresh;
            if fresh {
                let t = std::time::Instant::now();
                self.refresh = false;
                self.make_symmetric_part(values);
                let symmetric_part = std::mem::take(&mut self.symmetric_part);
                let factorised = self.factorise_kept(pattern, &symmetric_part, par);
                self.symmetric_part = symmetric_part;
                timing.factorise += t.elapsed().as_secs_f64();
                if !factorised {
                    if self.double_kept {
                        // Not a matter of precision: the symmetric part is
                        // not positive definite.
                        return Err(GmresFailure::NotPositiveDefinite);
                    }
                    self.double_kept = true;
                    continue;
                }
            }
            let (Some(symbolic), Some(kept)) = (self.llt.as_ref(), self.kept.as_ref()) else {
                return Err(GmresFailure::NotPositiveDefinite);
            };
            let t = std::time::Instant::now();
            let mut inverse = KeptSolve::new(symbolic, kept, self.schedule.as_ref(), par);
            let limit = if fresh {
                GMRES_MAX_ITERATIONS
            } else {
                GMRES_MAX_ITERATIONS_STALE
            };
            let transpose = self.transpose.as_deref().expect("found above");
            let (x, outcome) = gmres_on(
                pattern,
                (values, transpose),
                |z| inverse.apply(z),
                rhs,
                accuracy,
                limit,
            );
            timing.solve += t.elapsed().as_secs_f64();
            if self.krylov_finished(outcome, fresh, REFRESH_RATE) {
                return Ok((x, timing));
            }
            if fresh {
                if self.double_kept {
                    return Err(GmresFailure::NotConverging);
                }
                // A fresh single factor may be too imprecise.
                self.double_kept = true;
            }
            self.refresh = true;
        }
    }

    /// Factorises `K` into the kept factor, in the precision the solver
    /// keeps; false (keeping none) when it is not positive definite in it.
    fn factorise_kept(&mut self, pattern: &Pattern, values: &[f64], par: Par) -> bool {
        let Some(symbolic) = self.llt.as_ref() else {
            return false;
        };
        let len = symbolic.len_val();
        // The old factor's storage is reused when the precision is the same.
        let kept = match (self.kept.take(), self.double_kept) {
            (Some(KeptFactor::Double(mut v)), true) => {
                v.resize(len, 0.0);
                KeptFactor::Double(v)
            }
            (Some(KeptFactor::Single(mut v)), false) => {
                v.resize(len, 0.0);
                KeptFactor::Single(v)
            }
            (_, true) => KeptFactor::Double(vec![0.0; len]),
            (_, false) => KeptFactor::Single(vec![0.0; len]),
        };
        let tangent = Tangent::new(pattern, values);
        let (kept, ok, scratch_bytes) = match kept {
            KeptFactor::Double(mut factor) => {
                let (ok, bytes) = factorise(symbolic, tangent, exact, &mut factor, par);
                (KeptFactor::Double(factor), ok, bytes)
            }
            KeptFactor::Single(mut factor) => {
                let entry = single_precision(tangent);
                let (ok, bytes) = factorise(symbolic, tangent, entry, &mut factor, par);
                (KeptFactor::Single(factor), ok, bytes)
            }
        };
        self.scratch_bytes = scratch_bytes;
        self.factor_bytes = kept.bytes();
        self.factorisations += 1;
        self.tally.fresh_factor(Some(len));
        self.kept = ok.then_some(kept);
        ok
    }

    /// Factorises `K` (values in the layout of `pattern`) and solves
    /// `K x = rhs`. Returns the factorisation used, or a message.
    pub fn solve(
        &mut self,
        pattern: &Pattern,
        values: &[f64],
        rhs: &[f64],
        symmetric: bool,
        accuracy: f64,
    ) -> Result<(Vec<f64>, Factorisation, Timing), String> {
        let (mut x, kind, timing) =
            self.solve_columns(pattern, values, &[rhs], symmetric, accuracy)?;
        Ok((x.pop().expect("one right-hand side"), kind, timing))
    }

    /// [`SparseSolver::solve`] for several right-hand sides with one
    /// factorisation (a direct solve takes them together; an iterative one
    /// solves each with the same preconditioner).
    pub fn solve_columns(
        &mut self,
        pattern: &Pattern,
        values: &[f64],
        rhs: &[&[f64]],
        symmetric: bool,
        accuracy: f64,
    ) -> Result<(Vec<Vec<f64>>, Factorisation, Timing), String> {
        let t0 = std::time::Instant::now();
        let tangent = Tangent::new(pattern, values);
        let gmres = !symmetric && self.unsymmetric == UnsymmetricMethod::SymmetricPartGmres;
        let multigrid = if symmetric {
            self.method
        } else {
            self.gmres_method
        } == SymmetricMethod::Multigrid;
        if (symmetric || gmres) && multigrid {
            let mut solved = Vec::with_capacity(rhs.len());
            let mut total = Timing::default();
            for b in rhs {
                let made = if symmetric {
                    self.cg_with_multigrid(pattern, values, b, accuracy)
                } else {
                    self.gmres_with_multigrid(pattern, values, b, accuracy)
                };
                match made {
                    Some((x, timing)) => {
                        total.add(timing);
                        solved.push(x);
                    }
                    None => break,
                }
            }
            if solved.len() == rhs.len() {
                let kind = if symmetric {
                    Factorisation::Multigrid
                } else {
                    Factorisation::Gmres
                };
                return Ok((solved, kind, total));
            }
            // No hierarchy serves this tangent or its symmetric part (no
            // grid, aggregation that stalls, or a matrix that is not
            // positive definite): the kept factor does, in
            // nested-dissection order, for the rest of the increment.
            if symmetric {
                self.method = SymmetricMethod::KeptFactorCg;
            } else {
                self.gmres_method = SymmetricMethod::KeptFactorCg;
            }
            self.hierarchy = None;
        }
        let b = Mat::from_fn(self.n, rhs.len(), |i, j| rhs[j][i]);
        if symmetric {
            self.analyse_cholesky(pattern, self.method == SymmetricMethod::KeptFactorCg)?;
            let par = if self.n >= PARALLEL_FROM_DOFS {
                Par::rayon(0)
            } else {
                Par::Seq
            };
            let kept = match self.method {
                SymmetricMethod::KeptFactorCg => {
                    // The symbolic analysis, if this solve made it, counts
                    // as factorisation.
                    let analysis = t0.elapsed().as_secs_f64();
                    let mut solved = Vec::with_capacity(rhs.len());
                    let mut total = Timing {
                        factorise: analysis,
                        solve: 0.0,
                    };
                    for b in rhs {
                        match self.cg_with_kept_factor(pattern, values, b, accuracy, par) {
                            Kept::Solved(x, timing) => {
                                total.add(timing);
                                solved.push(x);
                            }
                            Kept::NotPositiveDefinite => break,
                        }
                    }
                    Some((solved.len() == rhs.len()).then_some((solved, total)))
                }
                SymmetricMethod::Direct | SymmetricMethod::Multigrid => None,
            };
            match kept {
                Some(Some((x, timing))) => return Ok((x, Factorisation::Cholesky, timing)),
                // Neither precision factorised it: only LU serves.
                Some(None) => {}
                None => {
                    let symbolic = self.llt.as_ref().expect("just built");
                    self.factor_bytes = symbolic.len_val() * std::mem::size_of::<f64>();
                    self.factorisations += 1;
                    let (solved, scratch_bytes) = cholesky(symbolic, tangent, &b, par, t0);
                    self.scratch_bytes = scratch_bytes;
                    if let Some((x, timing)) = solved {
                        self.tally.fresh_factor(Some(symbolic.len_val()));
                        return Ok((x, Factorisation::Cholesky, timing));
                    }
                }
            }
        }
        if gmres {
            self.analyse_cholesky(pattern, true)?;
            let par = if self.n >= PARALLEL_FROM_DOFS {
                Par::rayon(0)
            } else {
                Par::Seq
            };
            // The symbolic analysis, if this solve made it, counts as
            // factorisation.
            let mut total = Timing {
                factorise: t0.elapsed().as_secs_f64(),
                solve: 0.0,
            };
            let mut solved = Vec::with_capacity(rhs.len());
            let mut failure = None;
            for b in rhs {
                match self.gmres_with_kept_factor(pattern, values, b, accuracy, par) {
                    Ok((x, timing)) => {
                        total.add(timing);
                        solved.push(x);
                    }
                    Err(why) => {
                        failure = Some(why);
                        break;
                    }
                }
            }
            match failure {
                None => {
                    self.indefinite_solves = 0;
                    return Ok((solved, Factorisation::Gmres, total));
                }
                // An iterate far from equilibrium (compression, an early
                // overshoot) can make the symmetric part indefinite where
                // the later ones are not: LU solves this one, and the next
                // tries a fresh factor again, up to a limit in a row.
                Some(GmresFailure::NotPositiveDefinite) => {
                    self.indefinite_solves += 1;
                    if self.indefinite_solves >= GMRES_INDEFINITE_LIMIT {
                        self.unsymmetric = UnsymmetricMethod::Direct;
                    }
                }
                // The tangent is too far from its symmetric part.
                Some(GmresFailure::NotConverging) => {
                    self.unsymmetric = UnsymmetricMethod::Direct;
                }
            }
            self.kept = None;
            self.double_kept = false;
        }
        // faer's LU takes `usize` row indices: a copy for the solve.
        let row_idx: Vec<usize> = pattern.row_idx.iter().map(|&r| r as usize).collect();
        let structure =
            SymbolicSparseColMatRef::new_checked(self.n, self.n, &pattern.col_ptr, None, &row_idx);
        let matrix = SparseColMatRef::new(structure, values);
        if self.lu.is_none() {
            self.lu = Some(SymbolicLu::try_new(structure).map_err(|e| format!("{e:?}"))?);
        }
        let symbolic = self.lu.clone().expect("just built");
        let lu = Lu::try_new_with_symbolic(symbolic, matrix)
            .map_err(|e| format!("LU factorisation failed: {e:?}"))?;
        let (x, timing) = timed_solve(&lu, &b, t0);
        Ok((x, Factorisation::Lu, timing))
    }
}

/// An elimination order (`order[k]` the DOF eliminated k-th) with its
/// inverse.
fn with_inverse(order: Vec<usize>) -> (Vec<usize>, Vec<usize>) {
    let mut inverse = vec![0; order.len()];
    for (k, &dof) in order.iter().enumerate() {
        inverse[dof] = k;
    }
    (order, inverse)
}

/// GMRES on `K x = rhs` preconditioned by `precondition`, to the relative
/// residual `accuracy` (at least [`CG_FLOOR`]) in at most `limit` Arnoldi
/// steps, `K x` made from the columns of `K^T`: `K`'s `values` read at
/// their transposes' places (`transpose`, in the places of `pattern`).
fn gmres_on(
    pattern: &Pattern,
    (values, transpose): (&[f64], &[u32]),
    precondition: impl FnMut(&mut [f64]),
    rhs: &[f64],
    accuracy: f64,
    limit: usize,
) -> (Vec<f64>, krylov::CgOutcome) {
    krylov::preconditioned_gmres(
        |x, y| {
            krylov::transposed_product(
                &pattern.col_ptr,
                &pattern.row_idx,
                (values, transpose),
                x,
                y,
            )
        },
        precondition,
        rhs,
        accuracy.max(CG_FLOOR),
        limit,
        GMRES_RESTART,
    )
}

/// The hierarchy that preconditions a solve with `op`: when `fresh`, one
/// built on `op` (counted, with its time, as a factorisation), else the
/// one in `slot` fitted to `op` on its finest level (the coarse levels
/// kept). `None` when there is no grid or the setup fails.
fn fitted_hierarchy<'h>(
    slot: &'h mut Option<Hierarchy>,
    op: multigrid::Operator<'_>,
    (nodes, wide_stencil): (Option<&GridNodes>, bool),
    fresh: bool,
    (tally, factorisations): (&SolveTally, &mut usize),
    timing: &mut Timing,
) -> Option<&'h mut Hierarchy> {
    if fresh {
        let t = std::time::Instant::now();
        *slot = None;
        *slot = Some(nodes?.hierarchy(op, wide_stencil)?);
        *factorisations += 1;
        tally.fresh_factor(None);
        timing.factorise += t.elapsed().as_secs_f64();
        slot.as_mut()
    } else {
        let hierarchy = slot.as_mut()?;
        let t = std::time::Instant::now();
        hierarchy.fit_finest(op);
        timing.solve += t.elapsed().as_secs_f64();
        Some(hierarchy)
    }
}

/// Where each entry's transpose lies in `pattern`: `places[k]` holds
/// `K_ji` for the entry `k` holding `K_ij`. `None` when some `K_ji` has no
/// place (the pattern is not structurally symmetric). Rows are sorted in
/// each column.
fn transpose_places(pattern: &Pattern) -> Option<Vec<u32>> {
    let n = pattern.col_ptr.len() - 1;
    u32::try_from(pattern.row_idx.len()).ok()?;
    let places: Vec<u32> = (0..n)
        .into_par_iter()
        .flat_map_iter(|j| {
            let range = pattern.col_ptr[j]..pattern.col_ptr[j + 1];
            pattern.row_idx[range].iter().map(move |&i| {
                let column = pattern.col_ptr[i as usize]..pattern.col_ptr[i as usize + 1];
                let rows = &pattern.row_idx[column.clone()];
                rows.binary_search(&(j as u32))
                    .map_or(NO_PLACE, |k| (column.start + k) as u32)
            })
        })
        .collect();
    (!places.contains(&NO_PLACE)).then_some(places)
}

/// A transpose's place that is not in the pattern ([`transpose_places`]);
/// no place is, as a pattern's entries number fewer than `u32::MAX`.
const NO_PLACE: u32 = u32::MAX;

/// How a kept single-precision factor takes `K`'s entries: in single
/// precision, without those that are round-off of their own terms. Those
/// below `2^-48 sqrt(K_ii K_jj)`, the bound on any entry of a positive
/// semi-definite sum (`|K_ij| <= sqrt(K_ii K_jj)`), are set to zero. They
/// stay in the pattern: a simplicial factorisation walks each row's fill
/// from the entries present, and with one left out its places in the
/// factor fall out of step and the factor is wrong.
/// A tangent's cancelling terms leave such "zeros" (3.1M entries of the
/// 1e6 column's first tangent are below 1e-20; 27k are subnormal in single
/// precision), and their products fill the factor with subnormal numbers,
/// on which x86 arithmetic is orders of magnitude slower (docs/scale.md).
fn single_precision(tangent: Tangent<'_>) -> impl Fn(usize, usize, f64) -> f32 {
    let scale: Vec<f64> = (0..tangent.n())
        .map(|col| tangent.diagonal(col).abs().sqrt())
        .collect();
    move |row, col, v| {
        if v.abs() < ROUND_OFF * scale[row] * scale[col] {
            0.0
        } else {
            v as f32
        }
    }
}

/// Below this fraction of `sqrt(K_ii K_jj)` an entry is taken for
/// round-off ([`single_precision`]): sums of a few dozen terms in double
/// precision err by about `2^-52` of the largest times their count.
const ROUND_OFF: f64 = 1.0 / (1u64 << 48) as f64;

/// `K`'s entries as they are, for a factor in double precision.
pub(crate) fn exact(_row: usize, _col: usize, v: f64) -> f64 {
    v
}

/// A tangent's values in the compressed columns of its pattern.
#[derive(Clone, Copy)]
pub(crate) struct Tangent<'a> {
    col_ptr: &'a [usize],
    row_idx: &'a [u32],
    values: &'a [f64],
}

impl<'a> Tangent<'a> {
    pub(crate) fn new(pattern: &'a Pattern, values: &'a [f64]) -> Self {
        assert_eq!(pattern.row_idx.len(), values.len());
        Self {
            col_ptr: &pattern.col_ptr,
            row_idx: &pattern.row_idx,
            values,
        }
    }

    fn n(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// Column `j`'s entries on and above the diagonal, `(row, value)`.
    fn upper(&self, j: usize) -> impl Iterator<Item = (usize, f64)> + 'a {
        let range = self.col_ptr[j]..self.col_ptr[j + 1];
        let (rows, values) = (&self.row_idx[range.clone()], &self.values[range]);
        rows.iter()
            .zip(values)
            .map(|(&i, &v)| (i as usize, v))
            .filter(move |&(i, _)| i <= j)
    }

    /// `K_jj` (zero if the pattern has no such entry).
    fn diagonal(&self, j: usize) -> f64 {
        self.upper(j).find(|&(i, _)| i == j).map_or(0.0, |(_, v)| v)
    }
}

/// The upper triangle of `pattern` with `usize` row indices, for faer's
/// symbolic analysis (once a pattern; it reads the upper triangle only).
fn upper_triangle(pattern: &Pattern) -> (Vec<usize>, Vec<usize>) {
    let n = pattern.col_ptr.len() - 1;
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::with_capacity(pattern.row_idx.len() / 2 + n);
    col_ptr.push(0);
    for j in 0..n {
        let rows = &pattern.row_idx[pattern.col_ptr[j]..pattern.col_ptr[j + 1]];
        row_idx.extend(rows.iter().map(|&i| i as usize).filter(|&i| i <= j));
        col_ptr.push(row_idx.len());
    }
    (col_ptr, row_idx)
}

/// The triangle of `P K P^T` a numeric factorisation reads (lower for
/// supernodes, upper for a simplicial factor) in compressed columns, rows
/// unsorted, made from `K`'s upper triangle with each entry `K_ij` taken as
/// `entry(i, j, K_ij)`. faer's own path (`factorize_numeric_llt`) takes
/// `K` already in the factor's precision (a copy in the layout of both
/// triangles) and permutes it into buffers sized for every entry the
/// symbolic analysis saw; this holds the one triangle the factorisation
/// reads, and is all it needs besides the factor and a small scratch (at
/// 1e6 column points, 154 MB against 390 MB).
struct PermutedTriangle<T> {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<T>,
}

impl<T: Copy + Default> PermutedTriangle<T> {
    fn new(
        tangent: Tangent<'_>,
        perm_inv: Option<&[usize]>,
        lower: bool,
        entry: &impl Fn(usize, usize, f64) -> T,
    ) -> Self {
        let n = tangent.n();
        let new = |i: usize| perm_inv.map_or(i, |p| p[i]);
        // Where K_ij (i <= j) goes: its column and row in P K P^T's triangle.
        let place = |i: usize, j: usize| {
            let (a, b) = (new(i), new(j));
            if (a >= b) == lower { (b, a) } else { (a, b) }
        };
        let upper = |j: usize| tangent.upper(j).map(move |(i, v)| (i, entry(i, j, v)));
        let mut next = vec![0usize; n + 1];
        for j in 0..n {
            for (i, _) in upper(j) {
                next[place(i, j).0 + 1] += 1;
            }
        }
        for c in 0..n {
            next[c + 1] += next[c];
        }
        let col_ptr = next.clone();
        let nnz = col_ptr[n];
        let mut row_idx = vec![0; nnz];
        let mut values = vec![T::default(); nnz];
        for j in 0..n {
            for (i, v) in upper(j) {
                let (col, row) = place(i, j);
                row_idx[next[col]] = row;
                values[next[col]] = v;
                next[col] += 1;
            }
        }
        Self {
            col_ptr,
            row_idx,
            values,
        }
    }

    fn matrix(&self) -> SparseColMatRef<'_, usize, T> {
        let n = self.col_ptr.len() - 1;
        let structure =
            SymbolicSparseColMatRef::new_unsorted_checked(n, n, &self.col_ptr, None, &self.row_idx);
        SparseColMatRef::new(structure, &self.values)
    }

    fn bytes(&self) -> usize {
        std::mem::size_of_val(self.col_ptr.as_slice())
            + std::mem::size_of_val(self.row_idx.as_slice())
            + std::mem::size_of_val(self.values.as_slice())
    }
}

/// Factorises `K` (`tangent`, both triangles stored; the upper one is read,
/// as faer's own path reads it) by Cholesky on `symbolic` into `factor`,
/// each entry `K_ij` taken as `entry(i, j, K_ij)` (every entry is kept in
/// the pattern, zero or not):
/// whether it was positive definite, and the bytes needed besides the
/// factor (the permuted triangle and faer's scratch).
pub(crate) fn factorise<T: ComplexField + Copy + Default>(
    symbolic: &SymbolicCholesky<usize>,
    tangent: Tangent<'_>,
    entry: impl Fn(usize, usize, f64) -> T,
    factor: &mut [T],
    par: Par,
) -> (bool, usize) {
    let perm_inv = symbolic.perm().map(|p| p.arrays().1);
    let (ok, a_bytes, request) = match symbolic.raw() {
        SymbolicCholeskyRaw::Supernodal(s) => {
            let a = PermutedTriangle::new(tangent, perm_inv, true, &entry);
            let request = supernodal::factorize_supernodal_numeric_llt_scratch::<usize, T>(
                s,
                par,
                Default::default(),
            );
            let mut scratch = MemBuffer::new(request);
            let info = supernodal::factorize_supernodal_numeric_llt(
                factor,
                a.matrix(),
                Default::default(),
                s,
                par,
                MemStack::new(&mut scratch),
                Default::default(),
            );
            (info.is_ok(), a.bytes(), request)
        }
        SymbolicCholeskyRaw::Simplicial(s) => {
            let a = PermutedTriangle::new(tangent, perm_inv, false, &entry);
            let request =
                simplicial::factorize_simplicial_numeric_llt_scratch::<usize, T>(symbolic.nrows());
            let mut scratch = MemBuffer::new(request);
            let info = simplicial::factorize_simplicial_numeric_llt(
                factor,
                a.matrix(),
                Default::default(),
                s,
                MemStack::new(&mut scratch),
            );
            (info.is_ok(), a.bytes(), request)
        }
    };
    (ok, a_bytes + request.size_bytes())
}

/// Factorises `tangent` (its upper triangle) by Cholesky on `symbolic` and
/// solves for `b` (`None` when it is not positive definite), with the
/// bytes the factorisation needed besides the factor.
fn cholesky(
    symbolic: &SymbolicCholesky<usize>,
    tangent: Tangent<'_>,
    b: &Mat<f64>,
    par: Par,
    started: std::time::Instant,
) -> (Option<(Columns, Timing)>, usize) {
    let mut values = vec![0.0; symbolic.len_val()];
    let (ok, scratch_bytes) = factorise(symbolic, tangent, exact, &mut values, par);
    if !ok {
        return (None, scratch_bytes);
    }
    let factorise = started.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let mut x = b.clone();
    let mut scratch = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(b.ncols(), par));
    LltRef::new(symbolic, &values).solve_in_place_with_conj(
        Conj::No,
        x.as_mut(),
        par,
        MemStack::new(&mut scratch),
    );
    let timing = Timing {
        factorise,
        solve: t.elapsed().as_secs_f64(),
    };
    (Some((columns(&x), timing)), scratch_bytes)
}

/// Solves with a finished factorisation; the factorisation's time is the
/// time since `started`.
fn timed_solve(
    factors: &impl Solve<f64>,
    b: &Mat<f64>,
    started: std::time::Instant,
) -> (Vec<Vec<f64>>, Timing) {
    let factorise = started.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let x = factors.solve(b);
    let timing = Timing {
        factorise,
        solve: t.elapsed().as_secs_f64(),
    };
    (columns(&x), timing)
}

/// Solutions, one a right-hand side.
type Columns = Vec<Vec<f64>>;

/// Wall-clock seconds of one solve.
#[derive(Debug, Clone, Copy, Default)]
pub struct Timing {
    pub factorise: f64,
    pub solve: f64,
}

impl Timing {
    fn add(&mut self, other: Timing) {
        self.factorise += other.factorise;
        self.solve += other.solve;
    }
}

fn columns(x: &Mat<f64>) -> Vec<Vec<f64>> {
    (0..x.ncols())
        .map(|j| (0..x.nrows()).map(|i| x[(i, j)]).collect())
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The 5-point Laplacian of an m x m grid plus `shift` on the diagonal,
    /// both triangles stored.
    pub(crate) fn laplacian(m: usize, shift: f64) -> (Pattern, Vec<f64>) {
        let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
        for j in 0..m * m {
            let (x, y) = (j % m, j / m);
            let mut entries = vec![(j, 4.0 + shift)];
            if x > 0 {
                entries.push((j - 1, -1.0));
            }
            if x + 1 < m {
                entries.push((j + 1, -1.0));
            }
            if y > 0 {
                entries.push((j - m, -1.0));
            }
            if y + 1 < m {
                entries.push((j + m, -1.0));
            }
            entries.sort_by_key(|e| e.0);
            for (i, v) in entries {
                row_idx.push(i as u32);
                values.push(v);
            }
            col_ptr.push(row_idx.len());
        }
        (Pattern::from_columns(col_ptr, row_idx), values)
    }

    /// `pattern`'s row indices widened for faer's own functions.
    pub(crate) fn wide_rows(pattern: &Pattern) -> Vec<usize> {
        pattern.row_idx.iter().map(|&i| i as usize).collect()
    }

    /// A kept single-precision factor takes as zero exactly the
    /// entries below `2^-48 sqrt(K_ii K_jj)`, whatever the scale of their
    /// unknowns: a 4x4-node Laplacian (diagonal 4, so the cut is 2^-46)
    /// with unknown 5 scaled by 1e-15 (its entries, -1e-15 and 4e-30, are
    /// kept: a cut relative to the largest entry, or to the column's own
    /// diagonal alone, would drop them), an
    /// entry at half the cut (dropped) and one at twice it (kept).
    #[test]
    fn round_off_entries_are_zero_in_the_single_factor() {
        let (pattern, mut values) = laplacian(4, 0.0);
        let place = |row: usize, col: usize| {
            let rows = &pattern.row_idx[pattern.col_ptr[col]..pattern.col_ptr[col + 1]];
            let row = row as u32;
            pattern.col_ptr[col] + rows.binary_search(&row).unwrap()
        };
        let d = |i: usize| if i == 5 { 1e-15 } else { 1.0 };
        for col in 0..16 {
            for k in pattern.col_ptr[col]..pattern.col_ptr[col + 1] {
                values[k] *= d(pattern.row_idx[k] as usize) * d(col);
            }
        }
        let cut = 4.0 * ROUND_OFF;
        for (row, col, v) in [(0, 1, -0.5 * cut), (1, 2, -2.0 * cut)] {
            values[place(row, col)] = v;
            values[place(col, row)] = v;
        }
        let single = single_precision(Tangent::new(&pattern, &values));
        for col in 0..16 {
            for k in pattern.col_ptr[col]..pattern.col_ptr[col + 1] {
                let row = pattern.row_idx[k] as usize;
                let dropped = (row.min(col), row.max(col)) == (0, 1);
                let expected = if dropped { 0.0 } else { values[k] as f32 };
                assert_eq!(
                    single(row, col, values[k]),
                    expected,
                    "({row}, {col}): {}",
                    values[k]
                );
                assert!(dropped || expected != 0.0, "({row}, {col})");
            }
        }
    }

    /// The factor made from the one permuted triangle is faer's own
    /// (`factorize_numeric_llt`, which permutes both triangles itself), to
    /// the bit, in double precision and in single with the round-off cut
    /// (against faer's factor of the single-precision copy the cut makes):
    /// each entry of `K` lands in its place in the factor's storage
    /// unchanged, in whatever order, and the elimination is the same. For
    /// a supernodal and a simplicial factor, each by a custom order (a
    /// rotation of the unknowns, not its own inverse) and by faer's minimum
    /// degree; the symbolic analysis of the upper triangle alone (what the
    /// solver gives faer) is that of the whole pattern. The Laplacian's
    /// lower triangle is perturbed, so that reading it instead of the upper
    /// one would show; a few entries are round-off-small, so that the cut
    /// sets some to zero (a simplicial factor missing them as entries
    /// misses fill, and differs); the factor storage starts full of stale
    /// values.
    #[test]
    fn the_permuted_triangle_gives_faers_own_factor() {
        let m = 30;
        let n = m * m;
        let (pattern, mut values) = laplacian(m, 1e-2);
        for col in 0..n {
            for k in pattern.col_ptr[col]..pattern.col_ptr[col + 1] {
                let row = pattern.row_idx[k] as usize;
                if row > col {
                    values[k] *= 1.0 + 1e-3;
                }
                if (row.min(col) * 7) % 23 == 0 && row != col {
                    values[k] = -1e-16;
                }
            }
        }
        let rows = wide_rows(&pattern);
        let structure = SymbolicSparseColMatRef::new_checked(n, n, &pattern.col_ptr, None, &rows);
        let matrix = SparseColMatRef::new(structure, &values[..]);
        let tangent = Tangent::new(&pattern, &values);
        let cut = single_precision(tangent);
        let single: Vec<f32> = (0..n)
            .flat_map(|col| {
                let range = pattern.col_ptr[col]..pattern.col_ptr[col + 1];
                let (rows, values) = (&rows[range.clone()], &values[range]);
                rows.iter().zip(values).map(move |(&row, &v)| (row, col, v))
            })
            .map(|(row, col, v)| cut(row, col, v))
            .collect();
        let zeros = single.iter().filter(|&&v| v == 0.0).count();
        assert!(zeros >= 20, "{zeros} entries cut");
        // Unknown (k + 7m + 3) mod n eliminated k-th.
        let order: Vec<usize> = (0..n).map(|k| (k + 7 * m + 3) % n).collect();
        let mut inverse = vec![0; n];
        for (k, &dof) in order.iter().enumerate() {
            inverse[dof] = k;
        }
        let (upper_ptr, upper_rows) = upper_triangle(&pattern);
        let upper = SymbolicSparseColMatRef::new_checked(n, n, &upper_ptr, None, &upper_rows);
        for supernodal in [true, false] {
            for custom in [true, false] {
                let ordering = if custom {
                    SymmetricOrdering::Custom(PermRef::new_checked(&order, &inverse, n))
                } else {
                    SymmetricOrdering::Amd
                };
                let threshold = if supernodal {
                    faer::sparse::linalg::SupernodalThreshold::FORCE_SUPERNODAL
                } else {
                    faer::sparse::linalg::SupernodalThreshold::FORCE_SIMPLICIAL
                };
                let params = faer::sparse::linalg::cholesky::CholeskySymbolicParams {
                    supernodal_flop_ratio_threshold: threshold,
                    ..Default::default()
                };
                let symbolic =
                    factorize_symbolic_cholesky(structure, Side::Upper, ordering, params).unwrap();
                let from_upper =
                    factorize_symbolic_cholesky(upper, Side::Upper, ordering, params).unwrap();
                let perm = |s: &SymbolicCholesky<usize>| s.perm().map(|p| p.arrays().0.to_vec());
                assert_eq!(perm(&from_upper), perm(&symbolic));
                assert_eq!(from_upper.len_val(), symbolic.len_val());
                let is_supernodal = matches!(symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_));
                assert_eq!(is_supernodal, supernodal);
                let case = format!("supernodal {supernodal}, custom order {custom}");
                let ours = ours_against_faers(&symbolic, tangent, exact, matrix);
                assert_eq!(ours, 0, "double, {case}");
                let copy = SparseColMatRef::new(structure, &single[..]);
                let ours = ours_against_faers(&symbolic, tangent, &cut, copy);
                assert_eq!(ours, 0, "single, {case}");
            }
        }
    }

    /// Entries of the factor `factorise` makes of `tangent` by `entry` that
    /// differ, to the bit, from faer's factor of `copy`.
    fn ours_against_faers<T: ComplexField + Copy + Default + From<i8>>(
        symbolic: &SymbolicCholesky<usize>,
        tangent: Tangent<'_>,
        entry: impl Fn(usize, usize, f64) -> T,
        copy: SparseColMatRef<'_, usize, T>,
    ) -> usize {
        let mut ours = vec![T::from(7); symbolic.len_val()];
        assert!(factorise(symbolic, tangent, entry, &mut ours, Par::Seq).0);
        let mut faers = vec![T::default(); symbolic.len_val()];
        let request = symbolic.factorize_numeric_llt_scratch::<T>(Par::Seq, Default::default());
        let mut scratch = MemBuffer::new(request);
        symbolic
            .factorize_numeric_llt(
                &mut faers,
                copy,
                Side::Upper,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut scratch),
                Default::default(),
            )
            .unwrap();
        let bits = |v: &T| format!("{v:?}");
        ours.iter()
            .zip(&faers)
            .filter(|(a, b)| bits(a) != bits(b))
            .count()
    }

    /// What a solver foresees of its next solve (the equilibrium gives the
    /// points' spent responses back before a factorisation): a kept-factor
    /// solver factorises at its first symmetric solve and not at the next,
    /// whose stale factor serves; a direct one every time; LU (an
    /// unsymmetric tangent) every time.
    fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
        let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|x| x * x).sum::<f64>().sqrt();
        norm(&mut a.iter().zip(b).map(|(x, y)| x - y)) / norm(&mut b.iter().copied())
    }

    /// CG with a kept single-precision factor answers as a fresh double
    /// factorisation does, to the accuracy CG is asked for (1e-12 on the
    /// residual; the Laplacian's condition number, about 700 at m = 40,
    /// allows 1e-9 on the solution), first with the factor of the same
    /// matrix and then with it stale: 0.01 added to the diagonal moves the
    /// lowest eigenvalue (0.0117) by 85%, so CG needs several iterations,
    /// but far fewer than its limit of 30, and does not refactorise.
    /// A solver asked for multigrid without the grid its aggregates need
    /// solves by the kept factor instead, and says so: the answer is the
    /// direct one, reported as Cholesky's.
    #[test]
    fn multigrid_without_a_grid_falls_back_to_the_kept_factor() {
        let (pattern, values) = laplacian(30, 1e-3);
        let n = pattern.col_ptr.len() - 1;
        let b: Vec<f64> = (0..n).map(|i| ((i * 13) % 7) as f64 - 3.0).collect();
        let mut solver = SparseSolver::new(n, None, &SolverSettings::default(), Default::default())
            .with_method(SymmetricMethod::Multigrid);
        let (x, kind, _) = solver.solve(&pattern, &values, &b, true, 1e-12).unwrap();
        assert_eq!(kind, Factorisation::Cholesky);
        assert_eq!(solver.factorisations(), 1);
        let mut direct = SparseSolver::new(n, None, &SolverSettings::default(), Default::default())
            .with_method(SymmetricMethod::Direct);
        let (y, _, _) = direct.solve(&pattern, &values, &b, true, 1e-12).unwrap();
        assert!(
            relative_difference(&x, &y) < 1e-9,
            "{}",
            relative_difference(&x, &y)
        );
    }

    #[test]
    fn a_kept_factor_answers_as_a_fresh_one() {
        let m = 40;
        let rhs: Vec<f64> = (0..m * m).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        let mut kept =
            SparseSolver::new(m * m, None, &SolverSettings::default(), Default::default())
                .with_method(SymmetricMethod::KeptFactorCg);
        let mut direct =
            SparseSolver::new(m * m, None, &SolverSettings::default(), Default::default())
                .with_method(SymmetricMethod::Direct);
        for shift in [0.0, 0.01] {
            let (pattern, values) = laplacian(m, shift);
            let (x, kind, _) = kept.solve(&pattern, &values, &rhs, true, 1e-12).unwrap();
            let (y, _, _) = direct.solve(&pattern, &values, &rhs, true, 1e-12).unwrap();
            assert_eq!(kind, Factorisation::Cholesky);
            let cg = kept.last_cg().expect("CG ran");
            assert!(cg.converged, "{cg:?}");
            // The stale factor makes CG work for it; a fresh one hardly.
            assert!(
                (shift > 0.0) == (cg.iterations >= 3),
                "shift {shift}: {cg:?}"
            );
            assert_eq!(kept.factorisations(), 1);
            let difference = relative_difference(&x, &y);
            assert!(difference < 1e-9, "shift {shift}: {difference:e}");
        }
    }

    /// An indefinite symmetric matrix defeats the single and double kept
    /// factors and Cholesky; LU answers it.
    #[test]
    fn an_indefinite_tangent_falls_back_to_lu() {
        let m = 10;
        let (pattern, values) = laplacian(m, -4.5);
        let rhs = vec![1.0; m * m];
        let mut solver =
            SparseSolver::new(m * m, None, &SolverSettings::default(), Default::default())
                .with_method(SymmetricMethod::KeptFactorCg);
        let (x, kind, _) = solver.solve(&pattern, &values, &rhs, true, 1e-12).unwrap();
        assert_eq!(kind, Factorisation::Lu);
        let mut kx = vec![0.0; m * m];
        krylov::symmetric_product(&pattern.col_ptr, &pattern.row_idx, &values, &x, &mut kx);
        assert!(relative_difference(&kx, &rhs) < 1e-10);
    }
}
