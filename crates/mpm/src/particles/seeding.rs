//! Filling a body's reference geometry with material points.
//!
//! Rectangles are divided exactly: `n = round(width / spacing)` points per
//! direction at the centres of equal sub-cells, so the points' volumes add up
//! to the area. Quadrilaterals are divided the same way in the parameters of
//! their bilinear map, and annulus sectors on a polar lattice; each point has
//! the exact area of its cell. Other shapes keep the points of a lattice
//! aligned with the grid (offset half a spacing from the grid lines) that
//! fall inside; each point has the volume of its lattice square, so the total
//! volume differs from the area by the staircase error along curved edges.

use crate::geometry::Geometry;

/// One material point as generated: position, volume, its cell, and its
/// place `(i, j)` in the body's lattice (neighbours differ by one in `i` or
/// `j`; the boundary is found from it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeedPoint {
    pub position: [f64; 2],
    pub volume: f64,
    pub lattice: [i64; 2],
    /// The point's cell of the body's own lattice: GIMP's domain, and the
    /// boundary's offset to the material edge.
    pub domain: Domain,
}

/// A point's cell as the bilinear image of a square,
/// `x + s a + t b + s t c` for `|s|, |t| <= 1`: `axes` `[a, b]` are the
/// half-axes from the point to the middles of the cell's sides along the
/// lattice directions (`i`, then `j`), and `twist` `c` moves the corners
/// where the cell is not a parallelogram. A rectangle's axes are its
/// half-widths along x and y; a polar cell's are radial and tangential; a
/// quadrilateral's follow its mapped lattice.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Domain {
    pub axes: [[f64; 2]; 2],
    pub twist: [f64; 2],
}

impl Domain {
    /// An axis-aligned rectangle of these half-widths, turned by `angle`
    /// (radians).
    pub fn turned(half_width: [f64; 2], angle: f64) -> Self {
        let (s, c) = angle.sin_cos();
        Self {
            axes: [
                [half_width[0] * c, half_width[0] * s],
                [-half_width[1] * s, half_width[1] * c],
            ],
            twist: [0.0, 0.0],
        }
    }

    /// The longer half-axis.
    pub fn reach(&self) -> f64 {
        let [a, b] = self.axes;
        a[0].hypot(a[1]).max(b[0].hypot(b[1]))
    }

    /// From the point to the cell's edge in the direction of the outward
    /// normal `n`: `n` is written on the unit normals of the sides of the
    /// parallelogram `(a, b)`, `n = alpha nu_i + beta nu_j`, and with
    /// `(s, t) = (alpha, beta) / max(|alpha|, |beta|)` the offset is
    /// `s a + t b + s t c`. With `n` the normal of a row or column of
    /// points, as the boundary's data ring gives, that reaches the middle
    /// of the cell's side; at a corner (`n` the sum of the two) the corner
    /// itself. With `n` a little off (the true edge of a tapered cell), it
    /// still ends on that side, off its middle. For a rectangle,
    /// `(alpha, beta)` is `n` in its frame.
    pub fn edge_offset(&self, n: [f64; 2]) -> [f64; 2] {
        let [a, b] = self.axes;
        let det = a[0] * b[1] - a[1] * b[0];
        if det == 0.0 {
            return [0.0, 0.0];
        }
        // The outward normals of the sides s_i = +1 and s_j = +1 are the
        // rows of A^-1, (b_y, -b_x) / det and (-a_y, a_x) / det, normalised.
        let nu_i = [b[1] / det, -b[0] / det];
        let nu_j = [-a[1] / det, a[0] / det];
        let (li, lj) = (nu_i[0].hypot(nu_i[1]), nu_j[0].hypot(nu_j[1]));
        let nu_i = [nu_i[0] / li, nu_i[1] / li];
        let nu_j = [nu_j[0] / lj, nu_j[1] / lj];
        let d = nu_i[0] * nu_j[1] - nu_i[1] * nu_j[0];
        let alpha = (n[0] * nu_j[1] - n[1] * nu_j[0]) / d;
        let beta = (nu_i[0] * n[1] - nu_i[1] * n[0]) / d;
        let m = alpha.abs().max(beta.abs());
        if m == 0.0 {
            return [0.0, 0.0];
        }
        let (s, t) = (alpha / m, beta / m);
        let c = self.twist;
        [
            s * a[0] + t * b[0] + s * t * c[0],
            s * a[1] + t * b[1] + s * t * c[1],
        ]
    }
}

/// Which lattice a body's points sit on (the case's `crate::case::Lattice`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Lattice {
    /// The body's own: rectangles and quadrilaterals mapped, sectors,
    /// circles and annuli polar, polygons cut into triangles and each
    /// triangle into three mapped quadrilaterals. The points' cells tile
    /// the body and its edges are rows of points.
    #[default]
    Body,
    /// The grid's, for any shape: the sites of a square lattice aligned
    /// with the grid that fall inside, each the volume of its square; a
    /// slanted or curved edge is a staircase.
    Grid,
}

/// Whether the points of `geometry` on `lattice` are more than one lattice
/// (patches, or polar rings of their own counts), so that their boundary
/// loops come from the exact edge ([`crate::boundary::edge_detection`]),
/// not from lattice neighbours.
pub fn follows_edge(geometry: &Geometry, lattice: Lattice) -> bool {
    lattice == Lattice::Body
        && matches!(
            geometry,
            Geometry::Polygon { .. }
                | Geometry::Circle { .. }
                | Geometry::Annulus { .. }
                | Geometry::Mesh(_)
        )
}

/// How densely a region is filled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Density {
    /// Points this far apart (metres).
    Spacing(f64),
    /// `[nx, ny]` points; rectangles and quadrilaterals only.
    Count([u32; 2]),
}

/// The material points of `geometry` at `density` on `lattice` (the
/// grid's goes through the grid's `origin`).
pub fn fill(
    geometry: &Geometry,
    density: Density,
    origin: [f64; 2],
    lattice: Lattice,
) -> Vec<SeedPoint> {
    let (spacing, count) = match density {
        Density::Spacing(s) => (s, None),
        Density::Count(c) => (f64::NAN, Some(c)), // rectangles and quadrilaterals
    };
    if lattice == Lattice::Grid {
        let (lo, hi) = geometry.bounding_box();
        if let Geometry::Polygon { vertices, holes } = geometry {
            return lattice_inside(
                lo,
                hi,
                spacing,
                origin,
                inside_polygon_by_rows(vertices, holes),
            );
        }
        return lattice_inside(lo, hi, spacing, origin, |p| geometry.contains(p));
    }
    if let Some(corners) = geometry.turned_corners() {
        return mapped_quadrilateral(&corners, spacing, count);
    }
    match geometry {
        Geometry::Rectangle { min, max, .. } => {
            let size = [max[0] - min[0], max[1] - min[1]];
            let n = rectangle_counts(size, spacing, count).map(|n| n as usize);
            let step = [size[0] / n[0] as f64, size[1] / n[1] as f64];
            let mut out = Vec::with_capacity(n[0] * n[1]);
            for j in 0..n[1] {
                for i in 0..n[0] {
                    out.push(SeedPoint {
                        position: [
                            min[0] + (i as f64 + 0.5) * step[0],
                            min[1] + (j as f64 + 0.5) * step[1],
                        ],
                        volume: step[0] * step[1],
                        lattice: [i as i64, j as i64],
                        domain: Domain::turned([step[0] / 2.0, step[1] / 2.0], 0.0),
                    });
                }
            }
            out
        }
        Geometry::AnnulusSector {
            center,
            inner_radius,
            outer_radius,
            start_angle,
            end_angle,
        } => polar_sector(
            *center,
            *inner_radius,
            *outer_radius,
            start_angle.to_radians(),
            end_angle.to_radians(),
            spacing,
        ),
        Geometry::Quadrilateral { vertices } => {
            mapped_quadrilateral(&counter_clockwise(vertices), spacing, count)
        }
        Geometry::Polygon { vertices, holes } => match polygon_fill(vertices, holes, spacing) {
            PolygonFill::Patches(patches) => fill_patches(&patches, spacing),
            PolygonFill::Rings(star) => star.fill(spacing),
        },
        Geometry::Mesh(mesh) => fill_patches(&mesh_patches(mesh), spacing),
        Geometry::Circle { center, radius } => polar_rings(*center, 0.0, *radius, spacing),
        Geometry::Annulus {
            center,
            inner_radius,
            outer_radius,
        } => polar_rings(*center, *inner_radius, *outer_radius, spacing),
    }
}

/// Every patch's mapped lattice at spacing `s`; a point's lattice place is
/// (patch, its place in the patch), which is no lattice as a whole: the
/// loops of such bodies come from the edge.
fn fill_patches(patches: &[[[f64; 2]; 4]], s: f64) -> Vec<SeedPoint> {
    let mut out = Vec::new();
    for (k, quad) in patches.iter().enumerate() {
        out.extend(
            mapped_quadrilateral(quad, s, None)
                .into_iter()
                .map(|mut p| {
                    p.lattice = [k as i64, p.lattice[0] + (p.lattice[1] << 32)];
                    p
                }),
        );
    }
    out
}

/// The points [`fill_patches`] makes, counted without making them.
fn patch_sites(patches: &[[[f64; 2]; 4]], s: f64) -> f64 {
    patches
        .iter()
        .map(|q| {
            let [n_i, n_j] = quadrilateral_counts(q, s, None);
            n_i * n_j
        })
        .sum()
}

/// How a polygon on its own lattice is filled.
enum PolygonFill {
    /// Mapped patches ([`polygon_patches`]), every side of the polygon a
    /// side of some patch.
    Patches(Vec<[[f64; 2]; 4]>),
    /// Rings about its centroid ([`Star`]): a convex polygon whose patches
    /// would not follow its area. A patch's counts come from the mean
    /// lengths of its opposite sides, which overstate the area of any
    /// patch but a rectangle's: by 8% for the kites of a triangle, and 80
    /// times for the thin kites of a many-sided polygon (a 1000-sided
    /// circle of 5,027 points' area made 400,000). A patch holds a point
    /// at least, so no count makes a 10,000-sided one's fan follow its
    /// area.
    Rings(Star),
}

/// How far the patches' points may stray from the area's before a convex
/// polygon is filled by rings. A polygon that is not convex keeps its
/// patches: its thin triangles over-seed it (docs/guide.md, "Bodies and
/// their points"), and
/// their cells, were their counts cut to their area, would be slivers.
const PATCHES_AREA_TOLERANCE: f64 = 0.02;

fn polygon_fill(vertices: &[[f64; 2]], holes: &[Vec<[f64; 2]>], s: f64) -> PolygonFill {
    let patches = polygon_patches(vertices, holes);
    if holes.is_empty() && strictly_convex(vertices) {
        let target = crate::geometry::signed_area(vertices).abs() / (s * s);
        if (patch_sites(&patches, s) - target).abs() > PATCHES_AREA_TOLERANCE * target {
            return PolygonFill::Rings(Star::new(vertices));
        }
    }
    PolygonFill::Patches(patches)
}

/// A convex polygon seen from its centroid `g`: its edge as a function of
/// arc length `t` from its first vertex, `edge(t)`, and the area `fan(t)`
/// swept from `g` along it. The ring map `x(r, t) = g + r (edge(t) - g)`,
/// `r` in [0, 1], takes the square onto the polygon; a cell
/// `[r0, r1] x [t0, t1]` has the area `(r1^2 - r0^2) (fan(t1) - fan(t0))`,
/// exactly, whatever corners of the polygon its outer side turns.
struct Star {
    g: [f64; 2],
    /// Counter-clockwise, the first repeated at the end.
    vertices: Vec<[f64; 2]>,
    /// Arc length and swept area at each vertex.
    arc: Vec<f64>,
    swept: Vec<f64>,
}

impl Star {
    fn new(vertices: &[[f64; 2]]) -> Star {
        let mut v: Vec<[f64; 2]> = if crate::geometry::signed_area(vertices) > 0.0 {
            vertices.to_vec()
        } else {
            vertices.iter().rev().copied().collect()
        };
        let n = v.len() as f64;
        let g = [0, 1].map(|d| v.iter().map(|p| p[d]).sum::<f64>() / n);
        v.push(v[0]);
        let (mut arc, mut swept) = (vec![0.0], vec![0.0]);
        for w in v.windows(2) {
            let [a, b] = [w[0], w[1]];
            arc.push(arc.last().unwrap() + (b[0] - a[0]).hypot(b[1] - a[1]));
            let cross = (a[0] - g[0]) * (b[1] - g[1]) - (a[1] - g[1]) * (b[0] - g[0]);
            swept.push(swept.last().unwrap() + 0.5 * cross);
        }
        Star {
            g,
            vertices: v,
            arc,
            swept,
        }
    }

    fn perimeter(&self) -> f64 {
        *self.arc.last().unwrap()
    }

    fn area(&self) -> f64 {
        *self.swept.last().unwrap()
    }

    /// The edge's point at arc length `t` and the area swept to it.
    fn at(&self, t: f64) -> ([f64; 2], f64) {
        let k = (self.arc.partition_point(|&a| a <= t).max(1) - 1).min(self.arc.len() - 2);
        let (a, b) = (self.vertices[k], self.vertices[k + 1]);
        let f = ((t - self.arc[k]) / (self.arc[k + 1] - self.arc[k])).clamp(0.0, 1.0);
        let x = [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
        let g = self.g;
        let cross = (a[0] - g[0]) * (x[1] - g[1]) - (a[1] - g[1]) * (x[0] - g[0]);
        (x, self.swept[k] + 0.5 * cross)
    }

    /// Rings of equal width in `r`, about as many as the mean distance
    /// from the centroid to the edge (`2 area / perimeter`) holds spacings;
    /// each ring divided into as many cells of equal arc as its area holds
    /// squares of `s` (three at least).
    fn ring_counts(&self, s: f64) -> Vec<usize> {
        let n_r = ((2.0 * self.area() / self.perimeter()) / s)
            .round()
            .max(1.0) as usize;
        (0..n_r)
            .map(|i| {
                let (r0, r1) = (i as f64 / n_r as f64, (i + 1) as f64 / n_r as f64);
                ((r1 * r1 - r0 * r0) * self.area() / (s * s))
                    .round()
                    .max(3.0) as usize
            })
            .collect()
    }

    fn sites(&self, s: f64) -> f64 {
        self.ring_counts(s).iter().sum::<usize>() as f64
    }

    /// The points: each at the image of its cell's centre, with the cell's
    /// exact area and, as its domain, the quadrilateral of the cell's
    /// corners (its outer side, on the edge, may turn a corner of the
    /// polygon; the point's radial axis still ends on the edge).
    fn fill(&self, s: f64) -> Vec<SeedPoint> {
        let counts = self.ring_counts(s);
        let n_r = counts.len() as f64;
        let g = self.g;
        let map = |r: f64, e: [f64; 2]| [g[0] + r * (e[0] - g[0]), g[1] + r * (e[1] - g[1])];
        let mut out = Vec::with_capacity(counts.iter().sum());
        for (i, &n_t) in counts.iter().enumerate() {
            let (r0, r1) = (i as f64 / n_r, (i + 1) as f64 / n_r);
            let rm = 0.5 * (r0 + r1);
            let dt = self.perimeter() / n_t as f64;
            for j in 0..n_t {
                let (e0, f0) = self.at(j as f64 * dt);
                let (em, _) = self.at((j as f64 + 0.5) * dt);
                let (e1, f1) = self.at((j + 1) as f64 * dt);
                let corners = [map(r0, e0), map(r1, e0), map(r1, e1), map(r0, e1)];
                let (inner, outer) = (map(r0, em), map(r1, em));
                let (first, last) = (map(rm, e0), map(rm, e1));
                let half = |p: [f64; 2], q: [f64; 2]| [(q[0] - p[0]) / 2.0, (q[1] - p[1]) / 2.0];
                out.push(SeedPoint {
                    position: map(rm, em),
                    volume: (r1 * r1 - r0 * r0) * (f1 - f0),
                    lattice: [i as i64, j as i64],
                    domain: Domain {
                        axes: [half(inner, outer), half(first, last)],
                        twist: [0, 1].map(|d| {
                            (corners[2][d] - corners[1][d] - corners[3][d] + corners[0][d]) / 4.0
                        }),
                    },
                });
            }
        }
        out
    }
}

/// A polygon's patches, counter-clockwise quadrilaterals of which every
/// side of the polygon is a side of some. A convex quadrilateral is its
/// own patch; any other convex polygon is cut by the lines from its
/// centroid to the middles of its sides, one patch per vertex. Otherwise
/// its triangles ([`crate::triangulation`]) are cut so, three patches each.
pub(crate) fn polygon_patches(
    vertices: &[[f64; 2]],
    holes: &[Vec<[f64; 2]>],
) -> Vec<[[f64; 2]; 4]> {
    let mid = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
    if holes.is_empty() && strictly_convex(vertices) {
        let v = if crate::geometry::signed_area(vertices) > 0.0 {
            vertices.to_vec()
        } else {
            vertices.iter().rev().copied().collect()
        };
        let n = v.len();
        if n == 4 {
            return vec![[v[0], v[1], v[2], v[3]]];
        }
        // The centroid of the vertices lies inside a convex polygon.
        let g = [0, 1].map(|d| v.iter().map(|p| p[d]).sum::<f64>() / n as f64);
        return (0..n)
            .map(|k| {
                let (prev, here, next) = (v[(k + n - 1) % n], v[k], v[(k + 1) % n]);
                [here, mid(here, next), g, mid(prev, here)]
            })
            .collect();
    }
    crate::triangulation::triangulate(vertices, holes)
        .expect("validated: every hole inside the polygon")
        .into_iter()
        .flat_map(triangle_patches)
        .collect()
}

/// A counter-clockwise triangle cut into three counter-clockwise
/// quadrilaterals by the lines from its centroid to the middles of its
/// sides, a vertex of the triangle first in each.
fn triangle_patches([a, b, c]: [[f64; 2]; 3]) -> [[[f64; 2]; 4]; 3] {
    let mid = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
    let g = [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0];
    let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
    [[a, ab, g, ca], [b, bc, g, ab], [c, ca, g, bc]]
}

/// A mesh's patches: each quadrilateral element itself (validated convex),
/// each triangle cut in three ([`triangle_patches`]), all counter-clockwise.
/// Its points are those of a composite midpoint rule on each element's
/// map, each with its exact sub-cell's area (the rule's weight times the
/// Jacobian, integrated), and each sub-cell its point's GIMP domain.
pub(crate) fn mesh_patches(mesh: &crate::geometry::Mesh) -> Vec<[[f64; 2]; 4]> {
    mesh.element_corners()
        .flat_map(|v| match v.len() {
            3 => triangle_patches([v[0], v[1], v[2]]).to_vec(),
            _ => vec![[v[0], v[1], v[2], v[3]]],
        })
        .collect()
}

/// Whether every turn of the ring `v` is the same way and none is straight.
fn strictly_convex(v: &[[f64; 2]]) -> bool {
    let n = v.len();
    let turns: Vec<f64> = (0..n)
        .map(|k| {
            let (a, b, c) = (v[k], v[(k + 1) % n], v[(k + 2) % n]);
            (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0])
        })
        .collect();
    turns.iter().all(|&t| t > 0.0) || turns.iter().all(|&t| t < 0.0)
}

/// A full disc (`a = 0`) or annulus on polar rings: `n_r` rings of equal
/// width from the spacing, each ring divided into as many equal angles as
/// the spacing gives at its middle radius (at least three), so that the
/// cells stay near square from the centre out. Each point has the exact
/// area of its cell and a domain of that area turned with it; the points'
/// lattice places are (ring, division), which do not make one lattice: the
/// loops come from the edge.
fn polar_rings(c: [f64; 2], a: f64, b: f64, s: f64) -> Vec<SeedPoint> {
    let counts = ring_counts(a, b, s);
    let dr = (b - a) / counts.len() as f64;
    let mut out = Vec::with_capacity(counts.iter().sum::<usize>());
    for (i, &n_t) in counts.iter().enumerate() {
        let r = a + (i as f64 + 0.5) * dr;
        let dt = std::f64::consts::TAU / n_t as f64;
        for j in 0..n_t {
            let t = (j as f64 + 0.5) * dt;
            out.push(SeedPoint {
                position: [c[0] + r * t.cos(), c[1] + r * t.sin()],
                volume: r * dr * dt,
                lattice: [i as i64, j as i64],
                domain: Domain::turned([dr / 2.0, r * dt / 2.0], t),
            });
        }
    }
    out
}

/// Divisions of each polar ring between radii `a` and `b` at spacing `s`.
fn ring_counts(a: f64, b: f64, s: f64) -> Vec<usize> {
    let n_r = ((b - a) / s).round().max(1.0) as usize;
    let dr = (b - a) / n_r as f64;
    (0..n_r)
        .map(|i| {
            let r = a + (i as f64 + 0.5) * dr;
            (std::f64::consts::TAU * r / s).round().max(3.0) as usize
        })
        .collect()
}

/// The vertices in counter-clockwise order (the first kept), so that the
/// mapped lattice's `(i, j)` keeps the orientation loop detection expects.
fn counter_clockwise(v: &[[f64; 2]; 4]) -> [[f64; 2]; 4] {
    if crate::geometry::signed_area(v) >= 0.0 {
        *v
    } else {
        [v[0], v[3], v[2], v[1]]
    }
}

/// A quadrilateral `v` (counter-clockwise) divided as the unit square is
/// by `n_i x n_j` equal cells, through the bilinear map
/// `x(u, w) = (1-u)(1-w) v0 + u(1-w) v1 + u w v2 + (1-u) w v3`. Lines of
/// constant `u` or `w` map to straight lines, so every cell is a straight
/// sided quadrilateral and its area is exact. A point sits at the image of
/// its cell's centre, its domain is the cell itself (half-axes half the
/// mid-lines, and the twist), which is also its GIMP domain.
fn mapped_quadrilateral(v: &[[f64; 2]; 4], s: f64, count: Option<[u32; 2]>) -> Vec<SeedPoint> {
    let [n_i, n_j] = quadrilateral_counts(v, s, count).map(|n| n as usize);
    let map = |u: f64, w: f64| {
        let c = [(1.0 - u) * (1.0 - w), u * (1.0 - w), u * w, (1.0 - u) * w];
        [0, 1].map(|d| (0..4).map(|k| c[k] * v[k][d]).sum::<f64>())
    };
    let (du, dw) = (1.0 / n_i as f64, 1.0 / n_j as f64);
    let mut out = Vec::with_capacity(n_i * n_j);
    for j in 0..n_j {
        for i in 0..n_i {
            let (u0, w0) = (i as f64 * du, j as f64 * dw);
            let corners = [
                map(u0, w0),
                map(u0 + du, w0),
                map(u0 + du, w0 + dw),
                map(u0, w0 + dw),
            ];
            // Half the cross product of the diagonals: the area of any
            // quadrilateral, and free of the cancellation the shoelace sum
            // suffers far from the origin.
            let (d1, d2) = (
                [corners[2][0] - corners[0][0], corners[2][1] - corners[0][1]],
                [corners[3][0] - corners[1][0], corners[3][1] - corners[1][1]],
            );
            let volume = 0.5 * (d1[0] * d2[1] - d1[1] * d2[0]);
            let centre = map(u0 + du / 2.0, w0 + dw / 2.0);
            let half = |p: [f64; 2], q: [f64; 2]| [(q[0] - p[0]) / 2.0, (q[1] - p[1]) / 2.0];
            let along_i = half(map(u0, w0 + dw / 2.0), map(u0 + du, w0 + dw / 2.0));
            let along_j = half(map(u0 + du / 2.0, w0), map(u0 + du / 2.0, w0 + dw));
            out.push(SeedPoint {
                position: centre,
                volume,
                lattice: [i as i64, j as i64],
                domain: Domain {
                    axes: [along_i, along_j],
                    twist: [0, 1].map(|d| {
                        (corners[2][d] - corners[1][d] - corners[3][d] + corners[0][d]) / 4.0
                    }),
                },
            });
        }
    }
    out
}

/// `[n_i, n_j]` of a quadrilateral's mapped lattice: the given `count`, or
/// the mean lengths of its opposite edges over the spacing, rounded, at
/// least one each.
fn quadrilateral_counts(v: &[[f64; 2]; 4], s: f64, count: Option<[u32; 2]>) -> [f64; 2] {
    if let Some(c) = count {
        return c.map(f64::from);
    }
    let len = |a: usize, b: usize| (v[b][0] - v[a][0]).hypot(v[b][1] - v[a][1]);
    [
        (0.5 * (len(0, 1) + len(3, 2)) / s).round().max(1.0),
        (0.5 * (len(0, 3) + len(1, 2)) / s).round().max(1.0),
    ]
}

/// A polar lattice on an annulus sector: `n_r` rings of equal width and
/// `n_t` equal angular divisions, both from the spacing (at the mean
/// radius). Each point has the exact area of its annular cell, and a
/// domain of that area turned with it (radial by tangential); its lattice
/// place is (ring, division), which maps counter-clockwise loops to
/// counter-clockwise loops.
fn polar_sector(c: [f64; 2], a: f64, b: f64, t0: f64, t1: f64, s: f64) -> Vec<SeedPoint> {
    let [n_r, n_t] = sector_counts(a, b, t0, t1, s).map(|n| n as usize);
    let (dr, dt) = ((b - a) / n_r as f64, (t1 - t0) / n_t as f64);
    let mut out = Vec::with_capacity(n_r * n_t);
    for j in 0..n_t {
        for i in 0..n_r {
            let r = a + (i as f64 + 0.5) * dr;
            let t = t0 + (j as f64 + 0.5) * dt;
            let volume = r * dr * dt;
            out.push(SeedPoint {
                position: [c[0] + r * t.cos(), c[1] + r * t.sin()],
                volume,
                lattice: [i as i64, j as i64],
                domain: Domain::turned([dr / 2.0, r * dt / 2.0], t),
            });
        }
    }
    out
}

fn lattice_inside(
    lo: [f64; 2],
    hi: [f64; 2],
    s: f64,
    origin: [f64; 2],
    mut inside: impl FnMut([f64; 2]) -> bool,
) -> Vec<SeedPoint> {
    let first = |d: usize| lattice_range(lo, hi, s, origin, d).0 as i64;
    let last = |d: usize| lattice_range(lo, hi, s, origin, d).1 as i64;
    let mut out = Vec::new();
    for j in first(1)..=last(1) {
        for i in first(0)..=last(0) {
            let p = [
                origin[0] + (i as f64 + 0.5) * s,
                origin[1] + (j as f64 + 0.5) * s,
            ];
            if inside(p) {
                out.push(SeedPoint {
                    position: p,
                    volume: s * s,
                    lattice: [i, j],
                    domain: Domain::turned([s / 2.0, s / 2.0], 0.0),
                });
            }
        }
    }
    out
}

/// Whether a site lies in a polygon (with holes), asked a row of sites at a
/// time, as [`lattice_inside`] asks: each ring's crossings of the row are
/// found once a row, sorted, and a site is inside a ring when an odd number
/// of them lie to its right. That is [`crate::geometry::inside_ring`]'s
/// rule with its arithmetic, so the same sites, in time linear in the
/// vertices a row rather than a site (a 5,000-vertex polygon on the grid's
/// lattice took 18 s to admit, site by site).
fn inside_polygon_by_rows<'a>(
    vertices: &'a [[f64; 2]],
    holes: &'a [Vec<[f64; 2]>],
) -> impl FnMut([f64; 2]) -> bool + 'a {
    let rings: Vec<&[[f64; 2]]> = std::iter::once(vertices)
        .chain(holes.iter().map(Vec::as_slice))
        .collect();
    let crossings = |ring: &[[f64; 2]], y: f64| {
        let n = ring.len();
        let mut xs: Vec<f64> = (0..n)
            .filter_map(|i| {
                let (a, b) = (ring[i], ring[(i + 1) % n]);
                ((a[1] > y) != (b[1] > y))
                    .then(|| a[0] + (y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]))
            })
            .collect();
        xs.sort_by(f64::total_cmp);
        xs
    };
    let mut row_y = f64::NAN;
    let mut row: Vec<Vec<f64>> = Vec::new();
    move |p| {
        if p[1] != row_y {
            row_y = p[1];
            row = rings.iter().map(|r| crossings(r, p[1])).collect();
        }
        let odd = |xs: &Vec<f64>| (xs.len() - xs.partition_point(|&x| x <= p[0])) % 2 == 1;
        odd(&row[0]) && !row[1..].iter().any(odd)
    }
}

/// Points per direction of a rectangle of `size`: the given `count`, or
/// the spacing rounded, at least one.
fn rectangle_counts(size: [f64; 2], spacing: f64, count: Option<[u32; 2]>) -> [f64; 2] {
    match count {
        Some(c) => c.map(f64::from),
        None => size.map(|l| (l / spacing).round().max(1.0)),
    }
}

/// `[n_r, n_t]` of a polar lattice on an annulus sector (radii `a < b`,
/// angles `t0 < t1` in radians) at spacing `s`, at least one each.
fn sector_counts(a: f64, b: f64, t0: f64, t1: f64, s: f64) -> [f64; 2] {
    [
        ((b - a) / s).round().max(1.0),
        ((t1 - t0) * 0.5 * (a + b) / s).round().max(1.0),
    ]
}

/// First and last index, along direction `d`, of the lattice sites (spacing
/// `s`, offset half a spacing from `origin`) that cover `[lo, hi]`.
fn lattice_range(lo: [f64; 2], hi: [f64; 2], s: f64, origin: [f64; 2], d: usize) -> (f64, f64) {
    (
        ((lo[d] - origin[d]) / s - 0.5).floor(),
        ((hi[d] - origin[d]) / s - 0.5).ceil(),
    )
}

/// The points of [`polar_rings`], counted in floating point without
/// building them: a ring at radius `r` has about `2 pi r / s` of them.
fn ring_sites(a: f64, b: f64, s: f64) -> f64 {
    let n_r = ((b - a) / s).round().max(1.0);
    if n_r > 1e6 {
        // Too many rings to list: the area over the spacing squared.
        return std::f64::consts::PI * (b * b - a * a) / (s * s);
    }
    ring_counts(a, b, s).iter().map(|&n| n as f64).sum()
}

/// How many lattice sites [`fill`] visits, found without visiting them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FillSize {
    /// Sites visited: for rectangles, quadrilaterals and annulus sectors
    /// every site is a point; the other shapes scan the lattice over their bounding box and
    /// keep the sites inside.
    pub sites: f64,
    /// Whether every site is a point (rectangles, quadrilaterals and
    /// annulus sectors), so
    /// that `sites` is the number of points, not a bound on it.
    pub exact: bool,
}

/// The size of [`fill`]'s work for `geometry` at `density`, in
/// microseconds whatever the size: per-direction counts multiplied in
/// floating point, so a huge body gives a huge number, not an overflow.
pub fn size(geometry: &Geometry, density: Density, origin: [f64; 2], lattice: Lattice) -> FillSize {
    let (spacing, count) = match density {
        Density::Spacing(s) => (s, None),
        Density::Count(c) => (f64::NAN, Some(c)),
    };
    let scan = || {
        let (lo, hi) = geometry.bounding_box();
        let n = |d: usize| {
            let (first, last) = lattice_range(lo, hi, spacing, origin, d);
            last - first + 1.0
        };
        ([n(0), n(1)], false)
    };
    let (counts, exact) = match geometry {
        _ if lattice == Lattice::Grid => scan(),
        Geometry::Polygon { vertices, holes } => {
            let sites = match polygon_fill(vertices, holes, spacing) {
                PolygonFill::Patches(patches) => patch_sites(&patches, spacing),
                PolygonFill::Rings(star) => star.sites(spacing),
            };
            ([sites, 1.0], true)
        }
        Geometry::Mesh(mesh) => ([patch_sites(&mesh_patches(mesh), spacing), 1.0], true),
        Geometry::Circle { radius, .. } => ([ring_sites(0.0, *radius, spacing), 1.0], true),
        Geometry::Annulus {
            inner_radius,
            outer_radius,
            ..
        } => (
            [ring_sites(*inner_radius, *outer_radius, spacing), 1.0],
            true,
        ),
        Geometry::Rectangle { min, max, .. } => match geometry.turned_corners() {
            // As `fill` counts it, from the turned corners.
            Some(corners) => (quadrilateral_counts(&corners, spacing, count), true),
            None => (
                rectangle_counts([max[0] - min[0], max[1] - min[1]], spacing, count),
                true,
            ),
        },
        Geometry::Quadrilateral { vertices } => {
            (quadrilateral_counts(vertices, spacing, count), true)
        }
        Geometry::AnnulusSector {
            inner_radius,
            outer_radius,
            start_angle,
            end_angle,
            ..
        } => (
            sector_counts(
                *inner_radius,
                *outer_radius,
                start_angle.to_radians(),
                end_angle.to_radians(),
                spacing,
            ),
            true,
        ),
    };
    FillSize {
        sites: counts[0] * counts[1],
        exact,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rectangle_by_count_matches_the_paper_layout() {
        // The paper's cantilever: 10 m x 2 m with 56 x 16 = 896 points.
        let b = Geometry::Rectangle {
            min: [0.0, 0.0],
            max: [10.0, 2.0],
            angle: 0.0,
            about: None,
        };
        let pts = fill(&b, Density::Count([56, 16]), [0.0, 0.0], Lattice::Body);
        assert_eq!(pts.len(), 896);
        let area: f64 = pts.iter().map(|p| p.volume).sum();
        assert!((area - 20.0).abs() < 1e-12);
    }

    /// Cook's membrane, (0, 0), (48, 44), (48, 60), (0, 44): area 1440 (a
    /// trapezoid, parallel sides 44 and 16, 48 apart). At spacing 2 its
    /// mapped lattice has round(57.86 / 2) = 29 by round(30 / 2) = 15
    /// cells; their areas add up to the whole, and the cells of the outer
    /// points reach the true edges: their outer sides lie on the
    /// quadrilateral's edges and their corners at its vertices.
    #[test]
    fn a_quadrilateral_is_divided_exactly_and_its_cells_reach_its_edges() {
        let v = [[0.0, 0.0], [48.0, 44.0], [48.0, 60.0], [0.0, 44.0]];
        for vertices in [v, [v[0], v[3], v[2], v[1]]] {
            let q = Geometry::Quadrilateral { vertices };
            let pts = fill(&q, Density::Spacing(2.0), [0.0, 0.0], Lattice::Body);
            assert_eq!(pts.len(), 29 * 15);
            let counted = size(&q, Density::Spacing(2.0), [0.0, 0.0], Lattice::Body);
            assert_eq!((counted.sites, counted.exact), (435.0, true));
            let area: f64 = pts.iter().map(|p| p.volume).sum();
            assert!((area - 1440.0).abs() < 1e-9, "{area}");
            let at = |i: i64, j: i64| pts.iter().find(|p| p.lattice == [i, j]).unwrap();
            let reach = |p: &SeedPoint, n: [f64; 2]| {
                let d = p.domain.edge_offset(n);
                [p.position[0] + d[0], p.position[1] + d[1]]
            };
            // The loaded edge x = 48 (lattice column 28): each point's side.
            for j in 0..15 {
                let x = reach(at(28, j), [1.0, 0.0]);
                assert!((x[0] - 48.0).abs() < 1e-12, "{x:?}");
            }
            // The slanted bottom edge y = 44 x / 48 (row 0), normal
            // (44, -48) / |.|.
            let n = [44.0 / 65.1153, -48.0 / 65.1153];
            for i in 0..29 {
                let x = reach(at(i, 0), n);
                assert!((x[1] - 44.0 * x[0] / 48.0).abs() < 1e-9, "{x:?}");
            }
            // The top right corner, with the normals the boundary's data
            // ring gives there: of the last column's line of points
            // (x = const) and of the top row's, the line of constant
            // w = 1 - 1/30 of the map, along (1 - w)(v1 - v0) + w (v2 - v3).
            let w = 1.0 - 1.0 / 30.0;
            let row: [f64; 2] = [48.0, (1.0 - w) * 44.0 + w * 16.0];
            let length = row[0].hypot(row[1]);
            let corner = reach(at(28, 14), [1.0 - row[1] / length, row[0] / length]);
            assert!(
                (corner[0] - 48.0).abs() < 1e-12 && (corner[1] - 60.0).abs() < 1e-12,
                "{corner:?}"
            );
        }
    }

    /// A turned rectangle's cell gives the half-width along the normal
    /// of a side and its corner at a corner, whatever the turn.
    #[test]
    fn a_turned_cells_edge_offsets_are_its_sides_and_corners() {
        let angle = 0.4f64;
        let (s, c) = angle.sin_cos();
        let d = Domain::turned([0.3, 0.1], angle);
        let side = d.edge_offset([c, s]);
        assert!((side[0] - 0.3 * c).abs() < 1e-15 && (side[1] - 0.3 * s).abs() < 1e-15);
        let corner = d.edge_offset([c - s, s + c]);
        let exact = [0.3 * c - 0.1 * s, 0.3 * s + 0.1 * c];
        assert!((corner[0] - exact[0]).abs() < 1e-15 && (corner[1] - exact[1]).abs() < 1e-15);
    }

    #[test]
    fn annulus_volume_approaches_its_area() {
        // Area of an annulus: pi (ro^2 - ri^2). Lattice staircase error is
        // O(spacing * perimeter); with spacing 0.01 it is well under 1%.
        let b = Geometry::Annulus {
            center: [0.0, 0.0],
            inner_radius: 0.5,
            outer_radius: 1.0,
        };
        let area: f64 = fill(&b, Density::Spacing(0.01), [0.0, 0.0], Lattice::Body)
            .iter()
            .map(|p| p.volume)
            .sum();
        let exact = std::f64::consts::PI * 0.75;
        assert!((area - exact).abs() / exact < 5e-3, "{area} vs {exact}");
    }

    /// A regular polygon of 3 to 10,000 sides on its own lattice: as many
    /// points as its area holds spacings squared, within 3%, their cells
    /// adding up to the area, every point inside it, and `size` counting
    /// them. The 1000-sided circle of radius 10 m at 0.25 m spacing made
    /// 400,000 points where its area holds 5,027: each thin kite of its
    /// fan got 20 x 20, its counts from the mean of its opposite sides.
    #[test]
    fn a_regular_polygons_points_follow_its_area() {
        let (r, s) = (10.0, 0.25);
        for n in [3, 4, 5, 6, 8, 12, 30, 100, 300, 1000, 3000, 10_000] {
            let vertices: Vec<[f64; 2]> = (0..n)
                .map(|k| {
                    let t = std::f64::consts::TAU * k as f64 / n as f64;
                    [r * t.cos() + 3.0, r * t.sin() - 1.0]
                })
                .collect();
            let area = 0.5 * n as f64 * r * r * (std::f64::consts::TAU / n as f64).sin();
            let polygon = Geometry::Polygon {
                vertices,
                holes: vec![],
            };
            let points = fill(&polygon, Density::Spacing(s), [0.0, 0.0], Lattice::Body);
            let ratio = points.len() as f64 / (area / (s * s));
            assert!(
                (ratio - 1.0).abs() < 0.03,
                "{n} sides: {} points, {ratio:.4} of the area's",
                points.len()
            );
            let volume: f64 = points.iter().map(|p| p.volume).sum();
            assert!(
                (volume / area - 1.0).abs() < 1e-9,
                "{n} sides: volume {volume} of {area}"
            );
            assert!(points.iter().all(|p| p.volume > 0.0), "{n} sides");
            assert!(
                points.iter().all(|p| polygon.contains(p.position)),
                "{n} sides"
            );
            let counted = size(&polygon, Density::Spacing(s), [0.0, 0.0], Lattice::Body);
            assert_eq!(counted.sites, points.len() as f64, "{n} sides");
        }
    }

    /// A polygon on the grid's lattice, its sites found a row at a time,
    /// gets exactly the sites its `contains` takes, site by site.
    #[test]
    fn a_polygons_sites_found_by_rows_are_those_it_contains() {
        let n = 500;
        let star: Vec<[f64; 2]> = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                let r = if k % 2 == 0 { 3.0 } else { 5.0 };
                [r * t.cos() + 0.3, r * t.sin() - 0.2]
            })
            .collect();
        let hole = vec![[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]];
        let polygon = Geometry::Polygon {
            vertices: star,
            holes: vec![hole],
        };
        let (lo, hi) = polygon.bounding_box();
        let by_rows = fill(&polygon, Density::Spacing(0.05), [0.0, 0.0], Lattice::Grid);
        let by_sites = lattice_inside(lo, hi, 0.05, [0.0, 0.0], |p| polygon.contains(p));
        assert!(by_rows.len() > 10_000);
        assert!(
            by_rows
                .iter()
                .map(|p| p.lattice)
                .eq(by_sites.iter().map(|p| p.lattice)),
            "{} sites against {}",
            by_rows.len(),
            by_sites.len()
        );
    }

    #[test]
    fn polygon_holes_are_empty() {
        let square = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let hole = vec![[0.25, 0.25], [0.75, 0.25], [0.75, 0.75], [0.25, 0.75]];
        let b = Geometry::Polygon {
            vertices: square,
            holes: vec![hole],
        };
        // Four points per 0.25 m cell, on the grid's lattice: 16 x 16 sites
        // minus the 8 x 8 of the hole.
        let pts = fill(&b, Density::Spacing(0.25 / 4.0), [0.0, 0.0], Lattice::Grid);
        assert_eq!(pts.len(), 256 - 64);
        // On its own lattice the cells add up to the area exactly, and none
        // is in the hole.
        let pts = fill(&b, Density::Spacing(0.25 / 4.0), [0.0, 0.0], Lattice::Body);
        let area: f64 = pts.iter().map(|p| p.volume).sum();
        assert!((area - 0.75).abs() < 1e-12, "{area}");
        assert!(pts.iter().all(|p| b.contains(p.position)));
    }

    #[test]
    fn size_counts_the_sites_without_visiting_them() {
        let shapes = [
            Geometry::Rectangle {
                min: [0.0, 0.0],
                max: [1.3, 0.7],
                angle: 0.0,
                about: None,
            },
            Geometry::AnnulusSector {
                center: [0.5, 0.5],
                inner_radius: 0.5,
                outer_radius: 1.0,
                start_angle: 10.0,
                end_angle: 100.0,
            },
            Geometry::Circle {
                center: [0.3, 0.2],
                radius: 0.8,
            },
            Geometry::Polygon {
                vertices: vec![[0.0, 0.0], [2.0, 0.3], [0.4, 1.1]],
                holes: vec![],
            },
        ];
        for (g, lattice) in shapes
            .iter()
            .flat_map(|g| [(g, Lattice::Body), (g, Lattice::Grid)])
        {
            let made = fill(g, Density::Spacing(0.05), [0.1, 0.0], lattice).len() as f64;
            let size = size(g, Density::Spacing(0.05), [0.1, 0.0], lattice);
            if size.exact {
                assert_eq!(size.sites, made, "{g:?}");
            } else {
                assert!(
                    size.sites >= made && size.sites < 8.0 * made,
                    "{g:?}: {size:?}"
                );
            }
        }
        // A turned square whose side over the spacing is 3.5: its turned
        // corners' lengths round to 3.4999999999999996, and the count must
        // be the fill's (it once said 9 where the fill made 16).
        let turned = Geometry::Rectangle {
            min: [0.0, 0.0],
            max: [0.7, 0.7],
            angle: 30.0,
            about: None,
        };
        let made = fill(&turned, Density::Spacing(0.2), [0.0, 0.0], Lattice::Body).len() as f64;
        let counted = size(&turned, Density::Spacing(0.2), [0.0, 0.0], Lattice::Body);
        assert_eq!((counted.sites, counted.exact), (made, true));
        // The thin rectangle that once made 5e6 points to count them: its
        // bounding box's area is 5e-6, but it is a column of 5e6 points.
        let thin = Geometry::Rectangle {
            min: [0.0, 0.0],
            max: [1e-9, 5000.0],
            angle: 0.0,
            about: None,
        };
        assert_eq!(
            size(&thin, Density::Spacing(1e-3), [0.0, 0.0], Lattice::Body).sites,
            5e6
        );
        // A sliver polygon scans a column of 1e9 sites for a handful of
        // points; a body 1e300 long gives a finite or infinite count, never
        // a wrapped one.
        let sliver = Geometry::Polygon {
            vertices: vec![[0.0, 0.0], [1e-12, 0.0], [0.0, 1e6]],
            holes: vec![],
        };
        let s = size(&sliver, Density::Spacing(1e-3), [0.0, 0.0], Lattice::Grid);
        assert!(!s.exact && s.sites > 1e9, "{s:?}");
        // On its own lattice it has as many points as its area holds (half
        // of one: the least, three), not the 5e8 its thin kites once had.
        let s = size(&sliver, Density::Spacing(1e-3), [0.0, 0.0], Lattice::Body);
        assert_eq!((s.exact, s.sites), (true, 3.0), "{s:?}");
        let huge = Geometry::Rectangle {
            min: [0.0, 0.0],
            max: [1e300, 1e300],
            angle: 0.0,
            about: None,
        };
        assert!(size(&huge, Density::Spacing(1e-3), [0.0, 0.0], Lattice::Body).sites > 1e300);
    }
}
