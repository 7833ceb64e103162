#!/usr/bin/env python3
"""Compares our trajectory durations with TOPP-RA (the `toppra` package) on the same paths.

For each timed plan (`NAME.timed.json` from `edmp-host plan SCENE --timed`, jerk-limited, and
`NAME.nojerk.json` from `edmp-host plan SCENE --timed --no-jerk-limit`), the plan's waypoints are turned
into the same uniform cubic B-spline (first and last waypoint tripled as control points; our
formula, re-implemented here in numpy), sampled densely (20 samples per span), and handed to
toppra: `SplineInterpolator` over the samples (by chord length), `JointVelocityConstraint` and
`JointAccelerationConstraint` at Franka's limits times the plan's scales, `TOPPRA` on a grid of
8 points per span (ours) and on toppra's own proposed grid. Prints the duration ratios
ours/toppra per plan, then their median and maximum. Plans timed on the polyline are skipped
(toppra would see a different path).

    python3 -m venv /tmp/toppra && /tmp/toppra/bin/pip install -r benchmarks/requirements-toppra.txt
    for s in examples/wall.json ...; do n=$(basename $s .json)
        edmp-host plan $s --timed -o /tmp/timed/$n.timed.json
        edmp-host plan $s --timed --no-jerk-limit -o /tmp/timed/$n.nojerk.json; done
    /tmp/toppra/bin/python benchmarks/toppra_compare.py /tmp/timed/*.timed.json
"""

import json
import os
import sys

import numpy as np
import toppra as ta
import toppra.algorithm as algo
import toppra.constraint as constraint

VELOCITY = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])
ACCELERATION = np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])
SAMPLES_PER_SPAN = 20
GRID_PER_SPAN = 8


def spline_samples(waypoints):
    """Our B-spline: control points W0 W0 W0 W1 ... W_{H-1} W_{H-1} W_{H-1}, one unit of u per span."""
    w = np.asarray(waypoints, dtype=np.float64)
    p = np.concatenate([w[:1], w[:1], w, w[-1:], w[-1:]])
    spans = len(p) - 3
    u = np.linspace(0.0, spans, spans * SAMPLES_PER_SPAN + 1)
    i = np.minimum(np.floor(u).astype(int), spans - 1)
    s = (u - i)[:, None]
    b0 = (1 - s) ** 3 / 6
    b1 = (3 * s**3 - 6 * s**2 + 4) / 6
    b2 = (-3 * s**3 + 3 * s**2 + 3 * s + 1) / 6
    b3 = s**3 / 6
    q = b0 * p[i] + b1 * p[i + 1] + b2 * p[i + 2] + b3 * p[i + 3]
    return u, q, spans


def toppra_duration(waypoints, velocity_scale, acceleration_scale, own_grid):
    u, q, spans = spline_samples(waypoints)
    # toppra's reachability fails ("not controllable") where dq/du vanishes, as it does at our
    # tripled ends; the same curve by chord length (time-optimal timing does not depend on the
    # parameterization) is well conditioned.
    chord = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(q, axis=0)).max(axis=1))])
    keep = np.concatenate([[True], np.diff(chord) > 1e-9])
    s, q = chord[keep], q[keep]
    path = ta.SplineInterpolator(s, q)
    v = VELOCITY * velocity_scale
    a = ACCELERATION * acceleration_scale
    pc_vel = constraint.JointVelocityConstraint(np.stack([-v, v], axis=1))
    pc_acc = constraint.JointAccelerationConstraint(np.stack([-a, a], axis=1))
    grid = np.interp(np.linspace(0.0, spans, spans * GRID_PER_SPAN + 1), u[keep], s) if own_grid else None
    if grid is not None:
        grid = np.unique(grid)
    instance = algo.TOPPRA([pc_vel, pc_acc], path, gridpoints=grid, parametrizer="ParametrizeConstAccel")
    traj = instance.compute_trajectory(0.0, 0.0)
    return float("nan") if traj is None else float(traj.duration)


def duration(plan):
    return plan["trajectory"]["points"][-1]["time_from_start"]


def main():
    files = sys.argv[1:]
    if not files:
        print(__doc__)
        return 2
    ta.setup_logging("WARNING")
    rows = []
    for f in files:
        plan = json.load(open(f))
        tr = plan["trajectory"]
        if tr.get("shape", "spline") != "spline":
            print(f"{os.path.basename(f)}: timed on the {tr['shape']}, skipped")
            continue
        nojerk_file = f.replace(".timed.json", ".nojerk.json")
        ours_jerk = duration(plan) if tr["limits"]["jerk_limited"] else float("nan")
        ours_free = duration(json.load(open(nojerk_file))) if os.path.exists(nojerk_file) else float("nan")
        lim = tr["limits"]
        t_grid = toppra_duration(plan["waypoints"], lim["velocity_scale"], lim["acceleration_scale"], True)
        t_auto = toppra_duration(plan["waypoints"], lim["velocity_scale"], lim["acceleration_scale"], False)
        rows.append((os.path.basename(f).replace(".timed.json", ""), t_grid, t_auto, ours_free, ours_jerk))
    print(f"{'plan':24} {'toppra 8/span':>13} {'toppra auto':>11} {'ours':>8} {'ours+jerk':>9} "
          f"{'ours/toppra':>11} {'+jerk/toppra':>12}")
    r_free, r_jerk = [], []
    for name, tg, ta_, of, oj in rows:
        r_free.append(of / tg)
        r_jerk.append(oj / tg)
        print(f"{name:24} {tg:13.4f} {ta_:11.4f} {of:8.4f} {oj:9.4f} {of / tg:11.4f} {oj / tg:12.4f}")
    if rows:
        print(f"ours/toppra (no jerk): median {np.nanmedian(r_free):.4f}, max {np.nanmax(r_free):.4f}; "
              f"with jerk: median {np.nanmedian(r_jerk):.4f}, max {np.nanmax(r_jerk):.4f} ({len(rows)} plans)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
