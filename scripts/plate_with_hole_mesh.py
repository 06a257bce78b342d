"""Mesh a quarter of a plate with a circular hole with gmsh, for the
built-in case `plate-with-hole` (see gmsh_to_case.py).

The quarter is 0 <= x, y <= W with the hole r < a at the origin: a = 1 m,
W = 10 m, so the full plate is 20 m wide with a 2 m hole (d/D = 0.1).
Elements are about 0.1 m at the hole and 1 m far from it, recombined into
quadrilaterals where gmsh can (a few triangles remain).

    pip install gmsh
    python3 scripts/plate_with_hole_mesh.py plate-with-hole.msh
"""

import sys

import gmsh

A, W = 1.0, 10.0
NEAR, FAR = 0.1, 1.0


def main(path):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("plate-with-hole")
    occ = gmsh.model.occ
    plate = occ.addRectangle(0, 0, 0, W, W)
    hole = occ.addDisk(0, 0, 0, A, A)
    occ.cut([(2, plate)], [(2, hole)])
    occ.synchronize()
    # Element size growing linearly with the distance from the hole's edge.
    hole_curves = [c for _, c in gmsh.model.getEntities(1) if gmsh.model.getType(1, c) in ("Circle", "Ellipse")]
    field = gmsh.model.mesh.field
    distance = field.add("Distance")
    field.setNumbers(distance, "CurvesList", hole_curves)
    size = field.add("Threshold")
    field.setNumber(size, "InField", distance)
    field.setNumber(size, "SizeMin", NEAR)
    field.setNumber(size, "SizeMax", FAR)
    field.setNumber(size, "DistMin", 0.0)
    field.setNumber(size, "DistMax", W / 2)
    field.setAsBackgroundMesh(size)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.RecombineAll", 1)
    gmsh.option.setNumber("Mesh.Algorithm", 8)  # frontal-Delaunay for quads
    gmsh.model.mesh.generate(2)
    gmsh.write(path)
    gmsh.finalize()


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "plate-with-hole.msh")
