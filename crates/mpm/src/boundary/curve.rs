//! Local cubic B-spline interpolation of a closed loop of boundary points
//! (Piegl & Tiller, The NURBS Book, 2nd ed., section 9.3.4).
//!
//! 1. A unit tangent at every data point from the five-point formula
//!    (eq. 9.29-9.31): with chords `q_k = Q_k - Q_(k-1)`,
//!    `alpha_k = |q_(k-1) x q_k| / (|q_(k-1) x q_k| + |q_(k+1) x q_(k+2)|)`
//!    (with `|.|` smoothed for nearly parallel chords, see
//!    [`smooth_abs_cross`]) and `T_k ~ (1 - alpha_k) q_k + alpha_k q_(k+1)`.
//!    A corner (see [`is_corner`]) keeps two tangents, the incoming and the
//!    outgoing chord, so the curve turns sharply there.
//! 2. Between neighbours a cubic Bezier segment `Q_k, Q_k + a/3 T_k,
//!    Q_(k+1) - a/3 T_(k+1), Q_(k+1)` whose length `a` makes the speed equal
//!    at the start, middle and end (eq. 9.33-9.34):
//!    `(16 - |T_k + T_(k+1)|^2) a^2 + 12 (Q_(k+1) - Q_k).(T_k + T_(k+1)) a
//!    - 36 |Q_(k+1) - Q_k|^2 = 0`, positive root.
//! 3. The segments joined into one cubic B-spline on the parameters
//!    `u_0 = 0, u_(k+1) = u_k + a_k`: interior knots double (C1) at smooth
//!    data points, triple (C0) at corners.
//!
//! The curve is evaluated segment by segment; `u` runs over `[0, length)`
//! where `length = sum a_k` (close to the arc length).

use serde::Serialize;

pub type Point = [f64; 2];

/// A closed cubic curve through a loop of points.
#[derive(Debug, Clone, PartialEq)]
pub struct ClosedCurve {
    /// Bezier control points of segment k: from data point k to k+1.
    segments: Vec<[Point; 4]>,
    /// Parameter at each data point; `params[n]` closes the loop.
    params: Vec<f64>,
    /// Whether each data point is a corner.
    corners: Vec<bool>,
}

/// The B-spline form served to users: degree, knots, control points.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct BSplineData {
    pub degree: usize,
    pub knots: Vec<f64>,
    pub control_points: Vec<Point>,
}

fn sub(a: Point, b: Point) -> Point {
    [a[0] - b[0], a[1] - b[1]]
}
fn add(a: Point, b: Point) -> Point {
    [a[0] + b[0], a[1] + b[1]]
}
fn scale(a: Point, s: f64) -> Point {
    [a[0] * s, a[1] * s]
}
fn dot(a: Point, b: Point) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
fn cross(a: Point, b: Point) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}
fn norm(a: Point) -> f64 {
    dot(a, a).sqrt()
}
fn unit(a: Point) -> Point {
    scale(a, 1.0 / norm(a))
}

/// Turning angle (radians, unsigned) from chord `a` to chord `b`.
fn turn(a: Point, b: Point) -> f64 {
    cross(a, b).atan2(dot(a, b)).abs()
}

/// A data point is a corner when the loop turns there by at least 30
/// degrees and by more than twice as much as at one of its neighbours: on a
/// sampled smooth curve neighbouring turns are alike, at the corner of a
/// (deformed) polygon the side it comes from or goes to is nearly straight.
/// One straight side is enough: the two corners of a side only two points
/// long are neighbours, and each turns as much as the other. This extends
/// the book's rule (collinear chords on both sides) to deformed bodies.
pub fn is_corner(q_prev: Point, q_in: Point, q_out: Point, q_next: Point) -> bool {
    let here = turn(q_in, q_out);
    here >= 30f64.to_radians()
        && (here > 2.0 * turn(q_prev, q_in) || here > 2.0 * turn(q_out, q_next))
}

/// `|a x b|`, smoothed where the chords are nearly parallel:
/// `sqrt((a x b)^2 + (1e-3 |a| |b|)^2)`. On a straight run both crosses of
/// the five-point formula are round-off, and their ratio (the weight
/// `alpha`) would jump at random as the points move; Newton differentiates
/// the boundary loads through it, so it must be smooth. Chords that turn by
/// more than a few milliradians are unaffected.
fn smooth_abs_cross(a: Point, b: Point) -> f64 {
    let c = cross(a, b);
    let floor = 1e-3 * norm(a) * norm(b);
    (c * c + floor * floor).sqrt()
}

/// The tangents at a data point: equal unless it is a corner.
#[derive(Debug, Clone, Copy)]
pub struct DataTangent {
    incoming: Point,
    outgoing: Point,
    corner: bool,
}

/// Tangent(s) at data point `k` of a closed loop, from its five-point
/// stencil `Q_(k-2) .. Q_(k+2)`.
fn data_tangent(points: &[Point], k: usize) -> DataTangent {
    let n = points.len() as isize;
    let at = |i: isize| points[(k as isize + i).rem_euclid(n) as usize];
    // q(i) = Q_(k+i) - Q_(k+i-1)
    let q = |i: isize| sub(at(i), at(i - 1));
    if is_corner(q(-1), q(0), q(1), q(2)) {
        return DataTangent {
            incoming: unit(q(0)),
            outgoing: unit(q(1)),
            corner: true,
        };
    }
    let c1 = smooth_abs_cross(q(-1), q(0));
    let c2 = smooth_abs_cross(q(1), q(2));
    let alpha = if c1 + c2 > 0.0 { c1 / (c1 + c2) } else { 0.5 };
    let v = add(scale(q(0), 1.0 - alpha), scale(q(1), alpha));
    // Opposite chords (a spike) give v = 0: fall back to the chord.
    let t = if norm(v) > 0.0 { unit(v) } else { unit(q(1)) };
    DataTangent {
        incoming: t,
        outgoing: t,
        corner: false,
    }
}

/// The outward unit normals at each data point of a closed loop, before and
/// after it (they differ at corners). The material lies to the left.
pub fn data_normals(points: &[Point]) -> Vec<(Point, Point)> {
    (0..points.len())
        .map(|k| {
            let t = data_tangent(points, k);
            (
                [t.incoming[1], -t.incoming[0]],
                [t.outgoing[1], -t.outgoing[0]],
            )
        })
        .collect()
}

/// The equal-speed Bezier segment from data point `k` to `k + 1` and its
/// parameter length.
fn bezier_segment(
    points: &[Point],
    k: usize,
    start: &DataTangent,
    end: &DataTangent,
) -> ([Point; 4], f64) {
    let (p0, p3) = (points[k], points[(k + 1) % points.len()]);
    let (ts, te) = (start.outgoing, end.incoming);
    let chord = sub(p3, p0);
    let tsum = add(ts, te);
    let a = 16.0 - dot(tsum, tsum);
    let b = 12.0 * dot(chord, tsum);
    let c = -36.0 * dot(chord, chord);
    let length = (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
    (
        [
            p0,
            add(p0, scale(ts, length / 3.0)),
            sub(p3, scale(te, length / 3.0)),
            p3,
        ],
        length,
    )
}

/// Segment `k` of the curve through a closed loop, computed from the data
/// points around it only (the scheme is local: `Q_(k-2) .. Q_(k+3)`).
pub fn local_segment(points: &[Point], k: usize) -> [Point; 4] {
    let n = points.len();
    bezier_segment(
        points,
        k,
        &data_tangent(points, k),
        &data_tangent(points, (k + 1) % n),
    )
    .0
}

/// The tangents at every data point of a closed loop.
pub fn data_tangents(points: &[Point]) -> Vec<DataTangent> {
    (0..points.len()).map(|k| data_tangent(points, k)).collect()
}

/// A loop whose data point `k` has moved: its segments from the tangents
/// of the loop before the move (made once, for differencing the curve point
/// by point), of which only the five whose stencil holds `Q_k` are made
/// again. [`MovedPoint::segment`] is [`local_segment`] of the moved loop.
pub struct MovedPoint<'a> {
    points: &'a [Point],
    before: &'a [DataTangent],
    /// The tangents at `Q_(k-2) .. Q_(k+2)`, in that order.
    near: [DataTangent; 5],
    first_near: usize,
}

impl<'a> MovedPoint<'a> {
    /// `points` is the loop after the move, `before` [`data_tangents`] of
    /// the loop before it.
    pub fn new(points: &'a [Point], before: &'a [DataTangent], k: usize) -> Self {
        let n = points.len();
        let first_near = (k + 2 * n - 2) % n;
        Self {
            points,
            before,
            near: std::array::from_fn(|d| data_tangent(points, (first_near + d) % n)),
            first_near,
        }
    }

    fn tangent(&self, m: usize) -> &DataTangent {
        let n = self.points.len();
        match (m + n - self.first_near) % n {
            d if d < 5 => &self.near[d],
            _ => &self.before[m],
        }
    }

    /// Segment `j` of the curve through the moved loop.
    pub fn segment(&self, j: usize) -> [Point; 4] {
        let n = self.points.len();
        bezier_segment(self.points, j, self.tangent(j), self.tangent((j + 1) % n)).0
    }
}

impl ClosedCurve {
    /// Interpolates a closed loop (the first point is not repeated at the
    /// end). Consecutive duplicate points are not allowed.
    pub fn interpolate(points: &[Point]) -> Self {
        let n = points.len();
        assert!(n >= 3, "a closed loop needs at least 3 points");
        let tangents = data_tangents(points);
        let corners = tangents.iter().map(|t| t.corner).collect();
        let mut segments = Vec::with_capacity(n);
        let mut params = Vec::with_capacity(n + 1);
        params.push(0.0);
        for k in 0..n {
            let (segment, length) = bezier_segment(points, k, &tangents[k], &tangents[(k + 1) % n]);
            segments.push(segment);
            params.push(params[k] + length);
        }
        Self {
            segments,
            params,
            corners,
        }
    }

    pub fn n_segments(&self) -> usize {
        self.segments.len()
    }

    /// Parameter length of the whole loop.
    pub fn length_parameter(&self) -> f64 {
        *self.params.last().expect("non-empty")
    }

    /// The Bezier control points of segment `k` and its parameter interval.
    pub fn segment(&self, k: usize) -> ([Point; 4], f64, f64) {
        (self.segments[k], self.params[k], self.params[k + 1])
    }

    /// Segment and local parameter `t in [0, 1]` of global parameter `u`
    /// (taken modulo the loop's length).
    fn locate(&self, u: f64) -> (usize, f64) {
        let total = self.length_parameter();
        let u = u.rem_euclid(total);
        let k = match self.params.binary_search_by(|p| p.total_cmp(&u)) {
            Ok(k) => k.min(self.segments.len() - 1),
            Err(k) => k - 1,
        };
        (
            k,
            (u - self.params[k]) / (self.params[k + 1] - self.params[k]),
        )
    }

    /// Point at parameter `u`.
    pub fn point(&self, u: f64) -> Point {
        let (k, t) = self.locate(u);
        bezier(&self.segments[k], t)
    }

    /// `dC/du` at parameter `u` (at a corner: the outgoing side).
    pub fn derivative(&self, u: f64) -> Point {
        let (k, t) = self.locate(u);
        scale(
            bezier_derivative(&self.segments[k], t),
            1.0 / (self.params[k + 1] - self.params[k]),
        )
    }

    /// Outward unit normal at `u`: the material lies to the left of the
    /// direction of travel (outer loops counter-clockwise, holes clockwise),
    /// so the outward normal is the tangent turned clockwise.
    pub fn normal(&self, u: f64) -> Point {
        let d = unit(self.derivative(u));
        [d[1], -d[0]]
    }

    /// Arc length, by 8-point Gauss-Legendre quadrature on every segment.
    pub fn arc_length(&self) -> f64 {
        self.segments
            .iter()
            .map(|s| {
                GAUSS8
                    .iter()
                    .map(|&(x, w)| w * norm(bezier_derivative(s, x)))
                    .sum::<f64>()
            })
            .sum()
    }

    /// Closest point on the curve to `x`: `(parameter, point, distance)`.
    /// Each segment is sampled, then refined by Newton on
    /// `(C(t) - x) . C'(t) = 0`.
    pub fn closest_point(&self, x: Point) -> (f64, Point, f64) {
        let mut best = (0.0, self.segments[0][0], f64::INFINITY);
        for (k, s) in self.segments.iter().enumerate() {
            let mut t = (0..=8)
                .map(|i| i as f64 / 8.0)
                .min_by(|&a, &b| norm(sub(bezier(s, a), x)).total_cmp(&norm(sub(bezier(s, b), x))))
                .expect("samples");
            for _ in 0..20 {
                let d = sub(bezier(s, t), x);
                let d1 = bezier_derivative(s, t);
                let d2 = bezier_second_derivative(s, t);
                let g = dot(d, d1);
                let h = dot(d1, d1) + dot(d, d2);
                if h <= 0.0 {
                    break;
                }
                let next = (t - g / h).clamp(0.0, 1.0);
                let converged = (next - t).abs() < 1e-14;
                t = next;
                if converged {
                    break;
                }
            }
            let p = bezier(s, t);
            let dist = norm(sub(p, x));
            if dist < best.2 {
                best = (
                    self.params[k] + t * (self.params[k + 1] - self.params[k]),
                    p,
                    dist,
                );
            }
        }
        best
    }

    /// `count` points per segment (the data point first), for drawing.
    pub fn polyline(&self, per_segment: usize) -> Vec<Point> {
        let mut out = Vec::with_capacity(self.segments.len() * per_segment + 1);
        for s in &self.segments {
            for i in 0..per_segment {
                out.push(bezier(s, i as f64 / per_segment as f64));
            }
        }
        out.push(self.segments[0][0]);
        out
    }

    /// The B-spline form: degree 3, clamped at the first data point, each
    /// interior knot double where the curve is C1 and triple at corners.
    pub fn bspline(&self) -> BSplineData {
        let n = self.segments.len();
        let mut knots = vec![0.0; 4];
        let mut control_points = vec![self.segments[0][0]];
        for k in 0..n {
            let s = &self.segments[k];
            control_points.push(s[1]);
            control_points.push(s[2]);
            if k + 1 < n {
                let u = self.params[k + 1];
                knots.extend([u, u]);
                if self.corners[k + 1] {
                    knots.push(u);
                    control_points.push(s[3]);
                }
            }
        }
        control_points.push(self.segments[0][0]);
        knots.extend([self.length_parameter(); 4]);
        BSplineData {
            degree: 3,
            knots,
            control_points,
        }
    }
}

/// Point of a cubic Bezier segment at `t in [0, 1]`.
pub fn bezier(p: &[Point; 4], t: f64) -> Point {
    let s = 1.0 - t;
    let b = [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t];
    [
        b[0] * p[0][0] + b[1] * p[1][0] + b[2] * p[2][0] + b[3] * p[3][0],
        b[0] * p[0][1] + b[1] * p[1][1] + b[2] * p[2][1] + b[3] * p[3][1],
    ]
}

/// `dC/dt` of a cubic Bezier segment.
pub fn bezier_derivative(p: &[Point; 4], t: f64) -> Point {
    let s = 1.0 - t;
    let d = [sub(p[1], p[0]), sub(p[2], p[1]), sub(p[3], p[2])];
    let b = [3.0 * s * s, 6.0 * s * t, 3.0 * t * t];
    [
        b[0] * d[0][0] + b[1] * d[1][0] + b[2] * d[2][0],
        b[0] * d[0][1] + b[1] * d[1][1] + b[2] * d[2][1],
    ]
}

fn bezier_second_derivative(p: &[Point; 4], t: f64) -> Point {
    let a = add(sub(p[2], scale(p[1], 2.0)), p[0]);
    let b = add(sub(p[3], scale(p[2], 2.0)), p[1]);
    add(scale(a, 6.0 * (1.0 - t)), scale(b, 6.0 * t))
}

/// Gauss-Legendre nodes on [0, 1] and weights (summing to 1), 8 points
/// (the tabulated 18-digit values, rounded to f64 by the compiler).
#[allow(clippy::excessive_precision)]
pub const GAUSS8: [(f64, f64); 8] = [
    (0.019855071751231856, 0.050614268145188129),
    (0.101666761293186630, 0.111190517226687235),
    (0.237233795041835507, 0.156853322938943644),
    (0.408282678752175098, 0.181341891689180991),
    (0.591717321247824902, 0.181341891689180991),
    (0.762766204958164493, 0.156853322938943644),
    (0.898333238706813370, 0.111190517226687235),
    (0.980144928248768144, 0.050614268145188129),
];

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn circle(n: usize, r: f64) -> Vec<Point> {
        (0..n)
            .map(|k| {
                let a = 2.0 * PI * k as f64 / n as f64;
                [r * a.cos(), r * a.sin()]
            })
            .collect()
    }

    /// Lattice points along the sides of the rectangle [0, 4] x [0, 2]
    /// (counter-clockwise from the origin), as a body's outer layer is.
    fn rectangle() -> Vec<Point> {
        let mut p = Vec::new();
        for i in 0..4 {
            p.push([i as f64, 0.0]);
        }
        for j in 0..2 {
            p.push([4.0, j as f64]);
        }
        for i in (1..=4).rev() {
            p.push([i as f64, 2.0]);
        }
        for j in (1..=2).rev() {
            p.push([0.0, j as f64]);
        }
        p
    }

    #[test]
    fn passes_through_every_data_point() {
        for data in [circle(13, 2.0), rectangle()] {
            let c = ClosedCurve::interpolate(&data);
            for (k, q) in data.iter().enumerate() {
                let p = c.point(c.params[k]);
                assert!(norm(sub(p, *q)) < 1e-12, "{k}: {p:?} vs {q:?}");
            }
        }
    }

    #[test]
    fn rectangle_sides_are_straight_and_corners_sharp() {
        let c = ClosedCurve::interpolate(&rectangle());
        assert_eq!(c.corners.iter().filter(|c| **c).count(), 4);
        // Every sample of the bottom side (segments 0..4) lies on y = 0.
        for k in 0..4 {
            for i in 0..=10 {
                let u = c.params[k] + (c.params[k + 1] - c.params[k]) * i as f64 / 10.0;
                assert!(c.point(u)[1].abs() < 1e-12);
            }
        }
        // At the corner (4, 0) the normal jumps from -y to +x.
        let corner = c.params[4];
        let before = c.normal(corner - 1e-9);
        let after = c.normal(corner + 1e-9);
        assert!(norm(sub(before, [0.0, -1.0])) < 1e-6 && norm(sub(after, [1.0, 0.0])) < 1e-6);
        // Equal-speed segments on a straight side: the parameter is the arc length.
        assert!((c.length_parameter() - 12.0).abs() < 1e-12);
        assert!((c.arc_length() - 12.0).abs() < 1e-12);
    }

    #[test]
    fn bspline_form_has_consistent_sizes_and_reproduces_the_bezier_points() {
        for data in [circle(10, 1.0), rectangle()] {
            let c = ClosedCurve::interpolate(&data);
            let b = c.bspline();
            assert_eq!(b.knots.len(), b.control_points.len() + b.degree + 1);
            // De Boor evaluation of the B-spline agrees with the segments.
            for i in 0..50 {
                let u = c.length_parameter() * (i as f64 + 0.5) / 50.0;
                let p = de_boor(&b, u);
                assert!(
                    norm(sub(p, c.point(u))) < 1e-12,
                    "{u}: {p:?} vs {:?}",
                    c.point(u)
                );
            }
        }
    }

    /// Textbook de Boor evaluation, to check the served B-spline form.
    fn de_boor(b: &BSplineData, u: f64) -> Point {
        let p = b.degree;
        let k = (p..b.knots.len() - p - 1)
            .rfind(|&i| b.knots[i] <= u)
            .unwrap();
        let mut d: Vec<Point> = (0..=p).map(|j| b.control_points[j + k - p]).collect();
        for r in 1..=p {
            for j in (r..=p).rev() {
                let i = j + k - p;
                let alpha = (u - b.knots[i]) / (b.knots[i + p + 1 - r] - b.knots[i]);
                d[j] = add(scale(d[j - 1], 1.0 - alpha), scale(d[j], alpha));
            }
        }
        d[p]
    }

    /// Position error (max |C(u)| - R over the curve) and normal error (max
    /// angle to the radius) of a circle sampled at n points.
    fn circle_errors(n: usize) -> (f64, f64) {
        let c = ClosedCurve::interpolate(&circle(n, 1.0));
        let mut pos: f64 = 0.0;
        let mut ang: f64 = 0.0;
        for i in 0..(40 * n) {
            let u = c.length_parameter() * i as f64 / (40 * n) as f64;
            let p = c.point(u);
            pos = pos.max((norm(p) - 1.0).abs());
            ang = ang.max(cross(unit(p), c.normal(u)).abs().asin());
        }
        (pos, ang)
    }

    #[test]
    fn circle_converges_at_least_cubically_in_position() {
        // Measured: order 4.00 in position and 3.00 in the normal's angle for
        // uniform samples (n = 8..128; position error 9.9e-4 at n = 8 down to
        // 1.5e-8 at n = 128). A cubic interpolant with O(h^3)-accurate
        // tangents can do no better than h^4 in position; the issue asks for
        // at least 3. Asserted with a margin below the measured orders.
        let ns = [8, 16, 32, 64, 128];
        let errs: Vec<(f64, f64)> = ns.iter().map(|&n| circle_errors(n)).collect();
        for w in errs.windows(2) {
            let p_pos = (w[0].0 / w[1].0).log2();
            let p_ang = (w[0].1 / w[1].1).log2();
            eprintln!("order: position {p_pos:.2}, normal {p_ang:.2}");
            assert!(p_pos >= 3.8, "{errs:?}");
            assert!(p_ang >= 2.8, "{errs:?}");
        }
        eprintln!(
            "circle errors (n, position, normal angle): {:?}",
            ns.iter().zip(&errs).collect::<Vec<_>>()
        );
    }

    #[test]
    fn a_side_two_points_long_keeps_both_corners() {
        // The outer points of a body two points wide: the base has only its
        // two corners, each turning 90 degrees like its neighbour.
        let data = [
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [1.0, 3.0],
            [0.0, 3.0],
            [0.0, 2.0],
            [0.0, 1.0],
        ];
        let c = ClosedCurve::interpolate(&data);
        assert_eq!(c.corners.iter().filter(|c| **c).count(), 4);
        for i in 0..=10 {
            let u = c.params[1] * i as f64 / 10.0;
            assert!(
                c.point(u)[1].abs() < 1e-12,
                "the base bulges at {u}: {:?}",
                c.point(u)
            );
        }
    }

    #[test]
    fn closest_point_finds_the_foot_of_the_perpendicular() {
        let c = ClosedCurve::interpolate(&rectangle());
        let (_, p, d) = c.closest_point([1.5, 0.3]);
        assert!(norm(sub(p, [1.5, 0.0])) < 1e-10 && (d - 0.3).abs() < 1e-10);
        let (_, p, d) = c.closest_point([5.0, 1.0]);
        assert!(norm(sub(p, [4.0, 1.0])) < 1e-10 && (d - 1.0).abs() < 1e-10);
    }

    /// A moved point's segments from the tangents made before the move are
    /// the moved loop's own, to the bit, for every point and segment: on a
    /// circle, on the rectangle (moves that make and unmake corners), and
    /// on loops of three and four points, whose five-point stencils wrap
    /// onto themselves. Reusing the tangent before the move at `Q_(k+2)`
    /// (a window of four) fails (checked).
    #[test]
    fn a_moved_point_remakes_the_tangents_of_its_stencil() {
        let loops = [circle(13, 2.0), rectangle(), circle(3, 1.0), circle(4, 1.0)];
        for data in loops {
            let n = data.len();
            let before = data_tangents(&data);
            for k in 0..n {
                for delta in [[0.3, 0.0], [0.0, -0.45], [1e-6, 1e-6]] {
                    let mut moved = data.clone();
                    moved[k] = add(moved[k], delta);
                    let by_window = MovedPoint::new(&moved, &before, k);
                    for j in 0..n {
                        assert_eq!(
                            by_window.segment(j),
                            local_segment(&moved, j),
                            "n = {n}, point {k} moved by {delta:?}, segment {j}"
                        );
                    }
                }
            }
        }
    }
}
