//! The material boundary: the outer layer of material points, ordered into
//! loops once ([`detection`]), interpolated by a local cubic B-spline after
//! every step ([`curve`]).

pub mod curve;
pub mod detection;
pub mod edge_detection;
pub mod face_loads;
pub mod face_patches;
pub mod ibm;
pub mod loading;
pub mod quadrature;
pub mod surface;
pub mod surface_loading;
pub mod traction;

use serde::Serialize;

pub use curve::{BSplineData, ClosedCurve};
pub use detection::{BoundaryLoop, find_loops};

use crate::geometry::{Geometry, Selector};
use crate::particles::MaterialPoints;
use crate::reference_edge::{EdgeIndex, PointIndex, distance};

/// Where the boundary curve's data points are (the case's
/// `crate::case::Representation`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Representation {
    /// On the material's edge: each outer point pushed out to the edge of
    /// its domain (half a spacing), mapped by its deformation gradient.
    #[default]
    Edge,
    /// Through the outer material points themselves (the paper's choice),
    /// half a point spacing inside the material's edge.
    Points,
}

/// Sets each loop's data-point offsets for the chosen representation: zero
/// through the points; for the material edge, out along the reference
/// normal to the edge of the point's cell in the body's lattice
/// ([`crate::particles::seeding::Domain::edge_offset`]), which reaches the middle of
/// the cell's side on a straight edge and its corner at a corner (where `n`
/// is the mean of the two normals). Polar and mapped cells are turned and
/// sheared with their lattice, and the offset follows them.
pub fn set_offsets(
    loops: &mut [BoundaryLoop],
    points: &MaterialPoints,
    representation: Representation,
) {
    for l in loops.iter_mut() {
        l.offset = match representation {
            Representation::Points => vec![[0.0, 0.0]; l.points.len()],
            Representation::Edge => {
                let ring: Vec<[f64; 2]> = l.points.iter().map(|&p| points.reference[p]).collect();
                if ring.len() < 3 {
                    vec![[0.0, 0.0]; ring.len()]
                } else {
                    curve::data_normals(&ring)
                        .into_iter()
                        .zip(&l.points)
                        .map(|((n_in, n_out), &p)| {
                            points.domain[p].edge_offset([n_in[0] + n_out[0], n_in[1] + n_out[1]])
                        })
                        .collect()
                }
            }
        };
    }
}

/// Puts each loop's reference data points on the exact edge of its body's
/// geometry (the `edge` representation), so that straight sides are
/// straight, corners are corners and arcs lie on the arc whatever lattice
/// the points sit on.
/// - Each data point goes to the nearest point of the edge.
/// - Each corner of the geometry becomes a data point of the loop whose
///   data points come nearest it: the nearest one moves onto it if it is
///   within half a domain reach, otherwise the corner is added next to it,
///   on the side it lies ahead of, carried by the same material point. (On
///   the grid's lattice the nearest point of an acute corner can be more
///   than a spacing away.)
/// - A data point that lands within half a domain reach of the one kept
///   before it is dropped, its material point no longer on the curve: on a
///   lattice that steps along a gentle slope, neighbours land close
///   together, and the points in the shadow of a re-entrant corner all
///   land on it. A corner is kept over a plain point.
///
/// On the bodies' own lattices (rectangles, quadrilaterals, sectors) the
/// data points are on the edge already and this moves them by round-off.
pub fn snap_to_edge(loops: &mut [BoundaryLoop], points: &MaterialPoints, geometries: &[&Geometry]) {
    /// A data point: its material point, where it goes, whether a corner.
    struct Entry {
        point: usize,
        at: [f64; 2],
        corner: bool,
    }
    let reach = |p: usize| points.domain[p].reach();
    let mut entries: Vec<Vec<Entry>> = loops
        .iter()
        .map(|l| {
            let edge = geometries[l.body].edge();
            let ring = reference_ring(l, points);
            let radius = l.points.iter().map(|&p| 2.0 * reach(p)).fold(0.0, f64::max);
            let index = EdgeIndex::new(&edge, radius);
            (l.points.iter().zip(ring))
                .map(|(&point, x)| Entry {
                    point,
                    at: index.nearest_point(x, radius),
                    corner: false,
                })
                .collect()
        })
        .collect();
    for (body, geometry) in geometries.iter().enumerate() {
        // The body's data points as (loop, place) before any corner is
        // added: a corner goes next to the nearest of them.
        let slots: Vec<(usize, usize)> = (0..loops.len())
            .filter(|&l| loops[l].body == body && entries[l].len() >= 3)
            .flat_map(|l| (0..entries[l].len()).map(move |k| (l, k)))
            .collect();
        let size = slots
            .iter()
            .map(|&(l, k)| reach(entries[l][k].point))
            .fold(0.0, f64::max);
        let index = PointIndex::new(slots.iter().map(|&(l, k)| entries[l][k].at).collect(), size);
        let mut corners: Vec<([f64; 2], (usize, usize))> = geometry
            .corners()
            .into_iter()
            .filter_map(|c| index.nearest(c).map(|i| (c, slots[i])))
            .collect();
        // Inserting shifts the later places of a loop: from the back.
        corners.sort_by_key(|c| std::cmp::Reverse(c.1));
        for (c, (l, k)) in corners {
            let e = &mut entries[l];
            let n = e.len();
            let here = e[k].at;
            if distance(here, c) < 0.5 * reach(e[k].point) && !e[k].corner {
                (e[k].at, e[k].corner) = (c, true);
                continue;
            }
            let ahead = |j: usize| {
                let d = [e[j].at[0] - here[0], e[j].at[1] - here[1]];
                d[0] * (c[0] - here[0]) + d[1] * (c[1] - here[1])
            };
            let place = if ahead((k + 1) % n) >= ahead((k + n - 1) % n) {
                k + 1
            } else {
                k
            };
            let point = e[k].point;
            e.insert(
                place,
                Entry {
                    point,
                    at: c,
                    corner: true,
                },
            );
        }
    }
    for (l, e) in loops.iter_mut().zip(entries) {
        if e.len() < 3 {
            continue;
        }
        // Keep, in loop order, the data points not too close to the last
        // kept one, then close the loop the same way.
        let close = |a: &Entry, b: &Entry| distance(a.at, b.at) < 0.5 * reach(b.point);
        let mut kept: Vec<Entry> = Vec::with_capacity(e.len());
        for entry in e {
            match kept.last_mut() {
                // Two corners close together (a short side) both stay.
                Some(last) if close(last, &entry) && !(last.corner && entry.corner) => {
                    if entry.corner && !last.corner {
                        *last = entry;
                    }
                }
                _ => kept.push(entry),
            }
        }
        while kept.len() > 3
            && close(&kept[kept.len() - 1], &kept[0])
            && !(kept[kept.len() - 1].corner && kept[0].corner)
        {
            if kept[kept.len() - 1].corner && !kept[0].corner {
                kept.remove(0);
            } else {
                kept.pop();
            }
        }
        l.offset = (kept.iter())
            .map(|e| {
                let x = points.reference[e.point];
                [e.at[0] - x[0], e.at[1] - x[1]]
            })
            .collect();
        l.points = kept.iter().map(|e| e.point).collect();
    }
}

/// The segments of each loop that `selector` picks in the reference
/// configuration, as `(loop index, segments)` for loops with any.
///
/// A point selector picks the segment(s) nearest it ([`nearest_segments`]).
/// Otherwise a segment is picked when both its end data points (reference
/// positions, offsets set) are within a tolerance of the selection:
/// - `on_edge` (the `edge` representation: every data point on the exact
///   edge): a tenth of the segment's length, at most 1.5 domain
///   half-widths. A segment along the selected side is on it to round-off;
///   one that leaves it at a corner is picked only if the corner turns by
///   less than 6 degrees. The tolerance once was 1.5 half-widths alone,
///   which on the long cells of a sliver triangle reached round a corner
///   onto the next side.
/// - through the points: 1.5 domain half-widths, since the data points sit
///   a half-width inside a straight side; round a rectangle's corner the
///   next data point is three half-widths from the selected side, so the
///   selection stops at the corner.
pub fn selected_segments(
    selector: &Selector,
    loops: &[BoundaryLoop],
    points: &MaterialPoints,
    h: f64,
    on_edge: bool,
) -> Vec<(usize, Vec<usize>)> {
    per_loop(loops, points, h, on_edge, |ring, tol| {
        match selector.point() {
            Some(x) => nearest_segments(ring, x, |k| tol.reach(k) + 1e-9 * h),
            None => (0..ring.len())
                .filter(|&k| tol.ends_pass(ring, k, |p, t| selector.contains(p, t)))
                .collect(),
        }
    })
}

/// `pick(reference ring, tolerance)` on every loop, as `(loop index,
/// picked)` for the loops where it picks anything.
fn per_loop<T>(
    loops: &[BoundaryLoop],
    points: &MaterialPoints,
    h: f64,
    on_edge: bool,
    pick: impl Fn(&[[f64; 2]], &SegmentTolerance) -> Vec<T>,
) -> Vec<(usize, Vec<T>)> {
    loops
        .iter()
        .enumerate()
        .filter_map(|(l, lp)| {
            let ring = reference_ring(lp, points);
            let picked = pick(&ring, &SegmentTolerance::new(lp, &ring, points, h, on_edge));
            (!picked.is_empty()).then_some((l, picked))
        })
        .collect()
}

/// The part `t` (parameters on the segment, `t[0] < t[1]`) of one segment
/// of a loop's curve that a selection holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Piece {
    pub segment: usize,
    pub t: [f64; 2],
}

/// The pieces of each loop's reference curve that `selector` picks, as
/// `(loop index, pieces)` for loops with any: [`selected_segments`], except
/// that a selector with ranges (`x_between`, `y_between`, a `segment`'s
/// ends) holds exactly the part of the curve within them. A segment is a
/// candidate when both its ends lie on the selector's lines (to the
/// tolerance of [`selected_segments`]), and its piece runs between the
/// parameters where the curve crosses a range's end (found by sampling and
/// bisection, to round-off). So a stretch ends where the case says, not at
/// the last data point before it: a footing's edge between two data points
/// is where the footing ends.
pub fn selected_pieces(
    selector: &Selector,
    loops: &[BoundaryLoop],
    points: &MaterialPoints,
    h: f64,
    on_edge: bool,
) -> Vec<(usize, Vec<Piece>)> {
    if !selector.has_ranges() || selector.point().is_some() {
        return selected_segments(selector, loops, points, h, on_edge)
            .into_iter()
            .map(|(l, segments)| {
                let whole = |segment| Piece {
                    segment,
                    t: [0.0, 1.0],
                };
                (l, segments.into_iter().map(whole).collect())
            })
            .collect();
    }
    let exact = 1e-9 * h;
    per_loop(loops, points, h, on_edge, |ring, tol| {
        (0..ring.len())
            .filter(|&k| tol.ends_pass(ring, k, |p, t| selector.on_lines(p, t)))
            .flat_map(|k| {
                let segment = curve::local_segment(ring, k);
                let inside = |t: f64| selector.within_ranges(curve::bezier(&segment, t), exact);
                runs(inside)
                    .into_iter()
                    .map(move |t| Piece { segment: k, t })
            })
            .collect()
    })
}

/// Samples per segment when looking for where a selection's range ends.
const RANGE_SAMPLES: usize = 16;

/// The intervals of `[0, 1]` where `inside` holds, ends found by
/// bisection between samples; intervals shorter than 1e-9 are dropped.
fn runs(inside: impl Fn(f64) -> bool) -> Vec<[f64; 2]> {
    let crossing = |mut lo: f64, mut hi: f64| {
        let at_lo = inside(lo);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if inside(mid) == at_lo {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    let mut out = Vec::new();
    let mut start = inside(0.0).then_some(0.0);
    let mut prev = 0.0;
    for i in 1..=RANGE_SAMPLES {
        let t = i as f64 / RANGE_SAMPLES as f64;
        match (start, inside(t)) {
            (None, true) => start = Some(crossing(prev, t)),
            (Some(s), false) => {
                out.push([s, crossing(prev, t)]);
                start = None;
            }
            _ => {}
        }
        prev = t;
    }
    if let Some(s) = start {
        out.push([s, 1.0]);
    }
    out.retain(|[a, b]| b - a > 1e-9);
    out
}

/// How near a selection a segment's end data points must lie for the
/// segment to be picked (see [`selected_segments`]).
struct SegmentTolerance {
    reach: Vec<f64>,
    on_edge: bool,
    round_off: f64,
}

impl SegmentTolerance {
    fn new(
        l: &BoundaryLoop,
        ring: &[[f64; 2]],
        points: &MaterialPoints,
        h: f64,
        on_edge: bool,
    ) -> Self {
        debug_assert_eq!(l.points.len(), ring.len());
        Self {
            reach: (l.points.iter())
                .map(|&p| 1.5 * points.domain[p].reach())
                .collect(),
            on_edge,
            round_off: 1e-9 * h,
        }
    }

    fn reach(&self, k: usize) -> f64 {
        self.reach[k]
    }

    /// Whether both ends of segment `k` pass `test(point, tolerance)`.
    fn ends_pass(&self, ring: &[[f64; 2]], k: usize, test: impl Fn([f64; 2], f64) -> bool) -> bool {
        let j = (k + 1) % ring.len();
        let tol = if self.on_edge {
            self.reach[k]
                .min(self.reach[j])
                .min(0.1 * distance(ring[k], ring[j]))
        } else {
            self.reach[k].min(self.reach[j])
        } + self.round_off;
        test(ring[k], tol) && test(ring[j], tol)
    }
}

/// The segments of a closed `ring` nearest the point `x`, if their chord
/// passes within `tol(k)` of it: one segment when `x` falls inside a chord's
/// span, both segments meeting at a data point when `x` is that data point
/// (to 1e-9 of the ring's scale). A point selects a stretch of boundary about
/// it, wherever the data points fall; asking both ends of a segment to be
/// within `tol` of it, as for lines, selected nothing when a data point sat
/// on the point and its neighbours were a spacing away.
fn nearest_segments(ring: &[[f64; 2]], x: [f64; 2], tol: impl Fn(usize) -> f64) -> Vec<usize> {
    let n = ring.len();
    let distance = |k: usize| {
        let (a, b) = (ring[k], ring[(k + 1) % n]);
        let (d, r) = ([b[0] - a[0], b[1] - a[1]], [x[0] - a[0], x[1] - a[1]]);
        let length2 = d[0] * d[0] + d[1] * d[1];
        let t = if length2 > 0.0 {
            ((r[0] * d[0] + r[1] * d[1]) / length2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (r[0] - t * d[0]).hypot(r[1] - t * d[1])
    };
    let distances: Vec<f64> = (0..n).map(distance).collect();
    let Some(nearest) = distances.iter().copied().reduce(f64::min) else {
        return Vec::new();
    };
    let tie = 1e-9 * tol(0);
    (0..n)
        .filter(|&k| distances[k] <= nearest + tie && distances[k] <= tol(k))
        .collect()
}

/// Current position of a loop's data point `k`: its material point plus
/// the offset mapped by the point's deformation gradient.
pub fn data_point(l: &BoundaryLoop, k: usize, points: &MaterialPoints) -> [f64; 2] {
    let p = l.points[k];
    let x = points.position[p];
    let d = l.offset[k];
    let f = &points.deformation[p];
    [
        x[0] + f[(0, 0)] * d[0] + f[(0, 1)] * d[1],
        x[1] + f[(1, 0)] * d[0] + f[(1, 1)] * d[1],
    ]
}

/// A loop's data points in the reference configuration.
pub fn reference_ring(l: &BoundaryLoop, points: &MaterialPoints) -> Vec<[f64; 2]> {
    l.points
        .iter()
        .zip(&l.offset)
        .map(|(&p, d)| {
            let x = points.reference[p];
            [x[0] + d[0], x[1] + d[1]]
        })
        .collect()
}

/// A loop's data points in the current configuration ([`data_point`]).
pub fn current_ring(l: &BoundaryLoop, points: &MaterialPoints) -> Vec<[f64; 2]> {
    (0..l.points.len())
        .map(|k| data_point(l, k, points))
        .collect()
}

/// Polyline samples per curve segment in the outputs.
const POLYLINE_SAMPLES_PER_SEGMENT: usize = 8;

/// A boundary loop's curve as served: which body, whether it is a hole, the
/// B-spline and a sampled polyline.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct BoundaryOutput {
    pub body: usize,
    pub hole: bool,
    /// Material-point indices the curve interpolates, in order.
    pub points: Vec<usize>,
    pub bspline: BSplineData,
    /// Closed: the last point repeats the first.
    pub polyline: Vec<[f64; 2]>,
}

/// Interpolates every loop through the points' current positions. Loops of
/// fewer than three points (a body of one or two points) are skipped.
pub fn curves(loops: &[BoundaryLoop], points: &MaterialPoints) -> Vec<(usize, ClosedCurve)> {
    loops
        .iter()
        .enumerate()
        .filter(|(_, l)| l.points.len() >= 3)
        .map(|(i, l)| (i, ClosedCurve::interpolate(&current_ring(l, points))))
        .collect()
}

/// The served form of every loop's current curve.
pub fn outputs(loops: &[BoundaryLoop], points: &MaterialPoints) -> Vec<BoundaryOutput> {
    curves(loops, points)
        .into_iter()
        .map(|(i, c)| BoundaryOutput {
            body: loops[i].body,
            hole: loops[i].hole,
            points: loops[i].points.clone(),
            bspline: c.bspline(),
            polyline: c.polyline(POLYLINE_SAMPLES_PER_SEGMENT),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use crate::case::Case;
    use crate::fixtures;
    use crate::stepper::Simulation;

    /// The paper's cantilever (10 m x 2 m) with an IBM fixed point on its
    /// left edge, `count` points, cells of `h`.
    fn pinned_at(y: f64, count: [u32; 2], h: f64) -> Result<Simulation, String> {
        let mut case = fixtures::block([10.0, 2.0], count, h, [0.0, 0.0]);
        case["bodies"][0]["material"]["poisson_ratio"] = 0.25.into();
        case["supports"] = serde_json::json!([
            { "on": { "x": 0.0 }, "fix": "normal", "method": "ibm" },
            { "on": { "x": 0.0, "y": y }, "fix": "xy", "method": "ibm" }
        ]);
        let case = Case::from_json(&case.to_string()).map_err(|e| e.to_string())?;
        Simulation::new(&case).map_err(|e| e.to_string())
    }

    /// The cantilever on 0.75 m cells with 2 points per cell has a data
    /// point at y = 1 on its left edge, with its neighbours 0.4 m away; the
    /// fixed point (0, 1) once selected nothing there ("selects no stretch
    /// of any body's boundary"), and at 0.375 and 0.1875 m too.
    #[test]
    fn a_point_on_a_data_point_selects_the_stretch_about_it() {
        for (h, count) in [(0.75, [27, 5]), (0.375, [53, 11]), (0.1875, [107, 21])] {
            pinned_at(1.0, count, h).unwrap_or_else(|e| panic!("h {h}: {e}"));
        }
    }

    proptest! {
        /// A point selector anywhere on a body's edge selects a stretch,
        /// for any point counts.
        #[test]
        fn a_point_on_the_edge_always_selects_a_stretch(
            y in 0.0..2.0f64, nx in 2u32..60, ny in 2u32..24
        ) {
            prop_assert!(pinned_at(y, [nx, ny], 0.5).is_ok(), "y {} count [{}, {}]", y, nx, ny);
        }
    }
}
