//! Filling a body's reference geometry with material points.
//!
//! Rectangles are divided exactly: `n = round(width / spacing)` points per
//! direction at the centres of equal sub-cells, so the points' volumes add up
//! to the area. Other shapes keep the points of a lattice aligned with the
//! grid (offset half a spacing from the grid lines) that fall inside; each
//! point has the volume of its lattice square, so the total volume differs
//! from the area by the staircase error along curved edges.

use crate::case::{Body, Geometry};

/// One material point as generated: position, volume, the half-widths of
/// its (rectangular) domain, and its place `(i, j)` in the body's lattice
/// (neighbours differ by one in `i` or `j`; the boundary is found from it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeedPoint {
    pub position: [f64; 2],
    pub volume: f64,
    pub half_width: [f64; 2],
    pub lattice: [i64; 2],
    /// The point's domain as a rectangle in its own frame: half-widths and
    /// the frame's angle (radians; radial/tangential for polar fills). The
    /// boundary's offset to the material edge uses it.
    pub domain: Domain,
}

/// A point's rectangular domain in a rotated frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Domain {
    pub half_width: [f64; 2],
    pub angle: f64,
}

/// The material points of `body` for a grid of `cell_size` with a node at
/// `origin`.
pub fn fill_body(body: &Body, cell_size: f64, origin: [f64; 2]) -> Vec<SeedPoint> {
    let spacing = match (body.points.per_cell, body.points.spacing) {
        (Some(n), _) => cell_size / n as f64,
        (_, Some(s)) => s,
        _ => f64::NAN, // `count`: rectangles only, handled below
    };
    match &body.geometry {
        Geometry::Rectangle { min, max } => {
            let size = [max[0] - min[0], max[1] - min[1]];
            let n = body
                .points
                .count
                .map(|c| [c[0] as usize, c[1] as usize])
                .unwrap_or_else(|| size.map(|l| ((l / spacing).round() as usize).max(1)));
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
                        half_width: [step[0] / 2.0, step[1] / 2.0],
                        lattice: [i as i64, j as i64],
                        domain: Domain {
                            half_width: [step[0] / 2.0, step[1] / 2.0],
                            angle: 0.0,
                        },
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
        geometry => {
            let (lo, hi) = bounding_box(geometry);
            let inside = |p: [f64; 2]| contains(geometry, p);
            lattice_inside(lo, hi, spacing, origin, inside)
        }
    }
}

/// A polar lattice on an annulus sector: `n_r` rings of equal width and
/// `n_t` equal angular divisions, both from the spacing (at the mean
/// radius). Each point has the exact area of its annular cell; its lattice
/// place is (ring, division), which maps counter-clockwise loops to
/// counter-clockwise loops.
fn polar_sector(c: [f64; 2], a: f64, b: f64, t0: f64, t1: f64, s: f64) -> Vec<SeedPoint> {
    let n_r = (((b - a) / s).round() as usize).max(1);
    let n_t = (((t1 - t0) * 0.5 * (a + b) / s).round() as usize).max(1);
    let (dr, dt) = ((b - a) / n_r as f64, (t1 - t0) / n_t as f64);
    let mut out = Vec::with_capacity(n_r * n_t);
    for j in 0..n_t {
        for i in 0..n_r {
            let r = a + (i as f64 + 0.5) * dr;
            let t = t0 + (j as f64 + 0.5) * dt;
            let volume = r * dr * dt;
            // GIMP domains are axis-aligned: the square of the same area.
            let square = volume.sqrt() / 2.0;
            out.push(SeedPoint {
                position: [c[0] + r * t.cos(), c[1] + r * t.sin()],
                volume,
                half_width: [square, square],
                lattice: [i as i64, j as i64],
                domain: Domain {
                    half_width: [dr / 2.0, r * dt / 2.0],
                    angle: t,
                },
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
    inside: impl Fn([f64; 2]) -> bool,
) -> Vec<SeedPoint> {
    let first = |d: usize| ((lo[d] - origin[d]) / s - 0.5).floor() as i64;
    let last = |d: usize| ((hi[d] - origin[d]) / s - 0.5).ceil() as i64;
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
                    half_width: [s / 2.0, s / 2.0],
                    lattice: [i, j],
                    domain: Domain {
                        half_width: [s / 2.0, s / 2.0],
                        angle: 0.0,
                    },
                });
            }
        }
    }
    out
}

/// An upper bound on the number of points `fill_body` makes, without
/// making them: the bounding box's area over a point's area (exact for
/// rectangles). Lets a service refuse a huge case before allocating it.
pub fn max_points(body: &Body, cell_size: f64) -> f64 {
    let (lo, hi) = bounding_box(&body.geometry);
    let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
    match (body.points.count, body.points.per_cell, body.points.spacing) {
        (Some([nx, ny]), _, _) => nx as f64 * ny as f64,
        (_, Some(n), _) => area / (cell_size / n as f64).powi(2) + 1.0,
        (_, _, Some(s)) => area / (s * s) + 1.0,
        _ => 0.0,
    }
}

/// Axis-aligned bounding box of a geometry.
pub fn bounding_box(geometry: &Geometry) -> ([f64; 2], [f64; 2]) {
    match geometry {
        Geometry::Rectangle { min, max } => (*min, *max),
        Geometry::Polygon { vertices, .. } => {
            let mut lo = [f64::INFINITY; 2];
            let mut hi = [f64::NEG_INFINITY; 2];
            for v in vertices {
                for d in 0..2 {
                    lo[d] = lo[d].min(v[d]);
                    hi[d] = hi[d].max(v[d]);
                }
            }
            (lo, hi)
        }
        Geometry::Circle { center, radius: r }
        | Geometry::Annulus {
            center,
            outer_radius: r,
            ..
        }
        | Geometry::AnnulusSector {
            center,
            outer_radius: r,
            ..
        } => (
            [center[0] - r, center[1] - r],
            [center[0] + r, center[1] + r],
        ),
    }
}

/// Whether `p` lies inside the geometry (holes excluded).
pub fn contains(geometry: &Geometry, p: [f64; 2]) -> bool {
    let dist = |c: &[f64; 2]| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt();
    match geometry {
        Geometry::Rectangle { min, max } => {
            p[0] > min[0] && p[0] < max[0] && p[1] > min[1] && p[1] < max[1]
        }
        Geometry::Polygon { vertices, holes } => {
            point_in_ring(vertices, p) && !holes.iter().any(|h| point_in_ring(h, p))
        }
        Geometry::Circle { center, radius } => dist(center) < *radius,
        Geometry::Annulus {
            center,
            inner_radius,
            outer_radius,
        } => {
            let d = dist(center);
            d > *inner_radius && d < *outer_radius
        }
        Geometry::AnnulusSector {
            center,
            inner_radius,
            outer_radius,
            start_angle,
            end_angle,
        } => {
            let d = dist(center);
            let t = (p[1] - center[1]).atan2(p[0] - center[0]).to_degrees();
            let t = start_angle + (t - start_angle).rem_euclid(360.0);
            d > *inner_radius && d < *outer_radius && t < *end_angle
        }
    }
}

/// Even-odd crossing test against a closed ring of vertices.
fn point_in_ring(ring: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut inside = false;
    let n = ring.len();
    for i in 0..n {
        let a = ring[i];
        let b = ring[(i + 1) % n];
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Shoelace area, positive for counter-clockwise rings.
pub fn signed_area(ring: &[[f64; 2]]) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| {
            let a = ring[i];
            let b = ring[(i + 1) % n];
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::{MaterialSpec, PointFill};

    fn body(geometry: Geometry, points: PointFill) -> Body {
        Body {
            name: None,
            geometry,
            points,
            material: MaterialSpec::Hencky {
                youngs_modulus: 1.0,
                poisson_ratio: 0.0,
                density: 1.0,
            },
        }
    }

    #[test]
    fn rectangle_by_count_matches_the_paper_layout() {
        // The paper's cantilever: 10 m x 2 m with 56 x 16 = 896 points.
        let b = body(
            Geometry::Rectangle {
                min: [0.0, 0.0],
                max: [10.0, 2.0],
            },
            PointFill {
                count: Some([56, 16]),
                ..Default::default()
            },
        );
        let pts = fill_body(&b, 1.5, [0.0, 0.0]);
        assert_eq!(pts.len(), 896);
        let area: f64 = pts.iter().map(|p| p.volume).sum();
        assert!((area - 20.0).abs() < 1e-12);
    }

    #[test]
    fn annulus_volume_approaches_its_area() {
        // Area of an annulus: pi (ro^2 - ri^2). Lattice staircase error is
        // O(spacing * perimeter); with spacing 0.01 it is well under 1%.
        let b = body(
            Geometry::Annulus {
                center: [0.0, 0.0],
                inner_radius: 0.5,
                outer_radius: 1.0,
            },
            PointFill {
                spacing: Some(0.01),
                ..Default::default()
            },
        );
        let area: f64 = fill_body(&b, 0.1, [0.0, 0.0])
            .iter()
            .map(|p| p.volume)
            .sum();
        let exact = std::f64::consts::PI * 0.75;
        assert!((area - exact).abs() / exact < 5e-3, "{area} vs {exact}");
    }

    #[test]
    fn polygon_holes_are_empty() {
        let square = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let hole = vec![[0.25, 0.25], [0.75, 0.25], [0.75, 0.75], [0.25, 0.75]];
        let b = body(
            Geometry::Polygon {
                vertices: square,
                holes: vec![hole],
            },
            PointFill {
                per_cell: Some(4),
                ..Default::default()
            },
        );
        let pts = fill_body(&b, 0.25, [0.0, 0.0]);
        // 16 x 16 lattice minus the 8 x 8 hole.
        assert_eq!(pts.len(), 256 - 64);
    }
}
