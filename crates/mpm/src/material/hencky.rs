//! Finite-strain elasticity: Hencky strain of the elastic left
//! Cauchy-Green tensor, Kirchhoff stress linear in it (as in AMPLE).

use nalgebra::{Matrix2, Matrix4};

use super::{CauchyStress, Elastic, History, Response};

/// Hencky elasticity on the elastic left Cauchy-Green tensor:
/// `b = dF b_n dF^T`, `e = ln(b) / 2`, `tau = lambda tr(e) I + 2 mu e`,
/// `P = tau dF^-T`, with `dF = I + grad_u`. The history is `b_n - I`
/// ([`trial_excess`]). The tangent is differentiated exactly: for each
/// unit direction `E` of `dF`,
/// `db = E b_n dF^T + dF b_n E^T`, `de = L[db] / 2` with `L` the derivative
/// of the matrix logarithm, `dtau = lambda tr(de) I + 2 mu de`,
/// `dP = dtau dF^-T - tau dF^-T E^T dF^-T`.
/// Without `want_tangent`, the tangent is left zero.
pub(super) fn hencky(
    c: &Elastic,
    b_n_excess: &Matrix2<f64>,
    grad_u: &Matrix2<f64>,
    j_start: f64,
    want_tangent: bool,
) -> Response {
    let df = Matrix2::identity() + grad_u;
    let excess = trial_excess(b_n_excess, grad_u);
    let eig = SymEigen2::of_excess(&excess);
    let e = eig.compose(eig.log_strains());
    let (tau, tau_zz) = c.stress(&e);
    let b_n = Matrix2::identity() + b_n_excess;
    let (p, tangent) = piola_and_tangent(&b_n, &df, &eig, &tau, |de| c.stress(de).0, want_tangent);
    let j = j_start * df.determinant();
    Response {
        p,
        tangent,
        history: History::elastic(excess),
        cauchy: CauchyStress {
            plane: [tau[(0, 0)] / j, tau[(1, 1)] / j, tau[(0, 1)] / j],
            zz: tau_zz / j,
        },
        off_flow_rule: false,
    }
}

/// `b - I` of the trial `b = dF b_n dF^T`, from `b_n - I` and `grad_u =
/// dF - I`, without forming `b`: `grad_u + grad_u^T + grad_u grad_u^T +
/// dF (b_n - I) dF^T`. A small strain's `b` is one plus the strain, so
/// its entries hold the strain to the round-off of one (1e-16) and a
/// strain of 1e-6 to ten digits; `b - I` holds it to sixteen. The points
/// keep `b - I` for the same reason: with `b` kept, a block strained 1e-5
/// by its weight in 15 steps stalled at a relative residual of 4e-9
/// against Newton's 1e-9 (`hard_cases.rs`).
pub(super) fn trial_excess(b_n_excess: &Matrix2<f64>, grad_u: &Matrix2<f64>) -> Matrix2<f64> {
    let df = Matrix2::identity() + grad_u;
    grad_u + grad_u.transpose() + grad_u * grad_u.transpose() + df * b_n_excess * df.transpose()
}

/// `P = tau dF^-T` and its derivative `dP / d(dF)` (flattened as in the
/// module docs of `material`), for a Kirchhoff stress `tau` that depends on
/// `dF` through the logarithm of the trial elastic left Cauchy-Green tensor
/// `b = dF b_n dF^T` (eigen-decomposed in `eig`): for each unit direction
/// `E` of `dF`, `db = E b_n dF^T + dF b_n E^T`, `de = L[db] / 2` with `L`
/// the derivative of the matrix logarithm, `dtau(de)` the model's, and
/// `dP = dtau dF^-T - tau dF^-T E^T dF^-T`. Without `want_tangent`, the
/// tangent is left zero.
pub(super) fn piola_and_tangent(
    b_n: &Matrix2<f64>,
    df: &Matrix2<f64>,
    eig: &SymEigen2,
    tau: &Matrix2<f64>,
    dtau: impl Fn(&Matrix2<f64>) -> Matrix2<f64>,
    want_tangent: bool,
) -> (Matrix2<f64>, Matrix4<f64>) {
    let df_inv_t = df
        .try_inverse()
        .map(|m| m.transpose())
        .unwrap_or_else(|| Matrix2::from_element(f64::NAN));
    let mut tangent = Matrix4::zeros();
    if !want_tangent {
        return (tau * df_inv_t, tangent);
    }
    let weights = eig.log_derivative_weights();
    for j in 0..2 {
        for jj in 0..2 {
            let mut dir = Matrix2::zeros();
            dir[(j, jj)] = 1.0;
            let db = dir * b_n * df.transpose() + df * b_n * dir.transpose();
            let de = eig.log_derivative(&weights, &db) * 0.5;
            let dp = dtau(&de) * df_inv_t - tau * df_inv_t * dir.transpose() * df_inv_t;
            for i in 0..2 {
                for ii in 0..2 {
                    tangent[(2 * i + ii, 2 * j + jj)] = dp[(i, ii)];
                }
            }
        }
    }
    (tau * df_inv_t, tangent)
}

/// Eigen-decomposition of a symmetric 2x2 matrix, `b = sum_a l_a n_a n_a^T`.
pub(super) struct SymEigen2 {
    /// `l_a - 1`.
    pub(super) excess: [f64; 2],
    pub(super) values: [f64; 2],
    pub(super) vectors: [nalgebra::Vector2<f64>; 2],
}

impl SymEigen2 {
    /// Of `b` given by its excess `b - I`: the eigenvalues' excesses
    /// `l_a - 1` are found to the precision of `b - I`'s entries.
    pub(super) fn of_excess(excess: &Matrix2<f64>) -> Self {
        let (a, d, c) = (
            excess[(0, 0)],
            excess[(1, 1)],
            0.5 * (excess[(0, 1)] + excess[(1, 0)]),
        );
        let mean = 0.5 * (a + d);
        let radius = (0.25 * (a - d) * (a - d) + c * c).sqrt();
        let theta = 0.5 * (2.0 * c).atan2(a - d);
        let (s, co) = theta.sin_cos();
        let excess = [mean + radius, mean - radius];
        Self {
            excess,
            values: excess.map(|x| 1.0 + x),
            vectors: [
                nalgebra::Vector2::new(co, s),
                nalgebra::Vector2::new(-s, co),
            ],
        }
    }

    /// The logarithmic strains `ln(l_a) / 2`, as `ln_1p` of the excesses.
    pub(super) fn log_strains(&self) -> [f64; 2] {
        self.excess.map(|x| 0.5 * x.ln_1p())
    }

    /// `sum_a v_a n_a n_a^T`.
    pub(super) fn compose(&self, v: [f64; 2]) -> Matrix2<f64> {
        (0..2)
            .map(|k| self.vectors[k] * self.vectors[k].transpose() * v[k])
            .sum()
    }

    /// The weights `f_ab` of [`SymEigen2::log_derivative`]: `f_aa = 1/l_a`
    /// and `f_ab = (ln l_a - ln l_b)/(l_a - l_b)` (its limit `1/l_a` when
    /// the eigenvalues coincide), made once for the tangent's four
    /// directions.
    pub(super) fn log_derivative_weights(&self) -> [[f64; 2]; 2] {
        let [l0, l1] = self.values;
        let gap = self.excess[0] - self.excess[1];
        let f01 = if gap.abs() > 1e-8 * l0.abs() {
            (self.excess[0].ln_1p() - self.excess[1].ln_1p()) / gap
        } else {
            // Series of (ln l0 - ln l1)/(l0 - l1) about the mean m:
            // 1/m + gap^2 / (12 m^3) + ...
            let m = 0.5 * (l0 + l1);
            1.0 / m + gap * gap / (12.0 * m * m * m)
        };
        [[1.0 / l0, f01], [f01, 1.0 / l1]]
    }

    /// Directional derivative of `ln(b)` along a symmetric `db`:
    /// `sum_ab f_ab (n_a . db n_b) n_a n_b^T`, `f` the
    /// [`SymEigen2::log_derivative_weights`].
    pub(super) fn log_derivative(&self, f: &[[f64; 2]; 2], db: &Matrix2<f64>) -> Matrix2<f64> {
        let mut out = Matrix2::zeros();
        for a in 0..2 {
            for b in 0..2 {
                let na = &self.vectors[a];
                let nb = &self.vectors[b];
                out += na * nb.transpose() * (f[a][b] * na.dot(&(db * nb)));
            }
        }
        out
    }
}
