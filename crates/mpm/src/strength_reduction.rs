//! The factor of safety by strength reduction (Griffiths and Lane 1999):
//! with the loads held, divide every plastic material's strength by a
//! factor `F` ([`Material::with_strength_reduced`]) and solve for
//! equilibrium; the largest `F` at which the body still stands is its
//! factor of safety. Each trial starts from the state of the last one that
//! held. The factor goes up by a fixed increment from 1 until a trial
//! fails, then bisects between the largest that held and the smallest that
//! failed. A failure counts only once it is seen from close below: a trial
//! that fails from far below may have failed for the size of its jump, so
//! when the bracket has closed on such a failure it is tried again from
//! where the bisection stands, and if it holds the increments go on.

use crate::material::Material;
use crate::stages::StrengthReduction;

/// Where a strength-reduction stage stands between its steps.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ReductionState {
    /// The materials as the case gives them (factor 1).
    pub(crate) base: Vec<Material>,
    /// The largest factor that held (1: the stage before, at the case's
    /// strengths).
    pub(crate) held: f64,
    /// The smallest factor that failed, and the factor that held when it
    /// was tried.
    pub(crate) failed: Option<Failed>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Failed {
    pub(crate) factor: f64,
    pub(crate) tried_from: f64,
}

/// What the stage does next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Next {
    /// Try this factor.
    Trial(f64),
    /// The factor of safety is found: the largest that held.
    Found,
}

impl ReductionState {
    pub(crate) fn new(base: Vec<Material>) -> Self {
        Self {
            base,
            held: 1.0,
            failed: None,
        }
    }

    pub(crate) fn next(&self, spec: &StrengthReduction) -> Next {
        let Some(failed) = self.failed else {
            return Next::Trial(self.held + spec.increment);
        };
        // A little slack so that halving a width onto the tolerance closes it.
        let tolerance = spec.tolerance * (1.0 + 1e-9);
        if failed.factor - self.held > tolerance {
            Next::Trial(0.5 * (self.held + failed.factor))
        } else if failed.factor - failed.tried_from > 2.0 * tolerance {
            Next::Trial(failed.factor)
        } else {
            Next::Found
        }
    }

    /// Records a trial at `factor` that held or failed.
    pub(crate) fn record(&mut self, factor: f64, held: bool) {
        if held {
            self.held = factor;
            if self.failed.is_some_and(|f| f.factor <= factor) {
                self.failed = None;
            }
        } else {
            self.failed = Some(Failed {
                factor,
                tried_from: self.held,
            });
        }
    }

    /// The materials at `factor`.
    pub(crate) fn materials_at(&self, factor: f64) -> Vec<Material> {
        self.base
            .iter()
            .map(|m| m.with_strength_reduced(factor))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The trials of a body that fails above `collapse` (and, with
    /// `spurious`, also at that one factor when tried from more than one
    /// increment's tenth below), until found.
    fn trials(collapse: f64, spurious: Option<f64>) -> (Vec<f64>, f64) {
        let spec = StrengthReduction {
            increment: 0.1,
            tolerance: 0.01,
        };
        let mut state = ReductionState::new(Vec::new());
        let mut tried = Vec::new();
        while let Next::Trial(f) = state.next(&spec) {
            assert!(tried.len() < 40, "{tried:?}");
            let jump = f - state.held;
            let at_spurious = spurious.is_some_and(|s| (f - s).abs() < 1e-9);
            let holds = f <= collapse && !(at_spurious && jump > 0.05);
            tried.push(f);
            state.record(f, holds);
        }
        (tried, state.held)
    }

    #[test]
    fn the_bisection_closes_on_the_collapse_factor() {
        let (tried, found) = trials(1.437, None);
        // 1.1 .. 1.5 up, then 1.45, 1.425, 1.4375, 1.43125 in halves.
        assert!((found - 1.43125).abs() < 1e-12, "{tried:?}");
        assert!(found <= 1.437 && 1.437 - found < 0.01);
        assert_eq!(tried.len(), 9, "{tried:?}");
    }

    #[test]
    fn a_failure_from_far_below_is_tried_again_before_it_counts() {
        // Fails at 1.5 when jumped to from 1.4, holds from close below: the
        // true collapse, 1.637, is found.
        let (tried, found) = trials(1.637, Some(1.5));
        assert!(found <= 1.637 && 1.637 - found < 0.01, "{found} {tried:?}");
        let at = |f: &&f64| (**f - 1.5).abs() < 1e-9;
        assert_eq!(tried.iter().filter(at).count(), 2, "{tried:?}");
    }
}
