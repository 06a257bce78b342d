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

use super::BoundaryLoop;
use crate::particles::MaterialPoints;
use crate::reference_edge::{EdgeIndex, PointIndex, Ring, distance};

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
    let reach = ids
        .iter()
        .map(|&p| points.domain[p].reach())
        .fold(0.0, f64::max);
    let index = EdgeIndex::new(&ring.pieces, 3.0 * reach);
    let starts = ring.starts();
    let corners = ring.corners();
    let corner_index = PointIndex::new(corners.iter().map(|c| c.1).collect(), reach);
    let mut entries = Vec::new();
    let mut owned = vec![false; corners.len()];
    for &p in ids {
        let x = points.reference[p];
        let d = points.domain[p];
        let [a, b] = d.axes;
        // A millionth of the cell, and the rounding of coordinates far from
        // the origin.
        let tol = 1e-6 * d.reach() + 1e-12 * x[0].abs().max(x[1].abs());
        if index.nearest(x, 3.0 * d.reach()).is_none() {
            continue;
        }
        // A corner of the cell on a corner of the edge.
        let mut at_corner = false;
        for (s, t) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let o = [0, 1].map(|k| s * a[k] + t * b[k] + s * t * d.twist[k]);
            let c = [x[0] + o[0], x[1] + o[1]];
            if let Some(k) = corner_index.nearest_within(c, tol) {
                let (arc, corner) = corners[k];
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
            if let Some((k, s, off)) = index.nearest([x[0] + o[0], x[1] + o[1]], 2.0 * tol)
                && off <= tol
            {
                entries.push((starts[k] + s, p, o));
            }
        }
    }
    // Corners no cell has: carried by the point of the nearest data point.
    let at = |e: &(f64, usize, [f64; 2])| {
        let x = points.reference[e.1];
        [x[0] + e.2[0], x[1] + e.2[1]]
    };
    let sides = PointIndex::new(entries.iter().map(at).collect(), reach);
    let mut extra = Vec::new();
    for (k, &(arc, corner)) in corners.iter().enumerate() {
        if owned[k] {
            continue;
        }
        if let Some(nearest) = sides.nearest(corner) {
            let p = entries[nearest].1;
            let x = points.reference[p];
            extra.push((arc, p, [corner[0] - x[0], corner[1] - x[1]]));
        }
    }
    entries.extend(extra);
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
