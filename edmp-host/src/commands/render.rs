//! `edmp-host render`: a picture of a scene (and of a plan): a top, a side and a front view,
//! orthographic, obstacles in grey, the robot's collision hulls at the start (blue) and the
//! goal (green), and with a plan every fourth waypoint in orange, fading in along the
//! trajectory, and the path of the TCP in dark red. `--candidates` overlays the TCP path of
//! every candidate of the ensemble (plans written with `edmp-host plan --candidates`): one
//! colour per collision-free candidate, grey for colliding ones.
//! Clouds (`points` obstacles) and meshes are grey too: each cloud as a dot of its ball radius
//! per point (every k-th point when it has more than [`MAX_DRAWN_POINTS`]), each mesh as its
//! triangles, flat shaded; depth-tested within the obstacle, which is then blended once, as
//! translucent as a primitive.
//! A small convex-polygon rasteriser and the `png` encoder; no system fonts or libraries.

use crate::formats::json::{Goal, Problem, parse_problem_for, scene_arm};
use crate::formats::plan::{PlanDocument, parse_plan_for};
use crate::formats::surface::SurfaceKind;
use crate::with_arm;
use edmp_core::collision::convex::{Convex, Solid};
use edmp_core::robot::kinematics::{Joints, forward, forward_with};
use edmp_core::robot::{MAX_FRAMES, Robot};
use edmp_core::scene::Shape;
use nalgebra::Vector3;
use std::path::PathBuf;

/// Arguments of `edmp-host render`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene (`edmp-scene/1`).
    scene: PathBuf,
    /// A plan (`edmp-plan/1`) to draw on it.
    plan: Option<PathBuf>,
    /// Output PNG.
    #[arg(short, long)]
    output: PathBuf,
    /// Overlay the TCP path of every candidate in the plan (multimodality).
    #[arg(long)]
    candidates: bool,
}

const PANEL: usize = 600;
/// World window of the views: x (forward), y (left), z (up).
const X_RANGE: [f32; 2] = [-0.5, 1.4];
const Y_RANGE: [f32; 2] = [-0.95, 0.95];
const Z_RANGE: [f32; 2] = [-0.15, 1.75];

/// The most points of one cloud drawn: a larger cloud is drawn every k-th point (k the
/// smallest that fits), in the file's order.
pub const MAX_DRAWN_POINTS: usize = 20_000;

/// Colour of the obstacles, and its opacity.
const OBSTACLE: [f32; 3] = [0.35, 0.35, 0.38];
const OBSTACLE_ALPHA: f32 = 0.45;
/// Colours of a cloud's or mesh's surface turned away from the light and facing it.
const SURFACE_DARK: [f32; 3] = [0.22, 0.22, 0.25];
const SURFACE_LIGHT: [f32; 3] = [0.52, 0.52, 0.55];

/// The three panels, left to right: top (x right, y up), side (x right, z up), front (seen
/// from +x: y right, z up).
const VIEWS: [View; 3] = [View::Top, View::Side, View::Front];

#[derive(Clone, Copy, PartialEq, Eq)]
enum View {
    Top,
    Side,
    Front,
}

/// Colours of the candidates' TCP paths.
const CANDIDATE_COLOURS: [[f32; 3]; 6] = [
    [0.12, 0.47, 0.71],
    [0.17, 0.63, 0.17],
    [0.58, 0.40, 0.74],
    [0.89, 0.47, 0.76],
    [0.09, 0.75, 0.81],
    [0.74, 0.74, 0.13],
];

/// An RGB raster with alpha-blended convex fills (no anti-aliasing).
#[derive(Debug)]
pub struct Canvas {
    width: usize,
    height: usize,
    pixels: Vec<[f32; 3]>,
}

impl Canvas {
    /// A white canvas of `width` × `height` pixels.
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            pixels: vec![[1.0; 3]; width * height],
        }
    }

    /// Fills a convex polygon (pixel coordinates) blending `color` with opacity `alpha`.
    pub fn fill(&mut self, poly: &[[f32; 2]], color: [f32; 3], alpha: f32) {
        if poly.len() < 3 {
            return;
        }
        let (lo, hi) = poly.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), p| {
            (a.min(p[1]), b.max(p[1]))
        });
        let (y0, y1) = (
            lo.max(0.0).ceil() as usize,
            (hi.min(self.height as f32 - 1.0)).floor().max(0.0) as usize,
        );
        for y in y0..=y1.min(self.height - 1) {
            let yc = y as f32;
            let (mut left, mut right) = (f32::INFINITY, f32::NEG_INFINITY);
            for k in 0..poly.len() {
                let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
                if (a[1] <= yc && b[1] >= yc) || (b[1] <= yc && a[1] >= yc) {
                    let x = if (b[1] - a[1]).abs() < 1e-6 {
                        a[0].min(b[0])
                    } else {
                        a[0] + (yc - a[1]) / (b[1] - a[1]) * (b[0] - a[0])
                    };
                    let x2 = if (b[1] - a[1]).abs() < 1e-6 { a[0].max(b[0]) } else { x };
                    left = left.min(x);
                    right = right.max(x2);
                }
            }
            if left > right {
                continue;
            }
            let (x0, x1) = (
                left.max(0.0).ceil() as usize,
                right.min(self.width as f32 - 1.0).floor().max(0.0) as usize,
            );
            for x in x0..=x1.min(self.width - 1) {
                let p = &mut self.pixels[y * self.width + x];
                for c in 0..3 {
                    p[c] = p[c] * (1.0 - alpha) + color[c] * alpha;
                }
            }
        }
    }

    /// A straight segment `width` pixels wide.
    pub fn line(&mut self, a: [f32; 2], b: [f32; 2], width: f32, color: [f32; 3], alpha: f32) {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = (dx * dx + dy * dy).sqrt().max(1e-6);
        let (nx, ny) = (-dy / len * width * 0.5, dx / len * width * 0.5);
        let quad = [
            [a[0] + nx, a[1] + ny],
            [b[0] + nx, b[1] + ny],
            [b[0] - nx, b[1] - ny],
            [a[0] - nx, a[1] - ny],
        ];
        self.fill(&quad, color, alpha);
    }

    /// Writes the canvas as a PNG file.
    pub fn png(&self, path: &std::path::Path) -> Result<(), String> {
        let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), self.width as u32, self.height as u32);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
        let bytes: Vec<u8> = self
            .pixels
            .iter()
            .flat_map(|p| p.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8))
            .collect();
        writer.write_image_data(&bytes).map_err(|e| e.to_string())
    }
}

/// Convex hull of 2-D points (Andrew's monotone chain), counter-clockwise.
fn hull2(mut pts: Vec<[f32; 2]>) -> Vec<[f32; 2]> {
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let cross = |o: [f32; 2], a: [f32; 2], b: [f32; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    let mut lower: Vec<[f32; 2]> = Vec::new();
    for &p in &pts {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0.0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<[f32; 2]> = Vec::new();
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0.0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// Outline points of a primitive (from its support function in 64 directions around each
/// view axis, enough for the silhouettes of boxes, cylinders and spheres).
fn outline(p: &Solid) -> Vec<Vector3<f32>> {
    let mut out = Vec::new();
    for k in 0..64 {
        let a = k as f32 * core::f32::consts::TAU / 64.0;
        let (s, c) = a.sin_cos();
        out.push(p.support(&Vector3::new(c, s, 0.0)));
        out.push(p.support(&Vector3::new(c, 0.0, s)));
        out.push(p.support(&Vector3::new(0.0, c, s)));
    }
    if let Shape::Cuboid { .. } = p.shape {
        for k in 0..8 {
            let d = Vector3::new(
                if k & 1 == 1 { 1.0 } else { -1.0 },
                if k & 2 == 2 { 1.0 } else { -1.0 },
                if k & 4 == 4 { 1.0 } else { -1.0 },
            );
            out.push(p.support(&(p.rotation * d)));
        }
    }
    out
}

impl View {
    fn panel(self) -> usize {
        match self {
            View::Top => 0,
            View::Side => 1,
            View::Front => 2,
        }
    }

    /// World directions of the panel's right and up, and towards the viewer.
    fn axes(self) -> [Vector3<f32>; 3] {
        match self {
            View::Top => [Vector3::x(), Vector3::y(), Vector3::z()],
            View::Side => [Vector3::x(), Vector3::z(), -Vector3::y()],
            View::Front => [Vector3::y(), Vector3::z(), Vector3::x()],
        }
    }

    /// Where the light comes from: towards the viewer, from the upper left.
    fn light(self) -> Vector3<f32> {
        let [right, up, out] = self.axes();
        (out + 0.6 * up - 0.4 * right).normalize()
    }
}

/// Pixels per metre (the three windows are equally wide).
const SCALE: f32 = PANEL as f32 / (X_RANGE[1] - X_RANGE[0]);

/// Pixel of world point `p` within its view's panel, and its depth (metres, away from the
/// viewer).
fn panel_pixel(p: &Vector3<f32>, view: View) -> [f32; 3] {
    let scale = |x: f32, range: [f32; 2]| (x - range[0]) / (range[1] - range[0]) * PANEL as f32;
    let (u, v, depth) = match view {
        View::Top => (scale(p.x, X_RANGE), scale(p.y, Y_RANGE), -p.z),
        View::Side => (scale(p.x, X_RANGE), scale(p.z, Z_RANGE), p.y),
        View::Front => (scale(p.y, Y_RANGE), scale(p.z, Z_RANGE), -p.x),
    };
    [u, PANEL as f32 - v, depth]
}

/// Pixel of world point `p` in a view, with the panel offset.
fn pixel(p: &Vector3<f32>, view: View) -> [f32; 2] {
    let [u, v, _] = panel_pixel(p, view);
    [u + (view.panel() * PANEL) as f32, v]
}

fn mix(a: [f32; 3], b: [f32; 3], s: f32) -> [f32; 3] {
    let s = s.clamp(0.0, 1.0);
    [0, 1, 2].map(|c| a[c] + s * (b[c] - a[c]))
}

/// One obstacle in one panel: the nearest surface's colour and depth per pixel, so that the
/// obstacle is blended onto the canvas once however many of its pieces overlap.
struct Layer {
    view: View,
    depth: Vec<f32>,
    colour: Vec<[f32; 3]>,
}

impl Layer {
    fn new(view: View) -> Self {
        Self {
            view,
            depth: vec![f32::INFINITY; PANEL * PANEL],
            colour: vec![[0.0; 3]; PANEL * PANEL],
        }
    }

    /// Sets pixel (x, y) of the panel to `colour` if `depth` is nearer than what it holds.
    fn put(&mut self, x: i64, y: i64, depth: f32, colour: [f32; 3]) {
        if !(0..PANEL as i64).contains(&x) || !(0..PANEL as i64).contains(&y) {
            return;
        }
        let k = y as usize * PANEL + x as usize;
        if depth < self.depth[k] {
            self.depth[k] = depth;
            self.colour[k] = colour;
        }
    }

    /// A ball of `radius` pixels (at least one pixel) around `centre`, shaded as a sphere.
    fn ball(&mut self, centre: [f32; 3], radius: f32) {
        let light = {
            let [right, up, out] = self.view.axes();
            let l = self.view.light();
            Vector3::new(l.dot(&right), l.dot(&up), l.dot(&out))
        };
        // At least one pixel: the nearest pixel centre is within 0.71 of any point.
        let r = radius.max(1.0);
        let (x0, x1) = ((centre[0] - r).floor() as i64, (centre[0] + r).ceil() as i64);
        let (y0, y1) = ((centre[1] - r).floor() as i64, (centre[1] + r).ceil() as i64);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (dx, dy) = (x as f32 - centre[0], centre[1] - y as f32);
                let d2 = dx * dx + dy * dy;
                if d2 > r * r {
                    continue;
                }
                let dz = (r * r - d2).max(0.0).sqrt();
                let normal = Vector3::new(dx, dy, dz) / r;
                let colour = mix(SURFACE_DARK, SURFACE_LIGHT, normal.dot(&light));
                self.put(x, y, centre[2] - dz / SCALE, colour);
            }
        }
    }

    /// A triangle (world corners), flat shaded, its edges drawn too so that one seen edge-on
    /// is still a line.
    fn triangle(&mut self, corners: [Vector3<f32>; 3]) {
        let normal = (corners[1] - corners[0]).cross(&(corners[2] - corners[0]));
        let norm = normal.norm();
        if norm.is_nan() || norm <= 0.0 {
            return;
        }
        // Both sides lit alike: meshes need not be closed nor consistently wound.
        let colour = mix(
            SURFACE_DARK,
            SURFACE_LIGHT,
            (normal / norm).dot(&self.view.light()).abs(),
        );
        let p = corners.map(|c| panel_pixel(&c, self.view));
        let edge = |a: [f32; 3], b: [f32; 3], x: f32, y: f32| (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
        let area = edge(p[0], p[1], p[2][0], p[2][1]);
        if area.abs() > 1e-6 {
            let lo = |k: usize| p.iter().map(|q| q[k]).fold(f32::INFINITY, f32::min).floor().max(0.0) as i64;
            let hi = |k: usize| {
                p.iter()
                    .map(|q| q[k])
                    .fold(f32::NEG_INFINITY, f32::max)
                    .ceil()
                    .min(PANEL as f32 - 1.0) as i64
            };
            for y in lo(1)..=hi(1) {
                for x in lo(0)..=hi(0) {
                    let (xf, yf) = (x as f32, y as f32);
                    let w = [
                        edge(p[1], p[2], xf, yf) / area,
                        edge(p[2], p[0], xf, yf) / area,
                        edge(p[0], p[1], xf, yf) / area,
                    ];
                    if w.iter().all(|&wk| wk >= 0.0) {
                        self.put(x, y, w[0] * p[0][2] + w[1] * p[1][2] + w[2] * p[2][2], colour);
                    }
                }
            }
        }
        for k in 0..3 {
            let (a, b) = (p[k], p[(k + 1) % 3]);
            let steps = (b[0] - a[0])
                .abs()
                .max((b[1] - a[1]).abs())
                .ceil()
                .clamp(1.0, 4.0 * PANEL as f32) as usize;
            for i in 0..=steps {
                let s = i as f32 / steps as f32;
                let q = [0, 1, 2].map(|c| a[c] + s * (b[c] - a[c]));
                self.put(q[0].round() as i64, q[1].round() as i64, q[2], colour);
            }
        }
    }

    /// Blends what the layer holds onto its panel of the canvas.
    fn blend(&self, canvas: &mut Canvas, alpha: f32) {
        let offset = self.view.panel() * PANEL;
        for y in 0..PANEL {
            for x in 0..PANEL {
                let k = y * PANEL + x;
                if self.depth[k].is_finite() {
                    let p = &mut canvas.pixels[y * canvas.width + offset + x];
                    *p = mix(*p, self.colour[k], alpha);
                }
            }
        }
    }
}

/// Every `stride`-th point of a cloud, `stride` the smallest that draws at most `max`.
fn thinned(points: &[[f32; 3]], max: usize) -> impl Iterator<Item = &[f32; 3]> {
    points.iter().step_by(points.len().div_ceil(max.max(1)).max(1))
}

/// The scene's clouds and meshes, in every view.
fn draw_surfaces<const J: usize>(canvas: &mut Canvas, problem: &Problem<J>) {
    for o in &problem.surfaces.obstacles {
        for view in VIEWS {
            let mut layer = Layer::new(view);
            match &o.kind {
                SurfaceKind::Points { points, radius, .. } => {
                    for p in thinned(points, MAX_DRAWN_POINTS) {
                        layer.ball(panel_pixel(&Vector3::from(*p), view), radius * SCALE);
                    }
                }
                SurfaceKind::Mesh { vertices, triangles } => {
                    for t in triangles {
                        let corner = |i: u32| vertices.get(i as usize).map(|&v| Vector3::from(v));
                        if let (Some(a), Some(b), Some(c)) = (corner(t[0]), corner(t[1]), corner(t[2])) {
                            layer.triangle([a, b, c]);
                        }
                    }
                }
            }
            layer.blend(canvas, OBSTACLE_ALPHA);
        }
    }
}

fn draw(canvas: &mut Canvas, points: &[Vector3<f32>], color: [f32; 3], alpha: f32) {
    for view in VIEWS {
        let poly = hull2(points.iter().map(|p| pixel(p, view)).collect());
        canvas.fill(&poly, color, alpha);
    }
}

/// The TCP's path along a trajectory, as a polyline in every view.
fn draw_tcp_path<const J: usize>(
    canvas: &mut Canvas,
    robot: &'static Robot<f32, J>,
    path: &[Joints<f32, J>],
    width: f32,
    color: [f32; 3],
    alpha: f32,
) -> Result<(), String> {
    let points: Vec<Vector3<f32>> = path
        .iter()
        .map(|q| {
            forward(robot, q)
                .map(|k| k.tcp().translation)
                .map_err(|e| e.to_string())
        })
        .collect::<Result<_, _>>()?;
    for view in VIEWS {
        for pair in points.windows(2) {
            canvas.line(pixel(&pair[0], view), pixel(&pair[1], view), width, color, alpha);
        }
    }
    Ok(())
}

/// The arm's collision hulls at `q` (the fingers at `finger` where it has them).
fn draw_robot<const J: usize>(
    canvas: &mut Canvas,
    robot: &'static Robot<f32, J>,
    q: &Joints<f32, J>,
    finger: f32,
    color: [f32; 3],
    alpha: f32,
) -> Result<(), String> {
    let k = forward_with(robot, q, robot.finger_opening(finger)).map_err(|e| e.to_string())?;
    for (b, body) in robot.bodies.iter().enumerate() {
        let pose = &k.frames[body.frame.min(MAX_FRAMES - 1)];
        let pts: Vec<_> = robot.hull(b).iter().map(|p| pose.transform_point(p)).collect();
        draw(canvas, &pts, color, alpha);
    }
    Ok(())
}

/// Reads the scene (and plan), draws them with the arm the scene names and writes the PNG.
pub fn run(args: &Args) -> Result<(), String> {
    let text = std::fs::read_to_string(&args.scene).map_err(|e| format!("{}: {e}", args.scene.display()))?;
    let arm = scene_arm(&text).map_err(|e| format!("{}: {e}", args.scene.display()))?;
    with_arm!(arm, robot => render(args, &text, robot))
}

fn render<const J: usize>(args: &Args, text: &str, robot: &'static Robot<f32, J>) -> Result<(), String> {
    let dir = args.scene.parent().unwrap_or(std::path::Path::new("."));
    let problem = parse_problem_for(text, dir, robot).map_err(|e| format!("{}: {e}", args.scene.display()))?;
    let plan = match &args.plan {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
            Some(parse_plan_for::<J>(&text).map_err(|e| format!("{}: {e}", path.display()))?)
        }
        None => None,
    };
    picture(&problem, plan.as_ref(), args.candidates)?.png(&args.output)
}

/// The three views of `problem` (and `plan`, its candidates' paths with `candidates`).
fn picture<const J: usize>(
    problem: &Problem<J>,
    plan: Option<&PlanDocument<J>>,
    candidates: bool,
) -> Result<Canvas, String> {
    let robot = problem.robot;
    let mut canvas = Canvas::new(VIEWS.len() * PANEL, PANEL);
    // Panel frames and the floor line of the side and front views.
    for panel in 1..VIEWS.len() {
        let x = (panel * PANEL) as f32;
        canvas.fill(
            &[
                [x - 1.0, 0.0],
                [x + 1.0, 0.0],
                [x + 1.0, PANEL as f32],
                [x - 1.0, PANEL as f32],
            ],
            [0.3; 3],
            1.0,
        );
        let floor = pixel(&Vector3::zeros(), View::Side)[1];
        canvas.fill(
            &[
                [x, floor],
                [x + PANEL as f32, floor],
                [x + PANEL as f32, floor + 1.0],
                [x, floor + 1.0],
            ],
            [0.6; 3],
            1.0,
        );
    }
    for o in problem.scene().obstacles() {
        draw(&mut canvas, &outline(&Solid::obstacle(o)), OBSTACLE, OBSTACLE_ALPHA);
    }
    draw_surfaces(&mut canvas, problem);
    let finger = problem.scene().gripper();
    let path = plan.map(|p| &p.waypoints);
    if let Some(path) = &path {
        let n = path.len().max(1);
        for (i, q) in path.iter().enumerate().step_by(4) {
            draw_robot(
                &mut canvas,
                robot,
                q,
                finger,
                [0.95, 0.55, 0.1],
                0.08 + 0.2 * i as f32 / n as f32,
            )?;
        }
    }
    draw_robot(&mut canvas, robot, &problem.start, finger, [0.15, 0.35, 0.85], 0.35)?;
    if let Goal::Joints(goal) = problem.goal {
        draw_robot(&mut canvas, robot, &goal, finger, [0.1, 0.65, 0.25], 0.35)?;
    }
    if candidates {
        let list = plan
            .map(|p| &p.candidates)
            .filter(|c| !c.is_empty())
            .ok_or("--candidates: the plan has no candidates (write it with `edmp-host plan --candidates`)")?;
        let mut free = 0;
        for c in list {
            let colour = if c.collision_free {
                free += 1;
                CANDIDATE_COLOURS[(free - 1) % CANDIDATE_COLOURS.len()]
            } else {
                [0.55; 3]
            };
            draw_tcp_path(&mut canvas, robot, &c.waypoints, 2.0, colour, 0.8)?;
        }
    }
    if let Some(path) = &path {
        draw_tcp_path(&mut canvas, robot, path, 3.5, [0.6, 0.05, 0.05], 0.95)?;
    }
    Ok(canvas)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::json::parse_problem_in;

    #[test]
    fn a_large_cloud_is_drawn_every_kth_point_within_the_bound() {
        let cloud: Vec<[f32; 3]> = (0..60_001).map(|i| [i as f32, 0.0, 0.0]).collect();
        let drawn: Vec<_> = thinned(&cloud, MAX_DRAWN_POINTS).collect();
        assert_eq!(drawn.len(), 15_001, "every 4th point");
        assert_eq!((drawn[1][0], drawn[15_000][0]), (4.0, 60_000.0));
        assert_eq!(
            thinned(&cloud[..MAX_DRAWN_POINTS], MAX_DRAWN_POINTS).count(),
            MAX_DRAWN_POINTS
        );
        assert_eq!(thinned(&[], MAX_DRAWN_POINTS).count(), 0);
    }

    /// Pixel bounds (x0, y0, x1, y1, canvas coordinates) of world points in a view.
    fn bounds(points: &[[f32; 3]], view: View, margin: f32) -> [f32; 4] {
        let mut b = [f32::INFINITY, f32::INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY];
        for p in points {
            let [x, y] = pixel(&Vector3::from(*p), view);
            b = [
                b[0].min(x - margin),
                b[1].min(y - margin),
                b[2].max(x + margin),
                b[3].max(y + margin),
            ];
        }
        b
    }

    #[test]
    fn clouds_and_meshes_are_drawn_where_they_are_in_every_view_and_nowhere_else() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/surfaces.json");
        let dir = std::path::Path::new(path).parent().unwrap();
        let problem = parse_problem_in(&std::fs::read_to_string(path).unwrap(), dir).unwrap();
        let mut bare = problem.clone();
        bare.surfaces.obstacles.clear();
        let (with, without) = (
            picture(&problem, None, false).unwrap(),
            picture(&bare, None, false).unwrap(),
        );
        let changed = |x: usize, y: usize| {
            let k = y * with.width + x;
            (0..3).any(|c| (with.pixels[k][c] - without.pixels[k][c]).abs() > 1e-4)
        };
        // Each obstacle's pixel bounds: within them (less a pixel) mostly drawn (a cloud's
        // dots leave its corners), nothing drawn beyond them (plus a pixel and a half).
        let [cloud, mesh] = [0, 1].map(|k| match &problem.surfaces.obstacles[k].kind {
            SurfaceKind::Points { points, radius, .. } => (points.clone(), radius * SCALE),
            SurfaceKind::Mesh { vertices, triangles } => {
                assert_eq!(triangles.len(), 12);
                (vertices.clone(), 0.0)
            }
        });
        assert_eq!(cloud.0.len(), 400);
        let mut inside = vec![false; with.pixels.len()];
        let range = |lo: f32, hi: f32, end: usize| (lo.ceil().max(0.0) as usize)..=(hi.floor() as usize).min(end - 1);
        for view in VIEWS {
            for (points, margin) in [&cloud, &mesh] {
                let b = bounds(points, view, margin + 1.5);
                for y in range(b[1], b[3], PANEL) {
                    for x in range(b[0], b[2], with.width) {
                        inside[y * with.width + x] = true;
                    }
                }
                let b = bounds(points, view, margin - 1.0);
                let (mut n, mut hit) = (0, 0);
                for y in range(b[1], b[3], PANEL) {
                    for x in range(b[0], b[2], with.width) {
                        n += 1;
                        hit += usize::from(changed(x, y));
                    }
                }
                assert!(
                    n > 20 && hit as f32 >= 0.9 * n as f32,
                    "panel {}: {hit} of {n} pixels drawn",
                    view.panel()
                );
            }
        }
        let stray = (0..PANEL)
            .flat_map(|y| (0..with.width).map(move |x| (x, y)))
            .filter(|&(x, y)| changed(x, y) && !inside[y * with.width + x])
            .count();
        assert_eq!(stray, 0, "pixels drawn outside the cloud and the mesh");
        // The mesh's centre, in the side view: grey, as translucent as a primitive.
        let [x, y] = pixel(&Vector3::new(0.3, 0.65, 0.9), View::Side);
        let p = with.pixels[y as usize * with.width + x as usize];
        assert!(
            p.iter().all(|&c| (0.6..0.9).contains(&c)) && (p[0] - p[1]).abs() < 1e-3,
            "{p:?}"
        );
    }
}
