//! Triangles of a simple polygon with holes, by ear clipping: each hole is
//! first joined to the outer ring by a bridge to a vertex it can see, which
//! makes one simple ring (Eberly, "Triangulation by ear clipping", 2008).
//! Polygon bodies are filled by cutting these triangles into mapped patches
//! ([`crate::particles::seeding`]), so the points follow every side.

use crate::geometry::signed_area;

/// Counter-clockwise triangles covering `outer` minus `holes` (each given
/// either way round), as vertex triples: their areas add up to the
/// polygon's when the holes lie inside it and apart (validation checks
/// that sum). `None` when a hole has no edge of the ring to its right.
pub fn triangulate(outer: &[[f64; 2]], holes: &[Vec<[f64; 2]>]) -> Option<Vec<[[f64; 2]; 3]>> {
    let mut ring = oriented(outer, true);
    let mut holes: Vec<Vec<[f64; 2]>> = holes.iter().map(|h| oriented(h, false)).collect();
    // Bridge the holes in order of their rightmost vertex, rightmost first,
    // so that each bridge sees only the outer ring and the holes bridged.
    holes.sort_by(|a, b| rightmost(b).1[0].total_cmp(&rightmost(a).1[0]));
    for hole in &holes {
        ring = bridge(&ring, hole)?;
    }
    Some(clip_ears(ring))
}

fn oriented(v: &[[f64; 2]], counter_clockwise: bool) -> Vec<[f64; 2]> {
    let mut v = v.to_vec();
    if (signed_area(&v) > 0.0) != counter_clockwise {
        v.reverse();
    }
    v
}

fn rightmost(v: &[[f64; 2]]) -> (usize, [f64; 2]) {
    v.iter()
        .copied()
        .enumerate()
        .max_by(|a, b| a.1[0].total_cmp(&b.1[0]).then(b.1[1].total_cmp(&a.1[1])))
        .expect("a ring has vertices")
}

/// Twice the signed area of `(a, b, c)`.
fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Whether `p` is inside or on the counter-clockwise triangle `(a, b, c)`.
fn in_triangle(p: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0
}

/// The most vertices (holes' included) a polygon triangulated here may
/// have: ear clipping costs up to `n^2` times the reflex vertices.
pub const MAX_VERTICES: usize = 1000;

/// The ring with `hole` (clockwise) spliced in: from the hole's rightmost
/// vertex `m` a ray to +x meets the ring's edge nearest `m`; the bridge
/// goes to that edge's end with the larger x, or, if ring vertices lie in
/// the triangle that end makes with `m` and the hit point, to the one of
/// them at the smallest angle to the ray.
fn bridge(ring: &[[f64; 2]], hole: &[[f64; 2]]) -> Option<Vec<[f64; 2]>> {
    let (mi, m) = rightmost(hole);
    let n = ring.len();
    let mut best: Option<(f64, usize)> = None; // (x of the hit, edge start)
    for k in 0..n {
        let (a, b) = (ring[k], ring[(k + 1) % n]);
        if (a[1] > m[1]) == (b[1] > m[1]) {
            continue;
        }
        let x = a[0] + (m[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
        if x >= m[0] && best.is_none_or(|(bx, _)| x < bx) {
            best = Some((x, k));
        }
    }
    let (hit_x, k) = best?;
    let hit = [hit_x, m[1]];
    let pick = if ring[k][0] > ring[(k + 1) % n][0] {
        k
    } else {
        (k + 1) % n
    };
    let p = ring[pick];
    let (a, b, c) = if cross(m, hit, p) >= 0.0 {
        (m, hit, p)
    } else {
        (m, p, hit)
    };
    let angle = |v: [f64; 2]| (v[1] - m[1]).abs().atan2(v[0] - m[0]);
    let target = (0..n)
        .filter(|&j| {
            j != pick && ring[j] != m && in_triangle(ring[j], a, b, c) && is_reflex(ring, j)
        })
        .min_by(|&i, &j| {
            angle(ring[i])
                .total_cmp(&angle(ring[j]))
                .then(distance2(ring[i], m).total_cmp(&distance2(ring[j], m)))
        })
        .unwrap_or(pick);
    let mut out = Vec::with_capacity(n + hole.len() + 2);
    out.extend_from_slice(&ring[..=target]);
    for j in 0..=hole.len() {
        out.push(hole[(mi + j) % hole.len()]);
    }
    out.push(ring[target]);
    out.extend_from_slice(&ring[target + 1..]);
    Some(out)
}

fn distance2(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}

/// Whether vertex `j` of a counter-clockwise ring turns clockwise.
fn is_reflex(ring: &[[f64; 2]], j: usize) -> bool {
    let n = ring.len();
    cross(ring[(j + n - 1) % n], ring[j], ring[(j + 1) % n]) < 0.0
}

/// Ear clipping of a counter-clockwise ring (bridges allowed: a vertex may
/// appear twice). An ear is a convex vertex whose triangle holds no other
/// reflex vertex; of the ears, the one with the largest smallest angle is
/// cut first, which keeps slivers out where there is a choice.
fn clip_ears(mut ring: Vec<[f64; 2]>) -> Vec<[[f64; 2]; 3]> {
    let mut out = Vec::with_capacity(ring.len().saturating_sub(2));
    while ring.len() > 3 {
        let n = ring.len();
        let reflex: Vec<[f64; 2]> = (0..n)
            .filter(|&i| is_reflex(&ring, i))
            .map(|i| ring[i])
            .collect();
        let ear = (0..n)
            .filter(|&j| {
                let (a, b, c) = (ring[(j + n - 1) % n], ring[j], ring[(j + 1) % n]);
                cross(a, b, c) > 0.0
                    && reflex
                        .iter()
                        .all(|&v| v == a || v == b || v == c || !in_triangle(v, a, b, c))
            })
            .max_by(|&i, &j| {
                let q =
                    |j: usize| smallest_angle(ring[(j + n - 1) % n], ring[j], ring[(j + 1) % n]);
                q(i).total_cmp(&q(j))
            });
        // A ring with no ear is degenerate (collinear leftovers): drop the
        // flattest vertex.
        let j = ear.unwrap_or_else(|| {
            (0..n)
                .min_by(|&i, &j| {
                    let f =
                        |j: usize| cross(ring[(j + n - 1) % n], ring[j], ring[(j + 1) % n]).abs();
                    f(i).total_cmp(&f(j))
                })
                .expect("a ring of more than three vertices")
        });
        let (a, b, c) = (ring[(j + n - 1) % n], ring[j], ring[(j + 1) % n]);
        if ear.is_some() {
            out.push([a, b, c]);
        }
        ring.remove(j);
    }
    if ring.len() == 3 && cross(ring[0], ring[1], ring[2]) > 0.0 {
        out.push([ring[0], ring[1], ring[2]]);
    }
    out
}

/// The smallest angle of the triangle `(a, b, c)`, in radians.
fn smallest_angle(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let angle = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        let (u, v) = ([q[0] - p[0], q[1] - p[1]], [r[0] - p[0], r[1] - p[1]]);
        (u[0] * v[1] - u[1] * v[0])
            .abs()
            .atan2(u[0] * v[0] + u[1] * v[1])
    };
    angle(a, b, c).min(angle(b, c, a)).min(angle(c, a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(t: &[[f64; 2]; 3]) -> f64 {
        cross(t[0], t[1], t[2]) / 2.0
    }

    #[test]
    fn triangles_cover_a_polygon_with_holes_exactly() {
        let outer = vec![[0.0, 0.0], [3.0, 0.8], [2.5, 2.6], [1.2, 1.9], [0.4, 2.2]];
        let holes = vec![
            vec![[1.0, 0.6], [1.9, 0.9], [1.4, 1.4]],
            vec![[2.2, 1.2], [2.5, 1.2], [2.5, 1.5], [2.2, 1.5]],
        ];
        let tris = triangulate(&outer, &holes).unwrap();
        let total: f64 = tris.iter().map(area).sum();
        let exact =
            signed_area(&outer).abs() - holes.iter().map(|h| signed_area(h).abs()).sum::<f64>();
        assert!((total - exact).abs() < 1e-12, "{total} vs {exact}");
        assert!(tris.iter().all(|t| area(t) > 0.0));
        // 5 + 3 + 4 vertices, two bridges: 12 + 2 * 2 - 2 = 14 triangles.
        assert_eq!(tris.len(), 14);
        // No triangle's centroid falls in a hole or outside.
        for t in &tris {
            let c = [0, 1].map(|d| (t[0][d] + t[1][d] + t[2][d]) / 3.0);
            assert!(crate::geometry::inside_ring(&outer, c));
            assert!(holes.iter().all(|h| !crate::geometry::inside_ring(h, c)));
        }
    }

    #[test]
    fn a_square_gives_two_triangles_either_way_round() {
        let square = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let mut reversed = square.clone();
        reversed.reverse();
        for ring in [square, reversed] {
            let tris = triangulate(&ring, &[]).unwrap();
            assert_eq!(tris.len(), 2);
            assert!((tris.iter().map(area).sum::<f64>() - 1.0).abs() < 1e-15);
        }
    }
}
