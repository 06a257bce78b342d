#!/usr/bin/env bash
# Runs the standard comparison set with two mpm binaries and compares the
# results (scripts/compare_runs.py): the paper's cantilever study (quick)
# for every basis the new binary's case schema names, every built-in
# example both binaries list, and the footing study (quick: its first two
# cells).
#
#   scripts/compare_builds.sh OLD_MPM NEW_MPM [WORK_DIR]
set -euo pipefail
old=$1 new=$2 work=${3:-$(mktemp -d)}
here=$(cd "$(dirname "$0")" && pwd)
# Runs one command quietly; on failure shows its output and stops.
quiet() {
  local log; log=$(mktemp)
  if ! "$@" >"$log" 2>&1; then
    cat "$log" >&2; echo "failed: $*" >&2; exit 1
  fi
  rm -f "$log"
}
bases=$("$new" schema | python3 -c '
import json, sys
def find(o):
    if isinstance(o, dict):
        if "BasisKind" in o:
            return [c["const"] for c in o["BasisKind"]["oneOf"]]
        o = list(o.values())
    for v in o if isinstance(o, list) else []:
        if (found := find(v)):
            return found
print(" ".join(find(json.load(sys.stdin))))')
# The built-in examples both builds have (a new one has no "before").
old_examples=$("$old" example)
examples=$(for e in $("$new" example); do
  if grep -qx "$e" <<<"$old_examples"; then echo "$e"; fi; done)
for side in before after; do
  bin=$old; [ "$side" = after ] && bin=$new
  dir=$work/$side
  rm -rf "$dir"; mkdir -p "$dir"
  for basis in $bases; do
    quiet "$bin" study cantilever --quick --basis "$basis" --out "$dir/study_$basis"
  done
  for example in $examples; do
    quiet "$bin" run --example "$example" --out "$dir/$example"
  done
  quiet "$bin" study footing --quick --out "$dir/study_footing"
done
python3 "$here/compare_runs.py" "$work/before" "$work/after"
