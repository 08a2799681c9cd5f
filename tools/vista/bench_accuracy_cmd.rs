//! `vista bench accuracy [WORLD]`: what accuracy costs in time, against the
//! CPU ray-caster: a table, JSON (`--json`) and a Pareto plot (`--plot`).

use crate::bench_cmd::{write_json, ViewBench};
use anyhow::{bail, Result};
use std::path::Path;
use std::time::{Duration, Instant};
use vista::bench::accuracy::CLAY_ALBEDO;
use vista::bench::accuracy_shadows::ShadowSweep;
use vista::bench::{bench_accuracy, cull_views, AccuracyBench, AccuracyBenchConfig};
use vista::gpu::Context;
use vista::reference::{flip_magma, flip_map, RaycastConfig};

/// The full sweep of target errors (pixels).
pub const DEFAULT_TARGETS: [f32; 7] = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0];

/// The names `--views` accepts: the view's name with '-' for spaces.
fn view_key(name: &str) -> String {
    name.replace(' ', "-")
}

/// What `bench accuracy` takes beyond the view benches' arguments.
pub struct AccuracyArgs<'a> {
    pub targets: &'a [f32],
    pub views: Option<&'a [String]>,
    pub plot: Option<&'a Path>,
    pub images: Option<&'a Path>,
    /// None: what the default GPU budget buys (as `vista render`).
    pub slots: Option<u32>,
    pub shadows: ShadowSweep,
    pub rules: Vec<vista::render::LodRule>,
    pub fly: Option<vista::bench::accuracy_popping::FlySweep>,
}

pub fn accuracy(ctx: &Context, args: &ViewBench, a: &AccuracyArgs) -> Result<()> {
    let AccuracyArgs { targets, views, images, slots, .. } = *a;
    check_accuracy_args(a)?;
    let world = args.world.load()?;
    let slots = match slots {
        Some(s) => crate::world_args::check_slots(s, &world.desc).map(|_| s)?,
        None => crate::budget::default_slots(&world, &ctx.info().limits)?,
    };
    world.require_unplaced("vista bench accuracy")?;
    let d = world.desc;
    let mut all = cull_views(&d, &*world.source);
    if let Some(wanted) = views {
        let known: Vec<String> = all.iter().map(|(n, _)| view_key(n)).collect();
        if let Some(bad) = wanted.iter().find(|w| !known.contains(w)) {
            let known = known.join(", ");
            return Err(crate::InputError(format!("--views: no view named {bad:?} (known: {known})")).into());
        }
        all.retain(|(n, _)| wanted.contains(&view_key(n)));
    }
    let shading_target_px = if targets.contains(&args.target_error_px) { args.target_error_px } else { targets[0] };
    let cache = std::env::temp_dir().join(format!("vista-bench-accuracy-{}", std::process::id()));
    let cfg = AccuracyBenchConfig {
        size: args.size,
        fov_y_deg: 60.0,
        targets_px: targets.to_vec(),
        shading_target_px,
        shading: true,
        warmup_frames: 2,
        frames: args.frames,
        settle_timeout: Duration::from_secs(300),
        cache_dir: cache.clone(),
        errors: Some(world.errors(ctx, None)?),
        slots,
        // One ray per pixel: the renderer samples each pixel once too.
        raycast: RaycastConfig { colour_samples: 1, ..RaycastConfig::default() },
        keep_images: images.is_some(),
        shadows: Some(a.shadows.clone()),
        virtual_texture: Some(vista::bench::accuracy_vt::VtSweep::default()),
        rules: a.rules.clone(),
        fly: a.fly,
    };
    let start = Instant::now();
    let result = bench_accuracy(ctx, &d, world.source.clone(), &world.effects, &all, &cfg);
    let _ = std::fs::remove_dir_all(&cache);
    let b = result?;
    print_table(&b, &world.label, ctx, &cfg, start.elapsed().as_secs_f64());
    write_outputs(ctx, args.json, a, &world.label, &cfg, &b)
}

/// Checked before the (long) run: the sweeps' values and the output paths.
fn check_accuracy_args(a: &AccuracyArgs) -> Result<()> {
    let AccuracyArgs { targets, plot, images, .. } = *a;
    let max_side = vista::shaders::consts::SUN_SHADOW_MAX_SIDE;
    if a.shadows.resolutions.is_empty() || a.shadows.resolutions.iter().any(|r| !(2..=max_side).contains(r)) {
        bail!("--shadow-resolutions must be texels per node side, 2..={max_side}");
    }
    if a.shadows.steps.is_empty() || a.shadows.steps.iter().any(|s| !(1..=1024).contains(s)) {
        bail!("--shadow-steps must be whole numbers 1..=1024");
    }
    if targets.is_empty() || targets.iter().any(|t| !(t.is_finite() && *t > 0.0)) {
        bail!("--targets must be positive numbers of pixels");
    }
    if let Some(p) = plot {
        check_plot_path(p)?;
    }
    if let Some(dir) = images {
        if !dir.is_dir() {
            bail!("--images {}: not an existing folder", dir.display());
        }
    }
    Ok(())
}

/// `--json`, `--images` and `--plot`, after the table.
fn write_outputs(
    ctx: &Context,
    json: Option<&Path>,
    a: &AccuracyArgs,
    label: &str,
    cfg: &AccuracyBenchConfig,
    b: &AccuracyBench,
) -> Result<()> {
    if let Some(path) = json {
        let json = serde_json::json!({
            "device": ctx.info().name,
            "world": label,
            "size": cfg.size,
            "fov_y_deg": cfg.fov_y_deg,
            "clay_albedo": CLAY_ALBEDO,
            "frames": cfg.frames,
            "slots": cfg.slots,
            "warmup_frames": cfg.warmup_frames,
            "raycast": format!("{:?}", cfg.raycast),
            "bench": b,
        });
        write_json(path, &json)?;
    }
    if let Some(dir) = a.images {
        write_images(dir, b)?;
    }
    if let Some(path) = a.plot {
        let title = format!("{} on {}, {}x{}", label, ctx.info().name, cfg.size[0], cfg.size[1]);
        crate::accuracy_plot::pareto_plot(b, &title, path)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// Per view: `<view>_reference.png`, `<view>_frame.png` and the FLIP map
/// between them, `<view>_flip.png`.
fn write_images(dir: &Path, b: &AccuracyBench) -> Result<()> {
    for v in &b.images {
        let stem = v.view.replace(' ', "_");
        let flip = flip_magma(&flip_map(&v.reference, &v.frame, v.size), v.size);
        for (suffix, data, colour) in [
            ("reference", &v.reference, image::ExtendedColorType::Rgba8),
            ("frame", &v.frame, image::ExtendedColorType::Rgba8),
            ("flip", &flip, image::ExtendedColorType::Rgb8),
        ] {
            let path = dir.join(format!("{stem}_{suffix}.png"));
            vista::output::write_png(&path, data, v.size, colour)?;
        }
    }
    println!("wrote {} images to {}", 3 * b.images.len(), dir.display());
    Ok(())
}

/// Checked before the (long) run: a PNG path in an existing folder.
fn check_plot_path(p: &Path) -> Result<()> {
    if p.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() != Some("png") {
        bail!("--plot {}: the plot is a PNG; give a path ending in .png", p.display());
    }
    if p.is_dir() {
        bail!("--plot {} is a directory; give a file path ending in .png", p.display());
    }
    let parent = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !parent.is_dir() {
        bail!("--plot {}: the folder {} does not exist", p.display(), parent.display());
    }
    Ok(())
}

fn print_table(b: &AccuracyBench, label: &str, ctx: &Context, cfg: &AccuracyBenchConfig, seconds: f64) {
    let [w, h] = cfg.size;
    let device = &ctx.info().name;
    if !b.popping.is_empty() {
        println!("bench accuracy --fly: {label} on {device}, {w}x{h}, {} slots, clay albedo {CLAY_ALBEDO}", cfg.slots);
        print_popping(b);
        println!("({seconds:.0} s in all)");
        return;
    }
    println!(
        "bench accuracy: {label} on {device}, {w}x{h}, {} slots, clay albedo {CLAY_ALBEDO}; GPU ms = sum of pass medians over {} frames after {} warm-up",
        cfg.slots,
        cfg.frames,
        cfg.warmup_frames
    );
    println!("reference ray-caster (CPU, {} threads): bounds {:.1} s", rayon::current_num_threads(), b.bounds_seconds);
    for r in &b.references {
        println!(
            "  view {:<14} camera {}: {:.1} s, {:.0} samples/ray, {:.0}% terrain",
            format!("\"{}\"", r.view),
            r.camera,
            r.seconds,
            r.samples_per_ray,
            100.0 * r.terrain_fraction
        );
    }
    print_points(b);
    print_legend(cfg);
    if let Some(why) = &b.shading_skipped {
        println!("shading rows skipped: {why}");
    }
    print_shadows(b);
    print_virtual_texture(b);
    println!("({seconds:.0} s in all)");
}

/// `--fly`: a row per view, rule and target.
fn print_popping(b: &AccuracyBench) {
    println!(
        "popping: per step the new camera draws the previous one's LOD, then its own (settled); jump = a pixel's vertical move between them, projected (px); culling off"
    );
    println!(
        "{:<14} {:<9} {:>6} {:>7} {:>6} {:>9} {:>8} {:>8} {:>9} {:>8}",
        "view", "rule", "target", "step m", "steps", "pixels", "p99", "max", "> target", "settled"
    );
    for p in &b.popping {
        println!(
            "{:<14} {:<9} {:>6} {:>7} {:>6} {:>9} {:>8.3} {:>8.3} {:>9} {:>8}",
            p.view,
            p.rule,
            p.target_error_px,
            p.step_m,
            p.step_max_px.len(),
            p.pixels,
            p.p99_px,
            p.max_px,
            p.over_target_pixels,
            format!("{}/{}", p.settled_steps, p.step_max_px.len())
        );
    }
}

/// One row per (view, setting) point, under its header.
fn print_points(b: &AccuracyBench) {
    print_points_header();
    for p in &b.points {
        let e = &p.error;
        let setting = if p.family == "shading" { p.setting.clone() } else { p.family.clone() };
        let extra = match (p.differs_from_culled_px, p.texture_flip_vs_accurate) {
            (Some(n), _) => format!("diff {n}"),
            (_, Some(f)) => format!("tex {f:.4}"),
            _ => String::new(),
        };
        let held = match p.promise_held {
            Some(true) => "yes",
            Some(false) => "NO",
            None => "-",
        };
        let pair = |a: f64, b: f64| format!("{a:.2}/{b:.2}");
        println!(
            "{:<12} {:<32} {:>6} {:>6.2} {:>9.2} {:>10} {:>6.2} {:>13} {:>6} {:>7} {:>5} {:>5} {:>8.1e} {:>7} {:>13} {:>13} {:>13} {:>6.1} {:>6.4} {:>5} {:>8}{}",
            p.view,
            setting,
            p.target_error_px,
            p.bound_px,
            p.gpu_ms,
            p.triangles_drawn,
            p.triangles_per_pixel,
            format!("{:.3}/{:.3}", p.floor.triangles, p.floor.patches),
            p.floor.rule.map_or("-".to_string(), |r| format!("{:.3}{}", r.per_pixel, if r.below == 0 { "*" } else { "" })),
            p.patches_drawn,
            p.nodes_drawn_per_lod.iter().sum::<u32>(),
            p.wanted_finer,
            e.depth_rel_p99,
            e.silhouette_pixels,
            pair(e.geometric_px_max, e.geometric_px_p99),
            pair(e.lod_px_max, e.lod_px_p99),
            pair(e.repr_px_max, e.repr_px_p99),
            e.psnr_db,
            e.flip_mean,
            held,
            extra,
            if p.settled { "" } else { " (not settled)" }
        );
    }
}

fn print_points_header() {
    println!(
        "{:<12} {:<32} {:>6} {:>6} {:>9} {:>10} {:>6} {:>13} {:>6} {:>7} {:>5} {:>5} {:>8} {:>7} {:>13} {:>13} {:>13} {:>6} {:>6} {:>5} {:>8}",
        "view",
        "setting",
        "target",
        "bound",
        "GPU ms",
        "triangles",
        "tri/px",
        "floor tri/ptc",
        "rule",
        "patches",
        "nodes",
        "want+",
        "d p99",
        "silh px",
        "geo max/p99",
        "lod max/p99",
        "repr max/p99",
        "PSNR",
        "FLIP",
        "held",
        "extra"
    );
}

/// What the columns mean.
fn print_legend(cfg: &AccuracyBenchConfig) {
    println!(
        "bound: the largest projected selection error of any drawn patch (px: 99 % of each patch within it, all of it \
         within twice it; above the target when the slot budget could not meet it); tri/px: triangles drawn per screen pixel; \
         floor tri/ptc: the fewest triangles per screen pixel any LOD choice on vista's grids could draw for the \
         visible ground with every visible point within 2 x target, choosing per triangle / per whole patch (lower \
         bounds: nothing hidden, outside the view or for seams counted); rule: triangles per pixel the per-triangle \
         rule (a restricted bintree with saturated errors) is expected to draw for the same visible ground, counted \
         alike (*: not below the samples, the world's finest lattice being too large for the CPU here; -: too large \
         either way); want+: drawn nodes the camera wants finer whose children \
         are not resident; d: relative depth error; silh: pixels terrain in one image only; geo: vertical error to \
         the source surface projected on screen (px), split into lod (drawn surface vs the finest surface vista can \
         draw: what the target bounds) and repr (finest surface vs the source: what no LOD choice removes); PSNR, \
         FLIP: the clay-lit image vs the reference's over the pixels where either has terrain, both at {} sample(s) \
         per pixel; held: the promise where bound <= target (lod p99 <= target, lod max <= 2 x target), - where the \
         budget made no promise; extra: culling off, pixels differing from culling on; shading rows, FLIP of the \
         textured image vs every flavour + blended cliffs",
        cfg.raycast.colour_samples
    );
}

fn print_shadows(b: &AccuracyBench) {
    if let Some(why) = &b.shadows_skipped {
        println!("shadow rows skipped: {why}");
        return;
    }
    println!(
        "{:<12} {:<10} {:>9} {:>10} {:>10} {:>8} {:>9} {:>11} {:>9} {:>9}",
        "view", "shadows", "compared", "mismatch", "frame dark", "FLIP", "resident", "ms/node", "full ms", "resolve"
    );
    for p in &b.shadow_points {
        let setting = match (p.resolution, p.steps) {
            (Some(r), Some(s)) => format!("{r}x{r} {s}"),
            _ => "off".to_string(),
        };
        let ms = |v: Option<f64>, digits: usize| v.map_or("-".to_string(), |v| format!("{v:.digits$}"));
        println!(
            "{:<12} {:<10} {:>9} {:>9.2}% {:>9.2}% {:>8.4} {:>9} {:>11} {:>9} {:>9.2}{}",
            p.view,
            setting,
            p.compared_pixels,
            100.0 * p.state_mismatch,
            100.0 * p.mismatch_frame_dark,
            p.flip_mean,
            p.resident_nodes,
            ms(p.ms_per_node, 3),
            ms(p.full_update_ms, 1),
            p.resolve_ms,
            if p.settled { "" } else { " (not settled)" }
        );
    }
    println!(
        "shadow rows: against a reference casting an exact shadow ray from every lit hit, at the shading target; \
         shadows: texels per node side and march steps; mismatch: pixels facing the sun (n.l >= 0.15 in both) lit in \
         one image and shadowed in the other (frame dark: of them, shadowed in the frame only); FLIP: the clay-lit image vs that reference; ms/node: sun_shadows GPU ms \
         per node re-marched while the sun moves; full: for every resident node (a static sun costs nothing once \
         settled: the pass is idle); resolve: lighting_resolve's GPU ms"
    );
}

fn print_virtual_texture(b: &AccuracyBench) {
    if let Some(why) = &b.vt_skipped {
        println!("virtual-texture rows skipped: {why}");
        return;
    }
    println!(
        "{:<12} {:<14} {:>7} {:>7} {:>9} {:>7} {:>8} {:>8} {:>8} {:>9} {:>9} {:>9}",
        "view",
        "virtual tex.",
        "frames",
        "pages",
        "resident",
        "hits",
        "FLIP",
        "p99",
        "VT ms",
        "shade ms",
        "frame ms",
        "MiB"
    );
    for p in &b.vt_points {
        let setting = match (p.cache_mb, p.pages_per_frame) {
            (Some(c), Some(n)) => format!("{c} MiB {n}/fr"),
            _ => "off (splat)".to_string(),
        };
        println!(
            "{:<12} {:<14} {:>7} {:>7} {:>4}/{:<4} {:>6.1}% {:>8.4} {:>8.4} {:>8.2} {:>9.2} {:>9.2} {:>9.1}{}",
            p.view,
            setting,
            p.frames_to_settle,
            p.pages_rendered,
            p.pages_resident,
            p.cache_tiles,
            100.0 * p.hit_rate,
            p.flip_mean,
            p.flip_p99,
            p.vt_ms,
            p.shade_ms,
            p.frame_ms,
            p.memory_bytes as f64 / f64::from(1u32 << 20),
            if p.settled { "" } else { " (not settled)" }
        );
    }
    println!(
        "virtual-texture rows: at the shading target, against direct splat shading (the effect off); virtual tex.: \
         cache size and pages rendered per frame at most; frames: from the renderer's first until streaming and \
         pages settled (every page a whole feedback jitter cycle asked for resident); pages: rendered meanwhile; \
         resident: pages held / cache tiles; hits: requested pages resident in the newest read-back frame; FLIP, \
         p99: the textured image vs direct splat shading's over terrain pixels; VT ms: vt_update + vt_pages + \
         vt_feedback once settled; shade ms: every gbuffer_tiles draw; MiB: the virtual texture's GPU memory"
    );
}
