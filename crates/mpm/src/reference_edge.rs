//! The exact edge of a body's reference geometry, as the case gives it:
//! straight sides and circular arcs, and the corners where the edge turns.
//! The boundary curve's data points are put on it in the reference
//! configuration ([`crate::boundary::snap_to_edge`]), whatever lattice the
//! points were seeded on.

use std::collections::HashMap;
use std::f64::consts::TAU;

use crate::geometry::{Geometry, signed_area};

/// One smooth piece of a geometry's edge, in the direction its ring runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EdgePiece {
    Segment([f64; 2], [f64; 2]),
    /// From angle `start` through `sweep` radians: counter-clockwise when
    /// `sweep > 0`, clockwise when `sweep < 0` (`0 < |sweep| <= 2 pi`).
    Arc {
        center: [f64; 2],
        radius: f64,
        start: f64,
        sweep: f64,
    },
}

impl EdgePiece {
    pub fn length(&self) -> f64 {
        match *self {
            EdgePiece::Segment(a, b) => distance(a, b),
            EdgePiece::Arc { radius, sweep, .. } => radius * sweep.abs(),
        }
    }

    /// The point at arc length `s` from the piece's start.
    pub fn at(&self, s: f64) -> [f64; 2] {
        match *self {
            EdgePiece::Segment(a, b) => {
                let length = distance(a, b);
                if length == 0.0 {
                    return a;
                }
                let t = s / length;
                [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
            }
            EdgePiece::Arc {
                center: c,
                radius: r,
                start,
                sweep,
            } => {
                let t = start + sweep.signum() * s / r;
                [c[0] + r * t.cos(), c[1] + r * t.sin()]
            }
        }
    }

    /// The unit tangent, in the running direction, at arc length `s`.
    fn tangent(&self, s: f64) -> [f64; 2] {
        match *self {
            EdgePiece::Segment(a, b) => {
                let l = distance(a, b);
                [(b[0] - a[0]) / l, (b[1] - a[1]) / l]
            }
            EdgePiece::Arc {
                radius: r,
                start,
                sweep,
                ..
            } => {
                let t = start + sweep.signum() * s / r;
                [-sweep.signum() * t.sin(), sweep.signum() * t.cos()]
            }
        }
    }

    /// The arc length from the piece's start of its point nearest `x`.
    pub fn nearest_length(&self, x: [f64; 2]) -> f64 {
        match *self {
            EdgePiece::Segment(a, b) => {
                let d = [b[0] - a[0], b[1] - a[1]];
                let length = distance(a, b);
                if length == 0.0 {
                    return 0.0;
                }
                (((x[0] - a[0]) * d[0] + (x[1] - a[1]) * d[1]) / length).clamp(0.0, length)
            }
            EdgePiece::Arc {
                center: c,
                radius: r,
                start,
                sweep,
            } => {
                let t = (x[1] - c[1]).atan2(x[0] - c[0]);
                let along = (sweep.signum() * (t - start)).rem_euclid(TAU);
                if along <= sweep.abs() {
                    return r * along;
                }
                // Past the arc's end: the nearer end point.
                let end = self.length();
                if distance(x, self.at(0.0)) <= distance(x, self.at(end)) {
                    0.0
                } else {
                    end
                }
            }
        }
    }

    /// The point of the piece nearest `x`.
    pub fn nearest(&self, x: [f64; 2]) -> [f64; 2] {
        self.at(self.nearest_length(x))
    }
}

pub fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// One closed ring of a geometry's edge, the material on its left: an
/// outer boundary runs counter-clockwise, a hole's clockwise.
#[derive(Debug, Clone, PartialEq)]
pub struct Ring {
    pub pieces: Vec<EdgePiece>,
    pub hole: bool,
}

impl Ring {
    fn polygon(vertices: &[[f64; 2]], hole: bool) -> Self {
        let counter_clockwise = signed_area(vertices) > 0.0;
        let mut v = vertices.to_vec();
        // A vertex given twice in a row is one corner.
        v.dedup();
        while v.len() > 1 && v.first() == v.last() {
            v.pop();
        }
        if counter_clockwise == hole {
            v.reverse();
        }
        Self {
            pieces: (0..v.len())
                .map(|k| EdgePiece::Segment(v[k], v[(k + 1) % v.len()]))
                .collect(),
            hole,
        }
    }

    fn circle(center: [f64; 2], radius: f64, hole: bool) -> Self {
        Self {
            pieces: vec![EdgePiece::Arc {
                center,
                radius,
                start: 0.0,
                sweep: if hole { -TAU } else { TAU },
            }],
            hole,
        }
    }

    pub fn length(&self) -> f64 {
        self.pieces.iter().map(EdgePiece::length).sum()
    }

    /// The arc length along the ring at which each piece starts.
    pub fn starts(&self) -> Vec<f64> {
        let mut at = 0.0;
        self.pieces
            .iter()
            .map(|p| {
                let start = at;
                at += p.length();
                start
            })
            .collect()
    }

    /// The vertices where the ring turns (the tangents either side differ
    /// by more than a milliradian), with their arc lengths.
    pub fn corners(&self) -> Vec<(f64, [f64; 2])> {
        let n = self.pieces.len();
        let mut before = 0.0;
        let mut out = Vec::new();
        for k in 0..n {
            let (prev, here) = (&self.pieces[(k + n - 1) % n], &self.pieces[k]);
            let (t0, t1) = (prev.tangent(prev.length()), here.tangent(0.0));
            let turn = (t0[0] * t1[1] - t0[1] * t1[0]).atan2(t0[0] * t1[0] + t0[1] * t1[1]);
            if turn.abs() > 1e-3 {
                out.push((before, here.at(0.0)));
            }
            before += here.length();
        }
        out
    }
}

impl Geometry {
    /// The closed rings of the edge: the outer boundary counter-clockwise,
    /// holes clockwise.
    pub fn rings(&self) -> Vec<Ring> {
        match self {
            Geometry::Polygon { vertices, holes } => {
                std::iter::once(Ring::polygon(vertices, false))
                    .chain(holes.iter().map(|h| Ring::polygon(h, true)))
                    .collect()
            }
            Geometry::Circle { center, radius } => vec![Ring::circle(*center, *radius, false)],
            Geometry::Annulus {
                center,
                inner_radius,
                outer_radius,
            } => vec![
                Ring::circle(*center, *outer_radius, false),
                Ring::circle(*center, *inner_radius, true),
            ],
            Geometry::AnnulusSector {
                center,
                inner_radius: a,
                outer_radius: b,
                start_angle,
                end_angle,
            } => {
                let (start, end) = (start_angle.to_radians(), end_angle.to_radians());
                let at = |r: f64, t: f64| [center[0] + r * t.cos(), center[1] + r * t.sin()];
                let arc = |radius, start, sweep| EdgePiece::Arc {
                    center: *center,
                    radius,
                    start,
                    sweep,
                };
                vec![Ring {
                    pieces: vec![
                        EdgePiece::Segment(at(*a, start), at(*b, start)),
                        arc(*b, start, end - start),
                        EdgePiece::Segment(at(*b, end), at(*a, end)),
                        arc(*a, end, start - end),
                    ],
                    hole: false,
                }]
            }
            Geometry::Rectangle { min, max, .. } => {
                let corners = self.turned_corners().unwrap_or([
                    *min,
                    [max[0], min[1]],
                    *max,
                    [min[0], max[1]],
                ]);
                vec![Ring::polygon(&corners, false)]
            }
            Geometry::Quadrilateral { vertices } => vec![Ring::polygon(vertices, false)],
            Geometry::Mesh(mesh) => (mesh.boundary_rings().unwrap_or_default().iter())
                .map(|r| Ring::polygon(r, signed_area(r) < 0.0))
                .collect(),
        }
    }

    /// The pieces of the edge, holes' included.
    pub fn edge(&self) -> Vec<EdgePiece> {
        self.rings().into_iter().flat_map(|r| r.pieces).collect()
    }

    /// Where the edge is not smooth: the vertices of polygons (holes'
    /// included), rectangles and quadrilaterals, and a sector's four
    /// corners; circles and annuli have none.
    pub fn corners(&self) -> Vec<[f64; 2]> {
        self.rings()
            .iter()
            .flat_map(|r| r.corners().into_iter().map(|(_, x)| x))
            .collect()
    }

    /// The point of the edge nearest `x`.
    pub fn nearest_on_edge(&self, x: [f64; 2]) -> [f64; 2] {
        nearest_on(&self.edge(), x)
    }
}

/// Edge pieces bucketed by their bounding boxes, so that the piece nearest
/// a point costs a few pieces, not the whole edge of a mesh or a polygon.
pub struct EdgeIndex<'a> {
    pieces: &'a [EdgePiece],
    size: f64,
    buckets: HashMap<(i64, i64), Vec<usize>>,
}

impl<'a> EdgeIndex<'a> {
    /// Buckets at least `size` wide (and as wide as the largest piece).
    pub fn new(pieces: &'a [EdgePiece], size: f64) -> Self {
        let boxes: Vec<([f64; 2], [f64; 2])> = pieces.iter().map(bounding_box).collect();
        let size = boxes
            .iter()
            .map(|(lo, hi)| (hi[0] - lo[0]).max(hi[1] - lo[1]))
            .fold(size, f64::max)
            .max(f64::MIN_POSITIVE);
        let mut buckets: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        for (k, (lo, hi)) in boxes.iter().enumerate() {
            let (i0, j0) = bucket(*lo, size);
            let (i1, j1) = bucket(*hi, size);
            for i in i0..=i1 {
                for j in j0..=j1 {
                    buckets.entry((i, j)).or_default().push(k);
                }
            }
        }
        Self {
            pieces,
            size,
            buckets,
        }
    }

    /// The piece nearest `x` among those within `radius` of it: its index,
    /// the arc length along it and the distance; `None` if none is within.
    pub fn nearest(&self, x: [f64; 2], radius: f64) -> Option<(usize, f64, f64)> {
        if self.pieces.is_empty() {
            return None;
        }
        let mut best: Option<(usize, f64, f64)> = None;
        let mut consider = |k: usize| {
            let s = self.pieces[k].nearest_length(x);
            let d = distance(x, self.pieces[k].at(s));
            if d <= radius && best.is_none_or(|(_, _, e)| d < e) {
                best = Some((k, s, d));
            }
        };
        let reach = (radius / self.size).ceil();
        if reach > 100.0 {
            // Wider than a hundred buckets: every piece.
            (0..self.pieces.len()).for_each(consider);
            return best;
        }
        let reach = reach as i64;
        let (i, j) = bucket(x, self.size);
        for a in i - reach..=i + reach {
            for b in j - reach..=j + reach {
                for &k in self.buckets.get(&(a, b)).into_iter().flatten() {
                    consider(k);
                }
            }
        }
        best
    }

    /// The point of the edge nearest `x`, looked for within `radius`
    /// first and over the whole edge if nothing is that near.
    pub fn nearest_point(&self, x: [f64; 2], radius: f64) -> [f64; 2] {
        match self.nearest(x, radius) {
            Some((k, s, _)) => self.pieces[k].at(s),
            None => nearest_on(self.pieces, x),
        }
    }
}

/// Points bucketed on a square lattice, for the nearest of them to a
/// place without looking at all of them.
pub struct PointIndex {
    points: Vec<[f64; 2]>,
    size: f64,
    buckets: HashMap<(i64, i64), Vec<usize>>,
}

impl PointIndex {
    /// `points` in buckets at least `size` wide, and wide enough that there
    /// are no more buckets over their bounding box than points (so that a
    /// few points lie near any place among them).
    pub fn new(points: Vec<[f64; 2]>, size: f64) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &points {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        let spread = if points.is_empty() {
            0.0
        } else {
            ((hi[0] - lo[0]) * (hi[1] - lo[1]) / points.len() as f64)
                .sqrt()
                .max((hi[0] - lo[0]).max(hi[1] - lo[1]) / points.len() as f64)
        };
        let size = size.max(spread).max(f64::MIN_POSITIVE);
        let mut buckets: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        for (k, &p) in points.iter().enumerate() {
            buckets.entry(bucket(p, size)).or_default().push(k);
        }
        Self {
            points,
            size,
            buckets,
        }
    }

    /// The index of the point nearest `x` (ties to the lower index), if
    /// any: the buckets in growing squares about `x` until one holds a
    /// point, then one square more (a nearer point may sit just beyond the
    /// first square's corner), or all the points past a hundred buckets.
    pub fn nearest(&self, x: [f64; 2]) -> Option<usize> {
        self.nearest_within(x, f64::INFINITY)
    }

    /// [`Self::nearest`] among the points within `radius` of `x`.
    pub fn nearest_within(&self, x: [f64; 2], radius: f64) -> Option<usize> {
        if self.points.is_empty() {
            return None;
        }
        let (i, j) = bucket(x, self.size);
        let closer = |best: Option<usize>, k: usize| match best {
            Some(b) if (distance(self.points[b], x), b) <= (distance(self.points[k], x), k) => best,
            _ => Some(k),
        };
        let mut best = None;
        let mut found_at = None;
        // Squares out to the radius, at most a hundred buckets wide.
        let rings = (radius / self.size).ceil().min(100.0) as i64 + 1;
        for r in 0..rings {
            if found_at.is_some_and(|f: i64| r > 2 * f + 1) {
                break;
            }
            for a in i - r..=i + r {
                for b in j - r..=j + r {
                    if (a - i).abs() != r && (b - j).abs() != r {
                        continue; // inside the square searched already
                    }
                    for &k in self.buckets.get(&(a, b)).into_iter().flatten() {
                        best = closer(best, k);
                        found_at.get_or_insert(r);
                    }
                }
            }
        }
        let best = if best.is_none() && rings > 100 {
            (0..self.points.len()).fold(best, closer)
        } else {
            best
        };
        best.filter(|&k| distance(self.points[k], x) <= radius)
    }
}

/// The bucket of `x`, its indices kept far inside `i64` so that the
/// squares searched about it cannot overflow.
fn bucket(x: [f64; 2], size: f64) -> (i64, i64) {
    let index = |c: f64| (c / size).floor().clamp(-1e15, 1e15) as i64;
    (index(x[0]), index(x[1]))
}

fn bounding_box(piece: &EdgePiece) -> ([f64; 2], [f64; 2]) {
    match *piece {
        EdgePiece::Segment(a, b) => (
            [a[0].min(b[0]), a[1].min(b[1])],
            [a[0].max(b[0]), a[1].max(b[1])],
        ),
        EdgePiece::Arc { center, radius, .. } => (
            [center[0] - radius, center[1] - radius],
            [center[0] + radius, center[1] + radius],
        ),
    }
}

/// The point of `pieces` nearest `x` (`x` itself if there are none).
pub fn nearest_on(pieces: &[EdgePiece], x: [f64; 2]) -> [f64; 2] {
    pieces
        .iter()
        .map(|p| p.nearest(x))
        .min_by(|a, b| distance(x, *a).total_cmp(&distance(x, *b)))
        .unwrap_or(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The bucketed searches find what looking at everything finds.
        #[test]
        fn the_indexes_find_the_nearest(
            pts in proptest::collection::vec((-10.0..10.0f64, -10.0..10.0f64), 1..60),
            x in -15.0..15.0f64, y in -15.0..15.0f64, size in 0.01..5.0f64,
        ) {
            let pts: Vec<[f64; 2]> = pts.into_iter().map(|(a, b)| [a, b]).collect();
            let q = [x, y];
            let brute = (0..pts.len())
                .min_by(|&a, &b| distance(pts[a], q).total_cmp(&distance(pts[b], q)).then(a.cmp(&b)))
                .unwrap();
            let index = PointIndex::new(pts.clone(), size);
            let found = index.nearest(q).unwrap();
            prop_assert!((distance(pts[found], q) - distance(pts[brute], q)).abs() < 1e-12);
            let within = index.nearest_within(q, 1.0);
            prop_assert_eq!(within.is_some(), distance(pts[brute], q) <= 1.0);
            // The pieces of the closed polyline through the points.
            let pieces: Vec<EdgePiece> = (0..pts.len())
                .map(|k| EdgePiece::Segment(pts[k], pts[(k + 1) % pts.len()]))
                .collect();
            let exact = distance(nearest_on(&pieces, q), q);
            let edges = EdgeIndex::new(&pieces, size);
            prop_assert!((distance(edges.nearest_point(q, size), q) - exact).abs() < 1e-12);
        }
    }

    #[test]
    fn nearest_points_lie_on_sides_arcs_and_their_ends() {
        let sector = Geometry::AnnulusSector {
            center: [1.0, 2.0],
            inner_radius: 1.0,
            outer_radius: 2.0,
            start_angle: 0.0,
            end_angle: 90.0,
        };
        let close = |a: [f64; 2], b: [f64; 2]| distance(a, b) < 1e-12;
        // Outside the outer arc, inside the inner one, beyond the ends.
        assert!(close(sector.nearest_on_edge([4.0, 5.0]), {
            let s = 2.0 / 2f64.sqrt();
            [1.0 + s, 2.0 + s]
        }));
        assert!(close(sector.nearest_on_edge([1.5, 2.2]), {
            let d = 0.5f64.hypot(0.2);
            [1.0 + 0.5 / d, 2.0 + 0.2 / d]
        }));
        assert!(close(sector.nearest_on_edge([2.5, 1.0]), [2.5, 2.0]));
        assert!(close(sector.nearest_on_edge([-1.0, 1.0]), [1.0, 3.0]));
        assert_eq!(sector.corners().len(), 4);
        let turned = Geometry::Rectangle {
            min: [0.0, 0.0],
            max: [2.0, 1.0],
            angle: 90.0,
            about: Some([0.0, 0.0]),
        };
        assert!(close(turned.nearest_on_edge([0.2, 1.0]), [0.0, 1.0]));
        assert!(close(turned.nearest_on_edge([-0.5, 3.0]), [-0.5, 2.0]));
    }
}
