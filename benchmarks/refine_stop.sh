#!/usr/bin/env bash
# The ablation behind CHANGELOG.md, 2026-12-01, "the refinement ends on the checker's word": the refinement's budget
# and its early stop (`--refine-check-every`, `--refine-stop-free`), the first stage alone
# (`--no-global`) and the whole planner, on the first 25 problems of every family of both
# suites. Success, path length and MRESG are what it compares (the runs are serial, but their
# times are only comparable when nothing else runs). About 15 minutes on the 2-core machine.
#   benchmarks/refine_stop.sh [OUT]        # default bench-out/refine-stop
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -p edmp-host
B=target/release/edmp-host
OUT=${1:-bench-out/refine-stop}
run() {
    local name=$1
    shift
    for suite in problems unseen; do
        "$B" bench --problems "benchmarks/$suite" --per-family 25 --serial -o "$OUT/$name-$suite" "$@" >/dev/null
        printf '%-16s %-9s %s\n' "$name" "$suite" "$(grep '^| all |' "$OUT/$name-$suite/summary.md" | head -1)"
    done
}
never=(--refine-check-every 0)
# The first stage alone.
run ng-r48 --no-global "${never[@]}" --refine-steps 48   # the shipped setting until 2026-12-01
run ng-r96 --no-global "${never[@]}" --refine-steps 96
for r in 48 96 144 192; do run "ng-s8f1-r$r" --no-global --refine-check-every 8 --refine-stop-free 1 --refine-steps "$r"; done
run ng-s4f1-r96 --no-global --refine-check-every 4 --refine-stop-free 1 --refine-steps 96
run ng-s16f1-r96 --no-global --refine-check-every 16 --refine-stop-free 1 --refine-steps 96
run ng-s8f3-r96 --no-global --refine-check-every 8 --refine-stop-free 3 --refine-steps 96
for r in 48 96; do run "ng-s8f12-r$r" --no-global --refine-check-every 8 --refine-stop-free 12 --refine-steps "$r"; done
for k in 3 4; do run "ng-k$k" --no-global --steps "$k"; done
# The whole planner (global stage on).
run g-r48 "${never[@]}" --refine-steps 48
for r in 48 96 144; do run "g-s8f1-r$r" --refine-check-every 8 --refine-stop-free 1 --refine-steps "$r"; done
