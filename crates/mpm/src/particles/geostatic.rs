//! Initial stresses from the overburden, for a geostatic stage: each point
//! carries the weight of the material above it, vertically, and `K0` times
//! that horizontally and out of plane.
//!
//! The points are grouped into vertical columns by their `x` (to 1e-9 m):
//! a body seeded on a lattice, or bodies stacked on one lattice spacing,
//! makes exact columns. A point's share of its column's weight per unit
//! width is its mass over its width (its domain's, or `sqrt(V0)` for a cell
//! that is not an upright rectangle); it carries everything above it and
//! half of itself, so a uniform column of height `H` gives `sigma_v = -rho
//! g (H - y)` at every point.

use std::collections::HashMap;

use super::MaterialPoints;
use crate::material::Material;

/// `K0` of a material when the case gives none: `nu / (1 - nu)`, the
/// ratio of one-dimensional elastic compression.
pub fn poisson_k0(material: &Material) -> f64 {
    let e = material.elastic();
    e.lambda / (e.lambda + 2.0 * e.mu)
}

/// Puts every point in its overburden stress under gravity `g` (m/s^2,
/// downward positive), with `k0` (or each material's [`poisson_k0`]): its
/// history and its reported stress. The points do not move; what they
/// carried from an earlier stage's averaged stresses (F-bar's pressures,
/// the cell mean's stresses) is of the stresses replaced, and goes.
pub fn set_overburden_stresses(mp: &mut MaterialPoints, g: f64, k0: Option<f64>) {
    mp.fbar_pressure.clear();
    mp.cell_mean_stress.clear();
    let mut columns: HashMap<i64, Vec<usize>> = HashMap::new();
    for (p, x) in mp.position.iter().enumerate() {
        columns
            .entry((x[0] * 1e9).round() as i64)
            .or_default()
            .push(p);
    }
    let width = |p: usize| {
        let [a, b] = mp.domain[p].axes;
        if a[1] == 0.0 && b[0] == 0.0 {
            2.0 * a[0].abs()
        } else {
            mp.volume0[p].sqrt()
        }
    };
    let mut vertical = vec![0.0; mp.len()];
    for column in columns.values_mut() {
        column.sort_by(|&a, &b| mp.position[b][1].total_cmp(&mp.position[a][1]));
        let mut above = 0.0;
        for &p in column.iter() {
            let own = mp.mass[p] / width(p);
            vertical[p] = -g * (above + 0.5 * own);
            above += own;
        }
    }
    for p in 0..mp.len() {
        let j = mp.jacobian(p);
        let material = &mp.materials[mp.material[p] as usize];
        let k = k0.unwrap_or_else(|| poisson_k0(material));
        let sigma = [k * vertical[p], vertical[p], k * vertical[p]];
        let history = material.history_carrying(sigma);
        mp.stress[p] = material
            .respond_without_tangent(&history, &nalgebra::Matrix2::zeros(), j)
            .cauchy;
        mp.history[p] = history;
    }
}
