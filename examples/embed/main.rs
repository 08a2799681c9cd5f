//! A small deferred engine with vista inside, docs/embedding.md
//! as a program: the engine owns the instance, device, queue,
//! swapchain, command buffers, render targets and frame loop; vista gets
//! its handles through `Context::from_raw`, wraps the engine's images,
//! records the terrain into the engine's command buffer between the
//! engine's own passes, and submits nothing itself (its uploads go through
//! the engine's submit function). Each frame the engine
//! 1. clears its targets and draws a building of its own into them and the
//!    depth (vista loads that depth: `DepthOptions::load`),
//! 2. has vista draw the terrain as `--output` says: `gbuffer` (the
//!    default) into the engine's G-buffer images, `hdr` as linear radiance
//!    into its float target, `lit` as vista's own lit picture,
//! 3. lights its G-buffer itself (sun and sky ambient) or tonemaps vista's
//!    radiance into its display image, draws a marker depth-tested against
//!    the terrain, blits and presents.
//!
//! Once the terrain settles, six frames are drawn without the building
//! and six with it (each copy of occlusion's visibility bits, which frames
//! use in turn, reaches its steady state in three): the difference in patches the depth pyramid culled is
//! what the engine's occluder culled.
//!
//! `cargo run --release --example embed -- [--output gbuffer|hdr|lit] [--frames N] [--screenshot FILE.png] [--validation]`

mod engine;
mod passes;
mod setup;
mod targets;

use engine::Engine;
use passes::{BoxPush, LightPush, Marker};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use targets::{gbuffer_layout, rest_layout, Mode, Target, DEPTH, HDR_FORMAT, SIZE};
use vista::gpu::{Context, Image, ImageDesc, RawHandles, Recorder};
use vista::passes::terrain_geometry::COLOR_FORMAT;
use vista::render::{overview_camera, RenderTargets, RendererOptions, TerrainRenderer, View, DEFAULT_NEAR_M};
use vista::targets::Output;
use vista::world::{ProceduralSource, WorldDesc};
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

struct Args {
    frames: u64,
    screenshot: Option<std::path::PathBuf>,
    validation: bool,
    mode: Mode,
}

fn args() -> Result<Args, String> {
    let mut a = Args { frames: 0, screenshot: None, validation: false, mode: Mode::Gbuffer };
    let mut it = std::env::args().skip(1);
    let usage = "use --output gbuffer|hdr|lit, --frames N, --screenshot FILE, --validation";
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "--frames" => a.frames = it.next().and_then(|n| n.parse().ok()).ok_or("--frames takes a whole number")?,
            "--screenshot" => a.screenshot = Some(it.next().ok_or("--screenshot takes a file")?.into()),
            "--validation" => a.validation = true,
            "--output" => {
                a.mode = match it.next().as_deref() {
                    Some("gbuffer") => Mode::Gbuffer,
                    Some("hdr") => Mode::Hdr,
                    Some("lit") => Mode::Lit,
                    Some(other) => return Err(format!("--output {other}: {usage}")),
                    None => return Err(format!("--output takes a value: {usage}")),
                }
            }
            other => return Err(format!("unknown argument {other}: {usage}")),
        }
    }
    if a.screenshot.is_some() && a.frames == 0 {
        return Err("--screenshot needs --frames N".into());
    }
    Ok(a)
}

/// The terrain: a small procedural world, seen from its overview camera.
fn world() -> (WorldDesc, Arc<ProceduralSource>) {
    let desc = WorldDesc { extent_m: [2048.0, 2048.0], spacing_m: 2.0, lod_count: 4, ..WorldDesc::default() };
    let source = ProceduralSource::new(1, desc.extent_m, desc.height_range_m).expect("a valid procedural world");
    (desc, Arc::new(source))
}

/// What vista is asked to write into the engine's images.
fn output(mode: Mode) -> Output {
    match mode {
        Mode::Lit => Output::Lit { format: COLOR_FORMAT },
        Mode::Hdr => Output::Hdr { format: HDR_FORMAT, sky: false },
        Mode::Gbuffer => Output::Gbuffer(gbuffer_layout()),
    }
}

/// The engine's building: 240 m wide and 1 km tall, standing on the
/// ground 500 m ahead of the camera and 180 m to its right (the markers
/// stay in view on the left); centre and half size.
fn building(source: &ProceduralSource, view: &View) -> (glam::DVec3, glam::DVec3) {
    let c = view.camera.position_m;
    let (x, y) = (c[0] + 180.0, c[1] + 500.0);
    let ground = f64::from(vista::world::HeightSource::sample(source, x, y));
    (glam::DVec3::new(x, y, ground + 500.0), glam::DVec3::new(120.0, 40.0, 500.0))
}

/// The engine's images as vista sees them (vista tracks their layouts).
struct Wrapped {
    colour: Option<Image>,
    gbuffer: Vec<Image>,
    depth: Image,
}

fn wrap(ctx: &Context, engine: &Engine) -> Result<Wrapped, String> {
    let one = |name: &str, t: &Target, usage| {
        let d = ImageDesc { name, format: t.format, extent: SIZE, mip_levels: 1, array_layers: 1, usage };
        // SAFETY: the engine made `t` with this description; it outlives the
        // wrapper; the engine put it in its rest layout at start and gives
        // it back there after each of its passes.
        unsafe { Image::from_raw(ctx, t.image, &d, rest_layout(t)) }.map_err(|e| e.to_string())
    };
    let t = &engine.targets;
    let colour = match engine.mode {
        Mode::Lit => Some(one("engine_ldr", &t.ldr, targets::COLOR_USAGE)?),
        Mode::Hdr => Some(one("engine_hdr", t.hdr.as_ref().expect("hdr mode"), targets::COLOR_USAGE)?),
        Mode::Gbuffer => None,
    };
    let gbuffer = t.gbuffer.iter().map(|g| one("engine_gbuffer", g, targets::COLOR_USAGE)).collect::<Result<_, _>>()?;
    Ok(Wrapped { colour, gbuffer, depth: one("engine_depth", &t.depth, targets::DEPTH_USAGE)? })
}

/// Frames drawn without the building, then with it, once settled: each
/// copy of occlusion's visibility bits (frames use them in turn) reaches its
/// steady state in three.
const MEASURE: u32 = 6;

/// Patches the depth pyramid culled in the newest frame that came back.
fn culled(ctx: &Context, engine: &Engine, renderer: &mut TerrainRenderer) -> u32 {
    engine.wait_idle();
    ctx.frame_completed(ctx.frames_submitted());
    renderer.poll_timings(ctx);
    renderer.latest_counters().map_or(0, |k| k.cull.occlusion_tested - k.cull.drawn_phase2)
}

/// The render thread: everything vista runs here, between the engine's
/// own commands, on the engine's queue.
fn render(mut engine: Engine, args: &Args, done: &AtomicBool) -> Result<(), String> {
    let ctx = vista_context(&engine)?;
    let (desc, source) = world();
    let options = RendererOptions { depth: DEPTH, output: output(engine.mode), ..RendererOptions::default() };
    let mut renderer =
        TerrainRenderer::new(&ctx, &desc, source.clone(), Vec::new(), &options).map_err(|e| e.to_string())?;
    let camera = overview_camera(&desc, &*source);
    let view = View { camera, fov_y_deg: 60.0, size: SIZE, target_error_px: 1.0, near_m: DEFAULT_NEAR_M };
    let wrapped = wrap(&ctx, &engine)?;
    let gbuffer: Vec<&Image> = wrapped.gbuffer.iter().collect();
    let targets =
        RenderTargets { color: wrapped.colour.as_ref(), gbuffer: &gbuffer, depth: &wrapped.depth, clear: None };
    let light = LightPush::new(&renderer.effects.lighting, [0.55, 0.68, 0.85, 1.0]);
    let (centre, half) = building(&source, &view);
    let block = BoxPush::new(&view, centre, half);
    let markers = engine::marker_positions(&desc, &*source).map(|p| Marker::new(&view, p));
    let (mut frame, mut shot, mut measured) = (0u64, None, None);
    let started = std::time::Instant::now();
    // Once settled (two frames in a row with nothing loading, as
    // `Offscreen::settle` waits): MEASURE frames without the building, then
    // MEASURE with it, each block's last frame counted.
    let (mut measuring, mut calm): (Option<u32>, u32) = (None, 0);
    while !done.load(Ordering::Acquire) && (args.frames == 0 || frame < args.frames || shot.is_none()) {
        calm = if renderer.settled() && frame > 0 { calm + 1 } else { 0 };
        let settled = calm >= 2 || started.elapsed().as_secs() > 120;
        if settled && measured.is_none() && measuring.is_none() {
            measuring = Some(0);
        }
        let without = measuring.is_some_and(|m| m < MEASURE);
        // The last frame waits for the measurement (and streaming to
        // settle), so the screenshot shows the finished terrain and building.
        let last = args.frames > 0 && frame + 1 >= args.frames && measured.is_some() && measuring.is_none();
        let Some((slot, image)) = engine.begin_frame(&ctx)? else { continue };
        let cmd = engine.cmds[slot];
        engine.engine_pass(cmd, &light, (!without).then_some(&block));
        // SAFETY: `cmd` is recording (begin_frame), from the graphics
        // family, recorded nowhere else; the targets rest in the layouts
        // vista tracks.
        let mut rec = unsafe { Recorder::from_raw(&ctx, cmd) };
        renderer.record(&mut rec, &view, &targets).map_err(|e| e.to_string())?;
        drop(rec);
        engine.after_vista(cmd, &light, &markers);
        if last {
            shot = Some(args.screenshot.as_ref().map(|_| engine.readback_buffer()).transpose()?);
        }
        engine.end_frame(&ctx, slot, image, shot.as_ref().and_then(Option::as_ref))?;
        frame += 1;
        measuring = measure_step(measuring, &mut measured, &ctx, &engine, &mut renderer);
    }
    engine.wait_idle();
    if let (Some(Some(buffer)), Some(file)) = (shot, &args.screenshot) {
        engine.write_png(buffer, file)?;
        println!("screenshot: {}", file.display());
    }
    report(&ctx, &engine, measured)?;
    println!("{frame} frames presented in {:.1} s", started.elapsed().as_secs_f64());
    close(ctx, engine, wrapped, renderer)
}

/// The context vista runs on: the engine's handles and submit function.
fn vista_context(engine: &Engine) -> Result<Context, String> {
    let handles = RawHandles {
        entry: engine.entry.clone(),
        instance: engine.instance.clone(),
        physical_device: engine.physical,
        device: engine.device.clone(),
        graphics_queue_family: engine.family,
        graphics_queue: engine.queue(),
        compute_queue_family: engine.family,
        compute_queue: engine.queue(),
        debug_utils: false,
        submit: Some(engine.submitter()),
    };
    // SAFETY: the engine's handles, made together, outlive the context
    // (dropped before `engine` in `render`); the device enables what vista needs.
    unsafe { Context::from_raw(handles) }.map_err(|e| e.to_string())
}

/// One frame of the measurement: after each block's last frame, the
/// patches the depth pyramid culled.
fn measure_step(
    measuring: Option<u32>,
    measured: &mut Option<(u32, u32)>,
    ctx: &Context,
    engine: &Engine,
    renderer: &mut TerrainRenderer,
) -> Option<u32> {
    match measuring {
        Some(m) if m == MEASURE - 1 => Some(culled(ctx, engine, renderer)).map(|open| {
            *measured = Some((open, 0));
            MEASURE
        }),
        Some(m) if m == 2 * MEASURE - 1 => {
            let walled = culled(ctx, engine, renderer);
            *measured = measured.map(|(open, _)| (open, walled));
            None
        }
        Some(m) => Some(m + 1),
        None => None,
    }
}

/// vista's objects go first and none may be left; then the engine's.
fn close(ctx: Context, engine: Engine, wrapped: Wrapped, renderer: TerrainRenderer) -> Result<(), String> {
    drop((wrapped, renderer));
    // Objects vista retired wait for frames the engine reported done.
    ctx.frame_completed(ctx.frames_submitted());
    let live = ctx.live_objects();
    drop(ctx);
    if live.total() != 0 {
        return Err(format!("{} vista objects alive at exit: {live:?}", live.total()));
    }
    engine.destroy();
    Ok(())
}

/// The lines each run prints: what the engine's depth and lighting did.
fn report(ctx: &Context, engine: &Engine, measured: Option<(u32, u32)>) -> Result<(), String> {
    match measured {
        Some((open, walled)) => println!(
            "engine depth: kept ({} terrain patches culled by the engine's occluders: the depth pyramid culled \
             {walled} with its building, {open} without it)",
            walled.saturating_sub(open)
        ),
        None => println!("engine depth: kept (the occluders' culling was not measured: the run ended first)"),
    }
    let pixels = engine.terrain_pixels()?;
    match engine.mode {
        Mode::Gbuffer => println!("engine lighting: lit vista's G-buffer ({pixels} terrain pixels)"),
        Mode::Hdr => println!("engine lighting: tonemapped vista's linear radiance ({pixels} terrain pixels)"),
        Mode::Lit => println!("engine lighting: none, vista lit its terrain itself ({pixels} terrain pixels)"),
    }
    let made = ctx.submissions();
    println!(
        "vista submissions: {} through the engine's submit function, {} of its own",
        made.through_engine, made.direct
    );
    Ok(())
}

struct App {
    args: Args,
    window: Option<Arc<Window>>,
    thread: Option<std::thread::JoinHandle<Result<(), String>>>,
    done: Arc<AtomicBool>,
    result: Result<(), String>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let attrs = Window::default_attributes()
            .with_title("vista embedded in an engine")
            .with_inner_size(winit::dpi::PhysicalSize::new(SIZE[0], SIZE[1]))
            .with_resizable(false);
        let window = match el.create_window(attrs) {
            Ok(w) => Arc::new(w),
            Err(e) => {
                self.result = Err(format!("cannot open a window: {}", reason(&e)));
                return el.exit();
            }
        };
        let engine = match Engine::new(&window, self.args.validation, self.args.mode) {
            Ok(e) => e,
            Err(e) => {
                self.result = Err(e);
                return el.exit();
            }
        };
        let (done, args) = (self.done.clone(), Args { screenshot: self.args.screenshot.clone(), ..self.args });
        let keep = window.clone();
        self.thread = Some(std::thread::spawn(move || {
            let r = render(engine, &args, &done);
            done.store(true, Ordering::Release);
            drop(keep);
            r
        }));
        self.window = Some(window);
    }

    fn window_event(&mut self, _el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if matches!(event, WindowEvent::CloseRequested) {
            self.done.store(true, Ordering::Release);
        }
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        el.set_control_flow(ControlFlow::WaitUntil(std::time::Instant::now() + std::time::Duration::from_millis(10)));
        if self.done.load(Ordering::Acquire) && self.thread.as_ref().is_none_or(|t| t.is_finished()) {
            if let Some(t) = self.thread.take() {
                self.result = t.join().unwrap_or_else(|_| Err("the render thread panicked".into()));
            }
            el.exit();
        }
    }
}

fn main() {
    let args = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    // No display is the user's to fix: one line, not a panic's backtrace.
    let event_loop = match EventLoop::new() {
        Ok(l) => l,
        Err(e) => {
            eprintln!("embed: cannot open a window ({}); without a display, run it under `xvfb-run -a`", reason(&e));
            std::process::exit(2);
        }
    };
    let mut app = App { args, window: None, thread: None, done: Arc::default(), result: Ok(()) };
    if let Err(e) = event_loop.run_app(&mut app) {
        eprintln!("embed: the window's event loop failed: {e}");
        std::process::exit(1);
    }
    if let Err(e) = app.result {
        eprintln!("embed: {e}");
        std::process::exit(1);
    }
}

/// The window system's reason without the source position winit's errors
/// carry ("os error at .../linux/mod.rs:765: ...").
fn reason(e: &dyn std::fmt::Display) -> String {
    let text = e.to_string();
    match text.split_once(".rs:").and_then(|(_, rest)| rest.split_once(": ")) {
        Some((_, reason)) => reason.to_string(),
        None => text,
    }
}
