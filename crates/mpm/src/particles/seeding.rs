//! Filling a body's reference geometry with material points.
//!
//! Rectangles are divided exactly: `n = round(width / spacing)` points per
//! direction at the centres of equal sub-cells, so the points' volumes add up
//! to the area. Other shapes keep the points of a lattice aligned with the
//! grid (offset half a spacing from the grid lines) that fall inside; each
//! point has the volume of its lattice square, so the total volume differs
//! from the area by the staircase error along curved edges.

use crate::geometry::Geometry;

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

/// How densely a region is filled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Density {
    /// Points this far apart (metres).
    Spacing(f64),
    /// `[nx, ny]` points; rectangles only.
    Count([u32; 2]),
}

/// The material points of `geometry` at `density`, on a lattice through
/// the grid's `origin`.
pub fn fill(geometry: &Geometry, density: Density, origin: [f64; 2]) -> Vec<SeedPoint> {
    let (spacing, count) = match density {
        Density::Spacing(s) => (s, None),
        Density::Count(c) => (f64::NAN, Some(c)), // rectangles only
    };
    match geometry {
        Geometry::Rectangle { min, max } => {
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
            let (lo, hi) = geometry.bounding_box();
            let inside = |p: [f64; 2]| geometry.contains(p);
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
    let [n_r, n_t] = sector_counts(a, b, t0, t1, s).map(|n| n as usize);
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

/// How many lattice sites [`fill`] visits, found without visiting them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FillSize {
    /// Sites visited: for rectangles and annulus sectors every site is a
    /// point; the other shapes scan the lattice over their bounding box and
    /// keep the sites inside.
    pub sites: f64,
    /// Whether every site is a point (rectangles and annulus sectors), so
    /// that `sites` is the number of points, not a bound on it.
    pub exact: bool,
}

/// The size of [`fill`]'s work for `geometry` at `density`, in
/// microseconds whatever the size: per-direction counts multiplied in
/// floating point, so a huge body gives a huge number, not an overflow.
pub fn size(geometry: &Geometry, density: Density, origin: [f64; 2]) -> FillSize {
    let (spacing, count) = match density {
        Density::Spacing(s) => (s, None),
        Density::Count(c) => (f64::NAN, Some(c)),
    };
    let (counts, exact) = match geometry {
        Geometry::Rectangle { min, max } => (
            rectangle_counts([max[0] - min[0], max[1] - min[1]], spacing, count),
            true,
        ),
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
        geometry => {
            let (lo, hi) = geometry.bounding_box();
            let n = |d: usize| {
                let (first, last) = lattice_range(lo, hi, spacing, origin, d);
                last - first + 1.0
            };
            ([n(0), n(1)], false)
        }
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
        };
        let pts = fill(&b, Density::Count([56, 16]), [0.0, 0.0]);
        assert_eq!(pts.len(), 896);
        let area: f64 = pts.iter().map(|p| p.volume).sum();
        assert!((area - 20.0).abs() < 1e-12);
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
        let area: f64 = fill(&b, Density::Spacing(0.01), [0.0, 0.0])
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
        let b = Geometry::Polygon {
            vertices: square,
            holes: vec![hole],
        };
        // Four points per 0.25 m cell.
        let pts = fill(&b, Density::Spacing(0.25 / 4.0), [0.0, 0.0]);
        // 16 x 16 lattice minus the 8 x 8 hole.
        assert_eq!(pts.len(), 256 - 64);
    }

    #[test]
    fn size_counts_the_sites_without_visiting_them() {
        let shapes = [
            Geometry::Rectangle {
                min: [0.0, 0.0],
                max: [1.3, 0.7],
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
        for g in &shapes {
            let made = fill(g, Density::Spacing(0.05), [0.1, 0.0]).len() as f64;
            let size = size(g, Density::Spacing(0.05), [0.1, 0.0]);
            if size.exact {
                assert_eq!(size.sites, made, "{g:?}");
            } else {
                assert!(
                    size.sites >= made && size.sites < 3.0 * made,
                    "{g:?}: {size:?}"
                );
            }
        }
        // The thin rectangle that once made 5e6 points to count them: its
        // bounding box's area is 5e-6, but it is a column of 5e6 points.
        let thin = Geometry::Rectangle {
            min: [0.0, 0.0],
            max: [1e-9, 5000.0],
        };
        assert_eq!(size(&thin, Density::Spacing(1e-3), [0.0, 0.0]).sites, 5e6);
        // A sliver polygon scans a column of 1e9 sites for a handful of
        // points; a body 1e300 long gives a finite or infinite count, never
        // a wrapped one.
        let sliver = Geometry::Polygon {
            vertices: vec![[0.0, 0.0], [1e-12, 0.0], [0.0, 1e6]],
            holes: vec![],
        };
        let s = size(&sliver, Density::Spacing(1e-3), [0.0, 0.0]);
        assert!(!s.exact && s.sites > 1e9, "{s:?}");
        let huge = Geometry::Rectangle {
            min: [0.0, 0.0],
            max: [1e300, 1e300],
        };
        assert!(size(&huge, Density::Spacing(1e-3), [0.0, 0.0]).sites > 1e300);
    }
}
