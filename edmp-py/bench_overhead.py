#!/usr/bin/env python3
"""The cost of planning through Python: `edmp.plan` (validate, plan, write the edmp-plan/1
document, parse it, numpy arrays) against the Rust API alone (`plan_problem`, timed inside Rust
on the already parsed problem), same scene, same seed, same process, interleaved.

    python3 edmp-py/bench_overhead.py [--scene examples/wall.json] [--repeats 20] [--candidates]

Prints the median of each and their difference: the overhead per plan (it includes the
document's intersection-volume cost, which the CLI computes too). Plan times vary by tens of
ms from run to run, so it also times the Python-side steps alone: validating the scene (the
host's JSON reader), and parsing the returned document into a Plan with numpy arrays.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import json

import edmp
from edmp import _edmp


def main() -> None:
    root = Path(__file__).resolve().parents[1]
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default=str(root / "examples" / "wall.json"))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--candidates", action="store_true", help="also return the 12 candidates")
    args = ap.parse_args()

    scene = edmp.Scene.from_file(args.scene)
    text = scene.to_json()
    edmp.plan(scene, seed=args.seed)  # warm up (page in the prior, allocator)
    python_ms: list[float] = []
    rust_ms: list[float] = []
    for _ in range(args.repeats):
        began = time.perf_counter()
        edmp.plan(scene, seed=args.seed, candidates=args.candidates)
        python_ms.append((time.perf_counter() - began) * 1e3)
        rust_ms.extend(_edmp.plan_problem_ms(text, args.seed, 1))
    py, rs = statistics.median(python_ms), statistics.median(rust_ms)
    print(f"scene {args.scene}, seed {args.seed}, {args.repeats} runs each, candidates={args.candidates}")
    print(f"edmp.plan (Python, end to end): median {py:.2f} ms  (min {min(python_ms):.2f})")
    print(f"plan_problem (Rust API alone):  median {rs:.2f} ms  (min {min(rust_ms):.2f})")
    print(f"overhead per plan: {py - rs:.2f} ms ({(py - rs) / rs * 100:.1f} %)")

    doc_text = _edmp.plan(text, args.seed, args.candidates, False)
    n = 200
    began = time.perf_counter()
    for _ in range(n):
        _edmp.validate(text)
    validate_ms = (time.perf_counter() - began) * 1e3 / n
    began = time.perf_counter()
    for _ in range(n):
        edmp.Plan.from_document(json.loads(doc_text))
    parse_ms = (time.perf_counter() - began) * 1e3 / n
    print(f"of which, alone: validating the scene {validate_ms:.3f} ms, "
          f"document ({len(doc_text)} bytes) to Plan {parse_ms:.3f} ms")


if __name__ == "__main__":
    main()
