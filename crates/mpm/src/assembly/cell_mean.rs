//! The cell-mean strain, against locking by incompressibility and by
//! dilatancy: every point of an averaging cell (F-bar's,
//! [`super::fbar`]) answers to the cell's mean displacement gradient
//! `g_bar = sum_q w_q g_q` (weights by volume at the step's start), from
//! its own history. A plastic soil's flow rule then binds one strain per
//! cell, not one per point: with dilation, `d eps_v = sin(psi) d gamma`
//! at each of a cell's four points is four constraints on about two
//! degrees of freedom, and F-bar, which averages only the volume change,
//! still asks each point's shear to be its cell's (de Borst & Groen
//! 1995 found B-bar of no help with dilation).
//!
//! The stress is the derivative of the step's incremental potential
//! `sum_p V0_p W_p(I + g_bar) + beta V0_c / 2 sum_p w_p |g_p - g_bar|^2`:
//! the second sum holds the modes whose cell means are zero (the
//! hourglass modes of one-point quadrature) by an elastic stiffness
//! `beta`, a fraction (`analysis.stabilisation.hourglass`, 1e-2) of the
//! material's `2 mu`, on each point's departure from its cell's mean
//! only. Point `q`'s stress, paired with its own gradient, is
//!
//! ```text
//! S_q = w_q / V0_q [T_c + beta V0_c (g_q - g_bar)],   T_c = sum_p V0_p P_p(g_bar),
//! ```
//!
//! (the departures sum to zero; `+ O_q` once the points carry their
//! stresses across the grid's reset, [`CellMean::carrying`]), and the
//! tangent is, per cell,
//! `G_bar^T (sum_p V0_p A_p - beta V0_c) G_bar` with `G_bar` the cell's
//! mean gradient operator, plus `beta V0_c w_q` on each point's own
//! gradient. It is symmetric where the models' are.
//!
//! A homogeneous deformation gives every point of a cell the same
//! gradient: the cell mean is each point's own and the stabilisation is
//! zero, so the patch tests hold as for the standard points. A point
//! alone in its cell is a standard point. What it measures on footings,
//! and what it loses in bending (the strain's variation within a cell):
//! docs/guide.md, Material models, and `mpm study bearing`.

use nalgebra::SMatrix;
use rayon::prelude::*;

use super::Pattern;
use super::fbar::{FbarCells, higher_invariants};
use crate::configuration::Configuration;
use crate::grid::{Connectivity, increment};
use crate::parallel;
use crate::particles::admissible::{self, InadmissiblePoint};
use crate::particles::{Dim, MaterialPoints, Space, TangentMatrix};

type Tensor<const D: usize> = SMatrix<f64, D, D>;
type Tangent<const D: usize> = <Dim<D> as Space<D>>::Tangent;
type Response<const D: usize> = <Dim<D> as Space<D>>::Response;

/// The averaging cells of a step, with each cell's `beta V0_c`.
pub struct CellMean<const D: usize = 2> {
    cells: FbarCells<D>,
    /// Per cell, `beta V0_c`.
    stiffness: Vec<f64>,
    /// Per point, the stress it carries beside its cell's mean (`O_q`, see
    /// [`CellMean::carrying`]); zero until it is given.
    offset: Vec<Tensor<D>>,
}

/// A trial state's cell terms.
pub struct CellTrial<const D: usize = 2> {
    /// Per point, its own displacement gradient `g_q`.
    grads: Vec<Tensor<D>>,
    /// Per cell, `g_bar`.
    means: Vec<Tensor<D>>,
    /// Per cell, `T_c`.
    stress: Vec<Tensor<D>>,
}

impl<const D: usize> CellTrial<D> {
    /// Bytes held on the heap.
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.grads.as_slice())
            + size_of_val(self.means.as_slice())
            + size_of_val(self.stress.as_slice())
    }
}

impl<const D: usize> CellMean<D>
where
    Dim<D>: Space<D>,
{
    /// The cells of the step starting at `start`, with `beta` the fraction
    /// `hourglass` of each cell's material's `2 mu`.
    pub fn new(start: &Configuration<D>, hourglass: f64) -> Self {
        let cells = FbarCells::new(start);
        let points = start.points;
        let fraction = hourglass;
        let stiffness = (0..cells.cells())
            .map(|c| {
                let members = cells.members(c);
                let p = members[0] as usize;
                let mu = points.materials[points.material[p] as usize].elastic().mu;
                let v0: f64 = members.iter().map(|&q| points.volume0[q as usize]).sum();
                fraction * 2.0 * mu * v0
            })
            .collect();
        let offset = vec![Tensor::zeros(); points.len()];
        Self {
            cells,
            stiffness,
            offset,
        }
    }

    /// The cells with each point's stress carried across the grid's reset:
    /// `carried[q]` is how far the stress point `q` worked with at the end
    /// of the last step stood from its own model's ([`CellMean::carried`];
    /// empty before the first, when every point takes its cell's mean). A
    /// point that changes cell, or whose cellmates do, would otherwise
    /// take its new cell's mean at once, and that jump is force out of
    /// balance at the step's start whatever the step's size: on a rough
    /// footing on heavy sand (h = B/8) the load fell by a fifth in the
    /// step where the points under the footing crossed a grid line, and
    /// rose again after it. So each point keeps for the step the constant
    /// `O_q = carried_q + P_q(0) - S_q(0)` beside its cell's mean, a stress
    /// on its own gradient (a term of the step's potential linear in
    /// `g_q`: the tangent is unchanged), and the stress's increment is the
    /// cell's, as F-bar's pressure ([`FbarCells::carrying`]). At `u = 0`
    /// the point works with `carried_q + P_q(0)`: where its model answers
    /// as it ended (`P_q(0)` its last stress), the stress it ended with;
    /// where the model changed (a strength-reduction trial weakens it),
    /// that less what its own stress lost. A point alone in its cell is a
    /// standard point and carries nothing.
    pub fn carrying(mut self, start: &Configuration<D>, carried: &[Tensor<D>]) -> Self {
        let mp = start.points;
        if carried.len() != mp.len() {
            return self;
        }
        let zero = vec![0.0; start.conn.n_dofs()];
        let Ok(trial) = self.trial(start.conn, mp, &zero) else {
            return self;
        };
        let offset = (0..mp.len())
            .into_par_iter()
            .with_min_len(parallel::POINT_RESPONSES)
            .map(|q| {
                if self.cells.members(self.cells.place(q).0).len() == 1 {
                    return Tensor::zeros();
                }
                let offset = self.response(&trial, mp, q, false).map(|own| {
                    carried[q] + Dim::<D>::stress_of(&own) - self.mean_stress(&trial, mp, q)
                });
                match offset {
                    Ok(o) if o.iter().all(|x| x.is_finite()) => o,
                    _ => Tensor::zeros(),
                }
            })
            .collect();
        self.offset = offset;
        self
    }

    /// How far the stress each point works with at `trial` (its cell's
    /// mean and its `O_q`, without the hourglass term, which holds a step's
    /// departures only) stands from its own model's stress `P_q(g_bar)`,
    /// pushed to the step's end by its cell's mean `dF`, for
    /// [`CellMean::carrying`] in the next step: where no point changes
    /// cell, the next step's offsets are those of this one, as moved.
    pub fn carried(&self, trial: &CellTrial<D>, mp: &MaterialPoints<D>) -> Vec<Tensor<D>> {
        (0..mp.len())
            .into_par_iter()
            .with_min_len(parallel::POINT_RESPONSES)
            .map(|q| {
                let df_bar = Tensor::<D>::identity() + trial.means[self.cells.place(q).0];
                let worked = self.mean_stress(trial, mp, q) + self.offset[q];
                let own = (self.response(trial, mp, q, false))
                    .map_or(worked, |r| Dim::<D>::stress_of(&r));
                (worked - own) * df_bar.transpose()
            })
            .collect()
    }

    /// Point `q`'s share of its cell's stress, `w_q / V0_q T_c`.
    fn mean_stress(&self, trial: &CellTrial<D>, mp: &MaterialPoints<D>, q: usize) -> Tensor<D> {
        let (c, w) = self.cells.place(q);
        trial.stress[c] * (w / mp.volume0[q])
    }

    /// The node groups the cell terms join (for the stiffness pattern).
    pub fn coupling_groups(&self) -> Vec<Vec<u32>> {
        self.cells.coupling_groups()
    }

    /// The trial's gradients and cell means at `u`, and every point's
    /// response to its cell's mean; or the first inadmissible point.
    pub fn trial(
        &self,
        conn: &Connectivity<D>,
        mp: &MaterialPoints<D>,
        u: &[f64],
    ) -> Result<CellTrial<D>, InadmissiblePoint> {
        let grads: Vec<Tensor<D>> = (0..mp.len())
            .into_par_iter()
            .with_min_len(parallel::BOOKKEEPING)
            .map(|p| increment(conn.point_links(p), u).1)
            .collect();
        let means: Vec<Tensor<D>> = (0..self.cells.cells())
            .map(|c| {
                self.cells
                    .members(c)
                    .iter()
                    .map(|&q| grads[q as usize] * self.cells.place(q as usize).1)
                    .sum()
            })
            .collect();
        let mut trial = CellTrial {
            grads,
            means,
            stress: Vec::new(),
        };
        let stresses: Vec<Tensor<D>> = (0..mp.len())
            .into_par_iter()
            .with_min_len(parallel::POINT_RESPONSES)
            .map(|p| {
                self.response(&trial, mp, p, false)
                    .map(|r| Dim::<D>::stress_of(&r) * mp.volume0[p])
            })
            .collect::<Result<_, _>>()?;
        trial.stress = (0..self.cells.cells())
            .map(|c| {
                self.cells
                    .members(c)
                    .iter()
                    .map(|&q| stresses[q as usize])
                    .sum()
            })
            .collect();
        Ok(trial)
    }

    /// Point `p`'s model response to its cell's mean gradient (its history
    /// and Cauchy stress are what it commits), or the point, if its own
    /// gradient or its cell's inverts it or the response is not finite.
    pub fn response(
        &self,
        trial: &CellTrial<D>,
        mp: &MaterialPoints<D>,
        p: usize,
        want_tangent: bool,
    ) -> Result<Response<D>, InadmissiblePoint> {
        let (c, _) = self.cells.place(p);
        let (g, g_bar) = (&trial.grads[p], &trial.means[c]);
        let j_start = mp.jacobian(p);
        let dj = |g: &Tensor<D>| 1.0 + g.trace() + higher_invariants(g);
        let j_bar = j_start * dj(g_bar);
        admissible::check_volume(p, j_start, &[j_start * dj(g), j_bar])?;
        let material = &mp.materials[mp.material[p] as usize];
        let response = Dim::<D>::respond(material, &mp.history[p], g_bar, j_start, want_tangent);
        admissible::check_response(p, j_bar, response)
    }

    /// Point `q`'s stress `S_q`, paired with its own gradient (see the
    /// module docs), with the offset it carries.
    pub fn stress(&self, trial: &CellTrial<D>, mp: &MaterialPoints<D>, q: usize) -> Tensor<D> {
        let (c, w) = self.cells.place(q);
        (trial.stress[c] + (trial.grads[q] - trial.means[c]) * self.stiffness[c])
            * (w / mp.volume0[q])
            + self.offset[q]
    }

    /// The local part of point `q`'s tangent (on its own gradient),
    /// `beta V0_c w_q / V0_q` times the identity: the stiffness assembly
    /// multiplies by `V0_q`.
    pub fn local_tangent(&self, mp: &MaterialPoints<D>, q: usize) -> Tangent<D> {
        let (c, w) = self.cells.place(q);
        Tangent::<D>::identity() * (self.stiffness[c] * w / mp.volume0[q])
    }

    /// Adds the cell terms' stiffness, `G_bar^T (sum_p V0_p A_p - beta
    /// V0_c) G_bar` per cell, to tangent values in `pattern`'s layout
    /// (which must hold [`CellMean::coupling_groups`]). The models'
    /// tangents are made here, at the cells' means.
    pub fn add_to(
        &self,
        conn: &Connectivity<D>,
        mp: &MaterialPoints<D>,
        trial: &CellTrial<D>,
        pattern: &Pattern,
        values: &mut [f64],
    ) {
        let blocks: Vec<(usize, Vec<[f64; D]>, Tangent<D>)> = (0..self.cells.cells())
            .into_par_iter()
            .map(|c| {
                let nodes = self.cells.nodes(c);
                let index = |n: u32| nodes.binary_search(&n).expect("a node of the cell");
                let mut mean_grad = vec![[0.0; D]; nodes.len()];
                let mut a = Tangent::<D>::identity() * -self.stiffness[c];
                for &q in self.cells.members(c) {
                    let q = q as usize;
                    let w = self.cells.place(q).1;
                    for l in conn.point_links(q) {
                        let k = index(l.node);
                        for d in 0..D {
                            mean_grad[k][d] += w * l.grad[d];
                        }
                    }
                    // An admissible trial: the point loop checked it.
                    let response = self
                        .response(trial, mp, q, true)
                        .expect("an admissible trial state");
                    a += Dim::<D>::tangent_of(&response) * mp.volume0[q];
                }
                (c, mean_grad, a)
            })
            .collect();
        for (c, m, a) in blocks {
            let nodes = self.cells.nodes(c);
            // q[D i + l][j] = sum_n a[(D i + l), (D j + n)] m_b,n, per
            // node b (rows 0..D^2 of nine); sums from their first term.
            for (kb, &nb) in nodes.iter().enumerate() {
                let mut q = [[0.0; D]; 9];
                for (row, qr) in q.iter_mut().enumerate().take(D * D) {
                    for (j, qrj) in qr.iter_mut().enumerate() {
                        let mut sum = a[(row, D * j)] * m[kb][0];
                        for n in 1..D {
                            sum += a[(row, D * j + n)] * m[kb][n];
                        }
                        *qrj = sum;
                    }
                }
                for (ka, &na) in nodes.iter().enumerate() {
                    let (base, stride) = pattern.block(na, nb);
                    for i in 0..D {
                        for j in 0..D {
                            let mut sum = m[ka][0] * q[D * i][j];
                            for l in 1..D {
                                sum += m[ka][l] * q[D * i + l][j];
                            }
                            values[base + i + j * stride] += sum;
                        }
                    }
                }
            }
        }
    }
}
