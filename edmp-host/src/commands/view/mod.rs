//! `edmp-host view`: a scene (and a plan) as one self-contained HTML page, an interactive 3-D
//! viewer that opens offline in a browser (docs/viewer.md).
//!
//! Everything the page draws is computed here and embedded as JSON: the scene's arm's meshes
//! (the URDF's `<visual>` meshes with their origins; the xArm's `<collision>` meshes, its visual
//! STL files not being shipped in `weights/`), the obstacles (clouds and meshes as
//! base64 little-endian `f32`/`u32` arrays, a cloud thinned to [`MAX_VIEW_POINTS`] points in
//! all), and for every sample of
//! the animation the world pose of each link frame from the core's forward kinematics. The
//! page's JavaScript (`page.js`, on the vendored three.js in `vendor/three`) only places meshes
//! at those poses and interpolates between samples; it computes no kinematics.

use crate::formats::json::{Goal, Problem, parse_problem_for, scene_arm};
use crate::formats::plan::{PlanDocument, parse_plan_for};
use crate::formats::surface::{SurfaceKind, SurfaceObstacle};
use crate::{Failure, with_arm};
use edmp_core::robot::Robot;
use edmp_core::robot::kinematics::{Pose, forward_with};
use edmp_core::scene::{Obstacle, Shape};
use nalgebra::{Rotation3, UnitQuaternion};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Arguments of `edmp-host view`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene (`edmp-scene/1`).
    scene: PathBuf,
    /// A plan (`edmp-plan/1`) to animate on it.
    plan: Option<PathBuf>,
    /// Output HTML page.
    #[arg(short, long)]
    output: PathBuf,
}

/// Where the meshes the page draws for an arm come from.
struct Visuals {
    /// The arm's scene-format name.
    arm: &'static str,
    /// The URDF's file name, for errors.
    file: &'static str,
    /// The URDF: the meshes and their origins come from its `<visual>` elements.
    urdf: &'static str,
    /// Draw the `<collision>` meshes instead (the visual ones are not shipped).
    collision: bool,
    /// The mesh files the URDF names, by their path (`package://` dropped): the OBJ text and
    /// its MTL text (empty when the mesh has no colours of its own).
    files: &'static [(&'static str, &'static str, &'static str)],
}

/// Every arm's meshes.
const VISUALS: [Visuals; 3] = [
    Visuals {
        arm: "panda",
        file: "panda.urdf",
        urdf: include_str!("../../../../weights/panda/panda.urdf"),
        collision: false,
        files: &PANDA_FILES,
    },
    Visuals {
        arm: "iiwa7",
        file: "model.urdf",
        urdf: include_str!("../../../../weights/iiwa7/model.urdf"),
        collision: false,
        files: &IIWA7_FILES,
    },
    Visuals {
        arm: "xarm6",
        file: "xarm6_robot.urdf",
        urdf: include_str!("../../../../weights/xarm6/xarm6_robot.urdf"),
        collision: true,
        files: &XARM6_FILES,
    },
];

/// The iiwa 7's visual meshes (pybullet_data's `kuka_iiwa/meshes`).
const IIWA7_FILES: [(&str, &str, &str); 8] = {
    macro_rules! link {
        ($n:literal) => {
            (
                concat!("meshes/link_", $n, ".obj"),
                include_str!(concat!("../../../../weights/iiwa7/meshes/link_", $n, ".obj")),
                include_str!(concat!("../../../../weights/iiwa7/meshes/link_", $n, ".mtl")),
            )
        };
    }
    [
        link!(0),
        link!(1),
        link!(2),
        link!(3),
        link!(4),
        link!(5),
        link!(6),
        link!(7),
    ]
};

/// The xArm 6's collision meshes (V-HACD pieces, uncoloured).
const XARM6_FILES: [(&str, &str, &str); 7] = {
    macro_rules! link {
        ($n:literal) => {
            (
                concat!("xarm_description/meshes/xarm6/collision/", $n, "_vhacd.obj"),
                include_str!(concat!(
                    "../../../../weights/xarm6/xarm_description/meshes/xarm6/collision/",
                    $n,
                    "_vhacd.obj"
                )),
                "",
            )
        };
    }
    [
        link!("base"),
        link!("link1"),
        link!("link2"),
        link!("link3"),
        link!("link4"),
        link!("link5"),
        link!("link6"),
    ]
};

/// The Panda's meshes (visual ones, reduced by `scripts/visual-meshes`; two links have only
/// collision meshes in PyBullet's package).
const PANDA_FILES: [(&str, &str, &str); 10] = [
    (
        "meshes/collision/link0.obj",
        include_str!("../../../../weights/panda/meshes/collision/link0.obj"),
        "",
    ),
    (
        "meshes/visual/link1.obj",
        include_str!("../../../../weights/panda/meshes/visual/link1.obj"),
        include_str!("../../../../weights/panda/meshes/visual/link1.mtl"),
    ),
    (
        "meshes/visual/link2.obj",
        include_str!("../../../../weights/panda/meshes/visual/link2.obj"),
        include_str!("../../../../weights/panda/meshes/visual/link2.mtl"),
    ),
    (
        "meshes/visual/link3.obj",
        include_str!("../../../../weights/panda/meshes/visual/link3.obj"),
        include_str!("../../../../weights/panda/meshes/visual/link3.mtl"),
    ),
    (
        "meshes/visual/link4.obj",
        include_str!("../../../../weights/panda/meshes/visual/link4.obj"),
        include_str!("../../../../weights/panda/meshes/visual/link4.mtl"),
    ),
    (
        "meshes/visual/link5.obj",
        include_str!("../../../../weights/panda/meshes/visual/link5.obj"),
        include_str!("../../../../weights/panda/meshes/visual/link5.mtl"),
    ),
    (
        "meshes/visual/link6.obj",
        include_str!("../../../../weights/panda/meshes/visual/link6.obj"),
        include_str!("../../../../weights/panda/meshes/visual/link6.mtl"),
    ),
    (
        "meshes/collision/link7.obj",
        include_str!("../../../../weights/panda/meshes/collision/link7.obj"),
        "",
    ),
    (
        "meshes/visual/hand.obj",
        include_str!("../../../../weights/panda/meshes/visual/hand.obj"),
        include_str!("../../../../weights/panda/meshes/visual/hand.mtl"),
    ),
    (
        "meshes/visual/finger.obj",
        include_str!("../../../../weights/panda/meshes/visual/finger.obj"),
        include_str!("../../../../weights/panda/meshes/visual/finger.mtl"),
    ),
];

/// The page around the data and the scripts.
const TEMPLATE: &str = include_str!("page.html");
/// The page's own script: builds the three.js scene from the embedded data.
const APP_JS: &str = include_str!("page.js");
/// three.js 0.170.0 (npm `three`, MIT), unmodified.
const THREE_JS: &str = include_str!("../../../vendor/three/three.module.min.js");
/// three.js's OrbitControls, from the same package.
const ORBIT_JS: &str = include_str!("../../../vendor/three/OrbitControls.js");

/// Colour of a mesh whose file names none (the URDF's `panda_white`).
const DEFAULT_COLOUR: [f32; 3] = [0.9, 0.9, 0.9];
/// Seconds between waypoints when the plan has no timed trajectory (the path is played evenly).
pub const EVEN_STEP_S: f32 = 0.1;
/// Most animation samples per second taken from a timed trajectory (the page interpolates
/// between them); a denser trajectory is thinned, its last point always kept.
pub const MAX_SAMPLE_RATE: f32 = 50.0;
/// Most cloud points the page holds, all clouds together: beyond it every k-th point of the
/// clouds (taken in the scene's order) is kept, k the smallest that fits.
pub const MAX_VIEW_POINTS: usize = 100_000;

/// Reads the scene (and plan), writes the page. Bad input: exit 2 naming the file and JSON path,
/// nothing written.
pub fn run(args: &Args) -> Result<(), Failure> {
    let text = read(&args.scene)?;
    let arm = scene_arm(&text).map_err(|e| Failure::Input(format!("{}: {e}", args.scene.display())))?;
    with_arm!(arm, robot => write(args, &text, robot))
}

fn read(path: &Path) -> Result<String, Failure> {
    std::fs::read_to_string(path).map_err(|e| Failure::Input(format!("{}: {e}", path.display())))
}

fn write<const J: usize>(args: &Args, text: &str, robot: &'static Robot<f32, J>) -> Result<(), Failure> {
    let dir = args.scene.parent().unwrap_or(Path::new("."));
    let problem =
        parse_problem_for(text, dir, robot).map_err(|e| Failure::Input(format!("{}: {e}", args.scene.display())))?;
    let plan = match &args.plan {
        Some(path) => {
            Some(parse_plan_for::<J>(&read(path)?).map_err(|e| Failure::Input(format!("{}: {e}", path.display())))?)
        }
        None => None,
    };
    let title = match &args.plan {
        Some(plan) => format!("{} — {}", file_name(&args.scene), file_name(plan)),
        None => file_name(&args.scene),
    };
    let html = page(&problem, plan.as_ref(), &title).map_err(Failure::Input)?;
    std::fs::write(&args.output, html).map_err(|e| Failure::Input(format!("{}: {e}", args.output.display())))
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// The HTML page of `problem` (and `plan`), titled `title`: the one writer of the viewer, which
/// the CLI and the Python package share. Errors name the plan field the kinematics refused.
pub fn page<const J: usize>(
    problem: &Problem<J>,
    plan: Option<&PlanDocument<J>>,
    title: &str,
) -> Result<String, String> {
    let data = page_data(problem, plan, title)?;
    // `</` cannot end the data's script element once escaped (`\/` is a JSON escape of `/`).
    let data = serde_json::to_string(&data)
        .map_err(|e| e.to_string())?
        .replace("</", "<\\/");
    for (name, source) in [
        ("three.module.min.js", THREE_JS),
        ("OrbitControls.js", ORBIT_JS),
        ("view.js", APP_JS),
    ] {
        // Embedded as raw script text: these sequences would end or confuse the element.
        if source.contains("</script") || source.contains("<!--") {
            return Err(format!("{name} cannot be embedded: it contains </script or <!--"));
        }
    }
    let title = escape_html(title);
    fill(
        TEMPLATE,
        &[
            ("{{TITLE}}", &title),
            ("{{THREE}}", THREE_JS),
            ("{{ORBIT}}", ORBIT_JS),
            ("{{APP}}", APP_JS),
            ("{{DATA}}", &data),
        ],
    )
}

/// `template` with each placeholder replaced by its text, in one pass (a text never has its
/// own placeholders replaced); an error if one is missing.
fn fill(template: &str, parts: &[(&str, &str)]) -> Result<String, String> {
    let mut out = String::with_capacity(template.len() + parts.iter().map(|(_, t)| t.len()).sum::<usize>());
    let mut rest = template;
    for (key, text) in parts {
        let (before, after) = rest
            .split_once(key)
            .ok_or_else(|| format!("page.html: no {key} (or out of order)"))?;
        out.push_str(before);
        out.push_str(text);
        rest = after;
    }
    out.push_str(rest);
    Ok(out)
}

fn escape_html(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Rounded to the micrometre (or microsecond): enough for the page, and shorter text than the
/// shortest round-trip form of an `f32`.
fn micro(x: f32) -> f64 {
    (f64::from(x) * 1e6).round() / 1e6
}

fn micro3(v: &nalgebra::Vector3<f32>) -> [f64; 3] {
    [micro(v.x), micro(v.y), micro(v.z)]
}

fn quaternion(rotation: &nalgebra::Matrix3<f32>) -> [f64; 4] {
    let pose = Pose {
        rotation: *rotation,
        translation: nalgebra::Vector3::zeros(),
    };
    pose.quaternion_wxyz().map(micro)
}

/// One animation sample: the world pose of every link frame (`x y z qw qx qy qz` each, frames
/// in the arm's `frame_names` order, flattened) and the TCP position, from the core's FK.
fn sample<const J: usize>(
    robot: &'static Robot<f32, J>,
    q: &[f32; J],
    finger: f32,
    at: &str,
) -> Result<(Vec<f64>, [f64; 3]), String> {
    let k = forward_with(robot, q, finger).map_err(|e| format!("{at}: {e}"))?;
    let frames = robot.frame_names.len();
    let mut poses = Vec::with_capacity(frames * 7);
    for frame in k.frames.iter().take(frames) {
        poses.extend(micro3(&frame.translation));
        poses.extend(frame.quaternion_wxyz().map(micro));
    }
    Ok((poses, micro3(&k.tcp().translation)))
}

/// The animated configurations and their times: the timed trajectory (thinned to at most
/// `MAX_SAMPLE_RATE` per second) when the plan has one, else the waypoints `EVEN_STEP_S`
/// apart, else the start alone. Each with the JSON path that names it in errors.
fn timeline<const J: usize>(problem: &Problem<J>, plan: Option<&PlanDocument<J>>) -> Vec<(f32, [f32; J], String)> {
    let Some(plan) = plan else {
        return vec![(0.0, problem.start, "start".to_string())];
    };
    if plan.trajectory.is_empty() {
        return plan
            .waypoints
            .iter()
            .enumerate()
            .map(|(i, q)| (i as f32 * EVEN_STEP_S, *q, format!("waypoints[{i}]")))
            .collect();
    }
    let points = &plan.trajectory;
    let duration = points[points.len() - 1].0;
    let rate = (points.len() - 1) as f32 / duration.max(f32::MIN_POSITIVE);
    let stride = (rate / MAX_SAMPLE_RATE).ceil().max(1.0) as usize;
    let last = points.len() - 1;
    (0..points.len())
        .filter(|&i| i % stride == 0 || i == last)
        .map(|i| (points[i].0, points[i].1, format!("trajectory.points[{i}].positions")))
        .collect()
}

/// A primitive as the page draws it: its kind, sizes and pose. New kinds of obstacle get a
/// case here and a drawing function in `page.js`'s `SHAPES`.
fn primitive(o: &Obstacle) -> Value {
    let pose = json!({"position": micro3(&o.center), "quaternion": quaternion(&o.rotation)});
    let mut out = match o.shape {
        Shape::Cuboid { dims } => json!({"type": "cuboid", "dims": micro3(&dims)}),
        Shape::Cylinder { radius, height } => {
            json!({"type": "cylinder", "radius": micro(radius), "height": micro(height)})
        }
        Shape::Sphere { radius } => json!({"type": "sphere", "radius": micro(radius)}),
    };
    out["position"] = pose["position"].clone();
    out["quaternion"] = pose["quaternion"].clone();
    out
}

/// The kept points of each cloud: every `stride`-th of the clouds taken in order, `stride`
/// the smallest that keeps at most `max` in all.
fn thin_clouds<'a>(clouds: &[&'a [[f32; 3]]], max: usize) -> Vec<Vec<&'a [f32; 3]>> {
    let total: usize = clouds.iter().map(|c| c.len()).sum();
    let stride = total.div_ceil(max.max(1)).max(1);
    let mut at = 0;
    clouds
        .iter()
        .map(|c| {
            // The first point of this cloud that is a multiple of `stride` in the whole list.
            let first = (stride - at % stride) % stride;
            at += c.len();
            c.iter().skip(first).step_by(stride).collect()
        })
        .collect()
}

/// The clouds and meshes as the page draws them: `points` (a cloud's kept points, `x y z`
/// little-endian `f32`, base64) with the ball `radius` and the cloud's full `count`; a mesh's
/// `vertices` (`f32`) and triangle `indices` (`u32`), base64. `index` is the obstacle's index
/// in the scene file.
fn surfaces(obstacles: &[SurfaceObstacle]) -> Vec<Value> {
    let clouds: Vec<&[[f32; 3]]> = obstacles
        .iter()
        .filter_map(|o| match &o.kind {
            SurfaceKind::Points { points, .. } => Some(points.as_slice()),
            SurfaceKind::Mesh { .. } => None,
        })
        .collect();
    let mut kept = thin_clouds(&clouds, MAX_VIEW_POINTS).into_iter();
    let floats =
        |v: &mut dyn Iterator<Item = &[f32; 3]>| base64(&v.flatten().flat_map(|x| x.to_le_bytes()).collect::<Vec<_>>());
    obstacles
        .iter()
        .map(|o| match &o.kind {
            SurfaceKind::Points { points, radius, .. } => {
                let drawn = kept.next().unwrap_or_default();
                json!({
                    "type": "points",
                    "index": o.index,
                    "radius": radius,
                    "count": points.len(),
                    "drawn": drawn.len(),
                    "points": floats(&mut drawn.into_iter()),
                })
            }
            SurfaceKind::Mesh { vertices, triangles } => json!({
                "type": "mesh",
                "index": o.index,
                "triangles": triangles.len(),
                "vertices": floats(&mut vertices.iter()),
                "indices": base64(&triangles.iter().flatten().flat_map(|i| i.to_le_bytes()).collect::<Vec<_>>()),
            }),
        })
        .collect()
}

fn tcp_path<const J: usize>(
    robot: &'static Robot<f32, J>,
    path: &[[f32; J]],
    finger: f32,
    at: &str,
) -> Result<Vec<[f64; 3]>, String> {
    path.iter()
        .enumerate()
        .map(|(i, q)| sample(robot, q, finger, &format!("{at}[{i}]")).map(|(_, tcp)| tcp))
        .collect()
}

fn page_data<const J: usize>(
    problem: &Problem<J>,
    plan: Option<&PlanDocument<J>>,
    title: &str,
) -> Result<Value, String> {
    let robot = problem.robot;
    let finger = robot.finger_opening(problem.scene().gripper());
    let mut times = Vec::new();
    let mut poses = Vec::new();
    let mut tcp = Vec::new();
    for (time, q, at) in timeline(problem, plan) {
        let (p, t) = sample(robot, &q, finger, &at)?;
        times.push(micro(time));
        poses.push(p);
        tcp.push(t);
    }
    let start_tcp = sample(robot, &problem.start, finger, "start")?.1;
    let goal_tcp = match problem.goal {
        Goal::Joints(q) => sample(robot, &q, finger, "goal.joints")?.1,
        Goal::Pose { position, .. } => position.map(micro),
    };
    let waypoints_tcp = match plan {
        Some(plan) => tcp_path(robot, &plan.waypoints, finger, "waypoints")?,
        None => Vec::new(),
    };
    let candidates = match plan {
        Some(plan) => plan
            .candidates
            .iter()
            .enumerate()
            .map(|(i, c)| {
                Ok(json!({
                    "guide": c.guide,
                    "collision_free": c.collision_free,
                    "tcp": tcp_path(robot, &c.waypoints, finger, &format!("candidates[{i}].waypoints"))?,
                }))
            })
            .collect::<Result<Vec<_>, String>>()?,
        None => Vec::new(),
    };
    let info = match plan {
        Some(plan) => json!({
            "status": plan.status,
            "stage": plan.stage,
            "waypoints": plan.waypoints.len(),
            "timed": !plan.trajectory.is_empty(),
            "timing_ms": plan.timing_ms.iter().map(|(k, v)| json!([k, v])).collect::<Vec<_>>(),
        }),
        None => json!({"status": null, "timed": false, "timing_ms": []}),
    };
    Ok(json!({
        "title": title,
        "robot": robot.name,
        "frames": robot.frame_names,
        "tcp_frame": robot.tcp_frame,
        "hand_frame": robot.hand_frame,
        "meshes": robot_meshes(robot.name, robot.frame_names)?,
        "obstacles": problem.scene().obstacles().iter().map(primitive).collect::<Vec<_>>(),
        "surfaces": surfaces(&problem.surfaces.obstacles),
        "held": problem.scene().held().map(primitive),
        "samples": {"times": times, "poses": poses, "tcp": tcp},
        "start_tcp": start_tcp,
        "goal_tcp": goal_tcp,
        "waypoints_tcp": waypoints_tcp,
        "candidates": candidates,
        "info": info,
    }))
}

/// Every `<visual>` mesh of the arm's URDF (the xArm's: every `<collision>` mesh): the link
/// frame it moves with (an index into `frames`), its origin in that frame, and its triangles
/// (little-endian `f32` vertices and `u32` indices, base64) in colour groups.
pub fn robot_meshes(arm: &str, frames: &[&str]) -> Result<Vec<Value>, String> {
    let v = VISUALS
        .iter()
        .find(|v| v.arm == arm)
        .ok_or_else(|| format!("{arm}: the viewer has no meshes for this arm"))?;
    let name = v.file;
    let robot = urdf_rs::read_from_string(v.urdf).map_err(|e| format!("{name}: {e}"))?;
    let mut out = Vec::new();
    for link in &robot.links {
        let drawn: Vec<(&urdf_rs::Geometry, &urdf_rs::Pose)> = if v.collision {
            link.collision.iter().map(|c| (&c.geometry, &c.origin)).collect()
        } else {
            link.visual.iter().map(|c| (&c.geometry, &c.origin)).collect()
        };
        for (geometry, origin) in drawn {
            let urdf_rs::Geometry::Mesh { filename, scale } = geometry else {
                return Err(format!("{name}: {}: only mesh visuals are drawn", link.name));
            };
            let frame = frames
                .iter()
                .position(|&n| n == link.name)
                .ok_or_else(|| format!("{name}: link {} has a visual but no frame", link.name))?;
            let file = filename.trim_start_matches("package://");
            let (_, obj, mtl) = v
                .files
                .iter()
                .find(|(path, _, _)| *path == file)
                .ok_or_else(|| format!("{name}: {}: mesh {file} is not embedded", link.name))?;
            let mesh = parse_obj(obj, &parse_mtl(mtl)).map_err(|e| format!("{file}: {e}"))?;
            let [x, y, z] = *origin.xyz;
            let [roll, pitch, yaw] = *origin.rpy;
            // URDF rpy: fixed axes x, y, z, i.e. Rz(yaw)·Ry(pitch)·Rx(roll).
            let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_euler_angles(roll, pitch, yaw));
            out.push(json!({
                "link": link.name,
                "frame": frame,
                "position": [x, y, z],
                "quaternion": [q.w, q.i, q.j, q.k],
                "scale": scale.as_ref().map_or([1.0; 3], |s| **s),
                "vertices": base64(&mesh.vertices.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<_>>()),
                "indices": base64(&mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect::<Vec<_>>()),
                "groups": mesh.groups.iter().map(|g| json!({"start": g.start, "count": g.count, "colour": g.colour})).collect::<Vec<_>>(),
            }));
        }
    }
    Ok(out)
}

/// A triangle mesh: vertex coordinates (x y z each), triangle corner indices grouped by colour.
#[derive(Debug, PartialEq)]
struct Mesh {
    vertices: Vec<f32>,
    indices: Vec<u32>,
    groups: Vec<Group>,
}

/// A run of `indices` drawn in one colour.
#[derive(Debug, PartialEq)]
struct Group {
    start: usize,
    count: usize,
    colour: [f32; 3],
}

/// Material name → diffuse colour (`Kd`) of a Wavefront MTL file.
fn parse_mtl(text: &str) -> Vec<(String, [f32; 3])> {
    let mut out = Vec::new();
    let mut name = None;
    for line in text.lines() {
        let mut parts = line.split_whitespace();
        match parts.next() {
            Some("newmtl") => name = parts.next().map(str::to_string),
            Some("Kd") => {
                let rgb: Vec<f32> = parts.filter_map(|p| p.parse().ok()).collect();
                if let (Some(n), [r, g, b]) = (&name, rgb.as_slice()) {
                    out.push((n.clone(), [*r, *g, *b]));
                }
            }
            _ => {}
        }
    }
    out
}

/// The vertices and triangles of a Wavefront OBJ file (polygons split into fans), grouped by
/// their `usemtl` colour; other statements (normals, texture coordinates) are not needed.
fn parse_obj(text: &str, colours: &[(String, [f32; 3])]) -> Result<Mesh, String> {
    let mut vertices = Vec::new();
    let mut by_colour: Vec<([f32; 3], Vec<u32>)> = Vec::new();
    let mut colour = DEFAULT_COLOUR;
    for (n, line) in text.lines().enumerate() {
        let at = || format!("line {}", n + 1);
        let mut parts = line.split_whitespace();
        match parts.next() {
            Some("v") => {
                let xyz: Vec<f32> = parts
                    .take(3)
                    .map(str::parse)
                    .collect::<Result<_, _>>()
                    .map_err(|e| format!("{}: {e}", at()))?;
                if xyz.len() != 3 {
                    return Err(format!("{}: a vertex needs 3 coordinates", at()));
                }
                vertices.extend(xyz);
            }
            Some("usemtl") => {
                let name = parts.next().unwrap_or_default();
                colour = colours
                    .iter()
                    .find(|(m, _)| m == name)
                    .map_or(DEFAULT_COLOUR, |(_, c)| *c);
            }
            Some("f") => {
                let ids: Vec<u32> = parts
                    .map(|p| {
                        let first = p.split('/').next().unwrap_or_default();
                        match first.parse::<u32>() {
                            Ok(i) if i >= 1 && (i as usize) <= vertices.len() / 3 => Ok(i - 1),
                            _ => Err(format!("{}: bad vertex index {p:?}", at())),
                        }
                    })
                    .collect::<Result<_, _>>()?;
                if ids.len() < 3 {
                    return Err(format!("{}: a face needs 3 vertices", at()));
                }
                let slot = match by_colour.iter().position(|(c, _)| *c == colour) {
                    Some(k) => k,
                    None => {
                        by_colour.push((colour, Vec::new()));
                        by_colour.len() - 1
                    }
                };
                for k in 1..ids.len() - 1 {
                    by_colour[slot].1.extend([ids[0], ids[k], ids[k + 1]]);
                }
            }
            _ => {}
        }
    }
    let mut indices = Vec::new();
    let mut groups = Vec::new();
    for (colour, list) in by_colour {
        groups.push(Group {
            start: indices.len(),
            count: list.len(),
            colour,
        });
        indices.extend(list);
    }
    if indices.is_empty() {
        return Err("no faces".to_string());
    }
    Ok(Mesh {
        vertices,
        indices,
        groups,
    })
}

/// Standard base64 (RFC 4648, padded): binary arrays in the page at 4/3 of their size.
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(char::from(ALPHABET[((n >> (18 - 6 * k)) & 63) as usize]));
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use edmp_core::robot::kinematics::Joints;
    use edmp_core::robot::{FRAMES, TCP_FRAME};

    #[test]
    fn base64_matches_the_rfc_examples() {
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), coded);
        }
    }

    #[test]
    fn obj_faces_become_coloured_triangles() {
        let mtl = parse_mtl("newmtl dark\nKd 0.25 0.25 0.25\n");
        let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1/1 2/2/2 3/3/3 4/4/4\nusemtl dark\nf 1 2 3\n";
        let mesh = parse_obj(obj, &mtl).unwrap();
        assert_eq!(mesh.vertices.len(), 12);
        assert_eq!(mesh.indices, vec![0, 1, 2, 0, 2, 3, 0, 1, 2]);
        assert_eq!(mesh.groups[0].colour, DEFAULT_COLOUR);
        assert_eq!((mesh.groups[1].start, mesh.groups[1].count), (6, 3));
        assert_eq!(mesh.groups[1].colour, [0.25; 3]);
        assert!(
            parse_obj("v 0 0 0\nf 1 2 3\n", &mtl)
                .unwrap_err()
                .starts_with("line 2: bad vertex index")
        );
    }

    #[test]
    fn every_visual_of_the_urdf_is_embedded_and_on_a_frame() {
        let meshes = robot_meshes("panda", edmp_core::robot::PANDA.frame_names).unwrap();
        // link0..link7, hand, two fingers: every link with a mesh.
        assert_eq!(meshes.len(), 11);
        let right = meshes.iter().find(|m| m["link"] == "panda_rightfinger").unwrap();
        // The right finger's visual is turned half a turn about z (its URDF origin).
        let q = right["quaternion"].as_array().unwrap();
        assert!(q[0].as_f64().unwrap().abs() < 1e-9 && (q[3].as_f64().unwrap().abs() - 1.0).abs() < 1e-9);
    }

    /// Another arm's scene and plan: its own meshes on its own frames, its FK in the samples.
    fn another_arms_page<const J: usize>(robot: &'static Robot<f32, J>, meshes: usize) {
        let path = format!(
            "{}/../benchmarks/{}/problems/cubby/000.json",
            env!("CARGO_MANIFEST_DIR"),
            robot.name
        );
        let text = std::fs::read_to_string(&path).unwrap();
        let problem = parse_problem_for(&text, Path::new("."), robot).unwrap();
        let plan = PlanDocument {
            waypoints: vec![problem.start; 3],
            ..parse_plan_for::<J>(&plan_text(robot)).unwrap()
        };
        let data = embedded_data(&page(&problem, Some(&plan), "arm").unwrap());
        assert_eq!(data["robot"], robot.name);
        assert_eq!(data["frames"].as_array().unwrap().len(), robot.frame_names.len());
        let list = data["meshes"].as_array().unwrap();
        assert_eq!(list.len(), meshes, "{}", robot.name);
        for m in list {
            let frame = m["frame"].as_u64().unwrap() as usize;
            assert_eq!(m["link"], robot.frame_names[frame]);
            assert!(!m["indices"].as_str().unwrap().is_empty());
        }
        let poses = data["samples"]["poses"].as_array().unwrap();
        assert_eq!(poses.len(), 3);
        assert_eq!(poses[0].as_array().unwrap().len(), robot.frame_names.len() * 7);
    }

    /// The smallest `edmp-plan/1` document of `robot`'s joint count.
    fn plan_text<const J: usize>(robot: &Robot<f32, J>) -> String {
        let q = vec![0.0f32; robot.joint_names.len()];
        serde_json::json!({"format": "edmp-plan/1", "status": "success", "waypoints": vec![q; 50]}).to_string()
    }

    #[test]
    fn another_arm_is_drawn_with_its_own_meshes() {
        // The iiwa's eight visual meshes; the xArm's seven collision meshes (base and links).
        another_arms_page(&edmp_core::robot::arms::iiwa7::ROBOT, 8);
        another_arms_page(&edmp_core::robot::arms::xarm6::ROBOT, 7);
    }

    fn embedded_data(html: &str) -> Value {
        let start = html.find(r#"id="edmp-data">"#).unwrap() + r#"id="edmp-data">"#.len();
        let end = start + html[start..].find("</script>").unwrap();
        serde_json::from_str(&html[start..end]).unwrap()
    }

    #[test]
    fn a_timed_trajectory_plays_at_its_own_times_thinned_to_the_sample_rate() {
        let problem = crate::formats::json::parse_problem(include_str!("../../../../examples/wall.json")).unwrap();
        let (a, b) = (problem.start, [0.3, -0.5, 0.1, -2.0, 0.0, 1.6, 0.9]);
        // 1 kHz over 1.5 s: thinned to every 20th point (50 per second) and the last.
        let trajectory: Vec<(f32, Joints<f32>)> = (0..=1500)
            .map(|k| {
                let s = k as f32 / 1500.0;
                (k as f32 / 1000.0, core::array::from_fn(|j| a[j] + s * (b[j] - a[j])))
            })
            .collect();
        let plan = PlanDocument {
            status: "success".to_string(),
            stage: Some("diffusion".to_string()),
            waypoints: vec![a, b],
            trajectory: trajectory.clone(),
            candidates: Vec::new(),
            timing_ms: vec![("total".to_string(), 2.0)],
        };
        let data = embedded_data(&page(&problem, Some(&plan), "t</script>").unwrap());
        let times: Vec<f64> = serde_json::from_value(data["samples"]["times"].clone()).unwrap();
        assert_eq!(times.len(), 76);
        assert_eq!((times[0], times[1], times[75]), (0.0, 0.02, 1.5));
        assert_eq!(data["title"], "t</script>");
        // Each sample is the core's FK of its trajectory point: 13 frames, the TCP as its own.
        let k = forward_with(&edmp_core::robot::PANDA, &trajectory[1500].1, problem.scene().gripper()).unwrap();
        let tcp: [f64; 3] = serde_json::from_value(data["samples"]["tcp"][75].clone()).unwrap();
        let poses: Vec<f64> = serde_json::from_value(data["samples"]["poses"][75].clone()).unwrap();
        assert_eq!(poses.len(), 7 * FRAMES);
        for c in 0..3 {
            assert!((tcp[c] - f64::from(k.tcp().translation[c])).abs() < 1e-6);
            assert_eq!(poses[7 * TCP_FRAME + c], tcp[c]);
        }
    }

    fn unbase64(text: &str) -> Vec<u8> {
        const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let sextets: Vec<u32> = text
            .bytes()
            .filter(|&b| b != b'=')
            .map(|b| ALPHABET.iter().position(|&a| a == b).unwrap() as u32)
            .collect();
        let mut out = Vec::new();
        for chunk in sextets.chunks(4) {
            let n = chunk.iter().enumerate().fold(0, |n, (k, s)| n | (s << (18 - 6 * k)));
            out.extend(&n.to_be_bytes()[1..chunk.len()]);
        }
        out
    }

    #[test]
    fn clouds_are_thinned_to_every_kth_point_of_all_together() {
        let (a, b): (Vec<[f32; 3]>, Vec<[f32; 3]>) = (
            (0..70_000).map(|i| [i as f32, 0.0, 0.0]).collect(),
            (70_000..150_001).map(|i| [i as f32, 0.0, 0.0]).collect(),
        );
        let kept = thin_clouds(&[&a, &[], &b], MAX_VIEW_POINTS);
        // 150,001 points: every 2nd, 75,001 in all, by their index in the whole list.
        assert_eq!(kept.iter().map(Vec::len).sum::<usize>(), 75_001);
        assert!(kept.iter().flatten().all(|p| (p[0] as usize).is_multiple_of(2)));
        assert_eq!(kept[1].len(), 0);
        let small = thin_clouds(&[&a[..10]], MAX_VIEW_POINTS);
        assert_eq!(small[0].len(), 10);
    }

    #[test]
    fn the_page_holds_the_clouds_points_and_the_meshes_triangles() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/surfaces.json");
        let dir = Path::new(path).parent().unwrap();
        let problem = crate::formats::json::parse_problem_in(&std::fs::read_to_string(path).unwrap(), dir).unwrap();
        let data = embedded_data(&page(&problem, None, "surfaces").unwrap());
        assert_eq!(data["obstacles"].as_array().unwrap().len(), 1, "the sphere");
        let floats = |v: &Value| -> Vec<f32> {
            unbase64(v.as_str().unwrap())
                .chunks(4)
                .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
                .collect()
        };
        let list = data["surfaces"].as_array().unwrap();
        assert_eq!(list.len(), 2);
        let (cloud, mesh) = (&list[0], &list[1]);
        assert_eq!(
            (cloud["type"].as_str(), cloud["index"].as_u64()),
            (Some("points"), Some(0))
        );
        assert_eq!(
            (cloud["count"].as_u64(), cloud["drawn"].as_u64()),
            (Some(400), Some(400))
        );
        assert_eq!(cloud["radius"].as_f64(), Some(0.01f32 as f64));
        let SurfaceKind::Points { points, .. } = &problem.surfaces.obstacles[0].kind else {
            panic!("a cloud first")
        };
        assert_eq!(
            floats(&cloud["points"]),
            points.iter().flatten().copied().collect::<Vec<_>>()
        );
        // Placed in the world: the grid's corner is at the centre plus (0, -0.15, -0.15).
        assert!((points[0][1] - -0.75).abs() < 1e-6 && (points[0][2] - 0.9).abs() < 1e-6);
        assert_eq!((mesh["type"].as_str(), mesh["index"].as_u64()), (Some("mesh"), Some(2)));
        let SurfaceKind::Mesh { vertices, triangles } = &problem.surfaces.obstacles[1].kind else {
            panic!("a mesh second")
        };
        assert_eq!(mesh["triangles"].as_u64(), Some(12));
        assert_eq!(
            floats(&mesh["vertices"]),
            vertices.iter().flatten().copied().collect::<Vec<_>>()
        );
        let indices: Vec<u32> = unbase64(mesh["indices"].as_str().unwrap())
            .chunks(4)
            .map(|b| u32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(indices, triangles.iter().flatten().copied().collect::<Vec<_>>());
    }
}
