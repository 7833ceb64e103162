//! edmp-core's planner as Cortex-M4F firmware, run under QEMU (`mps2-an386`).
//!
//! Plans each embedded scene (postcard bytes from `edmp-host embed`; a scene with a point cloud or
//! a mesh carries its pieces and their tree, decoded into a `static` and validated) with the
//! shipped configuration, EDMP's 12 guides and 12 rows, and prints one line per scene over
//! semihosting:
//!
//! ```text
//! plan <name> <success|collision> <fingerprint> instructions <n> stack <bytes>
//! timed <name> <fingerprint|none> instructions <n>
//! ```
//!
//! The `timed` line is the chosen path's time parameterization (`edmp_core::trajectory`, the
//! spline checked against the scene, the arm's limits, jerk-limited), for free plans (`none`
//! otherwise). The arm is a build-time choice: the Panda by default, the KUKA iiwa 7 with the
//! cargo feature `iiwa7`, the UFACTORY xArm 6 (six joints) with `xarm6`, each on its own scenes
//! (`scenes/NAME/`; `scripts/firmware --robot NAME`). `scripts/firmware` compares name, status and fingerprints with the host's plan
//! and trajectory of the same bytes. Instructions come from SysTick under `-icount shift=0` (calibrated at start against a
//! loop of known length); stack is the high-water mark of a painted stack. Printing uses no
//! `core::fmt`, so that the `panic-check` build links only what the planner needs.
#![no_std]
#![no_main]

use core::ptr::addr_of_mut;
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::debug::{self, EXIT_FAILURE, EXIT_SUCCESS};
use cortex_m_semihosting::hio::{self, HostStream};
use edmp_core::Error;
use edmp_core::guidance::guides::EDMP_GUIDES;
use edmp_core::path::HORIZON;
use edmp_core::planner::{Plan, PlanConfig, Request, Workspace, plan};
use edmp_core::prior::{STEPS, Scratch, initial_noise};
use edmp_core::rng::Rng;
use edmp_core::scene::{Scene, SceneError};
use edmp_core::surface::bvh::nodes_for;
use edmp_core::trajectory::{Limits, Timed, parameterize_checked};
use edmp_core::wire::{Problem, WireError, WireSurface, decode as decode_wire};

#[cfg(feature = "panic-report")]
use panic_semihosting as _;

/// The `panic-check` build's handler: it calls a symbol that no object defines, so the link
/// succeeds only if the optimiser removed every call to the panic machinery, i.e. no panic
/// path is left in the firmware (the planner, the decoder, the printing).
#[cfg(all(feature = "panic-check", not(feature = "panic-report")))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    unsafe extern "C" {
        fn edmp_firmware_panic_path_is_linked() -> !;
    }
    // SAFETY: never runs: the symbol is undefined, so a binary that could reach this does not link.
    unsafe { edmp_firmware_panic_path_is_linked() }
}

/// Rows of the batch: one per EDMP guide, as on the host.
const ROWS: usize = 12;

/// Obstacle capacity (the suite's largest scene has 34). The host plans with capacity 64;
/// capacity changes no result, only memory: the checker prepares every obstacle slot
/// (about 410 bytes of stack each, measured).
const OBSTACLES: usize = 40;

/// Pieces of a scene's clouds and meshes (balls and triangles together): `edmp-host embed`
/// refuses more (its `FIRMWARE_PIECES`). About 44 bytes each, in `.bss`.
const PIECES: usize = 320;

/// Tree nodes: as many as any tree over `PIECES` pieces has. 36 bytes each, in `.bss`.
const NODES: usize = nodes_for(PIECES);

#[cfg(all(feature = "iiwa7", feature = "xarm6"))]
compile_error!("the firmware plans for one arm: enable at most one of the features `iiwa7` and `xarm6`");

/// The Panda: its tables, its prior and its scenes.
#[cfg(not(any(feature = "iiwa7", feature = "xarm6")))]
mod arm {
    use edmp_core::prior::Network;
    pub use edmp_core::robot::arms::panda::{JOINTS, ROBOT};

    /// The arm's trained prior.
    pub const NETWORK: &Network<JOINTS> = edmp_core::prior::PANDA;

    /// The embedded scenes, in `edmp-host embed`'s order (scripts/firmware lists the same files).
    pub const SCENES: &[(&str, &[u8])] = &[
        ("examples-wall", include_bytes!("../scenes/examples-wall.postcard")),
        (
            "examples-tabletop-pose-held",
            include_bytes!("../scenes/examples-tabletop-pose-held.postcard"),
        ),
        ("cubby-000", include_bytes!("../scenes/cubby-000.postcard")),
        ("dresser-000", include_bytes!("../scenes/dresser-000.postcard")),
        // An unseen kind whose first stage collides: the global stage (search, reseeding) runs.
        ("window_box-003", include_bytes!("../scenes/window_box-003.postcard")),
        // The wall's vertical box as a cloud of 280 points, then as a mesh of 12 triangles.
        (
            "examples-wall-points",
            include_bytes!("../scenes/examples-wall-points.postcard"),
        ),
        (
            "examples-wall-mesh",
            include_bytes!("../scenes/examples-wall-mesh.postcard"),
        ),
    ];
}

/// The KUKA LBR iiwa 7: its tables, its prior and its scenes (from its own suites).
#[cfg(feature = "iiwa7")]
mod arm {
    use edmp_core::prior::Network;
    pub use edmp_core::robot::arms::iiwa7::{JOINTS, ROBOT};

    /// The arm's trained prior (the build stops here if it has none).
    pub const NETWORK: &Network<JOINTS> = match edmp_core::prior::arms::iiwa7::NETWORK {
        Some(network) => network,
        None => panic!("the iiwa 7 has no trained prior (weights/README.md, \"Another arm\")"),
    };

    /// The embedded scenes, in `edmp-host embed`'s order (scripts/firmware lists the same files).
    pub const SCENES: &[(&str, &[u8])] = &[
        ("tabletop-000", include_bytes!("../scenes/iiwa7/tabletop-000.postcard")),
        ("cubby-000", include_bytes!("../scenes/iiwa7/cubby-000.postcard")),
        ("dresser-000", include_bytes!("../scenes/iiwa7/dresser-000.postcard")),
        // An unseen kind: the global stage (search, reseeding) runs.
        ("cage-000", include_bytes!("../scenes/iiwa7/cage-000.postcard")),
    ];
}

/// The UFACTORY xArm 6: its tables, its prior and its scenes (from its own suites). Six joints:
/// every buffer below takes the arm's `JOINTS`.
#[cfg(feature = "xarm6")]
mod arm {
    use edmp_core::prior::Network;
    pub use edmp_core::robot::arms::xarm6::{JOINTS, ROBOT};

    /// The arm's trained prior (the build stops here if it has none).
    pub const NETWORK: &Network<JOINTS> = match edmp_core::prior::arms::xarm6::NETWORK {
        Some(network) => network,
        None => panic!("the xArm 6 has no trained prior (weights/README.md, \"Another arm\")"),
    };

    /// The embedded scenes, in `edmp-host embed`'s order (scripts/firmware lists the same files).
    pub const SCENES: &[(&str, &[u8])] = &[
        ("tabletop-000", include_bytes!("../scenes/xarm6/tabletop-000.postcard")),
        ("cubby-000", include_bytes!("../scenes/xarm6/cubby-000.postcard")),
        ("dresser-000", include_bytes!("../scenes/xarm6/dresser-000.postcard")),
        // An unseen kind whose first stage collides: the global stage (search, reseeding) runs.
        ("cage-002", include_bytes!("../scenes/xarm6/cage-002.postcard")),
    ];
}

use arm::{JOINTS, NETWORK, ROBOT, SCENES};

/// A path of the arm's joints.
type Path = edmp_core::path::Path<JOINTS>;

/// The network's working memory for one trajectory at a time (`.bss`, not the stack).
static mut SCRATCH: Scratch<1> = Scratch::new();
/// The planner's gradients and noise predictions for the 12 rows (`.bss`).
static mut WORK: Workspace<ROWS, { edmp_core::planner::DEFAULT_SEARCH_NODES }, JOINTS> = Workspace::new();
/// The chosen path's time parameterization (`.bss`).
static mut TIMED: Timed<{ edmp_core::trajectory::DEFAULT_GRID }, HORIZON, JOINTS> = Timed::new();
/// The decoded pieces and tree of the scene's clouds and meshes (`.bss`).
static mut SURFACE: WireSurface<PIECES, NODES> = WireSurface::new();

/// SysTick wraps (every 2^24 ticks), counted by its exception.
static WRAPS: AtomicU32 = AtomicU32::new(0);

/// What a painted stack word holds until something writes it.
const PAINT: u32 = 0xDEAD_BEEF;

/// Reload value: the counter's whole 24 bits.
const RELOAD: u32 = 0x00FF_FFFF;

#[exception]
fn SysTick() {
    WRAPS.fetch_add(1, Ordering::Relaxed);
}

/// SysTick ticks since start (the counter counts down from `RELOAD`).
fn ticks() -> u64 {
    cortex_m::interrupt::free(|_| {
        let mut wraps = WRAPS.load(Ordering::Relaxed);
        let mut current = SYST::get_current();
        // A wrap whose exception is still pending (masked here) has not been counted yet.
        if cortex_m::peripheral::SCB::is_pendst_pending() {
            wraps += 1;
            current = SYST::get_current();
        }
        u64::from(wraps) * u64::from(RELOAD + 1) + u64::from(RELOAD - current)
    })
}

/// Guest instructions per SysTick tick, measured on a loop of known length (2 instructions per
/// turn). Under `-icount shift=0` one instruction is 1 ns of virtual time, so this is the
/// SysTick clock's period in ns.
fn instructions_per_tick() -> u64 {
    const TURNS: u32 = 5_000_000;
    let before = ticks();
    // SAFETY: a register-only countdown loop (`subs` + `bne`): no memory, no stack.
    unsafe {
        core::arch::asm!("2:", "subs {0}, {0}, #1", "bne 2b", inout(reg) TURNS => _, options(nomem, nostack));
    }
    let spent = ticks() - before;
    (2 * u64::from(TURNS) + spent / 2) / spent.max(1)
}

unsafe extern "C" {
    /// Lowest address of the stack region (cortex-m-rt's `link.x`: the end of `.uninit`).
    static _stack_end: u32;
    /// The initial stack pointer: the top of RAM.
    static _stack_start: u32;
}

fn stack_bottom() -> usize {
    (&raw const _stack_end) as usize
}

fn stack_top() -> usize {
    (&raw const _stack_start) as usize
}

/// Fills the free stack below the caller's frame with [`PAINT`].
#[inline(never)]
fn paint_stack() {
    // 256 bytes below this function's own stack pointer stay untouched.
    let limit = cortex_m::register::msp::read() as usize - 256;
    let mut at = stack_bottom();
    while at < limit {
        // SAFETY: [stack_bottom, limit) is RAM that cortex-m-rt reserves for the stack, below
        // every live frame (the stack grows down and `limit` is under our own frame).
        unsafe { core::ptr::write_volatile(at as *mut u32, PAINT) };
        at += 4;
    }
}

/// Bytes of stack used at most since the last [`paint_stack`]: from the top down to the
/// lowest word that no longer holds the paint.
fn stack_high_water() -> usize {
    let mut at = stack_bottom();
    // SAFETY: reads of stack RAM below the live frames (see `paint_stack`).
    while at < stack_top() && unsafe { core::ptr::read_volatile(at as *const u32) } == PAINT {
        at += 4;
    }
    stack_top() - at
}

/// Semihosting output with hand-rolled number formatting (no `core::fmt`).
struct Out(Option<HostStream>);

impl Out {
    fn str(&mut self, s: &str) -> &mut Self {
        if let Some(stream) = self.0.as_mut() {
            let _ = stream.write_all(s.as_bytes());
        }
        self
    }

    fn strs(&mut self, parts: &[&str]) -> &mut Self {
        for part in parts {
            self.str(part);
        }
        self
    }

    fn dec(&mut self, mut v: u64) -> &mut Self {
        let mut digits = [0u8; 20];
        let mut i = digits.len();
        loop {
            i -= 1;
            digits[i] = b'0' + (v % 10) as u8;
            v /= 10;
            if v == 0 {
                break;
            }
        }
        self.bytes(&digits[i..])
    }

    /// 16 lower-case hex digits, as the host's `{:016x}`.
    fn hex(&mut self, v: u64) -> &mut Self {
        let mut digits = [0u8; 16];
        for (k, d) in digits.iter_mut().enumerate() {
            let nibble = (v >> (60 - 4 * k)) & 0xF;
            *d = b"0123456789abcdef"[nibble as usize];
        }
        self.bytes(&digits)
    }

    fn bytes(&mut self, b: &[u8]) -> &mut Self {
        if let Some(stream) = self.0.as_mut() {
            let _ = stream.write_all(b);
        }
        self
    }
}

fn error_name(e: Error) -> &'static str {
    match e {
        Error::NonFiniteJoint { .. } => "non-finite joint",
        Error::NonFiniteGradient => "non-finite gradient",
        Error::Overflow => "overflow",
        Error::BadParameter => "bad parameter",
        Error::SegmentTooLong => "segment too long",
        _ => "planner error",
    }
}

fn scene_error_name(e: SceneError) -> &'static str {
    match e {
        SceneError::NonFinite => "scene: non-finite value",
        SceneError::QuaternionNorm => "scene: quaternion norm",
        SceneError::NonPositiveSize => "scene: non-positive size",
        SceneError::TooManyObstacles => "scene: too many obstacles",
        _ => "scene error",
    }
}

fn wire_error_name(e: WireError) -> &'static str {
    match e {
        WireError::Decode => "bad postcard bytes (or more than OBSTACLES obstacles)",
        WireError::Capacity => "more pieces or nodes than PIECES or NODES",
        WireError::TooManyBoxes => "too many guide boxes",
        WireError::DegenerateTriangle => "surface: degenerate triangle",
        WireError::Surface(_) => "surface: a piece or the tree refused",
        WireError::Scene(e) => scene_error_name(e),
        _ => "wire error",
    }
}

/// Why a scene was not planned.
enum Failure {
    Wire(WireError),
    Plan(Error),
}

impl Failure {
    fn name(&self) -> &'static str {
        match self {
            Self::Wire(e) => wire_error_name(*e),
            Self::Plan(e) => error_name(*e),
        }
    }
}

/// What the comparison needs from a plan.
struct Summary {
    free: bool,
    fingerprint: u64,
    path: Path,
}

/// The problem and its scene, the scene's surface decoded into `surface`.
fn decode<'a>(
    bytes: &[u8],
    surface: &'a mut WireSurface<PIECES, NODES>,
) -> Result<(Problem<OBSTACLES, JOINTS>, Scene<'a, OBSTACLES>), Failure> {
    let problem: Problem<OBSTACLES, JOINTS> = decode_wire(bytes, surface).map_err(Failure::Wire)?;
    let surface: &'a WireSurface<PIECES, NODES> = surface;
    let scene = problem.to_scene_with(surface).map_err(Failure::Wire)?;
    Ok((problem, scene))
}

/// Decodes and plans one scene. Not inlined, and the plan stays in this frame: the stack
/// high-water mark is the planner's, plus `main`'s small frame.
#[inline(never)]
fn plan_scene(
    bytes: &[u8],
    scratch: &mut Scratch<1>,
    work: &mut Workspace<ROWS, { edmp_core::planner::DEFAULT_SEARCH_NODES }, JOINTS>,
    surface: &mut WireSurface<PIECES, NODES>,
) -> Result<Summary, Failure> {
    let (problem, scene) = decode(bytes, surface)?;
    let mut rng = Rng::new(problem.seed);
    let plan: Plan<ROWS, JOINTS> = plan::<ROWS, OBSTACLES, 1, { edmp_core::planner::DEFAULT_SEARCH_NODES }, JOINTS>(
        &Request {
            robot: &ROBOT,
            network: NETWORK,
            scene: &scene,
            start: &problem.start,
            goal: &problem.goal,
            guides: &EDMP_GUIDES,
            config: &PlanConfig::DEFAULT,
        },
        &mut rng,
        scratch,
        work,
    )
    .map_err(Failure::Plan)?;
    let path = plan.paths.get(plan.best).copied().unwrap_or([[0.0; JOINTS]; HORIZON]);
    Ok(Summary {
        free: plan.is_free(),
        fingerprint: plan.fingerprint(),
        path,
    })
}

/// Times a free plan's path as the host's `--timed` does: the spline checked against the scene
/// (else the polyline), the arm's limits, jerk-limited.
#[inline(never)]
fn time_path(
    bytes: &[u8],
    path: &Path,
    timed: &mut Timed<{ edmp_core::trajectory::DEFAULT_GRID }, HORIZON, JOINTS>,
    surface: &mut WireSurface<PIECES, NODES>,
) -> Result<u64, Failure> {
    let (_, scene) = decode(bytes, surface)?;
    parameterize_checked(
        &ROBOT,
        &scene,
        path,
        &Limits::DEFAULT,
        &PlanConfig::DEFAULT.check,
        timed,
    )
    .map_err(Failure::Plan)?;
    Ok(timed.fingerprint())
}

/// Ticks of one network evaluation of all 12 rows (noise between the scene's ends, step 255),
/// to split a plan's instructions into network and the rest.
#[inline(never)]
fn time_network(
    bytes: &[u8],
    scratch: &mut Scratch<1>,
    surface: &mut WireSurface<PIECES, NODES>,
) -> Result<u64, Failure> {
    let (problem, _) = decode(bytes, surface)?;
    let mut rng = Rng::new(problem.seed);
    let mut paths = [[[0.0f32; JOINTS]; HORIZON]; ROWS];
    let mut eps = paths;
    for x in paths.iter_mut() {
        initial_noise(x, &mut rng, &problem.start, &problem.goal);
    }
    let time = NETWORK.time(STEPS as u16).map_err(Failure::Plan)?;
    let began = ticks();
    NETWORK
        .predict_noise(&paths, &time, scratch, &mut eps)
        .map_err(Failure::Plan)?;
    Ok(ticks() - began)
}

#[entry]
fn main() -> ! {
    let mut out = Out(hio::hstdout().ok());
    let Some(mut core) = cortex_m::Peripherals::take() else {
        out.str("error: peripherals taken\n");
        exit(false);
    };
    core.SYST.set_clock_source(SystClkSource::Core);
    core.SYST.set_reload(RELOAD);
    core.SYST.clear_current();
    core.SYST.enable_interrupt();
    core.SYST.enable_counter();
    // The counter reads 0 until its first reload (which raises no wrap): start after it.
    while SYST::get_current() == 0 {}

    // SAFETY: `main` never returns and takes these references once; nothing else (no
    // interrupt handler) touches SCRATCH, WORK, TIMED or SURFACE.
    let (scratch, work, timed, surface) = unsafe {
        (
            &mut *addr_of_mut!(SCRATCH),
            &mut *addr_of_mut!(WORK),
            &mut *addr_of_mut!(TIMED),
            &mut *addr_of_mut!(SURFACE),
        )
    };

    let per_tick = instructions_per_tick();
    out.str("systick instructions-per-tick ").dec(per_tick).str("\n");

    let mut failed = false;
    let mut peak_stack = 0;
    for &(name, bytes) in SCENES {
        paint_stack();
        let began = ticks();
        let result = plan_scene(bytes, scratch, work, surface);
        let spent = (ticks() - began) * per_tick;
        let stack = stack_high_water();
        peak_stack = peak_stack.max(stack);
        match result {
            Ok(plan) => {
                let status = if plan.free { "success" } else { "collision" };
                out.strs(&["plan ", name, " ", status, " "]).hex(plan.fingerprint);
                out.str(" instructions ")
                    .dec(spent)
                    .str(" stack ")
                    .dec(stack as u64)
                    .str("\n");
                out.strs(&["timed ", name, " "]);
                if !plan.free {
                    out.str("none instructions 0\n");
                    continue;
                }
                paint_stack();
                let began = ticks();
                let result = time_path(bytes, &plan.path, timed, surface);
                let spent = (ticks() - began) * per_tick;
                peak_stack = peak_stack.max(stack_high_water());
                match result {
                    Ok(fingerprint) => {
                        out.hex(fingerprint).str(" instructions ").dec(spent).str("\n");
                    }
                    Err(e) => {
                        failed = true;
                        out.strs(&["error ", e.name(), "\n"]);
                    }
                }
            }
            Err(e) => {
                failed = true;
                out.strs(&["error ", name, " ", e.name(), "\n"]);
            }
        }
    }
    if let Some(&(name, bytes)) = SCENES.first() {
        paint_stack();
        match time_network(bytes, scratch, surface) {
            Ok(t) => {
                let evaluations = PlanConfig::DEFAULT.sampler.evaluations() as u64;
                out.strs(&["network ", name, " instructions-per-evaluation "])
                    .dec(t * per_tick);
                out.str(" evaluations-per-plan ").dec(evaluations).str("\n");
            }
            Err(e) => {
                failed = true;
                out.str("error network ").str(e.name()).str("\n");
            }
        }
        peak_stack = peak_stack.max(stack_high_water());
    }
    out.str("peak-stack ").dec(peak_stack as u64).str("\n");
    out.str("done\n");
    exit(!failed)
}

/// Ends the QEMU run with the host-side exit status (semihosting `target=native`).
fn exit(success: bool) -> ! {
    debug::exit(if success { EXIT_SUCCESS } else { EXIT_FAILURE });
    // Only reached without a semihosting host.
    loop {
        cortex_m::asm::wfi();
    }
}
