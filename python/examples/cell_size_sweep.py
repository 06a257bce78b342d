"""Cost against accuracy on the paper's cantilever: a sweep over cell sizes.

Submits the cantilever of Bing et al. (2017) at several grid cell sizes h,
with the points refined with the cells (the paper's 56 x 16 points at
h = 1.5 m, twice as many each way at each halving), waits for them, and
plots the error of the tip deflection against the finest run versus the
job's solve time, log-log.

The deflection is the tip's vertical displacement relative to the mean of
the left edge's (the loaded beam also turns about its pinned stretch, whose
size shrinks with the point spacing; docs/study/linear/cantilever.md shows
why the tip's own u_y does not converge and this does).

    pip install "./python[plot]"
    python examples/cell_size_sweep.py --url http://127.0.0.1:8080 [--token T]

Writes cell_size_sweep.png (--out) and prints a table.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import dataclass

import numpy as np

from mpm_client import Client, cases

LEFT_PROBES = 9  # equally spaced on the left edge, x = 0, for its mean u_y


@dataclass
class Run:
    cell_size: float  # m
    points: int
    job: int
    seconds: float = 0.0  # the service's solve time
    deflection: float = 0.0  # tip u_y minus the left edge's mean u_y, m


def sweep_case(cell_size: float) -> dict:
    """The cantilever at cell size h (m), 16 x 1.5/h rows of points, 3.5 times as many columns."""
    rows = round(16 * 1.5 / cell_size)
    case = cases.cantilever(cell_size=cell_size, points=(rows * 7 // 2, rows))
    case["probes"] += [
        {"name": f"left{i}", "at": [0.0, 2.0 * i / (LEFT_PROBES - 1)]} for i in range(LEFT_PROBES)
    ]
    # Only the reports are read: keep the points of step 0 and the last step, positions only.
    case["output"] = {"every": case["analysis"]["load_steps"], "fields": []}
    return case


def relative_deflection(probes: dict) -> float:
    """Tip u_y minus the left edge's mean u_y (trapezoidal), at the last step, m."""
    tip = probes["tip"]["displacement"][-1, 1]
    left = np.array([probes[f"left{i}"]["displacement"][-1, 1] for i in range(LEFT_PROBES)])
    mean = (left[1:-1].sum() + 0.5 * (left[0] + left[-1])) / (LEFT_PROBES - 1)
    return float(tip - mean)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--url", default="http://127.0.0.1:8080")
    parser.add_argument("--token", default=os.environ.get("MPM_TOKEN"))
    parser.add_argument(
        "--cells", type=float, nargs="+", default=[1.5, 0.75, 0.375, 0.1875, 0.09375],
        help="cell sizes (m); the smallest is the reference",
    )
    parser.add_argument("--out", default="cell_size_sweep.png")
    args = parser.parse_args()

    client = Client(args.url, token=args.token)
    runs: list[Run] = []
    for h in sorted(args.cells, reverse=True):  # all queued first, then waited for
        case = sweep_case(h)
        points = case["bodies"][0]["points"]["count"]
        runs.append(Run(cell_size=h, points=points[0] * points[1], job=client.submit(case)))
    for run in runs:
        job = client.wait(run.job)
        run.seconds = job["solve_seconds"]
        run.deflection = relative_deflection(client.result(run.job).probes)

    reference = runs[-1]
    print(f"{'h (m)':>8} {'points':>8} {'deflection (m)':>15} {'error':>9} {'solve (s)':>10}")
    for run in runs:
        error = abs(run.deflection - reference.deflection) / abs(reference.deflection)
        print(f"{run.cell_size:8.4g} {run.points:8d} {run.deflection:15.6f} {error:9.2e} {run.seconds:10.3f}")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    coarse = runs[:-1]
    errors = [abs(r.deflection - reference.deflection) / abs(reference.deflection) for r in coarse]
    figure, axes = plt.subplots(figsize=(6, 4.5))
    axes.loglog([r.seconds for r in coarse], errors, "o-")
    for run, error in zip(coarse, errors):
        axes.annotate(
            f"h = {run.cell_size:g} m\n{run.points} points", (run.seconds, error),
            textcoords="offset points", xytext=(6, 4), fontsize=8,
        )
    axes.margins(x=0.3, y=0.15)  # room for the labels (in log space)
    axes.set_xlabel("solve time (s)")
    axes.set_ylabel("relative error of the tip deflection")
    axes.set_title(
        f"Cantilever (Bing et al. 2017): error against h = {reference.cell_size:g} m",
        fontsize=10,
    )
    axes.grid(True, which="both", alpha=0.3)
    figure.tight_layout()
    figure.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
