"""Case builders and the bundled schema; no server needed but the binary for `mpm example`."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from mpm_client import CaseError, cases


def test_cantilever_defaults_are_the_built_in_example(binary: Path) -> None:
    printed = subprocess.run(
        [str(binary), "example", "cantilever"], check=True, capture_output=True, text=True
    ).stdout
    built_in = json.loads(printed)
    assert cases.cantilever() == built_in
    # Equal as JSON text too, so ints and floats are of the same kinds.
    assert json.dumps(cases.cantilever(), sort_keys=True) == json.dumps(built_in, sort_keys=True)


def test_every_bundled_example_is_the_built_in_one_and_valid(binary: Path) -> None:
    listed = subprocess.run([str(binary), "example"], check=True, capture_output=True, text=True).stdout
    # The client bundles every example, plane strain and 3D, in the
    # binary's order.
    assert tuple(listed.split()) == cases.EXAMPLES
    for name in cases.EXAMPLES:
        printed = subprocess.run(
            [str(binary), "example", name], check=True, capture_output=True, text=True
        ).stdout
        assert cases.example(name) == json.loads(printed), name
        cases.validate(cases.example(name))
    with pytest.raises(ValueError, match="no built-in example"):
        cases.example("bridge")


def test_cantilever_takes_cells_points_and_steps() -> None:
    case = cases.cantilever(cell_size=0.75, points=(112, 32), load_steps=10)
    assert case["grid"]["cell_size"] == 0.75
    assert case["bodies"][0]["points"] == {"count": [112, 32]}
    assert case["analysis"]["load_steps"] == 10
    assert "3584 points" in case["title"] and "in 10 steps" in case["title"]
    cases.validate(case)


def test_validate_names_the_path_of_the_error() -> None:
    case = cases.cantilever()
    case["bodies"] = "beam"
    with pytest.raises(CaseError) as raised:
        cases.validate(case)
    assert raised.value.path == "bodies"
    assert isinstance(raised.value, ValueError)

    case = cases.cantilever()
    del case["version"]
    with pytest.raises(CaseError, match=r"^\$: 'version' is a required property"):
        cases.validate(case)


def test_validate_names_the_field_inside_a_choice_of_models() -> None:
    # A material is one of several models: the error was "is not valid
    # under any of the given schemas" at bodies[0].material.
    case = cases.cantilever()
    case["bodies"][0]["material"]["youngs_modulus"] = "200 GPa"
    with pytest.raises(CaseError) as raised:
        cases.validate(case)
    assert raised.value.path == "bodies[0].material.youngs_modulus"
    assert "any of the given schemas" not in raised.value.message

    case = cases.cantilever()
    case["bodies"][0]["material"]["model"] = "steel"
    with pytest.raises(CaseError, match=r"'steel' is not one of 'hencky', 'linear_elastic'"):
        cases.validate(case)


def test_json_path_is_written_as_the_service_writes_it() -> None:
    assert cases.json_path(["bodies", 0, "material", "poisson_ratio"]) == "bodies[0].material.poisson_ratio"
    assert cases.json_path([]) == "$"


def test_schema_is_package_data() -> None:
    schema = cases.schema()
    assert schema["type"] == "object"
    for format in ("Case", "SolidCase"):
        assert {"version", "bodies"} <= set(schema["$defs"][format]["required"])


def test_a_3d_case_is_validated_as_one() -> None:
    # `analysis.type: "3d"` selects the 3D format (the schema's if/then):
    # its fields are checked there, and the plane-strain ones refused.
    case = cases.example("column3d")
    cases.validate(case)
    case["loads"]["gravity"] = [0.0, -10.0]
    with pytest.raises(CaseError) as raised:
        cases.validate(case)
    assert raised.value.path == "loads.gravity"
    case = cases.example("column3d")
    case["probes"] = []
    with pytest.raises(CaseError, match="probes"):
        cases.validate(case)
