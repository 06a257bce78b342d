"""Case builders and local validation against the bundled JSON Schema.

Cases are plain dicts in the service's JSON format (version 1, SI units:
m, Pa, kg/m^3, N per metre of thickness); see the README of the solver for
every field.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from functools import lru_cache
from importlib import resources
from typing import Any

from jsonschema.exceptions import best_match
from jsonschema.validators import validator_for

from .errors import CaseError

__all__ = ["cantilever", "example", "EXAMPLES", "validate", "schema", "CaseError"]

# The service's built-in examples (`mpm example NAME`), bundled as JSON.
EXAMPLES = (
    "column",
    "cantilever-grid",
    "cantilever",
    "plate-with-hole",
    "footing",
    "slope",
    "column3d",
    "sphere3d",
    "footing3d",
)


def example(name: str) -> dict:
    """The built-in example `name` (one of `EXAMPLES`), as `mpm example NAME` prints it."""
    if name not in EXAMPLES:
        raise ValueError(f"no built-in example {name!r}; available: {', '.join(EXAMPLES)}")
    text = resources.files(__package__).joinpath("examples", f"{name}.json").read_text()
    return json.loads(text)

# The paper's beam (Bing et al. 2017): 10 m x 2 m, E = 1 MPa, nu = 0.25.
_LENGTH = 10.0
_HEIGHT = 2.0
_PRESSURE = 1500.0


def cantilever(
    cell_size: float = 1.5,
    points: tuple[int, int] = (56, 16),
    load_steps: int = 5,
) -> dict:
    """The paper's cantilever, as `mpm example cantilever` prints it at the defaults.

    A 10 m x 2 m Hencky beam (E = 1 MPa, nu = 0.25, weightless) under a
    1500 Pa follower pressure on its top, the left edge on rollers and fixed
    at mid-height, both by the implicit boundary method; a probe `tip` at
    (10, 1).

    cell_size: grid cell size (m). points: material points (nx, ny) along
    the length and the height. load_steps: equal load increments.
    """
    nx, ny = (int(n) for n in points)
    return {
        "version": 1,
        "title": (
            "The paper's cantilever (Bing et al. 2017): 10 m x 2 m, "
            f"{nx * ny} points, 1500 Pa follower pressure on top in {load_steps} steps; "
            "left edge on rollers, fixed at mid-height, both by the implicit boundary method"
        ),
        "analysis": {"type": "plane_strain", "load_steps": int(load_steps)},
        "grid": {"cell_size": float(cell_size), "origin": [0.0, 0.0]},
        "basis": "linear",
        "bodies": [
            {
                "name": "beam",
                "geometry": {"rectangle": {"min": [0.0, 0.0], "max": [_LENGTH, _HEIGHT]}},
                "points": {"count": [nx, ny]},
                "material": {
                    "model": "hencky",
                    "youngs_modulus": 1.0e6,
                    "poisson_ratio": 0.25,
                    "density": 0.0,
                },
            }
        ],
        "loads": {"boundary": [{"on": {"y": _HEIGHT}, "pressure": _PRESSURE}]},
        "supports": [
            {"on": {"x": 0.0}, "fix": "normal", "method": "ibm"},
            {"on": {"x": 0.0, "y": _HEIGHT / 2}, "fix": "xy", "method": "ibm"},
        ],
        "probes": [{"name": "tip", "at": [_LENGTH, _HEIGHT / 2]}],
    }


@lru_cache(maxsize=1)
def schema() -> dict:
    """The bundled case schema (`mpm_client/case.schema.json`)."""
    text = resources.files("mpm_client").joinpath("case.schema.json").read_text(encoding="utf-8")
    return json.loads(text)


@lru_cache(maxsize=1)
def _validator() -> Any:
    cls = validator_for(schema())
    return cls(schema())


def json_path(parts: Iterable[str | int]) -> str:
    """`["bodies", 0, "material"]` -> `bodies[0].material`; the case itself is `$`."""
    path = ""
    for part in parts:
        if isinstance(part, int):
            path += f"[{part}]"
        else:
            path += f".{part}" if path else str(part)
    return path or "$"


def validate(case: Mapping[str, Any]) -> None:
    """Check `case` against the bundled JSON Schema.

    Raises `CaseError` naming the JSON path of the first error (jsonschema's
    most relevant one). The service checks more than a schema can (e.g.
    that polygons are simple), so a case that passes may still be refused.
    """
    error = best_match(_validator().iter_errors(case))
    if error is not None:
        raise CaseError(*_most_specific(error))


def _most_specific(error: Any) -> tuple[str, str]:
    """`(path, message)` of an error; inside a `oneOf` or `anyOf` (a
    material, a geometry), of the alternative that got furthest into the
    case, as the service reports it: `bodies[0].material.youngs_modulus`,
    not "is not valid under any of the given schemas" at
    `bodies[0].material`. Alternatives told apart by a constant (the
    material's `model`) that all fail on it name the constants."""
    while error.context:
        depth = max(len(e.absolute_path) for e in error.context)
        deepest = [e for e in error.context if len(e.absolute_path) == depth]
        if len(deepest) > 1 and all(e.validator == "const" for e in deepest):
            names = ", ".join(repr(e.validator_value) for e in deepest)
            return json_path(deepest[0].absolute_path), f"{deepest[0].instance!r} is not one of {names}"
        error = deepest[0]
    return json_path(error.absolute_path), error.message
