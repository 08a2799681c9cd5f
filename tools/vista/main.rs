//! The `vista` command line: device info, rendering with per-pass timings,
//! baking node payloads and memory reports.

mod accuracy_plot;
mod bake;
mod bake_shard;
mod bench_accuracy_cmd;
mod bench_cmd;
mod bench_cpu_cmd;
mod bench_cull_cmd;
mod bench_effects_cmd;
mod bench_shade_cmd;
mod budget;
mod golden_cmd;
mod heightmap_files;
mod numbers;
mod out_path;
mod placements;
mod progress;
mod render_cmd;
mod render_out;
mod render_print;
mod scene;
mod scene_words;
mod stability_cmd;
mod vegetate_cmd;
#[cfg(feature = "view")]
mod view;
mod world_args;
mod world_errors;
mod world_notes;
mod world_spec;

use anyhow::{bail, Context as _, Result};
use clap::{Parser, Subcommand};
use vista::gpu::{Context, ContextOptions};

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
    /// Render the terrain and print per-pass GPU medians, patch counts per
    /// culling stage, triangles drawn and nodes per LOD.
    Render(render_cmd::RenderArgs),
    /// Bake node payloads (every LOD) to disk and report counts, time, disk
    /// size and, for a region, the extrapolation to the whole world.
    Bake(bake::BakeArgs),
    /// Print CPU and GPU memory per payload kind for N resident nodes.
    Memory(bake::MemoryArgs),
    /// GPU-time benchmarks (medians after warm-up), e.g. `vista bench traverse --json t.json`.
    Bench(bench_cmd::BenchArgs),
    /// Render the golden views and compare them with their references (FLIP);
    /// `--update` rewrites the references and prints what changed.
    Golden(golden_cmd::GoldenArgs),
    /// Open a window over the world: a fly camera (WASD, mouse, wheel) and a
    /// live overlay of per-pass GPU times, counters and switches.
    #[cfg(feature = "view")]
    View(view::ViewArgs),
    /// Run the hard cases (far from the origin, depth, octahedral normals,
    /// grazing angles, NaN hygiene, seams, determinism, faults, fuzzing,
    /// soak) under the validation layer and print the table; exits 1 when a
    /// case fails.
    Stability(stability_cmd::StabilityArgs),
    /// Grow vegetation over the world (REDengine 3's offline generator):
    /// resource flowing downhill, the day's sun, the scene's brushes; writes
    /// instances, occurrence maps and the maps' pictures.
    Vegetate(vegetate_cmd::VegetateArgs),
}

/// When the process started: `vista render` says how long the first frame
/// took to come (the world, its error tree and the renderer made).
pub static STARTED: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();

fn main() {
    STARTED.get_or_init(std::time::Instant::now);
    fewer_malloc_arenas();
    quiet_when_stdout_closes();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    // `vista bench KIND --help` is the kind's own (clap's would list every
    // kind's options).
    let argv: Vec<String> = std::env::args().collect();
    if let [_, bench, kind, help] = &argv[..] {
        if bench == "bench" && (help == "--help" || help == "-h") {
            if let Some(text) = bench_cmd::kind_help(kind) {
                print!("{text}");
                return;
            }
        }
    }
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => exit_on_usage_error(e),
    };
    // Tests walk every write-failure path: the Nth write, fsync or rename
    // (from 0) fails (`VISTA_FAIL_WRITE`, `_SYNC`, `_RENAME`).
    vista::output::arm_from_env(&|name| std::env::var(name).ok());
    let result = match std::env::var_os("VISTA_CHECK_ONLY") {
        Some(_) => check_only(&cli),
        None => run(cli),
    };
    write_peak_rss();
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        // Bad input (a scene, a height map, a view) is the caller's to fix:
        // exit 2 like a usage error; 1 is a failure while running.
        std::process::exit(if e.chain().any(|c| c.is::<InputError>()) { 2 } else { 1 });
    }
}

/// `vista ... | head`: once the reader has gone, `println!` panics on the
/// closed pipe; stop quietly instead, with the status a shell gives a
/// process SIGPIPE ended (128 + 13), as Unix tools do.
fn quiet_when_stdout_closes() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let text = payload.downcast_ref::<String>().map(String::as_str).or(payload.downcast_ref::<&str>().copied());
        if text.is_some_and(|t| t.starts_with("failed printing to stdout") && t.contains("Broken pipe")) {
            std::process::exit(141);
        }
        default(info);
    }));
}

/// glibc gives each thread that allocates its own arena, up to 8 per core,
/// and keeps what a thread freed in it: the loader threads' node buffers and
/// the error tree's tiles read again left a 160x120 render of the default
/// world at 608-617 MiB peak, 450 MiB with an arena per core (403 with one),
/// streaming as fast. Other C libraries (and an environment's
/// MALLOC_ARENA_MAX, read earlier) are left alone.
fn fewer_malloc_arenas() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get()).clamp(1, 64) as i32;
        if std::env::var_os("MALLOC_ARENA_MAX").is_none() {
            // SAFETY: mallopt only sets an allocator parameter; called first
            // in main, before any thread this process starts.
            unsafe { libc::mallopt(libc::M_ARENA_MAX, cores) };
        }
    }
}

/// Tests read the process's peak memory here (`VISTA_PEAK_RSS_FILE=PATH`):
/// the kernel's high-water mark, VmHWM of /proc/self/status (Linux), which
/// unlike a sample taken from outside cannot miss a short-lived peak.
fn write_peak_rss() {
    let Some(path) = std::env::var_os("VISTA_PEAK_RSS_FILE") else { return };
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let line = status.lines().find(|l| l.starts_with("VmHWM:")).unwrap_or("VmHWM: unknown");
    if let Err(e) = std::fs::write(&path, format!("{line}\n")) {
        eprintln!("warning: cannot write VISTA_PEAK_RSS_FILE {}: {e}", std::path::Path::new(&path).display());
    }
}

/// An error in what the user gave (a scene, a world, a view): exit code 2.
#[derive(Debug)]
pub struct InputError(pub String);

impl std::fmt::Display for InputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for InputError {}

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
    let options = ContextOptions { validation: cli.validation, device_name: cli.device.clone(), ..Default::default() };
    match cli.command {
        Command::Info { json } => with_gpu(&options, |ctx| info(ctx, json)),
        Command::Render(args) => {
            // A bad world or view fails before the (slow) Vulkan start.
            let world = args.world.load()?;
            budget::check(&args.viewpoint, &world)?;
            let view = render_cmd::view_of(&args, &world).map_err(|e| InputError(format!("{e:#}")))?;
            render_cmd::check_paths(&args)?;
            with_gpu(&options, |ctx| render_cmd::render(ctx, &world, &view, &args))
        }
        // Baking and accounting are CPU-only: no Vulkan needed.
        Command::Bake(args) => bake::bake(args),
        Command::Memory(args) => bake::memory(args),
        Command::Bench(args) => {
            bench_cmd::check(&args)?;
            with_gpu(&options, |ctx| bench_cmd::bench(ctx, args))
        }
        Command::Golden(args) => {
            golden_cmd::check(&args)?;
            with_gpu(&options, |ctx| golden_cmd::golden(ctx, &args))
        }
        #[cfg(feature = "view")]
        Command::View(args) => {
            // A bad world, view or path fails before the window opens.
            let (world, path) = view::check(&args).map_err(|e| InputError(format!("{e:#}")))?;
            view::view(options, args, world, path)
        }
        Command::Stability(args) => stability_cmd::stability(cli.device.clone(), &args),
        // CPU-only, like baking.
        Command::Vegetate(args) if args.sun == vegetate_cmd::SunOn::Gpu => {
            vegetate_cmd::check(&args)?;
            with_gpu(&options, |ctx| vegetate_cmd::vegetate(&args, Some(ctx)))
        }
        Command::Vegetate(args) => vegetate_cmd::vegetate(&args, None),
    }
}

/// `VISTA_CHECK_ONLY=1 vista ...`: the command's arguments and inputs
/// (scene, height map, view, paths) checked as the command checks them
/// before it starts a device or any long work, then nothing more. The
/// docs' commands are tested this way (`tools/vista/tests/doc_commands.rs`).
fn check_only(cli: &Cli) -> Result<()> {
    match &cli.command {
        Command::Info { .. } | Command::Stability(_) => {}
        Command::Render(args) => {
            let world = args.world.load()?;
            budget::check(&args.viewpoint, &world)?;
            render_cmd::view_of(args, &world).map_err(|e| InputError(format!("{e:#}")))?;
            render_cmd::check_paths(args)?;
        }
        Command::Bake(args) => {
            let spec = args.world.resolve()?;
            spec.check(&spec.plan(args.region), &spec.limits)?;
        }
        Command::Memory(args) => {
            args.world.resolve()?;
        }
        Command::Bench(args) => bench_cmd::check(args)?,
        Command::Golden(args) => golden_cmd::check(args)?,
        Command::Vegetate(args) => vegetate_cmd::check(args)?,
        #[cfg(feature = "view")]
        Command::View(args) => {
            view::check(args).map_err(|e| InputError(format!("{e:#}")))?;
        }
    }
    println!("checked: the arguments and inputs are valid (VISTA_CHECK_ONLY: nothing run)");
    Ok(())
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
    // What `vista render --queues auto` will do on this device, not a claim
    // that anything ran.
    if i.async_compute {
        println!(
            "async compute: available (compute-only family {}); `vista render` submits streaming, traversal and \
             culling there by default (--queues auto), the graphics queue waiting on a timeline semaphore",
            i.compute_family
        );
    } else {
        println!(
            "async compute: not available (no compute-only family); `vista render` records one command buffer on \
             family {} (--queues split: two command buffers on the one queue, joined by a timeline semaphore)",
            i.graphics_family
        );
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
