//! The document of one finished load step: its report, the material points
//! and the boundary curves. `mpm run` writes it as `steps/step_NNNN.json`,
//! the service stores its parts and serves it at `GET /jobs/{id}/steps/{k}`.

use mpm::case::OutputSpec;
use mpm::case::solid::SolidOutput;
use mpm::report::{PointColumns, SolidPointColumns};
use mpm::{SolidStepState, StepReport, StepState};
use serde::Serialize;
use serde_json::value::{RawValue, to_raw_value};

/// The step document's shape. Its parts are the solver's values where they
/// are written (`mpm run`) and their JSON text where stored and served.
#[derive(Debug, Serialize)]
pub struct StepDocument<R, P, B> {
    /// `mpm::StepReport`
    pub report: R,
    /// `mpm::report::PointColumns`
    pub points: P,
    /// `[mpm::boundary::BoundaryOutput]`, or in 3D
    /// `[mpm::boundary::face_patches::SurfaceOutput]`
    pub boundaries: B,
}

/// A step document as stored: each part as JSON text, served as it is.
pub type StoredStep = StepDocument<Box<RawValue>, Box<RawValue>, Box<RawValue>>;

impl StoredStep {
    /// The stored form of a step the solver has just finished (or step 0):
    /// with its points (the columns `output` asks for) and boundary curves
    /// if `output` stores them at this step of `load_steps`, else with
    /// `null` for both.
    pub fn new(
        report: &StepReport,
        state: &StepState<'_>,
        output: &OutputSpec,
        load_steps: usize,
    ) -> Self {
        let stores_points = output.stores_points(report.step, load_steps);
        let report = to_raw_value(report).expect("reports serialise");
        if !stores_points {
            let null = || RawValue::from_string("null".into()).expect("null is JSON");
            return Self {
                report,
                points: null(),
                boundaries: null(),
            };
        }
        let fields = mpm::model::point_fields(output);
        let columns = PointColumns::selected(state.points, fields.as_deref());
        Self {
            report,
            points: to_raw_value(&columns).expect("points serialise"),
            boundaries: to_raw_value(&state.boundaries()).expect("boundaries serialise"),
        }
    }

    /// The stored form of a 3D run's step: its points (every column) and
    /// its bodies' surfaces (`SurfaceOutput`: the B-spline patches) if
    /// `output` stores them at this step, else `null` for both.
    pub fn solid(report: &StepReport, state: &SolidStepState<'_>, output: &SolidOutput) -> Self {
        let load_steps = state.load_steps();
        let raw = |text: &str| RawValue::from_string(text.into()).expect("JSON");
        let stores_points = output.stores_points(report.step, load_steps);
        let report = to_raw_value(report).expect("reports serialise");
        if !stores_points {
            return Self {
                report,
                points: raw("null"),
                boundaries: raw("null"),
            };
        }
        Self {
            report,
            points: to_raw_value(&SolidPointColumns::new(state.points)).expect("points serialise"),
            boundaries: to_raw_value(&state.surfaces()).expect("surfaces serialise"),
        }
    }

    /// Whether the points were stored with this step.
    pub fn has_points(&self) -> bool {
        self.points.get() != "null"
    }

    /// Reads back the stored parts.
    pub fn from_text(
        report: String,
        points: String,
        boundaries: String,
    ) -> serde_json::Result<Self> {
        Ok(Self {
            report: RawValue::from_string(report)?,
            points: RawValue::from_string(points)?,
            boundaries: RawValue::from_string(boundaries)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stored_step_is_served_as_its_parts_as_stored() {
        let report = r#"{"step":1,"load_factor":0.5}"#;
        let points = r#"{"position":[[0.0,1.5]]}"#;
        let stored =
            StoredStep::from_text(report.into(), points.into(), "[]".into()).expect("JSON");
        assert_eq!(
            serde_json::to_string(&stored).unwrap(),
            format!(r#"{{"report":{report},"points":{points},"boundaries":[]}}"#)
        );
    }
}
