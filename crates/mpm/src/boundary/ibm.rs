//! Dirichlet conditions on the boundary curve by the implicit boundary
//! method (Burla & Kumar 2008; Kumar et al. 2008; in MPM, Cortis et al.
//! 2018).
//!
//! The trial displacement is `u = D u_h + u_a`: `u_h` the grid
//! interpolation, `u_a` the prescribed values, `D` a D-function of the
//! distance `phi` from the boundary, `D = 1 - (1 - phi/delta)^2` across a
//! band of width `delta` inside the material and 1 beyond. Integrated across
//! the band, the strain energy of `D u_h` has the leading part
//! `1/2 int_Gamma (4 / (3 delta)) (u_h - u_a) . A_nn (u_h - u_a) dGamma`, since
//! `int_0^delta D'(phi)^2 dphi = 4 / (3 delta)`, with `A_nn` the acoustic
//! tensor `A_iKjL n_K n_L` of the material next to the boundary. The band is
//! far thinner than a point spacing, so no point lies in it and the points
//! keep their ordinary integration; the band adds that boundary term,
//! integrated by Gauss quadrature along the B-spline (split at grid lines,
//! as tractions are). A fixed condition holds both components, a roller the
//! normal one (`P = n n` in `P A_nn P`), so inclined and curved rollers are
//! the same code.
//!
//! The band width: the term acts as a penalty of about `(4/3) C / delta` per
//! unit boundary length against a cell's stiffness of about `C`, so the
//! condition holds to a gap of about `(3/4) delta` times the boundary
//! strain, and the matrix's conditioning grows like `h / delta`. Two errors
//! pull delta opposite ways:
//! - the gap: the patch test's error is `0.3 delta / h` down to
//!   `delta = h / 10^4`; a clamped cantilever's tip moves by `0.07 delta / h`
//!   of itself; a pinned stretch, which carries a concentrated force,
//!   converges more slowly (a cantilever's relative deflection 1.0e-3,
//!   2.3e-4, 3.0e-5 off its delta -> 0 value at `h / 10^2, 10^3, 10^4`);
//! - locking: along a boundary that crosses cells at an angle, the bilinear
//!   field cannot meet a stiff constraint at every quadrature point, and
//!   the body stiffens as delta shrinks: Lame's cylinder on rollers turned
//!   30 degrees to the grid (h = 0.125) has u_r errors of 1.5%, -0.3%,
//!   -7.6% and -18% at `delta = h / 10^2, 10^3, 10^4, 10^5` (fewer
//!   quadrature points per segment delay it by about a decade, no more).
//!
//! The conditioning grows as predicted (condition number of the patch
//! test's tangent 3.1e2, 2.7e3, 2.6e4, 2.6e5, 2.6e6 at `delta = h / 10 ..
//! h / 10^5`, against 3.6e1 on grid-node supports; `stepper` tests) but
//! costs nothing here: the direct solver takes the same Newton iterations
//! to the same residuals from `h / 10` to `h / 10^5`. The default `delta = h / 100` keeps both errors at or below
//! the discretisation error of the grids we run; a case whose supports are
//! all on grid-aligned straight sides can take a smaller one.
//!
//! Updated-Lagrangian steps reset the grid, so a step's band term sees only
//! that step's increment, while a support must hold the boundary's total
//! displacement: a penalty spring rebuilt each step would let the boundary
//! creep by `reaction / penalty` every step. The band's quadrature points
//! are therefore [`Anchor`]s: fixed on the reference curve (Gauss points of
//! its segments, split at the grid lines of the first step) and carried by
//! the grid's own displacement at the end of every step, so that each one
//! knows how far it has moved; the step's target is the prescribed
//! displacement minus that. Measuring the motion on the rebuilt curve
//! instead (whose data points follow the points' deformation gradients, not
//! the grid field the band holds) feeds their difference back every step,
//! and a self-weight column with rollers grew a sideways mode by about five
//! times per step until it collapsed.
//!
//! Nodes beyond a supported boundary: GIMP domains reach a little past the
//! boundary as the body deforms, and the nodes there, touched by a sliver of
//! a domain, get a tiny stiffness but a force proportional to the point's
//! stress. Their equilibrium then asks that stress component to vanish,
//! which at a support it cannot: the self-weight column's base points
//! inverted at step 10. (At a free surface the same condition is the
//! traction-free one, which is why this only bites at supports.) Such nodes
//! get a ghost tie (a ghost penalty in its simplest form): the second
//! difference `u_I - 2 u_J + u_K` towards the inside, weighted by 0.1 of the
//! band's `A_nn`, is penalised. It vanishes for linear fields, so the patch
//! tests stay exact, and it makes those nodes follow the linear
//! continuation of the field inside. Only nodes more than a tenth of a cell
//! beyond the boundary and outside the current curve are tied: a first
//! version also tied the nodes on a grid-aligned support once its anchors
//! had moved a hair, which stiffened the paper's cantilever at its root
//! (tip deflection -2.187 m against -2.260 m now and -2.285 m on grid-node
//! supports).

use std::collections::BTreeMap;

use nalgebra::{Matrix2, Vector2};

use super::bspline::{bezier, bezier_derivative, local_segment};
use super::detection::BoundaryLoop;
use super::quadrature::{gauss_points, hat_shares};
use super::{current_ring, reference_ring};
use crate::assembly::Pattern;
use crate::configuration::Configuration;
use crate::geometry::winding_number;
use crate::grid::{Grid, NodeKey, node_indices, node_key};
use crate::particles::MaterialPoints;
use crate::supports::{Fix, Rotation};

/// A support imposed on the boundary curve by the implicit boundary method.
#[derive(Debug, Clone, PartialEq)]
pub struct IbmSupport {
    /// Its index among the case's supports (for reactions).
    pub index: usize,
    /// The segments of each loop it holds, `(loop index, segments)`.
    pub segments: Vec<(usize, Vec<usize>)>,
    pub fix: Fix,
    /// Prescribed displacement at load factor 1.
    pub displacement: [f64; 2],
    pub rotation: Option<Rotation>,
}

/// A quadrature point of an implicit-boundary support, Lagrangian: fixed on
/// the reference curve, carried by the grid's displacement.
#[derive(Debug, Clone, PartialEq)]
pub struct Anchor {
    /// Index of the support in the case (for reactions).
    pub support: usize,
    loop_index: usize,
    segment: usize,
    /// Parameter on the segment and Gauss weight in it.
    t: f64,
    weight: f64,
    /// The material point next to it (the nearer end of the segment): its
    /// tangent stiffness stands for the band's, and it carries the anchor
    /// in a step where the anchor touches no active node.
    point: usize,
    fix: Fix,
    /// Outward unit normal of the reference curve: the wall a roller slides
    /// on. It stays put while the body deforms; the body's own normal turns
    /// with its shear, and a roller held along that would push the body
    /// sideways by the tilt times its sliding, tilting it further (a
    /// self-weight column with sliding sides collapsed that way).
    normal: [f64; 2],
    /// Prescribed displacement and rotation at load factor 1.
    prescribed: [f64; 2],
    rotation: Option<Rotation>,
    /// Reference position and the displacement since.
    reference: [f64; 2],
    moved: [f64; 2],
}

impl Anchor {
    /// The prescribed displacement at load factor `lambda`:
    /// `lambda d + (R(lambda theta) - I)(X - c)`.
    fn prescribed_at(&self, lambda: f64) -> [f64; 2] {
        let mut u = [lambda * self.prescribed[0], lambda * self.prescribed[1]];
        if let Some(r) = self.rotation {
            let (sin, cos) = (lambda * r.angle.to_radians()).sin_cos();
            let x = [
                self.reference[0] - r.center[0],
                self.reference[1] - r.center[1],
            ];
            u[0] += (cos - 1.0) * x[0] - sin * x[1];
            u[1] += sin * x[0] + (cos - 1.0) * x[1];
        }
        u
    }

    /// Current position.
    pub fn position(&self) -> [f64; 2] {
        [
            self.reference[0] + self.moved[0],
            self.reference[1] + self.moved[1],
        ]
    }
}

/// The anchors of the implicit-boundary supports: Gauss points of the
/// reference-curve segments each support holds.
pub fn anchors(
    supports: &[IbmSupport],
    loops: &[BoundaryLoop],
    points: &MaterialPoints,
    grid: &Grid,
) -> Vec<Anchor> {
    let mut out = Vec::new();
    for s in supports {
        for (loop_index, segments) in &s.segments {
            let (loop_index, l) = (*loop_index, &loops[*loop_index]);
            if l.points.len() < 3 {
                continue; // no curve through one or two points
            }
            let n = l.points.len();
            let ring = reference_ring(l, points);
            for &k in segments {
                let segment = local_segment(&ring, k);
                for (t, weight) in gauss_points(&segment, grid) {
                    let d = bezier_derivative(&segment, t);
                    let length = (d[0] * d[0] + d[1] * d[1]).sqrt();
                    out.push(Anchor {
                        normal: [d[1] / length, -d[0] / length],
                        support: s.index,
                        loop_index,
                        segment: k,
                        t,
                        weight,
                        point: l.points[if t < 0.5 { k } else { (k + 1) % n }],
                        fix: s.fix,
                        prescribed: s.displacement,
                        rotation: s.rotation,
                        reference: bezier(&segment, t),
                        moved: [0.0, 0.0],
                    });
                }
            }
        }
    }
    out
}

/// One anchor's band term in a load step.
#[derive(Debug, Clone)]
struct BandPoint {
    anchor: usize,
    /// Its shares of the active nodes are `shares[first..last]`.
    first: usize,
    last: usize,
    /// `dGamma * 4 / (3 delta) * P A_nn P`.
    stiffness: Matrix2<f64>,
    /// Displacement increment the boundary should make in this step.
    target: [f64; 2],
}

/// Default band width `delta` in cells (see the module docs).
pub const DEFAULT_BAND_WIDTH: f64 = 1e-2;

/// Weight of the ghost ties against the band's material stiffness.
const GHOST: f64 = 0.1;

/// An active node beyond a supported boundary (`I`) and the next two
/// inward (`J`, `K`), whose second difference `u_I - 2 u_J + u_K` is
/// penalised (module docs).
#[derive(Debug, Clone)]
struct GhostTie {
    nodes: [usize; 3],
    stiffness: Matrix2<f64>,
    /// The support whose anchor found it (its reaction takes the tie's
    /// force where part of it lands on a grid-held node).
    support: usize,
}

impl GhostTie {
    /// `K (u_I - 2 u_J + u_K)`.
    fn force(&self, u: &[f64]) -> Vector2<f64> {
        let mut g = Vector2::zeros();
        for (&a, c) in self.nodes.iter().zip(GHOST_STENCIL) {
            g += c * Vector2::new(u[2 * a], u[2 * a + 1]);
        }
        self.stiffness * g
    }
}

/// The band terms of one load step.
#[derive(Debug, Clone, Default)]
pub struct BandTerms {
    points: Vec<BandPoint>,
    shares: Vec<(usize, f64)>,
    ghosts: Vec<GhostTie>,
    /// `3 delta / (4 h)`: turns band forces into a cell's material forces.
    material_scale: f64,
}

impl BandTerms {
    pub fn new(
        start: &Configuration,
        anchors: &[Anchor],
        band_width: f64,
        load_factor: f64,
    ) -> Self {
        let Configuration {
            grid,
            conn,
            points,
            loops,
        } = *start;
        let mut terms = BandTerms {
            material_scale: 0.75 * band_width / grid.h,
            ..Default::default()
        };
        let mut weights = Vec::with_capacity(4);
        // Nodes just beyond a supported boundary, with the anchor that saw
        // them first.
        let mut beyond: BTreeMap<NodeKey, usize> = BTreeMap::new();
        // The current data points of the loops with anchors.
        let mut rings: BTreeMap<usize, Vec<[f64; 2]>> = BTreeMap::new();
        for (i, a) in anchors.iter().enumerate() {
            let current = rings
                .entry(a.loop_index)
                .or_insert_with(|| current_ring(&loops[a.loop_index], points));
            let first = terms.shares.len();
            if !hat_shares(
                grid,
                a.position(),
                &conn.nodes,
                &mut weights,
                &mut terms.shares,
            ) {
                continue;
            }
            let d = bezier_derivative(&local_segment(current, a.segment), a.t);
            let length = a.weight * (d[0] * d[0] + d[1] * d[1]).sqrt();
            let a_nn = acoustic_tensor(points, a.point, a.normal);
            for key in nodes_beyond(grid, a.position(), a.normal) {
                if conn.nodes.binary_search(&key).is_ok() {
                    beyond.entry(key).or_insert(i);
                }
            }
            let held = projection(a.fix, a.normal);
            let stiffness = held * a_nn * held * (length * 4.0 / (3.0 * band_width));
            terms.points.push(BandPoint {
                anchor: i,
                first,
                last: terms.shares.len(),
                stiffness,
                target: {
                    let u = a.prescribed_at(load_factor);
                    [u[0] - a.moved[0], u[1] - a.moved[1]]
                },
            });
        }
        for (key, anchor) in beyond {
            let a = &anchors[anchor];
            // Beyond the tangent at the anchor but inside the material (a
            // concave stretch, or a curve through the points half a spacing
            // inside the edge): no tie.
            let material_side = if loops[a.loop_index].hole { 0 } else { 1 };
            if winding_number(grid.node_position(key), &rings[&a.loop_index]) == material_side {
                continue;
            }
            let (normal, a_nn) = (a.normal, acoustic_tensor(points, a.point, a.normal));
            let (i, j) = node_indices(key);
            // Inward along the grid axis closest to the normal.
            let (di, dj) = if normal[0].abs() >= normal[1].abs() {
                (-normal[0].signum() as i64, 0)
            } else {
                (0, -normal[1].signum() as i64)
            };
            let index = |k: i64| {
                conn.nodes
                    .binary_search(&node_key(i + k * di, j + k * dj))
                    .ok()
            };
            if let (Some(a), Some(b), Some(c)) = (index(0), index(1), index(2)) {
                terms.ghosts.push(GhostTie {
                    nodes: [a, b, c],
                    stiffness: a_nn * GHOST,
                    support: anchors[anchor].support,
                });
            }
        }
        terms
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Node groups the band and the ghost ties couple (for the stiffness
    /// pattern).
    pub fn coupling_groups(&self) -> Vec<Vec<u32>> {
        self.points
            .iter()
            .map(|b| {
                self.shares[b.first..b.last]
                    .iter()
                    .map(|&(a, _)| a as u32)
                    .collect()
            })
            .chain(
                self.ghosts
                    .iter()
                    .map(|g| g.nodes.iter().map(|&a| a as u32).collect()),
            )
            .collect()
    }

    /// The grid's displacement increment `u` at a band point.
    fn increment(&self, b: &BandPoint, u: &[f64]) -> [f64; 2] {
        let mut v = [0.0; 2];
        for &(a, n) in &self.shares[b.first..b.last] {
            v[0] += n * u[2 * a];
            v[1] += n * u[2 * a + 1];
        }
        v
    }

    /// `K (u_h - target)` at a band point: the band's contribution to the
    /// internal force there (the force on the body is its negative).
    fn force(&self, b: &BandPoint, u: &[f64]) -> Vector2<f64> {
        let v = self.increment(b, u);
        b.stiffness * Vector2::new(v[0] - b.target[0], v[1] - b.target[1])
    }

    /// Adds the band's internal force `N_a K (u_h - target)` and the ghost
    /// ties' `c_a K (u_I - 2 u_J + u_K)` to `f`.
    pub fn add_forces(&self, u: &[f64], f: &mut [f64]) {
        for b in &self.points {
            let force = self.force(b, u);
            for &(a, n) in &self.shares[b.first..b.last] {
                f[2 * a] += n * force[0];
                f[2 * a + 1] += n * force[1];
            }
        }
        for tie in &self.ghosts {
            let force = tie.force(u);
            for (&a, c) in tie.nodes.iter().zip(GHOST_STENCIL) {
                f[2 * a] += c * force[0];
                f[2 * a + 1] += c * force[1];
            }
        }
    }

    /// What a prescribed displacement asks of the material next to it: the
    /// norm of the band forces at zero increment, `|N_a K target|`, with the
    /// penalty's `4 / (3 delta)` replaced by a cell's `1 / h`. A yardstick
    /// for residuals when nothing else loads the body; the band forces
    /// themselves are `h / delta` times larger, and measuring against them
    /// would let the material's balance go that much looser.
    pub fn load_norm(&self, n_dofs: usize) -> f64 {
        let mut f = vec![0.0; n_dofs];
        self.add_forces(&vec![0.0; n_dofs], &mut f);
        self.material_scale * f.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// Adds the band's stiffness `N_a N_b K` to tangent values.
    pub fn add_stiffness(&self, pattern: &Pattern, values: &mut [f64]) {
        for b in &self.points {
            let shares = &self.shares[b.first..b.last];
            for &(a, na) in shares {
                for &(c, nc) in shares {
                    for i in 0..2 {
                        for j in 0..2 {
                            let added = pattern.add(
                                values,
                                2 * a + i,
                                2 * c + j,
                                na * nc * b.stiffness[(i, j)],
                            );
                            debug_assert!(added, "band couplings are in the pattern");
                        }
                    }
                }
            }
        }
        for tie in &self.ghosts {
            let k = &tie.stiffness;
            for (&a, ca) in tie.nodes.iter().zip(GHOST_STENCIL) {
                for (&b, cb) in tie.nodes.iter().zip(GHOST_STENCIL) {
                    for i in 0..2 {
                        for j in 0..2 {
                            let added =
                                pattern.add(values, 2 * a + i, 2 * b + j, ca * cb * k[(i, j)]);
                            debug_assert!(added, "ghost couplings are in the pattern");
                        }
                    }
                }
            }
        }
    }

    /// Per support of the case (`n` of them), the force the band terms and
    /// ghost ties exert on the body at increment `u`: their nodal forces on
    /// the DOFs that are free. On a DOF a grid support holds, the band
    /// pushes against that support, not the body, and the grid support's
    /// reaction (from the material's forces) is the body's side of it.
    pub fn reactions(
        &self,
        anchors: &[Anchor],
        u: &[f64],
        fixed: &[bool],
        n: usize,
    ) -> Vec<[f64; 2]> {
        let mut out = vec![[0.0; 2]; n];
        let mut take = |support: usize, a: usize, share: f64, force: Vector2<f64>| {
            for c in 0..2 {
                if !fixed[2 * a + c] {
                    out[support][c] -= share * force[c];
                }
            }
        };
        for b in &self.points {
            let force = self.force(b, u);
            for &(a, share) in &self.shares[b.first..b.last] {
                take(anchors[b.anchor].support, a, share, force);
            }
        }
        for tie in &self.ghosts {
            let force = tie.force(u);
            for (&a, c) in tie.nodes.iter().zip(GHOST_STENCIL) {
                take(tie.support, a, c, force);
            }
        }
        out
    }

    /// Moves the anchors with the converged increment `u`. An anchor that
    /// found no active node this step (it has drifted off the cells the
    /// material touches) moves with its material point instead, given as
    /// that point's displacement over the step in `point_moved`.
    pub fn advance(
        &self,
        anchors: &mut [Anchor],
        u: &[f64],
        point_moved: impl Fn(usize) -> [f64; 2],
    ) {
        let mut carried = vec![false; anchors.len()];
        for b in &self.points {
            let v = self.increment(b, u);
            let a = &mut anchors[b.anchor];
            a.moved[0] += v[0];
            a.moved[1] += v[1];
            carried[b.anchor] = true;
        }
        for (a, _) in anchors.iter_mut().zip(carried).filter(|(_, c)| !c) {
            let v = point_moved(a.point);
            a.moved[0] += v[0];
            a.moved[1] += v[1];
        }
    }
}

/// `A_nn[i][j] = A[(2i+K),(2j+L)] n_K n_L` of point `p`'s material tangent
/// at the start of the step.
fn acoustic_tensor(points: &MaterialPoints, p: usize, n: [f64; 2]) -> Matrix2<f64> {
    let material = &points.materials[points.material[p] as usize];
    let j = points.deformation[p].determinant();
    let tangent = material
        .respond(&points.history[p], &Matrix2::zeros(), j)
        .tangent;
    Matrix2::from_fn(|i, jj| {
        let mut sum = 0.0;
        for k in 0..2 {
            for l in 0..2 {
                sum += n[k] * tangent[(2 * i + k, 2 * jj + l)] * n[l];
            }
        }
        sum
    })
}

/// The second difference's weights along `[I, J, K]`.
const GHOST_STENCIL: [f64; 3] = [1.0, -2.0, 1.0];

/// Grid nodes that GIMP domains reaching just past a supported boundary at
/// `x` (outward normal `n`) can touch: beyond it by more than a tenth of a
/// cell (nearer ones take at least 90% of the band's shares there, and a
/// node on a grid-aligned boundary that has moved a hair is not beyond it)
/// and at most one cell, and within one cell of `x` along it.
fn nodes_beyond(grid: &Grid, x: [f64; 2], n: [f64; 2]) -> impl Iterator<Item = NodeKey> + '_ {
    let [ci, cj] = grid.cell_of(x);
    let tol = 1e-9 * grid.h;
    (cj - 1..=cj + 2)
        .flat_map(move |j| (ci - 1..=ci + 2).map(move |i| node_key(i, j)))
        .filter(move |&key| {
            let p = grid.node_position(key);
            let r = [p[0] - x[0], p[1] - x[1]];
            let out = r[0] * n[0] + r[1] * n[1];
            let along = (r[0] * n[1] - r[1] * n[0]).abs();
            out > 0.1 * grid.h && out <= grid.h + tol && along <= grid.h + tol
        })
}

/// The components a support holds, as a projection.
fn projection(fix: Fix, n: [f64; 2]) -> Matrix2<f64> {
    match fix {
        Fix::Xy => Matrix2::identity(),
        Fix::X => Matrix2::new(1.0, 0.0, 0.0, 0.0),
        Fix::Y => Matrix2::new(0.0, 0.0, 0.0, 1.0),
        Fix::Normal => Matrix2::new(n[0] * n[0], n[0] * n[1], n[1] * n[0], n[1] * n[1]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn winding_number_tells_inside_from_outside_either_way_round() {
        let ccw = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert_eq!(winding_number([0.5, 0.5], &ccw), 1);
        assert_eq!(winding_number([1.5, 0.5], &ccw), 0);
        let cw: Vec<[f64; 2]> = ccw.iter().rev().copied().collect();
        assert_eq!(winding_number([0.5, 0.5], &cw), -1);
        assert_eq!(winding_number([-0.5, 0.5], &cw), 0);
    }

    #[test]
    fn nodes_beyond_a_grid_aligned_side_are_the_next_column_out() {
        let grid = Grid {
            h: 1.0,
            origin: [0.0, 0.0],
        };
        // An anchor on x = 0 that has moved a hair left: the nodes on x = 0
        // are not beyond it, those on x = -1 within a cell along it are.
        let found: Vec<[f64; 2]> = nodes_beyond(&grid, [-1e-4, 2.3], [-1.0, 0.0])
            .map(|k| grid.node_position(k))
            .collect();
        assert_eq!(found, vec![[-1.0, 2.0], [-1.0, 3.0]]);
    }

    #[test]
    fn projections_hold_the_right_components() {
        let n = [0.6, 0.8];
        let p = projection(Fix::Normal, n);
        let v = p * Vector2::new(0.8, -0.6); // tangential
        assert!(v.norm() < 1e-15);
        let v = p * Vector2::new(0.6, 0.8);
        assert!((v - Vector2::new(0.6, 0.8)).norm() < 1e-15);
        assert_eq!(projection(Fix::X, n), Matrix2::new(1.0, 0.0, 0.0, 0.0));
    }
}
