//! GIMP on a point's own cell when that cell is not an axis-aligned
//! rectangle: a turned rectangle's, a mapped quadrilateral's or a polar
//! lattice's. The weights are the grid's functions averaged over the cell
//! `D`,
//!
//! `S_i = (1/A) int_D N_i`, `grad S_i = (1/A) int_D grad N_i`,
//!
//! the second being the derivative of the first as `D` moves with the
//! point. Both integrals are exact: `D` (convex, straight-sided) is clipped
//! to every knot span it overlaps (the grid's cells, or for quadratic
//! B-splines the cells shifted by half a cell), where the functions are
//! polynomials, and each piece is cut into a fan of triangles. For the
//! hats, the rule at the edge midpoints (exact for quadratics) integrates
//! `N_i` (bilinear) and `grad N_i`; for B-splines of degree `p` (a
//! polynomial of degree `2p`), the collapsed (Duffy) `(p+1) x (p+1)` Gauss
//! rule, exact to degree `2p + 1`.
//!
//! So `sum S_i = 1`, `sum grad S_i = 0`, `sum x_i (x) grad S_i = I`, and
//! cells that tile the body give interior nodes a zero net force under a
//! uniform stress, whatever the angle: the patch test. On an axis-aligned
//! rectangle this is the tensor product of [`super`] (tested).

use super::{Basis, NodeWeight};
use crate::grid::{Grid, lattice_key};

/// The most vertices a convex quadrilateral clipped to a rectangle has.
const MAX_VERTICES: usize = 8;

/// A convex polygon of at most [`MAX_VERTICES`] vertices, on the stack.
#[derive(Clone, Copy)]
struct Polygon {
    v: [[f64; 2]; MAX_VERTICES],
    len: usize,
}

impl Polygon {
    fn new(corners: &[[f64; 2]]) -> Self {
        let mut p = Self {
            v: [[0.0; 2]; MAX_VERTICES],
            len: corners.len(),
        };
        p.v[..corners.len()].copy_from_slice(corners);
        p
    }

    /// The part with `sign * (x[d] - at) >= 0` (one Sutherland-Hodgman
    /// pass).
    fn clip(&self, d: usize, at: f64, sign: f64) -> Self {
        let mut out = Self {
            v: [[0.0; 2]; MAX_VERTICES],
            len: 0,
        };
        for k in 0..self.len {
            let (a, b) = (self.v[k], self.v[(k + 1) % self.len]);
            let (fa, fb) = (sign * (a[d] - at), sign * (b[d] - at));
            if fa >= 0.0 {
                out.push(a);
            }
            if (fa > 0.0 && fb < 0.0) || (fa < 0.0 && fb > 0.0) {
                let t = fa / (fa - fb);
                let mut x = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                x[d] = at;
                out.push(x);
            }
        }
        out
    }

    fn push(&mut self, x: [f64; 2]) {
        // A convex polygon cut by one line gains at most one vertex, so
        // four cuts of a quadrilateral stay within the capacity.
        self.v[self.len] = x;
        self.len += 1;
    }
}

/// Twice the signed area of the triangle `(a, b, c)`.
fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Signed area of the quadrilateral `corners` (half the cross product of
/// its diagonals).
pub fn area(c: &[[f64; 2]; 4]) -> f64 {
    let d1 = [c[2][0] - c[0][0], c[2][1] - c[0][1]];
    let d2 = [c[3][0] - c[1][0], c[3][1] - c[1][1]];
    0.5 * (d1[0] * d2[1] - d1[1] * d2[0])
}

/// The lowest and highest corner of the quadrilateral's bounding box.
pub fn bounds(corners: &[[f64; 2]; 4]) -> ([f64; 2], [f64; 2]) {
    let lo = [0, 1].map(|d| corners.iter().map(|c| c[d]).fold(f64::INFINITY, f64::min));
    let hi = [0, 1].map(|d| {
        corners
            .iter()
            .map(|c| c[d])
            .fold(f64::NEG_INFINITY, f64::max)
    });
    (lo, hi)
}

/// The lowest and highest cell `(i, j)` that the quadrilateral `corners`
/// overlaps.
fn cell_range(grid: &Grid, corners: &[[f64; 2]; 4]) -> ([i64; 2], [i64; 2]) {
    let (lo, hi) = bounds(corners);
    (grid.cell_of(lo), grid.cell_of(hi))
}

/// Pushes a zero weight for every node `(i, j)` with `lo <= (i, j) <= hi`,
/// in `(i, j)` order, and returns the first one's index in `out`.
fn push_slots<const D: usize>(lo: [i64; 2], hi: [i64; 2], out: &mut Vec<NodeWeight<D>>) -> usize {
    let first = out.len();
    for j in lo[1]..=hi[1] {
        for i in lo[0]..=hi[0] {
            out.push(NodeWeight {
                node: lattice_key::<D>(super::from_plane([i, j])),
                n: 0.0,
                grad: [0.0; D],
            });
        }
    }
    first
}

/// Drops the weights from `first` on that are zero with their gradient.
fn drop_zeros<const D: usize>(first: usize, out: &mut Vec<NodeWeight<D>>) {
    let mut k = first;
    for i in first..out.len() {
        if out[i].n != 0.0 || out[i].grad != [0.0; D] {
            out[k] = out[i];
            k += 1;
        }
    }
    out.truncate(k);
}

/// The part of `domain` in the axis-aligned box from `x0` to `x0 + h`.
fn clip_to_box(domain: &Polygon, x0: [f64; 2], h: f64) -> Polygon {
    domain
        .clip(0, x0[0], 1.0)
        .clip(0, x0[0] + h, -1.0)
        .clip(1, x0[1], 1.0)
        .clip(1, x0[1] + h, -1.0)
}

/// Appends to `out` the averaged hats of every node the convex
/// quadrilateral `corners` (absolute positions, either orientation)
/// reaches. The grid is 2D; `D` is the weights' (2).
pub fn eval<const D: usize>(grid: &Grid<D>, corners: &[[f64; 2]; 4], out: &mut Vec<NodeWeight<D>>) {
    let grid = &planar(grid);
    let whole = area(corners);
    let (lo, hi) = cell_range(grid, corners);
    // One slot per node of the overlapped cells, in (i, j) order.
    let width = (hi[0] - lo[0] + 2) as usize;
    let first = push_slots(lo, [hi[0] + 1, hi[1] + 1], out);
    let h = grid.h;
    let domain = Polygon::new(corners);
    for cj in lo[1]..=hi[1] {
        for ci in lo[0]..=hi[0] {
            let x0 = [
                grid.origin[0] + h * ci as f64,
                grid.origin[1] + h * cj as f64,
            ];
            let piece = clip_to_box(&domain, x0, h);
            if piece.len < 3 {
                continue;
            }
            // Slots of the cell's nodes (i, j), (i+1, j), (i, j+1), (i+1, j+1).
            let s00 = first + (ci - lo[0]) as usize + (cj - lo[1]) as usize * width;
            let slots = [s00, s00 + 1, s00 + width, s00 + width + 1];
            for k in 1..piece.len - 1 {
                let (a, b, c) = (piece.v[0], piece.v[k], piece.v[k + 1]);
                let weight = cross(a, b, c) / 6.0 / whole; // (area / 3) / A
                for (p, q) in [(a, b), (b, c), (c, a)] {
                    let xi = ((p[0] + q[0]) / 2.0 - x0[0]) / h;
                    let eta = ((p[1] + q[1]) / 2.0 - x0[1]) / h;
                    let values = [
                        (1.0 - xi) * (1.0 - eta),
                        xi * (1.0 - eta),
                        (1.0 - xi) * eta,
                        xi * eta,
                    ];
                    let grads = [
                        [-(1.0 - eta), -(1.0 - xi)],
                        [1.0 - eta, -xi],
                        [-eta, 1.0 - xi],
                        [eta, xi],
                    ];
                    for m in 0..4 {
                        let w = &mut out[slots[m]];
                        w.n += weight * values[m];
                        w.grad[0] += weight * grads[m][0] / h;
                        w.grad[1] += weight * grads[m][1] / h;
                    }
                }
            }
        }
    }
    drop_zeros(first, out);
}

/// Appends to `out` the uniform B-splines of `degree` (2 or 3) averaged
/// over the convex quadrilateral `corners` (absolute positions, either
/// orientation), for every node it reaches. The grid is 2D; `D` is the
/// weights' (2).
pub fn eval_bsplines<const D: usize>(
    grid: &Grid<D>,
    corners: &[[f64; 2]; 4],
    degree: usize,
    out: &mut Vec<NodeWeight<D>>,
) {
    let grid = &planar(grid);
    let basis = if degree == 2 {
        Basis::BSpline2
    } else {
        Basis::BSpline3
    };
    // Knot spans start on the grid lines (cubic) or half a cell past them
    // (quadratic, whose knots are the cells' middles).
    let shift = if degree == 2 { 0.5 } else { 0.0 };
    let h = grid.h;
    let whole = area(corners);
    let (lo, hi) = bounds(corners);
    let span = |v: f64, d: usize| ((v - grid.origin[d]) / h - shift).floor() as i64;
    let (span_lo, span_hi) = (
        [span(lo[0], 0), span(lo[1], 1)],
        [span(hi[0], 0), span(hi[1], 1)],
    );
    // The nodes whose functions reach the box.
    let reach = basis.half_support();
    let node = |v: f64, d: usize, side: f64| (v - grid.origin[d]) / h + side * reach;
    let node_lo = [0, 1].map(|d| node(lo[d], d, -1.0).ceil() as i64);
    let node_hi = [0, 1].map(|d| node(hi[d], d, 1.0).floor() as i64);
    let width = (node_hi[0] - node_lo[0] + 1) as usize;
    let first = push_slots(node_lo, node_hi, out);
    let gauss: &[(f64, f64)] = if degree == 2 { &GAUSS3_01 } else { &GAUSS4_01 };
    let domain = Polygon::new(corners);
    for sj in span_lo[1]..=span_hi[1] {
        for si in span_lo[0]..=span_hi[0] {
            let x0 = [0, 1].map(|d| grid.origin[d] + h * ([si, sj][d] as f64 + shift));
            let piece = clip_to_box(&domain, x0, h);
            for k in 1..piece.len.max(2) - 1 {
                let (a, b, c) = (piece.v[0], piece.v[k], piece.v[k + 1]);
                // x = a + u (b - a) + u v (c - b), dx = 2 (area) u du dv.
                let jacobian = cross(a, b, c) / whole;
                for &(u, wu) in gauss {
                    for &(v, wv) in gauss {
                        let x = [0, 1].map(|d| a[d] + u * (b[d] - a[d]) + u * v * (c[d] - b[d]));
                        let weight = wu * wv * u * jacobian;
                        let wx = basis.eval_1d(h, x[0] - grid.origin[0], 0.0);
                        let wy = basis.eval_1d(h, x[1] - grid.origin[1], 0.0);
                        for &(j, sy, dsy) in wy.as_slice() {
                            let row = first + (j - node_lo[1]) as usize * width;
                            for &(i, sx, dsx) in wx.as_slice() {
                                let w = &mut out[row + (i - node_lo[0]) as usize];
                                w.n += weight * sx * sy;
                                w.grad[0] += weight * dsx * sy;
                                w.grad[1] += weight * sx * dsy;
                            }
                        }
                    }
                }
            }
        }
    }
    drop_zeros(first, out);
}

/// A 2D grid as itself: quadrilateral domains are 2D.
fn planar<const D: usize>(grid: &Grid<D>) -> Grid {
    Grid {
        h: grid.h,
        origin: super::in_plane(grid.origin),
    }
}

/// Gauss-Legendre points and weights on `[0, 1]`, 3 and 4 points.
const GAUSS3_01: [(f64, f64); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];
const GAUSS4_01: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_9),
    (0.330_009_478_207_571_9, 0.326_072_577_431_273_1),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_1),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_9),
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::basis::{Basis, Support};
    use proptest::prelude::*;

    const GRID: Grid = Grid {
        h: 0.7,
        origin: [-0.3, 1.1],
    };

    /// A parallelogram with half-axes `a`, `b` about `x`, twisted by `c`.
    fn cell(x: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> [[f64; 2]; 4] {
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(s, t)| [0, 1].map(|d| x[d] + s * a[d] + t * b[d] + s * t * c[d]))
    }

    /// The hats (degree 1) or the B-splines of `degree` averaged.
    fn degree_weights(corners: &[[f64; 2]; 4], degree: usize) -> Vec<NodeWeight> {
        let mut w = Vec::new();
        match degree {
            1 => eval(&GRID, corners, &mut w),
            p => eval_bsplines(&GRID, corners, p, &mut w),
        }
        w
    }

    fn basis(degree: usize) -> Basis {
        [Basis::Gimp, Basis::BSpline2, Basis::BSpline3][degree - 1]
    }

    proptest! {
        // The sums the patch test needs: sum S = 1, sum grad S = 0,
        // sum S x_i = the centroid, sum x_i (x) grad S = I.
        #[test]
        fn averaged_hats_reproduce_linear_fields(
            x in -3.0..3.0f64, y in -3.0..3.0f64,
            la in 0.05..0.7f64, lb in 0.05..0.7f64, angle in 0.0..6.3f64,
            cx in -0.3..0.3f64, cy in -0.3..0.3f64, flip in proptest::bool::ANY,
            degree in 1..=3usize,
        ) {
            let (s, co) = angle.sin_cos();
            let (a, b) = ([la * co, la * s], [-lb * s, lb * co]);
            let c = [cx * la.min(lb) / 2.0, cy * la.min(lb) / 2.0];
            let mut corners = cell([x, y], a, b, c);
            if flip {
                corners.reverse();
            }
            let w = degree_weights(&corners, degree);
            let n: f64 = w.iter().map(|w| w.n).sum();
            prop_assert!((n - 1.0).abs() < 1e-12, "{}", n);
            let mut first = [0.0; 2];
            let mut identity = [[0.0; 2]; 2];
            let mut g = [0.0; 2];
            for nw in &w {
                let xi = GRID.node_position(nw.node);
                for d in 0..2 {
                    first[d] += nw.n * xi[d];
                    g[d] += nw.grad[d];
                    for e in 0..2 {
                        identity[d][e] += xi[d] * nw.grad[e];
                    }
                }
            }
            prop_assert!(g[0].abs() < 1e-10 && g[1].abs() < 1e-10, "{:?}", g);
            for d in 0..2 {
                for e in 0..2 {
                    let exact = if d == e { 1.0 } else { 0.0 };
                    prop_assert!((identity[d][e] - exact).abs() < 1e-10, "{:?}", identity);
                }
            }
            // The centroid of a quadrilateral: the area-weighted centroids
            // of the two triangles either side of a diagonal.
            let (t1, t2) = (
                cross(corners[0], corners[1], corners[2]),
                cross(corners[0], corners[2], corners[3]),
            );
            let centroid = [0, 1].map(|d| {
                (t1 * (corners[0][d] + corners[1][d] + corners[2][d])
                    + t2 * (corners[0][d] + corners[2][d] + corners[3][d]))
                    / (3.0 * (t1 + t2))
            });
            prop_assert!((first[0] - centroid[0]).abs() < 1e-12);
            prop_assert!((first[1] - centroid[1]).abs() < 1e-12);
        }

        // On an upright rectangle the average is the tensor product (GIMP,
        // or the B-splines averaged in x and in y).
        #[test]
        fn an_upright_cell_is_the_tensor_product(
            x in -3.0..3.0f64, y in -3.0..3.0f64, lx in 0.01..0.35f64, ly in 0.01..0.35f64,
            degree in 1..=3usize,
        ) {
            let w = degree_weights(&cell([x, y], [lx, 0.0], [0.0, ly], [0.0, 0.0]), degree);
            let mut gimp = Vec::new();
            basis(degree).eval(&GRID, [x, y], Support::Rectangle([lx, ly]), &mut gimp);
            for g in &gimp {
                let q = w.iter().find(|w| w.node == g.node).copied().unwrap_or(NodeWeight {
                    node: g.node, n: 0.0, grad: [0.0, 0.0],
                });
                prop_assert!((q.n - g.n).abs() < 1e-12, "{:?} {:?}", q, g);
                prop_assert!((q.grad[0] - g.grad[0]).abs() < 1e-11, "{:?} {:?}", q, g);
                prop_assert!((q.grad[1] - g.grad[1]).abs() < 1e-11, "{:?} {:?}", q, g);
            }
            let total: f64 = w.iter().map(|w| w.n.abs()).sum();
            prop_assert!((total - 1.0).abs() < 1e-12);
        }

        // The gradient is the derivative of the value as the cell moves.
        #[test]
        fn the_gradient_follows_the_moving_cell(
            x in -3.0..3.0f64, y in -3.0..3.0f64, angle in 0.0..6.3f64, degree in 1..=3usize,
        ) {
            let (s, co) = angle.sin_cos();
            let (a, b, c) = ([0.2 * co, 0.2 * s], [-0.15 * s, 0.15 * co], [0.02, -0.01]);
            let eps = 1e-6;
            let value = |p: [f64; 2], key| {
                degree_weights(&cell(p, a, b, c), degree).iter().find(|w| w.node == key).map_or(0.0, |w| w.n)
            };
            for nw in degree_weights(&cell([x, y], a, b, c), degree) {
                let fx = (value([x + eps, y], nw.node) - value([x - eps, y], nw.node)) / (2.0 * eps);
                let fy = (value([x, y + eps], nw.node) - value([x, y - eps], nw.node)) / (2.0 * eps);
                prop_assert!((fx - nw.grad[0]).abs() < 1e-5, "{} vs {}", fx, nw.grad[0]);
                prop_assert!((fy - nw.grad[1]).abs() < 1e-5, "{} vs {}", fy, nw.grad[1]);
            }
        }
    }
}
