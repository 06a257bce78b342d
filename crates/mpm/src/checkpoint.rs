//! Saving a run between load steps and resuming it.
//!
//! A [`crate::Simulation`] is built from its case the same way every time, so a
//! checkpoint holds only what load steps change: the material points'
//! positions, deformation gradients (their volumes follow as `det F V0`),
//! constitutive history, yield flags and stress; the probes' positions;
//! the IBM anchors' displacements; the step-size and arc-length controls
//! and the last increment (Newton's predictor) carried between steps. The boundary loops, found once before any step, are kept
//! to check against: a solver that finds them differently refuses it. Restoring it into a simulation built
//! from the same case and running on gives the run that was never stopped.
//!
//! The encoding is postcard (little-endian, variable-length integers):
//! about 130 bytes a material point. A fingerprint of the seeded points,
//! the load steps and the supports and probes guards against restoring a
//! checkpoint into another case.

use serde::{Deserialize, Serialize};

use crate::boundary::BoundaryLoop;
use crate::report::Settled;

/// The encoding's version: a checkpoint of another one is refused (5:
/// the points' history holds `b - I` and `b_zz - 1` where 4 held `b`; 6:
/// the points' stress slopes; 7: F-bar's carried pressures; 8: the cell
/// mean's carried stresses, and F-bar's carried as departures from the
/// points' own; 9: the strength reduction's displacement scale and movement).
pub(crate) const FORMAT: u32 = 9;

/// The state of a run after `steps_done` load steps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    pub(crate) format: u32,
    pub(crate) fingerprint: u64,
    pub(crate) steps_done: usize,
    pub(crate) position: Vec<[f64; 2]>,
    /// `F` column-major: `[F00, F10, F01, F11]`.
    pub(crate) deformation: Vec<[f64; 4]>,
    pub(crate) history: Vec<HistoryState>,
    pub(crate) yielding: Vec<bool>,
    /// `[xx, yy, xy, zz]`.
    pub(crate) stress: Vec<[f64; 4]>,
    /// The stress slopes of the points that have them (those seeded one a
    /// cell or fewer), by point.
    pub(crate) stress_slopes: Vec<(u32, [f64; 6])>,
    /// With F-bar, what each point carries of its mean pressure to the
    /// next step (`MaterialPoints::fbar_pressure`); empty otherwise.
    pub(crate) fbar_pressure: Vec<f64>,
    /// With the cell-mean strain, what each point carries to the next step
    /// (`MaterialPoints::cell_mean_stress`), column-major; empty otherwise.
    pub(crate) cell_mean_stress: Vec<[f64; 4]>,
    pub(crate) probes: Vec<[f64; 2]>,
    pub(crate) anchors_moved: Vec<[f64; 2]>,
    pub(crate) loops: Vec<LoopState>,
    pub(crate) step_size: StepSizeState,
    /// The arc-length control, once an arc-length stage has begun.
    pub(crate) arc: Option<ArcControlState>,
    /// The last converged increment of the stage's load-factor steps, which
    /// the next one's Newton starts from: `(node keys, displacements,
    /// change of load factor)`.
    pub(crate) last_increment: Option<IncrementState>,
    /// The strength reduction, once its stage has begun: the largest
    /// factor that held, the smallest that failed with the factor it was
    /// tried from, and `[scale, travelled]`: the points' displacement at
    /// the stage's start that trials' movement is measured against, and
    /// how far the trials that held moved them.
    pub(crate) reduction: Option<(f64, Option<[f64; 2]>, [f64; 2])>,
    /// What the last step reported of its state (reactions, tractions).
    pub(crate) settled: Option<Settled>,
}

/// The encoding's version of a 3D run's checkpoint ([`SolidCheckpoint`]),
/// apart from the plane-strain ones so that neither reads as the other.
pub(crate) const SOLID_FORMAT: u32 = 3002;

/// The state of a 3D run after `steps_done` load steps: the points'
/// positions, deformation gradients, histories, yield flags and stresses,
/// the step-size control, Newton's predictor, and what the last step
/// reported, and the surface supports' anchors' displacements. A 3D run
/// has no probes, arc length or strength reduction yet.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolidCheckpoint {
    pub(crate) format: u32,
    pub(crate) fingerprint: u64,
    pub(crate) steps_done: usize,
    pub(crate) position: Vec<[f64; 3]>,
    /// `F`, column-major.
    pub(crate) deformation: Vec<[f64; 9]>,
    /// `b - I` (the small strain for linear elasticity), column-major, and
    /// the accumulated plastic strain.
    pub(crate) history: Vec<([f64; 9], f64)>,
    pub(crate) yielding: Vec<bool>,
    /// Cauchy stress, column-major.
    pub(crate) stress: Vec<[f64; 9]>,
    /// With F-bar, the pressures the points carry into the next step
    /// (`MaterialPoints::fbar_pressure`); empty otherwise.
    pub(crate) fbar_pressure: Vec<f64>,
    /// With the cell mean, the stresses the points carry into the next
    /// step (`MaterialPoints::cell_mean_stress`), column-major; empty
    /// otherwise.
    pub(crate) cell_mean_stress: Vec<[f64; 9]>,
    pub(crate) step_size: StepSizeState,
    pub(crate) last_increment: Option<IncrementState>,
    pub(crate) settled: Option<Settled>,
    /// Each surface anchor's displacement since the reference
    /// configuration (`SurfaceAnchor::moved`).
    #[serde(default)]
    pub(crate) surface_anchors_moved: Vec<[f64; 3]>,
}

impl SolidCheckpoint {
    /// Load steps done when it was taken; a resumed run goes on with the next.
    pub fn steps_done(&self) -> usize {
        self.steps_done
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        postcard::to_stdvec(self).expect("a checkpoint holds only numbers and vectors")
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<Self, CheckpointError> {
        let checkpoint: SolidCheckpoint =
            postcard::from_bytes(bytes).map_err(|e| CheckpointError::Unreadable(e.to_string()))?;
        if checkpoint.format != SOLID_FORMAT {
            return Err(CheckpointError::Unreadable(format!(
                "format {} (this solver reads {SOLID_FORMAT} for 3D runs)",
                checkpoint.format
            )));
        }
        Ok(checkpoint)
    }
}

/// The arc-length control between steps: `[length, first length, load
/// factor]`, easy steps in a row, and the last increment `(node keys,
/// displacements, change of load factor)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct ArcControlState {
    pub(crate) arc: [f64; 3],
    pub(crate) easy_in_a_row: usize,
    pub(crate) last: Option<IncrementState>,
}

/// A converged increment: `(node keys, displacements, change of load
/// factor)`.
pub(crate) type IncrementState = (Vec<u64>, Vec<f64>, f64);

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct HistoryState {
    pub(crate) tensor: [f64; 4],
    pub(crate) zz: f64,
    pub(crate) plastic_strain: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct LoopState {
    pub(crate) body: usize,
    pub(crate) points: Vec<usize>,
    pub(crate) hole: bool,
    pub(crate) offset: Vec<[f64; 2]>,
}

impl LoopState {
    pub(crate) fn of(l: &BoundaryLoop) -> Self {
        Self {
            body: l.body,
            points: l.points.clone(),
            hole: l.hole,
            offset: l.offset.clone(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct StepSizeState {
    pub(crate) size: f64,
    pub(crate) easy_in_a_row: usize,
    pub(crate) clean_steps: usize,
    pub(crate) wait: usize,
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CheckpointError {
    #[error("not a checkpoint this solver can read: {0}")]
    Unreadable(String),
    #[error("the checkpoint belongs to another case ({0} differ)")]
    OtherCase(&'static str),
}

impl Checkpoint {
    /// Load steps done when it was taken; a resumed run goes on with the next.
    pub fn steps_done(&self) -> usize {
        self.steps_done
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        postcard::to_stdvec(self).expect("a checkpoint holds only numbers and vectors")
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<Self, CheckpointError> {
        let checkpoint: Checkpoint =
            postcard::from_bytes(bytes).map_err(|e| CheckpointError::Unreadable(e.to_string()))?;
        if checkpoint.format != FORMAT {
            return Err(CheckpointError::Unreadable(format!(
                "format {} (this solver reads {FORMAT})",
                checkpoint.format
            )));
        }
        Ok(checkpoint)
    }
}
