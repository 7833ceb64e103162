#!/usr/bin/env python3
"""User CPU time per plan of several edmp-host configurations, interleaved problem by problem
(each problem planned by every configuration in turn, ROUNDS times; the least time per problem
kept), so that a machine whose speed drifts treats all of them alike. Prints the median and mean
per suite and the p95 over both. Standard library only; Linux (os.wait4).

    python3 benchmarks/user_cpu.py ROUNDS PER_FAMILY 'BINARY [plan args]' ['BINARY [plan args]' ...]
    e.g. python3 benchmarks/user_cpu.py 2 12 target/release/edmp-host 'target/release/edmp-host --refine-check-every 4'

A configuration whose first argument is `rrt` runs `BINARY rrt` (the RRT-Connect baseline)
instead of `BINARY plan`: 'target/release/edmp-host rrt'.

Problems: the first PER_FAMILY of every family of benchmarks/problems and benchmarks/unseen
(SUITES overrides the list of suite folders, space-separated).
"""

import glob
import os
import statistics
import sys


def user_seconds(command: list[str], problem: str) -> float:
    pid = os.fork()
    if pid == 0:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.dup2(null, 2)
        sub, args = ("rrt", command[2:]) if command[1:2] == ["rrt"] else ("plan", command[1:])
        os.execv(command[0], [command[0], sub, problem, "-o", os.devnull, *args])
    _, _, usage = os.wait4(pid, 0)
    return usage.ru_utime


def main() -> int:
    if len(sys.argv) < 4:
        print(__doc__, file=sys.stderr)
        return 2
    rounds, per_family = int(sys.argv[1]), int(sys.argv[2])
    configs = [c.split() for c in sys.argv[3:]]
    suites = os.environ.get("SUITES", "benchmarks/problems benchmarks/unseen").split()
    problems = [
        p
        for suite in suites
        for family in sorted(glob.glob(f"{suite}/*/"))
        for p in sorted(glob.glob(f"{family}*.json"))[:per_family]
    ]
    best: list[dict[str, float]] = [{} for _ in configs]
    for r in range(rounds):
        for i, p in enumerate(problems, 1):
            for times, command in zip(best, configs):
                t = user_seconds(command, p)
                times[p] = min(t, times.get(p, float("inf")))
            print(f"\rround {r + 1}/{rounds}: {i}/{len(problems)}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    for times, command in zip(best, configs):
        parts = []
        for suite in suites:
            v = [1e3 * t for p, t in times.items() if p.startswith(suite)]
            if v:
                parts.append(f"{suite}: median {statistics.median(v):.1f} mean {statistics.mean(v):.1f} ms")
        every = sorted(times.values())
        p95 = 1e3 * every[int(0.95 * (len(every) - 1))]
        print(f"{' '.join(command)}: {' | '.join(parts)} | p95 {p95:.1f} ms (user CPU, least of {rounds})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
