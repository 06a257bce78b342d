//! The 3D case (`analysis.type: "3d"`): bodies as solids (boxes,
//! cylinders, extrusions of any plane section, spheres and spherical
//! shells), gravity and point loads of three components, and supports on
//! grid planes. Materials, bases and the solver's settings are the plane
//! strain case's. The B-spline surfaces, their tractions and the implicit
//! boundary method in 3D are issue 38's part 2; F-bar, the cell mean and
//! stages wait for cells of eight corners.
//!
//! A field of the plane-strain case that a 3D case does not read is an
//! unknown field, named with its path (`boundary`, `probes`,
//! `bodies[0].geometry.rectangle`); a vector of two components where three
//! are needed is refused at its path too.

use serde::{Deserialize, Serialize};

use super::validate::{
    check_mesh_size, check_newton, check_substepping, check_version, parse, positive,
};
use super::{BasisKind, CaseError, Constraint, MaterialSpec, NewtonSpec, SubsteppingSpec};
use crate::geometry::{Geometry, HexMesh};
use crate::particles::solid_seeding::{self, Solid};

/// A complete 3D analysis.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidCase {
    /// Case-format version; must be 1.
    pub version: u32,
    /// Free-text title shown in summaries.
    #[serde(default)]
    pub title: Option<String>,
    pub analysis: SolidAnalysis,
    pub grid: SolidGrid,
    /// Shape functions of the background grid (their 3D tensor products).
    #[serde(default)]
    pub basis: BasisKind,
    pub bodies: Vec<SolidBody>,
    #[serde(default)]
    pub loads: SolidLoads,
    /// Supports on the grid nodes of planes normal to an axis.
    #[serde(default)]
    pub supports: Vec<PlaneSupportSpec>,
    /// Supports on regions of the bodies' B-spline surfaces, imposed by
    /// the implicit boundary method. Their reactions follow the plane
    /// supports' in a step's `reactions`.
    #[serde(default)]
    pub surface_supports: Vec<SurfaceSupportSpec>,
    #[serde(default)]
    pub output: SolidOutput,
}

/// The analysis kind of a 3D case: `"3d"`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
pub enum SolidKind {
    #[serde(rename = "3d")]
    ThreeD,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidAnalysis {
    #[serde(rename = "type")]
    pub kind: SolidKind,
    /// Number of equal load increments; gravity and the point loads are
    /// ramped linearly.
    pub load_steps: u32,
    #[serde(default)]
    pub newton: NewtonSpec,
    #[serde(default)]
    pub substepping: SubsteppingSpec,
    #[serde(default)]
    pub stabilisation: SolidStabilisation,
    /// As the plane-strain case's: each point's volume change the average
    /// of its cell's (`fbar`, against volumetric locking near
    /// incompressibility), its whole strain increment its cell's mean
    /// (`cell_mean`, against locking by dilatancy), or its own
    /// (`standard`); the cells have eight corners.
    #[serde(default)]
    pub volumetric: super::Volumetric,
}

/// The stabilisation a 3D step has so far.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidStabilisation {
    /// The ghost penalty's `gamma` on the faces of the cells at the
    /// material's edge (`assembly/solid_ghost_faces.rs`), as the plane
    /// strain case's `analysis.stabilisation.ghost_penalty`; 0 turns it off.
    #[serde(default = "super::default_ghost_penalty")]
    pub ghost_penalty: f64,
    /// With `analysis.volumetric: cell_mean`, the plane-strain case's
    /// `analysis.stabilisation.hourglass` (default 1e-2).
    #[serde(default = "super::default_hourglass")]
    pub hourglass: f64,
}

impl Default for SolidStabilisation {
    fn default() -> Self {
        Self {
            ghost_penalty: super::default_ghost_penalty(),
            hourglass: super::default_hourglass(),
        }
    }
}

/// The background grid: cubes of side `cell_size`, one node at `origin`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidGrid {
    pub cell_size: f64,
    #[serde(default)]
    pub origin: [f64; 3],
    /// Where the mesh ends (nodes outside do not exist); unbounded if
    /// left out.
    #[serde(default)]
    pub extent: Option<SolidBox>,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidBox {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidBody {
    #[serde(default)]
    pub name: Option<String>,
    pub geometry: SolidGeometry,
    pub points: SolidFill,
    pub material: MaterialSpec,
}

/// A body's shape.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum SolidGeometry {
    /// An axis-aligned box.
    Box {
        min: [f64; 3],
        max: [f64; 3],
    },
    /// A circular cylinder along z: its axis through `center` (x, y), from
    /// `z[0]` to `z[1]`.
    Cylinder {
        center: [f64; 2],
        radius: f64,
        z: [f64; 2],
    },
    /// A plane section (any 2D geometry of the plane-strain case: a
    /// polygon, a circle, an annulus, ...) in x and y, from `z[0]` to
    /// `z[1]`.
    Extrusion {
        section: Geometry,
        z: [f64; 2],
    },
    Sphere {
        center: [f64; 3],
        radius: f64,
    },
    SphericalShell {
        center: [f64; 3],
        inner_radius: f64,
        outer_radius: f64,
    },
    /// A mesh of hexahedra (`nodes` `[[x, y, z], ...]`, `elements` eight
    /// node indices each in gmsh's order), as `scripts/gmsh_to_case.py`
    /// makes it from a `.msh` file.
    Mesh(HexMesh),
}

/// How densely a body is filled: exactly one of `per_cell` (points per
/// cell in each direction) or `spacing` (metres).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidFill {
    #[serde(default)]
    pub per_cell: Option<u32>,
    #[serde(default)]
    pub spacing: Option<f64>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidLoads {
    /// Gravitational acceleration (m/s^2), e.g. `[0, 0, -9.81]`.
    #[serde(default)]
    pub gravity: Option<[f64; 3]>,
    #[serde(default)]
    pub point_loads: Vec<SolidPointLoad>,
    /// Tractions on faces of the bodies that lie on grid-aligned planes
    /// (a box's faces): a stopgap until the B-spline surfaces (part 2).
    #[serde(default)]
    pub tractions: Vec<FaceTraction>,
    /// Tractions and follower pressures on the bodies' B-spline surfaces,
    /// on the regions `on` selects.
    #[serde(default)]
    pub surface: Vec<SurfaceLoadSpec>,
}

/// The most surface loads a 3D case may give.
pub const MAX_SURFACE_LOADS: usize = 64;

/// A load on a region of the bodies' surfaces: exactly one of a dead
/// `traction` (Pa, per unit current area) or a follower `pressure` (Pa,
/// positive pushes into the material), ramped with the load factor.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SurfaceLoadSpec {
    pub on: SurfaceSelector,
    #[serde(default)]
    pub traction: Option<[f64; 3]>,
    #[serde(default)]
    pub pressure: Option<f64>,
}

/// A region of the bodies' surfaces, judged in the reference
/// configuration: the surface cells whose middle lies within `tolerance`
/// of every surface given (a `plane`, a `sphere`, a `cylinder` about an
/// axis along z), and within the ranges given: `inside` a box,
/// `inside_cylinder` (within its radius of its axis); on body `body`
/// only, if given. At least one of these. The tolerance defaults to a
/// tenth of the body's point spacing. A load takes the cells whose middle
/// is within the ranges; a support holds exactly the part of the cells
/// within them (judged at its quadrature points), so a footing has its
/// own width wherever the cells end.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SurfaceSelector {
    #[serde(default)]
    pub body: Option<usize>,
    #[serde(default)]
    pub plane: Option<PlaneThrough>,
    #[serde(default)]
    pub sphere: Option<SphereSpec>,
    #[serde(default)]
    pub cylinder: Option<CylinderSpec>,
    #[serde(default)]
    pub inside: Option<SolidBox>,
    #[serde(default)]
    pub inside_cylinder: Option<CylinderSpec>,
    #[serde(default)]
    pub tolerance: Option<f64>,
}

/// The plane through `point` normal to `normal`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlaneThrough {
    pub point: [f64; 3],
    pub normal: [f64; 3],
}

/// The sphere of `radius` about `center`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    pub center: [f64; 3],
    pub radius: f64,
}

/// The cylinder of `radius` about the line through `center` along z.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CylinderSpec {
    pub center: [f64; 2],
    pub radius: f64,
}

impl SurfaceSelector {
    /// Whether the reference place `x` is in the region, with `tolerance`
    /// where the selector gives none.
    pub fn contains(&self, x: [f64; 3], tolerance: f64) -> bool {
        self.on_surfaces(x, tolerance) && self.within_ranges(x)
    }

    /// Whether `x` lies within the ranges (`inside`, `inside_cylinder`);
    /// true when the selector gives none.
    pub fn within_ranges(&self, x: [f64; 3]) -> bool {
        let inside = self
            .inside
            .is_none_or(|b| (0..3).all(|k| x[k] >= b.min[k] && x[k] <= b.max[k]));
        let within = self
            .inside_cylinder
            .is_none_or(|c| (x[0] - c.center[0]).hypot(x[1] - c.center[1]) <= c.radius);
        inside && within
    }

    /// Whether the selector gives ranges.
    pub fn has_ranges(&self) -> bool {
        self.inside.is_some() || self.inside_cylinder.is_some()
    }

    /// Whether `x` lies within the tolerance of every surface given (true
    /// when none is).
    pub fn on_surfaces(&self, x: [f64; 3], tolerance: f64) -> bool {
        let tol = self.tolerance.unwrap_or(tolerance);
        let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let plane = self.plane.is_none_or(|p| {
            let d: f64 = (0..3).map(|k| (x[k] - p.point[k]) * p.normal[k]).sum();
            d.abs() <= tol * norm(p.normal)
        });
        let sphere = self.sphere.is_none_or(|s| {
            (norm(std::array::from_fn(|k| x[k] - s.center[k])) - s.radius).abs() <= tol
        });
        let cylinder = self.cylinder.is_none_or(|c| {
            ((x[0] - c.center[0]).hypot(x[1] - c.center[1]) - c.radius).abs() <= tol
        });
        plane && sphere && cylinder
    }

    fn validate(&self, path: &str, bodies: usize) -> Result<(), CaseError> {
        if self.plane.is_none()
            && self.sphere.is_none()
            && self.cylinder.is_none()
            && !self.has_ranges()
        {
            return Err(CaseError::new(
                path,
                "give at least one of plane, sphere, cylinder, inside or inside_cylinder",
            ));
        }
        if let Some(b) = self.body
            && b >= bodies
        {
            return Err(CaseError::new(
                format!("{path}.body"),
                format!("no body {b} ({bodies} bodies)"),
            ));
        }
        if let Some(p) = &self.plane {
            finite(&format!("{path}.plane.point"), &p.point)?;
            finite(&format!("{path}.plane.normal"), &p.normal)?;
            if p.normal.iter().all(|&v| v == 0.0) {
                return Err(CaseError::new(
                    format!("{path}.plane.normal"),
                    "must not be zero",
                ));
            }
        }
        if let Some(s) = &self.sphere {
            finite(&format!("{path}.sphere.center"), &s.center)?;
            positive(&format!("{path}.sphere.radius"), s.radius)?;
        }
        if let Some(c) = &self.cylinder {
            finite(&format!("{path}.cylinder.center"), &c.center)?;
            positive(&format!("{path}.cylinder.radius"), c.radius)?;
        }
        if let Some(b) = &self.inside {
            ordered(&format!("{path}.inside"), b.min, b.max)?;
        }
        if let Some(c) = &self.inside_cylinder {
            finite(&format!("{path}.inside_cylinder.center"), &c.center)?;
            positive(&format!("{path}.inside_cylinder.radius"), c.radius)?;
        }
        if let Some(t) = self.tolerance {
            positive(&format!("{path}.tolerance"), t)?;
        }
        Ok(())
    }
}

/// A dead traction (Pa) on the faces of the points' domains that lie on
/// the plane `on` in the reference configuration: each such point carries
/// the traction times its face's area, ramped with the load factor.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FaceTraction {
    pub on: PlaneSpec,
    pub traction: [f64; 3],
}

/// A force (N) carried by the material point nearest to `at` in the
/// reference configuration.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidPointLoad {
    pub at: [f64; 3],
    pub force: [f64; 3],
}

/// The most surface supports a 3D case may give.
pub const MAX_SURFACE_SUPPORTS: usize = 64;

/// Displacement components held on the region `on` of the bodies'
/// surfaces by the implicit boundary method: `fix` names them (`normal`:
/// a roller on the reference surface's normal, wherever it points), and
/// `displacement` (m, default zero) is where the held components go by
/// the last load step, ramped with the load factor. `constraint:
/// averaged` holds them on average over pieces about two cells a side
/// (a rigid footing, whose edge lies inside the body's surface).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SurfaceSupportSpec {
    pub on: SurfaceSelector,
    pub fix: SolidFix,
    #[serde(default)]
    pub displacement: Option<[f64; 3]>,
    #[serde(default)]
    pub constraint: Constraint,
}

/// Displacement components held on the grid nodes of the plane `on`:
/// at rest, or turned with `rotation`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlaneSupportSpec {
    pub on: PlaneSpec,
    pub fix: SolidFix,
    /// The nodes' prescribed motion: the rotation about the plane's normal
    /// through `center`, ramped with the load factor. `fix` must hold both
    /// components in the plane; a held normal component stays at rest.
    #[serde(default)]
    pub rotation: Option<PlaneRotationSpec>,
}

/// A rigid rotation of a support plane about its normal axis.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlaneRotationSpec {
    /// Degrees at the last load step, counter-clockwise looking down the
    /// axis from its positive side (x: y towards z; y: z towards x; z: x
    /// towards y); at most 360 in size.
    pub angle: f64,
    /// A point of the axis of rotation (m).
    pub center: [f64; 3],
}

/// A grid plane normal to an axis: exactly one of `x`, `y`, `z`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlaneSpec {
    #[serde(default)]
    pub x: Option<f64>,
    #[serde(default)]
    pub y: Option<f64>,
    #[serde(default)]
    pub z: Option<f64>,
}

/// The components a support holds: `xyz` fixes, one axis is a roller,
/// `normal` a roller on the surface's normal (on a grid plane, its axis).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SolidFix {
    X,
    Y,
    Z,
    Xy,
    Xz,
    Yz,
    Xyz,
    Normal,
}

impl SolidFix {
    /// Which of x, y, z it holds; `None` for the normal.
    pub fn held(self) -> Option<[bool; 3]> {
        Some(match self {
            SolidFix::X => [true, false, false],
            SolidFix::Y => [false, true, false],
            SolidFix::Z => [false, false, true],
            SolidFix::Xy => [true, true, false],
            SolidFix::Xz => [true, false, true],
            SolidFix::Yz => [false, true, true],
            SolidFix::Xyz => [true, true, true],
            SolidFix::Normal => return None,
        })
    }

    /// Which of x, y, z it holds on the grid plane normal to `axis`.
    pub fn components_on(self, axis: usize) -> [bool; 3] {
        self.held().unwrap_or(std::array::from_fn(|c| c == axis))
    }
}

impl PlaneSpec {
    /// `(axis, at)` of the plane, when exactly one coordinate is given.
    pub fn plane(&self) -> Option<(usize, f64)> {
        match (self.x, self.y, self.z) {
            (Some(x), None, None) => Some((0, x)),
            (None, Some(y), None) => Some((1, y)),
            (None, None, Some(z)) => Some((2, z)),
            _ => None,
        }
    }
}

/// What a 3D run stores: the points every `every` load steps (and at
/// step 0 and the last).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidOutput {
    #[serde(default = "every_step")]
    pub every: u32,
}

fn every_step() -> u32 {
    1
}

impl Default for SolidOutput {
    fn default() -> Self {
        Self { every: 1 }
    }
}

impl SolidOutput {
    /// Whether step `step` of `load_steps` stores its points.
    pub fn stores_points(&self, step: usize, load_steps: usize) -> bool {
        super::stores_points_every(self.every, step, load_steps)
    }

    /// How many of the steps 0..=load_steps store their points.
    pub fn point_steps(&self, load_steps: usize) -> usize {
        super::point_steps_every(self.every, load_steps)
    }
}

/// Whether a case's JSON text asks for a 3D analysis (`analysis.type` is
/// `"3d"`); text that is not JSON is not.
pub fn is_solid(text: &str) -> bool {
    serde_json::from_str::<serde_json::Value>(text).is_ok_and(|v| {
        v.pointer("/analysis/type")
            .is_some_and(|t| t.as_str() == Some("3d"))
    })
}

impl SolidCase {
    /// Parses and validates a 3D case from JSON text.
    pub fn from_json(text: &str) -> Result<SolidCase, CaseError> {
        let case: SolidCase = parse(text)?;
        case.validate()?;
        Ok(case)
    }

    /// Checks values that the types cannot: signs, ranges, consistency.
    pub fn validate(&self) -> Result<(), CaseError> {
        check_version(self.version)?;
        let a = &self.analysis;
        if a.load_steps == 0 {
            return Err(CaseError::new("analysis.load_steps", "must be at least 1"));
        }
        check_newton(&a.newton)?;
        check_substepping(&a.substepping)?;
        let s = &a.stabilisation;
        for (value, path) in [
            (s.ghost_penalty, "analysis.stabilisation.ghost_penalty"),
            (s.hourglass, "analysis.stabilisation.hourglass"),
        ] {
            if !(value >= 0.0 && value.is_finite()) {
                return Err(CaseError::new(path, "must be a finite number, 0 or more"));
            }
        }
        if self.output.every == 0 {
            return Err(CaseError::new("output.every", "must be at least 1"));
        }
        positive("grid.cell_size", self.grid.cell_size)?;
        finite("grid.origin", &self.grid.origin)?;
        if let Some(b) = &self.grid.extent {
            ordered("grid.extent", b.min, b.max)?;
        }
        if self.bodies.is_empty() {
            return Err(CaseError::new("bodies", "at least one body is required"));
        }
        for (i, body) in self.bodies.iter().enumerate() {
            body.validate(&format!("bodies[{i}]"), self.grid.cell_size)?;
        }
        if let Some(g) = &self.loads.gravity {
            finite("loads.gravity", g)?;
        }
        for (i, load) in self.loads.point_loads.iter().enumerate() {
            finite(&format!("loads.point_loads[{i}].at"), &load.at)?;
            finite(&format!("loads.point_loads[{i}].force"), &load.force)?;
        }
        for (i, t) in self.loads.tractions.iter().enumerate() {
            if t.on.plane().is_none() {
                return Err(CaseError::new(
                    format!("loads.tractions[{i}].on"),
                    "give exactly one of x, y, z: the plane normal to that axis",
                ));
            }
            finite(&format!("loads.tractions[{i}].traction"), &t.traction)?;
        }
        if self.loads.surface.len() > MAX_SURFACE_LOADS {
            return Err(CaseError::new(
                "loads.surface",
                format!(
                    "{} surface loads: at most {MAX_SURFACE_LOADS} (each is integrated over the \
                     surface every Newton iteration)",
                    self.loads.surface.len()
                ),
            ));
        }
        for (i, load) in self.loads.surface.iter().enumerate() {
            let path = format!("loads.surface[{i}]");
            load.on.validate(&format!("{path}.on"), self.bodies.len())?;
            match (&load.traction, load.pressure) {
                (Some(t), None) => finite(&format!("{path}.traction"), t)?,
                (None, Some(p)) => finite(&format!("{path}.pressure"), &[p])?,
                _ => {
                    return Err(CaseError::new(
                        path,
                        "give exactly one of traction or pressure",
                    ));
                }
            }
        }
        for (i, support) in self.supports.iter().enumerate() {
            let Some((axis, _)) = support.on.plane() else {
                return Err(CaseError::new(
                    format!("supports[{i}].on"),
                    "give exactly one of x, y, z: the plane normal to that axis",
                ));
            };
            if let Some(rotation) = &support.rotation {
                let path = format!("supports[{i}].rotation");
                finite(&format!("{path}.center"), &rotation.center)?;
                if !rotation.angle.is_finite() || rotation.angle.abs() > 360.0 {
                    return Err(CaseError::new(
                        format!("{path}.angle"),
                        format!("is {}: give degrees, at most 360 in size", rotation.angle),
                    ));
                }
                let held = support.fix.components_on(axis);
                if (0..3).any(|c| c != axis && !held[c]) {
                    return Err(CaseError::new(
                        format!("supports[{i}].fix"),
                        "a rotating support must hold both components in its plane (the rotation \
                         prescribes them): give \"xyz\", or the two in-plane axes",
                    ));
                }
            }
        }
        if self.surface_supports.len() > MAX_SURFACE_SUPPORTS {
            return Err(CaseError::new(
                "surface_supports",
                format!(
                    "{} surface supports: at most {MAX_SURFACE_SUPPORTS}",
                    self.surface_supports.len()
                ),
            ));
        }
        for (i, support) in self.surface_supports.iter().enumerate() {
            let path = format!("surface_supports[{i}]");
            support
                .on
                .validate(&format!("{path}.on"), self.bodies.len())?;
            if let Some(d) = &support.displacement {
                finite(&format!("{path}.displacement"), d)?;
            }
        }
        // As in plane strain, where such supports need the implicit
        // boundary method: fixing the coefficients on a plane does not fix
        // the field there (a cantilever clamped so came out 20% too
        // flexible at 1 m cells, converging at first order).
        if matches!(self.basis, BasisKind::Bspline2 | BasisKind::Bspline3)
            && !self.supports.is_empty()
        {
            return Err(CaseError::new(
                "basis",
                "the B-spline bases hold coefficients at the grid nodes, not the field, so a support on \
                 grid nodes does not hold the body there: give the supports as surface_supports \
                 (the implicit boundary method), or use \"linear\" or \"gimp\"",
            ));
        }
        Ok(())
    }

    /// The spacing of body `i`'s points.
    pub fn spacing(&self, i: usize) -> f64 {
        let fill = &self.bodies[i].points;
        match (fill.per_cell, fill.spacing) {
            (Some(n), _) => self.grid.cell_size / n as f64,
            (None, Some(s)) => s,
            (None, None) => unreachable!("validated: a fill gives one"),
        }
    }

    /// An upper bound on the points the bodies will have, from their
    /// bounding boxes, before any is seeded.
    pub fn points_bound(&self) -> f64 {
        (0..self.bodies.len())
            .map(|i| {
                let s = self.spacing(i);
                if let SolidGeometry::Mesh(mesh) = &self.bodies[i].geometry {
                    // Its elements' counts, whatever their shapes.
                    return (0..mesh.elements.len())
                        .map(|k| {
                            let n = solid_seeding::hexahedron_counts(&mesh.corners(k), s);
                            n.iter().map(|&c| c as f64).product::<f64>()
                        })
                        .sum();
                }
                let (lo, hi) = self.bodies[i].geometry.bounds();
                (0..3)
                    .map(|d| ((hi[d] - lo[d]) / s).ceil() + 1.0)
                    .product::<f64>()
            })
            .sum()
    }
}

impl SolidBody {
    fn validate(&self, path: &str, cell_size: f64) -> Result<(), CaseError> {
        let g = format!("{path}.geometry");
        match &self.geometry {
            SolidGeometry::Box { min, max } => ordered(&format!("{g}.box"), *min, *max)?,
            SolidGeometry::Cylinder { center, radius, z } => {
                finite(&format!("{g}.cylinder.center"), center)?;
                positive(&format!("{g}.cylinder.radius"), *radius)?;
                ordered(&format!("{g}.cylinder.z"), [z[0]], [z[1]])?;
            }
            SolidGeometry::Extrusion { z, .. } => {
                ordered(&format!("{g}.extrusion.z"), [z[0]], [z[1]])?;
            }
            SolidGeometry::Sphere { center, radius } => {
                finite(&format!("{g}.sphere.center"), center)?;
                positive(&format!("{g}.sphere.radius"), *radius)?;
            }
            SolidGeometry::SphericalShell {
                center,
                inner_radius,
                outer_radius,
            } => {
                finite(&format!("{g}.spherical_shell.center"), center)?;
                if !(*inner_radius >= 0.0
                    && inner_radius < outer_radius
                    && outer_radius.is_finite())
                {
                    return Err(CaseError::new(
                        format!("{g}.spherical_shell"),
                        "needs 0 <= inner_radius < outer_radius",
                    ));
                }
            }
            SolidGeometry::Mesh(mesh) => check_hex_mesh(&format!("{g}.mesh"), mesh)?,
        }
        if let SolidGeometry::Extrusion { section, .. } = &self.geometry {
            // The section is a plane-strain body's geometry, checked as one.
            let plane = super::Body {
                name: None,
                geometry: section.clone(),
                points: super::PointFill {
                    spacing: Some(cell_size),
                    ..Default::default()
                },
                material: self.material,
            };
            plane.validate(path).map_err(|e| CaseError {
                path: e.path.replace(
                    &format!("{path}.geometry"),
                    &format!("{g}.extrusion.section"),
                ),
                ..e
            })?;
        }
        let p = format!("{path}.points");
        match (self.points.per_cell, self.points.spacing) {
            (Some(0), None) => {
                return Err(CaseError::new(
                    format!("{p}.per_cell"),
                    "must be at least 1",
                ));
            }
            (Some(_), None) => {}
            (None, Some(s)) => positive(&format!("{p}.spacing"), s)?,
            _ => {
                return Err(CaseError::new(p, "give exactly one of per_cell or spacing"));
            }
        }
        self.material.validate(&format!("{path}.material"))
    }
}

impl SolidGeometry {
    /// The solid the seeding fills.
    pub fn solid(&self) -> Solid {
        match self {
            SolidGeometry::Box { min, max } => Solid::cuboid(*min, *max),
            SolidGeometry::Cylinder { center, radius, z } => Solid::Extrusion {
                section: Geometry::Circle {
                    center: *center,
                    radius: *radius,
                },
                z: *z,
            },
            SolidGeometry::Extrusion { section, z } => Solid::Extrusion {
                section: section.clone(),
                z: *z,
            },
            SolidGeometry::Sphere { center, radius } => Solid::SphericalShell {
                center: *center,
                inner_radius: 0.0,
                outer_radius: *radius,
            },
            SolidGeometry::SphericalShell {
                center,
                inner_radius,
                outer_radius,
            } => Solid::SphericalShell {
                center: *center,
                inner_radius: *inner_radius,
                outer_radius: *outer_radius,
            },
            SolidGeometry::Mesh(mesh) => {
                // Each element right-handed: a mirrored one turned over.
                let mut mesh = mesh.clone();
                for k in 0..mesh.elements.len() {
                    if solid_seeding::trilinear(&mesh.corners(k), [0.5; 3]).1 < 0.0 {
                        let e = mesh.elements[k];
                        mesh.elements[k] = [e[0], e[3], e[2], e[1], e[4], e[7], e[6], e[5]];
                    }
                }
                Solid::Mesh(mesh)
            }
        }
    }

    /// Its bounding box `(min, max)`.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        match self {
            SolidGeometry::Box { min, max } => (*min, *max),
            SolidGeometry::Cylinder { center, radius, z } => (
                [center[0] - radius, center[1] - radius, z[0]],
                [center[0] + radius, center[1] + radius, z[1]],
            ),
            SolidGeometry::Extrusion { section, z } => {
                let (lo, hi) = section.bounding_box();
                ([lo[0], lo[1], z[0]], [hi[0], hi[1], z[1]])
            }
            SolidGeometry::Sphere { center, radius: r }
            | SolidGeometry::SphericalShell {
                center,
                outer_radius: r,
                ..
            } => (center.map(|c| c - r), center.map(|c| c + r)),
            SolidGeometry::Mesh(mesh) => {
                let bound = |pick: fn(f64, f64) -> f64, start: f64| -> [f64; 3] {
                    std::array::from_fn(|d| mesh.nodes.iter().map(|x| x[d]).fold(start, pick))
                };
                (
                    bound(f64::min, f64::INFINITY),
                    bound(f64::max, f64::NEG_INFINITY),
                )
            }
        }
    }
}

/// A hexahedral mesh: finite nodes, no more of them or of elements than a
/// 2D mesh may have ([`check_mesh_size`]); at least one element, each of
/// eight distinct nodes that exist, not inverted (its map's Jacobian of one sign, and not near zero,
/// at all eight corners: a right-handed or a mirrored element, never a
/// folded one); and no face shared by more than two elements. Elements
/// that overlap without sharing faces are not detected.
fn check_hex_mesh(path: &str, mesh: &HexMesh) -> Result<(), CaseError> {
    let nodes = &mesh.nodes;
    check_mesh_size(path, nodes.len(), mesh.elements.len())?;
    for (i, v) in nodes.iter().enumerate() {
        finite(&format!("{path}.nodes[{i}]"), v)?;
    }
    let (lo, hi) = SolidGeometry::Mesh(HexMesh {
        nodes: nodes.clone(),
        elements: Vec::new(),
    })
    .bounds();
    let scale = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    let mut faces: std::collections::HashMap<[usize; 4], u8> = std::collections::HashMap::new();
    for (k, e) in mesh.elements.iter().enumerate() {
        let at = format!("{path}.elements[{k}]");
        if let Some(&i) = e.iter().find(|&&i| i >= nodes.len()) {
            return Err(CaseError::new(
                at,
                format!("node {i} does not exist ({} nodes)", nodes.len()),
            ));
        }
        if (0..8).any(|a| (a + 1..8).any(|b| e[a] == e[b])) {
            return Err(CaseError::new(at, "repeats a node"));
        }
        let corners = mesh.corners(k);
        let jacobians: Vec<f64> = (0..8)
            .map(|c| {
                let xi = [(c & 1) as f64, ((c >> 1) & 1) as f64, (c >> 2) as f64];
                solid_seeding::trilinear(&corners, xi).1
            })
            .collect();
        let small = 1e-12 * scale.powi(3);
        if !(jacobians.iter().all(|&j| j > small) || jacobians.iter().all(|&j| j < -small)) {
            return Err(CaseError::new(
                at,
                "is inverted or flat: its shape's Jacobian changes sign or vanishes at a corner \
                 (nodes in gmsh's order: one face 0 1 2 3, then 4 5 6 7 across from them)",
            ));
        }
        for face in 0..6 {
            let key = mesh.face_key(k, face);
            let count = faces.entry(key).or_insert(0);
            *count += 1;
            if *count > 2 {
                return Err(CaseError::new(
                    at,
                    format!("shares its face through nodes {key:?} with two other elements"),
                ));
            }
        }
    }
    Ok(())
}

/// Every component finite.
fn finite(path: &str, v: &[f64]) -> Result<(), CaseError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(CaseError::new(path, "must be finite numbers"))
    }
}

/// `min` below `max` in every component, both finite.
fn ordered<const N: usize>(path: &str, min: [f64; N], max: [f64; N]) -> Result<(), CaseError> {
    finite(path, &min)?;
    finite(path, &max)?;
    if (0..N).all(|d| min[d] < max[d]) {
        Ok(())
    } else {
        Err(CaseError::new(
            path,
            "each minimum must lie below its maximum",
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn column() -> serde_json::Value {
        crate::case::builtin::json("column3d").unwrap()
    }

    fn refused(case: &serde_json::Value) -> CaseError {
        SolidCase::from_json(&case.to_string()).unwrap_err()
    }

    #[test]
    fn the_built_in_3d_cases_are_valid() {
        for name in crate::case::builtin::SOLID_NAMES {
            let text = crate::case::builtin::get(name).unwrap();
            assert!(is_solid(text), "{name}");
            SolidCase::from_json(text).unwrap();
        }
    }

    /// Each shape's bounding box holds the points seeded in it, and
    /// [`SolidCase::points_bound`] is not below their count.
    #[test]
    fn the_point_bound_holds_every_shape() {
        let section = serde_json::json!({ "annulus": { "center": [0.0, 0.0],
            "inner_radius": 0.5, "outer_radius": 1.0 } });
        for geometry in [
            serde_json::json!({ "box": { "min": [0.0, 0.0, 0.0], "max": [1.0, 2.0, 0.5] } }),
            serde_json::json!({ "cylinder": { "center": [1.0, 0.0], "radius": 0.7, "z": [0.0, 1.0] } }),
            serde_json::json!({ "extrusion": { "section": section, "z": [-1.0, 0.0] } }),
            serde_json::json!({ "sphere": { "center": [0.0, 0.0, 0.0], "radius": 1.0 } }),
            serde_json::json!({ "spherical_shell": { "center": [0.0, 0.0, 3.0],
                "inner_radius": 0.6, "outer_radius": 1.0 } }),
        ] {
            let mut case = column();
            case["bodies"][0]["geometry"] = geometry.clone();
            case["grid"].as_object_mut().unwrap().remove("extent");
            case["grid"]["cell_size"] = 0.25.into();
            let case = SolidCase::from_json(&case.to_string()).unwrap();
            let seeds = crate::particles::solid_seeding::fill(
                &case.bodies[0].geometry.solid(),
                case.spacing(0),
            );
            let (lo, hi) = case.bodies[0].geometry.bounds();
            assert!(!seeds.is_empty(), "{geometry}");
            for s in &seeds {
                assert!((0..3).all(|d| s.position[d] >= lo[d] && s.position[d] <= hi[d]));
            }
            assert!(case.points_bound() >= seeds.len() as f64, "{geometry}");
        }
    }

    /// Surface loads: a region needs a surface or a box, and one of
    /// traction or pressure; their count is bounded; each is refused at
    /// its path.
    #[test]
    fn surface_loads_are_refused_at_their_field() {
        let with = |loads: serde_json::Value| {
            let mut case = column();
            case["loads"]["surface"] = loads;
            case
        };
        let top = serde_json::json!({ "plane": { "point": [0.0, 0.0, 50.0], "normal": [0.0, 0.0, 1.0] } });
        assert!(
            SolidCase::from_json(
                &with(serde_json::json!([{ "on": top, "pressure": 1.0 }])).to_string()
            )
            .is_ok()
        );
        for (loads, path) in [
            (
                serde_json::json!([{ "on": {}, "pressure": 1.0 }]),
                "loads.surface[0].on",
            ),
            (
                serde_json::json!([{ "on": top, "pressure": 1.0, "traction": [0.0, 0.0, 1.0] }]),
                "loads.surface[0]",
            ),
            (
                serde_json::json!([{ "on": { "plane": { "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 0.0] } }, "pressure": 1.0 }]),
                "loads.surface[0].on.plane.normal",
            ),
            (
                serde_json::json!([{ "on": { "sphere": { "center": [0.0, 0.0, 0.0], "radius": -1.0 } }, "pressure": 1.0 }]),
                "loads.surface[0].on.sphere.radius",
            ),
            (
                serde_json::json!([{ "on": { "body": 3, "inside": { "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0] } }, "pressure": 1.0 }]),
                "loads.surface[0].on.body",
            ),
            (
                serde_json::Value::Array(vec![
                    serde_json::json!({ "on": top, "pressure": 1.0 });
                    MAX_SURFACE_LOADS + 1
                ]),
                "loads.surface",
            ),
        ] {
            assert_eq!(refused(&with(loads.clone())).path, path, "{loads}");
        }
    }

    /// Values the types cannot check are refused at their path.
    #[test]
    fn bad_values_name_their_field() {
        let mut steps = column();
        steps["analysis"]["load_steps"] = 0.into();
        let mut plane = column();
        plane["supports"][0]["on"] = serde_json::json!({ "x": 0.0, "y": 0.0 });
        let mut fill = column();
        fill["bodies"][0]["points"] = serde_json::json!({ "per_cell": 2, "spacing": 0.5 });
        let mut shell = column();
        shell["bodies"][0]["geometry"] = serde_json::json!({ "spherical_shell": {
            "center": [0.0, 0.0, 0.0], "inner_radius": 2.0, "outer_radius": 1.0 } });
        let mut section = column();
        section["bodies"][0]["geometry"] = serde_json::json!({ "extrusion": {
            "section": { "circle": { "center": [0.0, 0.0], "radius": -1.0 } }, "z": [0.0, 1.0] } });
        let mut material = column();
        material["bodies"][0]["material"]["poisson_ratio"] = 0.5.into();
        let mut spline = column();
        spline["basis"] = "bspline2".into();
        let mut volumetric = column();
        volumetric["analysis"]["volumetric"] = "b_bar".into();
        let turning = |fix: &str, angle: f64| {
            let mut case = column();
            case["supports"][0]["fix"] = fix.into();
            case["supports"][0]["rotation"] =
                serde_json::json!({ "angle": angle, "center": [0.0, 0.0, 0.0] });
            case
        };
        for (case, path) in [
            (spline, "basis"),
            (volumetric, "analysis.volumetric"),
            (turning("z", 10.0), "supports[0].fix"),
            (turning("xyz", 400.0), "supports[0].rotation.angle"),
            (steps, "analysis.load_steps"),
            (plane, "supports[0].on"),
            (fill, "bodies[0].points"),
            (shell, "bodies[0].geometry.spherical_shell"),
            (section, "bodies[0].geometry.extrusion.section.circle"),
            (material, "bodies[0].material.poisson_ratio"),
        ] {
            let e = refused(&case);
            assert!(e.path.starts_with(path), "{path}: {e}");
        }
    }

    /// A hexahedral mesh body is refused at the element that is not one
    /// (a missing or repeated node, an inverted or flat shape, a face of
    /// three elements); a good one of two elements, one of them mirrored,
    /// is taken, and seeds its exact volume.
    #[test]
    fn a_hexahedral_mesh_that_is_not_one_is_refused() {
        let nodes: Vec<[f64; 3]> = (0..12)
            .map(|n| [(n % 3) as f64, ((n / 3) % 2) as f64, (n / 6) as f64])
            .collect();
        let good = [[0, 1, 4, 3, 6, 7, 10, 9], [2, 1, 4, 5, 8, 7, 10, 11]];
        let case = |elements: Vec<[usize; 8]>| {
            let mut case = column();
            case["bodies"][0]["geometry"] =
                serde_json::json!({ "mesh": { "nodes": nodes.clone(), "elements": elements } });
            case["grid"].as_object_mut().unwrap().remove("extent");
            case["supports"] = serde_json::json!([]);
            case
        };
        let taken = SolidCase::from_json(&case(good.to_vec()).to_string()).unwrap();
        let seeds = crate::particles::solid_seeding::fill(
            &taken.bodies[0].geometry.solid(),
            taken.spacing(0),
        );
        let volume: f64 = seeds.iter().map(|s| s.volume).sum();
        assert!((volume - 2.0).abs() < 1e-14, "{volume}");
        let flat = [0, 1, 4, 3, 0, 1, 4, 3];
        let folded = [0, 1, 3, 4, 6, 7, 10, 9];
        for (elements, message) in [
            (vec![good[0], [0, 1, 4, 3, 6, 7, 10, 12]], "does not exist"),
            (vec![good[0], flat], "repeats a node"),
            (vec![good[0], folded], "inverted or flat"),
            (vec![good[0], good[0], good[0]], "two other elements"),
        ] {
            let e = refused(&case(elements));
            assert!(
                e.path.starts_with("bodies[0].geometry.mesh.elements["),
                "{e}"
            );
            assert!(e.message.contains(message), "{e}");
        }
    }

    /// A plane-strain case is no 3D case, and the reverse: each refuses
    /// the other's fields at their path.
    #[test]
    fn the_two_formats_refuse_each_others_fields() {
        let mut boundary = column();
        boundary["boundary"] = serde_json::json!({ "representation": "points" });
        assert_eq!(refused(&boundary).path, "boundary");
        let mut origin = column();
        origin["grid"]["origin"] = serde_json::json!([0.0, 0.0]);
        assert_eq!(refused(&origin).path, "grid.origin");
        let mut plane = crate::case::builtin::json("column").unwrap();
        plane["grid"]["origin"] = serde_json::json!([0.0, 0.0, 0.0]);
        let e = crate::Case::from_json(&plane.to_string()).unwrap_err();
        assert_eq!(e.path, "grid.origin");
        assert!(!is_solid(&plane.to_string()));
    }
}
