//! `vista view`: a window (winit, X11) presenting `TerrainRenderer`'s output
//! every frame, a fly camera, and a live overlay of per-pass GPU times and
//! counters (egui, drawn by egui-ash-renderer). `--frames N` runs N frames
//! and exits, `--path` flies a scripted path, `--screenshot` writes the
//! last presented image read back from the swapchain image.

mod fly;
mod minimise;
mod overlay;
mod scene_edit;
mod viewer;

use crate::render_cmd::{check_view, ViewpointArgs};
use crate::world_args::{LoadedWorld, WorldArgs};
use anyhow::{anyhow, bail, Context as _, Result};
use clap::Args;
use fly::{FlightPath, FlyCamera};
use minimise::{ScriptedMinimise, Step};
use overlay::{Overlay, Settings};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use viewer::{Frame, OverlayFrame, Viewer};
use vista::gpu::present::Presenter;
use vista::gpu::{Context, ContextOptions};
use vista::passes::debug_view::DebugView;
use vista::render::{TerrainRenderer, View};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::{Window, WindowId};

#[derive(Args)]
pub struct ViewArgs {
    // Size, camera (P prints the current one in `--camera`'s form), field
    // of view, target error, culling stages at the start, slots.
    #[command(flatten)]
    pub viewpoint: ViewpointArgs,
    /// Cache baked nodes here across runs (as `vista render --cache`).
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// Present N frames, then exit (0: until the window is closed or Esc).
    /// With --screenshot, the camera then waits at its last position until
    /// streaming settled (as `vista render`'s), and the last of those
    /// frames is written.
    #[arg(long, default_value_t = 0, value_parser = crate::numbers::whole_u32, allow_negative_numbers = true)]
    pub frames: u32,
    /// A scripted flight over --frames: one X,Y,Z,YAW,PITCH per line (#
    /// comments), flown through at even spacing; a line `size WxH` resizes
    /// the window when the flight gets there, a line `minimise` minimises
    /// it there (restored after 10 skipped redraws; needs a window manager),
    /// a line `lose-surface` makes the next acquisition report a lost
    /// surface (injected), which is remade, a line `scene FILE` takes that
    /// scene's stamps there (as an edit of --scene's file does at any time).
    #[arg(long, value_name = "FILE")]
    pub path: Option<PathBuf>,
    /// Write the last presented frame (PNG), read back from the swapchain
    /// image; needs --frames.
    #[arg(long, value_name = "FILE.png")]
    pub screenshot: Option<PathBuf>,
    /// Start with a debug view over the picture: lod, classification,
    /// edges or phase (the overlay's selector changes it).
    #[arg(long, value_parser = parse_debug_view)]
    pub debug_view: Option<DebugView>,
    /// Start with the overlay hidden (F1 shows it).
    #[arg(long)]
    pub no_overlay: bool,
    /// Present without waiting for the vertical blank (mailbox or
    /// immediate where the display offers one).
    #[arg(long)]
    pub no_vsync: bool,
    /// Longest wait for streaming to settle before --screenshot's frame.
    #[arg(long, default_value_t = 120.0, value_parser = crate::numbers::number_f64, allow_negative_numbers = true)]
    pub settle_seconds: f64,
    #[command(flatten)]
    pub world: WorldArgs,
}

fn parse_debug_view(s: &str) -> Result<DebugView, String> {
    match s {
        "lod" => Ok(DebugView::Lod),
        "classification" => Ok(DebugView::Classification),
        "edges" => Ok(DebugView::PatchEdges),
        "phase" => Ok(DebugView::OcclusionPhase),
        _ => Err(format!("debug view {s:?} is not one of lod, classification, edges, phase")),
    }
}

/// Checks what needs no window: the world, the view, the files.
pub fn check(args: &ViewArgs) -> Result<(LoadedWorld, Option<FlightPath>)> {
    if args.screenshot.is_some() && args.frames == 0 {
        bail!("--screenshot needs --frames N (the run must end for the last frame to be written)");
    }
    if args.path.is_some() && args.frames == 0 {
        bail!("--path needs --frames N (the flight is spread over them)");
    }
    if let Some(shot) = &args.screenshot {
        // PNG is what it writes: another extension would name bytes it is not.
        if !shot.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
            bail!("--screenshot {}: the screenshot is a PNG; give a file name ending in .png", shot.display());
        }
        crate::out_path::check_out_file(shot, "--screenshot")?;
    }
    if !(args.settle_seconds.is_finite() && args.settle_seconds >= 0.0) {
        bail!("--settle-seconds must be a non-negative number");
    }
    let path = args.path.as_deref().map(FlightPath::load).transpose()?;
    let world = args.world.load()?;
    crate::budget::check(&args.viewpoint, &world)?;
    Ok((world, path))
}

pub fn view(options: ContextOptions, args: ViewArgs, world: LoadedWorld, path: Option<FlightPath>) -> Result<()> {
    if std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) {
        bail!("cannot open a window: DISPLAY is not set (no X display); without one, run `xvfb-run -a vista view ...`");
    }
    let display = std::env::var("DISPLAY").unwrap_or_default();
    let event_loop =
        EventLoop::new().map_err(|e| anyhow!("cannot open a window on DISPLAY {display}: {}", reason(&e)))?;
    let mut view = args.viewpoint.view(&world);
    if let Some(p) = &path {
        view.camera = p.first();
    }
    check_view(&view, &world)?;
    let camera = view.camera;
    let args_scene = args.world.scene.clone();
    let mut app = App {
        fly: FlyCamera::new(camera, world.desc.extent_m),
        settings: Settings {
            target_error_px: args.viewpoint.target_error,
            stages: args.viewpoint.cull,
            switches: vista::render::FrameSwitches::default(),
            lighting: world.effects.lighting,
            debug_view: args.debug_view,
        },
        show_overlay: !args.no_overlay,
        args,
        world,
        path,
        options,
        view,
        state: None,
        failure: None,
        presented: 0,
        presented_all: 0,
        started: None,
        settling_since: None,
        calm: 0,
        last: Instant::now(),
        fps: 0.0,
        overlay: Overlay::default(),
        cursor: None,
        looking: false,
        resized_at: None,
        minimising: None,
        minimised_at: None,
        skipped_minimised: 0,
        surface_lost_at: None,
        scene_at: None,
        scene_watch: args_scene.map(scene_edit::SceneWatch::new),
        result: None,
    };
    event_loop.run_app(&mut app).map_err(|e| anyhow!("the window's event loop failed: {e}"))?;
    if let Some(e) = app.failure {
        return Err(e);
    }
    app.result.unwrap_or_else(|| Err(anyhow!("the window closed before vista started")))
}

/// The window and everything drawn into it.
struct Open {
    egui_state: egui_winit::State,
    egui: egui::Context,
    viewer: Viewer,
    /// Dropped last: the presenter's surface belongs to it.
    window: Window,
}

struct App {
    args: ViewArgs,
    world: LoadedWorld,
    path: Option<FlightPath>,
    options: ContextOptions,
    view: View,
    fly: FlyCamera,
    settings: Settings,
    overlay: Overlay,
    show_overlay: bool,
    state: Option<Open>,
    failure: Option<anyhow::Error>,
    /// Frames of --frames presented (settling before a screenshot excluded).
    presented: u32,
    /// Every frame presented.
    presented_all: u64,
    started: Option<Instant>,
    /// When --frames ended with a screenshot pending: waiting for streaming.
    settling_since: Option<Instant>,
    /// Redraws in a row that found the renderer settled.
    calm: u32,
    last: Instant,
    fps: f64,
    cursor: Option<[f64; 2]>,
    looking: bool,
    /// The scripted frame whose `size` line was applied.
    resized_at: Option<u32>,
    /// A `minimise` line under way, and the frame of the last one done.
    minimising: Option<ScriptedMinimise>,
    minimised_at: Option<u32>,
    /// Redraws skipped while minimised since the last frame presented.
    skipped_minimised: u64,
    /// The scripted frame whose `lose-surface` line was applied.
    surface_lost_at: Option<u32>,
    /// The scripted frame whose `scene` line was applied.
    scene_at: Option<u32>,
    /// The scene file, read again when it changes.
    scene_watch: Option<scene_edit::SceneWatch>,
    result: Option<Result<()>>,
}

impl App {
    fn open(&mut self, el: &ActiveEventLoop) -> Result<Open> {
        let [w, h] = self.args.viewpoint.size;
        let attrs = Window::default_attributes()
            .with_title(format!("vista: {}", self.world.label))
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h));
        let window = el.create_window(attrs).context("creating the window")?;
        let display = window.display_handle().context("the window's display")?.as_raw();
        let options = ContextOptions { display: Some(display), ..self.options.clone() };
        let ctx = Context::headless(&options).context("creating the Vulkan context")?;
        let errors = match self.args.viewpoint.lod_rule {
            vista::render::LodRule::Patch => self.world.errors_on_demand(&ctx, self.args.cache.as_deref())?,
            vista::render::LodRule::Triangle => self.world.errors(&ctx, self.args.cache.as_deref())?,
        };
        let ropts = self.args.viewpoint.renderer_options(&ctx, &self.world, self.args.cache.as_deref(), errors)?;
        let d = &self.world.desc;
        let renderer = TerrainRenderer::new(&ctx, d, self.world.source.clone(), self.world.holes.clone(), &ropts)
            .map_err(crate::world_args::plan_error_is_input)?;
        let depth = ropts.terrain.frames_in_flight;
        let size = [window.inner_size().width, window.inner_size().height];
        let raw_window = window.window_handle().context("the window's handle")?.as_raw();
        // SAFETY: the handles are the live window's, on the display the
        // context was made for; `Open` drops the viewer before the window.
        let presenter = unsafe { Presenter::new(&ctx, display, raw_window, size, depth, !self.args.no_vsync) }?;
        self.view.size = presenter.extent();
        let viewer = Viewer::new(ctx, renderer, presenter, depth)?;
        let egui = egui::Context::default();
        let egui_state = egui_winit::State::new(egui.clone(), egui::ViewportId::ROOT, &window, None, None, Some(4096));
        Ok(Open { egui_state, egui, viewer, window })
    }

    /// Takes `file`'s stamps (scene_edit.rs); a scene that cannot be read
    /// is one line, and the view goes on with the world it has.
    fn edit_scene(&mut self, file: &Path) {
        let Some(open) = self.state.as_mut() else { return };
        match scene_edit::apply(&self.args.world, file, &mut self.world, &mut open.viewer.renderer) {
            Ok(line) => println!("{line}"),
            Err(e) => println!("scene {}: {e:#}", file.display()),
        }
    }

    fn fail(&mut self, el: &ActiveEventLoop, e: anyhow::Error) {
        self.failure.get_or_insert(e);
        el.exit();
    }

    /// One frame: camera, overlay, render, present; ends the run when its
    /// frames are done.
    fn redraw(&mut self, el: &ActiveEventLoop) -> Result<()> {
        let now = Instant::now();
        let dt = now.duration_since(self.last).as_secs_f64();
        self.last = now;
        if dt > 0.0 {
            self.fps = if self.fps == 0.0 { 1.0 / dt } else { 0.9 * self.fps + 0.1 / dt };
        }
        let frames = self.args.frames;
        let scripted_frame = self.presented.min(frames.saturating_sub(1));
        if !self.steer(now, dt, scripted_frame) {
            return Ok(());
        }
        let scripted_scene = self.path.as_ref().and_then(|p| p.scene_at(scripted_frame, frames));
        let scripted_scene = scripted_scene.filter(|_| self.scene_at != Some(scripted_frame)).map(Path::to_path_buf);
        if scripted_scene.is_some() {
            self.scene_at = Some(scripted_frame);
        }
        let watched = self.scene_watch.as_mut().and_then(|w| w.changed(now));
        if let Some(file) = scripted_scene.or(watched) {
            self.edit_scene(&file);
        }
        let Some(open) = self.state.as_mut() else { return Ok(()) };
        self.view.camera = self.fly.camera;
        viewer::apply(&mut open.viewer.renderer, &self.settings, &mut self.view);
        self.view.size = open.viewer.presenter.extent();
        // Minimised (X11 keeps the size, other systems report none): no
        // frame; the loader threads keep baking meanwhile.
        let minimised = self.view.size == [0, 0] || open.window.is_minimized() == Some(true);
        self.step_minimise(minimised, now);
        if minimised {
            self.skipped_minimised += 1;
            std::thread::sleep(minimise::SKIPPED_REDRAW_PAUSE);
            return Ok(());
        }
        let overlay = if self.show_overlay { Some(self.run_overlay()?) } else { None };
        let open = self.state.as_mut().expect("checked above");
        let final_frame = frames > 0 && self.presented + 1 >= frames;
        self.calm = if open.viewer.renderer.settled() { self.calm + 1 } else { 0 };
        let settled = self.calm >= vista::render::offscreen::CALM_FRAMES
            || self.settling_since.is_some_and(|t| t.elapsed() > Duration::from_secs_f64(self.args.settle_seconds));
        let shoot = final_frame && self.args.screenshot.is_some() && settled;
        let shot = if shoot { Some(open.viewer.readback()?) } else { None };
        if !open.viewer.frame(&self.view, overlay.as_ref(), shot.as_ref())? {
            let s = open.window.inner_size();
            let surfaces = open.viewer.presenter.surfaces_made();
            open.viewer.resize([s.width, s.height])?;
            if open.viewer.presenter.surfaces_made() > surfaces {
                let [w, h] = open.viewer.presenter.extent();
                println!("surface lost after frame {}: remade, swapchain {w}x{h}", self.presented);
            }
            return Ok(());
        }
        self.presented_one(el, now, final_frame, shot)
    }

    /// The camera from the scripted path (with its size, minimise and
    /// lose-surface lines) or the keys; false without a window.
    fn steer(&mut self, now: Instant, dt: f64, scripted_frame: u32) -> bool {
        let frames = self.args.frames;
        let Some(open) = self.state.as_mut() else { return false };
        match &self.path {
            Some(p) => {
                self.fly.camera = p.at(scripted_frame, frames);
                let asked = p.size_at(scripted_frame, frames).filter(|_| self.settling_since.is_none());
                if let Some([w, h]) = asked.filter(|_| self.resized_at != Some(scripted_frame)) {
                    self.resized_at = Some(scripted_frame);
                    let _ = open.window.request_inner_size(winit::dpi::PhysicalSize::new(w, h));
                }
                let minimise = p.minimise_at(scripted_frame, frames) && self.minimised_at != Some(scripted_frame);
                if minimise && self.minimising.is_none() {
                    self.minimising = Some(ScriptedMinimise::new(scripted_frame, now));
                    open.window.set_minimized(true);
                }
                if p.surface_lost_at(scripted_frame, frames) && self.surface_lost_at != Some(scripted_frame) {
                    self.surface_lost_at = Some(scripted_frame);
                    open.viewer.ctx.faults().lose_surface_at_acquire_in(0);
                }
            }
            None => self.fly.update(dt.min(0.25)),
        }
        true
    }

    /// A scripted `minimise` under way: asks again, restores, or gives up.
    fn step_minimise(&mut self, minimised: bool, now: Instant) {
        let Some(open) = self.state.as_mut() else { return };
        if let Some(m) = self.minimising.as_mut() {
            let step = m.step(minimised, now);
            if step == Step::Ask {
                open.window.set_minimized(true);
            } else if step != Step::Hold {
                let frame = m.frame;
                self.minimising = None;
                self.minimised_at = Some(frame);
                match step {
                    Step::Restore => open.window.set_minimized(false),
                    _ => println!("minimise at frame {frame}: the window manager did not minimise the window"),
                }
            }
        }
    }

    /// After a frame was presented: counts it, and on the last one writes
    /// the screenshot and ends the run (or holds until streaming settled).
    fn presented_one(
        &mut self,
        el: &ActiveEventLoop,
        now: Instant,
        final_frame: bool,
        shot: Option<viewer::Readback>,
    ) -> Result<()> {
        let open = self.state.as_mut().expect("checked above");
        let shoot = shot.is_some();
        self.started.get_or_insert(now);
        self.presented_all += 1;
        if self.skipped_minimised > 0 {
            let (n, [w, h]) = (self.skipped_minimised, open.viewer.presenter.extent());
            println!("restored: presenting {w}x{h} again after {n} redraws skipped while minimised");
            self.skipped_minimised = 0;
        }
        if !final_frame {
            self.presented += 1;
            return Ok(());
        }
        if self.args.screenshot.is_some() && !shoot {
            // The camera holds while the streamed set catches up.
            self.settling_since.get_or_insert(now);
            return Ok(());
        }
        self.presented += 1;
        if let (Some(shot), Some(file)) = (shot, &self.args.screenshot) {
            let (rgba, size) = open.viewer.read(&shot)?;
            vista::output::write_png(file, &rgba, size, image::ExtendedColorType::Rgba8)?;
            println!("screenshot: {} ({}x{})", file.display(), size[0], size[1]);
        }
        el.exit();
        Ok(())
    }

    fn run_overlay(&mut self) -> Result<OverlayFrame> {
        let open = self.state.as_mut().expect("open");
        let raw = open.egui_state.take_egui_input(&open.window);
        if let Some(t) = open.viewer.renderer.latest_timings() {
            self.overlay.observe(t);
        }
        let f = Frame {
            view: &self.view,
            fps: self.fps,
            camera: self.fly.camera.to_string(),
            speed_mps: self.fly.speed_mps,
            size: self.view.size,
            slots: open.viewer.renderer.terrain.slots(),
        };
        let shown = viewer::shown(&open.viewer, f);
        let (overlay, settings) = (&mut self.overlay, &mut self.settings);
        let out = open.egui.run_ui(raw, |ui| overlay.ui(&ui.ctx().clone(), &shown, settings));
        open.egui_state.handle_platform_output(&open.window, out.platform_output);
        open.viewer.overlay_textures(&out.textures_delta)?;
        let primitives = open.egui.tessellate(out.shapes, out.pixels_per_point);
        Ok(OverlayFrame { primitives, pixels_per_point: out.pixels_per_point })
    }

    fn key(&mut self, el: &ActiveEventLoop, code: KeyCode, pressed: bool) {
        match code {
            KeyCode::Escape if pressed => el.exit(),
            KeyCode::F1 if pressed => self.show_overlay = !self.show_overlay,
            KeyCode::KeyP if pressed => println!("--camera {}", self.fly.camera),
            _ => self.fly.key(code, pressed),
        }
    }

    /// Ends the run: every object destroyed, none left alive.
    fn finish(&mut self) -> Result<()> {
        let Some(open) = self.state.take() else { return Ok(()) };
        let Open { egui_state, egui, viewer, window } = open;
        drop((egui_state, egui));
        let (ctx, live) = viewer.close()?;
        drop(window);
        if live.total() != 0 {
            bail!("{} Vulkan objects still alive at exit: {live:?}", live.total());
        }
        let log = ctx.validation_log();
        drop(ctx);
        let messages = log.messages();
        if !messages.is_empty() {
            bail!(
                "{} validation message(s); the first: [{}] {}",
                messages.len(),
                messages[0].id_name,
                messages[0].text
            );
        }
        if let Some(m) = &self.minimising {
            println!("minimise at frame {}: the window manager did not minimise the window before the end", m.frame);
        }
        if let Some(t) = self.started {
            let s = t.elapsed().as_secs_f64();
            let n = self.presented_all;
            println!("presented {n} frames in {s:.1} s ({:.2} fps); 0 Vulkan objects alive at exit", n as f64 / s);
        }
        Ok(())
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.state.is_some() || self.failure.is_some() {
            return;
        }
        match self.open(el) {
            Ok(open) => {
                open.window.request_redraw();
                self.state = Some(open);
            }
            Err(e) => self.fail(el, e),
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(open) = self.state.as_mut() else { return };
        let consumed = self.show_overlay && open.egui_state.on_window_event(&open.window, &event).consumed;
        match event {
            WindowEvent::CloseRequested => el.exit(),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(el) {
                    self.fail(el, e);
                }
            }
            WindowEvent::Resized(s) => match open.viewer.resize([s.width, s.height]) {
                Ok(()) if self.path.is_some() => {
                    let [w, h] = open.viewer.presenter.extent();
                    println!("resized: swapchain {w}x{h} after frame {}", self.presented);
                }
                Ok(()) => {}
                Err(e) => self.fail(el, e),
            },
            WindowEvent::Focused(false) => self.fly.release_all(),
            WindowEvent::KeyboardInput { event, .. } if !consumed => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    self.key(el, code, event.state == ElementState::Pressed);
                }
            }
            WindowEvent::MouseInput { button: MouseButton::Right, state, .. } => {
                self.looking = state == ElementState::Pressed && !consumed;
            }
            WindowEvent::CursorMoved { position, .. } => {
                let p = [position.x, position.y];
                if let (true, Some(c)) = (self.looking, self.cursor) {
                    self.fly.look(p[0] - c[0], p[1] - c[1]);
                }
                self.cursor = Some(p);
            }
            WindowEvent::MouseWheel { delta, .. } if !consumed => match delta {
                MouseScrollDelta::LineDelta(_, y) => self.fly.wheel(f64::from(y)),
                MouseScrollDelta::PixelDelta(p) => self.fly.wheel(p.y / 50.0),
            },
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _el: &ActiveEventLoop) {
        if let Some(open) = &self.state {
            open.window.request_redraw();
        }
    }

    fn exiting(&mut self, _el: &ActiveEventLoop) {
        let r = self.finish();
        self.result = Some(match self.failure.take() {
            Some(e) => Err(e),
            None => r,
        });
    }
}

/// The window system's reason without the source position winit's errors
/// carry ("os error at .../linux/mod.rs:788: ...").
fn reason(e: &dyn std::fmt::Display) -> String {
    let text = e.to_string();
    match text.split_once(".rs:").and_then(|(_, rest)| rest.split_once(": ")) {
        Some((_, reason)) => reason.to_string(),
        None => text,
    }
}
