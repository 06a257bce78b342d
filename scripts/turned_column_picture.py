#!/usr/bin/env python3
"""Draws docs/turned-column.svg: the 2 m x 10 m self-weight column turned 30
degrees on 0.5 m cells (the case of `bodies.rs` in the verification tests),
filled as a turned rectangle (its own lattice) and as a polygon on the
grid's lattice (`points.lattice: grid`, a staircase; its boundary curve is
put on the true edge all the same), with the points in the reference
configuration, the true edge and the boundary curve at the last load step.
A polygon on its own lattice (the default) is filled as the rectangle is.

    cargo build --release && python3 scripts/turned_column_picture.py
"""

import glob
import json
import math
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MPM = os.path.join(ROOT, "target", "release", "mpm")
ANGLE, W, L = 30.0, 2.0, 10.0


def turn(p):
    c, s = math.cos(math.radians(ANGLE)), math.sin(math.radians(ANGLE))
    return [c * p[0] - s * p[1], s * p[0] + c * p[1]]


def case(geometry, lattice="body"):
    axis = turn([0.0, 1.0])
    return {
        "version": 1,
        "analysis": {"load_steps": 5},
        "grid": {"cell_size": 0.5},
        "basis": "gimp",
        "bodies": [{
            "geometry": geometry,
            "points": {"per_cell": 2, "lattice": lattice},
            "material": {"model": "hencky", "youngs_modulus": 1e6, "poisson_ratio": 0.25,
                         "density": 1000.0},
        }],
        "loads": {"gravity": [-10 * axis[0], -10 * axis[1]]},
        "supports": [
            {"on": {"segment": [turn([0, 0]), turn([0, L])]}, "fix": "normal", "method": "ibm"},
            {"on": {"segment": [turn([W, 0]), turn([W, L])]}, "fix": "normal", "method": "ibm"},
            {"on": {"segment": [turn([0, 0]), turn([W, 0])]}, "fix": "xy", "method": "ibm"},
        ],
    }


def solve(geometry, work, lattice="body"):
    path = os.path.join(work, "case.json")
    out = os.path.join(work, "out")
    with open(path, "w") as f:
        json.dump(case(geometry, lattice), f)
    subprocess.run([MPM, "run", path, "--out", out], check=True, capture_output=True)
    with open(sorted(glob.glob(os.path.join(out, "steps", "*.json")))[-1]) as f:
        last = json.load(f)
    reference = [[p[0] - d[0], p[1] - d[1]]
                 for p, d in zip(last["points"]["position"], last["points"]["displacement"])]
    return reference, last["boundaries"][0]["polyline"]


def panel(left, title, points, curve, corners):
    scale, x0, y0, x1, y1 = 60.0, -5.6, -0.4, 2.2, 10.0
    X = lambda x: left + (x - x0) * scale
    Y = lambda y: 40 + (y1 - y) * scale
    out = [f'<text x="{left + 10}" y="25" font-family="sans-serif" font-size="15">{title}</text>']
    for k in range(-12, 5):
        x = 0.5 * k
        if x0 <= x <= x1:
            out.append(f'<line x1="{X(x):.1f}" y1="{Y(y0):.1f}" x2="{X(x):.1f}" y2="{Y(y1):.1f}" '
                       'stroke="#ddd" stroke-width="0.7"/>')
    for k in range(0, 21):
        y = 0.5 * k
        out.append(f'<line x1="{X(x0):.1f}" y1="{Y(y):.1f}" x2="{X(x1):.1f}" y2="{Y(y):.1f}" '
                   'stroke="#ddd" stroke-width="0.7"/>')
    ring = corners + [corners[0]]
    out.append('<polyline fill="none" stroke="#888" stroke-dasharray="4 3" stroke-width="1.2" '
               'points="' + " ".join(f"{X(a):.1f},{Y(b):.1f}" for a, b in ring) + '"/>')
    out += [f'<circle cx="{X(a):.1f}" cy="{Y(b):.1f}" r="1.6" fill="#1f5fa8"/>' for a, b in points]
    out.append('<polyline fill="none" stroke="#c0392b" stroke-width="1.4" points="'
               + " ".join(f"{X(a):.1f},{Y(b):.1f}" for a, b in curve) + '"/>')
    return out


def main():
    corners = [turn([0, 0]), turn([W, 0]), turn([W, L]), turn([0, L])]
    with tempfile.TemporaryDirectory() as work:
        own = solve({"rectangle": {"min": [0, 0], "max": [W, L], "angle": ANGLE,
                                   "about": [0, 0]}}, work)
        staircase = solve({"polygon": {"vertices": corners}}, work, "grid")
    svg = ['<svg xmlns="http://www.w3.org/2000/svg" width="940" height="720" viewBox="0 0 940 720">',
           '<rect width="940" height="720" fill="white"/>']
    svg += panel(0, "turned rectangle (its own lattice)", *own, corners)
    svg += panel(470, "polygon on the grid's lattice (a staircase)", *staircase, corners)
    svg.append('<text x="10" y="705" font-family="sans-serif" font-size="12">The 2 m x 10 m column '
               'turned 30 degrees on 0.5 m cells (grey), 2 points per cell: points in the reference '
               'configuration (blue), the true edge (dashed), the boundary curve after 5 steps (red).</text>')
    svg.append("</svg>")
    with open(os.path.join(ROOT, "docs", "turned-column.svg"), "w") as f:
        f.write("\n".join(svg) + "\n")


if __name__ == "__main__":
    main()
