"""Records the near-surface table: problems whose start or goal lies 0.05-2 mm from a surface
by PyBullet's own measure, which docs/formats.md calls valid ends and which must plan.

For each of three settings (a top-down grasp over a table, a forward reach into a shelf
pocket, a hand in front of a drawer's front panel) and each distance d, the surface nearest
the robot is moved (bisection on one coordinate, PyBullet 3.2.7's `getClosestPoints` through
the judge's own robot and primitives) until the smallest distance between any robot body and
the scene is d (to 1 µm). Half the problems end at the near-surface configuration, half start
there; the other end is the Panda's ready pose. Written as `edmp-scene/1` with a `meta` field
(`pybullet_distance`, the end that is near) to `benchmarks/near_surface/<setting>/NNN.json`.

Usage (from the repository root):
    python3 -m pip install -r benchmarks/requirements.txt
    python3 benchmarks/near_surface.py --out benchmarks/near_surface
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
from typing import Any

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import judge  # noqa: E402  (the judge's robot, primitives and contact rule)

p = judge.p
READY = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
DISTANCES_MM = [0.05, 0.1, 0.3, 0.5, 1.0, 2.0]
IDENTITY = [1.0, 0.0, 0.0, 0.0]


def cuboid(center: list[float], dims: list[float]) -> dict[str, Any]:
    return {"type": "cuboid", "center": [float(c) for c in center], "dims": dims, "quaternion": IDENTITY}


def settings() -> dict[str, dict[str, Any]]:
    """Each setting: the near configuration, the fixed obstacles, and the moving surface as a
    function of one coordinate s (which way s moves the surface away from the robot)."""
    down = [0.0, 0.35, 0.0, -2.25, 0.0, 2.6, 0.785]  # hand pointing down over the table
    forward = [0.0, 0.2, 0.0, -1.8, 0.0, 3.57, 0.785]  # hand level, reaching forward
    return {
        "table": {
            "q": down,
            "fixed": [],
            # A table top whose upper face is at height s.
            "surface": lambda s: cuboid([0.6, 0.0, s - 0.02], [0.7, 1.2, 0.04]),
            "away": -1.0,
            "bracket": (-0.2, 0.5),
        },
        "shelf": {
            "q": forward,
            # The shelf's top board and back wall; the board under the hand moves.
            "fixed": [cuboid([0.75, 0.0, 0.78], [0.5, 0.8, 0.02]), cuboid([1.01, 0.0, 0.5], [0.02, 0.8, 0.6])],
            "surface": lambda s: cuboid([0.75, 0.0, s - 0.01], [0.5, 0.8, 0.02]),
            "away": -1.0,
            "bracket": (0.3, 0.7),
        },
        "drawer_front": {
            "q": forward,
            "fixed": [],
            # A dresser's front panel whose face towards the robot is at x = s.
            "surface": lambda s: cuboid([s + 0.01, 0.0, 0.55], [0.02, 0.6, 0.5]),
            "away": 1.0,
            "bracket": (0.4, 1.2),
        },
    }


def min_distance(robot: judge.Robot, bodies: list[int], within: float = 0.1) -> float:
    best = within
    for b in bodies:
        for link in robot.moving:
            d = judge.closest(robot.client, robot.body, b, within, link, None)
            if d is not None:
                best = min(best, d)
    return best


def place_surface(robot: judge.Robot, body: int, o: dict[str, Any]) -> None:
    p.resetBasePositionAndOrientation(body, o["center"], judge.xyzw(o["quaternion"]), physicsClientId=robot.client)
    p.performCollisionDetection(physicsClientId=robot.client)


def solve(robot: judge.Robot, setting: dict[str, Any], target: float) -> float:
    """The coordinate s at which the moving surface is `target` metres from the robot."""
    surface = setting["surface"]
    body = judge.spawn(robot, surface(setting["bracket"][0]))
    judge.set_state(robot, np.array(setting["q"]))

    def gap(s: float) -> float:
        place_surface(robot, body, surface(s))
        return min_distance(robot, [body])

    # Far end of the bracket: the surface well clear of the robot; near end: in contact.
    lo, hi = setting["bracket"]
    far, near = (lo, hi) if setting["away"] < 0 else (hi, lo)
    # Walk from the far end towards the robot until the gap falls below the target.
    s = far
    step = (near - far) / 200
    while gap(s) > target and abs(s - far) < abs(near - far):
        s += step
    a, b = s - step, s  # gap(a) > target >= gap(b)
    for _ in range(60):
        m = 0.5 * (a + b)
        if gap(m) > target:
            a = m
        else:
            b = m
    p.removeBody(body, physicsClientId=robot.client)
    return a


def verify(robot: judge.Robot, scene: dict[str, Any]) -> tuple[float, bool]:
    """PyBullet's smallest robot-obstacle distance at the near end, and whether the judge's
    full rule (self-collision included) finds both ends free."""
    bodies = [judge.spawn(robot, o) for o in scene["obstacles"]]
    pairs = judge.queries(robot, bodies, None)
    ends_free = True
    for q in (scene["start"], scene["goal"]["joints"]):
        if judge.contact_at(robot, np.array(q), pairs, None, None) is not None:
            ends_free = False
    near = scene["meta"]["near_end"]
    judge.set_state(robot, np.array(scene["start"] if near == "start" else scene["goal"]["joints"]))
    p.performCollisionDetection(physicsClientId=robot.client)
    d = min_distance(robot, bodies)
    for b in bodies:
        p.removeBody(b, physicsClientId=robot.client)
    return d, ends_free


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("benchmarks/near_surface"))
    args = ap.parse_args(argv)
    robot = judge.connect()
    for name, setting in settings().items():
        folder = args.out / name
        folder.mkdir(parents=True, exist_ok=True)
        index = 0
        for mm in DISTANCES_MM:
            s = solve(robot, setting, mm / 1000)
            for near in ("goal", "start"):
                far_q, near_q = READY, setting["q"]
                start, goal = (far_q, near_q) if near == "goal" else (near_q, far_q)
                scene = {
                    "format": "edmp-scene/1",
                    "obstacles": [setting["surface"](s), *setting["fixed"]],
                    "start": start,
                    "goal": {"joints": goal},
                    "meta": {"family": f"near_surface_{name}", "near_end": near, "target_mm": mm},
                }
                d, ends_free = verify(robot, scene)
                if not ends_free or abs(d - mm / 1000) > 2e-6:
                    print(f"{name} {mm} mm ({near}): PyBullet distance {d * 1000:.4f} mm, ends free: {ends_free}", file=sys.stderr)
                    return 1
                scene["meta"]["pybullet_distance"] = d
                (folder / f"{index:03}.json").write_text(json.dumps(scene, indent=1) + "\n")
                print(f"{name}/{index:03}.json: {near} {d * 1000:.4f} mm from the surface (PyBullet)")
                index += 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
