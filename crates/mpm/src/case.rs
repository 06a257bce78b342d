//! The case format (JSON, version 1): what a user submits.
//!
//! Parsing happens in two passes. `serde` with `deny_unknown_fields` catches
//! shape errors (a missing field, a typo, a string where a number belongs) and
//! `serde_path_to_error` names where they are; [`Case::validate`] then checks
//! the values (positive moduli, Poisson's ratio in `[0, 0.5)`, non-empty
//! geometry). Every error names the field path, e.g.
//! `bodies[0].material.poisson_ratio: must be in [0, 0.5), got 0.5`.
//!
//! All quantities are SI: metres, pascals, kg/m^3, newtons per metre of
//! out-of-plane thickness (plane strain).

use serde::{Deserialize, Serialize};

/// The only case-format version this build reads.
pub const CASE_VERSION: u32 = 1;

/// A complete analysis: geometry, material, grid, loads, supports.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// Case-format version; must be 1.
    pub version: u32,
    /// Free-text title shown in summaries.
    #[serde(default)]
    pub title: Option<String>,
    pub analysis: Analysis,
    pub grid: GridSpec,
    /// Shape functions of the background grid.
    #[serde(default)]
    pub basis: BasisKind,
    pub bodies: Vec<Body>,
    #[serde(default)]
    pub loads: Loads,
    /// Supports on grid nodes chosen geometrically.
    #[serde(default)]
    pub supports: Vec<Support>,
    /// Named reference points advected with the grid displacement.
    #[serde(default)]
    pub probes: Vec<Probe>,
    /// Where the boundary curve runs.
    #[serde(default)]
    pub boundary: BoundarySpec,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    #[serde(default)]
    pub representation: Representation,
    /// Width `delta` (m) of the band inside the boundary over which the
    /// implicit boundary method's D-functions rise from 0 to 1. Default
    /// 1% of the cell size (see `boundary::ibm`).
    #[serde(default)]
    pub band_width: Option<f64>,
}

/// Where the boundary curve's data points are.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum Representation {
    /// On the material's edge: each outer point pushed out to the edge of
    /// its domain (half a spacing), mapped by its deformation gradient.
    #[default]
    Edge,
    /// Through the outer material points themselves (the paper's choice),
    /// half a point spacing inside the material's edge.
    Points,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum AnalysisKind {
    #[default]
    PlaneStrain,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Analysis {
    /// Only `plane_strain` for now.
    #[serde(default, rename = "type")]
    pub kind: AnalysisKind,
    /// Number of equal load increments; every load is ramped linearly.
    pub load_steps: u32,
    #[serde(default)]
    pub newton: NewtonSpec,
}

/// Newton-Raphson controls.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct NewtonSpec {
    /// Converged when the out-of-balance force norm over the free degrees of
    /// freedom, relative to the external (or internal, if larger) force norm,
    /// falls below this. Default 1e-9.
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// Iteration cap per load step; reaching it fails the job. Default 30.
    #[serde(default = "default_max_iterations")]
    pub max_iterations: u32,
    /// Stiffness of the soft background added to the tangent over the
    /// cells the material touches, relative to the stiffest material
    /// (default 1e-6; 0 turns it off). It keeps the solve regular when a
    /// point alone reaches new nodes; the converged answer does not depend on
    /// it.
    #[serde(default = "default_tangent_regularisation")]
    pub tangent_regularisation: f64,
}

fn default_tolerance() -> f64 {
    1e-9
}
fn default_max_iterations() -> u32 {
    30
}
fn default_tangent_regularisation() -> f64 {
    1e-6
}

impl Default for NewtonSpec {
    fn default() -> Self {
        Self {
            tolerance: default_tolerance(),
            max_iterations: default_max_iterations(),
            tangent_regularisation: default_tangent_regularisation(),
        }
    }
}

/// The background grid: square cells of side `cell_size` with a node at
/// `origin`. The lattice is unbounded unless `extent` is given; either way
/// only the nodes that the material touches enter the system, so a large
/// extent costs nothing.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    pub cell_size: f64,
    #[serde(default)]
    pub origin: [f64; 2],
    /// Where the mesh ends, as a finite mesh would: nodes outside do not
    /// exist (shape functions are cut there) and material leaving it stops
    /// the run. Default: unbounded.
    #[serde(default)]
    pub extent: Option<BoxSpec>,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    pub min: [f64; 2],
    pub max: [f64; 2],
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum BasisKind {
    /// Bilinear finite-element hat functions (the paper's choice).
    #[default]
    Linear,
    /// Generalised interpolation MPM with the point domain following the
    /// stretch of the point (cpGIMP-style, axis-aligned domain).
    Gimp,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Body {
    #[serde(default)]
    pub name: Option<String>,
    pub geometry: Geometry,
    pub points: PointFill,
    pub material: MaterialSpec,
}

/// The region a body fills, in the reference configuration.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Geometry {
    Rectangle {
        min: [f64; 2],
        max: [f64; 2],
    },
    /// A simple polygon (either orientation) with optional polygonal holes.
    Polygon {
        vertices: Vec<[f64; 2]>,
        #[serde(default)]
        holes: Vec<Vec<[f64; 2]>>,
    },
    Circle {
        center: [f64; 2],
        radius: f64,
    },
    Annulus {
        center: [f64; 2],
        inner_radius: f64,
        outer_radius: f64,
    },
    /// The part of an annulus between two angles (degrees, counter-clockwise
    /// from +x, less than a full turn apart), filled on a polar lattice so
    /// that its arcs are rows of points.
    AnnulusSector {
        center: [f64; 2],
        inner_radius: f64,
        outer_radius: f64,
        start_angle: f64,
        end_angle: f64,
    },
}

/// How densely a body is filled with material points: exactly one of
/// `per_cell` (points per cell per direction), `spacing` (metres) or `count`
/// (`[nx, ny]`, rectangles only).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct PointFill {
    #[serde(default)]
    pub per_cell: Option<u32>,
    #[serde(default)]
    pub spacing: Option<f64>,
    #[serde(default)]
    pub count: Option<[u32; 2]>,
}

/// Constitutive model of a body.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(tag = "model", rename_all = "snake_case", deny_unknown_fields)]
pub enum MaterialSpec {
    /// Finite-strain elasticity: Hencky strain of the elastic left
    /// Cauchy-Green tensor, Kirchhoff stress linear in it.
    Hencky {
        youngs_modulus: f64,
        poisson_ratio: f64,
        density: f64,
    },
    /// Geometrically linear small-strain elasticity, for checks against
    /// linear theory.
    LinearElastic {
        youngs_modulus: f64,
        poisson_ratio: f64,
        density: f64,
    },
}

impl MaterialSpec {
    /// `(youngs_modulus, poisson_ratio, density)`.
    pub fn constants(&self) -> (f64, f64, f64) {
        match *self {
            MaterialSpec::Hencky {
                youngs_modulus,
                poisson_ratio,
                density,
            }
            | MaterialSpec::LinearElastic {
                youngs_modulus,
                poisson_ratio,
                density,
            } => (youngs_modulus, poisson_ratio, density),
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct Loads {
    /// Gravitational acceleration (m/s^2), e.g. `[0, -9.81]`.
    #[serde(default)]
    pub gravity: Option<[f64; 2]>,
    #[serde(default)]
    pub point_loads: Vec<PointLoad>,
    /// Loads on the boundary curve, ramped with the load factor.
    #[serde(default)]
    pub boundary: Vec<BoundaryLoad>,
}

/// A load on the stretch of boundary that `on` selects in the reference
/// configuration: exactly one of a dead `traction` `[tx, ty]` (Pa) or a
/// follower `pressure` (Pa, positive pushes into the material, normal to
/// the current boundary).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BoundaryLoad {
    pub on: Selector,
    #[serde(default)]
    pub traction: Option<[f64; 2]>,
    #[serde(default)]
    pub pressure: Option<f64>,
}

/// A dead force (N per metre thickness) carried by the material point
/// nearest to `at` in the reference configuration.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PointLoad {
    pub at: [f64; 2],
    pub force: [f64; 2],
}

/// Zero displacement on the grid nodes that `on` selects.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Support {
    pub on: Selector,
    pub fix: Fix,
    /// How the condition is imposed (default `grid`).
    #[serde(default)]
    pub method: SupportMethod,
    /// Prescribed displacement `[ux, uy]` (m) reached at the last load step,
    /// ramped with the load factor; only its held components count.
    /// Implicit boundary method only. Default zero.
    #[serde(default)]
    pub displacement: Option<[f64; 2]>,
    /// Prescribed rotation of the selected boundary about a point, on top
    /// of `displacement`, its angle ramped with the load factor. Implicit
    /// boundary method only.
    #[serde(default)]
    pub rotation: Option<Rotation>,
}

/// A rigid rotation of the boundary it applies to.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Rotation {
    /// Counter-clockwise angle in degrees at the last load step.
    pub angle: f64,
    /// Centre (m), in the reference configuration.
    pub center: [f64; 2],
}

/// Where a support acts.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum SupportMethod {
    /// On the grid nodes that the selector contains (AMPLE's way): exact
    /// when the boundary lies on grid lines.
    #[default]
    Grid,
    /// The implicit boundary method on the boundary curve the selector
    /// picks: works for boundaries anywhere in the grid, at any angle.
    Ibm,
}

/// Which displacement components a support holds.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Fix {
    /// Horizontal displacement held (a roller on a wall normal to x).
    X,
    /// Vertical displacement held (a roller on a floor normal to y).
    Y,
    /// Both held.
    Xy,
    /// The component normal to the boundary held (a roller on a boundary at
    /// any angle, or curved). Implicit boundary method only.
    Normal,
}

impl Fix {
    /// Whether a grid support holds Cartesian component `component`.
    pub fn holds(self, component: usize) -> bool {
        matches!((self, component), (Fix::Xy, _) | (Fix::X, 0) | (Fix::Y, 1))
    }
}

/// A geometric selection in the reference configuration: every given
/// condition must hold. `{"x": 0}` is the line x = 0; add
/// `"y_between": [0, 2]` for a segment of it; `x_between` with `y_between`
/// is a box.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct Selector {
    #[serde(default)]
    pub x: Option<f64>,
    #[serde(default)]
    pub y: Option<f64>,
    #[serde(default)]
    pub x_between: Option<[f64; 2]>,
    #[serde(default)]
    pub y_between: Option<[f64; 2]>,
    /// With `radius`: on the circle of that radius about `center`.
    #[serde(default)]
    pub center: Option<[f64; 2]>,
    #[serde(default)]
    pub radius: Option<f64>,
    /// On the straight segment between these two points: a side at any
    /// angle.
    #[serde(default)]
    pub segment: Option<[[f64; 2]; 2]>,
}

impl Selector {
    /// Whether `p` is selected; `tol` is the distance that counts as "on" a
    /// line or inside a range.
    pub fn contains(&self, p: [f64; 2], tol: f64) -> bool {
        let on = |v: Option<f64>, c: f64| v.is_none_or(|v| (c - v).abs() <= tol);
        let within = |r: Option<[f64; 2]>, c: f64| {
            r.is_none_or(|[a, b]| c >= a.min(b) - tol && c <= a.max(b) + tol)
        };
        let on_circle = match (self.center, self.radius) {
            (Some(c), Some(r)) => {
                (((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt() - r).abs() <= tol
            }
            _ => true,
        };
        let on_segment = self.segment.is_none_or(|[a, b]| {
            let (d, r) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
            let t = ((r[0] * d[0] + r[1] * d[1]) / (d[0] * d[0] + d[1] * d[1])).clamp(0.0, 1.0);
            (r[0] - t * d[0]).hypot(r[1] - t * d[1]) <= tol
        });
        on(self.x, p[0])
            && on(self.y, p[1])
            && within(self.x_between, p[0])
            && within(self.y_between, p[1])
            && on_circle
            && on_segment
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Probe {
    pub name: String,
    pub at: [f64; 2],
}

/// A case that could not be read: where, and what was expected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{path}: {message}")]
pub struct CaseError {
    /// Field path such as `bodies[0].material.poisson_ratio`; `$` for the
    /// document itself.
    pub path: String,
    pub message: String,
}

impl CaseError {
    fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            path: path.into(),
            message: message.into(),
        }
    }
}

impl Case {
    /// Parses and validates a case from JSON text.
    pub fn from_json(text: &str) -> Result<Case, CaseError> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let case: Case = serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let path = if path == "." || path.is_empty() {
                "$".to_string()
            } else {
                path
            };
            CaseError::new(path, e.into_inner().to_string())
        })?;
        case.validate()?;
        Ok(case)
    }

    /// Checks values that the types cannot: signs, ranges, consistency.
    pub fn validate(&self) -> Result<(), CaseError> {
        if self.version != CASE_VERSION {
            return Err(CaseError::new(
                "version",
                format!(
                    "unsupported case version {}, this build reads {CASE_VERSION}",
                    self.version
                ),
            ));
        }
        let a = &self.analysis;
        if a.load_steps == 0 {
            return Err(CaseError::new("analysis.load_steps", "must be at least 1"));
        }
        positive("analysis.newton.tolerance", a.newton.tolerance)?;
        if a.newton.max_iterations == 0 {
            return Err(CaseError::new(
                "analysis.newton.max_iterations",
                "must be at least 1",
            ));
        }
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
        }
        if let Some(g) = self.loads.gravity {
            finite_pair("loads.gravity", g)?;
        }
        for (i, l) in self.loads.point_loads.iter().enumerate() {
            finite_pair(&format!("loads.point_loads[{i}].at"), l.at)?;
            finite_pair(&format!("loads.point_loads[{i}].force"), l.force)?;
        }
        for (i, l) in self.loads.boundary.iter().enumerate() {
            let path = format!("loads.boundary[{i}]");
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
        for (i, s) in self.supports.iter().enumerate() {
            s.on.validate(&format!("supports[{i}].on"))?;
            if s.method == SupportMethod::Grid && s.fix == Fix::Normal {
                return Err(CaseError::new(
                    format!("supports[{i}].fix"),
                    "normal needs \"method\": \"ibm\"",
                ));
            }
            if let Some(d) = s.displacement {
                finite_pair(&format!("supports[{i}].displacement"), d)?;
                if s.method == SupportMethod::Grid {
                    return Err(CaseError::new(
                        format!("supports[{i}].displacement"),
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
                        format!("supports[{i}].displacement"),
                        format!(
                            "the {name} component is not held (fix is not {name} or xy), so it cannot be prescribed"
                        ),
                    ));
                }
            }
            if let Some(r) = s.rotation {
                if !r.angle.is_finite() {
                    return Err(CaseError::new(
                        format!("supports[{i}].rotation.angle"),
                        "must be finite",
                    ));
                }
                finite_pair(&format!("supports[{i}].rotation.center"), r.center)?;
                if s.method == SupportMethod::Grid {
                    return Err(CaseError::new(
                        format!("supports[{i}].rotation"),
                        "prescribed rotations need \"method\": \"ibm\"",
                    ));
                }
                if s.fix != Fix::Xy {
                    return Err(CaseError::new(
                        format!("supports[{i}].rotation"),
                        "a prescribed rotation needs \"fix\": \"xy\" (a roller's wall does not turn)",
                    ));
                }
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
        for (i, p) in self.probes.iter().enumerate() {
            if p.name.trim().is_empty() {
                return Err(CaseError::new(
                    format!("probes[{i}].name"),
                    "must not be empty",
                ));
            }
            if self.probes[..i].iter().any(|q| q.name == p.name) {
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

impl Body {
    fn validate(&self, path: &str) -> Result<(), CaseError> {
        let g = format!("{path}.geometry");
        match &self.geometry {
            Geometry::Rectangle { min, max } => check_box(
                &format!("{g}.rectangle"),
                &BoxSpec {
                    min: *min,
                    max: *max,
                },
            )?,
            Geometry::Polygon { vertices, holes } => {
                check_ring(&format!("{g}.polygon.vertices"), vertices)?;
                for (k, h) in holes.iter().enumerate() {
                    check_ring(&format!("{g}.polygon.holes[{k}]"), h)?;
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
            if !matches!(self.geometry, Geometry::Rectangle { .. }) {
                return Err(CaseError::new(
                    format!("{path}.points.count"),
                    "only for rectangles; use per_cell or spacing",
                ));
            }
            if c[0] == 0 || c[1] == 0 {
                return Err(CaseError::new(
                    format!("{path}.points.count"),
                    "both counts must be at least 1",
                ));
            }
        }
        let m = format!("{path}.material");
        let (e, nu, rho) = self.material.constants();
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
        Ok(())
    }
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

fn positive(path: &str, v: f64) -> Result<(), CaseError> {
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
    if crate::fill::signed_area(ring).abs() <= 0.0 {
        return Err(CaseError::new(path, "encloses no area"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn column_json() -> serde_json::Value {
        serde_json::from_str(crate::examples::get("column").unwrap()).unwrap()
    }

    fn error_for(v: serde_json::Value) -> CaseError {
        Case::from_json(&v.to_string()).unwrap_err()
    }

    #[test]
    fn built_in_examples_parse() {
        for name in crate::examples::NAMES {
            Case::from_json(crate::examples::get(name).unwrap()).unwrap();
        }
    }

    #[test]
    fn poisson_ratio_of_one_half_names_the_field() {
        let mut v = column_json();
        v["bodies"][0]["material"]["poisson_ratio"] = 0.5.into();
        let e = error_for(v);
        assert_eq!(e.path, "bodies[0].material.poisson_ratio");
        assert!(e.message.contains("[0, 0.5)"), "{e}");
    }

    #[test]
    fn unknown_field_names_its_parent() {
        let mut v = column_json();
        v["bodies"][0]["material"]["youngs_modulos"] = 1.0.into();
        let e = error_for(v);
        assert_eq!(e.path, "bodies[0].material");
        assert!(e.message.contains("youngs_modulos"), "{e}");
    }

    #[test]
    fn negative_modulus_and_wrong_types_are_rejected_with_paths() {
        let mut v = column_json();
        v["bodies"][0]["material"]["youngs_modulus"] = (-1.0).into();
        assert_eq!(error_for(v).path, "bodies[0].material.youngs_modulus");
        let mut v = column_json();
        v["grid"]["cell_size"] = "big".into();
        assert_eq!(error_for(v).path, "grid.cell_size");
        let mut v = column_json();
        v["bodies"] = serde_json::json!([]);
        assert_eq!(error_for(v).path, "bodies");
    }

    #[test]
    fn empty_geometry_is_rejected() {
        let mut v = column_json();
        v["bodies"][0]["geometry"] =
            serde_json::json!({"rectangle": {"min": [0, 0], "max": [0, 1]}});
        assert_eq!(error_for(v).path, "bodies[0].geometry.rectangle.max");
    }

    #[test]
    fn a_radius_without_a_center_is_rejected() {
        // Otherwise the circle condition would be ignored and the selector
        // would pick everything.
        let mut v = column_json();
        v["supports"][0]["on"] = serde_json::json!({"radius": 1.0});
        let e = error_for(v);
        assert_eq!(e.path, "supports[0].on");
        assert!(e.message.contains("center and radius"), "{e}");
    }

    #[test]
    fn selector_matches_segments_and_lines() {
        let s = Selector {
            x: Some(0.0),
            y_between: Some([0.0, 2.0]),
            ..Default::default()
        };
        assert!(s.contains([0.0, 1.0], 1e-9));
        assert!(s.contains([1e-12, 2.0], 1e-9));
        assert!(!s.contains([0.0, 2.1], 1e-9));
        assert!(!s.contains([0.1, 1.0], 1e-9));
    }

    #[test]
    fn segment_selector_measures_distance_to_the_segment() {
        let s = Selector {
            segment: Some([[0.0, 0.0], [1.0, 1.0]]),
            ..Default::default()
        };
        assert!(s.contains([0.5, 0.5], 1e-9));
        assert!(s.contains([0.5, 0.6], 0.08)); // 0.0707 from the line
        assert!(!s.contains([0.5, 0.6], 0.06));
        assert!(!s.contains([1.1, 1.1], 0.1)); // beyond the end: 0.141
    }

    #[test]
    fn ibm_only_options_and_unheld_components_are_rejected_with_paths() {
        let set = |f: &dyn Fn(&mut serde_json::Value)| {
            let mut v = column_json();
            f(&mut v);
            error_for(v)
        };
        let e = set(&|v| v["supports"][0]["fix"] = "normal".into());
        assert_eq!(e.path, "supports[0].fix");
        let e = set(&|v| v["supports"][0]["displacement"] = serde_json::json!([0.1, 0.0]));
        assert_eq!(e.path, "supports[0].displacement");
        assert!(e.message.contains("ibm"), "{e}");
        // fix x: a y displacement is not held.
        let e = set(&|v| {
            v["supports"][0]["method"] = "ibm".into();
            v["supports"][0]["displacement"] = serde_json::json!([0.0, 0.1]);
        });
        assert_eq!(e.path, "supports[0].displacement");
        assert!(e.message.contains("y component"), "{e}");
        let e = set(&|v| {
            v["supports"][0]["method"] = "ibm".into();
            v["supports"][0]["rotation"] = serde_json::json!({"angle": 5.0, "center": [0, 0]});
        });
        assert_eq!(e.path, "supports[0].rotation");
        let e = set(&|v| v["boundary"] = serde_json::json!({"band_width": 10.0}));
        assert_eq!(e.path, "boundary.band_width");
        assert!(e.message.contains("cell size"), "{e}");
    }
}
