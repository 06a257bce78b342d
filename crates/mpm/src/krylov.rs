//! Conjugate gradients preconditioned by the Cholesky factor of an earlier
//! tangent of the same pattern ([`crate::linsolve`]), and restarted GMRES
//! for tangents that are not symmetric, preconditioned by the Cholesky
//! factor of a symmetric part.
//!
//! Within a load step the tangent changes little from one Newton iteration
//! to the next, so the factor of the first iteration's tangent `M` is close
//! to every later one `K`: `M^-1 K` has its eigenvalues clustered at 1 and
//! CG reaches round-off in a few iterations, each a pair of triangular
//! solves with the stale factor and a product with `K`, a fraction of a
//! factorisation's cost. PARDISO offers the same idea (a Krylov solver
//! preconditioned by an earlier factorisation, its `iparm(4)`).

use rayon::prelude::*;

/// How a preconditioned CG or GMRES solve ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CgOutcome {
    /// CG: products with `K` after the first preconditioned solve. GMRES:
    /// the Arnoldi steps' products (each cycle's true residual takes one
    /// more).
    pub iterations: usize,
    /// `|r| / |b|` at the end: for CG, `r` its recurrence's residual
    /// (equal to `b - K x` in exact arithmetic; on an ill-conditioned `K`
    /// the true residual ends above it); for GMRES, the true residual.
    pub relative_residual: f64,
    pub converged: bool,
}

/// `y = K x` for a symmetric `K` stored with both triangles in compressed
/// columns: `y_j` is column `j` dotted with `x`, so the columns are shared
/// among threads with no write conflicts.
/// The same loop makes `y = A x` for any `A` in compressed rows (the
/// multigrid's prolongators, whose values are single precision).
pub fn symmetric_product<T: Copy + Into<f64> + Sync>(
    col_ptr: &[usize],
    row_idx: &[u32],
    values: &[T],
    x: &[f64],
    y: &mut [f64],
) {
    column_dots(col_ptr, row_idx, |k| values[k].into(), x, y);
}

/// `y_j` = column `j` (entry `k`'s value `value(k)`) dotted with `x`, the
/// columns shared among threads.
fn column_dots(
    col_ptr: &[usize],
    row_idx: &[u32],
    value: impl Fn(usize) -> f64 + Sync,
    x: &[f64],
    y: &mut [f64],
) {
    y.par_iter_mut()
        .with_min_len(1024)
        .enumerate()
        .for_each(|(j, yj)| {
            *yj = (col_ptr[j]..col_ptr[j + 1])
                .map(|k| value(k) * x[row_idx[k] as usize])
                .sum();
        });
}

/// `y = K x` for `K` stored in compressed columns whose pattern is
/// structurally symmetric: `y_j` is column `j` of `K^T` dotted with `x`,
/// column `j`'s entry `k` of `K^T` read from `K`'s `values` at
/// `transpose[k]`, the place of its transpose. As [`symmetric_product`]
/// on a copy of `K^T`, to the bit, without the copy.
pub fn transposed_product(
    col_ptr: &[usize],
    row_idx: &[u32],
    (values, transpose): (&[f64], &[u32]),
    x: &[f64],
    y: &mut [f64],
) {
    column_dots(col_ptr, row_idx, |k| values[transpose[k] as usize], x, y);
}

/// The length of the blocks a dot product sums on its own before the
/// blocks' sums are added in order.
const DOT_BLOCK: usize = 4096;

/// `a . b`, the same bits whatever the threads ([`ordered_sum`]).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    ordered_sum(a.len(), |range| {
        a[range.clone()]
            .iter()
            .zip(&b[range])
            .map(|(x, y)| x * y)
            .sum()
    })
}

/// The sum over `0..len` of `block(range)`, each `range` a block of
/// [`DOT_BLOCK`] indices summed on its own, the blocks' sums added in
/// order: the same bits whatever the threads and however rayon splits
/// the work (its own `sum` and `reduce` add in the order its threads
/// finish).
pub(crate) fn ordered_sum(len: usize, block: impl Fn(std::ops::Range<usize>) -> f64 + Sync) -> f64 {
    let blocks: Vec<f64> = (0..len.div_ceil(DOT_BLOCK))
        .into_par_iter()
        .map(|k| block(k * DOT_BLOCK..((k + 1) * DOT_BLOCK).min(len)))
        .collect();
    blocks.iter().sum()
}

/// Solves `K x = b` by CG from `x0 = M^-1 b`, with `precondition(z)`
/// replacing `z` by `M^-1 z`, until the residual `|b - K x| <= tolerance
/// |b|` or `max_iterations` products with `K`. Converged means CG's
/// recurrence's residual is within the tolerance ([`CgOutcome`]).
pub fn preconditioned_cg(
    product: impl Fn(&[f64], &mut [f64]),
    mut precondition: impl FnMut(&mut [f64]),
    b: &[f64],
    tolerance: f64,
    max_iterations: usize,
) -> (Vec<f64>, CgOutcome) {
    let n = b.len();
    let b_norm = dot(b, b).sqrt();
    if b_norm == 0.0 {
        let outcome = CgOutcome {
            iterations: 0,
            relative_residual: 0.0,
            converged: true,
        };
        return (vec![0.0; n], outcome);
    }
    let mut x = b.to_vec();
    precondition(&mut x);
    let mut kp = vec![0.0; n];
    product(&x, &mut kp);
    let mut r: Vec<f64> = b.iter().zip(&kp).map(|(b, k)| b - k).collect();
    let mut z = r.clone();
    precondition(&mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut outcome = CgOutcome {
        iterations: 0,
        relative_residual: dot(&r, &r).sqrt() / b_norm,
        converged: false,
    };
    while outcome.relative_residual > tolerance && outcome.iterations < max_iterations {
        product(&p, &mut kp);
        let pkp = dot(&p, &kp);
        if pkp.is_nan() || pkp <= 0.0 {
            // K is not positive definite along p (or p vanished).
            break;
        }
        let alpha = rz / pkp;
        x.par_iter_mut().zip(&p).for_each(|(x, p)| *x += alpha * p);
        r.par_iter_mut().zip(&kp).for_each(|(r, k)| *r -= alpha * k);
        outcome.iterations += 1;
        outcome.relative_residual = dot(&r, &r).sqrt() / b_norm;
        if outcome.relative_residual <= tolerance {
            break;
        }
        z.copy_from_slice(&r);
        precondition(&mut z);
        let rz_next = dot(&r, &z);
        if rz_next.is_nan() || rz_next <= 0.0 {
            // The preconditioner is not positive definite along r.
            break;
        }
        let beta = rz_next / rz;
        rz = rz_next;
        p.par_iter_mut()
            .zip(&z)
            .for_each(|(p, z)| *p = z + beta * *p);
    }
    outcome.converged = outcome.relative_residual <= tolerance;
    (x, outcome)
}

/// Solves `K x = b` for a `K` that need not be symmetric by restarted
/// flexible GMRES (Saad, Iterative methods for sparse linear systems,
/// 2003, algorithm 9.6), preconditioned on the right: `K M^-1 y = b`,
/// `x = M^-1 y`, with `precondition(z)` replacing `z` by `M^-1 z`. Right
/// preconditioning minimises the true residual `b - K x` over each
/// cycle's Krylov space, so the tolerance is on the residual Newton
/// measures. The preconditioned vectors `z_j = M^-1 v_j` are kept and the
/// answer made of them (`x += Z y`), so a preconditioner that is not
/// exactly linear (a factor applied in single precision) costs no
/// accuracy. From `x0 = 0`, until `|b - K x| <= tolerance |b|` or
/// `max_iterations` Arnoldi steps; a cycle holds `restart` vectors of
/// each kind. The outcome's residual is the true one, computed at the end
/// of each cycle.
pub fn preconditioned_gmres(
    product: impl Fn(&[f64], &mut [f64]),
    mut precondition: impl FnMut(&mut [f64]),
    b: &[f64],
    tolerance: f64,
    max_iterations: usize,
    restart: usize,
) -> (Vec<f64>, CgOutcome) {
    let n = b.len();
    let b_norm = dot(b, b).sqrt();
    let mut x = vec![0.0; n];
    let mut outcome = CgOutcome {
        iterations: 0,
        relative_residual: 1.0,
        converged: b_norm == 0.0,
    };
    if b_norm == 0.0 {
        outcome.relative_residual = 0.0;
        return (x, outcome);
    }
    let m = restart.max(1);
    let mut r = b.to_vec();
    let mut beta = b_norm;
    let mut w = vec![0.0; n];
    while outcome.iterations < max_iterations {
        // The cycle's orthonormal basis, its Hessenberg matrix by columns
        // (rotated into upper triangular form as it grows), the rotations
        // and the rotated right-hand side `g`.
        let mut basis: Vec<Vec<f64>> = vec![r.iter().map(|v| v / beta).collect()];
        let mut preconditioned: Vec<Vec<f64>> = Vec::with_capacity(m);
        let mut h: Vec<Vec<f64>> = Vec::with_capacity(m);
        let mut rotations: Vec<(f64, f64)> = Vec::with_capacity(m);
        let mut g = vec![beta];
        while h.len() < m && outcome.iterations < max_iterations {
            let j = h.len();
            let mut z = basis[j].clone();
            precondition(&mut z);
            product(&z, &mut w);
            preconditioned.push(z);
            outcome.iterations += 1;
            // Modified Gram-Schmidt against the basis.
            let mut column = Vec::with_capacity(j + 2);
            for v in &basis {
                let c = dot(&w, v);
                w.par_iter_mut().zip(v).for_each(|(w, v)| *w -= c * v);
                column.push(c);
            }
            let norm = dot(&w, &w).sqrt();
            column.push(norm);
            for (i, &(c, s)) in rotations.iter().enumerate() {
                let (a, b) = (column[i], column[i + 1]);
                column[i] = c * a + s * b;
                column[i + 1] = -s * a + c * b;
            }
            let (a, b) = (column[j], column[j + 1]);
            let radius = a.hypot(b);
            let (c, s) = if radius == 0.0 {
                (1.0, 0.0)
            } else {
                (a / radius, b / radius)
            };
            column[j] = radius;
            column[j + 1] = 0.0;
            rotations.push((c, s));
            g.push(-s * g[j]);
            g[j] *= c;
            h.push(column);
            // A basis that stops growing (norm 0) holds the solution.
            if g[j + 1].abs() <= tolerance * b_norm || norm == 0.0 || !norm.is_finite() {
                break;
            }
            basis.push(w.iter().map(|v| v / norm).collect());
        }
        // y from the triangular system, then x += Z y.
        let k = h.len();
        let mut y = vec![0.0; k];
        for i in (0..k).rev() {
            let sum: f64 = (i + 1..k).map(|l| h[l][i] * y[l]).sum();
            y[i] = (g[i] - sum) / h[i][i];
        }
        if y.iter().any(|v| !v.is_finite()) {
            break;
        }
        for (z, yi) in preconditioned.iter().zip(&y) {
            x.par_iter_mut().zip(z).for_each(|(x, z)| *x += yi * z);
        }
        product(&x, &mut w);
        r.par_iter_mut()
            .zip(b)
            .zip(&w)
            .for_each(|((r, b), w)| *r = b - w);
        beta = dot(&r, &r).sqrt();
        outcome.relative_residual = beta / b_norm;
        // A NaN residual stops too.
        if outcome.relative_residual <= tolerance || outcome.relative_residual.is_nan() {
            break;
        }
    }
    outcome.converged = outcome.relative_residual <= tolerance;
    (x, outcome)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1D Laplacian K (tridiagonal 2, -1, n = 200) preconditioned by the
    /// exact inverse of M = K + 1e-4 I. M^-1 K's eigenvalues l / (l + 1e-4)
    /// spread over k = 1.42 (K's smallest is 2 - 2 cos(pi / 201) = 2.44e-4),
    /// so CG's error falls by (sqrt(k) - 1) / (sqrt(k) + 1) = 0.087 or
    /// more an iteration in the energy norm: 1e-12 takes at most 12, and
    /// the residual's 2-norm, up to sqrt(cond K) = 128 times the energy
    /// norm's ratio, 14. It takes 5 (the spectrum clusters); one does not
    /// do.
    /// `K = tridiag(-1 - skew, 2, -1 + skew)` of order `n` in compressed
    /// columns: column `j` holds `K_(j-1) j = -1 + skew`, `K_jj = 2`,
    /// `K_(j+1) j = -1 - skew`.
    fn tridiagonal(n: usize, skew: f64) -> (Vec<usize>, Vec<u32>, Vec<f64>) {
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        for j in 0..n {
            for (i, v) in [
                (j.wrapping_sub(1), -1.0 + skew),
                (j, 2.0),
                (j + 1, -1.0 - skew),
            ] {
                if i < n {
                    row_idx.push(i as u32);
                    values.push(v);
                }
            }
            col_ptr.push(row_idx.len());
        }
        (col_ptr, row_idx, values)
    }

    /// `z <- M^-1 z` for `M = tridiag(-1, diagonal, -1)` of order `z.len()`,
    /// by the Thomas algorithm.
    fn thomas(diagonal: f64, z: &mut [f64]) {
        let n = z.len();
        let mut c = vec![0.0; n];
        c[0] = -1.0 / diagonal;
        z[0] /= diagonal;
        for i in 1..n {
            let m = diagonal + c[i - 1];
            c[i] = -1.0 / m;
            z[i] = (z[i] + z[i - 1]) / m;
        }
        for i in (0..n - 1).rev() {
            z[i] -= c[i] * z[i + 1];
        }
    }

    fn right_hand_side(n: usize) -> Vec<f64> {
        (0..n).map(|i| ((i * 7) % 13) as f64 - 6.0).collect()
    }

    /// `|b - K x| / |b|` for `K` in compressed columns, not symmetric:
    /// `(K x)_i` summed over the columns.
    fn true_residual(k: &(Vec<usize>, Vec<u32>, Vec<f64>), x: &[f64], b: &[f64]) -> f64 {
        let (col_ptr, row_idx, values) = k;
        let mut r = b.to_vec();
        for j in 0..x.len() {
            for p in col_ptr[j]..col_ptr[j + 1] {
                r[row_idx[p] as usize] -= values[p] * x[j];
            }
        }
        (dot(&r, &r) / dot(b, b)).sqrt()
    }

    /// GMRES preconditioned on the right by `K` itself converges in one
    /// product (the Krylov space of `K M^-1 = I` is spanned by `b`); by
    /// the symmetric part of `K = tridiag(-1.1, 2, -0.9)`, `M^-1 K = I +
    /// M^-1 S` with `S` skew, its eigenvalues `1 + i t` on a vertical
    /// line, it reaches 1e-12 in a full cycle, and with cycles of 5
    /// vectors it still does, in more products. Each answer is checked by
    /// its true residual.
    #[test]
    fn gmres_solves_an_unsymmetric_system_preconditioned_by_its_symmetric_part() {
        let n: usize = 200;
        let b = right_hand_side(n);
        let exact = tridiagonal(n, 0.0);
        let (x, outcome) = preconditioned_gmres(
            |x, y| symmetric_product(&exact.0, &exact.1, &exact.2, x, y),
            |z| thomas(2.0, z),
            &b,
            1e-12,
            50,
            30,
        );
        assert!(outcome.converged, "{outcome:?}");
        assert_eq!(outcome.iterations, 1, "{outcome:?}");
        assert!(true_residual(&exact, &x, &b) <= 1e-12, "{outcome:?}");

        let k = tridiagonal(n, 0.1);
        // K^T in compressed columns is K in compressed rows: its column
        // products make `K x`.
        let transposed = tridiagonal(n, -0.1);
        let product = |x: &[f64], y: &mut [f64]| {
            symmetric_product(&transposed.0, &transposed.1, &transposed.2, x, y)
        };
        let mut last = 0;
        for restart in [30, 5] {
            let (x, outcome) =
                preconditioned_gmres(product, |z| thomas(2.0, z), &b, 1e-12, 200, restart);
            assert!(outcome.converged, "restart {restart}: {outcome:?}");
            let residual = true_residual(&k, &x, &b);
            assert!(residual <= 1e-12, "restart {restart}: {residual:e}");
            assert!(outcome.iterations > last, "restart {restart}: {outcome:?}");
            last = outcome.iterations;
        }
    }

    /// `K x` read through the transposes' places is the column products of
    /// a copy of `K^T`, to the bit, and is `K x` (the product `K^T x`,
    /// which the same places would give transposed, differs).
    #[test]
    fn the_transposed_product_is_k_x_without_a_copy() {
        let n: usize = 50;
        let k = tridiagonal(n, 0.1);
        let (col_ptr, row_idx, values) = &k;
        // The place of each entry's transpose: tridiagonal columns hold
        // rows j-1, j, j+1 in order.
        let place = |i: usize, j: usize| {
            (col_ptr[j]..col_ptr[j + 1])
                .find(|&p| row_idx[p] as usize == i)
                .unwrap() as u32
        };
        let transpose: Vec<u32> = (0..n)
            .flat_map(|j| (col_ptr[j]..col_ptr[j + 1]).map(move |p| (row_idx[p] as usize, j)))
            .map(|(i, j)| place(j, i))
            .collect();
        let x: Vec<f64> = (0..n).map(|i| 1.0 / (1.0 + i as f64) + 0.3).collect();
        let mut through_places = vec![0.0; n];
        transposed_product(
            col_ptr,
            row_idx,
            (values, &transpose),
            &x,
            &mut through_places,
        );
        let copy = tridiagonal(n, -0.1);
        let mut from_copy = vec![0.0; n];
        symmetric_product(&copy.0, &copy.1, &copy.2, &x, &mut from_copy);
        assert!(
            through_places
                .iter()
                .zip(&from_copy)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
        // `K x` summed over K's own columns.
        assert!(true_residual(&k, &x, &through_places) <= 1e-15);
        let mut k_transposed_x = vec![0.0; n];
        symmetric_product(col_ptr, row_idx, values, &x, &mut k_transposed_x);
        assert!(
            k_transposed_x
                .iter()
                .zip(&from_copy)
                .any(|(a, b)| (a - b).abs() > 1e-3)
        );
    }

    #[test]
    fn a_near_preconditioner_converges_in_a_few_iterations() {
        let n: usize = 200;
        let (col_ptr, row_idx, values) = tridiagonal(n, 0.0);
        // M^-1 z by the Thomas algorithm on (M's diagonal, -1).
        let precondition = |z: &mut [f64]| thomas(2.0 + 1e-4, z);
        let b = right_hand_side(n);
        let product =
            |x: &[f64], y: &mut [f64]| symmetric_product(&col_ptr, &row_idx, &values, x, y);
        let (x, outcome) = preconditioned_cg(product, precondition, &b, 1e-12, 50);
        assert!(outcome.converged, "{outcome:?}");
        assert!((2..=14).contains(&outcome.iterations), "{outcome:?}");
        let mut kx = vec![0.0; n];
        symmetric_product(&col_ptr, &row_idx, &values, &x, &mut kx);
        let error = kx
            .iter()
            .zip(&b)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        let b_norm = b.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(error <= 1e-12 * b_norm * 1.0001, "{error:e}");
    }
}
