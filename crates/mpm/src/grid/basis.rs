//! Shape functions of the background grid, tensor products of 1D functions:
//! - `Linear`: the bilinear finite-element hat `max(0, 1 - |d|/h)`.
//! - `Gimp`: the hat convolved with the point's characteristic function of
//!   half-width `lp` (generalised interpolation MPM). The convolution is
//!   written with the hat's antiderivative `H`, `S(d) = (H(d+lp) - H(d-lp)) /
//!   2lp`, which is valid for any `lp` (not only `lp <= h/2`). A point
//!   whose cell is not an axis-aligned rectangle has its hats averaged over
//!   that cell instead ([`super::quadrilateral_domain`]).

use super::{Grid, NodeKey, node_key, quadrilateral_domain};

/// One node's contribution at a point: `N` and its gradient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeWeight {
    pub node: NodeKey,
    pub n: f64,
    pub grad: [f64; 2],
}

/// Up to four 1D weights per direction (GIMP with `lp <= h`).
type Weights1d = smallvec1d::Small;

/// A point's domain for GIMP, about the point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Support {
    /// An axis-aligned rectangle of these half-widths.
    Rectangle([f64; 2]),
    /// A convex quadrilateral: its corners relative to the point, in order
    /// round it.
    Quadrilateral([[f64; 2]; 4]),
}

/// A quadrilateral domain's corners about `x`, shrunk about it to reach at
/// most a cell in x and in y, as a rectangle's half-widths are capped: a
/// wider domain reaches nodes the point does not need, and a huge one (a
/// body of one point on a fine grid) would list cells without bound.
fn placed(grid: &Grid, x: [f64; 2], corners: [[f64; 2]; 4]) -> [[f64; 2]; 4] {
    let reach = corners
        .iter()
        .map(|c| c[0].abs().max(c[1].abs()))
        .fold(0.0, f64::max);
    let k = if reach > grid.h { grid.h / reach } else { 1.0 };
    corners.map(|c| [x[0] + k * c[0], x[1] + k * c[1]])
}

/// The shape functions of a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Basis {
    Linear,
    Gimp,
}

impl Basis {
    /// Appends to `out` every node whose shape function or gradient is
    /// non-zero at `x`, for a point of domain `support` (ignored by the
    /// linear basis).
    pub fn eval(&self, grid: &Grid, x: [f64; 2], support: Support, out: &mut Vec<NodeWeight>) {
        let half_width = match (self, support) {
            (Basis::Linear, _) => [0.0, 0.0],
            (Basis::Gimp, Support::Rectangle(half_width)) => half_width,
            (Basis::Gimp, Support::Quadrilateral(corners)) => {
                let corners = placed(grid, x, corners);
                if quadrilateral_domain::area(&corners).abs() <= 1e-12 * grid.h * grid.h {
                    // A cell crushed flat has no average: the hats at x.
                    return Basis::Linear.eval(grid, x, support, out);
                }
                return quadrilateral_domain::eval(grid, &corners, out);
            }
        };
        let wx = self.eval_1d(grid.h, x[0] - grid.origin[0], half_width[0]);
        let wy = self.eval_1d(grid.h, x[1] - grid.origin[1], half_width[1]);
        for &(j, sy, dsy) in wy.as_slice() {
            for &(i, sx, dsx) in wx.as_slice() {
                let w = NodeWeight {
                    node: node_key(i, j),
                    n: sx * sy,
                    grad: [dsx * sy, sx * dsy],
                };
                if w.n != 0.0 || w.grad != [0.0, 0.0] {
                    out.push(w);
                }
            }
        }
    }

    /// The lowest and highest cell `(i, j)` that a point at `x` with domain
    /// `support` reaches (its own cell for the linear basis).
    pub fn cell_range(&self, grid: &Grid, x: [f64; 2], support: Support) -> ([i64; 2], [i64; 2]) {
        let lp = match (self, support) {
            (Basis::Linear, _) => [0.0, 0.0],
            // As `eval_1d`, which caps the domain at a cell.
            (Basis::Gimp, Support::Rectangle(half_width)) => half_width.map(|l| l.min(grid.h)),
            (Basis::Gimp, Support::Quadrilateral(corners)) => {
                return quadrilateral_domain::cell_range(grid, &placed(grid, x, corners));
            }
        };
        (
            grid.cell_of([x[0] - lp[0], x[1] - lp[1]]),
            grid.cell_of([x[0] + lp[0], x[1] + lp[1]]),
        )
    }

    /// 1D weights `(node index, S, dS/dx)` at coordinate `x` measured from
    /// the origin.
    fn eval_1d(&self, h: f64, x: f64, lp: f64) -> Weights1d {
        let mut w = Weights1d::default();
        match self {
            Basis::Linear => {
                let c = (x / h).floor();
                let xi = x / h - c;
                let c = c as i64;
                w.push((c, 1.0 - xi, -1.0 / h));
                w.push((c + 1, xi, 1.0 / h));
            }
            Basis::Gimp => {
                let lp = lp.min(h); // a wider domain would need more than four nodes
                let first = ((x - lp - h) / h).ceil() as i64;
                let last = ((x + lp + h) / h).floor() as i64;
                for i in first..=last {
                    let d = x - h * i as f64;
                    let s = (hat_integral(d + lp, h) - hat_integral(d - lp, h)) / (2.0 * lp);
                    let ds = (hat(d + lp, h) - hat(d - lp, h)) / (2.0 * lp);
                    if s > 0.0 || ds != 0.0 {
                        w.push((i, s.max(0.0), ds));
                    }
                }
            }
        }
        w
    }
}

fn hat(s: f64, h: f64) -> f64 {
    (1.0 - s.abs() / h).max(0.0)
}

/// `H(s) = integral of hat from 0 to s`.
fn hat_integral(s: f64, h: f64) -> f64 {
    let a = s.abs().min(h);
    s.signum() * (a - a * a / (2.0 * h))
}

/// A fixed-capacity list, so shape-function evaluation never allocates.
mod smallvec1d {
    #[derive(Default)]
    pub struct Small {
        items: [(i64, f64, f64); 5],
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
        assert!(w.iter().all(|w| w.n.is_finite()));
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
}
