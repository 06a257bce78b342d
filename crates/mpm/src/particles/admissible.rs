//! What a point's trial state must be for Newton to accept it, and for a
//! load step to be kept: the point loop asks it of every point at every
//! trial, so that a step which inverts, explodes or breaks a point is
//! halved by the line search and, failing that, cut.
//!
//! A trial state is admissible when
//! - its Jacobian `J = J_start det(dF)` is positive (the point is not
//!   inverted);
//! - the step changes its volume by less than [`MAX_STEP_VOLUME_RATIO`]
//!   either way (`1 / r < det(dF) < r`);
//! - its stress, `P` and history are finite numbers;
//! - the return map met the model's own flow rule
//!   ([`Response::off_flow_rule`]).

use crate::material::{APEX_SEPARATION, Response, Response3};

/// The largest factor by which one load step may grow or shrink a point's
/// volume. A soil changes volume by its elastic strain (`p / K`, a few
/// percent at the stresses of a footing) and its dilatancy (`tan(psi)`
/// times the step's plastic shear); a compressible elastic column squeezed
/// by half in one step (`hard_cases.rs`) shrinks its base points by about
/// that. A point four times or a quarter of its volume after one step is
/// broken, not deformed: a lone point over an edge cell, pulled by nodes
/// that nothing else holds (the explosions this guards against reach
/// `J = 1e6`).
pub const MAX_STEP_VOLUME_RATIO: f64 = 4.0;

/// Why a point's trial state is not admissible.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Inadmissible {
    /// `J <= 0` (or not a number).
    Inverted,
    /// The step changes its volume by more than [`MAX_STEP_VOLUME_RATIO`].
    VolumeJump,
    /// Its stress, `P` or history is not a finite number.
    NonFinite,
    /// The return map left the flow rule: a trial past the apex of a
    /// frictional model that opens by more than its dilation takes and
    /// [`APEX_SEPARATION`] of separation (`psi = 0` with the point pulled
    /// apart).
    OffFlowRule,
}

impl std::fmt::Display for Inadmissible {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Inadmissible::Inverted => f.write_str("inverted"),
            Inadmissible::VolumeJump => write!(
                f,
                "changed volume by more than a factor of {MAX_STEP_VOLUME_RATIO} in one step"
            ),
            Inadmissible::NonFinite => f.write_str("has a non-finite stress"),
            Inadmissible::OffFlowRule => write!(
                f,
                "was pulled open past its yield surface's apex by more than {}% of its volume \
                 in one step beyond what its flow rule (its dilation angle) takes",
                100.0 * APEX_SEPARATION
            ),
        }
    }
}

/// A point whose trial state is not admissible.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InadmissiblePoint {
    pub point: usize,
    /// Its trial Jacobian.
    pub jacobian: f64,
    pub reason: Inadmissible,
}

/// Point `point`'s volume at a trial: admissible when each of `jacobians`
/// (`J_start` times the step's `det(dF)`, one per volume the point's
/// response sees: F-bar's cell average beside its own) is positive and
/// within [`MAX_STEP_VOLUME_RATIO`] of `j_start`.
pub fn check_volume(
    point: usize,
    j_start: f64,
    jacobians: &[f64],
) -> Result<(), InadmissiblePoint> {
    for &jacobian in jacobians {
        let reason = if jacobian.is_nan() || jacobian <= 0.0 {
            Inadmissible::Inverted
        } else if !(jacobian / j_start).is_finite()
            || jacobian > MAX_STEP_VOLUME_RATIO * j_start
            || jacobian * MAX_STEP_VOLUME_RATIO < j_start
        {
            Inadmissible::VolumeJump
        } else {
            continue;
        };
        return Err(InadmissiblePoint {
            point,
            jacobian,
            reason,
        });
    }
    Ok(())
}

/// What [`check_response`] reads of a model's response, in either
/// dimension.
pub trait TrialResponse {
    /// Its stress, `P` and history are finite numbers.
    fn is_finite(&self) -> bool;
    /// [`Response::off_flow_rule`].
    fn off_flow_rule(&self) -> bool;
}

impl TrialResponse for Response {
    fn is_finite(&self) -> bool {
        self.p.iter().all(|x| x.is_finite())
            && self.cauchy.plane.iter().all(|x| x.is_finite())
            && self.cauchy.zz.is_finite()
            && self.history.tensor.iter().all(|x| x.is_finite())
            && self.history.zz.is_finite()
            && self.history.plastic_strain.is_finite()
    }

    fn off_flow_rule(&self) -> bool {
        self.off_flow_rule
    }
}

impl TrialResponse for Response3 {
    fn is_finite(&self) -> bool {
        self.p.iter().all(|x| x.is_finite())
            && self.cauchy.iter().all(|x| x.is_finite())
            && self.history.tensor.iter().all(|x| x.is_finite())
            && self.history.plastic_strain.is_finite()
    }

    fn off_flow_rule(&self) -> bool {
        self.off_flow_rule
    }
}

/// Point `point`'s response at a trial whose volume passed
/// [`check_volume`] (`jacobian` its own): admissible when its numbers are
/// finite and its return met the flow rule.
pub fn check_response<R: TrialResponse>(
    point: usize,
    jacobian: f64,
    response: R,
) -> Result<R, InadmissiblePoint> {
    let reason = if !response.is_finite() {
        Inadmissible::NonFinite
    } else if response.off_flow_rule() {
        Inadmissible::OffFlowRule
    } else {
        return Ok(response);
    };
    Err(InadmissiblePoint {
        point,
        jacobian,
        reason,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_volume_is_admissible_within_a_factor_of_four_of_the_steps_start() {
        assert!(check_volume(3, 0.5, &[0.5, 0.126, 1.99]).is_ok());
        for (j, reason) in [
            (0.0, Inadmissible::Inverted),
            (-0.1, Inadmissible::Inverted),
            (f64::NAN, Inadmissible::Inverted),
            (2.01, Inadmissible::VolumeJump),
            (0.124, Inadmissible::VolumeJump),
            (f64::INFINITY, Inadmissible::VolumeJump),
        ] {
            let e = check_volume(3, 0.5, &[0.5, j]).unwrap_err();
            assert_eq!((e.point, e.reason), (3, reason), "{j}");
        }
    }

    /// In 3D as in plane strain: a Mohr-Coulomb point without dilation
    /// pulled open past its apex is off its flow rule, one with a
    /// non-finite stress is not finite, and a point compressed past yield
    /// is admissible.
    #[test]
    fn three_dimensional_responses_are_checked_as_plane_strain_ones() {
        use crate::material::{Elastic, History3, Material, MohrCoulomb};
        use nalgebra::Matrix3;
        let soil = Material::MohrCoulomb(MohrCoulomb {
            elastic: Elastic::from_young_poisson(1e7, 0.3),
            cohesion: 1e3,
            friction: 30f64.to_radians(),
            dilation: 0.0,
        });
        let virgin = History3::virgin();
        let opened = soil.respond_3d(&virgin, &(Matrix3::identity() * 0.02), 1.0);
        let e = check_response(7, 1.06, opened).unwrap_err();
        assert_eq!((e.point, e.reason), (7, Inadmissible::OffFlowRule));
        let squeezed = Matrix3::new(-0.01, 0.002, 0.0, 0.0, 0.003, 0.0, 0.001, 0.0, -0.002);
        let yielded = soil.respond_3d(&virgin, &squeezed, 1.0);
        assert!(yielded.history.plastic_strain > 0.0);
        assert!(check_response(7, 0.99, yielded).is_ok());
        let mut broken = yielded;
        broken.cauchy[(2, 1)] = f64::NAN;
        let e = check_response(7, 0.99, broken).unwrap_err();
        assert_eq!(e.reason, Inadmissible::NonFinite);
    }
}
