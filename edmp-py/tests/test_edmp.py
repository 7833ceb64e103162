"""The `edmp` package: plan, fk, check, ik, errors and MoveIt scenes, against the CLI where it
is at hand (set EDMP_HOST to the edmp-host binary; scripts/test does)."""

from __future__ import annotations

import json
import os
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import edmp

ROOT = Path(__file__).resolve().parents[2]
WALL = ROOT / "examples" / "wall.json"
MOVEIT = ROOT / "edmp-host" / "tests" / "moveit"
HOST = os.environ.get("EDMP_HOST")


@pytest.fixture(scope="module")
def wall() -> edmp.Scene:
    return edmp.Scene.from_file(WALL)


@pytest.fixture(scope="module")
def wall_plan(wall: edmp.Scene) -> edmp.Plan:
    return edmp.plan(wall, seed=0, candidates=True)


def test_scene_constructors_agree(wall: edmp.Scene) -> None:
    text = WALL.read_text()
    for scene in (edmp.Scene.from_json(text), edmp.Scene.from_dict(json.loads(text))):
        assert scene.to_dict() == wall.to_dict()
    np.testing.assert_array_equal(wall.start, [0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785])
    assert isinstance(wall.goal, np.ndarray) and wall.goal.shape == (7,)
    assert len(wall.obstacles) == 4 and wall.held_object is None
    pose_scene = edmp.Scene.from_file(ROOT / "examples" / "tabletop-pose-held.json")
    assert isinstance(pose_scene.goal, edmp.Pose) and pose_scene.goal.quaternion.shape == (4,)


def test_the_wall_example_plans_collision_free(wall: edmp.Scene, wall_plan: edmp.Plan) -> None:
    p = wall_plan
    assert p.status == "success" and p.success
    assert p.waypoints.shape == (50, 7) and p.waypoints.dtype == np.float64
    np.testing.assert_allclose(p.waypoints[0], wall.start, atol=1e-6)
    np.testing.assert_allclose(p.waypoints[-1], wall.goal, atol=1e-6)
    assert p.stage in ("diffusion", "reseeded", "search")
    assert set(p.costs) == {"swept_volume", "intersection_volume"}
    assert p.timing_ms["total"] > 0
    assert p.document["format"] == "edmp-plan/1"


def test_a_seed_makes_the_plan_deterministic(wall: edmp.Scene, wall_plan: edmp.Plan) -> None:
    again = edmp.plan(wall, seed=0, candidates=True)
    np.testing.assert_array_equal(again.waypoints, wall_plan.waypoints)
    assert again.guide == wall_plan.guide and again.costs == wall_plan.costs


def test_candidates_are_the_ensemble(wall: edmp.Scene, wall_plan: edmp.Plan) -> None:
    cands = wall_plan.candidates
    assert cands is not None and len(cands) == 12
    assert all(c.waypoints.shape == (50, 7) for c in cands)
    assert any(np.array_equal(c.waypoints, wall_plan.waypoints) for c in cands)
    assert edmp.plan(wall, seed=1).candidates is None


def test_timed_plans_start_and_end_at_rest_within_the_limits(wall: edmp.Scene) -> None:
    p = edmp.plan(wall, seed=0, timed=True, rate=200.0, velocity_scale=0.5)
    t = p.trajectory
    assert t is not None and t["joint_names"][0] == "panda_joint1"
    n = len(t["time_from_start"])
    assert t["positions"].shape == (n, 7) and n > 10
    assert np.all(np.diff(t["time_from_start"]) > 0)
    np.testing.assert_allclose(t["positions"][0], p.waypoints[0], atol=1e-6)
    np.testing.assert_allclose(t["positions"][-1], p.waypoints[-1], atol=1e-6)
    assert np.all(t["velocities"][[0, -1]] == 0.0)
    limit = 0.5 * np.array([2.175] * 4 + [2.61] * 3)
    assert np.all(np.abs(t["velocities"]) <= limit * (1 + 1e-4))
    assert t["limits"]["velocity_scale"] == 0.5 and t["limits"]["jerk_limited"]
    assert edmp.plan(wall, seed=0).trajectory is None


def test_bad_timing_scales_are_value_errors(wall: edmp.Scene) -> None:
    with pytest.raises(ValueError, match="velocity_scale: 1.5"):
        edmp.plan(wall, timed=True, velocity_scale=1.5)
    with pytest.raises(ValueError, match="rate"):
        edmp.plan(wall, timed=True, rate=0.0)


def test_planning_releases_the_gil(wall: edmp.Scene) -> None:
    done = threading.Event()
    ticks = 0

    def run() -> None:
        edmp.plan(wall, seed=2)
        done.set()

    worker = threading.Thread(target=run)
    worker.start()
    time.sleep(0.01)
    while not done.is_set():
        ticks += 1
        time.sleep(0)
    worker.join()
    # With the GIL held through the plan (hundreds of ms), this thread could not run at all.
    assert ticks > 100, ticks


@pytest.mark.skipif(HOST is None, reason="EDMP_HOST (the edmp-host binary) not set")
def test_a_plan_is_the_cli_document(wall_plan: edmp.Plan) -> None:
    out = subprocess.run(
        [HOST, "plan", str(WALL), "--seed", "0", "--candidates"], capture_output=True, text=True, check=True
    )
    cli = json.loads(out.stdout)
    ours = dict(wall_plan.document)
    for doc in (cli, ours):
        doc.pop("timing_ms")
    assert ours == cli


def test_fk_of_the_ready_pose() -> None:
    q = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
    r = edmp.fk(q)
    np.testing.assert_allclose(r["tcp"]["position"], [0.307, 0.0, 0.4853], atol=1e-3)
    assert abs(abs(r["tcp"]["quaternion"][1]) - 1.0) < 1e-3  # pointing down: 180° about x
    assert len(r["frames"]) == 13 and len(r["collision_boxes"]) == 11
    assert r["frames"][-1]["name"] == "panda_grasptarget"
    np.testing.assert_allclose(r["frames"][-1]["position"], r["tcp"]["position"])
    assert r["within_soft_limits"] is True
    with pytest.raises(ValueError, match="expected shape"):
        edmp.fk([0.0] * 6)


@pytest.mark.skipif(HOST is None, reason="EDMP_HOST (the edmp-host binary) not set")
def test_fk_is_what_the_cli_prints() -> None:
    q = ["0.1", "-0.5", "0.2", "-2.0", "0.3", "1.8", "-0.4"]
    out = subprocess.run([HOST, "fk", *q, "--json"], capture_output=True, text=True, check=True)
    cli = json.loads(out.stdout)
    ours = edmp.fk([float(x) for x in q])
    assert cli["within_soft_limits"] == ours["within_soft_limits"]
    for key in ("frames", "collision_boxes"):
        for a, b in zip(cli[key], ours[key], strict=True):
            assert a["name"] == b["name"]
            np.testing.assert_array_equal(np.float32(a["position"]), np.float32(b["position"]))
            np.testing.assert_array_equal(np.float32(a["quaternion"]), np.float32(b["quaternion"]))


@pytest.mark.parametrize("robot, joints, tcp", [("iiwa7", 7, "lbr_iiwa_link_7"), ("xarm6", 6, "link6")])
def test_fk_of_another_arm(robot: str, joints: int, tcp: str) -> None:
    names = edmp.joint_names(robot)
    assert len(names) == joints
    r = edmp.fk(np.zeros(joints), robot=robot)
    assert r["robot"] == robot and r["tcp_frame"] == tcp
    assert r["frames"][0]["position"].shape == (3,)
    with pytest.raises(ValueError, match=f"expected shape \\({joints},\\)"):
        edmp.fk(np.zeros(joints + 1), robot=robot)
    with pytest.raises(ValueError, match="not an arm this package knows"):
        edmp.fk(np.zeros(7), robot="ur5")


@pytest.mark.skipif(HOST is None, reason="EDMP_HOST (the edmp-host binary) not set")
@pytest.mark.parametrize("robot", ["iiwa7", "xarm6"])
def test_fk_of_another_arm_is_what_the_cli_prints(robot: str) -> None:
    q = ["0.3", "-0.4", "0.5", "-1.2", "0.6", "0.9", "-0.2"][: len(edmp.joint_names(robot))]
    out = subprocess.run([HOST, "fk", *q, "--robot", robot, "--json"], capture_output=True, text=True, check=True)
    cli = json.loads(out.stdout)
    ours = edmp.fk([float(x) for x in q], robot=robot)
    for key in ("frames", "collision_boxes"):
        for a, b in zip(cli[key], ours[key], strict=True):
            assert a["name"] == b["name"]
            np.testing.assert_array_equal(np.float32(a["position"]), np.float32(b["position"]))


def test_check_tells_a_free_path_from_a_colliding_one(wall: edmp.Scene, wall_plan: edmp.Plan) -> None:
    free = edmp.check(wall, wall_plan.waypoints)
    assert free and free.colliding_states == 0 and free.first_contact is None and free.states >= 50
    # Straight through joint space: joint 1 swings the arm from one side of the wall to the other.
    straight = np.linspace(wall.start, wall.goal, 50)
    hit = edmp.check(wall, straight)
    assert not hit and hit.colliding_states > 0
    assert "touches obstacles[1]" in hit.first_contact["contact"]  # the wall
    with pytest.raises(ValueError, match="expected 50 rows"):
        edmp.check(wall, straight[:10])


def test_ik_reaches_a_pose_or_says_none(wall: edmp.Scene) -> None:
    goal_tcp = edmp.fk(wall.goal)["tcp"]
    q = edmp.ik(wall, goal_tcp["position"], goal_tcp["quaternion"])
    assert q is not None and q.shape == (7,)
    reached = edmp.fk(q)["tcp"]
    np.testing.assert_allclose(reached["position"], goal_tcp["position"], atol=1e-3)
    assert edmp.ik(wall, [2.0, 0.0, 0.5], [1.0, 0.0, 0.0, 0.0]) is None  # out of reach
    with pytest.raises(ValueError, match="quaternion: norm"):
        edmp.ik(wall, [0.5, 0.0, 0.5], [0.5, 0.0, 0.0, 0.0])


def test_errors_name_the_json_path() -> None:
    doc = json.loads(WALL.read_text())
    doc["obstacles"][0]["quaternion"] = [0.71, 0, 0, 0]
    with pytest.raises(edmp.SceneError) as e:
        edmp.Scene.from_dict(doc)
    assert str(e.value) == "obstacles[0].quaternion: norm 0.71, expected 1"
    assert isinstance(e.value, ValueError)
    doc = json.loads(WALL.read_text())
    doc["start"] = [0.0, -0.785]
    with pytest.raises(edmp.SceneError, match=r"^start: expected 7 numbers, found 2$"):
        edmp.plan(doc)
    with pytest.raises(edmp.SceneError, match="not valid JSON"):
        edmp.Scene.from_json("{")


def test_an_unreachable_pose_goal_is_a_plan_error(wall: edmp.Scene) -> None:
    doc = wall.to_dict()
    doc["goal"] = {"pose": {"position": [2.0, 0.0, 0.5], "quaternion": [1, 0, 0, 0]}}
    scene = edmp.Scene.from_dict(doc)  # valid input ...
    with pytest.raises(edmp.PlanError, match="goal.pose: unreachable"):
        edmp.plan(scene)  # ... that no configuration reaches


def test_moveit_scene_and_request_import_and_plan(wall: edmp.Scene) -> None:
    scene = edmp.import_moveit(MOVEIT / "table_box.scene.yaml", MOVEIT / "joint_goal.request.yaml")
    assert [o["type"] for o in scene.obstacles] == [o["type"] for o in wall.obstacles]
    np.testing.assert_array_equal(scene.start, wall.start)
    np.testing.assert_array_equal(scene.goal, wall.goal)
    assert scene.to_dict()["meta"]["object_ids"] == ["table", "wall", "can", "ball"]
    assert edmp.plan(scene, seed=0).success
    posed = edmp.import_moveit(
        (MOVEIT / "table_box.scene.yaml").read_text(), (MOVEIT / "pose_goal.request.yaml").read_text()
    )
    assert isinstance(posed.goal, edmp.Pose)
    np.testing.assert_allclose(posed.goal.position, [0.48748365, -0.3335055, 0.25502735], atol=1e-6)
    alone = edmp.import_moveit(MOVEIT / "table_box.scene.yaml")
    np.testing.assert_array_equal(alone.goal, alone.start)


def test_moveit_scene_of_another_arm_names_its_arm() -> None:
    names = edmp.joint_names("xarm6")
    start, goal = [0.0, -0.5, -0.8, 0.0, 1.3, 0.0], [0.5, -0.5, -0.8, 0.0, 1.3, 0.0]
    scene_yaml = f"robot_state:\n  joint_state:\n    name: [{', '.join(names)}]\n    position: {start}\n"
    goals = "".join(f"  - {{joint_name: {n}, position: {x}}}\n" for n, x in zip(names, goal))
    request_yaml = f"group_name: xarm6\ngoal_constraints:\n- joint_constraints:\n{goals}"
    scene = edmp.import_moveit(scene_yaml, request_yaml)
    assert scene.robot == "xarm6"
    np.testing.assert_allclose(scene.start, start)
    with pytest.raises(edmp.SceneError, match="group_name"):
        edmp.import_moveit(scene_yaml, request_yaml.replace("xarm6", "panda_arm"))


def test_moveit_meshes_become_mesh_obstacles() -> None:
    scene = edmp.import_moveit(MOVEIT / "mesh.scene.yaml", MOVEIT / "joint_goal.request.yaml")
    assert [o["type"] for o in scene.obstacles].count("mesh") == 1


def test_cloud_files_are_read_beside_the_scene_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    doc = json.loads((ROOT / "examples" / "wall.json").read_text())
    points = np.array([[1.5, y, z] for y in (-0.1, 0.0, 0.1) for z in (0.2, 0.3)], dtype="<f4")
    header = f"ply\nformat binary_little_endian 1.0\nelement vertex {len(points)}\n"
    header += "property float x\nproperty float y\nproperty float z\nend_header\n"
    (tmp_path / "far.ply").write_bytes(header.encode() + points.tobytes())
    doc["obstacles"].append({"type": "points", "file": "far.ply", "radius": 0.01})
    (tmp_path / "scene.json").write_text(json.dumps(doc))
    monkeypatch.chdir(ROOT)
    scene = edmp.Scene.from_file(tmp_path / "scene.json")
    assert edmp.plan(scene, seed=0).status == "success"


def test_the_gripper_opening_is_part_of_the_problem() -> None:
    # Fingers open to 0.04 m around a can: the grasp plans; at the default 0.025 m the open
    # grasp pose puts a finger into the can, so no collision-free IK goal exists.
    grasp = json.loads((ROOT / "examples" / "grasp-can.json").read_text())
    p = edmp.plan(edmp.Scene.from_dict(grasp), seed=0)
    assert p.status == "success"
    q = p.waypoints[-1]
    assert edmp.check(edmp.Scene.from_dict({**grasp, "goal": {"joints": q.tolist()}}), p.waypoints)
    closed = {k: v for k, v in grasp.items() if k != "gripper"}
    # The same joint goal with the fingers at 0.025 m touches the can: refused as input.
    with pytest.raises(edmp.SceneError, match="collision"):
        edmp.Scene.from_dict({**closed, "goal": {"joints": q.tolist()}})
    with pytest.raises(edmp.PlanError, match="unreachable"):
        edmp.plan(edmp.Scene.from_dict(closed), seed=0)
    with pytest.raises(edmp.SceneError, match=r"gripper\.finger"):
        edmp.Scene.from_dict({**grasp, "gripper": {"finger": 0.05}})


def _page_data(page: str) -> dict:
    """The JSON the viewer page embeds (poses, meshes, paths, report)."""
    start = page.index('<script type="application/json" id="edmp-data">')
    start = page.index(">", start) + 1
    return json.loads(page[start : page.index("</script>", start)])


def test_show_writes_the_viewer_page_and_opens_it(
    wall: edmp.Scene, wall_plan: edmp.Plan, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    opened: list[str] = []
    monkeypatch.setattr("webbrowser.open", lambda url: opened.append(url) or True)
    monkeypatch.setattr(edmp, "_in_notebook", lambda: False)
    target = tmp_path / "plan.html"
    assert edmp.show(wall, wall_plan, path=target) == target.resolve()
    assert opened == [target.resolve().as_uri()]
    page = target.read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and "<script src" not in page
    data = _page_data(page)
    # Untimed: one sample per waypoint, the first at the start; every candidate's TCP path.
    assert len(data["samples"]["times"]) == 50
    np.testing.assert_allclose(data["samples"]["tcp"][0], edmp.fk(wall.start)["tcp"]["position"], atol=1e-5)
    assert len(data["candidates"]) == len(wall_plan.candidates or [])
    assert data["info"]["status"] == "success"
    # A scene alone: the arm at the start, written to a temporary file.
    alone = edmp.show(wall)
    assert opened[-1] == alone.as_uri() and len(_page_data(alone.read_text())["samples"]["times"]) == 1
    alone.unlink()


def test_show_names_the_bad_plan_field(wall: edmp.Scene, wall_plan: edmp.Plan, tmp_path: Path) -> None:
    doc = dict(wall_plan.document)
    doc["waypoints"] = [list(w) for w in doc["waypoints"]]
    doc["waypoints"][1] = doc["waypoints"][1][:6]
    with pytest.raises(ValueError, match=r"plan: waypoints\[1\]: expected 7 numbers, found 6"):
        edmp.show(wall, doc, path=tmp_path / "bad.html")
    assert not (tmp_path / "bad.html").exists()


def test_show_returns_an_inline_page_in_jupyter(
    wall: edmp.Scene, wall_plan: edmp.Plan, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("IPython")
    monkeypatch.setattr(edmp, "_in_notebook", lambda: True)
    shown = edmp.show(wall, wall_plan)
    assert type(shown).__name__ == "HTML" and shown.data.startswith("<div><iframe srcdoc=")
    assert "edmp-data" in shown.data and "<script" not in shown.data  # the page is escaped


@pytest.mark.skipif(HOST is None, reason="EDMP_HOST (the edmp-host binary) not set")
def test_show_draws_what_the_cli_view_draws(
    wall: edmp.Scene, wall_plan: edmp.Plan, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("webbrowser.open", lambda url: True)
    monkeypatch.setattr(edmp, "_in_notebook", lambda: False)
    plan_file = tmp_path / "plan.json"
    plan_file.write_text(json.dumps(wall_plan.document))
    cli = tmp_path / "cli.html"
    subprocess.run([HOST, "view", str(WALL), str(plan_file), "-o", str(cli)], check=True)
    ours = _page_data(edmp.show(wall, wall_plan, path=tmp_path / "py.html").read_text())
    theirs = _page_data(cli.read_text())
    assert ours.pop("title") == "edmp plan" and theirs.pop("title") == "wall.json — plan.json"
    assert ours == theirs


# Point clouds, meshes and depth images: the wall of examples/wall.json (obstacles[1], a
# 0.3 × 0.02 × 0.5 m box at (0.55, 0, 0.45)) given as a cloud or a mesh instead.


def _without_the_wall(wall: edmp.Scene) -> edmp.Scene:
    doc = wall.to_dict()
    del doc["obstacles"][1]
    return edmp.Scene.from_dict(doc)


def _wall_points(spacing: float = 0.01) -> np.ndarray:
    """The wall's mid-plane y = 0 as a grid of points (x in [0.4, 0.7], z in [0.2, 0.7])."""
    x, z = np.meshgrid(np.arange(0.4, 0.7 + 1e-9, spacing), np.arange(0.2, 0.7 + 1e-9, spacing))
    return np.stack([x.ravel(), np.zeros(x.size), z.ravel()], axis=1)


def _straight(scene: edmp.Scene) -> np.ndarray:
    """The straight joint-space motion from start to goal, as 50 waypoints."""
    return np.linspace(scene.start, scene.goal, 50)


def _blocks_the_straight_motion_and_plans_around(scene: edmp.Scene, index: int) -> None:
    report = edmp.check(scene, _straight(scene))
    assert not report and report.first_contact is not None
    assert f"obstacles[{index}]" in report.first_contact["contact"]
    p = edmp.plan(scene, seed=0)
    assert p.status == "success"
    assert edmp.check(scene, p.waypoints)


def test_a_wall_of_points_blocks_the_straight_motion_and_is_planned_around(wall: edmp.Scene) -> None:
    open_scene = _without_the_wall(wall)
    assert edmp.check(open_scene, _straight(open_scene))  # the wall's box was the obstacle
    points = _wall_points()
    scene = open_scene.add_points(points, radius=0.0075)
    assert isinstance(scene, edmp.Scene) and len(open_scene.obstacles) == 3  # a new scene
    added = scene.obstacles[-1]
    assert added["type"] == "points" and added["radius"] == 0.0075 and "filter_robot" not in added
    np.testing.assert_array_equal(added["points"], points)
    assert edmp.Scene.from_json(scene.to_json()).to_dict() == scene.to_dict()
    _blocks_the_straight_motion_and_plans_around(scene, 3)


def test_filter_robot_drops_the_points_on_the_arm(wall: edmp.Scene) -> None:
    # The wall and, as a camera that sees the arm would have it, points on the arm at the start.
    on_arm = [f["position"] for f in edmp.fk(wall.start)["frames"][3:10]]  # panda_link3 .. panda_hand
    cloud = np.vstack([_wall_points(0.02), on_arm])
    with pytest.raises(edmp.SceneError, match=r"start: in collision: .*obstacles\[3\]"):
        _without_the_wall(wall).add_points(cloud, radius=0.0075)
    scene = _without_the_wall(wall).add_points(cloud, radius=0.0075, filter_robot=0.01)
    assert scene.obstacles[-1]["filter_robot"] == 0.01
    assert not edmp.check(scene, _straight(scene))


def test_a_box_mesh_blocks_the_straight_motion_and_is_planned_around(wall: edmp.Scene) -> None:
    corners = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    # Two triangles per face of the unit cube (vertex index = 4x + 2y + z, each 0 or 1).
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    triangles = np.array([t for a, b, c, d in faces for t in ((a, b, c), (a, c, d))], dtype=np.int32)
    scene = _without_the_wall(wall).add_mesh(
        corners, triangles, center=[0.55, 0.0, 0.45], quaternion=[1, 0, 0, 0], scale=[0.3, 0.02, 0.5]
    )
    added = scene.obstacles[-1]
    assert added["type"] == "mesh" and added["scale"] == [0.3, 0.02, 0.5] and len(added["triangles"]) == 12
    _blocks_the_straight_motion_and_plans_around(scene, 3)
    # Placed by hand instead: the same obstacle.
    placed = _without_the_wall(wall).add_mesh(corners * [0.3, 0.02, 0.5] + [0.55, 0.0, 0.45], triangles)
    assert not edmp.check(placed, _straight(placed))
    assert _without_the_wall(wall).add_mesh(corners, triangles, scale=0.01).obstacles[-1]["scale"] == 0.01


def test_bad_clouds_and_meshes_are_value_errors_naming_the_argument(wall: edmp.Scene) -> None:
    ok = _wall_points(0.05)
    cube = np.eye(3)
    tri = np.array([[0, 1, 2]])
    infinite = cube.copy()
    infinite[1, 2] = np.inf
    bad = ok.copy()
    bad[3, 1] = np.nan
    cases = [
        (lambda: wall.add_points(ok[:, :2], 0.01), r"points: expected shape \(N, 3\), found \(77, 2\)"),
        (lambda: wall.add_points(ok.ravel(), 0.01), r"points: expected shape \(N, 3\)"),
        (lambda: wall.add_points(bad, 0.01), r"points\[3\]: \[.*nan.*\] is not finite"),
        (lambda: wall.add_points([["a", "b", "c"]], 0.01), "points: not an array of numbers"),
        (lambda: wall.add_points(ok, 0.0), "radius: 0.0 is not positive"),
        (lambda: wall.add_points(ok, float("inf")), "radius"),
        (lambda: wall.add_points(ok, 0.01, filter_robot=-1), "filter_robot: -1.0 is not non-negative"),
        (lambda: wall.add_mesh(cube[:, :2], tri), r"vertices: expected shape \(N, 3\)"),
        (lambda: wall.add_mesh(infinite, tri), r"vertices\[1\]: \[0.0, 1.0, inf\] is not finite"),
        (lambda: wall.add_mesh(cube, tri.astype(float)), "triangles: expected integer vertex indices"),
        (lambda: wall.add_mesh(cube, [[0, 1, 2], [1, 2, 3]]), r"triangles\[1\]: \[1, 2, 3\]: a vertex index outside"),
        (lambda: wall.add_mesh(cube, [[0, -1, 2]]), r"triangles\[0\]"),
        (lambda: wall.add_mesh(cube, [0, 1, 2]), r"triangles: expected shape \(T, 3\)"),
        (lambda: wall.add_mesh(cube, tri, center=[0, 0]), r"center: expected shape \(3,\)"),
        (lambda: wall.add_mesh(cube, tri, center=[0, np.nan, 0]), "center: .* is not finite"),
        (lambda: wall.add_mesh(cube, tri, quaternion=[1, 0, 0]), "quaternion"),
        (lambda: wall.add_mesh(cube, tri, scale=[1, 0, 1]), "scale: 0.0 is not positive"),
        (lambda: wall.add_mesh(cube, tri, scale=[1, 1]), r"scale: expected a number or shape \(3,\)"),
    ]
    for call, message in cases:
        with pytest.raises(ValueError, match=message):
            call()
    # What only the scene reader knows is a SceneError naming the JSON path.
    with pytest.raises(edmp.SceneError, match=r"obstacles\[4\]\.quaternion: norm"):
        wall.add_mesh(cube, tri, quaternion=[1, 1, 0, 0])
    assert len(wall.obstacles) == 4  # nothing was added


# A pinhole camera: 100 px per metre at 1 m, principal point at the centre of a 64 × 48 image.
K = np.array([[100.0, 0.0, 31.5], [0.0, 100.0, 23.5], [0.0, 0.0, 1.0]])


def test_points_from_depth_of_a_plane_in_the_camera_frame() -> None:
    depth = np.ones((48, 64), dtype=np.float32)
    pts = edmp.points_from_depth(depth, K, np.eye(4))
    assert pts.shape == (64 * 48, 3) and pts.dtype == np.float64
    np.testing.assert_array_equal(pts[:, 2], 1.0)
    u, v = np.meshgrid(np.arange(64), np.arange(48))  # row-major: v is the row
    np.testing.assert_allclose(pts[:, 0], (u.ravel() - 31.5) / 100.0, atol=1e-7)
    np.testing.assert_allclose(pts[:, 1], (v.ravel() - 23.5) / 100.0, atol=1e-7)
    # No return (0, NaN, inf) and beyond max_depth: dropped. Depth scales the ray.
    depth[0, 0], depth[0, 1], depth[0, 2], depth[1, 0] = 0.0, np.nan, np.inf, 2.0
    assert len(edmp.points_from_depth(depth, K, np.eye(4))) == 64 * 48 - 3
    near = edmp.points_from_depth(depth, K, np.eye(4), max_depth=1.5)
    assert len(near) == 64 * 48 - 4 and near[:, 2].max() == 1.0
    far = edmp.points_from_depth(depth.astype(np.float64), K, np.eye(4))[61]  # pixel (0, 1)
    np.testing.assert_allclose(far, [2.0 * -31.5 / 100, 2.0 * -22.5 / 100, 2.0], atol=1e-6)


def _rotation(w: float, x: float, y: float, z: float) -> np.ndarray:
    q = np.array([w, x, y, z]) / np.linalg.norm([w, x, y, z])
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def test_points_from_depth_with_a_rotated_translated_camera() -> None:
    # Looking down from 1.5 m (camera z = world −z, camera x = world x, so image down = world −y).
    down = np.array([[1.0, 0, 0, 0.5], [0, -1.0, 0, 0.0], [0, 0, -1.0, 1.5], [0, 0, 0, 1]])
    pts = edmp.points_from_depth(np.full((48, 64), 1.5), K, down)
    np.testing.assert_allclose(pts[:, 2], 0.0, atol=1e-6)  # the table at z = 0
    np.testing.assert_allclose(pts[0], [0.5 - 1.5 * 0.315, 1.5 * 0.235, 0.0], atol=1e-6)
    # Any pose: R · d · K⁻¹ · [u, v, 1] + t.
    rng = np.random.default_rng(0)
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = _rotation(0.3, -0.5, 0.7, 0.2), [0.1, -0.4, 0.9]
    depth = rng.uniform(0.3, 2.0, (48, 64))
    u, v = np.meshgrid(np.arange(64), np.arange(48))
    rays = np.linalg.inv(K) @ np.stack([u.ravel(), v.ravel(), np.ones(u.size)])
    expected = (pose[:3, :3] @ (rays * depth.ravel()) + pose[:3, 3:]).T
    np.testing.assert_allclose(edmp.points_from_depth(depth, K, pose), expected, atol=1e-5)


def test_points_from_depth_names_the_bad_argument() -> None:
    ok = np.ones((4, 5))
    skewed = np.eye(4)
    skewed[0, 1] = 0.01
    cases = [
        (lambda: edmp.points_from_depth(np.ones(20), K, np.eye(4)), r"depth: expected an \(H, W\) image"),
        (lambda: edmp.points_from_depth(ok.astype(np.uint16), K, np.eye(4)), "depth: expected float metres"),
        (lambda: edmp.points_from_depth(ok, K[:2], np.eye(4)), r"K: expected shape \(3, 3\)"),
        (lambda: edmp.points_from_depth(ok, np.diag([0.0, 100.0, 1.0]), np.eye(4)), "K: focal lengths"),
        (lambda: edmp.points_from_depth(ok, K * np.nan, np.eye(4)), "K: not finite"),
        (lambda: edmp.points_from_depth(ok, K, np.eye(3)), r"pose: expected shape \(4, 4\)"),
        (lambda: edmp.points_from_depth(ok, K, skewed), "pose: the rotation .* is not orthonormal"),
        (lambda: edmp.points_from_depth(ok, K, np.diag([1.0, 1.0, -1.0, 1.0])), "pose: .* reflection"),
        (lambda: edmp.points_from_depth(ok, K, np.eye(4), max_depth=0.0), "max_depth"),
    ]
    for call, message in cases:
        with pytest.raises(ValueError, match=message):
            call()


def test_a_depth_image_of_the_wall_plans_like_the_wall(wall: edmp.Scene) -> None:
    # The docs/python.md example: a camera 1 m in front of the wall's plane, looking along +y
    # (camera x = world x, y = world −z, z = world y); the wall at 1 m, the room behind at 3 m.
    k = np.array([[100.0, 0.0, 32.0], [0.0, 100.0, 32.0], [0.0, 0.0, 1.0]])
    pose = np.array([[1.0, 0, 0, 0.55], [0, 0, 1.0, -1.0], [0, -1.0, 0, 0.45], [0, 0, 0, 1]])
    u, v = np.meshgrid(np.arange(64), np.arange(64))
    on_wall = (np.abs(u - 32) <= 15) & (np.abs(v - 32) <= 25)
    depth = np.where(on_wall, 1.0, 3.0).astype(np.float32)
    points = edmp.points_from_depth(depth, k, pose, max_depth=2.0)
    assert points.shape == (31 * 51, 3)
    rows = [np.round(p, 6) for p in (points, _wall_points())]
    np.testing.assert_allclose(*(r[np.lexsort(r.T)] for r in rows), atol=1e-6)
    scene = _without_the_wall(wall).add_points(points, radius=0.0075)
    _blocks_the_straight_motion_and_plans_around(scene, 3)


@pytest.mark.parametrize("robot, joints", [("xarm6", 6), ("iiwa7", 7)])
def test_another_arms_scene_plans_with_its_joints_and_is_the_cli_document(robot: str, joints: int) -> None:
    path = ROOT / "benchmarks" / robot / "problems" / "tabletop" / "000.json"
    scene = edmp.Scene.from_file(path)
    assert scene.robot == robot and scene.start.shape == (joints,)
    p = edmp.plan(scene, seed=0, timed=True)
    assert p.success and p.waypoints.shape == (50, joints)
    np.testing.assert_allclose(p.waypoints[0], scene.start, atol=1e-6)
    np.testing.assert_allclose(p.waypoints[-1], scene.goal, atol=1e-6)
    assert p.trajectory is not None and p.trajectory["positions"].shape[1] == joints
    assert len(p.trajectory["joint_names"]) == joints
    if HOST:
        out = subprocess.run([HOST, "plan", str(path), "--timed"], check=True, capture_output=True, text=True)
        cli = json.loads(out.stdout)
        ours = dict(p.document)
        for doc in (cli, ours):
            doc.pop("timing_ms")
        assert ours == cli
    bad = scene.to_dict()
    bad["start"] = bad["start"] + [0.0]
    with pytest.raises(edmp.SceneError, match=f"start: expected {joints} numbers, found {joints + 1}"):
        edmp.Scene.from_dict(bad)
    report = edmp.check(scene, p.waypoints)
    assert report and report.colliding_states == 0
    straight = np.linspace(scene.start, scene.goal, 50)
    assert edmp.check(scene, straight).states >= 50
    with pytest.raises(ValueError, match=rf"waypoints\[0\]: expected {joints} joint angles, found {joints + 1}"):
        edmp.check(scene, np.hstack([p.waypoints, np.zeros((50, 1))]))
    pose = scene.to_dict()["meta"]["goal_pose"]
    q = edmp.ik(scene, pose["position"], pose["quaternion"])
    assert q is not None and q.shape == (joints,)
