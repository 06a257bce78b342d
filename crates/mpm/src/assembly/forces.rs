//! Internal and body forces on the active nodes.

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
