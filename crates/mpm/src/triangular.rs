//! Triangular solves `L L^T x = b` with a supernodal Cholesky factor made
//! by faer, independent subtrees of its elimination tree on rayon's
//! threads.
//!
//! CG with a kept factor ([`crate::krylov`], [`crate::linsolve`]) spends
//! most of its time in these solves: each reads the whole factor twice
//! and does two flops an entry, so it is bound by memory bandwidth, which
//! one core of this machine does not saturate (measured: 14 GB/s on one
//! thread, 22 GB/s on two). faer solves supernode after supernode.
//!
//! A supernode's rows below its diagonal block are ancestors of it in the
//! elimination tree, so the supernodes of a subtree touch only the
//! subtree's own rows and its ancestors'. The tree is cut into subtrees
//! (tasks) and the ancestors above them (the top, the separators of the
//! nested dissection). Forward (`L y = b`): the tasks run in parallel,
//! each writing its own rows in place and what it subtracts from the
//! top's rows into a buffer of its own; the buffers are added; the top
//! runs in order. Backward (`L^T x = y`): the top runs in reverse, then
//! the tasks in parallel, each reading the top's finished rows. The
//! arithmetic is the sequential solve's in double precision (a single-
//! precision factor's entries are widened; faer solves with it in single),
//! with the sums in another order.
//!
//! Measured on the 1e6-point GIMP column (479k unknowns, 155M factor
//! entries in single precision, 9 tasks and a top of 9% of the entries on
//! 2 threads): 0.115 s a solve (0.041 forward, 0.064 backward, the rest
//! the permutation) against faer's 0.145 s.

use std::ops::Range;

use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use rayon::prelude::*;

/// Tasks a thread's share of the work is cut into, for balance.
const TASKS_PER_THREAD: usize = 4;

/// The supernodes of a factor arranged for the parallel solve.
#[derive(Debug, Clone)]
pub struct SubtreeSchedule {
    /// Per supernode: first column, columns, offset of its values (a
    /// column-major block of `columns + pattern` rows), and its pattern
    /// (rows below the diagonal block) as a range of the factor's row
    /// indices.
    first_column: Vec<usize>,
    columns: Vec<usize>,
    value_offset: Vec<usize>,
    pattern: Vec<Range<usize>>,
    /// Supernode ranges that are whole subtrees, in order; with the
    /// columns each owns.
    tasks: Vec<(Range<usize>, Range<usize>)>,
    /// The other supernodes, in order.
    top: Vec<usize>,
    /// The factor's unknowns and values, to check a solve is given the
    /// factor the schedule was made for.
    n: usize,
    len_val: usize,
    /// The top's columns, in order, and each column's place among them
    /// (`usize::MAX` for a task's column).
    top_columns: Vec<usize>,
    top_slot: Vec<usize>,
}

impl SubtreeSchedule {
    /// The schedule of a supernodal factor for `threads` threads; `None`
    /// for a simplicial one, or when the supernodes are not numbered in
    /// postorder (each subtree contiguous), which the tasks need.
    pub fn new(symbolic: &SymbolicCholesky<usize>, threads: usize) -> Option<Self> {
        let SymbolicCholeskyRaw::Supernodal(sn) = symbolic.raw() else {
            return None;
        };
        let n = sn.nrows();
        let count = sn.n_supernodes();
        let begin = sn.supernode_begin();
        let end = sn.supernode_end();
        let mut supernode_of = vec![0; n];
        let mut first_column = Vec::with_capacity(count);
        let mut columns = Vec::with_capacity(count);
        let mut pattern = Vec::with_capacity(count);
        let rows = sn.row_idx();
        let row_start = sn.col_ptr_for_row_idx();
        for s in 0..count {
            supernode_of[begin[s]..end[s]].fill(s);
            first_column.push(begin[s]);
            columns.push(end[s] - begin[s]);
            let start = row_start[s];
            pattern.push(start..start + sn.supernode(s).pattern().len());
        }
        let value_offset = sn.col_ptr_for_val()[..count].to_vec();
        // The supernodal tree: a supernode's parent holds its first row
        // below the diagonal block.
        let parent: Vec<Option<usize>> = (0..count)
            .map(|s| rows[pattern[s].clone()].first().map(|&r| supernode_of[r]))
            .collect();
        let mut weight: Vec<usize> = (0..count)
            .map(|s| columns[s] * (columns[s] + pattern[s].len()))
            .collect();
        let mut size = vec![1usize; count];
        let mut first = (0..count).collect::<Vec<_>>();
        let mut children = vec![Vec::new(); count];
        for s in 0..count {
            if let Some(p) = parent[s] {
                if p <= s {
                    return None;
                }
                weight[p] += weight[s];
                size[p] += size[s];
                first[p] = first[p].min(first[s]);
                children[p].push(s);
            }
        }
        if (0..count).any(|s| s + 1 - first[s] != size[s]) {
            return None;
        }
        // Split the heaviest subtree until each is a small share of the
        // work; the nodes split off form the top.
        let total: usize = weight
            .iter()
            .enumerate()
            .filter(|(s, _)| parent[*s].is_none())
            .map(|(_, w)| w)
            .sum();
        let target = total / (TASKS_PER_THREAD * threads.max(1));
        let mut candidates: Vec<usize> = (0..count).filter(|&s| parent[s].is_none()).collect();
        let mut top = Vec::new();
        while let Some((k, &s)) = candidates
            .iter()
            .enumerate()
            .max_by_key(|(_, s)| weight[**s])
        {
            if weight[s] <= target || children[s].is_empty() {
                break;
            }
            candidates.swap_remove(k);
            top.push(s);
            candidates.extend(&children[s]);
        }
        top.sort_unstable();
        candidates.sort_unstable();
        let tasks: Vec<_> = candidates
            .iter()
            .map(|&s| {
                let supernodes = first[s]..s + 1;
                let cols = first_column[first[s]]..first_column[s] + columns[s];
                (supernodes, cols)
            })
            .collect();
        let mut top_slot = vec![usize::MAX; n];
        let mut top_columns = Vec::new();
        for &s in &top {
            for c in first_column[s]..first_column[s] + columns[s] {
                top_slot[c] = top_columns.len();
                top_columns.push(c);
            }
        }
        // Every row a task's supernode touches is its own or the top's.
        for (supernodes, cols) in &tasks {
            for s in supernodes.clone() {
                if rows[pattern[s].clone()]
                    .iter()
                    .any(|&r| !cols.contains(&r) && top_slot[r] == usize::MAX)
                {
                    return None;
                }
            }
        }
        Some(Self {
            n,
            len_val: sn.len_val(),
            first_column,
            columns,
            value_offset,
            pattern,
            tasks,
            top,
            top_columns,
            top_slot,
        })
    }

    /// The number of parallel tasks.
    pub fn tasks(&self) -> usize {
        self.tasks.len()
    }

    /// Heap bytes of the schedule.
    pub fn heap_bytes(&self) -> usize {
        let words = self.first_column.len() * 3
            + self.pattern.len() * 2
            + self.tasks.len() * 4
            + self.top.len()
            + self.top_columns.len()
            + self.top_slot.len();
        words * std::mem::size_of::<usize>()
    }

    /// Replaces `b` by `(L L^T)^-1 b` in the original order of the
    /// unknowns, with `symbolic` the factor's structure this schedule was
    /// made from, `values` its values (single or double precision) and `x`
    /// scratch of `b`'s length.
    pub fn solve<T>(
        &self,
        symbolic: &SymbolicCholesky<usize>,
        values: &[T],
        b: &mut [f64],
        x: &mut Vec<f64>,
    ) where
        T: Copy + Into<f64> + Sync,
    {
        let SymbolicCholeskyRaw::Supernodal(sn) = symbolic.raw() else {
            unreachable!("a schedule is made of supernodal factors only");
        };
        assert!(
            sn.nrows() == self.n
                && sn.len_val() == self.len_val
                && values.len() == self.len_val
                && sn.n_supernodes() == self.columns.len()
                && b.len() == self.n,
            "a schedule solves with the factor it was made for"
        );
        let rows = sn.row_idx();
        let order = symbolic.perm().map(|p| p.arrays().0);
        x.clear();
        match order {
            Some(order) => x.extend(order.iter().map(|&i| b[i])),
            None => x.extend_from_slice(b),
        }
        self.forward(rows, values, x);
        self.backward(rows, values, x);
        match order {
            Some(order) => {
                for (k, &i) in order.iter().enumerate() {
                    b[i] = x[k];
                }
            }
            None => b.copy_from_slice(x),
        }
    }

    /// `x = L^-1 x`.
    fn forward<T: Copy + Into<f64> + Sync>(&self, rows: &[usize], values: &[T], x: &mut [f64]) {
        let pieces = self.task_slices(x);
        let buffers: Vec<Vec<f64>> = self
            .tasks
            .par_iter()
            .zip(pieces)
            .map(|((supernodes, cols), own)| {
                let mut buffer = vec![0.0; self.top_columns.len()];
                let piece = Piece {
                    own,
                    cols: cols.clone(),
                };
                self.sweep(
                    rows,
                    values,
                    supernodes.clone(),
                    piece,
                    Sweep::Forward {
                        buffer: &mut buffer,
                    },
                );
                buffer
            })
            .collect();
        for buffer in buffers {
            for (&c, t) in self.top_columns.iter().zip(buffer) {
                x[c] -= t;
            }
        }
        let piece = Piece {
            cols: 0..x.len(),
            own: x,
        };
        let sweep = Sweep::Forward { buffer: &mut [] };
        self.sweep(rows, values, self.top.iter().copied(), piece, sweep);
    }

    /// `x = L^-T x`.
    fn backward<T: Copy + Into<f64> + Sync>(&self, rows: &[usize], values: &[T], x: &mut [f64]) {
        let piece = Piece {
            cols: 0..x.len(),
            own: x,
        };
        let sweep = Sweep::Backward { top: &[] };
        self.sweep(rows, values, self.top.iter().rev().copied(), piece, sweep);
        let top: Vec<f64> = self.top_columns.iter().map(|&c| x[c]).collect();
        let pieces = self.task_slices(x);
        self.tasks
            .par_iter()
            .zip(pieces)
            .for_each(|((supernodes, cols), own)| {
                let piece = Piece {
                    own,
                    cols: cols.clone(),
                };
                let sweep = Sweep::Backward { top: &top };
                self.sweep(rows, values, supernodes.clone().rev(), piece, sweep);
            });
    }

    /// A sweep over `supernodes` on the columns `piece` holds: forward
    /// with a buffer for the top's rows, backward reading them; compiled
    /// for AVX2 when the processor has it (the build targets plain x86-64,
    /// whose vectors are half as wide).
    fn sweep<T: Copy + Into<f64>>(
        &self,
        rows: &[usize],
        values: &[T],
        supernodes: impl Iterator<Item = usize>,
        piece: Piece,
        sweep: Sweep,
    ) {
        #[inline(always)]
        fn run<T: Copy + Into<f64>>(
            this: &SubtreeSchedule,
            rows: &[usize],
            values: &[T],
            supernodes: impl Iterator<Item = usize>,
            piece: Piece,
            sweep: Sweep,
        ) {
            match sweep {
                Sweep::Forward { buffer } => {
                    this.forward_supernodes(rows, values, supernodes, piece, buffer)
                }
                Sweep::Backward { top } => {
                    this.backward_supernodes(rows, values, supernodes, piece, top)
                }
            }
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            #[target_feature(enable = "avx2")]
            unsafe fn wide<T: Copy + Into<f64>>(
                this: &SubtreeSchedule,
                rows: &[usize],
                values: &[T],
                supernodes: impl Iterator<Item = usize>,
                piece: Piece,
                sweep: Sweep,
            ) {
                run(this, rows, values, supernodes, piece, sweep)
            }
            // SAFETY: the processor has the feature `wide` is compiled for.
            return unsafe { wide(self, rows, values, supernodes, piece, sweep) };
        }
        run(self, rows, values, supernodes, piece, sweep)
    }

    /// The forward solve over `supernodes` (in order) on the columns
    /// `piece` holds; what they take from other rows (the top's) is added
    /// to `buffer`, by the top's slots.
    #[inline(always)]
    fn forward_supernodes<T: Copy + Into<f64>>(
        &self,
        rows: &[usize],
        values: &[T],
        supernodes: impl Iterator<Item = usize>,
        piece: Piece,
        buffer: &mut [f64],
    ) {
        let Piece { own, cols } = piece;
        let mut tmp = Vec::new();
        for s in supernodes {
            self.forward_supernode(values, s, own, cols.start, &mut tmp);
            // The pattern is sorted: the piece's rows, then the top's.
            let rows = &rows[self.pattern[s].clone()];
            let split = rows.partition_point(|&r| r < cols.end);
            for (&r, &t) in rows[..split].iter().zip(&tmp) {
                own[r - cols.start] -= t;
            }
            for (&r, &t) in rows[split..].iter().zip(&tmp[split..]) {
                buffer[self.top_slot[r]] += t;
            }
        }
    }

    /// The backward solve over `supernodes` (in reverse order) on the
    /// columns `piece` holds, reading other rows from `top` (by the top's
    /// slots).
    #[inline(always)]
    fn backward_supernodes<T: Copy + Into<f64>>(
        &self,
        rows: &[usize],
        values: &[T],
        supernodes: impl Iterator<Item = usize>,
        piece: Piece,
        top: &[f64],
    ) {
        let Piece { own, cols } = piece;
        let mut gathered = Vec::new();
        for s in supernodes {
            gathered.clear();
            let rows = &rows[self.pattern[s].clone()];
            let split = rows.partition_point(|&r| r < cols.end);
            gathered.extend(rows[..split].iter().map(|&r| own[r - cols.start]));
            gathered.extend(rows[split..].iter().map(|&r| top[self.top_slot[r]]));
            self.backward_supernode(values, s, own, cols.start, &gathered);
        }
    }

    /// Each task's columns of `x`, as disjoint slices.
    fn task_slices<'x>(&self, mut x: &'x mut [f64]) -> Vec<&'x mut [f64]> {
        let mut slices = Vec::with_capacity(self.tasks.len());
        let mut at = 0;
        for (_, cols) in &self.tasks {
            let (_, rest) = x.split_at_mut(cols.start - at);
            let (own, rest) = rest.split_at_mut(cols.len());
            slices.push(own);
            x = rest;
            at = cols.end;
        }
        slices
    }

    /// Supernode `s`'s diagonal block solved in place on its columns of
    /// `x` (which starts at column `offset`), and in `tmp` what its rows
    /// below take from them (`L_below x_block`, to subtract).
    #[inline(always)]
    fn forward_supernode<T: Copy + Into<f64>>(
        &self,
        values: &[T],
        s: usize,
        x: &mut [f64],
        offset: usize,
        tmp: &mut Vec<f64>,
    ) {
        let c = self.columns[s];
        let p = self.pattern[s].len();
        let m = c + p;
        let block = &values[self.value_offset[s]..][..m * c];
        let x = &mut x[self.first_column[s] - offset..][..c];
        tmp.clear();
        tmp.resize(p, 0.0);
        for j in 0..c {
            let column = &block[j * m..(j + 1) * m];
            let xj = x[j] / column[j].into();
            x[j] = xj;
            for (x, &l) in x[j + 1..].iter_mut().zip(&column[j + 1..c]) {
                *x -= l.into() * xj;
            }
            for (t, &l) in tmp.iter_mut().zip(&column[c..]) {
                *t += l.into() * xj;
            }
        }
    }

    /// Supernode `s`'s columns of `x` (which starts at column `offset`)
    /// solved with its block transposed, given `x` at its rows below
    /// (`gathered`).
    #[inline(always)]
    fn backward_supernode<T: Copy + Into<f64>>(
        &self,
        values: &[T],
        s: usize,
        x: &mut [f64],
        offset: usize,
        gathered: &[f64],
    ) {
        let c = self.columns[s];
        let m = c + gathered.len();
        let block = &values[self.value_offset[s]..][..m * c];
        let x = &mut x[self.first_column[s] - offset..][..c];
        let below = |j: usize| &block[j * m + c..(j + 1) * m];
        // What the rows below give each column, four columns at a time.
        let mut j = 0;
        while j + 4 <= c {
            let given = dots4(
                [below(j), below(j + 1), below(j + 2), below(j + 3)],
                gathered,
            );
            for (k, g) in given.into_iter().enumerate() {
                x[j + k] -= g;
            }
            j += 4;
        }
        for j in j..c {
            x[j] -= dot(below(j), gathered);
        }
        for j in (0..c).rev() {
            let column = &block[j * m..j * m + c];
            let within = dot(&column[j + 1..], &x[j + 1..c]);
            x[j] = (x[j] - within) / column[j].into();
        }
    }
}

/// Four dot products `l_i . g`, each with four running sums (which the
/// compiler keeps in a vector register), `g` read once for all four.
#[inline(always)]
fn dots4<T: Copy + Into<f64>>(l: [&[T]; 4], g: &[f64]) -> [f64; 4] {
    let mut sums = [[0.0; 4]; 4];
    let chunks = l.map(|l| l.chunks_exact(4));
    let tails = chunks.clone().map(|c| c.remainder());
    let [c0, c1, c2, c3] = chunks;
    let g_chunks = g.chunks_exact(4);
    let g_tail = g_chunks.remainder();
    for ((((g, a), b), c), d) in g_chunks.zip(c0).zip(c1).zip(c2).zip(c3) {
        for lane in 0..4 {
            sums[0][lane] += a[lane].into() * g[lane];
            sums[1][lane] += b[lane].into() * g[lane];
            sums[2][lane] += c[lane].into() * g[lane];
            sums[3][lane] += d[lane].into() * g[lane];
        }
    }
    let mut out = [0.0; 4];
    for ((o, sum), tail) in out.iter_mut().zip(&sums).zip(tails) {
        *o = sum.iter().sum::<f64>()
            + tail
                .iter()
                .zip(g_tail)
                .map(|(&a, &b)| a.into() * b)
                .sum::<f64>();
    }
    out
}

/// `l . g` with eight running sums (which the compiler keeps in vector
/// registers; one sum would wait on each addition).
#[inline(always)]
fn dot<T: Copy + Into<f64>>(l: &[T], g: &[f64]) -> f64 {
    let mut sums = [0.0; 8];
    let (l_chunks, g_chunks) = (l.chunks_exact(8), g.chunks_exact(8));
    let tail: f64 = l_chunks
        .remainder()
        .iter()
        .zip(g_chunks.remainder())
        .map(|(&a, &b)| a.into() * b)
        .sum();
    for (a, b) in l_chunks.zip(g_chunks) {
        for k in 0..8 {
            sums[k] += a[k].into() * b[k];
        }
    }
    sums.iter().sum::<f64>() + tail
}

/// Which sweep, with the top's rows: a buffer for what a forward sweep
/// subtracts from them, their final values for a backward one.
enum Sweep<'t> {
    Forward { buffer: &'t mut [f64] },
    Backward { top: &'t [f64] },
}

/// A task's columns of the solution: `own[k]` is column `cols.start + k`.
struct Piece<'x> {
    own: &'x mut [f64],
    cols: Range<usize>,
}

#[cfg(test)]
mod tests {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::sparse::SymbolicSparseColMatRef;
    use faer::sparse::linalg::SupernodalThreshold;
    use faer::sparse::linalg::cholesky::{
        CholeskySymbolicParams, LltRef, SymmetricOrdering, factorize_symbolic_cholesky,
    };
    use faer::{Conj, Mat, Par, Side};

    use super::*;
    use crate::linsolve::tests::{laplacian, wide_rows};
    use crate::linsolve::{Tangent, exact, factorise};

    /// The shifted 5-point Laplacian of a 48 x 48 grid (2,304 unknowns),
    /// ordered by faer's minimum degree, factorised into supernodes.
    fn factor(threshold: SupernodalThreshold) -> (SymbolicCholesky<usize>, Vec<f64>, Vec<f64>) {
        let m = 48;
        let (pattern, values) = laplacian(m, 1e-3);
        let n = m * m;
        let rows = wide_rows(&pattern);
        let structure = SymbolicSparseColMatRef::new_checked(n, n, &pattern.col_ptr, None, &rows);
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: threshold,
            ..Default::default()
        };
        let symbolic =
            factorize_symbolic_cholesky(structure, Side::Upper, SymmetricOrdering::Amd, params)
                .unwrap();
        let mut factor = vec![0.0; symbolic.len_val()];
        assert!(
            factorise(
                &symbolic,
                Tangent::new(&pattern, &values),
                exact,
                &mut factor,
                Par::Seq
            )
            .0
        );
        let b = (0..n).map(|i| ((i * 37) % 101) as f64 - 50.0).collect();
        (symbolic, factor, b)
    }

    /// faer's sequential solve with `factor`.
    fn faer_solve(symbolic: &SymbolicCholesky<usize>, factor: &[f64], b: &[f64]) -> Vec<f64> {
        let n = b.len();
        let mut x = Mat::from_fn(n, 1, |i, _| b[i]);
        let mut scratch = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        LltRef::new(symbolic, factor).solve_in_place_with_conj(
            Conj::No,
            x.as_mut(),
            Par::Seq,
            MemStack::new(&mut scratch),
        );
        (0..n).map(|i| x[(i, 0)]).collect()
    }

    fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
        let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|x| x * x).sum::<f64>().sqrt();
        norm(&mut a.iter().zip(b).map(|(x, y)| x - y)) / norm(&mut b.iter().copied())
    }

    /// In parallel over subtrees (in pools of 1, 2 and 4 threads, with a
    /// schedule made for as many), the solve is faer's sequential one with
    /// the sums in another order: equal to round-off (the Laplacian's
    /// condition number, 8e3 with the shift, times 1e-16), for a factor
    /// in double precision and in single (whose entries, widened to
    /// double, faer solves with).
    #[test]
    fn the_parallel_solve_answers_as_faers_sequential_one() {
        let (symbolic, factor, b) = factor(SupernodalThreshold::FORCE_SUPERNODAL);
        for threads in [1, 2, 4] {
            let schedule =
                SubtreeSchedule::new(&symbolic, threads).expect("postordered supernodes");
            assert!(
                schedule.tasks() >= 2 * threads,
                "{} tasks",
                schedule.tasks()
            );
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let solve = |run: &(dyn Fn(&mut [f64]) + Sync)| {
                let mut x = b.clone();
                pool.install(|| run(&mut x));
                x
            };
            let x = solve(&|x| schedule.solve(&symbolic, &factor, x, &mut Vec::new()));
            let error = relative_difference(&x, &faer_solve(&symbolic, &factor, &b));
            assert!(error < 1e-12, "{threads} threads: {error:e}");

            let single: Vec<f32> = factor.iter().map(|&v| v as f32).collect();
            let widened: Vec<f64> = single.iter().map(|&v| f64::from(v)).collect();
            let x = solve(&|x| schedule.solve(&symbolic, &single, x, &mut Vec::new()));
            let error = relative_difference(&x, &faer_solve(&symbolic, &widened, &b));
            assert!(error < 1e-12, "{threads} threads, single: {error:e}");
        }
    }

    /// A simplicial factor has no supernodes to schedule.
    #[test]
    fn a_simplicial_factor_has_no_schedule() {
        let (symbolic, _, _) = factor(SupernodalThreshold::FORCE_SIMPLICIAL);
        assert!(SubtreeSchedule::new(&symbolic, 2).is_none());
    }
}
