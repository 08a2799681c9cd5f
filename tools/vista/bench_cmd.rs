//! `vista bench`: GPU-time benchmarks with medians after warm-up.

use crate::world_args::WorldArgs;
use anyhow::Result;
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};
use vista::bench::{bench_traverse, TraverseBenchConfig};
use vista::gpu::Context;

#[derive(Clone, Copy, Debug, PartialEq, ValueEnum)]
pub enum BenchKind {
    /// One-dispatch vs per-level traversal over resident sets and error targets.
    Traverse,
    /// Patch culling per view: patches per stage, triangles vs the full mesh,
    /// (traverse + cull) vs geometry time, the cone stage's cost and saving.
    Cull,
    /// GPU frame time and memory of the minimal scene, the full scene and
    /// the full scene without each effect in turn.
    Effects,
    /// Tiled shading vs one pipeline doing every flavour, on views with and
    /// without cliffs; classification's share; tiles per variant; stochastic
    /// vs blended cliffs.
    Shade,
    /// What accuracy costs: target error, culling and shading settings
    /// against a CPU ray-caster (depth, silhouette, geometric error in px,
    /// PSNR and FLIP of the lit image), with a Pareto plot (`--plot`).
    Accuracy,
    /// The renderer's CPU ms per frame on the world and on a far larger one
    /// from the same generator (--far-extent), same view and slots: per-frame
    /// CPU work should follow what is near, not the world's size.
    Cpu,
}

#[derive(Args)]
pub struct BenchArgs {
    /// What to benchmark.
    #[arg(value_enum)]
    kind: BenchKind,
    /// Write the table as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
    /// `bench traverse`: resident-set sizes (nodes; at most 2047: slots are
    /// 11-bit) [default: 64,256,512,1000].
    #[arg(long, value_delimiter = ',', value_parser = crate::numbers::whole_u32, allow_negative_numbers = true)]
    sets: Option<Vec<u32>>,
    /// `bench traverse` and `bench accuracy`: target projected errors in
    /// pixels [default: 0.5,1,2,4,8 for traverse; 0.25,0.5,1,2,4,8,16 for
    /// accuracy].
    #[arg(long, value_delimiter = ',', value_parser = crate::numbers::number_f32, allow_negative_numbers = true)]
    targets: Option<Vec<f32>>,
    /// `bench accuracy`: only these views (ground, low-flight, high-flight,
    /// facing-ridge) [default: all four].
    #[arg(long, value_delimiter = ',')]
    views: Option<Vec<String>>,
    /// `bench accuracy`: write the Pareto plot (GPU ms against error) here, as PNG.
    #[arg(long)]
    plot: Option<PathBuf>,
    /// `bench accuracy`: write each view's reference, its frame at the
    /// shading target and their FLIP map into this folder.
    #[arg(long)]
    images: Option<PathBuf>,
    /// `bench accuracy`: shadow texture resolutions of the shadow rows
    /// (texels per node side, 2..=257) [default: 33,65,129].
    #[arg(long, value_delimiter = ',', value_parser = crate::numbers::whole_u32, allow_negative_numbers = true)]
    shadow_resolutions: Option<Vec<u32>>,
    /// `bench accuracy`: march steps of the shadow rows (1..=1024)
    /// [default: 8,24,64].
    #[arg(long, value_delimiter = ',', value_parser = crate::numbers::whole_u32, allow_negative_numbers = true)]
    shadow_steps: Option<Vec<u32>>,
    /// `bench accuracy` and `bench cpu`: resident node slots of the renderers
    /// (at most 2047) [default: what the default GPU budget buys, as `vista
    /// render`, for accuracy; 128 for cpu, in both worlds].
    #[arg(long, value_parser = crate::numbers::whole_u32, allow_negative_numbers = true)]
    slots: Option<u32>,
    /// `bench accuracy`: the LOD rules of the geometry rows, side by side:
    /// patch (culling on and off) and triangle (the per-triangle rule; its
    /// world's per-vertex bounds are computed first) [default: patch].
    #[arg(long, value_delimiter = ',', value_parser = crate::render_cmd::parse_lod_rule)]
    lod_rules: Option<Vec<vista::render::LodRule>>,
    /// `bench accuracy`: popping only, measured along a flight of STEPS
    /// steps of STEP metres from each view (level, along its heading): at
    /// each step the new camera draws the previous camera's LOD, then its
    /// own once settled; the largest screen jump of a pixel, p99 and max,
    /// per rule and target (STEP > 0, STEPS 1..=1000).
    #[arg(long, value_name = "STEP,STEPS", value_parser = parse_fly)]
    fly: Option<vista::bench::accuracy_popping::FlySweep>,
    /// `bench cpu`: the far world's side, metres [default: 292000].
    #[arg(long, value_parser = crate::numbers::number_f64, allow_negative_numbers = true)]
    far_extent: Option<f64>,
    /// `bench cpu`: the far world's post spacing, metres (its error tree is
    /// made, so not as fine as a 10 km world's) [default: 32].
    #[arg(long, value_parser = crate::numbers::number_f64, allow_negative_numbers = true)]
    far_spacing: Option<f64>,
    /// Measured frames per row (after warm-up); the median is reported
    /// [default: 15 for traverse, 7 per stage block for cull, 2 per block (4 rounds) for effects, 3 per block (3 rounds) for shade, 10 per block (3 rounds) for cpu].
    #[arg(long, value_parser = crate::numbers::whole_u32, allow_negative_numbers = true)]
    frames: Option<u32>,
    /// Target size of every kind but traverse [default: 1280x720; 320x180 for cpu].
    #[arg(long, value_parser = crate::render_cmd::parse_size, allow_hyphen_values = true)]
    size: Option<[u32; 2]>,
    /// Target projected error of every kind but traverse, pixels [default: 1].
    #[arg(long, value_parser = crate::numbers::number_f32, allow_negative_numbers = true)]
    target_error: Option<f32>,
    /// `bench traverse`: camera position (x,y,z metres); default: 60 m above
    /// the world's centre at mid height.
    #[arg(long, value_parser = crate::render_cmd::parse_position, allow_hyphen_values = true)]
    camera: Option<[f64; 3]>,
    #[command(flatten)]
    world: WorldArgs,
}

/// What the view benchmarks (cull, effects, shade) take, checked once.
pub struct ViewBench<'a> {
    pub world: &'a WorldArgs,
    pub frames: u32,
    pub size: [u32; 2],
    pub target_error_px: f32,
    pub json: Option<&'a Path>,
}

impl<'a> ViewBench<'a> {
    fn new(args: &'a BenchArgs, default_frames: u32) -> Result<Self> {
        let frames = args.frames.unwrap_or(default_frames);
        let target_error_px = args.target_error.unwrap_or(1.0);
        if frames == 0 || !(target_error_px.is_finite() && target_error_px > 0.0) {
            input_error("--frames must be at least 1 and --target-error a positive number of pixels")?;
        }
        Ok(ViewBench {
            world: &args.world,
            frames,
            size: args.size.unwrap_or([1280, 720]),
            target_error_px,
            json: args.json.as_deref(),
        })
    }
}

/// Writes a benchmark's table as pretty JSON and says so.
pub fn write_json(path: &Path, json: &serde_json::Value) -> Result<()> {
    vista::output::write(path, serde_json::to_string_pretty(json)?.as_bytes())?;
    println!("wrote {}", path.display());
    Ok(())
}

/// Which kinds read each kind-specific option (by its argument id); every
/// other option is read by all kinds.
const USED_BY: [(&str, &[BenchKind]); 13] = {
    use BenchKind::*;
    [
        ("sets", &[Traverse]),
        ("camera", &[Traverse]),
        ("targets", &[Traverse, Accuracy]),
        ("size", &[Cull, Effects, Shade, Accuracy, Cpu]),
        ("target_error", &[Cull, Effects, Shade, Accuracy, Cpu]),
        ("views", &[Accuracy]),
        ("plot", &[Accuracy]),
        ("images", &[Accuracy]),
        ("slots", &[Accuracy, Cpu]),
        ("lod_rules", &[Accuracy]),
        ("fly", &[Accuracy]),
        ("far_extent", &[Cpu]),
        ("far_spacing", &[Cpu]),
    ]
};

/// The options a kind does not read, given anyway: each would be silently
/// ignored, so giving one is an error (each option's help names its kinds).
fn unused_options(args: &BenchArgs) -> Vec<String> {
    let given = [
        args.sets.is_some(),
        args.camera.is_some(),
        args.targets.is_some(),
        args.size.is_some(),
        args.target_error.is_some(),
        args.views.is_some(),
        args.plot.is_some(),
        args.images.is_some(),
        args.slots.is_some(),
        args.lod_rules.is_some(),
        args.fly.is_some(),
        args.far_extent.is_some(),
        args.far_spacing.is_some(),
    ];
    USED_BY
        .iter()
        .zip(given)
        .filter(|((_, kinds), on)| *on && !kinds.contains(&args.kind))
        .map(|((id, _), _)| format!("--{}", id.replace('_', "-")))
        .collect()
}

/// `vista bench KIND --help`: the kind's own description and only the
/// options it reads. `None` for a name that is no kind (clap then says so).
pub fn kind_help(name: &str) -> Option<String> {
    use clap::Args as _;
    let kind = BenchKind::from_str(name, false).ok()?;
    let about = kind.to_possible_value()?.get_help().map(ToString::to_string).unwrap_or_default();
    let mut cmd = BenchArgs::augment_args(clap::Command::new("vista bench").bin_name(format!("vista bench {name}")))
        .about(about)
        .override_usage(format!("vista bench {name} [OPTIONS]"))
        .mut_arg("kind", |a| a.hide(true));
    for (id, kinds) in USED_BY {
        if !kinds.contains(&kind) {
            cmd = cmd.mut_arg(id, |a| a.hide(true));
        }
    }
    Some(cmd.render_long_help().to_string())
}

/// The arguments' own checks, before Vulkan starts.
pub fn check(args: &BenchArgs) -> Result<()> {
    let unused = unused_options(args);
    if !unused.is_empty() {
        let name = args.kind.to_possible_value().map_or(String::new(), |v| v.get_name().to_string());
        input_error(format!(
            "vista bench {name} does not use {}: drop {} (`vista bench {name} --help` lists what it takes)",
            unused.join(", "),
            if unused.len() == 1 { "it" } else { "them" }
        ))?;
    }
    if let Some(path) = &args.json {
        crate::out_path::check_out_file(path, "--json")?;
    }
    Ok(())
}

/// `--fly STEP,STEPS`: metres a step (> 0) and whole steps (1..=1000).
fn parse_fly(s: &str) -> std::result::Result<vista::bench::accuracy_popping::FlySweep, String> {
    let bad = || format!("{s:?}: give STEP,STEPS (metres a step > 0, whole steps 1..=1000), e.g. 2,20");
    let (step, steps) = s.split_once(',').ok_or_else(bad)?;
    let step_m: f64 = step.trim().parse().map_err(|_| bad())?;
    let steps: u32 = steps.trim().parse().map_err(|_| bad())?;
    if !(step_m.is_finite() && step_m > 0.0 && (1..=1000).contains(&steps)) {
        return Err(bad());
    }
    Ok(vista::bench::accuracy_popping::FlySweep { step_m, steps })
}

pub fn input_error(message: impl Into<String>) -> Result<()> {
    Err(anyhow::Error::new(crate::InputError(message.into())))
}

pub fn bench(ctx: &Context, args: BenchArgs) -> Result<()> {
    match args.kind {
        BenchKind::Traverse => traverse(ctx, args),
        BenchKind::Cull => crate::bench_cull_cmd::cull(ctx, &ViewBench::new(&args, 7)?),
        BenchKind::Effects => crate::bench_effects_cmd::effects(ctx, &ViewBench::new(&args, 2)?),
        BenchKind::Shade => crate::bench_shade_cmd::shade(ctx, &ViewBench::new(&args, 3)?),
        BenchKind::Cpu => cpu(ctx, &args),
        BenchKind::Accuracy => {
            let targets = args.targets.clone().unwrap_or(crate::bench_accuracy_cmd::DEFAULT_TARGETS.to_vec());
            let bench = ViewBench::new(&args, 3)?;
            let default = vista::bench::accuracy_shadows::ShadowSweep::default();
            let shadows = vista::bench::accuracy_shadows::ShadowSweep {
                resolutions: args.shadow_resolutions.clone().unwrap_or(default.resolutions),
                steps: args.shadow_steps.clone().unwrap_or(default.steps),
            };
            let a = crate::bench_accuracy_cmd::AccuracyArgs {
                targets: &targets,
                views: args.views.as_deref(),
                plot: args.plot.as_deref(),
                images: args.images.as_deref(),
                slots: args.slots,
                shadows,
                rules: args.lod_rules.clone().unwrap_or(vec![vista::render::LodRule::Patch]),
                fly: args.fly,
            };
            crate::bench_accuracy_cmd::accuracy(ctx, &bench, &a)
        }
    }
}

fn cpu(ctx: &Context, args: &BenchArgs) -> Result<()> {
    let b = ViewBench::new(args, 10)?;
    let a = crate::bench_cpu_cmd::CpuArgs {
        far_extent_m: args.far_extent.unwrap_or(292_000.0),
        far_spacing_m: args.far_spacing.unwrap_or(32.0),
        slots: args.slots.unwrap_or(128),
        frames: b.frames,
        size: args.size.unwrap_or([320, 180]),
        target_error_px: b.target_error_px,
    };
    for (v, name) in [(a.far_extent_m, "--far-extent"), (a.far_spacing_m, "--far-spacing")] {
        if !(v.is_finite() && v > 0.0) {
            input_error(format!("{name} {v}: give a positive number of metres"))?;
        }
    }
    crate::bench_cpu_cmd::cpu(ctx, &args.world, &a, b.json)
}

fn traverse(ctx: &Context, args: BenchArgs) -> Result<()> {
    let frames = args.frames.unwrap_or(15);
    let targets = args.targets.clone().unwrap_or(vec![0.5, 1.0, 2.0, 4.0, 8.0]);
    let sets = args.sets.clone().unwrap_or(vec![64, 256, 512, 1000]);
    let max = vista::terrain::quadtree::MAX_SLOTS;
    if let Some(n) = sets.iter().find(|&&n| n == 0 || n > max) {
        input_error(format!("--sets {n}: a resident set is 1 to {max} nodes (slots are atlas layers)"))?;
    }
    if let Some(t) = targets.iter().find(|t| !(t.is_finite() && **t > 0.0)) {
        input_error(format!("--targets {t}: a target error is a positive number of pixels"))?;
    }
    if frames == 0 {
        input_error("--frames 0: measure at least 1 frame")?;
    }
    let world = args.world.load()?;
    world.require_unplaced("vista bench traverse")?;
    let d = &world.desc;
    let mid = f64::from(d.height_range_m[0] + d.height_range_m[1]) / 2.0;
    let camera = args.camera.unwrap_or([d.extent_m[0] / 2.0, d.extent_m[1] / 2.0, mid + 60.0]);
    let cfg = TraverseBenchConfig {
        resident_sets: sets,
        targets_px: targets,
        warmup_frames: 3,
        frames,
        camera_m: camera,
        viewport_height_px: 1080,
        errors: Some(world.errors(ctx, None)?),
    };
    let rows = bench_traverse(ctx, d, std::sync::Arc::clone(&world.source), &cfg)?;
    println!(
        "bench traverse: {} on {}  camera ({:.0}, {:.0}, {:.0}), 1080 px, 60 deg; median of {} frames after 3 warm-up",
        world.label,
        ctx.info().name,
        camera[0],
        camera[1],
        camera[2],
        cfg.frames
    );
    println!(
        "{:>9} {:>9} {:>9} {:>7} {:>13} {:>13} {:>13}",
        "requested", "resident", "target px", "final", "one-dispatch", "per-level", "one/per-level"
    );
    for r in &rows {
        println!(
            "{:>9} {:>9} {:>9} {:>7} {:>10.4} ms {:>10.4} ms {:>13.3}",
            r.requested,
            r.resident,
            r.target_error_px,
            r.final_nodes,
            r.single_dispatch_ms,
            r.multi_dispatch_ms,
            r.ratio
        );
    }
    if let Some(path) = args.json {
        let json = serde_json::json!({ "device": ctx.info().name, "world": world.label, "camera_m": camera, "frames": cfg.frames, "rows": rows });
        write_json(&path, &json)?;
    }
    Ok(())
}
