#!/usr/bin/env python3
"""Draws docs/bodies.svg: bodies of any shape on their own lattices, with
the points in the reference configuration (blue), the true edge (dashed)
and the boundary curve (red):
- the hexagon with a triangular hole of the polygon patch test (`bodies.rs`)
  on its own lattice: cut into triangles, each into three mapped patches;
- the same on the grid's lattice (`points.lattice: grid`): a staircase,
  the curve put on the true edge;
- the built-in `plate-with-hole` (a gmsh mesh body) near its hole: each
  element filled on its own map, the mesh's boundary as the edge.

    cargo build --release && python3 scripts/bodies_picture.py
"""

import glob
import json
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MPM = os.path.join(ROOT, "target", "release", "mpm")
OUTER = [[0.0, 0.0], [2.0, 0.0], [2.5, 1.0], [1.2, 0.9], [0.8, 1.8], [0.0, 1.5]]
HOLE = [[0.5, 0.4], [1.2, 0.5], [0.7, 0.8]]


def polygon_case(lattice):
    return {
        "version": 1,
        "analysis": {"load_steps": 1},
        "grid": {"cell_size": 0.2, "origin": [-0.037, 0.081]},
        "basis": "gimp",
        "bodies": [{
            "geometry": {"polygon": {"vertices": OUTER, "holes": [HOLE]}},
            "points": {"per_cell": 2, "lattice": lattice},
            "material": {"model": "linear_elastic", "youngs_modulus": 1e6, "poisson_ratio": 0.3,
                         "density": 0.0},
        }],
        "supports": [{"on": {"x": 0.0}, "fix": "x", "method": "ibm"},
                     {"on": {"y": 0.0}, "fix": "y", "method": "ibm"}],
    }


def solve(case, work):
    path = os.path.join(work, "case.json")
    out = os.path.join(work, "out")
    with open(path, "w") as f:
        json.dump(case, f)
    subprocess.run([MPM, "run", path, "--out", out], check=True, capture_output=True)
    with open(sorted(glob.glob(os.path.join(out, "steps", "*.json")))[-1]) as f:
        last = json.load(f)
    reference = [[p[0] - d[0], p[1] - d[1]]
                 for p, d in zip(last["points"]["position"], last["points"]["displacement"])]
    return reference, [b["polyline"] for b in last["boundaries"]]


def panel(left, title, view, h, origin, points, curves, edges, scale):
    x0, y0, x1, y1 = view
    X = lambda x: left + 10 + (x - x0) * scale
    Y = lambda y: 40 + (y1 - y) * scale
    out = [f'<text x="{left + 10}" y="25" font-family="sans-serif" font-size="15">{title}</text>']
    k0, k1 = int((x0 - origin[0]) // h), int((x1 - origin[0]) // h) + 1
    for k in range(k0, k1 + 1):
        x = origin[0] + k * h
        if x0 <= x <= x1:
            out.append(f'<line x1="{X(x):.1f}" y1="{Y(y0):.1f}" x2="{X(x):.1f}" y2="{Y(y1):.1f}" '
                       'stroke="#ddd" stroke-width="0.7"/>')
    k0, k1 = int((y0 - origin[1]) // h), int((y1 - origin[1]) // h) + 1
    for k in range(k0, k1 + 1):
        y = origin[1] + k * h
        if y0 <= y <= y1:
            out.append(f'<line x1="{X(x0):.1f}" y1="{Y(y):.1f}" x2="{X(x1):.1f}" y2="{Y(y):.1f}" '
                       'stroke="#ddd" stroke-width="0.7"/>')
    inside = lambda p: x0 <= p[0] <= x1 and y0 <= p[1] <= y1
    for ring in edges:
        out.append('<polyline fill="none" stroke="#888" stroke-dasharray="4 3" stroke-width="1.2" points="'
                   + " ".join(f"{X(a):.1f},{Y(b):.1f}" for a, b in ring + [ring[0]]) + '"/>')
    out += [f'<circle cx="{X(a):.1f}" cy="{Y(b):.1f}" r="1.5" fill="#1f5fa8"/>'
            for a, b in points if inside([a, b])]
    for curve in curves:
        # The runs of the curve inside the view, each drawn on its own.
        runs, run = [], []
        for p in curve:
            if inside(p):
                run.append(p)
            elif run:
                runs.append(run)
                run = []
        runs.append(run)
        for pts in (r for r in runs if len(r) > 1):
            out.append('<polyline fill="none" stroke="#c0392b" stroke-width="1.4" points="'
                       + " ".join(f"{X(a):.1f},{Y(b):.1f}" for a, b in pts) + '"/>')
    return out


def main():
    with open(os.path.join(ROOT, "crates", "mpm", "cases", "plate-with-hole.json")) as f:
        plate = json.load(f)
    with tempfile.TemporaryDirectory() as work:
        own = solve(polygon_case("body"), work)
        grid = solve(polygon_case("grid"), work)
        mesh = solve(plate, work)
    nodes = plate["bodies"][0]["geometry"]["mesh"]["nodes"]
    arc = sorted([n for n in nodes if abs((n[0] ** 2 + n[1] ** 2) ** 0.5 - 1) < 1e-6],
                 key=lambda n: n[1])
    square = [[0, 1], [0, 10], [10, 10], [10, 0], [1, 0]]
    hexagon = [OUTER, HOLE]
    view = (-0.1, -0.1, 2.6, 1.9)
    svg = ['<svg xmlns="http://www.w3.org/2000/svg" width="1280" height="420" viewBox="0 0 1280 420">',
           '<rect width="1280" height="420" fill="white"/>']
    svg += panel(0, "polygon with a hole, its own lattice", view, 0.2, [-0.037, 0.081], *own, hexagon, 150)
    svg += panel(420, "the same on the grid's lattice", view, 0.2, [-0.037, 0.081], *grid, hexagon, 150)
    svg += panel(840, "plate-with-hole (gmsh mesh), near the hole", (0, 0, 2.7, 2.7), 0.25, [0, 0],
                 *mesh, [arc + square[:1] + square[1:]], 130)
    svg.append('<text x="10" y="405" font-family="sans-serif" font-size="12">Points in the reference '
               'configuration (blue), the true edge (dashed), the boundary curve (red), grid cells '
               '(grey), 2 points per cell.</text>')
    svg.append("</svg>")
    with open(os.path.join(ROOT, "docs", "bodies.svg"), "w") as f:
        f.write("\n".join(svg) + "\n")


if __name__ == "__main__":
    main()
