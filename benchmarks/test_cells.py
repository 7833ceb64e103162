"""Checks of the point-cloud and mesh generators of benchmarks/cells.py:

    python3 -m pytest benchmarks/test_cells.py -q
"""

from __future__ import annotations

import json
import math
import pathlib
import sys

import numpy as np
import pytest

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import cells  # noqa: E402
import judge  # noqa: E402

TURN = [math.cos(0.3), math.sin(0.3) * 0.6, math.sin(0.3) * 0.8, 0.0]  # a unit quaternion, 0.6 rad about (0.6, 0.8, 0)
PRIMITIVES = [
    {"type": "cuboid", "center": [0.5, -0.1, 0.3], "dims": [0.23, 0.051, 0.4], "quaternion": TURN},
    {"type": "cylinder", "center": [0.4, 0.3, 0.2], "radius": 0.043, "height": 0.17, "quaternion": TURN},
    {"type": "sphere", "center": [0.6, 0.2, 0.5], "radius": 0.061},
]


def local(o: dict, world: np.ndarray) -> np.ndarray:
    """World points in the primitive's own frame."""
    return (world - o["center"]) @ judge.rotation(o.get("quaternion", cells.IDENTITY))


def surface_error(o: dict, q: np.ndarray) -> np.ndarray:
    """Distance of local points from the primitive's surface."""
    if o["type"] == "cuboid":
        half = np.asarray(o["dims"]) / 2
        outside = np.maximum(np.abs(q) - half, 0)
        inside = np.min(half - np.abs(q), axis=1)
        return np.where(np.any(outside > 0, axis=1), np.linalg.norm(outside, axis=1), inside)
    if o["type"] == "cylinder":
        rho, z = np.hypot(q[:, 0], q[:, 1]), np.abs(q[:, 2])
        dr, dz = rho - o["radius"], z - o["height"] / 2
        return np.where((dr > 0) | (dz > 0), np.hypot(np.maximum(dr, 0), np.maximum(dz, 0)), np.minimum(-dr, -dz))
    return np.abs(np.linalg.norm(q, axis=1) - o["radius"])


def random_surface(o: dict, n: int, rng: np.random.Generator) -> np.ndarray:
    """Uniform-ish random points on the primitive's surface, local frame."""
    if o["type"] == "cuboid":
        half = np.asarray(o["dims"]) / 2
        q = rng.uniform(-half, half, (n, 3))
        axis = rng.integers(0, 3, n)
        q[np.arange(n), axis] = half[axis] * rng.choice([-1, 1], n)
        return q
    if o["type"] == "cylinder":
        t = rng.uniform(0, 2 * math.pi, n)
        side = np.stack([o["radius"] * np.cos(t), o["radius"] * np.sin(t), rng.uniform(-0.5, 0.5, n) * o["height"]], 1)
        rho = o["radius"] * np.sqrt(rng.uniform(0, 1, n))
        cap = np.stack([rho * np.cos(t), rho * np.sin(t), rng.choice([-0.5, 0.5], n) * o["height"]], 1)
        return np.where(rng.uniform(size=(n, 1)) < 0.5, side, cap)
    v = rng.normal(size=(n, 3))
    return o["radius"] * v / np.linalg.norm(v, axis=1, keepdims=True)


@pytest.mark.parametrize("o", PRIMITIVES, ids=lambda o: o["type"])
def test_surface_points_lie_on_the_surface_and_cover_it(o, tmp_path):
    h = cells.SPACING
    points = cells.surface_points([o], h)
    path = tmp_path / "c.ply"
    cells.write_ply(path, points)
    read, faces = judge.read_ply(path)
    assert faces is None and read.shape == points.shape
    q = local(o, read)  # as written: float32
    assert np.max(surface_error(o, q)) < 1e-5
    # Every surface point is within h / sqrt 2 of a sample: the 7.5 mm balls cover the surface.
    probe = random_surface(o, 3000, np.random.default_rng(1))
    ql = local(o, points)
    nearest = np.array([np.min(np.linalg.norm(ql - x, axis=1)) for x in probe])
    assert nearest.max() <= h / math.sqrt(2) + 1e-9 < cells.RADIUS


def test_dense_sampling_reaches_its_target():
    target = 20_000
    h = cells.spacing_for(lambda s: sum(len(cells.surface_local(o, s)) for o in PRIMITIVES), target)
    assert h < cells.SPACING
    assert abs(len(cells.surface_points(PRIMITIVES, h)) - target) < 0.1 * target
    edge = cells.spacing_for(lambda e: sum(len(cells.mesh_local(o, e)[1]) for o in PRIMITIVES), 3000, 0.05)
    assert abs(len(cells.scene_mesh(PRIMITIVES, edge)[1]) - 3000) < 300


@pytest.mark.parametrize("edge", [None, 0.02])
@pytest.mark.parametrize("o", PRIMITIVES, ids=lambda o: o["type"])
def test_the_mesh_covers_the_primitive(o, edge, tmp_path):
    vertices, triangles = cells.scene_mesh([o], edge)
    path = tmp_path / "m.obj"
    cells.write_obj(path, vertices, triangles)
    v, f = judge.read_obj(path)
    assert np.allclose(v, vertices, atol=1e-6) and np.array_equal(f, triangles)
    if o["type"] == "cuboid" and edge is None:
        assert len(triangles) == 12 and len(vertices) == 8
    # The mesh is a closed convex polyhedron: every face plane has the whole true surface
    # (and the primitive) behind it.
    tri = v[f]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    normal *= np.sign(np.einsum("ij,ij->i", normal, tri[:, 0] - np.asarray(o["center"])))[:, None]
    surface = judge.placed(o, random_surface(o, 1000, np.random.default_rng(2)), scaled=False)
    height = np.einsum("fj,pfj->pf", normal, surface[:, None, :] - tri[None, :, 0, :])
    assert height.max() <= 1e-5  # the OBJ keeps 0.1 um; thin cells tilt their planes by a few um
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    _, counts = np.unique(np.sort(edges, axis=1), axis=0, return_counts=True)
    assert np.all(counts == 2)  # closed: every edge shared by two triangles


@pytest.fixture(scope="module")
def robot() -> judge.Robot:
    cells._init()
    return cells._ROBOT


def test_a_depth_camera_sees_a_known_box_within_the_noise(robot):
    box = {"type": "cuboid", "center": [0.65, -0.2, 0.15], "dims": [0.3, 0.2, 0.3], "quaternion": [math.cos(0.2), 0, 0, math.sin(0.2)]}
    robot.finger = judge.FINGER_OPENING
    judge.set_state(robot, np.asarray(cells.PANDA_READY))
    body = cells.visual(robot, box)
    try:
        points, is_robot = cells.depth_cloud(robot, cells.CAMERAS[0], np.random.default_rng(0))
        quiet, quiet_robot = cells.depth_cloud(robot, cells.CAMERAS[0], np.random.default_rng(0), noise=0.0)
    finally:
        judge.p.removeBody(body, physicsClientId=robot.client)
    assert is_robot.sum() > 1000  # the arm is in view
    seen = points[~is_robot]
    assert len(seen) > 5000
    error = np.abs(surface_error(box, local(box, seen)))
    # Gaussian noise of 1.5 mm along the ray: nearly all within 4 sigma, the worst within 7.
    assert np.mean(error < 4 * cells.NOISE) > 0.99
    assert error.max() < 7 * cells.NOISE + 1e-3
    assert np.percentile(np.abs(surface_error(box, local(box, quiet[~quiet_robot]))), 95) < 1e-5


def test_a_rendered_scene_has_the_robot_and_the_filter_removes_it(robot):
    scene = json.loads((HERE / "judge" / "cubby_003.json").read_text())
    points, near, info = cells.render_scene(robot, scene, np.random.default_rng(0))
    assert len(points) == info["points"] == len(near) > 20_000
    assert info["robot_points"] > 1000 and info["robot_points_kept_by_filter"] == 0
    assert [c["points"] > 0 for c in info["cameras"]] == [True] * len(cells.CAMERAS)
    # One point per 5 mm voxel.
    keys = np.floor(points / cells.VOXEL)
    assert len(np.unique(keys, axis=0)) >= 0.9 * len(points)
