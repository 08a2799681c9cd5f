//! The `vista` command line: device info, rendering with per-pass timings,
//! baking node payloads and memory reports.

mod bake;
mod bench_cmd;
mod scene;
mod world_args;

use anyhow::{bail, Context as _, Result};
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use vista::gpu::{Context, ContextOptions};
use vista::terrain::{Terrain, TerrainOptions};
use world_args::WorldArgs;

#[derive(Parser)]
#[command(name = "vista", version, about = "GPU-driven terrain renderer for Vulkan")]
struct Cli {
    /// Enable the Khronos validation layer (prints every message it reports).
    #[arg(long, global = true)]
    validation: bool,
    /// Use the first Vulkan device whose name contains this (also: env VISTA_DEVICE).
    #[arg(long, global = true)]
    device: Option<String>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Device, driver, Vulkan version, queue families, async-compute mode and
    /// the limits the renderer depends on.
    Info {
        /// Print as JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Render frames and print the median GPU time of every pass.
    Render {
        /// Target size, e.g. 256x256.
        #[arg(long, default_value = "256x256", value_parser = parse_size)]
        size: [u32; 2],
        /// Frames to render (the first few are warm-up and excluded from medians).
        #[arg(long, default_value_t = 12)]
        frames: u32,
        /// Write image.png, timings.json and trace.json (Chrome/Perfetto) here.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Camera position in world metres (x,y,z); default: above the world's centre.
        #[arg(long, value_parser = parse_camera)]
        camera: Option<[f64; 3]>,
        /// Resident node slots (at most 1023: slots are 10-bit).
        #[arg(long, default_value_t = 512)]
        slots: u32,
        /// Cache baked nodes here across runs (default: bake in memory only).
        #[arg(long)]
        cache: Option<PathBuf>,
        /// Longest wait for the streamed set to become resident before the timed frames.
        #[arg(long, default_value_t = 120.0)]
        settle_seconds: f64,
        /// The world to stream (default: the procedural world, baked lazily).
        #[command(flatten)]
        world: WorldArgs,
    },
    /// Bake node payloads (every LOD) to disk and report counts, time, disk
    /// size and, for a region, the extrapolation to the whole world.
    Bake(bake::BakeArgs),
    /// Print CPU and GPU memory per payload kind for N resident nodes.
    Memory(bake::MemoryArgs),
    /// GPU-time benchmarks (medians after warm-up), e.g. `vista bench traverse --json t.json`.
    Bench(bench_cmd::BenchArgs),
}

pub(crate) fn parse_camera(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("camera {s:?} is not X,Y,Z in metres"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([x, y, z]),
        _ => Err(format!("camera {s:?} is not three finite numbers X,Y,Z")),
    }
}

fn parse_size(s: &str) -> Result<[u32; 2], String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("size {s:?} is not WIDTHxHEIGHT"))?;
    let p = |v: &str| v.trim().parse::<u32>().map_err(|_| format!("size {s:?}: {v:?} is not a number"));
    let (w, h) = (p(w)?, p(h)?);
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!("size {w}x{h} must be between 1x1 and 16384x16384"));
    }
    Ok([w, h])
}

fn main() {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => exit_on_usage_error(e),
    };
    if let Err(e) = run(cli) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

/// Help and version print as clap renders them; usage errors collapse to one
/// line (clap's own spans several, with a usage excerpt).
fn exit_on_usage_error(e: clap::Error) -> ! {
    use clap::error::ErrorKind;
    if matches!(
        e.kind(),
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        e.exit();
    }
    let text = e.render().to_string();
    // The first paragraph names the problem; usage and hints follow.
    let body = text.trim_start().split("\n\n").next().unwrap_or(&text);
    let line = body.split_whitespace().collect::<Vec<_>>().join(" ");
    eprintln!("{line}");
    std::process::exit(2);
}

fn run(cli: Cli) -> Result<()> {
    let options =
        ContextOptions { validation: cli.validation, sync_validation: false, device_name: cli.device.clone() };
    match cli.command {
        Command::Info { json } => with_gpu(&options, |ctx| info(ctx, json)),
        Command::Render { size, frames, out, camera, slots, cache, settle_seconds, world } => {
            // A bad world fails before the (slow) Vulkan start.
            let world = world.load()?;
            let run = RenderRun { size, frames, out, camera, slots, cache, settle_seconds };
            with_gpu(&options, |ctx| render(ctx, &world, run))
        }
        // Baking and accounting are CPU-only: no Vulkan needed.
        Command::Bake(args) => bake::bake(args),
        Command::Memory(args) => bake::memory(args),
        Command::Bench(args) => with_gpu(&options, |ctx| bench_cmd::bench(ctx, args)),
    }
}

/// Runs `f` on a fresh context and fails if the validation layer reported
/// anything.
fn with_gpu(options: &ContextOptions, f: impl FnOnce(&Context) -> Result<()>) -> Result<()> {
    let ctx = Context::headless(options).context("creating the Vulkan context")?;
    f(&ctx)?;
    let log = ctx.validation_log();
    drop(ctx);
    let messages = log.messages();
    if !messages.is_empty() {
        bail!("{} validation message(s); the first: [{}] {}", messages.len(), messages[0].id_name, messages[0].text);
    }
    Ok(())
}

fn info(ctx: &Context, json: bool) -> Result<()> {
    let i = ctx.info();
    if json {
        println!("{}", serde_json::to_string_pretty(i)?);
        return Ok(());
    }
    println!("device:        {} ({})", i.name, i.device_type);
    println!("driver:        {} {}", i.driver_name, i.driver_info);
    println!("vulkan:        {}", i.api_version);
    println!("queue families:");
    for f in &i.queue_families {
        let caps: Vec<&str> = [(f.graphics, "graphics"), (f.compute, "compute"), (f.transfer, "transfer")]
            .iter()
            .filter(|c| c.0)
            .map(|c| c.1)
            .collect();
        println!("  [{}] {} x{} (timestamp bits {})", f.index, caps.join("+"), f.queue_count, f.timestamp_valid_bits);
    }
    if i.async_compute {
        println!(
            "culling:       async compute queue (family {}), synchronised by timeline semaphores",
            i.compute_family
        );
    } else {
        println!("culling:       single-queue fallback: traversal and culling run on the graphics queue (family {}), same semaphores", i.graphics_family);
    }
    let l = &i.limits;
    println!("limits:");
    println!("  compute shared memory:  {} bytes", l.max_compute_shared_memory_bytes);
    println!(
        "  workgroup invocations:  {} (size {:?})",
        l.max_compute_workgroup_invocations, l.max_compute_workgroup_size
    );
    println!("  subgroup size:          {}", l.subgroup_size);
    println!("  push constants:         {} bytes", l.max_push_constants_bytes);
    println!("  image 2D / layers:      {} / {}", l.max_image_dimension_2d, l.max_image_array_layers);
    if l.timestamps_supported {
        println!("  timestamps:             yes, period {} ns", l.timestamp_period_ns);
    } else {
        println!("  timestamps:             no (renders without pass timings)");
    }
    Ok(())
}

/// Frames excluded from medians (pipeline creation, first-use costs).
const WARMUP_FRAMES: usize = 2;

struct RenderRun {
    size: [u32; 2],
    frames: u32,
    out: Option<PathBuf>,
    camera: Option<[f64; 3]>,
    slots: u32,
    cache: Option<PathBuf>,
    settle_seconds: f64,
}

fn render(ctx: &Context, world: &world_args::LoadedWorld, run: RenderRun) -> Result<()> {
    let RenderRun { size, frames, out, camera, slots, cache, settle_seconds } = run;
    if frames == 0 {
        bail!("--frames must be at least 1");
    }
    if !(settle_seconds.is_finite() && settle_seconds >= 0.0) {
        bail!("--settle-seconds must be a non-negative number");
    }
    let d = &world.desc;
    let camera = camera.unwrap_or([d.extent_m[0] / 2.0, d.extent_m[1] / 2.0, f64::from(d.height_range_m[1]) + 100.0]);
    let options = TerrainOptions { slots, cache_dir: cache, ..TerrainOptions::default() };
    let mut terrain = Terrain::new(ctx, d, world.source.clone(), world.holes.clone(), &options)?;
    let settle = std::time::Duration::from_secs_f64(settle_seconds);
    let result = vista::smoke::render_with(ctx, Some(&mut terrain), camera, size, frames, settle)?;
    let timed = if result.frames.len() > WARMUP_FRAMES { &result.frames[WARMUP_FRAMES..] } else { &result.frames[..] };
    println!("device: {}  ({} timed frames, {}x{})", ctx.info().name, frames, size[0], size[1]);
    println!("world:  {}  camera ({:.0}, {:.0}, {:.0}) m", world.label, camera[0], camera[1], camera[2]);
    let st = &terrain.stats;
    println!(
        "stream: {} resident of {} slots ({} on the GPU), {} loading, {} waiting upload, {} failed; settled after {} frames, {:.2} s (lazy bake, no bake step)",
        st.resident,
        slots,
        terrain.tree.shadow.resident_count(),
        st.loading,
        st.waiting_upload,
        st.failed,
        result.settle_frames,
        result.settle_seconds
    );
    // Debug check: the last frame's GPU node list against the CPU reference.
    let (header, gpu) = terrain.traverse.read_result(ctx)?;
    let cpu = vista::traverse_cpu::traverse_cpu(&terrain.tree.shadow, d, &vista::smoke::view_params(camera, size));
    let per_lod: Vec<String> = (0..d.lod_count as usize).map(|l| header.lod_counts[l].to_string()).collect();
    println!(
        "traverse: {} nodes (per LOD 0..: {}), overflow {}, missing roots {}; CPU reference: {}",
        header.node_count,
        per_lod.join("/"),
        header.overflow,
        header.missing_roots,
        if cpu == gpu { "identical" } else { "DIFFERENT" }
    );
    if cpu != gpu {
        bail!("the GPU traversal differs from the CPU reference ({} vs {} nodes)", gpu.nodes.len(), cpu.nodes.len());
    }
    println!("terrain geometry passes are not drawn yet; smoke passes stand in for them");
    if timed.is_empty() {
        println!("no pass timings (timestamps unsupported or no frame finished)");
    } else {
        println!("{:<16} {:<9} {:>10} {:>10} {:>10} {:>8}", "pass", "queue", "median ms", "min ms", "max ms", "frames");
        for s in vista::profiler::summarize(timed) {
            println!(
                "{:<16} {:<9} {:>10.4} {:>10.4} {:>10.4} {:>8}",
                s.name,
                format!("{:?}", s.queue).to_lowercase(),
                s.median_ms,
                s.min_ms,
                s.max_ms,
                s.samples
            );
        }
    }
    if let Some(dir) = out {
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        std::fs::write(dir.join("timings.json"), vista::profiler::to_json(&result.frames))?;
        std::fs::write(dir.join("trace.json"), vista::profiler::to_chrome_trace(&result.frames))?;
        image::save_buffer(
            dir.join("image.png"),
            &result.image,
            result.size[0],
            result.size[1],
            image::ExtendedColorType::Rgba8,
        )?;
        println!("wrote {}/{{image.png, timings.json, trace.json}}", dir.display());
    }
    print!("{}", terrain.memory_report());
    Ok(())
}
