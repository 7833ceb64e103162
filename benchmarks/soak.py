#!/usr/bin/env python3
"""Soak test of `edmp-host plan` (standard library only; scripts/soak runs it).

COUNT problems, WORKERS at a time: the committed suites (benchmarks/problems, unseen,
near_surface) with random `--seed`s, and mutated scenes (NaN / huge / tiny / negative sizes,
duplicated obstacles, more than 64 obstacles, ends outside the joint limits, unreachable pose
goals, bad quaternions, unknown fields, truncated JSON, ...). Checks the command line's contract
(docs/formats.md, "The command line"):

- no process dies by a signal, none runs past --timeout seconds (killed and counted);
- the exit status is 0, 1 or 2, and the one the mutation calls for where it calls for one;
- 0 and 1 write an `edmp-plan/1` file whose status matches (success / collision), with 50
  finite waypoints from the start (a NaN would be written as null);
- 2 writes nothing, and standard error names the offending field by its JSON path (or says
  the text is not valid JSON);
- each process's peak resident memory (`/usr/bin/time -f %M`; without it ru_maxrss from wait4,
  which also counts the driver's own image copied before exec, an upper bound) stays flat.

Findings (inputs, arguments and stderr) are written under --work/findings; exit 1 if any.
"""

import argparse
import copy
import glob
import json
import math
import os
import random
import re
import shutil
import signal
import statistics
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor

TIME = "/usr/bin/time" if os.access("/usr/bin/time", os.X_OK) else None
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SUITES = ["benchmarks/problems", "benchmarks/unseen", "benchmarks/near_surface"]
# Upper soft limits would do; the hard limits of the Panda, padded, are certainly outside.
OUTSIDE = [3.5, 2.5, 3.5, 0.5, 3.5, 4.5, 3.5]
FIELD = re.compile(r"[A-Za-z_]+(?:\[\d+\])?(?:\.[A-Za-z_]+(?:\[\d+\])?)*")

# How a mutation should end: a set of allowed exit codes, and for 2 the field stderr must name.
PLAN = {0, 1}
ANY = {0, 1, 2}


def sizes_key(o):
    return "dims" if o["type"] == "cuboid" else "radius"


def set_size(o, value, rng):
    if o["type"] == "cuboid":
        o["dims"][rng.randrange(3)] = value
    elif o["type"] == "cylinder" and rng.random() < 0.5:
        o["height"] = value
    else:
        o["radius"] = value


def mutate(doc, rng):
    """(name, text, allowed exit codes, expected field prefix or None)."""
    d = copy.deepcopy(doc)
    obs = d["obstacles"]
    i = rng.randrange(len(obs)) if obs else None
    kind = rng.choice(
        ["nan", "inf_literal", "overflow_f32", "huge_size", "huge_center", "tiny_size", "subnormal_size",
         "negative_size", "zero_size", "duplicate", "too_many", "start_outside", "goal_outside",
         "pose_unreachable", "pose_bad_quaternion", "bad_quaternion", "zero_quaternion", "short_quaternion",
         "unknown_top", "unknown_obstacle", "truncated", "wrong_type", "empty_obstacles", "missing_goal"]
    )
    if kind in ("nan", "inf_literal", "overflow_f32", "huge_size", "tiny_size", "subnormal_size",
                "negative_size", "zero_size", "huge_center", "bad_quaternion", "zero_quaternion",
                "short_quaternion", "unknown_obstacle") and i is None:
        kind = "unknown_top"
    o = obs[i] if i is not None else None
    at = f"obstacles[{i}]"
    if kind == "nan":
        set_size(o, float("nan"), rng)  # json.dumps writes NaN: not valid JSON
        return kind, json.dumps(d), {2}, None
    if kind == "inf_literal":
        o["center"][rng.randrange(3)] = float("inf")
        return kind, json.dumps(d), {2}, None
    if kind == "overflow_f32":
        set_size(o, 1e39, rng)
        return kind, json.dumps(d), {2}, at
    if kind == "huge_size":
        set_size(o, rng.choice([1e3, 1e6, 1e20, 3e38]), rng)
        return kind, json.dumps(d), ANY, None
    if kind == "huge_center":
        o["center"] = [rng.choice([1e6, -1e20, 3e38]) for _ in range(3)]
        return kind, json.dumps(d), ANY, None
    if kind == "tiny_size":
        set_size(o, rng.choice([1e-6, 1e-20, 1e-38]), rng)
        return kind, json.dumps(d), ANY, None
    if kind == "subnormal_size":
        set_size(o, 1e-46, rng)  # rounds to 0.0 in f32
        return kind, json.dumps(d), {2}, at
    if kind == "negative_size":
        set_size(o, -rng.uniform(1e-3, 1.0), rng)
        return kind, json.dumps(d), {2}, at
    if kind == "zero_size":
        set_size(o, 0.0, rng)
        return kind, json.dumps(d), {2}, at
    if kind == "duplicate":
        d["obstacles"] = (obs + obs)[:64]
        return kind, json.dumps(d), PLAN, None
    if kind == "too_many":
        base = obs or [{"type": "sphere", "center": [5.0, 5.0, 5.0], "radius": 0.1}]
        d["obstacles"] = (base * (65 // len(base) + 1))[: rng.randint(65, 130)]
        return kind, json.dumps(d), {2}, "obstacles"
    if kind == "start_outside":
        j = rng.randrange(7)
        d["start"][j] = OUTSIDE[j] * rng.choice([1, -1]) if j != 3 else rng.choice([0.5, -3.5])
        return kind, json.dumps(d), {2}, f"start[{j}]"
    if kind == "goal_outside":
        j = rng.randrange(7)
        q = d["start"][:] if "joints" not in d["goal"] else d["goal"]["joints"]
        q[j] = OUTSIDE[j] * rng.choice([1, -1]) if j != 3 else rng.choice([0.5, -3.5])
        d["goal"] = {"joints": q}
        return kind, json.dumps(d), {2}, f"goal.joints[{j}]"
    if kind == "pose_unreachable":
        p = rng.choice([[3.0, 0.0, 0.5], [0.0, 0.0, -2.0], [1e6, 1e6, 1e6], [0.0, 2.5, 2.5]])
        d["goal"] = {"pose": {"position": p, "quaternion": [0.0, 1.0, 0.0, 0.0]}}
        return kind, json.dumps(d), {2}, "goal.pose"
    if kind == "pose_bad_quaternion":
        d["goal"] = {"pose": {"position": [0.5, 0.0, 0.5], "quaternion": [0.5, 0.5, 0.0, 0.0]}}
        return kind, json.dumps(d), {2}, "goal.pose.quaternion"
    if kind in ("bad_quaternion", "zero_quaternion", "short_quaternion") and o["type"] == "sphere":
        kind = "unknown_obstacle"
    if kind == "bad_quaternion":
        o["quaternion"] = [rng.uniform(0.1, 0.6), 0.0, rng.uniform(0.0, 0.5), 0.0]
        return kind, json.dumps(d), {2}, f"{at}.quaternion"
    if kind == "zero_quaternion":
        o["quaternion"] = [0.0, 0.0, 0.0, 0.0]
        return kind, json.dumps(d), {2}, f"{at}.quaternion"
    if kind == "short_quaternion":
        o["quaternion"] = o["quaternion"][:3]
        return kind, json.dumps(d), {2}, f"{at}.quaternion"
    if kind == "unknown_obstacle":
        o["colour"] = "red"
        return kind, json.dumps(d), {2}, f"{at}.colour"
    if kind == "unknown_top":
        d["velocity"] = 1
        return kind, json.dumps(d), {2}, "velocity"
    if kind == "truncated":
        text = json.dumps(d)
        return kind, text[: rng.randrange(0, text.rindex("}"))], {2}, None
    if kind == "wrong_type":
        d["start"] = "ready"
        return kind, json.dumps(d), {2}, "start"
    if kind == "empty_obstacles":
        d["obstacles"] = []
        return kind, json.dumps(d), PLAN, None
    d.pop("goal")
    return "missing_goal", json.dumps(d), {2}, "goal"


def finite_waypoints(plan):
    w = plan.get("waypoints")
    return (isinstance(w, list) and len(w) == 50
            and all(isinstance(q, list) and len(q) == 7
                    and all(isinstance(x, (int, float)) and math.isfinite(x) for x in q) for q in w))


def run_one(job, args, kill_after):
    """Runs one plan; returns a result dict."""
    n, name, text, allowed, field, source, seed = job
    scene = os.path.join(args.work, "in", f"{threading.get_ident()}.json")
    out = scene[:-5] + ".plan.json"
    err = scene[:-5] + ".stderr"
    with open(scene, "w") as f:
        f.write(text)
    if os.path.exists(out):
        os.remove(out)
    argv = [args.host, "plan", scene, "-o", out, "--seed", str(seed)]
    rss_file = scene[:-5] + ".rss"
    wrapped = [TIME, "-f", "%M", "-o", rss_file] + argv if TIME else argv
    began = time.monotonic()
    with open(err, "w") as ef:
        # setsid: its own process group, so a timeout kills /usr/bin/time and the plan together.
        pid = os.posix_spawn(wrapped[0], wrapped, os.environ, setsid=True,
                             file_actions=[(os.POSIX_SPAWN_OPEN, 0, os.devnull, os.O_RDONLY, 0),
                                           (os.POSIX_SPAWN_OPEN, 1, os.devnull, os.O_WRONLY, 0),
                                           (os.POSIX_SPAWN_DUP2, ef.fileno(), 2)])
        killed = []
        timer = threading.Timer(kill_after, lambda: (killed.append(1), os.killpg(pid, signal.SIGKILL)))
        timer.start()
        _, status, usage = os.wait4(pid, 0)
        timer.cancel()
        timed_out = bool(killed)
    seconds = time.monotonic() - began
    stderr = open(err, errors="replace").read()
    rss_kb, died = usage.ru_maxrss, None
    if TIME and not timed_out:
        lines = open(rss_file).read().split()
        text = open(rss_file).read()
        rss_kb = int(lines[-1]) if lines and lines[-1].isdigit() else 0
        m = re.search(r"terminated by signal (\d+)", text)
        died = int(m.group(1)) if m else None
    elif os.WIFSIGNALED(status):
        died = os.WTERMSIG(status)
    r = {"n": n, "name": name, "source": source, "seed": seed, "seconds": seconds,
         "rss_kb": rss_kb, "problems": []}
    if timed_out:
        r["code"] = "timeout"
        r["problems"].append(f"killed after {kill_after} s")
    elif died is not None:
        r["code"] = f"signal {died}"
        r["problems"].append(f"died by signal {died}")
    else:
        code = os.WEXITSTATUS(status)
        r["code"] = code
        if code not in (0, 1, 2):
            r["problems"].append(f"exit {code}, not 0/1/2")
        elif code not in allowed:
            r["problems"].append(f"exit {code}, expected {sorted(allowed)}")
        if code in (0, 1):
            try:
                plan = json.load(open(out))
                want = "success" if code == 0 else "collision"
                if plan.get("format") != "edmp-plan/1" or plan.get("status") != want:
                    r["problems"].append(f"plan format/status {plan.get('format')}/{plan.get('status')}, exit {code}")
                if not finite_waypoints(plan):
                    r["problems"].append("plan waypoints missing, not 50 x 7, or not finite (NaN is written as null)")
            except (OSError, ValueError) as e:
                r["problems"].append(f"exit {code} but no readable plan: {e}")
        elif code == 2:
            if os.path.exists(out):
                r["problems"].append("exit 2 but a plan file was written")
            line = stderr.strip().splitlines()[-1] if stderr.strip() else ""
            rest = line.removeprefix("edmp-host: ").removeprefix(scene + ": ")
            head = rest.split(": ")[0]
            if rest.startswith("not valid JSON"):
                named = "JSON"
            elif ": " in rest and FIELD.fullmatch(head):
                named = head
            else:
                named = None
                r["problems"].append(f"exit 2, stderr names no field: {line!r}")
            if field and named is not None and not named.startswith(field):
                r["problems"].append(f"stderr names {named!r}, expected {field!r}: {line!r}")
            r["named"] = named
    if r["problems"]:
        base = os.path.join(args.work, "findings", f"{n:06d}-{name}")
        shutil.copy(scene, base + ".json")
        with open(base + ".txt", "w") as f:
            f.write(" ".join(argv[:2] + [base + ".json"] + argv[3:]) + "\n" + "\n".join(r["problems"]) + "\n--- stderr\n" + stderr)
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("count", type=int, nargs="?", default=10000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=30.0, help="seconds before a plan is killed")
    ap.add_argument("--host", default=os.path.join(ROOT, "target/release/edmp-host"))
    ap.add_argument("--work", default=os.path.join(ROOT, "target/soak"))
    ap.add_argument("--rng", type=int, default=1, help="seed of the problem and mutation choice")
    ap.add_argument("--mutated", type=float, default=0.5, help="fraction of mutated problems")
    ap.add_argument("--deadline", type=float, default=0.0,
                    help="start no problem after this many seconds (0: none); the report says how many ran")
    args = ap.parse_args()
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(os.path.join(args.work, "in"))
    os.makedirs(os.path.join(args.work, "findings"))
    files = sorted(f for s in SUITES for f in glob.glob(os.path.join(ROOT, s, "**/*.json"), recursive=True))
    docs = [(os.path.relpath(f, ROOT), json.load(open(f))) for f in files]
    rng = random.Random(args.rng)
    jobs = []
    for n in range(args.count):
        source, doc = rng.choice(docs)
        seed = rng.randrange(2**63)
        if rng.random() < args.mutated:
            name, text, allowed, field = mutate(doc, rng)
        else:
            name, text, allowed, field = "original", json.dumps(doc), PLAN, None
        jobs.append((n, name, text, allowed, field, source, seed))
    print(f"soak: {args.count} problems from {len(docs)} files, {args.workers} workers, "
          f"kill after {args.timeout:g} s, work dir {os.path.relpath(args.work, ROOT)}", flush=True)
    results, began = [], time.monotonic()
    stop_at = began + args.deadline if args.deadline > 0 else float("inf")
    step, shown = max(1, args.count // 20), began

    def one(job):
        return run_one(job, args, args.timeout) if time.monotonic() < stop_at else None

    with ThreadPoolExecutor(args.workers) as pool:
        for r in pool.map(one, jobs):
            if r is None:
                continue
            results.append(r)
            done = len(results)
            if done % step == 0 or done == args.count or time.monotonic() - shown > 60:
                shown = time.monotonic()
                el = time.monotonic() - began
                codes = {c: sum(1 for x in results if x["code"] == c) for c in (0, 1, 2)}
                print(f"[{done:>6}/{args.count}] exit0 {codes[0]} exit1 {codes[1]} exit2 {codes[2]} "
                      f"other {done - sum(codes.values())} findings {sum(1 for x in results if x['problems'])} "
                      f"{done / el:.1f}/s eta {(args.count - done) * el / done:.0f} s", flush=True)
    report(results, time.monotonic() - began, args)
    return 1 if any(r["problems"] for r in results) else 0


def report(results, elapsed, args):
    by_code = {}
    for r in results:
        by_code[str(r["code"])] = by_code.get(str(r["code"]), 0) + 1
    if len(results) < args.count:
        print(f"\nstopped at the --deadline of {args.deadline:g} s: {len(results)} of {args.count} problems ran")
    print(f"\n{len(results)} plans in {elapsed:.0f} s; by exit code: "
          + ", ".join(f"{k}: {v}" for k, v in sorted(by_code.items())))
    names = sorted({r["name"] for r in results})
    print(f"\n{'input':<20} {'n':>6} {'exit 0':>7} {'exit 1':>7} {'exit 2':>7} {'other':>6} {'max s':>7} {'findings':>8}")
    for name in names:
        rs = [r for r in results if r["name"] == name]
        c = [sum(1 for r in rs if r["code"] == k) for k in (0, 1, 2)]
        print(f"{name:<20} {len(rs):>6} {c[0]:>7} {c[1]:>7} {c[2]:>7} {len(rs) - sum(c):>6} "
              f"{max(r['seconds'] for r in rs):>7.2f} {sum(1 for r in rs if r['problems']):>8}")
    slow = max(results, key=lambda r: r["seconds"])
    print(f"\nslowest: {slow['seconds']:.2f} s, {slow['source']} ({slow['name']}) --seed {slow['seed']}, exit {slow['code']}")
    planned = [r for r in results if r["code"] in (0, 1)]
    peak = max(results, key=lambda r: r["rss_kb"])
    print(f"peak RSS: {peak['rss_kb'] / 1024:.1f} MiB ({peak['source']}, {peak['name']}, exit {peak['code']})")
    if len(planned) >= 20:
        tenth = max(1, len(planned) // 10)
        first = statistics.median(r["rss_kb"] for r in planned[:tenth]) / 1024
        last = statistics.median(r["rss_kb"] for r in planned[-tenth:]) / 1024
        print(f"RSS of planning runs (median): first tenth {first:.1f} MiB, last tenth {last:.1f} MiB"
              f" ({'flat' if last <= first * 1.1 + 2 else 'GROWING'})")
    bad = [r for r in results if r["problems"]]
    print(f"findings: {len(bad)}" + (f" (inputs and stderr under {os.path.relpath(args.work, ROOT)}/findings)" if bad else ""))
    for r in bad[:20]:
        print(f"  #{r['n']} {r['source']} ({r['name']}) --seed {r['seed']}: {'; '.join(r['problems'])}")


if __name__ == "__main__":
    sys.exit(main())
