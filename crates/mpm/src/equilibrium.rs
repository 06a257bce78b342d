//! The equilibrium of one load step as Newton sees it: the out-of-balance
//! force of a trial increment (the point loop: every point's trial stress,
//! in parallel, summed into the internal force), the force scale it is
//! measured against, and the consistent tangent's correction.
//!
//! The points' responses at the trial increment are made where they are
//! used (the internal force, the tangent, the commit) and not kept: at a
//! million points, kept, they were 240 bytes a point, alive with the
//! tangent at its assembly. Making them again costs one more evaluation
//! of the material a tangent, and one at the commit.

use std::any::Any;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use nalgebra::SMatrix;
use rayon::prelude::*;

use crate::assembly::averaging::{Averaging, CellAverages};
use crate::assembly::{self, NodeAdjacency, Pattern, Side, StepTerm};
use crate::configuration::Configuration;
use crate::grid::{Basis, Connectivity, Grid, NodeKey, increment, lattice_coordinates};
use crate::linsolve::{Factorisation, GridNodes, SolveTally, SolverSettings, SparseSolver};
use crate::material::Material;
use crate::newton::{Equilibrium, PathEquilibrium};
use crate::parallel;
use crate::particles::admissible::{self, InadmissiblePoint};
use crate::particles::{Dim, MaterialPoints, Space};
use crate::report::{StepMemory, StepTimings};
use crate::supports::{GridSupport, HeldDofs, NodeHold, PlaneSupport};

/// What a step's equilibrium needs that differs by dimension beyond the
/// points' types ([`Space`]): the supports on grid nodes, the averagings
/// it may hold, and the grid coordinates its solver orders the nodes by.
pub trait StepSpace<const D: usize>: Space<D>
where
    Dim<D>: Space<D>,
{
    /// A support on grid nodes (plane strain: on the selector's lines; 3D:
    /// on a plane normal to an axis).
    type Support: NodeHold<D> + Clone + std::fmt::Debug + PartialEq + Send + Sync;
    type Averages: Averaging<D>;
    fn grid_nodes(keys: &[NodeKey]) -> GridNodes;
}

impl StepSpace<2> for Dim<2> {
    type Support = GridSupport;
    type Averages = CellAverages;
    fn grid_nodes(keys: &[NodeKey]) -> GridNodes {
        GridNodes::Plane(keys.iter().map(|&key| lattice_coordinates(key)).collect())
    }
}

impl StepSpace<3> for Dim<3> {
    type Support = PlaneSupport<3>;
    type Averages = CellAverages<3>;
    fn grid_nodes(keys: &[NodeKey]) -> GridNodes {
        GridNodes::Solid(keys.iter().map(|&key| lattice_coordinates(key)).collect())
    }
}

type Averages<const D: usize> = <Dim<D> as StepSpace<D>>::Averages;
type Trial<const D: usize> = <Averages<D> as Averaging<D>>::Trial;
type Response<const D: usize> = <Dim<D> as Space<D>>::Response;

/// What a load step's system is made of besides the material points: the
/// grid supports' hold, the loads that do not move, the averaging of the
/// points' deformation over cells (which changes the points' own
/// response), and the step terms (boundary loads, the IBM band, the soft
/// background, the ghost penalty), whose stiffness goes into the tangent in
/// the list's order.
pub struct StepTerms<'a, const D: usize = 2>
where
    Dim<D>: StepSpace<D>,
{
    pub held: HeldDofs,
    /// Gravity and point loads at the step's load factor.
    pub f_ext: Vec<f64>,
    /// For a step whose load factor is an unknown (path following): that
    /// factor, and the derivative of `f_ext` by it (the ramped parts).
    pub f_ext_rate: Option<(f64, Vec<f64>)>,
    /// F-bar's or the cell-mean strain's cells, when the case asks for one.
    pub averaging: Option<Averages<D>>,
    pub terms: Vec<Box<dyn StepTerm<D> + 'a>>,
}

impl<const D: usize> StepTerms<'_, D>
where
    Dim<D>: StepSpace<D>,
{
    /// The stiffness pattern: the material's couplings (points' nodes) and
    /// those the averaging and the step terms add.
    pub fn pattern(&self, conn: &Connectivity<D>) -> Pattern {
        let mut groups: Vec<Vec<u32>> = self
            .terms
            .iter()
            .flat_map(|term| term.coupling_groups())
            .collect();
        if let Some(averaging) = &self.averaging {
            groups.extend(averaging.coupling_groups());
        }
        Pattern::build(conn, &groups)
    }
}

/// The equilibrium equations of one load step, as Newton sees them.
pub struct StepEquilibrium<'a, const D: usize = 2>
where
    Dim<D>: StepSpace<D>,
{
    conn: &'a Connectivity<D>,
    pattern: Pattern,
    points: &'a MaterialPoints<D>,
    /// DOFs the grid supports hold.
    held: HeldDofs,
    averaging: Option<Averages<D>>,
    /// The averaging's state at the last trial state (F-bar's cell
    /// averages and coupling terms, the cell mean's gradients and sums).
    averaged_trial: Option<Trial<D>>,
    /// The step terms, in the order their stiffness is added.
    terms: Vec<Box<dyn StepTerm<D> + 'a>>,
    /// The largest of the terms' [`StepTerm::force_scale`], once per step.
    terms_scale: f64,
    /// The supports' forces at the last trial state (kept apart from
    /// `f_int`, from which grid supports take their reactions).
    f_support: Vec<f64>,
    /// Loads that do not depend on the displacement (gravity, point loads).
    f_ext_fixed: Vec<f64>,
    /// Path following: the load factor `f_ext_fixed` was made at, and its
    /// derivative by the load factor ([`StepTerms::f_ext_rate`]).
    f_ext_rate: Option<(f64, Vec<f64>)>,
    /// What `f_ext_fixed` is at the load factor of `f_ext_rate`.
    f_ext_made: Vec<f64>,
    /// All external forces at the last trial state.
    f_ext: Vec<f64>,
    /// The last trial increment.
    u: Vec<f64>,
    f_int: Vec<f64>,
    /// The tangent's values, kept from iteration to iteration.
    k: Vec<f64>,
    /// Whether `k` is the tangent at the last trial state.
    assembled: bool,
    solver: SparseSolver,
    pub(crate) timings: StepTimings,
    memory: StepMemory,
}

/// A step's pattern (its node adjacency) with the solver that analysed it,
/// handed to the next step: if its pattern is the same, the solver's
/// analysis serves it.
pub struct AnalysedPattern {
    adjacency: NodeAdjacency,
    pub(crate) solver: SparseSolver,
}

/// What a converged step leaves: the points' states to commit, what its
/// terms carry to the next step ([`StepTerm::into_carried`]), what it
/// cost, and its analysed pattern.
pub struct ConvergedStep<const D: usize = 2>
where
    Dim<D>: StepSpace<D>,
{
    pub states: Vec<PointState<D>>,
    /// With an averaging, what the next step carries of it
    /// ([`Averaging::carried`]: how far the pressure or the stress each
    /// point worked with stood from its own model's).
    pub averaged: Option<<Averages<D> as Averaging<D>>::Carried>,
    pub carried: Vec<Box<dyn Any>>,
    pub timings: StepTimings,
    pub memory: StepMemory,
    pub analysed: AnalysedPattern,
}

/// What a point commits when its step converges: its response's history
/// and Cauchy stress.
#[derive(Debug, Clone, Copy)]
pub struct PointState<const D: usize = 2>
where
    Dim<D>: Space<D>,
{
    pub history: <Dim<D> as Space<D>>::History,
    pub cauchy: <Dim<D> as Space<D>>::Stress,
}

impl<'a, const D: usize> StepEquilibrium<'a, D>
where
    Dim<D>: StepSpace<D>,
{
    /// The system of a step on the configuration `start`; `pattern` must
    /// hold every coupling of `terms` ([`StepTerms::pattern`]). `previous`
    /// is the last step's analysed pattern, whose solver is reused when
    /// the patterns are the same.
    pub fn new(
        start: &Configuration<'a, D>,
        terms: StepTerms<'a, D>,
        pattern: Pattern,
        previous: Option<AnalysedPattern>,
        (settings, tally): (&SolverSettings, &Arc<SolveTally>),
    ) -> Self {
        let conn = start.conn;
        let StepTerms {
            held,
            f_ext,
            f_ext_rate,
            averaging,
            terms,
        } = terms;
        let solver = match previous {
            Some(previous) if pattern.is(&previous.adjacency) => previous.solver.reused(),
            previous => {
                // Freed before the new order and factor are made.
                drop(previous);
                // The nodes' grid coordinates: Cholesky's nested-dissection
                // order (of a symmetric tangent, or of the symmetric part
                // that preconditions GMRES) and the multigrid's aggregates
                // are made from them. LU orders its own columns.
                let solver = SparseSolver::new(conn.n_dofs(), None, settings, tally.clone())
                    .with_grid(
                        Dim::<D>::grid_nodes(&conn.nodes),
                        matches!(start.basis, Basis::BSpline2 | Basis::BSpline3),
                    );
                if start.points.materials.iter().all(Material::is_elastic) {
                    solver.with_elastic_tangents()
                } else {
                    solver
                }
            }
        };
        Self {
            conn,
            pattern,
            points: start.points,
            held,
            averaging,
            averaged_trial: None,
            terms_scale: terms
                .iter()
                .map(|term| term.force_scale(conn.n_dofs()))
                .fold(0.0, f64::max),
            terms,
            f_support: vec![0.0; conn.n_dofs()],
            f_ext: f_ext.clone(),
            f_ext_made: if f_ext_rate.is_some() {
                f_ext.clone()
            } else {
                Vec::new()
            },
            f_ext_fixed: f_ext,
            f_ext_rate,
            u: Vec::new(),
            f_int: Vec::new(),
            k: Vec::new(),
            assembled: false,
            solver,
            timings: StepTimings::default(),
            memory: StepMemory::default(),
        }
    }

    /// Whether a grid support holds DOF `dof`.
    pub fn is_held(&self, dof: usize) -> bool {
        self.held.fixed[dof]
    }

    /// The number of DOFs that are not held.
    pub fn n_free_dofs(&self) -> usize {
        self.conn.n_dofs() - self.held.count()
    }

    /// Per support of the case (`n` of them), the force it exerts on the
    /// body at the converged increment `u`: grid supports' from the
    /// material's forces on their DOFs, the others' from their step terms.
    pub fn reactions(&self, u: &[f64], n: usize) -> Vec<[f64; D]> {
        let mut reactions = vec![[0.0; D]; n];
        self.held
            .add_reactions(&self.f_int, &self.f_ext, &mut reactions);
        for term in &self.terms {
            let Some(forces) = term.reactions(u, &self.held.fixed, n) else {
                continue;
            };
            for (r, b) in reactions.iter_mut().zip(forces) {
                for c in 0..D {
                    r[c] += b[c];
                }
            }
        }
        reactions
    }

    /// Resultant of the loads applied to the grid at the last trial state.
    pub fn applied_load(&self) -> [f64; D] {
        std::array::from_fn(|c| self.f_ext.iter().skip(c).step_by(D).sum())
    }

    /// What the step commits once converged (the points' states at the
    /// last trial increment, Newton's converged one), and what it hands on.
    pub fn into_converged(mut self) -> ConvergedStep<D> {
        // The tangent and the compressed columns are done with: given back
        // before the states are made.
        self.k = Vec::new();
        let adjacency = self.pattern.adjacency();
        self.pattern = Pattern::default();
        let responses = self.trial_responses();
        let states = (0..self.points.len())
            .into_par_iter()
            .with_min_len(parallel::POINT_RESPONSES)
            .map(|p| {
                let (history, cauchy) = Dim::<D>::state_of(&responses.at(p, false));
                PointState { history, cauchy }
            })
            .collect::<Vec<PointState<D>>>();
        let averaged = (self.averaging.as_ref())
            .zip(self.averaged_trial.as_ref())
            .map(|(averaging, trial)| averaging.carried(trial, self.points));
        ConvergedStep {
            states,
            averaged,
            carried: self
                .terms
                .into_iter()
                .filter_map(StepTerm::into_carried)
                .collect(),
            timings: self.timings,
            memory: self.memory,
            analysed: AnalysedPattern {
                adjacency,
                solver: self.solver,
            },
        }
    }

    /// The points' responses at the last trial increment (which the point
    /// loop found admissible, if the tangent or a commit asks for them).
    fn trial_responses(&self) -> TrialResponses<'_, D> {
        TrialResponses {
            conn: self.conn,
            points: self.points,
            u: &self.u,
            averaged: self.averaging.as_ref().map(|averaging| {
                let trial = self
                    .averaged_trial
                    .as_ref()
                    .expect("the cells' averages are made with each trial state");
                (averaging, trial)
            }),
        }
    }

    /// The tangent at the last trial state, into `k` (once a trial state:
    /// a second correction there solves with it again).
    fn assemble_tangent(&mut self) {
        let t = Instant::now();
        let mut k = std::mem::take(&mut self.k);
        let (conn, mp) = (self.conn, self.points);
        let responses = self.trial_responses();
        if let (Some(averaging), Some(trial)) = (&self.averaging, &self.averaged_trial) {
            assembly::stiffness(
                conn,
                &self.pattern,
                mp,
                |p| {
                    averaging
                        .own_tangent(mp, p)
                        .unwrap_or_else(|| Dim::<D>::tangent_of(&responses.at(p, true)))
                },
                false,
                &mut k,
            );
            averaging.add_couplings(trial, conn, mp, &self.pattern, &mut k);
        } else {
            // Loads that move add their own unsymmetric part below.
            let symmetric_points = mp.materials.iter().all(Material::symmetric_tangent);
            assembly::stiffness(
                conn,
                &self.pattern,
                mp,
                |p| Dim::<D>::tangent_of(&responses.at(p, true)),
                symmetric_points,
                &mut k,
            );
        }
        for term in &self.terms {
            let t = Instant::now();
            term.add_stiffness(&self.u, &self.pattern, &mut k);
            if term.side() != Side::Stabilisation {
                self.timings.boundary += t.elapsed().as_secs_f64();
            }
        }
        assembly::constrain(&self.pattern, &mut k, &self.held.fixed);
        self.k = k;
        self.assembled = true;
        self.timings.assembly += t.elapsed().as_secs_f64();
    }
}

impl<const D: usize> Equilibrium for StepEquilibrium<'_, D>
where
    Dim<D>: StepSpace<D>,
{
    fn n_dofs(&self) -> usize {
        self.conn.n_dofs()
    }

    /// The point loop: the trial stress of every point, in parallel,
    /// summed into the internal force.
    fn out_of_balance(&mut self, u: &[f64]) -> Result<(Vec<f64>, f64), InadmissiblePoint> {
        let t = Instant::now();
        self.assembled = false;
        self.averaged_trial = None;
        self.u.clear();
        self.u.extend_from_slice(u);
        let (conn, mp) = (self.conn, self.points);
        if let Some(averaging) = &self.averaging {
            let (f_int, trial) = averaging.internal_force(conn, mp, u)?;
            self.f_int = f_int;
            self.averaged_trial = Some(trial);
        } else {
            // An inadmissible point adds nothing meanwhile, and the
            // lowest-numbered one is reported.
            let responses = self.trial_responses();
            let refused = AtomicUsize::new(usize::MAX);
            let f_int = assembly::internal_force(conn, mp, |p| match responses.checked(p, false) {
                Ok(response) => Dim::<D>::stress_of(&response),
                Err(_) => {
                    refused.fetch_min(p, Ordering::Relaxed);
                    SMatrix::zeros()
                }
            });
            let point = refused.into_inner();
            if point != usize::MAX
                && let Err(refused) = responses.checked(point, false)
            {
                return Err(refused);
            }
            self.f_int = f_int;
        }
        // Forces are measured against the material's own internal force
        // (which includes the reactions), the loads, and what prescribed
        // displacements ask of the material (the terms' force scales); a
        // band's forces themselves are a stiff penalty's and would loosen
        // the balance by h / delta.
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let material_norm = norm(&self.f_int);
        if self.terms.iter().any(|term| term.side() == Side::Load) {
            self.f_ext.clone_from(&self.f_ext_fixed);
        }
        self.f_support.fill(0.0);
        for term in &self.terms {
            let t = Instant::now();
            let f = match term.side() {
                Side::Load => &mut self.f_ext,
                Side::Stabilisation => &mut self.f_int,
                Side::Support => &mut self.f_support,
            };
            term.add_force(u, f);
            if term.side() != Side::Stabilisation {
                self.timings.boundary += t.elapsed().as_secs_f64();
            }
        }
        let scale = norm(&self.f_ext)
            .max(material_norm)
            .max(self.terms_scale)
            .max(f64::MIN_POSITIVE);
        let r = (0..u.len())
            .map(|i| {
                if self.held.fixed[i] {
                    0.0
                } else {
                    self.f_ext[i] - self.f_int[i] - self.f_support[i]
                }
            })
            .collect();
        self.timings.point_loop += t.elapsed().as_secs_f64();
        Ok((r, scale))
    }

    fn correction(
        &mut self,
        r: &[f64],
        accuracy: f64,
    ) -> Result<(Vec<f64>, Factorisation), String> {
        let (mut du, kind) = self.solve_columns(&[r], accuracy)?;
        Ok((du.pop().expect("one right-hand side"), kind))
    }

    fn impose(&self, u: &mut [f64]) {
        self.held.impose(u);
    }
}

impl<const D: usize> PathEquilibrium for StepEquilibrium<'_, D>
where
    Dim<D>: StepSpace<D>,
{
    fn set_load_factor(&mut self, lambda: f64) {
        let (made_at, rate) = self
            .f_ext_rate
            .as_ref()
            .expect("a path-following step is made with its load rate");
        for ((f, made), q) in self.f_ext_fixed.iter_mut().zip(&self.f_ext_made).zip(rate) {
            *f = made + (lambda - made_at) * q;
        }
        self.f_ext.clone_from(&self.f_ext_fixed);
        for term in &mut self.terms {
            term.set_load_factor(lambda);
        }
    }

    fn load_rate(&self) -> Vec<f64> {
        let (_, rate) = self
            .f_ext_rate
            .as_ref()
            .expect("a path-following step is made with its load rate");
        let mut q = rate.clone();
        for term in &self.terms {
            term.add_load_rate(&self.u, &mut q);
        }
        for (qi, &fixed) in q.iter_mut().zip(&self.held.fixed) {
            if fixed {
                *qi = 0.0;
            }
        }
        q
    }

    fn corrections(
        &mut self,
        rhs: &[&[f64]],
        accuracy: f64,
    ) -> Result<(Vec<Vec<f64>>, Factorisation), String> {
        self.solve_columns(rhs, accuracy)
    }
}

impl<const D: usize> StepEquilibrium<'_, D>
where
    Dim<D>: StepSpace<D>,
{
    /// The grid supports move the nodes they hold in a step from load
    /// factor `from` to `to` ([`HeldDofs::moving`]), which Newton's
    /// iterates then carry ([`Equilibrium::impose`]).
    pub(crate) fn move_supports<S: NodeHold<D>>(
        &mut self,
        supports: &[S],
        grid: &Grid<D>,
        factors: (f64, f64),
    ) {
        self.held = std::mem::take(&mut self.held).moving(supports, grid, self.conn, factors);
    }

    /// Solves `K x = b` for each of `rhs` with the tangent at the last
    /// trial state.
    fn solve_columns(
        &mut self,
        rhs: &[&[f64]],
        accuracy: f64,
    ) -> Result<(Vec<Vec<f64>>, Factorisation), String> {
        if !self.assembled {
            self.assemble_tangent();
        }
        let averaged = self.averaging.is_some();
        let symmetric = symmetric_tangent(&self.terms, averaged, self.points);
        let solved = self
            .solver
            .solve_columns(&self.pattern, &self.k, rhs, symmetric, accuracy);
        self.memory = StepMemory {
            points: self.points.heap_bytes(),
            links: self.conn.heap_bytes(),
            pattern: self.pattern.heap_bytes(),
            tangent: std::mem::size_of_val(self.k.as_slice()),
            responses: self
                .averaged_trial
                .as_ref()
                .map_or(0, <Averages<D> as Averaging<D>>::trial_bytes),
            solver: self.solver.memory(),
        };
        let (du, kind, timing) = solved?;
        self.timings.factorisation += timing.factorise;
        self.timings.solve += timing.solve;
        if du.iter().flatten().any(|v| !v.is_finite()) {
            return Err("the solution has non-finite entries (singular tangent)".into());
        }
        Ok((du, kind))
    }
}

/// Whether a step's tangent is symmetric (then Cholesky and CG solve it).
/// Boundary loads move with the boundary: their load stiffness makes the
/// tangent non-symmetric, and so does non-associated plastic flow. The
/// elastic models and associated flow under loads that do not move have a
/// symmetric tangent; with the cells' averages (`averaged`, F-bar or the
/// cell mean) it is taken as unsymmetric.
fn symmetric_tangent<const D: usize>(
    terms: &[Box<dyn StepTerm<D> + '_>],
    averaged: bool,
    points: &MaterialPoints<D>,
) -> bool
where
    Dim<D>: Space<D>,
{
    terms.iter().all(|term| term.symmetric())
        && !averaged
        && points.materials.iter().all(Material::symmetric_tangent)
}

/// Every point's response at a trial increment `u`, made on request.
struct TrialResponses<'s, const D: usize>
where
    Dim<D>: StepSpace<D>,
{
    conn: &'s Connectivity<D>,
    points: &'s MaterialPoints<D>,
    u: &'s [f64],
    /// The averaging's cells, with their state at `u`.
    averaged: Option<(&'s Averages<D>, &'s Trial<D>)>,
}

impl<const D: usize> TrialResponses<'_, D>
where
    Dim<D>: StepSpace<D>,
{
    /// Point `p`'s response, or the point if it is not admissible at `u`
    /// ([`admissible`]). Without `want_tangent` its tangent may be left
    /// zero ([`Material::respond_without_tangent`]; F-bar's point needs it).
    fn checked(&self, p: usize, want_tangent: bool) -> Result<Response<D>, InadmissiblePoint> {
        let (conn, mp) = (self.conn, self.points);
        if let Some((averaging, trial)) = self.averaged {
            return averaging.response(trial, conn, mp, self.u, p, want_tangent);
        }
        let (_, grad_u) = increment(conn.point_links(p), self.u);
        let j_start = Dim::<D>::determinant(&mp.deformation[p]);
        let jacobian = j_start * Dim::<D>::determinant(&(SMatrix::identity() + grad_u));
        admissible::check_volume(p, j_start, &[jacobian])?;
        let material = &mp.materials[mp.material[p] as usize];
        let response = Dim::<D>::respond(material, &mp.history[p], &grad_u, j_start, want_tangent);
        admissible::check_response(p, jacobian, response)
    }

    /// Point `p`'s response at a trial state the point loop found
    /// admissible: the only ones Newton assembles a tangent at or converges
    /// to. (An inadmissible point would answer its start's response.)
    fn at(&self, p: usize, want_tangent: bool) -> Response<D> {
        self.checked(p, want_tangent).unwrap_or_else(|_| {
            let mp = self.points;
            let j_start = Dim::<D>::determinant(&mp.deformation[p]);
            let material = &mp.materials[mp.material[p] as usize];
            Dim::<D>::respond(material, &mp.history[p], &SMatrix::zeros(), j_start, true)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{StepEquilibrium, StepSpace};
    use crate::assembly;
    use crate::boundary::loading::BoundaryLoading;
    use crate::case::Case;
    use crate::case::solid::SolidCase;
    use crate::fixtures;
    use crate::newton::Equilibrium;
    use crate::particles::{Dim, Space};
    use crate::stepper::Simulation;

    /// A Hencky body bent and squeezed past 2% strain, GIMP on a grid cut
    /// at an offset, held at x = 0.1 (a grid line): `check` is given its
    /// step, with every point's response at that trial state, and its
    /// material tangent assembled in full and mirrored
    /// ([`assembly::stiffness`]).
    fn bent_body(check: impl FnOnce(&StepEquilibrium, Vec<f64>, Vec<f64>)) {
        let mut case = fixtures::block([2.0, 1.0], [7, 5], 0.5, [0.1, 0.13]);
        case["basis"] = "gimp".into();
        case["supports"] = serde_json::json!([ { "on": { "x": 0.1 }, "fix": "xy" } ]);
        let sim = fixtures::simulation(&case);
        let conn = sim.reset_grid();
        let mut eq = sim.assemble(&conn, 1.0, false, None);
        let u: Vec<f64> = (0..conn.n_dofs())
            .map(|dof| {
                let x = sim.grid.node_position(conn.nodes[dof / 2]);
                if dof % 2 == 0 {
                    0.02 * x[1] * x[0] - 0.01 * x[0] * x[0]
                } else {
                    -0.02 * x[0] * x[0] - 0.01 * x[1]
                }
            })
            .collect();
        eq.out_of_balance(&u).unwrap();
        let assemble = |symmetric: bool| {
            let mut k = Vec::new();
            assembly::stiffness(
                eq.conn,
                &eq.pattern,
                eq.points,
                |p| eq.trial_responses().at(p, true).tangent,
                symmetric,
                &mut k,
            );
            k
        };
        check(&eq, assemble(false), assemble(true));
    }

    /// The follower load's stiffness (differenced over its data points in
    /// parallel, each task on its own copy of the trial ring) is the same
    /// to the bit on pools of 1, 2 and 4 threads, on the paper's cantilever
    /// at a bent trial state. A point is put back by assignment after its
    /// differences; put back as `x + d - d`, which is not always `x`, this
    /// state still passes (no drift reached a task's boundary: checked),
    /// so the test guards the split, not that drift.
    #[test]
    fn the_load_stiffness_does_not_depend_on_the_threads() {
        let case = crate::case::builtin::get("cantilever").unwrap();
        bent_cantilever(case, |loading, u| {
            let on = |threads: usize| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| loading.stiffness(u))
                    .iter()
                    .flat_map(|point| point.entries())
                    .collect::<Vec<_>>()
            };
            let one = on(1);
            assert!(one.len() > 1000, "{} entries", one.len());
            for threads in [2, 4] {
                let other = on(threads);
                assert!(
                    one.len() == other.len()
                        && one.iter().zip(&other).all(|(a, b)| a.0 == b.0
                            && a.1 == b.1
                            && a.2.to_bits() == b.2.to_bits()),
                    "{threads} threads"
                );
            }
        });
    }

    /// The paper's cantilever `case` (JSON) at a bent trial state of its
    /// first step: its boundary loading and that increment, for `check`.
    fn bent_cantilever(case: &str, check: impl FnOnce(&BoundaryLoading, &[f64])) {
        let sim = Simulation::new(&Case::from_json(case).unwrap()).unwrap();
        let conn = sim.reset_grid();
        let start = sim.configuration(&conn);
        let loading = BoundaryLoading::new(&start, &sim.loops, &sim.stages[0].boundary_loads, 1.0);
        let u: Vec<f64> = (0..conn.n_dofs())
            .map(|dof| {
                let x = sim.grid.node_position(conn.nodes[dof / 2]);
                if dof % 2 == 0 {
                    0.013 * x[0] * x[1]
                } else {
                    -0.021 * x[0] * x[0]
                }
            })
            .collect();
        check(&loading, &u);
    }

    /// The load stiffness (each segment's quadrature differentiated
    /// exactly, its control points by central differences of the curve) is
    /// `-df/du` by central differences of the nodal forces themselves, on
    /// the paper's cantilever at a bent trial state, for its follower
    /// pressure and for a dead traction. Measured: 3.0e-9 and 1.9e-9 of the
    /// largest entry, the same at steps of `1e-4` and `1e-5` of the largest
    /// displacement here (so the error is the stiffness's own: its control
    /// points' differences, `loading::CONTROL_POINT_STEP`, 4e-7 at the
    /// step of 1e-6 cells it had). The check allows `3e-8`. Dropping a
    /// segment's derivative, or its control points' motion, misses by the
    /// size of the entries.
    #[test]
    fn the_load_stiffness_is_the_derivative_of_the_forces() {
        for load in [
            serde_json::json!({ "on": { "y": 2.0 }, "pressure": 1500.0 }),
            serde_json::json!({ "on": { "y": 2.0 }, "traction": [400.0, -1500.0] }),
        ] {
            let mut case: serde_json::Value =
                serde_json::from_str(crate::case::builtin::get("cantilever").unwrap()).unwrap();
            case["loads"]["boundary"] = serde_json::json!([load]);
            bent_cantilever(&case.to_string(), |loading, u| {
                let n = u.len();
                let mut k = vec![0.0; n * n];
                for (row, col, value) in loading.stiffness(u).iter().flat_map(|p| p.entries()) {
                    k[row + n * col] += value;
                }
                let largest = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let step = 1e-4 * u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let (mut worst, mut columns) = (0.0f64, 0);
                for col in 0..n {
                    let force = |sign: f64| {
                        let mut moved = u.to_vec();
                        moved[col] += sign * step;
                        let mut f = vec![0.0; n];
                        loading.add_forces(&moved, &mut f);
                        f
                    };
                    let (plus, minus) = (force(1.0), force(-1.0));
                    if plus != minus {
                        columns += 1;
                    }
                    for row in 0..n {
                        let by_differences = -(plus[row] - minus[row]) / (2.0 * step);
                        worst = worst.max((k[row + n * col] - by_differences).abs());
                    }
                }
                eprintln!(
                    "{load}: {columns} columns, largest miss {:e} of the largest entry",
                    worst / largest
                );
                assert!(largest > 0.0 && columns > 20, "{columns} columns");
                assert!(worst <= 3e-8 * largest, "{load}: {worst:e} of {largest:e}");
            });
        }
    }

    /// Assembling only the blocks on and above the diagonal of a symmetric
    /// tangent and mirroring them gives the full assembly's upper triangle
    /// to the bit, and its lower triangle to the round-off by which each
    /// point's tangent is not symmetric (`material::tests` allows 1e-10 of
    /// its norm; Hencky's is round-off: on the bent body the largest miss
    /// is 1.4e-16 of the largest entry, and 1e-12 leaves room). A block
    /// mirrored untransposed, or from the wrong column, misses by the size
    /// of the entries.
    #[test]
    fn the_mirrored_tangent_is_the_full_one() {
        bent_body(|eq, full, mirrored| {
            let largest = full.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let (mut lower, mut worst) = (0, 0.0f64);
            for col in 0..eq.conn.n_dofs() {
                for i in eq.pattern.col_ptr[col]..eq.pattern.col_ptr[col + 1] {
                    if eq.pattern.row_idx[i] as usize <= col {
                        assert_eq!(full[i], mirrored[i], "({}, {col})", eq.pattern.row_idx[i]);
                    } else {
                        lower += 1;
                        worst = worst.max((full[i] - mirrored[i]).abs() / largest);
                    }
                }
            }
            eprintln!("lower triangle: largest miss {worst:e} of the largest entry");
            assert!(worst < 1e-12, "{worst:e}");
            assert!(lower > full.len() / 3, "{lower} of {}", full.len());
        });
    }

    /// F-bar's tangent is the derivative of its out-of-balance force, and
    /// symmetric where the model's is (F-bar's stress is the derivative of
    /// an incremental potential in `dF_bar`): on a block sheared 5% and
    /// bent, with several points a cell, elastic (Hencky) and yielding
    /// with dilation (Mohr-Coulomb, phi = psi = 30 degrees, every point on
    /// a plane or an edge of its surface), `K v` against central
    /// differences of the force along a direction `v` over the free DOFs.
    /// The points carry pressures and stresses from an earlier step
    /// ([`FbarCells::carrying`], [`CellMean::carrying`]). Measured misses: 3e-11 (Hencky) and
    /// 4e-10 (Mohr-Coulomb) of `|K v|`, and the tangent symmetric to 3e-16
    /// of its largest entry. With the coupling by the other points'
    /// pressure left out the Mohr-Coulomb block misses by 8e-2; with the
    /// carried pressures' own stiffness left out, the Hencky block by 9e-6.
    #[test]
    fn the_averaged_tangents_are_the_derivatives_of_their_forces() {
        let hencky = serde_json::json!({ "model": "hencky", "youngs_modulus": 1e6,
            "poisson_ratio": 0.3, "density": 0.0 });
        let sand = serde_json::json!({ "model": "mohr_coulomb", "youngs_modulus": 1e6,
            "poisson_ratio": 0.3, "density": 0.0, "cohesion": 1e2, "friction_angle": 30.0 });
        let variants = ["fbar", "cell_mean"].map(|v| [(v, hencky.clone()), (v, sand.clone())]);
        for (volumetric, material) in variants.into_iter().flatten() {
            let mut case = fixtures::block([2.0, 1.0], [9, 6], 0.5, [0.1, 0.13]);
            case["basis"] = "gimp".into();
            case["analysis"]["volumetric"] = volumetric.into();
            case["bodies"][0]["material"] = material.clone();
            case["supports"] = serde_json::json!([ { "on": { "x": 0.1 }, "fix": "xy" } ]);
            let mut sim = fixtures::simulation(&case);
            // Pressures and stresses carried from a step before, unlike
            // each other (F-bar's `c_p`, the cell mean's `O_q`).
            sim.points.fbar_pressure = (0..sim.points.len())
                .map(|p| 20.0 * ((p * 37) % 11) as f64 - 100.0)
                .collect();
            sim.points.cell_mean_stress = (0..sim.points.len())
                .map(|p| {
                    let s = 20.0 * ((p * 37) % 11) as f64 - 100.0;
                    nalgebra::Matrix2::new(s, 0.3 * s, 0.3 * s, -0.5 * s)
                })
                .collect();
            let conn = sim.reset_grid();
            let mut eq = sim.assemble(&conn, 1.0, false, None);
            let n = conn.n_dofs();
            let u: Vec<f64> = (0..n)
                .map(|dof| {
                    let x = sim.grid.node_position(conn.nodes[dof / 2]);
                    if dof % 2 == 0 {
                        0.02 * x[1] * x[0] - 0.013 * x[0] * x[0] + 0.05 * x[1]
                    } else {
                        -0.02 * x[0] * x[0] + 0.004 * x[0] * x[1]
                    }
                })
                .collect();
            let label = format!("{volumetric}, {}", material["model"]);
            assert_tangent_is_derivative(&mut eq, &u, &label, material["model"] == "mohr_coulomb");
        }
    }

    /// The tangent at `u` is the derivative of the out-of-balance force
    /// (central differences along a direction over the free DOFs, to 1e-6
    /// of `|K v|`) and symmetric (to 1e-10 of its largest entry); with
    /// `plastic`, most points yield at `u`.
    fn assert_tangent_is_derivative<const D: usize>(
        eq: &mut StepEquilibrium<D>,
        u: &[f64],
        label: &str,
        plastic: bool,
    ) where
        Dim<D>: StepSpace<D>,
    {
        eq.out_of_balance(u).unwrap();
        let n_points = eq.points.len();
        let yielded = (0..n_points)
            .filter(|&p| {
                let response = eq.trial_responses().at(p, false);
                Dim::<D>::plastic_strain(&Dim::<D>::state_of(&response).0) > 0.0
            })
            .count();
        let (miss, asymmetry) = tangent_misses(eq, u);
        eprintln!(
            "{label}: {yielded} of {n_points} points yielded; miss {miss:e} of |K v|, asymmetry {asymmetry:e}"
        );
        if plastic {
            assert!(2 * yielded > n_points, "{label}: {yielded}");
        }
        assert!(miss < 1e-6, "{label}: {miss:e}");
        assert!(asymmetry < 1e-10, "{label}: {asymmetry:e}");
    }

    /// How far the tangent at `u` is from central differences of the
    /// out-of-balance force along a direction over the free DOFs (relative
    /// to `|K v|`), and from symmetry (relative to its largest entry).
    fn tangent_misses<const D: usize>(eq: &mut StepEquilibrium<D>, u: &[f64]) -> (f64, f64)
    where
        Dim<D>: StepSpace<D>,
    {
        let n = u.len();
        let free: Vec<bool> = eq.held.fixed.iter().map(|f| !f).collect();
        let v: Vec<f64> = (0..n)
            .map(|dof| {
                if free[dof] {
                    ((dof * 7919) % 13) as f64 / 13.0 - 0.5
                } else {
                    0.0
                }
            })
            .collect();
        eq.out_of_balance(u).unwrap();
        eq.assemble_tangent();
        let mut kv = vec![0.0; n];
        let mut asymmetry = 0.0f64;
        let largest = eq.k.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for col in 0..n {
            for i in eq.pattern.col_ptr[col]..eq.pattern.col_ptr[col + 1] {
                let row = eq.pattern.row_idx[i] as usize;
                kv[row] += eq.k[i] * v[col];
                let mirror = (eq.pattern.col_ptr[row]..eq.pattern.col_ptr[row + 1])
                    .find(|&j| eq.pattern.row_idx[j] as usize == col)
                    .map_or(0.0, |j| eq.k[j]);
                asymmetry = asymmetry.max((eq.k[i] - mirror).abs() / largest);
            }
        }
        let eps = 1e-6;
        let mut shifted = |sign: f64| {
            let t: Vec<f64> = u.iter().zip(&v).map(|(a, b)| a + sign * eps * b).collect();
            eq.out_of_balance(&t).unwrap().0
        };
        let (plus, minus) = (shifted(1.0), shifted(-1.0));
        let (mut miss, mut size) = (0.0f64, 0.0f64);
        for dof in (0..n).filter(|&d| free[d]) {
            let difference = -(plus[dof] - minus[dof]) / (2.0 * eps);
            miss += (difference - kv[dof]).powi(2);
            size += kv[dof].powi(2);
        }
        ((miss / size).sqrt(), asymmetry)
    }

    /// The averagings' tangents in 3D, as
    /// [`the_averaged_tangents_are_the_derivatives_of_their_forces`]
    /// checks them in plane strain: a block of 4 x 2 x 2 cells (GIMP, 8
    /// points a cell, the grid off the body), clamped at one end, sheared,
    /// bent and twisted, with pressures and stresses carried from an
    /// earlier step; Hencky and Mohr-Coulomb (phi = psi = 30 degrees,
    /// every point yielding). Measured misses, F-bar: 1.4e-11 (Hencky) and
    /// 2.5e-10 (Mohr-Coulomb) of `|K v|`; the cell mean: 3.2e-11 and
    /// 9.4e-11; all symmetric to 3.3e-16 of the largest entry.
    #[test]
    fn the_3d_averaged_tangents_are_the_derivatives_of_their_forces() {
        let hencky = serde_json::json!({ "model": "hencky", "youngs_modulus": 1e6,
            "poisson_ratio": 0.3, "density": 0.0 });
        let sand = serde_json::json!({ "model": "mohr_coulomb", "youngs_modulus": 1e6,
            "poisson_ratio": 0.3, "density": 0.0, "cohesion": 1e2, "friction_angle": 30.0 });
        let variants = ["fbar", "cell_mean"].map(|v| [(v, hencky.clone()), (v, sand.clone())]);
        for (volumetric, material) in variants.into_iter().flatten() {
            let case = serde_json::json!({
                "version": 1,
                "analysis": { "type": "3d", "load_steps": 1, "volumetric": volumetric },
                "grid": { "cell_size": 0.5, "origin": [0.1, 0.13, 0.07] },
                "basis": "gimp",
                "bodies": [{
                    "geometry": { "box": { "min": [0.0, 0.0, 0.0], "max": [2.0, 1.0, 1.0] } },
                    "points": { "per_cell": 2 },
                    "material": material
                }],
                "supports": [ { "on": { "x": 0.1 }, "fix": "xyz" } ]
            });
            let case = SolidCase::from_json(&case.to_string()).unwrap();
            let mut sim = Simulation::from_solid_case(&case).unwrap();
            let carried = |p: usize| 20.0 * ((p * 37) % 11) as f64 - 100.0;
            sim.points.fbar_pressure = (0..sim.points.len()).map(carried).collect();
            sim.points.cell_mean_stress = (0..sim.points.len())
                .map(|p| {
                    let s = carried(p);
                    nalgebra::Matrix3::new(
                        s,
                        0.3 * s,
                        0.0,
                        0.3 * s,
                        -0.5 * s,
                        0.2 * s,
                        0.1 * s,
                        0.2 * s,
                        0.4 * s,
                    )
                })
                .collect();
            let conn = sim.reset_grid();
            let mut eq = sim.assemble(&conn, 1.0, false, None);
            let u: Vec<f64> = (0..conn.n_dofs())
                .map(|dof| {
                    let [x, y, z] = sim.grid.node_position(conn.nodes[dof / 3]);
                    match dof % 3 {
                        0 => 0.02 * x * y - 0.013 * x * x + 0.05 * y - 0.01 * z * y,
                        1 => -0.02 * x * x + 0.004 * x * y + 0.03 * z * x,
                        _ => 0.015 * x * x - 0.02 * y * x + 0.01 * y * z,
                    }
                })
                .collect();
            let label = format!("3D {volumetric}, {}", material["model"]);
            assert_tangent_is_derivative(&mut eq, &u, &label, material["model"] == "mohr_coulomb");
        }
    }

    /// A quadratic B-spline tangent's multigrid smooths with the wider
    /// stencils' degree (`multigrid::WIDE_DEGREE`, chosen by the basis):
    /// CG to 1e-10 on a held block (80 x 40 cells, 2 x 2 points each, the
    /// grid off the body by 0.3 cells) takes fewer iterations than with
    /// GIMP's degree. Measured: 26 against 65.
    #[test]
    fn a_b_spline_tangent_is_smoothed_with_the_wider_degree() {
        let mut case = fixtures::block([8.0, 4.0], [160, 80], 0.1, [-0.03, -0.03]);
        case["basis"] = "bspline2".into();
        case["supports"] =
            serde_json::json!([ { "on": { "y": 0.0 }, "fix": "xy", "method": "ibm" } ]);
        case["loads"] = serde_json::json!({ "gravity": [0.0, -9.81] });
        case["bodies"][0]["material"]["density"] = 2000.0.into();
        let sim = fixtures::simulation(&case);
        let conn = sim.reset_grid();
        let mut eq = sim.assemble(&conn, 1.0, false, None);
        let n = conn.n_dofs();
        let (r, _) = eq.out_of_balance(&vec![0.0; n]).unwrap();
        eq.assemble_tangent();
        let nodes: Vec<[i64; 2]> = conn
            .nodes
            .iter()
            .map(|&k| crate::grid::node_coordinates(k))
            .collect();
        let op = crate::multigrid::Operator {
            ptr: &eq.pattern.col_ptr,
            col: &eq.pattern.row_idx,
            val: &eq.k,
        };
        let iterations = |wide: bool| {
            let mut hierarchy = crate::multigrid::Hierarchy::new(op, &nodes, wide).unwrap();
            let (_, outcome) = crate::krylov::preconditioned_cg(
                |x, y| {
                    crate::krylov::symmetric_product(
                        &eq.pattern.col_ptr,
                        &eq.pattern.row_idx,
                        &eq.k,
                        x,
                        y,
                    )
                },
                |z| hierarchy.apply(op, z),
                &r,
                1e-10,
                500,
            );
            assert!(outcome.converged, "{outcome:?}");
            outcome.iterations
        };
        let (narrow, wide) = (iterations(false), iterations(true));
        eprintln!("CG iterations: {narrow} with GIMP's degree, {wide} with the wider");
        assert!(4 * wide < 3 * narrow, "{wide} against {narrow}");
    }

    /// Constraining the held DOFs leaves what the definition says: their
    /// rows and columns zero but for a diagonal equal to the mean magnitude
    /// of the free DOFs' diagonal entries, every other entry as it was
    /// (entry by entry, on the bent body's tangent).
    #[test]
    fn held_dofs_become_a_scaled_identity() {
        bent_body(|eq, full, _| {
            let (n, fixed) = (eq.conn.n_dofs(), &eq.held.fixed);
            assert!(fixed.iter().filter(|&&f| f).count() >= 4);
            let place = |row: usize, col: usize| {
                (eq.pattern.col_ptr[col]..eq.pattern.col_ptr[col + 1])
                    .find(|&i| eq.pattern.row_idx[i] as usize == row)
                    .unwrap()
            };
            let free: Vec<usize> = (0..n).filter(|&d| !fixed[d]).collect();
            let scale =
                free.iter().map(|&d| full[place(d, d)].abs()).sum::<f64>() / free.len() as f64;
            let mut k = full.clone();
            assembly::constrain(&eq.pattern, &mut k, fixed);
            for col in 0..n {
                for i in eq.pattern.col_ptr[col]..eq.pattern.col_ptr[col + 1] {
                    let row = eq.pattern.row_idx[i] as usize;
                    let expected = match (fixed[row] || fixed[col], row == col) {
                        (true, true) => scale,
                        (true, false) => 0.0,
                        (false, _) => full[i],
                    };
                    assert_eq!(k[i], expected, "({row}, {col})");
                }
            }
        });
    }
}
