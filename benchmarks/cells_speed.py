#!/usr/bin/env python3
"""Plan time of clouds and meshes against the same problems' primitives, in one run.

For every problem of a dense cloud set and a dense mesh set made by `benchmarks/cells.py`
(`--sets surface_dense mesh_dense`, ~200,000 points or ~10,000 triangles a scene), runs
`edmp-host plan` on the source problem (primitives), its cloud version and its mesh version,
interleaved, `--repeats` times each, and reads `timing_ms.total` (reading the scene and its
files included: everything after the process started until the plan is made). Prints, per
version, the median and p95 over problems of each problem's median time, and their ratios to
the primitives. Problems a version refuses (an end inside the cloud's balls) are listed and
left out of every version's numbers. Standard library only.

    python3 benchmarks/cells_speed.py --cells bench-out/cells [--repeats 3] [--binary target/release/edmp-host]
"""

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path


def plan_ms(binary: str, scene: Path) -> float | None:
    out = subprocess.run([binary, "plan", str(scene)], capture_output=True, text=True)
    if out.returncode not in (0, 1):
        return None
    return json.loads(out.stdout)["timing_ms"]["total"]


def p95(xs: list[float]) -> float:
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(0.95 * (len(xs) - 1))))]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cells", type=Path, default=Path("bench-out/cells"))
    ap.add_argument("--binary", default="target/release/edmp-host")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    clouds = sorted((args.cells / "surface_dense").glob("*/*.json"))
    rows = []
    refused = []
    for i, cloud in enumerate(clouds):
        rel = cloud.relative_to(args.cells / "surface_dense")
        mesh = args.cells / "mesh_dense" / rel
        source = Path(json.loads(cloud.read_text())["meta"]["source"])
        versions = {"primitives": source, "cloud": cloud, "mesh": mesh}
        times = {k: [] for k in versions}
        for _ in range(args.repeats):
            for name, scene in versions.items():
                times[name].append(plan_ms(args.binary, scene))
        if any(t is None for ts in times.values() for t in ts):
            refused.append(str(rel))
        else:
            rows.append({k: statistics.median(v) for k, v in times.items()})
        print(f"\r{i + 1}/{len(clouds)} problems", end="", file=sys.stderr)
    print(file=sys.stderr)
    base = [r["primitives"] for r in rows]
    print(f"{len(rows)} problems, {args.repeats} runs each (the median per problem), `timing_ms.total` of `edmp-host plan`\n")
    print("| version | median ms | p95 ms | median / primitives' | p95 / primitives' |")
    print("|---|---|---|---|---|")
    for name in ("primitives", "cloud", "mesh"):
        xs = [r[name] for r in rows]
        print(
            f"| {name} | {statistics.median(xs):.1f} | {p95(xs):.1f} | "
            f"{statistics.median(xs) / statistics.median(base):.2f} | {p95(xs) / p95(base):.2f} |"
        )
    if refused:
        print(f"\nrefused (an end inside a cloud's balls), left out: {', '.join(refused)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
