//! The uniform quadratic and cubic B-splines centred on the nodes (C1 and
//! C2; 3 and 4 nodes per direction at a point; Steffen, Kirby & Berzins
//! 2008), averaged over the point's domain as GIMP averages the hat: up to
//! 4 and 5 nodes per direction. The nodal values are the field's B-spline
//! coefficients: linear fields are reproduced with the nodes' own values,
//! `x^2` with `x_i^2 - h^2/4` (quadratic) or `x_i^2 - h^2/3` (cubic).
//! Evaluated at a point (a zero domain), as the boundary's quadrature
//! does, they are the B-splines themselves. The average, not the value at
//! the point, is what converges: at the point, a body whose edge cuts the
//! functions' supports leaves an error of a few 1e-3 that no refinement
//! removes (the column, docs/bsplines.md). A point whose cell is not an
//! axis-aligned rectangle has them averaged over that cell
//! ([`super::quadrilateral_domain`]).

use super::Weights1d;

/// The 1D weights `(node index, S, dS/dx)` of the B-splines of `degree`
/// (2 or 3) at coordinate `x` from the origin, averaged over a domain of
/// half-width `lp`.
pub(super) fn bspline_1d(degree: usize, h: f64, x: f64, lp: f64, w: &mut Weights1d) {
    let f = if degree == 2 {
        quadratic_bspline
    } else {
        cubic_bspline
    };
    // The half-support in cells, as `Basis::half_support`.
    let reach = (degree as f64 + 1.0) / 2.0;
    let xi = x / h;
    let l = lp / h; // the domain's half-width in cells (0: at the point)
    let first = (xi - l - reach).ceil() as i64;
    let last = (xi + l + reach).floor() as i64;
    for i in first..=last {
        let d = xi - i as f64;
        let (n, dn) = if l > 0.0 {
            // The mean over [d - l, d + l]; its derivative as the
            // domain moves is the difference of the ends.
            (
                mean(&|t| f(t).0, d - l, d + l),
                (f(d + l).0 - f(d - l).0) / (2.0 * l),
            )
        } else {
            f(d)
        };
        if super::reaches(n, dn, xi, (2.0 * l).max(1.0)) {
            w.push((i, n.max(0.0), dn / h));
        }
    }
}

/// The mean of `g`, a polynomial between multiples of one half (the knots
/// of both B-splines, in cells from their node), over `[a, b]`: 3-point
/// Gauss on each piece, exact to degree 5.
fn mean(g: &dyn Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    const GAUSS3: [(f64, f64); 3] = [
        (-0.774_596_669_241_483_4, 5.0 / 9.0),
        (0.0, 8.0 / 9.0),
        (0.774_596_669_241_483_4, 5.0 / 9.0),
    ];
    let mut total = 0.0;
    let mut left = a;
    let mut knot = (2.0 * a).floor() / 2.0 + 0.5;
    while left < b {
        let right = knot.min(b);
        let (c, r) = ((left + right) / 2.0, (right - left) / 2.0);
        total += GAUSS3
            .iter()
            .map(|&(t, wt)| wt * r * g(c + r * t))
            .sum::<f64>();
        left = right;
        knot += 0.5;
    }
    total / (b - a)
}

/// The quadratic B-spline centred at 0 on unit knots, and its derivative:
/// `3/4 - d^2` for `|d| <= 1/2`, `(3/2 - |d|)^2 / 2` out to `3/2`.
fn quadratic_bspline(d: f64) -> (f64, f64) {
    let a = d.abs();
    if a <= 0.5 {
        (0.75 - d * d, -2.0 * d)
    } else if a < 1.5 {
        let r = 1.5 - a;
        (0.5 * r * r, -r * d.signum())
    } else {
        (0.0, 0.0)
    }
}

/// The cubic B-spline centred at 0 on unit knots, and its derivative:
/// `2/3 - d^2 + |d|^3 / 2` for `|d| <= 1`, `(2 - |d|)^3 / 6` out to 2.
fn cubic_bspline(d: f64) -> (f64, f64) {
    let a = d.abs();
    if a <= 1.0 {
        (2.0 / 3.0 - d * d + 0.5 * a * a * a, -2.0 * d + 1.5 * d * a)
    } else if a < 2.0 {
        let r = 2.0 - a;
        (r * r * r / 6.0, -0.5 * r * r * d.signum())
    } else {
        (0.0, 0.0)
    }
}
