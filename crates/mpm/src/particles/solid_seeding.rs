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
//! - A hexahedral mesh: each element's trilinear map of a lattice on the
//!   unit cube, as many cells along each of its directions as the mean
//!   length of its four edges that way holds spacings; a point at each
//!   cell's mapped centre, its volume the cell's exact one (the map's
//!   Jacobian is quadratic in each direction, so 2 x 2 x 2 Gauss points
//!   integrate it).
//!
//! A point's GIMP domain in 3D is an axis-aligned box (the 3D bases
//! average over boxes only, `grid::basis`): an upright cell's own box,
//! exactly; a mesh's cell the extents of its linearised shape through its
//! centre ([`cell_half_widths`]); any other cell (a turned or polar
//! section, a spherical cell) the cube of its volume, which keeps its
//! volume but not its shape.

use super::seeding::{self, Density, Lattice};
use crate::geometry::{Geometry, HexMesh};

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
    /// Hexahedra, each with corners of one handedness (the case's
    /// validation orders them).
    Mesh(HexMesh),
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
        Solid::Mesh(mesh) => hexahedra(mesh, spacing),
    }
}

/// Cells of element `corners` along each of its directions at spacing `s`.
pub fn hexahedron_counts(corners: &[[f64; 3]; 8], s: f64) -> [usize; 3] {
    // The corners joined along direction d differ in bit d of their
    // lattice place (x fastest: 0, 1, 3, 2 round the first face).
    const PLACE: [usize; 8] = [0, 1, 3, 2, 4, 5, 7, 6];
    std::array::from_fn(|d| {
        let mut length = 0.0;
        for (a, &pa) in PLACE.iter().enumerate() {
            if pa & (1 << d) == 0 {
                let b = PLACE
                    .iter()
                    .position(|&pb| pb == pa | (1 << d))
                    .expect("a corner");
                length += distance(corners[a], corners[b]) / 4.0;
            }
        }
        (length / s).round().max(1.0) as usize
    })
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The trilinear map of element `corners` at `xi` in the unit cube, and
/// its Jacobian's determinant there.
pub fn trilinear(corners: &[[f64; 3]; 8], xi: [f64; 3]) -> ([f64; 3], f64) {
    let (x, j) = trilinear_map(corners, xi);
    let det = j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
        - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
        + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0]);
    (x, det)
}

/// The trilinear map of element `corners` at `xi` and its Jacobian
/// `dx_i / dxi_d`, row `i`.
fn trilinear_map(corners: &[[f64; 3]; 8], xi: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    // Lattice place of each corner, x fastest (gmsh's 2 and 3 swap).
    const PLACE: [[bool; 3]; 8] = [
        [false, false, false],
        [true, false, false],
        [true, true, false],
        [false, true, false],
        [false, false, true],
        [true, false, true],
        [true, true, true],
        [false, true, true],
    ];
    let mut x = [0.0; 3];
    let mut jacobian = [[0.0; 3]; 3];
    for (c, place) in corners.iter().zip(PLACE) {
        let w: [f64; 3] = std::array::from_fn(|d| if place[d] { xi[d] } else { 1.0 - xi[d] });
        let sign: [f64; 3] = std::array::from_fn(|d| if place[d] { 1.0 } else { -1.0 });
        let n = w[0] * w[1] * w[2];
        let dn = [
            sign[0] * w[1] * w[2],
            w[0] * sign[1] * w[2],
            w[0] * w[1] * sign[2],
        ];
        for i in 0..3 {
            x[i] += n * c[i];
            for d in 0..3 {
                jacobian[i][d] += dn[d] * c[i];
            }
        }
    }
    (x, jacobian)
}

/// The box domain of the cell of element `corners` centred at `xi`, `n`
/// cells along each of its directions: along each axis, the cell's
/// extent through its centre on the map's linearisation there (where the
/// line along the axis leaves the parallelepiped `J [-d xi / 2, d xi /
/// 2]^3`). A cell of an axis-aligned box gets its own box; a cell on a
/// plane face of the body reaches that face and no farther, so a support
/// on the face's grid plane holds it as it holds a box's. (The cube of the
/// cell's volume, the spheres' choice, reached past a clamped face and
/// left the distorted beam of `verification/cantilever3d.rs` 0.1% too
/// flexible whatever the cell size.)
fn cell_half_widths(corners: &[[f64; 3]; 8], xi: [f64; 3], n: [usize; 3]) -> [f64; 3] {
    let j = trilinear_map(corners, xi).1;
    let m = nalgebra::Matrix3::from_fn(|r, c| j[r][c]);
    let inverse = m.try_inverse().expect("a validated element is not flat");
    std::array::from_fn(|i| {
        (0..3)
            .filter(|&k| inverse[(k, i)] != 0.0)
            .map(|k| 0.5 / (n[k] as f64 * inverse[(k, i)].abs()))
            .fold(f64::INFINITY, f64::min)
    })
}

fn hexahedra(mesh: &HexMesh, s: f64) -> Vec<SolidSeed> {
    let gauss = [0.5 - 0.5 / 3f64.sqrt(), 0.5 + 0.5 / 3f64.sqrt()];
    let mut out = Vec::new();
    for k in 0..mesh.elements.len() {
        let corners = mesh.corners(k);
        let n = hexahedron_counts(&corners, s);
        for l in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let cell = [i, j, l];
                    let at = |d: usize, t: f64| (cell[d] as f64 + t) / n[d] as f64;
                    let mut volume = 0.0;
                    for a in gauss {
                        for b in gauss {
                            for c in gauss {
                                volume += trilinear(&corners, [at(0, a), at(1, b), at(2, c)]).1;
                            }
                        }
                    }
                    volume /= 8.0 * (n[0] * n[1] * n[2]) as f64;
                    let centre = [at(0, 0.5), at(1, 0.5), at(2, 0.5)];
                    out.push(SolidSeed {
                        position: trilinear(&corners, centre).0,
                        volume,
                        lattice: [k as i64, i as i64, ((j as i64) << 32) + l as i64],
                        half_widths: cell_half_widths(&corners, centre, n),
                    });
                }
            }
        }
    }
    out
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

    /// A hexahedral mesh holds its exact volume with every point in its
    /// element: a unit cube cut into two hexahedra by a skewed, warped
    /// middle face (its four nodes moved off the plane x = 0.5), each
    /// element a cube of 0.5 m sides filled at 0.1 m, and a mirrored
    /// element seeded as its right-handed twin. An axis-aligned element's
    /// points are its lattice's boxes.
    #[test]
    fn a_hexahedral_mesh_holds_its_exact_volume() {
        let mut nodes = Vec::new();
        for z in [0.0, 1.0] {
            for y in [0.0, 1.0] {
                for x in [0.0, 0.5, 1.0] {
                    nodes.push([x, y, z]);
                }
            }
        }
        // The middle face: x = 0.5 moved to 0.3, 0.7, 0.45, 0.6 at its corners.
        for (n, x) in [(1, 0.3), (4, 0.7), (7, 0.45), (10, 0.6)] {
            nodes[n][0] = x;
        }
        let elements = vec![[0, 1, 4, 3, 6, 7, 10, 9], [1, 2, 5, 4, 7, 8, 11, 10]];
        let mesh = HexMesh { nodes, elements };
        let seeds = fill(&Solid::Mesh(mesh.clone()), 0.1);
        assert!((total(&seeds) - 1.0).abs() < 1e-14, "{}", total(&seeds));
        assert!(seeds.iter().all(|s| s.volume > 0.0));
        for s in &seeds {
            assert!(
                s.position.iter().all(|&x| (0.0..=1.0).contains(&x)),
                "{s:?}"
            );
        }
        // The left element alone, its volume by the divergence theorem:
        // the middle face's mean x over the unit square (0.5125) times 1.
        let left = fill(
            &Solid::Mesh(HexMesh {
                elements: vec![mesh.elements[0]],
                ..mesh.clone()
            }),
            0.1,
        );
        assert!((total(&left) - 0.5125).abs() < 1e-14, "{}", total(&left));
        let e = mesh.elements[0];
        let mirrored = [e[0], e[3], e[2], e[1], e[4], e[7], e[6], e[5]];
        let twin = fill(
            &Solid::Mesh(HexMesh {
                elements: vec![mirrored],
                ..mesh.clone()
            }),
            0.1,
        );
        assert!(
            (total(&twin) + 0.5125).abs() < 1e-14,
            "the seeding takes elements as given"
        );
        let cube = HexMesh {
            nodes: vec![
                [0.0, 0.0, 0.0],
                [0.5, 0.0, 0.0],
                [0.5, 1.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 2.0],
                [0.5, 0.0, 2.0],
                [0.5, 1.0, 2.0],
                [0.0, 1.0, 2.0],
            ],
            elements: vec![[0, 1, 2, 3, 4, 5, 6, 7]],
        };
        let seeds = fill(&Solid::Mesh(cube), 0.25);
        assert_eq!(seeds.len(), 2 * 4 * 8);
        assert!(
            seeds.iter().all(|s| s.half_widths == [0.125; 3]),
            "{:?}",
            seeds[0]
        );
        assert!((total(&seeds) - 1.0).abs() < 1e-14);
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
