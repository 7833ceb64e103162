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

With `--against OTHER`, every plan is also made by the binary OTHER, in turn with `--binary`,
and the table is followed by the median and quartiles over problems of each version's time
ratio (binary / OTHER): how two builds compare, in one run.

    python3 benchmarks/cells_speed.py --cells bench-out/cells [--repeats 3] [--binary target/release/edmp-host] [--against OLD]
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
    ap.add_argument("--against", help="a second binary, planned in turn with --binary")
    args = ap.parse_args()
    binaries = [args.binary] + ([args.against] if args.against else [])
    clouds = sorted((args.cells / "surface_dense").glob("*/*.json"))
    rows = []
    ratios = []
    refused = []
    for i, cloud in enumerate(clouds):
        rel = cloud.relative_to(args.cells / "surface_dense")
        mesh = args.cells / "mesh_dense" / rel
        source = Path(json.loads(cloud.read_text())["meta"]["source"])
        versions = {"primitives": source, "cloud": cloud, "mesh": mesh}
        times = {(k, b): [] for k in versions for b in binaries}
        for _ in range(args.repeats):
            for name, scene in versions.items():
                for b in binaries:
                    times[(name, b)].append(plan_ms(b, scene))
        if any(t is None for ts in times.values() for t in ts):
            refused.append(str(rel))
        else:
            medians = {k: statistics.median(v) for k, v in times.items()}
            rows.append({name: medians[(name, args.binary)] for name in versions})
            if args.against:
                ratios.append({name: medians[(name, args.binary)] / medians[(name, args.against)] for name in versions})
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
    if ratios:
        print(f"\ntime of {args.binary} / time of {args.against}, per problem (planned in turn):\n")
        print("| version | median ratio | quartiles |")
        print("|---|---|---|")
        for name in ("primitives", "cloud", "mesh"):
            xs = sorted(r[name] for r in ratios)
            print(f"| {name} | {statistics.median(xs):.3f} | {xs[len(xs) // 4]:.3f}-{xs[3 * len(xs) // 4]:.3f} |")
    if refused:
        print(f"\nrefused (an end inside a cloud's balls), left out: {', '.join(refused)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
