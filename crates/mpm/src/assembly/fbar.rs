//! F-bar against volumetric locking (Coombs, Charlton, Cortis & Augarde
//! 2018, "Overcoming volumetric locking in material point methods", CMAME
//! 333; de Souza Neto et al. 1996 for finite elements): each point's
//! incremental deformation gradient `dF` is replaced by
//! `dF_bar = alpha dF`, `alpha = (dJ_bar / dJ)^(1/D)` in `D` dimensions
//! (plane strain: `D = 2`, `dF_zz = 1` kept), where `dJ_bar`
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
//! The stress is the derivative of the step's incremental potential in
//! the points' `dF_bar` (the variational F-bar, the finite-strain mean
//! dilatation of Nagtegaal, Parks & Rice 1974 and Simo, Taylor & Pister
//! 1985): the virtual work of point `p` is `V0_p P^ : d(dF_bar_p)`, with
//! `P^` the model's stress at `dF_bar`. Split by the mean Cauchy stress
//! `sigma_m` over the `D` components (in plane strain the in-plane mean;
//! tension positive), each point's deviator works
//! against its own deformation and the cell's mean pressure against its
//! own volume change:
//!
//! ```text
//! P_p  = J_start [dJ_bar dev(sigma_p) + dJ_p Pi] dF_p^-T = P~_p + Pi J_start dJ_p dF_p^-T,
//! Pi   = sum_q w_q sigma_m,q,      w_q = V_q / sum V
//! ```
//!
//! (with `Pi + c_p` for `Pi` once the points carry their pressures across
//! the grid's reset, [`FbarCells::carrying`]) where `dev` takes off
//! `sigma_m` and `P~ = alpha P^ - alpha (P^ : dF) / D
//! dF^-T`. The tangent is the force's derivative: a local part by the
//! point's own `d(dF)` (through `P^`'s tangent `A^`, `alpha` and `dF^-T`),
//! and two couplings with every point of the cell, by `dJ_bar` (in `P~`,
//! `sigma_m` and so `Pi`) and by the other points' `sigma_m` (in `Pi`).
//! Where the model's tangent is symmetric (elastic, associated flow) so is
//! this one, a potential's second derivative.
//!
//! Why this form, and not the one that pairs each point's whole stress
//! with its own volume change (indefinite with dilation): docs/guide.md,
//! Material models. F-bar does not relieve the locking of dilatant flow,
//! which binds each point's shear too: [`super::cell_mean`] does.
//!
//! The small-strain model takes F-bar's linearisation, B-bar:
//! `g_bar = g + (b - a) / D I` with `a = tr g` and `b` its cell average
//! ([`FbarCells::adjust_small_strain`]), its stress on the point's own
//! strain. F-bar's `alpha dF` would make that model nonlinear, with
//! second-order terms scaled by the bulk modulus: near incompressibility
//! those outgrow the shear response at strains of `mu / K`, and Newton did
//! not converge on Cook's membrane.
//!
//! The couplings join each point with every point of its cell; in the
//! stiffness they are, per cell, two outer products of nodal vectors
//! ([`FbarCells::add_to`]), so they cost one dense block per cell.
//!
//! One code for both dimensions: in 3D the cells have eight corners and the
//! sums three terms. In plane strain every expression is the one it was
//! before the code was made generic (`D as f64` is 2 exactly, sums start
//! from their first term, the roots and cofactors are chosen by `D`), so
//! the 2D answers did not change by a bit (`scripts/compare_builds.sh`).

use nalgebra::SMatrix;
use rayon::prelude::*;

use super::Pattern;
use crate::configuration::Configuration;
use crate::grid::{Connectivity, increment, lattice_key};
use crate::material::Material;
use crate::parallel;
use crate::particles::admissible::{self, InadmissiblePoint};
use crate::particles::{Dim, MaterialPoints, Space, TangentMatrix};

type Tensor<const D: usize> = SMatrix<f64, D, D>;
type Tangent<const D: usize> = <Dim<D> as Space<D>>::Tangent;
type Response<const D: usize> = <Dim<D> as Space<D>>::Response;

/// The averaging cells of a step: which points each holds, and their
/// weights.
pub struct FbarCells<const D: usize = 2> {
    /// Points of each cell, cell by cell (`start[c]..start[c + 1]`).
    points: Vec<u32>,
    start: Vec<usize>,
    /// Per point, its weight in its cell (`V_q / sum V`).
    weight: Vec<f64>,
    /// Per point, its cell.
    cell_of: Vec<u32>,
    /// Active nodes of each cell's points (sorted, deduplicated).
    nodes: Vec<Vec<u32>>,
    /// Per point, the pressure it carries beside its cell's mean (`c_p`,
    /// see [`FbarCells::carrying`]); zero until it is given.
    offset: Vec<f64>,
}

/// What the trial state's responses and the coupling terms of the tangent
/// need from the trial state.
pub struct FbarTrial<const D: usize = 2> {
    /// Per cell, `dJ_bar - 1` ([`FbarCells::averages`]).
    pub averages: Vec<f64>,
    /// Per cell, its mean pressure term `Pi` (the volume-weighted mean of
    /// the points' mean Cauchy stress), which every point's own volume
    /// change works against.
    pub means: Vec<f64>,
    /// Per cell, the mean of the points' `d sigma_m / d dJ_bar`.
    mean_rates: Vec<f64>,
    /// Per point, its share of the coupling terms.
    parts: Vec<FbarPart<D>>,
}

impl<const D: usize> FbarCells<D>
where
    Dim<D>: Space<D>,
{
    pub fn new(start: &Configuration<D>) -> Self {
        let Configuration {
            grid, conn, points, ..
        } = *start;
        let n = points.len();
        // Keyed by cell and material: points of different materials in one
        // cell average apart (a small-strain and a finite-strain model
        // measure their volume change differently, and an interface is not
        // to be smeared). The lattice key orders cells as their
        // coordinates do, the first axis first.
        let mut keyed: Vec<((u64, u32), u32)> = (0..n)
            .map(|p| {
                let cell = lattice_key(grid.cell_of(points.position[p]));
                ((cell, points.material[p]), p as u32)
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
            offset: vec![0.0; n],
        }
    }

    /// The cells with each point's pressure carried across the grid's
    /// reset: `carried[p]` is how far the mean pressure point `p` worked
    /// with at the end of the last step stood from its own model's
    /// ([`FbarCells::carried`]; empty before the first, when every point
    /// takes its cell's mean). A point that changes cell, or whose
    /// cellmates do, would otherwise take its new cell's mean at once, and
    /// that jump in its pressure is force out of balance at the step's
    /// start whatever the step's size (measured: docs/guide.md, Material
    /// models). So each point keeps the constant `c_p = carried_p +
    /// sigma_m,p - Pi_start` beside its cell's mean `Pi` for the step, a
    /// pressure on its own volume change (a term of the step's potential,
    /// linear in `dJ_p`: the tangent stays symmetric), and the pressure's
    /// increment is the cell's. `sigma_m,p` and `Pi_start` are its own and
    /// its cell's at `u = 0` as the trial makes them ([`FbarPart`]'s
    /// `sigma_m` on `J_start`). The point starts with `carried_p +
    /// sigma_m,p`: where its model answers as it ended, the pressure it
    /// ended with (the departure was taken on its own volume,
    /// [`FbarPart`]'s `own_sigma_m`); where the model was weakened (a
    /// strength-reduction trial), that less what its own pressure lost,
    /// as the cell mean's stresses ([`super::cell_mean::CellMean::carrying`]).
    pub fn carrying(mut self, start: &Configuration<D>, carried: &[f64]) -> Self {
        let mp = start.points;
        if carried.len() != mp.len() {
            return self;
        }
        let zero = vec![0.0; start.conn.n_dofs()];
        let averages = vec![0.0; self.cells()];
        let sigma_m: Vec<f64> = (0..mp.len())
            .into_par_iter()
            .with_min_len(parallel::BOOKKEEPING)
            .map(|p| {
                point_response(&self, (&averages, None), start.conn, mp, &zero, p)
                    .map_or(f64::NAN, |(_, part)| part.sigma_m)
            })
            .collect();
        let means = self.averages(&sigma_m);
        for p in 0..mp.len() {
            let alone = self.members(self.cell_of[p] as usize).len() == 1;
            let offset = carried[p] + sigma_m[p] - self.of(&means, p);
            self.offset[p] = if alone || !offset.is_finite() {
                0.0
            } else {
                offset
            };
        }
        self
    }

    /// How far the mean pressure each point works with at `trial` (its
    /// cell's `Pi` and its `c_p`) stands from its own model's, on its own
    /// volume, for [`FbarCells::carrying`] in the next step (zero for a
    /// point alone in its cell, and for the small-strain model, whose
    /// B-bar carries no pressure term).
    pub fn carried(&self, trial: &FbarTrial<D>) -> Vec<f64> {
        (0..self.cell_of.len())
            .map(|p| self.of(&trial.means, p) + self.offset[p] - trial.parts[p].own_sigma_m)
            .collect()
    }

    /// The node groups the coupling term joins (for the stiffness pattern).
    pub fn coupling_groups(&self) -> Vec<Vec<u32>> {
        self.nodes.clone()
    }

    pub(super) fn cells(&self) -> usize {
        self.start.len() - 1
    }

    pub(super) fn members(&self, c: usize) -> &[u32] {
        &self.points[self.start[c]..self.start[c + 1]]
    }

    /// Point `p`'s cell and its weight in it.
    pub(super) fn place(&self, p: usize) -> (usize, f64) {
        (self.cell_of[p] as usize, self.weight[p])
    }

    /// The active nodes of cell `c`'s points.
    pub(super) fn nodes(&self, c: usize) -> &[u32] {
        &self.nodes[c]
    }

    /// Each cell's volume-weighted mean of a per-point value (of `dJ - 1`
    /// for `dJ_bar - 1`, the weights adding up to one; of `sigma_m` for
    /// `Pi`).
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

    /// Turns the model's response `P^`, `A^` to `dF_bar = alpha dF` into
    /// the point's local stress `P~ = dJ_bar dev(sigma) dF^-T` and its local
    /// tangent, and returns the point's part in its cell's terms (see the
    /// module docs). With the point's `mean` pressure known (its cell's
    /// `Pi` and the `c_p` it carries), the stress and the tangent are
    /// completed with `(Pi + c_p) J dF^-T` and its derivative at fixed
    /// `Pi`.
    pub fn adjust(
        &self,
        p: usize,
        response: &mut Response<D>,
        (df, j_start): (&Tensor<D>, f64),
        (dj, dj_bar): (f64, f64),
        mean: Option<f64>,
    ) -> FbarPart<D> {
        if self.members(self.cell_of[p] as usize).len() == 1 {
            // Alone in its cell: dJ_bar = dJ, and F-bar is the identity.
            return FbarPart::default();
        }
        let n = D as f64;
        let (a, jb) = (root::<D>(dj_bar / dj), dj_bar);
        let (stress, tangent) = <Dim<D> as Space<D>>::stress_and_tangent(response);
        let (k, pk) = (*tangent, *stress);
        // dF^-T = cof(dF) / dJ, with the dJ > 0 the caller checked.
        let c = cofactor(df) / dj;
        let k_df = contract_right::<D>(&k, df);
        let df_k = contract_left::<D>(df, &k);
        let s = df.component_mul(&k_df).sum();
        let t = pk.component_mul(df).sum();
        // Rates by the point's own d(dF) (D x D rows, or D^2 x D^2) and by
        // d(dJ_bar) (the `_bar` ones).
        let alpha_own = c * (-a / n);
        let alpha_bar = a / (n * jb);
        let t_own = df_k * a + pk - c * (a * s / n);
        let t_bar = a * s / (n * jb);
        let at_own = alpha_own * t + t_own * a;
        let at_bar = alpha_bar * t + a * t_bar;
        let dc = inverse_transpose_rate::<D>(&c);
        let p_own = outer::<D>(&pk, &alpha_own) + (k * a - outer::<D>(&k_df, &c) * (a / n)) * a
            - outer::<D>(&c, &at_own) * (1.0 / n)
            - dc * (a * t / n);
        let p_bar = pk * alpha_bar + k_df * (a * a / (n * jb)) - c * (at_bar / n);
        let jc = c * (j_start * dj);
        *stress = pk * a - c * (a * t / n);
        *tangent = p_own;
        if let Some(pi) = mean {
            *stress += jc * pi;
            *tangent += (outer::<D>(&jc, &c) + dc * (j_start * dj)) * pi;
        }
        let scale = n * jb * j_start;
        FbarPart {
            sigma_m: a * t / scale,
            own_sigma_m: a * t / (n * dj * j_start),
            mean_rate: at_bar / scale - a * t / (scale * jb),
            mean_own: at_own * (self.weight[p] / scale),
            by_bar: p_bar,
            pressure: jc,
            volume: c * (self.weight[p] * dj),
        }
    }

    /// The small-strain model's F-bar, B-bar: `g_bar = g + (b - a) / D I`
    /// with `a = tr g` and `b` its cell average, so the stress is linear in
    /// the increments and its tangent is `A^ - B (x) I` locally plus
    /// `B (x) sum_q w_q I : d(g_q)`, `B = A^ : I / D`. Returns the point's
    /// share of the coupling as [`FbarCells::adjust`] does.
    pub fn adjust_small_strain(&self, p: usize, response: &mut Response<D>) -> FbarPart<D> {
        if self.members(self.cell_of[p] as usize).len() == 1 {
            return FbarPart::default();
        }
        let (_, tangent) = <Dim<D> as Space<D>>::stress_and_tangent(response);
        let a = *tangent;
        let b = Tensor::<D>::from_fn(|i, ii| {
            let mut sum = a[(D * i + ii, 0)];
            for k in 1..D {
                sum += a[(D * i + ii, (D + 1) * k)];
            }
            sum * (1.0 / D as f64)
        });
        let identity = Tensor::<D>::identity();
        *tangent =
            Tangent::<D>::from_fn(|r, c| a[(r, c)] - b[(r / D, r % D)] * identity[(c / D, c % D)]);
        FbarPart {
            by_bar: b,
            volume: identity * self.weight[p],
            ..FbarPart::default()
        }
    }

    /// Adds the couplings' stiffness to tangent values in `pattern`'s
    /// layout (which must hold [`FbarCells::coupling_groups`]): per cell,
    /// `x (x) y + x2 (x) z` with, summed over the cell's points,
    /// `x_a = V0_p (dP~_p / d dJ_bar + J_start dJ_p dF_p^-T dPi / d dJ_bar) g_pa`,
    /// `y_b = w_q dJ_q dF_q^-T g_qb` (`d dJ_bar`), `x2_a = V0_p J_start dJ_p
    /// dF_p^-T g_pa` and `z_b = w_q (d sigma_m,q / d(dF_q)) g_qb` (`d Pi` by
    /// the points' own deformation).
    pub fn add_to(
        &self,
        conn: &Connectivity<D>,
        points: &MaterialPoints<D>,
        trial: &FbarTrial<D>,
        pattern: &Pattern,
        values: &mut [f64],
    ) {
        let blocks: Vec<CellBlock<D>> = (0..self.cells())
            .into_par_iter()
            .filter(|&c| self.members(c).len() > 1)
            .map(|c| {
                let nodes = &self.nodes[c];
                let index = |n: u32| nodes.binary_search(&n).expect("a node of the cell");
                let mut x = vec![[0.0; D]; nodes.len()];
                let mut y = vec![[0.0; D]; nodes.len()];
                let mut x2 = vec![[0.0; D]; nodes.len()];
                let mut z = vec![[0.0; D]; nodes.len()];
                let rate = trial.mean_rates[c];
                let row = |m: &Tensor<D>, grad: [f64; D], i: usize| {
                    let mut sum = m[(i, 0)] * grad[0];
                    for k in 1..D {
                        sum += m[(i, k)] * grad[k];
                    }
                    sum
                };
                for &p in self.members(c) {
                    let p = p as usize;
                    let part = &trial.parts[p];
                    let by_bar = part.by_bar + part.pressure * rate;
                    let v0 = points.volume0[p];
                    for l in conn.point_links(p) {
                        let k = index(l.node);
                        for i in 0..D {
                            x[k][i] += v0 * row(&by_bar, l.grad, i);
                            y[k][i] += row(&part.volume, l.grad, i);
                            x2[k][i] += v0 * row(&part.pressure, l.grad, i);
                            z[k][i] += row(&part.mean_own, l.grad, i);
                        }
                    }
                }
                (c, [x, x2], [y, z])
            })
            .collect();
        for (c, xs, ys) in blocks {
            let nodes = &self.nodes[c];
            for (kb, &nb) in nodes.iter().enumerate() {
                for (ka, &na) in nodes.iter().enumerate() {
                    let (base, stride) = pattern.block(na, nb);
                    for (x, y) in xs.iter().zip(&ys) {
                        for i in 0..D {
                            for j in 0..D {
                                values[base + i + j * stride] += x[ka][i] * y[kb][j];
                            }
                        }
                    }
                }
            }
        }
    }
}

/// A cell's coupling block: the cell, and the two nodal vectors of each of
/// its two outer products (one entry per node of
/// [`FbarCells::coupling_groups`]' group, `D` components).
type CellBlock<const D: usize> = (usize, [Vec<[f64; D]>; 2], [Vec<[f64; D]>; 2]);

impl<const D: usize> FbarTrial<D>
where
    Dim<D>: Space<D>,
{
    /// The trial's cell terms from its `averages` and the points' `parts`.
    pub fn new(fbar: &FbarCells<D>, averages: Vec<f64>, parts: Vec<FbarPart<D>>) -> Self {
        // Pi = sum_p w_p sigma_m,p, and its rate by dJ_bar likewise.
        let means = fbar.averages(&parts.iter().map(|q| q.sigma_m).collect::<Vec<_>>());
        let mean_rates = fbar.averages(&parts.iter().map(|q| q.mean_rate).collect::<Vec<_>>());
        Self {
            averages,
            means,
            mean_rates,
            parts,
        }
    }

    /// Point `p`'s stress: its local `P~` completed by its pressure term
    /// `(Pi + c_p) J dF^-T`, its cell's mean and the pressure it carries
    /// ([`FbarCells::carrying`]) (none for the small-strain model, whose
    /// own volume change pairs with its whole stress).
    pub fn stress(&self, fbar: &FbarCells<D>, p: usize, local: &Tensor<D>) -> Tensor<D> {
        local + self.parts[p].pressure * (fbar.of(&self.means, p) + fbar.offset[p])
    }

    /// Bytes held on the heap.
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.averages.as_slice())
            + size_of_val(self.means.as_slice())
            + size_of_val(self.mean_rates.as_slice())
            + size_of_val(self.parts.as_slice())
    }
}

/// A point's part in its cell's terms. Rates are by the point's own
/// `d(dF)` (`_own`, as `D x D` rows) or by `d(dJ_bar)`.
#[derive(Debug, Clone, Copy)]
pub struct FbarPart<const D: usize = 2> {
    /// Its mean Cauchy stress `sigma_m` (in plane strain, in-plane).
    sigma_m: f64,
    /// The same Kirchhoff stress on the point's own volume, `J_start dJ`
    /// rather than `J_start dJ_bar`: what its model answers with at the
    /// next step's start, on the volume the step leaves it.
    own_sigma_m: f64,
    /// `d sigma_m / d dJ_bar`.
    mean_rate: f64,
    /// `w_p d sigma_m / d(dF)`.
    mean_own: Tensor<D>,
    /// `d P~ / d dJ_bar` (small-strain: `B`).
    by_bar: Tensor<D>,
    /// `J dF^-T`, what the cell's pressure term multiplies in its stress.
    pressure: Tensor<D>,
    /// `w_p dJ dF^-T`: `d dJ_bar / d(dF_p)`.
    volume: Tensor<D>,
}

impl<const D: usize> Default for FbarPart<D> {
    fn default() -> Self {
        Self {
            sigma_m: 0.0,
            own_sigma_m: 0.0,
            mean_rate: 0.0,
            mean_own: Tensor::zeros(),
            by_bar: Tensor::zeros(),
            pressure: Tensor::zeros(),
            volume: Tensor::zeros(),
        }
    }
}

/// `x^(1/D)`: F-bar's `alpha` from `dJ_bar / dJ`.
fn root<const D: usize>(x: f64) -> f64 {
    if D == 2 { x.sqrt() } else { x.cbrt() }
}

/// `1 + alpha + ... + alpha^(D-1)`, which turns `alpha^D - 1` into
/// `alpha - 1`.
fn powers_below<const D: usize>(alpha: f64) -> f64 {
    if D == 2 {
        alpha + 1.0
    } else {
        alpha * alpha + alpha + 1.0
    }
}

/// The cofactor matrix of `m` (`det(m) m^-T`).
fn cofactor<const D: usize>(m: &Tensor<D>) -> Tensor<D> {
    Tensor::<D>::from_fn(|i, j| {
        if D == 2 {
            let sign = if i == j { 1.0 } else { -1.0 };
            sign * m[(1 - i, 1 - j)]
        } else {
            let (i1, i2, j1, j2) = ((i + 1) % 3, (i + 2) % 3, (j + 1) % 3, (j + 2) % 3);
            m[(i1, j1)] * m[(i2, j2)] - m[(i1, j2)] * m[(i2, j1)]
        }
    })
}

/// `dJ - 1 - tr g` for `dJ = det(I + g)`: `det g` in 2D, the second
/// invariant and `det g` in 3D.
pub(super) fn higher_invariants<const D: usize>(g: &Tensor<D>) -> f64
where
    Dim<D>: Space<D>,
{
    let det = <Dim<D> as Space<D>>::determinant(g);
    if D == 2 {
        det
    } else {
        let minor = |a: usize, b: usize| g[(a, a)] * g[(b, b)] - g[(a, b)] * g[(b, a)];
        minor(0, 1) + minor(0, 2) + minor(1, 2) + det
    }
}

/// `(m : x)_r = sum_c m_rc x_c` over the flattened `x`.
fn contract_right<const D: usize>(m: &Tangent<D>, x: &Tensor<D>) -> Tensor<D>
where
    Dim<D>: Space<D>,
{
    Tensor::<D>::from_fn(|i, ii| {
        (0..D * D)
            .map(|col| m[(D * i + ii, col)] * x[(col / D, col % D)])
            .sum()
    })
}

/// `(x : m)_c = sum_r x_r m_rc`.
fn contract_left<const D: usize>(x: &Tensor<D>, m: &Tangent<D>) -> Tensor<D>
where
    Dim<D>: Space<D>,
{
    Tensor::<D>::from_fn(|j, jj| {
        (0..D * D)
            .map(|r| x[(r / D, r % D)] * m[(r, D * j + jj)])
            .sum()
    })
}

/// `x (x) y` on flattened tensors.
fn outer<const D: usize>(x: &Tensor<D>, y: &Tensor<D>) -> Tangent<D>
where
    Dim<D>: Space<D>,
{
    Tangent::<D>::from_fn(|r, col| x[(r / D, r % D)] * y[(col / D, col % D)])
}

/// The rate of `dF^-T` (`c`) by `d(dF)`: `d c = -c d(dF)^T c`.
fn inverse_transpose_rate<const D: usize>(c: &Tensor<D>) -> Tangent<D>
where
    Dim<D>: Space<D>,
{
    Tangent::<D>::from_fn(|r, col| {
        let ((i, j), (l, k)) = ((r / D, r % D), (col / D, col % D));
        -c[(i, k)] * c[(l, j)]
    })
}

/// Whether point `p` has the small-strain model, which F-bar averages by
/// its own volumetric strain.
fn small_strain<const D: usize>(mp: &MaterialPoints<D>, p: usize) -> bool
where
    Dim<D>: Space<D>,
{
    matches!(
        mp.materials[mp.material[p] as usize],
        Material::LinearElastic(_)
    )
}

/// Point `p`'s volume change for F-bar's average, from its displacement
/// gradient `g`: as `dJ - 1 = tr g + det g` (in 3D `tr g + I2(g) + det
/// g`), so the volumetric strains of small increments stay exact to
/// round-off, which matters where the bulk modulus is thousands of times
/// the shear modulus. The small-strain model averages its own volumetric
/// strain, `tr g`.
fn volume_growth<const D: usize>(mp: &MaterialPoints<D>, p: usize, g: &Tensor<D>) -> f64
where
    Dim<D>: Space<D>,
{
    g.trace()
        + if small_strain(mp, p) {
            0.0
        } else {
            higher_invariants(g)
        }
}

/// F-bar's first pass at `u`: every cell's average volume change (see
/// the module docs).
pub fn trial_averages<const D: usize>(
    fbar: &FbarCells<D>,
    conn: &Connectivity<D>,
    mp: &MaterialPoints<D>,
    u: &[f64],
) -> Vec<f64>
where
    Dim<D>: Space<D>,
{
    let growth: Vec<f64> = (0..mp.len())
        .into_par_iter()
        .with_min_len(parallel::BOOKKEEPING)
        .map(|p| volume_growth(mp, p, &increment(conn.point_links(p), u).1))
        .collect();
    fbar.averages(&growth)
}

/// Point `p`'s response to its `dF_bar` at `u`, given its cell's
/// `averages` (and, once the trial's point loop has made them, its
/// `means`), with its part in its cell's terms; or the point, if `u` or its
/// cell's average inverts it.
pub fn point_response<const D: usize>(
    fbar: &FbarCells<D>,
    (averages, means): (&[f64], Option<&[f64]>),
    conn: &Connectivity<D>,
    mp: &MaterialPoints<D>,
    u: &[f64],
    p: usize,
) -> Result<(Response<D>, FbarPart<D>), InadmissiblePoint>
where
    Dim<D>: Space<D>,
{
    let g = &increment(conn.point_links(p), u).1;
    let j_start = mp.jacobian(p);
    let (a, b) = (volume_growth(mp, p, g), fbar.of(averages, p));
    let (dj, dj_bar) = (1.0 + g.trace() + higher_invariants(g), 1.0 + b);
    admissible::check_volume(p, j_start, &[j_start * dj, j_start * dj_bar])?;
    let material = &mp.materials[mp.material[p] as usize];
    let respond = |grad_bar: &Tensor<D>| {
        <Dim<D> as Space<D>>::respond(material, &mp.history[p], grad_bar, j_start, true)
    };
    let n = D as f64;
    if small_strain(mp, p) {
        // B-bar, F-bar's linearisation: the volumetric strain replaced by
        // the cell's, g_bar = g + (b - a) / D I.
        let grad_bar = g + Tensor::<D>::identity() * ((b - a) / n);
        let response = respond(&grad_bar);
        let mut response = admissible::check_response(p, j_start * dj_bar, response)?;
        let part = fbar.adjust_small_strain(p, &mut response);
        return Ok((response, part));
    }
    let df = Tensor::<D>::identity() + g;
    let alpha = root::<D>(dj_bar / dj);
    // alpha dF - I, with alpha - 1 = (b - a) / (dJ (1 + alpha + ...)).
    let grad_bar =
        Tensor::<D>::identity() * ((b - a) / (dj * powers_below::<D>(alpha))) + g * alpha;
    let response = respond(&grad_bar);
    let mut response = admissible::check_response(p, j_start * dj_bar, response)?;
    let mean = means.map(|m| fbar.of(m, p) + fbar.offset[p]);
    let part = fbar.adjust(p, &mut response, (&df, j_start), (dj, dj_bar), mean);
    Ok((response, part))
}
