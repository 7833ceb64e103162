//! `edmp-host view` as a person uses it: the page is one self-contained file, and headless
//! Chromium (software WebGL) draws the arm where the core's forward kinematics puts it.
//!
//! The browser part runs where `/usr/bin/chromium` exists (scripts/test installs it); without
//! it the test prints a note and skips, except under CI (`CI=true`), where it fails.

use edmp_core::robot::kinematics::forward_with;
use edmp_host::commands::view::EVEN_STEP_S;
use edmp_host::formats::json::parse_problem;
use edmp_host::formats::plan::parse_plan;
use std::path::{Path, PathBuf};
use std::process::Command;

const CHROMIUM: &str = "/usr/bin/chromium";
/// The page of a 50-waypoint plan with its candidates stays under this many bytes.
const MAX_PAGE_BYTES: usize = 3_000_000;
/// Browser window (CSS pixels at scale 1 = screenshot pixels).
const WIDTH: usize = 1000;
const HEIGHT: usize = 700;

fn edmp_host(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_edmp-host"))
        .args(args)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("edmp-host runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("edmp-view-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Plans `examples/wall.json` (50 waypoints, with candidates) and writes its page.
fn wall_page(dir: &Path) -> (PathBuf, PathBuf) {
    let (plan, page) = (dir.join("plan.json"), dir.join("plan.html"));
    let out = edmp_host(&[
        "plan",
        "examples/wall.json",
        "--candidates",
        "-o",
        plan.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = edmp_host(&[
        "view",
        "examples/wall.json",
        plan.to_str().unwrap(),
        "-o",
        page.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    (plan, page)
}

#[test]
fn the_page_is_one_small_file_that_fetches_nothing() {
    let dir = scratch("offline");
    let (_, page) = wall_page(&dir);
    let html = std::fs::read_to_string(&page).unwrap();
    println!("page of a 50-waypoint plan with candidates: {} bytes", html.len());
    assert!(html.len() < MAX_PAGE_BYTES, "{} bytes", html.len());
    // Outside the scripts' text: no element that loads anything.
    let mut markup = String::new();
    let mut rest = html.as_str();
    while let Some(open) = rest.find("<script") {
        let close = rest[open..].find("</script>").expect("every script is closed") + open;
        markup.push_str(&rest[..open]);
        markup.push_str(&rest[open..open + rest[open..].find('>').unwrap() + 1]);
        rest = &rest[close + "</script>".len()..];
    }
    markup.push_str(rest);
    for word in ["src=", "href=", "url(", "http:", "https:", "<link", "<iframe", "<img"] {
        assert!(!markup.contains(word), "the page's markup has {word}");
    }
    // Nowhere a script import or fetch of a URL (three.js's comments and XML namespaces name
    // URLs; none is loaded).
    for scheme in ["http://", "https://"] {
        for (at, _) in html.match_indices(scheme) {
            let before = &html[at.saturating_sub(40)..at];
            for word in ["src=", "import", "from", "fetch(", "url(", "href"] {
                assert!(
                    !before.contains(word),
                    "{word} … {}",
                    &html[at..(at + 60).min(html.len())]
                );
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_names_the_field_exits_2_and_writes_nothing() {
    let dir = scratch("bad");
    let plan = dir.join("plan.json");
    let page = dir.join("plan.html");
    let doc = serde_json::json!({
        "format": "edmp-plan/1",
        "status": "success",
        "waypoints": [[0.6, 0.2, 0.0, -2.0, 0.0, 2.2, 0.785], [0.6, 0.2, 0.0, -2.0, 0.0, 2.2]],
    });
    std::fs::write(&plan, doc.to_string()).unwrap();
    let out = edmp_host(&[
        "view",
        "examples/wall.json",
        plan.to_str().unwrap(),
        "-o",
        page.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("plan.json: waypoints[1]: expected 7 numbers, found 6"),
        "{stderr}"
    );
    assert!(!page.exists());
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/wall.json"))
        .unwrap()
        .replace(r#""radius": 0.06"#, r#""radius": -0.06"#);
    let scene = dir.join("scene.json");
    std::fs::write(&scene, text).unwrap();
    let out = edmp_host(&["view", scene.to_str().unwrap(), "-o", page.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("scene.json: obstacles[3].radius: must be positive"),
        "{stderr}"
    );
    assert!(!page.exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// What one headless Chromium load of the page reported, and its screenshot.
struct Shot {
    /// Seconds into the motion (`data-t`).
    time: f64,
    /// The drawn TCP's world position (`data-tcp`), from three.js's world matrix.
    tcp: [f64; 3],
    /// Where it is drawn, pixels (`data-tcp-px`).
    pixel: [f64; 2],
    /// Milliseconds from navigation to the first frame drawn (`data-load-ms`).
    load_ms: f64,
    /// RGB rows of the screenshot.
    rgb: Vec<u8>,
    /// The `<body>` tag with its `data-` attributes.
    body: String,
}

fn chromium(dir: &Path, page: &Path, fragment: &str, extra: &str) -> std::process::Output {
    let profile = tempdir(dir, "profile");
    let out = Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            // WebGL on the CPU (SwiftShader): headless Chromium has no GPU.
            "--enable-unsafe-swiftshader",
            // Nothing resolves: the page must not need the network.
            "--host-resolver-rules=MAP * ~NOTFOUND",
            &format!("--user-data-dir={}", profile.display()),
            &format!("--window-size={WIDTH},{HEIGHT}"),
            "--force-device-scale-factor=1",
            "--hide-scrollbars",
            "--virtual-time-budget=5000",
            extra,
            &format!("file://{}#{fragment}", page.display()),
        ])
        .output()
        .expect("chromium runs");
    std::fs::remove_dir_all(&profile).ok();
    out
}

fn tempdir(dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(format!(
        "{name}-{}",
        std::time::SystemTime::UNIX_EPOCH.elapsed().unwrap().as_nanos()
    ));
    std::fs::create_dir_all(&path).unwrap();
    path
}

fn attribute<'a>(body: &'a str, name: &str) -> Option<&'a str> {
    let at = body.find(&format!(" {name}=\""))? + name.len() + 3;
    Some(&body[at..at + body[at..].find('"')?])
}

fn numbers<const N: usize>(text: &str) -> [f64; N] {
    let v: Vec<f64> = text.split(' ').map(|x| x.parse().unwrap()).collect();
    v.try_into().unwrap()
}

fn shoot(dir: &Path, page: &Path, fraction: f64) -> Shot {
    let fragment = format!("t={fraction}");
    let out = chromium(dir, page, &fragment, "--dump-dom");
    let dom = String::from_utf8_lossy(&out.stdout);
    let body = &dom[dom.find("<body").expect("a body in the DOM")..];
    let body = &body[..body.find('>').unwrap()];
    assert!(attribute(body, "data-error").is_none(), "the page failed: {body}");
    assert_eq!(
        attribute(body, "data-ready"),
        Some("1"),
        "the page did not finish: {body}"
    );
    let png = dir.join(format!("shot-{fraction}.png"));
    let out = chromium(dir, page, &fragment, &format!("--screenshot={}", png.display()));
    assert!(png.exists(), "no screenshot: {}", String::from_utf8_lossy(&out.stderr));
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buffer = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buffer).unwrap();
    assert_eq!((info.width as usize, info.height as usize), (WIDTH, HEIGHT));
    let channels = info.color_type.samples();
    let rgb = buffer[..info.buffer_size()]
        .chunks(channels)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    Shot {
        time: attribute(body, "data-t").unwrap().parse().unwrap(),
        tcp: numbers(attribute(body, "data-tcp").unwrap()),
        pixel: numbers(attribute(body, "data-tcp-px").unwrap()),
        load_ms: attribute(body, "data-load-ms").unwrap().parse().unwrap(),
        rgb,
        body: body.to_string(),
    }
}

fn pixel(rgb: &[u8], x: usize, y: usize) -> [i32; 3] {
    let k = 3 * (y * WIDTH + x);
    [i32::from(rgb[k]), i32::from(rgb[k + 1]), i32::from(rgb[k + 2])]
}

/// Pixels of the obstacles' orange (lit or not, blended with what is behind).
fn orange_pixels(rgb: &[u8]) -> usize {
    (0..HEIGHT)
        .flat_map(|y| (0..WIDTH).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let [r, g, b] = pixel(rgb, x, y);
            r > 120 && r > g + 20 && g > b + 20
        })
        .count()
}

/// Pixels within `radius` of `centre` whose colour differs clearly between the two shots.
fn changed_near(a: &[u8], b: &[u8], centre: [f64; 2], radius: usize) -> usize {
    let (cx, cy) = (centre[0] as usize, centre[1] as usize);
    let mut n = 0;
    for y in cy.saturating_sub(radius)..(cy + radius).min(HEIGHT) {
        for x in cx.saturating_sub(radius)..(cx + radius).min(WIDTH) {
            let (p, q) = (pixel(a, x, y), pixel(b, x, y));
            if (0..3).map(|c| (p[c] - q[c]).abs()).sum::<i32>() > 60 {
                n += 1;
            }
        }
    }
    n
}

/// Whether Chromium is there to run the page; under CI it must be (`scripts/test` installs it).
fn chromium_present() -> bool {
    if Path::new(CHROMIUM).exists() {
        return true;
    }
    assert_ne!(
        std::env::var("CI").as_deref(),
        Ok("true"),
        "{CHROMIUM} is missing under CI: scripts/test installs it (apt-get install chromium)"
    );
    println!("note: {CHROMIUM} not found, the browser check is skipped (apt-get install chromium)");
    false
}

#[test]
fn chromium_draws_the_arm_where_the_kinematics_put_it() {
    if !chromium_present() {
        return;
    }
    let dir = scratch("chromium");
    let (plan_path, page) = wall_page(&dir);
    let problem =
        parse_problem(&std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/wall.json")).unwrap())
            .unwrap();
    let plan = parse_plan(&std::fs::read_to_string(&plan_path).unwrap()).unwrap();
    assert!(
        plan.trajectory.is_empty(),
        "untimed: the waypoints are played {EVEN_STEP_S} s apart"
    );
    let finger = problem.scene().gripper();
    let fk_tcp = |i: usize| {
        forward_with(&edmp_core::robot::PANDA, &plan.waypoints[i], finger)
            .unwrap()
            .tcp()
            .translation
            .map(f64::from)
    };
    let duration = f64::from(EVEN_STEP_S) * (plan.waypoints.len() - 1) as f64;

    let began = std::time::Instant::now();
    let shots = [shoot(&dir, &page, 0.25), shoot(&dir, &page, 0.75)];
    println!("4 headless Chromium loads: {:.1} s", began.elapsed().as_secs_f64());
    for (shot, fraction) in shots.iter().zip([0.25, 0.75]) {
        assert!(
            (shot.time - fraction * duration).abs() < 1e-4,
            "data-t {} for #t={fraction}",
            shot.time
        );
        // Between waypoints k and k+1 the page interpolates each frame's position linearly.
        let at = shot.time / f64::from(EVEN_STEP_S);
        let k = (at.floor() as usize).min(plan.waypoints.len() - 2);
        let s = at - k as f64;
        let expected = fk_tcp(k) * (1.0 - s) + fk_tcp(k + 1) * s;
        let error = (0..3).map(|c| (shot.tcp[c] - expected[c]).powi(2)).sum::<f64>().sqrt();
        println!(
            "#t={fraction}: drawn TCP {:?}, FK {:?}: {:.3} mm apart; first frame after {} ms (Chromium's virtual clock)",
            shot.tcp,
            [expected.x, expected.y, expected.z],
            error * 1e3,
            shot.load_ms
        );
        assert!(error < 1e-3, "the drawn TCP is {:.3} mm from the FK", error * 1e3);
        let orange = orange_pixels(&shot.rgb);
        println!("#t={fraction}: {orange} orange (obstacle) pixels");
        assert!(orange > 5000, "obstacles drawn: only {orange} orange pixels");
        assert!(
            (0.0..WIDTH as f64).contains(&shot.pixel[0]) && (0.0..HEIGHT as f64).contains(&shot.pixel[1]),
            "the TCP is off screen at {:?}",
            shot.pixel
        );
    }
    // The arm moved: around the TCP of each shot, the two pictures differ.
    for shot in &shots {
        let changed = changed_near(&shots[0].rgb, &shots[1].rgb, shot.pixel, 30);
        println!(
            "{changed} of 3600 pixels around the TCP at {:?} differ between the shots",
            shot.pixel
        );
        assert!(
            changed > 400,
            "only {changed} pixels changed around the TCP at {:?}",
            shot.pixel
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn chromium_draws_the_clouds_and_meshes() {
    if !chromium_present() {
        return;
    }
    let dir = scratch("surfaces");
    // A 400-point cloud (PLY) and a 12-triangle cube (OBJ), with a small sphere: the orange
    // of the obstacles is mostly the cloud's and the cube's.
    let page = dir.join("surfaces.html");
    let out = edmp_host(&[
        "view",
        "edmp-host/tests/data/surfaces.json",
        "-o",
        page.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let shot = shoot(&dir, &page, 0.0);
    assert_eq!(attribute(&shot.body, "data-cloud-points"), Some("400"), "{}", shot.body);
    assert_eq!(
        attribute(&shot.body, "data-mesh-triangles"),
        Some("12"),
        "{}",
        shot.body
    );
    let orange = orange_pixels(&shot.rgb);
    println!("{orange} orange (obstacle) pixels");
    assert!(
        orange > 6000,
        "the cloud and the cube drawn: only {orange} orange pixels"
    );
    std::fs::remove_dir_all(&dir).ok();
}
