//! The outer layer of a body's material points, ordered into closed loops.
//!
//! Points are generated on a lattice, so a body is a set of lattice cells
//! ("pixels", one per point). The boundary of that set is a chain of unit
//! edges, each with its pixel on the left; following the chain gives the
//! outer loops counter-clockwise and the holes clockwise. The loop of points
//! is the sequence of the edges' pixels with repeats removed. Where two
//! pixels touch only at a corner, the chain turns left, so the pixels stay in
//! separate loops.
//!
//! The loops are found once, in the reference configuration, and kept: the
//! same material points are the boundary at every step (Lagrangian tracking).

use std::collections::HashMap;

use crate::geometry::signed_area;

/// One closed loop of boundary points of a body.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundaryLoop {
    /// Index of the body in the case.
    pub body: usize,
    /// Material-point indices in loop order (material on the left).
    pub points: Vec<usize>,
    /// True for a loop around a hole (clockwise).
    pub hole: bool,
    /// Per data point, the vector in the reference configuration from the
    /// material point to the curve's data point: zero when the curve runs
    /// through the points, out to the edge of the point's domain otherwise
    /// (see [`crate::boundary::Representation`]).
    pub offset: Vec<[f64; 2]>,
}

/// Loops of the pixels at `lattice` (one entry per point, `ids` the points'
/// indices), each as a list of point indices, material on the left.
pub fn loops_of_lattice(lattice: &[[i64; 2]], ids: &[usize]) -> Vec<Vec<usize>> {
    let occupied: HashMap<[i64; 2], usize> =
        lattice.iter().copied().zip(ids.iter().copied()).collect();
    // Directed boundary edges (from, to, point), pixel on the left.
    let mut edges: Vec<([i64; 2], [i64; 2], usize)> = Vec::new();
    for (&[i, j], &p) in lattice.iter().zip(ids) {
        let empty = |di: i64, dj: i64| !occupied.contains_key(&[i + di, j + dj]);
        if empty(0, -1) {
            edges.push(([i, j], [i + 1, j], p));
        }
        if empty(1, 0) {
            edges.push(([i + 1, j], [i + 1, j + 1], p));
        }
        if empty(0, 1) {
            edges.push(([i + 1, j + 1], [i, j + 1], p));
        }
        if empty(-1, 0) {
            edges.push(([i, j + 1], [i, j], p));
        }
    }
    // Deterministic order: start each loop from the lowest unused edge.
    edges.sort_by_key(|e| (e.0[1], e.0[0], e.1[1], e.1[0]));
    let mut outgoing: HashMap<[i64; 2], Vec<usize>> = HashMap::new();
    for (k, e) in edges.iter().enumerate() {
        outgoing.entry(e.0).or_default().push(k);
    }
    let mut used = vec![false; edges.len()];
    let mut loops = Vec::new();
    for start in 0..edges.len() {
        if used[start] {
            continue;
        }
        let mut pixels = Vec::new();
        let mut k = start;
        loop {
            used[k] = true;
            let (from, to, p) = edges[k];
            if pixels.last() != Some(&p) {
                pixels.push(p);
            }
            let dir = [to[0] - from[0], to[1] - from[1]];
            // Of the unused edges leaving `to`, take the leftmost turn.
            let next = outgoing[&to]
                .iter()
                .copied()
                .filter(|&e| !used[e])
                .max_by_key(|&e| {
                    let d = [edges[e].1[0] - edges[e].0[0], edges[e].1[1] - edges[e].0[1]];
                    let cross = dir[0] * d[1] - dir[1] * d[0];
                    let dot = dir[0] * d[0] + dir[1] * d[1];
                    // left (cross > 0) before straight (dot > 0) before right
                    (cross, dot)
                });
            match next {
                Some(e) => k = e,
                None => break, // back at the start
            }
        }
        if pixels.len() > 1 && pixels.first() == pixels.last() {
            pixels.pop();
        }
        loops.push(pixels);
    }
    loops
}

/// Boundary loops of the bodies `b` for which `wanted(b)` holds:
/// `lattice[p]` and `body[p]` per point, `reference[p]` the reference
/// position (for orientation).
pub fn find_loops(
    lattice: &[[i64; 2]],
    body: &[u32],
    reference: &[[f64; 2]],
    wanted: impl Fn(usize) -> bool,
) -> Vec<BoundaryLoop> {
    let n_bodies = body.iter().map(|&b| b as usize + 1).max().unwrap_or(0);
    let mut out = Vec::new();
    for b in (0..n_bodies).filter(|&b| wanted(b)) {
        let ids: Vec<usize> = (0..body.len()).filter(|&p| body[p] as usize == b).collect();
        let cells: Vec<[i64; 2]> = ids.iter().map(|&p| lattice[p]).collect();
        for points in loops_of_lattice(&cells, &ids) {
            let ring: Vec<[f64; 2]> = points.iter().map(|&p| reference[p]).collect();
            let hole = ring.len() >= 3 && signed_area(&ring) < 0.0;
            let offset = vec![[0.0, 0.0]; points.len()];
            out.push(BoundaryLoop {
                body: b,
                points,
                hole,
                offset,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pixels(rows: &[&str]) -> (Vec<[i64; 2]>, Vec<usize>) {
        // rows[0] is the top row; '#' is a point.
        let mut lattice = Vec::new();
        for (r, row) in rows.iter().enumerate() {
            let j = (rows.len() - 1 - r) as i64;
            for (i, c) in row.chars().enumerate() {
                if c == '#' {
                    lattice.push([i as i64, j]);
                }
            }
        }
        let ids = (0..lattice.len()).collect();
        (lattice, ids)
    }

    #[test]
    fn rectangle_gives_one_counter_clockwise_loop_of_its_outer_layer() {
        let (lattice, ids) = pixels(&["####", "####", "####"]);
        let loops = loops_of_lattice(&lattice, &ids);
        assert_eq!(loops.len(), 1);
        // 4 x 3 pixels: 2 (4 + 3) - 4 = 10 on the outer layer, the middle two not.
        assert_eq!(loops[0].len(), 10);
        let ring: Vec<[f64; 2]> = loops[0]
            .iter()
            .map(|&p| lattice[p].map(|c| c as f64))
            .collect();
        assert!(signed_area(&ring) > 0.0);
    }

    #[test]
    fn a_hole_gives_a_clockwise_inner_loop() {
        let (lattice, _) = pixels(&["#####", "#...#", "#...#", "#####"]);
        let reference: Vec<[f64; 2]> = lattice.iter().map(|l| l.map(|c| c as f64)).collect();
        let body = vec![0; lattice.len()];
        let loops = find_loops(&lattice, &body, &reference, |_| true);
        assert_eq!(loops.len(), 2);
        assert_eq!(loops.iter().filter(|l| l.hole).count(), 1);
        // A one-pixel-thick frame of 14 pixels: the outer loop visits all of
        // them, the hole's loop the 10 that share a side with the hole.
        let outer = loops.iter().find(|l| !l.hole).unwrap();
        let inner = loops.iter().find(|l| l.hole).unwrap();
        assert_eq!((outer.points.len(), inner.points.len()), (14, 10));
    }

    #[test]
    fn bodies_touching_at_a_corner_stay_separate_loops() {
        let (lattice, ids) = pixels(&["..##", "..##", "##..", "##.."]);
        let loops = loops_of_lattice(&lattice, &ids);
        assert_eq!(loops.len(), 2);
        assert!(loops.iter().all(|l| l.len() == 4));
    }
}
