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
//!
//! A trial also fails when it holds only by flowing. A body below its
//! factor of safety moves little as its strength falls; at the factor its
//! displacement grows without bound. A discrete updated-Lagrangian body
//! past that point may still find an equilibrium, far from where it
//! stood: the mechanism's points cross a good part of a cell, and what
//! the discretisation adds (locking, stabilisation, the moved geometry)
//! holds them again, so that the factor such a trial "holds" at follows
//! the path the increments took (Griffiths and Lane's slope at h = H/20
//! held to 1.60 rising by 0.05 and failed at 1.40 rising by 0.03). So a
//! trial that held counts as failed when both
//! - its points moved, per unit of the factor's rise, more than
//!   `flow_limit` times their displacement at the stage's start (root
//!   mean squares over the volume): the displacement-factor curve turned
//!   up (below the factor of safety the body moves about its stage-start
//!   displacement or less per unit of factor);
//! - and the points have moved on the grid since the stage began: the
//!   largest movements of the trials that held and of this one add up to
//!   more than [`FLOW_CELL_FRACTION`] of a cell, far enough for the
//!   discretisation to hold them again. A body whose points moved less,
//!   however steep its curve (a block whose points all yield at once),
//!   fails only when Newton does.

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
    /// The points' displacement at the stage's start, root mean square
    /// over their volume (m): what a trial's movement is measured against.
    pub(crate) scale: f64,
    /// The largest movements of the trials that held, summed (m): a bound
    /// on how far any point has travelled since the stage began.
    pub(crate) travelled: f64,
}

/// How far, as a fraction of the cell, the points must have moved since
/// a strength-reduction stage began before a trial may count as flowing
/// (the module's docs). Griffiths and Lane's slope at h = H/20 had moved
/// its crest about 0.7% of a cell when its curve turned up, and the
/// trials that held past that moved points 7-50% of a cell each; a
/// uniform block reaches its collapse having moved under 0.1%. The
/// built-in footing's clay moves the points by its edge 1-3% of a cell
/// before its collapse, which the limit then finds up to 2.5% low
/// (docs/guide.md, Strength reduction).
pub(crate) const FLOW_CELL_FRACTION: f64 = 0.01;

/// How far a trial may move the points before it counts as failed
/// (the module's docs): their displacement in the trial (root mean square
/// over the volume) at most `limit` times `per_factor`, the stage's
/// [`ReductionState::scale`] times the factor's rise from the last that
/// held, unless what the trials that held have `travelled` and the
/// trial's largest movement add up to at most [`FLOW_CELL_FRACTION`] of
/// the cell `h`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FlowLimit {
    pub(crate) per_factor: f64,
    pub(crate) limit: f64,
    pub(crate) travelled: f64,
    pub(crate) h: f64,
}

/// What a trial that held moved: its displacement (rms over the volume)
/// over its [`FlowLimit`]'s measure, and its largest (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Flow {
    pub(crate) ratio: f64,
    pub(crate) largest: f64,
}

impl FlowLimit {
    /// How far the points may have travelled since the stage began, with
    /// a trial that moved one `largest` (m).
    pub(crate) fn travelled_with(&self, largest: f64) -> f64 {
        self.travelled + largest
    }

    /// What a trial that moved the points `rms` (the root mean square over
    /// their volume), one of them `largest`, flowed by; `Err` when past
    /// the limit.
    pub(crate) fn measure(&self, rms: f64, largest: f64) -> Result<Flow, Flow> {
        let flow = Flow {
            ratio: rms / self.per_factor,
            largest,
        };
        if flow.ratio > self.limit && self.travelled_with(largest) > FLOW_CELL_FRACTION * self.h {
            Err(flow)
        } else {
            Ok(flow)
        }
    }
}

/// How far a trial moved the points, each by `displacement`: the root
/// mean square over their reference `volume` (a weightless body has no
/// mass to weigh by), and the largest (m).
pub(crate) fn trial_movement<const D: usize>(
    volume: &[f64],
    displacement: impl Fn(usize) -> [f64; D],
) -> (f64, f64) {
    let (mut sum, mut total, mut largest) = (0.0, 0.0, 0.0f64);
    for (p, v) in volume.iter().enumerate() {
        let d = displacement(p);
        let squared = (1..D).fold(d[0] * d[0], |s, c| s + d[c] * d[c]);
        sum += v * squared;
        total += v;
        largest = largest.max(squared.sqrt());
    }
    let rms = if total > 0.0 {
        (sum / total).sqrt()
    } else {
        0.0
    };
    (rms, largest)
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
    /// The stage's start: the case's `base` materials, and the points'
    /// displacement `scale` ([`ReductionState::scale`]).
    pub(crate) fn new(base: Vec<Material>, scale: f64) -> Self {
        Self {
            base,
            held: 1.0,
            failed: None,
            scale,
            travelled: 0.0,
        }
    }

    /// The limit on a trial at `factor`'s movement on a grid of cell `h`:
    /// none when the stage's `flow_limit` is 0 or the points had not moved
    /// at the stage's start (a geostatic stage before it reports no
    /// displacement), so that nothing measures it.
    pub(crate) fn flow_limit(
        &self,
        spec: &StrengthReduction,
        factor: f64,
        h: f64,
    ) -> Option<FlowLimit> {
        let per_factor = self.scale * (factor - self.held);
        (spec.flow_limit > 0.0 && per_factor > 0.0).then_some(FlowLimit {
            per_factor,
            limit: spec.flow_limit,
            travelled: self.travelled,
            h,
        })
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
            flow_limit: 10.0,
        };
        let mut state = ReductionState::new(Vec::new(), 1.0);
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
    fn a_trial_is_measured_against_the_stage_start_per_unit_of_the_rise() {
        let spec = StrengthReduction {
            increment: 0.1,
            tolerance: 0.01,
            flow_limit: 10.0,
        };
        // Two points of volumes 1 and 3, moved 2 m and 0 m: the root mean
        // square over the volume is sqrt(4 / 4) = 1 m.
        let (scale, largest) =
            trial_movement(&[1.0, 3.0], |p| if p == 0 { [0.0, 2.0] } else { [0.0; 2] });
        assert_eq!((scale, largest), (1.0, 2.0));
        let mut state = ReductionState::new(Vec::new(), scale);
        state.record(1.3, true);
        // A rise of 0.05 that moves the points 0.4 m (rms): 8 times the
        // stage's start per unit of factor, within the limit however far
        // a point moved.
        let limit = state.flow_limit(&spec, 1.35, 0.5).expect("measured");
        let flow = limit.measure(0.4, 1.0).expect("within the limit");
        assert!((flow.ratio - 8.0).abs() < 1e-12);
        assert_eq!(limit.limit, 10.0);
        // Past the limit, it flowed if a point moved more than 1% of the
        // 0.5 m cell, less what the trials that held have moved.
        assert!(limit.measure(1.5, 0.0051).is_err());
        assert!(limit.measure(1.5, 0.0049).is_ok());
        state.travelled = 0.003;
        let limit = state.flow_limit(&spec, 1.35, 0.5).expect("measured");
        assert!(limit.measure(1.5, 0.0021).is_err());
        assert!(limit.measure(1.5, 0.0019).is_ok());
        // Nothing measures it when the limit is off or nothing had moved.
        let off = StrengthReduction {
            flow_limit: 0.0,
            ..spec
        };
        assert_eq!(state.flow_limit(&off, 1.35, 0.5), None);
        let still = ReductionState::new(Vec::new(), 0.0);
        assert_eq!(still.flow_limit(&spec, 1.1, 0.5), None);
        // No points: nothing to measure.
        assert_eq!(trial_movement(&[], |_| [1.0, 1.0]), (0.0, 0.0));
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
