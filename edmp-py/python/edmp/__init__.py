"""EDMP motion planning for the Franka Panda, the KUKA LBR iiwa 7 and the UFACTORY xArm 6, from Python.

The planner, kinematics, checker and IK are edmp-rs's (Rust, ``edmp._edmp``); this module is
the typed, numpy-facing API over them. Scenes are ``edmp-scene/1`` documents read by the same
reader as ``edmp-host plan`` (so errors name the same JSON paths), and a :class:`Plan` is the
CLI's ``edmp-plan/1`` document, parsed.

>>> import edmp
>>> scene = edmp.Scene.from_file("examples/wall.json")
>>> plan = edmp.plan(scene, seed=0)
>>> plan.status, plan.waypoints.shape
('success', (50, 7))

A scene names its arm in ``robot`` (``"panda"`` when absent, ``"iiwa7"``, ``"xarm6"``); joint
vectors then have that arm's joint count (:attr:`Scene.robot`). :func:`plan` plans for every
arm, and so do :func:`check`, :func:`ik`, :func:`fk` (its ``robot`` argument) and
:func:`import_moveit` (the arm its joint names name) and :func:`show`.
"""

from __future__ import annotations

import html
import json
import math
import os
import tempfile
import webbrowser
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from . import _edmp
from ._edmp import PlanError, SceneError

__all__ = [
    "Candidate",
    "CheckReport",
    "Plan",
    "PlanError",
    "Pose",
    "Scene",
    "SceneError",
    "check",
    "fk",
    "ik",
    "import_moveit",
    "joint_names",
    "plan",
    "points_from_depth",
    "show",
]

Array = npt.NDArray[np.float64]
ArrayLike = Union[npt.ArrayLike, Sequence[float]]


def _vector(x: ArrayLike, n: int, what: str) -> list[float]:
    a = np.asarray(x, dtype=np.float64)
    if a.shape != (n,):
        raise ValueError(f"{what}: expected shape ({n},), found {a.shape}")
    return [float(v) for v in a]


def _array(x: Any, what: str, dtype: Any = np.float64) -> np.ndarray:
    try:
        return np.asarray(x, dtype=dtype)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{what}: not an array of numbers ({e})") from None


def _finite_vector(x: ArrayLike, n: int, what: str) -> list[float]:
    v = _vector(_array(x, what), n, what)
    if not all(math.isfinite(c) for c in v):
        raise ValueError(f"{what}: {v} is not finite")
    return v


def _rows(x: ArrayLike, what: str) -> Array:
    """``x`` as a finite ``(N, 3)`` float64 array, else a ``ValueError`` naming ``what``."""
    a = _array(x, what)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{what}: expected shape (N, 3), found {a.shape}")
    bad = ~np.isfinite(a).all(axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(f"{what}[{i}]: {a[i].tolist()} is not finite")
    return a


def _positive(x: float, what: str, zero: bool = False) -> float:
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: expected a number, found {x!r}") from None
    if not math.isfinite(v) or v < 0 or (v == 0 and not zero):
        raise ValueError(f"{what}: {v} is not {'non-negative' if zero else 'positive'} and finite")
    return v


@dataclass(frozen=True)
class Pose:
    """A TCP pose: ``position`` (m, world frame) and ``quaternion`` ``[w, x, y, z]``."""

    position: Array
    quaternion: Array


class Scene:
    """A validated ``edmp-scene/1`` problem: obstacles, held object, start and goal.

    Build one with :meth:`from_file`, :meth:`from_json`, :meth:`from_dict` or
    :func:`import_moveit`. Invalid input raises :class:`SceneError` whose message names the
    field by its JSON path (``obstacles[0].quaternion: norm 0.71, expected 1``).
    """

    __slots__ = ("_doc", "_text")

    def __init__(self, document: Mapping[str, Any]) -> None:
        text = json.dumps(document)
        _edmp.validate(text)
        self._doc: dict[str, Any] = json.loads(text)
        self._text = text

    @classmethod
    def from_dict(cls, document: Mapping[str, Any]) -> "Scene":
        """A scene from a dict shaped like the JSON document."""
        return cls(document)

    @classmethod
    def from_json(cls, text: str) -> "Scene":
        """A scene from JSON text."""
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as e:
            raise SceneError(f"not valid JSON: {e}") from None
        if not isinstance(doc, dict):
            raise SceneError("expected an object")
        return cls(doc)

    @classmethod
    def from_file(cls, path: Union[str, os.PathLike[str]]) -> "Scene":
        """A scene from an ``edmp-scene/1`` JSON file. The cloud and mesh files its obstacles
        name are relative to the file's folder, as for ``edmp-host plan``: they are made
        absolute here, so the scene plans from any working directory."""
        with open(path, encoding="utf-8") as f:
            text = f.read()
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as e:
            raise SceneError(f"{os.fspath(path)}: not valid JSON: {e}") from None
        folder = os.path.dirname(os.path.abspath(path))
        obstacles = doc.get("obstacles") if isinstance(doc, dict) else None
        for o in obstacles if isinstance(obstacles, list) else []:
            if isinstance(o, dict) and isinstance(o.get("file"), str) and not os.path.isabs(o["file"]):
                o["file"] = os.path.join(folder, o["file"])
        try:
            return cls.from_dict(doc)
        except SceneError as e:
            raise SceneError(f"{os.fspath(path)}: {e}") from None

    @property
    def robot(self) -> str:
        """The arm the scene is for: ``"panda"`` (the field absent), ``"iiwa7"`` or ``"xarm6"``."""
        return str(self._doc.get("robot", "panda"))

    @property
    def start(self) -> Array:
        """The start configuration, shape ``(J,)``: the arm's joints (7 for the Panda)."""
        return np.asarray(self._doc["start"], dtype=np.float64)

    @property
    def goal(self) -> Union[Array, Pose]:
        """The goal: joints, shape ``(J,)``, or a TCP :class:`Pose` (solved by IK when planning)."""
        goal = self._doc["goal"]
        if "joints" in goal:
            return np.asarray(goal["joints"], dtype=np.float64)
        pose = goal["pose"]
        return Pose(
            np.asarray(pose["position"], dtype=np.float64),
            np.asarray(pose["quaternion"], dtype=np.float64),
        )

    @property
    def obstacles(self) -> list[dict[str, Any]]:
        """The obstacles as in the document (a copy)."""
        return json.loads(json.dumps(self._doc["obstacles"]))

    @property
    def held_object(self) -> Optional[dict[str, Any]]:
        """The primitive held in the hand frame, if any (a copy)."""
        held = self._doc.get("held_object")
        return None if held is None else dict(held)

    def to_dict(self) -> dict[str, Any]:
        """The document (a copy): edit it and build a new scene with :meth:`from_dict`."""
        return json.loads(self._text)

    def to_json(self, indent: Optional[int] = None) -> str:
        """The document as JSON text."""
        return json.dumps(self._doc, indent=indent)

    def with_goal(self, joints: ArrayLike) -> "Scene":
        """The same scene with a joint goal."""
        doc = self.to_dict()
        doc["goal"] = {"joints": _vector(joints, len(self._doc["start"]), "joints")}
        return Scene(doc)

    def add_points(self, points: ArrayLike, radius: float, filter_robot: Optional[float] = None) -> "Scene":
        """The same scene plus a point-cloud obstacle: a ball of ``radius`` (m) around each
        row of ``points``, an ``(N, 3)`` array in the world frame (for example from
        :func:`points_from_depth`). With ``filter_robot`` the points within that distance (m)
        of the robot at the start are dropped first (a camera that sees the arm).

        Like :meth:`with_goal` it returns a new scene (scenes are values); it appends
        ``{"type": "points", "points": [...], "radius": r}`` to ``obstacles``, read by the
        same reader as a scene file. Clouds beyond the host's capacity (262,144 pieces, all
        clouds and meshes together) are reduced to fit. Raises ``ValueError`` naming the
        argument for a bad shape or a non-finite value, :class:`SceneError` for what the
        reader refuses (the start or goal in collision with the cloud, say).
        """
        p = _rows(points, "points")
        obstacle: dict[str, Any] = {"type": "points", "points": p.tolist(), "radius": _positive(radius, "radius")}
        if filter_robot is not None:
            obstacle["filter_robot"] = _positive(filter_robot, "filter_robot", zero=True)
        return self._with_obstacle(obstacle)

    def add_mesh(
        self,
        vertices: ArrayLike,
        triangles: ArrayLike,
        center: Optional[ArrayLike] = None,
        quaternion: Optional[ArrayLike] = None,
        scale: Union[float, ArrayLike, None] = None,
    ) -> "Scene":
        """The same scene plus a triangle-mesh obstacle: ``vertices`` an ``(V, 3)`` float
        array, ``triangles`` a ``(T, 3)`` integer array of vertex indices. The mesh is placed
        at world = ``center`` + rotation(``quaternion`` ``[w, x, y, z]``) · (``scale`` ⊙
        vertex); ``scale`` is one number or three (default: the vertices are in the world).

        Returns a new scene, as :meth:`add_points`, with ``{"type": "mesh", "vertices": [...],
        "triangles": [...], ...}`` appended to ``obstacles``. Raises ``ValueError`` naming the
        argument for a bad shape or dtype, a non-finite value or an index out of range, and
        :class:`SceneError` for what the reader refuses (a quaternion of norm ≠ 1, say).
        """
        v = _rows(vertices, "vertices")
        t = np.asarray(triangles)
        if t.ndim != 2 or t.shape[1] != 3:
            raise ValueError(f"triangles: expected shape (T, 3), found {t.shape}")
        if t.size and not np.issubdtype(t.dtype, np.integer):
            raise ValueError(f"triangles: expected integer vertex indices, found dtype {t.dtype}")
        bad = ((t < 0) | (t >= len(v))).any(axis=1)
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(f"triangles[{i}]: {t[i].tolist()}: a vertex index outside [0, {len(v)})")
        obstacle: dict[str, Any] = {"type": "mesh", "vertices": v.tolist(), "triangles": t.astype(np.int64).tolist()}
        if center is not None:
            obstacle["center"] = _finite_vector(center, 3, "center")
        if quaternion is not None:
            obstacle["quaternion"] = _finite_vector(quaternion, 4, "quaternion")
        if scale is not None:
            sa = _array(scale, "scale")
            if sa.shape not in ((), (3,)):
                raise ValueError(f"scale: expected a number or shape (3,), found {sa.shape}")
            factors = [_positive(x, "scale") for x in sa.reshape(-1)]
            obstacle["scale"] = factors[0] if sa.shape == () else factors
        return self._with_obstacle(obstacle)

    def _with_obstacle(self, obstacle: dict[str, Any]) -> "Scene":
        # The document is never mutated in place, so the new one shares the old obstacles
        # (no deep copy: a big cloud is serialised once, for the reader).
        doc = dict(self._doc)
        doc["obstacles"] = [*self._doc["obstacles"], obstacle]
        text = json.dumps(doc)
        _edmp.validate(text)
        scene = Scene.__new__(Scene)
        scene._doc = doc
        scene._text = text
        return scene

    def __repr__(self) -> str:
        kind = "joints" if "joints" in self._doc["goal"] else "pose"
        return f"Scene({len(self._doc['obstacles'])} obstacles, {kind} goal)"


@dataclass(frozen=True)
class Candidate:
    """One trajectory of the ensemble (``Plan.candidates``)."""

    guide: int
    collision_free: bool
    swept_volume: float
    waypoints: Array


@dataclass(frozen=True)
class Plan:
    """An ``edmp-plan/1`` document, parsed: the CLI's plan for the same scene and seed."""

    status: str
    """``"success"`` (passed the exact checker) or ``"collision"`` (least colliding returned)."""
    waypoints: Array
    """The chosen trajectory, shape ``(50, J)`` (``J`` the arm's joints: 7 for the Panda)."""
    guide: int
    stage: str
    """Which stage won: ``diffusion``, ``reseeded``, ``search`` or ``none``."""
    costs: dict[str, float]
    seed: int
    timing_ms: dict[str, float]
    candidates: Optional[list[Candidate]] = None
    search: Optional[dict[str, Any]] = None
    trajectory: Optional[dict[str, Any]] = None
    document: dict[str, Any] = field(default_factory=dict, repr=False)
    """The whole document as the CLI writes it."""

    @property
    def success(self) -> bool:
        """Whether the waypoints passed the planner's exact collision check."""
        return self.status == "success"

    @classmethod
    def from_document(cls, doc: Mapping[str, Any]) -> "Plan":
        """A plan from a parsed ``edmp-plan/1`` document."""
        cands = doc.get("candidates")
        return cls(
            status=doc["status"],
            waypoints=np.asarray(doc["waypoints"], dtype=np.float64),
            guide=int(doc["guide"]),
            stage=doc["stage"],
            costs=dict(doc["costs"]),
            seed=int(doc["seed"]),
            timing_ms=dict(doc["timing_ms"]),
            candidates=None
            if cands is None
            else [
                Candidate(
                    guide=int(c["guide"]),
                    collision_free=bool(c["collision_free"]),
                    swept_volume=float(c["swept_volume"]),
                    waypoints=np.asarray(c["waypoints"], dtype=np.float64),
                )
                for c in cands
            ],
            search=doc.get("search"),
            trajectory=_trajectory(doc.get("trajectory")),
            document=dict(doc),
        )


def _scene_text(scene: Union[Scene, Mapping[str, Any], str]) -> str:
    if isinstance(scene, Scene):
        return scene._text
    if isinstance(scene, str):
        return Scene.from_json(scene)._text
    return Scene.from_dict(scene)._text


def _trajectory(t: Optional[Mapping[str, Any]]) -> Optional[dict[str, Any]]:
    """The document's ``trajectory`` with its points as numpy arrays."""
    if t is None:
        return None
    out = {k: v for k, v in t.items() if k != "points"}
    points = t["points"]
    for key in ("positions", "velocities", "accelerations"):
        out[key] = np.asarray([p[key] for p in points], dtype=np.float64).reshape(len(points), -1)
    out["time_from_start"] = np.asarray([p["time_from_start"] for p in points], dtype=np.float64)
    return out


def plan(
    scene: Union[Scene, Mapping[str, Any]],
    seed: int = 0,
    candidates: bool = False,
    timed: bool = False,
    rate: float = 100.0,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
) -> Plan:
    """Plans with EDMP for the scene's arm (the shipped configuration, as ``edmp-host plan``).

    ``candidates=True`` adds every trajectory of the ensemble: all 12 guides then run as one
    batch, as EDMP (without it the guides run in waves that stop at the first free candidate,
    so the winner may differ; ``edmp-host plan --candidates`` does the same). ``timed=True`` adds
    ``Plan.trajectory``, as ``edmp-host plan --timed``: the path timed within the arm's velocity,
    acceleration and jerk limits times ``velocity_scale`` / ``acceleration_scale`` (each in
    (0, 1], else ``ValueError``), from rest to rest, sampled at ``rate`` Hz (at most 1000); a
    dict shaped like ROS ``JointTrajectory`` whose ``positions``, ``velocities``,
    ``accelerations`` are ``(n, J)`` arrays and ``time_from_start`` an ``(n,)`` array. A colliding
    plan is not timed (``trajectory`` is ``None``). The GIL is released while planning. Raises
    :class:`SceneError` for bad input and :class:`PlanError` when the core refuses the problem
    (for example an unreachable pose goal). A plan with ``status == "collision"`` is returned,
    not raised (the CLI's exit 1).
    """
    if seed < 0:
        raise ValueError(f"seed: {seed} is negative")
    doc = json.loads(
        _edmp.plan(_scene_text(scene), seed, candidates, timed, rate, velocity_scale, acceleration_scale)
    )
    return Plan.from_document(doc)


def points_from_depth(
    depth: ArrayLike,
    K: ArrayLike,
    pose: ArrayLike,
    max_depth: Optional[float] = None,
) -> Array:
    """The world points of a depth image: an ``(N, 3)`` float64 array, for
    :meth:`Scene.add_points`.

    ``depth`` is an ``(H, W)`` float image in metres, each pixel the z of its point in the
    camera frame (a z-buffer, as RGB-D drivers give it once scaled to metres; an integer
    image, such as millimetres, is refused). ``K`` is the ``3 × 3`` pinhole intrinsics
    ``[[fx, s, cx], [0, fy, cy], [0, 0, 1]]`` and ``pose`` the camera's ``4 × 4`` pose in the
    world (camera → world), both in OpenCV's convention: camera x right, y down, z forward;
    pixel ``(u, v)`` is column ``u``, row ``v``, with integer coordinates at pixel centres.
    Pixels with no return (0, negative, NaN, inf) and beyond ``max_depth`` are dropped; the
    rest come in row-major order. The back-projection is edmp-rs's
    (``edmp_host::depth``; computed in f64, rounded to f32, the planner's precision).
    Raises ``ValueError`` naming the argument: a bad shape, ``K`` not finite, not of that
    form or with a focal length ≤ 0, ``pose`` not finite, not homogeneous, or its rotation
    not orthonormal within 1e-4 or a reflection.
    """
    d = np.asarray(depth)
    if d.ndim != 2:
        raise ValueError(f"depth: expected an (H, W) image, found shape {d.shape}")
    if not np.issubdtype(d.dtype, np.floating):
        raise ValueError(
            f"depth: expected float metres, found dtype {d.dtype} (convert integer depth, e.g. millimetres, to metres)"
        )
    k = _array(K, "K")
    if k.shape != (3, 3):
        raise ValueError(f"K: expected shape (3, 3), found {k.shape}")
    p = _array(pose, "pose")
    if p.shape != (4, 4):
        raise ValueError(f"pose: expected shape (4, 4), found {p.shape}")
    m = None if max_depth is None else float(max_depth)
    h, w = d.shape
    raw = _edmp.points_from_depth(np.ascontiguousarray(d, dtype="<f4").tobytes(), w, h, k.tolist(), p.tolist(), m)
    return np.frombuffer(raw, dtype="<f4").reshape(-1, 3).astype(np.float64)


def joint_names(robot: str = "panda") -> list[str]:
    """The joint names of the arm called ``robot`` (a scene's ``robot`` names), joint 1 first."""
    return list(_edmp.joint_names(robot))


def fk(q: ArrayLike, robot: str = "panda") -> dict[str, Any]:
    """Forward kinematics of ``robot`` at ``q``, as ``edmp-host fk --robot ROBOT --json``:
    ``tcp``, ``frames`` (the link frames; the Panda's 13), ``collision_boxes`` (the Panda's 11,
    with ``half_extents``), ``within_soft_limits``. Positions in metres, quaternions ``[w, x, y,
    z]``, both as numpy arrays."""
    report = json.loads(_edmp.fk(_vector(q, len(_edmp.joint_names(robot)), "q"), robot))

    def arrays(p: dict[str, Any]) -> dict[str, Any]:
        out = dict(p)
        for key in ("position", "quaternion", "half_extents"):
            if key in out:
                out[key] = np.asarray(out[key], dtype=np.float64)
        return out

    report["joints"] = np.asarray(report["joints"], dtype=np.float64)
    report["tcp"] = arrays(report["tcp"])
    report["frames"] = [arrays(f) for f in report["frames"]]
    report["collision_boxes"] = [arrays(b) for b in report["collision_boxes"]]
    return report


@dataclass(frozen=True)
class CheckReport:
    """The exact checker's verdict on a trajectory; truthy when collision-free."""

    free: bool
    states: int
    """States checked: waypoints and interpolated states (steps of at most 0.01 rad)."""
    colliding_states: int
    first_contact: Optional[dict[str, Any]]
    """``{"segment", "step", "contact"}`` of the first contact, e.g. ``panda_hand touches obstacles[1]``."""

    def __bool__(self) -> bool:
        return self.free


def check(scene: Union[Scene, Mapping[str, Any]], waypoints: ArrayLike) -> CheckReport:
    """Checks a ``(50, J)`` trajectory of the scene's arm (``J`` its joints, 7 for the Panda) in
    the scene with the core's exact checker (``checker::check_trajectory``, the rule of a solved
    problem; every contact counted)."""
    w = np.asarray(waypoints, dtype=np.float64)
    if w.ndim != 2:
        raise ValueError(f"waypoints: expected shape (50, J), found {w.shape}")
    r = json.loads(_edmp.check(_scene_text(scene), w.tolist()))
    return CheckReport(r["free"], r["states"], r["colliding_states"], r["first_contact"])


def ik(
    scene: Union[Scene, Mapping[str, Any]],
    position: ArrayLike,
    quaternion: ArrayLike,
) -> Optional[Array]:
    """Joints of the scene's arm that put the TCP at ``position`` / ``quaternion``
    (``[w, x, y, z]``), within the limits and collision-free in the scene, nearest its start: the
    core IK as a pose goal uses it. ``None`` when no solution is found."""
    q = _edmp.ik(
        _scene_text(scene),
        _vector(position, 3, "position"),
        _vector(quaternion, 4, "quaternion"),
    )
    return None if q is None else np.asarray(q, dtype=np.float64)


def import_moveit(
    scene_yaml: Union[str, os.PathLike[str]],
    request_yaml: Union[str, os.PathLike[str], None] = None,
) -> Scene:
    """A MoveIt planning scene (``moveit_msgs/PlanningScene`` YAML) and optionally a motion
    plan request (``moveit_msgs/MotionPlanRequest`` YAML) as a :class:`Scene`, as
    ``edmp-host import-moveit``. The arm is the one ``robot_model_name`` or the joint names
    name (the Panda, the iiwa 7, the xArm 6). Each argument is YAML text or a path to a file. Unsupported
    entries (octomaps, point clouds, planes, other frames or links...) raise :class:`SceneError` naming their
    YAML path. Without a request the start is the scene's robot state and the goal equals it
    (set one with :meth:`Scene.with_goal`)."""

    def text(x: Union[str, os.PathLike[str]]) -> str:
        if isinstance(x, os.PathLike) or (isinstance(x, str) and "\n" not in x and os.path.isfile(x)):
            with open(x, encoding="utf-8") as f:
                return f.read()
        return str(x)

    doc = _edmp.import_moveit(text(scene_yaml), None if request_yaml is None else text(request_yaml))
    return Scene.from_json(doc)


def _in_notebook() -> bool:
    """Whether this runs in a Jupyter kernel (IPython's ZMQ shell)."""
    try:
        from IPython import get_ipython  # type: ignore[import-not-found]
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and type(shell).__name__ == "ZMQInteractiveShell"


def show(
    scene: Union[Scene, Mapping[str, Any], str],
    plan: Union[Plan, Mapping[str, Any], str, None] = None,
    path: Union[str, os.PathLike[str], None] = None,
) -> Any:
    """Shows the scene (and the plan, animated) in the interactive 3-D viewer of
    ``edmp-host view`` (docs/viewer.md): one self-contained HTML page, written by the same
    Rust code. ``plan`` is a :class:`Plan`, its document as a dict, or its JSON text.

    Inside Jupyter it returns an ``IPython.display.HTML`` object that shows the page inline
    (and writes it to ``path`` too when given). Elsewhere it writes the page to ``path`` (a
    temporary file when ``None``), opens it in the web browser and returns its path.
    Invalid input raises :class:`SceneError` (scene) or ``ValueError`` (plan) naming the field.
    """
    if plan is None:
        plan_text = None
    elif isinstance(plan, Plan):
        plan_text = json.dumps(plan.document)
    elif isinstance(plan, str):
        plan_text = plan
    else:
        plan_text = json.dumps(dict(plan))
    title = "edmp plan" if plan is not None else "edmp scene"
    page = _edmp.view_page(_scene_text(scene), plan_text, title)
    if path is not None:
        Path(path).write_text(page, encoding="utf-8")
    if _in_notebook():
        from IPython.display import HTML  # type: ignore[import-not-found]

        # In its own document (srcdoc), so the page's scripts do not meet the notebook's.
        frame = f'<iframe srcdoc="{html.escape(page, quote=True)}" style="width: 100%; height: 600px; border: 0"></iframe>'
        return HTML(f"<div>{frame}</div>")
    if path is None:
        handle, name = tempfile.mkstemp(prefix="edmp-view-", suffix=".html")
        with os.fdopen(handle, "w", encoding="utf-8") as f:
            f.write(page)
        path = name
    target = Path(path).resolve()
    webbrowser.open(target.as_uri())
    return target
