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
