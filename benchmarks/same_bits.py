#!/usr/bin/env python3
"""Whether two edmp-host builds plan the same bits: runs `plan --candidates` of both on the first
N problems of every family of both committed suites and compares the plans field by field, with
the times (`timing_ms`) left out. For changes that must not change a plan (a faster kernel, a
cheaper broad phase): a difference names the problem and the first field that differs.

    python3 benchmarks/same_bits.py OLD_BINARY NEW_BINARY [--per-family 25] [--jobs 2] [--winner-only]
    python3 benchmarks/same_bits.py [--per-family 25] [--jobs 2] [--winner-only] -- OLD_BINARY NEW_BINARY \
        [extra plan args, e.g. --waves 4]

`--winner-only` plans without `--candidates`, as a user does: the chosen plan alone, which the
planner judges only as many candidates for as the winner needs (`Judging::Winner`).

Exit 0 when every plan is identical, 1 otherwise. Standard library only.
"""

import argparse
import concurrent.futures
import json
import subprocess
import sys
from pathlib import Path

SUITES = ["benchmarks/problems", "benchmarks/unseen"]


def plan(binary: str, problem: Path, extra: list[str], candidates: bool = True) -> dict:
    flags = ["--candidates"] if candidates else []
    out = subprocess.run([binary, "plan", str(problem), *flags, *extra], capture_output=True, text=True)
    try:
        doc = json.loads(out.stdout)
    except json.JSONDecodeError:
        return {"exit": out.returncode, "stderr": out.stderr.strip()}
    doc.pop("timing_ms", None)
    doc["exit"] = out.returncode
    return doc


def first_difference(a, b, path="$"):
    if type(a) is not type(b):
        return path
    if isinstance(a, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                return f"{path}.{k}"
            d = first_difference(a[k], b[k], f"{path}.{k}")
            if d:
                return d
        return None
    if isinstance(a, list):
        if len(a) != len(b):
            return f"{path} (length)"
        for i, (x, y) in enumerate(zip(a, b)):
            d = first_difference(x, y, f"{path}[{i}]")
            if d:
                return d
        return None
    return None if a == b else path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--per-family", type=int, default=25)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--winner-only", action="store_true", help="plan without --candidates")
    ap.add_argument("extra", nargs="*", help="extra `plan` arguments (after --)")
    args = ap.parse_args()
    problems = [
        p
        for suite in SUITES
        for family in sorted(Path(suite).iterdir())
        if family.is_dir()
        for p in sorted(family.glob("*.json"))[: args.per_family]
    ]

    def compare(p: Path):
        every = not args.winner_only
        return p, first_difference(plan(args.old, p, args.extra, every), plan(args.new, p, args.extra, every))

    differ = 0
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        for i, (p, diff) in enumerate(pool.map(compare, problems), 1):
            if diff:
                differ += 1
                print(f"{p}: differs at {diff}")
            print(f"\r{i}/{len(problems)} compared, {differ} differ", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    print(f"{len(problems) - differ} of {len(problems)} plans identical")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
