#!/usr/bin/env bash
# Times the plan of every problem of a suite and judges the trajectories from outside:
#   1. `edmp-host plan P --timed` (jerk-limited, 100 Hz) -> OUT/FAMILY-NNN.timed.json, and
#      `--timed --no-jerk-limit` -> OUT/FAMILY-NNN.nojerk.json (two plans at a time);
#   2. benchmarks/check_timed.py (numpy only) on every timed plan: on the path, within the
#      limits at the sample rate, from rest to rest;
#   3. benchmarks/toppra_compare.py in its own venv (benchmarks/requirements-toppra.txt): our
#      durations against TOPP-RA's time-optimal ones on the same curve.
#
#   benchmarks/timed_suite.sh [SUITE] [OUT] [PER_FAMILY]   e.g. benchmarks/timed_suite.sh benchmarks/unseen /tmp/timed-unseen 100
set -euo pipefail
cd "$(dirname "$0")/.."
suite=${1:-benchmarks/problems}
out=${2:-bench-out/timed}
per_family=${3:-100}
mkdir -p "$out"
cargo build -q --release -p edmp-host
bin=target/release/edmp-host
list=$(for d in "$suite"/*/; do ls "$d"*.json | head -n "$per_family"; done)
plan_one() {
    local p=$1 name
    name=$(basename "$(dirname "$p")")-$(basename "$p" .json)
    "$2" plan "$p" --timed -o "$3/$name.timed.json" 2>/dev/null || true
    "$2" plan "$p" --timed --no-jerk-limit -o "$3/$name.nojerk.json" 2>/dev/null || true
}
export -f plan_one
echo "$list" | xargs -P 2 -I{} bash -c 'plan_one "$@"' _ {} "$bin" "$out"
# Plans whose status is "collision" carry no trajectory: check the rest.
timed=$(python3 -c 'import json,sys; [print(f) for f in sys.argv[1:] if "trajectory" in json.load(open(f))]' "$out"/*.json)
python3 benchmarks/check_timed.py $timed > "$out/check_timed.txt" || { tail -n 20 "$out/check_timed.txt"; exit 1; }
tail -n 1 "$out/check_timed.txt"
venv=${TOPPRA_VENV:-/tmp/toppra-venv}
[ -x "$venv/bin/python" ] || { python3 -m venv "$venv" && "$venv/bin/pip" install -q -r benchmarks/requirements-toppra.txt; }
"$venv/bin/python" benchmarks/toppra_compare.py $(printf '%s\n' $timed | grep '\.timed\.json$') > "$out/toppra.txt"
tail -n 4 "$out/toppra.txt"
