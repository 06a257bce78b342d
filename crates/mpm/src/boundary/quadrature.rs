//! Quadrature along the boundary curve, shared by tractions and the
//! implicit boundary method's band: each Bezier segment is split where it
//! crosses a knot line of the shape functions (the grid lines; for
//! quadratic B-splines the cell middles too), so every piece sees smooth
//! shape functions, and each piece gets 4-point Gauss-Legendre quadrature
//! in the segment parameter.
//!
//! The shape functions there are the bilinear finite-element hats for the
//! linear basis and for GIMP (whose cell averages would reach across the
//! boundary), and the B-splines themselves for the B-spline bases: their
//! nodal values are coefficients, not the field's values, so a load or a
//! constraint given to the hats would act on another field (and leave the
//! outer ring of nodes, which the hats never reach, unbalanced).

use super::curve::{Point, bezier};
use crate::grid::{Basis, Grid, NodeKey, NodeWeight, Support};

/// Gauss-Legendre nodes on [0, 1] and weights (summing to 1), 4 points.
const GAUSS4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_87, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

/// Samples per segment when looking for grid-line crossings; a cubic segment
/// spanning about one point spacing crosses at most a few lines.
const CROSSING_SAMPLES: usize = 16;

/// The shape functions the boundary uses with `basis` (see the module).
fn boundary_basis(basis: Basis) -> Basis {
    match basis {
        Basis::Linear | Basis::Gimp => Basis::Linear,
        b => b,
    }
}

/// Appends to `shares` the active nodes' boundary shape functions at `x`
/// as `(active node index, N)` and returns their sum, which is below one
/// where some of their nodes are inactive. `weights` is scratch space.
pub fn active_hats<const D: usize>(
    basis: Basis,
    grid: &Grid<D>,
    x: [f64; D],
    nodes: &[NodeKey],
    weights: &mut Vec<NodeWeight<D>>,
    shares: &mut Vec<(usize, f64)>,
) -> f64 {
    weights.clear();
    boundary_basis(basis).eval(grid, x, Support::Rectangle([0.0; D]), weights);
    let before = shares.len();
    shares.extend(
        weights
            .iter()
            .filter_map(|nw| nodes.binary_search(&nw.node).ok().map(|a| (a, nw.n))),
    );
    shares[before..].iter().map(|(_, n)| n).sum()
}

/// [`active_hats`] normalised to sum to one (a point on the edge of the
/// active cells may touch an inactive node with a zero or round-off share).
/// Returns false, appending nothing, when no active node has a share.
pub fn hat_shares<const D: usize>(
    basis: Basis,
    grid: &Grid<D>,
    x: [f64; D],
    nodes: &[NodeKey],
    weights: &mut Vec<NodeWeight<D>>,
    shares: &mut Vec<(usize, f64)>,
) -> bool {
    let before = shares.len();
    let total = active_hats(basis, grid, x, nodes, weights, shares);
    if total <= 0.0 {
        shares.truncate(before);
        return false;
    }
    for share in &mut shares[before..] {
        share.1 /= total;
    }
    true
}

/// `(t, weight in t)` of four Gauss points on each piece of the segment
/// between knot lines: the integrands (products of the shape functions and
/// the curve's smooth terms) are smooth on each piece.
pub fn gauss_points(
    ctrl: &[Point; 4],
    grid: &Grid,
    basis: Basis,
) -> impl Iterator<Item = (f64, f64)> {
    gauss_points_between(ctrl, grid, basis, [0.0, 1.0])
}

/// [`gauss_points`] on the part `range` of the segment's parameter: the
/// pieces between knot lines clipped to it, so a stretch that ends inside
/// a cell is integrated to its end and no further.
pub fn gauss_points_between(
    ctrl: &[Point; 4],
    grid: &Grid,
    basis: Basis,
    range: [f64; 2],
) -> impl Iterator<Item = (f64, f64)> {
    // Quadratic B-splines centred on the nodes have knots at the cells'
    // middles as well as on the grid lines.
    let knots = match basis {
        Basis::BSpline2 => Grid {
            h: grid.h / 2.0,
            origin: grid.origin,
        },
        _ => *grid,
    };
    let mut cuts: Vec<f64> = cell_crossings(ctrl, &knots)
        .into_iter()
        .filter(|&t| t > range[0] && t < range[1])
        .collect();
    cuts.insert(0, range[0]);
    cuts.push(range[1]);
    (1..cuts.len()).flat_map(move |i| {
        let (t0, t1) = (cuts[i - 1], cuts[i]);
        GAUSS4
            .iter()
            .map(move |&(xi, w)| (t0 + xi * (t1 - t0), w * (t1 - t0)))
    })
}

/// Parameters `0 = t_0 < ... < t_m = 1` where the segment crosses grid
/// lines, found by sampling and bisection.
fn cell_crossings(ctrl: &[Point; 4], grid: &Grid) -> Vec<f64> {
    let cell = |t: f64| grid.cell_of(bezier(ctrl, t));
    let mut out = vec![0.0];
    let mut prev = 0.0;
    for i in 1..=CROSSING_SAMPLES {
        let t = i as f64 / CROSSING_SAMPLES as f64;
        if cell(t) != cell(prev) {
            let (mut lo, mut hi) = (prev, t);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if cell(mid) == cell(lo) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            out.push(0.5 * (lo + hi));
        }
        prev = t;
    }
    out.push(1.0);
    out
}

/// The nodes of a quadrature's `shares` (`(node, share)`), sorted, and
/// each share's node's place among them.
pub fn share_nodes(shares: &[(usize, f64)]) -> (Vec<usize>, Vec<u32>) {
    let mut nodes: Vec<usize> = shares.iter().map(|&(a, _)| a).collect();
    nodes.sort_unstable();
    nodes.dedup();
    let place = (shares.iter())
        .map(|(a, _)| nodes.binary_search(a).expect("a share's node") as u32)
        .collect();
    (nodes, place)
}
