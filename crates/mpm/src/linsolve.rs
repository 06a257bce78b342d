//! Sparse direct solves with faer, symbolic analysis once per load step.
//!
//! The pattern of the tangent is fixed during a step, so the fill-reducing
//! ordering and elimination tree are computed at the first iteration and
//! reused by every later one; only the numeric factorisation is repeated.
//! A symmetric tangent (hyperelastic material, dead loads) is factorised by
//! Cholesky; LU is used when the tangent is not symmetric, and as a fallback
//! when Cholesky meets a non-positive pivot (an indefinite tangent, e.g. past
//! a limit point). On this 2-core machine faer's sequential mode measured
//! about 1.8x faster than its rayon mode, so the solver sets `Par::Seq`.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Mat, Side};

use crate::assembly::Pattern;

/// Which factorisation produced a solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Factorisation {
    Cholesky,
    Lu,
}

/// A linear solver bound to one sparsity pattern.
pub struct SparseSolver {
    n: usize,
    llt: Option<SymbolicLlt<usize>>,
    lu: Option<SymbolicLu<usize>>,
    /// Seconds spent in symbolic analysis (reported inside factorisation time).
    pub symbolic_seconds: f64,
}

impl SparseSolver {
    pub fn new(n: usize) -> Self {
        faer::set_global_parallelism(faer::Par::Seq);
        Self {
            n,
            llt: None,
            lu: None,
            symbolic_seconds: 0.0,
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
                let s = std::time::Instant::now();
                self.llt = Some(
                    SymbolicLlt::try_new(structure, Side::Upper).map_err(|e| format!("{e:?}"))?,
                );
                self.symbolic_seconds += s.elapsed().as_secs_f64();
            }
            let symbolic = self.llt.clone().expect("just built");
            if let Ok(llt) = Llt::try_new_with_symbolic(symbolic, matrix, Side::Upper) {
                let (x, timing) = timed_solve(&llt, &b, t0);
                return Ok((x, Factorisation::Cholesky, timing));
            }
        }
        if self.lu.is_none() {
            let s = std::time::Instant::now();
            self.lu = Some(SymbolicLu::try_new(structure).map_err(|e| format!("{e:?}"))?);
            self.symbolic_seconds += s.elapsed().as_secs_f64();
        }
        let symbolic = self.lu.clone().expect("just built");
        let lu = Lu::try_new_with_symbolic(symbolic, matrix)
            .map_err(|e| format!("LU factorisation failed: {e:?}"))?;
        let (x, timing) = timed_solve(&lu, &b, t0);
        Ok((x, Factorisation::Lu, timing))
    }
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
