//! The `edmp-plan/1` plan format (docs/formats.md): the one writer ([`plan_document`], with
//! [`add_trajectory`] for the timed `trajectory`) and the one reader ([`parse_plan`]), which
//! the CLI, the viewer and the Python package share.

use super::surface::SurfaceKind;
use crate::Failure;
use crate::formats::fields::{InputError, field, number, numbers};
use crate::formats::json::Problem;
use crate::formats::trajectory::{TimedRequest, trajectory_document};
use crate::planning::{Planned, ROWS};
use edmp_core::cost::boxes::Inflation;
use edmp_core::cost::{CostConfig, CostKind, trajectory_cost};
use edmp_core::guidance::guides::Guide;
use edmp_core::planner::{Plan, PlanConfig};
use edmp_core::robot::JOINTS;
use edmp_core::robot::kinematics::Joints;
use serde_json::{Value, json};
use std::time::Instant;

/// The `edmp-plan/1` document of a planned problem (docs/formats.md): the one writer of the
/// format, which the CLI and the Python package share. `total_ms` is the caller's wall time.
pub fn plan_document<const J: usize>(
    problem: &Problem<J>,
    planned: &Planned<J>,
    guides: &[Guide],
    config: &PlanConfig,
    seed: u64,
    candidates: bool,
    total_ms: f64,
) -> Result<serde_json::Value, Failure> {
    let plan = &planned.plan;
    let best = &plan.paths[plan.best];
    let iv = CostConfig {
        kind: CostKind::Intersection,
        inflation: Inflation::default(),
        cylinder: config.cylinder,
        frame: config.frame,
    };
    let intersection =
        trajectory_cost(problem.robot, &problem.scene(), best, &iv, None).map_err(|e| Failure::Input(e.to_string()))?;
    let per_guide = ROWS / guides.len();
    let guide_of = |row: usize| guides[row / per_guide].id;
    let status = if plan.is_free() { "success" } else { "collision" };
    let mut out = json!({
        "format": "edmp-plan/1",
        "status": status,
        "waypoints": best.iter().map(|q| q.to_vec()).collect::<Vec<_>>(),
        "guide": guide_of(plan.best),
        "stage": plan.stage.name(),
        "search": plan.search.map(|s| json!({
            "found": s.found,
            "nodes": s.nodes,
            "iterations": s.iterations,
            "attempts": s.attempts,
            "segment_checks": s.segment_checks,
        })),
        "shortcut": plan.shortcut.map(|s| json!({
            "length_before": s.length_before,
            "length_after": s.length_after,
            "dropped": s.dropped,
            "smoothing": s.smoothing,
        })),
        "costs": {"swept_volume": plan.verdicts[plan.best].swept, "intersection_volume": intersection},
        "seed": seed,
        "timing_ms": {
            "total": total_ms,
            "ik": planned.ik_ms,
            "denoise": planned.denoise_ms,
            "select": planned.select_ms,
            "global": planned.global_ms,
            "shortcut": planned.shortcut_ms,
        },
    });
    let filtering = problem.surfaces.obstacles.iter().any(|o| {
        matches!(
            o.kind,
            SurfaceKind::Points {
                filter_robot: Some(_),
                ..
            }
        )
    });
    if filtering {
        out["points_filtered"] = json!(problem.surfaces.points_filtered);
    }
    if candidates {
        out["candidates"] = plan
            .paths
            .iter()
            .zip(&plan.verdicts)
            .enumerate()
            .filter(|(_, (_, verdict))| verdict.made)
            .map(|(row, (path, verdict))| {
                json!({
                    "guide": guide_of(row),
                    "collision_free": verdict.free,
                    "swept_volume": verdict.swept,
                    "waypoints": path.iter().map(|q| q.to_vec()).collect::<Vec<_>>(),
                })
            })
            .collect();
    }
    Ok(out)
}

/// Adds the `trajectory` field (and `timing_ms.trajectory`) to a plan document when the plan
/// is free, timed within the problem's arm's limits; `false` when it collides (a colliding path
/// is not timed).
pub fn add_trajectory<const J: usize>(
    doc: &mut serde_json::Value,
    problem: &Problem<J>,
    plan: &Plan<ROWS, J>,
    config: &PlanConfig,
    request: &TimedRequest,
) -> Result<bool, Failure> {
    let Some(path) = plan.paths.get(plan.best).filter(|_| plan.is_free()) else {
        return Ok(false);
    };
    let began = Instant::now();
    doc["trajectory"] = trajectory_document(problem.robot, &problem.scene(), path, &config.check, request)?;
    doc["timing_ms"]["trajectory"] = json!(began.elapsed().as_secs_f64() * 1e3);
    Ok(true)
}

/// One alternative path of a plan written with `--candidates`, for an arm of `J` joints.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanCandidate<const J: usize = JOINTS> {
    /// The guide that steered it.
    pub guide: Option<u64>,
    /// Whether the checker passed it.
    pub collision_free: bool,
    /// Its waypoints.
    pub waypoints: Vec<Joints<f32, J>>,
}

/// An `edmp-plan/1` document as read back (by `edmp-host view`): the chosen path, its timed
/// trajectory, the candidates and the report fields. Fields it does not use are not checked.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanDocument<const J: usize = JOINTS> {
    /// `"success"` or `"collision"`.
    pub status: String,
    /// The stage that found the path (`diffusion`, `reseeded`, `search`), when written.
    pub stage: Option<String>,
    /// The chosen path.
    pub waypoints: Vec<Joints<f32, J>>,
    /// `trajectory.points` as (time from start in seconds, joint positions), when timed.
    pub trajectory: Vec<(f32, Joints<f32, J>)>,
    /// `candidates`, empty when the plan was written without them.
    pub candidates: Vec<PlanCandidate<J>>,
    /// `timing_ms`: every stage's milliseconds, by name.
    pub timing_ms: Vec<(String, f64)>,
}

fn path_of<const J: usize>(v: &Value, path: &str) -> Result<Vec<Joints<f32, J>>, InputError> {
    let rows = v
        .as_array()
        .ok_or_else(|| InputError::at(path, "expected an array of waypoints"))?;
    if rows.is_empty() {
        return Err(InputError::at(path, "no waypoints"));
    }
    rows.iter()
        .enumerate()
        .map(|(i, row)| numbers::<J>(row, &format!("{path}[{i}]")))
        .collect()
}

/// Parses a Panda's `edmp-plan/1` document (what `edmp-host plan` writes) for reading back.
pub fn parse_plan(text: &str) -> Result<PlanDocument, InputError> {
    parse_plan_for::<JOINTS>(text)
}

/// [`parse_plan`] for an arm of `J` joints: every joint vector must have `J` entries.
pub fn parse_plan_for<const J: usize>(text: &str) -> Result<PlanDocument<J>, InputError> {
    let root: Value = serde_json::from_str(text).map_err(|e| InputError::at("", format!("not valid JSON: {e}")))?;
    let map = root
        .as_object()
        .ok_or_else(|| InputError::at("", "expected an object"))?;
    let (format, fp) = field(map, "", "format")?;
    if format.as_str() != Some("edmp-plan/1") {
        return Err(InputError::at(&fp, format!("expected \"edmp-plan/1\", found {format}")));
    }
    let (status, sp) = field(map, "", "status")?;
    let status = status
        .as_str()
        .ok_or_else(|| InputError::at(&sp, format!("expected a string, found {status}")))?
        .to_string();
    let stage = map.get("stage").and_then(Value::as_str).map(str::to_string);
    let (waypoints, wp) = field(map, "", "waypoints")?;
    let waypoints = path_of(waypoints, &wp)?;
    let mut trajectory = Vec::new();
    if let Some(t) = map.get("trajectory") {
        let tm = t
            .as_object()
            .ok_or_else(|| InputError::at("trajectory", "expected an object"))?;
        let (points, pp) = field(tm, "trajectory", "points")?;
        let points = points
            .as_array()
            .ok_or_else(|| InputError::at(&pp, "expected an array"))?;
        if points.is_empty() {
            return Err(InputError::at(&pp, "no points"));
        }
        for (i, point) in points.iter().enumerate() {
            let at = format!("{pp}[{i}]");
            let pm = point
                .as_object()
                .ok_or_else(|| InputError::at(&at, "expected an object"))?;
            let (q, qp) = field(pm, &at, "positions")?;
            let (time, tp) = field(pm, &at, "time_from_start")?;
            let time = number(time, &tp)?;
            if trajectory.last().is_some_and(|&(before, _)| time < before) {
                return Err(InputError::at(
                    &tp,
                    format!("{time} is before the previous point's time"),
                ));
            }
            trajectory.push((time, numbers::<J>(q, &qp)?));
        }
    }
    let mut candidates = Vec::new();
    if let Some(list) = map.get("candidates") {
        let list = list
            .as_array()
            .ok_or_else(|| InputError::at("candidates", "expected an array"))?;
        for (i, c) in list.iter().enumerate() {
            let at = format!("candidates[{i}]");
            let cm = c.as_object().ok_or_else(|| InputError::at(&at, "expected an object"))?;
            let (w, wp) = field(cm, &at, "waypoints")?;
            let (free, fp) = field(cm, &at, "collision_free")?;
            candidates.push(PlanCandidate {
                guide: cm.get("guide").and_then(Value::as_u64),
                collision_free: free
                    .as_bool()
                    .ok_or_else(|| InputError::at(&fp, format!("expected true or false, found {free}")))?,
                waypoints: path_of(w, &wp)?,
            });
        }
    }
    let mut timing_ms = Vec::new();
    if let Some(t) = map.get("timing_ms") {
        let tm = t
            .as_object()
            .ok_or_else(|| InputError::at("timing_ms", "expected an object"))?;
        for (key, value) in tm {
            let ms = value.as_f64().ok_or_else(|| {
                InputError::at(&format!("timing_ms.{key}"), format!("expected a number, found {value}"))
            })?;
            timing_ms.push((key.clone(), ms));
        }
    }
    Ok(PlanDocument {
        status,
        stage,
        waypoints,
        trajectory,
        candidates,
        timing_ms,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plan_errors_name_the_field() {
        let q = "[0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785]";
        let plan =
            |rest: &str| format!(r#"{{"format": "edmp-plan/1", "status": "success", "waypoints": [{q}, {q}]{rest}}}"#);
        let ok = parse_plan(&plan(r#", "timing_ms": {"total": 1.5}"#)).unwrap();
        assert_eq!(
            (ok.waypoints.len(), ok.timing_ms.clone()),
            (2, vec![("total".to_string(), 1.5)])
        );
        let error = |text: &str| parse_plan(text).unwrap_err().to_string();
        assert_eq!(
            error(&plan("").replace("plan/1", "scene/1")),
            r#"format: expected "edmp-plan/1", found "edmp-scene/1""#
        );
        let timed = format!(
            r#", "trajectory": {{"points": [{{"positions": {q}, "time_from_start": 0.5}}, {{"positions": {q}, "time_from_start": 0.25}}]}}"#
        );
        assert_eq!(
            error(&plan(&timed)),
            "trajectory.points[1].time_from_start: 0.25 is before the previous point's time"
        );
        let candidate = format!(r#", "candidates": [{{"collision_free": "yes", "waypoints": [{q}]}}]"#);
        assert_eq!(
            error(&plan(&candidate)),
            r#"candidates[0].collision_free: expected true or false, found "yes""#
        );
        assert_eq!(
            error(&plan("").replace(&format!("[{q}, {q}]"), "[]")),
            "waypoints: no waypoints"
        );
    }
}
