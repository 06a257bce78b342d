//! The material part of the tangent stiffness.

use nalgebra::Matrix4;
use rayon::prelude::*;

use super::Pattern;
use super::pattern::SharedValues;
use crate::grid::Connectivity;
use crate::particles::MaterialPoints;

/// Values of the tangent stiffness
/// `K_(ai),(bj) = sum_p V0_p g_pa,I A_p[(2i+I),(2j+J)] g_pb,J`
/// in the layout of `pattern`, written over `k` (resized to the pattern).
/// `tangent(p)` is point `p`'s `A_p`, asked for once.
///
/// The points are summed tile by tile, the tiles of one colour in
/// parallel ([`super::pattern::PointTiles`]: their points share no node),
/// so threads need no accumulators of their own and each point's tangent
/// is made where it is used, not kept.
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
    tangent: impl Fn(usize) -> Matrix4<f64> + Sync,
    symmetric: bool,
    k: &mut Vec<f64>,
) {
    k.clear();
    k.resize(pattern.nnz(), 0.0);
    let shared = SharedValues(k.as_mut_ptr());
    let tiles = &pattern.tiles;
    for colour in 0..4 {
        tiles.of_colour(colour).into_par_iter().for_each(|t| {
            let shared = &shared;
            for &p in tiles.points(t) {
                let p = p as usize;
                let v0 = points.volume0[p];
                let a = tangent(p);
                let links = conn.point_links(p);
                for lb in links {
                    // q[2i+I][j] = V0 sum_J A[(2i+I),(2j+J)] g_b,J
                    let mut q = [[0.0; 2]; 4];
                    for (row, qr) in q.iter_mut().enumerate() {
                        for (j, qrj) in qr.iter_mut().enumerate() {
                            *qrj = v0
                                * (a[(row, 2 * j)] * lb.grad[0] + a[(row, 2 * j + 1)] * lb.grad[1]);
                        }
                    }
                    for la in links {
                        if symmetric && la.node > lb.node {
                            continue;
                        }
                        let (base, stride) = pattern.block(la.node, lb.node);
                        for i in 0..2 {
                            for j in 0..2 {
                                // SAFETY: the place is inside `k` (the
                                // pattern's own), and in a block of two
                                // nodes of this tile's points, which no
                                // other tile of this colour has
                                // (`PointTiles`); colours run one after
                                // another.
                                unsafe {
                                    *shared.0.add(base + i + j * stride) +=
                                        la.grad[0] * q[2 * i][j] + la.grad[1] * q[2 * i + 1][j];
                                }
                            }
                        }
                    }
                }
            }
        });
    }
    if symmetric {
        pattern.mirror_upper(k);
    }
}
