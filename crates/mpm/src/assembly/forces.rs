//! Internal and external forces on the active nodes, in `D` dimensions
//! (node `a`'s components at `D a .. D a + D`).

use nalgebra::SMatrix;

use super::scatter_sum;
use crate::grid::Connectivity;
use crate::particles::{Dim, MaterialPoints, Space};

/// Internal force `f_a = sum_p V0_p P_p g_pa` over all active DOFs, with
/// `stress(p)` point `p`'s `P_p`, asked for once.
pub fn internal_force<const D: usize>(
    conn: &Connectivity<D>,
    points: &MaterialPoints<D>,
    stress: impl Fn(usize) -> SMatrix<f64, D, D> + Sync,
) -> Vec<f64>
where
    Dim<D>: Space<D>,
{
    scatter_sum(conn.n_points(), conn.n_dofs(), |p, f| {
        let v0 = points.volume0[p];
        let pk = &stress(p);
        for l in conn.point_links(p) {
            let a = D * l.node as usize;
            for i in 0..D {
                // Summed from the first term: in 2D, P_i0 g_0 + P_i1 g_1.
                let mut sum = pk[(i, 0)] * l.grad[0];
                for k in 1..D {
                    sum += pk[(i, k)] * l.grad[k];
                }
                f[a + i] += v0 * sum;
            }
        }
    })
}

/// Body force `f_a = sum_p m_p N_pa g`.
pub fn body_force<const D: usize>(
    conn: &Connectivity<D>,
    points: &MaterialPoints<D>,
    gravity: [f64; D],
) -> Vec<f64>
where
    Dim<D>: Space<D>,
{
    scatter_sum(conn.n_points(), conn.n_dofs(), |p, f| {
        let m = points.mass[p];
        for l in conn.point_links(p) {
            let a = D * l.node as usize;
            for i in 0..D {
                f[a + i] += m * l.n * gravity[i];
            }
        }
    })
}

/// A dead force (N per metre in 2D, N in 3D) on a material point: held at
/// its full value through the stage, or ramped with the load factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointLoad<const D: usize = 2> {
    pub point: usize,
    pub force: [f64; D],
    pub held: bool,
}

/// The loads that do not move with the body: gravity `g = held + t
/// ramped` (`gravity = [held, ramped]`, `t` the load factor) on every
/// point's mass and each point load, held or scaled by `t`, on its point's
/// nodes.
pub fn external_force<const D: usize>(
    conn: &Connectivity<D>,
    points: &MaterialPoints<D>,
    gravity: [[f64; D]; 2],
    point_loads: &[PointLoad<D>],
    load_factor: f64,
) -> Vec<f64>
where
    Dim<D>: Space<D>,
{
    let [held, ramped] = gravity;
    let g: [f64; D] = std::array::from_fn(|c| held[c] + ramped[c] * load_factor);
    let mut f = if g == [0.0; D] {
        vec![0.0; conn.n_dofs()]
    } else {
        body_force(conn, points, g)
    };
    for load in point_loads {
        let factor = if load.held { 1.0 } else { load_factor };
        for l in conn.point_links(load.point) {
            for c in 0..D {
                f[D * l.node as usize + c] += factor * l.n * load.force[c];
            }
        }
    }
    f
}

/// The derivative of [`external_force`] by the load factor: the ramped
/// gravity on every point's mass and the ramped point loads.
pub fn external_force_rate<const D: usize>(
    conn: &Connectivity<D>,
    points: &MaterialPoints<D>,
    gravity: [[f64; D]; 2],
    point_loads: &[PointLoad<D>],
) -> Vec<f64>
where
    Dim<D>: Space<D>,
{
    let ramped = [[0.0; D], gravity[1]];
    let ramped_loads: Vec<PointLoad<D>> = point_loads.iter().filter(|l| !l.held).cloned().collect();
    external_force(conn, points, ramped, &ramped_loads, 1.0)
}

#[cfg(test)]
mod tests {
    use nalgebra::Matrix3;

    use super::*;
    use crate::fixtures;
    use crate::grid::Basis;
    use crate::material::{Elastic, Material};

    /// In 3D, on GIMP over a grid offset from a box of points: gravity's
    /// nodal forces add up to the weight, and a uniform stress `P` gives
    /// internal forces with no resultant whose first moment
    /// `sum_a f_a,i x_a,k` is `V P_ik` (the shape functions' partition of
    /// unity and their reproduction of `x`), to round-off.
    #[test]
    fn three_dimensional_forces_add_up_to_the_weight_and_the_stress() {
        let (points, grid) = fixtures::solid_box([0.1, 0.2, 0.3], [1.1, 0.7, 0.8], 0.125, 0.25);
        let conn = fixtures::solid_links(&points, &grid, Basis::Gimp);
        let g = [0.5, -2.0, -9.81];
        let weight = body_force(&conn, &points, g);
        let mass: f64 = points.mass.iter().sum();
        for i in 0..3 {
            let sum: f64 = weight.iter().skip(i).step_by(3).sum();
            assert!(
                (sum - mass * g[i]).abs() < 1e-10 * mass * 10.0,
                "{i}: {sum}"
            );
        }
        let p = Matrix3::new(3.0, 1.0, -2.0, 0.5, -4.0, 1.5, 2.5, -1.0, 6.0) * 1e3;
        let f = internal_force(&conn, &points, |_| p);
        let volume: f64 = points.volume0.iter().sum();
        for i in 0..3 {
            let resultant: f64 = f.iter().skip(i).step_by(3).sum();
            assert!(resultant.abs() < 1e-9 * p.norm(), "{i}: {resultant}");
            for k in 0..3 {
                let moment: f64 = conn
                    .nodes
                    .iter()
                    .enumerate()
                    .map(|(a, &key)| f[3 * a + i] * grid.node_position(key)[k])
                    .sum();
                assert!(
                    (moment - volume * p[(i, k)]).abs() < 1e-9 * p.norm(),
                    "{i}{k}: {moment}"
                );
            }
        }
    }

    /// The 3D patch test through the grid: nodal displacements of a
    /// homogeneous deformation, `u_a = (F - I) x_a`, give every point of
    /// a box on an offset grid the increment `F - I` to round-off, on each
    /// basis (the functions reproduce linear fields), so every point has
    /// the model's stress at `F`: the same for all, a Mohr-Coulomb soil past
    /// yield included.
    #[test]
    fn a_homogeneous_deformation_reaches_every_point_in_three_dimensions() {
        use crate::grid::increment;
        use crate::material::{History3, MohrCoulomb};
        let (mut points, grid) = fixtures::solid_box([0.1, 0.2, 0.3], [1.1, 0.7, 0.8], 0.125, 0.25);
        let soil = Material::MohrCoulomb(MohrCoulomb {
            elastic: Elastic::from_young_poisson(1e7, 0.3),
            cohesion: 1e3,
            friction: 30f64.to_radians(),
            dilation: 5f64.to_radians(),
        });
        points.materials[0] = soil;
        let grad_u = Matrix3::new(-2e-3, 1e-3, 0.0, 5e-4, 1.5e-3, -1e-3, 0.0, 2e-3, -3e-3);
        let reference = soil.respond_3d(&History3::virgin(), &grad_u, 1.0);
        assert!(reference.history.plastic_strain > 0.0);
        for basis in [Basis::Linear, Basis::Gimp, Basis::BSpline2, Basis::BSpline3] {
            let conn = fixtures::solid_links(&points, &grid, basis);
            let u: Vec<f64> = conn
                .nodes
                .iter()
                .flat_map(|&key| {
                    let x = grid.node_position(key);
                    let v = grad_u * nalgebra::Vector3::from(x);
                    [v[0], v[1], v[2]]
                })
                .collect();
            for p in 0..points.len() {
                let (dx, g) = increment(conn.point_links(p), &u);
                let x = nalgebra::Vector3::from(points.position[p]);
                assert!((g - grad_u).norm() < 1e-13, "{basis:?} point {p}: {g}");
                assert!(
                    (nalgebra::Vector3::from(dx) - grad_u * x).norm() < 1e-13,
                    "{basis:?}"
                );
                let r = soil.respond_3d(&points.history[p], &g, 1.0);
                assert!((r.cauchy - reference.cauchy).norm() < 1e-8 * reference.cauchy.norm());
            }
        }
    }
}
