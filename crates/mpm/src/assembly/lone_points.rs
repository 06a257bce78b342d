//! Physical hourglass stabilisation of bodies seeded one point a cell: the
//! bending a single point cannot feel, restored with the material's own
//! stiffness (docs/one_point_cells.md has the derivation, the literature
//! and the prototype).
//!
//! A point carries one stress, so it restrains only the mean strain over
//! its domain. With one point a cell the rest of the grid field is free:
//! the bilinear cell's hourglass modes `u ∝ (x - x_c)(y - y_c)`, GIMP's
//! zigzags where domains straddle grid lines, the B-splines'
//! checkerboards. A beam one point a cell deep then has almost no bending
//! stiffness, and Newton wanders in the near-null modes.
//!
//! The term is Belytschko & Bindeman's assumed-strain stabilisation
//! (1991, CMAME 88, "ASQBI"; Belytschko, Liu & Moran, *Nonlinear Finite
//! Elements*, ch. 8) written for a point's domain instead of an element.
//! It measures the six slopes of the step's strain increment across the
//! domain, `e = [eps_xx in x, eps_xx in y, eps_yy in x, eps_yy in y,
//! gamma_xy in x, gamma_xy in y]`, with the basis's 1D moments
//! ([`crate::grid::Basis::moments_1d`]: averages `a`, `b` of value and
//! gradient, slopes `c`, `d`; node `(i, j)`):
//!
//! | slope | on `u_x` | on `u_y` | weight |
//! |---|---|---|---|
//! | `eps_xx` in x | `d_i a_j` | | `l_x^2/3` |
//! | `eps_xx` in y (bending) | `b_i c_j` | | `l_y^2/3` |
//! | `eps_yy` in x (bending) | | `c_i b_j` | `l_x^2/3` |
//! | `eps_yy` in y | | `a_i d_j` | `l_y^2/3` |
//! | `gamma_xy` in x | `c_i b_j` (B-splines) | `d_i a_j` | `l_x^2/3` |
//! | `gamma_xy` in y | `a_i d_j` | `b_i c_j` (B-splines) | `l_y^2/3` |
//!
//! with `l` the domain's half-widths. On the hats (bilinear, GIMP) the
//! shear strain's slopes leave out `d2u_x/dxdy` and `d2u_y/dxdy`: they are
//! the bilinear field's parasitic shear in bending, which ASQBI removes.
//! The moduli `M` take the strain's slopes to the stress's, `T = M e`
//! ([`moduli`]): on the hats ASQBI's, `E' = 4 mu (lambda + mu) / (lambda +
//! 2 mu) = 2 mu / (1 - nu)` on each normal strain's slope and `mu` on the
//! shear strain's, so that on the bilinear basis (where only the bending
//! slopes are not zero inside a cell) a rectangle bends exactly and does
//! not lock near incompressibility; on the B-splines, which hold a bending
//! field exactly, an energy that a true plane-strain bending field (its
//! Poisson slope and zero shear-strain slopes) meets with the beam's `E'
//! kappa^2 / 2`, with moduli that stay bounded as `nu` nears 1/2 (`E' <= 4
//! mu`, `nu' <= 1`), so nothing locks. `T` is the stress's slope on a
//! bending field along the grid's axes, not in general: `M` is not
//! isotropic (on a square domain at `nu = 0.3` a bending field turned 45
//! degrees costs 9% less than `E' kappa^2 / 2`), yet `T` is turned as a
//! third-order tensor. GIMP's domains across grid lines keep the hats'
//! slopes and so still see a bending field's Poisson slope and
//! `d2u_y/dx2` (docs/one_point_cells.md, section 6).
//!
//! Point `p`'s potential in a step is `V_p sum_k w_k (T_k e_k + e_k (M
//! e)_k / 2)`: force `V w (T + M e) g`, tangent `V w M g g^T`, symmetric
//! and exact. Every slope is zero on an affine increment (a rigid rotation
//! included), so the patch tests hold. Once the step converges, the stored
//! slopes `T` ([`crate::particles::MaterialPoints::stress_slopes`]) take
//! their increment `M e` and turn with the step's rotation as the
//! components of `dsigma_ij/dx_k`.
//!
//! It acts on the points seeded one a cell or fewer (a reference volume of
//! at least [`LONE_VOLUME`] of a cell's), for the whole run. Two or more
//! points a cell restrain the modes themselves, and their results are
//! untouched. Counting the points in each cell at every step instead lost
//! the bending held by points that met another point in a cell (a clamped
//! elastica at one point a cell, GIMP at h = 0.25: 8.4% off in `u_x`
//! against 4.1%), and changed cases of two points a cell whose edge cells
//! hold one. A domain that is not an upright rectangle is measured on the
//! upright rectangle of its area and of its bounding box's proportions.
//!
//! It acts on the elastic materials only. Its stress slopes are elastic,
//! and a plastic point's would have to stay within its strength across
//! its domain, which is not built. Tried on the undrained footing one
//! point a cell (h = B/8, 0.01 B; exact `N_c` 5.142): a yielded point
//! lending a fifth of its moduli, as to the ghost penalty, carried 8.32 c;
//! yielded points left out with their slopes dropped, 5.175 c, but the
//! von Mises beam in pure bending (`hinge.rs`, one point a cell) then
//! overshot its plastic moment by 2-4% where its points began to flow,
//! and at one grid placement failed once their slopes were dropped.
//! Without it those plastic cases at one point a cell come to 5.136 c and
//! 0.999 `M_p`: collapse needs no hourglass control there, their elastic
//! bending does.

use nalgebra::{Matrix2, Matrix3, Vector3};
use rayon::prelude::*;

use super::{Pattern, Side, StepTerm};
use crate::configuration::Configuration;
use crate::grid::basis::quadrilateral_domain;
use crate::grid::{Basis, LatticeIndex, Support, node_coordinates};
use crate::parallel;

/// A point is stabilised when its reference volume is at least this
/// share of a cell's: a body seeded with fewer than two points a cell.
pub const LONE_VOLUME: f64 = 0.5;

/// The direction each slope is taken in (0: x, 1: y), in the order of
/// [`crate::particles::MaterialPoints::stress_slopes`]: `[xx,x; xx,y;
/// yy,x; yy,y; xy,x; xy,y]`.
const ACROSS: [usize; 6] = [0, 1, 0, 1, 0, 1];

/// A node's coefficients in the six strain slopes, on `u_x` and on `u_y`.
type Slopes = [[f64; 2]; 6];

/// One stabilised point of a step.
struct LonePoint {
    point: u32,
    /// Its entries' range in `LonePoints::nodes` and `coefficients`.
    start: usize,
    end: usize,
    /// Per slope, `V w`: the domain's volume times its second moment per
    /// area in the slope's direction.
    scale: [f64; 6],
    /// The moduli `M` taking the strain's slopes to the stored slopes `T`.
    moduli: [[f64; 6]; 6],
    /// The stored stress slopes `T` at the step's start.
    slope: [f64; 6],
}

/// The step's points seeded one a cell or fewer, and their strain slopes.
pub struct LonePoints {
    points: Vec<LonePoint>,
    /// Per material point, its place in `points` (`u32::MAX`: none).
    place: Vec<u32>,
    /// Active node of each entry.
    nodes: Vec<u32>,
    /// Per entry, its coefficients in each of the six strain slopes.
    coefficients: Vec<Slopes>,
}

impl LonePoints {
    /// The points of `start` seeded one a cell or fewer, with their strain slopes.
    pub fn new(start: &Configuration) -> Self {
        let Configuration {
            grid,
            basis,
            conn,
            points,
        } = *start;
        let alone: Vec<u32> = (0..points.len() as u32)
            .filter(|&p| points.volume0[p as usize] >= LONE_VOLUME * grid.h * grid.h)
            .filter(|&p| points.materials[points.material[p as usize] as usize].is_elastic())
            .collect();
        let lattice: Vec<[i64; 2]> = conn.nodes.iter().map(|&k| node_coordinates(k)).collect();
        let index = LatticeIndex::new(&lattice);
        let built: Vec<(LonePoint, Vec<u32>, Vec<Slopes>)> = alone
            .par_iter()
            .with_min_len(parallel::BOOKKEEPING)
            .map(|&p| {
                let p = p as usize;
                let x = points.position[p];
                let l = half_widths(basis, grid.h, points.support(p), points.volume(p));
                let m = [0, 1].map(|d| basis.moments_1d(grid.h, x[d] - grid.origin[d], l[d]));
                let elastic = points.materials[points.material[p] as usize].elastic();
                let linked: Vec<u32> = conn.point_links(p).iter().map(|k| k.node).collect();
                let (mut nodes, mut coefficients, mut at) = (Vec::new(), Vec::new(), Vec::new());
                let mut dropped = false;
                for &(j, my) in &m[1] {
                    for &(i, mx) in &m[0] {
                        let a = index.get([i, j]).map(|a| a as u32);
                        let Some(a) = a.filter(|a| linked.contains(a)) else {
                            dropped = true;
                            continue;
                        };
                        nodes.push(a);
                        at.push([(i - m[0][0].0) as f64, (j - m[1][0].0) as f64]);
                        coefficients.push(strain_slopes(basis, mx, my));
                    }
                }
                if dropped && !without_affine_part(&mut coefficients, &at) {
                    coefficients.clear();
                    nodes.clear();
                }
                let volume = points.volume(p);
                let lone = LonePoint {
                    point: p as u32,
                    start: 0,
                    end: 0,
                    scale: ACROSS.map(|d| volume * l[d] * l[d] / 3.0),
                    moduli: moduli(basis, elastic.lambda, elastic.mu),
                    slope: points.stress_slopes[p],
                };
                (lone, nodes, coefficients)
            })
            .collect();
        let mut place = vec![u32::MAX; points.len()];
        for (k, &p) in alone.iter().enumerate() {
            place[p as usize] = k as u32;
        }
        let mut out = Self {
            points: Vec::with_capacity(built.len()),
            place,
            nodes: Vec::new(),
            coefficients: Vec::new(),
        };
        for (mut lone, nodes, coefficients) in built {
            lone.start = out.nodes.len();
            out.nodes.extend(nodes);
            out.coefficients.extend(coefficients);
            lone.end = out.nodes.len();
            out.points.push(lone);
        }
        out
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The six strain slopes `e` of `lone` under the increment `u`.
    fn slopes_of(&self, lone: &LonePoint, u: &[f64]) -> [f64; 6] {
        let mut k = [0.0; 6];
        for e in lone.start..lone.end {
            let node = self.nodes[e] as usize;
            for (r, g) in self.coefficients[e].iter().enumerate() {
                k[r] += g[0] * u[2 * node] + g[1] * u[2 * node + 1];
            }
        }
        k
    }

    /// Each stabilised point's stress slopes once the step converged at
    /// increment `u`, turned with the step's rotation `rotation(p)` (the
    /// order of [`crate::particles::MaterialPoints::stress_slopes`]).
    pub fn settled(
        &self,
        u: &[f64],
        rotation: impl Fn(usize) -> Matrix2<f64>,
    ) -> Vec<(usize, [f64; 6])> {
        self.points
            .iter()
            .map(|lone| {
                let e = self.slopes_of(lone, u);
                let slopes: [f64; 6] = std::array::from_fn(|i| {
                    lone.slope[i] + (0..6).map(|j| lone.moduli[i][j] * e[j]).sum::<f64>()
                });
                let p = lone.point as usize;
                (p, rotated(slopes, &rotation(p)))
            })
            .collect()
    }
}

impl LonePoints {
    /// `lone`'s stiffness, passed to `add` as (place in the pattern's
    /// values, value).
    fn add_point_stiffness(
        &self,
        lone: &LonePoint,
        pattern: &Pattern,
        mut add: impl FnMut(usize, f64),
    ) {
        let weight: [[f64; 6]; 6] =
            std::array::from_fn(|i| std::array::from_fn(|j| lone.scale[i] * lone.moduli[i][j]));
        for a in lone.start..lone.end {
            // The slopes' stresses per unit displacement of node `a`.
            let ga = &self.coefficients[a];
            let stress: [[f64; 6]; 2] = std::array::from_fn(|c| {
                std::array::from_fn(|j| (0..6).map(|i| ga[i][c] * weight[i][j]).sum())
            });
            for b in lone.start..lone.end {
                let gb = &self.coefficients[b];
                let (base, stride) = pattern.block(self.nodes[a], self.nodes[b]);
                for (c, row) in stress.iter().enumerate() {
                    for d in 0..2 {
                        let k: f64 = (0..6).map(|j| row[j] * gb[j][d]).sum();
                        if k != 0.0 {
                            add(base + c + d * stride, k);
                        }
                    }
                }
            }
        }
    }
}

impl StepTerm for LonePoints {
    fn side(&self) -> Side {
        Side::Stabilisation
    }

    /// Adds `V w (T + M e) g` over the six slopes.
    fn add_force(&self, u: &[f64], f: &mut [f64]) {
        for lone in &self.points {
            let e = self.slopes_of(lone, u);
            let t: [f64; 6] = std::array::from_fn(|i| {
                let m: f64 = (0..6).map(|j| lone.moduli[i][j] * e[j]).sum();
                lone.scale[i] * (lone.slope[i] + m)
            });
            for e in lone.start..lone.end {
                let node = self.nodes[e] as usize;
                for (r, g) in self.coefficients[e].iter().enumerate() {
                    f[2 * node] += t[r] * g[0];
                    f[2 * node + 1] += t[r] * g[1];
                }
            }
        }
    }

    /// Adds `V w M g g^T` over the six slopes: one block per pair of the point's nodes,
    /// the pattern's tiles of one colour in parallel, as the points' own
    /// stiffness is summed (`super::stiffness`).
    fn add_stiffness(&self, _u: &[f64], pattern: &Pattern, values: &mut [f64]) {
        // SAFETY: a point's entries are among its linked nodes (`new`),
        // and their blocks the pattern's own places.
        unsafe {
            pattern.tiles.sum_into(values, |p, values| {
                if let Some(lone) = self.points.get(self.place[p] as usize) {
                    self.add_point_stiffness(lone, pattern, |at, v| values.add(at, v));
                }
            });
        }
    }

    /// Itself: the stepper takes the stress slopes from it
    /// ([`LonePoints::settled`]).
    fn into_carried(self: Box<Self>) -> Option<Box<dyn std::any::Any>> {
        Some(self)
    }
}

/// Takes out of each slope's coefficients (over nodes at lattice places
/// `at`) their part along the affine fields `1, i, j`, so that the slope
/// measures nothing on an affine increment. The slopes of a full set of a
/// point's nodes have none (the bases reproduce affine fields with the
/// nodes' own values); a slope missing nodes its rectangle reaches and the
/// point's own domain does not (a turned domain measured on an upright
/// rectangle; the grid's extent) would measure a translation. False when
/// the nodes left span no plane.
fn without_affine_part(coefficients: &mut [Slopes], at: &[[f64; 2]]) -> bool {
    let phi = |a: &[f64; 2]| Vector3::new(1.0, a[0], a[1]);
    let gram: Matrix3<f64> = at.iter().map(|a| phi(a) * phi(a).transpose()).sum();
    let Some(inverse) = gram.try_inverse() else {
        return false;
    };
    for r in 0..6 {
        for c in 0..2 {
            let moment: Vector3<f64> = (coefficients.iter().zip(at))
                .map(|(g, a)| phi(a) * g[r][c])
                .sum();
            let alpha = inverse * moment;
            for (g, a) in coefficients.iter_mut().zip(at) {
                g[r][c] -= phi(a).dot(&alpha);
            }
        }
    }
    true
}

/// A node's coefficients in the six strain slopes (the order of the
/// stress slopes: `eps_xx` in x and y, `eps_yy` in x and y, `gamma_xy` in
/// x and y), on `u_x` and `u_y`, from its 1D moments `mx`, `my` (`[a, b,
/// c, d]`). On the hats (bilinear, GIMP) the shear strain's slopes leave
/// out `d2u_x/dxdy` and `d2u_y/dxdy`, the bilinear field's parasitic shear
/// in bending, as ASQBI does; the B-splines hold a bending field exactly
/// and keep them.
fn strain_slopes(basis: Basis, mx: [f64; 4], my: [f64; 4]) -> Slopes {
    let [ax, bx, cx, dx] = mx;
    let [ay, by, cy, dy] = my;
    let parasitic = if basis.degree() == 1 { 0.0 } else { 1.0 };
    [
        [dx * ay, 0.0],
        [bx * cy, 0.0],
        [0.0, cx * by],
        [0.0, ax * dy],
        [parasitic * cx * by, dx * ay],
        [ax * dy, parasitic * bx * cy],
    ]
}

/// The moduli taking the strain slopes to the stress slopes, per
/// direction (no coupling across directions), from the Lame constants.
/// - On the hats, ASQBI's: `E' = 2 mu / (1 - nu)` on each normal strain's
///   slope, `mu` on the shear strain's. Along the bilinear basis only the
///   bending slopes (`eps_xx` in y, `eps_yy` in x) are not zero inside a
///   cell, and `E'` is exact in pure bending.
/// - On the B-splines, the energy `E' q^2 / 2 + mu (p + nu' q)^2 + mu
///   g^2 / 2` per direction, `q` the bending slope (`eps_xx` in y, `eps_yy`
///   in x), `p` the other normal strain's slope in that direction, `g` the
///   shear strain's, `nu' = nu / (1 - nu)`: a true plane-strain bending
///   field (`p = -nu' q`, `g = 0`) costs `E' q^2 / 2`, the plane-strain
///   bending energy, and a zigzag of one component (`p` alone) is held by
///   `2 mu`. No `lambda` appears, so nothing locks near incompressibility.
fn moduli(basis: Basis, lambda: f64, mu: f64) -> [[f64; 6]; 6] {
    let bending = 4.0 * mu * (lambda + mu) / (lambda + 2.0 * mu);
    let mut m = [[0.0; 6]; 6];
    if basis.degree() == 1 {
        for (i, row) in m.iter_mut().enumerate() {
            row[i] = if i < 4 { bending } else { mu };
        }
        return m;
    }
    let poisson = lambda / (lambda + 2.0 * mu);
    // (q, p) per direction: x: (eps_yy,x = 2, eps_xx,x = 0); y: (1, 3).
    for (q, p) in [(2, 0), (1, 3)] {
        m[q][q] = bending + 2.0 * mu * poisson * poisson;
        m[q][p] = 2.0 * mu * poisson;
        m[p][q] = 2.0 * mu * poisson;
        m[p][p] = 2.0 * mu;
    }
    m[4][4] = mu;
    m[5][5] = mu;
    m
}

/// The half-widths a point's bending is measured over: its upright
/// domain's; for a turned or mapped domain, the upright rectangle of its
/// area and its bounding box's proportions; for the bilinear basis, which
/// has no domain, the square of the point's volume.
fn half_widths(basis: Basis, h: f64, support: Support, volume: f64) -> [f64; 2] {
    let l = match (basis, support) {
        (Basis::Linear, _) => return [0.5 * volume.sqrt(); 2],
        (_, Support::Rectangle(l)) => l,
        (_, Support::Quadrilateral(corners)) => {
            let (lo, hi) = quadrilateral_domain::bounds(&corners);
            let half = [0.5 * (hi[0] - lo[0]), 0.5 * (hi[1] - lo[1])];
            let area = quadrilateral_domain::area(&corners).abs();
            let k = (area / (4.0 * half[0] * half[1])).sqrt();
            if k.is_finite() {
                half.map(|x| k * x)
            } else {
                [0.0; 2]
            }
        }
    };
    l.map(|x| x.min(basis.widest_domain(h)))
}

/// The stress slopes `T_ijk = dsigma_ij/dx_k` turned by `r`: `T'_ijk =
/// R_ia R_jb R_kc T_abc`, in the order of [`crate::particles::MaterialPoints::stress_slopes`]:
/// `[T_xxx, T_xxy, T_yyx, T_yyy, T_xyx, T_xyy]`.
pub fn rotated(s: [f64; 6], r: &Matrix2<f64>) -> [f64; 6] {
    let mut t = [[[0.0; 2]; 2]; 2];
    t[0][0] = [s[0], s[1]];
    t[1][1] = [s[2], s[3]];
    t[0][1] = [s[4], s[5]];
    t[1][0] = [s[4], s[5]];
    let turned = |i: usize, j: usize, k: usize| {
        let mut sum = 0.0;
        for (a, ta) in t.iter().enumerate() {
            for (b, tab) in ta.iter().enumerate() {
                for (c, tabc) in tab.iter().enumerate() {
                    sum += r[(i, a)] * r[(j, b)] * r[(k, c)] * tabc;
                }
            }
        }
        sum
    };
    [
        turned(0, 0, 0),
        turned(0, 0, 1),
        turned(1, 1, 0),
        turned(1, 1, 1),
        turned(0, 1, 0),
        turned(0, 1, 1),
    ]
}

/// The rotation of the polar decomposition of a 2x2 `F` with `det F > 0`.
pub fn polar_rotation(f: &Matrix2<f64>) -> Matrix2<f64> {
    let angle = (f[(1, 0)] - f[(0, 1)]).atan2(f[(0, 0)] + f[(1, 1)]);
    let (s, c) = angle.sin_cos();
    Matrix2::new(c, -s, s, c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::Pattern;
    use crate::fixtures;

    const BASES: [&str; 4] = ["linear", "gimp", "bspline2", "bspline3"];

    /// A 2 m x 1 m block of `count` points on cells of 0.5 m with a node
    /// at `origin`: its term, its pattern and its active nodes' positions.
    fn block(
        basis: &str,
        count: [u32; 2],
        origin: [f64; 2],
    ) -> (LonePoints, Pattern, Vec<[f64; 2]>) {
        let mut case = fixtures::block([2.0, 1.0], count, 0.5, origin);
        case["basis"] = basis.into();
        let sim = fixtures::simulation(&case);
        let conn = sim.reset_grid();
        let lone = LonePoints::new(&sim.configuration(&conn));
        let nodes = conn
            .nodes
            .iter()
            .map(|&k| sim.grid.node_position(k))
            .collect();
        (lone, Pattern::build(&conn, &[]), nodes)
    }

    /// An affine field and a finite rigid rotation `(R - I) x` at `nodes`.
    fn affine_fields(nodes: &[[f64; 2]]) -> [Vec<f64>; 2] {
        let (s, c) = 0.9f64.sin_cos();
        let field = |f: &dyn Fn([f64; 2]) -> [f64; 2]| -> Vec<f64> {
            nodes.iter().flat_map(|&x| f(x)).collect()
        };
        [
            field(&|[x, y]| [0.3 + 0.2 * x - 0.7 * y, -0.1 + 0.5 * x + 0.4 * y]),
            field(&|[x, y]| [(c - 1.0) * x - s * y, s * x + (c - 1.0) * y]),
        ]
    }

    /// One point a cell is stabilised, every point; two a cell, none.
    #[test]
    fn one_point_a_cell_is_stabilised_and_two_are_not() {
        for basis in BASES {
            assert_eq!(
                block(basis, [4, 2], [0.0, 0.0]).0.points.len(),
                8,
                "{basis}"
            );
            assert!(block(basis, [8, 4], [0.0, 0.0]).0.is_empty(), "{basis}");
        }
    }

    /// Every strain slope is zero on an affine increment, a finite rigid
    /// rotation `(R - I) x` included (every basis reproduces linear fields
    /// with the nodes' own values), on aligned and offset grids. Bending
    /// costs the plane-strain beam's energy `E' kappa^2 / 2` per unit `V
    /// w_y` and nothing else: on the hats `u_x = -kappa x y` (bilinear,
    /// reproduced likewise; the slopes leave out its parasitic shear); on
    /// the B-splines the true bending field `u_x = -kappa x y`, `u_y =
    /// kappa (x^2 + nu' y^2) / 2` with `nu' = nu / (1 - nu)` (reproduced
    /// with `x_i^2` less a constant, which no slope sees), whose Poisson
    /// slope and shear-strain slopes are not hourglass modes. The block's
    /// `nu` is 0.3, `E` 1e6.
    #[test]
    fn affine_increments_have_no_slopes_and_bending_costs_the_beams_energy() {
        let (kappa, nu, e) = (0.37, 0.3, 1e6);
        let poisson = nu / (1.0 - nu);
        let beam = e / (1.0 - nu * nu) * kappa * kappa / 2.0;
        for basis in BASES {
            for origin in [[0.0, 0.0], [0.13, -0.21]] {
                let (lone, _, nodes) = block(basis, [4, 2], origin);
                let hats = basis == "linear" || basis == "gimp";
                let bending: Vec<f64> = nodes
                    .iter()
                    .flat_map(|&[x, y]| {
                        if hats {
                            [-kappa * x * y, 0.0]
                        } else {
                            [-kappa * x * y, kappa * (x * x + poisson * y * y) / 2.0]
                        }
                    })
                    .collect();
                for p in &lone.points {
                    for u in &affine_fields(&nodes) {
                        let k = lone.slopes_of(p, u);
                        assert!(
                            k.iter().all(|k| k.abs() < 1e-12),
                            "{basis} {origin:?} {k:?}"
                        );
                    }
                    let k = lone.slopes_of(p, &bending);
                    assert!((k[1] + kappa).abs() < 1e-12, "{basis} {origin:?} {k:?}");
                    let poisson_slope = if hats { 0.0 } else { poisson * kappa };
                    assert!((k[3] - poisson_slope).abs() < 1e-12, "{basis} {k:?}");
                    assert!(
                        [k[0], k[2], k[4], k[5]].iter().all(|k| k.abs() < 1e-12),
                        "{k:?}"
                    );
                    let energy: f64 = (0..6)
                        .flat_map(|i| (0..6).map(move |j| (i, j)))
                        .map(|(i, j)| k[i] * p.moduli[i][j] * k[j] / 2.0)
                        .sum();
                    assert!(
                        (energy / beam - 1.0).abs() < 1e-12,
                        "{basis}: {energy} {beam}"
                    );
                }
            }
        }
    }

    /// A body turned 30 and 45 degrees (turned domains, measured on
    /// upright rectangles that may reach nodes the domain does not) on
    /// grids at two placements: no slope measures an affine increment or a
    /// finite rigid rotation, on any basis. Without the affine part taken
    /// out of slopes missing nodes, GIMP at 30 degrees measured 0.01-0.02.
    #[test]
    fn turned_domains_measure_nothing_on_affine_increments() {
        for basis in BASES {
            for angle in [30.0, 45.0] {
                for origin in [[0.0, 0.0], [0.07, -0.21]] {
                    let mut case = fixtures::block([2.0, 1.0], [4, 2], 0.5, origin);
                    case["basis"] = basis.into();
                    case["bodies"][0]["geometry"]["rectangle"]["angle"] = angle.into();
                    let sim = fixtures::simulation(&case);
                    let conn = sim.reset_grid();
                    let lone = LonePoints::new(&sim.configuration(&conn));
                    assert_eq!(lone.points.len(), 8, "{basis}");
                    let nodes: Vec<[f64; 2]> = conn
                        .nodes
                        .iter()
                        .map(|&k| sim.grid.node_position(k))
                        .collect();
                    for p in &lone.points {
                        for u in &affine_fields(&nodes) {
                            let k = lone.slopes_of(p, u);
                            assert!(
                                k.iter().all(|k| k.abs() < 1e-11),
                                "{basis} {angle} {origin:?} {k:?}"
                            );
                        }
                    }
                }
            }
        }
    }

    /// The tangent is the force's derivative: the force is `K u` plus the
    /// stored slopes' part, so `f(u) - f(0)` must be the assembled `K`
    /// times `u`, for a random `u` on every basis.
    #[test]
    fn the_tangent_is_the_derivative_of_the_force() {
        for basis in BASES {
            let (mut lone, pattern, nodes) = block(basis, [4, 2], [0.13, -0.21]);
            for (i, p) in lone.points.iter_mut().enumerate() {
                p.slope = std::array::from_fn(|r| 1e3 * (i + r) as f64);
            }
            let n = 2 * nodes.len();
            let u: Vec<f64> = (0..n)
                .map(|i| ((i * 7919) % 101) as f64 / 101.0 - 0.5)
                .collect();
            let (mut f0, mut f) = (vec![0.0; n], vec![0.0; n]);
            lone.add_force(&vec![0.0; n], &mut f0);
            lone.add_force(&u, &mut f);
            let mut values = vec![0.0; pattern.row_idx.len()];
            lone.add_stiffness(&u, &pattern, &mut values);
            let mut ku = vec![0.0; n];
            for col in 0..n {
                for k in pattern.col_ptr[col]..pattern.col_ptr[col + 1] {
                    ku[pattern.row_idx[k] as usize] += values[k] * u[col];
                }
            }
            let scale = f.iter().map(|x| x.abs()).fold(0.0, f64::max);
            for i in 0..n {
                assert!(
                    (f[i] - f0[i] - ku[i]).abs() <= 1e-12 * scale,
                    "{basis} dof {i}"
                );
            }
        }
    }

    /// The slopes `dsigma_ij/dx_k` turn as a third-order tensor: a
    /// quarter turn takes `dsigma_xx/dy` to `-dsigma_yy/dx` (the field
    /// `sigma_xx = y` turned is `sigma'_yy = -x'`), and turning back
    /// restores them.
    #[test]
    fn the_slopes_turn_as_a_third_order_tensor() {
        let quarter = Matrix2::new(0.0, -1.0, 1.0, 0.0);
        let turned = rotated([0.0, 1.0, 0.0, 0.0, 0.0, 0.0], &quarter);
        assert!((turned[2] + 1.0).abs() < 1e-15);
        assert!(
            turned
                .iter()
                .enumerate()
                .all(|(k, t)| k == 2 || t.abs() < 1e-15)
        );
        let s = [1.0, -2.0, 3.0, 0.5, -0.25, 4.0];
        let r = polar_rotation(&Matrix2::new(1.1, -0.4, 0.7, 0.9));
        let back = rotated(rotated(s, &r), &r.transpose());
        assert!(s.iter().zip(back).all(|(a, b)| (a - b).abs() < 1e-13));
        assert!((r.transpose() * r - Matrix2::identity()).norm() < 1e-15);
    }
}
