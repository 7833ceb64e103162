#!/usr/bin/env python3
"""Independent check of timed plans: `edmp-plan/1` files that carry a `trajectory` field.

For every plan, at the trajectory's own sample rate (numpy only, none of our code):
- times start at 0 and strictly increase;
- the first point is the first waypoint, the last the last one, both at rest (zero velocity;
  zero acceleration at the end, and at the start when `jerk_limited`);
- every position lies within the stated `trajectory.tolerance` (default 1e-5: the polyline)
  of the waypoints' polyline, in max-norm over joints (exact distance to each segment by
  ternary search on its convex distance function);
- no joint exceeds Franka's velocity or acceleration limits times the scales, as reported or as
  finite differences (velocity from positions, acceleration from velocities), nor the jerk limit
  (times `acceleration_scale`) as the finite difference of consecutive accelerations when
  `jerk_limited`. Finite differences are allowed the f32 rounding of their inputs.

Prints one row per plan and exits 1 on any violation.

    python3 benchmarks/check_timed.py PLAN.json [PLAN.json ...]
"""

import json
import os
import sys

import numpy as np

VELOCITY = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])
ACCELERATION = np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])
JERK = np.array([7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0])
LIMIT_SLACK = 1.0 + 1e-4
F32_EPS = float(np.finfo(np.float32).eps)


def distance_to_polyline(points, waypoints):
    """Max-norm distance from each row of `points` to the polyline through `waypoints`."""
    a = waypoints[:-1][None, :, :]  # 1 x S x 7
    d = (waypoints[1:] - waypoints[:-1])[None, :, :]
    p = points[:, None, :]  # P x 1 x 7
    lo = np.zeros(points.shape[:1] + (a.shape[1],))
    hi = np.ones_like(lo)

    def f(t):
        return np.abs(p - (a + t[..., None] * d)).max(axis=-1)

    for _ in range(60):
        m1, m2 = lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0
        left = f(m1) <= f(m2)
        hi = np.where(left, m2, hi)
        lo = np.where(left, lo, m1)
    return f(0.5 * (lo + hi)).min(axis=1)


def noise(x):
    """Rounding of one f32 value."""
    return np.maximum(np.abs(x), 1.0) * F32_EPS


def check(path):
    plan = json.load(open(path))
    problems = []
    w = np.array(plan["waypoints"], dtype=np.float64)
    tr = plan.get("trajectory")
    if tr is None:
        return {"plan": path, "problems": ["no trajectory field"]}
    lim = tr["limits"]
    vs, acs, jerk_limited = lim["velocity_scale"], lim["acceleration_scale"], lim["jerk_limited"]
    if not (0 < vs <= 1 and 0 < acs <= 1):
        problems.append(f"scales {vs}, {acs} outside (0, 1]")
    vl, al, jl = VELOCITY * vs, ACCELERATION * acs, JERK * acs
    tol = float(tr.get("tolerance", 1e-5))
    pts = tr["points"]
    t = np.array([p["time_from_start"] for p in pts], dtype=np.float64)
    q = np.array([p["positions"] for p in pts], dtype=np.float64)
    v = np.array([p["velocities"] for p in pts], dtype=np.float64)
    a = np.array([p["accelerations"] for p in pts], dtype=np.float64)
    if len(tr.get("joint_names", [])) != 7:
        problems.append("joint_names is not 7 names")
    if t[0] != 0.0:
        problems.append(f"first time {t[0]} != 0")
    if np.any(np.diff(t) <= 0):
        problems.append("times do not strictly increase")
    if np.abs(q[0] - w[0]).max() > 1e-6 or np.abs(q[-1] - w[-1]).max() > 1e-6:
        problems.append("does not start at the first waypoint and end at the last")
    if np.abs(v[0]).max() > 1e-9 or np.abs(v[-1]).max() > 1e-9 or np.abs(a[-1]).max() > 1e-9:
        problems.append("does not start and end at rest")
    if jerk_limited and np.abs(a[0]).max() > 1e-9:
        problems.append("jerk-limited but starts with an acceleration")
    dev = distance_to_polyline(q, w).max()
    if dev > tol + 1e-6:
        problems.append(f"position {dev:.3g} rad from the polyline > tolerance {tol:.3g}")
    h = np.diff(t)[:, None]
    # Time rounding moves a sample by ~ulp(t) * speed.
    tn = noise(t)[:, None]
    qn = noise(q) + 2.0 * np.abs(v) * tn + 1e-6
    vn = noise(v) + 2.0 * np.abs(a) * tn
    an = noise(a)
    ratios = {
        "v": np.abs(v) / vl,
        "a": np.abs(a) / al,
        "v_fd": (np.abs(np.diff(q, axis=0)) - qn[1:] - qn[:-1]) / h / vl,
        "a_fd": (np.abs(np.diff(v, axis=0)) - vn[1:] - vn[:-1]) / h / al,
    }
    if jerk_limited:
        ratios["j_fd"] = (np.abs(np.diff(a, axis=0)) - an[1:] - an[:-1]) / h / jl
    worst = {k: float(r.max()) for k, r in ratios.items()}
    for k, r in worst.items():
        if r > LIMIT_SLACK:
            problems.append(f"{k} at {r:.4f} of its limit")
    return {
        "plan": path,
        "shape": tr.get("shape", "?"),
        "jerk": jerk_limited,
        "points": len(pts),
        "rate": (len(pts) - 1) / t[-1] if t[-1] > 0 else 0.0,
        "duration": t[-1],
        "tolerance": tol,
        "deviation": dev,
        "v": max(worst["v"], worst["v_fd"]),
        "a": max(worst["a"], worst["a_fd"]),
        "j": worst.get("j_fd", float("nan")),
        "problems": problems,
    }


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    rows = [check(p) for p in sys.argv[1:]]
    print(f"{'plan':40} {'shape':8} {'jerk':5} {'points':>6} {'Hz':>6} {'duration':>9} {'tol':>8} "
          f"{'dev':>8} {'v/lim':>6} {'a/lim':>6} {'j/lim':>6}  result")
    bad = 0
    for r in rows:
        if "shape" not in r:
            print(f"{r['plan']:40} FAIL: {'; '.join(r['problems'])}")
            bad += 1
            continue
        ok = not r["problems"]
        bad += not ok
        print(f"{os.path.basename(r['plan'])[-40:]:40} {r['shape']:8} {str(r['jerk']):5} {r['points']:6d} {r['rate']:6.0f} "
              f"{r['duration']:9.4f} {r['tolerance']:8.2e} {r['deviation']:8.2e} {r['v']:6.3f} {r['a']:6.3f} "
              f"{r['j']:6.3f}  {'ok' if ok else 'FAIL: ' + '; '.join(r['problems'])}")
    print(f"{len(rows) - bad} of {len(rows)} plans pass")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
