#!/usr/bin/env python3
"""Why a plan on a depth camera's cloud touched the true geometry: was the spot ever seen?

For every false success of the depth set (`benchmarks/cells.py --sets depth`; the verdicts of
`benchmarks/judge.py --json`), finds where the robot touches the true geometry (the judge's
first contact: PyBullet's `getClosestPoints` between that link and that true obstacle, the
point on the obstacle), then asks each of the scene's cameras (`meta.cameras`, the field of
view and range of `meta.camera`) whether that spot was in view and in its line of sight, with
the robot standing at `start` as it stood when the cameras looked. A spot no camera had in
sight is **unseen** (occluded, or outside every view): the cloud could not hold it. A spot some
camera saw is **seen**: the cloud lost it to the depth noise, the 5 mm voxels or a grazing view
(the table gives the angle between the line of sight and the surface). Prints one line per
false success and the counts.

    python3 benchmarks/judge.py --problems bench-out/cells-depth/depth \
        --results RUN/results.jsonl --json RUN/verdicts.json
    python3 benchmarks/occlusion.py --problems bench-out/cells-depth/depth --results RUN/results.jsonl \
        --verdicts RUN/verdicts.json
"""

import argparse
import json
import math
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import judge  # noqa: E402

p = judge._import_pybullet()

# How far short of the spot a ray may stop and still count as reaching it (m): the spot lies on
# the true surface, where the ray itself ends.
REACH = 0.002


def contact_spot(robot: judge.Robot, scene: dict, plan: dict, contact: dict) -> np.ndarray | None:
    """The point on the true obstacle where the judge's first contact lies."""
    w = np.asarray(plan["waypoints"], dtype=np.float64)
    seg, step = contact["segment"], contact["step"]
    along = judge.segment_states(w[seg], w[seg + 1]) if seg + 1 < len(w) else [w[seg]]
    judge.set_state(robot, along[step])
    truth = judge.judged_obstacles(scene)[contact["obstacle"]]
    body = judge.spawn(robot, truth)
    try:
        link = next(k for k, name in robot.names.items() if name == contact["link"])
        hits = p.getClosestPoints(robot.body, body, 0.0, linkIndexA=link, physicsClientId=robot.client)
        if not hits:
            return None
        deepest = min(hits, key=lambda h: h[8])
        return np.asarray(deepest[6])
    finally:
        p.removeBody(body, physicsClientId=robot.client)


def in_view(camera: dict, setup: dict, spot: np.ndarray) -> bool:
    """Whether `spot` lies in the camera's frustum and range."""
    eye, target = np.asarray(camera["eye"]), np.asarray(camera["target"])
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    d = spot - eye
    depth = float(d @ forward)
    if not setup["near"] < depth < setup["far"] or np.linalg.norm(d) > setup["max_range"]:
        return False
    half_v = math.radians(setup["fov_deg"]) / 2
    half_h = math.atan(math.tan(half_v) * setup["width"] / setup["height"])
    return abs(math.atan2(float(d @ up), depth)) <= half_v and abs(math.atan2(float(d @ right), depth)) <= half_h


def sight(robot: judge.Robot, scene: dict, spot: np.ndarray) -> list[tuple[str, float]]:
    """(camera, angle between its line of sight and the surface, degrees) for every camera that
    had `spot` in view and in sight, the true scene and the robot at `start` in the way."""
    judge.set_state(robot, np.asarray(scene["start"], dtype=np.float64))
    bodies = [judge.spawn(robot, o) for o in judge.judged_obstacles(scene)]
    seen = []
    try:
        for camera in scene["meta"]["cameras"]:
            if not in_view(camera, scene["meta"]["camera"], spot):
                continue
            eye = np.asarray(camera["eye"])
            ray = spot - eye
            past = spot + ray / np.linalg.norm(ray) * REACH
            hit = p.rayTest(eye.tolist(), past.tolist(), physicsClientId=robot.client)[0]
            if hit[0] < 0:
                continue
            if np.linalg.norm(np.asarray(hit[3]) - spot) <= REACH:
                normal = np.asarray(hit[4])
                cos = abs(float(normal @ ray)) / (np.linalg.norm(normal) * np.linalg.norm(ray) + 1e-12)
                seen.append((camera["name"], 90.0 - math.degrees(math.acos(min(1.0, cos)))))
    finally:
        for b in bodies:
            p.removeBody(b, physicsClientId=robot.client)
    return seen


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--problems", type=pathlib.Path, required=True, help="the depth set's folder (family/NNN.json)")
    ap.add_argument("--results", type=pathlib.Path, required=True, help="the plans: `edmp-host bench --out`'s results.jsonl")
    ap.add_argument("--verdicts", type=pathlib.Path, required=True, help="benchmarks/judge.py --json's output for those plans")
    args = ap.parse_args()
    verdicts = json.loads(args.verdicts.read_text())["verdicts"]
    plans = {}
    for line in args.results.read_text().splitlines():
        if line.strip():
            row = json.loads(line)
            plans[row["problem"]] = {"waypoints": row["waypoints"]}
    false = [v for v in verdicts if v["status"] == "success" and not v["solved"] and v.get("first_contact")]
    robot = judge.connect("panda")
    unseen = seen = 0
    for v in false:
        path = args.problems / v["problem"]
        scene = json.loads(path.read_text())
        plan = plans[v["problem"]]
        robot.finger = judge.finger_opening(scene)
        c = v["first_contact"]
        spot = contact_spot(robot, scene, plan, c)
        if spot is None:
            print(f"{v['problem']}: no contact point found")
            continue
        cams = sight(robot, scene, spot)
        where = "seen by " + ", ".join(f"{n} at {a:.0f} deg" for n, a in cams) if cams else "unseen"
        if cams:
            seen += 1
        else:
            unseen += 1
        print(f"{v['problem']}: {c['link']} {-c['distance'] * 1000:.2f} mm into true obstacle {c['obstacle']} at {np.round(spot, 3).tolist()}: {where}")
    print(f"\n{len(false)} false successes: {unseen} at spots no camera saw, {seen} at spots a camera saw")
    return 0


if __name__ == "__main__":
    sys.exit(main())
