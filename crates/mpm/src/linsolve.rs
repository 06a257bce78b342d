//! Sparse direct solves with faer, symbolic analysis once per pattern.
//!
//! The pattern of the tangent is fixed during a step, so the fill-reducing
//! ordering and elimination tree are computed at the first iteration and
//! reused by every later one; only the numeric factorisation is repeated.
//! A step whose pattern equals the last step's (no point crossed into a
//! new cell's reach) takes over the last step's solver and its analysis
//! ([`crate::equilibrium::StepEquilibrium::new`]).
//! A symmetric tangent (hyperelastic material, dead loads) is factorised by
//! Cholesky; LU is used when the tangent is not symmetric, and as a fallback
//! when Cholesky meets a non-positive pivot (an indefinite tangent, e.g. past
//! a limit point). Cholesky orders the unknowns by nested dissection of the
//! grid's active nodes (`ordering.rs`) when it is given them, and runs on
//! rayon's threads for the largest systems; LU keeps faer's COLAMD and
//! sequential mode (which measured about 1.8x faster than its rayon mode
//! at 1e5 unknowns on this 2-core machine).

use std::sync::atomic::{AtomicU8, AtomicUsize, Ordering as Atomic};

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Mat, Par, Side};

use crate::assembly::Pattern;

/// The fill-reducing ordering of a Cholesky factorisation (LU orders its
/// columns by faer's COLAMD, which takes no other).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FillOrdering {
    /// faer's approximate minimum degree.
    MinimumDegree,
    /// Nested dissection of the active nodes by grid lines (`ordering.rs`),
    /// when the solver is given the nodes.
    NestedDissection,
}

static ORDERING: AtomicU8 = AtomicU8::new(1);
/// Entries of the last Cholesky factor in this process, for benchmarks.
static LAST_FACTOR_ENTRIES: AtomicUsize = AtomicUsize::new(0);
/// Steps of this process that analysed their pattern, and that took over
/// the last step's analysis, for benchmarks.
static ANALYSED: AtomicUsize = AtomicUsize::new(0);
static REUSED: AtomicUsize = AtomicUsize::new(0);

/// Solvers this process built for a new pattern, and solvers it reused for
/// an unchanged one (see [`SparseSolver::reused`]).
pub fn solver_reuse_counts() -> (usize, usize) {
    (ANALYSED.load(Atomic::Relaxed), REUSED.load(Atomic::Relaxed))
}

/// Entries (the fill) of the last Cholesky factor this process computed;
/// 0 before the first.
pub fn last_factor_entries() -> usize {
    LAST_FACTOR_ENTRIES.load(Atomic::Relaxed)
}

/// The ordering every later Cholesky factorisation in this process uses
/// (for benchmarks comparing them; nested dissection by default).
pub fn set_fill_ordering(ordering: FillOrdering) {
    ORDERING.store(ordering as u8, Atomic::Relaxed);
}

pub fn fill_ordering() -> FillOrdering {
    match ORDERING.load(Atomic::Relaxed) {
        0 => FillOrdering::MinimumDegree,
        _ => FillOrdering::NestedDissection,
    }
}

/// Which factorisation produced a solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Factorisation {
    Cholesky,
    Lu,
}

/// From this many unknowns up, Cholesky factorises on rayon's threads:
/// measured on the GIMP column (2 cores, `mpm bench-row`, one run each),
/// sequential was 1.28x faster at 48k DOFs and parallel 1.15x faster at
/// 479k; the crossover lies between, and this splits the difference.
const PARALLEL_FROM_DOFS: usize = 150_000;

/// A linear solver bound to one sparsity pattern.
pub struct SparseSolver {
    n: usize,
    /// The nested-dissection order of the DOFs, `order[k]` eliminated k-th,
    /// and its inverse.
    order: Option<(Vec<usize>, Vec<usize>)>,
    llt: Option<SymbolicCholesky<usize>>,
    lu: Option<SymbolicLu<usize>>,
    /// Bytes of the last Cholesky factorisation: its values and its
    /// numeric scratch.
    factor_bytes: usize,
    scratch_bytes: usize,
    /// Later systems (load steps) this solver was reused for.
    reuses: usize,
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
}

impl SparseSolver {
    /// A solver of `n` unknowns; `order`, when given (and the process's
    /// [`fill_ordering`] is nested dissection), is the elimination order
    /// of Cholesky factorisations.
    pub fn new(n: usize, order: Option<Vec<usize>>) -> Self {
        faer::set_global_parallelism(faer::Par::Seq);
        ANALYSED.fetch_add(1, Atomic::Relaxed);
        let order = order
            .filter(|_| fill_ordering() == FillOrdering::NestedDissection)
            .map(|order| {
                let mut inverse = vec![0; n];
                for (k, &dof) in order.iter().enumerate() {
                    inverse[dof] = k;
                }
                (order, inverse)
            });
        Self {
            n,
            order,
            llt: None,
            lu: None,
            factor_bytes: 0,
            scratch_bytes: 0,
            reuses: 0,
        }
    }

    /// This solver, for a later system of the same pattern (the caller
    /// checks that it is): counted for [`solver_reuse_counts`].
    pub fn reused(mut self) -> Self {
        REUSED.fetch_add(1, Atomic::Relaxed);
        self.reuses += 1;
        self
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
        SolverMemory {
            factor_values: self.factor_bytes,
            factor_structure: structure,
            scratch: self.scratch_bytes,
        }
    }

    fn structure<'a>(&self, pattern: &'a Pattern) -> SymbolicSparseColMatRef<'a, usize> {
        SymbolicSparseColMatRef::new_checked(
            self.n,
            self.n,
            &pattern.col_ptr,
            None,
            &pattern.row_idx,
        )
    }

    /// Factorises `K` (values in the layout of `pattern`) and solves
    /// `K x = rhs`. Returns the factorisation used, or a message.
    pub fn solve(
        &mut self,
        pattern: &Pattern,
        values: &[f64],
        rhs: &[f64],
        symmetric: bool,
    ) -> Result<(Vec<f64>, Factorisation, Timing), String> {
        let t0 = std::time::Instant::now();
        let structure = self.structure(pattern);
        let matrix = SparseColMatRef::new(structure, values);
        let b = Mat::from_fn(self.n, 1, |i, _| rhs[i]);
        if symmetric {
            if self.llt.is_none() {
                let ordering = match &self.order {
                    Some((order, inverse)) => {
                        SymmetricOrdering::Custom(PermRef::new_checked(order, inverse, self.n))
                    }
                    None => SymmetricOrdering::Amd,
                };
                self.llt = Some(
                    factorize_symbolic_cholesky(
                        structure,
                        Side::Upper,
                        ordering,
                        Default::default(),
                    )
                    .map_err(|e| format!("{e:?}"))?,
                );
            }
            let symbolic = self.llt.as_ref().expect("just built");
            let par = if self.n >= PARALLEL_FROM_DOFS {
                Par::rayon(0)
            } else {
                Par::Seq
            };
            let scratch = symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default());
            self.scratch_bytes = scratch.size_bytes();
            self.factor_bytes = symbolic.len_val() * std::mem::size_of::<f64>();
            if let Some((x, timing)) = cholesky(symbolic, matrix, &b, par, t0) {
                LAST_FACTOR_ENTRIES.store(symbolic.len_val(), Atomic::Relaxed);
                return Ok((x, Factorisation::Cholesky, timing));
            }
        }
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

/// Factorises `matrix` (its upper triangle) by Cholesky on `symbolic` and
/// solves for `b`; `None` when it is not positive definite.
fn cholesky(
    symbolic: &SymbolicCholesky<usize>,
    matrix: SparseColMatRef<'_, usize, f64>,
    b: &Mat<f64>,
    par: Par,
    started: std::time::Instant,
) -> Option<(Vec<f64>, Timing)> {
    let mut values = vec![0.0; symbolic.len_val()];
    let mut scratch =
        MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
    let llt = symbolic
        .factorize_numeric_llt(
            &mut values,
            matrix,
            Side::Upper,
            Default::default(),
            par,
            MemStack::new(&mut scratch),
            Default::default(),
        )
        .ok()?;
    let factorise = started.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let mut x = b.clone();
    let mut scratch = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, par));
    llt.solve_in_place_with_conj(Conj::No, x.as_mut(), par, MemStack::new(&mut scratch));
    let timing = Timing {
        factorise,
        solve: t.elapsed().as_secs_f64(),
    };
    Some((column(&x), timing))
}

/// Solves with a finished factorisation; the factorisation's time is the
/// time since `started`.
fn timed_solve(
    factors: &impl Solve<f64>,
    b: &Mat<f64>,
    started: std::time::Instant,
) -> (Vec<f64>, Timing) {
    let factorise = started.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let x = factors.solve(b);
    let timing = Timing {
        factorise,
        solve: t.elapsed().as_secs_f64(),
    };
    (column(&x), timing)
}

/// Wall-clock seconds of one solve.
#[derive(Debug, Clone, Copy, Default)]
pub struct Timing {
    pub factorise: f64,
    pub solve: f64,
}

fn column(x: &Mat<f64>) -> Vec<f64> {
    (0..x.nrows()).map(|i| x[(i, 0)]).collect()
}
