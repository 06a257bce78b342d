//! Built-in cases, shipped in `crates/mpm/cases/` and compiled in.

/// The built-in plane-strain cases' names, accepted by [`get`].
pub const NAMES: [&str; 6] = [
    "column",
    "cantilever-grid",
    "cantilever",
    "plate-with-hole",
    "footing",
    "slope",
];

/// The built-in 3D cases (`analysis.type: "3d"`, read by
/// [`super::solid::SolidCase`]).
pub const SOLID_NAMES: [&str; 3] = ["column3d", "sphere3d", "footing3d"];

/// The JSON text of a built-in case.
pub fn get(name: &str) -> Option<&'static str> {
    match name {
        "column3d" => Some(include_str!("../../cases/column3d.json")),
        "sphere3d" => Some(include_str!("../../cases/sphere3d.json")),
        "footing3d" => Some(include_str!("../../cases/footing3d.json")),
        "column" => Some(include_str!("../../cases/column.json")),
        "cantilever-grid" => Some(include_str!("../../cases/cantilever-grid.json")),
        "cantilever" => Some(include_str!("../../cases/cantilever.json")),
        // Made by scripts/plate_with_hole_mesh.py and scripts/gmsh_to_case.py.
        "plate-with-hole" => Some(include_str!("../../cases/plate-with-hole.json")),
        "footing" => Some(include_str!("../../cases/footing.json")),
        "slope" => Some(include_str!("../../cases/slope.json")),
        _ => None,
    }
}

/// A built-in case as a JSON value, to edit into a new case.
pub fn json(name: &str) -> Option<serde_json::Value> {
    get(name).map(|text| serde_json::from_str(text).expect("built-in cases are JSON"))
}
