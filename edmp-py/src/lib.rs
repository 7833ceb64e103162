//! `edmp._edmp`: the native half of the `edmp` Python package. Every function takes and returns
//! plain values or JSON text; the typed, numpy-facing API is `python/edmp/__init__.py`.
//!
//! Scenes go through the host's one reader of `edmp-scene/1` (`edmp_host::formats::json`), plans through
//! its planner driver and its one writer of `edmp-plan/1` (`edmp_host::commands::plan`), so a plan
//! from Python is the CLI's document. Planning releases the GIL.

use edmp_core::collision::checker::{CheckConfig, check_trajectory};
use edmp_core::path::HORIZON;
use edmp_core::planner::{Judging, PlanConfig};
use edmp_core::prior::Network;
use edmp_core::robot::Robot;
use edmp_core::scene::QUATERNION_NORM_TOLERANCE;
use edmp_host::Failure;
use edmp_host::arm::Arm;
use edmp_host::formats::json::{Goal, Problem, describe, joint_goal, parse_problem, parse_problem_for, scene_arm};
use edmp_host::formats::plan::{add_trajectory, parse_plan_for, plan_document};
use edmp_host::formats::trajectory::TimedRequest;
use edmp_host::planning::{HOST_CONFIG, chosen_guides, plan_problem};
use edmp_host::with_arm;
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use serde_json::{Value, json};
use std::path::Path;
use std::time::Instant;

create_exception!(
    edmp,
    SceneError,
    PyValueError,
    "Invalid scene input. The message names the offending field by its JSON (or, for MoveIt input, YAML) path, as the CLI does: `obstacles[0].quaternion: norm 0.71, expected 1`."
);
create_exception!(
    edmp,
    PlanError,
    PyRuntimeError,
    "The planner or a core routine refused the problem (e.g. an unreachable pose goal)."
);

fn scene_error(e: impl ToString) -> PyErr {
    SceneError::new_err(e.to_string())
}

fn failure(e: Failure) -> PyErr {
    match e {
        Failure::Input(m) | Failure::NoPath(m) => PlanError::new_err(m),
    }
}

/// A Panda's scene (the functions that run the Panda alone: another arm is refused by name).
fn parse(text: &str) -> PyResult<Problem> {
    parse_problem(text).map_err(scene_error)
}

/// A scene for `robot`; file paths in it are absolute (`Scene.from_file` made them so).
fn parse_for<const J: usize>(text: &str, robot: &'static Robot<f32, J>) -> PyResult<Problem<J>> {
    parse_problem_for(text, Path::new("."), robot).map_err(scene_error)
}

fn to_json(v: &Value) -> PyResult<String> {
    serde_json::to_string(v).map_err(|e| PlanError::new_err(e.to_string()))
}

/// Validates an `edmp-scene/1` document (JSON text) for the arm it names; raises `SceneError`
/// naming the field.
#[pyfunction]
fn validate(scene: &str) -> PyResult<()> {
    let arm = scene_arm(scene).map_err(scene_error)?;
    with_arm!(arm, robot => parse_for(scene, robot).map(|_| ()))
}

/// Plans for the arm the scene names with the shipped configuration and returns the
/// `edmp-plan/1` document as JSON text; `timed` adds the `trajectory` field as `edmp-host plan
/// --timed` does (free plans only).
#[pyfunction]
#[pyo3(signature = (scene, seed = 0, candidates = false, timed = false, rate = 100.0, velocity_scale = 1.0, acceleration_scale = 1.0))]
#[allow(clippy::too_many_arguments)]
fn plan(
    py: Python<'_>,
    scene: &str,
    seed: u64,
    candidates: bool,
    timed: bool,
    rate: f64,
    velocity_scale: f32,
    acceleration_scale: f32,
) -> PyResult<String> {
    let arm = scene_arm(scene).map_err(scene_error)?;
    // Validated before planning, as the CLI does: a bad scale is a ValueError, nothing runs.
    let request = if timed {
        Some(
            TimedRequest::new(rate, velocity_scale, acceleration_scale).map_err(|e| match e {
                // The CLI names its flags; here they are keyword arguments.
                Failure::Input(m) | Failure::NoPath(m) => PyValueError::new_err(
                    m.replacen("--rate", "rate", 1)
                        .replacen("--velocity-scale", "velocity_scale", 1)
                        .replacen("--acceleration-scale", "acceleration_scale", 1),
                ),
            })?,
        )
    } else {
        None
    };
    let options = Options {
        seed,
        candidates,
        request,
    };
    with_arm!(arm, robot, network => plan_for(py, scene, robot, network, &options)).map_err(PlanError::new_err)?
}

/// What `plan` asks beyond the scene.
struct Options {
    seed: u64,
    candidates: bool,
    request: Option<TimedRequest>,
}

fn plan_for<const J: usize>(
    py: Python<'_>,
    scene: &str,
    robot: &'static Robot<f32, J>,
    network: &'static Network<J>,
    options: &Options,
) -> PyResult<String> {
    let problem = parse_for(scene, robot)?;
    let Options {
        seed,
        candidates,
        ref request,
    } = *options;
    let doc = py.detach(move || -> Result<Value, Failure> {
        let began = Instant::now();
        let guides = chosen_guides(&[])?;
        let config = PlanConfig {
            // Every alternative returned is made (one batch of every guide, as EDMP) and gets
            // its verdict.
            judging: if candidates { Judging::Every } else { Judging::Winner },
            waves: if candidates { 1 } else { PlanConfig::DEFAULT.waves },
            ..HOST_CONFIG
        };
        let planned = plan_problem(network, &problem, &guides, &config, seed)?;
        let total_ms = began.elapsed().as_secs_f64() * 1e3;
        let mut doc = plan_document(&problem, &planned, &guides, &config, seed, candidates, total_ms)?;
        if let Some(request) = request {
            add_trajectory(&mut doc, &problem, &planned.plan, &config, request)?;
        }
        Ok(doc)
    });
    to_json(&doc.map_err(failure)?)
}

/// Milliseconds of `plan_problem` alone (parsing done, no JSON written), `repeats` times: the
/// Rust side of `bench_overhead.py`.
#[pyfunction]
#[pyo3(signature = (scene, seed = 0, repeats = 10))]
fn plan_problem_ms(py: Python<'_>, scene: &str, seed: u64, repeats: u32) -> PyResult<Vec<f64>> {
    let problem = parse(scene)?;
    py.detach(move || {
        let guides = chosen_guides(&[])?;
        (0..repeats)
            .map(|_| {
                let began = Instant::now();
                plan_problem(edmp_core::prior::PANDA, &problem, &guides, &HOST_CONFIG, seed)?;
                Ok(began.elapsed().as_secs_f64() * 1e3)
            })
            .collect::<Result<Vec<f64>, Failure>>()
    })
    .map_err(failure)
}

/// `q` as `robot`'s joints: `J` finite numbers, else a `ValueError` naming the entry.
fn joints_of<const J: usize>(robot: &Robot<f32, J>, q: &[f64], what: &str) -> PyResult<[f32; J]> {
    if q.len() != J {
        return Err(PyValueError::new_err(format!(
            "{what}: expected {J} joint angles, found {}",
            q.len()
        )));
    }
    let mut out = [0.0f32; J];
    for (i, (slot, &x)) in out.iter_mut().zip(q).enumerate() {
        if !x.is_finite() || x.abs() > f64::from(f32::MAX) {
            return Err(PyValueError::new_err(format!(
                "{what}[{i}] ({}): {x} is not a finite number",
                robot.joint_names[i]
            )));
        }
        *slot = x as f32;
    }
    Ok(out)
}

/// Forward kinematics of the arm called `robot` (the scene format's names) as `edmp-host fk
/// --robot ROBOT --json` prints it (JSON text): the TCP, every link frame and every collision
/// box.
#[pyfunction]
#[pyo3(signature = (q, robot = "panda"))]
fn fk(q: Vec<f64>, robot: &str) -> PyResult<String> {
    let doc = with_arm!(arm_named(robot)?, robot => joints_of(robot, &q, "q").and_then(|q| {
        edmp_host::commands::fk::document(robot, &q).map_err(|e| PyValueError::new_err(format!("q: {e}")))
    }))?;
    to_json(&doc)
}

/// The arm called `name` (the scene format's `robot`), else a `ValueError` listing the known ones.
fn arm_named(name: &str) -> PyResult<Arm> {
    Arm::from_name(name).ok_or_else(|| {
        let known: Vec<&str> = Arm::ALL.iter().map(|a| a.name()).collect();
        PyValueError::new_err(format!(
            "robot: \"{name}\" is not an arm this package knows ({})",
            known.join(", ")
        ))
    })
}

/// The joint names of the arm called `robot`, joint 1 first.
#[pyfunction]
fn joint_names(robot: &str) -> PyResult<Vec<&'static str>> {
    Ok(with_arm!(arm_named(robot)?, robot => robot.joint_names.to_vec()))
}

/// The exact checker (`checker::check_trajectory`, every contact counted) on `HORIZON`
/// waypoints of the scene's arm in the scene: a JSON report.
#[pyfunction]
fn check(scene: &str, waypoints: Vec<Vec<f64>>) -> PyResult<String> {
    let arm = scene_arm(scene).map_err(scene_error)?;
    with_arm!(arm, robot => check_for(scene, robot, &waypoints))
}

fn check_for<const J: usize>(scene: &str, robot: &'static Robot<f32, J>, waypoints: &[Vec<f64>]) -> PyResult<String> {
    let problem = parse_for(scene, robot)?;
    if waypoints.len() != HORIZON {
        return Err(PyValueError::new_err(format!(
            "waypoints: expected {HORIZON} rows (the plan format's), found {}",
            waypoints.len()
        )));
    }
    let mut path = [[0.0f32; J]; HORIZON];
    for (i, (slot, row)) in path.iter_mut().zip(waypoints).enumerate() {
        *slot = joints_of(robot, row, &format!("waypoints[{i}]"))?;
    }
    let report = check_trajectory(robot, &problem.scene(), &path, &CheckConfig::default(), false)
        .map_err(|e| PlanError::new_err(format!("checker: {e}")))?;
    let first = report.first_contact.map(
        |c| json!({"segment": c.segment, "step": c.step, "contact": describe(problem.robot, c.contact, &problem.primitive_index)}),
    );
    to_json(&json!({
        "free": report.is_free(),
        "states": report.states,
        "colliding_states": report.colliding_states,
        "first_contact": first,
    }))
}

/// The core IK of the scene's arm as a pose goal uses it (`json::joint_goal`): the
/// collision-free solution in the scene nearest its start, or `None` when none is found.
#[pyfunction]
fn ik(scene: &str, position: Vec<f64>, quaternion: Vec<f64>) -> PyResult<Option<Vec<f32>>> {
    let arm = scene_arm(scene).map_err(scene_error)?;
    with_arm!(arm, robot => ik_for(scene, robot, &position, &quaternion))
}

fn ik_for<const J: usize>(
    scene: &str,
    robot: &'static Robot<f32, J>,
    position: &[f64],
    quaternion: &[f64],
) -> PyResult<Option<Vec<f32>>> {
    let problem = parse_for(scene, robot)?;
    let finite = |v: &[f64], n: usize, what: &str| -> PyResult<Vec<f32>> {
        if v.len() != n || v.iter().any(|x| !x.is_finite()) {
            return Err(PyValueError::new_err(format!("{what}: expected {n} finite numbers")));
        }
        Ok(v.iter().map(|&x| x as f32).collect())
    };
    let (p, q) = (finite(position, 3, "position")?, finite(quaternion, 4, "quaternion")?);
    let norm = q.iter().map(|x| x * x).sum::<f32>().sqrt();
    if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
        return Err(PyValueError::new_err(format!("quaternion: norm {norm:.2}, expected 1")));
    }
    let mut posed = problem;
    posed.goal = Goal::Pose {
        position: [p[0], p[1], p[2]],
        quaternion: [q[0], q[1], q[2], q[3]],
    };
    Ok(joint_goal(&posed).ok().map(|j| j.to_vec()))
}

/// A MoveIt planning scene (and motion plan request), YAML text, as `edmp-scene/1` JSON text,
/// validated by the host's reader; raises `SceneError` naming the YAML or JSON path.
#[pyfunction]
#[pyo3(signature = (scene_yaml, request_yaml = None))]
fn import_moveit(scene_yaml: &str, request_yaml: Option<&str>) -> PyResult<String> {
    let doc = edmp_host::formats::moveit::import_validated(scene_yaml, request_yaml).map_err(scene_error)?;
    to_json(&doc)
}

/// The viewer page of `edmp-host view` (one self-contained HTML document) for a scene and
/// optionally a plan (`edmp-plan/1` JSON text); raises `SceneError` for the scene and
/// `ValueError` for the plan, naming the JSON path.
#[pyfunction]
#[pyo3(signature = (scene, plan = None, title = "edmp"))]
fn view_page(scene: &str, plan: Option<&str>, title: &str) -> PyResult<String> {
    let arm = scene_arm(scene).map_err(scene_error)?;
    with_arm!(arm, robot => view_page_for(scene, robot, plan, title))
}

fn view_page_for<const J: usize>(
    scene: &str,
    robot: &'static Robot<f32, J>,
    plan: Option<&str>,
    title: &str,
) -> PyResult<String> {
    let problem = parse_for(scene, robot)?;
    let plan = match plan {
        Some(text) => Some(parse_plan_for::<J>(text).map_err(|e| PyValueError::new_err(format!("plan: {e}")))?),
        None => None,
    };
    edmp_host::commands::view::page(&problem, plan.as_ref(), title).map_err(PlanError::new_err)
}

/// `edmp_host::depth::points_from_depth_le_bytes` (conventions in `edmp_host::depth`): `depth`
/// is the `height × width` image, row-major, as little-endian `f32` bytes (numpy's
/// `astype('<f4').tobytes()`); the world points come back as little-endian `f32` bytes, `x, y,
/// z` per point. Raises `ValueError` naming the argument. The GIL is released while it runs.
#[pyfunction]
#[pyo3(signature = (depth, width, height, k, pose, max_depth = None))]
fn points_from_depth<'py>(
    py: Python<'py>,
    depth: &[u8],
    width: usize,
    height: usize,
    k: [[f64; 3]; 3],
    pose: [[f64; 4]; 4],
    max_depth: Option<f32>,
) -> PyResult<Bound<'py, PyBytes>> {
    let bytes =
        py.detach(move || edmp_host::depth::points_from_depth_le_bytes(depth, width, height, k, pose, max_depth));
    Ok(PyBytes::new(py, &bytes.map_err(PyValueError::new_err)?))
}

/// The native half of `edmp` (use the `edmp` package).
#[pymodule]
mod _edmp {
    #[pymodule_export]
    use super::{
        PlanError, SceneError, check, fk, ik, import_moveit, joint_names, plan, plan_problem_ms, points_from_depth,
        validate, view_page,
    };
}
