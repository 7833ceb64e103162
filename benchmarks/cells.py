"""Point-cloud and mesh test sets (issue 33), made from the committed suites and judged against
the true geometry.

Every problem of benchmarks/problems (tabletop, cubby, merged_cubby, dresser) and
benchmarks/unseen (bookshelf, cage, under_table, window_box), or the first K of each family
(`--per-family K`), becomes one scene per set, written as `<out>/<set>/<family>/<NNN>.json`
(`edmp-scene/1`, the source's start, goal, gripper and held object) next to its geometry file:

- `surface`: every primitive's surface sampled at spacing <= 1 cm (cuboid faces as grids,
  cylinder sides and caps as rings, spheres as latitude rings): one `points` obstacle, radius
  7.5 mm (> 1 cm / sqrt 2, so the balls cover the surface), binary little-endian PLY `NNN.ply`.
- `depth`: the scene and the Panda at `start` (pybullet_data's URDF, visual meshes) seen by 4
  simulated depth cameras (PyBullet ER_TINY_RENDERER, 640 x 480, 60 degree vertical field of
  view, near 0.1 m, far 4 m): the depth buffer turned into metric depth, gaussian noise of
  sigma 1.5 mm along each ray (seeded), pixels at the far plane or beyond 3 m dropped, points
  back-projected to the world, the 4 clouds merged and voxel-downsampled to one centroid per
  5 mm voxel. One `points` obstacle, radius 7.5 mm, `filter_robot` 0.02 m (noise 3 sigma
  4.5 mm + voxel centroid shift + the visual meshes against the collision hulls; `meta` counts
  the robot's points that survive this filter, which must be 0). `meta.cameras` gives each
  camera's pose and point count.
- `mesh`: the primitives merged into one OBJ `NNN.obj`, one `mesh` obstacle: cuboids as 12
  triangles, cylinders as 32-gon prisms whose polygon circumscribes the circle, spheres as
  icospheres (2 subdivisions) scaled so their faces circumscribe the sphere. The mesh covers
  the primitives.
- `surface_dense`, `mesh_dense`: the speed targets, the same as `surface` and `mesh` with
  about `--points` (default 200,000) points and `--triangles` (default 10,000) triangles per
  scene (finer sampling; faces subdivided into grids).
- `real`: scenes of pybullet_data meshes (`real/<kiva|table_tray>/NNN.json`, `--real N`
  problems, default 32): the Kiva pod (`kiva_shelf/meshes/pod_lowres.stl`, copied) with goals
  reaching into its bins, and pybullet_data's table (its URDF's five scaled `table.obj`
  boxes, written as one OBJ) with the tray (`tray/tray_textured4.obj`, copied, scale 0.5) on
  it, goals above and inside the tray. Start and goal are PyBullet IK solutions checked on the
  exact meshes: every robot body at least `--real-clearance` (default 5 mm) from the
  obstacles and 2.02 mm from the other robot bodies, within the joint limits.

`meta` records `set`, `source` (the problem's path in the repository), the source's own `meta`
(`source_meta`), `truth` (what the judge compares against) and, for the sets made from
primitives, `truth_obstacles`: the source problem's primitives, which benchmarks/judge.py then
uses instead of `obstacles`. `real` scenes have no `truth_obstacles`: their mesh is the truth.
`meta.end_clearance_m` gives, for `start` and `goal`, the smallest PyBullet distance between
the robot (links 1-7, hand, fingers) and the scene's own obstacle as a planner sees it (after
`filter_robot`), null beyond 5 cm: a negative value means the representation itself covers that
end (a cloud's balls reach 7.5 mm beyond the true surface).

Usage (from the repository root):
    python3 -m pip install -r benchmarks/requirements.txt
    python3 benchmarks/cells.py                                  # surface, depth, mesh, real
    python3 benchmarks/cells.py --sets surface_dense mesh_dense --per-family 10
    python3 benchmarks/judge.py --problems bench-out/cells/surface --results RUN/results.jsonl
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import os
import pathlib
import shutil
import sys
import time
import zlib
from typing import Any

import numpy as np
from tqdm import tqdm

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import judge  # noqa: E402  (its robot, readers, placement and obstacle bodies)

p = judge.p
ROOT = judge.ROOT
SUITES = [ROOT / "benchmarks" / "problems", ROOT / "benchmarks" / "unseen"]
SETS = ["surface", "depth", "mesh", "real", "surface_dense", "mesh_dense"]
DEFAULT_SETS = ["surface", "depth", "mesh", "real"]
SPACING = 0.01
RADIUS = 0.0075
CYLINDER_SIDES = 32
SPHERE_LEVEL = 2
NOISE = 0.0015
VOXEL = 0.005
FILTER_ROBOT = 0.02
MAX_RANGE = 3.0
NEAR, FAR, FOV, WIDTH, HEIGHT = 0.1, 4.0, 60.0, 640, 480
CAMERAS = [  # name, eye, target: around the workspace, all seeing the robot
    ("shoulder", [-0.45, 0.0, 1.25], [0.6, 0.0, 0.3]),
    ("left", [0.5, 1.5, 0.9], [0.55, 0.0, 0.3]),
    ("right", [0.5, -1.5, 0.9], [0.55, 0.0, 0.3]),
    ("front", [1.8, 0.3, 1.4], [0.55, 0.0, 0.3]),
]
END_WITHIN = 0.05
IDENTITY = [1.0, 0.0, 0.0, 0.0]


# ---- surfaces ------------------------------------------------------------------------------


def grid(a: float, h: float) -> np.ndarray:
    """Points from -a/2 to a/2, both included, at most h apart."""
    return np.linspace(-a / 2, a / 2, max(1, math.ceil(a / h - 1e-9)) + 1)


def rings(r: float, h: float) -> np.ndarray:
    """A disc of radius r in the z = 0 plane: concentric rings <= h apart, points on each <= h
    apart along the arc, the centre included."""
    out = [np.zeros((1, 3))]
    m = max(1, math.ceil(r / h - 1e-9))
    for i in range(1, m + 1):
        rho = r * i / m
        n = max(3, math.ceil(2 * math.pi * rho / h - 1e-9))
        t = 2 * math.pi * np.arange(n) / n
        out.append(np.stack([rho * np.cos(t), rho * np.sin(t), np.zeros(n)], axis=1))
    return np.concatenate(out)


def surface_local(o: dict[str, Any], h: float) -> np.ndarray:
    """Points on a primitive's surface in its own frame, neighbours at most h apart."""
    if o["type"] == "cuboid":
        dims = o["dims"]
        faces = []
        for axis in range(3):
            u, v = [a for a in range(3) if a != axis]
            gu, gv = np.meshgrid(grid(dims[u], h), grid(dims[v], h), indexing="ij")
            for sign in (-1, 1):
                f = np.zeros((gu.size, 3))
                f[:, u], f[:, v], f[:, axis] = gu.ravel(), gv.ravel(), sign * dims[axis] / 2
                faces.append(f)
        return np.concatenate(faces)
    if o["type"] == "cylinder":
        r, height = o["radius"], o["height"]
        n = max(3, math.ceil(2 * math.pi * r / h - 1e-9))
        t = 2 * math.pi * np.arange(n) / n
        zs = grid(height, h)
        side = np.stack([np.tile(r * np.cos(t), len(zs)), np.tile(r * np.sin(t), len(zs)), np.repeat(zs, n)], axis=1)
        cap = rings(r, h)
        return np.concatenate([side, cap + [0, 0, height / 2], cap - [0, 0, height / 2]])
    if o["type"] == "sphere":
        r = o["radius"]
        m = max(2, math.ceil(math.pi * r / h - 1e-9))
        out = []
        for i in range(m + 1):
            phi = math.pi * i / m
            n = max(1, math.ceil(2 * math.pi * r * math.sin(phi) / h - 1e-9))
            t = 2 * math.pi * np.arange(n) / n
            out.append(np.stack([r * math.sin(phi) * np.cos(t), r * math.sin(phi) * np.sin(t), np.full(n, r * math.cos(phi))], axis=1))
        return np.concatenate(out)
    raise ValueError(f"unknown primitive type {o['type']!r}")


def surface_points(obstacles: list[dict[str, Any]], h: float) -> np.ndarray:
    """Every primitive's surface points in the world frame, duplicates (shared edges) merged."""
    pts = np.concatenate([judge.placed(o, surface_local(o, h), scaled=False) for o in obstacles])
    return np.unique(np.round(pts, 7), axis=0)


def spacing_for(count: Any, target: int, h0: float = SPACING) -> float:
    """The sampling spacing (or edge length) whose count(h) is closest to target, by bisection
    on log h (count falls as h grows)."""
    lo, hi = h0 / 100, h0 * 10
    for _ in range(24):
        mid = math.sqrt(lo * hi)
        if count(mid) > target:
            lo = mid
        else:
            hi = mid
    return min((lo, hi), key=lambda h: abs(count(h) - target))


# ---- meshes --------------------------------------------------------------------------------


def icosphere(level: int) -> tuple[np.ndarray, np.ndarray]:
    t = (1 + math.sqrt(5)) / 2
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
         [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]  # fmt: skip
    vertices = [np.asarray(x, dtype=np.float64) / np.linalg.norm(x) for x in v]
    faces = f
    for _ in range(level):
        middle: dict[tuple[int, int], int] = {}

        def mid(a: int, b: int) -> int:
            key = (min(a, b), max(a, b))
            if key not in middle:
                m = vertices[a] + vertices[b]
                vertices.append(m / np.linalg.norm(m))
                middle[key] = len(vertices) - 1
            return middle[key]

        faces = [g for a, b, c in faces for g in ([a, mid(a, b), mid(a, c)], [b, mid(b, c), mid(a, b)], [c, mid(a, c), mid(b, c)], [mid(a, b), mid(b, c), mid(a, c)])]
    return np.array(vertices), np.array(faces, dtype=np.int64)


def quad_grid(origin: np.ndarray, du: np.ndarray, dv: np.ndarray, nu: int, nv: int) -> tuple[np.ndarray, np.ndarray]:
    """A parallelogram origin + s du + t dv (s, t in [0, 1]) as nu x nv cells, 2 triangles each."""
    s, t = np.meshgrid(np.linspace(0, 1, nu + 1), np.linspace(0, 1, nv + 1), indexing="ij")
    v = origin + s.reshape(-1, 1) * du + t.reshape(-1, 1) * dv
    i = np.arange(nu)[:, None] * (nv + 1) + np.arange(nv)[None, :]
    i = i.ravel()
    f = np.concatenate([np.stack([i, i + nv + 1, i + nv + 2], 1), np.stack([i, i + nv + 2, i + 1], 1)])
    return v, f


def merge(parts: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """One mesh from several; coincident vertices (to 1 nm) shared."""
    vs, fs, n = [], [], 0
    for v, f in parts:
        vs.append(v)
        fs.append(f + n)
        n += len(v)
    v, f = np.concatenate(vs), np.concatenate(fs)
    v, inverse = np.unique(np.round(v, 9), axis=0, return_inverse=True)
    return v, inverse.reshape(-1)[f]


def mesh_local(o: dict[str, Any], edge: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """A primitive as a closed triangle mesh in its own frame that contains it; with `edge`,
    faces are split into cells at most about `edge` long."""
    cells = (lambda a: max(1, math.ceil(a / edge - 1e-9))) if edge else (lambda a: 1)
    if o["type"] == "cuboid":
        d = np.asarray(o["dims"], dtype=np.float64)
        parts = []
        for axis in range(3):
            u, v = [a for a in range(3) if a != axis]
            for sign in (-1, 1):
                origin = np.zeros(3)
                origin[axis] = sign * d[axis] / 2
                origin[u], origin[v] = -d[u] / 2, -d[v] / 2
                du, dv = np.zeros(3), np.zeros(3)
                du[u], dv[v] = d[u], d[v]
                parts.append(quad_grid(origin, du, dv, cells(d[u]), cells(d[v])))
        return merge(parts)
    if o["type"] == "cylinder":
        r, height = o["radius"], o["height"]
        n = CYLINDER_SIDES
        if edge:
            n = max(n, math.ceil(2 * math.pi * r / edge))
        big = r / math.cos(math.pi / n)  # the polygon's corners: its sides touch the circle
        t = 2 * math.pi * np.arange(n + 1) / n
        corner = np.stack([big * np.cos(t), big * np.sin(t), np.zeros(n + 1)], 1)
        parts = []
        for k in range(n):
            parts.append(quad_grid(corner[k] - [0, 0, height / 2], corner[k + 1] - corner[k], np.array([0, 0, height]), 1, cells(height)))
            for z, flip in ((height / 2, False), (-height / 2, True)):  # caps: rings of triangles
                m = cells(big)
                tri_v = [np.array([0, 0, z])] + [corner[k] * (i / m) + [0, 0, z] for i in range(1, m + 1)] + [corner[k + 1] * (i / m) + [0, 0, z] for i in range(1, m + 1)]
                tri_f = []
                a = lambda i: 0 if i == 0 else i  # noqa: E731
                b = lambda i: 0 if i == 0 else m + i  # noqa: E731
                for i in range(m):
                    tri_f.append([a(i), a(i + 1), b(i + 1)])
                    if i:
                        tri_f.append([a(i), b(i + 1), b(i)])
                f = np.array(tri_f, dtype=np.int64)
                parts.append((np.array(tri_v), f[:, ::-1] if flip else f))
        return merge(parts)
    if o["type"] == "sphere":
        level = SPHERE_LEVEL
        while edge and 2 * math.pi * o["radius"] / (5 * 2**level) > edge:
            level += 1
        v, f = icosphere(level)
        tri = v[f]
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        inner = np.min(np.abs(np.einsum("ij,ij->i", normal / np.linalg.norm(normal, axis=1, keepdims=True), tri[:, 0])))
        return v * (o["radius"] / inner), f
    raise ValueError(f"unknown primitive type {o['type']!r}")


def scene_mesh(obstacles: list[dict[str, Any]], edge: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    return merge([(judge.placed(o, v, scaled=False), f) for o in obstacles for v, f in [mesh_local(o, edge)]])


# ---- files ---------------------------------------------------------------------------------


def write_ply(path: pathlib.Path, points: np.ndarray) -> None:
    header = f"ply\nformat binary_little_endian 1.0\ncomment edmp-rs benchmarks/cells.py\nelement vertex {len(points)}\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
    path.write_bytes(header.encode("ascii") + np.ascontiguousarray(points, dtype="<f4").tobytes())


def write_obj(path: pathlib.Path, vertices: np.ndarray, triangles: np.ndarray) -> None:
    lines = ["# edmp-rs benchmarks/cells.py"]
    lines += [f"v {x:.7f} {y:.7f} {z:.7f}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in triangles]
    path.write_text("\n".join(lines) + "\n")


# ---- depth cameras -------------------------------------------------------------------------


def visual(robot: judge.Robot, o: dict[str, Any]) -> int:
    c = robot.client
    if o["type"] == "cuboid":
        shape = p.createVisualShape(p.GEOM_BOX, halfExtents=[d / 2 for d in o["dims"]], physicsClientId=c)
    elif o["type"] == "cylinder":
        shape = p.createVisualShape(p.GEOM_CYLINDER, radius=o["radius"], length=o["height"], physicsClientId=c)
    else:
        shape = p.createVisualShape(p.GEOM_SPHERE, radius=o["radius"], physicsClientId=c)
    return p.createMultiBody(0, -1, shape, basePosition=o["center"], baseOrientation=judge.xyzw(o.get("quaternion", IDENTITY)), physicsClientId=c)


def depth_cloud(robot: judge.Robot, camera: tuple[str, list[float], list[float]], rng: np.random.Generator, noise: float = NOISE) -> tuple[np.ndarray, np.ndarray]:
    """One camera's world points (noisy) and whether each pixel showed the robot."""
    _, eye, target = camera
    view = p.computeViewMatrix(eye, target, [0, 0, 1])
    proj = p.computeProjectionMatrixFOV(FOV, WIDTH / HEIGHT, NEAR, FAR)
    img = p.getCameraImage(WIDTH, HEIGHT, view, proj, renderer=p.ER_TINY_RENDERER, physicsClientId=robot.client)
    buffer = np.asarray(img[3], dtype=np.float64).reshape(HEIGHT, WIDTH)
    seg = np.asarray(img[4]).reshape(HEIGHT, WIDTH)
    metric = FAR * NEAR / (FAR - (FAR - NEAR) * buffer)  # eye-space depth along the view axis
    v, u = np.mgrid[0:HEIGHT, 0:WIDTH]
    # ER_TINY_RENDERER's pixel (u, v) is the ray through NDC (2u / W - 1, 1 - 2(v + 1) / H):
    # found by rendering a known box (test_cells.py), which then back-projects to within 1 um.
    x = 2 * u / WIDTH - 1
    y = 1 - 2 * (v + 1) / HEIGHT
    # PyBullet's matrices are column-major lists: reshape(4, 4).T is the usual matrix.
    inverse = np.linalg.inv(np.asarray(proj).reshape(4, 4).T @ np.asarray(view).reshape(4, 4).T)
    ndc = np.stack([x, y, 2 * buffer - 1, np.ones_like(x)], axis=-1).reshape(-1, 4)
    world = ndc @ inverse.T
    world = world[:, :3] / world[:, 3:]
    keep = (buffer.ravel() < 1.0 - 1e-6) & (metric.ravel() <= MAX_RANGE)
    z = metric.ravel()[keep]
    world = world[keep]
    eye_ = np.asarray(eye, dtype=np.float64)
    world = eye_ + (world - eye_) * ((z + rng.normal(0.0, noise, len(z))) / z)[:, None]
    return world, seg.ravel()[keep] == robot.body


def voxel_centroids(points: np.ndarray, labels: np.ndarray, size: float = VOXEL) -> tuple[np.ndarray, np.ndarray]:
    """One centroid per occupied voxel; its label is true when any point in it had one."""
    cell = np.floor(points / size).astype(np.int64)
    cell -= cell.min(axis=0)
    keys = (cell[:, 0] << 42) | (cell[:, 1] << 21) | cell[:, 2]  # one integer per voxel
    _, inverse, counts = np.unique(keys, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)
    sums = np.zeros((len(counts), 3))
    np.add.at(sums, inverse, points)
    label = np.zeros(len(counts), dtype=bool)
    label[inverse[labels]] = True
    return sums / counts[:, None], label


def render_scene(robot: judge.Robot, scene: dict[str, Any], rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """The merged, voxelized cloud of the scene with the robot at `start`, the mask of its
    points that `filter_robot` drops, and its record."""
    robot.finger = judge.finger_opening(scene)
    judge.set_state(robot, np.asarray(scene["start"], dtype=np.float64))
    bodies = [visual(robot, o) for o in scene["obstacles"]]
    try:
        clouds, labels, record = [], [], []
        for camera in CAMERAS:
            pts, is_robot = depth_cloud(robot, camera, rng)
            clouds.append(pts)
            labels.append(is_robot)
            record.append({"name": camera[0], "eye": camera[1], "target": camera[2], "points": int(len(pts)), "robot_points": int(is_robot.sum())})
    finally:
        for b in bodies:
            p.removeBody(b, physicsClientId=robot.client)
    points, robot_label = voxel_centroids(np.concatenate(clouds), np.concatenate(labels))
    near = judge.near_robot(robot, points, FILTER_ROBOT)
    info = {
        "cameras": record,
        "camera": {"width": WIDTH, "height": HEIGHT, "fov_deg": FOV, "near": NEAR, "far": FAR, "max_range": MAX_RANGE, "renderer": "ER_TINY_RENDERER"},
        "noise_sigma_m": NOISE,
        "voxel_m": VOXEL,
        "points": int(len(points)),
        "robot_points": int(robot_label.sum()),
        "robot_points_kept_by_filter": int((robot_label & ~near).sum()),
        "scene_points_dropped_by_filter": int((~robot_label & near).sum()),
    }
    return points, near, info


# ---- end clearances ------------------------------------------------------------------------


def end_clearance(robot: judge.Robot, scene: dict[str, Any], base: pathlib.Path, cloud: np.ndarray | None = None) -> dict[str, float | None]:
    """The closest robot body (links 1-7, hand, fingers) to the scene's own obstacles, at start
    and goal (joint goals only), as the planner sees them (`cloud`: the points left after
    `filter_robot`, when already known); None beyond END_WITHIN."""
    robot.finger = judge.finger_opening(scene)
    own = {k: v for k, v in scene.items() if k != "meta"}
    spawned = [(0, judge.Cloud(robot, cloud, RADIUS))] if cloud is not None else judge.spawn_scene(robot, own, base)
    pairs = [q for q in judge.queries(robot, [b for _, b in spawned], None, [k for k, _ in spawned]) if q[4]["kind"] == "obstacle"]
    try:
        out: dict[str, float | None] = {}
        for end in ("start", "goal"):
            q = scene["start"] if end == "start" else scene["goal"].get("joints")
            if q is not None:
                near = judge.nearest_at(robot, np.asarray(q, dtype=np.float64), pairs, None, None, END_WITHIN)
                out[end] = None if near is None else round(near["distance"], 6)
        return out
    finally:
        for _, body in spawned:
            body.remove() if isinstance(body, judge.Cloud) else p.removeBody(body, physicsClientId=robot.client)


# ---- the sets from the suites --------------------------------------------------------------


def sources(per_family: int | None) -> list[pathlib.Path]:
    out = []
    for suite in SUITES:
        for family in sorted(d for d in suite.iterdir() if d.is_dir()):
            files = sorted(family.glob("*.json"))
            out += files[:per_family] if per_family else files
    return out


def base_scene(source: dict[str, Any]) -> dict[str, Any]:
    scene = {"format": "edmp-scene/1", "obstacles": [], "start": source["start"], "goal": source["goal"]}
    for key in ("held_object", "gripper"):
        if key in source:
            scene[key] = source[key]
    return scene


_ROBOT: judge.Robot | None = None


def _init() -> None:
    global _ROBOT
    _ROBOT = judge.connect()


def make(job: dict[str, Any]) -> dict[str, Any]:
    """One scene of one set from one source problem; returns its sizes and time."""
    assert _ROBOT is not None
    t0 = time.perf_counter()
    src_path = pathlib.Path(job["source"])
    source = json.loads(src_path.read_text())
    family, stem = src_path.parent.name, src_path.stem
    folder = pathlib.Path(job["out"]) / job["set"] / family
    folder.mkdir(parents=True, exist_ok=True)
    truth = source["obstacles"]
    scene = base_scene(source)
    meta: dict[str, Any] = {"set": job["set"], "source": src_path.relative_to(ROOT).as_posix(), "source_meta": source.get("meta", {})}
    sizes: dict[str, Any] = {}
    kind = job["set"]
    kept = None
    if kind in ("surface", "surface_dense"):
        h = SPACING
        if kind == "surface_dense":
            h = spacing_for(lambda s: sum(len(surface_local(o, s)) for o in truth), job["points"])
        points = surface_points(truth, h)
        write_ply(folder / f"{stem}.ply", points)
        scene["obstacles"] = [{"type": "points", "file": f"{stem}.ply", "radius": RADIUS}]
        meta["spacing_m"] = h
        sizes["points"] = meta["points"] = int(len(points))
    elif kind == "depth":
        rng = np.random.default_rng([job["seed"], zlib.crc32(meta["source"].encode())])
        points, near, info = render_scene(_ROBOT, source, rng)
        kept = points[~near]
        write_ply(folder / f"{stem}.ply", points)
        scene["obstacles"] = [{"type": "points", "file": f"{stem}.ply", "radius": RADIUS, "filter_robot": FILTER_ROBOT}]
        meta |= info
        sizes |= {"points": info["points"], "robot_points": info["robot_points"], "robot_kept": info["robot_points_kept_by_filter"]}
    elif kind in ("mesh", "mesh_dense"):
        edge = None
        if kind == "mesh_dense":
            edge = spacing_for(lambda e: sum(len(mesh_local(o, e)[1]) for o in truth), job["triangles"], 0.05)
            meta["edge_m"] = edge
        vertices, triangles = scene_mesh(truth, edge)
        write_obj(folder / f"{stem}.obj", vertices, triangles)
        scene["obstacles"] = [{"type": "mesh", "file": f"{stem}.obj"}]
        sizes["triangles"] = meta["triangles"] = int(len(triangles))
        meta["vertices"] = int(len(vertices))
    meta["truth"] = "meta.truth_obstacles: the source problem's primitives"
    meta["truth_obstacles"] = truth
    scene["meta"] = meta
    meta["end_clearance_m"] = end_clearance(_ROBOT, scene, folder, kept if kind == "depth" else None)
    (folder / f"{stem}.json").write_text(json.dumps(scene) + "\n")
    sizes["seconds"] = time.perf_counter() - t0
    return {"set": kind, "scene": f"{family}/{stem}", **sizes, "end_clearance_m": meta["end_clearance_m"]}


# ---- the `real` set: pybullet_data meshes --------------------------------------------------

PANDA_READY = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
REAL_CLEARANCE = 0.005
SELF_CLEARANCE = 0.00202
# The Kiva pod: its STL is y-up (2.37 m tall, 0.88 m square); turned upright (+90 deg about x),
# its face toward the robot at x = 0.5, 0.2 m lower so three rows of bins are in reach.
KIVA = {"type": "mesh", "file": "pod_lowres.stl", "center": [0.94, 0.0, -0.2], "quaternion": [0.5, 0.5, 0.5, 0.5]}
# pybullet_data's table.urdf: a 1.5 x 1 x 0.05 top at 0.6 m and four 0.1 x 0.1 x 0.58 legs, all
# `table.obj` (a unit cube) scaled; turned 90 deg about z, its top 0.25 m above the robot's base.
TABLE = {"type": "mesh", "file": "table.obj", "center": [0.85, 0.0, -0.375], "quaternion": [math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)]}
TRAY = {"type": "mesh", "file": "tray_textured4.obj", "center": [0.6, 0.0, 0.25], "quaternion": IDENTITY, "scale": 0.5}


def table_obj(data: pathlib.Path) -> tuple[np.ndarray, np.ndarray]:
    cube_v, cube_f = judge.read_obj(data / "table" / "table.obj")
    parts = [(cube_v * [1.5, 1.0, 0.05] + [0, 0, 0.6], cube_f)]
    parts += [(cube_v * [0.1, 0.1, 0.58] + [x, y, 0.29], cube_f) for x in (-0.65, 0.65) for y in (-0.4, 0.4)]
    return merge(parts)


def robot_clearance(robot: judge.Robot, bodies: list[int], q: np.ndarray) -> tuple[float, float]:
    """Smallest distance robot (links 1..) to the bodies and between non-neighbour robot bodies."""
    judge.set_state(robot, q)
    p.performCollisionDetection(physicsClientId=robot.client)
    obstacle = min((judge.closest(robot.client, robot.body, b, 1.0, link, None) or 1.0) for b in bodies for link in robot.moving)
    own = min((judge.closest(robot.client, robot.body, robot.body, 1.0, a, b) or 1.0) for a, b in robot.self_pairs)
    return obstacle, own


def ik(robot: judge.Robot, position: list[float], down: bool, rng: np.random.Generator) -> np.ndarray | None:
    """PyBullet IK for the TCP at `position`, the hand pointing down (down) or along +x."""
    c = robot.client
    quat = p.getQuaternionFromEuler([math.pi, 0, rng.uniform(-0.6, 0.6)] if down else [0, math.pi / 2, rng.uniform(-0.6, 0.6)])
    lows = [lo for lo, _ in judge.LIMITS]
    highs = [hi for _, hi in judge.LIMITS]
    rest = (np.asarray(PANDA_READY) + rng.normal(0, 0.3, 7)).clip(lows, highs)
    judge.set_state(robot, rest)
    q = None
    for _ in range(4):
        sol = p.calculateInverseKinematics(robot.body, robot.tcp, position, quat, lowerLimits=lows + [0, 0], upperLimits=highs + [0.04, 0.04],
                                           jointRanges=[h - l for l, h in zip(lows, highs)] + [0.04, 0.04], restPoses=list(rest) + [robot.finger] * 2,
                                           maxNumIterations=200, residualThreshold=1e-5, physicsClientId=c)  # fmt: skip
        q = np.asarray(sol[:7])
        judge.set_state(robot, q)
    pos, got = judge.link_pose(robot, robot.tcp)
    if math.dist(pos, position) > 0.005 or judge.quaternion_angle(got, quat) > math.radians(5):
        return None
    if any(not lo <= v <= hi for v, (lo, hi) in zip(q, judge.LIMITS)):
        return None
    return q


def real_set(out: pathlib.Path, n: int, seed: int, clearance: float) -> list[dict[str, Any]]:
    data = pathlib.Path(judge.pybullet_data.getDataPath())
    folder = out / "real"
    for family in ("kiva", "table_tray"):  # each family's meshes beside its scenes
        (folder / family).mkdir(parents=True, exist_ok=True)
    shutil.copyfile(data / "kiva_shelf" / "meshes" / "pod_lowres.stl", folder / "kiva" / "pod_lowres.stl")
    shutil.copyfile(data / "tray" / "tray_textured4.obj", folder / "table_tray" / "tray_textured4.obj")
    write_obj(folder / "table_tray" / "table.obj", *table_obj(data))
    robot = judge.connect()
    rng = np.random.default_rng([seed, 33])
    rows = []
    layouts = {
        # family: obstacles (files relative to real/<family>/), TCP target volume, hand down?
        "kiva": ([KIVA], ([0.56, -0.32, 0.2], [0.68, 0.32, 0.75]), False),
        "table_tray": ([TABLE, TRAY], ([0.45, -0.3, 0.29], [0.75, 0.3, 0.45]), True),
    }
    counts = {"kiva": n - n // 2, "table_tray": n // 2}
    bar = tqdm(total=n, unit="scene", desc="real", file=sys.stderr)
    for family, (obstacles, (lo, hi), down) in layouts.items():
        (folder / family).mkdir(exist_ok=True)
        placed = obstacles
        robot.finger = judge.FINGER_OPENING
        spawned = judge.spawn_scene(robot, {"obstacles": placed, "start": PANDA_READY}, folder / family)
        bodies = [b for _, b in spawned]
        tries = 0
        ends: list[tuple[np.ndarray, list[float], float, float]] = []
        while len(ends) < 2 * counts[family]:
            tries += 1
            if tries > 200 * max(1, counts[family]):
                raise SystemExit(f"real/{family}: only {len(ends)} free ends in {tries} tries")
            target = rng.uniform(lo, hi).tolist()
            q = ik(robot, target, down, rng)
            if q is None:
                continue
            d_obs, d_self = robot_clearance(robot, bodies, q)
            if d_obs >= clearance and d_self >= SELF_CLEARANCE:
                ends.append((q, target, d_obs, d_self))
        for b in bodies:
            p.removeBody(b, physicsClientId=robot.client)
        for i in range(counts[family]):
            (qs, ts, ds, _), (qg, tg, dg, _) = ends[2 * i], ends[2 * i + 1]
            scene = {
                "format": "edmp-scene/1",
                "obstacles": placed,
                "start": [round(float(v), 9) for v in qs],
                "goal": {"joints": [round(float(v), 9) for v in qg]},
                "meta": {
                    "set": "real",
                    "family": family,
                    "source": "pybullet_data " + ", ".join(pathlib.PurePosixPath(o["file"]).name for o in obstacles),
                    "truth": "the scene's own mesh obstacles (pybullet_data's meshes, exact)",
                    "seed": seed,
                    "start_tcp": ts,
                    "goal_tcp": tg,
                    "end_clearance_m": {"start": round(ds, 6), "goal": round(dg, 6)},
                },
            }
            (folder / family / f"{i:03d}.json").write_text(json.dumps(scene) + "\n")
            rows.append({"set": "real", "scene": f"{family}/{i:03d}", "triangles": 0, "end_clearance_m": scene["meta"]["end_clearance_m"]})
            bar.update()
        rows[-1]["ik_tries"] = tries
    bar.close()
    p.disconnect(physicsClientId=robot.client)
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=pathlib.Path, default=ROOT / "bench-out" / "cells", help="output folder (default: bench-out/cells)")
    parser.add_argument("--sets", nargs="+", choices=SETS, default=DEFAULT_SETS, help=f"sets to make (default: {' '.join(DEFAULT_SETS)})")
    parser.add_argument("--per-family", type=int, help="only the first K problems of each family (default: all)")
    parser.add_argument("--points", type=int, default=200_000, help="points per scene of surface_dense (default 200000)")
    parser.add_argument("--triangles", type=int, default=10_000, help="triangles per scene of mesh_dense (default 10000)")
    parser.add_argument("--real", type=int, default=32, help="problems of the real set (default 32)")
    parser.add_argument("--real-clearance", type=float, default=REAL_CLEARANCE, help="smallest robot-mesh distance at the real set's ends (m)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the depth noise and the real set (default 0)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="worker processes (default: number of CPUs)")
    args = parser.parse_args(argv)

    judge.packaged_urdf()
    rows: list[dict[str, Any]] = []
    timing: dict[str, float] = {}
    jobs = [{"set": s, "source": str(f), "out": str(args.out), "seed": args.seed, "points": args.points, "triangles": args.triangles} for s in args.sets if s != "real" for f in sources(args.per_family)]
    if jobs:
        start = time.perf_counter()
        bar = tqdm(total=len(jobs), unit="scene", file=sys.stderr)
        if args.jobs <= 1:
            _init()
            for job in jobs:
                rows.append(make(job))
                bar.update()
        else:
            with multiprocessing.Pool(args.jobs, initializer=_init) as pool:
                for row in pool.imap_unordered(make, jobs, chunksize=4):
                    rows.append(row)
                    bar.update()
        bar.close()
        timing["suites_s"] = time.perf_counter() - start
    if "real" in args.sets:
        start = time.perf_counter()
        rows += real_set(args.out, args.real, args.seed, args.real_clearance)
        timing["real_s"] = time.perf_counter() - start
    summary = summarize(rows)
    (args.out).mkdir(parents=True, exist_ok=True)
    (args.out / "summary.json").write_text(json.dumps({"args": {k: str(v) for k, v in vars(args).items()}, "timing": timing, "sets": summary}, indent=1) + "\n")
    print(json.dumps({"timing": timing, "sets": summary}, indent=1))
    return 0


def summarize(rows: list[dict[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for s in sorted({r["set"] for r in rows}):
        mine = [r for r in rows if r["set"] == s]
        entry: dict[str, Any] = {"scenes": len(mine)}
        for key in ("points", "triangles", "robot_points", "robot_kept", "seconds"):
            values = [r[key] for r in mine if key in r]
            if values and (key != "triangles" or s != "real"):
                entry[key] = {"min": round(min(values), 3), "median": round(float(np.median(values)), 3), "max": round(max(values), 3), "sum": round(sum(values), 3)}
        ends = [v for r in mine for v in r["end_clearance_m"].values()]
        entry["ends_covered"] = sum(v is not None and v <= 0 for v in ends)  # the representation touches the robot at an end
        entry["ends_within_2mm"] = sum(v is not None and v <= 0.002 for v in ends)
        out[s] = entry
    return out


if __name__ == "__main__":
    sys.exit(main())
