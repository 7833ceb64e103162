#!/usr/bin/env bash
# Every planner run behind docs/benchmark.md's tables, then the report.
# Runs land in bench-out/<name>/ (results.jsonl, summary.md, charts); the report in
# docs/benchmark/. Measured: 14 min on the 2-core development machine before the last five runs
# were added (the unseeded search, no stall stop, two start-draw runs, the one batch: about a
# minute each on the whole suite, by the runs in CHANGELOG.md).
#   benchmarks/ablations.sh            # everything
#   ONLY="edmp rrt" benchmarks/ablations.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -p edmp-host
B=target/release/edmp-host
OUT=${OUT:-bench-out}
want() { [ -z "${ONLY:-}" ] || [[ " $ONLY " == *" $1 "* ]]; }
run() {
    local name=$1
    shift
    if want "$name"; then
        echo "== $name: $*"
        # Every candidate judged: the ensemble tables count free candidates per guide (the
        # default judges only up to the winner; timings here are a little above the default's).
        local every=()
        [[ " $* " == *" --planner rrt-connect "* ]] || every=(--judge-every)
        "$B" bench -o "$OUT/$name" "${every[@]}" "$@" | tail -1
    fi
}

# Timings: one plan at a time on one core.
run edmp --serial
# The paper's one batch of 12 guides (the default deals them into 4 waves).
run one-batch --serial --waves 1 --label "EDMP, one batch of 12 guides (the paper's ensemble)"
run rrt --planner rrt-connect --serial --label "RRT-Connect, 1 s budget"
# Ablations of this project's deviations (success; both cores, so their times are not comparable).
run original-strided --waves 1 --steps 10 --gradient-steps 4 --refine-steps 0 --step-limit inf --world-boxes \
    --label "EDMP, strided K = 10, the original's costs and steps"
run world-boxes --world-boxes
run no-refine --refine-steps 0
run no-step-limit --step-limit inf
run no-conditioning --no-conditioning
run k5 --steps 5 --gradient-steps 4
run k10 --steps 10
run k25 --steps 25 --gradient-steps 2
# Switches of the global stage and the refinement (CHANGELOG.md, 2026-12-02): the classical
# search, no stall stop, rows that share their first draw of noise; and the search that checks
# every edge it grows (CHANGELOG.md, 2026-12-07).
run unseeded-search --no-search-seed
run eager-search --eager-search
run no-stall --refine-stall 0
run start-draws-4 --start-draws 4
run start-draws-1 --start-draws 1
# The original sampler (255 steps, guidance on even t), on 25 problems per family.
run ancestral-original --waves 1 --ancestral --per-family 25 --refine-steps 0 --step-limit inf --world-boxes \
    --label "EDMP, ancestral K = 255, the original's costs and steps"
run ancestral --ancestral --per-family 25
# Table III and Figure 7: each guide alone (12 rows of it).
for g in 1 2 3 4 5 10 11 13 14 16 18 21; do
    run "guide-$g" --waves 1 --guides "$g"
done
# Figure 6: prefixes of the guides interleaving iv and sv (1 guide is guide-1 above), each
# ensemble one batch as in the paper (the 12-guide point is one-batch).
run guides-2 --waves 1 --guides 1,10
run guides-3 --waves 1 --guides 1,10,2
run guides-4 --waves 1 --guides 1,10,2,11
run guides-6 --waves 1 --guides 1,10,2,11,4,18

runs=()
# one-batch first: the report's tables compare the runs with its settings (one batch, as the paper).
for name in one-batch edmp rrt original-strided world-boxes no-refine no-step-limit no-conditioning k5 k10 k25 \
    unseeded-search no-stall start-draws-4 start-draws-1 \
    ancestral-original ancestral guides-2 guides-3 guides-4 guides-6 \
    guide-1 guide-2 guide-3 guide-4 guide-5 guide-10 guide-11 guide-13 guide-14 guide-16 guide-18 guide-21; do
    [ -f "$OUT/$name/results.jsonl" ] && runs+=("$OUT/$name")
done
"$B" bench-report "${runs[@]}" -o docs/benchmark > /dev/null
echo "report: docs/benchmark/report.md"
