//! Newton-Raphson for the equilibrium of one load step.
//!
//! The unknowns are the incremental nodal displacements `u` of the step. An
//! iteration evaluates the out-of-balance force `r(u) = f_ext - f_int(u)`
//! (zero on constrained DOFs), stops when `|r| / scale <= tolerance`, and
//! otherwise solves `K du = r` with the consistent tangent `K = df_int/du`.

use crate::report::NewtonInfo;

use crate::linsolve::Factorisation;
pub use crate::settings::NewtonSettings;

/// What a solve tells as it goes, and asks whether to stop: the run's
/// observer ([`crate::Observer`]) stands behind it.
pub trait Monitor {
    /// The relative out-of-balance force at an iteration of load step `step`.
    fn newton_iteration(&mut self, step: usize, iteration: usize, residual: f64);
    /// Asked at every iteration; `true` ends the solve with
    /// [`SolveError::Cancelled`].
    fn should_cancel(&mut self) -> bool;
}

pub use crate::particles::admissible::{Inadmissible, InadmissiblePoint};

/// Coordinates to four places, comma-separated.
fn four_places(x: &[f64]) -> String {
    x.iter()
        .map(|c| format!("{c:.4}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Why a solve stopped without an answer. Every variant says where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    #[error(
        "Newton did not converge in load step {step}: relative residual {residual:.3e} after {iteration} iterations (the limit){}",
        round_off_hint(*.residual, *.stalled, *.tolerance)
    )]
    NotConverged {
        step: usize,
        iteration: usize,
        residual: f64,
        /// The residual fell by less than tenfold over the last two
        /// iterations: Newton had stopped making progress.
        stalled: bool,
        /// The tolerance it was to reach.
        tolerance: f64,
    },
    /// A try that stopped converging far from equilibrium, given up
    /// before its iteration limit so that a smaller increment is tried
    /// ([`stuck`]); only when one can be.
    #[error(
        "Newton stopped converging in load step {step}: relative residual {residual:.3e} at iteration {iteration}, above half its value {STUCK_WINDOW} iterations before"
    )]
    Stuck {
        step: usize,
        iteration: usize,
        residual: f64,
    },
    #[error(
        "Newton diverged in load step {step} at iteration {iteration}: relative residual {residual:.3e}"
    )]
    Diverged {
        step: usize,
        iteration: usize,
        residual: f64,
        /// The last finite residual of the step before it, if any.
        last_finite: Option<f64>,
    },
    /// A trial state Newton could not get past without a point that is not
    /// admissible (`particles::admissible`): inverted, its volume jumped,
    /// non-finite, or off its flow rule.
    #[error(
        "material point {point} {reason} (J = {jacobian:.3e}) in load step {step} at iteration {iteration}"
    )]
    Inadmissible {
        step: usize,
        iteration: usize,
        point: usize,
        jacobian: f64,
        reason: Inadmissible,
        /// The residual of the last admissible trial state (none at
        /// iteration 0).
        residual: Option<f64>,
    },
    #[error("linear solve failed in load step {step} at iteration {iteration}: {message}")]
    LinearSolve {
        step: usize,
        iteration: usize,
        message: String,
        /// The residual the solve was to correct.
        residual: f64,
    },
    #[error(
        "material point {point} left the grid extent at ({}) after load step {step}",
        four_places(.at)
    )]
    LeftGrid {
        step: usize,
        point: usize,
        /// Where it was (`D` coordinates).
        at: Vec<f64>,
    },
    /// A converged step whose results are not finite numbers: never
    /// committed, never reported as a success.
    #[error("load step {step} converged to non-finite {quantity}")]
    NonFinite {
        step: usize,
        /// What was not finite, e.g. `reactions` or `stress of material point 12`.
        quantity: String,
    },
    /// A load step's increment failed however far it was cut: `cause` is
    /// how its last try failed.
    #[error(
        "load step {step} failed at load factor {load_factor:.6} after {tries} failed tries, the last of {fraction:.3e} of the step's increment: {cause}"
    )]
    SubstepsExhausted {
        step: usize,
        /// The load factor of the last converged sub-increment.
        load_factor: f64,
        /// The size of the last try, as a fraction of the step's increment.
        fraction: f64,
        /// Failed tries in the step.
        tries: usize,
        cause: Box<SolveError>,
    },
    /// Path following: the arc about the step's start does not meet the
    /// equilibrium path the iteration's tangent predicts (the constraint's
    /// quadratic has no real root); a shorter arc may.
    #[error(
        "the arc of load step {step} does not meet the equilibrium path at iteration {iteration}: relative residual {residual:.3e}"
    )]
    ArcMissed {
        step: usize,
        iteration: usize,
        residual: f64,
    },
    /// A strength-reduction trial that converged only by flowing
    /// ([`crate::strength_reduction`]): its points moved, per unit of the
    /// factor's rise, more than `limit` times their displacement at the
    /// stage's start (root mean squares over the volume), the points
    /// having moved up to `cells` cells since the stage began.
    #[error(
        "the body flowed in load step {step}: its points moved {moved:.3e} m (root mean square over the volume), {ratio:.2} times their displacement at the stage's start per unit of the factor's rise, past the flow limit {limit}, having moved up to {cells:.3} of a cell since the stage began"
    )]
    Flowed {
        step: usize,
        /// Newton's iterations to the state that flowed.
        iterations: usize,
        moved: f64,
        ratio: f64,
        limit: f64,
        cells: f64,
    },
    #[error("cancelled in load step {step} at iteration {iteration}")]
    Cancelled {
        step: usize,
        iteration: usize,
        residual: f64,
    },
}

/// How close to its tolerance a Newton solve that stalled counts as at
/// the residual's round-off floor rather than failing for the increment's
/// size: no smaller increment lowers that floor (at nu = 0.4999 it is
/// 1.2e-9 against the default 1e-9; a rough footing on heavy sand at
/// 61,440 points, 8.9e-9).
pub const ROUND_OFF_MARGIN: f64 = 100.0;

/// Whether a solve that stalled at `residual` did so at its round-off
/// floor, within [`ROUND_OFF_MARGIN`] of `tolerance`.
pub fn at_round_off_floor(residual: f64, stalled: bool, tolerance: f64) -> bool {
    stalled && residual < ROUND_OFF_MARGIN * tolerance
}

/// What the failure's message adds when Newton stalled at its round-off
/// floor: the tolerance that would take it.
fn round_off_hint(residual: f64, stalled: bool, tolerance: f64) -> String {
    if at_round_off_floor(residual, stalled, tolerance) {
        format!(
            "; it stalled near the tolerance {tolerance:.0e}, at the residual's round-off floor, \
             which no smaller increment lowers: analysis.newton.tolerance {:.0e} would take it",
            10f64.powf(residual.log10().floor() + 1.0)
        )
    } else {
        String::new()
    }
}

/// What kind of failure a [`SolveError`] is, by its cause: the kinds the
/// job service serves as `error.kind` and the studies count.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FailureKind {
    /// Newton did not converge (an arc that misses the path is Newton's
    /// failure on it).
    NotConverged,
    Diverged,
    /// A point's `J` stayed at or below zero however far the step was cut.
    InvertedPoint,
    /// A point's trial state was otherwise not admissible.
    InadmissiblePoint,
    LinearSolve,
    LeftGrid,
    NonFinite,
    Cancelled,
}

impl FailureKind {
    /// Its name in `openapi.yaml`'s `error.kind`.
    pub fn name(self) -> &'static str {
        match self {
            FailureKind::NotConverged => "not_converged",
            FailureKind::Diverged => "diverged",
            FailureKind::InvertedPoint => "inverted_point",
            FailureKind::InadmissiblePoint => "inadmissible_point",
            FailureKind::LinearSolve => "linear_solve",
            FailureKind::LeftGrid => "left_grid",
            FailureKind::NonFinite => "non_finite",
            FailureKind::Cancelled => "cancelled",
        }
    }
}

impl SolveError {
    /// The kind of failure, by [`SolveError::cause`].
    pub fn kind(&self) -> FailureKind {
        match self.cause() {
            SolveError::NotConverged { .. }
            | SolveError::Stuck { .. }
            | SolveError::ArcMissed { .. } => FailureKind::NotConverged,
            SolveError::Diverged { .. } => FailureKind::Diverged,
            SolveError::Inadmissible {
                reason: Inadmissible::Inverted,
                ..
            } => FailureKind::InvertedPoint,
            SolveError::Inadmissible { .. } => FailureKind::InadmissiblePoint,
            SolveError::LinearSolve { .. } => FailureKind::LinearSolve,
            SolveError::LeftGrid { .. } => FailureKind::LeftGrid,
            SolveError::NonFinite { .. } => FailureKind::NonFinite,
            SolveError::Cancelled { .. } => FailureKind::Cancelled,
            // A strength-reduction stage counts it as a failed trial; it
            // never ends a run.
            SolveError::Flowed { .. } => FailureKind::NotConverged,
            // cause() never returns it.
            SolveError::SubstepsExhausted { .. } => FailureKind::NotConverged,
        }
    }

    /// The linear solve of `iteration` of load step `step` failed with the
    /// message it is given (for `map_err`); `residual` is the one it was
    /// to correct.
    fn linear_solve(step: usize, iteration: usize, residual: f64) -> impl FnOnce(String) -> Self {
        move |message| SolveError::LinearSolve {
            step,
            iteration,
            message,
            residual,
        }
    }

    /// The point `p` was not admissible at `iteration` of load step `step`
    /// (`residual`: that of the last admissible trial state).
    fn inadmissible(
        step: usize,
        iteration: usize,
        p: InadmissiblePoint,
        residual: Option<f64>,
    ) -> Self {
        SolveError::Inadmissible {
            step,
            iteration,
            point: p.point,
            jacobian: p.jacobian,
            reason: p.reason,
            residual,
        }
    }

    /// How the solve failed in the end: the error a cut increment's last
    /// try met, or this one.
    pub fn cause(&self) -> &SolveError {
        match self {
            SolveError::SubstepsExhausted { cause, .. } => cause.cause(),
            other => other,
        }
    }

    /// Whether a smaller load increment may succeed where this failed.
    pub fn may_pass_when_cut(&self) -> bool {
        matches!(
            self,
            SolveError::NotConverged { .. }
                | SolveError::Stuck { .. }
                | SolveError::Diverged { .. }
                | SolveError::Inadmissible { .. }
                | SolveError::LinearSolve { .. }
                | SolveError::ArcMissed { .. }
                | SolveError::Flowed { .. }
        )
    }

    /// `(step, iteration, residual)` where known, for reports: the
    /// residual is the last finite relative residual of the step (none when
    /// the step stopped before computing one, or left the grid between
    /// steps).
    pub fn location(&self) -> (usize, Option<usize>, Option<f64>) {
        let (step, iteration, residual) = match *self {
            SolveError::NotConverged {
                step,
                iteration,
                residual,
                ..
            }
            | SolveError::LinearSolve {
                step,
                iteration,
                residual,
                ..
            }
            | SolveError::Cancelled {
                step,
                iteration,
                residual,
            }
            | SolveError::Stuck {
                step,
                iteration,
                residual,
            }
            | SolveError::ArcMissed {
                step,
                iteration,
                residual,
            } => (step, Some(iteration), Some(residual)),
            SolveError::Diverged {
                step,
                iteration,
                residual,
                last_finite,
            } => (
                step,
                Some(iteration),
                Some(residual).filter(|r| r.is_finite()).or(last_finite),
            ),
            SolveError::Inadmissible {
                step,
                iteration,
                residual,
                ..
            } => (step, Some(iteration), residual),
            SolveError::Flowed {
                step, iterations, ..
            } => (step, Some(iterations), None),
            SolveError::LeftGrid { step, .. } | SolveError::NonFinite { step, .. } => {
                (step, None, None)
            }
            SolveError::SubstepsExhausted { ref cause, .. } => return cause.location(),
        };
        (step, iteration, residual.filter(|r| r.is_finite()))
    }
}

/// The discrete equilibrium equations of one load step.
pub trait Equilibrium {
    fn n_dofs(&self) -> usize;
    /// Updates the trial state for increment `u` and returns the
    /// out-of-balance force (zero on constrained DOFs) and the force scale it
    /// is measured against.
    fn out_of_balance(&mut self, u: &[f64]) -> Result<(Vec<f64>, f64), InadmissiblePoint>;
    /// Solves `K du = r` with the tangent at the last trial state, to a
    /// relative residual `|r - K du| / |r|` of at most `accuracy` (an
    /// iterative solver may stop there; a direct one answers exactly).
    fn correction(&mut self, r: &[f64], accuracy: f64)
    -> Result<(Vec<f64>, Factorisation), String>;
    /// Writes the increments the supports prescribe into `u`'s
    /// constrained DOFs (which corrections leave alone); none by default.
    fn impose(&self, _u: &mut [f64]) {}
}

/// A step's equilibrium whose load factor is an unknown beside the
/// displacements: what path following ([`solve_arc_length`]) asks of it.
pub trait PathEquilibrium: Equilibrium {
    /// The load factor the next [`Equilibrium::out_of_balance`] applies
    /// the ramped loads at.
    fn set_load_factor(&mut self, lambda: f64);
    /// `df_ext / dlambda` at the last trial state (zero on constrained DOFs).
    fn load_rate(&self) -> Vec<f64>;
    /// Solves `K x = b` for each of `rhs` with one factorisation of the
    /// tangent at the last trial state, each to `accuracy` as in
    /// [`Equilibrium::correction`].
    fn corrections(
        &mut self,
        rhs: &[&[f64]],
        accuracy: f64,
    ) -> Result<(Vec<Vec<f64>>, Factorisation), String>;
}

/// The corrector's load-factor change `x` on an iteration of
/// [`solve_arc_length`] from increment `u`, with `w = u + du_r` and the
/// load's correction `du_q`: a root of `|w + x du_q| = length`, the one
/// whose increment turns least from `u`; where the arc and the line miss
/// each other (the residual's correction is longer than the arc), the
/// correction normal to `u` instead (Ramm's normal plane, "Strategies
/// for tracing the nonlinear response near limit points", 1981), which
/// always meets it unless the load's correction is normal to `u` too.
fn arc_root(u: &[f64], w: &[f64], du_q: &[f64], length: f64) -> Option<f64> {
    let (a, b, c) = (
        dot(du_q, du_q),
        2.0 * dot(du_q, w),
        dot(w, w) - length * length,
    );
    let discriminant = b * b - 4.0 * a * c;
    if a > 0.0 && discriminant >= 0.0 {
        let root = discriminant.sqrt();
        let roots = [(-b + root) / (2.0 * a), (-b - root) / (2.0 * a)];
        let along = |x: f64| dot(u, w) + x * dot(u, du_q);
        return Some(if along(roots[0]) >= along(roots[1]) {
            roots[0]
        } else {
            roots[1]
        });
    }
    let (uw, uq) = (dot(u, w) - dot(u, u), dot(u, du_q));
    (uq != 0.0).then(|| -uw / uq).filter(|x| x.is_finite())
}

/// One path-following increment: the length of its arc (the norm of its
/// displacement increment), the load factor it starts from, and the last
/// converged increment on this step's DOFs with its change of load
/// factor, if there was one (the secant predictor).
#[derive(Debug, Clone, PartialEq)]
pub struct ArcStep {
    pub length: f64,
    pub load_factor: f64,
    pub last: Option<(Vec<f64>, f64)>,
}

/// Solves one increment of the arc-length method, Crisfield's cylindrical
/// arc ("A fast incremental/iterative solution procedure that handles
/// snap-through", Computers & Structures 13, 1981; and his "Non-linear
/// Finite Element Analysis of Solids and Structures" vol. 1, sec. 9.3):
/// the load factor `lambda` is an unknown, and the increment `u` keeps
/// `|u| = length` at every iteration. Each iteration solves with one
/// factorisation for the corrections of the residual and of the load,
/// `K du_r = r` and `K du_q = q` (`q = df_ext/dlambda`), and takes
/// `du = du_r + dlambda du_q` with `dlambda` a root of
/// `|u + du| = length`:
/// - the predictor goes on along the last converged increment, scaled to
///   the arc with its change of load factor (the secant predictor: past
///   yield the tangent at a step's start is the elastic one, as no point
///   flows at a zero increment, and a predictor along it misses the
///   mechanism the body flows in). Without a last increment it goes along
///   the tangent, forward while the tangent's stiffness along the load is
///   positive (`q . du_q > 0`; Bergan's current stiffness parameter);
///   The predictor also takes out the residual the step starts with (the
///   grid's reset leaves a little of the last step's balance undone);
/// - a corrector keeps the root whose increment turns least from the
///   last one (the larger `u . (u + du)`), or where there is none, takes
///   the correction normal to the increment ([`arc_root`]).
///
/// There is no line search: a trial state with an inadmissible point, or
/// an arc that misses the path ([`SolveError::ArcMissed`]), fails the
/// increment, and the stepper shortens the arc. Returns the increment, the
/// load factor it converged at, and Newton's record.
pub fn solve_arc_length<M: Monitor + ?Sized>(
    eq: &mut impl PathEquilibrium,
    settings: &NewtonSettings,
    step: usize,
    monitor: &mut M,
    arc: ArcStep,
) -> Result<(Vec<f64>, f64, NewtonInfo), SolveError> {
    let mut u = vec![0.0; eq.n_dofs()];
    let mut lambda = arc.load_factor;
    let mut info = NewtonInfo::default();
    let inadmissible = |iteration, p: InadmissiblePoint, residual| {
        SolveError::inadmissible(step, iteration, p, residual)
    };
    // The secant predictor, when there is a last increment.
    let secant = arc.last.as_ref().and_then(|(last, dlambda)| {
        let along = norm(last);
        (along > 0.0).then(|| (last, dlambda * arc.length / along, arc.length / along))
    });
    if let Some((last, dlambda, scale)) = secant {
        for (ui, li) in u.iter_mut().zip(last) {
            *ui = scale * li;
        }
        lambda += dlambda;
    }
    eq.set_load_factor(lambda);
    let (mut r, mut scale) = eq
        .out_of_balance(&u)
        .map_err(|p| inadmissible(0, p, None))?;
    for iteration in 0.. {
        let (_, residual) = record(&mut info, settings, monitor, (step, iteration), &r, scale)?;
        // The tangent's predictor is always taken: at the start the step
        // has not moved.
        if (iteration > 0 || secant.is_some()) && residual <= settings.tolerance {
            info.iterations = iteration;
            return Ok((u, lambda, info));
        }
        out_of_iterations_or_cancelled(&info, settings, monitor, (step, iteration, residual))?;
        let q = eq.load_rate();
        let (solved, kind) = eq
            .corrections(&[&r, &q], forcing_term(residual, settings.tolerance))
            .map_err(SolveError::linear_solve(step, iteration, residual))?;
        info.factorisation = Some(kind);
        let (du_r, du_q) = (&solved[0], &solved[1]);
        let w: Vec<f64> = u.iter().zip(du_r).map(|(a, b)| a + b).collect();
        let dlambda = if iteration == 0 && secant.is_none() {
            // Along the tangent by the arc, forward while the stiffness
            // along the load is positive; `du_r` takes out what the grid's
            // reset left of the last step's balance.
            let along = self::norm(du_q);
            if along == 0.0 {
                return Err(SolveError::ArcMissed {
                    step,
                    iteration,
                    residual,
                });
            }
            let forward = dot(&q, du_q) >= 0.0;
            if forward {
                arc.length / along
            } else {
                -arc.length / along
            }
        } else {
            arc_root(&u, &w, du_q, arc.length).ok_or(SolveError::ArcMissed {
                step,
                iteration,
                residual,
            })?
        };
        for ((ui, wi), qi) in u.iter_mut().zip(&w).zip(du_q) {
            *ui = wi + dlambda * qi;
        }
        lambda += dlambda;
        info.step_lengths.push(1.0);
        eq.set_load_factor(lambda);
        (r, scale) = eq
            .out_of_balance(&u)
            .map_err(|p| inadmissible(iteration + 1, p, Some(residual)))?;
    }
    unreachable!("the loop returns")
}

/// The line search along a Newton direction `du` from a state with
/// out-of-balance force `r`. A step length `alpha` is kept when either
/// - the energy-like projection `s(alpha) = du . r(alpha)` has fallen to
///   [`SLACK`] of `s(0)` in magnitude (Crisfield's criterion, "Non-linear
///   Finite Element Analysis of Solids and Structures" vol. 1, sec. 9.3.2:
///   the step is near the minimum of the potential along `du`; it needs
///   `s(0) > 0`, a tangent positive along `du`) and the trial is not one
///   Newton would call diverged (where there is no potential, as with
///   follower loads or F-bar, the slack alone proves less), or
/// - the residual norm has fallen by Armijo's margin: along a Newton
///   direction `|r|` has the slope `-|r|` whatever the tangent's symmetry,
///   so this holds for follower loads too.
///
/// A full step that does neither is cut: to the zero of `s` interpolated
/// linearly when `s` changed sign, else to the minimum of the parabola
/// through `|r(0)|^2`, its slope and `|r(alpha)|^2`, within [`CUT_BOUNDS`].
///
/// Except that an increment's first full step, if admissible, is taken
/// anyway when its out-of-balance force is at most
/// [`NewtonSettings::free_step_growth`] times the larger of the first
/// out-of-balance force and the step's force scale at its start (a
/// yardstick that does not grow with a diverging trial's internal force,
/// as the relative residual's does): a non-monotone search (Grippo,
/// Lampariello & Lucidi 1986, SIAM J. Numer. Anal. 23).
///
/// Later full steps are searched like any other. Were they free too, on
/// the pushed footing with F-bar (`mpm example footing` at 9,933 points) a
/// full step at the fourth iteration would take the residual from 9e-3 to
/// 1.0 (the internal force grown with the unbalance), and every direction
/// after it would invert points until the iteration limit: 7 cut
/// increments, 208 failed iterations and 34.8 s for the run, against 1, 30
/// and 11.5 s (docs/scale.md, "Plastic iterations"; `newton::tests::
/// only_the_first_full_step_is_free` on one equation).
///
/// Near incompressibility the first full step of a load step rotates the
/// body by a linearised rotation, whose spurious volume change costs the
/// P-wave modulus where the shear it corrects costs the shear modulus: the
/// out-of-balance force rises by up to a few times their ratio, and the
/// next iteration removes it. Measured on the paper's cantilever (GIMP,
/// 0.25 m cells): rises of 361 (nu = 0.499), 2.1e3 (F-bar, 0.499) and 2.1e4
/// (F-bar, 0.4999), against ratios of 501 and 5001. The model therefore
/// sets the growth to ten times the largest ratio, and at least 1e3: a
/// slender beam's first full step from rest is its linear solution, which
/// stretches it (the elastica's raised the force 100-300 times). With the monotone
/// search the cantilever at nu = 0.499 took 78 iterations (F-bar: 161 and
/// 10 cut increments) against plain Newton's 26 (30); it now takes plain
/// Newton's path.
struct Search<'a> {
    du: &'a [f64],
    s0: f64,
    norm0: f64,
    /// [`NewtonSettings::divergence_limit`].
    divergence_limit: f64,
}

const SLACK: f64 = 0.8;
const ARMIJO: f64 = 1e-4;
const CUT_BOUNDS: (f64, f64) = (0.1, 0.5);
/// The shortest step length tried; it is taken whatever it gives.
const SHORTEST_STEP: f64 = 1.0 / 1024.0;

impl<'a> Search<'a> {
    fn new(r: &[f64], du: &'a [f64], norm0: f64, divergence_limit: f64) -> Self {
        Self {
            du,
            s0: dot(du, r),
            norm0,
            divergence_limit,
        }
    }

    /// `None` to keep the step `alpha` with residual `r` (norm `n`, relative
    /// residual `relative`), or the shorter step to try instead.
    fn cut(&self, alpha: f64, r: &[f64], n: f64, relative: f64) -> Option<f64> {
        let s = dot(self.du, r);
        let energy =
            self.s0 > 0.0 && s.abs() <= SLACK * self.s0 && relative <= self.divergence_limit;
        let armijo = n <= (1.0 - ARMIJO * alpha) * self.norm0;
        if energy || armijo {
            return None;
        }
        let (lo, hi) = (CUT_BOUNDS.0 * alpha, CUT_BOUNDS.1 * alpha);
        let shorter = if self.s0 > 0.0 && s < 0.0 {
            alpha * self.s0 / (self.s0 - s)
        } else {
            let slope = -self.norm0 * self.norm0;
            let rise = 0.5 * (n * n - self.norm0 * self.norm0) - slope * alpha;
            -slope * alpha * alpha / (2.0 * rise)
        };
        // A trial without a finite residual is halved, as an inadmissible one.
        Some(if shorter.is_finite() {
            shorter.clamp(lo, hi)
        } else {
            0.5 * alpha
        })
    }
}

/// A try whose relative residual is above this, and above half what it
/// was [`STUCK_WINDOW`] iterations before, has stopped converging far
/// from equilibrium ([`stuck`]).
const STUCK_LEVEL: f64 = 1e-2;
/// Iterations over which a try far from equilibrium must halve its
/// residual.
const STUCK_WINDOW: usize = 8;

/// Whether a try with these relative residuals (iteration 0 first) is
/// stuck: its last is above [`STUCK_LEVEL`] and above half the one
/// [`STUCK_WINDOW`] iterations before. Newton's plastic tries do this
/// when an increment has carried the plastic zone past where the tangent
/// can find it: the line search cuts every direction to a few hundredths
/// and the residual creeps. Traced on `mpm bench-row 4`'s pushed F-bar
/// footing at 9,933 and 99,960 points (docs/scale.md "Stuck tries"):
/// every try that sat above 1e-2 for eight iterations without halving
/// ran out of its 30 iterations, and the smaller pieces after it
/// converged in 4 to 13. A try near its solution halves its residual
/// every iteration or two. A bet, which can lose: the built-in footing
/// (960 points) gives up one try that would have converged.
fn stuck(residuals: &[f64]) -> bool {
    let n = residuals.len();
    n > STUCK_WINDOW + 1 && {
        let (now, then) = (residuals[n - 1], residuals[n - 1 - STUCK_WINDOW]);
        now > STUCK_LEVEL && now > 0.5 * then
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solves one load step from `u = 0`; returns the converged increment.
/// As [`solve_from`] without a predicted increment.
pub fn solve<M: Monitor + ?Sized>(
    eq: &mut impl Equilibrium,
    settings: &NewtonSettings,
    step: usize,
    monitor: &mut M,
) -> Result<(Vec<f64>, NewtonInfo), SolveError> {
    solve_from(eq, settings, step, monitor, None)
}

/// Solves one load step, from the `predicted` increment when it is
/// admissible and leaves less out-of-balance force than `u = 0`, else from
/// `u = 0` (either with the increments the supports prescribe,
/// [`Equilibrium::impose`]); returns the converged increment.
///
/// The predictor matters past yield: at `u = 0` no point flows, so the
/// first tangent is the elastic one whatever the step's size, and every
/// increment, however short, starts by undoing an elastic guess (for a
/// cohesionless soil under a footing the first correction leaves about
/// 1% of the force at every size of increment). From a predicted
/// increment the points that flowed in the last one flow again, and the
/// first tangent is theirs.
///
/// Each Newton direction is searched along (see [`Search`]): the full step
/// is taken when it passes the energy slack or Armijo's decrease of the
/// residual norm (or converges), and is cut otherwise. A trial state with
/// an inadmissible point (`particles::admissible`) is halved. Near the solution the full step always
/// passes Armijo's test, so convergence stays quadratic.
pub fn solve_from<M: Monitor + ?Sized>(
    eq: &mut impl Equilibrium,
    settings: &NewtonSettings,
    step: usize,
    monitor: &mut M,
    predicted: Option<Vec<f64>>,
) -> Result<(Vec<f64>, NewtonInfo), SolveError> {
    let mut u = vec![0.0; eq.n_dofs()];
    eq.impose(&mut u);
    let mut info = NewtonInfo::default();
    let inadmissible = |iteration, p: InadmissiblePoint, residual| {
        SolveError::inadmissible(step, iteration, p, residual)
    };
    let at_zero = eq.out_of_balance(&u);
    let predicted = predicted
        .filter(|p| p.len() == u.len() && p.iter().any(|&x| x != 0.0))
        .map(|mut p| {
            eq.impose(&mut p);
            p
        });
    let mut from_prediction = false;
    let (mut r, mut scale) = match (at_zero, predicted) {
        (at_zero, Some(p)) => match (eq.out_of_balance(&p), at_zero) {
            (Ok((rp, sp)), Ok((r0, _))) if self::norm(&rp) < self::norm(&r0) => {
                (u, from_prediction) = (p, true);
                (rp, sp)
            }
            (Ok((rp, sp)), Err(_)) => {
                (u, from_prediction) = (p, true);
                (rp, sp)
            }
            // The equilibrium keeps its last trial state: back to zero.
            _ => eq
                .out_of_balance(&u)
                .map_err(|p| inadmissible(0, p, None))?,
        },
        (at_zero, None) => at_zero.map_err(|p| inadmissible(0, p, None))?,
    };
    // For the free first step: the force scale at the step's start.
    let scale_start = scale;
    for iteration in 0.. {
        let (norm, residual) = record(&mut info, settings, monitor, (step, iteration), &r, scale)?;
        // A prediction is corrected at least once: it carries the last
        // increment's error, within the tolerance, and steps would add it up.
        if residual <= settings.tolerance && (iteration > 0 || !from_prediction) {
            info.iterations = iteration;
            return Ok((u, info));
        }
        out_of_iterations_or_cancelled(&info, settings, monitor, (step, iteration, residual))?;
        if settings.give_up_when_stuck && stuck(&info.residuals) {
            return Err(SolveError::Stuck {
                step,
                iteration,
                residual,
            });
        }
        let (du, kind) = eq
            .correction(&r, forcing_term(residual, settings.tolerance))
            .map_err(SolveError::linear_solve(step, iteration, residual))?;
        info.factorisation = Some(kind);
        let search = Search::new(&r, &du, norm, settings.divergence_limit);
        let mut alpha = 1.0;
        let mut trial = u.clone();
        loop {
            for ((t, ui), dui) in trial.iter_mut().zip(&u).zip(&du) {
                *t = ui + alpha * dui;
            }
            match eq.out_of_balance(&trial) {
                Ok((r_trial, scale_trial)) => {
                    let n = self::norm(&r_trial);
                    let converged = n <= settings.tolerance * scale_trial;
                    let mut cut = if !settings.line_search || converged || alpha <= SHORTEST_STEP {
                        None
                    } else {
                        search.cut(alpha, &r_trial, n, n / scale_trial)
                    };
                    if cut.is_some()
                        && alpha == 1.0
                        && iteration == 0
                        && n <= settings.free_step_growth * norm.max(scale_start)
                        && n / scale_trial <= settings.divergence_limit
                    {
                        cut = None;
                    }
                    match cut {
                        None => {
                            (r, scale) = (r_trial, scale_trial);
                            info.step_lengths.push(alpha);
                            break;
                        }
                        Some(shorter) => alpha = shorter,
                    }
                }
                // An inadmissible trial state is halved.
                Err(_) if settings.line_search && alpha > SHORTEST_STEP => alpha *= 0.5,
                Err(p) => return Err(inadmissible(iteration + 1, p, Some(residual))),
            }
        }
        u = trial;
    }
    unreachable!("the loop returns")
}

/// Records the relative residual of `r` (against `scale`) at an iteration
/// and tells the monitor; returns `|r|` and it, or ends the solve as
/// diverged when it is not finite or past the divergence limit.
fn record<M: Monitor + ?Sized>(
    info: &mut NewtonInfo,
    settings: &NewtonSettings,
    monitor: &mut M,
    (step, iteration): (usize, usize),
    r: &[f64],
    scale: f64,
) -> Result<(f64, f64), SolveError> {
    let last_finite = info.residuals.iter().rev().copied().find(|r| r.is_finite());
    let norm = norm(r);
    let residual = if norm == 0.0 { 0.0 } else { norm / scale };
    info.residuals.push(residual);
    monitor.newton_iteration(step, iteration, residual);
    if !residual.is_finite() || residual > settings.divergence_limit {
        return Err(SolveError::Diverged {
            step,
            iteration,
            residual,
            last_finite,
        });
    }
    Ok((norm, residual))
}

/// The end of a solve that has used up its iterations (`NotConverged`,
/// `stalled` when the residual fell less than tenfold over the last two)
/// or that the monitor cancels, at `(step, iteration, residual)`.
fn out_of_iterations_or_cancelled<M: Monitor + ?Sized>(
    info: &NewtonInfo,
    settings: &NewtonSettings,
    monitor: &mut M,
    (step, iteration, residual): (usize, usize, f64),
) -> Result<(), SolveError> {
    if iteration >= settings.max_iterations {
        let earlier = info
            .residuals
            .len()
            .checked_sub(3)
            .map(|k| info.residuals[k]);
        return Err(SolveError::NotConverged {
            step,
            iteration,
            residual,
            stalled: earlier.is_some_and(|r| residual > 0.1 * r),
            tolerance: settings.tolerance,
        });
    }
    if monitor.should_cancel() {
        return Err(SolveError::Cancelled {
            step,
            iteration,
            residual,
        });
    }
    Ok(())
}

/// How accurately the correction at a Newton iteration whose relative
/// out-of-balance force is `residual` must solve `K du = r`, as the
/// relative linear residual `|r - K du| / |r|`: an inexact Newton method's
/// forcing term (Dembo, Eisenstat & Steihaug 1982, SIAM J. Numer. Anal.
/// 19; Eisenstat & Walker 1996, SIAM J. Sci. Comput. 17).
///
/// The reasoning, a heuristic (it takes the tangent as exact, a full step,
/// and the force scale as unchanged between iterations): a linear
/// residual of `eta |r|` adds about `eta * residual` to the next
/// iteration's relative out-of-balance force, beside exact Newton's
/// `C residual^2`. The larger of two bounds is asked for:
/// - [`FORCING_GAIN`]` * residual`: what it adds is of Newton's own
///   quadratic order, so far from the tolerance convergence stays
///   quadratic (DES: a forcing term of the order of the residual keeps
///   Newton's quadratic rate);
/// - `0.1 * tolerance / residual`: near the solution what it adds is a
///   tenth of the tolerance, so an iteration whose exact solve would end
///   below 0.9 of the tolerance still converges.
///
/// capped at [`FORCING_MAX`] far from the solution. The smallest it asks
/// for is `sqrt(0.1 tolerance FORCING_GAIN)`, 3e-7 at the default
/// tolerance, where Newton's own error is 1e-7 of the force scale.
/// `inexact_corrections_take_no_more_iterations` checks the outcome.
pub fn forcing_term(residual: f64, tolerance: f64) -> f64 {
    (FORCING_GAIN * residual)
        .max(0.1 * tolerance / residual)
        .min(FORCING_MAX)
}

/// [`forcing_term`]'s gain on the relative residual.
const FORCING_GAIN: f64 = 1e-3;
/// [`forcing_term`]'s loosest accuracy.
const FORCING_MAX: f64 = 1e-3;

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Observed order of convergence of three successive residuals,
/// `p = log(r_2 / r_1) / log(r_1 / r_0)`: 2 for quadratic, 1 for linear
/// convergence (meaningful in the asymptotic range, above round-off).
pub fn observed_order(r: [f64; 3]) -> f64 {
    (r[2] / r[1]).ln() / (r[1] / r[0]).ln()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observer::NoObserver;

    /// Scalar equation `x^3 = 8` with its exact derivative: Newton must
    /// converge to 2 quadratically. `inexact`: each correction leaves the
    /// largest linear residual allowed, `accuracy |r|`.
    struct Cubic {
        x0: f64,
        x: f64,
        inexact: bool,
    }

    impl Equilibrium for Cubic {
        fn n_dofs(&self) -> usize {
            1
        }
        fn out_of_balance(&mut self, u: &[f64]) -> Result<(Vec<f64>, f64), InadmissiblePoint> {
            self.x = self.x0 + u[0];
            Ok((vec![8.0 - self.x.powi(3)], 8.0))
        }
        fn correction(
            &mut self,
            r: &[f64],
            accuracy: f64,
        ) -> Result<(Vec<f64>, Factorisation), String> {
            let short = if self.inexact { 1.0 - accuracy } else { 1.0 };
            Ok((
                vec![short * r[0] / (3.0 * self.x * self.x)],
                Factorisation::Lu,
            ))
        }
    }

    /// Two springs, one softening, with internal forces `f0 = 2 u0 - u0^3
    /// / 3 - u1` and `f1 = 2 u1 - u0`, loaded by `lambda` on DOF 0. On the equilibrium path `u1 =
    /// u0 / 2` and `lambda = 1.5 u0 - u0^3 / 3`, whose peak is at `u0 =
    /// sqrt(1.5)`: `lambda = (2/3) 1.5^1.5 = 1.224745`. Its tangent is
    /// singular there.
    struct SofteningSprings {
        start: [f64; 2],
        u: [f64; 2],
        lambda: f64,
    }

    impl SofteningSprings {
        fn f(&self) -> [f64; 2] {
            let [a, b] = self.u;
            [2.0 * a - a.powi(3) / 3.0 - b, 2.0 * b - a]
        }
    }

    impl Equilibrium for SofteningSprings {
        fn n_dofs(&self) -> usize {
            2
        }
        fn out_of_balance(&mut self, u: &[f64]) -> Result<(Vec<f64>, f64), InadmissiblePoint> {
            self.u = [self.start[0] + u[0], self.start[1] + u[1]];
            let f = self.f();
            Ok((vec![self.lambda - f[0], -f[1]], 1.0))
        }
        fn correction(
            &mut self,
            r: &[f64],
            accuracy: f64,
        ) -> Result<(Vec<f64>, Factorisation), String> {
            let (mut x, kind) = self.corrections(&[r], accuracy)?;
            Ok((x.pop().unwrap(), kind))
        }
    }

    impl PathEquilibrium for SofteningSprings {
        fn set_load_factor(&mut self, lambda: f64) {
            self.lambda = lambda;
        }
        fn load_rate(&self) -> Vec<f64> {
            vec![1.0, 0.0]
        }
        fn corrections(
            &mut self,
            rhs: &[&[f64]],
            _accuracy: f64,
        ) -> Result<(Vec<Vec<f64>>, Factorisation), String> {
            let a = self.u[0];
            let k = [[2.0 - a * a, -1.0], [-1.0, 2.0]];
            let det = k[0][0] * k[1][1] - k[0][1] * k[1][0];
            Ok((
                rhs.iter()
                    .map(|r| {
                        vec![
                            (k[1][1] * r[0] - k[0][1] * r[1]) / det,
                            (k[0][0] * r[1] - k[1][0] * r[0]) / det,
                        ]
                    })
                    .collect(),
                Factorisation::Lu,
            ))
        }
    }

    #[test]
    fn the_arc_length_method_passes_the_peak_of_a_softening_spring() {
        let settings = NewtonSettings {
            tolerance: 1e-12,
            ..NewtonSettings::default()
        };
        let mut springs = SofteningSprings {
            start: [0.0; 2],
            u: [0.0; 2],
            lambda: 0.0,
        };
        let (length, peak) = (0.1, 2.0 / 3.0 * 1.5_f64.powf(1.5));
        let mut path = vec![(0.0, 0.0)];
        // The first step from the tangent, the others from the secant.
        let mut last: Option<(Vec<f64>, f64)> = None;
        for step in 1..=30 {
            let start = springs.lambda;
            let arc = ArcStep {
                length,
                load_factor: start,
                last: last.clone(),
            };
            let (u, lambda, info) =
                solve_arc_length(&mut springs, &settings, step, &mut NoObserver, arc).unwrap();
            assert!((norm(&u) - length).abs() < 1e-12 * length, "step {step}");
            assert!(info.iterations <= 6, "step {step}: {:?}", info.residuals);
            springs.start = springs.u;
            last = Some((u.clone(), lambda - start));
            // On the equilibrium path.
            let a = springs.u[0];
            assert!((springs.u[1] - a / 2.0).abs() < 1e-9);
            assert!((lambda - (1.5 * a - a.powi(3) / 3.0)).abs() < 1e-9);
            path.push((a, lambda));
        }
        let top = path.iter().map(|p| p.1).fold(f64::MIN, f64::max);
        // Sampled every 0.1 / sqrt(1.25) in u0 around a peak of curvature
        // -2 sqrt(1.5): at most 2.45 * 0.045^2 / 2 = 0.0025 below it.
        assert!(
            top <= peak + 1e-12 && top > peak - 0.0025,
            "{top} against {peak}"
        );
        // Past the peak and down the other side, u0 still growing.
        let (a_end, lambda_end) = *path.last().unwrap();
        assert!(a_end > 2.0, "{a_end}");
        assert!(lambda_end < 0.5 * peak, "{lambda_end}");
        assert!(path.windows(2).all(|w| w[1].0 > w[0].0));
    }

    #[test]
    fn converges_quadratically_on_a_smooth_equation() {
        let mut eq = Cubic {
            x0: 3.0,
            x: 3.0,
            inexact: false,
        };
        let (u, info) = solve(&mut eq, &NewtonSettings::default(), 1, &mut NoObserver).unwrap();
        assert!((3.0 + u[0] - 2.0).abs() < 1e-9);
        // Once in the basin, r_{k+1} ~ C r_k^p with p = 2.
        let r = &info.residuals;
        let n = r.len();
        let order = observed_order([r[n - 4], r[n - 3], r[n - 2]]);
        assert!(order > 1.8, "{r:?}");
        // Every full step reduced the residual: the line search took them.
        assert!(info.step_lengths.iter().all(|&a| a == 1.0), "{info:?}");
    }

    /// Corrections that leave as large a linear residual as the forcing
    /// term allows take exactly as many iterations as exact ones, from
    /// near and far, at the default tolerance and a tighter one.
    #[test]
    fn inexact_corrections_take_no_more_iterations() {
        for tolerance in [1e-9, 1e-12] {
            let settings = NewtonSettings {
                tolerance,
                ..Default::default()
            };
            for x0 in [2.1, 3.0, 10.0, 100.0] {
                let iterations = |inexact| {
                    let mut eq = Cubic { x0, x: x0, inexact };
                    let (u, info) = solve(&mut eq, &settings, 1, &mut NoObserver).unwrap();
                    assert!((x0 + u[0] - 2.0).abs() < 1e-8, "{info:?}");
                    info.iterations
                };
                assert_eq!(iterations(true), iterations(false), "x0 = {x0}");
            }
        }
    }

    /// The forcing term's bounds (its doc): 1e-3 at the loosest, and at
    /// the tightest `sqrt(0.1 tolerance 1e-3)`, reached where the two
    /// bounds cross.
    #[test]
    fn the_forcing_term_is_loose_far_and_tightest_midway() {
        assert_eq!(forcing_term(10.0, 1e-9), 1e-3);
        let tightest = (1e-10_f64 * 1e-3).sqrt();
        let sweep: Vec<f64> = (0..=90).map(|k| 10f64.powf(-0.1 * k as f64)).collect();
        let lowest = sweep
            .iter()
            .map(|&r| forcing_term(r, 1e-9))
            .fold(f64::INFINITY, f64::min);
        assert!(lowest >= tightest * (1.0 - 1e-12), "{lowest}");
        assert!(lowest < 1.2 * tightest, "{lowest}");
    }

    /// `atan(x) = 0` with its exact derivative: from |x0| > 1.39 full Newton
    /// steps overshoot further each time and diverge (a textbook case,
    /// e.g. Dennis & Schnabel, "Numerical Methods for Unconstrained
    /// Optimization", sec. 6.3); the line search cuts the first steps and
    /// then converges quadratically to 0 with full steps.
    struct Arctangent {
        x0: f64,
        x: f64,
    }

    impl Equilibrium for Arctangent {
        fn n_dofs(&self) -> usize {
            1
        }
        fn out_of_balance(&mut self, u: &[f64]) -> Result<(Vec<f64>, f64), InadmissiblePoint> {
            self.x = self.x0 + u[0];
            Ok((vec![-self.x.atan()], 1.0))
        }
        fn correction(
            &mut self,
            r: &[f64],
            _accuracy: f64,
        ) -> Result<(Vec<f64>, Factorisation), String> {
            Ok((vec![r[0] * (1.0 + self.x * self.x)], Factorisation::Lu))
        }
    }

    #[test]
    fn a_line_search_turns_a_diverging_newton_into_a_converging_one() {
        let plain = NewtonSettings {
            line_search: false,
            ..Default::default()
        };
        let e = solve(
            &mut Arctangent { x0: 3.0, x: 3.0 },
            &plain,
            1,
            &mut NoObserver,
        )
        .unwrap_err();
        assert!(
            matches!(
                e,
                SolveError::Diverged { .. } | SolveError::NotConverged { .. }
            ),
            "{e}"
        );
        let settings = NewtonSettings::default();
        let (u, info) = solve(
            &mut Arctangent { x0: 3.0, x: 3.0 },
            &settings,
            1,
            &mut NoObserver,
        )
        .unwrap();
        assert!((3.0 + u[0]).abs() < 1e-9, "{info:?}");
        let cut = info.step_lengths.iter().filter(|&&a| a < 1.0).count();
        assert!(cut >= 1, "{info:?}");
        // The last steps are full, and quadratic: atan is odd, so its Newton
        // converges cubically near 0; at least quadratically is asked.
        let tail = &info.step_lengths[info.step_lengths.len() - 2..];
        assert_eq!(tail, [1.0, 1.0], "{info:?}");
        let r = &info.residuals;
        let n = r.len();
        assert!(
            observed_order([r[n - 4], r[n - 3], r[n - 2]]) > 1.8,
            "{r:?}"
        );
    }

    /// `x^3 = 8` measured as MPM measures forces, against the larger of the
    /// load and the internal force `x^3`, so that the relative residual of a
    /// far overshoot stays near 1. From x = 0.1 the full step goes to
    /// x = 267, an out-of-balance force of 1.9e7 against 8 at the start: no
    /// free step, it is searched; the free steps' yardstick does not grow
    /// with the trial's own force.
    struct ScaledCubic {
        x: f64,
    }

    impl Equilibrium for ScaledCubic {
        fn n_dofs(&self) -> usize {
            1
        }
        fn out_of_balance(&mut self, u: &[f64]) -> Result<(Vec<f64>, f64), InadmissiblePoint> {
            self.x = 0.1 + u[0];
            let internal = self.x.powi(3);
            Ok((vec![8.0 - internal], internal.abs().max(8.0)))
        }
        fn correction(
            &mut self,
            r: &[f64],
            _accuracy: f64,
        ) -> Result<(Vec<f64>, Factorisation), String> {
            Ok((vec![r[0] / (3.0 * self.x * self.x)], Factorisation::Lu))
        }
    }

    #[test]
    fn a_full_step_to_a_far_larger_force_is_searched_not_taken_free() {
        let mut eq = ScaledCubic { x: 0.1 };
        let (u, info) = solve(&mut eq, &NewtonSettings::default(), 1, &mut NoObserver).unwrap();
        assert!((0.1 + u[0] - 2.0).abs() < 1e-6, "{info:?}");
        assert!(info.step_lengths[0] < 1.0, "{info:?}");
    }

    /// Relative residuals of two tries of the pushed F-bar footing at
    /// 9,933 points (the bench's scene, traced by `mpm run`): the first
    /// try of its second load step, which crept from 8.7e-2 to 3.5e-2 in
    /// 30 iterations and failed (the pieces after it converged in 4 to
    /// 13), is stuck at iteration 9; the first step's only try, which sat near
    /// 3e-3 for eleven iterations and converged at 23, never is.
    #[test]
    fn a_try_creeping_far_from_equilibrium_is_stuck() {
        let creeping = [
            2.94e-1, 8.65e-2, 8.59e-2, 8.44e-2, 8.29e-2, 7.90e-2, 7.86e-2, 7.72e-2, 7.37e-2,
            6.96e-2, 6.82e-2,
        ];
        let first = (1..=creeping.len()).find(|&n| stuck(&creeping[..n]));
        assert_eq!(first, Some(10), "stuck at iteration 9");
        let converging = [
            133.3, 3.57e-3, 3.52e-3, 3.62e-3, 3.66e-3, 3.02e-3, 2.69e-3, 2.57e-3, 2.57e-3, 2.27e-3,
            3.26e-3, 3.18e-3, 1.24e-3, 1.22e-3, 5.48e-4, 5.32e-4, 4.37e-4, 3.17e-4, 8.57e-5,
            4.05e-5, 1.51e-5, 2.04e-6, 1.67e-8, 4.38e-13,
        ];
        assert!((1..=converging.len()).all(|n| !stuck(&converging[..n])));
    }

    /// [`Arctangent`] from x = 1.5: Newton overshoots further each
    /// iteration, |atan| 0.98, then 1.04 at x = -1.69, then 1.16 at x =
    /// 2.32 (by hand, `x - atan(x) (1 + x^2)`). The first full step is
    /// free; the second, which raises the residual again, is searched
    /// (taken free, Newton would go on diverging).
    #[test]
    fn only_the_first_full_step_is_free() {
        let mut eq = Arctangent { x0: 1.5, x: 1.5 };
        let (u, info) = solve(&mut eq, &NewtonSettings::default(), 1, &mut NoObserver).unwrap();
        assert!((1.5 + u[0]).abs() < 1e-8, "{info:?}");
        assert_eq!(info.step_lengths[0], 1.0, "{info:?}");
        assert!(info.step_lengths[1] < 1.0, "{info:?}");
    }

    /// A trial state with an inverted point shortens the step instead of
    /// failing: the full first step from x = 1 goes to 3.33, past the
    /// refused x > 3; half of it (x = 2.17) is admissible and Newton goes
    /// on to 2. A trial with a NaN residual is cut the same way.
    #[test]
    fn an_inverted_or_nan_trial_state_shortens_the_step() {
        for nan_past in [false, true] {
            let mut eq = Fragile { x: 1.0, nan_past };
            let (u, info) = solve(&mut eq, &NewtonSettings::default(), 1, &mut NoObserver)
                .unwrap_or_else(|e| panic!("nan_past {nan_past}: {e}"));
            assert!((1.0 + u[0] - 2.0).abs() < 1e-9, "{info:?}");
            assert_eq!(info.step_lengths[0], 0.5, "{info:?}");
        }
    }

    #[test]
    fn iteration_cap_is_an_error_that_says_where() {
        let mut eq = Cubic {
            x0: 3.0,
            x: 3.0,
            inexact: false,
        };
        let settings = NewtonSettings {
            max_iterations: 2,
            ..Default::default()
        };
        match solve(&mut eq, &settings, 7, &mut NoObserver) {
            Err(SolveError::NotConverged {
                step: 7,
                iteration: 2,
                residual,
                ..
            }) => assert!(residual > 1e-9),
            other => panic!("{other:?}"),
        }
    }

    /// `x^3 = 8` from `x = 1`, whose trial states past `x = 3` are refused
    /// (an inverted point) or, if `nan_past` is set, give a NaN residual.
    struct Fragile {
        x: f64,
        nan_past: bool,
    }

    impl Equilibrium for Fragile {
        fn n_dofs(&self) -> usize {
            1
        }
        fn out_of_balance(&mut self, u: &[f64]) -> Result<(Vec<f64>, f64), InadmissiblePoint> {
            let x = 1.0 + u[0];
            if x > 3.0 && !self.nan_past {
                return Err(InadmissiblePoint {
                    point: 7,
                    jacobian: -1.0,
                    reason: Inadmissible::Inverted,
                });
            }
            self.x = x;
            let r = if x > 3.0 { f64::NAN } else { 8.0 - x.powi(3) };
            Ok((vec![r], 8.0))
        }
        fn correction(
            &mut self,
            r: &[f64],
            _accuracy: f64,
        ) -> Result<(Vec<f64>, Factorisation), String> {
            Ok((vec![r[0] / (3.0 * self.x * self.x)], Factorisation::Lu))
        }
    }

    /// Every failure after a residual was computed reports the last finite
    /// one: Newton's first step from x = 1 overshoots to x = 3.33, which is
    /// refused (an inverted point) or gives a NaN residual (divergence);
    /// the residual before it was |8 - 1| / 8 = 0.875.
    #[test]
    fn failures_report_the_last_finite_residual() {
        let settings = NewtonSettings {
            line_search: false,
            ..Default::default()
        };
        for (nan_past, step) in [(false, 4), (true, 2)] {
            let mut eq = Fragile { x: 1.0, nan_past };
            let e = solve(&mut eq, &settings, step, &mut NoObserver).unwrap_err();
            if nan_past {
                assert!(matches!(e, SolveError::Diverged { .. }), "{e}");
            } else {
                assert!(matches!(e, SolveError::Inadmissible { .. }), "{e}");
            }
            assert_eq!(e.location(), (step, Some(1), Some(0.875)), "{e}");
        }
    }
}
