//! The material points of 3D bodies: each body on its own lattice, each
//! point with the exact volume of its cell, as in 2D
//! ([`super::seeding`]).
//!
//! - An extrusion along z of any 2D section (a box is an extruded
//!   rectangle, a cylinder an extruded circle or annulus): the section's
//!   2D points, each repeated in equal layers, its area times the layer's
//!   height.
//! - A sphere or a spherical shell: shells of equal thickness, each cut
//!   into bands of equal polar angle, each band into equal sectors, as many
//!   as the spacing gives at its middle (so that the cells stay near
//!   cubic from the centre out); a cell's volume is the exact
//!   `(r1^3 - r0^3) / 3 (cos t0 - cos t1) dphi`.
//!
//! A point's GIMP domain in 3D is an axis-aligned box (the 3D bases
//! average over boxes only, `grid::basis`): an upright cell's own box,
//! exactly; any other cell (a turned or polar section, a spherical cell)
//! the cube of its volume, which keeps its volume but not its shape.

use super::seeding::{self, Density, Lattice};
use crate::geometry::Geometry;

/// A 3D point as seeded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolidSeed {
    pub position: [f64; 3],
    pub volume: f64,
    /// Place in the body's lattice: the section's place and the layer;
    /// (shell, band, sector) on a sphere.
    pub lattice: [i64; 3],
    /// Half-widths of the point's box domain.
    pub half_widths: [f64; 3],
}

/// The 3D bodies seeded so far.
#[derive(Debug, Clone, PartialEq)]
pub enum Solid {
    /// `section` (a 2D geometry in x, y) from `z[0]` to `z[1]`.
    Extrusion { section: Geometry, z: [f64; 2] },
    /// The shell between two radii about `center` (a ball with
    /// `inner_radius` 0).
    SphericalShell {
        center: [f64; 3],
        inner_radius: f64,
        outer_radius: f64,
    },
}

impl Solid {
    /// The box `min`..`max`.
    pub fn cuboid(min: [f64; 3], max: [f64; 3]) -> Self {
        Solid::Extrusion {
            section: Geometry::Rectangle {
                min: [min[0], min[1]],
                max: [max[0], max[1]],
                angle: 0.0,
                about: None,
            },
            z: [min[2], max[2]],
        }
    }
}

/// The points of `solid` about `spacing` apart.
pub fn fill(solid: &Solid, spacing: f64) -> Vec<SolidSeed> {
    match solid {
        Solid::Extrusion { section, z } => extrusion(section, *z, spacing),
        Solid::SphericalShell {
            center,
            inner_radius,
            outer_radius,
        } => spherical_shell(*center, *inner_radius, *outer_radius, spacing),
    }
}

fn extrusion(section: &Geometry, z: [f64; 2], s: f64) -> Vec<SolidSeed> {
    let plane = seeding::fill(section, Density::Spacing(s), [0.0, 0.0], Lattice::Body);
    let layers = ((z[1] - z[0]) / s).round().max(1.0) as usize;
    let dz = (z[1] - z[0]) / layers as f64;
    let mut out = Vec::with_capacity(plane.len() * layers);
    for k in 0..layers {
        for seed in &plane {
            let [a, b] = seed.domain.axes;
            let upright = a[1] == 0.0 && b[0] == 0.0 && seed.domain.twist == [0.0, 0.0];
            let [hx, hy] = if upright {
                [a[0].abs(), b[1].abs()]
            } else {
                [seed.volume.sqrt() / 2.0; 2]
            };
            out.push(SolidSeed {
                position: [
                    seed.position[0],
                    seed.position[1],
                    z[0] + (k as f64 + 0.5) * dz,
                ],
                volume: seed.volume * dz,
                lattice: [seed.lattice[0], seed.lattice[1], k as i64],
                half_widths: [hx, hy, dz / 2.0],
            });
        }
    }
    out
}

fn spherical_shell(c: [f64; 3], a: f64, b: f64, s: f64) -> Vec<SolidSeed> {
    use std::f64::consts::{PI, TAU};
    let shells = ((b - a) / s).round().max(1.0) as usize;
    let dr = (b - a) / shells as f64;
    let mut out = Vec::new();
    for i in 0..shells {
        let (r0, r1) = (a + i as f64 * dr, a + (i + 1) as f64 * dr);
        let r = 0.5 * (r0 + r1);
        let bands = (PI * r / s).round().max(2.0) as usize;
        let dt = PI / bands as f64;
        for j in 0..bands {
            let (t0, t1) = (j as f64 * dt, (j + 1) as f64 * dt);
            let t = 0.5 * (t0 + t1);
            let sectors = (TAU * r * t.sin() / s).round().max(3.0) as usize;
            let dphi = TAU / sectors as f64;
            let volume = (r1.powi(3) - r0.powi(3)) / 3.0 * (t0.cos() - t1.cos()) * dphi;
            for k in 0..sectors {
                let phi = (k as f64 + 0.5) * dphi;
                out.push(SolidSeed {
                    position: [
                        c[0] + r * t.sin() * phi.cos(),
                        c[1] + r * t.sin() * phi.sin(),
                        c[2] + r * t.cos(),
                    ],
                    volume,
                    lattice: [i as i64, j as i64, k as i64],
                    half_widths: [volume.cbrt() / 2.0; 3],
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn total(seeds: &[SolidSeed]) -> f64 {
        seeds.iter().map(|s| s.volume).sum()
    }

    /// A box is a lattice of equal boxes that tile it: the counts the
    /// spacing gives, the volume exact, each point its box's centre.
    #[test]
    fn a_box_is_tiled_by_the_boxes_of_its_points() {
        let solid = Solid::cuboid([0.0, -1.0, 2.0], [3.0, 1.0, 2.5]);
        let seeds = fill(&solid, 0.25);
        assert_eq!(seeds.len(), 12 * 8 * 2);
        assert!((total(&seeds) - 3.0).abs() < 1e-12);
        for s in &seeds {
            assert_eq!(s.half_widths, [0.125; 3]);
            assert!((s.volume - 8.0 * 0.125f64.powi(3)).abs() < 1e-15);
            let [i, j, k] = s.lattice.map(|v| v as f64);
            let expected = [0.125 + 0.25 * i, -0.875 + 0.25 * j, 2.125 + 0.25 * k];
            for d in 0..3 {
                assert!((s.position[d] - expected[d]).abs() < 1e-12, "{s:?}");
            }
        }
    }

    /// Cylinders (extruded circles and annuli) and an extruded L-shaped
    /// polygon hold their exact volumes, `pi (b^2 - a^2) h` and area times
    /// height, with every point inside.
    #[test]
    fn extrusions_hold_their_exact_volumes() {
        use std::f64::consts::PI;
        let cylinder = Solid::Extrusion {
            section: Geometry::Circle {
                center: [1.0, 2.0],
                radius: 0.8,
            },
            z: [0.0, 2.0],
        };
        let tube = Solid::Extrusion {
            section: Geometry::Annulus {
                center: [0.0, 0.0],
                inner_radius: 0.5,
                outer_radius: 1.0,
            },
            z: [-1.0, 1.0],
        };
        let l_shape = Solid::Extrusion {
            section: Geometry::Polygon {
                vertices: vec![
                    [0.0, 0.0],
                    [2.0, 0.0],
                    [2.0, 1.0],
                    [1.0, 1.0],
                    [1.0, 2.0],
                    [0.0, 2.0],
                ],
                holes: vec![],
            },
            z: [0.0, 0.5],
        };
        let exact = [PI * 0.64 * 2.0, PI * 0.75 * 2.0, 3.0 * 0.5];
        for (solid, exact) in [cylinder, tube, l_shape].iter().zip(exact) {
            let seeds = fill(solid, 0.1);
            assert!(
                (total(&seeds) - exact).abs() < 1e-12 * exact,
                "{solid:?}: {}",
                total(&seeds)
            );
            let Solid::Extrusion { section, z } = solid else {
                unreachable!()
            };
            for s in &seeds {
                assert!(
                    section.contains([s.position[0], s.position[1]])
                        && s.position[2] > z[0]
                        && s.position[2] < z[1]
                );
                let box_volume = 8.0 * s.half_widths.iter().product::<f64>();
                assert!((box_volume - s.volume).abs() < 1e-12 * s.volume, "{s:?}");
            }
        }
    }

    /// A ball and spherical shells: the cells' exact volumes add up to
    /// `4/3 pi (b^3 - a^3)` to round-off, every point lies in the shell,
    /// and no cell is far from the spacing's size (the cube root of its
    /// volume between a tenth and three spacings).
    #[test]
    fn spheres_hold_their_exact_volumes_in_near_cubic_cells() {
        use std::f64::consts::PI;
        for (a, b, s) in [(0.0, 1.0, 0.1), (0.6, 1.0, 0.05), (2.0, 2.3, 0.1)] {
            let solid = Solid::SphericalShell {
                center: [0.5, -1.0, 3.0],
                inner_radius: a,
                outer_radius: b,
            };
            let seeds = fill(&solid, s);
            let exact = 4.0 / 3.0 * PI * (b * b * b - a * a * a);
            assert!(
                (total(&seeds) - exact).abs() < 1e-12 * exact,
                "{a} {b}: {}",
                total(&seeds)
            );
            for p in &seeds {
                let d = [0, 1, 2].map(|k| p.position[k] - [0.5, -1.0, 3.0][k]);
                let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                assert!(r > a && r < b, "{p:?}");
                let width = p.volume.cbrt();
                assert!(width < 3.0 * s && width > s / 10.0, "{p:?}");
            }
        }
    }
}
