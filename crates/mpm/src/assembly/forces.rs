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

/// The loads that do not move with the body, scaled by the load factor:
/// gravity `g` on every point's mass and each `(point, force)` of
/// `point_loads` on its point's nodes.
pub fn external_force(
    conn: &Connectivity,
    points: &MaterialPoints,
    gravity: [f64; 2],
    point_loads: &[(usize, [f64; 2])],
    load_factor: f64,
) -> Vec<f64> {
    let g = gravity.map(|g| g * load_factor);
    let mut f = if g == [0.0, 0.0] {
        vec![0.0; conn.n_dofs()]
    } else {
        body_force(conn, points, g)
    };
    for &(p, force) in point_loads {
        for l in conn.point_links(p) {
            for c in 0..2 {
                f[2 * l.node as usize + c] += load_factor * l.n * force[c];
            }
        }
    }
    f
}
