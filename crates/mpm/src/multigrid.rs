//! Smoothed-aggregation algebraic multigrid: a preconditioner for CG on
//! symmetric tangents whose memory grows linearly with the unknowns, where
//! a Cholesky factor's grows as `n log n` (at 1e7 GIMP column points the
//! kept single-precision factor is 8.2 GB, two fifths of the step's peak).
//!
//! The method is Vanek, Mandel & Brezina (1996), "Algebraic multigrid by
//! smoothed aggregation for second and fourth order elliptic problems",
//! with the rigid-body modes as the near-null space (their section 5 for
//! elasticity):
//!
//! - **Aggregates** are blocks of 3 grid nodes a side (3 x 3 in plane
//!   strain, 3 x 3 x 3 in 3D; the active nodes carry integer grid
//!   coordinates, as in `ordering.rs`), and on every coarser level blocks
//!   of 3 a side of the aggregates below. A structured grid needs
//!   no strength-of-connection graph to find them.
//! - **Tentative prolongation.** On each aggregate, the near-null-space
//!   vectors (two translations and the rotation in plane strain, three
//!   of each in 3D) restricted to its DOFs are orthonormalised; they are
//!   the columns of the tentative prolongator `T`, and their coefficients
//!   (the QR's `R`) the coarse level's near-null space. A DOF a support holds (its row
//!   is the diagonal alone) is left out of every column.
//! - **Smoothed prolongation** `P = (I - w D^-1 A) T`, `w = 4 / (3 l)`,
//!   `l` the smoother's bound on the largest eigenvalue of `D^-1 A` (an
//!   estimate with a margin, at most Gershgorin's bound).
//! - **Galerkin coarse operators** `A_c = P^T A P`, down to a level small
//!   enough for a dense Cholesky factorisation.
//! - **Smoothing** by a Chebyshev polynomial in `D^-1 A` (Adams, Brezina,
//!   Hu & Tuminaro 2003, "Parallel multigrid smoothing: polynomial versus
//!   Gauss-Seidel"), of degree 1 (damped Jacobi with the Chebyshev
//!   interval's weight; [`DEGREE`] says why; [`WIDE_DEGREE`] for the
//!   B-splines' wider stencils): only products with `A`, so
//!   it runs on every thread, and the same polynomial before and after
//!   the coarse correction makes the V-cycle a symmetric positive definite
//!   operator, as CG needs.

use faer::linalg::solvers::{Llt, Solve};
use faer::{Mat, MatMut, Side};
use rayon::prelude::*;

use crate::krylov;

/// Nodes (or aggregates) per aggregate in each direction.
const BLOCK: i64 = 3;
/// A level with at most this many unknowns is solved by a dense Cholesky
/// factorisation (1,500^3 / 3 flops, about 0.1 s, and 18 MB at most).
const COARSEST: usize = 1500;
/// Coarse rows a band of the Galerkin product ([`galerkin`]) makes at a
/// time: 5 bands on the first coarse level at 1e6 GIMP column points,
/// one below 16k coarse unknowns.
const GALERKIN_BAND: usize = 16_384;
/// Levels below the finest, at most; aggregation by 3 x 3 blocks divides
/// the unknowns by about 6 per level (3 x 3 x 3 in 3D, by about 13), so 12 reach a dense level from any
/// size this machine can hold.
const MAX_LEVELS: usize = 12;
/// Degree of the Chebyshev smoother, before and after the coarse
/// correction, for a basis whose nodes couple at most two apart (GIMP,
/// linear). Each degree is a product with the level's operator, and
/// the finest level's products are most of a V-cycle's cost. Measured on
/// the GIMP column at 3e5 points (first two steps, alternating runs):
/// degree 1 took 1.06-1.22 s a step in CG against 1.74-1.97 s for degree
/// 2, with the same CG iterations (85; with an eigenvalue margin of 1.1,
/// since raised); on the plate of the tests, 20 iterations against 17.
/// The paper's cantilever at 1e6 points (GMRES, `mpm bench-row 2`): 9.4 s
/// a step at degree 1, 11.5 s at degree 2 (107 iterations against 114).
const DEGREE: usize = 1;
/// The degree for the B-splines (quadratic and cubic), whose smoother
/// shape functions reach farther (a quadratic B-spline point's 4 x 4
/// nodes, 3 x 3 while its domain lies within one cell; more on cubic
/// ones). The paper's cantilever on
/// quadratic B-splines at 1e6 points (`mpm bench-row 3`): 46.7, 36.9 and
/// 34.7 s a step at degrees 1, 2 and 3 (GMRES iterations 305, 170, 126;
/// this session's host, one run each).
const WIDE_DEGREE: usize = 3;
/// The smoother damps `D^-1 A`'s spectrum from its largest eigenvalue down
/// to this fraction of it (the rest is the coarse levels' work); 1/30 as
/// in Adams et al. (2003).
const SMOOTHED_FRACTION: f64 = 1.0 / 30.0;
/// Power iterations estimating `D^-1 A`'s largest eigenvalue, and the
/// margin put on the estimate (a Rayleigh quotient, so from below). The
/// V-cycle is positive definite only if the top of the smoother's
/// interval is above about 0.97 of the largest eigenvalue; on the tests'
/// plate at 116k DOFs the estimate was 0.85 of it (2.01 against 2.37,
/// from 300 iterations), and with a margin of 1.1 CG broke down. The top
/// is never put above Gershgorin's bound, which is safe.
const POWER_ITERATIONS: usize = 15;
const EIGENVALUE_MARGIN: f64 = 1.25;
/// Power iterations fitting the finest smoother to a later tangent, from
/// the last eigenvector estimate.
const REFIT_ITERATIONS: usize = 4;
/// A near-null-space vector whose part orthogonal to the ones before it
/// is below this fraction of its norm on an aggregate is dependent there
/// (a one-node aggregate rotates as it translates).
const DEPENDENT: f64 = 1e-8;

/// A matrix in compressed rows, 32-bit column indices; as an operator of
/// the hierarchy, a symmetric one with both triangles stored (so its rows
/// are its columns too: the tangent's compressed columns serve).
#[derive(Clone, Copy)]
pub(crate) struct Operator<'a, T = f64> {
    pub ptr: &'a [usize],
    pub col: &'a [u32],
    pub val: &'a [T],
}

impl<'a, T: Copy + Into<f64>> Operator<'a, T> {
    fn n(self) -> usize {
        self.ptr.len() - 1
    }

    fn row(self, i: usize) -> impl Iterator<Item = (usize, f64)> + 'a {
        let range = self.ptr[i]..self.ptr[i + 1];
        self.col[range.clone()]
            .iter()
            .zip(&self.val[range])
            .map(|(&c, &v)| (c as usize, v.into()))
    }
}

impl Operator<'_> {
    fn product(&self, x: &[f64], y: &mut [f64]) {
        krylov::symmetric_product(self.ptr, self.col, self.val, x, y);
    }
}

/// A matrix in compressed rows, 32-bit column indices.
struct Rows<T> {
    ptr: Vec<usize>,
    col: Vec<u32>,
    val: Vec<T>,
}

impl<T: Entry> Rows<T> {
    /// Builds `n_rows` rows over `n_cols` columns, row `i`'s entries the
    /// sums `fill(i, acc)` adds into `acc`, on rayon's threads: pieces of
    /// [`CHUNK`] rows, each made once, then put end to end
    /// ([`Rows::concatenate`], which gives each piece back as it copies
    /// it, so the rows are held about once).
    fn build(n_rows: usize, n_cols: usize, fill: impl Fn(usize, &mut Accumulator) + Sync) -> Self {
        let pieces = n_rows.div_ceil(CHUNK);
        // A few runs of pieces a thread, each run with one accumulator (a
        // dense row of `n_cols`).
        let run = pieces.div_ceil(4 * rayon::current_num_threads()).max(1);
        let pieces: Vec<Self> = (0..pieces)
            .into_par_iter()
            .with_min_len(run)
            .map_init(
                || Accumulator::new(n_cols),
                |acc, piece| {
                    let rows = piece * CHUNK..((piece + 1) * CHUNK).min(n_rows);
                    let mut made = Self {
                        ptr: Vec::with_capacity(rows.len() + 1),
                        col: Vec::new(),
                        val: Vec::new(),
                    };
                    made.ptr.push(0);
                    for i in rows {
                        fill(i, acc);
                        for (c, v) in acc.drain() {
                            made.col.push(c);
                            made.val.push(T::from_f64(v));
                        }
                        made.ptr.push(made.col.len());
                    }
                    made
                },
            )
            .collect();
        Self::concatenate(pieces)
    }

    fn n_rows(&self) -> usize {
        self.ptr.len() - 1
    }

    /// The rows of `parts`, one after another. The first part's storage
    /// is grown in place (a large block is remapped, not copied), and each
    /// other part given back once copied.
    fn concatenate(parts: Vec<Self>) -> Self {
        let mut parts = parts.into_iter();
        let Some(mut whole) = parts.next() else {
            return Self {
                ptr: vec![0],
                col: Vec::new(),
                val: Vec::new(),
            };
        };
        let rest: Vec<Self> = parts.collect();
        let (rows, nnz) = rest.iter().fold((0, 0), |(r, n), part| {
            (r + part.n_rows(), n + part.col.len())
        });
        whole.ptr.reserve_exact(rows);
        whole.col.reserve_exact(nnz);
        whole.val.reserve_exact(nnz);
        for part in rest {
            let offset = whole.col.len();
            whole.ptr.extend(part.ptr[1..].iter().map(|k| k + offset));
            whole.col.extend_from_slice(&part.col);
            whole.val.extend_from_slice(&part.val);
        }
        whole
    }

    fn row(&self, i: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.view().row(i)
    }

    fn view(&self) -> Operator<'_, T> {
        Operator {
            ptr: &self.ptr,
            col: &self.col,
            val: &self.val,
        }
    }

    fn bytes(&self) -> usize {
        std::mem::size_of_val(self.ptr.as_slice())
            + std::mem::size_of_val(self.col.as_slice())
            + std::mem::size_of_val(self.val.as_slice())
    }
}

/// The value types a [`Rows`] stores: the prolongators in single
/// precision (they only shape the preconditioner, and the restriction
/// reads the same numbers, so the V-cycle stays symmetric), the coarse
/// operators in double.
trait Entry: Copy + Default + Send + Sync + Into<f64> {
    fn from_f64(v: f64) -> Self;
}

impl Entry for f32 {
    fn from_f64(v: f64) -> Self {
        v as f32
    }
}

impl Entry for f64 {
    fn from_f64(v: f64) -> Self {
        v
    }
}

/// Rows a piece of [`Rows::build`] makes.
const CHUNK: usize = 2048;

/// One row's sums, by column, over a dense array stamped by row.
struct Accumulator {
    value: Vec<f64>,
    seen: Vec<bool>,
    cols: Vec<u32>,
}

impl Accumulator {
    fn new(n_cols: usize) -> Self {
        Self {
            value: vec![0.0; n_cols],
            seen: vec![false; n_cols],
            cols: Vec::new(),
        }
    }

    fn add(&mut self, col: usize, v: f64) {
        if self.seen[col] {
            self.value[col] += v;
        } else {
            self.seen[col] = true;
            self.value[col] = v;
            self.cols.push(col as u32);
        }
    }

    /// The row's entries in column order; the accumulator is empty after.
    fn drain(&mut self) -> impl Iterator<Item = (u32, f64)> + '_ {
        self.cols.sort_unstable();
        let (value, seen) = (&self.value, &mut self.seen);
        self.cols.drain(..).map(move |c| {
            seen[c as usize] = false;
            (c, value[c as usize])
        })
    }
}

/// One level above the coarsest: its operator (the caller's on the finest
/// level), its smoother, and the prolongation from the level below.
struct Level {
    a: Option<Rows<f64>>,
    inv_diag: Vec<f64>,
    /// The top of `D^-1 A`'s spectrum, with [`EIGENVALUE_MARGIN`].
    top: f64,
    /// The power iterations' last iterate, on the finest level (whose
    /// smoother is fitted to later tangents from it).
    eigenvector: Vec<f64>,
    p: Rows<f32>,
    n_coarse: usize,
}

/// Vectors a V-cycle works in on one level.
struct Work {
    r: Vec<f64>,
    d: Vec<f64>,
    t: Vec<f64>,
    /// The restricted residual, then the coarse correction.
    x_coarse: Vec<f64>,
    /// One partial restriction a thread.
    partial: Vec<Vec<f64>>,
}

/// A multigrid hierarchy built on one tangent; [`Hierarchy::apply`] is one
/// V-cycle with the current tangent on the finest level.
pub struct Hierarchy {
    levels: Vec<Level>,
    /// The smoother's degree ([`DEGREE`], [`WIDE_DEGREE`]).
    degree: usize,
    coarsest: Llt<f64>,
    coarsest_n: usize,
    work: Vec<Work>,
}

/// Why no hierarchy was built.
#[derive(Debug, Clone, PartialEq)]
pub enum SetupError {
    /// Aggregation stopped shrinking the problem before a dense level.
    NoCoarsening { unknowns: usize },
    /// An operator with no positive diagonal (or a NaN), or a coarsest
    /// operator that is not positive definite.
    NotPositiveDefinite,
}

impl Hierarchy {
    /// The hierarchy of `a`, whose DOFs `D k` to `D k + D - 1` are the
    /// displacements of the node at grid coordinates `nodes[k]`; `wide`
    /// for the B-splines' stencils ([`WIDE_DEGREE`]).
    pub(crate) fn new<const D: usize>(
        a: Operator<'_>,
        nodes: &[[i64; D]],
        wide: bool,
    ) -> Result<Self, SetupError> {
        assert_eq!(a.n(), D * nodes.len());
        let mut coords = nodes.to_vec();
        let mut dof_start: Vec<usize> = (0..=nodes.len()).map(|k| D * k).collect();
        let mut modes = rigid_body_modes(a, nodes);
        let degree = if wide { WIDE_DEGREE } else { DEGREE };
        let mut levels: Vec<Level> = Vec::new();
        let mut owned: Option<Rows<f64>> = None;
        loop {
            let op = owned.as_ref().map_or(a, Rows::view);
            let n = op.n();
            if n <= COARSEST {
                break;
            }
            if levels.len() == MAX_LEVELS {
                return Err(SetupError::NoCoarsening { unknowns: n });
            }
            let mut eigenvector = power_start(n);
            let (inv_diag, top) = smoother(op, &mut eigenvector, POWER_ITERATIONS);
            if !(top.is_finite() && top > 0.0) {
                // No positive diagonal, or a NaN in the operator.
                return Err(SetupError::NotPositiveDefinite);
            }
            if !levels.is_empty() {
                // Only the finest level's smoother is fitted again.
                eigenvector = Vec::new();
            }
            let (aggregate_of, coarse_coords) = aggregate(&coords);
            let tentative = Tentative::new(&aggregate_of, coarse_coords.len(), &dof_start, &modes);
            let n_coarse = tentative.n_coarse;
            if n_coarse * 4 > n * 3 {
                return Err(SetupError::NoCoarsening { unknowns: n });
            }
            let p = smoothed_prolongator(op, &inv_diag, 4.0 / (3.0 * top), &tentative);
            let coarse = galerkin(op, &p, n_coarse, GALERKIN_BAND);
            modes = tentative.coarse_modes;
            dof_start = tentative.coarse_dof_start;
            coords = coarse_coords;
            levels.push(Level {
                a: owned.take(),
                inv_diag,
                top,
                eigenvector,
                p,
                n_coarse,
            });
            owned = Some(coarse);
        }
        let op = owned.as_ref().map_or(a, Rows::view);
        let n = op.n();
        let mut dense = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            for (j, v) in op.row(i) {
                dense[(i, j)] = v;
            }
        }
        let coarsest = dense
            .llt(Side::Lower)
            .map_err(|_| SetupError::NotPositiveDefinite)?;
        let work = levels
            .iter()
            .map(|level| {
                let n = level.inv_diag.len();
                Work {
                    r: vec![0.0; n],
                    d: vec![0.0; n],
                    t: vec![0.0; n],
                    x_coarse: vec![0.0; level.n_coarse],
                    partial: vec![vec![0.0; level.n_coarse]; rayon::current_num_threads()],
                }
            })
            .collect();
        Ok(Self {
            levels,
            degree,
            coarsest,
            coarsest_n: n,
            work,
        })
    }

    /// Fits the finest level's smoother to `a`, a later tangent of the
    /// pattern the hierarchy was built on: its diagonal, and the top of
    /// its spectrum, which may have grown beyond what the smoother damps
    /// (a Chebyshev polynomial grows outside its interval; with the first
    /// tangent's smoother, CG on the column's second tangent stalled).
    pub(crate) fn fit_finest(&mut self, a: Operator<'_>) {
        if let Some(finest) = self.levels.first_mut() {
            (finest.inv_diag, finest.top) = smoother(a, &mut finest.eigenvector, REFIT_ITERATIONS);
        }
    }

    /// Unknowns on each level, finest first.
    pub fn level_sizes(&self) -> Vec<usize> {
        let mut sizes: Vec<usize> = self.levels.iter().map(|l| l.inv_diag.len()).collect();
        sizes.push(self.coarsest_n);
        sizes
    }

    /// Bytes the hierarchy holds (the finest operator is the caller's).
    pub fn bytes(&self) -> usize {
        let f64s = |n: usize| n * std::mem::size_of::<f64>();
        let levels: usize = self
            .levels
            .iter()
            .map(|l| {
                l.a.as_ref().map_or(0, Rows::bytes)
                    + f64s(l.inv_diag.len() + l.eigenvector.len())
                    + l.p.bytes()
            })
            .sum();
        let work: usize = self
            .work
            .iter()
            .map(|w| {
                let partial: usize = w.partial.iter().map(Vec::len).sum();
                f64s(w.r.len() + w.d.len() + w.t.len() + w.x_coarse.len() + partial)
            })
            .sum();
        levels + work + f64s(self.coarsest_n * self.coarsest_n)
    }

    /// Replaces `z` by one V-cycle's approximation of `A^-1 z`, with `a`
    /// (of the pattern the hierarchy was built on) the finest operator.
    pub(crate) fn apply(&mut self, a: Operator<'_>, z: &mut [f64]) {
        v_cycle(
            &self.levels,
            self.degree,
            &self.coarsest,
            a,
            &mut self.work,
            z,
        );
    }
}

/// One V-cycle from the level `levels[0]` down: `x` holds the right-hand
/// side on entry and the approximate solution on exit.
fn v_cycle(
    levels: &[Level],
    degree: usize,
    coarsest: &Llt<f64>,
    a: Operator<'_>,
    work: &mut [Work],
    x: &mut [f64],
) {
    let (Some((level, coarser)), Some((w, coarser_work))) =
        (levels.split_first(), work.split_first_mut())
    else {
        let n = x.len();
        coarsest.solve_in_place(MatMut::from_column_major_slice_mut(x, n, 1));
        return;
    };
    let op = level.a.as_ref().map_or(a, Rows::view);
    w.r.copy_from_slice(x);
    x.fill(0.0);
    chebyshev(op, level, degree, x, w, true);
    restrict(&level.p, &w.r, &mut w.partial, &mut w.x_coarse);
    v_cycle(coarser, degree, coarsest, a, coarser_work, &mut w.x_coarse);
    // The coarse correction e = P x_c, and r = b - A x kept with it.
    prolong(&level.p, &w.x_coarse, &mut w.d);
    x.par_iter_mut().zip(&w.d).for_each(|(x, d)| *x += d);
    op.product(&w.d, &mut w.t);
    w.r.par_iter_mut().zip(&w.t).for_each(|(r, t)| *r -= t);
    chebyshev(op, level, degree, x, w, false);
}

/// `degree` steps of Chebyshev iteration on `A x = b` preconditioned by
/// `D^-1`, from `x` with `w.r = b - A x`, over `[top * SMOOTHED_FRACTION,
/// top]` (Saad, "Iterative methods for sparse linear systems", 2nd ed.,
/// algorithm 12.1). `w.r` is kept equal to `b - A x` if `keep_residual`.
fn chebyshev(
    op: Operator<'_>,
    level: &Level,
    degree: usize,
    x: &mut [f64],
    w: &mut Work,
    keep_residual: bool,
) {
    let (hi, lo) = (level.top, level.top * SMOOTHED_FRACTION);
    let (theta, delta) = ((hi + lo) / 2.0, (hi - lo) / 2.0);
    let sigma = theta / delta;
    let mut rho = 1.0 / sigma;
    let inv_diag = &level.inv_diag;
    w.d.par_iter_mut()
        .zip(&w.r)
        .zip(inv_diag)
        .for_each(|((d, r), m)| *d = m * r / theta);
    for k in 0..degree {
        x.par_iter_mut().zip(&w.d).for_each(|(x, d)| *x += d);
        let last = k + 1 == degree;
        if last && !keep_residual {
            break;
        }
        op.product(&w.d, &mut w.t);
        w.r.par_iter_mut().zip(&w.t).for_each(|(r, t)| *r -= t);
        if last {
            break;
        }
        let rho_next = 1.0 / (2.0 * sigma - rho);
        let (keep, step) = (rho_next * rho, 2.0 * rho_next / delta);
        w.d.par_iter_mut()
            .zip(&w.r)
            .zip(inv_diag)
            .for_each(|((d, r), m)| *d = keep * *d + step * m * r);
        rho = rho_next;
    }
}

/// `x_c = P^T r`: each of `partial`'s sums over its share of the fine
/// rows, on its own thread, then their total.
fn restrict(p: &Rows<f32>, r: &[f64], partial: &mut [Vec<f64>], x_coarse: &mut [f64]) {
    let rows = p.n_rows();
    let share = rows.div_ceil(partial.len().max(1));
    partial.par_iter_mut().enumerate().for_each(|(k, sum)| {
        sum.fill(0.0);
        for i in k * share..((k + 1) * share).min(rows) {
            for (c, v) in p.row(i) {
                sum[c] += v * r[i];
            }
        }
    });
    x_coarse
        .par_iter_mut()
        .enumerate()
        .for_each(|(c, x)| *x = partial.iter().map(|sum| sum[c]).sum());
}

/// `e = P x_c`.
fn prolong(p: &Rows<f32>, x_coarse: &[f64], e: &mut [f64]) {
    krylov::symmetric_product(&p.ptr, &p.col, &p.val, x_coarse, e);
}

/// A level's smoother: `D^-1` (zero where the diagonal is not positive),
/// and the top of `D^-1 A`'s spectrum with [`EIGENVALUE_MARGIN`], at most
/// Gershgorin's bound.
fn smoother(op: Operator<'_>, v: &mut [f64], iterations: usize) -> (Vec<f64>, f64) {
    let inv_diag: Vec<f64> = (0..op.n())
        .into_par_iter()
        .map(|i| {
            let d = op.row(i).find(|&(c, _)| c == i).map_or(0.0, |(_, v)| v);
            if d > 0.0 { 1.0 / d } else { 0.0 }
        })
        .collect();
    let estimate = EIGENVALUE_MARGIN * largest_eigenvalue(op, &inv_diag, v, iterations);
    // Gershgorin: no eigenvalue of D^-1 A lies above its largest row sum.
    let bound = (0..op.n())
        .into_par_iter()
        .map(|i| inv_diag[i] * op.row(i).map(|(_, a)| a.abs()).sum::<f64>())
        .reduce(|| 0.0, f64::max);
    (inv_diag, estimate.min(bound))
}

/// A start for the power iterations with every mode in it, the same from
/// run to run (so is a hierarchy): a hash of the index, in [-1, 1).
fn power_start(n: usize) -> Vec<f64> {
    (0..n as u64)
        .map(|i| {
            let h = i.wrapping_mul(0x9E37_79B9_7F4A_7C15).rotate_left(29);
            (h >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        })
        .collect()
}

/// `D^-1 A`'s largest eigenvalue, estimated from below by the Rayleigh
/// quotient `v.Av / v.Dv` after `iterations` power iterations from `v`,
/// which is left the last iterate.
fn largest_eigenvalue(op: Operator<'_>, inv_diag: &[f64], v: &mut [f64], iterations: usize) -> f64 {
    let n = op.n();
    let mut av = vec![0.0; n];
    let mut estimate = 0.0;
    for _ in 0..iterations {
        op.product(v, &mut av);
        // In a fixed order: the estimate sets the smoother, and with it
        // every later answer's bits.
        let kept = |i: usize| inv_diag[i] > 0.0;
        let vav = krylov::ordered_sum(n, |range| {
            range.filter(|&i| kept(i)).map(|i| v[i] * av[i]).sum()
        });
        let vdv = krylov::ordered_sum(n, |range| {
            range
                .filter(|&i| kept(i))
                .map(|i| v[i] * v[i] / inv_diag[i])
                .sum()
        });
        estimate = if vdv > 0.0 { vav / vdv } else { 0.0 };
        let scale = av
            .par_iter()
            .zip(inv_diag)
            .map(|(a, m)| (a * m).abs())
            .reduce(|| 0.0, f64::max);
        if scale == 0.0 {
            break;
        }
        v.par_iter_mut()
            .zip(&av)
            .zip(inv_diag)
            .for_each(|((v, a), m)| *v = a * m / scale);
    }
    estimate
}

/// Near-null-space vectors, one row of `width` values a DOF: the rigid
/// body modes on the finest level (3 in plane strain, 6 in 3D), their
/// coarse coefficients below it.
struct Modes {
    width: usize,
    values: Vec<f64>,
}

impl Modes {
    fn len(&self) -> usize {
        self.values.len() / self.width
    }

    fn row(&self, dof: usize) -> &[f64] {
        &self.values[dof * self.width..(dof + 1) * self.width]
    }
}

/// The rigid-body modes of the finest level, zero on the DOFs a support
/// holds (whose row of `a` is its diagonal alone): in plane strain one
/// `[x-translation, y-translation, rotation]` row a DOF; in 3D the three
/// translations, then the rotations about z, x and y. Coordinates are
/// taken from the middle of the nodes' box, so the rotation columns are
/// not swamped by the translations.
fn rigid_body_modes<const D: usize>(a: Operator<'_>, nodes: &[[i64; D]]) -> Modes {
    let middle = |d: usize| {
        let lo = nodes.iter().map(|c| c[d]).min().unwrap_or(0);
        let hi = nodes.iter().map(|c| c[d]).max().unwrap_or(0);
        (lo + hi) as f64 / 2.0
    };
    let centre: [f64; D] = std::array::from_fn(middle);
    let width = D * (D + 1) / 2;
    let held = |dof: usize| a.row(dof).all(|(c, v)| c == dof || v == 0.0);
    let rows: Vec<[f64; 6]> = (0..a.n())
        .into_par_iter()
        .map(|dof| {
            let mut row = [0.0; 6];
            if held(dof) {
                return row;
            }
            let c = nodes[dof / D];
            let x: [f64; D] = std::array::from_fn(|d| c[d] as f64 - centre[d]);
            let axis = dof % D;
            row[axis] = 1.0;
            // A rotation `(column, a, b)` moves the point at `x` along
            // `-x[b]` on axis `a` and `x[a]` on axis `b`: about z, (-y, x);
            // in 3D about x, (-z, y) on (y, z); about y, (-x, z) on (z, x).
            let rotations: &[(usize, usize, usize)] = if D == 2 {
                &[(2, 0, 1)]
            } else {
                &[(3, 0, 1), (4, 1, 2), (5, 2, 0)]
            };
            for &(column, a, b) in rotations {
                if axis == a {
                    row[column] = -x[b];
                } else if axis == b {
                    row[column] = x[a];
                }
            }
            row
        })
        .collect();
    Modes {
        width,
        values: rows
            .iter()
            .flat_map(|r| r[..width].iter().copied())
            .collect(),
    }
}

/// Each node's aggregate (the block of 3 grid coordinates a side it lies
/// in) and each aggregate's coordinates on the coarser grid, aggregates
/// numbered row by row (the first axis fastest).
fn aggregate<const D: usize>(coords: &[[i64; D]]) -> (Vec<u32>, Vec<[i64; D]>) {
    let block = |c: &[i64; D]| -> [i64; D] { std::array::from_fn(|d| c[d].div_euclid(BLOCK)) };
    // The last axis first, so that a band of coarse rows is a slab.
    let order = |k: &[i64; D]| -> [i64; D] { std::array::from_fn(|d| k[D - 1 - d]) };
    let mut keys: Vec<[i64; D]> = coords.iter().map(block).collect();
    keys.sort_unstable_by_key(order);
    keys.dedup();
    let aggregate_of = coords
        .iter()
        .map(|c| {
            let k = order(&block(c));
            keys.binary_search_by_key(&k, order)
                .expect("every block is listed") as u32
        })
        .collect();
    (aggregate_of, keys)
}

/// The tentative prolongator: on each aggregate, the near-null space
/// orthonormalised. Row `i` (a fine DOF) has `count[i]` entries, in the
/// coarse DOFs from `start[i]`, its values `values[i * width..]`.
struct Tentative {
    start: Vec<u32>,
    count: Vec<u8>,
    values: Vec<f64>,
    width: usize,
    n_coarse: usize,
    coarse_dof_start: Vec<usize>,
    coarse_modes: Modes,
}

impl Tentative {
    fn new(aggregate_of: &[u32], n_aggregates: usize, dof_start: &[usize], modes: &Modes) -> Self {
        let (n, width) = (modes.len(), modes.width);
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); n_aggregates];
        for (node, &g) in aggregate_of.iter().enumerate() {
            members[g as usize].extend(dof_start[node]..dof_start[node + 1]);
        }
        let mut tentative = Self {
            start: vec![0; n],
            count: vec![0; n],
            values: vec![0.0; n * width],
            width,
            n_coarse: 0,
            coarse_dof_start: vec![0],
            coarse_modes: Modes {
                width,
                values: Vec::new(),
            },
        };
        let mut q: Vec<Vec<f64>> = Vec::new();
        for dofs in &members {
            // Modified Gram-Schmidt, twice, on the modes' columns.
            q.clear();
            for m in 0..width {
                let column: Vec<f64> = dofs.iter().map(|&i| modes.row(i)[m]).collect();
                let norm = column.iter().map(|v| v * v).sum::<f64>().sqrt();
                let mut v = column.clone();
                for _ in 0..2 {
                    for qk in &q {
                        let dot: f64 = qk.iter().zip(&v).map(|(a, b)| a * b).sum();
                        v.iter_mut().zip(qk).for_each(|(v, q)| *v -= dot * q);
                    }
                }
                let rest = v.iter().map(|v| v * v).sum::<f64>().sqrt();
                if norm > 0.0 && rest > DEPENDENT * norm {
                    v.iter_mut().for_each(|v| *v /= rest);
                    q.push(v);
                }
            }
            // The coarse modes: R = Q^T B, one row a coarse DOF.
            for qk in &q {
                for m in 0..width {
                    let r = dofs.iter().zip(qk).map(|(&i, q)| q * modes.row(i)[m]).sum();
                    tentative.coarse_modes.values.push(r);
                }
            }
            let first = tentative.n_coarse;
            for (k, &i) in dofs.iter().enumerate() {
                tentative.start[i] = first as u32;
                // A held DOF is in no column (its entries would be zeros).
                let held = modes.row(i).iter().all(|&b| b == 0.0);
                tentative.count[i] = if held { 0 } else { q.len() as u8 };
                for (slot, qk) in q.iter().enumerate() {
                    tentative.values[i * width + slot] = qk[k];
                }
            }
            tentative.n_coarse += q.len();
            tentative.coarse_dof_start.push(tentative.n_coarse);
        }
        tentative
    }

    fn row(&self, i: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let start = self.start[i] as usize;
        let values = &self.values[i * self.width..];
        (0..self.count[i] as usize).map(move |k| (start + k, values[k]))
    }
}

/// `P = (I - omega D^-1 A) T`.
fn smoothed_prolongator(
    op: Operator<'_>,
    inv_diag: &[f64],
    omega: f64,
    tentative: &Tentative,
) -> Rows<f32> {
    Rows::build(op.n(), tentative.n_coarse, |i, acc| {
        for (c, t) in tentative.row(i) {
            acc.add(c, t);
        }
        let s = -omega * inv_diag[i];
        if s != 0.0 {
            for (k, a) in op.row(i) {
                for (c, t) in tentative.row(k) {
                    acc.add(c, s * a * t);
                }
            }
        }
    })
}

/// `A_c = P^T A P`, band by band of coarse rows: a band's rows are
/// `P^T (A P)` over the rows of `A P` its columns of `P` reach, made for
/// the band alone, as are its rows of `P^T`. Made whole, `A P` and `P^T`
/// were the setup's largest transients (about 230 and 80 bytes a point at
/// 1e6 GIMP column points, with the tangent and the finest prolongator
/// alive); a band's are [`GALERKIN_BAND`] coarse rows' worth, and the rows
/// of `A P` two bands share (the aggregates are numbered row by row of the
/// grid, so a band is a strip) are made twice.
/// `band` is the coarse rows of a band ([`GALERKIN_BAND`]).
fn galerkin(op: Operator<'_>, p: &Rows<f32>, n_coarse: usize, band: usize) -> Rows<f64> {
    // Each band's rows of `A P`, numbered by `local` (fine row -> row of
    // the band's `A P`).
    let mut local = vec![u32::MAX; op.n()];
    let mut bands: Vec<Rows<f64>> = Vec::new();
    for start in (0..n_coarse).step_by(band) {
        let end = (start + band).min(n_coarse);
        // The band's rows of P^T: (fine row, value) by coarse column, from
        // the rows of P that reach the band (in order; each row's columns
        // are sorted, so its entries in the band are a run).
        let in_band = |i: usize| {
            let cols = &p.col[p.ptr[i]..p.ptr[i + 1]];
            let first = cols.partition_point(|&c| (c as usize) < start);
            let last = cols.partition_point(|&c| (c as usize) < end);
            p.ptr[i] + first..p.ptr[i] + last
        };
        let mut reached: Vec<u32> = Vec::new();
        let mut ptr = vec![0usize; end - start + 1];
        for i in 0..p.n_rows() {
            let run = in_band(i);
            if !run.is_empty() {
                reached.push(i as u32);
            }
            for &c in &p.col[run] {
                ptr[c as usize - start + 1] += 1;
            }
        }
        for r in 0..end - start {
            ptr[r + 1] += ptr[r];
        }
        let mut next = ptr.clone();
        let mut fine = vec![0u32; ptr[end - start]];
        let mut value = vec![0f32; ptr[end - start]];
        for &i in &reached {
            for k in in_band(i as usize) {
                let r = p.col[k] as usize - start;
                fine[next[r]] = i;
                value[next[r]] = p.val[k];
                next[r] += 1;
            }
        }
        drop(next);
        for (l, &i) in reached.iter().enumerate() {
            local[i as usize] = l as u32;
        }
        let ap: Rows<f64> = Rows::build(reached.len(), n_coarse, |l, acc| {
            for (k, a) in op.row(reached[l] as usize) {
                for (c, v) in p.row(k) {
                    acc.add(c, a * v);
                }
            }
        });
        bands.push(Rows::build(end - start, n_coarse, |r, acc| {
            for k in ptr[r]..ptr[r + 1] {
                let (l, pv) = (local[fine[k] as usize] as usize, f64::from(value[k]));
                for (j, v) in ap.row(l) {
                    acc.add(j, pv * v);
                }
            }
        }));
    }
    Rows::concatenate(bands)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// Plane-strain elasticity (E = 1, nu = 0.3) on an m x m grid of unit
    /// bilinear squares (2 x 2 Gauss points), the left edge's DOFs held as
    /// the solver holds them (row and column zero, the diagonal kept), and
    /// a unit downward force on each right-edge node: both triangles in
    /// compressed columns, the node coordinates, and the right-hand side.
    struct Plate<const D: usize = 2> {
        ptr: Vec<usize>,
        col: Vec<u32>,
        val: Vec<f64>,
        nodes: Vec<[i64; D]>,
        b: Vec<f64>,
    }

    impl<const D: usize> Plate<D> {
        /// The sum over `elements` (each its nodes, in the order of the
        /// element matrix `ke(p, q)`'s blocks of `D` DOFs) on `nodes`,
        /// with the DOFs `held` says held as the solver holds them (row
        /// and column zero, the diagonal kept), and no load yet.
        fn assemble(
            nodes: Vec<[i64; D]>,
            elements: impl Iterator<Item = Vec<usize>>,
            ke: impl Fn(usize, usize) -> f64,
            held: impl Fn(usize) -> bool,
        ) -> Self {
            let n = D * nodes.len();
            let mut columns: Vec<BTreeMap<u32, f64>> = vec![BTreeMap::new(); n];
            for element in elements {
                let dofs: Vec<usize> = element
                    .iter()
                    .flat_map(|&k| (0..D).map(move |i| D * k + i))
                    .collect();
                for (p, &r) in dofs.iter().enumerate() {
                    for (q, &c) in dofs.iter().enumerate() {
                        let v = if (held(r) || held(c)) && r != c {
                            0.0
                        } else {
                            ke(p, q)
                        };
                        *columns[c].entry(r as u32).or_default() += v;
                    }
                }
            }
            let mut plate = Plate {
                ptr: vec![0],
                col: Vec::new(),
                val: Vec::new(),
                nodes,
                b: vec![0.0; n],
            };
            for column in columns {
                for (r, v) in column {
                    plate.col.push(r);
                    plate.val.push(v);
                }
                plate.ptr.push(plate.col.len());
            }
            plate
        }

        fn operator(&self) -> Operator<'_> {
            Operator {
                ptr: &self.ptr,
                col: &self.col,
                val: &self.val,
            }
        }
    }

    impl Plate {
        fn new(m: usize) -> Self {
            let (e, nu) = (1.0, 0.3);
            let c = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
            let d = [
                [c * (1.0 - nu), c * nu, 0.0],
                [c * nu, c * (1.0 - nu), 0.0],
                [0.0, 0.0, c * (1.0 - 2.0 * nu) / 2.0],
            ];
            let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
            let g = 1.0 / 3f64.sqrt();
            let mut ke = [[0.0; 8]; 8];
            for (xi, eta) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
                // Unit square: dx = dxi / 2, det J = 1/4.
                let grads: Vec<[f64; 2]> = corners
                    .iter()
                    .map(|&(a, b)| [a * (1.0 + b * eta) / 2.0, b * (1.0 + a * xi) / 2.0])
                    .collect();
                let mut bm = [[0.0; 8]; 3];
                for (a, gr) in grads.iter().enumerate() {
                    bm[0][2 * a] = gr[0];
                    bm[1][2 * a + 1] = gr[1];
                    bm[2][2 * a] = gr[1];
                    bm[2][2 * a + 1] = gr[0];
                }
                for p in 0..8 {
                    for q in 0..8 {
                        let mut s = 0.0;
                        for i in 0..3 {
                            for j in 0..3 {
                                s += bm[i][p] * d[i][j] * bm[j][q];
                            }
                        }
                        ke[p][q] += s * 0.25;
                    }
                }
            }
            let node = |i: usize, j: usize| j * (m + 1) + i;
            let n_nodes = (m + 1) * (m + 1);
            let held = |dof: usize| (dof / 2).is_multiple_of(m + 1);
            let elements = (0..m * m).map(|e| {
                let (ei, ej) = (e % m, e / m);
                [
                    node(ei, ej),
                    node(ei + 1, ej),
                    node(ei + 1, ej + 1),
                    node(ei, ej + 1),
                ]
                .to_vec()
            });
            let nodes = (0..n_nodes)
                .map(|k| [(k % (m + 1)) as i64, (k / (m + 1)) as i64])
                .collect();
            let mut plate = Plate::assemble(nodes, elements, |p, q| ke[p][q], held);
            for j in 0..=m {
                plate.b[2 * node(m, j) + 1] = -1.0;
            }
            plate
        }
    }

    /// 3D elasticity (E = 1, nu = 0.3) on an m x m x m grid of unit
    /// trilinear cubes (2 x 2 x 2 Gauss points), in the layout of
    /// [`Plate`]: the x = 0 face's DOFs held, a unit force in -z on each
    /// node of the x = m face.
    fn block(m: usize) -> Plate<3> {
        let (e, nu) = (1.0, 0.3);
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        // Corner a of the cube is bit d of a set when it lies at s_d = 1.
        let g = 0.5 / 3f64.sqrt();
        let mut ke = [[0.0; 24]; 24];
        for q in 0..8 {
            let s: [f64; 3] = std::array::from_fn(|d| 0.5 + if q >> d & 1 == 1 { g } else { -g });
            let grads: Vec<[f64; 3]> = (0..8)
                .map(|a| {
                    let f = |d: usize| if a >> d & 1 == 1 { s[d] } else { 1.0 - s[d] };
                    let df = |d: usize| if a >> d & 1 == 1 { 1.0 } else { -1.0 };
                    std::array::from_fn(|d| {
                        (0..3).map(|k| if k == d { df(k) } else { f(k) }).product()
                    })
                })
                .collect();
            for (a, ga) in grads.iter().enumerate() {
                for (b, gb) in grads.iter().enumerate() {
                    let dot: f64 = (0..3).map(|k| ga[k] * gb[k]).sum();
                    for i in 0..3 {
                        for j in 0..3 {
                            let delta = if i == j { dot } else { 0.0 };
                            ke[3 * a + i][3 * b + j] +=
                                (lambda * ga[i] * gb[j] + mu * (ga[j] * gb[i] + delta)) / 8.0;
                        }
                    }
                }
            }
        }
        let side = m + 1;
        let node = |c: [usize; 3]| (c[2] * side + c[1]) * side + c[0];
        let n_nodes = side * side * side;
        let held = |dof: usize| (dof / 3).is_multiple_of(side);
        let elements = (0..m * m * m).map(|cell| {
            let c = [cell % m, cell / m % m, cell / (m * m)];
            (0..8)
                .map(|a| node(std::array::from_fn(|d| c[d] + (a >> d & 1))))
                .collect()
        });
        let nodes = (0..n_nodes)
            .map(|k| {
                [
                    (k % side) as i64,
                    (k / side % side) as i64,
                    (k / (side * side)) as i64,
                ]
            })
            .collect();
        let mut block = Plate::assemble(nodes, elements, |p, q| ke[p][q], held);
        for k in 0..side * side {
            block.b[3 * node([m, k % side, k / side]) + 2] = -1.0;
        }
        block
    }

    fn norm(v: &[f64]) -> f64 {
        v.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// CG preconditioned by a hierarchy gives the same bits run after run
    /// on a pool of the same threads (2 and 4, five runs each, on the
    /// plate of 116,162 DOFs; at 13k the old sums happened to agree):
    /// every sum
    /// is taken in an order that does not depend on which thread finishes
    /// first (the smoother's eigenvalue estimate summed by rayon's
    /// `reduce` made answers differ from run to run). Pools of different
    /// sizes may differ: the restriction's partial sums are one a thread.
    #[test]
    fn the_answer_is_the_same_run_after_run() {
        let plate = Plate::new(240);
        let op = plate.operator();
        for threads in [2, 4] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let solve = || {
                pool.install(|| {
                    let mut hierarchy = Hierarchy::new(op, &plate.nodes, false).unwrap();
                    krylov::preconditioned_cg(
                        |x, y| op.product(x, y),
                        |z| hierarchy.apply(op, z),
                        &plate.b,
                        1e-10,
                        200,
                    )
                    .0
                })
            };
            let first = solve();
            for run in 1..5 {
                let again = solve();
                assert!(
                    again
                        .iter()
                        .zip(&first)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{threads} threads, run {run}"
                );
            }
        }
    }

    /// Multigrid's defining property: the V-cycle's error reduction does
    /// not depend on the mesh size, so CG preconditioned by it takes
    /// about the same iterations on every grid (Vanek, Mandel & Brezina
    /// 1996 prove it for smoothed aggregation with a bound that grows
    /// with the number of levels only). Here 1, 2 and 3 levels below the
    /// finest (m = 40, 80, 240; 3,362 to 116,162 DOFs), each to a relative
    /// residual of 1e-10, checked afresh: 18, 21 and 21 iterations. With
    /// the tentative prolongator unsmoothed (plain aggregation) they grow,
    /// 25, 45 and 84, and the test fails.
    #[test]
    fn cg_iterations_do_not_grow_with_the_grid() {
        let iterations: Vec<usize> = [40, 80, 240]
            .into_iter()
            .map(|m| cg_iterations(&Plate::new(m)))
            .collect();
        let (lo, hi) = (
            *iterations.iter().min().unwrap(),
            *iterations.iter().max().unwrap(),
        );
        assert!(hi <= 30 && hi <= lo + 6, "{iterations:?}");
    }

    /// The same in 3D, on [`block`]s of m = 8, 16 and 32 cubes a side
    /// (2,187 to 107,811 DOFs; 1, 1 and 2 levels below the finest): 20, 19
    /// and 22 iterations. Translations alone as the near-null space (the
    /// rotations dropped) take 28, 35 and 45, growing.
    #[test]
    fn cg_iterations_do_not_grow_with_a_3d_grid() {
        let iterations: Vec<usize> = [8, 16, 32]
            .into_iter()
            .map(|m| cg_iterations(&block(m)))
            .collect();
        let (lo, hi) = (
            *iterations.iter().min().unwrap(),
            *iterations.iter().max().unwrap(),
        );
        assert!(hi <= 30 && hi <= lo + 6, "{iterations:?}");
    }

    /// CG preconditioned by a fresh hierarchy on `plate`, to a relative
    /// residual of 1e-10 (checked afresh): its iterations.
    fn cg_iterations<const D: usize>(plate: &Plate<D>) -> usize {
        let op = plate.operator();
        let mut hierarchy = Hierarchy::new(op, &plate.nodes, false).unwrap();
        let (x, outcome) = krylov::preconditioned_cg(
            |x, y| op.product(x, y),
            |z| hierarchy.apply(op, z),
            &plate.b,
            1e-10,
            200,
        );
        let mut kx = vec![0.0; x.len()];
        op.product(&x, &mut kx);
        let r: Vec<f64> = kx.iter().zip(&plate.b).map(|(a, b)| a - b).collect();
        eprintln!(
            "{} DOFs: levels {:?}, {outcome:?}",
            x.len(),
            hierarchy.level_sizes()
        );
        assert!(norm(&r) <= 1.01e-10 * norm(&plate.b), "{}", norm(&r));
        outcome.iterations
    }

    fn dot(a: &[f64], b: &[f64]) -> f64 {
        a.iter().zip(b).map(|(a, b)| a * b).sum()
    }

    /// A V-cycle with the same polynomial smoother before and after the
    /// coarse correction is a symmetric operator, which CG needs of its
    /// preconditioner: `y.M x = x.M y` to round-off, for two unrelated
    /// vectors, on a plate with two levels below the finest. (Smoothing
    /// only before the correction fails: the two products differ by a
    /// third.)
    #[test]
    fn the_v_cycle_is_symmetric() {
        let plate = Plate::new(80);
        let op = plate.operator();
        let mut hierarchy = Hierarchy::new(op, &plate.nodes, false).unwrap();
        assert_eq!(hierarchy.level_sizes().len(), 3);
        let n = plate.b.len();
        let x: Vec<f64> = (0..n).map(|i| ((i * 37) % 101) as f64 - 50.0).collect();
        let y: Vec<f64> = (0..n).map(|i| ((i * 11) % 23) as f64 - 11.0).collect();
        let (mut mx, mut my) = (x.clone(), y.clone());
        hierarchy.apply(op, &mut mx);
        hierarchy.apply(op, &mut my);
        let (a, b) = (dot(&y, &mx), dot(&x, &my));
        let scale = norm(&x) * norm(&my).max(norm(&mx)) * n as f64;
        assert!((a - b).abs() <= 1e-14 * scale, "{a} {b}");
        // And positive definite along both.
        assert!(dot(&x, &mx) > 0.0 && dot(&y, &my) > 0.0);
    }

    /// The tentative prolongator carries the near-null space exactly:
    /// `T B_c = B` on the fine DOFs, with held DOFs (zero rows of `B`) and
    /// a one-node aggregate at the corner (m = 39: 40 nodes a side, the
    /// last block column one node wide), whose rotation depends on its
    /// translations and is dropped (2 coarse DOFs). The columns of `T` are
    /// orthonormal on each aggregate.
    #[test]
    fn the_tentative_prolongator_reproduces_the_rigid_body_modes() {
        let plate = Plate::new(39);
        let op = plate.operator();
        let modes = rigid_body_modes(op, &plate.nodes);
        assert_eq!(modes.row(0), [0.0; 3], "a held DOF");
        let t = tentative_reproduces_the_modes(&plate.nodes, &modes);
        let corner = t.coarse_dof_start.len() - 2;
        let corner_dofs = t.coarse_dof_start[corner + 1] - t.coarse_dof_start[corner];
        assert_eq!(corner_dofs, 2);
    }

    /// In 3D: six rigid-body modes (the rotations checked against their
    /// definition at one node), reproduced by the tentative prolongator;
    /// the corner's one-node aggregate (m = 9: 10 nodes a side) keeps its
    /// three translations, an edge's one-node-thick aggregate (a 1 x 3 x 3
    /// plate of nodes) all six.
    #[test]
    fn the_tentative_prolongator_reproduces_the_3d_rigid_body_modes() {
        let body = block(9);
        let op = body.operator();
        let modes = rigid_body_modes(op, &body.nodes);
        assert_eq!(modes.width, 6);
        assert_eq!(modes.row(0), [0.0; 6], "a held DOF");
        // Node (9, 2, 7) of a box centred at (4.5, 4.5, 4.5): lever
        // (4.5, -2.5, 2.5); about z (-y, x, 0), about x (0, -z, y), about
        // y (z, 0, -x).
        let k = (7 * 10 + 2) * 10 + 9;
        let (x, y, z) = (4.5, -2.5, 2.5);
        assert_eq!(modes.row(3 * k), [1.0, 0.0, 0.0, -y, 0.0, z]);
        assert_eq!(modes.row(3 * k + 1), [0.0, 1.0, 0.0, x, -z, 0.0]);
        assert_eq!(modes.row(3 * k + 2), [0.0, 0.0, 1.0, 0.0, y, -x]);
        let t = tentative_reproduces_the_modes(&body.nodes, &modes);
        let dofs = |g: usize| t.coarse_dof_start[g + 1] - t.coarse_dof_start[g];
        // Aggregates are numbered x fastest, 4 a side.
        assert_eq!(dofs(4 * 4 * 4 - 1), 3, "the corner");
        assert_eq!(dofs(4 * 4 + 4 + 3), 6, "a plate on the x = 9 face");
    }

    /// The tentative prolongator of `modes` on `nodes`' aggregates, checked
    /// to give `T B_c = B` and orthonormal columns on each aggregate.
    fn tentative_reproduces_the_modes<const D: usize>(
        nodes: &[[i64; D]],
        modes: &Modes,
    ) -> Tentative {
        let (aggregate_of, coarse) = aggregate(nodes);
        let dof_start: Vec<usize> = (0..=nodes.len()).map(|k| D * k).collect();
        let t = Tentative::new(&aggregate_of, coarse.len(), &dof_start, modes);
        for i in 0..modes.len() {
            for (m, &b) in modes.row(i).iter().enumerate() {
                let tb: f64 = t.row(i).map(|(c, v)| v * t.coarse_modes.row(c)[m]).sum();
                assert!(
                    (tb - b).abs() <= 1e-12 * (1.0 + b.abs()),
                    "{i} {m}: {tb} {b}"
                );
            }
        }
        // Orthonormal columns: T^T T = I.
        let mut gram = std::collections::HashMap::new();
        for i in 0..modes.len() {
            for (a, va) in t.row(i) {
                for (b, vb) in t.row(i) {
                    *gram.entry((a, b)).or_insert(0.0) += va * vb;
                }
            }
        }
        for ((a, b), v) in gram {
            let expected = if a == b { 1.0 } else { 0.0 };
            assert!((v - expected).abs() < 1e-12, "{a} {b} {v}");
        }
        t
    }

    /// `A_c = P^T A P` against the product of dense matrices.
    #[test]
    fn the_coarse_operator_is_the_galerkin_product() {
        // 2,178 rows: more than one of `Rows::build`'s pieces. The product
        // is made whole, and in bands of 100 coarse rows (the last one
        // short), which must agree to the bit.
        let plate = Plate::new(32);
        let op = plate.operator();
        let n = op.n();
        let modes = rigid_body_modes(op, &plate.nodes);
        let (aggregate_of, coarse) = aggregate(&plate.nodes);
        let dof_start: Vec<usize> = (0..=plate.nodes.len()).map(|k| 2 * k).collect();
        let t = Tentative::new(&aggregate_of, coarse.len(), &dof_start, &modes);
        let (inv_diag, top) = smoother(op, &mut power_start(n), POWER_ITERATIONS);
        let p = smoothed_prolongator(op, &inv_diag, 4.0 / (3.0 * top), &t);
        let a_c = galerkin(op, &p, t.n_coarse, t.n_coarse);
        let banded = galerkin(op, &p, t.n_coarse, 100);
        assert!(
            t.n_coarse > 300 && !t.n_coarse.is_multiple_of(100),
            "{}",
            t.n_coarse
        );
        assert_eq!(
            (&banded.ptr, &banded.col, &banded.val),
            (&a_c.ptr, &a_c.col, &a_c.val)
        );
        let dense = |rows: &mut dyn Iterator<Item = (usize, usize, f64)>, r, c| {
            let mut m = Mat::<f64>::zeros(r, c);
            for (i, j, v) in rows {
                m[(i, j)] += v;
            }
            m
        };
        let a = dense(
            &mut (0..n).flat_map(|i| op.row(i).map(move |(j, v)| (i, j, v))),
            n,
            n,
        );
        let pd = dense(
            &mut (0..n).flat_map(|i| p.row(i).map(move |(j, v)| (i, j, v))),
            n,
            t.n_coarse,
        );
        let expected = pd.transpose() * &a * &pd;
        let got = dense(
            &mut (0..t.n_coarse).flat_map(|i| a_c.row(i).map(move |(j, v)| (i, j, v))),
            t.n_coarse,
            t.n_coarse,
        );
        let largest = expected.norm_max();
        assert!((&got - &expected).norm_max() <= 1e-13 * largest);
    }

    /// A hierarchy kept for later tangents of its pattern must fit its
    /// finest smoother to them: on a tangent three times as stiff, the
    /// first tangent's Chebyshev polynomial acts outside its interval and
    /// V-cycle is not positive definite and CG stops at once; fitted, it
    /// converges, in under twice the iterations of a fresh hierarchy (30
    /// against 18: the stale coarse levels' correction is three times too
    /// large, which the smoother and CG make up for).
    #[test]
    fn a_kept_hierarchy_fits_its_smoother_to_a_later_tangent() {
        let plate = Plate::new(80);
        let stiffer: Vec<f64> = plate.val.iter().map(|v| 3.0 * v).collect();
        let later = Operator {
            ptr: &plate.ptr,
            col: &plate.col,
            val: &stiffer,
        };
        let mut hierarchy = Hierarchy::new(plate.operator(), &plate.nodes, false).unwrap();
        let solve = |hierarchy: &mut Hierarchy| {
            krylov::preconditioned_cg(
                |x, y| later.product(x, y),
                |z| hierarchy.apply(later, z),
                &plate.b,
                1e-10,
                100,
            )
            .1
        };
        let stale = solve(&mut hierarchy);
        hierarchy.fit_finest(later);
        let fitted = solve(&mut hierarchy);
        eprintln!("stale {stale:?}, fitted {fitted:?}");
        assert!(!stale.converged);
        assert!(fitted.converged && fitted.iterations <= 40, "{fitted:?}");
    }
}
