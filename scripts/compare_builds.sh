#!/usr/bin/env bash
# Runs the standard comparison set with two mpm binaries and compares the
# results (scripts/compare_runs.py): the paper's cantilever study for both
# bases, the column and the cantilever examples.
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
for side in before after; do
  bin=$old; [ "$side" = after ] && bin=$new
  dir=$work/$side
  rm -rf "$dir"; mkdir -p "$dir"
  quiet "$bin" study cantilever --quick --basis gimp --out "$dir/study_gimp"
  quiet "$bin" study cantilever --quick --basis linear --out "$dir/study_linear"
  quiet "$bin" run --example column --out "$dir/column"
  quiet "$bin" run --example cantilever --out "$dir/cantilever"
done
python3 "$here/compare_runs.py" "$work/before" "$work/after"
