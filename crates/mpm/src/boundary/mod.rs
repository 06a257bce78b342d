//! The material boundary: the outer layer of material points, ordered into
//! loops once ([`detection`]), interpolated by a local cubic B-spline after
//! every step ([`bspline`]).

pub mod bspline;
pub mod detection;

use serde::Serialize;

pub use bspline::{BSplineData, ClosedCurve};
pub use detection::{BoundaryLoop, find_loops};

use crate::points::MaterialPoints;

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
        .map(|(i, l)| {
            let ring: Vec<[f64; 2]> = l.points.iter().map(|&p| points.position[p]).collect();
            (i, ClosedCurve::interpolate(&ring))
        })
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
