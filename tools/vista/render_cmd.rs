//! `vista render`: streams the world, renders it through `TerrainRenderer`
//! exactly as an engine would, prints per-pass GPU medians, patch counts per
//! culling stage, triangles and nodes per LOD, and writes the picture, the
//! depth and the numbers with `--out`.

use crate::render_out::Outputs;
use crate::world_args::{show_m, LoadedWorld, WorldArgs};
use anyhow::{bail, Result};
use clap::Args;
use std::path::{Path, PathBuf};
use vista::effects::virtual_texture::state::VtCounters;
use vista::frame::FrameTimings;
use vista::gpu::{Context, QueueMode};
use vista::passes::cull_patches::CullStages;
use vista::render::offscreen::{Offscreen, OffscreenDesc};
use vista::render::{
    overview_camera, Camera, LodOptions, LodRule, RendererOptions, TerrainRenderer, View, DEFAULT_NEAR_M,
};
use vista::targets::{GbufferLayout, Output};
use vista::terrain::TerrainOptions;
use vista::world::Work;

/// Frames excluded from medians (pipeline creation, first-use costs).
const WARMUP_FRAMES: usize = 2;
/// Background of the lit image where there is no terrain (sky blue, linear).
pub(crate) const SKY_CLEAR: [f32; 4] = [0.55, 0.68, 0.85, 1.0];

#[derive(Args)]
pub struct RenderArgs {
    /// Frames rendered after streaming settled. Of more than 2, the first 2
    /// are warm-up, left out of the medians and timings.json; 1 or 2 frames
    /// are all timed (and include first-use costs).
    #[arg(long, default_value_t = 12, value_parser = crate::numbers::whole_u32, allow_negative_numbers = true)]
    pub frames: u32,
    /// Folder for the output's images (lit: image.png and lit.exr; hdr:
    /// lit.exr; gbuffer: albedo.png, normal.exr, roughness.png), depth.exr,
    /// classification.png, timings.json (the timed frames), trace.json
    /// (every frame), stats.json and report.json: created (if needed) once
    /// the render succeeded, its files written whole and all together, or
    /// none of them.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// What the frame writes, as an engine would choose: lit (vista's own
    /// lit, tonemapped picture), hdr (linear radiance, no tonemap, into an
    /// R16G16B16A16_SFLOAT target) or gbuffer (no lighting: base colour,
    /// normal, roughness and material into an engine's G-buffer, the
    /// octahedral layout: RGBA8 sRGB base colour, RG16 octahedral normal,
    /// RG8 roughness and material).
    #[arg(long, default_value = "lit", value_parser = parse_output)]
    pub output: Output,
    /// Print the pass report: effects and why each is on or off, pipelines
    /// built, per pass not built / idle / ran with GPU ms and work, GPU
    /// memory per effect.
    #[arg(long)]
    pub report: bool,
    /// Count each graphics-queue pass's pipeline statistics and print a
    /// draw's triangles in, vertex shader invocations, triangles out of
    /// clipping and fragment shader invocations beside its time (medians;
    /// also in timings.json). Needs the device's pipelineStatisticsQuery.
    #[arg(long)]
    pub counters: bool,
    /// How frames are submitted: auto (async where the device has a
    /// compute-only queue family, else single), single (one command buffer),
    /// split (compute and graphics command buffers on the graphics queue,
    /// joined by a timeline semaphore) or async.
    #[arg(long, default_value = "auto", value_parser = parse_queues)]
    pub queues: QueuesArg,
    /// Cache baked nodes and the error tree here across runs (default: bake
    /// in memory only; the error tree goes to $VISTA_CACHE, else
    /// $XDG_CACHE_HOME/vista, else ~/.cache/vista).
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// Longest wait for the streamed set to become resident before the measured frames.
    #[arg(long, default_value_t = 120.0, value_parser = crate::numbers::number_f64, allow_negative_numbers = true)]
    pub settle_seconds: f64,
    /// A fly-through: after settling, the camera moves this many metres a
    /// frame along its heading, keeping its height above the ground, over
    /// the --frames frames (streaming and pages follow it); prints the
    /// virtual texture's pages per frame. The image is the last frame's.
    #[arg(long, value_parser = crate::numbers::number_f64, allow_negative_numbers = true)]
    pub fly: Option<f64>,
    #[command(flatten)]
    pub viewpoint: ViewpointArgs,
    /// The world to render (default: the procedural world, baked lazily).
    #[command(flatten)]
    pub world: WorldArgs,
}

/// The view and streaming options `vista render` and `vista view` share.
#[derive(Args)]
pub struct ViewpointArgs {
    /// Target (`vista view`: window) size, e.g. 1280x720.
    #[arg(long, default_value = "1280x720", value_parser = parse_size, allow_hyphen_values = true)]
    pub size: [u32; 2],
    /// Camera X,Y,Z[,YAW,PITCH]: metres (x east, y north, z up; the world's
    /// south-west corner at --origin, default 0,0); YAW compass degrees (0 = +y, 90 = +x);
    /// PITCH degrees above the horizon (-90 = straight down). Default: above
    /// the south edge looking north over the world.
    #[arg(long, value_parser = parse_camera, allow_hyphen_values = true)]
    pub camera: Option<CameraArg>,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = 60.0, value_parser = crate::numbers::number_f64, allow_negative_numbers = true)]
    pub fov: f64,
    /// Largest accepted projected vertical error in pixels (the accuracy
    /// knob; a slider in `vista view`'s overlay).
    #[arg(long, default_value_t = 1.0, value_parser = crate::numbers::number_f32, allow_negative_numbers = true)]
    pub target_error: f32,
    /// Culling stages to run: any of frustum,cone,hole,occlusion, or none.
    #[arg(long, default_value = "frustum,cone,hole,occlusion", value_parser = parse_stages)]
    pub cull: CullStages,
    /// GPU memory for resident nodes, MiB: their payload atlases and each
    /// effect's layer per node. Sets how many nodes stay resident (the
    /// `stream:` line prints it) [default: a quarter of the device's local
    /// memory, at most what its most slots need].
    #[arg(long, value_parser = crate::numbers::number_f64, allow_negative_numbers = true)]
    pub gpu_budget: Option<f64>,
    /// Resident node slots instead of a budget (at most 2047: slots are
    /// 11-bit).
    #[arg(long, conflicts_with = "gpu_budget", value_parser = crate::numbers::whole_u32, allow_negative_numbers = true)]
    pub slots: Option<u32>,
    /// LOD selection: `patch` (per 8x8-quad patch, Far Cry 5's) or
    /// `triangle` (per triangle inside each node, a restricted bintree with
    /// saturated errors, refined below the samples; computes the world's
    /// per-vertex bounds first; effect cone_cull drops the triangles it
    /// leaves whole that face away).
    #[arg(long, default_value = "patch", value_parser = parse_lod_rule)]
    pub lod_rule: LodRule,
}

pub fn parse_lod_rule(s: &str) -> Result<LodRule, String> {
    match s {
        "patch" => Ok(LodRule::Patch),
        "triangle" => Ok(LodRule::Triangle),
        _ => Err(format!("unknown LOD rule {s:?}: use patch or triangle")),
    }
}

impl ViewpointArgs {
    /// The view these options ask for (the default camera needs the world).
    pub fn view(&self, world: &LoadedWorld) -> View {
        View {
            camera: camera_of(self.camera, world),
            fov_y_deg: self.fov,
            size: self.size,
            target_error_px: self.target_error,
            near_m: DEFAULT_NEAR_M,
        }
    }

    /// The renderer these options and the world ask for on this device.
    pub fn renderer_options(
        &self,
        ctx: &Context,
        world: &LoadedWorld,
        cache: Option<&Path>,
        errors: std::sync::Arc<vista::world::ErrorTree>,
    ) -> Result<RendererOptions> {
        let budget = crate::budget::NodeBudget::of(self, world, &ctx.info().limits)?;
        Ok(RendererOptions {
            terrain: TerrainOptions {
                slots: budget.slots,
                cache_dir: cache.map(Path::to_path_buf),
                errors: Some(errors),
                bake: world.bake.clone(),
                limits: world.limits.clone(),
                ..TerrainOptions::default()
            },
            stages: self.cull,
            lod: LodOptions { rule: self.lod_rule, ..LodOptions::default() },
            effects: world.effects.clone(),
            origin_m: world.origin_m,
            decals: world.decals.clone(),
            assets: world.assets.clone(),
            ..RendererOptions::default()
        })
    }
}

fn parse_output(s: &str) -> Result<Output, String> {
    match s {
        "lit" => Ok(Output::default()),
        "hdr" => Ok(Output::hdr()),
        "gbuffer" => Ok(Output::Gbuffer(GbufferLayout::octahedral())),
        _ => Err(format!("unknown output {s:?}: use lit, hdr or gbuffer")),
    }
}

#[derive(Clone, Copy, Debug)]
pub enum QueuesArg {
    Auto,
    Mode(QueueMode),
}

fn parse_queues(s: &str) -> Result<QueuesArg, String> {
    match s {
        "auto" => Ok(QueuesArg::Auto),
        "single" => Ok(QueuesArg::Mode(QueueMode::Single)),
        "split" => Ok(QueuesArg::Mode(QueueMode::SplitOneQueue)),
        "async" => Ok(QueuesArg::Mode(QueueMode::AsyncCompute)),
        _ => Err(format!("unknown queue mode {s:?}: use auto, single, split or async")),
    }
}

/// `--camera` as given: a position, and a heading and pitch if given.
#[derive(Clone, Copy, Debug)]
pub struct CameraArg {
    pub position: [f64; 3],
    pub angles: Option<[f64; 2]>,
}

fn numbers(s: &str, what: &str) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("{what} {s:?} is not a comma-separated list of numbers"))?;
    if v.iter().any(|c| !c.is_finite()) {
        return Err(format!("{what} {s:?} has a value that is not a finite number"));
    }
    Ok(v)
}

pub(crate) fn parse_position(s: &str) -> Result<[f64; 3], String> {
    match numbers(s, "camera")?[..] {
        [x, y, z] => Ok([x, y, z]),
        _ => Err(format!("camera {s:?} is not X,Y,Z in metres")),
    }
}

pub(crate) fn parse_camera(s: &str) -> Result<CameraArg, String> {
    match numbers(s, "camera")?[..] {
        [x, y, z] => Ok(CameraArg { position: [x, y, z], angles: None }),
        [x, y, z, yaw, pitch] if (-90.0..=90.0).contains(&pitch) => {
            Ok(CameraArg { position: [x, y, z], angles: Some([yaw, pitch]) })
        }
        [.., pitch] if s.split(',').count() == 5 => {
            Err(format!("camera pitch {pitch} is outside -90..=90 degrees (-90 looks straight down)"))
        }
        _ => Err(format!("camera {s:?} is not X,Y,Z or X,Y,Z,YAW,PITCH")),
    }
}

pub(crate) fn parse_size(s: &str) -> Result<[u32; 2], String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("size {s:?} is not WIDTHxHEIGHT"))?;
    let p = |v: &str| v.trim().parse::<u32>().map_err(|_| format!("size {s:?}: {v:?} is not a whole number"));
    let (w, h) = (p(w)?, p(h)?);
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!("size {w}x{h} must be between 1x1 and 16384x16384"));
    }
    Ok([w, h])
}

pub(crate) fn parse_stages(s: &str) -> Result<CullStages, String> {
    let mut st = CullStages::NONE;
    if s.trim() == "none" {
        return Ok(st);
    }
    for part in s.split(',') {
        match part.trim() {
            "frustum" => st.frustum = true,
            "cone" => st.cone = true,
            "hole" => st.hole = true,
            "occlusion" => st.occlusion = true,
            other => return Err(format!("culling stage {other:?} is not one of frustum, cone, hole, occlusion, none")),
        }
    }
    Ok(st)
}

/// Checks that `--out` and `--cache` can be written, so a bad path fails
/// before the render, not after it. Neither is created here: `--out`
/// appears with the render's files, the cache with its first file.
pub fn check_paths(args: &RenderArgs) -> Result<()> {
    if let Some(dir) = &args.out {
        crate::out_path::check_out_dir(dir, "--out", crate::render_out::files(&args.output))?;
    }
    if let Some(dir) = &args.cache {
        crate::out_path::check_out_dir(dir, "--cache", "the baked node files")?;
    }
    Ok(())
}

/// The view the arguments ask for (the default camera needs the world).
pub fn view_of(args: &RenderArgs, world: &LoadedWorld) -> Result<View> {
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    if !(args.settle_seconds.is_finite() && args.settle_seconds >= 0.0) {
        bail!("--settle-seconds must be a non-negative number");
    }
    let view = args.viewpoint.view(world);
    check_view(&view, world)?;
    if let Some(m) = args.fly {
        if !(m.is_finite() && m > 0.0) {
            bail!("--fly {m}: metres a frame, a positive number");
        }
        let end = flown(&view, world, m, args.frames).camera.position_m;
        let [ox, oy] = world.origin_m;
        let [ex, ey] = world.desc.extent_m;
        if !(ox..=ox + ex).contains(&end[0]) || !(oy..=oy + ey).contains(&end[1]) {
            bail!(
                "--fly {m} over {} frames ends at ({:.0}, {:.0}), outside the world; fly slower or fewer frames",
                args.frames,
                end[0],
                end[1]
            );
        }
    }
    Ok(view)
}

/// `view` moved `m` metres a frame for `frame` frames along its heading,
/// at its height above the ground where it started.
fn flown(view: &View, world: &LoadedWorld, m: f64, frame: u32) -> View {
    let c = view.camera;
    let ground = |x: f64, y: f64| f64::from(world.source.sample(x - world.origin_m[0], y - world.origin_m[1]));
    let up = c.position_m[2] - ground(c.position_m[0], c.position_m[1]);
    let (sin, cos) = c.yaw_deg.to_radians().sin_cos();
    let d = m * f64::from(frame);
    let (x, y) = (c.position_m[0] + d * sin, c.position_m[1] + d * cos);
    View { camera: Camera { position_m: [x, y, ground(x, y) + up], ..c }, ..view.clone() }
}

/// Frame by frame along a fly-through: the timings that came back (as
/// `Offscreen::run`), the virtual texture's counters after each frame and
/// the last view.
fn fly(
    ctx: &Context,
    off: &mut Offscreen,
    renderer: &mut TerrainRenderer,
    world: &LoadedWorld,
    view: &View,
    (m, frames): (f64, u32),
    progress: &vista::world::Reporter,
) -> Result<(Vec<FrameTimings>, Vec<VtCounters>, View)> {
    let (mut timings, mut pages) = (Vec::<FrameTimings>::new(), Vec::new());
    let mut last = view.clone();
    for i in 1..=frames {
        last = flown(view, world, m, i);
        off.frame(ctx, renderer, &last)?;
        progress.inc();
        if let Some(t) = renderer.latest_timings() {
            if timings.last().is_none_or(|l| l.frame < t.frame) {
                timings.push(t.clone());
            }
        }
        pages.extend(renderer.effect::<vista::effects::virtual_texture::VirtualTexture>().map(|v| v.counters()));
    }
    Ok((timings, pages, last))
}

/// `--camera`, or the default view above the south edge.
pub fn camera_of(arg: Option<CameraArg>, world: &LoadedWorld) -> Camera {
    match arg {
        None => {
            let mut c = overview_camera(&world.desc, &*world.source);
            c.position_m[0] += world.origin_m[0];
            c.position_m[1] += world.origin_m[1];
            c
        }
        Some(CameraArg { position, angles }) => {
            let [yaw_deg, pitch_deg] = angles.unwrap_or([0.0, -20.0]);
            Camera { position_m: position, yaw_deg, pitch_deg }
        }
    }
}

/// What a user can get wrong in a view, in the options' words.
pub fn check_view(view: &View, world: &LoadedWorld) -> Result<()> {
    if let Err(e) = view.validate() {
        let message = e.to_string().replace("field of view", "--fov").replace("target error", "--target-error");
        bail!("{}", message.trim_start_matches("bad input: "));
    }
    let p = view.camera.position_m;
    if p.iter().any(|v| v.abs() > PROVEN_RANGE_M) {
        bail!(
            "--camera {},{},{}: coordinates beyond +-{PROVEN_RANGE_M:e} m are outside what `vista stability` case 1 \
             proves exact",
            show_m(p[0]),
            show_m(p[1]),
            show_m(p[2])
        );
    }
    note_camera_place(view, world);
    Ok(())
}

/// Placement and camera coordinates `vista stability` case 1 renders
/// exactly (f64 world-relative views, 2 nm at 1e7 m).
pub const PROVEN_RANGE_M: f64 = 1e7;

/// A camera outside the world or under the ground still renders (a user
/// may mean it), but says so in one line.
fn note_camera_place(view: &View, world: &LoadedWorld) {
    let [x, y, z] = view.camera.position_m;
    let (lx, ly) = (x - world.origin_m[0], y - world.origin_m[1]);
    let [ex, ey] = world.desc.extent_m;
    if !(0.0..=ex).contains(&lx) || !(0.0..=ey).contains(&ly) {
        let [ox, oy] = world.origin_m;
        eprintln!(
            "note: the camera ({x}, {y}) is outside the world ({ox}..{} x {oy}..{} m); it looks from outside",
            ox + ex,
            oy + ey
        );
        return;
    }
    let ground = f64::from(world.source.sample(lx, ly));
    if z < ground {
        eprintln!(
            "note: the camera is {:.1} m below the ground ({ground:.1} m) at ({x}, {y}); it sees the terrain from \
             underneath",
            ground - z
        );
    }
}

pub fn render(ctx: &Context, world: &LoadedWorld, view: &View, args: &RenderArgs) -> Result<()> {
    let (mut renderer, mut off) = renderer_and_target(ctx, world, view, args)?;
    let ready_s = crate::STARTED.get().map_or(0.0, |t| t.elapsed().as_secs_f64());
    // Settling spends more a frame to need fewer; the timed frames after it do not.
    renderer.set_catch_up(true);
    let settle = off.settle(ctx, &mut renderer, view, std::time::Duration::from_secs_f64(args.settle_seconds))?;
    renderer.set_catch_up(false);
    let first = renderer.frames_recorded() + 1;
    // A bar on a terminal, a line every 5 s otherwise (long runs only).
    let progress = vista::world::Reporter::new(crate::progress::auto(), u64::from(args.frames), Work::Frames);
    let (mut frames, pages, end) = match args.fly {
        Some(m) => fly(ctx, &mut off, &mut renderer, world, view, (m, args.frames), &progress)?,
        None => (off.run_observed(ctx, &mut renderer, view, args.frames, || progress.inc())?, Vec::new(), view.clone()),
    };
    let view = &end;
    progress.finish();
    let capture = off.capture(ctx)?;
    // The last frame's timings are back once capture waited for it; they
    // count like the others.
    let last = renderer.poll_timings(ctx).cloned();
    if let Some(t) = &last {
        if frames.last().is_none_or(|l| l.frame < t.frame) {
            frames.push(t.clone());
        }
    }
    let report = vista::render::frame_report(ctx, &renderer, last.as_ref())?;
    // Only this run's frames (the first poll may return a settling one),
    // warm-up counted in frames rendered, not in timings received (some
    // can be dropped when the GPU lags). The printed medians and
    // timings.json come from these same frames.
    frames.retain(|f| f.frame >= first);
    let warmup = if args.frames as usize > WARMUP_FRAMES { WARMUP_FRAMES } else { 0 };
    let warmup_timed = frames.iter().take_while(|f| f.frame < first + warmup as u64).count();
    let timed = &frames[warmup_timed..];
    crate::render_print::print_device_and_world(ctx, world, view, args, timed.len(), warmup);
    let budget = crate::budget::NodeBudget::of(&args.viewpoint, world, &ctx.info().limits)?;
    crate::render_print::print_stream_and_queues(ctx, &renderer, args, (&settle, &budget), timed);
    let on_demand = renderer.terrain.errors().roots_on_demand();
    println!(
        "time: {ready_s:.1} s from start to the first frame ({}), then {:.1} s streaming to {}",
        if on_demand { "world, the error tree of the roots in view, renderer" } else { "world, error tree, renderer" },
        settle.seconds,
        if settle.settled { "settled" } else { "the --settle-seconds limit" }
    );
    crate::render_print::print_error_tree(&renderer.terrain);
    let stats = vista::render::stats::collect(ctx, &renderer, view)?;
    let built = built_stages(args, &renderer);
    if let Some(m) = args.fly {
        let budget = renderer.effect::<vista::effects::virtual_texture::VirtualTexture>().map(|v| v.state.budget);
        crate::render_print::print_fly(m, args.frames, &pages, budget);
    }
    crate::render_print::print_stats(&stats, built, built.occlusion);
    crate::render_print::print_timings(timed);
    if args.report {
        print!("{}", report.to_text());
    }
    if let Some(dir) = &args.out {
        let gbuffer = renderer.gbuffer.as_ref().expect("a frame was rendered").capture(ctx)?;
        let output = &args.output;
        let files = Outputs {
            frames: &frames,
            warmup: warmup_timed,
            capture: &capture,
            gbuffer: &gbuffer,
            stats: &stats,
            output,
        };
        files.write(dir, view, &serde_json::to_string_pretty(&report)?)?;
    }
    print!("{}", renderer.terrain.memory_report());
    Ok(())
}

/// The renderer as the options build it, and the offscreen target it draws into.
fn renderer_and_target(
    ctx: &Context,
    world: &LoadedWorld,
    view: &View,
    args: &RenderArgs,
) -> Result<(TerrainRenderer, Offscreen)> {
    // The per-triangle rule's bounds are made whole anyway: so is the tree.
    let errors = match args.viewpoint.lod_rule {
        LodRule::Patch => {
            let tree = world.errors_on_demand(ctx, args.cache.as_deref())?;
            world.prepare_roots_in_view(&tree, view);
            tree
        }
        LodRule::Triangle => world.errors(ctx, args.cache.as_deref())?,
    };
    let mut options = args.viewpoint.renderer_options(ctx, world, args.cache.as_deref(), errors)?;
    options.output = args.output.clone();
    options.counters = args.counters;
    if args.counters && !ctx.info().limits.pipeline_statistics {
        anyhow::bail!("--counters: {} has no pipeline statistics queries (pipelineStatisticsQuery)", ctx.info().name);
    }
    let d = &world.desc;
    let start = std::time::Instant::now();
    if options.lod.rule == LodRule::Triangle {
        println!("per-triangle rule: the per-vertex bounds of the whole world first (from the cache, else every LOD-0 sample)");
    }
    let renderer = TerrainRenderer::new(ctx, d, world.source.clone(), world.holes.clone(), &options)
        .map_err(crate::world_args::plan_error_is_input)?;
    if let Some(origin) = renderer.terrain.bounds_origin() {
        println!("per-triangle rule: renderer made in {:.1} s; the bounds {origin}", start.elapsed().as_secs_f64());
    }
    let mode = match args.queues {
        QueuesArg::Auto => QueueMode::auto(ctx.info()),
        QueuesArg::Mode(m) => m,
    };
    // An engine's G-buffer starts cleared to 0 (no surface).
    let clear = if args.output.lights() { SKY_CLEAR } else { [0.0; 4] };
    let desc = OffscreenDesc {
        frames_in_flight: options.terrain.frames_in_flight,
        mode,
        output: args.output.clone(),
        ..OffscreenDesc::new(view.size, clear)
    };
    let off = Offscreen::with_desc(ctx, &desc)?;
    Ok((renderer, off))
}

/// The culling stages asked for that the renderer built.
fn built_stages(args: &RenderArgs, renderer: &TerrainRenderer) -> CullStages {
    CullStages {
        frustum: args.viewpoint.cull.frustum,
        cone: args.viewpoint.cull.cone && renderer.cull.build.cone,
        hole: args.viewpoint.cull.hole && renderer.cull.build.holes,
        occlusion: args.viewpoint.cull.occlusion && renderer.cull.build.occlusion,
    }
}
