//! The material part of the tangent stiffness.

use super::Pattern;
use crate::grid::Connectivity;
use crate::particles::{Dim, MaterialPoints, Space};

/// A point's tangent `A_p` in `D` dimensions.
type Tangent<const D: usize> = <Dim<D> as Space<D>>::Tangent;

/// Values of the tangent stiffness
/// `K_(ai),(bj) = sum_p V0_p g_pa,I A_p[(Di+I),(Dj+J)] g_pb,J`
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
pub fn stiffness<const D: usize>(
    conn: &Connectivity<D>,
    pattern: &Pattern,
    points: &MaterialPoints<D>,
    tangent: impl Fn(usize) -> Tangent<D> + Sync,
    symmetric: bool,
    k: &mut Vec<f64>,
) where
    Dim<D>: Space<D>,
{
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
fn sum_tiles<const D: usize>(
    conn: &Connectivity<D>,
    pattern: &Pattern,
    points: &MaterialPoints<D>,
    tangent: impl Fn(usize) -> Tangent<D> + Sync,
    symmetric: bool,
    k: &mut [f64],
) where
    Dim<D>: Space<D>,
{
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
fn add_point<const D: usize>(
    conn: &Connectivity<D>,
    pattern: &Pattern,
    points: &MaterialPoints<D>,
    p: usize,
    a: &Tangent<D>,
    symmetric: bool,
    mut add: impl FnMut(usize, f64),
) where
    Dim<D>: Space<D>,
{
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
        // q[Di+I][j] = V0 sum_J A[(Di+I),(Dj+J)] g_b,J, summed from the
        // first term (in 2D, the two-term sum as written); rows past D^2
        // unused.
        let mut q = [[0.0; D]; 9];
        for (row, qr) in q.iter_mut().enumerate().take(D * D) {
            for (j, qrj) in qr.iter_mut().enumerate() {
                let mut sum = a[(row, D * j)] * lb.grad[0];
                for jj in 1..D {
                    sum += a[(row, D * j + jj)] * lb.grad[jj];
                }
                *qrj = v0 * sum;
            }
        }
        let mut column = pattern.column(lb.node);
        for &ia in order.iter() {
            let la = &links[ia as usize];
            if symmetric && la.node > lb.node {
                break;
            }
            let (base, stride) = column.block(la.node);
            for i in 0..D {
                for j in 0..D {
                    let mut sum = la.grad[0] * q[D * i][j];
                    for ii in 1..D {
                        sum += la.grad[ii] * q[D * i + ii][j];
                    }
                    add(base + i + j * stride, sum);
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

    /// In 3D the assembled stiffness is the derivative of the internal
    /// force: about a non-uniform deformation of a Hencky box (GIMP, an
    /// offset grid), `K v` against central differences of `f_int(u)` along
    /// a varied `v`, to 1e-9 of `|K v|` (measured: 5e-12, the differences'
    /// own error).
    #[test]
    fn the_three_dimensional_stiffness_is_the_derivative_of_the_force() {
        use crate::assembly::internal_force;
        use crate::grid::{Basis, increment};
        use crate::material::History3;
        let (points, grid) = fixtures::solid_box([0.0; 3], [1.0, 0.75, 0.5], 0.125, 0.25);
        let conn = fixtures::solid_links(&points, &grid, Basis::Gimp);
        let pattern = Pattern::build(&conn, &[]);
        let n = conn.n_dofs();
        let u: Vec<f64> = (0..n)
            .map(|dof| {
                let x = grid.node_position(conn.nodes[dof / 3]);
                1e-2 * [x[1] * x[2], -x[0] * x[0], 0.5 * x[0] * x[1]][dof % 3]
            })
            .collect();
        let v: Vec<f64> = (0..n)
            .map(|dof| ((dof * 7919) % 13) as f64 / 13.0 - 0.5)
            .collect();
        let model = points.materials[0];
        let respond = |u: &[f64], p: usize| {
            let (_, grad_u) = increment(conn.point_links(p), u);
            model.respond_3d(&History3::virgin(), &grad_u, 1.0)
        };
        let mut k = Vec::new();
        stiffness(
            &conn,
            &pattern,
            &points,
            |p| respond(&u, p).tangent,
            false,
            &mut k,
        );
        let mut kv = vec![0.0; n];
        for col in 0..n {
            for at in pattern.col_ptr[col]..pattern.col_ptr[col + 1] {
                kv[pattern.row_idx[at] as usize] += k[at] * v[col];
            }
        }
        let eps = 1e-6;
        let force = |sign: f64| {
            let shifted: Vec<f64> = u.iter().zip(&v).map(|(a, b)| a + sign * eps * b).collect();
            internal_force(&conn, &points, |p| respond(&shifted, p).p)
        };
        let (plus, minus) = (force(1.0), force(-1.0));
        let (mut miss, mut size) = (0.0f64, 0.0f64);
        for dof in 0..n {
            let difference = (plus[dof] - minus[dof]) / (2.0 * eps);
            miss += (difference - kv[dof]).powi(2);
            size += kv[dof].powi(2);
        }
        let miss = (miss / size).sqrt();
        eprintln!("3D stiffness: miss {miss:e} of |K v|");
        assert!(miss < 1e-9, "{miss:e}");
    }
}
