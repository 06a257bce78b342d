//! Internal and external forces on the active nodes.

use nalgebra::Matrix2;

use super::scatter_sum;
use crate::grid::Connectivity;
use crate::particles::MaterialPoints;

/// Internal force `f_a = sum_p V0_p P_p g_pa` over all active DOFs, with
/// `stress(p)` point `p`'s `P_p`, asked for once.
pub fn internal_force(
    conn: &Connectivity,
    points: &MaterialPoints,
    stress: impl Fn(usize) -> Matrix2<f64> + Sync,
) -> Vec<f64> {
    scatter_sum(conn.n_points(), conn.n_dofs(), |p, f| {
        let v0 = points.volume0[p];
        let pk = &stress(p);
        for l in conn.point_links(p) {
            let a = 2 * l.node as usize;
            f[a] += v0 * (pk[(0, 0)] * l.grad[0] + pk[(0, 1)] * l.grad[1]);
            f[a + 1] += v0 * (pk[(1, 0)] * l.grad[0] + pk[(1, 1)] * l.grad[1]);
        }
    })
}

/// Body force `f_a = sum_p m_p N_pa g`.
pub fn body_force(conn: &Connectivity, points: &MaterialPoints, gravity: [f64; 2]) -> Vec<f64> {
    scatter_sum(conn.n_points(), conn.n_dofs(), |p, f| {
        let m = points.mass[p];
        for l in conn.point_links(p) {
            let a = 2 * l.node as usize;
            f[a] += m * l.n * gravity[0];
            f[a + 1] += m * l.n * gravity[1];
        }
    })
}

/// A dead force (N per metre) on a material point: held at its full value
/// through the stage, or ramped with the load factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointLoad {
    pub point: usize,
    pub force: [f64; 2],
    pub held: bool,
}

/// The loads that do not move with the body: gravity `g = held + t
/// ramped` (`gravity = [held, ramped]`, `t` the load factor) on every
/// point's mass and each point load, held or scaled by `t`, on its point's
/// nodes.
pub fn external_force(
    conn: &Connectivity,
    points: &MaterialPoints,
    gravity: [[f64; 2]; 2],
    point_loads: &[PointLoad],
    load_factor: f64,
) -> Vec<f64> {
    let [held, ramped] = gravity;
    let g = [0, 1].map(|c| held[c] + ramped[c] * load_factor);
    let mut f = if g == [0.0, 0.0] {
        vec![0.0; conn.n_dofs()]
    } else {
        body_force(conn, points, g)
    };
    for load in point_loads {
        let factor = if load.held { 1.0 } else { load_factor };
        for l in conn.point_links(load.point) {
            for c in 0..2 {
                f[2 * l.node as usize + c] += factor * l.n * load.force[c];
            }
        }
    }
    f
}

/// The derivative of [`external_force`] by the load factor: the ramped
/// gravity on every point's mass and the ramped point loads.
pub fn external_force_rate(
    conn: &Connectivity,
    points: &MaterialPoints,
    gravity: [[f64; 2]; 2],
    point_loads: &[PointLoad],
) -> Vec<f64> {
    let ramped = [[0.0; 2], gravity[1]];
    let ramped_loads: Vec<PointLoad> = point_loads.iter().filter(|l| !l.held).cloned().collect();
    external_force(conn, points, ramped, &ramped_loads, 1.0)
}
