//! Local bicubic interpolation of a structured grid of boundary points in
//! 3D: the tensor product of the 2D curve's local cubic scheme
//! ([`super::curve`]), after Piegl & Tiller, The NURBS Book, 2nd ed.,
//! section 9.3.5.
//!
//! The data are a grid `Q_(i,j)` of one face patch of a body, `i` along
//! `u` (fastest), `j` along `v`; each direction is open (a face that ends)
//! or closed (the side of a cylinder round its axis).
//!
//! 1. Along every grid line, a unit tangent at each data point: that of
//!    the circle through it and its two neighbours (at an open end, the
//!    circle through it and the next two), see [`line_tangents`]. A corner
//!    of a line (the curve's rule) keeps two tangents.
//! 2. Each edge between neighbouring data points is the curve's
//!    equal-speed cubic segment of length `a` (eq. 9.33-9.34): two patches
//!    sharing an edge share it exactly, so the surface is continuous.
//! 3. Each cell `[Q_(i,j), Q_(i+1,j+1)]` becomes a bicubic Bezier patch on
//!    `(s, t)` in `[0, 1]^2`: its four boundary curves are the edges, and
//!    its four inner control points follow from the twist `S_st` at its
//!    corners (`S_st(0, 0) = 9 (P_11 - P_10 - P_01 + P_00)`). The twist is
//!    estimated as the book does, from differences of the neighbouring
//!    cross derivatives: along `v` of `a_u T_u` on the patch's column, and
//!    along `u` of `a_v T_v` on its row, each of second order (Bessel's
//!    central difference on uneven spacing, one-sided of second order at
//!    an open end or a corner), and the two averaged.
//!
//! What this gives: positions continuous everywhere; at every data point
//! the four patches around it share the tangent plane spanned by `T_u` and
//! `T_v`; between data points the tangent planes of two patches meet at
//! an angle that vanishes as the spacing falls (the cross derivatives are
//! interpolated from the same corner values on both sides, scaled by the
//! two sides' edge lengths). On a smooth surface sampled at spacing `h`
//! the distance to it falls as `h^4` where the grid lines are circles
//! (any spacing: a cylinder's, a cube-sphere's great circles), as the 2D
//! circle's does, and as `h^3` where their curvature changes (tested
//! below).

pub type Point3 = [f64; 3];

fn sub(a: Point3, b: Point3) -> Point3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: Point3, b: Point3) -> Point3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: Point3, s: f64) -> Point3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: Point3, b: Point3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub fn cross(a: Point3, b: Point3) -> Point3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: Point3) -> f64 {
    dot(a, a).sqrt()
}
fn unit(a: Point3) -> Point3 {
    scale(a, 1.0 / norm(a))
}

/// Turning angle (radians) from chord `a` to chord `b`.
fn turn(a: Point3, b: Point3) -> f64 {
    norm(cross(a, b)).atan2(dot(a, b))
}

/// The curve's corner rule ([`super::curve::is_corner`]) in 3D.
fn is_corner(q_prev: Point3, q_in: Point3, q_out: Point3, q_next: Point3) -> bool {
    let here = turn(q_in, q_out);
    here >= 30f64.to_radians()
        && (here > 2.0 * turn(q_prev, q_in) || here > 2.0 * turn(q_out, q_next))
}

/// The tangents at a data point along one grid line: equal unless it is a
/// corner of the line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineTangent {
    pub incoming: Point3,
    pub outgoing: Point3,
    pub corner: bool,
}

impl LineTangent {
    fn smooth(t: Point3) -> Self {
        Self {
            incoming: t,
            outgoing: t,
            corner: false,
        }
    }
}

/// The unit tangent at the middle of three points `a`, `b`, `c` on the
/// circle through them: `|q_2|^2 q_1 + |q_1|^2 q_2` with `q_1 = b - a`,
/// `q_2 = c - b` (each chord leans off the tangent by half the angle it
/// subtends, which is proportional to its length). Exact on a circle
/// whatever the spacing, and on a line.
fn circle_tangent(q1: Point3, q2: Point3) -> Point3 {
    let v = add(scale(q1, dot(q2, q2)), scale(q2, dot(q1, q1)));
    if norm(v) > 0.0 { unit(v) } else { unit(q2) }
}

/// The tangent at the end of chord `q` on the circle whose tangent at its
/// other end is `t`: `t` mirrored in the chord.
fn mirrored(t: Point3, q: Point3) -> Point3 {
    let c = unit(q);
    sub(scale(c, 2.0 * dot(t, c)), t)
}

/// The unit tangents at every point of a line of data points, open or
/// closed. At a point inside the line, the tangent of the circle through
/// it and its two neighbours; at an open end, that of the circle through
/// the end and the next two; a corner (the curve's rule on the two chords
/// either side and the next ones out) keeps its two chords.
///
/// The 2D curve's five-point rule ([`super::curve`]) is exact on a circle
/// only where its points are evenly spaced. The grid lines of a surface are
/// not: a cube-sphere's are great circles sampled at equal angles of its
/// faces, unevenly along the circle, and on them that rule's tangents are
/// off by `O(h^2)` (the surface by `O(h^3)`, measured); the circle's are
/// exact, and the sphere converges at order 4. On a line whose curvature
/// changes, both are off by `O(h^2)`.
pub fn line_tangents(line: &[Point3], closed: bool) -> Vec<LineTangent> {
    let n = line.len();
    if n == 2 && !closed {
        let t = unit(sub(line[1], line[0]));
        return vec![LineTangent::smooth(t); 2];
    }
    let at = |k: isize| line[k.rem_euclid(n as isize) as usize];
    // chord(i) = Q_i - Q_(i-1), where both are on the line.
    let chord = |i: isize| sub(at(i), at(i - 1));
    let has = |i: isize| closed || (1..n as isize).contains(&i);
    let mut out: Vec<LineTangent> = (0..n as isize)
        .map(|k| {
            if !has(k) || !has(k + 1) {
                return LineTangent::smooth([0.0; 3]);
            }
            let (q_in, q_out) = (chord(k), chord(k + 1));
            let (q_prev, q_next) = (
                if has(k - 1) { chord(k - 1) } else { q_in },
                if has(k + 2) { chord(k + 2) } else { q_out },
            );
            if is_corner(q_prev, q_in, q_out, q_next) {
                return LineTangent {
                    incoming: unit(q_in),
                    outgoing: unit(q_out),
                    corner: true,
                };
            }
            LineTangent::smooth(circle_tangent(q_in, q_out))
        })
        .collect();
    if !closed {
        // The ends: the circle through the end and the next two, whose
        // tangent at the middle one is already known (its corner's chord
        // if it is one).
        let first = mirrored(out[1].incoming, chord(1));
        let last = mirrored(out[n - 2].outgoing, chord(n as isize - 1));
        out[0] = LineTangent::smooth(first);
        out[n - 1] = LineTangent::smooth(last);
    }
    out
}

/// The equal-speed length `a` of the cubic from `p0` (tangent `t0`) to `p3`
/// (tangent `t3`), as the curve's segments have.
fn edge_length(p0: Point3, t0: Point3, p3: Point3, t3: Point3) -> f64 {
    let chord = sub(p3, p0);
    let tsum = add(t0, t3);
    let a = 16.0 - dot(tsum, tsum);
    let b = 12.0 * dot(chord, tsum);
    let c = -36.0 * dot(chord, chord);
    if a.abs() < 1e-12 {
        return -c / b;
    }
    (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a)
}

/// A structured grid of data points on one face patch: `counts[0]` along
/// `u` (fastest), `counts[1]` along `v`; `closed[d]` when direction `d`
/// wraps round.
#[derive(Debug, Clone, PartialEq)]
pub struct DataGrid {
    pub counts: [usize; 2],
    pub closed: [bool; 2],
    pub points: Vec<Point3>,
}

impl DataGrid {
    fn at(&self, i: usize, j: usize) -> Point3 {
        self.points[i + self.counts[0] * j]
    }
    /// Cells (patches) along each direction.
    pub fn cells(&self) -> [usize; 2] {
        [0, 1].map(|d| {
            if self.closed[d] {
                self.counts[d]
            } else {
                self.counts[d] - 1
            }
        })
    }
}

/// A bicubic Bezier patch: `control[a][b]` is `P_ab`, `a` along `s` (the
/// grid's `u`), `b` along `t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BezierPatch {
    pub control: [[Point3; 4]; 4],
}

/// The cubic Bernstein polynomials at `s` and their derivatives.
pub(crate) fn bernstein(s: f64) -> ([f64; 4], [f64; 4]) {
    let r = 1.0 - s;
    (
        [r * r * r, 3.0 * s * r * r, 3.0 * s * s * r, s * s * s],
        [
            -3.0 * r * r,
            3.0 * r * (r - 2.0 * s),
            3.0 * s * (2.0 * r - s),
            3.0 * s * s,
        ],
    )
}

impl BezierPatch {
    /// The point and its derivatives along `s` and `t`.
    pub fn evaluate(&self, s: f64, t: f64) -> (Point3, Point3, Point3) {
        let (bs, ds) = bernstein(s);
        let (bt, dt) = bernstein(t);
        let mut out = [[0.0; 3]; 3];
        for a in 0..4 {
            for b in 0..4 {
                let p = self.control[a][b];
                for (o, w) in out
                    .iter_mut()
                    .zip([bs[a] * bt[b], ds[a] * bt[b], bs[a] * dt[b]])
                {
                    *o = add(*o, scale(p, w));
                }
            }
        }
        (out[0], out[1], out[2])
    }

    /// The point at `(s, t)`.
    pub fn point(&self, s: f64, t: f64) -> Point3 {
        self.evaluate(s, t).0
    }

    /// The unit normal `S_s x S_t / |S_s x S_t|` at `(s, t)`.
    pub fn normal(&self, s: f64, t: f64) -> Point3 {
        let (_, a, b) = self.evaluate(s, t);
        unit(cross(a, b))
    }
}

/// A face patch's surface: `cells[0] x cells[1]` Bezier patches, `u`
/// fastest.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    pub cells: [usize; 2],
    pub patches: Vec<BezierPatch>,
}

/// The derivative at `here` of a smooth function sampled along a line at
/// uneven steps: `back` and `ahead` are the samples behind and ahead with
/// the step to each (nearest first). Central of second order (Bessel's)
/// when there is one on each side; one-sided of second order from two on
/// one side; a plain difference from one; zero alone.
fn derivative(here: Point3, back: &[(Point3, f64)], ahead: &[(Point3, f64)]) -> Point3 {
    let slope = |a: Point3, b: Point3, h: f64| scale(sub(b, a), 1.0 / h);
    match (back, ahead) {
        ([(fm, hm), ..], [(fp, hp), ..]) => {
            let (dm, dp) = (slope(*fm, here, *hm), slope(here, *fp, *hp));
            scale(add(scale(dp, *hm), scale(dm, *hp)), 1.0 / (hm + hp))
        }
        ([], [(f1, h1), (f2, h2), ..]) => {
            let (d1, d2) = (slope(here, *f1, *h1), slope(*f1, *f2, *h2));
            let w = h1 / (h1 + h2);
            sub(scale(d1, 1.0 + w), scale(d2, w))
        }
        ([(f1, h1), (f2, h2), ..], []) => {
            let (d1, d2) = (slope(*f1, here, *h1), slope(*f2, *f1, *h2));
            let w = h1 / (h1 + h2);
            sub(scale(d1, 1.0 + w), scale(d2, w))
        }
        ([], [(f1, h1)]) => slope(here, *f1, *h1),
        ([(f1, h1)], []) => slope(*f1, here, *h1),
        _ => [0.0; 3],
    }
}

/// The surface through `grid`, each patch from the data around it.
pub fn interpolate(grid: &DataGrid) -> Surface {
    let interpolation = Interpolation::new(grid.clone());
    let cells = grid.cells();
    let patches = (0..cells[1])
        .flat_map(|l| (0..cells[0]).map(move |k| (k, l)))
        .map(|(k, l)| interpolation.patch(k, l))
        .collect();
    Surface { cells, patches }
}

/// A data grid with what its patches are made from: the tangents along
/// its rows (`tu`) and columns (`tv`) at every data point, and the lengths
/// of its edges (`au[i + nu j]` from `(i, j)` to `(i + 1, j)`, `av` from
/// `(i, j)` to `(i, j + 1)`). A data point moved ([`Interpolation::move_point`])
/// changes only its row's and its column's, and the patches within
/// [`Interpolation::REACH`] of it.
#[derive(Debug, Clone)]
pub struct Interpolation {
    grid: DataGrid,
    tu: Vec<LineTangent>,
    tv: Vec<LineTangent>,
    au: Vec<f64>,
    av: Vec<f64>,
}

impl Interpolation {
    /// How far (in cells, each way) the patches a data point shapes reach:
    /// patch `(k, l)` reads data up to three rows and columns beyond its
    /// corners (the twist's differences two along a line, each of an edge
    /// whose tangent reads one further). Checked by
    /// `moving_a_data_point_changes_only_the_patches_within_reach` (at 2 it
    /// fails).
    pub const REACH: usize = 3;

    pub fn new(grid: DataGrid) -> Self {
        let n = grid.points.len();
        let mut out = Self {
            grid,
            tu: vec![LineTangent::smooth([0.0; 3]); n],
            tv: vec![LineTangent::smooth([0.0; 3]); n],
            au: vec![0.0; n],
            av: vec![0.0; n],
        };
        for j in 0..out.grid.counts[1] {
            out.row(j);
        }
        for i in 0..out.grid.counts[0] {
            out.column(i);
        }
        out
    }

    pub fn grid(&self) -> &DataGrid {
        &self.grid
    }

    /// Index `k` along direction `d`, wrapped round a closed direction;
    /// `None` past an open end.
    fn wrap(&self, k: isize, d: usize) -> Option<usize> {
        let n = self.grid.counts[d] as isize;
        if self.grid.closed[d] {
            Some(k.rem_euclid(n) as usize)
        } else {
            (0..n).contains(&k).then_some(k as usize)
        }
    }

    /// Row `j`'s tangents and edges.
    fn row(&mut self, j: usize) {
        let nu = self.grid.counts[0];
        let row: Vec<Point3> = (0..nu).map(|i| self.grid.at(i, j)).collect();
        for (i, t) in line_tangents(&row, self.grid.closed[0])
            .into_iter()
            .enumerate()
        {
            self.tu[i + nu * j] = t;
        }
        for i in 0..nu {
            if let Some(i1) = self.wrap(i as isize + 1, 0) {
                self.au[i + nu * j] = edge_length(
                    row[i],
                    self.tu[i + nu * j].outgoing,
                    row[i1],
                    self.tu[i1 + nu * j].incoming,
                );
            }
        }
    }

    /// Column `i`'s tangents and edges.
    fn column(&mut self, i: usize) {
        let [nu, nv] = self.grid.counts;
        let column: Vec<Point3> = (0..nv).map(|j| self.grid.at(i, j)).collect();
        for (j, t) in line_tangents(&column, self.grid.closed[1])
            .into_iter()
            .enumerate()
        {
            self.tv[i + nu * j] = t;
        }
        for j in 0..nv {
            if let Some(j1) = self.wrap(j as isize + 1, 1) {
                self.av[i + nu * j] = edge_length(
                    column[j],
                    self.tv[i + nu * j].outgoing,
                    column[j1],
                    self.tv[i + nu * j1].incoming,
                );
            }
        }
    }

    /// Moves data point `(i, j)` to `to`, and remakes its row's and its
    /// column's tangents and edges.
    pub fn move_point(&mut self, i: usize, j: usize, to: Point3) {
        let nu = self.grid.counts[0];
        self.grid.points[i + nu * j] = to;
        self.row(j);
        self.column(i);
    }

    /// The patches `(k, l)` a data point at `(i, j)` shapes: those within
    /// [`Interpolation::REACH`] cells, wrapped round closed directions,
    /// each once.
    pub fn patches_near(&self, i: usize, j: usize) -> Vec<(usize, usize)> {
        let cells = self.grid.cells();
        let near = |m: usize, d: usize| -> Vec<usize> {
            let r = Self::REACH as isize;
            let mut v: Vec<usize> = (m as isize - r..=m as isize + r)
                .filter_map(|k| {
                    if self.grid.closed[d] {
                        Some(k.rem_euclid(cells[d] as isize) as usize)
                    } else {
                        (0..cells[d] as isize).contains(&k).then_some(k as usize)
                    }
                })
                .collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let (ks, ls) = (near(i, 0), near(j, 1));
        ls.iter()
            .flat_map(|&l| ks.iter().map(move |&k| (k, l)))
            .collect()
    }

    /// Patch `(k, l)`, from the data point `(k, l)` to `(k + 1, l + 1)`.
    pub fn patch(&self, k: usize, l: usize) -> BezierPatch {
        let nu = self.grid.counts[0];
        let (tu, tv, au, av) = (&self.tu, &self.tv, &self.au, &self.av);
        let wrap = |k: isize, d: usize| self.wrap(k, d);
        let i = [k, wrap(k as isize + 1, 0).unwrap()];
        let j = [l, wrap(l as isize + 1, 1).unwrap()];
        let q = |a: usize, b: usize| self.grid.at(i[a], j[b]);
        // Tangent along u leaving the patch's side a, toward the
        // other: outgoing at a = 0, incoming at a = 1.
        let tu_side = |ii: usize, jj: usize, a: usize| {
            let t = tu[ii + nu * jj];
            if a == 0 { t.outgoing } else { t.incoming }
        };
        let tv_side = |ii: usize, jj: usize, b: usize| {
            let t = tv[ii + nu * jj];
            if b == 0 { t.outgoing } else { t.incoming }
        };
        let mut c = [[[0.0; 3]; 4]; 4];
        for a in 0..2 {
            for b in 0..2 {
                c[3 * a][3 * b] = q(a, b);
            }
        }
        for b in 0..2 {
            let len = au[k + nu * j[b]];
            c[1][3 * b] = add(q(0, b), scale(tu_side(i[0], j[b], 0), len / 3.0));
            c[2][3 * b] = sub(q(1, b), scale(tu_side(i[1], j[b], 1), len / 3.0));
        }
        for a in 0..2 {
            let len = av[i[a] + nu * l];
            c[3 * a][1] = add(q(a, 0), scale(tv_side(i[a], j[0], 0), len / 3.0));
            c[3 * a][2] = sub(q(a, 1), scale(tv_side(i[a], j[1], 1), len / 3.0));
        }
        // The twist at each corner (a, b).
        for a in 0..2 {
            for b in 0..2 {
                // Along v, on column i[a], of F(m) = au(k, m) T_u.
                let f = |m: usize| scale(tu_side(i[a], m, a), au[k + nu * m]);
                let corner_v = |m: usize| tv[i[a] + nu * m].corner;
                let len_v = |m: usize| av[i[a] + nu * m];
                let line = Line {
                    d: 1,
                    corner: &corner_v,
                    f: &f,
                    length: &len_v,
                    wrap: &wrap,
                };
                let w_a = scale(line.slope_at(j[b], b == 0), av[i[a] + nu * l]);
                // Along u, on row j[b], of G(m) = av(m, l) T_v.
                let g = |m: usize| scale(tv_side(m, j[b], b), av[m + nu * l]);
                let corner_u = |m: usize| tu[m + nu * j[b]].corner;
                let len_u = |m: usize| au[m + nu * j[b]];
                let line = Line {
                    d: 0,
                    corner: &corner_u,
                    f: &g,
                    length: &len_u,
                    wrap: &wrap,
                };
                let w_b = scale(line.slope_at(i[a], a == 0), au[k + nu * j[b]]);
                let twist = scale(add(w_a, w_b), 0.5 / 9.0);
                // P_inner = P_edge_s + P_edge_t - P_corner +- twist / 9.
                let (ai, bi) = (if a == 0 { 1 } else { 2 }, if b == 0 { 1 } else { 2 });
                let sign = if a == b { 1.0 } else { -1.0 };
                c[ai][bi] = add(
                    sub(add(c[ai][3 * b], c[3 * a][bi]), c[3 * a][3 * b]),
                    scale(twist, sign),
                );
            }
        }
        BezierPatch { control: c }
    }
}

/// A function sampled along one grid line, for the twist's differences.
struct Line<'a> {
    /// The grid direction the line runs along.
    d: usize,
    /// Whether the line has a corner at an index.
    corner: &'a dyn Fn(usize) -> bool,
    f: &'a dyn Fn(usize) -> Point3,
    /// The edge from an index to the next.
    length: &'a dyn Fn(usize) -> f64,
    wrap: &'a dyn Fn(isize, usize) -> Option<usize>,
}

impl Line<'_> {
    /// The derivative at `m`, along the line, of its function; the patch
    /// lies ahead of `m` or behind it.
    fn slope_at(&self, m: usize, patch_ahead: bool) -> Point3 {
        let back = self.samples(m, -1, !patch_ahead);
        let ahead = self.samples(m, 1, patch_ahead);
        derivative((self.f)(m), &back, &ahead)
    }

    /// Up to two samples from `m` stepping by `step` (+1 or -1), with the
    /// step to each, never across a corner: the first step is taken from a
    /// corner only toward the patch (`patch_side`).
    fn samples(&self, m: usize, step: isize, patch_side: bool) -> Vec<(Point3, f64)> {
        let mut out = Vec::new();
        let mut from = m;
        for n in 0..2 {
            if (n > 0 || !patch_side) && (self.corner)(from) {
                break;
            }
            let Some(next) = (self.wrap)(from as isize + step, self.d) else {
                break;
            };
            let h = if step > 0 {
                (self.length)(from)
            } else {
                (self.length)(next)
            };
            out.push(((self.f)(next), h));
            from = next;
        }
        out
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::f64::consts::TAU;

    /// The largest of `distance` over a 5 x 5 sample of every patch, and
    /// over the patches for which `inner(k, l)` holds.
    fn worst(surface: &Surface, distance: impl Fn(Point3) -> f64) -> f64 {
        let mut worst: f64 = 0.0;
        for p in &surface.patches {
            for a in 0..5 {
                for b in 0..5 {
                    let x = p.point(a as f64 / 4.0, b as f64 / 4.0);
                    worst = worst.max(distance(x).abs());
                }
            }
        }
        worst
    }

    pub(crate) fn sci(v: &[f64]) -> String {
        let v: Vec<String> = v.iter().map(|x| format!("{x:.3e}")).collect();
        v.join(", ")
    }

    fn order(coarse: f64, fine: f64) -> f64 {
        (coarse / fine).log2()
    }

    /// Points on a plane, unevenly spaced: every patch lies in the plane,
    /// and passes through its data.
    #[test]
    fn a_plane_is_reproduced() {
        let n = [0.0, 0.3, 0.45, 1.0, 1.2];
        let m = [0.0, 0.25, 0.7, 0.8];
        let origin = [1.0, -2.0, 0.5];
        let (e1, e2) = ([0.6, 0.8, 0.0], [0.0, 0.6, 0.8]);
        let normal = unit(cross(e1, e2));
        let mut points = Vec::new();
        for &y in &m {
            for &x in &n {
                points.push(add(
                    origin,
                    add(scale(e1, x), scale(e2, y * (1.0 + 0.2 * x))),
                ));
            }
        }
        let grid = DataGrid {
            counts: [n.len(), m.len()],
            closed: [false, false],
            points,
        };
        let surface = interpolate(&grid);
        assert_eq!(surface.cells, [4, 3]);
        let off = worst(&surface, |x| dot(sub(x, origin), normal));
        assert!(off < 1e-14, "off the plane by {off:e}");
        for l in 0..3 {
            for k in 0..4 {
                let p = &surface.patches[k + 4 * l];
                for (s, t, i, j) in [(0.0, 0.0, k, l), (1.0, 1.0, k + 1, l + 1)] {
                    let miss = norm(sub(p.point(s, t), grid.at(i, j)));
                    assert!(miss < 1e-14);
                }
            }
        }
    }

    /// Neighbouring patches share their common edge exactly: the surface is
    /// continuous. On a wavy sheet, whose tangents and twists all differ.
    #[test]
    fn neighbouring_patches_share_their_edges() {
        let (nu, nv) = (7, 6);
        let mut points = Vec::new();
        for j in 0..nv {
            for i in 0..nu {
                let (x, y) = (i as f64 * 0.3 + 0.02 * (j * j) as f64, j as f64 * 0.25);
                points.push([x, y, (2.0 * x).sin() * (1.5 * y).cos()]);
            }
        }
        let grid = DataGrid {
            counts: [nu, nv],
            closed: [false, false],
            points,
        };
        let s = interpolate(&grid);
        let [cu, cv] = s.cells;
        for l in 0..cv {
            for k in 0..cu {
                let p = &s.patches[k + cu * l];
                for r in 0..=8 {
                    let w = r as f64 / 8.0;
                    if k + 1 < cu {
                        let q = &s.patches[k + 1 + cu * l];
                        assert!(norm(sub(p.point(1.0, w), q.point(0.0, w))) < 1e-14);
                    }
                    if l + 1 < cv {
                        let q = &s.patches[k + cu * (l + 1)];
                        assert!(norm(sub(p.point(w, 1.0), q.point(w, 0.0))) < 1e-14);
                    }
                }
            }
        }
    }

    /// Moving one data point changes only the patches
    /// [`Interpolation::patches_near`] lists, and as remaking the whole
    /// surface would: on a wavy sheet (open both ways, with a corner line)
    /// and round a wavy tube (closed one way).
    #[test]
    fn moving_a_data_point_changes_only_the_patches_within_reach() {
        for closed in [false, true] {
            let (nu, nv) = (12, 11);
            let mut points = Vec::new();
            for j in 0..nv {
                for i in 0..nu {
                    let a = TAU * i as f64 / nu as f64;
                    let y = j as f64 * 0.3;
                    points.push(if closed {
                        [
                            (1.0 + 0.1 * (3.0 * a).sin()) * a.cos(),
                            (1.0 + 0.05 * y) * a.sin(),
                            y,
                        ]
                    } else {
                        // A ridge (corner) along i = 5.
                        let x = i as f64 * 0.3;
                        [
                            x,
                            y + 0.02 * (i * i) as f64,
                            (x - 1.5).abs() + 0.2 * (1.5 * y).cos(),
                        ]
                    });
                }
            }
            let grid = DataGrid {
                counts: [nu, nv],
                closed: [closed, false],
                points,
            };
            let before = interpolate(&grid);
            let cells = grid.cells();
            let mut moved = Interpolation::new(grid.clone());
            for j in 0..nv {
                for i in 0..nu {
                    let at = grid.at(i, j);
                    let to = add(at, [0.01, -0.02, 0.015]);
                    moved.move_point(i, j, to);
                    let mut changed_grid = grid.clone();
                    changed_grid.points[i + nu * j] = to;
                    let rebuilt = interpolate(&changed_grid);
                    let near = moved.patches_near(i, j);
                    for l in 0..cells[1] {
                        for k in 0..cells[0] {
                            let p = moved.patch(k, l);
                            assert_eq!(p, rebuilt.patches[k + cells[0] * l]);
                            if p != before.patches[k + cells[0] * l] {
                                assert!(near.contains(&(k, l)), "({i}, {j}) moved ({k}, {l})");
                            }
                        }
                    }
                    moved.move_point(i, j, at);
                }
            }
        }
    }

    /// The side of a cylinder, closed round it and open along it: the
    /// distance to the true surface falls as h^4.
    #[test]
    fn a_cylinder_converges_at_fourth_order() {
        let r = 1.3;
        let error = |n: usize| {
            let layers = n / 4;
            let mut points = Vec::new();
            for j in 0..=layers {
                for i in 0..n {
                    let a = TAU * (i as f64 + 0.5) / n as f64;
                    points.push([r * a.cos(), r * a.sin(), j as f64 * 1.5 / layers as f64]);
                }
            }
            let grid = DataGrid {
                counts: [n, layers + 1],
                closed: [true, false],
                points,
            };
            let surface = interpolate(&grid);
            // Outward normals.
            let p = &surface.patches[0];
            let x = p.point(0.5, 0.5);
            assert!(dot(p.normal(0.5, 0.5), [x[0], x[1], 0.0]) > 0.0);
            worst(&surface, |x| x[0].hypot(x[1]) - r) / r
        };
        let e: Vec<f64> = [8, 16, 32, 64].into_iter().map(error).collect();
        let orders: Vec<f64> = e.windows(2).map(|w| order(w[0], w[1])).collect();
        eprintln!("cylinder: errors {}, orders {orders:.2?}", sci(&e));
        assert!(orders[1..].iter().all(|&p| p > 3.8), "{orders:?}");
    }

    /// An elliptic cylinder (semi-axes 2 and 1): round it the grid lines
    /// are ellipses, whose curvature changes, and the circle's tangents are
    /// off by `O(h^2)`: the distance to it falls at order 3 (measured 7.9e-3,
    /// 6.1e-4, 6.1e-5, 7.2e-6 at 16 .. 128 round; orders 3.70, 3.32, 3.08).
    #[test]
    fn an_elliptic_cylinder_converges_at_third_order() {
        let (a, b) = (2.0, 1.0);
        let error = |n: usize| {
            let mut points = Vec::new();
            for j in 0..=2 {
                for i in 0..n {
                    let t = TAU * (i as f64 + 0.5) / n as f64;
                    points.push([a * t.cos(), b * t.sin(), j as f64 * 0.5]);
                }
            }
            let grid = DataGrid {
                counts: [n, 3],
                closed: [true, false],
                points,
            };
            // The ellipse's implicit function over its gradient's length:
            // the distance to first order.
            worst(&interpolate(&grid), |x| {
                let f = (x[0] / a).powi(2) + (x[1] / b).powi(2) - 1.0;
                let g = (2.0 * x[0] / (a * a)).hypot(2.0 * x[1] / (b * b));
                f / g
            })
        };
        let e: Vec<f64> = [16, 32, 64, 128].into_iter().map(error).collect();
        let orders: Vec<f64> = e.windows(2).map(|w| order(w[0], w[1])).collect();
        eprintln!("ellipse: errors {}, orders {orders:.2?}", sci(&e));
        assert!(orders.iter().all(|&p| p > 2.8), "{orders:?}");
    }

    /// The data grid on face `f` of a cube-sphere of radius `r` (its
    /// corners of `n` cells a side: [`ReferenceFace::SphereFace`]).
    fn cube_sphere_face(f: usize, n: usize, r: f64) -> DataGrid {
        let face = super::super::face_patches::ReferenceFace::SphereFace {
            center: [0.0; 3],
            radius: r,
            face: f,
            inward: false,
        };
        let mut points = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                points.push(face.at(i as f64 / n as f64, j as f64 / n as f64));
            }
        }
        DataGrid {
            counts: [n + 1, n + 1],
            closed: [false, false],
            points,
        }
    }

    /// A sphere as the six faces of a cube-sphere, each face's data its
    /// own (one-sided at the cube's edges): the distance to the sphere
    /// converges at order 4. Measured (n = 8 .. 128 cells a face side):
    /// in the patches along the faces' edges, which hold the largest
    /// errors, 3.1e-5 .. 6.5e-10 of the radius, orders 3.77, 3.88, 3.94,
    /// 3.97; inside the faces 1.1e-5 .. 2.0e-10, orders 4.32, 4.02, 3.57,
    /// 3.79 (the largest of a sample of each patch: a noisy measure).
    /// With the 2D curve's five-point tangents instead of the circle's the
    /// orders were 2.7 and 2.9.
    #[test]
    fn a_sphere_converges_at_fourth_order_inside_its_faces() {
        let r = 0.8;
        let errors = |n: usize| {
            let (mut inside, mut edge): (f64, f64) = (0.0, 0.0);
            for f in 0..6 {
                let surface = interpolate(&cube_sphere_face(f, n, r));
                for (c, p) in surface.patches.iter().enumerate() {
                    let (k, l) = (c % n, c / n);
                    let one = Surface {
                        cells: [1, 1],
                        patches: vec![*p],
                    };
                    let e = worst(&one, |x| norm(x) - r) / r;
                    let border = k < 2 || l < 2 || k + 2 >= n || l + 2 >= n;
                    if border {
                        edge = edge.max(e);
                    } else {
                        inside = inside.max(e);
                    }
                }
            }
            (inside, edge)
        };
        let e: Vec<(f64, f64)> = [8, 16, 32, 64, 128].into_iter().map(errors).collect();
        let inside: Vec<f64> = e.windows(2).map(|w| order(w[0].0, w[1].0)).collect();
        let edge: Vec<f64> = e.windows(2).map(|w| order(w[0].1, w[1].1)).collect();
        let (a, b): (Vec<f64>, Vec<f64>) = e.iter().copied().unzip();
        eprintln!(
            "sphere: errors inside {}, at the edges {}; orders inside {inside:.2?}, at the edges {edge:.2?}",
            sci(&a),
            sci(&b)
        );
        assert!(edge[1..].iter().all(|&p| p > 3.8), "{edge:?}");
        assert!(inside[1..].iter().all(|&p| p > 3.5), "{inside:?}");
    }
}
