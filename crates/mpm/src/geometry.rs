//! Plane geometry shared by the case and the solver: the regions bodies
//! fill, the selections supports and loads act on, and the polygon
//! primitives (area, point in ring) used by seeding, validation and the boundary.
//!
//! The case schema re-exports [`Geometry`] and [`Selector`]: they are values
//! the solver reads directly, so the solver never imports the schema.

use serde::{Deserialize, Serialize};

/// The region a body fills, in the reference configuration.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Geometry {
    /// The box `min`..`max`, turned by `angle` (degrees, counter-clockwise)
    /// about `about` (default: its centre). A turned rectangle is filled on
    /// its own lattice, as a quadrilateral is.
    Rectangle {
        min: [f64; 2],
        max: [f64; 2],
        #[serde(default)]
        angle: f64,
        #[serde(default)]
        about: Option<[f64; 2]>,
    },
    /// A simple polygon (either orientation) with optional polygonal holes.
    Polygon {
        vertices: Vec<[f64; 2]>,
        #[serde(default)]
        holes: Vec<Vec<[f64; 2]>>,
    },
    Circle {
        center: [f64; 2],
        radius: f64,
    },
    Annulus {
        center: [f64; 2],
        inner_radius: f64,
        outer_radius: f64,
    },
    /// A convex quadrilateral (vertices in order, either orientation),
    /// filled on its own mapped lattice: the bilinear map of a grid on the
    /// unit square, so its four edges are rows of points whatever their
    /// slope.
    Quadrilateral {
        vertices: [[f64; 2]; 4],
    },
    /// A 2D mesh of triangles and quadrilaterals (node indices, either way
    /// round), as meshio reads it from a gmsh file. Its boundary is the
    /// edges that one element alone has.
    Mesh(Mesh),
    /// The part of an annulus between two angles (degrees, counter-clockwise
    /// from +x, less than a full turn apart), filled on a polar lattice so
    /// that its arcs are rows of points.
    AnnulusSector {
        center: [f64; 2],
        inner_radius: f64,
        outer_radius: f64,
        start_angle: f64,
        end_angle: f64,
    },
}

/// The nodes and elements of a mesh body.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Mesh {
    pub nodes: Vec<[f64; 2]>,
    /// Three or four node indices each.
    pub elements: Vec<Vec<usize>>,
}

/// The nodes and hexahedra of a 3D mesh body, as meshio reads them from a
/// gmsh file: each element's eight corners in gmsh's (and VTK's) order, the
/// face `0 1 2 3` then the opposite face `4 5 6 7`, node `k + 4` across
/// from node `k`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HexMesh {
    pub nodes: Vec<[f64; 3]>,
    pub elements: Vec<[usize; 8]>,
}

impl HexMesh {
    /// A hexahedron's six faces, as its corners (gmsh's order).
    pub const FACES: [[usize; 4]; 6] = [
        [0, 1, 2, 3],
        [4, 5, 6, 7],
        [0, 1, 5, 4],
        [1, 2, 6, 5],
        [2, 3, 7, 6],
        [3, 0, 4, 7],
    ];

    /// The nodes of face `face` of element `k`, sorted: the same for the
    /// two elements that share it.
    pub fn face_key(&self, k: usize, face: usize) -> [usize; 4] {
        let mut key = Self::FACES[face].map(|c| self.elements[k][c]);
        key.sort_unstable();
        key
    }

    /// Element `k`'s corners.
    pub fn corners(&self, k: usize) -> [[f64; 3]; 8] {
        self.elements[k].map(|i| self.nodes[i])
    }
}

impl Mesh {
    /// Each element's corners, counter-clockwise.
    pub fn element_corners(&self) -> impl Iterator<Item = Vec<[f64; 2]>> + '_ {
        self.elements.iter().map(|e| {
            let mut v: Vec<[f64; 2]> = e.iter().map(|&i| self.nodes[i]).collect();
            if signed_area(&v) < 0.0 {
                v.reverse();
            }
            v
        })
    }

    /// The boundary as closed rings of nodes, each with the material on its
    /// left (outer boundaries counter-clockwise, holes clockwise): the
    /// edges that one element alone has, directed as that element runs
    /// counter-clockwise, chained end to start. `Err` names an element or
    /// node where the boundary is not a set of simple closed rings.
    pub fn boundary_rings(&self) -> Result<Vec<Vec<[f64; 2]>>, String> {
        use std::collections::HashMap;
        let mut count: HashMap<(usize, usize), u32> = HashMap::new();
        let mut directed = Vec::new();
        for e in &self.elements {
            let v: Vec<[f64; 2]> = e.iter().map(|&i| self.nodes[i]).collect();
            let mut e = e.clone();
            if signed_area(&v) < 0.0 {
                e.reverse();
            }
            for k in 0..e.len() {
                let (a, b) = (e[k], e[(k + 1) % e.len()]);
                *count.entry((a.min(b), a.max(b))).or_default() += 1;
                directed.push((a, b));
            }
        }
        if let Some(((a, b), n)) = count.iter().find(|(_, n)| **n > 2) {
            return Err(format!(
                "the edge from node {a} to node {b} is shared by {n} elements"
            ));
        }
        let mut next: HashMap<usize, usize> = HashMap::new();
        for &(a, b) in &directed {
            if count[&(a.min(b), a.max(b))] == 1 && next.insert(a, b).is_some() {
                return Err(format!(
                    "node {a} starts two stretches of boundary (elements meet only at it)"
                ));
            }
        }
        let mut starts: Vec<usize> = next.keys().copied().collect();
        starts.sort_unstable();
        let mut seen = std::collections::HashSet::new();
        let mut rings = Vec::new();
        for start in starts {
            if seen.contains(&start) {
                continue;
            }
            let mut ring = Vec::new();
            let mut at = start;
            loop {
                if !seen.insert(at) {
                    return Err(format!("the boundary through node {at} does not close"));
                }
                ring.push(self.nodes[at]);
                at = match next.get(&at) {
                    Some(&b) => b,
                    None => return Err(format!("the boundary stops at node {at}")),
                };
                if at == start {
                    break;
                }
            }
            rings.push(ring);
        }
        Ok(rings)
    }
}

impl Geometry {
    /// A turned rectangle's corners, counter-clockwise; `None` for any
    /// other geometry and for a rectangle that is not turned.
    pub fn turned_corners(&self) -> Option<[[f64; 2]; 4]> {
        match *self {
            Geometry::Rectangle {
                min,
                max,
                angle,
                about,
            } if angle != 0.0 => Some(turned_rectangle(min, max, angle, about)),
            _ => None,
        }
    }

    /// Axis-aligned bounding box of a geometry.
    pub fn bounding_box(&self) -> ([f64; 2], [f64; 2]) {
        match self {
            Geometry::Rectangle { min, max, .. } => match self.turned_corners() {
                Some(corners) => vertex_box(&corners),
                None => (*min, *max),
            },
            Geometry::Polygon { vertices, .. } => vertex_box(vertices),
            Geometry::Mesh(mesh) => vertex_box(&mesh.nodes),
            Geometry::Quadrilateral { vertices } => vertex_box(vertices),
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
    pub fn contains(&self, p: [f64; 2]) -> bool {
        let dist = |c: &[f64; 2]| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt();
        match self {
            Geometry::Rectangle { min, max, .. } => match self.turned_corners() {
                Some(corners) => inside_ring(&corners, p),
                None => p[0] > min[0] && p[0] < max[0] && p[1] > min[1] && p[1] < max[1],
            },
            Geometry::Polygon { vertices, holes } => {
                inside_ring(vertices, p) && !holes.iter().any(|h| inside_ring(h, p))
            }
            Geometry::Quadrilateral { vertices } => inside_ring(vertices, p),
            Geometry::Mesh(mesh) => mesh.element_corners().any(|v| inside_ring(&v, p)),
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
}

/// The corners of the box `min`..`max` turned by `angle` degrees about
/// `about` (default: its centre), counter-clockwise from the turned `min`.
pub fn turned_rectangle(
    min: [f64; 2],
    max: [f64; 2],
    angle: f64,
    about: Option<[f64; 2]>,
) -> [[f64; 2]; 4] {
    let c = about.unwrap_or([(min[0] + max[0]) / 2.0, (min[1] + max[1]) / 2.0]);
    let (sin, cos) = angle.to_radians().sin_cos();
    [
        [min[0], min[1]],
        [max[0], min[1]],
        [max[0], max[1]],
        [min[0], max[1]],
    ]
    .map(|[x, y]| {
        let (dx, dy) = (x - c[0], y - c[1]);
        [c[0] + cos * dx - sin * dy, c[1] + sin * dx + cos * dy]
    })
}

/// Axis-aligned bounding box of a list of vertices.
fn vertex_box(vertices: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
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

/// A geometric selection in the reference configuration: every given
/// condition must hold. `{"x": 0}` is the line x = 0; add
/// `"y_between": [0, 2]` for a segment of it; `x_between` with `y_between`
/// is a box.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Selector {
    #[serde(default)]
    pub x: Option<f64>,
    #[serde(default)]
    pub y: Option<f64>,
    #[serde(default)]
    pub x_between: Option<[f64; 2]>,
    #[serde(default)]
    pub y_between: Option<[f64; 2]>,
    /// With `radius`: on the circle of that radius about `center`.
    #[serde(default)]
    pub center: Option<[f64; 2]>,
    #[serde(default)]
    pub radius: Option<f64>,
    /// On the straight segment between these two points: a side at any
    /// angle.
    #[serde(default)]
    pub segment: Option<[[f64; 2]; 2]>,
}

impl Selector {
    /// The point `(x, y)` when the selector is one (both coordinates given,
    /// nothing else).
    pub fn point(&self) -> Option<[f64; 2]> {
        match *self {
            Selector {
                x: Some(x),
                y: Some(y),
                x_between: None,
                y_between: None,
                center: None,
                radius: None,
                segment: None,
            } => Some([x, y]),
            _ => None,
        }
    }

    /// Whether `p` lies on the selector's lines (`x`, `y`, the circle, the
    /// segment's line extended past its ends) to within `tol`, whatever
    /// its ranges.
    pub fn on_lines(&self, p: [f64; 2], tol: f64) -> bool {
        let on = |v: Option<f64>, c: f64| v.is_none_or(|v| (c - v).abs() <= tol);
        let on_circle = match (self.center, self.radius) {
            (Some(c), Some(r)) => ((p[0] - c[0]).hypot(p[1] - c[1]) - r).abs() <= tol,
            _ => true,
        };
        let on_line = self.segment.is_none_or(|[a, b]| {
            let (d, r) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
            (r[0] * d[1] - r[1] * d[0]).abs() / d[0].hypot(d[1]) <= tol
        });
        on(self.x, p[0]) && on(self.y, p[1]) && on_circle && on_line
    }

    /// Whether `p` lies within the selector's ranges (`x_between`,
    /// `y_between`, and between the segment's ends along it) to within
    /// `tol`, wherever its lines are.
    pub fn within_ranges(&self, p: [f64; 2], tol: f64) -> bool {
        let within = |r: Option<[f64; 2]>, c: f64| {
            r.is_none_or(|[a, b]| c >= a.min(b) - tol && c <= a.max(b) + tol)
        };
        let along = self.segment.is_none_or(|[a, b]| {
            let (d, r) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
            let length = d[0].hypot(d[1]);
            let s = (r[0] * d[0] + r[1] * d[1]) / length;
            s >= -tol && s <= length + tol
        });
        within(self.x_between, p[0]) && within(self.y_between, p[1]) && along
    }

    /// Whether the selector has ranges, so that a stretch it picks can end
    /// inside a segment of the boundary curve.
    pub fn has_ranges(&self) -> bool {
        self.x_between.is_some() || self.y_between.is_some() || self.segment.is_some()
    }

    /// Whether `p` is selected; `tol` is the distance that counts as "on" a
    /// line or inside a range.
    pub fn contains(&self, p: [f64; 2], tol: f64) -> bool {
        let on = |v: Option<f64>, c: f64| v.is_none_or(|v| (c - v).abs() <= tol);
        let within = |r: Option<[f64; 2]>, c: f64| {
            r.is_none_or(|[a, b]| c >= a.min(b) - tol && c <= a.max(b) + tol)
        };
        let on_circle = match (self.center, self.radius) {
            (Some(c), Some(r)) => {
                (((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt() - r).abs() <= tol
            }
            _ => true,
        };
        let on_segment = self.segment.is_none_or(|[a, b]| {
            let (d, r) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
            let t = ((r[0] * d[0] + r[1] * d[1]) / (d[0] * d[0] + d[1] * d[1])).clamp(0.0, 1.0);
            (r[0] - t * d[0]).hypot(r[1] - t * d[1]) <= tol
        });
        on(self.x, p[0])
            && on(self.y, p[1])
            && within(self.x_between, p[0])
            && within(self.y_between, p[1])
            && on_circle
            && on_segment
    }
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

/// Whether `p` lies inside the closed ring of vertices (either
/// orientation): the even-odd crossing test.
pub fn inside_ring(ring: &[[f64; 2]], p: [f64; 2]) -> bool {
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

/// The first pair of edges `(i, j)` of a closed ring that cross or touch
/// without being neighbours (edge `k` runs from vertex `k` to `k + 1`), or
/// `None` for a simple ring. Quadratic in the number of vertices.
pub fn self_crossing(ring: &[[f64; 2]]) -> Option<(usize, usize)> {
    let n = ring.len();
    let edge = |k: usize| (ring[k], ring[(k + 1) % n]);
    for i in 0..n {
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue; // neighbours through vertex 0
            }
            let ((a, b), (c, d)) = (edge(i), edge(j));
            if segments_meet(a, b, c, d) {
                return Some((i, j));
            }
        }
    }
    None
}

/// Whether segments `ab` and `cd` share a point.
fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let orient = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        let v = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
        (v > 0.0) as i8 - (v < 0.0) as i8
    };
    let within = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        (0..2).all(|k| r[k] >= p[k].min(q[k]) && r[k] <= p[k].max(q[k]))
    };
    let (o1, o2, o3, o4) = (
        orient(a, b, c),
        orient(a, b, d),
        orient(c, d, a),
        orient(c, d, b),
    );
    (o1 != o2 && o3 != o4)
        || (o1 == 0 && within(a, b, c))
        || (o2 == 0 && within(a, b, d))
        || (o3 == 0 && within(c, d, a))
        || (o4 == 0 && within(c, d, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inside_ring_tells_inside_from_outside_either_way_round() {
        let ccw = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(inside_ring(&ccw, [0.5, 0.5]));
        assert!(!inside_ring(&ccw, [1.5, 0.5]));
        let cw: Vec<[f64; 2]> = ccw.iter().rev().copied().collect();
        assert!(inside_ring(&cw, [0.5, 0.5]));
        assert!(!inside_ring(&cw, [-0.5, 0.5]));
    }

    #[test]
    fn self_crossings_are_found_and_simple_rings_pass() {
        // A bow tie: edges 0 and 2 cross.
        let bow = [[0.0, 0.0], [4.0, 2.0], [4.0, 0.0], [0.0, 1.0]];
        assert_eq!(self_crossing(&bow), Some((0, 2)));
        let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert_eq!(self_crossing(&square), None);
        let triangle = [[0.0, 0.0], [1e-12, 0.0], [0.0, 1e6]];
        assert_eq!(self_crossing(&triangle), None);
        // A vertex touching a non-neighbouring edge.
        let pinched = [
            [0.0, 0.0],
            [2.0, 0.0],
            [1.0, 1.0],
            [2.0, 2.0],
            [0.0, 2.0],
            [1.0, 0.0],
        ];
        assert!(self_crossing(&pinched).is_some());
    }
}
