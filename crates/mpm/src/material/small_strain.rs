//! Geometrically linear elasticity, for checks against linear theory.

use nalgebra::{Matrix2, Matrix4};

use super::{CauchyStress, Elastic, History, Response};

/// Geometrically linear elasticity: `eps = eps_n + sym(grad_u)`, `P = sigma`.
pub(super) fn small_strain(c: &Elastic, eps_n: &Matrix2<f64>, h: &Matrix2<f64>) -> Response {
    let eps = eps_n + (h + h.transpose()) * 0.5;
    let (sigma, zz) = c.stress(&eps);
    let mut tangent = Matrix4::zeros();
    let delta = |a: usize, b: usize| if a == b { 1.0 } else { 0.0 };
    for i in 0..2 {
        for ii in 0..2 {
            for j in 0..2 {
                for jj in 0..2 {
                    tangent[(2 * i + ii, 2 * j + jj)] = c.lambda * delta(i, ii) * delta(j, jj)
                        + c.mu * (delta(i, j) * delta(ii, jj) + delta(i, jj) * delta(ii, j));
                }
            }
        }
    }
    Response {
        p: sigma,
        tangent,
        history: History::elastic(eps),
        cauchy: CauchyStress {
            plane: [sigma[(0, 0)], sigma[(1, 1)], sigma[(0, 1)]],
            zz,
        },
        off_flow_rule: false,
    }
}
