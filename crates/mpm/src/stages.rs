//! A run's stages, one after another: each its own load steps, the loads it
//! holds and those it ramps, and its supports ([`crate::model`] builds
//! them from the case; a case without stages is one). Within a stage every
//! quantity goes linearly with the stage's load factor `t` from where the
//! stage before left it to its value at the stage's end: a load is split
//! into its held part (its value at the stage's start, factor 1) and its
//! ramped part (its change over the stage, factor `t`).

use crate::assembly::PointLoad;
use crate::boundary::face_loads::FaceLoad;
use crate::boundary::ibm::IbmMotion;
use crate::boundary::loading::LoadedStretch;
use crate::boundary::surface_loading::LoadedCells;
use crate::equilibrium::StepSpace;
use crate::particles::Dim;

/// One stage of a run, in `D` dimensions (the boundary's loads and IBM
/// supports are plane strain's: empty in 3D until the B-spline surfaces).
#[derive(Debug, Clone, PartialEq)]
pub struct Stage<const D: usize = 2>
where
    Dim<D>: StepSpace<D>,
{
    /// The case's name for it (`stage k` if it gave none); `None` when the
    /// case has no stages.
    pub name: Option<String>,
    pub load_steps: usize,
    /// Gravity `[held, ramped]` (m/s^2).
    pub gravity: [[f64; D]; 2],
    pub point_loads: Vec<PointLoad<D>>,
    /// Tractions on faces of boxes (3D, until the B-spline surfaces).
    pub face_loads: Vec<FaceLoad<D>>,
    pub boundary_loads: Vec<LoadedStretch>,
    /// Tractions on the run's surface patches (3D).
    pub surface_loads: Vec<LoadedCells>,
    pub grid_supports: Vec<<Dim<D> as StepSpace<D>>::Support>,
    /// Per implicit-boundary support of the run (in the first stage's
    /// order), its motion in this stage, or `None` once released. The
    /// first stage's are the anchors' own and are not read.
    pub ibm: Vec<Option<IbmMotion>>,
    /// The stage's supports (grid and IBM), for reactions.
    pub n_supports: usize,
    /// A geostatic stage's `K0` (`Some(None)`: each material's `nu / (1 -
    /// nu)`): it starts from the overburden stresses and does not move the
    /// points ([`crate::particles::geostatic`]).
    pub geostatic: Option<Option<f64>>,
    /// Whether its load factor is found by the arc-length method (from its
    /// second step on) rather than stepped in equal increments.
    pub arc_length: bool,
    /// A strength-reduction stage's factor steps: its steps are trials
    /// that divide the strengths by a factor ([`crate::reduction`]).
    pub strength_reduction: Option<StrengthReduction>,
}

/// How a strength-reduction stage moves its factor: up by `increment`
/// from 1 until a trial fails, then in halves between the last that held
/// and the first that failed until they are `tolerance` apart.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrengthReduction {
    pub increment: f64,
    pub tolerance: f64,
    /// How far a trial may move the points, per unit of the factor's rise,
    /// as a multiple of their displacement at the stage's start, before it
    /// counts as failed (0: no limit).
    pub flow_limit: f64,
}

/// The stage that holds load step `step` (counted from 1 over the run),
/// and the load steps of the stages before it.
pub fn stage_of<const D: usize>(stages: &[Stage<D>], step: usize) -> (usize, usize)
where
    Dim<D>: StepSpace<D>,
{
    let mut before = 0;
    for (k, s) in stages.iter().enumerate() {
        if step <= before + s.load_steps || k + 1 == stages.len() {
            return (k, before);
        }
        before += s.load_steps;
    }
    (0, 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stage(load_steps: usize) -> Stage {
        Stage {
            name: None,
            load_steps,
            gravity: [[0.0; 2]; 2],
            point_loads: Vec::new(),
            face_loads: Vec::new(),
            surface_loads: Vec::new(),
            boundary_loads: Vec::new(),
            grid_supports: Vec::new(),
            ibm: Vec::new(),
            n_supports: 0,
            geostatic: None,
            arc_length: false,
            strength_reduction: None,
        }
    }

    #[test]
    fn steps_are_numbered_across_stages() {
        let stages = [stage(2), stage(3), stage(1)];
        let found: Vec<_> = (1..=6).map(|s| stage_of(&stages, s)).collect();
        assert_eq!(found, [(0, 0), (0, 0), (1, 2), (1, 2), (1, 2), (2, 5)]);
    }
}
