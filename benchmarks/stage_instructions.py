#!/usr/bin/env python3
"""Instructions per plan and per stage, counted by callgrind (not timed): the same binary and
problem give the same count whatever else the machine runs, so a change can be measured on a
shared 2-core machine. Standard library only; needs valgrind (callgrind_annotate).

    python3 benchmarks/stage_instructions.py [--binary B] [--every K] [--jobs 2] PROBLEM_DIR... \
        [--extra-args "--no-shortcut"]

Runs `B plan P -o /dev/null` under `valgrind --tool=callgrind` for every K-th problem (sorted)
of each family folder, then prints one row per problem and the median of each column: the whole
plan, and inclusive counts of the network (`predict_noise_on`, or `predict_noise` in older builds), the guidance (`guidance::step_rows`), the
selection (`judge`), the global stage (`planner::global::rescue`, or its caller `planner::finish_on`) and the shortening (`shortcut::shorten`, or its caller `planner::polish`),
and the costs with their gradients (`cost::trajectory_cost_memo`, or `trajectory_cost` in builds before it: the guidance's work, plus the
judge's swept volumes; a column that does not depend on what the compiler inlined).
A stage's count is inclusive: the global stage's network and guidance are counted in it too.
"""

import argparse
import concurrent.futures
import os
import re
import statistics
import subprocess
import tempfile
from pathlib import Path

STAGES = {
    "network": ("edmp_core::prior::net::predict_noise_on", "edmp_core::prior::net::predict_noise"),
    "guidance": "edmp_core::guidance::step_rows",
    "costs": ("edmp_core::cost::trajectory_cost_memo", "edmp_core::cost::trajectory_cost"),
    "select": "edmp_core::planner::judge::judge",
    "global": ("edmp_core::planner::global::rescue", "edmp_core::planner::finish_on"),
    "shortcut": ("edmp_core::planner::shortcut::shorten", "edmp_core::planner::polish"),
}


def count(binary: str, problem: Path, extra: list[str]) -> dict[str, int]:
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "cg.out")
        subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", binary, "plan", str(problem), "-o",
             os.devnull, *extra],
            check=False,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        text = subprocess.run(
            ["callgrind_annotate", "--inclusive=yes", "--threshold=100", out],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
    row = {"total": 0}
    m = re.search(r"^\s*([\d,]+) \(100\.0+%\)\s+PROGRAM TOTALS", text, re.M)
    if m:
        row["total"] = int(m.group(1).replace(",", ""))
    for stage, symbols in STAGES.items():
        # The largest inclusive count among the lines naming the function (callgrind lists a
        # function once per file its inlined code came from; the largest is the function itself).
        # A stage may name two functions, the second one's caller, in case one was inlined.
        best = 0
        pattern = "|".join(re.escape(s) for s in ([symbols] if isinstance(symbols, str) else symbols))
        for line in text.splitlines():
            if re.search(r":(?:" + pattern + r")(?:[\s<]|$)", line):
                m = re.match(r"\s*([\d,]+)", line)
                if m:
                    best = max(best, int(m.group(1).replace(",", "")))
        row[stage] = best
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+", type=Path, help="problem folders (a suite, or one family)")
    ap.add_argument("--binary", default="target/release/edmp-host")
    ap.add_argument("--every", type=int, default=10, help="every K-th problem of each family")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--extra-args", default="", help="more `plan` arguments, e.g. --no-shortcut")
    args = ap.parse_args()
    problems = []
    for d in args.dirs:
        files = sorted(d.rglob("*.json"))
        families = sorted({f.parent for f in files})
        for fam in families:
            problems += sorted(f for f in files if f.parent == fam)[:: args.every]
    extra = args.extra_args.split()
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        rows = list(pool.map(lambda p: count(args.binary, p, extra), problems))
    cols = ["total", *STAGES]
    print("| problem | " + " | ".join(cols) + " |")
    print("|---|" + "---:|" * len(cols))
    for p, r in zip(problems, rows):
        name = f"{p.parent.name}/{p.name}"
        print(f"| {name} | " + " | ".join(f"{r[c] / 1e6:.1f}" for c in cols) + " |")
    print("| **median** (10⁶) | " + " | ".join(f"{statistics.median(r[c] for r in rows) / 1e6:.1f}" for c in cols) + " |")


if __name__ == "__main__":
    main()
