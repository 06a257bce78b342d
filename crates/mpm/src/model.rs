//! From the case (what a user submits) to the solver's own types: the only
//! module that reads the case schema. It seeds the bodies with points,
//! finds their boundary loops and resolves every boundary selector to loop
//! segments once ([`Seeded`]), then splits the supports by how they are
//! imposed.

use crate::assembly::PointLoad;
use crate::assembly::lone_points::LONE_VOLUME;
use crate::boundary::edge_detection::loops_on_edge;
use crate::boundary::face_loads::FaceLoad;
use crate::boundary::face_patches::{FacePatch, face_patches};
use crate::boundary::ibm::{self, IbmMotion, IbmSupport, SurfaceSupport};
use crate::boundary::loading::LoadedStretch;
use crate::boundary::surface_loading::{LoadedCells, SurfaceTraction};
use crate::boundary::traction::Traction;
use crate::boundary::{
    BoundaryLoop, Piece, Representation, find_loops, selected_pieces, selected_segments,
    set_offsets, snap_to_edge,
};
use crate::case::solid::{SolidCase, SurfaceSelector};
use crate::case::{
    self, BasisKind, Body, Case, CaseError, GridSpec, Loads, MaterialSpec, SupportMethod,
    Volumetric,
};
use crate::geometry::Geometry;
use crate::geometry::Selector;
use crate::grid::{Basis, Grid};
use crate::linsolve::SolverSettings;
use crate::material::{DruckerPrager, Elastic, Material, MohrCoulomb, StiffnessScales, VonMises};
use crate::newton::NewtonSettings;
use crate::particles::seeding::{self, Density, FillSize, Lattice};
use crate::particles::solid_seeding::fill;
use crate::particles::{Dim, MaterialPoints, Space};
use crate::probes::Probes;
use crate::report::{PointField, RunWarning, StepReport};
use crate::stages::{Stage, StrengthReduction};
use crate::stepper::{Simulation, StepSize, Substepping};
use crate::supports::{Fix, GridSupport, HeldDofs, PlaneSupport, Rotation};

/// What a case's bodies make before any load step: the material points
/// and their boundary loops. Seeding is where reading a case costs time and
/// memory; the one check left after validation, a boundary selector that
/// picks nothing, is made on what it seeds ([`Seeded::segments`],
/// [`Seeded::pieces`]), naming the field.
pub struct Seeded {
    pub points: MaterialPoints,
    pub loops: Vec<BoundaryLoop>,
    h: f64,
    on_edge: bool,
}

impl Seeded {
    /// Seeds a validated case.
    pub fn new(case: &Case) -> Self {
        let points = material_points(case);
        let loops = boundary_loops(case, &points);
        Self {
            points,
            loops,
            h: case.grid.cell_size,
            on_edge: Representation::from(case.boundary.representation) == Representation::Edge,
        }
    }

    fn none_selected(path: &str) -> CaseError {
        CaseError::new(
            path,
            "selects no stretch of any body's boundary (it must pass within about \
             a point spacing of two neighbouring outer points)",
        )
    }

    /// The loop segments, `(loop index, segments)`, a boundary load's `on`
    /// (at `path`) picks.
    fn segments(&self, on: &Selector, path: &str) -> Result<Vec<(usize, Vec<usize>)>, CaseError> {
        let s = selected_segments(on, &self.loops, &self.points, self.h, self.on_edge);
        (!s.is_empty())
            .then_some(s)
            .ok_or_else(|| Self::none_selected(path))
    }

    /// The pieces of curve, `(loop index, pieces)`, an IBM support's `on`
    /// (at `path`) holds.
    fn pieces(&self, on: &Selector, path: &str) -> Result<Vec<(usize, Vec<Piece>)>, CaseError> {
        let s = selected_pieces(on, &self.loops, &self.points, self.h, self.on_edge);
        (!s.is_empty())
            .then_some(s)
            .ok_or_else(|| Self::none_selected(path))
    }
}

/// The loads of a stage's end, each with the field it came from: gravity,
/// point loads by `at`, boundary loads by `on` and kind.
#[derive(Default, Clone)]
struct LoadState {
    gravity: [f64; 2],
    point: Vec<([f64; 2], [f64; 2], String)>,
    boundary: Vec<(Selector, Traction, String)>,
}

impl LoadState {
    /// `loads` (at `prefix`) added to this state, matched by identity.
    fn add(&mut self, loads: &Loads, prefix: &str) {
        if let Some(g) = loads.gravity {
            self.gravity = [self.gravity[0] + g[0], self.gravity[1] + g[1]];
        }
        for (i, l) in loads.point_loads.iter().enumerate() {
            match self.point.iter_mut().find(|(at, _, _)| *at == l.at) {
                Some((_, f, _)) => *f = [f[0] + l.force[0], f[1] + l.force[1]],
                None => self
                    .point
                    .push((l.at, l.force, format!("{prefix}.point_loads[{i}]"))),
            }
        }
        for (i, l) in loads.boundary.iter().enumerate() {
            let t = match (l.traction, l.pressure) {
                (Some(t), _) => Traction::Dead(t),
                (None, Some(p)) => Traction::Pressure(p),
                (None, None) => continue, // rejected by validation
            };
            let same = |(on, u, _): &&mut (Selector, Traction, String)| {
                *on == l.on
                    && matches!(
                        (u, t),
                        (Traction::Dead(_), Traction::Dead(_))
                            | (Traction::Pressure(_), Traction::Pressure(_))
                    )
            };
            match self.boundary.iter_mut().find(same) {
                Some((_, u, _)) => *u = traction_sum(*u, t, 1.0),
                None => self
                    .boundary
                    .push((l.on, t, format!("{prefix}.boundary[{i}].on"))),
            }
        }
    }

    /// The loads of stage `k`'s end, after the state `before` of the stage
    /// before.
    fn of_stage(case: &Case, k: usize, before: &LoadState) -> LoadState {
        let Some(stage) = case.stages.get(k) else {
            let mut state = LoadState::default();
            state.add(&case.loads, "loads");
            return state;
        };
        let mut state = match &stage.loads {
            Some(targets) => {
                let mut s = LoadState::default();
                s.add(targets, &format!("stages[{k}].loads"));
                s
            }
            None => before.clone(),
        };
        if let Some(increments) = &stage.load_increments {
            state.add(increments, &format!("stages[{k}].load_increments"));
        }
        state
    }
}

/// `a + w b` for tractions of one kind.
fn traction_sum(a: Traction, b: Traction, w: f64) -> Traction {
    match (a, b) {
        (Traction::Dead(x), Traction::Dead(y)) => {
            Traction::Dead([x[0] + w * y[0], x[1] + w * y[1]])
        }
        (Traction::Pressure(x), Traction::Pressure(y)) => Traction::Pressure(x + w * y),
        _ => unreachable!("matched by kind"),
    }
}

fn is_zero(t: Traction) -> bool {
    match t {
        Traction::Dead(x) => x == [0.0, 0.0],
        Traction::Pressure(p) => p == 0.0,
    }
}

/// The stages of a case, from its seeded bodies: each stage's loads split
/// into what it holds from the stage before and what it ramps, and its
/// supports; with the run's implicit-boundary supports (the first
/// stage's), whose anchors the later stages move on.
fn stages(case: &Case, seeded: &Seeded) -> Result<(Vec<Stage>, Vec<IbmSupport>), CaseError> {
    let views = case.stage_views();
    let mut out = Vec::with_capacity(views.len());
    let mut ibm_supports: Vec<IbmSupport> = Vec::new();
    let mut before = LoadState::default();
    for (k, view) in views.iter().enumerate() {
        let end = LoadState::of_stage(case, k, &before);
        let mut boundary_loads = Vec::new();
        let mut stretches = |on: &Selector, path: &str, traction: Traction, held: bool| {
            let selection = seeded.segments(on, path)?;
            boundary_loads.extend(selection.into_iter().map(|(loop_index, segments)| {
                LoadedStretch {
                    loop_index,
                    segments,
                    traction,
                    held,
                }
            }));
            Ok::<(), CaseError>(())
        };
        for (on, t, path) in &before.boundary {
            if !is_zero(*t) {
                stretches(on, path, *t, true)?;
            }
        }
        for (on, t, path) in &end.boundary {
            let start = before.boundary.iter().find(|(o, u, _)| {
                o == on && std::mem::discriminant(u) == std::mem::discriminant(t)
            });
            match start {
                None => stretches(on, path, *t, false)?,
                Some((_, u, _)) => {
                    let change = traction_sum(*t, *u, -1.0);
                    if !is_zero(change) {
                        stretches(on, path, change, false)?;
                    }
                }
            }
        }
        for (on, u, path) in &before.boundary {
            let kept = end
                .boundary
                .iter()
                .any(|(o, t, _)| o == on && std::mem::discriminant(u) == std::mem::discriminant(t));
            if !kept && !is_zero(*u) {
                stretches(on, path, traction_sum(*u, *u, -2.0), false)?;
            }
        }
        let mut point_loads = Vec::new();
        let point = |at: [f64; 2]| nearest_point(&seeded.points, at);
        for (at, f, _) in &before.point {
            if *f != [0.0, 0.0] {
                point_loads.push(PointLoad {
                    point: point(*at),
                    force: *f,
                    held: true,
                });
            }
        }
        for (at, f, _) in &end.point {
            let start = before
                .point
                .iter()
                .find(|(a, _, _)| a == at)
                .map_or([0.0; 2], |p| p.1);
            let change = [f[0] - start[0], f[1] - start[1]];
            if change != [0.0, 0.0] || before.point.is_empty() {
                point_loads.push(PointLoad {
                    point: point(*at),
                    force: change,
                    held: false,
                });
            }
        }
        for (at, f, _) in &before.point {
            if !end.point.iter().any(|(a, _, _)| a == at) && *f != [0.0, 0.0] {
                point_loads.push(PointLoad {
                    point: point(*at),
                    force: [-f[0], -f[1]],
                    held: false,
                });
            }
        }
        let geostatic = case.stages.get(k).and_then(|s| s.geostatic).map(|g| g.k0);
        // A geostatic stage's gravity is on in full: its stresses carry it.
        let gravity = if geostatic.is_some() {
            [end.gravity, [0.0, 0.0]]
        } else {
            [
                before.gravity,
                [
                    end.gravity[0] - before.gravity[0],
                    end.gravity[1] - before.gravity[1],
                ],
            ]
        };
        let mut grid_supports = Vec::new();
        let mut ibm = vec![None; ibm_supports.len()];
        for (index, s) in view.supports.iter().enumerate() {
            let path = format!("{}[{index}].on", view.supports_path);
            match s.method {
                SupportMethod::Grid => grid_supports.push(GridSupport {
                    index,
                    on: s.on,
                    fix: s.fix.into(),
                }),
                SupportMethod::Ibm if k == 0 => ibm_supports.push(IbmSupport {
                    index,
                    pieces: seeded.pieces(&s.on, &path)?,
                    fix: s.fix.into(),
                    displacement: s.displacement.unwrap_or([0.0, 0.0]),
                    rotation: s.rotation.map(Into::into),
                    averaged: (s.constraint == case::Constraint::Averaged)
                        .then_some((ibm::AVERAGED_PIECE_CELLS * case.grid.cell_size, s.on)),
                }),
                SupportMethod::Ibm => {
                    let first = &views[0].supports;
                    let owner = (first.iter().filter(|f| f.method == SupportMethod::Ibm))
                        .position(|f| f.same_as(s))
                        .expect("validated: it continues one of the first stage");
                    ibm[owner] = Some(IbmMotion {
                        index,
                        displacement: s.displacement.unwrap_or([0.0, 0.0]),
                        rotation: s.rotation.map(Into::into),
                    });
                }
            }
        }
        out.push(Stage {
            name: (!case.stages.is_empty()).then(|| {
                view.name
                    .map_or_else(|| format!("stage {}", k + 1), str::to_string)
            }),
            load_steps: view.load_steps as usize,
            gravity,
            point_loads,
            face_loads: Vec::new(),
            surface_loads: Vec::new(),
            boundary_loads,
            grid_supports,
            ibm,
            n_supports: view.supports.len(),
            geostatic,
            arc_length: view.control == case::Control::ArcLength,
            strength_reduction: case
                .stages
                .get(k)
                .and_then(|s| s.strength_reduction)
                .map(|r| StrengthReduction {
                    increment: r.increment,
                    tolerance: r.tolerance,
                    flow_limit: r.flow_limit,
                }),
        });
        before = end;
    }
    Ok((out, ibm_supports))
}

impl Simulation {
    /// Builds the initial state of a validated case. Fails, naming the
    /// field, when a boundary load or an IBM support selects no stretch of
    /// any body's boundary, or a grid-node support no node the material
    /// reaches (which could not be told before the points were generated).
    pub fn new(case: &Case) -> Result<Self, CaseError> {
        let seeded = Seeded::new(case);
        let (stages, ibm_supports) = stages(case, &seeded)?;
        let Seeded { points, loops, .. } = seeded;
        let grid = Grid {
            h: case.grid.cell_size,
            origin: case.grid.origin,
        };
        let anchors = ibm::anchors(&ibm_supports, &loops, &points, &grid, basis(case.basis));
        let newton = &case.analysis.newton;
        let stabilisation = case.analysis.stabilisation_settings();
        let stiffness = StiffnessScales::of(&points.materials);
        let free_step_growth = (10.0 * stiffness.p_wave_to_shear).max(BENDING_FREE_GROWTH);
        let sim = Self {
            grid,
            basis: basis(case.basis),
            extent: case.grid.extent.map(|b| (b.min, b.max)),
            probes: Probes::new(case.probes.iter().map(|p| (p.name.clone(), p.at))),
            first_stage_anchors: anchors.len(),
            anchors,
            surface_anchors: Vec::new(),
            band_width: case
                .boundary
                .band_width
                .unwrap_or(ibm::DEFAULT_BAND_WIDTH * grid.h),
            loops,
            faces: Vec::new(),
            points,
            stages,
            stage: 0,
            settings: NewtonSettings {
                tolerance: newton.tolerance,
                max_iterations: newton.max_iterations as usize,
                tangent_regularisation: stabilisation.tangent_regularisation,
                line_search: newton.line_search,
                predictor: newton.predictor,
                ghost_penalty: stabilisation.ghost_penalty,
                hourglass: stabilisation.hourglass,
                lone_points: stabilisation.lone_points,
                free_step_growth,
                ..Default::default()
            },
            volumetric: case.analysis.volumetric,
            step_size: StepSize::default(),
            arc: None,
            last_increment: None,
            reduction: None,
            settled: None,
            steps_done: 0,
            stiffness,
            solver: SolverSettings::default(),
            solve_tally: Default::default(),
            analysed: None,
            substepping: Substepping {
                min_fraction: case.analysis.substepping.min_fraction,
                max_cutbacks: case.analysis.substepping.max_cutbacks as usize,
            },
            load_steps: case.total_load_steps() as usize,
        };
        sim.check_grid_supports(case)?;
        check_inside_extent(case, &sim.points)?;
        check_probes(case, &sim.points, &grid)?;
        Ok(sim)
    }

    /// A grid-node support must hold some node the material reaches at the
    /// start: one that holds none (a point between nodes, a line between
    /// grid lines) would leave the body free there, and the run would fail
    /// later with an inverted point or a stalled Newton that does not say
    /// why. Each stage's, on the configuration the run starts from.
    fn check_grid_supports(&self, case: &Case) -> Result<(), CaseError> {
        let views = case.stage_views();
        for (stage, view) in self.stages.iter().zip(&views) {
            if stage.grid_supports.is_empty() {
                continue;
            }
            let held = HeldDofs::find(&stage.grid_supports, &self.grid, &self.reset_grid());
            if let Some(index) = held.first_idle() {
                return Err(CaseError::new(
                    format!("{}[{index}].on", view.supports_path),
                    format!(
                        "selects none of the grid nodes the material reaches (grid-node supports hold \
                         nodes, which lie at grid.origin + k * {} m); move it onto a node or grid line, \
                         or use \"method\": \"ibm\" to hold the boundary curve itself",
                        self.grid.h
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// A 3D run as the solver's parts make it, until the case schema reads 3D
/// bodies (issue 38): one stage of `load_steps` equal steps, gravity and
/// the point loads ramped with the load factor, supports on grid planes.
pub struct SolidRun {
    pub grid: Grid<3>,
    pub basis: Basis,
    /// The grid's extent `(min, max)`, if bounded.
    pub extent: Option<([f64; 3], [f64; 3])>,
    pub points: MaterialPoints<3>,
    pub gravity: [f64; 3],
    pub point_loads: Vec<PointLoad<3>>,
    /// Tractions on faces of boxes ([`face_loads`]).
    pub face_loads: Vec<FaceLoad<3>>,
    /// The bodies' surfaces ([`face_patches`]) and the loads on them.
    pub faces: Vec<FacePatch>,
    pub surface_loads: Vec<LoadedCells>,
    pub supports: Vec<PlaneSupport<3>>,
    /// Supports on the surfaces by the implicit boundary method, indexed
    /// after `supports`.
    pub surface_supports: Vec<SurfaceSupport>,
    pub load_steps: usize,
}

/// A surface region's default tolerance, in the body's point spacings:
/// well under the quarter spacing by which the cells of a face's
/// neighbour along their common edge stand off it
/// ([`FacePatch::cell_middles`]), well over a curved face's cells' error.
pub const SURFACE_TOLERANCE: f64 = 0.1;

impl Simulation<3> {
    /// Builds the initial state of a validated 3D case. Fails, naming the
    /// field, when a body holds no point or a support no node the material
    /// reaches, or a point lies outside the grid's extent.
    pub fn from_solid_case(case: &SolidCase) -> Result<Self, CaseError> {
        let mut points = MaterialPoints::<3>::default();
        let mut faces = Vec::new();
        for (i, body) in case.bodies.iter().enumerate() {
            let solid = body.geometry.solid();
            let seeds = fill(&solid, case.spacing(i));
            if seeds.is_empty() {
                return Err(CaseError::new(
                    format!("bodies[{i}].points"),
                    "the body holds no point at this spacing",
                ));
            }
            let (_, _, rho) = body.material.constants();
            points.add_solid(material(&body.material), rho, &seeds);
            faces.extend(face_patches(&points, i, &solid, case.spacing(i)));
        }
        let extent = case.grid.extent.map(|b| (b.min, b.max));
        if let Some((lo, hi)) = extent {
            let tol = 1e-9 * case.grid.cell_size;
            if let Some(p) = (0..points.len()).find(|&p| {
                let x = points.position[p];
                !(0..3).all(|d| x[d] >= lo[d] - tol && x[d] <= hi[d] + tol)
            }) {
                return Err(CaseError::new(
                    "grid.extent",
                    format!(
                        "material point {p} at {:?} lies outside the extent",
                        points.position[p]
                    ),
                ));
            }
        }
        let point_loads = (case.loads.point_loads.iter())
            .map(|load| PointLoad {
                point: nearest_point(&points, load.at),
                force: load.force,
                held: false,
            })
            .collect();
        let mut tractions = Vec::new();
        for (i, t) in case.loads.tractions.iter().enumerate() {
            let (axis, at) = t.on.plane().expect("validated: one plane");
            let tol = 1e-9 * case.grid.cell_size;
            let loads = face_loads(&points, (axis, at, tol), t.traction, false);
            if loads.is_empty() {
                return Err(CaseError::new(
                    format!("loads.tractions[{i}].on"),
                    "no body has a face on this plane",
                ));
            }
            tractions.extend(loads);
        }
        let middles: Vec<Vec<[f64; 3]>> = faces.iter().map(|f| f.cell_middles(&points)).collect();
        // The cells of each patch a selector takes (those whose middle
        // it contains; for a support, those on its surfaces, whose
        // quadrature points its ranges then choose), or the error at `path`.
        let select = |on: &SurfaceSelector, path: String, whole: bool| {
            let regions: Vec<(usize, Vec<usize>)> = (faces.iter().enumerate())
                .filter(|(_, face)| on.body.is_none_or(|b| b == face.body))
                .map(|(patch, face)| {
                    let tolerance = case.spacing(face.body) * SURFACE_TOLERANCE;
                    let cells = (middles[patch].iter().enumerate())
                        .filter(|(_, x)| {
                            if whole {
                                on.contains(**x, tolerance)
                            } else {
                                on.on_surfaces(**x, tolerance)
                            }
                        })
                        .map(|(c, _)| c)
                        .collect();
                    (patch, cells)
                })
                .filter(|(_, cells): &(usize, Vec<usize>)| !cells.is_empty())
                .collect();
            if regions.is_empty() {
                return Err(CaseError::new(
                    path,
                    "selects no part of any body's surface",
                ));
            }
            Ok(regions)
        };
        let mut surface_loads = Vec::new();
        for (i, load) in case.loads.surface.iter().enumerate() {
            let traction = match (load.traction, load.pressure) {
                (Some(t), _) => SurfaceTraction::Dead(t),
                (None, p) => SurfaceTraction::Pressure(p.expect("validated: one of the two")),
            };
            let regions = select(&load.on, format!("loads.surface[{i}].on"), true)?;
            surface_loads.extend(regions.into_iter().map(|(patch, cells)| LoadedCells {
                patch,
                cells,
                traction,
                held: false,
            }));
        }
        let surface_supports = (case.surface_supports.iter().enumerate())
            .map(|(i, s)| {
                Ok(SurfaceSupport {
                    index: case.supports.len() + i,
                    regions: select(&s.on, format!("surface_supports[{i}].on"), false)?,
                    ranges: s.on.has_ranges().then_some(s.on),
                    held: s.fix.held(),
                    displacement: s.displacement.unwrap_or_default(),
                    averaged: (s.constraint == case::Constraint::Averaged)
                        .then_some(ibm::AVERAGED_PIECE_CELLS * case.grid.cell_size),
                })
            })
            .collect::<Result<Vec<_>, CaseError>>()?;
        let supports = (case.supports.iter().enumerate())
            .map(|(index, s)| {
                let (axis, at) = s.on.plane().expect("validated: one plane");
                PlaneSupport {
                    index,
                    axis,
                    at,
                    fix: s.fix.components_on(axis),
                    rotation: s.rotation.map(|r| (r.angle.to_radians(), r.center)),
                }
            })
            .collect();
        let newton = &case.analysis.newton;
        let mut sim = Simulation::solid(SolidRun {
            grid: Grid {
                h: case.grid.cell_size,
                origin: case.grid.origin,
            },
            basis: basis(case.basis),
            extent,
            points,
            gravity: case.loads.gravity.unwrap_or_default(),
            point_loads,
            face_loads: tractions,
            faces,
            surface_loads,
            supports,
            surface_supports,
            load_steps: case.analysis.load_steps as usize,
        });
        for i in 0..case.surface_supports.len() {
            let index = case.supports.len() + i;
            if !sim.surface_anchors.iter().any(|a| a.support == index) {
                return Err(CaseError::new(
                    format!("surface_supports[{i}].on"),
                    "selects no part of any body's surface within its ranges",
                ));
            }
        }
        sim.settings.tolerance = newton.tolerance;
        sim.settings.max_iterations = newton.max_iterations as usize;
        sim.settings.line_search = newton.line_search;
        sim.settings.predictor = newton.predictor;
        sim.settings.ghost_penalty = case.analysis.stabilisation.ghost_penalty;
        sim.volumetric = case.analysis.volumetric;
        sim.settings.hourglass = case.analysis.stabilisation.hourglass;
        sim.substepping = Substepping {
            min_fraction: case.analysis.substepping.min_fraction,
            max_cutbacks: case.analysis.substepping.max_cutbacks as usize,
        };
        let held = HeldDofs::find(&sim.stages[0].grid_supports, &sim.grid, &sim.reset_grid());
        if let Some(idle) = held.first_idle() {
            return Err(CaseError::new(
                format!("supports[{idle}].on"),
                "holds no grid node the material reaches: put the plane on a grid plane at the body",
            ));
        }
        Ok(sim)
    }

    /// The run `run` describes, with the default Newton settings and
    /// load-step cutting.
    pub fn solid(run: SolidRun) -> Self {
        let SolidRun {
            grid,
            basis,
            extent,
            points,
            gravity,
            point_loads,
            face_loads,
            faces,
            surface_loads,
            supports,
            surface_supports,
            load_steps,
        } = run;
        let surface_anchors = ibm::surface_anchors(&surface_supports, &faces, &points);
        let stiffness = StiffnessScales::of(&points.materials);
        let free_step_growth = (10.0 * stiffness.p_wave_to_shear).max(BENDING_FREE_GROWTH);
        let stage = Stage {
            name: None,
            load_steps,
            gravity: [[0.0; 3], gravity],
            point_loads,
            face_loads,
            surface_loads,
            boundary_loads: Vec::new(),
            n_supports: supports.len() + surface_supports.len(),
            grid_supports: supports,
            ibm: Vec::new(),
            geostatic: None,
            arc_length: false,
            strength_reduction: None,
        };
        Self {
            grid,
            basis,
            extent,
            points,
            loops: Vec::new(),
            faces,
            probes: Probes::default(),
            stages: vec![stage],
            stage: 0,
            anchors: Vec::new(),
            surface_anchors,
            first_stage_anchors: 0,
            band_width: ibm::DEFAULT_BAND_WIDTH * grid.h,
            settings: NewtonSettings {
                free_step_growth,
                ..Default::default()
            },
            substepping: Substepping::default(),
            step_size: StepSize::default(),
            arc: None,
            last_increment: None,
            reduction: None,
            settled: None,
            volumetric: Volumetric::Standard,
            load_steps,
            steps_done: 0,
            stiffness,
            solver: SolverSettings::default(),
            solve_tally: Default::default(),
            analysed: None,
        }
    }
}

/// Every point must start inside the grid's extent, which has no nodes
/// beyond it: a body outside it failed on the worker ("left the grid")
/// rather than being refused, named.
fn check_inside_extent(case: &Case, points: &MaterialPoints) -> Result<(), CaseError> {
    let Some(extent) = &case.grid.extent else {
        return Ok(());
    };
    let outside = |x: &[f64; 2]| (0..2).any(|d| !(x[d] >= extent.min[d] && x[d] <= extent.max[d]));
    match points.position.iter().position(outside) {
        Some(p) => {
            let [x, y] = points.position[p];
            Err(CaseError::new(
                format!("bodies[{}].geometry", points.material[p]),
                format!(
                    "has material at ({x}, {y}) m, outside grid.extent [{}, {}] x [{}, {}] m: \
                     the grid has no nodes there",
                    extent.min[0], extent.max[0], extent.min[1], extent.max[1]
                ),
            ))
        }
        None => Ok(()),
    }
}

/// A probe must start in the material: within the cells that hold points
/// or next to one. One outside every body follows no grid node, and
/// reported [0, 0] at every step.
fn check_probes(case: &Case, points: &MaterialPoints, grid: &Grid) -> Result<(), CaseError> {
    if case.probes.is_empty() {
        return Ok(());
    }
    let cell = |x: [f64; 2]| [0, 1].map(|d| ((x[d] - grid.origin[d]) / grid.h).floor() as i64);
    let occupied: std::collections::HashSet<[i64; 2]> =
        points.position.iter().map(|&x| cell(x)).collect();
    for (i, probe) in case.probes.iter().enumerate() {
        let [ci, cj] = cell(probe.at);
        let near = (-1..=1).any(|di| (-1..=1).any(|dj| occupied.contains(&[ci + di, cj + dj])));
        if !near {
            return Err(CaseError::new(
                format!("probes[{i}].at"),
                format!(
                    "({}, {}) lies outside every body: a probe follows the material it starts in",
                    probe.at[0], probe.at[1]
                ),
            ));
        }
    }
    Ok(())
}

/// Every body of the case filled with points in its reference state.
fn material_points(case: &Case) -> MaterialPoints {
    let mut mp = MaterialPoints::default();
    for body in &case.bodies {
        let seeds = seeding::fill(
            &body.geometry,
            density(body, case.grid.cell_size),
            case.grid.origin,
            body.points.lattice.into(),
        );
        let (_, _, rho) = body.material.constants();
        mp.add_body(material(&body.material), rho, &seeds);
    }
    mp
}

/// The boundary loops of every body with their data-point offsets: from
/// lattice neighbours for a body on one lattice, its data points then put
/// on the exact edge (`edge` representation); from the exact edge itself
/// for a body of patches or polar rings ([`seeding::follows_edge`]).
fn boundary_loops(case: &Case, points: &MaterialPoints) -> Vec<BoundaryLoop> {
    let representation = Representation::from(case.boundary.representation);
    let on_edge: Vec<bool> = (case.bodies.iter())
        .map(|b| seeding::follows_edge(&b.geometry, b.points.lattice.into()))
        .collect();
    let mut loops: Vec<BoundaryLoop> =
        find_loops(&points.lattice, &points.material, &points.reference, |b| {
            !on_edge[b]
        });
    set_offsets(&mut loops, points, representation);
    if representation == Representation::Edge {
        let geometries: Vec<&Geometry> = case.bodies.iter().map(|b| &b.geometry).collect();
        snap_to_edge(&mut loops, points, &geometries);
    }
    for (b, body) in case.bodies.iter().enumerate().filter(|(b, _)| on_edge[*b]) {
        let ids: Vec<usize> = (0..points.len())
            .filter(|&p| points.material[p] as usize == b)
            .collect();
        for mut l in loops_on_edge(b, &body.geometry.rings(), points, &ids) {
            if representation == Representation::Points {
                // Through the points: each once, in the edge's order.
                l.points.dedup();
                if l.points.len() > 1 && l.points.first() == l.points.last() {
                    l.points.pop();
                }
                l.offset = vec![[0.0, 0.0]; l.points.len()];
            }
            loops.push(l);
        }
    }
    loops
}

/// The constitutive model of a material spec.
fn material(spec: &MaterialSpec) -> Material {
    let (e, nu, _) = spec.constants();
    let constants = Elastic::from_young_poisson(e, nu);
    match spec {
        MaterialSpec::Hencky { .. } => Material::Hencky(constants),
        MaterialSpec::LinearElastic { .. } => Material::LinearElastic(constants),
        MaterialSpec::VonMises {
            yield_stress,
            hardening,
            ..
        } => Material::VonMises(VonMises {
            elastic: constants,
            yield_stress: *yield_stress,
            hardening: *hardening,
        }),
        MaterialSpec::DruckerPrager {
            cohesion,
            friction_angle,
            dilation_angle,
            ..
        } => Material::DruckerPrager(DruckerPrager::plane_strain_match(
            constants,
            *cohesion,
            friction_angle.to_radians(),
            dilation_angle.unwrap_or(*friction_angle).to_radians(),
        )),
        MaterialSpec::MohrCoulomb {
            cohesion,
            friction_angle,
            dilation_angle,
            ..
        } => Material::MohrCoulomb(MohrCoulomb {
            elastic: constants,
            cohesion: *cohesion,
            friction: friction_angle.to_radians(),
            dilation: dilation_angle.unwrap_or(*friction_angle).to_radians(),
        }),
    }
}

/// How densely a body is seeded, on a grid of `cell_size`.
fn density(body: &Body, cell_size: f64) -> Density {
    let p = &body.points;
    match (p.count, p.per_cell, p.spacing) {
        (Some(c), _, _) => Density::Count(c),
        (_, Some(n), _) => Density::Spacing(cell_size / n as f64),
        (_, _, Some(s)) => Density::Spacing(s),
        _ => Density::Spacing(f64::NAN), // rejected by validation
    }
}

/// How many lattice sites seeding a body visits, counted without seeding
/// it (see [`seeding::size`]).
pub fn fill_size(body: &Body, grid: &GridSpec) -> FillSize {
    seeding::size(
        &body.geometry,
        density(body, grid.cell_size),
        grid.origin,
        body.points.lattice.into(),
    )
}

/// The least growth of the out-of-balance force a free full Newton step
/// may take (`newton::Search`), whatever the material. A slender beam's
/// first iteration from rest is its linear solution, which stretches the
/// beam: on the elastica of `mpm study robustness` (L / d = 10, nu = 0.2,
/// P L^2 / EI = 0.5 in its first step) the full step raises the force by
/// between 100 and 300 times, against the 27 that ten times the P-wave to
/// shear ratio allows. Cut there, the search crept at a hundredth of each
/// step and the first try failed after 30 iterations (117 in all, one cut);
/// taken, the run takes 97 and no cut, to the same answer.
const BENDING_FREE_GROWTH: f64 = 1e3;

/// What a case and its finished steps warn a reader of:
/// - `bilinear_crossing`: the bilinear basis, with points that left the
///   cell they started in. Its gradient jumps at cell edges, so on large
///   deformation its answers move with the load steps and do not converge
///   with the cell (docs/study/bases).
/// - `one_point_a_cell`: a body filled with one point a cell or fewer
///   (`per_cell` 1, a `spacing` of 0.71 cells or more, or a `count` of
///   as much area a point, as the stabilisation of one-point cells counts
///   them) where that costs
///   accuracy: a plastic body, or any with the stabilisation of one-point
///   cells off (nothing then holds a cell's hourglass modes); or on GIMP
///   or the bilinear basis, whose large rotations drift with the load steps
///   more than at two points a cell (docs/study/robustness). Elastic
///   bodies on the B-splines, stabilised, are within 1.3% on a clamped
///   elastica two cells deep (two points a cell: 2.7%) and are not warned
///   of.
pub fn warnings(case: &Case, steps: &[StepReport]) -> Vec<RunWarning> {
    let mut out = Vec::new();
    let crossed = steps
        .iter()
        .map(|s| s.points_in_new_cells)
        .max()
        .unwrap_or(0);
    if case.basis == BasisKind::Linear && crossed > 0 {
        out.push(RunWarning {
            kind: "bilinear_crossing",
            message: format!(
                "{crossed} points left the cell they started in on the bilinear basis (\"linear\"): \
                 its gradient jumps at cell edges, so on large deformation its answers move with \
                 the load steps (7% to 35% on the paper's cantilever from 5 to 100 steps) and do \
                 not converge with the cell (a clamped elastica's tip 10-17% off at three cells, \
                 no trend). For large deformation use \"gimp\" or \"bspline2\" (docs/study/bases, \
                 docs/study/robustness)."
            ),
        });
    }
    let stabilised = case.analysis.stabilisation_settings().lone_points;
    for (k, body) in case.bodies.iter().enumerate() {
        // Seeded as sparsely as the stabilisation of one-point cells takes
        // a body (a point's area at least `LONE_VOLUME` of a cell's).
        let h = case.grid.cell_size;
        let area_a_point = match density(body, h) {
            Density::Spacing(s) => s * s,
            Density::Count([nx, ny]) => {
                let area = match &body.geometry {
                    Geometry::Rectangle { min, max, .. } => (max[0] - min[0]) * (max[1] - min[1]),
                    Geometry::Quadrilateral { vertices } => {
                        crate::geometry::signed_area(vertices).abs()
                    }
                    _ => 0.0,
                };
                area / (f64::from(nx) * f64::from(ny))
            }
        };
        let sparse = area_a_point >= 0.999 * LONE_VOLUME * h * h;
        let name = || body.name.clone().unwrap_or_else(|| format!("bodies[{k}]"));
        let elastic = matches!(
            body.material,
            MaterialSpec::Hencky { .. } | MaterialSpec::LinearElastic { .. }
        );
        let message = match (sparse, stabilised && elastic, case.basis) {
            (false, ..) | (true, true, BasisKind::Bspline2 | BasisKind::Bspline3) => continue,
            (true, false, _) if stabilised => format!(
                "{} has one point a cell or fewer and a plastic material: the stabilisation of \
                 one-point cells acts on elastic materials only, so nothing but the ghost penalty \
                 holds its cells' hourglass modes. Collapse loads were measured close (a footing's \
                 N_c -0.1%, a hinge's plastic moment -0.1%), but its elastic bending is far too \
                 soft and may fail. Use two or more points a cell (docs/one_point_cells.md).",
                name()
            ),
            (true, false, _) => format!(
                "{} has one point a cell or fewer and `analysis.stabilisation.lone_points` is \
                 off: one point cannot hold a cell's hourglass modes, so its answers can be far \
                 off and bending may fail where two points a cell finish (GIMP: the self-weight \
                 column settles 42% short at 16 cells; docs/study/robustness).",
                name()
            ),
            (true, true, _) => format!(
                "{} has one point a cell or fewer, on {}: the stabilisation of one-point \
                 cells holds their bending, but large rotation drifts with the load steps more \
                 than at two points a cell (a clamped elastica's tip 3.7-4.4% off on GIMP, \
                 against 0.5-2.7% at two a cell and 0.35-1.3% on \"bspline2\" at one; the \
                 bilinear basis also crosses cells: its self-weight column 10-22% off). Use two \
                 or more a cell, or \"bspline2\" (docs/study/robustness).",
                name(),
                if case.basis == BasisKind::Gimp {
                    "GIMP"
                } else {
                    "the bilinear basis"
                }
            ),
        };
        out.push(RunWarning {
            kind: "one_point_a_cell",
            message,
        });
    }
    out
}

/// The schema's choices, as the solver's modules name them: the case
/// format keeps its own types, so a solver module can change without
/// changing the format.
impl From<case::Representation> for Representation {
    fn from(r: case::Representation) -> Self {
        match r {
            case::Representation::Edge => Representation::Edge,
            case::Representation::Points => Representation::Points,
        }
    }
}

impl From<case::Lattice> for Lattice {
    fn from(l: case::Lattice) -> Self {
        match l {
            case::Lattice::Body => Lattice::Body,
            case::Lattice::Grid => Lattice::Grid,
        }
    }
}

impl From<case::Fix> for Fix {
    fn from(f: case::Fix) -> Self {
        match f {
            case::Fix::X => Fix::X,
            case::Fix::Y => Fix::Y,
            case::Fix::Xy => Fix::Xy,
            case::Fix::Normal => Fix::Normal,
        }
    }
}

impl From<case::Rotation> for Rotation {
    fn from(r: case::Rotation) -> Self {
        Rotation {
            angle: r.angle,
            center: r.center,
        }
    }
}

impl From<case::PointField> for PointField {
    fn from(f: case::PointField) -> Self {
        match f {
            case::PointField::Position => PointField::Position,
            case::PointField::Displacement => PointField::Displacement,
            case::PointField::Stress => PointField::Stress,
            case::PointField::Volume => PointField::Volume,
            case::PointField::Jacobian => PointField::Jacobian,
            case::PointField::Body => PointField::Body,
            case::PointField::PlasticStrain => PointField::PlasticStrain,
            case::PointField::Yielding => PointField::Yielding,
        }
    }
}

/// The point columns a case's output asks for (`None`: all of them), for
/// [`crate::report::PointColumns::selected`].
pub fn point_fields(output: &case::OutputSpec) -> Option<Vec<PointField>> {
    output
        .fields
        .as_ref()
        .map(|fields| fields.iter().map(|&f| f.into()).collect())
}

fn basis(kind: BasisKind) -> Basis {
    match kind {
        BasisKind::Linear => Basis::Linear,
        BasisKind::Gimp => Basis::Gimp,
        BasisKind::Bspline2 => Basis::BSpline2,
        BasisKind::Bspline3 => Basis::BSpline3,
    }
}

/// A traction `t` on the faces of the points' box domains that lie on the
/// plane `x[axis] = at` (to `tol`) in the reference configuration: one
/// dead [`FaceLoad`] a face, `t` times its area, `held` or ramped with the
/// load factor (a stopgap for boxes until the B-spline surfaces).
pub fn face_loads(
    points: &MaterialPoints<3>,
    (axis, at, tol): (usize, f64, f64),
    t: [f64; 3],
    held: bool,
) -> Vec<FaceLoad<3>> {
    (0..points.len())
        .filter_map(|p| {
            let (x, h) = (points.reference[p][axis], points.domain[p][axis]);
            let side = if (x + h - at).abs() <= tol {
                h
            } else if (x - h - at).abs() <= tol {
                -h
            } else {
                return None;
            };
            let area: f64 = (0..3)
                .filter(|&d| d != axis)
                .map(|d| 2.0 * points.domain[p][d])
                .product();
            Some(FaceLoad {
                point: p,
                offset: std::array::from_fn(|d| if d == axis { side } else { 0.0 }),
                force: t.map(|c| c * area),
                held,
            })
        })
        .collect()
}

/// Index of the point nearest to `x`.
fn nearest_point<const D: usize>(points: &MaterialPoints<D>, x: [f64; D]) -> usize
where
    Dim<D>: Space<D>,
{
    let d2 = |p: &[f64; D]| (1..D).fold((p[0] - x[0]).powi(2), |s, d| s + (p[d] - x[d]).powi(2));
    (0..points.len())
        .min_by(|&a, &b| d2(&points.position[a]).total_cmp(&d2(&points.position[b])))
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use crate::fixtures;
    use crate::stepper::Simulation;

    /// A body one point a cell is warned of where that costs accuracy:
    /// GIMP and the bilinear basis, a plastic body, or any with the
    /// stabilisation of one-point cells off; not an elastic body on the
    /// stabilised B-splines, nor two a cell.
    #[test]
    fn one_point_a_cell_is_warned_of_where_it_costs_accuracy() {
        let kinds = |basis: &str, per_cell: u32, stabilised: bool| {
            let mut v = fixtures::block([2.0, 1.0], [4, 2], 0.5, [0.0, 0.0]);
            v["basis"] = basis.into();
            v["bodies"][0]["points"] = serde_json::json!({ "per_cell": per_cell });
            v["analysis"]["stabilisation"] = serde_json::json!({ "lone_points": stabilised });
            let case = fixtures::case(&v);
            super::warnings(&case, &[])
                .iter()
                .map(|w| w.kind)
                .collect::<Vec<_>>()
        };
        for basis in ["linear", "gimp"] {
            assert_eq!(kinds(basis, 1, true), ["one_point_a_cell"], "{basis}");
            assert!(kinds(basis, 2, true).is_empty(), "{basis}");
        }
        for basis in ["bspline2", "bspline3"] {
            assert!(kinds(basis, 1, true).is_empty(), "{basis}");
            assert_eq!(kinds(basis, 1, false), ["one_point_a_cell"], "{basis}");
        }
        // A `count` of one point a cell is as sparse; of two, not.
        for (count, warned) in [([4, 2], true), ([8, 4], false)] {
            let mut v = fixtures::block([2.0, 1.0], count, 0.5, [0.0, 0.0]);
            v["basis"] = "gimp".into();
            let kinds = super::warnings(&fixtures::case(&v), &[]).len();
            assert_eq!(kinds == 1, warned, "{count:?}");
        }
        // A plastic body: the stabilisation leaves it out.
        let mut v = fixtures::block([2.0, 1.0], [4, 2], 0.5, [0.0, 0.0]);
        v["basis"] = "bspline2".into();
        v["bodies"][0]["points"] = serde_json::json!({ "per_cell": 1 });
        v["bodies"][0]["material"] = serde_json::json!({ "model": "von_mises",
            "youngs_modulus": 1e6, "poisson_ratio": 0.3, "density": 0.0, "yield_stress": 1e3 });
        let warned = super::warnings(&fixtures::case(&v), &[]);
        assert_eq!(warned.len(), 1);
        assert!(
            warned[0].message.contains("plastic"),
            "{}",
            warned[0].message
        );
    }

    /// The paper's fixed point (0, 1) on grid nodes with 1.5 m cells
    /// selects no node (they lie at y = 0 and 1.5) and is refused, naming
    /// the support; on a grid with origin (0, 1) it holds a node.
    #[test]
    fn a_grid_support_that_holds_no_node_is_refused() {
        let with_origin = |origin: [f64; 2]| {
            let mut case = fixtures::block([10.0, 2.0], [56, 16], 1.5, origin);
            case["bodies"][0]["material"]["poisson_ratio"] = 0.25.into();
            case["supports"] = serde_json::json!([
                { "on": { "x": 0.0 }, "fix": "x" },
                { "on": { "x": 0.0, "y": 1.0 }, "fix": "xy" }
            ]);
            Simulation::new(&fixtures::case(&case))
        };
        let e = with_origin([0.0, 0.0]).err().expect("refused");
        assert_eq!(e.path, "supports[1].on", "{e}");
        assert!(e.message.contains("grid nodes"), "{e}");
        with_origin([0.0, 1.0]).expect("a node at (0, 1)");
    }
}
