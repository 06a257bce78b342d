//! Equivalent nodal forces of tractions on the boundary curve,
//! `f_a = int_Gamma N_a t dGamma` (the paper's eq. 2), by Gauss quadrature.
//!
//! The quadrature is [`super::quadrature`]'s: 4 Gauss points on each piece
//! of a segment between grid lines. With the mapping's Jacobian written out, a follower
//! pressure `p` on the current curve has the density `-p (C'_y, -C'_x)` per
//! unit parameter (the outward normal times `|C'|`), a polynomial of degree 2
//! in the parameter; times the bilinear `N_a` on the cubic curve the
//! integrand has degree 8, so 4 points leave an error of the curve's own
//! order. A dead traction `t` has the density `t |C'|`.
//!
//! The shape functions are the bilinear ones, as in the paper. A curve piece in a cell with an
//! inactive corner (rare: the curve bulging past the material's cells) gives
//! that corner's share to the active ones, in proportion.

use super::curve::{Point, bezier, bezier_derivative};
use super::quadrature::{gauss_points, hat_shares, share_nodes};
use crate::grid::{Basis, Grid, NodeKey};

/// What acts on a stretch of boundary.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Traction {
    /// A fixed force per unit current length, `[tx, ty]` (Pa).
    Dead([f64; 2]),
    /// A pressure (Pa, positive pushes into the material) normal to the
    /// current curve: a follower load.
    Pressure(f64),
}

impl Traction {
    /// Force per unit curve parameter, given `dC/dt`.
    fn density(&self, d: Point) -> [f64; 2] {
        match *self {
            Traction::Dead(t) => {
                let speed = (d[0] * d[0] + d[1] * d[1]).sqrt();
                [t[0] * speed, t[1] * speed]
            }
            // -p n |C'| with the outward normal n |C'| = (C'_y, -C'_x)
            Traction::Pressure(p) => [-p * d[1], p * d[0]],
        }
    }

    /// The derivative of [`Traction::density`] by `dC/dt`: entry `[r][s]`
    /// is `d density_r / d C'_s`.
    fn density_derivative(&self, d: Point) -> [[f64; 2]; 2] {
        match *self {
            // A curve at rest at a point (no length there) has no direction
            // to differentiate the length element by.
            Traction::Dead(_) if d == [0.0, 0.0] => [[0.0; 2]; 2],
            Traction::Dead(t) => {
                let speed = (d[0] * d[0] + d[1] * d[1]).sqrt();
                let unit = [d[0] / speed, d[1] / speed];
                [
                    [t[0] * unit[0], t[0] * unit[1]],
                    [t[1] * unit[0], t[1] * unit[1]],
                ]
            }
            Traction::Pressure(p) => [[0.0, -p], [p, 0.0]],
        }
    }
}

/// The derivative of the nodal forces of one node by a segment's four
/// control points: entry `[m][r][s]` is `d f_r / d P_(m, s)`.
pub type ControlPointDerivative = [[[f64; 2]; 2]; 4];

/// The quadrature of one boundary segment in the configuration at the
/// step's start: Gauss points (split at grid lines) with their weights and
/// their shares of the active nodes.
///
/// In a load step the shape functions belong to that configuration: a
/// boundary point moves with `u(X) = sum_a N_a(X) u_a`, so the virtual work
/// of the traction is `sum_a du_a . int N_a(X) t dGamma`. The shape
/// functions and cell crossings are therefore fixed for the step; the
/// segment's current shape (same parameter) only sets the traction's
/// direction and length element. Computed once per step, reused by every
/// Newton iteration and every finite difference of the load stiffness.
#[derive(Debug, Clone, Default)]
pub struct SegmentQuadrature {
    /// `(t, weight)` per Gauss point; its node shares are
    /// `shares[first[q]..first[q + 1]]`.
    points: Vec<(f64, f64)>,
    first: Vec<usize>,
    shares: Vec<(usize, f64)>,
    /// The active nodes the shares are of, sorted, and each share's
    /// node's place among them.
    nodes: Vec<usize>,
    place: Vec<u32>,
}

impl SegmentQuadrature {
    pub fn new(start: &[Point; 4], grid: &Grid, basis: Basis, nodes: &[NodeKey]) -> Self {
        let mut q = SegmentQuadrature {
            first: vec![0],
            ..Default::default()
        };
        let mut weights = Vec::with_capacity(4);
        for (t, w) in gauss_points(start, grid, basis) {
            if !hat_shares(
                basis,
                grid,
                bezier(start, t),
                nodes,
                &mut weights,
                &mut q.shares,
            ) {
                continue;
            }
            q.points.push((t, w));
            q.first.push(q.shares.len());
        }
        (q.nodes, q.place) = share_nodes(&q.shares);
        q
    }

    /// The active nodes the segment's forces reach, sorted: those of
    /// [`SegmentQuadrature::derivative`]'s entries.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    /// The derivative of [`SegmentQuadrature::forces`] by the segment's
    /// control points at `current`, one entry per node of
    /// [`SegmentQuadrature::nodes`] (written over `out`): the quadrature's
    /// own derivative, exact, as `C'` is linear in the control points.
    pub fn derivative(
        &self,
        current: &[Point; 4],
        traction: Traction,
        factor: f64,
        out: &mut Vec<ControlPointDerivative>,
    ) {
        out.clear();
        out.resize(self.nodes.len(), [[[0.0; 2]; 2]; 4]);
        for (i, &(t, w)) in self.points.iter().enumerate() {
            let j = traction.density_derivative(bezier_derivative(current, t));
            // C' = sum_m beta_m P_m (the derivative of the Bernstein basis).
            let s = 1.0 - t;
            let b = [3.0 * s * s, 6.0 * s * t, 3.0 * t * t];
            let beta = [-b[0], b[0] - b[1], b[1] - b[2], b[2]];
            let shares = self.first[i]..self.first[i + 1];
            for (&(_, share), &place) in self.shares[shares.clone()].iter().zip(&self.place[shares])
            {
                let d = &mut out[place as usize];
                let weight = factor * w * share;
                for (dm, beta_m) in d.iter_mut().zip(beta) {
                    for (row, j_row) in dm.iter_mut().zip(&j) {
                        for (entry, j_rs) in row.iter_mut().zip(j_row) {
                            *entry += weight * beta_m * j_rs;
                        }
                    }
                }
            }
        }
    }

    /// The nodal forces of `traction` (scaled by `factor`) on the segment
    /// whose current control points are `current`, passed to `sink` as
    /// `(active node index, force)`.
    pub fn forces(
        &self,
        current: &[Point; 4],
        traction: Traction,
        factor: f64,
        sink: &mut impl FnMut(usize, [f64; 2]),
    ) {
        for (i, &(t, w)) in self.points.iter().enumerate() {
            let density = traction.density(bezier_derivative(current, t));
            for &(a, share) in &self.shares[self.first[i]..self.first[i + 1]] {
                let s = factor * w * share;
                sink(a, [s * density[0], s * density[1]]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::curve::ClosedCurve;
    use crate::grid::node_key;

    /// Adds the nodal forces of `traction`, scaled by `factor`, on `segments`
    /// of `curve` with the bilinear hats; `nodes` are the step's active node keys (sorted), `f` is
    /// indexed `2a + c`.
    fn add_nodal_forces(
        curve: &ClosedCurve,
        segments: &[usize],
        traction: Traction,
        factor: f64,
        grid: &Grid,
        nodes: &[NodeKey],
        f: &mut [f64],
    ) {
        for &k in segments {
            let (ctrl, _, _) = curve.segment(k);
            SegmentQuadrature::new(&ctrl, grid, Basis::Linear, nodes).forces(
                &ctrl,
                traction,
                factor,
                &mut |a, force| {
                    f[2 * a] += force[0];
                    f[2 * a + 1] += force[1];
                },
            );
        }
    }

    /// All nodes of the lattice within `[-r, r]^2` cells, sorted.
    fn all_nodes(r: i64) -> Vec<NodeKey> {
        let mut v: Vec<NodeKey> = (-r..=r)
            .flat_map(|i| (-r..=r).map(move |j| node_key(i, j)))
            .collect();
        v.sort_unstable();
        v
    }

    fn resultant_and_moment(f: &[f64], grid: &Grid, nodes: &[NodeKey]) -> ([f64; 2], f64) {
        let mut r = [0.0; 2];
        let mut m = 0.0;
        for (a, &key) in nodes.iter().enumerate() {
            let x = grid.node_position(key);
            r[0] += f[2 * a];
            r[1] += f[2 * a + 1];
            m += x[0] * f[2 * a + 1] - x[1] * f[2 * a];
        }
        (r, m)
    }

    fn circle(n: usize, r: f64, c: Point) -> Vec<Point> {
        (0..n)
            .map(|k| {
                let a = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                [c[0] + r * a.cos(), c[1] + r * a.sin()]
            })
            .collect()
    }

    #[test]
    fn uniform_pressure_on_a_closed_curve_has_no_resultant_and_no_moment() {
        // int_closed n dGamma = 0 and int_closed x x n dGamma = 0 for any
        // closed curve, and the bilinear shape functions reproduce the
        // integrand's sums exactly (partition of unity, linear
        // reproduction), so both vanish to round-off, for any grid offset.
        for origin in [[0.0, 0.0], [0.137, -0.291], [0.5, 0.5]] {
            let grid = Grid { h: 0.3, origin };
            let nodes = all_nodes(20);
            let curve = ClosedCurve::interpolate(&circle(23, 1.7, [0.31, -0.2]));
            let segments: Vec<usize> = (0..curve.n_segments()).collect();
            let mut f = vec![0.0; 2 * nodes.len()];
            add_nodal_forces(
                &curve,
                &segments,
                Traction::Pressure(1500.0),
                1.0,
                &grid,
                &nodes,
                &mut f,
            );
            let (r, m) = resultant_and_moment(&f, &grid, &nodes);
            assert!(r[0].abs() < 1e-9 && r[1].abs() < 1e-9, "{r:?}");
            assert!(m.abs() < 1e-9, "{m}");
        }
    }

    #[test]
    fn pressure_on_a_straight_edge_gives_pressure_times_length() {
        // A 4 x 2 rectangle's top side from (0, 2) to (4, 2): resultant
        // -p * 4 in y, exactly, wherever the grid lines cut it.
        let data: Vec<Point> = [
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [3.0, 0.0],
            [4.0, 0.0],
            [4.0, 1.0],
            [4.0, 2.0],
            [3.0, 2.0],
            [2.0, 2.0],
            [1.0, 2.0],
            [0.0, 2.0],
            [0.0, 1.0],
        ]
        .to_vec();
        let curve = ClosedCurve::interpolate(&data);
        let top: Vec<usize> = (6..10).collect();
        for origin in [[0.0, 0.0], [0.123, 0.456], [-0.31, 0.77]] {
            let grid = Grid { h: 0.7, origin };
            let nodes = all_nodes(12);
            let mut f = vec![0.0; 2 * nodes.len()];
            add_nodal_forces(
                &curve,
                &top,
                Traction::Pressure(10.0),
                1.0,
                &grid,
                &nodes,
                &mut f,
            );
            let (r, m) = resultant_and_moment(&f, &grid, &nodes);
            assert!((r[1] + 40.0).abs() < 1e-11 && r[0].abs() < 1e-11, "{r:?}");
            // Its line of action is x = 2: moment about the origin -40 * 2.
            assert!((m + 80.0).abs() < 1e-10, "{m}");
        }
    }

    #[test]
    fn dead_traction_integrates_length() {
        // A dead traction t on a circle of radius R: resultant t 2 pi R, up
        // to the curve's length error (1e-6 relative for 64 points).
        let curve = ClosedCurve::interpolate(&circle(64, 1.0, [0.0, 0.0]));
        let segments: Vec<usize> = (0..curve.n_segments()).collect();
        let grid = Grid {
            h: 0.25,
            origin: [0.05, 0.02],
        };
        let nodes = all_nodes(10);
        let mut f = vec![0.0; 2 * nodes.len()];
        add_nodal_forces(
            &curve,
            &segments,
            Traction::Dead([0.0, -3.0]),
            1.0,
            &grid,
            &nodes,
            &mut f,
        );
        let (r, _) = resultant_and_moment(&f, &grid, &nodes);
        let exact = -3.0 * 2.0 * std::f64::consts::PI;
        assert!(
            (r[1] - exact).abs() < 1e-6 * exact.abs(),
            "{} vs {exact}",
            r[1]
        );
    }
}
