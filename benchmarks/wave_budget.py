#!/usr/bin/env python3
"""What a wave budget (`edmp-host bench --wave-budget N`) does to the tail, against a run without
one (`--wave-budget 0`), both suites (docs/benchmark.md, "Bounding the waves"). A plan the
budget leaves bit-identical keeps the unbounded run's time, so only the plans it changed carry
the machine's drift, and their times are scaled by the median ratio of the identical plans'
times between the two runs. Standard library only.

    python3 benchmarks/wave_budget.py BASE_PREFIX PREFIX [PREFIX ...]
    e.g. python3 benchmarks/wave_budget.py bench-out/wb-none bench-out/wb-24   # reads PREFIX-problems, PREFIX-unseen
"""

import json
import statistics
import sys
from pathlib import Path

SUITES = ("problems", "unseen")


def load(prefix: str, suite: str) -> dict:
    rows = Path(f"{prefix}-{suite}/results.jsonl").read_text().splitlines()
    return {r["problem"]: r for r in (json.loads(line) for line in rows if line.strip())}


def quantile(values: list[float], q: float) -> float:
    values = sorted(values)
    return values[min(len(values) - 1, int(q * len(values)))]


def main() -> None:
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    base, runs = sys.argv[1], sys.argv[2:]
    print(
        "| run | plans changed | first stage alone (in dist, unseen) | in dist p95 / p99 ms | unseen p95 / p99 ms "
        "| both: median, p95, p99 ms | mean path length, rad (in dist, unseen) |"
    )
    print("|---|---|---|---|---|---|---|")
    for run in [base, *runs]:
        both, cells, first, lengths, changed = [], [], [], [], 0
        for suite in SUITES:
            b, x = load(base, suite), load(run, suite)
            same = [p for p in b if b[p]["waypoints"] == x[p]["waypoints"]]
            drift = statistics.median(x[p]["time_ms"] / b[p]["time_ms"] for p in same) if same else 1.0
            t = [b[p]["time_ms"] if p in same else x[p]["time_ms"] / drift for p in b]
            both += t
            changed += len(b) - len(same)
            first.append(sum(r["stage"] == "diffusion" for r in x.values()))
            cells.append(f"{quantile(t, 0.95):.0f} / {quantile(t, 0.99):.0f}")
            lengths.append(statistics.mean(r["path_length"] for r in x.values() if r["path_length"] is not None))
        print(
            f"| {Path(run).name} | {changed} | {first[0]}, {first[1]} | {cells[0]} | {cells[1]} | "
            f"{quantile(both, 0.5):.1f}, {quantile(both, 0.95):.0f}, {quantile(both, 0.99):.0f} | "
            f"{lengths[0]:.3f}, {lengths[1]:.3f} |"
        )


if __name__ == "__main__":
    main()
