//! The bilinear finite-element hat `max(0, 1 - |d|/h)` and GIMP, the hat
//! convolved with the point's characteristic function of half-width `lp`
//! (generalised interpolation MPM). The convolution is written with the
//! hat's antiderivative `H`, `S(d) = (H(d+lp) - H(d-lp)) / 2lp`, which is
//! valid for any `lp` (not only `lp <= h/2`). A point whose cell is not an
//! axis-aligned rectangle has its hats averaged over that cell instead
//! ([`super::quadrilateral_domain`]).

use super::Weights1d;

/// The hats' 1D weights `(node index, S, dS/dx)` at coordinate `x` from
/// the origin.
pub(super) fn linear_1d(h: f64, x: f64, w: &mut Weights1d) {
    let c = (x / h).floor();
    let xi = x / h - c;
    let c = c as i64;
    w.push((c, 1.0 - xi, -1.0 / h));
    w.push((c + 1, xi, 1.0 / h));
}

/// GIMP's 1D weights at `x`, for a domain of half-width `lp`.
pub(super) fn gimp_1d(h: f64, x: f64, lp: f64, w: &mut Weights1d) {
    if lp <= 1e-12 * h {
        // No domain (a cell crushed flat): the hats at the point, where
        // the average's 0 / 0 is not a number.
        return linear_1d(h, x, w);
    }
    let lp = lp.min(h); // a wider domain would need more than four nodes
    let first = ((x - lp - h) / h).ceil() as i64;
    let last = ((x + lp + h) / h).floor() as i64;
    for i in first..=last {
        let d = x - h * i as f64;
        let s = (hat_integral(d + lp, h) - hat_integral(d - lp, h)) / (2.0 * lp);
        let ds = (hat(d + lp, h) - hat(d - lp, h)) / (2.0 * lp);
        if super::reaches(s, ds * h, x / h, 2.0 * lp / h) {
            w.push((i, s.max(0.0), ds));
        }
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
