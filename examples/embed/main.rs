//! A small engine with vista inside, the README's embedding section as a
//! program: the engine owns the instance, device, queue, swapchain, command
//! buffers, render targets and frame loop; vista gets its handles through
//! `Context::from_raw`, wraps the engine's own colour and depth images as
//! `RenderTargets`, records the terrain into the engine's command buffer,
//! and submits nothing itself (its uploads go through the engine's submit
//! function). After the terrain the engine draws a marker of its own, depth
//! tested against vista's depth, then blits to the swapchain and presents.
//! The frame loop runs on a render thread; the main thread runs the window.
//!
//! `cargo run --release --example embed -- [--frames N] [--screenshot FILE.png] [--validation]`

mod engine;

use engine::{Engine, SIZE};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use vista::gpu::{vk, Context, Image, ImageDesc, RawHandles, Recorder};
use vista::passes::terrain_geometry::COLOR_FORMAT;
use vista::render::{overview_camera, RenderTargets, RendererOptions, TerrainRenderer, View, DEFAULT_NEAR_M};
use vista::world::{ProceduralSource, WorldDesc};
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

struct Args {
    frames: u64,
    screenshot: Option<std::path::PathBuf>,
    validation: bool,
}

fn args() -> Result<Args, String> {
    let mut a = Args { frames: 0, screenshot: None, validation: false };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "--frames" => a.frames = it.next().and_then(|n| n.parse().ok()).ok_or("--frames takes a whole number")?,
            "--screenshot" => a.screenshot = Some(it.next().ok_or("--screenshot takes a file")?.into()),
            "--validation" => a.validation = true,
            other => {
                return Err(format!("unknown argument {other:?}: use --frames N, --screenshot FILE, --validation"))
            }
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

/// The render thread: everything vista runs here, between the engine's
/// own commands, on the engine's queue.
fn render(mut engine: Engine, args: &Args, done: &AtomicBool) -> Result<(), String> {
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
    // (dropped before `engine` below); the device enables what vista needs.
    let ctx = unsafe { Context::from_raw(handles) }.map_err(|e| e.to_string())?;
    let (desc, source) = world();
    let options = RendererOptions { depth: engine::DEPTH, ..RendererOptions::default() };
    let mut renderer =
        TerrainRenderer::new(&ctx, &desc, source.clone(), Vec::new(), &options).map_err(|e| e.to_string())?;
    let camera = overview_camera(&desc, &*source);
    let view = View { camera, fov_y_deg: 60.0, size: SIZE, target_error_px: 1.0, near_m: DEFAULT_NEAR_M };
    // The engine's own images, wrapped: vista tracks their layout from here.
    let wrap = |name, raw, format, usage| {
        let d = ImageDesc { name, format, extent: SIZE, mip_levels: 1, array_layers: 1, usage };
        // SAFETY: the engine made `raw` with this description; it outlives
        // the wrapper; it is UNDEFINED until the first frame transitions it.
        unsafe { Image::from_raw(&ctx, raw, &d, vk::ImageLayout::UNDEFINED) }.map_err(|e| e.to_string())
    };
    let color = wrap("engine_color", engine.color.image, COLOR_FORMAT, engine::COLOR_USAGE)?;
    let depth = wrap("engine_depth", engine.depth.image, engine::DEPTH.format, engine::DEPTH_USAGE)?;
    let markers = engine::marker_positions(&desc, &*source).map(|p| engine.marker_push(&view, p));
    let mut frame = 0u64;
    let mut shot = None;
    let started = std::time::Instant::now();
    while !done.load(Ordering::Acquire) && (args.frames == 0 || frame < args.frames || shot.is_none()) {
        // The last frame waits for streaming to settle (at most 2 minutes),
        // so the screenshot shows the finished terrain.
        let settled = renderer.settled() || started.elapsed().as_secs() > 120;
        let last = args.frames > 0 && frame + 1 >= args.frames && settled;
        let Some((slot, image)) = engine.begin_frame(&ctx)? else { continue };
        let cmd = engine.cmds[slot];
        // SAFETY: `cmd` is recording (begin_frame), from the graphics
        // family, recorded nowhere else; the targets' layouts are tracked.
        let mut rec = unsafe { Recorder::from_raw(&ctx, cmd) };
        if frame == 0 {
            rec.discard_to(&color, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
            rec.discard_to(&depth, engine::DEPTH.layout());
        }
        let targets = RenderTargets::color(&color, &depth, [0.55, 0.68, 0.85, 1.0]);
        renderer.record(&mut rec, &view, &targets).map_err(|e| e.to_string())?;
        // vista leaves the targets in their attachment layouts: the engine
        // draws its markers into them, depth tested against the terrain.
        engine.draw_markers(cmd, &markers);
        if last {
            shot = Some(args.screenshot.as_ref().map(|_| engine.readback_buffer()).transpose()?);
        }
        engine.end_frame(&ctx, slot, image, shot.as_ref().and_then(Option::as_ref))?;
        frame += 1;
    }
    engine.wait_idle();
    if let (Some(Some(buffer)), Some(file)) = (shot, &args.screenshot) {
        engine.write_png(&buffer, file)?;
        println!("screenshot: {}", file.display());
    }
    let made = ctx.submissions();
    println!(
        "vista submissions: {} through the engine's submit function, {} of its own; {frame} frames presented",
        made.through_engine, made.direct
    );
    drop((color, depth, renderer));
    // Objects vista retired wait for frames the engine reported done.
    ctx.frame_completed(ctx.frame_submitted());
    let live = ctx.live_objects();
    drop(ctx);
    if live.total() != 0 {
        return Err(format!("{} vista objects alive at exit: {live:?}", live.total()));
    }
    engine.destroy();
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
                self.result = Err(format!("cannot open a window: {e}"));
                return el.exit();
            }
        };
        let engine = match Engine::new(&window, self.args.validation) {
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
    let event_loop = EventLoop::new().expect("an X display (DISPLAY)");
    let mut app = App { args, window: None, thread: None, done: Arc::default(), result: Ok(()) };
    event_loop.run_app(&mut app).expect("the event loop");
    if let Err(e) = app.result {
        eprintln!("embed: {e}");
        std::process::exit(1);
    }
}
