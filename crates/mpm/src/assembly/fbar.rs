//! F-bar against volumetric locking (Coombs, Charlton, Cortis & Augarde
//! 2018, "Overcoming volumetric locking in material point methods", CMAME
//! 333; de Souza Neto et al. 1996 for finite elements): each point's
//! incremental deformation gradient `dF` is replaced by
//! `dF_bar = alpha dF`, `alpha = (dJ_bar / dJ)^(1/2)` in 2D, where `dJ_bar`
//! is the volume change of the point's averaging cell: the mean of the
//! `dJ` of the points in it, weighted by their volumes at the start of the
//! step. The material sees `dF_bar`; the point's own volume still changes
//! by `dJ`.
//!
//! For Hencky, the history a point keeps (its elastic `b`) is the model's
//! at `dF_bar`, so its volume is the product of the cell averages of the
//! steps, while the point's own `J` (which sets its Cauchy stress and its
//! volume) is the product of its own `dJ`: the two part over many steps,
//! by as much as the points of a cell deform unlike each other.
//!
//! The averaging domain is the grid cell holding the point at the start of
//! the step, for either basis: with GIMP a point's domain may reach into
//! neighbouring cells, but its volume is counted once, where its centre is.
//! A cell at the boundary averages over the points it holds, however few;
//! points of different materials in one cell average separately.
//!
//! With the model's stress `P^(dF_bar)` and tangent `A^`, the stress that
//! pairs with the point's own `dF` is `P = P^ / alpha` (its Cauchy stress
//! is the model's, on the point's true volume), and the consistent tangent
//! is
//!
//! ```text
//! dP = [A^ - B (x) dF^-T] : d(dF)  +  (B / dJ_bar) sum_q w_q dJ_q dF_q^-T : d(dF_q),
//! B  = (A^ : dF - P) / 2,   w_q = V_q / sum V
//! ```
//!
//! The small-strain model takes F-bar's linearisation, B-bar:
//! `g_bar = g + (b - a) / 2 I` with `a = tr g` and `b` its cell average
//! ([`FbarCells::adjust_small_strain`]). F-bar's `alpha dF` would make that
//! model nonlinear, with second-order terms scaled by the bulk modulus:
//! near incompressibility those outgrow the shear response at strains of
//! `mu / K`, and Newton did not converge on Cook's membrane.
//!
//! The second term couples each point with every point of its cell; in the
//! stiffness it is, per cell, the outer product of two nodal vectors (the
//! sums over the cell's points of `V0_p g_pa . B_p / dJ_bar` and of
//! `w_q dJ_q dF_q^-T g_qb`), so it costs one dense block per cell.

use nalgebra::{Matrix2, Matrix4};
use rayon::prelude::*;

use super::Pattern;
use crate::configuration::Configuration;
use crate::grid::{Connectivity, increment};
use crate::material::{Material, Response};
use crate::parallel;
use crate::particles::MaterialPoints;
use crate::particles::admissible::{self, InadmissiblePoint};

/// The averaging cells of a step: which points each holds, and their
/// weights.
pub struct FbarCells {
    /// Points of each cell, cell by cell (`start[c]..start[c + 1]`).
    points: Vec<u32>,
    start: Vec<usize>,
    /// Per point, its weight in its cell (`V_q / sum V`).
    weight: Vec<f64>,
    /// Per point, its cell.
    cell_of: Vec<u32>,
    /// Active nodes of each cell's points (sorted, deduplicated).
    nodes: Vec<Vec<u32>>,
}

/// What the trial state's responses and the coupling term of the tangent
/// need from the trial state.
pub struct FbarTrial {
    /// Per cell, `dJ_bar - 1` ([`FbarCells::averages`]).
    pub averages: Vec<f64>,
    /// Per point, `B_p / dJ_bar`.
    b: Vec<Matrix2<f64>>,
    /// Per point, `w_q dJ_q dF_q^-T`.
    v: Vec<Matrix2<f64>>,
}

impl FbarCells {
    pub fn new(start: &Configuration) -> Self {
        let Configuration {
            grid, conn, points, ..
        } = *start;
        let n = points.len();
        // Keyed by cell and material: points of different materials in one
        // cell average apart (a small-strain and a finite-strain model
        // measure their volume change differently, and an interface is not
        // to be smeared).
        let mut keyed: Vec<((i64, i64, u32), u32)> = (0..n)
            .map(|p| {
                let [i, j] = grid.cell_of(points.position[p]);
                ((i, j, points.material[p]), p as u32)
            })
            .collect();
        keyed.sort_unstable();
        let mut cell_of = vec![0u32; n];
        let mut order = Vec::with_capacity(n);
        let mut start_of = vec![0usize];
        for (k, &(key, p)) in keyed.iter().enumerate() {
            if k > 0 && keyed[k - 1].0 != key {
                start_of.push(k);
            }
            cell_of[p as usize] = (start_of.len() - 1) as u32;
            order.push(p);
        }
        start_of.push(n);
        let mut weight = vec![0.0; n];
        let mut nodes = Vec::with_capacity(start_of.len() - 1);
        for c in 0..start_of.len() - 1 {
            let members = &order[start_of[c]..start_of[c + 1]];
            let volume = |p: u32| points.volume(p as usize);
            let total: f64 = members.iter().map(|&p| volume(p)).sum();
            let mut cell_nodes = Vec::new();
            for &p in members {
                weight[p as usize] = volume(p) / total;
                cell_nodes.extend(conn.point_links(p as usize).iter().map(|l| l.node));
            }
            cell_nodes.sort_unstable();
            cell_nodes.dedup();
            nodes.push(cell_nodes);
        }
        Self {
            points: order,
            start: start_of,
            weight,
            cell_of,
            nodes,
        }
    }

    /// The node groups the coupling term joins (for the stiffness pattern).
    pub fn coupling_groups(&self) -> Vec<Vec<u32>> {
        self.nodes.clone()
    }

    fn cells(&self) -> usize {
        self.start.len() - 1
    }

    fn members(&self, c: usize) -> &[u32] {
        &self.points[self.start[c]..self.start[c + 1]]
    }

    /// Each cell's volume-weighted mean of a per-point value (of `dJ - 1`,
    /// for `dJ_bar - 1`: the weights add up to one).
    pub fn averages(&self, dj: &[f64]) -> Vec<f64> {
        (0..self.cells())
            .map(|c| {
                self.members(c)
                    .iter()
                    .map(|&p| self.weight[p as usize] * dj[p as usize])
                    .sum()
            })
            .collect()
    }

    /// The average of point `p`'s cell.
    pub fn of(&self, averages: &[f64], p: usize) -> f64 {
        averages[self.cell_of[p] as usize]
    }

    /// Turns the model's response to `dF_bar = alpha dF` into the point's:
    /// `P = P^ / alpha` and the local part of the tangent. Returns the
    /// point's share of the coupling term.
    pub fn adjust(
        &self,
        p: usize,
        response: &mut Response,
        df: &Matrix2<f64>,
        dj: f64,
        dj_bar: f64,
    ) -> (Matrix2<f64>, Matrix2<f64>) {
        if self.members(self.cell_of[p] as usize).len() == 1 {
            // Alone in its cell: dJ_bar = dJ, and F-bar is the identity.
            return (Matrix2::zeros(), Matrix2::zeros());
        }
        let alpha = (dj_bar / dj).sqrt();
        let p_point = response.p / alpha;
        let a = &response.tangent;
        let a_df = Matrix2::from_fn(|i, ii| {
            (0..2)
                .flat_map(|j| (0..2).map(move |jj| (j, jj)))
                .map(|(j, jj)| a[(2 * i + ii, 2 * j + jj)] * df[(j, jj)])
                .sum()
        });
        let b = (a_df - p_point) * 0.5;
        // dF^-T = cof(dF) / dJ, with the dJ > 0 the caller checked.
        let df_inv_t = Matrix2::new(df[(1, 1)], -df[(1, 0)], -df[(0, 1)], df[(0, 0)]) / dj;
        let local =
            Matrix4::from_fn(|r, c| a[(r, c)] - b[(r / 2, r % 2)] * df_inv_t[(c / 2, c % 2)]);
        response.p = p_point;
        response.tangent = local;
        (b / dj_bar, df_inv_t * (self.weight[p] * dj))
    }

    /// The small-strain model's F-bar, B-bar: `g_bar = g + (b - a) / 2 I`
    /// with `a = tr g` and `b` its cell average, so the stress is linear in
    /// the increments and its tangent is `A^ - B (x) I` locally plus
    /// `B (x) sum_q w_q I : d(g_q)`, `B = A^ : I / 2`. Returns the point's
    /// share of the coupling as [`FbarCells::adjust`] does.
    pub fn adjust_small_strain(
        &self,
        p: usize,
        response: &mut Response,
    ) -> (Matrix2<f64>, Matrix2<f64>) {
        if self.members(self.cell_of[p] as usize).len() == 1 {
            return (Matrix2::zeros(), Matrix2::zeros());
        }
        let a = &response.tangent;
        let b = Matrix2::from_fn(|i, ii| 0.5 * (a[(2 * i + ii, 0)] + a[(2 * i + ii, 3)]));
        let identity = Matrix2::<f64>::identity();
        response.tangent =
            Matrix4::from_fn(|r, c| a[(r, c)] - b[(r / 2, r % 2)] * identity[(c / 2, c % 2)]);
        (b, identity * self.weight[p])
    }

    /// Adds the coupling term's stiffness to tangent values in `pattern`'s
    /// layout (which must hold [`FbarCells::coupling_groups`]).
    pub fn add_to(
        &self,
        conn: &Connectivity,
        points: &MaterialPoints,
        trial: &FbarTrial,
        pattern: &Pattern,
        values: &mut [f64],
    ) {
        let blocks: Vec<CellBlock> = (0..self.cells())
            .into_par_iter()
            .filter(|&c| self.members(c).len() > 1)
            .map(|c| {
                let nodes = &self.nodes[c];
                let index = |n: u32| nodes.binary_search(&n).expect("a node of the cell");
                let mut x = vec![[0.0; 2]; nodes.len()];
                let mut y = vec![[0.0; 2]; nodes.len()];
                for &p in self.members(c) {
                    let p = p as usize;
                    let (b, v) = (&trial.b[p], &trial.v[p]);
                    let v0 = points.volume0[p];
                    for l in conn.point_links(p) {
                        let k = index(l.node);
                        for i in 0..2 {
                            x[k][i] += v0 * (b[(i, 0)] * l.grad[0] + b[(i, 1)] * l.grad[1]);
                            y[k][i] += v[(i, 0)] * l.grad[0] + v[(i, 1)] * l.grad[1];
                        }
                    }
                }
                (c, x, y)
            })
            .collect();
        for (c, x, y) in blocks {
            let nodes = &self.nodes[c];
            for (kb, &nb) in nodes.iter().enumerate() {
                for (ka, &na) in nodes.iter().enumerate() {
                    let (base, stride) = pattern.block(na, nb);
                    for i in 0..2 {
                        for j in 0..2 {
                            values[base + i + j * stride] += x[ka][i] * y[kb][j];
                        }
                    }
                }
            }
        }
    }
}

/// A cell's coupling block: the cell, and its two nodal vectors (one entry
/// per node of [`FbarCells::coupling_groups`]' group, two components).
type CellBlock = (usize, Vec<[f64; 2]>, Vec<[f64; 2]>);

impl FbarTrial {
    pub fn new(averages: Vec<f64>, shares: Vec<(Matrix2<f64>, Matrix2<f64>)>) -> Self {
        let (b, v) = shares.into_iter().unzip();
        Self { averages, b, v }
    }

    /// Bytes held on the heap.
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.averages.as_slice())
            + size_of_val(self.b.as_slice())
            + size_of_val(self.v.as_slice())
    }
}
/// Whether point `p` has the small-strain model, which F-bar averages by
/// its own volumetric strain.
fn small_strain(mp: &MaterialPoints, p: usize) -> bool {
    matches!(
        mp.materials[mp.material[p] as usize],
        Material::LinearElastic(_)
    )
}

/// Point `p`'s volume change for F-bar's average, from its displacement
/// gradient `g`: as `dJ - 1 = tr g + det g`, so the volumetric strains of
/// small increments stay exact to round-off, which matters where the bulk
/// modulus is thousands of times the shear modulus. The small-strain model
/// averages its own volumetric strain, `tr g`.
fn volume_growth(mp: &MaterialPoints, p: usize, g: &Matrix2<f64>) -> f64 {
    g.trace()
        + if small_strain(mp, p) {
            0.0
        } else {
            g.determinant()
        }
}

/// F-bar's first pass at `u`: every cell's average volume change (see
/// the module docs).
pub fn trial_averages(
    fbar: &FbarCells,
    conn: &Connectivity,
    mp: &MaterialPoints,
    u: &[f64],
) -> Vec<f64> {
    let growth: Vec<f64> = (0..mp.len())
        .into_par_iter()
        .with_min_len(parallel::BOOKKEEPING)
        .map(|p| volume_growth(mp, p, &increment(conn.point_links(p), u).1))
        .collect();
    fbar.averages(&growth)
}

/// A point's share of F-bar's coupling term ([`FbarCells::adjust`]).
pub type FbarShare = (Matrix2<f64>, Matrix2<f64>);

/// Point `p`'s response to its `dF_bar` at `u`, given its cell's
/// `averages`, with its share of the coupling term; or the point, if `u`
/// or its cell's average inverts it.
pub fn point_response(
    fbar: &FbarCells,
    averages: &[f64],
    conn: &Connectivity,
    mp: &MaterialPoints,
    u: &[f64],
    p: usize,
) -> Result<(Response, FbarShare), InadmissiblePoint> {
    let g = &increment(conn.point_links(p), u).1;
    let j_start = mp.deformation[p].determinant();
    let (a, b) = (volume_growth(mp, p, g), fbar.of(averages, p));
    let (dj, dj_bar) = (1.0 + g.trace() + g.determinant(), 1.0 + b);
    admissible::check_volume(p, j_start, &[j_start * dj, j_start * dj_bar])?;
    let material = &mp.materials[mp.material[p] as usize];
    if small_strain(mp, p) {
        // B-bar, F-bar's linearisation: the volumetric strain replaced by
        // the cell's, g_bar = g + (b - a) / 2 I.
        let grad_bar = g + Matrix2::identity() * ((b - a) / 2.0);
        let response = material.respond(&mp.history[p], &grad_bar, j_start);
        let mut response = admissible::check_response(p, j_start * dj_bar, response)?;
        let share = fbar.adjust_small_strain(p, &mut response);
        return Ok((response, share));
    }
    let df = Matrix2::identity() + g;
    let alpha = (dj_bar / dj).sqrt();
    // alpha dF - I, with alpha - 1 = (b - a) / (dJ (alpha + 1)).
    let grad_bar = Matrix2::identity() * ((b - a) / (dj * (alpha + 1.0))) + g * alpha;
    let response = material.respond(&mp.history[p], &grad_bar, j_start);
    let mut response = admissible::check_response(p, j_start * dj_bar, response)?;
    let share = fbar.adjust(p, &mut response, &df, dj, dj_bar);
    Ok((response, share))
}
