"""Writes the grasp table: a can on a table, the goal a horizontal grasp around it with the
fingers open to 0.04 m (`"gripper": {"finger": 0.04}`, docs/formats.md).

Each problem: a table top (upper face at height `top`), a can (a cylinder of radius r and
height h standing on it) and, in some, a second can beside it; the start is the Panda's ready
pose; the goal is a TCP (`panda_grasptarget`) pose at the can's centre, the hand's z (the
approach) horizontal, pointing from the base towards the can turned by `yaw`, the fingers
(the hand's y) horizontal so they straddle the can: with the default opening (0.025 m, inner
faces 2.5 cm from the TCP) they would cut into a can of radius 3 cm, at 0.04 m they clear it
by about 1 cm on each side. Deterministic: the numbers below are the table. (The yaw offsets
avoid 0-5 degrees: there the core IK finds no solution from its starts, even with no obstacles.)

Usage (from the repository root):
    python3 benchmarks/grasp/generate.py               # rewrites benchmarks/grasp/NNN.json
    python3 benchmarks/grasp/generate.py --example     # also examples/grasp-can.json (problem 0)
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]
READY = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
FINGER = 0.04
IDENTITY = [1.0, 0.0, 0.0, 0.0]

# (can x, can y, radius, height, table top, yaw offset of the approach (deg), second can (dx, dy) or None)
TABLE = [
    (0.55, 0.00, 0.030, 0.14, 0.20, -10.0, None),
    (0.50, 0.15, 0.030, 0.14, 0.20, 10.0, None),
    (0.50, -0.15, 0.030, 0.14, 0.20, -5.0, None),
    (0.60, 0.10, 0.028, 0.12, 0.25, 15.0, None),
    (0.45, -0.05, 0.032, 0.16, 0.15, -10.0, None),
    (0.60, -0.20, 0.030, 0.14, 0.20, 20.0, None),
    (0.55, 0.05, 0.030, 0.14, 0.20, -10.0, (0.0, 0.15)),
    (0.50, -0.10, 0.030, 0.14, 0.20, 10.0, (0.05, -0.14)),
    (0.65, 0.00, 0.026, 0.12, 0.30, -15.0, (0.10, 0.12)),
    (0.40, 0.20, 0.030, 0.14, 0.20, -20.0, None),
]


def quaternion_wxyz(m: list[list[float]]) -> list[float]:
    """The unit quaternion [w, x, y, z] of a rotation matrix (rows), w >= 0."""
    t = m[0][0] + m[1][1] + m[2][2]
    if t > 0:
        s = math.sqrt(t + 1.0) * 2
        q = [0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s]
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2
        q = [(m[2][1] - m[1][2]) / s, 0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s]
    elif m[1][1] > m[2][2]:
        s = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2
        q = [(m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s]
    else:
        s = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2
        q = [(m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s]
    if q[0] < 0:
        q = [-v for v in q]
    return [round(v, 9) for v in q]


def grasp_quaternion(psi: float) -> list[float]:
    """Hand z (approach) = (cos psi, sin psi, 0), hand y (fingers) = (-sin psi, cos psi, 0),
    hand x = y x z = (0, 0, -1): columns of the TCP's rotation."""
    z = [math.cos(psi), math.sin(psi), 0.0]
    y = [-math.sin(psi), math.cos(psi), 0.0]
    x = [y[1] * z[2] - y[2] * z[1], y[2] * z[0] - y[0] * z[2], y[0] * z[1] - y[1] * z[0]]
    return quaternion_wxyz([[x[r], y[r], z[r]] for r in range(3)])


def cylinder(center: list[float], radius: float, height: float) -> dict:
    return {"type": "cylinder", "center": [round(c, 6) for c in center], "radius": radius, "height": height, "quaternion": IDENTITY}


def problem(n: int) -> dict:
    x, y, r, h, top, yaw, other = TABLE[n]
    obstacles = [
        {"type": "cuboid", "center": [0.6, 0.0, round(top - 0.01, 6)], "dims": [0.6, 1.0, 0.02], "quaternion": IDENTITY},
        cylinder([x, y, top + h / 2], r, h),
    ]
    if other is not None:
        obstacles.append(cylinder([x + other[0], y + other[1], top + h / 2], r, h))
    psi = math.atan2(y, x) + math.radians(yaw)
    return {
        "format": "edmp-scene/1",
        "obstacles": obstacles,
        "gripper": {"finger": FINGER},
        "start": READY,
        "goal": {"pose": {"position": [x, y, round(top + h / 2, 6)], "quaternion": grasp_quaternion(psi)}},
        "meta": {
            "family": "grasp",
            "seed": n,
            "note": "TCP at the can's centre, approach horizontal, fingers open to 0.04 m around the can (benchmarks/grasp/generate.py)",
        },
    }


def dumps(doc: dict) -> str:
    """As the examples are laid out: one top-level field (and one obstacle) per line."""
    lines = []
    for key, value in doc.items():
        if key == "obstacles":
            items = ",\n".join(f"    {json.dumps(o)}" for o in value)
            lines.append(f'  "obstacles": [\n{items}\n  ]')
        else:
            lines.append(f"  {json.dumps(key)}: {json.dumps(value)}")
    return "{\n" + ",\n".join(lines) + "\n}\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--example", action="store_true", help="also write examples/grasp-can.json (problem 000)")
    args = parser.parse_args()
    for n in range(len(TABLE)):
        (HERE / f"{n:03d}.json").write_text(dumps(problem(n)))
    if args.example:
        doc = problem(0)
        doc.pop("meta")
        (ROOT / "examples" / "grasp-can.json").write_text(dumps(doc))


if __name__ == "__main__":
    main()
