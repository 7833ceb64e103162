#!/usr/bin/env python3
"""One markdown row per `edmp-host bench` run: solved, which stage solved each problem, median /
p95 time per plan, path length and MRESG of the solved plans. For ablations side by side
(CHANGELOG.md, 2026-12-02, "a stronger local optimizer").

    python3 benchmarks/stage_table.py bench-out/opt-*/unseen-*     # any number of run folders
"""
import json
import statistics
import sys
from pathlib import Path


def quantile(values, q):
    values = sorted(values)
    if not values:
        return float("nan")
    return values[min(len(values) - 1, int(q * len(values)))]


def row(run: Path) -> str:
    rows = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines() if line.strip()]
    solved = [r for r in rows if r["status"] == "success"]
    stages = {s: sum(r.get("stage") == s for r in rows) for s in ("diffusion", "reseeded", "search", "none")}
    times = [r["time_ms"] for r in rows]
    length = statistics.mean(r["path_length"] for r in solved) if solved else float("nan")
    mresg = statistics.mean(r["roughness"]["mresg"] for r in solved) if solved else float("nan")
    return (
        f"| {run.name} | {len(solved)}/{len(rows)} | {stages['diffusion']} / {stages['reseeded']} / "
        f"{stages['search']} / {stages['none']} | {statistics.median(times):.1f} | {quantile(times, 0.95):.1f} | "
        f"{length:.3f} | {mresg:.4f} |"
    )


def main() -> None:
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    print("| run | solved | diffusion / reseeded / search / none | median ms | p95 ms | path length | MRESG |")
    print("|---|---|---|---|---|---|---|")
    for arg in sys.argv[1:]:
        print(row(Path(arg)))


if __name__ == "__main__":
    main()
