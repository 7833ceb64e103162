#!/usr/bin/env python3
"""EDMP against RRT-Connect from `edmp-host bench --serial` runs of both suites made in one
session: median, p95 and p99 per suite and over both, and EDMP's as a multiple of RRT-Connect's
(docs/benchmark.md, "Speed against RRT-Connect"). Standard library only.

    python3 benchmarks/ratios.py EDMP_PREFIX RRT_PREFIX
    e.g. python3 benchmarks/ratios.py bench-out/after bench-out/rrt   # reads bench-out/after-problems, -unseen, ...

A quantile is the value at index ⌊q·n⌋ of the sorted times (the same rule for both planners).
"""

import json
import sys
from pathlib import Path

SUITES = ("problems", "unseen")


def times(prefix: str, suite: str) -> list[float]:
    rows = Path(f"{prefix}-{suite}/results.jsonl").read_text().splitlines()
    return [json.loads(line)["time_ms"] for line in rows if line.strip()]


def quantile(values: list[float], q: float) -> float:
    values = sorted(values)
    return values[min(len(values) - 1, int(q * len(values)))]


def main() -> None:
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    edmp, rrt = sys.argv[1:]
    print("| suites | EDMP median / p95 / p99 ms | RRT-Connect median / p95 / p99 ms | EDMP / RRT-Connect: median, p95, p99 |")
    print("|---|---|---|---|")
    for suites in ([SUITES[0]], [SUITES[1]], list(SUITES)):
        e = [t for s in suites for t in times(edmp, s)]
        r = [t for s in suites for t in times(rrt, s)]
        qs = (0.5, 0.95, 0.99)
        cells = [
            " / ".join(f"{quantile(e, q):.1f}" for q in qs),
            " / ".join(f"{quantile(r, q):.1f}" for q in qs),
            ", ".join(f"{quantile(e, q) / quantile(r, q):.2f}" for q in qs),
        ]
        print(f"| {' + '.join(suites)} ({len(e)}) | {' | '.join(cells)} |")


if __name__ == "__main__":
    main()
