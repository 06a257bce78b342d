//! The surface of a 3D body as face patches: each face of its reference
//! geometry (a box's six, a cylinder's side and two discs, a cube-sphere's
//! six, a hexahedral mesh's outer element faces) sampled on a structured
//! grid of data points, each carried by the body's material point nearest
//! it. A data point at reference offset `o` from its point `p` is at
//! `x_p + F_p o` now: the 2D boundary's `edge` representation (an outer
//! point pushed to the material's edge, mapped by its deformation) on a
//! grid. [`super::surface::interpolate`] makes each patch's bicubic surface
//! from its data every step.
//!
//! Along each direction of a face the grid has `n = round(length /
//! spacing)` cells of the body's own spacing; the data points are the
//! cells' middles and the two ends (a closed direction, round a cylinder,
//! has no ends). On a body seeded on its own lattice (a box; the side of an
//! extrusion along z) the cells are the lattice's, so each data point is
//! the outer point's face middle: the paper's surface through the outer
//! points, pushed to the edge. Elsewhere (a sphere's bands, a disc's rings)
//! the grid does not follow the points, and each data point rides the
//! point nearest it, a Taylor step of at most about a spacing.
//!
//! Joins. Faces that meet at a smooth seam (a cube-sphere's) sample their
//! common edge at the same places, so their data points coincide and the
//! edge curves, made from the same line of data, are the same: the surface
//! is closed there. Faces that meet at an edge of the body (a box's, a
//! cylinder's rims), and a hexahedral mesh's neighbouring element faces,
//! are sampled each on its own: their data points lie on the same edge,
//! and their edge curves differ by the interpolation's error there.
//! Neither is a problem for the loads or the boundary method, which
//! integrate each patch on its own.

use super::surface::{DataGrid, Point3};
use crate::geometry::{Geometry, HexMesh};
use crate::particles::MaterialPoints;
use crate::particles::solid_seeding::Solid;

/// One face of a body's reference geometry, mapped from `(s, t)` in `[0,
/// 1]^2`; its outward normal is along `X_s x X_t`.
#[derive(Debug, Clone, PartialEq)]
pub enum ReferenceFace {
    /// A bilinear quadrilateral, corners at `(0, 0), (1, 0), (1, 1), (0, 1)`.
    Quad([[f64; 3]; 4]),
    /// Part of a cylinder's side about the z axis through `center`: `s`
    /// along the angle (radians, counter-clockwise), `t` along z; outward
    /// unless `inward`.
    CylinderSide {
        center: [f64; 2],
        radius: f64,
        angles: [f64; 2],
        z: [f64; 2],
        inward: bool,
    },
    /// Part of an annulus in the plane `z`: `s` along the radius, `t` along
    /// the angle; facing +z unless `down`.
    Ring {
        center: [f64; 2],
        radii: [f64; 2],
        angles: [f64; 2],
        z: f64,
        down: bool,
    },
    /// One of the four outer patches of a disc in the plane `z` (the inner
    /// patch is the square of half-side `r / 2`, a [`ReferenceFace::Quad`]):
    /// `s` from the square's side (0) to the rim (1), `t` along the angle
    /// from `-45 + 90 part` degrees; facing +z unless `down`.
    DiscSide {
        center: [f64; 2],
        radius: f64,
        part: usize,
        z: f64,
        down: bool,
    },
    /// Face `face` of a cube-sphere (equiangular gnomonic: the face `axis =
    /// face / 2` on the side `(-1)^face`); outward unless `inward`.
    SphereFace {
        center: [f64; 3],
        radius: f64,
        face: usize,
        inward: bool,
    },
}

fn lerp(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    std::array::from_fn(|d| a[d] + t * (b[d] - a[d]))
}

impl ReferenceFace {
    /// The point at `(s, t)`.
    pub fn at(&self, s: f64, t: f64) -> [f64; 3] {
        use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};
        match *self {
            ReferenceFace::Quad(c) => lerp(lerp(c[0], c[1], s), lerp(c[3], c[2], s), t),
            ReferenceFace::CylinderSide {
                center,
                radius,
                angles,
                z,
                inward,
            } => {
                let s = if inward { 1.0 - s } else { s };
                let a = angles[0] + s * (angles[1] - angles[0]);
                [
                    center[0] + radius * a.cos(),
                    center[1] + radius * a.sin(),
                    z[0] + t * (z[1] - z[0]),
                ]
            }
            ReferenceFace::Ring {
                center,
                radii,
                angles,
                z,
                down,
            } => {
                let t = if down { 1.0 - t } else { t };
                let (r, a) = (
                    radii[0] + s * (radii[1] - radii[0]),
                    angles[0] + t * (angles[1] - angles[0]),
                );
                [center[0] + r * a.cos(), center[1] + r * a.sin(), z]
            }
            ReferenceFace::DiscSide {
                center,
                radius,
                part,
                z,
                down,
            } => {
                let t = if down { 1.0 - t } else { t };
                let a = -FRAC_PI_4 + FRAC_PI_2 * (part as f64 + t);
                // The square's side between its corners at the patch's
                // two angles, and the rim.
                let corner = |a: f64| {
                    let r = radius / 2.0 * std::f64::consts::SQRT_2;
                    [center[0] + r * a.cos(), center[1] + r * a.sin(), z]
                };
                let a0 = -FRAC_PI_4 + FRAC_PI_2 * part as f64;
                let inner = lerp(corner(a0), corner(a0 + FRAC_PI_2), t);
                let rim = [
                    center[0] + radius * a.cos(),
                    center[1] + radius * a.sin(),
                    z,
                ];
                lerp(inner, rim, s)
            }
            ReferenceFace::SphereFace {
                center,
                radius,
                face,
                inward,
            } => {
                let s = if inward { 1.0 - s } else { s };
                let axis = face / 2;
                let sign = if face.is_multiple_of(2) { 1.0 } else { -1.0 };
                let (e1, e2) = ((axis + 1) % 3, (axis + 2) % 3);
                let mut d = [0.0; 3];
                d[axis] = sign;
                d[e1] = (-FRAC_PI_4 + FRAC_PI_2 * s).tan() * sign;
                d[e2] = (-FRAC_PI_4 + FRAC_PI_2 * t).tan();
                let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                std::array::from_fn(|k| center[k] + radius * d[k] / n)
            }
        }
    }

    /// Whether direction `d` closes on itself (a full turn round).
    pub fn closed(&self) -> [bool; 2] {
        let full = |a: [f64; 2]| (a[1] - a[0]).abs() >= std::f64::consts::TAU - 1e-12;
        match self {
            ReferenceFace::CylinderSide { angles, .. } => [full(*angles), false],
            ReferenceFace::Ring { angles, .. } => [false, full(*angles)],
            _ => [false, false],
        }
    }

    /// The face's length along `s` and along `t`: the longer of its two
    /// sides each way (its middle line, for a closed direction).
    fn lengths(&self) -> [f64; 2] {
        let polyline = |f: &dyn Fn(f64) -> [f64; 3]| {
            (0..32)
                .map(|k| {
                    let (a, b) = (f(k as f64 / 32.0), f((k + 1) as f64 / 32.0));
                    (0..3).map(|d| (b[d] - a[d]).powi(2)).sum::<f64>().sqrt()
                })
                .sum::<f64>()
        };
        let along_s = |t: f64| polyline(&|s| self.at(s, t));
        let along_t = |s: f64| polyline(&|t| self.at(s, t));
        [
            along_s(0.0).max(along_s(0.5)).max(along_s(1.0)),
            along_t(0.0).max(along_t(0.5)).max(along_t(1.0)),
        ]
    }

    /// The data parameters along each direction at about `spacing`: the
    /// middles of `n` equal cells (at least four round a closed one), and
    /// the ends where the direction is open.
    pub fn samples(&self, spacing: f64) -> [Vec<f64>; 2] {
        let lengths = self.lengths();
        let closed = self.closed();
        [0, 1].map(|d| {
            // A closed line needs three points for its circle tangents;
            // four keep a thin cylinder round.
            let least = if closed[d] { 4.0 } else { 1.0 };
            let n = (lengths[d] / spacing).round().max(least) as usize;
            let middles = (0..n).map(|i| (i as f64 + 0.5) / n as f64);
            if closed[d] {
                middles.collect()
            } else {
                std::iter::once(0.0)
                    .chain(middles)
                    .chain(std::iter::once(1.0))
                    .collect()
            }
        })
    }
}

/// The faces of a body's reference geometry, each oriented outward.
pub fn reference_faces(solid: &Solid) -> Vec<ReferenceFace> {
    match solid {
        Solid::Extrusion { section, z } => extrusion_faces(section, *z),
        Solid::SphericalShell {
            center,
            inner_radius,
            outer_radius,
        } => {
            let mut faces: Vec<ReferenceFace> = (0..6)
                .map(|face| ReferenceFace::SphereFace {
                    center: *center,
                    radius: *outer_radius,
                    face,
                    inward: false,
                })
                .collect();
            if *inner_radius > 0.0 {
                faces.extend((0..6).map(|face| ReferenceFace::SphereFace {
                    center: *center,
                    radius: *inner_radius,
                    face,
                    inward: true,
                }));
            }
            faces
        }
        Solid::Mesh(mesh) => mesh_faces(mesh),
    }
}

fn at_z(p: [f64; 2], z: f64) -> [f64; 3] {
    [p[0], p[1], z]
}

/// The sides of the closed ring `ring` (material on its left) from `z[0]`
/// to `z[1]`, one quadrilateral each.
fn ring_sides(ring: &[[f64; 2]], z: [f64; 2], out: &mut Vec<ReferenceFace>) {
    for k in 0..ring.len() {
        let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
        out.push(ReferenceFace::Quad([
            at_z(a, z[0]),
            at_z(b, z[0]),
            at_z(b, z[1]),
            at_z(a, z[1]),
        ]));
    }
}

/// The two caps from counter-clockwise quadrilaterals of the section.
fn quad_caps(quads: &[[[f64; 2]; 4]], z: [f64; 2], out: &mut Vec<ReferenceFace>) {
    for q in quads {
        out.push(ReferenceFace::Quad(
            [q[0], q[3], q[2], q[1]].map(|p| at_z(p, z[0])),
        ));
        out.push(ReferenceFace::Quad(q.map(|p| at_z(p, z[1]))));
    }
}

/// A ring with the material on its left: counter-clockwise for an outer
/// boundary, clockwise for a hole.
fn oriented(ring: &[[f64; 2]], outer: bool) -> Vec<[f64; 2]> {
    let ccw = crate::geometry::signed_area(ring) > 0.0;
    if ccw == outer {
        ring.to_vec()
    } else {
        ring.iter().rev().copied().collect()
    }
}

fn extrusion_faces(section: &Geometry, z: [f64; 2]) -> Vec<ReferenceFace> {
    use std::f64::consts::TAU;
    let mut out = Vec::new();
    match section {
        Geometry::Circle { center, radius } => {
            out.push(ReferenceFace::CylinderSide {
                center: *center,
                radius: *radius,
                angles: [0.0, TAU],
                z,
                inward: false,
            });
            let h = radius / 2.0;
            let square =
                [[-h, -h], [h, -h], [h, h], [-h, h]].map(|[x, y]| [center[0] + x, center[1] + y]);
            quad_caps(&[square], z, &mut out);
            for (zc, down) in [(z[0], true), (z[1], false)] {
                for part in 0..4 {
                    out.push(ReferenceFace::DiscSide {
                        center: *center,
                        radius: *radius,
                        part,
                        z: zc,
                        down,
                    });
                }
            }
        }
        Geometry::Annulus {
            center,
            inner_radius,
            outer_radius,
        } => annulus_faces(
            *center,
            [*inner_radius, *outer_radius],
            [0.0, TAU],
            z,
            &mut out,
        ),
        Geometry::AnnulusSector {
            center,
            inner_radius,
            outer_radius,
            start_angle,
            end_angle,
        } => {
            let angles = [start_angle.to_radians(), end_angle.to_radians()];
            let angles = if angles[1] > angles[0] {
                angles
            } else {
                [angles[0], angles[1] + TAU]
            };
            annulus_faces(*center, [*inner_radius, *outer_radius], angles, z, &mut out);
            let radial = |a: f64, r: f64| [center[0] + r * a.cos(), center[1] + r * a.sin()];
            // The two straight sides, material on the left going out along
            // the end angle and in along the start angle.
            let (r0, r1) = (*inner_radius, *outer_radius);
            ring_sides_open(&[radial(angles[1], r1), radial(angles[1], r0)], z, &mut out);
            ring_sides_open(&[radial(angles[0], r0), radial(angles[0], r1)], z, &mut out);
        }
        Geometry::Mesh(mesh) => {
            let rings = mesh
                .boundary_rings()
                .expect("validated: the mesh's boundary is rings");
            for ring in &rings {
                ring_sides(ring, z, &mut out);
            }
            quad_caps(&crate::particles::seeding::mesh_patches(mesh), z, &mut out);
        }
        _ => {
            let (outer, holes) = section_rings(section);
            ring_sides(&oriented(&outer, true), z, &mut out);
            for h in &holes {
                ring_sides(&oriented(h, false), z, &mut out);
            }
            quad_caps(
                &crate::particles::seeding::polygon_patches(&outer, &holes),
                z,
                &mut out,
            );
        }
    }
    out
}

/// The straight side from `a` to `b` (material on its left) as one
/// quadrilateral.
fn ring_sides_open(ab: &[[f64; 2]; 2], z: [f64; 2], out: &mut Vec<ReferenceFace>) {
    let [a, b] = *ab;
    out.push(ReferenceFace::Quad([
        at_z(a, z[0]),
        at_z(b, z[0]),
        at_z(b, z[1]),
        at_z(a, z[1]),
    ]));
}

/// The curved sides and caps of an annulus or its sector.
fn annulus_faces(
    center: [f64; 2],
    radii: [f64; 2],
    angles: [f64; 2],
    z: [f64; 2],
    out: &mut Vec<ReferenceFace>,
) {
    out.push(ReferenceFace::CylinderSide {
        center,
        radius: radii[1],
        angles,
        z,
        inward: false,
    });
    out.push(ReferenceFace::CylinderSide {
        center,
        radius: radii[0],
        angles,
        z,
        inward: true,
    });
    for (zc, down) in [(z[0], true), (z[1], false)] {
        out.push(ReferenceFace::Ring {
            center,
            radii,
            angles,
            z: zc,
            down,
        });
    }
}

/// A polygonal section's outer ring and holes (a rectangle's or a
/// quadrilateral's corners).
fn section_rings(section: &Geometry) -> (Vec<[f64; 2]>, Vec<Vec<[f64; 2]>>) {
    match section {
        Geometry::Polygon { vertices, holes } => (vertices.clone(), holes.clone()),
        Geometry::Quadrilateral { vertices } => (vertices.to_vec(), Vec::new()),
        Geometry::Rectangle { min, max, .. } => {
            let corners = section.turned_corners().unwrap_or([
                *min,
                [max[0], min[1]],
                *max,
                [min[0], max[1]],
            ]);
            (corners.to_vec(), Vec::new())
        }
        _ => unreachable!("curved sections and meshes have their own faces"),
    }
}

/// The element faces of a hexahedral mesh that no other element has,
/// each oriented away from its element.
fn mesh_faces(mesh: &HexMesh) -> Vec<ReferenceFace> {
    use std::collections::HashMap;
    let mut count: HashMap<[usize; 4], usize> = HashMap::new();
    for k in 0..mesh.elements.len() {
        for f in 0..6 {
            *count.entry(mesh.face_key(k, f)).or_default() += 1;
        }
    }
    let mut out = Vec::new();
    for k in 0..mesh.elements.len() {
        let corners = mesh.corners(k);
        let centre: [f64; 3] =
            std::array::from_fn(|d| corners.iter().map(|c| c[d]).sum::<f64>() / 8.0);
        for f in 0..6 {
            if count[&mesh.face_key(k, f)] != 1 {
                continue;
            }
            let mut quad = HexMesh::FACES[f].map(|i| corners[i]);
            let face = ReferenceFace::Quad(quad);
            let (p, n) = (face.at(0.5, 0.5), face_normal(&face));
            let away: f64 = (0..3).map(|d| n[d] * (p[d] - centre[d])).sum();
            if away < 0.0 {
                quad.swap(1, 3);
            }
            out.push(ReferenceFace::Quad(quad));
        }
    }
    out
}

/// `X_s x X_t` at the face's middle, by differences.
fn face_normal(face: &ReferenceFace) -> [f64; 3] {
    let e = 1e-6;
    let d = |a: [f64; 3], b: [f64; 3]| -> [f64; 3] {
        std::array::from_fn(|k| (b[k] - a[k]) / (2.0 * e))
    };
    let xs = d(face.at(0.5 - e, 0.5), face.at(0.5 + e, 0.5));
    let xt = d(face.at(0.5, 0.5 - e), face.at(0.5, 0.5 + e));
    super::surface::cross(xs, xt)
}

/// A data point: carried by material point `point`, at `offset` from it
/// in the reference configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DataPoint {
    pub point: usize,
    pub offset: [f64; 3],
}

/// One face patch of a body's surface: its structured grid of carried data
/// points (`counts[0]` along `s`, fastest).
#[derive(Debug, Clone, PartialEq)]
pub struct FacePatch {
    pub body: usize,
    pub counts: [usize; 2],
    pub closed: [bool; 2],
    pub data: Vec<DataPoint>,
}

impl FacePatch {
    /// Bezier cells along each direction.
    pub fn data_grid_cells(&self) -> [usize; 2] {
        [0, 1].map(|d| {
            if self.closed[d] {
                self.counts[d]
            } else {
                self.counts[d] - 1
            }
        })
    }

    /// Each cell's middle in the reference configuration (the reference
    /// surface's point at the cell's parameter middle, on the true face to
    /// the interpolation's error), cells `k + cells_u l` in order: what a
    /// region selects cells by. A face's end cells are half a spacing
    /// wide, so the middles of a neighbouring face's cells along their
    /// common edge lie a quarter spacing off it.
    pub fn cell_middles(&self, points: &MaterialPoints<3>) -> Vec<[f64; 3]> {
        (super::surface::interpolate(&self.reference_grid(points))
            .patches
            .iter())
        .map(|patch| patch.point(0.5, 0.5))
        .collect()
    }

    /// The data points in the reference configuration.
    pub fn reference_grid(&self, points: &MaterialPoints<3>) -> DataGrid {
        DataGrid {
            counts: self.counts,
            closed: self.closed,
            points: (self.data.iter())
                .map(|c| {
                    let r = points.reference[c.point];
                    std::array::from_fn(|d| r[d] + c.offset[d])
                })
                .collect(),
        }
    }

    /// The data point at corner `corner` (`[0 or 1; 2]`) of cell `cell`.
    pub fn corner(&self, cell: usize, corner: [usize; 2]) -> &DataPoint {
        let cu = self.data_grid_cells()[0];
        let [nu, nv] = self.counts;
        let (i, j) = ((cell % cu + corner[0]) % nu, (cell / cu + corner[1]) % nv);
        &self.data[i + nu * j]
    }

    /// The data points where the points are now.
    pub fn data_grid(&self, points: &MaterialPoints<3>) -> DataGrid {
        DataGrid {
            counts: self.counts,
            closed: self.closed,
            points: self
                .data
                .iter()
                .map(|c| carried_position(points, c))
                .collect(),
        }
    }
}

/// A face patch's surface as served: a bicubic B-spline of `cells[0] x
/// cells[1]` Bezier cells, each interior knot triple (the cells meet with
/// continuous position; their tangent planes agree at the data points).
/// `control_points` is the `(3 cells[0] + 1) x (3 cells[1] + 1)` net, the
/// first index fastest; a closed direction's last row repeats its first.
/// The knots run over `0..=cells[d]`, one unit a cell.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SurfaceOutput {
    pub body: usize,
    pub cells: [usize; 2],
    pub closed: [bool; 2],
    pub degree: usize,
    pub knots: [Vec<f64>; 2],
    pub control_points: Vec<[f64; 3]>,
}

impl SurfaceOutput {
    /// The served form of `surface`, a face of body `body`.
    pub fn new(body: usize, closed: [bool; 2], surface: &super::surface::Surface) -> Self {
        let [cu, cv] = surface.cells;
        let (nu, nv) = (3 * cu + 1, 3 * cv + 1);
        let mut net = vec![[0.0; 3]; nu * nv];
        for (c, patch) in surface.patches.iter().enumerate() {
            let (k, l) = (c % cu, c / cu);
            for a in 0..4 {
                for b in 0..4 {
                    net[3 * k + a + nu * (3 * l + b)] = patch.control[a][b];
                }
            }
        }
        let knots = |n: usize| -> Vec<f64> {
            let mut k = vec![0.0; 4];
            for i in 1..n {
                k.extend([i as f64; 3]);
            }
            k.extend([n as f64; 4]);
            k
        };
        Self {
            body,
            cells: surface.cells,
            closed,
            degree: 3,
            knots: [knots(cu), knots(cv)],
            control_points: net,
        }
    }

    /// The point at `(s, t)` of cell `(k, l)`, from the net.
    pub fn point(&self, k: usize, l: usize, s: f64, t: f64) -> [f64; 3] {
        let nu = 3 * self.cells[0] + 1;
        let (bs, _) = super::surface::bernstein(s);
        let (bt, _) = super::surface::bernstein(t);
        let mut x = [0.0; 3];
        for a in 0..4 {
            for b in 0..4 {
                let p = self.control_points[3 * k + a + nu * (3 * l + b)];
                for d in 0..3 {
                    x[d] += bs[a] * bt[b] * p[d];
                }
            }
        }
        x
    }
}

/// Every face patch's surface through the points' current places.
pub fn surface_outputs(faces: &[FacePatch], points: &MaterialPoints<3>) -> Vec<SurfaceOutput> {
    faces
        .iter()
        .map(|f| {
            SurfaceOutput::new(
                f.body,
                f.closed,
                &super::surface::interpolate(&f.data_grid(points)),
            )
        })
        .collect()
}

/// `x_p + F_p o`.
pub fn carried_position(points: &MaterialPoints<3>, c: &DataPoint) -> Point3 {
    let (x, f) = (points.position[c.point], points.deformation[c.point]);
    std::array::from_fn(|i| x[i] + (0..3).map(|j| f[(i, j)] * c.offset[j]).sum::<f64>())
}

/// The face patches of body `body` (seeded from `solid` at `spacing`),
/// each data point carried by the body's point nearest it in the reference
/// configuration.
pub fn face_patches(
    points: &MaterialPoints<3>,
    body: usize,
    solid: &Solid,
    spacing: f64,
) -> Vec<FacePatch> {
    let nearest = Nearest::new(points, body, spacing);
    reference_faces(solid)
        .iter()
        .map(|face| {
            let [s, t] = face.samples(spacing);
            let data = t
                .iter()
                .flat_map(|&t| s.iter().map(move |&s| (s, t)))
                .map(|(s, t)| {
                    let x = face.at(s, t);
                    let point = nearest.find(points, x);
                    let r = points.reference[point];
                    DataPoint {
                        point,
                        offset: std::array::from_fn(|d| x[d] - r[d]),
                    }
                })
                .collect();
            FacePatch {
                body,
                counts: [s.len(), t.len()],
                closed: face.closed(),
                data,
            }
        })
        .collect()
}

/// A body's points binned by reference position, for the nearest to a
/// place.
struct Nearest {
    cell: f64,
    bins: std::collections::HashMap<[i64; 3], Vec<usize>>,
}

impl Nearest {
    fn new(points: &MaterialPoints<3>, body: usize, spacing: f64) -> Self {
        let mut bins: std::collections::HashMap<[i64; 3], Vec<usize>> = Default::default();
        for p in (0..points.len()).filter(|&p| points.material[p] as usize == body) {
            bins.entry(Self::key(points.reference[p], spacing))
                .or_default()
                .push(p);
        }
        Self {
            cell: spacing,
            bins,
        }
    }

    fn key(x: [f64; 3], cell: f64) -> [i64; 3] {
        x.map(|v| (v / cell).floor() as i64)
    }

    /// The nearest point to `x`: the bins within a growing reach, until
    /// one holds a point and the reach covers its distance.
    fn find(&self, points: &MaterialPoints<3>, x: [f64; 3]) -> usize {
        let k = Self::key(x, self.cell);
        let mut best: Option<(f64, usize)> = None;
        for reach in 1i64.. {
            for a in -reach..=reach {
                for b in -reach..=reach {
                    for c in -reach..=reach {
                        if a.abs().max(b.abs()).max(c.abs()) != reach && reach > 1 {
                            continue;
                        }
                        for &p in self
                            .bins
                            .get(&[k[0] + a, k[1] + b, k[2] + c])
                            .into_iter()
                            .flatten()
                        {
                            let r = points.reference[p];
                            let d2: f64 = (0..3).map(|d| (r[d] - x[d]).powi(2)).sum();
                            if best.is_none_or(|(bd, bp)| d2 < bd || (d2 == bd && p < bp)) {
                                best = Some((d2, p));
                            }
                        }
                    }
                }
            }
            if let Some((d2, p)) = best
                && d2.sqrt() <= reach as f64 * self.cell
            {
                return p;
            }
            assert!(reach < 1 << 20, "a body has no points");
        }
        unreachable!()
    }
}

#[cfg(test)]
mod tests {
    use super::super::surface::tests::sci;
    use super::super::surface::{Surface, interpolate};
    use super::*;
    use crate::material::{Elastic, Material};
    use crate::particles::solid_seeding;
    use std::f64::consts::PI;

    fn body(solid: &Solid, spacing: f64) -> MaterialPoints<3> {
        let mut points = MaterialPoints::<3>::default();
        let elastic = Elastic::from_young_poisson(1e6, 0.3);
        points.add_solid(
            Material::Hencky(elastic),
            1000.0,
            &solid_seeding::fill(solid, spacing),
        );
        points
    }

    /// Gauss-Legendre nodes and weights on [0, 1], 4 points.
    const GAUSS: [(f64, f64); 4] = [
        (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
        (0.330_009_478_207_571_87, 0.326_072_577_431_273_07),
        (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
        (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
    ];

    /// The area and the enclosed volume, `1/3 sum x . n dA`, of surfaces.
    fn area_and_volume(surfaces: &[Surface]) -> (f64, f64) {
        let (mut area, mut volume) = (0.0, 0.0);
        for s in surfaces {
            for p in &s.patches {
                for (a, wa) in GAUSS {
                    for (b, wb) in GAUSS {
                        let (x, xs, xt) = p.evaluate(a, b);
                        let n = super::super::surface::cross(xs, xt);
                        area += wa * wb * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                        volume += wa * wb * (x[0] * n[0] + x[1] * n[1] + x[2] * n[2]) / 3.0;
                    }
                }
            }
        }
        (area, volume)
    }

    fn surfaces(points: &MaterialPoints<3>, solid: &Solid, spacing: f64) -> Vec<Surface> {
        face_patches(points, 0, solid, spacing)
            .iter()
            .map(|f| interpolate(&f.data_grid(points)))
            .collect()
    }

    /// A box's six faces: the data points of each are its outer points'
    /// face middles (a reference offset of half a spacing along the
    /// normal) and the face's edges; area and volume exact; a homogeneous
    /// deformation maps the surface exactly.
    #[test]
    fn a_boxs_faces_pass_through_its_outer_points_pushed_to_its_faces() {
        let solid = Solid::cuboid([0.0, 1.0, -1.0], [2.0, 2.5, 0.0]);
        let s = 0.25;
        let mut points = body(&solid, s);
        let patches = face_patches(&points, 0, &solid, s);
        assert_eq!(patches.len(), 6);
        let counts: Vec<[usize; 2]> = patches.iter().map(|p| p.counts).collect();
        // x-faces: 6 x 4 cells in y, z; y-faces: 8 x 4; z-faces: 8 x 6.
        assert!(counts.contains(&[8, 6]) && counts.contains(&[10, 6]) && counts.contains(&[10, 8]));
        for patch in &patches {
            for (k, c) in patch.data.iter().enumerate() {
                let (i, j) = (k % patch.counts[0], k / patch.counts[0]);
                let inside = |n: usize, i: usize| i > 0 && i + 1 < n;
                if inside(patch.counts[0], i) && inside(patch.counts[1], j) {
                    let mut o: Vec<f64> = c.offset.iter().map(|v| v.abs()).collect();
                    o.sort_by(f64::total_cmp);
                    assert!(
                        o[0] < 1e-12 && o[1] < 1e-12 && (o[2] - s / 2.0).abs() < 1e-12,
                        "{o:?}"
                    );
                }
            }
        }
        let (area, volume) = area_and_volume(&surfaces(&points, &solid, s));
        assert!(
            (area - 2.0 * (2.0 * 1.5 + 2.0 + 1.5)).abs() < 1e-12,
            "{area}"
        );
        assert!((volume - 3.0).abs() < 1e-12, "{volume}");
        // x -> F x, F with det 1.2 * 0.9 * 1.1 and shears.
        let f = nalgebra::Matrix3::new(1.2, 0.3, 0.0, 0.0, 0.9, -0.2, 0.1, 0.0, 1.1);
        for p in 0..points.len() {
            let x = f * nalgebra::Vector3::from(points.reference[p]);
            points.position[p] = [x[0], x[1], x[2]];
            points.deformation[p] = f;
        }
        let (_, volume) = area_and_volume(&surfaces(&points, &solid, s));
        assert!((volume - 3.0 * f.determinant()).abs() < 1e-12, "{volume}");
    }

    /// Every kind of body: the surface is closed, outward and of the right
    /// size (the volume it encloses is the body's to the interpolation's
    /// error, which the curved faces converge at order 4).
    #[test]
    fn every_bodys_faces_enclose_its_volume() {
        let circle = Geometry::Circle {
            center: [0.5, -0.2],
            radius: 0.8,
        };
        let annulus = Geometry::Annulus {
            center: [0.0, 0.0],
            inner_radius: 0.5,
            outer_radius: 1.0,
        };
        let sector = Geometry::AnnulusSector {
            center: [0.0, 0.0],
            inner_radius: 0.5,
            outer_radius: 1.0,
            start_angle: 30.0,
            end_angle: 120.0,
        };
        let polygon = Geometry::Polygon {
            vertices: vec![[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.6], [0.0, 1.0]],
            holes: vec![vec![[0.5, 0.3], [0.5, 0.7], [1.5, 0.7], [1.5, 0.3]]],
        };
        let turned = Geometry::Rectangle {
            min: [0.0, 0.0],
            max: [1.0, 0.5],
            angle: 30.0,
            about: None,
        };
        let mesh = HexMesh {
            nodes: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 1.0],
                [1.0, 1.0, 1.0],
                [0.0, 1.0, 1.0],
                [2.0, 0.0, 0.0],
                [2.0, 1.0, 0.0],
                [2.0, 0.0, 1.0],
                [2.2, 1.0, 1.3],
            ],
            elements: vec![[0, 1, 2, 3, 4, 5, 6, 7], [1, 8, 9, 2, 5, 10, 11, 6]],
        };
        let z = [0.0, 1.2];
        let extruded = |section: &Geometry| Solid::Extrusion {
            section: section.clone(),
            z,
        };
        let cases: Vec<(&str, Solid, f64, f64)> = vec![
            ("cylinder", extruded(&circle), PI * 0.64 * 1.2, 1e-5),
            ("tube", extruded(&annulus), PI * 0.75 * 1.2, 1e-5),
            ("sector", extruded(&sector), PI * 0.75 / 4.0 * 1.2, 1e-5),
            (
                "polygon with a hole",
                extruded(&polygon),
                (2.0 + 0.6 - 0.4) * 1.2,
                1e-12,
            ),
            ("turned box", extruded(&turned), 0.5 * 1.2, 1e-12),
            (
                "ball",
                Solid::SphericalShell {
                    center: [0.1, 0.2, 0.3],
                    inner_radius: 0.0,
                    outer_radius: 1.0,
                },
                4.0 / 3.0 * PI,
                1e-4,
            ),
            (
                "shell",
                Solid::SphericalShell {
                    center: [0.0; 3],
                    inner_radius: 0.6,
                    outer_radius: 1.0,
                },
                4.0 / 3.0 * PI * (1.0 - 0.216),
                1e-4,
            ),
            (
                "hexahedra",
                Solid::Mesh(mesh.clone()),
                1.0 + mesh_second_volume(),
                1e-12,
            ),
        ];
        for (name, solid, exact, tolerance) in cases {
            let s = 0.1;
            let points = body(&solid, s);
            let (_, volume) = area_and_volume(&surfaces(&points, &solid, s));
            let error = (volume - exact) / exact;
            eprintln!("{name}: volume error {error:.2e}");
            assert!(error.abs() < tolerance, "{name}: {volume} against {exact}");
        }
    }

    /// The second element of the test's mesh: a unit cube with one corner
    /// moved to (2.2, 1.0, 1.3), by 8 Gauss points (exact for a trilinear
    /// map's Jacobian).
    fn mesh_second_volume() -> f64 {
        let corners = [
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.0, 0.0, 1.0],
            [2.0, 0.0, 1.0],
            [2.2, 1.0, 1.3],
            [1.0, 1.0, 1.0],
        ];
        let g = [0.5 - 0.5 / 3f64.sqrt(), 0.5 + 0.5 / 3f64.sqrt()];
        let mut v = 0.0;
        for a in g {
            for b in g {
                for c in g {
                    v += solid_seeding::trilinear(&corners, [a, b, c]).1 / 8.0;
                }
            }
        }
        v
    }

    /// The surface of a seeded sphere and cylinder: the distance to the
    /// true surface against the spacing (a quarter turn in 8 .. 64). Measured,
    /// as a fraction of the radius: the sphere 1.1e-5, 5.5e-7, 4.8e-8,
    /// 3.5e-9 (orders 4.32, 3.53, 3.77; 3.88 over the three halvings: the
    /// largest of samples, a noisy measure); the cylinder 3.9e-6 .. 9.5e-10,
    /// orders 4.00.
    #[test]
    fn a_seeded_sphere_and_cylinder_converge_at_fourth_order() {
        let r = 1.0;
        let distance = |solid: &Solid, s: f64, d: &dyn Fn([f64; 3]) -> f64| {
            let points = body(solid, s);
            let mut worst: f64 = 0.0;
            for surface in surfaces(&points, solid, s) {
                for p in &surface.patches {
                    for a in 0..5 {
                        for b in 0..5 {
                            worst = worst.max(d(p.point(a as f64 / 4.0, b as f64 / 4.0)).abs());
                        }
                    }
                }
            }
            worst
        };
        // A shell, to keep the finest seeding small: its inner faces too.
        let sphere = Solid::SphericalShell {
            center: [0.0; 3],
            inner_radius: 0.8 * r,
            outer_radius: r,
        };
        let cylinder = Solid::Extrusion {
            section: Geometry::Circle {
                center: [0.0, 0.0],
                radius: r,
            },
            z: [0.0, 0.5],
        };
        // Spacings that divide a quarter turn into 8, 16 and 32.
        let spacings = [8.0, 16.0, 32.0, 64.0].map(|n| std::f64::consts::FRAC_PI_2 / n);
        let on_sphere = |x: [f64; 3]| {
            let rho = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
            // The outer faces only: the inner ones have 0.8 as many
            // cells, not halved each time.
            if rho > 0.9 * r { rho - r } else { 0.0 }
        };
        // The cylinder's side and its caps' rims.
        let on_cylinder = |x: [f64; 3]| {
            let rho = x[0].hypot(x[1]);
            if x[2] > 1e-9 && x[2] < 0.5 - 1e-9 {
                rho - r
            } else {
                (rho - r).max(0.0)
            }
        };
        let e_sphere: Vec<f64> = spacings
            .iter()
            .map(|&s| distance(&sphere, s, &on_sphere))
            .collect();
        let e_cylinder: Vec<f64> = spacings
            .iter()
            .map(|&s| distance(&cylinder, s, &on_cylinder))
            .collect();
        let orders =
            |e: &[f64]| -> Vec<f64> { e.windows(2).map(|w| (w[0] / w[1]).log2()).collect() };
        eprintln!(
            "sphere {} orders {:.2?}; cylinder {} orders {:.2?}",
            sci(&e_sphere),
            orders(&e_sphere),
            sci(&e_cylinder),
            orders(&e_cylinder)
        );
        for e in [&e_sphere, &e_cylinder] {
            let overall = (e[0] / e[3]).log2() / 3.0;
            assert!(
                overall > 3.7 && orders(e).iter().all(|&p| p > 3.4),
                "{:?}",
                orders(e)
            );
        }
    }
}
