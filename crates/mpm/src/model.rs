//! From the case (what a user submits) to the solver's own types: the only
//! module that reads the case schema. It seeds the bodies with points,
//! finds their boundary loops and resolves every boundary selector to loop
//! segments once ([`Seeded`]), then splits the supports by how they are
//! imposed.

use crate::boundary::edge_detection::loops_on_edge;
use crate::boundary::ibm::{self, IbmSupport};
use crate::boundary::loading::LoadedStretch;
use crate::boundary::traction::Traction;
use crate::boundary::{
    BoundaryLoop, Piece, Representation, find_loops, selected_pieces, selected_segments,
    set_offsets, snap_to_edge,
};
use crate::case::{self, BasisKind, Body, Case, CaseError, GridSpec, MaterialSpec, SupportMethod};
use crate::geometry::Geometry;
use crate::grid::{Basis, Grid};
use crate::linsolve::SolverSettings;
use crate::material::{DruckerPrager, Elastic, Material, MohrCoulomb, StiffnessScales, VonMises};
use crate::newton::NewtonSettings;
use crate::particles::MaterialPoints;
use crate::particles::seeding::{self, Density, FillSize, Lattice};
use crate::probes::Probes;
use crate::report::PointField;
use crate::stepper::{Simulation, StepSize, Substepping};
use crate::supports::{Fix, GridSupport, HeldDofs, Rotation};

/// Loop segments per loop, `(loop index, segments)`, that a selector picks.
type Selection = Vec<(usize, Vec<usize>)>;

/// The pieces of curve per loop, `(loop index, pieces)`, that a support's
/// selector holds.
type Held = Vec<(usize, Vec<Piece>)>;

/// What a case's bodies make before any load step: the material points,
/// their boundary loops, and the loop segments each boundary selector picks.
/// Seeding is where reading a case costs time and memory, and the one check
/// left after validation: a boundary selector that picks nothing fails
/// here, naming its field.
pub struct Seeded {
    pub points: MaterialPoints,
    pub loops: Vec<BoundaryLoop>,
    /// Per boundary load of the case.
    loads: Vec<Selection>,
    /// Per support of the case, the pieces of curve it holds; `None` for
    /// the grid-node ones.
    supports: Vec<Option<Held>>,
}

impl Seeded {
    /// Seeds a validated case.
    pub fn new(case: &Case) -> Result<Self, CaseError> {
        let points = material_points(case);
        let loops = boundary_loops(case, &points);
        let on_edge = Representation::from(case.boundary.representation) == Representation::Edge;
        let h = case.grid.cell_size;
        let none_selected = |path: String| {
            CaseError::new(
                path,
                "selects no stretch of any body's boundary (it must pass within about \
                 a point spacing of two neighbouring outer points)",
            )
        };
        let loads = (case.loads.boundary.iter().enumerate())
            .map(|(i, load)| {
                let segments = selected_segments(&load.on, &loops, &points, h, on_edge);
                (!segments.is_empty())
                    .then_some(segments)
                    .ok_or_else(|| none_selected(format!("loads.boundary[{i}].on")))
            })
            .collect::<Result<_, _>>()?;
        let supports = (case.supports.iter().enumerate())
            .map(|(i, s)| match s.method {
                SupportMethod::Grid => Ok(None),
                SupportMethod::Ibm => {
                    let pieces = selected_pieces(&s.on, &loops, &points, h, on_edge);
                    (!pieces.is_empty())
                        .then_some(Some(pieces))
                        .ok_or_else(|| none_selected(format!("supports[{i}].on")))
                }
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            points,
            loops,
            loads,
            supports,
        })
    }
}

impl Simulation {
    /// Builds the initial state of a validated case. Fails, naming the
    /// field, when a boundary load or an IBM support selects no stretch of
    /// any body's boundary, or a grid-node support no node the material
    /// reaches (which could not be told before the points were generated).
    pub fn new(case: &Case) -> Result<Self, CaseError> {
        let Seeded {
            points,
            loops,
            loads,
            supports,
        } = Seeded::new(case)?;
        let grid = Grid {
            h: case.grid.cell_size,
            origin: case.grid.origin,
        };
        let mut boundary_loads = Vec::new();
        for (load, selection) in case.loads.boundary.iter().zip(loads) {
            let traction = match (load.traction, load.pressure) {
                (Some(t), _) => Traction::Dead(t),
                (None, Some(p)) => Traction::Pressure(p),
                (None, None) => continue, // rejected by validation
            };
            boundary_loads.extend(selection.into_iter().map(|(loop_index, segments)| {
                LoadedStretch {
                    loop_index,
                    segments,
                    traction,
                }
            }));
        }
        let (mut grid_supports, mut ibm_supports) = (Vec::new(), Vec::new());
        for ((index, s), selection) in case.supports.iter().enumerate().zip(supports) {
            match selection {
                None => grid_supports.push(GridSupport {
                    index,
                    on: s.on,
                    fix: s.fix.into(),
                }),
                Some(pieces) => ibm_supports.push(IbmSupport {
                    index,
                    pieces,
                    fix: s.fix.into(),
                    displacement: s.displacement.unwrap_or([0.0, 0.0]),
                    rotation: s.rotation.map(Into::into),
                    averaged: (s.constraint == case::Constraint::Averaged)
                        .then_some((ibm::AVERAGED_PIECE_CELLS * case.grid.cell_size, s.on)),
                }),
            }
        }
        let point_loads = case
            .loads
            .point_loads
            .iter()
            .map(|l| (nearest_point(&points, l.at), l.force))
            .collect();
        let newton = &case.analysis.newton;
        let stabilisation = case.analysis.stabilisation_settings();
        let stiffness = StiffnessScales::of(&points.materials);
        let free_step_growth = 10.0 * stiffness.p_wave_to_shear;
        let sim = Self {
            grid,
            basis: basis(case.basis),
            extent: case.grid.extent.map(|b| (b.min, b.max)),
            probes: Probes::new(case.probes.iter().map(|p| (p.name.clone(), p.at))),
            anchors: ibm::anchors(&ibm_supports, &loops, &points, &grid, basis(case.basis)),
            band_width: case
                .boundary
                .band_width
                .unwrap_or(ibm::DEFAULT_BAND_WIDTH * grid.h),
            loops,
            points,
            gravity: case.loads.gravity.unwrap_or([0.0, 0.0]),
            point_loads,
            boundary_loads,
            grid_supports,
            n_supports: case.supports.len(),
            settings: NewtonSettings {
                tolerance: newton.tolerance,
                max_iterations: newton.max_iterations as usize,
                tangent_regularisation: stabilisation.tangent_regularisation,
                line_search: newton.line_search,
                ghost_penalty: stabilisation.ghost_penalty,
                free_step_growth,
                ..Default::default()
            },
            fbar: case.analysis.volumetric == crate::case::Volumetric::Fbar,
            step_size: StepSize::default(),
            steps_done: 0,
            stiffness,
            solver: SolverSettings::default(),
            solve_tally: Default::default(),
            analysed: None,
            substepping: Substepping {
                min_fraction: case.analysis.substepping.min_fraction,
                max_cutbacks: case.analysis.substepping.max_cutbacks as usize,
            },
            load_steps: case.analysis.load_steps as usize,
        };
        sim.check_grid_supports()?;
        check_inside_extent(case, &sim.points)?;
        check_probes(case, &sim.points, &grid)?;
        Ok(sim)
    }

    /// A grid-node support must hold some node the material reaches at the
    /// start: one that holds none (a point between nodes, a line between
    /// grid lines) would leave the body free there, and the run would fail
    /// later with an inverted point or a stalled Newton that does not say
    /// why.
    fn check_grid_supports(&self) -> Result<(), CaseError> {
        if self.grid_supports.is_empty() {
            return Ok(());
        }
        let held = HeldDofs::find(&self.grid_supports, &self.grid, &self.reset_grid());
        match held.first_idle() {
            Some(index) => Err(CaseError::new(
                format!("supports[{index}].on"),
                format!(
                    "selects none of the grid nodes the material reaches (grid-node supports hold \
                     nodes, which lie at grid.origin + k * {} m); move it onto a node or grid line, \
                     or use \"method\": \"ibm\" to hold the boundary curve itself",
                    self.grid.h
                ),
            )),
            None => Ok(()),
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

/// Index of the point nearest to `x`.
fn nearest_point(points: &MaterialPoints, x: [f64; 2]) -> usize {
    let d2 = |p: &[f64; 2]| (p[0] - x[0]).powi(2) + (p[1] - x[1]).powi(2);
    (0..points.len())
        .min_by(|&a, &b| d2(&points.position[a]).total_cmp(&d2(&points.position[b])))
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use crate::fixtures;
    use crate::stepper::Simulation;

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
