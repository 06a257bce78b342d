//! Cases the solver's unit tests build on: one rectangular body, loaded in
//! one step, which each test adjusts (its grid, basis, material, supports)
//! as a JSON tree before it is read like any other case.

use serde_json::{Value, json};

use crate::case::Case;
use crate::stepper::Simulation;

/// A one-step case of one Hencky block (E = 1e6, nu = 0.3, weightless)
/// from the origin to `max`, seeded with `count` points, on cells of
/// `cell_size` whose grid has a node at `origin`; no supports, no loads.
pub fn block(max: [f64; 2], count: [u32; 2], cell_size: f64, origin: [f64; 2]) -> Value {
    json!({
        "version": 1,
        "analysis": { "load_steps": 1 },
        "grid": { "cell_size": cell_size, "origin": origin },
        "bodies": [{
            "geometry": { "rectangle": { "min": [0.0, 0.0], "max": max } },
            "points": { "count": count },
            "material": { "model": "hencky", "youngs_modulus": 1e6, "poisson_ratio": 0.3, "density": 0.0 }
        }]
    })
}

/// The case `case` describes, read and checked as a submitted one is.
pub fn case(case: &Value) -> Case {
    Case::from_json(&case.to_string()).expect("a valid case")
}

/// The case `case` describes, made ready to run.
pub fn simulation(case: &Value) -> Simulation {
    Simulation::new(&self::case(case)).expect("a case that builds")
}

/// The points of a 3D box from `min` to `max` (Hencky, E = 1e6, nu = 0.3,
/// density 1000), `spacing` apart, and a grid of cells of `cell_size`
/// offset from the box in every axis: what the 3D unit tests build on
/// until a case can be 3D.
pub fn solid_box(
    min: [f64; 3],
    max: [f64; 3],
    spacing: f64,
    cell_size: f64,
) -> (crate::particles::MaterialPoints<3>, crate::grid::Grid<3>) {
    use crate::material::{Elastic, Material};
    use crate::particles::solid_seeding::{Solid, fill};
    let mut points = crate::particles::MaterialPoints::<3>::default();
    let seeds = fill(&Solid::cuboid(min, max), spacing);
    let elastic = Elastic::from_young_poisson(1e6, 0.3);
    points.add_solid(Material::Hencky(elastic), 1000.0, &seeds);
    let grid = crate::grid::Grid {
        h: cell_size,
        origin: [-0.12, 0.2, 0.44].map(|f| f * cell_size),
    };
    (points, grid)
}

/// The connectivity of [`solid_box`]'s points on `basis`, every node
/// active.
pub fn solid_links(
    points: &crate::particles::MaterialPoints<3>,
    grid: &crate::grid::Grid<3>,
    basis: crate::grid::Basis,
) -> crate::grid::Connectivity<3> {
    crate::grid::Connectivity::build(
        grid,
        basis,
        &points.position,
        |p| points.support(p),
        |_| true,
    )
}
