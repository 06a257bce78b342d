//! Shape functions of the background grid, tensor products of 1D
//! functions, a family per file:
//! - `Linear` and `Gimp`: the finite-element hat, and its average over a
//!   point's domain ([`hat`]);
//! - `BSpline2`, `BSpline3`: the uniform quadratic and cubic B-splines,
//!   averaged the same way ([`bspline`]).
//!
//! A point whose domain is not an axis-aligned rectangle has either family
//! averaged over its own cell ([`quadrilateral_domain`], in 2D).
//!
//! In `D` dimensions a node's function is the product of `D` 1D functions
//! and each gradient component the product with one of them differentiated,
//! multiplied in axis order; in 2D that is `sx sy` and `(dsx sy, sx dsy)`.

mod bspline;
mod hat;
pub mod quadrilateral_domain;

use super::{Grid, NodeKey, lattice_key};

/// One node's contribution at a point: `N` and its gradient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeWeight<const D: usize = 2> {
    pub node: NodeKey,
    pub n: f64,
    pub grad: [f64; D],
}

/// Up to five 1D weights per direction (the averaged cubic B-spline).
type Weights1d = smallvec1d::Small;

/// A point's domain for GIMP, about the point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Support<const D: usize = 2> {
    /// An axis-aligned rectangle (a box in 3D) of these half-widths.
    Rectangle([f64; D]),
    /// In 2D, a convex quadrilateral: its corners relative to the point, in
    /// order round it.
    Quadrilateral([[f64; 2]; 4]),
}

/// A 2D quadrilateral domain's coordinates in the grid's `D`: only 2D
/// points have quadrilateral domains, so `D` is 2 and this is the identity.
fn in_plane<const D: usize>(x: [f64; D]) -> [f64; 2] {
    assert_eq!(D, 2, "quadrilateral domains are 2D");
    [x[0], x[1]]
}

/// [`in_plane`]'s inverse.
fn from_plane<T: Copy, const D: usize>(x: [T; 2]) -> [T; D] {
    assert_eq!(D, 2, "quadrilateral domains are 2D");
    std::array::from_fn(|d| x[d])
}

/// A quadrilateral domain's corners about `x`, shrunk about it to reach at
/// most `most` in x and in y, as a rectangle's half-widths are capped: a
/// wider domain reaches nodes the point does not need, and a huge one (a
/// body of one point on a fine grid) would list cells without bound.
fn placed(x: [f64; 2], corners: [[f64; 2]; 4], most: f64) -> [[f64; 2]; 4] {
    let reach = corners
        .iter()
        .map(|c| c[0].abs().max(c[1].abs()))
        .fold(0.0, f64::max);
    let k = if reach > most { most / reach } else { 1.0 };
    corners.map(|c| [x[0] + k * c[0], x[1] + k * c[1]])
}

/// The shape functions of a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Basis {
    Linear,
    Gimp,
    BSpline2,
    BSpline3,
}

impl Basis {
    /// Appends to `out` every node whose shape function or gradient is
    /// non-zero at `x`, for a point of domain `support` (ignored by the
    /// linear basis), the first axis's nodes fastest.
    pub fn eval<const D: usize>(
        &self,
        grid: &Grid<D>,
        x: [f64; D],
        support: Support<D>,
        out: &mut Vec<NodeWeight<D>>,
    ) {
        let half_width = match (self, support) {
            (Basis::Linear, _) => [0.0; D],
            (_, Support::Rectangle(half_width)) => half_width.map(|l| l.min(self.widest(grid.h))),
            (_, Support::Quadrilateral(corners)) => {
                let corners = placed(in_plane(x), corners, self.widest(grid.h));
                if quadrilateral_domain::area(&corners).abs() <= 1e-12 * grid.h * grid.h {
                    // A cell crushed flat has no average: the functions at x.
                    return self.eval(grid, x, Support::Rectangle([0.0; D]), out);
                }
                return match self.degree() {
                    1 => quadrilateral_domain::eval(grid, &corners, out),
                    p => quadrilateral_domain::eval_bsplines(grid, &corners, p, out),
                };
            }
        };
        // The product over the axes in axis order, the first axis's nodes
        // fastest, written out per dimension (an array of the axes' weights
        // with a loop over them evaluates GIMP 10% slower).
        let along = |d: usize| self.eval_1d(grid.h, x[d] - grid.origin[d], half_width[d]);
        let mut emit = |node: [i64; D], n: f64, grad: [f64; D]| {
            if n != 0.0 || grad != [0.0; D] {
                out.push(NodeWeight {
                    node: lattice_key(node),
                    n,
                    grad,
                });
            }
        };
        match D {
            2 => {
                let (wx, wy) = (along(0), along(1));
                for &(j, sy, dsy) in wy.as_slice() {
                    for &(i, sx, dsx) in wx.as_slice() {
                        let grad = [dsx * sy, sx * dsy];
                        emit(
                            std::array::from_fn(|d| [i, j][d]),
                            sx * sy,
                            std::array::from_fn(|d| grad[d]),
                        );
                    }
                }
            }
            3 => {
                let (wx, wy, wz) = (along(0), along(1), along(2));
                for &(k, sz, dsz) in wz.as_slice() {
                    for &(j, sy, dsy) in wy.as_slice() {
                        for &(i, sx, dsx) in wx.as_slice() {
                            let grad = [dsx * sy * sz, sx * dsy * sz, sx * sy * dsz];
                            emit(
                                std::array::from_fn(|d| [i, j, k][d]),
                                sx * sy * sz,
                                std::array::from_fn(|d| grad[d]),
                            );
                        }
                    }
                }
            }
            _ => unreachable!("the grid is 2D or 3D"),
        }
    }

    /// The polynomial degree of the 1D functions.
    pub fn degree(&self) -> usize {
        match self {
            Basis::Linear | Basis::Gimp => 1,
            Basis::BSpline2 => 2,
            Basis::BSpline3 => 3,
        }
    }

    /// How far, in cells, the 1D function of a node reaches either side of
    /// it: the hat a cell, the B-splines `(degree + 1) / 2`.
    pub fn half_support(&self) -> f64 {
        (self.degree() as f64 + 1.0) / 2.0
    }

    /// The widest a point's domain is taken, about the point, in x and in
    /// y: a cell for GIMP (beyond it would need more than four nodes per
    /// direction), half a cell for the wider B-splines (a domain of one
    /// point per cell, the coarsest a case is seeded with, and one node
    /// more per direction than at a point).
    fn widest(&self, h: f64) -> f64 {
        self.widest_domain(h)
    }

    /// [`Basis::widest`] on a grid of cell size `h`.
    pub fn widest_domain(&self, h: f64) -> f64 {
        match self {
            Basis::Linear => 0.0,
            Basis::Gimp => h,
            Basis::BSpline2 | Basis::BSpline3 => h / 2.0,
        }
    }

    /// How far, in cells, the functions of a point reach beyond points at
    /// most half a cell inside a boundary: where nodes may take a share of
    /// material they should not have (the ghost ties' search).
    pub fn reach_beyond_boundary(&self) -> f64 {
        match self {
            Basis::Linear | Basis::Gimp => 1.0,
            Basis::BSpline2 | Basis::BSpline3 => self.half_support() + 0.5,
        }
    }

    /// The lowest and highest cell `(i, j)` that a point at `x` with domain
    /// `support` reaches (its own cell for the linear basis).
    pub fn cell_range<const D: usize>(
        &self,
        grid: &Grid<D>,
        x: [f64; D],
        support: Support<D>,
    ) -> ([i64; D], [i64; D]) {
        // The functions' reach past the domain: none for the hat and GIMP,
        // whose functions are cell-wise; the B-splines' half-support.
        let beyond = if self.degree() == 1 {
            0.0
        } else {
            self.half_support() * grid.h
        };
        let (lo, hi) = match (self, support) {
            (Basis::Linear, _) => (x, x),
            (_, Support::Rectangle(half_width)) => {
                let l = half_width.map(|l| l.min(self.widest(grid.h)));
                (
                    std::array::from_fn(|d| x[d] - l[d]),
                    std::array::from_fn(|d| x[d] + l[d]),
                )
            }
            (_, Support::Quadrilateral(corners)) => {
                let (lo, hi) = quadrilateral_domain::bounds(&placed(
                    in_plane(x),
                    corners,
                    self.widest(grid.h),
                ));
                (from_plane(lo), from_plane(hi))
            }
        };
        (
            grid.cell_of(lo.map(|v| v - beyond)),
            grid.cell_of(hi.map(|v| v + beyond)),
        )
    }

    /// The 1D moments of the functions over a point's domain
    /// `[x - lp, x + lp]` (`x` measured from the origin, `lp` capped as
    /// [`Basis::eval`] caps it), per node `(i, [a, b, c, d])`:
    /// - `a = (1/2l) int N` and `b = (1/2l) int N'`, the averaged value and
    ///   gradient [`Basis::eval`] gives;
    /// - `c = (3/2l^3) int (t - x) N` and `d = (3/2l^3) int (t - x) N'`, the
    ///   slopes across the domain of the value and of the gradient (a
    ///   linear field's `c` is its gradient, its `d` zero).
    ///
    /// The bilinear basis (no domain) gives the limit at the point: `c =
    /// N'`, `d = N'' = 0` inside a cell. These are what
    /// `assembly::lone_points` measures a point's bending with.
    pub fn moments_1d(&self, h: f64, x: f64, lp: f64) -> Vec<(i64, [f64; 4])> {
        let lp = lp.min(self.widest_domain(h));
        // The functions at a point: GIMP's are the hats.
        let at = |t: f64| match self {
            Basis::Gimp => Basis::Linear.eval_1d(h, t, 0.0),
            _ => self.eval_1d(h, t, 0.0),
        };
        if lp <= 1e-9 * h {
            return at(x)
                .as_slice()
                .iter()
                .map(|&(i, n, dn)| (i, [n, dn, dn, 0.0]))
                .collect();
        }
        let mut out: Vec<(i64, [f64; 4])> = self
            .eval_1d(h, x, lp)
            .as_slice()
            .iter()
            .map(|&(i, a, b)| (i, [a, b, 0.0, 0.0]))
            .collect();
        let mut add = |t: f64, weight: f64, slot: usize| {
            for &(i, n, _) in at(t).as_slice() {
                if let Some((_, m)) = out.iter_mut().find(|(j, _)| *j == i) {
                    m[slot] += weight * n;
                }
            }
        };
        // d by parts: (3/2l^2) [N(x + l) + N(x - l) - 2 a].
        let kd = 1.5 / (lp * lp);
        add(x - lp, kd, 3);
        add(x + lp, kd, 3);
        // c by 3-point Gauss on the pieces between half cells (both
        // families' knots), exact for (t - x) times a cubic.
        const GAUSS3: [(f64, f64); 3] = [
            (-0.774_596_669_241_483_4, 5.0 / 9.0),
            (0.0, 8.0 / 9.0),
            (0.774_596_669_241_483_4, 5.0 / 9.0),
        ];
        let kc = 1.5 / (lp * lp * lp);
        let (mut left, end) = (x - lp, x + lp);
        let mut knot = ((2.0 * left / h).floor() + 1.0) * h / 2.0;
        while left < end {
            let right = knot.min(end);
            let (mid, r) = ((left + right) / 2.0, (right - left) / 2.0);
            for (t, w) in GAUSS3 {
                let t = mid + r * t;
                add(t, kc * w * r * (t - x), 2);
            }
            left = right;
            knot += h / 2.0;
        }
        out.iter_mut().for_each(|(_, m)| m[3] -= 2.0 * kd * m[0]);
        out
    }

    /// 1D weights `(node index, S, dS/dx)` at coordinate `x` measured from
    /// the origin.
    pub(super) fn eval_1d(&self, h: f64, x: f64, lp: f64) -> Weights1d {
        let mut w = Weights1d::default();
        match self {
            Basis::Linear => hat::linear_1d(h, x, &mut w),
            Basis::Gimp => hat::gimp_1d(h, x, lp, &mut w),
            Basis::BSpline2 | Basis::BSpline3 => {
                bspline::bspline_1d(self.degree(), h, x, lp, &mut w)
            }
        }
        w
    }
}

/// Whether a node's averaged function, of value `n` and gradient `dn_h`
/// (times the cell size), reaches a point at `x_h` cells from the origin
/// whose domain is `width_h` cells wide: more than round-off. A domain
/// that ends on a grid line reaches the nodes beyond it by a rounding of
/// its edge, about `eps x_h` cells, which makes the hat's averaged
/// gradient `eps x_h / width_h`: a node with no stiffness that no support
/// holds and no ghost face ties, which left the step's tangent singular (a
/// beam clamped by grid nodes at x = 0, its points' domains ending there,
/// failed at load factor 0 at any load). The B-splines' functions start
/// at their knots as a square or a cube, so the rounding leaves them
/// nothing above the floor.
fn reaches(n: f64, dn_h: f64, x_h: f64, width_h: f64) -> bool {
    let floor = ROUND_OFF.max(64.0 * f64::EPSILON * (x_h.abs() + 1.0) / width_h);
    n > floor || dn_h.abs() > floor
}

/// What [`reaches`] takes for round-off in a value of order one.
const ROUND_OFF: f64 = 1e-13;

/// A fixed-capacity list, so shape-function evaluation never allocates.
mod smallvec1d {
    #[derive(Default)]
    pub struct Small {
        items: [(i64, f64, f64); 8],
        len: usize,
    }
    impl Small {
        pub fn push(&mut self, item: (i64, f64, f64)) {
            self.items[self.len] = item;
            self.len += 1;
        }
        pub fn as_slice(&self) -> &[(i64, f64, f64)] {
            &self.items[..self.len]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const GRID: Grid = Grid {
        h: 0.7,
        origin: [-0.3, 1.1],
    };

    fn sums(basis: Basis, x: [f64; 2], lp: [f64; 2]) -> (f64, [f64; 2]) {
        let mut w = Vec::new();
        basis.eval(&GRID, x, Support::Rectangle(lp), &mut w);
        let n: f64 = w.iter().map(|w| w.n).sum();
        let g = w
            .iter()
            .fold([0.0, 0.0], |a, w| [a[0] + w.grad[0], a[1] + w.grad[1]]);
        (n, g)
    }

    proptest! {
        // Partition of unity (sum N = 1) and its derivative (sum grad N = 0)
        // hold exactly on an unbounded lattice, so only rounding is allowed.
        #[test]
        fn linear_is_a_partition_of_unity(x in -5.0..5.0f64, y in -5.0..5.0f64) {
            let (n, g) = sums(Basis::Linear, [x, y], [0.0, 0.0]);
            prop_assert!((n - 1.0).abs() < 1e-12);
            prop_assert!(g[0].abs() < 1e-12 && g[1].abs() < 1e-12);
        }

        #[test]
        fn gimp_is_a_partition_of_unity(x in -5.0..5.0f64, y in -5.0..5.0f64,
                                        lx in 0.01..0.7f64, ly in 0.01..0.7f64) {
            let (n, g) = sums(Basis::Gimp, [x, y], [lx, ly]);
            prop_assert!((n - 1.0).abs() < 1e-12);
            prop_assert!(g[0].abs() < 1e-11 && g[1].abs() < 1e-11);
        }

        // The gradient is the derivative of the value: compare with central
        // differences (the functions are C1 for GIMP, piecewise linear for
        // the hat; step and tolerance chosen for that).
        #[test]
        fn gimp_gradient_matches_finite_difference(x in -5.0..5.0f64, y in -5.0..5.0f64,
                                                   lx in 0.05..0.35f64) {
            let eps = 1e-6;
            let value = |p: [f64; 2], key: NodeKey| {
                let mut w = Vec::new();
                Basis::Gimp.eval(&GRID, p, Support::Rectangle([lx, lx]), &mut w);
                w.iter().find(|w| w.node == key).map_or(0.0, |w| w.n)
            };
            let mut w = Vec::new();
            Basis::Gimp.eval(&GRID, [x, y], Support::Rectangle([lx, lx]), &mut w);
            for nw in w {
                let fd = (value([x + eps, y], nw.node) - value([x - eps, y], nw.node)) / (2.0 * eps);
                prop_assert!((fd - nw.grad[0]).abs() < 1e-5, "{} vs {}", fd, nw.grad[0]);
            }
        }
    }

    /// A point's cell much wider than the grid's (one point filling a big
    /// turned body on a fine grid) is shrunk about the point to a cell
    /// either way, as a rectangle's half-widths are, so it reaches a few
    /// nodes, not millions; a cell crushed flat falls back to the hats.
    #[test]
    fn a_huge_or_flat_quadrilateral_domain_reaches_a_few_nodes() {
        let huge = Support::Quadrilateral([[-5e4, -3e4], [4e4, -5e4], [5e4, 3e4], [-4e4, 5e4]]);
        let mut w = Vec::new();
        Basis::Gimp.eval(&GRID, [0.3, 1.7], huge, &mut w);
        assert!(w.len() <= 16, "{}", w.len());
        assert!((w.iter().map(|w| w.n).sum::<f64>() - 1.0).abs() < 1e-12);
        let (lo, hi) = Basis::Gimp.cell_range(&GRID, [0.3, 1.7], huge);
        assert!(hi[0] - lo[0] <= 2 && hi[1] - lo[1] <= 2, "{lo:?} {hi:?}");
        let flat = Support::Quadrilateral([[-0.1, 0.0], [0.0, 0.0], [0.1, 0.0], [0.0, 0.0]]);
        w.clear();
        Basis::Gimp.eval(&GRID, [0.3, 1.7], flat, &mut w);
        assert_eq!(w.len(), 4);
        assert!(
            w.iter()
                .all(|w| w.n.is_finite() && w.grad.iter().all(|g| g.is_finite()))
        );
    }

    proptest! {
        // B-splines at a point and averaged over a domain of half-widths
        // `l`: partition of unity, gradients summing to zero, and the
        // reproduction of x (nodal values x_i) and of x^2 (coefficients
        // x_i^2 - c h^2, c = 1/4 quadratic and 1/3 cubic, whose mean over
        // the domain is x^2 + l^2/3), value and gradient, anywhere on an
        // unbounded grid.
        #[test]
        fn bsplines_reproduce_linear_and_quadratic_fields(x in -5.0..5.0f64, y in -5.0..5.0f64,
                                                          lx in 0.0..0.35f64, ly in 0.0..0.35f64,
                                                          at_point in proptest::bool::ANY,
                                                          cubic in proptest::bool::ANY) {
            let (basis, c) = if cubic { (Basis::BSpline3, 1.0 / 3.0) } else { (Basis::BSpline2, 0.25) };
            let l = if at_point { [0.0, 0.0] } else { [lx, ly] };
            let mut w = Vec::new();
            basis.eval(&GRID, [x, y], Support::Rectangle(l), &mut w);
            let per_direction = basis.degree() + if at_point { 1 } else { 2 };
            prop_assert!(w.len() <= per_direction * per_direction);
            let (mut n, mut g, mut lin, mut dlin, mut quad, mut dquad) = (0.0, [0.0; 2], [0.0; 2], [[0.0; 2]; 2], 0.0, [0.0; 2]);
            for nw in &w {
                let p = GRID.node_position(nw.node);
                let q = p[0] * p[0] - c * GRID.h * GRID.h;
                n += nw.n;
                quad += nw.n * q;
                for d in 0..2 {
                    g[d] += nw.grad[d];
                    lin[d] += nw.n * p[d];
                    dquad[d] += nw.grad[d] * q;
                    for e in 0..2 {
                        dlin[d][e] += p[d] * nw.grad[e];
                    }
                }
            }
            // An averaged gradient is a difference across the domain,
            // `(f(d + l) - f(d - l)) / 2l`, which rounds to about eps / l a
            // node: summed over up to 16 nodes at up to 6 cells, 100 eps / l
            // (1e-9 at l = 1.5e-5 cells, where a fixed 1e-11 failed); 600
            // eps / l against the quadratic's coefficients, up to 36.
            let narrowest = l.iter().copied().filter(|&l| l > 0.0).fold(f64::INFINITY, f64::min);
            let round_off = if narrowest.is_finite() { f64::EPSILON / narrowest } else { 0.0 };
            let (tol, quad_tol) = (1e-11 + 100.0 * round_off, 1e-10 + 600.0 * round_off);
            prop_assert!((n - 1.0).abs() < 1e-12);
            prop_assert!(g[0].abs() < tol && g[1].abs() < tol);
            prop_assert!((lin[0] - x).abs() < 1e-11 && (lin[1] - y).abs() < 1e-11);
            prop_assert!((dlin[0][0] - 1.0).abs() < tol && dlin[0][1].abs() < tol);
            prop_assert!(dlin[1][0].abs() < tol && (dlin[1][1] - 1.0).abs() < tol, "{:?}", dlin);
            let mean = x * x + l[0] * l[0] / 3.0;
            prop_assert!((quad - mean).abs() < 1e-10, "{} vs {}", quad, mean);
            prop_assert!((dquad[0] - 2.0 * x).abs() < quad_tol && dquad[1].abs() < quad_tol);
        }

        #[test]
        fn bspline_gradients_match_finite_differences(x in -5.0..5.0f64, y in -5.0..5.0f64,
                                                      l in 0.0..0.35f64, cubic in proptest::bool::ANY) {
            let basis = if cubic { Basis::BSpline3 } else { Basis::BSpline2 };
            let support = Support::Rectangle([l, 0.6 * l]);
            let eps = 1e-6;
            let value = |p: [f64; 2], key: NodeKey| {
                let mut w = Vec::new();
                basis.eval(&GRID, p, support, &mut w);
                w.iter().find(|w| w.node == key).map_or(0.0, |w| w.n)
            };
            let mut w = Vec::new();
            basis.eval(&GRID, [x, y], support, &mut w);
            for nw in w {
                let fx = (value([x + eps, y], nw.node) - value([x - eps, y], nw.node)) / (2.0 * eps);
                let fy = (value([x, y + eps], nw.node) - value([x, y - eps], nw.node)) / (2.0 * eps);
                prop_assert!((fx - nw.grad[0]).abs() < 1e-5 && (fy - nw.grad[1]).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn gimp_reduces_to_the_hat_far_from_kinks() {
        // With the point domain inside one cell and away from nodes, GIMP is
        // the hat function (Bardenhagen & Kober 2004, eq. for lp <= |d| <= h - lp).
        let mut w = Vec::new();
        Basis::Gimp.eval(
            &GRID,
            [GRID.origin[0] + 0.35, GRID.origin[1] + 0.35],
            Support::Rectangle([0.1, 0.1]),
            &mut w,
        );
        assert_eq!(w.len(), 4);
        for nw in w {
            assert!((nw.n - 0.25).abs() < 1e-14);
        }
    }

    proptest! {
        // The moments of every basis over any domain: the averages are
        // `eval`'s, and on the fields the basis reproduces they are the
        // field's: a constant has no slopes; `x` (nodal values `x_i`)
        // has `c = 1`, `d = 0`; on the B-splines `x^2` (coefficients
        // `x_i^2 - k h^2`) has `c = 2 x` and `d = 2`, which the exact
        // integrals give: `(3/2l^3) int (t - x) t^2 dt = 2 x`.
        #[test]
        fn moments_are_the_slopes_of_reproduced_fields(x in -5.0..5.0f64, l in 0.0..0.8f64,
                                                      which in 0usize..4) {
            let basis = [Basis::Linear, Basis::Gimp, Basis::BSpline2, Basis::BSpline3][which];
            let h = GRID.h;
            let moments = basis.moments_1d(h, x, l * h);
            let lp = match basis { Basis::Linear => 0.0, Basis::Gimp => l * h, _ => (l * h).min(h / 2.0) };
            let averaged = if lp > 0.0 { basis.eval_1d(h, x, lp) } else { Basis::Linear.eval_1d(h, x, 0.0) };
            let averaged = if basis.degree() > 1 && lp == 0.0 { basis.eval_1d(h, x, 0.0) } else { averaged };
            prop_assert_eq!(moments.len(), averaged.as_slice().len());
            for (&(i, m), &(j, a, b)) in moments.iter().zip(averaged.as_slice()) {
                prop_assert!(i == j && m[0] == a && m[1] == b);
            }
            let sum = |f: &dyn Fn(f64) -> f64, k: usize| -> f64 {
                moments.iter().map(|&(i, m)| m[k] * f(i as f64 * h)).sum()
            };
            // d divides a difference of averages, each rounded to about
            // eps h / l, by l^2; c's pieces end at knots rounded to eps x,
            // against its factor 1 / l^3.
            let narrow = (h / lp).powi(2).min(1e300);
            let (tol_c, tol_d) = (1e-11 + 1e-13 * narrow, 1e-11 + 10.0 * f64::EPSILON * h / lp.powi(3).max(1e-300));
            prop_assert!(sum(&|_| 1.0, 2).abs() < tol_c && sum(&|_| 1.0, 3).abs() < tol_d, "{:?}", moments);
            prop_assert!((sum(&|t| t, 2) - 1.0).abs() < tol_c, "{}", sum(&|t| t, 2));
            prop_assert!(sum(&|t| t, 3).abs() < 10.0 * tol_d, "{}", sum(&|t| t, 3));
            if basis.degree() > 1 {
                let k = if basis.degree() == 2 { 0.25 } else { 1.0 / 3.0 };
                let q = |t: f64| t * t - k * h * h;
                if lp > 0.0 {
                    prop_assert!((sum(&q, 2) - 2.0 * x).abs() < 1e-9, "{}", sum(&q, 2));
                    prop_assert!((sum(&q, 3) - 2.0).abs() < 100.0 * tol_d, "{}", sum(&q, 3));
                }
            }
        }
    }

    proptest! {
        // In 3D every basis, at a point or averaged over a box, is a
        // partition of unity and reproduces linear fields, value and
        // gradient (`sum N x_i = x`, `sum x_i (x) grad N = I`): the patch
        // test's homogeneous deformation, to round-off, on a grid through
        // the origin and on one offset in every axis.
        #[test]
        fn every_basis_in_three_dimensions_reproduces_linear_fields(
            x in proptest::array::uniform3(-5.0..5.0f64),
            l in proptest::array::uniform3(0.0..0.7f64),
            which in 0usize..4, offset in proptest::bool::ANY,
        ) {
            let basis = [Basis::Linear, Basis::Gimp, Basis::BSpline2, Basis::BSpline3][which];
            let grid = Grid { h: 0.7, origin: if offset { [-0.3, 1.1, 0.45] } else { [0.0; 3] } };
            let mut w = Vec::new();
            basis.eval(&grid, x, Support::Rectangle(l), &mut w);
            let per_axis = basis.degree() + 3;
            prop_assert!(!w.is_empty() && w.len() <= per_axis.pow(3));
            let (mut n, mut g, mut lin, mut dlin) = (0.0, [0.0; 3], [0.0; 3], [[0.0; 3]; 3]);
            for nw in &w {
                let p = grid.node_position(nw.node);
                n += nw.n;
                for d in 0..3 {
                    g[d] += nw.grad[d];
                    lin[d] += nw.n * p[d];
                    for e in 0..3 {
                        dlin[d][e] += p[d] * nw.grad[e];
                    }
                }
            }
            // As in 2D: an averaged gradient rounds to about eps / l a node.
            let narrowest = l.iter().map(|&l| l.min(basis.widest_domain(grid.h)))
                .filter(|&l| l > 0.0).fold(f64::INFINITY, f64::min);
            let round_off = if narrowest.is_finite() { f64::EPSILON / narrowest } else { 0.0 };
            let tol = 1e-11 + 500.0 * round_off;
            prop_assert!((n - 1.0).abs() < 1e-12, "{}", n);
            for d in 0..3 {
                prop_assert!(g[d].abs() < tol, "{:?}", g);
                prop_assert!((lin[d] - x[d]).abs() < 1e-11, "{:?} {:?}", lin, x);
                for e in 0..3 {
                    let identity = if d == e { 1.0 } else { 0.0 };
                    prop_assert!((dlin[d][e] - identity).abs() < tol, "{:?}", dlin);
                }
            }
        }

        // A 3D function is the 2D one times the third axis's 1D function:
        // what makes a one-cell slab a plane-strain body. Exactly, for the
        // product is taken in the same order.
        #[test]
        fn a_three_dimensional_function_is_the_planar_one_times_the_third_axis(
            x in proptest::array::uniform3(-5.0..5.0f64),
            l in proptest::array::uniform3(0.0..0.7f64),
            which in 0usize..4,
        ) {
            let basis = [Basis::Linear, Basis::Gimp, Basis::BSpline2, Basis::BSpline3][which];
            let grid = Grid { h: 0.7, origin: [-0.3, 1.1, 0.45] };
            let (mut planar, mut solid) = (Vec::new(), Vec::new());
            basis.eval(&GRID, [x[0], x[1]], Support::Rectangle([l[0], l[1]]), &mut planar);
            basis.eval(&grid, x, Support::Rectangle(l), &mut solid);
            let lz = if basis == Basis::Linear { 0.0 } else { l[2].min(basis.widest_domain(grid.h)) };
            let along_z = basis.eval_1d(grid.h, x[2] - grid.origin[2], lz);
            let expected: Vec<NodeWeight<3>> = along_z
                .as_slice()
                .iter()
                .flat_map(|&(k, sz, dsz)| planar.iter().map(move |p| {
                    let [i, j] = crate::grid::lattice_coordinates::<2>(p.node);
                    NodeWeight {
                        node: crate::grid::lattice_key([i, j, k]),
                        n: p.n * sz,
                        grad: [p.grad[0] * sz, p.grad[1] * sz, p.n * dsz],
                    }
                }))
                .filter(|w| w.n != 0.0 || w.grad != [0.0; 3])
                .collect();
            prop_assert_eq!(solid, expected);
        }
    }

    /// A domain that ends on a grid line reaches no node beyond it, however
    /// its edge rounds: points of width `h` seeded from a clamped end at a
    /// grid line, on a cell size with no short binary form (a random case
    /// that failed at load factor 0 on a node of gradient 1e-16).
    #[test]
    fn a_domain_ending_on_a_grid_line_reaches_no_node_beyond() {
        let h = 0.105_957_455_315_182_69;
        let mut beyond = 0;
        // At the origin and a million cells from it (site coordinates).
        for edge in [0_i64, 1_000_000] {
            for k in 1..2000 {
                let width = h * (0.5 + k as f64 / 4000.0);
                let x = edge as f64 * h + width / 2.0;
                for basis in [Basis::Gimp, Basis::BSpline3] {
                    let w = basis.eval_1d(h, x, width / 2.0);
                    let reach = edge + if basis == Basis::Gimp { -1 } else { -2 };
                    beyond += w.as_slice().iter().filter(|(i, ..)| *i <= reach).count();
                }
            }
        }
        assert_eq!(beyond, 0);
    }
}
