//! Boundary loops of bodies whose points are not one lattice (polygons cut
//! into mapped patches, meshes, full polar rings), found from the exact
//! edge the case gives rather than from lattice neighbours.
//!
//! The points' cells tile the body, so the cells along the edge have a side
//! on it. Each such side gives a data point at its middle, carried by the
//! cell's material point; a corner of the edge is a data point too, carried
//! by the cell that has it as a corner (or, failing one, by the point of
//! the nearest data point). Sorted by arc length along their ring, they are
//! the loop: the material on the left, outer rings counter-clockwise and
//! holes clockwise, as [`super::detection`] gives them. A cell with a
//! corner on an edge corner gives that corner only, as a lattice's corner
//! point does, so a rectangle's loop is the same either way.

use std::collections::HashMap;

use super::BoundaryLoop;
use crate::particles::MaterialPoints;
use crate::reference_edge::{EdgePiece, Ring, distance};

/// The loops of body `body`, whose points are `ids`, on the rings of its
/// geometry's edge. A ring that no cell reaches (thinner than its points)
/// gives no loop.
pub fn loops_on_edge(
    body: usize,
    rings: &[Ring],
    points: &MaterialPoints,
    ids: &[usize],
) -> Vec<BoundaryLoop> {
    rings
        .iter()
        .filter_map(|ring| {
            let l = ring_loop(ring, points, ids);
            (l.len() >= 3).then(|| BoundaryLoop {
                body,
                points: l.iter().map(|e| e.1).collect(),
                hole: ring.hole,
                offset: l.iter().map(|e| e.2).collect(),
            })
        })
        .collect()
}

/// The data points on one ring as `(arc length, point, offset)`, in order.
fn ring_loop(ring: &Ring, points: &MaterialPoints, ids: &[usize]) -> Vec<(f64, usize, [f64; 2])> {
    let index = PieceIndex::new(&ring.pieces);
    let corners = ring.corners();
    let mut entries = Vec::new();
    let mut owned = vec![false; corners.len()];
    for &p in ids {
        let x = points.reference[p];
        let d = points.domain[p];
        let [a, b] = d.axes;
        let tol = 1e-6 * d.reach();
        if !index.near(x, 3.0 * d.reach()) {
            continue;
        }
        // A corner of the cell on a corner of the edge.
        let mut at_corner = false;
        for (s, t) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let o = [0, 1].map(|k| s * a[k] + t * b[k] + s * t * d.twist[k]);
            let c = [x[0] + o[0], x[1] + o[1]];
            for (k, &(arc, corner)) in corners.iter().enumerate() {
                if !owned[k] && distance(c, corner) <= tol {
                    owned[k] = true;
                    at_corner = true;
                    entries.push((arc, p, o));
                }
            }
        }
        if at_corner {
            continue;
        }
        for o in [a, [-a[0], -a[1]], b, [-b[0], -b[1]]] {
            let (arc, off) = ring.locate([x[0] + o[0], x[1] + o[1]]);
            if off <= tol {
                entries.push((arc, p, o));
            }
        }
    }
    // Corners no cell has: carried by the point of the nearest data point.
    let sides = entries.clone();
    for (k, &(arc, corner)) in corners.iter().enumerate() {
        if owned[k] {
            continue;
        }
        let nearest = sides.iter().min_by(|e, f| {
            let at = |e: &(f64, usize, [f64; 2])| {
                let x = points.reference[e.1];
                distance([x[0] + e.2[0], x[1] + e.2[1]], corner)
            };
            at(e).total_cmp(&at(f))
        });
        if let Some(&(_, p, _)) = nearest {
            let x = points.reference[p];
            entries.push((arc, p, [corner[0] - x[0], corner[1] - x[1]]));
        }
    }
    entries.sort_by(|e, f| e.0.total_cmp(&f.0));
    // Two cells' sides cannot share a middle; a corner can meet a side's
    // middle only on a cell one side long: keep the corner.
    let length = ring.length();
    let mut out: Vec<(f64, usize, [f64; 2])> = Vec::with_capacity(entries.len());
    for e in entries {
        match out.last() {
            Some(last) if e.0 - last.0 <= 1e-9 * length => {}
            _ => out.push(e),
        }
    }
    out
}

/// The pieces of a ring bucketed by their bounding boxes, so that asking
/// whether a point is near the edge costs a few pieces, not all of a
/// mesh's boundary.
struct PieceIndex<'a> {
    pieces: &'a [EdgePiece],
    size: f64,
    buckets: HashMap<(i64, i64), Vec<usize>>,
}

impl<'a> PieceIndex<'a> {
    fn new(pieces: &'a [EdgePiece]) -> Self {
        let boxes: Vec<([f64; 2], [f64; 2])> = pieces.iter().map(bounding_box).collect();
        let size = boxes
            .iter()
            .map(|(lo, hi)| (hi[0] - lo[0]).max(hi[1] - lo[1]))
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let mut buckets: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        for (k, (lo, hi)) in boxes.iter().enumerate() {
            let (i0, j0) = key(*lo, size);
            let (i1, j1) = key(*hi, size);
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

    /// Whether some piece passes within `radius` of `x`.
    fn near(&self, x: [f64; 2], radius: f64) -> bool {
        let reach = (radius / self.size).ceil() as i64 + 1;
        let (i, j) = key(x, self.size);
        (i - reach..=i + reach).any(|a| {
            (j - reach..=j + reach).any(|b| {
                self.buckets.get(&(a, b)).is_some_and(|ks| {
                    ks.iter()
                        .any(|&k| distance(x, self.pieces[k].nearest(x)) <= radius)
                })
            })
        })
    }
}

fn key(x: [f64; 2], size: f64) -> (i64, i64) {
    ((x[0] / size).floor() as i64, (x[1] / size).floor() as i64)
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
