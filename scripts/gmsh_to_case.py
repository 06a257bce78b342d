"""Turn a gmsh mesh into a case body: `geometry: {"mesh": {...}}`.

meshio reads the .msh file. A mesh with hexahedra is a 3D body: its
hexahedra become the elements (eight node indices each, in gmsh's order,
either handedness), its nodes gmsh's points, and the case is a 3D one
(`analysis.type: "3d"`). Otherwise its triangles and quadrilaterals
become a plane-strain body's elements (node indices, either way round),
its nodes the x and y of gmsh's points. Nodes no element uses are
dropped. The case around the body comes from a template (a case JSON
whose first body's geometry is replaced), or a minimal one.

    pip install meshio
    python3 scripts/gmsh_to_case.py mesh.msh --template case.json > case.json

The built-in `plate-with-hole` was made so (see plate_with_hole_mesh.py):

    python3 scripts/plate_with_hole_mesh.py /tmp/plate.msh
    python3 scripts/gmsh_to_case.py /tmp/plate.msh \\
        --template scripts/plate_with_hole_template.json \\
        > crates/mpm/cases/plate-with-hole.json
"""

import argparse
import json
import sys

import meshio

CELL_TYPES = ("triangle", "quad")
SOLID_CELL_TYPES = ("hexahedron",)


def mesh_geometry(path, digits=9):
    """The body's `mesh` geometry, and whether it is 3D."""
    mesh = meshio.read(path)
    solid = any(block.type in SOLID_CELL_TYPES for block in mesh.cells)
    types, dims = (SOLID_CELL_TYPES, 3) if solid else (CELL_TYPES, 2)
    elements = []
    for block in mesh.cells:
        if block.type in types:
            elements.extend(block.data.tolist())
    if not elements:
        sys.exit(f"{path}: no hexahedra, triangles or quadrilaterals")
    used = sorted({i for e in elements for i in e})
    renumber = {old: new for new, old in enumerate(used)}
    nodes = [[round(float(mesh.points[i][d]), digits) for d in range(dims)] for i in used]
    return {"nodes": nodes, "elements": [[renumber[i] for i in e] for e in elements]}, solid


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mesh", help="a .msh file (or anything meshio reads)")
    parser.add_argument("--template", help="case JSON whose first body takes the mesh")
    args = parser.parse_args()
    mesh, solid = mesh_geometry(args.mesh)
    geometry = {"mesh": mesh}
    if args.template:
        with open(args.template) as f:
            case = json.load(f)
    else:
        case = {
            "version": 1,
            "analysis": {"type": "3d", "load_steps": 1} if solid else {"load_steps": 1},
            "grid": {"cell_size": 0.5},
            "basis": "gimp",
            "bodies": [
                {
                    "points": {"per_cell": 2},
                    "material": {"model": "linear_elastic", "youngs_modulus": 1e6, "poisson_ratio": 0.3, "density": 0},
                }
            ],
        }
    case["bodies"][0]["geometry"] = geometry
    json.dump(case, sys.stdout, separators=(",", ":"))
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
