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

pub mod builtin;
pub mod solid;
mod validate;

use serde::{Deserialize, Serialize};

pub use crate::geometry::{Geometry, Selector};
use crate::settings::{NewtonSettings, Substepping};
use solid::SolidCase;

/// The only case-format version this build reads.
pub const CASE_VERSION: u32 = 1;

/// A complete analysis: geometry, material, grid, loads, supports.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
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
    /// Supports: on the grid nodes or, by the implicit boundary method, on
    /// the boundary curve that each selects.
    #[serde(default)]
    pub supports: Vec<Support>,
    /// Stages run one after another, each with its own load steps, loads
    /// and supports (then the case has no top-level `loads`, `supports` or
    /// `analysis.load_steps`). Without stages the case is one stage.
    #[serde(default)]
    pub stages: Vec<StageSpec>,
    /// Named reference points advected with the grid displacement.
    #[serde(default)]
    pub probes: Vec<Probe>,
    /// Where the boundary curve runs.
    #[serde(default)]
    pub boundary: BoundarySpec,
    /// Which steps' material points are stored, and which of their columns.
    #[serde(default)]
    pub output: OutputSpec,
}

/// The case format's JSON Schema (draft 2020-12), derived from the types
/// below: what `GET /schema/case.json` serves and clients validate against.
/// It checks shapes and names; [`Case::validate`] checks the values.
pub fn json_schema() -> serde_json::Value {
    use serde_json::{Value, json};
    let settings = schemars::generate::SchemaSettings::draft2020_12();
    let (plane, mut defs) = split_root(&settings, "$defs", |g| g.into_root_schema_for::<Case>());
    let (solid, solid_defs) = split_root(&settings, "$defs", |g| {
        g.into_root_schema_for::<SolidCase>()
    });
    merge_definitions(&mut defs, solid_defs);
    defs.insert("Case".into(), plane);
    defs.insert("SolidCase".into(), solid);
    let mut schema = json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "Case",
        "description": "A plane-strain case, or a 3D one when analysis.type is \"3d\"",
        "type": "object",
        "if": {
            "type": "object",
            "required": ["analysis"],
            "properties": {
                "analysis": {
                    "type": "object",
                    "required": ["type"],
                    "properties": { "type": { "const": "3d" } }
                }
            }
        },
        "then": { "$ref": "#/$defs/SolidCase" },
        "else": { "$ref": "#/$defs/Case" },
        "$defs": Value::Object(defs),
    });
    no_nulls(&mut schema);
    schema
}

/// The root schema a generator with `settings` makes (`root`), without its
/// `$schema` and its definitions, and the definitions (kept under `defs`:
/// `$defs`, or `components` / `schemas` for OpenAPI).
fn split_root(
    settings: &schemars::generate::SchemaSettings,
    defs: &str,
    root: impl FnOnce(schemars::SchemaGenerator) -> schemars::Schema,
) -> (
    serde_json::Value,
    serde_json::Map<String, serde_json::Value>,
) {
    use serde_json::Value;
    let Value::Object(mut schema) = root(settings.clone().into_generator()).to_value() else {
        unreachable!("a struct's schema is an object")
    };
    schema.remove("$schema");
    let definitions = match schema.remove(defs) {
        Some(Value::Object(mut components)) if defs == "components" => {
            match components.remove("schemas") {
                Some(Value::Object(schemas)) => schemas,
                _ => serde_json::Map::new(),
            }
        }
        Some(Value::Object(definitions)) => definitions,
        _ => serde_json::Map::new(),
    };
    (Value::Object(schema), definitions)
}

/// Adds `more` to `defs`. The two case formats share types (materials,
/// the basis, Newton's settings) by name, so a name both hold must be the
/// same schema.
fn merge_definitions(
    defs: &mut serde_json::Map<String, serde_json::Value>,
    more: serde_json::Map<String, serde_json::Value>,
) {
    for (name, schema) in more {
        let kept = defs.entry(name.clone()).or_insert_with(|| schema.clone());
        assert_eq!(*kept, schema, "two schemas named {name}");
    }
}

/// A case takes no `null` (a field left out takes its default, and
/// [`Case::from_json`] refuses a null), so its schemas allow none:
/// schemars writes an `Option` as `type: [T, "null"]`, or as an `anyOf`
/// with a null branch, and a schema-driven client (schemathesis) sent
/// `band_width: null`, which the server refused.
fn no_nulls(schema: &mut serde_json::Value) {
    use serde_json::Value;
    match schema {
        Value::Object(map) => {
            if let Some(Value::Array(types)) = map.get_mut("type") {
                types.retain(|t| t != "null");
                if let [only] = types.as_slice() {
                    let only = only.clone();
                    map.insert("type".into(), only);
                }
            }
            if map.get("default") == Some(&Value::Null) {
                map.remove("default");
            }
            for key in ["anyOf", "oneOf"] {
                let Some(Value::Array(branches)) = map.get_mut(key) else {
                    continue;
                };
                branches.retain(|b| b.get("type") != Some(&Value::from("null")));
                if branches.len() == 1 {
                    let Some(Value::Object(only)) = branches.pop() else {
                        continue;
                    };
                    map.remove(key);
                    for (k, v) in only {
                        map.entry(k).or_insert(v);
                    }
                }
            }
            map.values_mut().for_each(no_nulls);
        }
        Value::Array(items) => items.iter_mut().for_each(no_nulls),
        _ => {}
    }
}

/// The case format as OpenAPI 3.0 schemas: `Case` and every type it uses,
/// by name, referring to each other as `#/components/schemas/NAME`.
pub fn openapi_schemas() -> serde_json::Map<String, serde_json::Value> {
    let settings = schemars::generate::SchemaSettings::openapi3();
    let (plane, mut schemas) = split_root(&settings, "components", |g| {
        g.into_root_schema_for::<Case>()
    });
    let (solid, solid_schemas) = split_root(&settings, "components", |g| {
        g.into_root_schema_for::<SolidCase>()
    });
    merge_definitions(&mut schemas, solid_schemas);
    schemas.insert("Case".into(), plane);
    schemas.insert("SolidCase".into(), solid);
    for schema in schemas.values_mut() {
        no_nulls(schema);
        to_openapi_3_0(schema);
    }
    schemas
}

/// Rewrites the JSON Schema keywords OpenAPI 3.0 lacks in its own terms,
/// in `schema` and its subschemas: `const: v` becomes `enum: [v]`, and
/// `type: [T, "null"]` becomes `type: T, nullable: true`.
fn to_openapi_3_0(schema: &mut serde_json::Value) {
    use serde_json::Value;
    match schema {
        Value::Object(map) => {
            if let Some(value) = map.remove("const") {
                map.insert("enum".into(), Value::Array(vec![value]));
            }
            if let Some(Value::Array(types)) = map.get("type") {
                let named: Vec<Value> = types.iter().filter(|t| *t != "null").cloned().collect();
                if named.len() == 1 && types.len() == 2 {
                    map.insert("type".into(), named[0].clone());
                    map.insert("nullable".into(), Value::Bool(true));
                }
            }
            map.values_mut().for_each(to_openapi_3_0);
        }
        Value::Array(items) => items.iter_mut().for_each(to_openapi_3_0),
        _ => {}
    }
}

/// What a run stores of its steps (the CLI's files, the service's rows).
/// Step reports (Newton, probes, reactions) are kept for every step; the
/// material points and boundary curves for step 0 (the undeformed state),
/// every `every`-th step and the last.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Store the points every this many load steps (default 1: every step).
    #[serde(default = "default_every")]
    pub every: u32,
    /// The point columns to store (default: all); `position` is always
    /// stored.
    #[serde(default)]
    pub fields: Option<Vec<PointField>>,
}

/// A column of the points' output, as `output.fields` names it.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PointField {
    Position,
    Displacement,
    Stress,
    Volume,
    Jacobian,
    Body,
    PlasticStrain,
    Yielding,
}

fn default_every() -> u32 {
    1
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            every: default_every(),
            fields: None,
        }
    }
}

impl OutputSpec {
    /// Whether step `step` of `load_steps` stores its points.
    pub fn stores_points(&self, step: usize, load_steps: usize) -> bool {
        stores_points_every(self.every, step, load_steps)
    }

    /// How many of the steps 0..=load_steps store their points.
    pub fn point_steps(&self, load_steps: usize) -> usize {
        point_steps_every(self.every, load_steps)
    }
}

/// Whether step `step` of `load_steps` stores its points when they are
/// stored `every` steps: step 0, the multiples of `every`, and the last.
pub(crate) fn stores_points_every(every: u32, step: usize, load_steps: usize) -> bool {
    step == 0 || step == load_steps || step.is_multiple_of(every.max(1) as usize)
}

/// How many of the steps 0..=load_steps store their points, every `every`.
pub(crate) fn point_steps_every(every: u32, load_steps: usize) -> usize {
    let every = every.max(1) as usize;
    // Step 0, the multiples of `every`, and the last if it is not one.
    1 + load_steps / every + usize::from(!load_steps.is_multiple_of(every))
}

/// Where the boundary curve's data points are.
#[derive(
    Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default, schemars::JsonSchema,
)]
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

/// Which lattice a body's points sit on.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Lattice {
    /// The body's own: rectangles and quadrilaterals mapped, sectors,
    /// circles and annuli polar, polygons cut into triangles and each
    /// triangle into three mapped quadrilaterals. The points' cells tile
    /// the body and its edges are rows of points.
    #[default]
    Body,
    /// The grid's, for any shape: the sites of a square lattice aligned
    /// with the grid that fall inside, each the volume of its square; a
    /// slanted or curved edge is a staircase.
    Grid,
}

/// Which displacement components a support holds.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
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

/// A rigid rotation of the boundary it applies to.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Rotation {
    /// Counter-clockwise angle in degrees at the last load step.
    pub angle: f64,
    /// Centre (m), in the reference configuration.
    pub center: [f64; 2],
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    #[serde(default)]
    pub representation: Representation,
    /// Width `delta` (m) of the band inside the boundary over which the
    /// implicit boundary method's D-functions rise from 0 to 1. Default
    /// [`crate::boundary::ibm::DEFAULT_BAND_WIDTH`] cells (a hundredth).
    #[serde(default)]
    pub band_width: Option<f64>,
}

#[derive(
    Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum AnalysisKind {
    #[default]
    PlaneStrain,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Analysis {
    /// Only `plane_strain` for now.
    #[serde(default, rename = "type")]
    pub kind: AnalysisKind,
    /// Number of equal load increments; every load is ramped linearly.
    /// Required unless the case has `stages`, each with its own.
    #[serde(default)]
    pub load_steps: u32,
    #[serde(default)]
    pub newton: NewtonSpec,
    #[serde(default)]
    pub stabilisation: StabilisationSpec,
    #[serde(default)]
    pub substepping: SubsteppingSpec,
    /// How a point's deformation enters its stress: its own (`standard`),
    /// its volume change the average of its cell's (`fbar`, against
    /// volumetric locking), or its whole strain increment the average of
    /// its cell's (`cell_mean`, against locking by incompressibility and by
    /// dilatancy, with a small hourglass stiffness).
    #[serde(default)]
    pub volumetric: Volumetric,
    /// How the load factor moves from step to step (default `load`); with
    /// `stages`, each stage gives its own.
    #[serde(default)]
    pub control: Control,
}

/// How a stage's load factor moves from step to step.
#[derive(
    Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Control {
    /// Equal increments: step `k` of `n` is at load factor `k / n`.
    #[default]
    Load,
    /// The arc-length method: the first step is at `1 / n`, and each after
    /// it moves the displacements by as much as the first did, the load
    /// factor found with them, so the load may pass a peak and fall. Its
    /// supports prescribe no motion; the last stage only.
    ArcLength,
}

#[derive(
    Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Volumetric {
    #[default]
    Standard,
    Fbar,
    CellMean,
}

/// Cutting a load step's increment when Newton fails on it: the failed
/// increment is retried in halves from the last converged state. The load
/// steps stay the output steps.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SubsteppingSpec {
    /// The smallest sub-increment, as a fraction of the step's increment
    /// (default 1/1024); 1 turns cutting off.
    #[serde(default = "default_min_fraction")]
    pub min_fraction: f64,
    /// Failed tries allowed in one load step (default 40).
    #[serde(default = "default_max_cutbacks")]
    pub max_cutbacks: u32,
}

fn default_min_fraction() -> f64 {
    Substepping::default().min_fraction
}
fn default_max_cutbacks() -> u32 {
    Substepping::default().max_cutbacks as u32
}

impl Default for SubsteppingSpec {
    fn default() -> Self {
        Self {
            min_fraction: default_min_fraction(),
            max_cutbacks: default_max_cutbacks(),
        }
    }
}

/// Newton-Raphson controls.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NewtonSpec {
    /// Converged when the out-of-balance force norm over the free degrees of
    /// freedom, relative to the external (or internal, if larger) force norm,
    /// falls below this. Default: [`NewtonSettings`]'s.
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// Iteration cap per load step; reaching it fails the job. Default:
    /// [`NewtonSettings`]'s.
    #[serde(default = "default_max_iterations")]
    pub max_iterations: u32,
    /// Deprecated: read as `analysis.stabilisation.tangent_regularisation`,
    /// where it has moved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangent_regularisation: Option<f64>,
    /// Search along each Newton direction, cutting steps that do not reduce
    /// the out-of-balance force or that invert a point (default true).
    #[serde(default = "default_line_search")]
    pub line_search: bool,
    /// Start each increment from the last converged one, scaled to its
    /// change of load factor, when that leaves less out-of-balance force
    /// than no displacement (default true). Past yield it saves most of
    /// the iterations: from no displacement the first tangent is the
    /// elastic one.
    #[serde(default = "default_predictor")]
    pub predictor: bool,
    /// Deprecated: read as `analysis.stabilisation.ghost_penalty`, where it
    /// has moved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ghost_penalty: Option<f64>,
}

/// Stabilisation of each step's tangent where the material reaches a cell
/// only in part.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StabilisationSpec {
    /// Ghost penalty on the faces of the cells at the material's edge,
    /// relative to twice the largest shear modulus (default:
    /// [`NewtonSettings`]'s, 1e-3; 0 turns it off).
    #[serde(default = "default_ghost_penalty")]
    pub ghost_penalty: f64,
    /// Stiffness of the soft background over the cells the material
    /// touches, relative to the stiffest material (default:
    /// [`NewtonSettings`]'s, 0: off). It keeps the solve regular when a
    /// point alone reaches new nodes, and stiffens each step's increment by
    /// a relative amount of its size.
    #[serde(default = "default_tangent_regularisation")]
    pub tangent_regularisation: f64,
    /// With `analysis.volumetric: cell_mean`, the stiffness against the
    /// points' departures from their cell's mean strain, relative to twice
    /// the material's shear modulus (default: [`NewtonSettings`]'s, 1e-2).
    /// Larger is easier for Newton and stronger in collapse.
    #[serde(default = "default_hourglass")]
    pub hourglass: f64,
    /// Give each point of a body seeded one point a cell or fewer the
    /// bending stiffness its domain has (Belytschko & Bindeman's physical
    /// hourglass stabilisation, with the material's own moduli; default
    /// true). One point cannot hold a cell's hourglass modes: without it
    /// such a body bends far too easily. Bodies of two or more points a
    /// cell are untouched.
    #[serde(default = "default_lone_points")]
    pub lone_points: bool,
}

impl Default for StabilisationSpec {
    fn default() -> Self {
        Self {
            ghost_penalty: default_ghost_penalty(),
            tangent_regularisation: default_tangent_regularisation(),
            hourglass: default_hourglass(),
            lone_points: default_lone_points(),
        }
    }
}

impl Analysis {
    /// The stabilisation the run uses: `stabilisation`'s, or a key still
    /// given at its old place in `newton` ([`Case::from_json`] refuses a
    /// case that gives a key in both).
    pub fn stabilisation_settings(&self) -> StabilisationSpec {
        StabilisationSpec {
            ghost_penalty: self
                .newton
                .ghost_penalty
                .unwrap_or(self.stabilisation.ghost_penalty),
            tangent_regularisation: self
                .newton
                .tangent_regularisation
                .unwrap_or(self.stabilisation.tangent_regularisation),
            hourglass: self.stabilisation.hourglass,
            lone_points: self.stabilisation.lone_points,
        }
    }
}

fn default_tolerance() -> f64 {
    NewtonSettings::default().tolerance
}
fn default_max_iterations() -> u32 {
    NewtonSettings::default().max_iterations as u32
}
fn default_tangent_regularisation() -> f64 {
    NewtonSettings::default().tangent_regularisation
}
pub(crate) fn default_ghost_penalty() -> f64 {
    NewtonSettings::default().ghost_penalty
}
pub(crate) fn default_hourglass() -> f64 {
    NewtonSettings::default().hourglass
}
fn default_lone_points() -> bool {
    NewtonSettings::default().lone_points
}
fn default_line_search() -> bool {
    NewtonSettings::default().line_search
}
fn default_predictor() -> bool {
    NewtonSettings::default().predictor
}

impl Default for NewtonSpec {
    fn default() -> Self {
        Self {
            tolerance: default_tolerance(),
            max_iterations: default_max_iterations(),
            tangent_regularisation: None,
            line_search: default_line_search(),
            predictor: default_predictor(),
            ghost_penalty: None,
        }
    }
}

/// The background grid: square cells of side `cell_size` with a node at
/// `origin`. The lattice is unbounded unless `extent` is given; either way
/// only the nodes that the material touches enter the system, so a large
/// extent costs nothing.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
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

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    pub min: [f64; 2],
    pub max: [f64; 2],
}

#[derive(
    Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum BasisKind {
    /// Bilinear finite-element hat functions (the paper's choice).
    #[default]
    Linear,
    /// Generalised interpolation MPM: the hats averaged over each point's
    /// own cell, an upright one following the point's stretch (cpGIMP), a
    /// turned, mapped or polar one carried by its deformation gradient.
    Gimp,
    /// Uniform quadratic B-splines on the grid (C1), averaged over each
    /// point's own cell as GIMP averages the hats (4 x 4 nodes a point).
    Bspline2,
    /// Uniform cubic B-splines on the grid (C2), averaged likewise (5 x 5
    /// nodes a point).
    Bspline3,
}

impl BasisKind {
    /// Every basis, in order of cost.
    pub const ALL: [BasisKind; 4] = [
        BasisKind::Linear,
        BasisKind::Gimp,
        BasisKind::Bspline2,
        BasisKind::Bspline3,
    ];
}

/// Its name in a case's `basis`, as the case format spells it.
impl std::fmt::Display for BasisKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match serde_json::to_value(self) {
            Ok(serde_json::Value::String(name)) => f.pad(&name),
            _ => unreachable!("a basis serialises as its name"),
        }
    }
}

impl std::str::FromStr for BasisKind {
    type Err = String;

    /// A basis by its name in the case format.
    fn from_str(name: &str) -> Result<Self, String> {
        serde_json::from_value(serde_json::Value::String(name.to_string())).map_err(|_| {
            let names: Vec<String> = Self::ALL.iter().map(ToString::to_string).collect();
            format!("{name:?} is not a basis: one of {}", names.join(", "))
        })
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Body {
    #[serde(default)]
    pub name: Option<String>,
    pub geometry: Geometry,
    pub points: PointFill,
    pub material: MaterialSpec,
}

/// How densely a body is filled with material points: exactly one of
/// `per_cell` (points per cell per direction), `spacing` (metres) or `count`
/// (`[nx, ny]`, rectangles and quadrilaterals only); and on which lattice.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PointFill {
    #[serde(default)]
    pub per_cell: Option<u32>,
    #[serde(default)]
    pub spacing: Option<f64>,
    #[serde(default)]
    pub count: Option<[u32; 2]>,
    /// `body` (default): the body's own lattice, whose rows follow its
    /// edges; `grid`: the grid's square lattice, for any shape.
    #[serde(default)]
    pub lattice: Lattice,
}

/// Constitutive model of a body.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
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
    /// Finite-strain J2 (von Mises) plasticity on Hencky elasticity, with
    /// linear isotropic hardening: yield at `sigma_y + H alpha` in the von
    /// Mises equivalent Kirchhoff stress (plane-strain shear strength
    /// `sigma_y / sqrt(3)`).
    VonMises {
        youngs_modulus: f64,
        poisson_ratio: f64,
        density: f64,
        /// Initial uniaxial yield stress `sigma_y` (Pa).
        yield_stress: f64,
        /// Hardening modulus `H` (Pa); 0 (default) is perfect plasticity.
        #[serde(default)]
        hardening: f64,
    },
    /// Finite-strain Drucker-Prager plasticity on Hencky elasticity,
    /// perfectly plastic, its cone matched to Mohr-Coulomb in plane strain.
    DruckerPrager {
        youngs_modulus: f64,
        poisson_ratio: f64,
        density: f64,
        /// Mohr-Coulomb cohesion `c` (Pa).
        cohesion: f64,
        /// Mohr-Coulomb friction angle `phi` (degrees).
        friction_angle: f64,
        /// Dilation angle `psi` (degrees); default: `phi` (associated flow).
        #[serde(default)]
        dilation_angle: Option<f64>,
    },
    /// Finite-strain Mohr-Coulomb plasticity on Hencky elasticity,
    /// perfectly plastic, returned in principal stress space (planes,
    /// edges and apex); Tresca without friction.
    MohrCoulomb {
        youngs_modulus: f64,
        poisson_ratio: f64,
        density: f64,
        /// Cohesion `c` (Pa).
        cohesion: f64,
        /// Friction angle `phi` (degrees).
        friction_angle: f64,
        /// Dilation angle `psi` (degrees); default: `phi` (associated flow).
        #[serde(default)]
        dilation_angle: Option<f64>,
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
            }
            | MaterialSpec::VonMises {
                youngs_modulus,
                poisson_ratio,
                density,
                ..
            }
            | MaterialSpec::DruckerPrager {
                youngs_modulus,
                poisson_ratio,
                density,
                ..
            }
            | MaterialSpec::MohrCoulomb {
                youngs_modulus,
                poisson_ratio,
                density,
                ..
            } => (youngs_modulus, poisson_ratio, density),
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default, schemars::JsonSchema)]
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

/// One stage of a staged analysis: its load steps, the loads at its end
/// and the supports during it. Each load goes linearly, over the stage's
/// steps, from where the stage before left it to its target here; a
/// support holds the boundary where the stage before left it and moves it
/// by its `displacement` (and `rotation`) over the stage.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StageSpec {
    /// Shown with each of its steps (default `stage 1`, `stage 2`, ...).
    #[serde(default)]
    pub name: Option<String>,
    /// Number of load increments of the stage.
    pub load_steps: u32,
    /// How its load factor moves (default `load`: equal increments).
    #[serde(default)]
    pub control: Control,
    /// The loads at the stage's end (targets): a load the stage before had
    /// and this one leaves out goes to zero. A boundary load is the same
    /// load from stage to stage when its `on` and its kind (traction or
    /// pressure) are; a point load when its `at` is. Absent: the stage
    /// before's loads, held.
    #[serde(default)]
    pub loads: Option<Loads>,
    /// Loads added over the stage to those it starts with (increments),
    /// after `loads`, matched as `loads` are.
    #[serde(default)]
    pub load_increments: Option<Loads>,
    /// A geostatic stage (the first only): its gravity, its only load, is
    /// on in full from its first step; the points start from the stress of
    /// the material above them, `sigma_v` vertically and `k0 sigma_v`
    /// horizontally and out of plane; its steps bring them to equilibrium
    /// without moving them, so the displacements start from zero after it.
    #[serde(default)]
    pub geostatic: Option<GeostaticSpec>,
    /// A strength-reduction stage (the last, after one that loads the
    /// body): the loads and supports of the stage before held, each step
    /// a trial that divides every plastic material's strength by a factor
    /// `F` (`c / F`, `tan(phi) / F`, `tan(psi) / F`; von Mises's yield
    /// stress and hardening `/ F`) and solves for equilibrium from the
    /// last trial that held. The factor goes up by `increment` until a
    /// trial fails, then bisects between the largest that held and the
    /// smallest that failed until they are `tolerance` apart: that largest
    /// is the factor of safety. `load_steps` is the most trials it takes.
    #[serde(default)]
    pub strength_reduction: Option<StrengthReductionSpec>,
    /// The supports during the stage. A support is the same one as in the
    /// stage before when its `on`, `fix`, `method` and `constraint` are:
    /// it holds on from where that stage left the boundary, moved by this
    /// stage's `displacement` and `rotation` (increments). A support the
    /// stage before had and this one leaves out is released. Absent: the
    /// stage before's supports, held still.
    #[serde(default)]
    pub supports: Option<Vec<Support>>,
}

/// How a strength-reduction stage steps its factor.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StrengthReductionSpec {
    /// How far each trial raises the factor above the last that held
    /// until one fails (from 1, the strengths the case gives).
    #[serde(default = "default_reduction_increment")]
    pub increment: f64,
    /// How far apart the factor that held and the one that failed are
    /// when the bisection stops.
    #[serde(default = "default_reduction_tolerance")]
    pub tolerance: f64,
    /// A trial that holds only by flowing counts as failed: one whose
    /// points move (root mean square over their volume), per unit of the
    /// factor's rise, more than this many times their displacement at the
    /// stage's start, once they have moved 1% of a cell since it began
    /// (10 suits a slope; docs/guide.md, Strength reduction); not right
    /// after a geostatic stage, which leaves no displacement to measure
    /// against. 0 (the default): no limit, a trial fails only when Newton
    /// does or a point is inadmissible.
    #[serde(default)]
    pub flow_limit: f64,
}

fn default_reduction_increment() -> f64 {
    0.1
}

fn default_reduction_tolerance() -> f64 {
    0.01
}

/// The initial stresses of a geostatic stage.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GeostaticSpec {
    /// The ratio of horizontal to vertical stress (default `nu / (1 -
    /// nu)` of each body's material, one-dimensional elastic compression).
    #[serde(default)]
    pub k0: Option<f64>,
}

/// A stage as the solver reads it, with or without `stages` in the case:
/// where its fields are (`""` or `"stages[k]."`), and what it holds.
#[derive(Debug, Clone, PartialEq)]
pub struct StageView<'a> {
    pub path: String,
    pub name: Option<&'a str>,
    pub load_steps: u32,
    pub control: Control,
    pub loads: &'a Loads,
    pub load_increments: Option<&'a Loads>,
    pub supports: &'a [Support],
    /// Where its supports came from: `"supports"` or `"stages[k].supports"`
    /// of the stage that last listed them.
    pub supports_path: String,
}

impl Case {
    /// The stages the case runs: its `stages`, each with the loads and
    /// supports it inherits filled in, or the case itself as one stage.
    pub fn stage_views(&self) -> Vec<StageView<'_>> {
        if self.stages.is_empty() {
            return vec![StageView {
                path: String::new(),
                name: None,
                load_steps: self.analysis.load_steps,
                control: self.analysis.control,
                loads: &self.loads,
                load_increments: None,
                supports: &self.supports,
                supports_path: "supports".into(),
            }];
        }
        let mut views: Vec<StageView<'_>> = Vec::new();
        for (k, st) in self.stages.iter().enumerate() {
            let path = format!("stages[{k}].");
            let before = views.last();
            let loads = match (&st.loads, before) {
                (Some(l), _) => l,
                (None, Some(b)) => b.loads,
                (None, None) => &self.loads,
            };
            let (supports, supports_path) = match (&st.supports, before) {
                (Some(s), _) => (s.as_slice(), format!("{path}supports")),
                (None, Some(b)) => (b.supports, b.supports_path.clone()),
                (None, None) => (self.supports.as_slice(), format!("{path}supports")),
            };
            views.push(StageView {
                name: st.name.as_deref(),
                load_steps: st.load_steps,
                control: st.control,
                loads,
                load_increments: st.load_increments.as_ref(),
                supports,
                supports_path,
                path,
            });
        }
        views
    }

    /// Load steps over all stages.
    pub fn total_load_steps(&self) -> u64 {
        self.stage_views()
            .iter()
            .map(|v| u64::from(v.load_steps))
            .sum()
    }
}

/// A load on the stretch of boundary that `on` selects in the reference
/// configuration: exactly one of a dead `traction` `[tx, ty]` (Pa) or a
/// follower `pressure` (Pa, positive pushes into the material, normal to
/// the current boundary).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
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
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PointLoad {
    pub at: [f64; 2],
    pub force: [f64; 2],
}

/// Displacement held on what `on` selects (zero, or prescribed by the
/// implicit boundary method): grid nodes or the boundary curve, by `method`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
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
    /// How the boundary method holds the stretch (default `pointwise`).
    /// Implicit boundary method only.
    #[serde(default)]
    pub constraint: Constraint,
}

impl Support {
    /// Whether `other`, in another stage, is the same support: the same
    /// `on`, `fix`, `method` and `constraint`.
    pub fn same_as(&self, other: &Support) -> bool {
        self.on == other.on
            && self.fix == other.fix
            && self.method == other.method
            && self.constraint == other.constraint
    }
}

/// How the implicit boundary method holds a support's stretch.
#[derive(
    Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Constraint {
    /// At every quadrature point of the boundary curve: clamps, rollers,
    /// prescribed displacements over whole sides.
    #[default]
    Pointwise,
    /// On average over pieces of the stretch about two cells long, to its
    /// exact ends: a rigid footing or punch whose edge lies inside the
    /// body's boundary. Held pointwise, the cell holding the edge locks
    /// and the footing acts up to a cell wider than it is.
    Averaged,
}

/// Where a support acts.
#[derive(
    Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default, schemars::JsonSchema,
)]
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

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
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
    pub kind: CaseErrorKind,
}

/// Whether a case could not be read as JSON at all, or is JSON that is not
/// a valid case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CaseErrorKind {
    Syntax,
    Invalid,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn column_json() -> serde_json::Value {
        builtin::json("column").unwrap()
    }

    fn error_for(v: serde_json::Value) -> CaseError {
        Case::from_json(&v.to_string()).unwrap_err()
    }

    /// The stabilisation moved from `analysis.newton` to
    /// `analysis.stabilisation`: a case that gives it at the old place runs
    /// with it, one that gives a key at both is refused at the old place,
    /// and a bad value is named where it was given.
    #[test]
    fn the_stabilisation_is_still_read_at_its_old_place() {
        let settings = |v: serde_json::Value| {
            Case::from_json(&v.to_string())
                .unwrap()
                .analysis
                .stabilisation_settings()
        };
        let mut old = column_json();
        old["analysis"]["newton"] =
            serde_json::json!({"ghost_penalty": 0.02, "tangent_regularisation": 1e-6});
        let mut new = column_json();
        new["analysis"]["stabilisation"] =
            serde_json::json!({"ghost_penalty": 0.02, "tangent_regularisation": 1e-6});
        let expected = StabilisationSpec {
            ghost_penalty: 0.02,
            tangent_regularisation: 1e-6,
            hourglass: 1e-2,
            lone_points: true,
        };
        assert_eq!(settings(old.clone()), expected);
        assert_eq!(settings(new.clone()), expected);
        assert_eq!(
            settings(column_json()),
            StabilisationSpec {
                ghost_penalty: 1e-3,
                tangent_regularisation: 0.0,
                hourglass: 1e-2,
                lone_points: true,
            }
        );
        let mut both = new.clone();
        both["analysis"]["newton"] = serde_json::json!({"ghost_penalty": 0.02});
        let e = error_for(both);
        assert_eq!(e.path, "analysis.newton.ghost_penalty", "{}", e.message);
        old["analysis"]["newton"]["tangent_regularisation"] = (-1.0).into();
        assert_eq!(
            error_for(old).path,
            "analysis.newton.tangent_regularisation"
        );
        new["analysis"]["stabilisation"]["ghost_penalty"] = (-1.0).into();
        assert_eq!(error_for(new).path, "analysis.stabilisation.ghost_penalty");
    }

    /// The column as two stages: its gravity applied, then held while a
    /// second stage adds nothing. Each misplaced or wrong field of a staged
    /// case is named.
    #[test]
    fn a_staged_case_names_its_wrong_fields() {
        let staged = || {
            let mut v = column_json();
            let (loads, supports) = (v["loads"].take(), v["supports"].take());
            v.as_object_mut().unwrap().remove("loads");
            v.as_object_mut().unwrap().remove("supports");
            v["analysis"].as_object_mut().unwrap().remove("load_steps");
            v["stages"] = serde_json::json!([
                { "name": "weight", "load_steps": 2, "loads": loads, "supports": supports },
                { "load_steps": 1 }
            ]);
            v
        };
        let case = Case::from_json(&staged().to_string()).unwrap();
        assert_eq!(case.total_load_steps(), 3);
        let views = case.stage_views();
        assert_eq!(views[1].supports, views[0].supports);
        assert_eq!(views[1].supports_path, "stages[0].supports");
        let mut wrong = Vec::new();
        let mut v = staged();
        v["analysis"]["load_steps"] = 3.into();
        wrong.push((v, "analysis.load_steps"));
        let mut v = staged();
        v["supports"] = v["stages"][0]["supports"].clone();
        wrong.push((v, "supports"));
        let mut v = staged();
        v["stages"][1]["load_steps"] = 0.into();
        wrong.push((v, "stages[1].load_steps"));
        let mut v = staged();
        v["stages"][1]["name"] = " ".into();
        wrong.push((v, "stages[1].name"));
        let mut v = staged();
        v["stages"][1]["load_increments"] = serde_json::json!({ "gravity": [0.0, "x"] });
        wrong.push((v, "stages[1].load_increments.gravity[1]"));
        let mut v = staged();
        v["stages"][1]["supports"] = serde_json::json!([
            { "on": { "y": 0.0 }, "fix": "y", "method": "ibm" }
        ]);
        wrong.push((v, "stages[1].supports[0]"));
        // Arc-length control: the last stage only, with loads of its own
        // to scale, supports that hold still, and not at the top level.
        let mut v = staged();
        v["analysis"]["control"] = "arc_length".into();
        wrong.push((v, "analysis.control"));
        let mut v = staged();
        v["stages"][0]["control"] = "arc_length".into();
        wrong.push((v, "stages[0].control"));
        let mut v = staged();
        v["stages"][1]["control"] = "arc_length".into();
        wrong.push((v, "stages[1].control"));
        let mut v = staged();
        v["stages"][1]["control"] = "arc_length".into();
        v["stages"][1]["load_increments"] = serde_json::json!({ "gravity": [0.0, -1.0] });
        v["stages"][1]["supports"] = v["stages"][0]["supports"].clone();
        v["stages"][1]["supports"][2]["method"] = "ibm".into();
        v["stages"][1]["supports"][2]["displacement"] = serde_json::json!([0.0, -0.1]);
        wrong.push((v, "stages[1].supports[2]"));
        // Strength reduction: the last stage of two or more, changing the
        // strength alone, its increment and tolerance in range.
        let reduce = serde_json::json!({ "increment": 0.1 });
        let mut v = staged();
        v["stages"][0]["strength_reduction"] = reduce.clone();
        wrong.push((v, "stages[0].strength_reduction"));
        let mut v = staged();
        v["stages"][1]["strength_reduction"] = reduce.clone();
        v["stages"][1]["load_increments"] = serde_json::json!({ "gravity": [0.0, -1.0] });
        wrong.push((v, "stages[1].load_increments"));
        let mut v = staged();
        v["stages"][1]["strength_reduction"] = reduce.clone();
        v["stages"][1]["supports"] = v["stages"][0]["supports"].clone();
        wrong.push((v, "stages[1].supports"));
        for (increment, tolerance, field) in [
            (0.0, 0.01, "increment"),
            (20.0, 0.01, "increment"),
            (0.1, 0.1, "tolerance"),
            (0.1, -0.01, "tolerance"),
            (0.1, 1e-8, "tolerance"),
        ] {
            let mut v = staged();
            v["stages"][1]["strength_reduction"] =
                serde_json::json!({ "increment": increment, "tolerance": tolerance });
            wrong.push((v, ["stages[1].strength_reduction.", field].concat().leak()));
        }
        let mut v = staged();
        v["stages"][1]["strength_reduction"] = serde_json::json!({ "flow_limit": -1.0 });
        wrong.push((v, "stages[1].strength_reduction.flow_limit"));
        // A flow limit right after a geostatic stage would measure nothing.
        let mut v = staged();
        v["stages"][0]["geostatic"] = serde_json::json!({});
        v["stages"][0]["loads"] = serde_json::json!({ "gravity": [0.0, -10.0] });
        v["stages"][1]["strength_reduction"] = serde_json::json!({ "flow_limit": 10.0 });
        wrong.push((v, "stages[1].strength_reduction.flow_limit"));
        for (v, path) in wrong {
            assert_eq!(error_for(v).path, path);
        }
        let mut v = staged();
        v["stages"][1]["strength_reduction"] = reduce;
        let case = Case::from_json(&v.to_string()).unwrap();
        let spec = case.stages[1].strength_reduction.unwrap();
        assert_eq!(
            (spec.increment, spec.tolerance, spec.flow_limit),
            (0.1, 0.01, 0.0)
        );
        let mut v = staged();
        v["stages"][1]["control"] = "arc_length".into();
        v["stages"][1]["load_increments"] = serde_json::json!({ "gravity": [0.0, -1.0] });
        let case = Case::from_json(&v.to_string()).unwrap();
        assert_eq!(case.stage_views()[1].control, Control::ArcLength);
    }

    /// A case without stages asks for the arc length in `analysis`; its
    /// supports must hold still.
    #[test]
    fn an_arc_length_case_scales_loads_not_motions() {
        let mut v = column_json();
        v["analysis"]["control"] = "arc_length".into();
        assert!(Case::from_json(&v.to_string()).is_ok());
        v["supports"][2] = serde_json::json!({ "on": { "y": 0.0 }, "fix": "xy", "method": "ibm", "displacement": [0.0, 0.1] });
        let e = error_for(v.clone());
        assert_eq!(e.path, "supports[2]");
        assert!(e.message.contains("hold still"), "{}", e.message);
        v["supports"][2] = serde_json::json!({ "on": { "y": 0.0 }, "fix": "xy" });
        v["loads"] = serde_json::json!({});
        assert_eq!(error_for(v).path, "analysis.control");
    }

    #[test]
    fn built_in_examples_parse() {
        for name in builtin::NAMES {
            Case::from_json(builtin::get(name).unwrap()).unwrap();
        }
    }

    #[test]
    fn text_that_is_not_json_is_a_syntax_error_and_a_wrong_case_is_not() {
        let text = column_json().to_string();
        for bad in [format!("{text} x"), text[..text.len() - 1].to_string()] {
            assert_eq!(
                Case::from_json(&bad).unwrap_err().kind,
                CaseErrorKind::Syntax
            );
        }
        let mut v = column_json();
        v["grid"]["cell_size"] = "big".into();
        assert_eq!(error_for(v).kind, CaseErrorKind::Invalid);
        // A number f64 cannot hold is an invalid value, and its field named.
        let text =
            column_json()
                .to_string()
                .replacen("\"cell_size\":3.125", "\"cell_size\":1e309", 1);
        assert!(text.contains("1e309"), "{text}");
        let e = Case::from_json(&text).unwrap_err();
        assert_eq!(
            (e.kind, e.path.as_str()),
            (CaseErrorKind::Invalid, "grid.cell_size")
        );
    }

    /// serde reads `null` as a field left out, so `"extent": null` was
    /// accepted and served back as given; `"geometry": {}` is JSON, but was
    /// called malformed because serde classed its error as syntax. Both are
    /// invalid cases with the field named.
    #[test]
    fn nulls_and_empty_choices_are_invalid_fields_not_malformed_text() {
        let mut v = column_json();
        v["grid"]["extent"] = serde_json::Value::Null;
        let e = error_for(v);
        assert_eq!(
            (e.kind, e.path.as_str()),
            (CaseErrorKind::Invalid, "grid.extent")
        );
        let mut v = column_json();
        v["supports"][1]["on"]["x"] = serde_json::Value::Null;
        assert_eq!(error_for(v).path, "supports[1].on.x");
        let mut v = column_json();
        v["title"] = "null and void".into();
        Case::from_json(&v.to_string()).unwrap();
        for empty in [serde_json::json!({}), serde_json::json!([])] {
            let mut v = column_json();
            v["bodies"][0]["geometry"] = empty;
            let e = error_for(v);
            assert_eq!(
                (e.kind, e.path.as_str()),
                (CaseErrorKind::Invalid, "bodies[0].geometry"),
                "{}",
                e.message
            );
        }
    }

    /// A tiny cell size, or a body far from the origin, once passed
    /// validation and stopped "after load step 0" with the material off
    /// the grid; the body is now refused, named.
    #[test]
    fn a_body_beyond_the_grids_reach_is_refused() {
        let mut v = column_json();
        v["grid"].as_object_mut().unwrap().remove("extent");
        v["grid"]["cell_size"] = 1e-300.into();
        v["bodies"][0]["points"] = serde_json::json!({"spacing": 0.5});
        assert_eq!(error_for(v).path, "bodies[0].geometry");
        let mut v = column_json();
        v["grid"].as_object_mut().unwrap().remove("extent");
        v["bodies"][0]["geometry"] =
            serde_json::json!({"rectangle": {"min": [1e14, 0], "max": [1.00000001e14, 1]}});
        assert_eq!(error_for(v).path, "bodies[0].geometry");
    }

    /// A self-intersecting polygon was accepted and failed with an
    /// inverted point at step 1.
    #[test]
    fn a_polygon_that_crosses_itself_is_refused() {
        let mut v = column_json();
        v["bodies"][0]["geometry"] =
            serde_json::json!({"polygon": {"vertices": [[0, 0], [4, 2], [4, 0], [0, 1]]}});
        let e = error_for(v);
        assert_eq!(e.path, "bodies[0].geometry.polygon.vertices");
        assert!(e.message.contains("crosses itself"), "{e}");
    }

    /// A quadrilateral must be strictly convex, in order round it: a
    /// crossed ("bow tie"), reflex or flattened one has no one-to-one
    /// bilinear map; three vertices are not a quadrilateral.
    #[test]
    fn a_quadrilateral_that_is_not_convex_is_refused() {
        for vertices in [
            serde_json::json!([[0, 0], [4, 2], [4, 0], [0, 1]]),
            serde_json::json!([[0, 0], [4, 0], [1, 1], [0, 4]]),
            serde_json::json!([[0, 0], [2, 0], [4, 0], [0, 4]]),
        ] {
            let mut v = column_json();
            v["bodies"][0]["geometry"] =
                serde_json::json!({"quadrilateral": {"vertices": vertices}});
            let e = error_for(v);
            assert_eq!(e.path, "bodies[0].geometry.quadrilateral.vertices", "{e}");
            assert!(e.message.contains("convex"), "{e}");
        }
        let mut v = column_json();
        v["bodies"][0]["geometry"] =
            serde_json::json!({"quadrilateral": {"vertices": [[0, 0], [4, 0], [0, 4]]}});
        assert!(
            error_for(v)
                .path
                .starts_with("bodies[0].geometry.quadrilateral.vertices"),
            "three vertices"
        );
        // Either orientation is accepted.
        let mut v = column_json();
        v["bodies"][0]["geometry"] = serde_json::json!({"quadrilateral": {"vertices": [[0, 0], [0, 50], [3.125, 50], [3.125, 0]]}});
        Case::from_json(&v.to_string()).unwrap();
    }

    /// A mesh body is refused, naming the field, when an element is not
    /// one (a wrong node count, a missing or repeated node, no area, a
    /// quadrilateral that is not convex), when its boundary is not closed
    /// simple rings, or when elements overlap; a good mesh, triangles and
    /// quadrilaterals either way round, passes.
    #[test]
    fn a_mesh_that_is_not_one_is_refused() {
        // 0-5: a 2 x 1 block of nodes; 6-9: a square inside the first cell;
        // 10: below the middle; 11, 12: the middle column again.
        let nodes = serde_json::json!([
            [0, 0],
            [1, 0],
            [2, 0],
            [0, 1],
            [1, 1],
            [2, 1],
            [0.2, 0.2],
            [0.8, 0.2],
            [0.8, 0.8],
            [0.2, 0.8],
            [1, -0.5],
            [1, 0],
            [1, 1]
        ]);
        let mesh_case = |elements: serde_json::Value| {
            let mut v = column_json();
            v["bodies"][0]["geometry"] =
                serde_json::json!({"mesh": {"nodes": nodes.clone(), "elements": elements}});
            v
        };
        Case::from_json(
            &mesh_case(serde_json::json!([[0, 1, 4, 3], [1, 5, 4], [1, 2, 5]])).to_string(),
        )
        .unwrap();
        Case::from_json(
            &mesh_case(serde_json::json!([[3, 4, 1, 0], [4, 5, 1], [1, 5, 2]])).to_string(),
        )
        .unwrap();
        for (elements, path, words) in [
            (
                serde_json::json!([[0, 1]]),
                "bodies[0].geometry.mesh.elements[0]",
                "3 or 4",
            ),
            (
                serde_json::json!([[0, 1, 99]]),
                "bodies[0].geometry.mesh.elements[0]",
                "does not exist",
            ),
            (
                serde_json::json!([[0, 1, 1]]),
                "bodies[0].geometry.mesh.elements[0]",
                "repeats",
            ),
            (
                serde_json::json!([[0, 1, 2]]),
                "bodies[0].geometry.mesh.elements[0]",
                "no area",
            ),
            (
                serde_json::json!([[0, 1, 2, 4]]),
                "bodies[0].geometry.mesh.elements[0]",
                "convex",
            ),
            (
                serde_json::json!([[0, 1, 4, 3], [3, 4, 1, 0]]),
                "bodies[0].geometry.mesh.elements",
                "overlap",
            ),
            (
                serde_json::json!([[0, 1, 4, 3], [6, 7, 8, 9]]),
                "bodies[0].geometry.mesh.elements",
                "overlap",
            ),
            (
                serde_json::json!([[0, 2, 5, 3], [0, 10, 1], [1, 10, 2]]),
                "bodies[0].geometry.mesh.elements",
                "",
            ),
            (
                serde_json::json!([[0, 1, 4, 3], [11, 2, 5, 12]]),
                "bodies[0].geometry.mesh.elements",
                "without sharing",
            ),
            (
                serde_json::json!([[0, 1, 4, 3], [0, 1, 4]]),
                "bodies[0].geometry.mesh.elements",
                "node 4",
            ),
            (
                serde_json::json!([[0, 1, 3], [1, 2, 5]]),
                "bodies[0].geometry.mesh.elements",
                "node 1",
            ),
            (
                serde_json::json!([]),
                "bodies[0].geometry.mesh.elements",
                "at least one",
            ),
        ] {
            let e = error_for(mesh_case(elements.clone()));
            assert_eq!(e.path, path, "{elements}: {e}");
            assert!(e.message.contains(words), "{elements}: {e}");
        }
        let mut v = mesh_case(serde_json::json!([[0, 1, 4, 3]]));
        v["bodies"][0]["points"]["lattice"] = "grid".into();
        assert_eq!(error_for(v).path, "bodies[0].points.lattice");
    }

    /// A polygon on its own lattice is cut into triangles: a hole outside
    /// it or overlapping another is refused, naming the holes.
    #[test]
    fn a_polygon_hole_outside_is_refused() {
        let square = serde_json::json!([[0, 0], [4, 0], [4, 4], [0, 4]]);
        for holes in [
            serde_json::json!([[[5, 1], [6, 1], [6, 2]]]),
            serde_json::json!([
                [[1, 1], [2, 1], [2, 2], [1, 2]],
                [[1.5, 1.5], [3, 1.5], [3, 3]]
            ]),
        ] {
            let mut v = column_json();
            v["bodies"][0]["geometry"] = serde_json::json!({"polygon": {"vertices": square.clone(), "holes": holes.clone()}});
            let e = error_for(v);
            assert_eq!(e.path, "bodies[0].geometry.polygon.holes", "{holes}: {e}");
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
    fn frictional_parameters_are_checked_by_name() {
        for model in ["drucker_prager", "mohr_coulomb"] {
            frictional_parameters_of(model);
        }
    }

    fn frictional_parameters_of(model: &str) {
        let soil = |c: f64, phi: f64, psi: Option<f64>| {
            let mut v = column_json();
            let mut m = serde_json::json!({"model": model, "youngs_modulus": 1e7,
                "poisson_ratio": 0.3, "density": 0.0, "cohesion": c, "friction_angle": phi});
            if let Some(psi) = psi {
                m["dilation_angle"] = psi.into();
            }
            v["bodies"][0]["material"] = m;
            v
        };
        assert!(Case::from_json(&soil(10e3, 20.0, None).to_string()).is_ok());
        for (v, field) in [
            (soil(0.0, 0.0, None), "cohesion"),
            (soil(-1.0, 20.0, None), "cohesion"),
            (soil(10e3, 75.0, None), "friction_angle"),
            (soil(10e3, -1.0, None), "friction_angle"),
            (soil(10e3, 20.0, Some(25.0)), "dilation_angle"),
        ] {
            let e = error_for(v);
            assert_eq!(e.path, format!("bodies[0].material.{field}"), "{e}");
        }
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
        // Grid-node supports hold a B-spline's coefficients, not the field.
        for basis in ["bspline2", "bspline3"] {
            let e = set(&|v| v["basis"] = basis.into());
            assert_eq!(e.path, "supports[0].method", "{basis}");
            assert!(e.message.contains("ibm"), "{e}");
        }
    }

    #[test]
    fn a_basis_is_named_as_a_case_names_it() {
        let names: Vec<String> = BasisKind::ALL.iter().map(|b| b.to_string()).collect();
        assert_eq!(names, ["linear", "gimp", "bspline2", "bspline3"]);
        for basis in BasisKind::ALL {
            assert_eq!(basis.to_string().parse::<BasisKind>(), Ok(basis));
            let case: BasisKind = serde_json::from_value(serde_json::json!(basis)).unwrap();
            assert_eq!(case, basis);
        }
        assert_eq!(format!("{:<8}|", BasisKind::Gimp), "gimp    |");
        let e = "quartic".parse::<BasisKind>().unwrap_err();
        assert!(e.contains("linear, gimp, bspline2, bspline3"), "{e}");
    }
}
