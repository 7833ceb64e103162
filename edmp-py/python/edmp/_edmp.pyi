"""Type stubs of the native module (edmp-py/src/lib.rs). Use the ``edmp`` package instead."""

from typing import Optional

class SceneError(ValueError):
    """Invalid scene input; the message names the field by its JSON or YAML path."""

class PlanError(RuntimeError):
    """The planner or a core routine refused the problem."""

def validate(scene: str) -> None: ...
def plan(
    scene: str,
    seed: int = 0,
    candidates: bool = False,
    timed: bool = False,
    rate: float = 100.0,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
) -> str: ...
def plan_problem_ms(scene: str, seed: int = 0, repeats: int = 10) -> list[float]: ...
def fk(q: list[float], robot: str = ...) -> str: ...
def joint_names(robot: str) -> list[str]: ...
def check(scene: str, waypoints: list[list[float]]) -> str: ...
def ik(scene: str, position: list[float], quaternion: list[float]) -> Optional[list[float]]: ...
def import_moveit(scene_yaml: str, request_yaml: Optional[str] = None) -> str: ...
def view_page(scene: str, plan: Optional[str] = None, title: str = "edmp") -> str: ...
def points_from_depth(
    depth: bytes,
    width: int,
    height: int,
    k: list[list[float]],
    pose: list[list[float]],
    max_depth: Optional[float] = None,
) -> bytes: ...
