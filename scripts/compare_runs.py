#!/usr/bin/env python3
"""Compare two runs of the solver for a behaviour-preserving change.

    scripts/compare_runs.py BEFORE_DIR AFTER_DIR

Each directory holds the outputs of the same commands from two builds:
`mpm run ... --out DIR/NAME` (compared through NAME/summary.json and, where
present, NAME/steps/step_NNNN.json) and `mpm study ... --out DIR/NAME`
(compared through NAME/cantilever.csv). Every value must be identical
except wall-clock times (`wall_seconds` and `timings` in the JSON, the
`seconds` column in the CSV): JSON is compared parsed, so each float is
compared exactly (to the last bit), and CSV cells as text. A result file
present on one side only is a difference. Exits 1 and lists the first
differences otherwise.

scripts/compare_builds.sh runs the standard set of commands with two
binaries and calls this.
"""

import csv
import json
import sys
from pathlib import Path

TIME_KEYS = {"wall_seconds", "timings"}


def strip_times(value):
    if isinstance(value, dict):
        return {k: strip_times(v) for k, v in value.items() if k not in TIME_KEYS}
    if isinstance(value, list):
        return [strip_times(v) for v in value]
    return value


def json_text(path):
    # Parsing keeps every float's exact value; dumping with repr-exact
    # floats makes equal documents compare equal as text.
    return json.dumps(strip_times(json.loads(path.read_text())), sort_keys=True)


def csv_rows(path):
    with path.open() as f:
        rows = list(csv.DictReader(f))
    for row in rows:
        row.pop("seconds", None)
    return rows


def loader_for(path):
    if path.suffix == ".json" and (path.name == "summary.json" or path.parent.name == "steps"):
        return json_text
    if path.suffix == ".csv":
        return csv_rows
    return None


def compare(before, after):
    differences = []
    compared = 0
    for new in sorted(after.rglob("*")):
        rel = new.relative_to(after)
        if loader_for(new) and not (before / rel).exists():
            differences.append(f"{rel}: missing in {before}")
    for old in sorted(before.rglob("*")):
        rel = old.relative_to(before)
        new = after / rel
        loader = loader_for(old)
        if loader is None:
            continue
        if not new.exists():
            differences.append(f"{rel}: missing in {after}")
            continue
        compared += 1
        if loader(old) != loader(new):
            differences.append(f"{rel}: differs")
    return compared, differences


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    before, after = Path(sys.argv[1]), Path(sys.argv[2])
    compared, differences = compare(before, after)
    if compared == 0:
        sys.exit(f"nothing to compare in {before}")
    for d in differences[:20]:
        print(d)
    if differences:
        print(f"{len(differences)} of {compared} files differ")
        sys.exit(1)
    print(f"{compared} files identical (wall times aside)")


if __name__ == "__main__":
    main()
