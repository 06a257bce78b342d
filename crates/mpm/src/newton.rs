//! Newton-Raphson for the equilibrium of one load step.
//!
//! The unknowns are the incremental nodal displacements `u` of the step. An
//! iteration evaluates the out-of-balance force `r(u) = f_ext - f_int(u)`
//! (zero on constrained DOFs), stops when `|r| / scale <= tolerance`, and
//! otherwise solves `K du = r` with the consistent tangent `K = df_int/du`.

use crate::report::NewtonInfo;

use crate::linsolve::Factorisation;
use crate::observer::Observer;

/// Newton controls; the defaults are the case format's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonSettings {
    /// Relative out-of-balance force at which a step has converged (1e-9).
    pub tolerance: f64,
    /// Linear solves allowed per load step (30).
    pub max_iterations: usize,
    /// A relative residual above this (or not finite) is divergence (1e8).
    pub divergence_limit: f64,
    /// Soft-background stiffness in the tangent, relative to the stiffest
    /// material (1e-6); see [`crate::assembly::SoftCells`].
    pub tangent_regularisation: f64,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-9,
            max_iterations: 30,
            divergence_limit: 1e8,
            tangent_regularisation: 1e-6,
        }
    }
}

/// A point whose trial state is not admissible.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InvertedPoint {
    pub point: usize,
    pub jacobian: f64,
}

/// Why a solve stopped without an answer. Every variant says where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    #[error(
        "Newton did not converge in load step {step}: relative residual {residual:.3e} after {iteration} iterations (the limit)"
    )]
    NotConverged {
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
    #[error(
        "material point {point} inverted (J = {jacobian:.3e}) in load step {step} at iteration {iteration}"
    )]
    Inverted {
        step: usize,
        iteration: usize,
        point: usize,
        jacobian: f64,
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
        "material point {point} left the grid extent at ({x:.4}, {y:.4}) after load step {step}"
    )]
    LeftGrid {
        step: usize,
        point: usize,
        x: f64,
        y: f64,
    },
    #[error("cancelled in load step {step} at iteration {iteration}")]
    Cancelled {
        step: usize,
        iteration: usize,
        residual: f64,
    },
}

impl SolveError {
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
            SolveError::Inverted {
                step,
                iteration,
                residual,
                ..
            } => (step, Some(iteration), residual),
            SolveError::LeftGrid { step, .. } => (step, None, None),
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
    fn out_of_balance(&mut self, u: &[f64]) -> Result<(Vec<f64>, f64), InvertedPoint>;
    /// Solves `K du = r` with the tangent at the last trial state.
    fn correction(&mut self, r: &[f64]) -> Result<(Vec<f64>, Factorisation), String>;
}

/// Solves one load step from `u = 0`; returns the converged increment.
pub fn solve(
    eq: &mut impl Equilibrium,
    settings: &NewtonSettings,
    step: usize,
    observer: &mut dyn Observer,
) -> Result<(Vec<f64>, NewtonInfo), SolveError> {
    let mut u = vec![0.0; eq.n_dofs()];
    let mut info = NewtonInfo {
        iterations: 0,
        residuals: Vec::new(),
        factorisation: None,
    };
    for iteration in 0.. {
        let last_finite = info.residuals.iter().rev().copied().find(|r| r.is_finite());
        let (r, scale) = eq.out_of_balance(&u).map_err(|p| SolveError::Inverted {
            step,
            iteration,
            point: p.point,
            jacobian: p.jacobian,
            residual: last_finite,
        })?;
        let norm = r.iter().map(|v| v * v).sum::<f64>().sqrt();
        let residual = if norm == 0.0 { 0.0 } else { norm / scale };
        info.residuals.push(residual);
        observer.newton_iteration(step, iteration, residual);
        if !residual.is_finite() || residual > settings.divergence_limit {
            return Err(SolveError::Diverged {
                step,
                iteration,
                residual,
                last_finite,
            });
        }
        if residual <= settings.tolerance {
            info.iterations = iteration;
            return Ok((u, info));
        }
        if iteration >= settings.max_iterations {
            return Err(SolveError::NotConverged {
                step,
                iteration,
                residual,
            });
        }
        if observer.should_cancel() {
            return Err(SolveError::Cancelled {
                step,
                iteration,
                residual,
            });
        }
        let (du, kind) = eq
            .correction(&r)
            .map_err(|message| SolveError::LinearSolve {
                step,
                iteration,
                message,
                residual,
            })?;
        info.factorisation = Some(kind);
        for (ui, dui) in u.iter_mut().zip(&du) {
            *ui += dui;
        }
    }
    unreachable!("the loop returns")
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
    /// converge to 2 quadratically.
    struct Cubic {
        x0: f64,
        x: f64,
    }

    impl Equilibrium for Cubic {
        fn n_dofs(&self) -> usize {
            1
        }
        fn out_of_balance(&mut self, u: &[f64]) -> Result<(Vec<f64>, f64), InvertedPoint> {
            self.x = self.x0 + u[0];
            Ok((vec![8.0 - self.x.powi(3)], 8.0))
        }
        fn correction(&mut self, r: &[f64]) -> Result<(Vec<f64>, Factorisation), String> {
            Ok((vec![r[0] / (3.0 * self.x * self.x)], Factorisation::Lu))
        }
    }

    #[test]
    fn converges_quadratically_on_a_smooth_equation() {
        let mut eq = Cubic { x0: 3.0, x: 3.0 };
        let (u, info) = solve(&mut eq, &NewtonSettings::default(), 1, &mut NoObserver).unwrap();
        assert!((3.0 + u[0] - 2.0).abs() < 1e-9);
        // Once in the basin, r_{k+1} ~ C r_k^p with p = 2.
        let r = &info.residuals;
        let n = r.len();
        let order = observed_order([r[n - 4], r[n - 3], r[n - 2]]);
        assert!(order > 1.8, "{r:?}");
    }

    #[test]
    fn iteration_cap_is_an_error_that_says_where() {
        let mut eq = Cubic { x0: 3.0, x: 3.0 };
        let settings = NewtonSettings {
            max_iterations: 2,
            ..Default::default()
        };
        match solve(&mut eq, &settings, 7, &mut NoObserver) {
            Err(SolveError::NotConverged {
                step: 7,
                iteration: 2,
                residual,
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
        fn out_of_balance(&mut self, u: &[f64]) -> Result<(Vec<f64>, f64), InvertedPoint> {
            let x = 1.0 + u[0];
            if x > 3.0 && !self.nan_past {
                return Err(InvertedPoint {
                    point: 7,
                    jacobian: -1.0,
                });
            }
            self.x = x;
            let r = if x > 3.0 { f64::NAN } else { 8.0 - x.powi(3) };
            Ok((vec![r], 8.0))
        }
        fn correction(&mut self, r: &[f64]) -> Result<(Vec<f64>, Factorisation), String> {
            Ok((vec![r[0] / (3.0 * self.x * self.x)], Factorisation::Lu))
        }
    }

    /// Every failure after a residual was computed reports the last finite
    /// one: Newton's first step from x = 1 overshoots to x = 3.33, which is
    /// refused (an inverted point) or gives a NaN residual (divergence);
    /// the residual before it was |8 - 1| / 8 = 0.875.
    #[test]
    fn failures_report_the_last_finite_residual() {
        let settings = NewtonSettings::default();
        for (nan_past, step) in [(false, 4), (true, 2)] {
            let mut eq = Fragile { x: 1.0, nan_past };
            let e = solve(&mut eq, &settings, step, &mut NoObserver).unwrap_err();
            if nan_past {
                assert!(matches!(e, SolveError::Diverged { .. }), "{e}");
            } else {
                assert!(matches!(e, SolveError::Inverted { .. }), "{e}");
            }
            assert_eq!(e.location(), (step, Some(1), Some(0.875)), "{e}");
        }
    }
}
