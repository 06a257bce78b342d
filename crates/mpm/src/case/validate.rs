//! Reading a case in two passes: `serde` for its shape, then the values the
//! types cannot check (signs, ranges, consistency). Every error names its
//! field.

use serde_json::Value;

use super::*;
use crate::geometry::{inside_ring, self_crossing, signed_area};
use crate::grid::REACH_CELLS;
use crate::triangulation;

impl CaseError {
    pub(crate) fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            path: path.into(),
            message: message.into(),
            kind: CaseErrorKind::Invalid,
        }
    }
}

/// The largest magnitude of a number in a case. A modulus of 1e12 Pa, a
/// coordinate of 1e6 m and a pressure of 1e9 Pa are far inside it; a
/// gravity of 1e308 is not, and its forces overflowed to infinity (the job
/// "succeeded" with null reactions). Products of a dozen such numbers stay
/// finite.
pub const MAX_MAGNITUDE: f64 = 1e15;

/// The least a body may measure across, in cells.
const MIN_BODY_CELLS: f64 = 1e-6;

/// A stabilisation key given at its old place in `analysis.newton` and at
/// its new one in `analysis.stabilisation`: the case says two things.
fn given_once(value: &Value) -> Result<(), CaseError> {
    for key in ["ghost_penalty", "tangent_regularisation"] {
        let old = value.pointer(&format!("/analysis/newton/{key}"));
        let new = value.pointer(&format!("/analysis/stabilisation/{key}"));
        if old.is_some() && new.is_some() {
            return Err(CaseError::new(
                format!("analysis.newton.{key}"),
                format!(
                    "has moved to analysis.stabilisation.{key}, which the case also gives: keep that one"
                ),
            ));
        }
    }
    Ok(())
}

/// What serde cannot refuse, found in the JSON tree; the first names its
/// path.
/// - `null`: serde reads it as the field left out, so a case given with
///   nulls would be stored and served with values it does not have.
/// - A NUL character in a string: PostgreSQL's text cannot hold it.
/// - A number beyond [`MAX_MAGNITUDE`].
fn reject_unfit(value: &Value, path: &mut String) -> Result<(), CaseError> {
    let here = |path: &str| {
        if path.is_empty() {
            "$".to_string()
        } else {
            path.to_string()
        }
    };
    match value {
        Value::Null => Err(CaseError::new(
            here(path),
            "null is not a value here: leave the field out for its default",
        )),
        Value::String(s) if s.contains('\0') => Err(CaseError::new(
            here(path),
            "must not contain the NUL character (U+0000)",
        )),
        Value::Number(n) => match n.as_f64() {
            Some(x) if x.abs() <= MAX_MAGNITUDE => Ok(()),
            _ => Err(CaseError::new(
                here(path),
                format!("{n} is out of range: a case's numbers lie within ±{MAX_MAGNITUDE:e}"),
            )),
        },
        Value::Array(items) => items.iter().enumerate().try_for_each(|(i, v)| {
            let len = path.len();
            path.push_str(&format!("[{i}]"));
            let checked = reject_unfit(v, path);
            path.truncate(len);
            checked
        }),
        Value::Object(fields) => fields.iter().try_for_each(|(k, v)| {
            let len = path.len();
            if !path.is_empty() {
                path.push('.');
            }
            path.push_str(k);
            let checked = reject_unfit(v, path);
            path.truncate(len);
            checked
        }),
        _ => Ok(()),
    }
}

/// The case format's version: the one this build reads.
pub(crate) fn check_version(version: u32) -> Result<(), CaseError> {
    if version != CASE_VERSION {
        return Err(CaseError::new(
            "version",
            format!("unsupported case version {version}, this build reads {CASE_VERSION}"),
        ));
    }
    Ok(())
}

/// `analysis.newton`'s tolerance and iterations.
pub(crate) fn check_newton(newton: &NewtonSpec) -> Result<(), CaseError> {
    positive("analysis.newton.tolerance", newton.tolerance)?;
    if newton.max_iterations == 0 {
        return Err(CaseError::new(
            "analysis.newton.max_iterations",
            "must be at least 1",
        ));
    }
    Ok(())
}

/// `analysis.substepping`.
pub(crate) fn check_substepping(sub: &SubsteppingSpec) -> Result<(), CaseError> {
    if !(sub.min_fraction > 0.0 && sub.min_fraction <= 1.0) {
        return Err(CaseError::new(
            "analysis.substepping.min_fraction",
            "must be in (0, 1]",
        ));
    }
    if sub.max_cutbacks > MAX_CUTBACKS {
        return Err(CaseError::new(
            "analysis.substepping.max_cutbacks",
            format!("must be at most {MAX_CUTBACKS}"),
        ));
    }
    Ok(())
}

/// Reads a case of type `T` from JSON text, its shape and what serde cannot
/// refuse (`reject_unfit`), naming the field of the first fault; the values
/// are the type's own `validate`'s. Text that is not JSON (text after the
/// case included) is a [`CaseErrorKind::Syntax`] error.
pub(crate) fn parse<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, CaseError> {
    let mut de = serde_json::Deserializer::from_str(text);
    let case: T = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        // A number beyond f64 is JSON the case cannot hold: name its
        // field. A wrong field can come before a fault that makes the
        // text not JSON at all: such text is malformed, whatever its
        // start says.
        let out_of_range = e.inner().to_string().starts_with("number out of range");
        // Not what serde says of the case: `"geometry": {}` is JSON, whose
        // error serde classifies as syntax ("expected value").
        let syntax = !out_of_range && serde_json::from_str::<Value>(text).is_err();
        let path = match e.path().to_string() {
            p if p.is_empty() || p == "." => "$".to_string(),
            p => p,
        };
        CaseError {
            kind: if syntax {
                CaseErrorKind::Syntax
            } else {
                CaseErrorKind::Invalid
            },
            ..CaseError::new(path, e.into_inner().to_string())
        }
    })?;
    de.end().map_err(|e| CaseError {
        kind: CaseErrorKind::Syntax,
        ..CaseError::new("$", e.to_string())
    })?;
    if let Ok(value) = serde_json::from_str::<Value>(text) {
        reject_unfit(&value, &mut String::new())?;
        given_once(&value)?;
    }
    Ok(case)
}

impl Case {
    /// Parses and validates a case from JSON text ([`parse`], then
    /// [`Case::validate`]).
    pub fn from_json(text: &str) -> Result<Case, CaseError> {
        let case: Case = parse(text)?;
        case.validate()?;
        Ok(case)
    }

    /// Checks values that the types cannot: signs, ranges, consistency.
    pub fn validate(&self) -> Result<(), CaseError> {
        check_version(self.version)?;
        let a = &self.analysis;
        if self.output.every == 0 {
            return Err(CaseError::new("output.every", "must be at least 1"));
        }
        check_newton(&a.newton)?;
        for (key, moved, value) in [
            (
                "ghost_penalty",
                a.newton.ghost_penalty,
                a.stabilisation.ghost_penalty,
            ),
            (
                "tangent_regularisation",
                a.newton.tangent_regularisation,
                a.stabilisation.tangent_regularisation,
            ),
        ] {
            let (path, value) = match moved {
                Some(v) => (format!("analysis.newton.{key}"), v),
                None => (format!("analysis.stabilisation.{key}"), value),
            };
            if !(value >= 0.0 && value.is_finite()) {
                return Err(CaseError::new(path, "must be a finite number, 0 or more"));
            }
        }
        let hourglass = a.stabilisation.hourglass;
        if !(hourglass >= 0.0 && hourglass.is_finite()) {
            return Err(CaseError::new(
                "analysis.stabilisation.hourglass",
                "must be a finite number, 0 or more",
            ));
        }
        check_substepping(&a.substepping)?;
        positive("grid.cell_size", self.grid.cell_size)?;
        finite_pair("grid.origin", self.grid.origin)?;
        if let Some(b) = &self.grid.extent {
            check_box("grid.extent", b)?;
        }
        if self.bodies.is_empty() {
            return Err(CaseError::new("bodies", "at least one body is required"));
        }
        for (i, body) in self.bodies.iter().enumerate() {
            body.validate(&format!("bodies[{i}]"))?;
            self.check_body_on_grid(i, body)?;
        }
        if self.stages.len() > MAX_STAGES {
            return Err(CaseError::new(
                "stages",
                format!("at most {MAX_STAGES} stages"),
            ));
        }
        let views = self.stage_views();
        if !self.stages.is_empty() {
            for (field, given) in [
                ("analysis.load_steps", a.load_steps != 0),
                ("analysis.control", a.control != Control::Load),
                ("loads", self.loads != Loads::default()),
                ("supports", !self.supports.is_empty()),
            ] {
                if given {
                    return Err(CaseError::new(
                        field,
                        "a case with stages gives its load steps, loads and supports in each stage",
                    ));
                }
            }
        }
        for (k, view) in views.iter().enumerate() {
            let stage = &view.path;
            if view.load_steps == 0 {
                let path = if stage.is_empty() {
                    "analysis.load_steps".to_string()
                } else {
                    format!("{stage}load_steps")
                };
                return Err(CaseError::new(path, "must be at least 1"));
            }
            if view.control == Control::ArcLength {
                arc_length(k, views.len(), view, self.stages.get(k))?;
            }
            if let Some(st) = self.stages.get(k) {
                if st.name.as_ref().is_some_and(|n| n.trim().is_empty()) {
                    return Err(CaseError::new(format!("{stage}name"), "must not be empty"));
                }
                if let Some(l) = &st.loads {
                    validate_loads(&format!("{stage}loads"), l)?;
                }
                if let Some(g) = &st.geostatic {
                    geostatic(k, st, g)?;
                }
                if let Some(r) = &st.strength_reduction {
                    let after_geostatic = k > 0 && self.stages[k - 1].geostatic.is_some();
                    strength_reduction(k, views.len(), st, r, after_geostatic)?;
                }
                if let Some(l) = &st.load_increments {
                    validate_loads(&format!("{stage}load_increments"), l)?;
                }
                if let Some(s) = &st.supports {
                    self.validate_supports(&format!("{stage}supports"), s)?;
                }
                if k > 0 {
                    continues_supports(&views[k - 1], view)?;
                }
            } else {
                validate_loads("loads", view.loads)?;
                self.validate_supports("supports", view.supports)?;
            }
        }
        if let Some(b) = self.boundary.band_width {
            positive("boundary.band_width", b)?;
            if b >= self.grid.cell_size {
                return Err(CaseError::new(
                    "boundary.band_width",
                    format!(
                        "must be smaller than the cell size ({}): the band is a thin layer along the boundary",
                        self.grid.cell_size
                    ),
                ));
            }
        }
        let mut names = std::collections::HashSet::new();
        for (i, p) in self.probes.iter().enumerate() {
            if p.name.trim().is_empty() {
                return Err(CaseError::new(
                    format!("probes[{i}].name"),
                    "must not be empty",
                ));
            }
            if !names.insert(p.name.as_str()) {
                return Err(CaseError::new(
                    format!("probes[{i}].name"),
                    format!("duplicate probe name {:?}", p.name),
                ));
            }
            finite_pair(&format!("probes[{i}].at"), p.at)?;
        }
        Ok(())
    }
}

impl Case {
    /// A case's or a stage's supports, their fields under `prefix`.
    fn validate_supports(&self, prefix: &str, supports: &[Support]) -> Result<(), CaseError> {
        for (i, s) in supports.iter().enumerate() {
            s.on.validate(&format!("{prefix}[{i}].on"))?;
            let smooth = matches!(self.basis, BasisKind::Bspline2 | BasisKind::Bspline3);
            if s.method == SupportMethod::Grid && smooth {
                // A B-spline's nodal unknowns are coefficients, not the
                // field's values: fixing the nodes on a line does not fix
                // the field on it (docs/bsplines.md: AMPLE's column at 64
                // cells tops at -1.85 m instead of -25.94 m).
                return Err(CaseError::new(
                    format!("{prefix}[{i}].method"),
                    "the B-spline bases need \"method\": \"ibm\" (grid nodes hold their coefficients, not the field)",
                ));
            }
            if s.method == SupportMethod::Grid && s.fix == Fix::Normal {
                return Err(CaseError::new(
                    format!("{prefix}[{i}].fix"),
                    "normal needs \"method\": \"ibm\"",
                ));
            }
            if s.constraint == Constraint::Averaged && s.method == SupportMethod::Grid {
                return Err(CaseError::new(
                    format!("{prefix}[{i}].constraint"),
                    "an averaged constraint needs \"method\": \"ibm\"",
                ));
            }
            if let Some(d) = s.displacement {
                finite_pair(&format!("{prefix}[{i}].displacement"), d)?;
                if s.method == SupportMethod::Grid {
                    return Err(CaseError::new(
                        format!("{prefix}[{i}].displacement"),
                        "prescribed displacements need \"method\": \"ibm\"",
                    ));
                }
                let free = match s.fix {
                    Fix::X => Some((1, "y")),
                    Fix::Y => Some((0, "x")),
                    Fix::Xy | Fix::Normal => None,
                };
                if let Some((c, name)) = free
                    && d[c] != 0.0
                {
                    return Err(CaseError::new(
                        format!("{prefix}[{i}].displacement"),
                        format!(
                            "the {name} component is not held (fix is not {name} or xy), so it cannot be prescribed"
                        ),
                    ));
                }
            }
            if let Some(r) = s.rotation {
                if !r.angle.is_finite() {
                    return Err(CaseError::new(
                        format!("{prefix}[{i}].rotation.angle"),
                        "must be finite",
                    ));
                }
                finite_pair(&format!("{prefix}[{i}].rotation.center"), r.center)?;
                if s.method == SupportMethod::Grid {
                    return Err(CaseError::new(
                        format!("{prefix}[{i}].rotation"),
                        "prescribed rotations need \"method\": \"ibm\"",
                    ));
                }
                if s.fix != Fix::Xy {
                    return Err(CaseError::new(
                        format!("{prefix}[{i}].rotation"),
                        "a prescribed rotation needs \"fix\": \"xy\" (a roller's wall does not turn)",
                    ));
                }
            }
        }
        Ok(())
    }

    /// A body must start within the node indices' reach of the grid's
    /// origin, which a tiny cell size or a far body exceeds (the run would
    /// stop before its first step with the material off the grid).
    fn check_body_on_grid(&self, i: usize, body: &Body) -> Result<(), CaseError> {
        let (lo, hi) = body.geometry.bounding_box();
        let g = &self.grid;
        let path = format!("bodies[{i}].geometry");
        let reach = g.cell_size * REACH_CELLS;
        let far = (0..2)
            .map(|d| (lo[d] - g.origin[d]).abs().max((hi[d] - g.origin[d]).abs()))
            .fold(0.0, f64::max);
        if far > reach {
            return Err(CaseError::new(
                path,
                format!(
                    "lies {far:.3e} m from grid.origin, beyond the grid's reach of {REACH_CELLS:.0} cells \
                     ({reach:.3e} m at this cell size)"
                ),
            ));
        }
        // A body a millionth of a cell across is no body the grid can see,
        // and its boundary curve's chords vanish (a 5e-324 m wide
        // rectangle's curve was NaN, and its stored step unreadable).
        let across = (hi[0] - lo[0]).min(hi[1] - lo[1]);
        if across.is_nan() || across < MIN_BODY_CELLS * g.cell_size {
            return Err(CaseError::new(
                path,
                format!(
                    "is {across:.3e} m across, less than {MIN_BODY_CELLS:e} of a cell ({} m)",
                    g.cell_size
                ),
            ));
        }
        Ok(())
    }
}

impl Body {
    pub(crate) fn validate(&self, path: &str) -> Result<(), CaseError> {
        let g = format!("{path}.geometry");
        match &self.geometry {
            Geometry::Rectangle {
                min,
                max,
                angle,
                about,
            } => {
                check_box(
                    &format!("{g}.rectangle"),
                    &BoxSpec {
                        min: *min,
                        max: *max,
                    },
                )?;
                if !angle.is_finite() {
                    return Err(CaseError::new(
                        format!("{g}.rectangle.angle"),
                        "must be finite",
                    ));
                }
                if let Some(c) = about {
                    finite_pair(&format!("{g}.rectangle.about"), *c)?;
                }
            }
            Geometry::Polygon { vertices, holes } => {
                // The counts first: the checks below take time quadratic in them.
                if self.points.lattice == Lattice::Body {
                    check_triangulation_size(&format!("{g}.polygon"), vertices, holes)?;
                }
                check_ring(&format!("{g}.polygon.vertices"), vertices)?;
                for (k, h) in holes.iter().enumerate() {
                    check_ring(&format!("{g}.polygon.holes[{k}]"), h)?;
                }
                if self.points.lattice == Lattice::Body {
                    check_triangulation(&format!("{g}.polygon"), vertices, holes)?;
                }
            }
            Geometry::Quadrilateral { vertices } => {
                check_convex_quadrilateral(&format!("{g}.quadrilateral.vertices"), vertices)?
            }
            Geometry::Mesh(mesh) => {
                check_mesh(&format!("{g}.mesh"), mesh)?;
                if self.points.lattice == Lattice::Grid {
                    return Err(CaseError::new(
                        format!("{path}.points.lattice"),
                        "a mesh is filled on its own elements (body)",
                    ));
                }
            }
            Geometry::Circle { center, radius } => {
                finite_pair(&format!("{g}.circle.center"), *center)?;
                positive(&format!("{g}.circle.radius"), *radius)?;
            }
            Geometry::AnnulusSector {
                center,
                inner_radius,
                outer_radius,
                start_angle,
                end_angle,
            } => {
                let g = format!("{g}.annulus_sector");
                check_annulus(&g, *center, *inner_radius, *outer_radius)?;
                let sweep = end_angle - start_angle;
                if !(sweep > 0.0 && sweep < 360.0) {
                    return Err(CaseError::new(
                        format!("{g}.end_angle"),
                        format!(
                            "must exceed start_angle by less than 360 degrees, got a sweep of {sweep}"
                        ),
                    ));
                }
            }
            Geometry::Annulus {
                center,
                inner_radius,
                outer_radius,
            } => check_annulus(
                &format!("{g}.annulus"),
                *center,
                *inner_radius,
                *outer_radius,
            )?,
        }
        let p = &self.points;
        let given = [p.per_cell.is_some(), p.spacing.is_some(), p.count.is_some()];
        if given.iter().filter(|g| **g).count() != 1 {
            return Err(CaseError::new(
                format!("{path}.points"),
                "give exactly one of per_cell, spacing, count",
            ));
        }
        if p.per_cell == Some(0) {
            return Err(CaseError::new(
                format!("{path}.points.per_cell"),
                "must be at least 1",
            ));
        }
        if let Some(s) = p.spacing {
            positive(&format!("{path}.points.spacing"), s)?;
        }
        if let Some(c) = p.count {
            if p.lattice == Lattice::Grid
                || !matches!(
                    self.geometry,
                    Geometry::Rectangle { .. } | Geometry::Quadrilateral { .. }
                )
            {
                return Err(CaseError::new(
                    format!("{path}.points.count"),
                    "only for rectangles and quadrilaterals on their own lattice; use per_cell or spacing",
                ));
            }
            if c[0] == 0 || c[1] == 0 {
                return Err(CaseError::new(
                    format!("{path}.points.count"),
                    "both counts must be at least 1",
                ));
            }
        }
        self.material.validate(&format!("{path}.material"))
    }
}

impl MaterialSpec {
    /// Checks the constants of the material at `m`.
    pub(crate) fn validate(&self, m: &str) -> Result<(), CaseError> {
        let (e, nu, rho) = self.constants();
        positive(&format!("{m}.youngs_modulus"), e)?;
        if !(0.0..0.5).contains(&nu) {
            return Err(CaseError::new(
                format!("{m}.poisson_ratio"),
                format!("must be in [0, 0.5), got {nu}"),
            ));
        }
        if !(rho >= 0.0 && rho.is_finite()) {
            return Err(CaseError::new(
                format!("{m}.density"),
                format!("must be zero or positive, got {rho}"),
            ));
        }
        // Every model named, so that a new one asks here for its checks.
        match *self {
            MaterialSpec::Hencky { .. } | MaterialSpec::LinearElastic { .. } => {}
            MaterialSpec::VonMises {
                yield_stress,
                hardening,
                ..
            } => {
                positive(&format!("{m}.yield_stress"), yield_stress)?;
                if !(hardening >= 0.0 && hardening.is_finite()) {
                    return Err(CaseError::new(
                        format!("{m}.hardening"),
                        format!("must be zero or positive, got {hardening}"),
                    ));
                }
            }
            MaterialSpec::DruckerPrager {
                cohesion,
                friction_angle,
                dilation_angle,
                ..
            }
            | MaterialSpec::MohrCoulomb {
                cohesion,
                friction_angle,
                dilation_angle,
                ..
            } => check_friction(m, cohesion, friction_angle, dilation_angle)?,
        }
        Ok(())
    }
}

/// A frictional model's strength: cohesion, friction and dilation angles.
fn check_friction(
    m: &str,
    cohesion: f64,
    phi: f64,
    dilation_angle: Option<f64>,
) -> Result<(), CaseError> {
    if !(cohesion >= 0.0 && cohesion.is_finite()) || (cohesion == 0.0 && phi == 0.0) {
        return Err(CaseError::new(
            format!("{m}.cohesion"),
            format!("must be zero or positive, and positive without friction, got {cohesion}"),
        ));
    }
    if !(0.0..=MAX_FRICTION_ANGLE).contains(&phi) {
        return Err(CaseError::new(
            format!("{m}.friction_angle"),
            format!("must be in [0, {MAX_FRICTION_ANGLE}] degrees, got {phi}"),
        ));
    }
    if let Some(psi) = dilation_angle
        && !(0.0..=phi).contains(&psi)
    {
        return Err(CaseError::new(
            format!("{m}.dilation_angle"),
            format!("must be in [0, friction_angle = {phi}] degrees, got {psi}"),
        ));
    }
    Ok(())
}

impl Selector {
    fn validate(&self, path: &str) -> Result<(), CaseError> {
        if *self == Selector::default() {
            return Err(CaseError::new(
                path,
                "select something: give x, y, x_between, y_between, segment or center with radius",
            ));
        }
        for (name, v) in [("x", self.x), ("y", self.y)] {
            if let Some(v) = v
                && !v.is_finite()
            {
                return Err(CaseError::new(format!("{path}.{name}"), "must be finite"));
            }
        }
        match (self.center, self.radius) {
            (Some(c), Some(r)) => {
                finite_pair(&format!("{path}.center"), c)?;
                positive(&format!("{path}.radius"), r)?;
            }
            (None, None) => {}
            _ => return Err(CaseError::new(path, "center and radius go together")),
        }
        for (name, r) in [("x_between", self.x_between), ("y_between", self.y_between)] {
            if let Some(r) = r {
                finite_pair(&format!("{path}.{name}"), r)?;
            }
        }
        if let Some([a, b]) = self.segment {
            finite_pair(&format!("{path}.segment[0]"), a)?;
            finite_pair(&format!("{path}.segment[1]"), b)?;
            if a == b {
                return Err(CaseError::new(
                    format!("{path}.segment"),
                    "needs two different end points",
                ));
            }
        }
        Ok(())
    }
}

fn check_annulus(path: &str, center: [f64; 2], inner: f64, outer: f64) -> Result<(), CaseError> {
    finite_pair(&format!("{path}.center"), center)?;
    positive(&format!("{path}.inner_radius"), inner)?;
    if outer.partial_cmp(&inner) != Some(std::cmp::Ordering::Greater) || !outer.is_finite() {
        return Err(CaseError::new(
            format!("{path}.outer_radius"),
            format!("must be greater than inner_radius ({inner}), got {outer}"),
        ));
    }
    Ok(())
}

/// A case's or a stage's loads, their fields under `prefix`.
fn validate_loads(prefix: &str, loads: &Loads) -> Result<(), CaseError> {
    if let Some(g) = loads.gravity {
        finite_pair(&format!("{prefix}.gravity"), g)?;
    }
    for (i, l) in loads.point_loads.iter().enumerate() {
        finite_pair(&format!("{prefix}.point_loads[{i}].at"), l.at)?;
        finite_pair(&format!("{prefix}.point_loads[{i}].force"), l.force)?;
    }
    for (i, l) in loads.boundary.iter().enumerate() {
        let path = format!("{prefix}.boundary[{i}]");
        l.on.validate(&format!("{path}.on"))?;
        match (l.traction, l.pressure) {
            (Some(t), None) => finite_pair(&format!("{path}.traction"), t)?,
            (None, Some(p)) if p.is_finite() => {}
            (None, Some(_)) => {
                return Err(CaseError::new(format!("{path}.pressure"), "must be finite"));
            }
            _ => {
                return Err(CaseError::new(
                    path,
                    "give exactly one of traction, pressure",
                ));
            }
        }
    }
    Ok(())
}

/// An arc-length stage (`k` of `n`; `spec` when the case has stages): the
/// last, with a load to scale, and no support motion (the load factor it
/// finds scales its loads alone).
fn arc_length(
    k: usize,
    n: usize,
    view: &StageView<'_>,
    spec: Option<&StageSpec>,
) -> Result<(), CaseError> {
    let path = if spec.is_some() {
        format!("{}control", view.path)
    } else {
        "analysis.control".to_string()
    };
    if k + 1 < n {
        return Err(CaseError::new(
            path,
            "only the last stage may be arc-length controlled (the load it reaches is not known before it runs)",
        ));
    }
    if spec.is_some_and(|s| s.geostatic.is_some()) {
        return Err(CaseError::new(
            path,
            "a geostatic stage is not arc-length controlled",
        ));
    }
    let loaded = |l: &Loads| {
        l.gravity.is_some_and(|g| g != [0.0, 0.0])
            || !l.point_loads.is_empty()
            || !l.boundary.is_empty()
    };
    let ramps = match spec {
        None => loaded(view.loads),
        Some(s) => {
            s.loads.as_ref().is_some_and(loaded) || s.load_increments.as_ref().is_some_and(loaded)
        }
    };
    if !ramps {
        return Err(CaseError::new(
            path,
            "an arc-length stage needs loads (its own loads or load_increments) for its load factor to scale",
        ));
    }
    let own_supports = spec.is_none_or(|s| s.supports.is_some());
    if own_supports {
        for (i, s) in view.supports.iter().enumerate() {
            let moves = s.displacement.is_some_and(|d| d != [0.0, 0.0])
                || s.rotation.is_some_and(|r| r.angle != 0.0);
            if moves {
                return Err(CaseError::new(
                    format!("{}[{i}]", view.supports_path),
                    "an arc-length stage's supports hold still: the load factor it finds scales its loads, not a prescribed motion",
                ));
            }
        }
    }
    Ok(())
}

/// A strength-reduction stage (`k` of `n`): the last, after a stage that
/// loads the body, holding that stage's loads and supports.
fn strength_reduction(
    k: usize,
    n: usize,
    stage: &StageSpec,
    spec: &StrengthReductionSpec,
    before_is_geostatic: bool,
) -> Result<(), CaseError> {
    let path = format!("stages[{k}].strength_reduction");
    let refuse = |field: String, why: &str| Err(CaseError::new(field, why));
    if k == 0 || k + 1 < n {
        return refuse(
            path,
            "only the last stage of two or more may reduce the strength: a stage before it loads the body, and the run ends when the factor of safety is found",
        );
    }
    for (field, given) in [
        ("loads", stage.loads.is_some()),
        ("load_increments", stage.load_increments.is_some()),
        ("supports", stage.supports.is_some()),
        ("geostatic", stage.geostatic.is_some()),
        ("control", stage.control != Control::Load),
    ] {
        if given {
            return refuse(
                format!("stages[{k}].{field}"),
                "a strength-reduction stage holds the loads and supports of the stage before: it changes the strength alone",
            );
        }
    }
    if !(spec.increment > 0.0 && spec.increment <= 10.0) {
        return refuse(
            format!("{path}.increment"),
            "must be above 0 and at most 10",
        );
    }
    if !(spec.tolerance > 0.0 && spec.tolerance < spec.increment) {
        return refuse(
            format!("{path}.tolerance"),
            "must be above 0 and below the increment",
        );
    }
    if spec.increment / spec.tolerance > 1e6 {
        return refuse(
            format!("{path}.tolerance"),
            "must be at least 1e-6 of the increment (twenty bisections)",
        );
    }
    if !(spec.flow_limit >= 0.0 && spec.flow_limit.is_finite()) {
        return refuse(
            format!("{path}.flow_limit"),
            "must be a finite number, 0 or above (0: no limit)",
        );
    }
    if spec.flow_limit > 0.0 && before_is_geostatic {
        return refuse(
            format!("{path}.flow_limit"),
            "a strength reduction right after a geostatic stage starts with no displacement to measure its trials against: load the body in a stage between them, or set it to 0",
        );
    }
    Ok(())
}

/// A geostatic stage: the first, loaded by vertical gravity alone.
fn geostatic(k: usize, stage: &StageSpec, spec: &GeostaticSpec) -> Result<(), CaseError> {
    let path = format!("stages[{k}].geostatic");
    if k > 0 {
        return Err(CaseError::new(
            path,
            "only the first stage may be geostatic (it sets the stresses from scratch)",
        ));
    }
    if let Some(k0) = spec.k0
        && !(k0 > 0.0 && k0.is_finite())
    {
        return Err(CaseError::new(
            format!("{path}.k0"),
            "must be a finite number above 0",
        ));
    }
    let loads = stage.loads.as_ref();
    let vertical = loads
        .and_then(|l| l.gravity)
        .is_some_and(|g| g[0] == 0.0 && g[1] < 0.0);
    let only_gravity = loads.is_none_or(|l| l.point_loads.is_empty() && l.boundary.is_empty())
        && stage.load_increments.is_none();
    if !(vertical && only_gravity) {
        return Err(CaseError::new(
            path,
            "a geostatic stage's only load is gravity, [0, -g] in its loads",
        ));
    }
    Ok(())
}

/// An implicit-boundary support of a later stage continues one of the
/// stage before: its anchors are laid on the reference curve once, before
/// the first step. A rotation that continues keeps its centre.
fn continues_supports(before: &StageView<'_>, stage: &StageView<'_>) -> Result<(), CaseError> {
    for (i, s) in stage.supports.iter().enumerate() {
        let path = format!("{}[{i}]", stage.supports_path);
        let earlier = before.supports.iter().find(|b| b.same_as(s));
        match earlier {
            None if s.method == SupportMethod::Ibm => {
                return Err(CaseError::new(
                    path,
                    "an implicit-boundary support must continue one of the stage before (the same \
                     on, fix, method and constraint); one that starts later is not supported yet: \
                     give it in the first stage, held still",
                ));
            }
            Some(b) => {
                if let (Some(r0), Some(r1)) = (b.rotation, s.rotation)
                    && r0.center != r1.center
                {
                    return Err(CaseError::new(
                        format!("{path}.rotation.center"),
                        "a support's rotation keeps its centre from stage to stage",
                    ));
                }
            }
            None => {}
        }
    }
    Ok(())
}

pub(crate) fn positive(path: &str, v: f64) -> Result<(), CaseError> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(CaseError::new(
            path,
            format!("must be positive and finite, got {v}"),
        ))
    }
}

fn finite_pair(path: &str, v: [f64; 2]) -> Result<(), CaseError> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(CaseError::new(path, "must be two finite numbers"))
    }
}

fn check_box(path: &str, b: &BoxSpec) -> Result<(), CaseError> {
    finite_pair(&format!("{path}.min"), b.min)?;
    finite_pair(&format!("{path}.max"), b.max)?;
    if b.max[0] > b.min[0] && b.max[1] > b.min[1] {
        Ok(())
    } else {
        Err(CaseError::new(
            format!("{path}.max"),
            format!(
                "must exceed min in both directions (min {:?}, max {:?})",
                b.min, b.max
            ),
        ))
    }
}

fn check_ring(path: &str, ring: &[[f64; 2]]) -> Result<(), CaseError> {
    if ring.len() < 3 {
        return Err(CaseError::new(
            path,
            format!("needs at least 3 vertices, got {}", ring.len()),
        ));
    }
    for (i, v) in ring.iter().enumerate() {
        finite_pair(&format!("{path}[{i}]"), *v)?;
    }
    if signed_area(ring).abs() <= 0.0 {
        return Err(CaseError::new(path, "encloses no area"));
    }
    if ring.len() > MAX_RING_VERTICES {
        return Err(CaseError::new(
            path,
            format!(
                "has {} vertices, more than the {MAX_RING_VERTICES} a ring may have",
                ring.len()
            ),
        ));
    }
    if let Some((i, j)) = self_crossing(ring) {
        return Err(CaseError::new(
            path,
            format!("crosses itself: edges {i} and {j} meet (a polygon must be simple)"),
        ));
    }
    Ok(())
}

/// A mesh of either dimension has at least one element, and at most
/// [`MAX_MESH_NODES`] nodes and elements.
pub(super) fn check_mesh_size(path: &str, nodes: usize, elements: usize) -> Result<(), CaseError> {
    if nodes > MAX_MESH_NODES || elements > MAX_MESH_NODES {
        return Err(CaseError::new(
            path,
            format!("more than {MAX_MESH_NODES} nodes or elements"),
        ));
    }
    if elements == 0 {
        return Err(CaseError::new(
            format!("{path}.elements"),
            "needs at least one element",
        ));
    }
    Ok(())
}

/// A mesh: at most [`MAX_MESH_NODES`] finite nodes; at least one element,
/// each of three or four distinct nodes that exist, enclosing area, a
/// quadrilateral strictly convex; a boundary of closed simple rings; and
/// elements that neither overlap nor leave gaps, which their areas adding
/// up to the area the rings enclose shows.
fn check_mesh(path: &str, mesh: &crate::geometry::Mesh) -> Result<(), CaseError> {
    let nodes = &mesh.nodes;
    check_mesh_size(path, nodes.len(), mesh.elements.len())?;
    for (i, v) in nodes.iter().enumerate() {
        finite_pair(&format!("{path}.nodes[{i}]"), *v)?;
    }
    let (lo, hi) = Geometry::Mesh(crate::geometry::Mesh {
        nodes: nodes.clone(),
        elements: Vec::new(),
    })
    .bounding_box();
    let scale = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let mut total = 0.0;
    for (k, e) in mesh.elements.iter().enumerate() {
        let at = format!("{path}.elements[{k}]");
        if !(3..=4).contains(&e.len()) {
            return Err(CaseError::new(
                at,
                format!("needs 3 or 4 nodes, got {}", e.len()),
            ));
        }
        if let Some(&i) = e.iter().find(|&&i| i >= nodes.len()) {
            return Err(CaseError::new(
                at,
                format!("node {i} does not exist ({} nodes)", nodes.len()),
            ));
        }
        if (0..e.len()).any(|a| (a + 1..e.len()).any(|b| e[a] == e[b])) {
            return Err(CaseError::new(at, "repeats a node"));
        }
        let v: Vec<[f64; 2]> = e.iter().map(|&i| nodes[i]).collect();
        let area = signed_area(&v).abs();
        if area <= 1e-12 * scale * scale {
            return Err(CaseError::new(at, "encloses no area"));
        }
        if e.len() == 4 {
            check_convex_quadrilateral(&at, &[v[0], v[1], v[2], v[3]])?;
        }
        total += area;
    }
    let rings = mesh
        .boundary_rings()
        .map_err(|m| CaseError::new(format!("{path}.elements"), m))?;
    let not_conforming = |m: String| CaseError::new(format!("{path}.elements"), m);
    if rings.len() > MAX_MESH_RINGS {
        return Err(not_conforming(format!(
            "the boundary has {} rings, more than {MAX_MESH_RINGS}",
            rings.len()
        )));
    }
    // Every boundary node at a place of its own: two there mean elements
    // that meet without sharing nodes (an unfused seam, a hanging node).
    let mut places = std::collections::HashSet::new();
    for v in rings.iter().flatten() {
        if !places.insert([v[0].to_bits(), v[1].to_bits()]) {
            return Err(not_conforming(format!(
                "two boundary nodes at ({}, {}): elements meet there without sharing a node",
                v[0], v[1]
            )));
        }
    }
    // Rings that nest as a body's boundary does: an outer ring
    // (counter-clockwise) inside an even number of others, a hole inside
    // an odd number; overlapping elements break it.
    for (k, r) in rings.iter().enumerate() {
        if signed_area(r).abs() <= 1e-12 * scale * scale {
            return Err(not_conforming(format!(
                "a boundary ring through ({}, {}) encloses no area",
                r[0][0], r[0][1]
            )));
        }
        let depth = (rings.iter().enumerate())
            .filter(|&(j, o)| j != k && inside_ring(o, r[0]))
            .count();
        if (depth % 2 == 0) != (signed_area(r) > 0.0) {
            return Err(not_conforming(format!(
                "elements overlap: the boundary through ({}, {}) lies inside another",
                r[0][0], r[0][1]
            )));
        }
    }
    let enclosed: f64 = rings.iter().map(|r| signed_area(r)).sum();
    if (total - enclosed).abs() > 1e-9 * total {
        return Err(CaseError::new(
            format!("{path}.elements"),
            format!(
                "elements overlap: their areas add up to {total}, their boundary encloses {enclosed}"
            ),
        ));
    }
    Ok(())
}

/// A polygon filled on its own lattice has at most
/// [`triangulation::MAX_VERTICES`] vertices, its holes' included.
fn check_triangulation_size(
    path: &str,
    outer: &[[f64; 2]],
    holes: &[Vec<[f64; 2]>],
) -> Result<(), CaseError> {
    let n = outer.len() + holes.iter().map(Vec::len).sum::<usize>();
    if n > triangulation::MAX_VERTICES {
        return Err(CaseError::new(
            format!("{path}.vertices"),
            format!(
                "has {n} vertices with its holes, more than the {} a polygon on its own lattice \
                 may have; give a mesh, or points.lattice: grid",
                triangulation::MAX_VERTICES
            ),
        ));
    }
    Ok(())
}

/// A polygon filled on its own lattice is cut into triangles first: at most
/// [`triangulation::MAX_VERTICES`] vertices (holes' included), and its
/// holes must lie inside it and apart, which the triangles' areas adding
/// up to the polygon's (less the holes') shows.
fn check_triangulation(
    path: &str,
    outer: &[[f64; 2]],
    holes: &[Vec<[f64; 2]>],
) -> Result<(), CaseError> {
    check_triangulation_size(path, outer, holes)?;
    let holes_area: f64 = holes.iter().map(|h| signed_area(h).abs()).sum();
    let exact = signed_area(outer).abs() - holes_area;
    let covered = triangulation::triangulate(outer, holes).map(|t| {
        t.iter()
            .map(|[a, b, c]| ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / 2.0)
            .sum::<f64>()
    });
    let inside = holes
        .iter()
        .all(|h| h.iter().all(|&v| inside_ring(outer, v)));
    match covered {
        Some(area) if inside && (area - exact).abs() <= 1e-9 * signed_area(outer).abs() => Ok(()),
        _ => Err(CaseError::new(
            format!("{path}.holes"),
            "every hole must lie inside the polygon, apart from the other holes and its edge",
        )),
    }
}

/// A quadrilateral's vertices must be finite and make a strictly convex
/// quadrilateral, in order (either orientation), so that its bilinear map
/// is one-to-one: every turn the same way, none straight.
fn check_convex_quadrilateral(path: &str, v: &[[f64; 2]; 4]) -> Result<(), CaseError> {
    for (i, p) in v.iter().enumerate() {
        finite_pair(&format!("{path}[{i}]"), *p)?;
    }
    let size = (0..4)
        .map(|k| (v[(k + 1) % 4][0] - v[k][0]).hypot(v[(k + 1) % 4][1] - v[k][1]))
        .fold(0.0, f64::max);
    let turns: Vec<f64> = (0..4)
        .map(|k| {
            let (a, b, c) = (v[k], v[(k + 1) % 4], v[(k + 2) % 4]);
            (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0])
        })
        .collect();
    let tiny = 1e-9 * size * size;
    let all = |f: fn(f64, f64) -> bool| turns.iter().all(|&t| f(t, tiny));
    if !(size.is_finite() && size > 0.0 && (all(|t, e| t > e) || all(|t, e| t < -e))) {
        return Err(CaseError::new(
            path,
            "must be the corners of a strictly convex quadrilateral, in order round it \
             (no straight or reflex corner, no crossing edges)",
        ));
    }
    Ok(())
}

/// Failed sub-increments a load step may allow: each costs up to a Newton
/// solve.
const MAX_CUTBACKS: u32 = 1000;

/// The most stages a case may list: each costs a selection of every
/// boundary load and support on the seeded bodies.
const MAX_STAGES: usize = 100;

/// The steepest friction angle taken (degrees): past it the cone's
/// plane-strain match grows as `tan(phi)` and soils do not reach it.
const MAX_FRICTION_ANGLE: f64 = 70.0;

/// Vertices a polygon's ring may have: the simplicity check is quadratic in
/// them (5e7 edge pairs at this size, a fraction of a second).
const MAX_RING_VERTICES: usize = 10_000;

/// The most nodes (and elements) a mesh body may have.
const MAX_MESH_NODES: usize = 1_000_000;

/// The most boundary rings (outer boundaries and holes) a mesh may have.
const MAX_MESH_RINGS: usize = 1000;
