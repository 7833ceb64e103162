"""The judge must be able to fail: plans broken on purpose, each caught by the right rule.

Built from a committed problem and a plan `edmp-host plan` made for it (copied into
`benchmarks/judge/` so the suite can change without breaking these tests):

    python3 -m pytest benchmarks/test_judge.py -q
"""

from __future__ import annotations

import copy
import json
import math
import pathlib
import sys

import numpy as np
import pytest

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import judge  # noqa: E402

SCENE = json.loads((HERE / "judge" / "cubby_003.json").read_text())
PLAN = json.loads((HERE / "judge" / "cubby_003.plan.json").read_text())
READY = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
# Arm stretched straight out in front at shoulder height: through the cubby's back wall.
STRETCHED = [0.0, 1.5, 0.0, -0.1, 0.0, 1.6, 0.785]
# From tests/fixtures/collision_pybullet.json: link6 folded into link0 (PyBullet: -0.13 m).
FOLDED = [2.05687895271, 1.336647363135, 0.235433259043, -2.891650307571, -2.152632174619, 0.483702902153, -0.229857950933]


@pytest.fixture(scope="module")
def robot() -> judge.Robot:
    return judge.connect()


def waypoints() -> list[list[float]]:
    return copy.deepcopy(PLAN["waypoints"])


def constant(q: list[float]) -> list[list[float]]:
    return [list(q) for _ in range(judge.HORIZON)]


def empty_scene(start: list[float], goal: list[float], obstacles: list[dict] | None = None) -> dict:
    return {"format": "edmp-scene/1", "obstacles": obstacles or [], "start": start, "goal": {"joints": goal}}


def test_the_planners_plan_is_solved(robot):
    assert PLAN["status"] == "success"
    v = judge.judge(robot, SCENE, PLAN)
    assert v["solved"], v
    assert v["failed"] == []
    assert v["states_checked"] > judge.HORIZON  # interpolated states were checked too


def test_a_waypoint_moved_into_an_obstacle_is_contact(robot):
    w = waypoints()
    w[25] = STRETCHED
    v = judge.judge(robot, SCENE, {"waypoints": w})
    assert not v["solved"]
    assert v["failed"] == ["contact"]
    c = v["first_contact"]
    assert c["kind"] == "obstacle" and c["distance"] <= 0.0
    assert 0 <= c["obstacle"] < len(SCENE["obstacles"])
    assert c["segment"] in (24, 25)
    assert c["link"].startswith("panda_")
    assert judge.p.getNumBodies(physicsClientId=robot.client) == 1  # the scene's bodies are gone


def test_contact_between_free_waypoints_is_found_by_interpolation(robot):
    # Joint 1 swings 1.6 rad between waypoints 24 and 25; a small sphere sits where the hand
    # passes half way, clear of the arm at either waypoint.
    q0 = list(READY)
    q1 = list(READY)
    q1[0] += 1.6
    middle = list(READY)
    middle[0] += 0.8
    judge.set_state(robot, np.array(middle))
    hand_pos, hand_quat = judge.link_pose(robot, robot.hand)
    center, _ = judge.p.multiplyTransforms(hand_pos, hand_quat, [0, 0, 0.05], [0, 0, 0, 1])
    sphere = {"type": "sphere", "center": list(center), "radius": 0.02}
    scene = empty_scene(q0, q1, [sphere])
    w = [q0] * 25 + [q1] * 25
    for q in (q0, q1):
        assert "contact" not in judge.judge(robot, scene, {"waypoints": constant(q)})["failed"]
    v = judge.judge(robot, scene, {"waypoints": w})
    assert v["failed"] == ["contact"]
    c = v["first_contact"]
    assert c["segment"] == 24 and 0 < c["step"] < c["steps"] == 160
    assert c["obstacle"] == 0


def test_self_contact_is_caught(robot):
    scene = empty_scene(FOLDED, FOLDED)
    v = judge.judge(robot, scene, {"waypoints": constant(FOLDED)})
    assert v["failed"] == ["contact"]
    c = v["first_contact"]
    assert c["kind"] == "self" and {c["link"], c["other"]} & {"panda_link0"}
    assert (c["segment"], c["step"]) == (0, 0)


def test_ready_pose_in_an_empty_scene_is_solved(robot):
    v = judge.judge(robot, empty_scene(READY, READY), {"waypoints": constant(READY)})
    assert v["solved"], v
    assert v["states_checked"] == judge.HORIZON


def test_a_waypoint_outside_the_limits_is_caught(robot):
    w = waypoints()
    w[10][3] = -0.0698 + 2e-5  # joint 4's upper limit is -0.0698
    v = judge.judge(robot, SCENE, {"waypoints": w})
    assert "limits" in v["failed"]
    assert v["limit_violation"]["waypoint"] == 10 and v["limit_violation"]["joint"] == 4


def test_the_limit_tolerance_is_1e5(robot):
    w = waypoints()
    w[10][6] = 2.8973 + 5e-6
    v = judge.judge(robot, SCENE, {"waypoints": w})
    assert "limits" not in v["failed"]


def test_a_wrong_end_is_caught(robot):
    w = waypoints()
    w[-1][0] += 1e-3
    v = judge.judge(robot, SCENE, {"waypoints": w})
    assert "goal" in v["failed"] and v["goal_error_rad"] == pytest.approx(1e-3)
    w = waypoints()
    w[-1][0] += 5e-5
    assert "goal" not in judge.judge(robot, SCENE, {"waypoints": w})["failed"]


def test_a_wrong_start_is_caught(robot):
    w = waypoints()
    w[0][2] -= 2e-4
    v = judge.judge(robot, SCENE, {"waypoints": w})
    assert "start" in v["failed"]


def pose_scene(offset_m: float = 0.0, turn_deg: float = 0.0) -> dict:
    # The suite records the TCP pose of the goal configuration (computed by the project's own
    # FK): the judge's PyBullet FK must agree within the tolerance.
    scene = copy.deepcopy(SCENE)
    pose = copy.deepcopy(scene["meta"]["goal_pose"])
    pose["position"][2] += offset_m
    w, x, y, z = pose["quaternion"]
    half = math.radians(turn_deg) / 2  # a turn about the world z axis, applied on the left
    c, s = math.cos(half), math.sin(half)
    pose["quaternion"] = [c * w - s * z, c * x - s * y, c * y + s * x, c * z + s * w]
    scene["goal"] = {"pose": pose}
    return scene


def test_pose_goals(robot):
    v = judge.judge(robot, pose_scene(), PLAN)
    assert v["solved"], v
    assert v["goal_position_error_m"] < 1e-4 and v["goal_angle_error_deg"] < 0.1
    assert judge.judge(robot, pose_scene(offset_m=0.004), PLAN)["solved"]
    assert judge.judge(robot, pose_scene(offset_m=0.006), PLAN)["failed"] == ["goal"]
    assert judge.judge(robot, pose_scene(turn_deg=4.0), PLAN)["solved"]
    v = judge.judge(robot, pose_scene(turn_deg=6.0), PLAN)
    assert v["failed"] == ["goal"] and v["goal_angle_error_deg"] == pytest.approx(6.0, abs=1e-3)


def test_the_held_object_moves_with_the_hand_and_counts(robot):
    # A 20 cm rod held along the hand's z, its far end 45 cm from the hand frame; a small sphere
    # where that end is at the ready pose touches only the rod.
    rod = {"type": "cylinder", "center": [0, 0, 0.35], "radius": 0.01, "height": 0.2, "quaternion": [1, 0, 0, 0]}
    judge.set_state(robot, np.array(READY))
    hand_pos, hand_quat = judge.link_pose(robot, robot.hand)
    tip, _ = judge.p.multiplyTransforms(hand_pos, hand_quat, [0, 0, 0.45], [0, 0, 0, 1])
    sphere = {"type": "sphere", "center": list(tip), "radius": 0.01}
    scene = empty_scene(READY, READY, [sphere])
    assert judge.judge(robot, scene, {"waypoints": constant(READY)})["solved"]
    v = judge.judge(robot, scene | {"held_object": rod}, {"waypoints": constant(READY)})
    assert v["failed"] == ["contact"]
    assert v["first_contact"]["link"] == judge.HELD and v["first_contact"]["obstacle"] == 0
    # Elsewhere on the plan the rod is far from the sphere: moving the arm moves the rod.
    away = list(READY)
    away[0] += 1.0
    moved = empty_scene(away, away, [sphere]) | {"held_object": rod}
    assert judge.judge(robot, moved, {"waypoints": constant(away)})["solved"]


def test_the_held_object_against_the_arm_is_self_contact(robot):
    # At this pose a 40 cm rod held along the hand's z reaches back into link2 (PyBullet:
    # -5.8 cm); a short stub in the same place touches nothing, the arm alone is free.
    q = [0.843, 1.361, 1.166, -1.762, 0.093, 0.353, -1.492]
    rod = {"type": "cylinder", "center": [0, 0, 0.3], "radius": 0.02, "height": 0.4, "quaternion": [1, 0, 0, 0]}
    stub = rod | {"center": [0, 0, 0.11], "height": 0.02}
    scene = empty_scene(q, q)
    assert judge.judge(robot, scene, {"waypoints": constant(q)})["solved"]
    assert judge.judge(robot, scene | {"held_object": stub}, {"waypoints": constant(q)})["solved"]
    v = judge.judge(robot, scene | {"held_object": rod}, {"waypoints": constant(q)})
    assert v["failed"] == ["contact"]
    c = v["first_contact"]
    assert c["kind"] == "self" and c["link"] == judge.HELD and c["other"] == "panda_link2"


def test_malformed_plans_are_not_solved(robot):
    assert judge.judge(robot, SCENE, {"waypoints": waypoints()[:49]})["failed"] == ["malformed"]
    assert judge.judge(robot, SCENE, {"waypoints": None})["failed"] == ["malformed"]
    assert judge.judge(robot, SCENE, {"waypoints": []})["detail"] == "no waypoints"
    w = waypoints()
    w[3][3] = float("nan")
    assert judge.judge(robot, SCENE, {"waypoints": w})["failed"] == ["malformed"]


def write(path: pathlib.Path, value: object) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(value))


def test_command_line_flags_a_false_success(tmp_path):
    problems, plans = tmp_path / "problems", tmp_path / "plans"
    write(problems / "cubby" / "003.json", SCENE)
    write(problems / "cubby" / "004.json", SCENE)
    write(plans / "cubby" / "003.json", PLAN)
    bad = copy.deepcopy(PLAN)
    bad["waypoints"][25] = STRETCHED
    write(plans / "cubby" / "004.json", bad)  # says "success", is in contact
    out = tmp_path / "verdicts.json"
    code = judge.main(["--problems", str(problems), "--plans", str(plans), "--json", str(out), "--jobs", "1", "--no-progress"])
    assert code == 1
    verdicts = {v["problem"]: v for v in json.loads(out.read_text())["verdicts"]}
    assert verdicts["cubby/003.json"]["solved"] and not verdicts["cubby/004.json"]["solved"]
    assert verdicts["cubby/004.json"]["first_contact"]["kind"] == "obstacle"
    # Without the false success: exit 0.
    (plans / "cubby" / "004.json").unlink()
    assert judge.main(["--problems", str(problems), "--plans", str(plans), "--jobs", "1", "--no-progress"]) == 0


def test_jsonl_results_and_false_failures(tmp_path, capsys):
    problems = tmp_path / "problems"
    write(problems / "cubby" / "003.json", SCENE)
    bad = copy.deepcopy(PLAN["waypoints"])
    bad[25] = STRETCHED
    rows = [
        {"problem": "cubby/003.json", "planner": "edmp", "status": "collision", "waypoints": PLAN["waypoints"], "time_ms": 40},
        {"problem": "cubby/003.json", "planner": "rrt", "status": "collision", "waypoints": bad},
        {"problem": "cubby/003.json", "planner": "none", "status": "failure", "waypoints": []},
    ]
    run = tmp_path / "run"  # as `edmp-host bench --out run` lays it out
    run.mkdir()
    (run / "results.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    out = tmp_path / "verdicts.json"
    code = judge.main(["--problems", str(problems), "--results", str(run), "--json", str(out), "--jobs", "2", "--no-progress"])
    assert code == 0
    table = capsys.readouterr().out
    assert "| cubby | 1 | 0 | 1 | 0 | 1 |" in table  # edmp: a false failure
    assert "| cubby | 1 | 0 | 0 | 0 | 0 |" in table  # rrt, none: honest failures
    verdicts = json.loads(out.read_text())["verdicts"]
    assert [v["planner"] for v in verdicts] == ["edmp", "none", "rrt"]
    near = verdicts[0]["closest_approach"]  # the free plan's closest approach, for the record
    assert near is None or 0.0 < near["distance"] <= judge.CLEARANCE_WITHIN
    assert "closest_approach" not in verdicts[2]


def test_bad_input_is_exit_2_not_a_false_success(tmp_path):
    problems, plans = tmp_path / "problems", tmp_path / "plans"
    broken = {k: v for k, v in SCENE.items() if k != "start"}
    write(problems / "cubby" / "003.json", broken)
    write(plans / "cubby" / "003.json", PLAN)
    assert judge.main(["--problems", str(problems), "--plans", str(plans), "--jobs", "1", "--no-progress"]) == 2
    write(plans / "cubby" / "005.json", PLAN)  # no such problem
    assert judge.main(["--problems", str(problems), "--plans", str(plans), "--jobs", "1", "--no-progress"]) == 2


def plate_between_the_fingers(robot, q: list[float]) -> dict:
    """A 1 cm x 2 cm x 2 cm plate between the fingers at q (9.5 cm along the hand's z, 2 cm
    across its y), turned with the hand."""
    judge.set_state(robot, np.array(q))
    hand_pos, hand_quat = judge.link_pose(robot, robot.hand)
    center, _ = judge.p.multiplyTransforms(hand_pos, hand_quat, [0, 0, 0.095], [0, 0, 0, 1])
    x, y, z, w = hand_quat
    return {"type": "cuboid", "center": list(center), "dims": [0.01, 0.02, 0.02], "quaternion": [w, x, y, z]}


def test_the_fingers_sit_at_the_scenes_opening(robot):
    plate = plate_between_the_fingers(robot, READY)
    scene = empty_scene(READY, READY, [plate])
    for w in (0.04, 0.025, 0.015):
        assert judge.judge(robot, scene | {"gripper": {"finger": w}}, {"waypoints": constant(READY)})["solved"], w
    assert judge.judge(robot, scene, {"waypoints": constant(READY)})["solved"]  # absent: 0.025
    v = judge.judge(robot, scene | {"gripper": {"finger": 0.0}}, {"waypoints": constant(READY)})
    assert v["failed"] == ["contact"]
    assert v["first_contact"]["link"] in ("panda_leftfinger", "panda_rightfinger")
    # The finger joints really are at w: each finger link 2w apart along the hand's y.
    robot.finger = 0.04
    judge.set_state(robot, np.array(READY))
    assert [judge.p.getJointState(robot.body, j, physicsClientId=robot.client)[0] for j in robot.prismatic] == [0.04, 0.04]
    left, right = (judge.link_pose(robot, j)[0] for j in robot.prismatic)
    assert math.dist(left, right) == pytest.approx(0.08, abs=1e-6)
    robot.finger = judge.FINGER_OPENING


def test_a_bad_gripper_is_bad_input(robot, tmp_path):
    for gripper in ({"finger": 0.05}, {"finger": -0.01}, {"finger": "open"}, {"finger": True}, {"fingers": 0.04}, {}, 0.04):
        with pytest.raises(ValueError):
            judge.finger_opening({"gripper": gripper})
    assert judge.finger_opening({}) == judge.FINGER_OPENING
    assert judge.finger_opening({"gripper": {"finger": 0}}) == 0.0
    problems, plans = tmp_path / "problems", tmp_path / "plans"
    write(problems / "cubby" / "003.json", SCENE | {"gripper": {"finger": 0.05}})
    write(plans / "cubby" / "003.json", PLAN)
    assert judge.main(["--problems", str(problems), "--plans", str(plans), "--jobs", "1", "--no-progress"]) == 2


# ---- point-cloud and mesh obstacles (issue 33) ----------------------------------------------


def tip_at_ready(robot, along: float = 0.05) -> list[float]:
    """A point `along` metres out of the hand at the ready pose (between the fingers' tips)."""
    judge.set_state(robot, np.array(READY))
    hand_pos, hand_quat = judge.link_pose(robot, robot.hand)
    point, _ = judge.p.multiplyTransforms(hand_pos, hand_quat, [0, 0, along], [0, 0, 0, 1])
    return list(point)


def little_cloud(center: list[float], half: float = 0.02, step: float = 0.01) -> list[list[float]]:
    g = np.arange(-half, half + 1e-9, step)
    return (np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3) + center).tolist()


CUBE_V = [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
CUBE_T = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]


def distance_at_ready(robot, point: list[float]) -> float:
    """PyBullet's distance from a point to the robot at the ready pose (0.1 mm probe sphere)."""
    probe = judge.spawn(robot, {"type": "sphere", "center": point, "radius": 1e-4})
    try:
        judge.set_state(robot, np.array(READY))
        judge.p.performCollisionDetection(physicsClientId=robot.client)
        return judge.closest(robot.client, robot.body, probe, 1.0) + 1e-4
    finally:
        judge.p.removeBody(probe, physicsClientId=robot.client)


def test_a_point_cloud_touches_or_not(robot):
    # A 5 x 5 x 5 cloud 20 cm out of the hand and one point 12 cm out (1.5 cm beyond the TCP,
    # about 25 mm from the fingertips): the balls touch when their radius exceeds that distance.
    point = tip_at_ready(robot, 0.12)
    d = distance_at_ready(robot, point)
    assert 0.015 < d < 0.04
    points = little_cloud(tip_at_ready(robot, 0.20)) + [point]
    for radius, failed in ((d + 0.001, ["contact"]), (d - 0.001, [])):
        v = judge.judge(robot, empty_scene(READY, READY, [{"type": "points", "points": points, "radius": radius}]), {"waypoints": constant(READY)})
        assert v["failed"] == failed, (radius, v)
    v = judge.judge(robot, empty_scene(READY, READY, [{"type": "points", "points": points, "radius": d + 0.001}]), {"waypoints": constant(READY)})
    assert v["first_contact"]["obstacle"] == 0 and v["first_contact"]["link"] in ("panda_leftfinger", "panda_rightfinger")
    # Placed: the same points in the frame of `center` / `quaternion` (a quarter turn about z
    # around the base): where they land decides.
    turn = [math.cos(math.pi / 4), 0, 0, math.sin(math.pi / 4)]
    local = (np.asarray(points) @ judge.rotation(turn)).tolist()  # R^T p: rotated back by R
    placed = {"type": "points", "points": local, "radius": d + 0.001, "center": [0, 0, 0], "quaternion": turn}
    assert judge.judge(robot, empty_scene(READY, READY, [placed]), {"waypoints": constant(READY)})["failed"] == ["contact"]
    assert judge.judge(robot, empty_scene(READY, READY, [placed | {"quaternion": [1, 0, 0, 0]}]), {"waypoints": constant(READY)})["solved"]
    assert judge.p.getNumBodies(physicsClientId=robot.client) == 1


def test_filter_robot_drops_the_points_on_the_arm_at_start(robot):
    # A 16 cm cloud around the flange (as a camera sees the arm): in contact, unless
    # filter_robot drops the points within 2 cm of the robot, which leaves the rest free.
    on_arm = little_cloud(tip_at_ready(robot, 0.0), half=0.08, step=0.02)
    cloud = {"type": "points", "points": on_arm, "radius": 0.0075}
    assert judge.judge(robot, empty_scene(READY, READY, [cloud]), {"waypoints": constant(READY)})["failed"] == ["contact"]
    assert judge.judge(robot, empty_scene(READY, READY, [cloud | {"filter_robot": 0.02}]), {"waypoints": constant(READY)})["solved"]
    assert judge.judge(robot, empty_scene(READY, READY, [cloud | {"filter_robot": 0.005}]), {"waypoints": constant(READY)})["failed"] == ["contact"]
    judge.set_state(robot, np.array(READY))
    near = judge.near_robot(robot, np.asarray(on_arm), 0.02)
    assert 0 < near.sum() < len(on_arm)
    # Exactly the points whose distance to the robot (link0 included) is within 2 cm.
    assert np.array_equal(near, np.array([distance_at_ready(robot, q) <= 0.02 for q in on_arm]))


def test_a_mesh_touches_or_not_like_the_box_it_draws(robot, tmp_path):
    # A cube mesh and the same cuboid primitive out of the hand: PyBullet's closest approach
    # agrees within 1 mm, and the judge calls both in contact when they reach the fingers
    # (6 cm cube, 13 cm out), both free when they do not (4 cm cube, 16 cm out).
    cases = ((tip_at_ready(robot, 0.13), 0.03, ["contact"]), (tip_at_ready(robot, 0.16), 0.02, []))
    for center, half, failed in cases:
        cube = {"type": "mesh", "vertices": CUBE_V, "triangles": CUBE_T, "center": center, "scale": half}
        box = {"type": "cuboid", "center": center, "dims": [2 * half] * 3, "quaternion": [1, 0, 0, 0]}
        verdicts = [judge.judge(robot, empty_scene(READY, READY, [o]), {"waypoints": constant(READY)}) for o in (cube, box)]
        assert [v["failed"] for v in verdicts] == [failed, failed], half
        if not failed:
            near = [judge.clearance(robot, empty_scene(READY, READY, [o]), constant(READY)[:1], 0.05)["distance"] for o in (cube, box)]
            assert abs(near[0] - near[1]) < 0.001, near
    # The same cube from OBJ, STL (binary and ASCII) and PLY files next to the scene.
    v, t = np.asarray(CUBE_V, dtype=np.float64), np.asarray(CUBE_T)
    (tmp_path / "c.obj").write_text("".join(f"v {a} {b} {c}\n" for a, b, c in v) + "vt 0 0\n" + "".join(f"f {a + 1}/1 {b + 1}/1 {c + 1}/1\n" for a, b, c in t))
    rec = np.zeros(len(t), np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]))
    rec["v"] = v[t]
    (tmp_path / "c.stl").write_bytes(b"solid binary".ljust(80) + np.uint32(len(t)).tobytes() + rec.tobytes())
    (tmp_path / "a.stl").write_text("solid a\n" + "".join("facet normal 0 0 0\nouter loop\n" + "".join(f"vertex {x} {y} {z}\n" for x, y, z in v[f]) + "endloop\nendfacet\n" for f in t) + "endsolid a\n")
    header = f"ply\nformat ascii 1.0\nelement vertex {len(v)}\nproperty double x\nproperty double y\nproperty double z\nproperty uchar red\nelement face {len(t)}\nproperty list uchar int vertex_indices\nend_header\n"
    (tmp_path / "c.ply").write_text(header + "".join(f"{a} {b} {c} 255\n" for a, b, c in v) + "".join(f"3 {a} {b} {c}\n" for a, b, c in t))
    for name in ("c.obj", "c.stl", "a.stl", "c.ply"):
        read_v, read_t = judge.read_mesh(tmp_path / name)
        assert np.allclose(np.sort(read_v[read_t].reshape(-1, 3), axis=0), np.sort(v[t].reshape(-1, 3), axis=0)), name
        for center, half, failed in cases:
            scene = empty_scene(READY, READY, [{"type": "mesh", "file": name, "center": center, "quaternion": [1, 0, 0, 0], "scale": [half] * 3}])
            assert judge.judge(robot, scene, {"waypoints": constant(READY)}, tmp_path)["failed"] == failed, name
    # An open mesh is its surface: the cube's two triangles of one face, across the fingers.
    judge.set_state(robot, np.array(READY))
    _, hand_quat = judge.link_pose(robot, robot.hand)
    x, y, z, w = hand_quat
    face = {"type": "mesh", "vertices": CUBE_V, "triangles": CUBE_T[:2], "center": tip_at_ready(robot, 0.10), "quaternion": [w, x, y, z], "scale": [0.005, 0.05, 0.01]}
    assert judge.judge(robot, empty_scene(READY, READY, [face]), {"waypoints": constant(READY)})["failed"] == ["contact"]
    thin = face | {"scale": [0.005, 0.01, 0.01]}  # the same plate, too narrow to reach the fingers
    assert judge.judge(robot, empty_scene(READY, READY, [thin]), {"waypoints": constant(READY)})["solved"]


def test_point_files_ply_and_pcd(tmp_path):
    pts = np.random.default_rng(0).uniform(-1, 1, (50, 3))
    (tmp_path / "b.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 50\nproperty float x\nproperty float y\nproperty float z\nproperty double intensity\nend_header\n" + np.rec.fromarrays([*pts.T.astype("<f4"), np.zeros(50)], dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("i", "<f8")]).tobytes())
    (tmp_path / "a.pcd").write_text("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 50\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 50\nDATA ascii\n" + "".join(f"{a} {b} {c} 7\n" for a, b, c in pts))
    rows = np.rec.fromarrays([*pts.T], dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8")]).tobytes()
    (tmp_path / "b.pcd").write_bytes(b"VERSION 0.7\nFIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 50\nHEIGHT 1\nDATA binary\n" + rows)
    for name in ("b.ply", "a.pcd", "b.pcd"):
        assert np.allclose(judge.read_points(tmp_path / name), pts, atol=1e-6), name


def test_truth_obstacles_replace_the_scenes_obstacles(robot, tmp_path):
    tip = tip_at_ready(robot, 0.06)  # inside the hand
    touching = {"type": "points", "points": little_cloud(tip), "radius": 0.0075}
    sphere = {"type": "sphere", "center": tip, "radius": 0.02}
    # The cloud would touch; the truth is empty: solved, and the verdict says what it judged.
    scene = empty_scene(READY, READY, [touching]) | {"meta": {"truth_obstacles": []}}
    v = judge.judge(robot, scene, {"waypoints": constant(READY)})
    assert v["solved"] and v["judged_against"] == "meta.truth_obstacles"
    # The scene's cloud is far away; the truth touches.
    far = {"type": "points", "points": [[2.0, 2.0, 2.0]], "radius": 0.0075}
    scene = empty_scene(READY, READY, [far]) | {"meta": {"truth_obstacles": [sphere]}}
    v = judge.judge(robot, scene, {"waypoints": constant(READY)})
    assert v["failed"] == ["contact"] and v["first_contact"]["obstacle"] == 0
    assert "judged_against" not in judge.judge(robot, empty_scene(READY, READY, [sphere]), {"waypoints": constant(READY)})
    # From the command line, a file beside the problem: resolved against the problem's folder.
    problems = tmp_path / "problems"
    write(problems / "cells" / "000.json", empty_scene(READY, READY, [{"type": "mesh", "file": "000.obj", "center": tip, "scale": 0.02}]))
    (problems / "cells" / "000.obj").write_text("".join(f"v {a} {b} {c}\n" for a, b, c in CUBE_V) + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in CUBE_T))
    run = tmp_path / "results.jsonl"
    run.write_text(json.dumps({"problem": "cells/000.json", "planner": "x", "status": "success", "waypoints": constant(READY)}) + "\n")
    assert judge.main(["--problems", str(problems), "--results", str(run), "--jobs", "1", "--no-progress"]) == 1
    (problems / "cells" / "000.obj").unlink()
    assert judge.main(["--problems", str(problems), "--results", str(run), "--jobs", "1", "--no-progress"]) == 2


# ---- other arms: the iiwa 7 and the xArm 6 (docs/formats.md, "Other arms") -------------------

FIXTURES = HERE.parent / "tests" / "fixtures"
# The example scenes: a table top and a 50 cm upright cylinder (obstacle 1) between the ends.
TABLE = {"type": "cuboid", "center": [0.5, 0.0, 0.0], "dims": [0.6, 1.2, 0.02], "quaternion": [1, 0, 0, 0]}
POST = {"type": "cylinder", "center": [0.35, 0.25, 0.25], "radius": 0.04, "height": 0.5, "quaternion": [1, 0, 0, 0]}
ARM_ENDS = {
    "xarm6": ([0, -0.5, -0.8, 0, 1.3, 0], [1.2, -0.3, -0.9, 0, 1.2, 0]),
    "iiwa7": ([0, 0.2, 0, -2.0, 0, 0.95, 0], [1.2, 0.3, 0, -1.8, 0, 0.95, 0]),
}
# A corner the arm swings through on its way: "over" passes the post (PyBullet: 33 mm for the
# xArm), "through" drives the wrist into it (-42 mm, -72 mm).
ARM_CORNERS = {
    "xarm6": {"over": [0.6, -0.6, -0.6, 0, 1.3, 0], "through": [0.6, -0.3, -1.0, 0, 1.3, 0]},
    "iiwa7": {"over": [0.6, 0.0, 0, -1.6, 0, 0.7, 0], "through": [0.6, 0.2, 0, -2.0, 0, 0.95, 0]},
}
ARM_LINKS = {
    "xarm6": ["link_base", "link1", "link2", "link3", "link4", "link5", "link6"],
    "iiwa7": [f"lbr_iiwa_link_{k}" for k in range(8)],
}


@pytest.fixture(scope="module")
def arms() -> dict[str, judge.Robot]:
    return {arm: judge.connect(arm) for arm in judge.ARMS}


def arm_scene(arm: str, start: list[float], goal: list[float], obstacles: list[dict] | None = None) -> dict:
    return empty_scene(start, goal, obstacles) | {"robot": arm}


def polyline(corners: list[list[float]]) -> list[list[float]]:
    """HORIZON waypoints evenly spaced (in joint space) along the corners, the ends exact."""
    c = np.asarray(corners, dtype=np.float64)
    length = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(c, axis=0), axis=1))]
    out = [np.array([np.interp(t, length, c[:, j]) for j in range(c.shape[1])]) for t in np.linspace(0.0, length[-1], judge.HORIZON)]
    out[0], out[-1] = c[0], c[-1]
    return [list(map(float, q)) for q in out]


def record_collision():
    import importlib.util

    spec = importlib.util.spec_from_file_location("record_collision", FIXTURES / "record_collision.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("arm", ["xarm6", "iiwa7"])
def test_other_arms_are_pybullet_datas_copies_with_the_urdfs_limits(arms, arm):
    r = arms[arm]
    assert judge.packaged_urdf(arm).read_bytes() == judge.ARMS[arm].urdf.read_bytes()
    assert str(judge.packaged_urdf(arm)).startswith(judge.pybullet_data.getDataPath())
    assert len(r.revolute) == judge.ARMS[arm].joints == len(ARM_ENDS[arm][0]) and r.prismatic == []
    names = [r.names[j] for j in [*r.fixed, *r.moving]]
    assert names == ARM_LINKS[arm]
    assert [r.names[j] for j in r.fixed] == ARM_LINKS[arm][:1]  # the base link is not checked against obstacles
    assert r.names[r.tcp] == r.names[r.hand] == ARM_LINKS[arm][-1]
    if arm == "xarm6":
        assert r.limits[2] == (-3.927, 0.19198) and r.limits[4] == (-1.69297, 3.14159265359)
    else:
        assert r.limits[1] == (-2.09439510239, 2.09439510239) and r.limits[6] == (-3.05432619099, 3.05432619099)
    # The held object may touch only the links within one actuated joint of the TCP's.
    assert [r.names[j] for j in r.held_partners] == ARM_LINKS[arm][:-2]


@pytest.mark.parametrize("arm", ["xarm6", "iiwa7"])
def test_other_arms_self_pairs_and_bodies_follow_record_collisions_rule(arms, arm):
    rc = record_collision()
    client = judge.p.connect(judge.p.DIRECT)
    try:
        body, revolute, limits, names, with_geometry = rc.load_arm(client, rc.ARMS[arm])
        pairs = [[names[a], names[b]] for a, b in rc.apart_at_zero_pairs(client, body, revolute, with_geometry)]
    finally:
        judge.p.disconnect(client)
    r = arms[arm]
    mine = [[r.names[a], r.names[b]] for a, b in r.self_pairs]
    assert mine == pairs
    assert mine == json.loads((FIXTURES / f"collision_pybullet_{arm}.json").read_text())["self_link_pairs"]
    assert mine == json.loads((FIXTURES / f"fk_pybullet_{arm}.json").read_text())["self_pairs"]
    assert r.limits == [tuple(lim) for lim in limits]
    assert sorted(r.names[j] for j in [*r.fixed, *r.moving]) == sorted(names[j] for j in with_geometry)
    # Parent and child are never a pair; links two apart are.
    assert [ARM_LINKS[arm][0], ARM_LINKS[arm][1]] not in mine and [ARM_LINKS[arm][1], ARM_LINKS[arm][3]] in mine


@pytest.mark.parametrize("arm", ["xarm6", "iiwa7"])
def test_other_arms_through_an_obstacle_is_contact_around_it_is_free(arms, arm):
    start, goal = ARM_ENDS[arm]
    scene = arm_scene(arm, start, goal, [TABLE, POST])
    over = polyline([start, ARM_CORNERS[arm]["over"], goal])
    v = judge.judge(arms[arm], scene, {"waypoints": over})
    assert v["solved"], v
    assert v["robot"] == arm and v["states_checked"] > judge.HORIZON
    v = judge.judge(arms[arm], scene, {"waypoints": polyline([start, ARM_CORNERS[arm]["through"], goal])})
    assert v["failed"] == ["contact"] and v["robot"] == arm
    c = v["first_contact"]
    assert c["kind"] == "obstacle" and c["obstacle"] == 1 and c["distance"] <= 0.0
    assert c["link"] in ARM_LINKS[arm][1:]
    # Without the post the same path is free; the Panda's judge refuses the scene.
    assert judge.judge(arms[arm], arm_scene(arm, start, goal, [TABLE]), {"waypoints": polyline([start, ARM_CORNERS[arm]["through"], goal])})["solved"]
    with pytest.raises(ValueError):
        judge.judge(judge.connect(), scene, {"waypoints": over})
    assert judge.p.getNumBodies(physicsClientId=arms[arm].client) == 1


@pytest.mark.parametrize("arm", ["xarm6", "iiwa7"])
def test_other_arms_obstacle_verdicts_match_the_pybullet_fixture(arms, arm):
    # tests/fixtures/collision_pybullet_NAME.json: PyBullet's distance from every moving link (the
    # base not included) to one obstacle. Contact entries a millimetre deep are contact with that
    # obstacle; free entries a millimetre clear have no obstacle contact (self-contact may remain).
    fixture = json.loads((FIXTURES / f"collision_pybullet_{arm}.json").read_text())["obstacle_pairs"]
    deep = [e for e in fixture if e["distance"] < -0.001][:15]
    clear = [e for e in fixture if e["distance"] > 0.001][:15]
    base_near = 0
    for e in deep + clear:
        v = judge.judge(arms[arm], arm_scene(arm, e["joints"], e["joints"], [e["obstacle"]]), {"waypoints": constant(e["joints"])})
        c = v.get("first_contact", {})
        if e["distance"] < 0:
            assert c.get("kind") == "obstacle" and c["obstacle"] == 0, (e, v)
        else:
            assert c.get("kind") != "obstacle", (e, v)
    # Fixture obstacles that touch only the base link are free: the base is bolted down.
    r = arms[arm]
    for e in fixture:
        if e["distance"] > 0.001:
            body = judge.spawn(r, e["obstacle"])
            judge.set_state(r, np.asarray(e["joints"]))
            judge.p.performCollisionDetection(physicsClientId=r.client)
            touches_base = any(judge.closest(r.client, r.body, body, 0.0, link) is not None for link in r.fixed)
            judge.p.removeBody(body, physicsClientId=r.client)
            if touches_base:
                base_near += 1
                v = judge.judge(r, arm_scene(arm, e["joints"], e["joints"], [e["obstacle"]]), {"waypoints": constant(e["joints"])})
                assert v.get("first_contact", {}).get("kind") != "obstacle", (e, v)
    assert base_near > 0, "no fixture obstacle touches the base link"


@pytest.mark.parametrize("arm", ["xarm6", "iiwa7"])
def test_other_arms_self_contact_matches_the_pybullet_fixture(arms, arm):
    fixture = json.loads((FIXTURES / f"collision_pybullet_{arm}.json").read_text())["self_pairs"]
    deep = [e for e in fixture if e["distance"] < -0.001][:10]
    clear = [e for e in fixture if e["distance"] > 0.001][:10]
    assert deep and clear
    r = arms[arm]
    pairs = {frozenset((r.names[a], r.names[b])) for a, b in r.self_pairs}
    for e in deep:
        v = judge.judge(r, arm_scene(arm, e["joints"], e["joints"]), {"waypoints": constant(e["joints"])})
        assert v["failed"] == ["contact"], (e, v)
        c = v["first_contact"]
        assert c["kind"] == "self" and frozenset((c["link"], c["other"])) in pairs
    for e in clear:
        v = judge.judge(r, arm_scene(arm, e["joints"], e["joints"]), {"waypoints": constant(e["joints"])})
        assert v["solved"], (e, v)


def test_other_arms_joint_counts(arms):
    start, goal = ARM_ENDS["xarm6"]
    scene = arm_scene("xarm6", start, goal, [TABLE, POST])
    over = polyline([start, ARM_CORNERS["xarm6"]["over"], goal])
    seven = [q + [0.0] for q in over]  # a 7-number waypoint for the 6-joint xArm
    v = judge.judge(arms["xarm6"], scene, {"waypoints": seven})
    assert v["failed"] == ["malformed"] and "expected 50x6" in v["detail"] and v["robot"] == "xarm6"
    iiwa_start, iiwa_goal = ARM_ENDS["iiwa7"]
    six = [q[:6] for q in polyline([iiwa_start, iiwa_goal])]
    v = judge.judge(arms["iiwa7"], arm_scene("iiwa7", iiwa_start, iiwa_goal), {"waypoints": six})
    assert v["failed"] == ["malformed"] and "expected 50x7" in v["detail"]
    # A Panda plan (7 numbers) for the xArm's scene, and ends of the wrong length: bad input.
    for bad in (arm_scene("xarm6", start + [0.0], goal), arm_scene("xarm6", start, goal[:5])):
        with pytest.raises(ValueError):
            judge.judge(arms["xarm6"], bad, {"waypoints": over})
    for name in ("ur5", "Panda", 7, None):
        with pytest.raises(ValueError):
            judge.scene_robot({"robot": name})
    assert judge.scene_robot({}) == "panda" and judge.scene_robot({"robot": "panda"}) == "panda"


def test_other_arms_limits_are_the_urdfs(arms):
    q = [0.0, -0.5, 0.19198 + 2e-5, 0.0, 1.3, 0.0]  # xArm joint 3's upper limit is 0.19198
    v = judge.judge(arms["xarm6"], arm_scene("xarm6", q, q), {"waypoints": constant(q)})
    assert v["limit_violation"]["joint"] == 3 and v["limit_violation"]["limits"] == [-3.927, 0.19198]
    q[2] = 0.19198 + 5e-6
    assert "limits" not in judge.judge(arms["xarm6"], arm_scene("xarm6", q, q), {"waypoints": constant(q)})["failed"]
    # Beyond the Panda's limits, within the iiwa's: joint 4 at +0.5 (the Panda's stays below -0.0698).
    q = [0.0, 0.3, 0.0, 0.5, 0.0, 0.3, 0.0]
    assert "limits" not in judge.judge(arms["iiwa7"], arm_scene("iiwa7", q, q), {"waypoints": constant(q)})["failed"]
    q[6] = -3.05432619099 - 2e-5
    v = judge.judge(arms["iiwa7"], arm_scene("iiwa7", q, q), {"waypoints": constant(q)})
    assert v["failed"] == ["limits"] and v["limit_violation"]["joint"] == 7


@pytest.mark.parametrize("arm", ["xarm6", "iiwa7"])
def test_other_arms_pose_goals_are_the_tcp_links(arms, arm):
    # tests/fixtures/fk_pybullet_NAME.json: the TCP link's world pose (x y z qw qx qy qz) at
    # random configurations, recorded from the repository's URDF.
    fk = json.loads((FIXTURES / f"fk_pybullet_{arm}.json").read_text())
    tcp = fk["links"].index(ARM_LINKS[arm][-1])
    for sample in fk["samples"][1:6]:
        q, pose = sample["joints"], sample["poses"][tcp]
        scene = arm_scene(arm, q, q) | {"goal": {"pose": {"position": pose[:3], "quaternion": pose[3:]}}}
        v = judge.judge(arms[arm], scene, {"waypoints": constant(q)})
        assert "goal" not in v["failed"] and v["goal_position_error_m"] < 1e-5 and v["goal_angle_error_deg"] < 0.1, v
        moved = copy.deepcopy(scene)
        moved["goal"]["pose"]["position"][2] += 0.006
        assert "goal" in judge.judge(arms[arm], moved, {"waypoints": constant(q)})["failed"]


@pytest.mark.parametrize("arm", ["xarm6", "iiwa7"])
def test_other_arms_hold_objects_at_the_tcp_and_ignore_the_gripper(arms, arm):
    # A 20 cm rod along the TCP link's z, its far end 30 cm out; a small sphere at that end
    # touches only the rod. Moving the first joint moves the rod away.
    r = arms[arm]
    q = list(ARM_ENDS[arm][0])
    rod = {"type": "cylinder", "center": [0, 0, 0.2], "radius": 0.01, "height": 0.2, "quaternion": [1, 0, 0, 0]}
    judge.set_state(r, np.array(q))
    tcp_pos, tcp_quat = judge.link_pose(r, r.tcp)
    tip, _ = judge.p.multiplyTransforms(tcp_pos, tcp_quat, [0, 0, 0.3], [0, 0, 0, 1])
    sphere = {"type": "sphere", "center": list(tip), "radius": 0.01}
    scene = arm_scene(arm, q, q, [sphere]) | {"gripper": {"finger": 0.5}}  # no hand: ignored, even out of the Panda's range
    assert judge.judge(r, scene, {"waypoints": constant(q)})["solved"]
    v = judge.judge(r, scene | {"held_object": rod}, {"waypoints": constant(q)})
    assert v["failed"] == ["contact"] and v["first_contact"]["link"] == judge.HELD and v["first_contact"]["obstacle"] == 0
    away = list(q)
    away[0] += 1.0
    assert judge.judge(r, arm_scene(arm, away, away, [sphere]) | {"held_object": rod}, {"waypoints": constant(away)})["solved"]
    # A 5 cm ball held at the TCP's origin overlaps the TCP link (and its parent): not a self
    # pair. Grown to 15 cm it reaches the links further down: self-contact.
    ball = {"type": "sphere", "center": [0, 0, 0], "radius": 0.05}
    judge.set_state(r, np.array(q))
    held = judge.spawn(r, ball | {"center": list(tcp_pos)})
    judge.p.performCollisionDetection(physicsClientId=r.client)
    assert judge.closest(r.client, held, r.body, 0.0, None, r.tcp) is not None
    judge.p.removeBody(held, physicsClientId=r.client)
    assert judge.judge(r, arm_scene(arm, q, q) | {"held_object": ball}, {"waypoints": constant(q)})["solved"]
    v = judge.judge(r, arm_scene(arm, q, q) | {"held_object": ball | {"radius": 0.15}}, {"waypoints": constant(q)})
    assert v["failed"] == ["contact"] and v["first_contact"]["kind"] == "self" and v["first_contact"]["link"] == judge.HELD
    assert v["first_contact"]["other"] in ARM_LINKS[arm][:-2]


def test_command_line_judges_every_arm(tmp_path, capsys):
    problems = tmp_path / "problems"
    write(problems / "cubby" / "003.json", SCENE)
    rows = [{"problem": "cubby/003.json", "planner": "p", "status": "success", "waypoints": PLAN["waypoints"]}]
    for arm, (start, goal) in ARM_ENDS.items():
        write(problems / "posts" / f"{arm}.json", arm_scene(arm, start, goal, [TABLE, POST]))
        rows.append({"problem": f"posts/{arm}.json", "planner": "p", "status": "success", "waypoints": polyline([start, ARM_CORNERS[arm]["over"], goal])})
        write(problems / "through" / f"{arm}.json", arm_scene(arm, start, goal, [TABLE, POST]))
        rows.append({"problem": f"through/{arm}.json", "planner": "p", "status": "success", "waypoints": polyline([start, ARM_CORNERS[arm]["through"], goal])})
    run = tmp_path / "results.jsonl"
    run.write_text("".join(json.dumps(r) + "\n" for r in rows))
    out = tmp_path / "verdicts.json"
    code = judge.main(["--problems", str(problems), "--results", str(run), "--json", str(out), "--jobs", "2", "--no-progress"])
    assert code == 1  # the two plans through the post
    table = capsys.readouterr().out
    assert "| cubby | 1 | 1 | 1 | 0 | 0 |" in table  # the Panda's row, as before
    assert "| posts (iiwa7) | 1 | 1 | 1 | 0 | 0 |" in table and "| posts (xarm6) | 1 | 1 | 1 | 0 | 0 |" in table
    assert "| through (xarm6) | 1 | 1 | 0 | 1 | 0 |" in table
    assert "- through/xarm6.json [xarm6]: contact link" in table and "- through/iiwa7.json [iiwa7]: contact lbr_iiwa_link_" in table
    verdicts = {v["problem"]: v for v in json.loads(out.read_text())["verdicts"]}
    assert "robot" not in verdicts["cubby/003.json"] and verdicts["posts/xarm6.json"]["robot"] == "xarm6"
    # An unknown robot is bad input.
    write(problems / "posts" / "xarm6.json", arm_scene("ur5", *ARM_ENDS["xarm6"]))
    assert judge.main(["--problems", str(problems), "--results", str(run), "--jobs", "1", "--no-progress"]) == 2


def ball_distance(r: judge.Robot, center: list[float], radius: float, link: int) -> float:
    """PyBullet's distance from a ball to one link of the arm in its current state."""
    ball = judge.spawn(r, {"type": "sphere", "center": center, "radius": radius})
    try:
        judge.p.performCollisionDetection(physicsClientId=r.client)
        d = judge.closest(r.client, ball, r.body, 1.0, None, link)
        return 1.0 if d is None else d
    finally:
        judge.p.removeBody(ball, physicsClientId=r.client)


@pytest.mark.parametrize("arm", ["xarm6", "iiwa7"])
def test_other_arms_clouds_skip_the_base_link(arms, arm):
    # Three 1 cm balls against the base link's side, 5 cm up, touch it and nothing else: free,
    # the base is bolted down. The arm leans forward and down, so that the balls lie within the
    # moving links' bounds and are probed one by one. The same balls beside the first moving
    # link touch it: contact.
    r = arms[arm]
    q = {"xarm6": [0, 0.5, -0.8, 0, 1.3, 0], "iiwa7": [0, 1.2, 0, -1.5, 0, 1.0, 0]}[arm]
    x = {"xarm6": 0.055, "iiwa7": 0.115}[arm]  # 1 to 6 mm out of the base link's hull
    low = [[x, y, 0.05] for y in (-0.02, 0.0, 0.02)]
    judge.set_state(r, np.array(q))
    assert all(ball_distance(r, c, 0.01, r.fixed[0]) <= 0.0 for c in low)
    assert all(ball_distance(r, c, 0.01, link) > 0.05 for c in low for link in r.moving)
    assert judge.near_robot(r, np.asarray(low), 0.01).all()  # filter_robot measures to the base too
    cloud = {"type": "points", "points": low, "radius": 0.01}
    v = judge.judge(r, arm_scene(arm, q, q, [cloud]), {"waypoints": constant(q)})
    assert v["solved"], v
    judge.set_state(r, np.array(q))
    link1_lo, link1_hi = judge.p.getAABB(r.body, r.moving[0], physicsClientId=r.client)
    high = [[link1_hi[0] - 0.01, y, (link1_lo[2] + link1_hi[2]) / 2] for y in (-0.02, 0.0, 0.02)]
    assert any(ball_distance(r, c, 0.01, r.moving[0]) <= 0.0 for c in high)
    v = judge.judge(r, arm_scene(arm, q, q, [cloud | {"points": high}]), {"waypoints": constant(q)})
    assert v["failed"] == ["contact"] and v["first_contact"]["link"] == ARM_LINKS[arm][1] and v["first_contact"]["obstacle"] == 0
    assert judge.p.getNumBodies(physicsClientId=r.client) == 1
