//! Conjugate gradients preconditioned by the Cholesky factor of an earlier
//! tangent of the same pattern ([`crate::linsolve`]).
//!
//! Within a load step the tangent changes little from one Newton iteration
//! to the next, so the factor of the first iteration's tangent `M` is close
//! to every later one `K`: `M^-1 K` has its eigenvalues clustered at 1 and
//! CG reaches round-off in a few iterations, each a pair of triangular
//! solves with the stale factor and a product with `K`, a fraction of a
//! factorisation's cost. PARDISO offers the same idea (a Krylov solver
//! preconditioned by an earlier factorisation, its `iparm(4)`).

use rayon::prelude::*;

/// How a preconditioned CG solve ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CgOutcome {
    /// Products with `K` after the first preconditioned solve.
    pub iterations: usize,
    /// `|r| / |b|` at the end, `r` CG's recurrence's residual (equal to
    /// `b - K x` in exact arithmetic; on an ill-conditioned `K` the true
    /// residual ends above it).
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
    y.par_iter_mut()
        .with_min_len(1024)
        .enumerate()
        .for_each(|(j, yj)| {
            *yj = (col_ptr[j]..col_ptr[j + 1])
                .map(|k| values[k].into() * x[row_idx[k] as usize])
                .sum();
        });
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.par_iter()
        .with_min_len(4096)
        .zip(b)
        .map(|(x, y)| x * y)
        .sum()
}

/// Solves `K x = b` by CG from `x0 = M^-1 b`, with `precondition(z)`
/// replacing `z` by `M^-1 z`, until the residual `|b - K x| <= tolerance
/// |b|` or `max_iterations` products with `K`. Converged means the true
/// residual, computed afresh at the end, is within [`TRUE_RESIDUAL_SLACK`]
/// of the tolerance.
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
    #[test]
    fn a_near_preconditioner_converges_in_a_few_iterations() {
        let n: usize = 200;
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        for j in 0..n {
            for (i, v) in [(j.wrapping_sub(1), -1.0), (j, 2.0), (j + 1, -1.0)] {
                if i < n {
                    row_idx.push(i as u32);
                    values.push(v);
                }
            }
            col_ptr.push(row_idx.len());
        }
        // M^-1 z by the Thomas algorithm on (M's diagonal, -1).
        let diagonal = 2.0 + 1e-4;
        let precondition = |z: &mut [f64]| {
            let mut c = vec![0.0; n];
            let mut d = z.to_vec();
            c[0] = -1.0 / diagonal;
            d[0] /= diagonal;
            for i in 1..n {
                let m = diagonal + c[i - 1];
                c[i] = -1.0 / m;
                d[i] = (d[i] + d[i - 1]) / m;
            }
            for i in (0..n - 1).rev() {
                d[i] -= c[i] * d[i + 1];
            }
            z.copy_from_slice(&d);
        };
        let b: Vec<f64> = (0..n).map(|i| ((i * 7) % 13) as f64 - 6.0).collect();
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
