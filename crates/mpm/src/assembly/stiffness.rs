//! The material part of the tangent stiffness.

use super::scatter_sum;

use super::Pattern;
use crate::grid::Connectivity;
use crate::material::Response;
use crate::particles::MaterialPoints;

/// Values of the tangent stiffness
/// `K_(ai),(bj) = sum_p V0_p g_pa,I A_p[(2i+I),(2j+J)] g_pb,J`
/// in the layout of `pattern`.
pub fn stiffness(
    conn: &Connectivity,
    pattern: &Pattern,
    points: &MaterialPoints,
    responses: &[Response],
) -> Vec<f64> {
    scatter_sum(conn.n_points(), pattern.nnz(), |p, k| {
        let v0 = points.volume0[p];
        let t = &responses[p].tangent;
        let links = conn.point_links(p);
        for lb in links {
            // q[2i+I][j] = V0 sum_J A[(2i+I),(2j+J)] g_b,J
            let mut q = [[0.0; 2]; 4];
            for (row, qr) in q.iter_mut().enumerate() {
                for (j, qrj) in qr.iter_mut().enumerate() {
                    *qrj = v0 * (t[(row, 2 * j)] * lb.grad[0] + t[(row, 2 * j + 1)] * lb.grad[1]);
                }
            }
            for la in links {
                let (base, stride) = pattern.block(la.node, lb.node);
                for i in 0..2 {
                    for j in 0..2 {
                        k[base + i + j * stride] +=
                            la.grad[0] * q[2 * i][j] + la.grad[1] * q[2 * i + 1][j];
                    }
                }
            }
        }
    })
}
