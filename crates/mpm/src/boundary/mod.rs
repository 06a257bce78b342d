//! The material boundary: the outer layer of material points, ordered into
//! loops once ([`detection`]), interpolated by a local cubic B-spline after
//! every step ([`bspline`]).

pub mod bspline;
pub mod detection;
pub mod ibm;
pub mod loading;
pub mod quadrature;
pub mod traction;

use serde::{Deserialize, Serialize};

pub use bspline::{BSplineData, ClosedCurve};
pub use detection::{BoundaryLoop, find_loops};

use crate::geometry::Selector;
use crate::particles::MaterialPoints;

/// Where the boundary curve's data points are.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
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
                    bspline::data_normals(&ring)
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

/// The segments of each loop that `selector` picks in the reference
/// configuration, as `(loop index, segments)` for loops with any: a segment
/// is picked when both its end data points (reference positions, offsets
/// set) are within 1.5 domain half-widths of the selection: the material
/// edge's data points lie on a straight selected side, and within about a
/// half-width of a curved edge filled on a Cartesian lattice; through the
/// points they sit a half-width inside a straight side. Round a rectangle's
/// corner the next data point is two half-widths (edge) or three (points)
/// from the selected side, so the selection stops at the corner.
pub fn selected_segments(
    selector: &Selector,
    loops: &[BoundaryLoop],
    points: &MaterialPoints,
    h: f64,
) -> Vec<(usize, Vec<usize>)> {
    loops
        .iter()
        .enumerate()
        .filter_map(|(l, lp)| {
            let n = lp.points.len();
            let ring = reference_ring(lp, points);
            let on = |k: usize| {
                let reach = points.domain[lp.points[k]].reach();
                selector.contains(ring[k], 1.5 * reach + 1e-9 * h)
            };
            let segments: Vec<usize> = (0..n).filter(|&k| on(k) && on((k + 1) % n)).collect();
            (!segments.is_empty()).then_some((l, segments))
        })
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
