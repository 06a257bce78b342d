//! The material part of the tangent stiffness.

use nalgebra::Matrix4;

use super::Pattern;
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
/// is made where it is used, not kept. A scene of a few tiles (fewer than
/// [`TILES_A_THREAD`] a thread in rayon's pool: a few thousand points)
/// would then run on one or two threads; there, if the copies fit in
/// [`COPIES_ENTRIES`], each thread sums its share of the points into a
/// copy of the values ([`super::scatter_sum`]), and the copies are added.
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
    let threads = rayon::current_num_threads();
    if pattern.tiles.count() < TILES_A_THREAD * threads && pattern.nnz() * threads <= COPIES_ENTRIES
    {
        *k = super::scatter_sum(points.len(), pattern.nnz(), |p, values| {
            add_point(conn, pattern, points, p, &tangent(p), symmetric, |at, v| {
                values[at] += v
            });
        });
    } else {
        k.clear();
        k.resize(pattern.nnz(), 0.0);
        sum_tiles(conn, pattern, points, tangent, symmetric, k);
    }
    if symmetric {
        pattern.mirror_upper(k);
    }
}

/// Adds every point's `K_p` to `k` (the pattern's values) tile by tile,
/// the tiles of one colour in parallel.
fn sum_tiles(
    conn: &Connectivity,
    pattern: &Pattern,
    points: &MaterialPoints,
    tangent: impl Fn(usize) -> Matrix4<f64> + Sync,
    symmetric: bool,
    k: &mut [f64],
) {
    assert_eq!(k.len(), pattern.nnz());
    // SAFETY: a point's K_p lies in blocks of its linked nodes, the
    // pattern's own places.
    unsafe {
        pattern.tiles.sum_into(k, |p, values| {
            add_point(conn, pattern, points, p, &tangent(p), symmetric, |at, v| {
                values.add(at, v)
            });
        });
    }
}

/// Below this many tiles a thread, the points are summed by threads'
/// copies of the values rather than by tiles ([`stiffness`]).
const TILES_A_THREAD: usize = 8;

/// The most entries the threads' copies hold together (8 MB): on a machine
/// of many threads, fewer tiles than it has threads can still be a pattern
/// too large to copy for each.
const COPIES_ENTRIES: usize = 1 << 20;

/// Point `p`'s `K_p` with its tangent `a`, passed to `add` as (place in
/// the pattern's values, value); on and above the diagonal alone when
/// `symmetric`.
#[inline]
fn add_point(
    conn: &Connectivity,
    pattern: &Pattern,
    points: &MaterialPoints,
    p: usize,
    a: &Matrix4<f64>,
    symmetric: bool,
    mut add: impl FnMut(usize, f64),
) {
    let v0 = points.volume0[p];
    let links = conn.point_links(p);
    // The links in ascending node order, for each column's walk along its
    // neighbours (`Pattern::column`): 25 at most for the bases there are.
    let (mut on_stack, mut on_heap) = ([0u16; 32], Vec::new());
    let order: &mut [u16] = if links.len() <= on_stack.len() {
        &mut on_stack[..links.len()]
    } else {
        on_heap.resize(links.len(), 0);
        &mut on_heap
    };
    for (i, o) in order.iter_mut().enumerate() {
        *o = i as u16;
    }
    order.sort_unstable_by_key(|&i| links[i as usize].node);
    for lb in links {
        // q[2i+I][j] = V0 sum_J A[(2i+I),(2j+J)] g_b,J
        let mut q = [[0.0; 2]; 4];
        for (row, qr) in q.iter_mut().enumerate() {
            for (j, qrj) in qr.iter_mut().enumerate() {
                *qrj = v0 * (a[(row, 2 * j)] * lb.grad[0] + a[(row, 2 * j + 1)] * lb.grad[1]);
            }
        }
        let mut column = pattern.column(lb.node);
        for &ia in order.iter() {
            let la = &links[ia as usize];
            if symmetric && la.node > lb.node {
                break;
            }
            let (base, stride) = column.block(la.node);
            for i in 0..2 {
                for j in 0..2 {
                    add(
                        base + i + j * stride,
                        la.grad[0] * q[2 * i][j] + la.grad[1] * q[2 * i + 1][j],
                    );
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Matrix4;

    use super::{COPIES_ENTRIES, TILES_A_THREAD, stiffness, sum_tiles};
    use crate::assembly::Pattern;
    use crate::fixtures;

    /// A scene of few tiles sums its points by threads' copies of the
    /// values; its tangent is the tiles' sum, to the round-off of adding
    /// the same terms in another order (1e-13 of the largest entry: each
    /// entry sums some hundred terms of either sign), with a tangent that
    /// differs from point to point (so one point's tangent summed at
    /// another's links fails, checked), unsymmetric and symmetric.
    #[test]
    fn threads_copies_give_the_tiles_sum() {
        let mut case = fixtures::block([6.0, 3.0], [12, 6], 1.0, [0.1, 0.13]);
        case["basis"] = "gimp".into();
        case["bodies"][0]["material"]["density"] = 1.0.into();
        let sim = fixtures::simulation(&case);
        let conn = sim.reset_grid();
        let pattern = Pattern::build(&conn, &[]);
        let threads = rayon::current_num_threads();
        assert!(pattern.tiles.count() < TILES_A_THREAD * threads);
        assert!(pattern.nnz() * threads <= COPIES_ENTRIES);
        for symmetric in [false, true] {
            let tangent = |p: usize| {
                Matrix4::from_fn(|r, c| {
                    let (r, c) = if symmetric {
                        (r.min(c), r.max(c))
                    } else {
                        (r, c)
                    };
                    (1.0 + p as f64) * (1.0 + r as f64 + 5.0 * c as f64)
                })
            };
            let mut by_threads = Vec::new();
            stiffness(
                &conn,
                &pattern,
                &sim.points,
                tangent,
                symmetric,
                &mut by_threads,
            );
            let mut by_tiles = vec![0.0; pattern.nnz()];
            sum_tiles(
                &conn,
                &pattern,
                &sim.points,
                tangent,
                symmetric,
                &mut by_tiles,
            );
            if symmetric {
                pattern.mirror_upper(&mut by_tiles);
            }
            let largest = by_tiles.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let miss = by_threads
                .iter()
                .zip(&by_tiles)
                .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(largest > 0.0);
            assert!(
                miss <= 1e-13 * largest,
                "symmetric: {symmetric}: {miss:e} of {largest:e}"
            );
        }
    }
}
