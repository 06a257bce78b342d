//! The material part of the tangent stiffness.

use rayon::prelude::*;

use super::Pattern;
use crate::grid::Connectivity;
use crate::material::Response;
use crate::particles::MaterialPoints;

/// Values of the tangent stiffness
/// `K_(ai),(bj) = sum_p V0_p g_pa,I A_p[(2i+I),(2j+J)] g_pb,J`
/// in the layout of `pattern`, written over `k` (resized to the pattern).
///
/// Each node's two columns are filled by one task from the points that
/// touch the node, so threads write disjoint parts of `k` and need no
/// accumulators of their own.
///
/// When every point's tangent `A_p` is `symmetric` (then so is `K`), only
/// the blocks on and above the diagonal are summed, as they would be
/// otherwise, and those below are copied from them
/// ([`Pattern::mirror_upper`]): half the flops, the same upper triangle
/// to the bit, so a Cholesky factor (which reads that triangle) is the
/// same too.
pub fn stiffness(
    conn: &Connectivity,
    pattern: &Pattern,
    points: &MaterialPoints,
    responses: &[Response],
    symmetric: bool,
    k: &mut Vec<f64>,
) {
    k.clear();
    k.resize(pattern.nnz(), 0.0);
    pattern
        .node_columns_mut(k)
        .into_par_iter()
        .enumerate()
        .for_each(|(b, column)| {
            let stride = column.len() / 2;
            for &(p, link) in pattern.incident(b) {
                let p = p as usize;
                let lb = &conn.links[link as usize];
                let v0 = points.volume0[p];
                let t = &responses[p].tangent;
                // q[2i+I][j] = V0 sum_J A[(2i+I),(2j+J)] g_b,J
                let mut q = [[0.0; 2]; 4];
                for (row, qr) in q.iter_mut().enumerate() {
                    for (j, qrj) in qr.iter_mut().enumerate() {
                        *qrj =
                            v0 * (t[(row, 2 * j)] * lb.grad[0] + t[(row, 2 * j + 1)] * lb.grad[1]);
                    }
                }
                for la in conn.point_links(p) {
                    if symmetric && la.node as usize > b {
                        continue;
                    }
                    let base = pattern.block_in_column(la.node, b as u32);
                    for i in 0..2 {
                        for j in 0..2 {
                            column[base + i + j * stride] +=
                                la.grad[0] * q[2 * i][j] + la.grad[1] * q[2 * i + 1][j];
                        }
                    }
                }
            }
        });
    if symmetric {
        pattern.mirror_upper(k);
    }
}
