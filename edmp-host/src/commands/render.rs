//! `edmp-host render`: a picture of a scene (and of a plan): a top, a side and a front view,
//! orthographic, obstacles in grey, the robot's collision hulls at the start (blue) and the
//! goal (green), and with a plan every fourth waypoint in orange, fading in along the
//! trajectory, and the path of the TCP in dark red. `--candidates` overlays the TCP path of
//! every candidate of the ensemble (plans written with `edmp-host plan --candidates`): one
//! colour per collision-free candidate, grey for colliding ones.
//! A small convex-polygon rasteriser and the `png` encoder; no system fonts or libraries.

use crate::formats::json::{Goal, parse_problem_in};
use crate::formats::plan::parse_plan;
use edmp_core::collision::convex::{Convex, Solid};
use edmp_core::robot::kinematics::{Joints, forward, forward_with};
use edmp_core::robot::{BODIES, PANDA};
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

/// Pixel of world point `p` in a view, with the panel offset.
fn pixel(p: &Vector3<f32>, view: View) -> [f32; 2] {
    let scale = |x: f32, range: [f32; 2]| (x - range[0]) / (range[1] - range[0]) * PANEL as f32;
    let (u, v, panel) = match view {
        View::Top => (scale(p.x, X_RANGE), scale(p.y, Y_RANGE), 0),
        View::Side => (scale(p.x, X_RANGE), scale(p.z, Z_RANGE), 1),
        View::Front => (scale(p.y, Y_RANGE), scale(p.z, Z_RANGE), 2),
    };
    [u + (panel * PANEL) as f32, PANEL as f32 - v]
}

fn draw(canvas: &mut Canvas, points: &[Vector3<f32>], color: [f32; 3], alpha: f32) {
    for view in VIEWS {
        let poly = hull2(points.iter().map(|p| pixel(p, view)).collect());
        canvas.fill(&poly, color, alpha);
    }
}

/// The TCP's path along a trajectory, as a polyline in every view.
fn draw_tcp_path(
    canvas: &mut Canvas,
    path: &[Joints<f32>],
    width: f32,
    color: [f32; 3],
    alpha: f32,
) -> Result<(), String> {
    let points: Vec<Vector3<f32>> = path
        .iter()
        .map(|q| forward(q).map(|k| k.tcp().translation).map_err(|e| e.to_string()))
        .collect::<Result<_, _>>()?;
    for view in VIEWS {
        for pair in points.windows(2) {
            canvas.line(pixel(&pair[0], view), pixel(&pair[1], view), width, color, alpha);
        }
    }
    Ok(())
}

fn draw_robot(canvas: &mut Canvas, q: &Joints<f32>, finger: f32, color: [f32; 3], alpha: f32) -> Result<(), String> {
    let k = forward_with(q, finger).map_err(|e| e.to_string())?;
    for b in 0..BODIES {
        let pose = &k.frames[PANDA.bodies[b].frame];
        let pts: Vec<_> = PANDA.hull(b).iter().map(|p| pose.transform_point(p)).collect();
        draw(canvas, &pts, color, alpha);
    }
    Ok(())
}

/// Draws the scene (and plan) and writes the PNG.
pub fn run(args: &Args) -> Result<(), String> {
    let text = std::fs::read_to_string(&args.scene).map_err(|e| format!("{}: {e}", args.scene.display()))?;
    let dir = args.scene.parent().unwrap_or(std::path::Path::new("."));
    let problem = parse_problem_in(&text, dir).map_err(|e| format!("{}: {e}", args.scene.display()))?;
    let plan = match &args.plan {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
            Some(parse_plan(&text).map_err(|e| format!("{}: {e}", path.display()))?)
        }
        None => None,
    };
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
        draw(&mut canvas, &outline(&Solid::obstacle(o)), [0.35, 0.35, 0.38], 0.45);
    }
    let finger = problem.scene().gripper();
    let path = plan.as_ref().map(|p| &p.waypoints);
    if let Some(path) = &path {
        let n = path.len().max(1);
        for (i, q) in path.iter().enumerate().step_by(4) {
            draw_robot(
                &mut canvas,
                q,
                finger,
                [0.95, 0.55, 0.1],
                0.08 + 0.2 * i as f32 / n as f32,
            )?;
        }
    }
    draw_robot(&mut canvas, &problem.start, finger, [0.15, 0.35, 0.85], 0.35)?;
    if let Goal::Joints(goal) = problem.goal {
        draw_robot(&mut canvas, &goal, finger, [0.1, 0.65, 0.25], 0.35)?;
    }
    if args.candidates {
        let list = plan
            .as_ref()
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
            draw_tcp_path(&mut canvas, &c.waypoints, 2.0, colour, 0.8)?;
        }
    }
    if let Some(path) = &path {
        draw_tcp_path(&mut canvas, path, 3.5, [0.6, 0.05, 0.05], 0.95)?;
    }
    canvas.png(&args.output)
}
