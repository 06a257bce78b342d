//! The implicit boundary method on a 3D body's surface patches
//! ([`crate::boundary::face_patches`]): the plane-strain method of the
//! module docs ([`super`]) with the curve's segments replaced by the
//! surface's Bezier cells.
//!
//! - **Anchors.** The 4 x 4 Gauss points of each selected reference cell
//!   (within the support's ranges), each with its parameter weight, the
//!   outward unit normal of the reference surface there (the wall a
//!   roller slides on) and the material point that carries the cell
//!   corner nearest it. Carried by the grid's increment at the end of
//!   every step, as in 2D. Unlike the curve's (and the surface loads'),
//!   the cells are not cut at the knot planes: a linear field, which the
//!   shape functions hold exactly, has no penalty energy at any point
//!   however the kinks fall, so the cuts buy no exactness, and quartering
//!   a cell three times where it straddles a plane made a slab's faces
//!   681,256 anchors (20 a cell's worth) and its assembly 4 s an
//!   iteration at 1,920 points. A cell of a data spacing (at most half a
//!   cell) holds 16 anchors, 64 a grid cell's face.
//! - **Band.** Each anchor's penalty `(4/3) P A_nn P dA / delta`, `dA` the
//!   area it stands for on the current surface, `A_nn` the acoustic
//!   tensor of its point's material, `P` the projection on the held
//!   components (`n n` for a roller on the normal).
//! - **Ghost ties, only without the ghost penalty.** With the ghost
//!   penalty off (`analysis.stabilisation.ghost_penalty: 0`), the nodes
//!   beyond a supported surface by more than a tenth of a cell (and within
//!   the basis's reach) are tied inward along the grid axis closest to the
//!   normal, as in 2D, with a tenth of `A_nn h` (a cell's stiffness in 3D
//!   is a modulus times a length). With the penalty on (the default) they
//!   are left out: the penalty already holds those nodes to the field
//!   inside, and a tie on top of the band slaves the node the band needs
//!   to bend the cut cell: it doubled a rigid footing's error (docs/ibm.md,
//!   In 3D, ties only without the ghost penalty). An averaged support's
//!   anchors (a rigid footing's) find none, as in plane strain. Plane
//!   strain also leaves out the nodes inside a concave stretch of the
//!   curve; the surfaces have no inside test yet, so on a concave
//!   supported region a node inside the material may be tied.

use std::collections::BTreeMap;

use nalgebra::SMatrix;
use rayon::prelude::*;

use super::anchors::{Carried, acoustic_tensor, held_projection};
use super::band::{BandPoint, BandTerms};
use super::ghost_ties::{GhostTie, nodes_beyond};
use crate::boundary::face_patches::FacePatch;
use crate::boundary::quadrature::hat_shares;
use crate::boundary::surface::{Interpolation, cross, interpolate};
use crate::boundary::surface_loading::cell_gauss_points;
use crate::case::solid::SurfaceSelector;
use crate::configuration::Configuration;
use crate::grid::NodeKey;
use crate::particles::MaterialPoints;

/// A support imposed on regions of the surface patches by the implicit
/// boundary method.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceSupport {
    /// Its index among the case's supports (for reactions).
    pub index: usize,
    /// The cells it holds, `(patch, cells k + cells_u l)`, and the
    /// selector whose ranges choose their quadrature points, if it gives
    /// any.
    pub regions: Vec<(usize, Vec<usize>)>,
    pub ranges: Option<SurfaceSelector>,
    /// The components it holds; `None`: the reference surface's normal.
    pub held: Option<[bool; 3]>,
    /// Prescribed displacement at load factor 1.
    pub displacement: [f64; 3],
    /// Held on average over pieces about this size (m) a side rather than
    /// at every quadrature point: [`super::AVERAGED_PIECE_CELLS`] cells.
    pub averaged: Option<f64>,
}

/// A quadrature point of a surface support, Lagrangian: fixed on the
/// reference surface, carried by the grid's displacement.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceAnchor {
    /// Index of the support among the case's (for reactions).
    pub support: usize,
    patch: usize,
    cell: usize,
    /// Parameters in the cell and the Gauss weight per unit parameter area.
    s: f64,
    t: f64,
    weight: f64,
    /// The material point that carries the cell corner nearest it: its
    /// tangent stands for the band's, and it carries the anchor in a step
    /// where the anchor touches no active node.
    point: usize,
    held: Option<[bool; 3]>,
    /// Outward unit normal of the reference surface.
    normal: [f64; 3],
    prescribed: [f64; 3],
    /// Reference position and the displacement since.
    reference: [f64; 3],
    moved: [f64; 3],
    /// The piece of an averaged support it belongs to, whose anchors share
    /// one constraint.
    piece: Option<usize>,
    /// Its support's ranges, if it gives any
    /// ([`SurfaceAnchor::share_inside`]).
    ranges: Option<SurfaceSelector>,
}

impl SurfaceAnchor {
    /// Its displacement since the reference configuration (what a
    /// checkpoint keeps of it).
    pub fn moved(&self) -> [f64; 3] {
        self.moved
    }

    pub(crate) fn set_moved(&mut self, moved: [f64; 3]) {
        self.moved = moved;
    }

    /// Current position.
    pub fn position(&self) -> [f64; 3] {
        std::array::from_fn(|d| self.reference[d] + self.moved[d])
    }

    /// The share of the surface it stands for, `area`, that lies within
    /// its support's ranges: 1 without ranges. Taken as a square of
    /// `area` about the anchor in the reference tangent plane, so that the share falls from 1 to 0 as the
    /// square crosses the edge, and placed, as the curve's anchors are
    /// (`Anchor::share_inside`), by the reference position plus the part
    /// of its motion the support does not hold, along the surface (a
    /// smooth footing's soil sliding out beneath it). The cells' quadrature does not end at the
    /// edge (the curve's does), so the shares also make the held area the
    /// region's to second order in the anchors' spacing.
    fn share_inside(&self, area: f64) -> f64 {
        let Some(ranges) = &self.ranges else {
            return 1.0;
        };
        let held = held_projection(self.held, self.normal);
        let moved = nalgebra::Vector3::from(self.moved);
        let free = moved - held * moved;
        // Along the surface only: the anchor's side of a range across the
        // normal stays where it was.
        let n = nalgebra::Vector3::from(self.normal);
        let along = free - n * n.dot(&free);
        let p = std::array::from_fn(|d| self.reference[d] + along[d]);
        overlap_share(ranges, p, area.sqrt(), self.normal)
    }
}

/// The share of a square of side `side` centred at `p` in the plane
/// normal to `n` that lies within the ranges of `ranges`: for each
/// coordinate a range measures (each axis of `inside`; the distance from
/// `inside_cylinder`'s axis), the overlap of the square's extent along it
/// (`side` times the sine of its angle to `n`) with the range, over that
/// extent; a position test (to a billionth of `side`) along a coordinate
/// the square does not extend in (the normal's).
fn overlap_share(ranges: &SurfaceSelector, p: [f64; 3], side: f64, n: [f64; 3]) -> f64 {
    let overlap = |c: f64, cos: f64, lo: f64, hi: f64| {
        let extent = side * (1.0 - cos * cos).max(0.0).sqrt();
        let tol = 1e-9 * side;
        if extent <= tol {
            return if c >= lo - tol && c <= hi + tol {
                1.0
            } else {
                0.0
            };
        }
        let half = 0.5 * extent;
        ((c + half).min(hi) - (c - half).max(lo)).clamp(0.0, extent) / extent
    };
    let mut share = 1.0;
    if let Some(b) = &ranges.inside {
        for d in 0..3 {
            share *= overlap(p[d], n[d], b.min[d], b.max[d]);
        }
    }
    if let Some(c) = &ranges.inside_cylinder {
        let (dx, dy) = (p[0] - c.center[0], p[1] - c.center[1]);
        let r = dx.hypot(dy);
        let cos = if r > 0.0 {
            (n[0] * dx + n[1] * dy) / r
        } else {
            0.0
        };
        share *= overlap(r, cos, f64::NEG_INFINITY, c.radius);
    }
    share
}

impl Carried<3> for SurfaceAnchor {
    fn point(&self) -> usize {
        self.point
    }

    fn moved_mut(&mut self) -> &mut [f64; 3] {
        &mut self.moved
    }
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn unit(v: [f64; 3]) -> [f64; 3] {
    v.map(|c| c / norm(v))
}

/// The anchors of the surface supports: Gauss points of the reference
/// cells each holds, within its ranges. An averaged support's are put in
/// pieces ([`into_pieces`]).
pub fn surface_anchors(
    supports: &[SurfaceSupport],
    faces: &[FacePatch],
    points: &MaterialPoints<3>,
) -> Vec<SurfaceAnchor> {
    let mut out = Vec::new();
    let mut surfaces = BTreeMap::new();
    let mut pieces = 0;
    for s in supports {
        let first = out.len();
        for (patch, cells) in &s.regions {
            let face = &faces[*patch];
            let surface = surfaces
                .entry(*patch)
                .or_insert_with(|| interpolate(&face.reference_grid(points)));
            for &cell in cells {
                let bezier = &surface.patches[cell];
                for (u, v, weight) in cell_gauss_points() {
                    let (x, a, b) = bezier.evaluate(u, v);
                    let normal = unit(cross(a, b));
                    let side = (weight * norm(cross(a, b))).sqrt();
                    if s.ranges
                        .is_some_and(|r| overlap_share(&r, x, side, normal) <= 0.0)
                    {
                        continue;
                    }
                    let corner = [usize::from(u >= 0.5), usize::from(v >= 0.5)];
                    out.push(SurfaceAnchor {
                        support: s.index,
                        patch: *patch,
                        cell,
                        s: u,
                        t: v,
                        weight,
                        point: face.corner(cell, corner).point,
                        held: s.held,
                        normal,
                        prescribed: s.displacement,
                        reference: x,
                        moved: [0.0; 3],
                        piece: None,
                        ranges: s.ranges,
                    });
                }
            }
        }
        if let Some(side) = s.averaged {
            pieces = into_pieces(&mut out[first..], side, pieces);
        }
    }
    out
}

/// Puts one averaged support's anchors into pieces of about `side` a
/// side, numbered from `next`: the box that holds their reference places
/// divided evenly along each axis into `round(extent / side)` parts (at
/// least one; on a flat footing, squares of about two cells). Returns the
/// next free piece number.
fn into_pieces(anchors: &mut [SurfaceAnchor], side: f64, next: usize) -> usize {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for a in anchors.iter() {
        for d in 0..3 {
            lo[d] = lo[d].min(a.reference[d]);
            hi[d] = hi[d].max(a.reference[d]);
        }
    }
    let parts: [usize; 3] =
        std::array::from_fn(|d| ((hi[d] - lo[d]) / side).round().max(1.0) as usize);
    let mut numbers = BTreeMap::new();
    for a in anchors.iter_mut() {
        let bin: [usize; 3] = std::array::from_fn(|d| {
            let x = if hi[d] > lo[d] {
                parts[d] as f64 * (a.reference[d] - lo[d]) / (hi[d] - lo[d])
            } else {
                0.0
            };
            (x as usize).min(parts[d] - 1)
        });
        let n = numbers.len();
        a.piece = Some(next + *numbers.entry(bin).or_insert(n));
    }
    next + numbers.len()
}

impl BandTerms<3> {
    /// The band terms of a 3D load step from `start`: each anchor's
    /// penalty on the current surface, and the ghost ties if `ties` (the
    /// module docs).
    pub fn on_surfaces(
        start: &Configuration<3>,
        faces: &[FacePatch],
        anchors: &[SurfaceAnchor],
        band_width: f64,
        load_factor: f64,
        ties: bool,
    ) -> Self {
        let Configuration {
            grid, conn, points, ..
        } = *start;
        let mut patches: Vec<usize> = anchors.iter().map(|a| a.patch).collect();
        patches.sort_unstable();
        patches.dedup();
        let surfaces: BTreeMap<usize, Interpolation> = (patches.par_iter())
            .map(|&k| (k, Interpolation::new(faces[k].data_grid(points))))
            .collect();
        // Each anchor's part, made in parallel and added in the anchors'
        // order (so the sums do not depend on the threads). The anchors of
        // a cell share their point and normal: the acoustic tensor of the
        // last one is kept.
        let made: Vec<Option<AnchorTerm>> = (anchors.par_iter())
            .with_min_len(256)
            .map_init(
                || (Vec::with_capacity(8), None),
                |(weights, last), a| {
                    let x = a.position();
                    let mut shares = Vec::with_capacity(8);
                    if !hat_shares(start.basis, grid, x, &conn.nodes, weights, &mut shares) {
                        return None;
                    }
                    let surface = &surfaces[&a.patch];
                    let cu = surface.grid().cells()[0];
                    let (_, ds, dt) = surface.patch(a.cell % cu, a.cell / cu).evaluate(a.s, a.t);
                    let n = cross(ds, dt);
                    let span = a.weight * norm(n);
                    let area = a.share_inside(span) * span;
                    if area <= 0.0 {
                        // Slid out from under an averaged support: it is
                        // only carried.
                        return Some(AnchorTerm { shares, held: None });
                    }
                    let a_nn = match *last {
                        Some((p, normal, a_nn)) if p == a.point && normal == a.normal => a_nn,
                        _ => acoustic_tensor(points, a.point, a.normal),
                    };
                    *last = Some((a.point, a.normal, a_nn));
                    let reach = start.basis.reach_beyond_boundary();
                    let beyond = if ties && a.piece.is_none() {
                        (nodes_beyond(grid, x, a.normal, reach))
                            .filter(|key| conn.nodes.binary_search(key).is_ok())
                            .collect()
                    } else {
                        Vec::new()
                    };
                    let held = held_projection(a.held, a.normal);
                    Some(AnchorTerm {
                        shares,
                        held: Some(Held {
                            stiffness: held * a_nn * held * (area * 4.0 / (3.0 * band_width)),
                            area,
                            beyond,
                        }),
                    })
                },
            )
            .collect();
        let mut terms = BandTerms::empty(grid.h, band_width);
        let mut beyond: BTreeMap<NodeKey, usize> = BTreeMap::new();
        let mut pieces = BTreeMap::new();
        for (i, (a, made)) in anchors.iter().zip(made).enumerate() {
            let Some(made) = made else { continue };
            let first = terms.shares.len();
            terms.shares.extend(made.shares);
            terms.carriers.push((i, first, terms.shares.len()));
            let Some(held) = made.held else { continue };
            for key in held.beyond {
                beyond.entry(key).or_insert(i);
            }
            let point = BandPoint {
                support: a.support,
                first,
                last: terms.shares.len(),
                stiffness: held.stiffness,
                length: held.area,
                at: a.position(),
                target: std::array::from_fn(|d| load_factor * a.prescribed[d] - a.moved[d]),
            };
            terms.add_point(&mut pieces, a.piece, point);
        }
        terms.add_pieces(pieces);
        for (&key, &i) in &beyond {
            let a = &anchors[i];
            let a_nn = acoustic_tensor(points, a.point, a.normal);
            terms.ghosts.extend(GhostTie::inward(
                key,
                a.normal,
                &conn.nodes,
                a_nn * grid.h,
                a.support,
            ));
        }
        terms.couple();
        terms
    }
}

/// What one anchor adds to a step's band: its shares of the active nodes
/// (which carry it), and what it holds unless it slid out from under an
/// averaged support.
struct AnchorTerm {
    shares: Vec<(usize, f64)>,
    held: Option<Held>,
}

struct Held {
    /// `P A_nn P dA (4/3) / delta`, and `dA`.
    stiffness: SMatrix<f64, 3, 3>,
    area: f64,
    /// The active nodes beyond the surface there.
    beyond: Vec<NodeKey>,
}

#[cfg(test)]
mod tests {
    use crate::case::solid::SolidCase;
    use crate::stepper::Simulation;

    use super::*;

    /// The area the anchors of each surface support stand for, in the
    /// reference configuration.
    fn held_areas(sim: &Simulation<3>, n: usize) -> Vec<f64> {
        let mut areas = vec![0.0; n];
        for a in &sim.surface_anchors {
            let surface = interpolate(&sim.faces[a.patch].reference_grid(&sim.points));
            let (_, ds, dt) = surface.patches[a.cell].evaluate(a.s, a.t);
            let normal = cross(ds, dt);
            let area = a.weight * norm(normal);
            areas[a.support] += a.share_inside(area) * area;
        }
        areas
    }

    /// A quarter disc of radius 0.5 m on the top of a box, its edge inside
    /// the surface's cells (0.125 m, the data points' spacing), held by
    /// the quadrature points within it: the area they stand for is the
    /// disc's to the quadrature's resolution at its edge (Gauss points
    /// a few hundredths of a metre apart there, each weighed by the share
    /// of its square within it: measured +3.4e-3); a whole
    /// face beside it, selected by its plane, is its exact area, and so
    /// is a rectangle of the top given as a box about it. Averaged,
    /// the disc's anchors are one piece (its side is two cells, 0.5 m).
    #[test]
    fn a_footing_holds_its_own_disc() {
        let case = serde_json::json!({
            "version": 1,
            "analysis": { "type": "3d", "load_steps": 1 },
            "grid": { "cell_size": 0.25, "origin": [-0.075, -0.075, -0.075] },
            "basis": "gimp",
            "bodies": [{
                "geometry": { "box": { "min": [0.0, 0.0, 0.0], "max": [2.0, 2.0, 1.5] } },
                "points": { "per_cell": 2 },
                "material": { "model": "linear_elastic", "youngs_modulus": 1.0e6, "poisson_ratio": 0.3, "density": 0.0 }
            }],
            "surface_supports": [
                { "on": { "plane": { "point": [0.0, 0.0, 1.5], "normal": [0.0, 0.0, 1.0] },
                          "inside_cylinder": { "center": [0.0, 0.0], "radius": 0.5 } },
                  "fix": "z", "constraint": "averaged" },
                { "on": { "plane": { "point": [0.0, 0.0, 0.0], "normal": [1.0, 0.0, 0.0] } }, "fix": "normal" },
                { "on": { "plane": { "point": [0.0, 0.0, 1.5], "normal": [0.0, 0.0, 1.0] },
                          "inside": { "min": [0.0, 0.0, 1.4], "max": [0.6, 0.7, 1.6] } }, "fix": "xyz" }
            ]
        });
        let case = SolidCase::from_json(&case.to_string()).unwrap();
        let sim = Simulation::from_solid_case(&case).unwrap();
        let areas = held_areas(&sim, 3);
        let disc = std::f64::consts::PI * 0.25 / 4.0;
        let miss = (areas[0] - disc) / disc;
        eprintln!("the disc's anchors stand for {miss:+.2e} of its area");
        assert!(miss.abs() < 5e-3, "{} against {disc}: {miss:e}", areas[0]);
        assert!((areas[1] - 3.0).abs() < 1e-9, "{}", areas[1]);
        // A box about a rectangle of the top: a range along the normal is a
        // position test, across it an overlap (measured -5.9e-3: the Gauss
        // points' squares do not tile their cells, their weights being
        // uneven).
        let flat = (areas[2] - 0.42) / 0.42;
        eprintln!("the box's anchors stand for {flat:+.2e} of its area");
        assert!(flat.abs() < 1e-2, "{}", areas[2]);
        let disc_anchors = sim.surface_anchors.iter().filter(|a| a.support == 0);
        assert!(disc_anchors.clone().all(|a| a.piece == Some(0)));
        assert!(
            disc_anchors
                .clone()
                .all(|a| (a.normal[2] - 1.0).abs() < 1e-12)
        );
        // The roller's normal is the face's outward one.
        let side = sim.surface_anchors.iter().find(|a| a.support == 1).unwrap();
        assert!((side.normal[0] + 1.0).abs() < 1e-12, "{:?}", side.normal);
    }
}
