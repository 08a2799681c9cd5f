//! `vista bench shade [WORLD]`: tiled shading against one pipeline doing
//! every flavour, on a view with cliffs and one without; classification's
//! share of shading time; tiles per variant; stochastic vs blended cliffs.

use crate::bench_cmd::{write_json, ViewBench};
use anyhow::Result;
use std::time::Duration;
use vista::bench::{bench_shade, shade_views, ShadeBench, ShadeBenchConfig};
use vista::gpu::Context;
use vista::render::Effect;
use vista::scene::shading::Shading;

/// The floors: classification at most this share of shading time;
/// tiled shading at most this share of the every-flavour shader's on the
/// view with cliffs.
const CLASSIFY_FLOOR: f64 = 0.1;
const TILED_FLOOR: f64 = 0.7;

pub fn shade(ctx: &Context, args: &ViewBench) -> Result<()> {
    let (frames, size, target_error_px) = (args.frames, args.size, args.target_error_px);
    let world = args.world.load()?;
    world.require_unplaced("vista bench shade")?;
    let d = world.desc;
    // The scene's shading parameters with every flavour allowed.
    let fx = world.effects.clone().with(Effect::Splat, true).with(Effect::Cliffs, true);
    let fov_y_deg = 60.0;
    let views = shade_views(&d, &*world.source, &fx.shade.allowing(fx.materials, true, true), fov_y_deg);
    let cache = std::env::temp_dir().join(format!("vista-bench-shade-{}", std::process::id()));
    let cfg = ShadeBenchConfig {
        fov_y_deg,
        size,
        target_error_px,
        warmup_frames: 2,
        frames,
        rounds: 3,
        settle_timeout: Duration::from_secs(300),
        cache_dir: cache.clone(),
        errors: Some(world.errors(ctx, None)?),
    };
    let result = bench_shade(ctx, &d, world.source.clone(), &world.holes, &fx, &views, &cfg);
    let _ = std::fs::remove_dir_all(&cache);
    let b = result?;
    println!(
        "bench shade: {} on {}, {}x{}, target {} px; medians of {} frames per renderer ({} rounds of {} after 2 warm-up), round-robin",
        world.label,
        ctx.info().name,
        size[0],
        size[1],
        target_error_px,
        cfg.rounds * frames,
        cfg.rounds,
        frames
    );
    print_views_and_rows(&b);
    print_tiles_and_stochastic_error(&b);
    floors(&b.rows);
    if let Some(path) = args.json {
        let json = serde_json::json!({
            "device": ctx.info().name, "world": world.label, "size": size, "target_error_px": target_error_px,
            "frames_per_renderer": cfg.rounds * frames, "views": b.views, "rows": b.rows,
            "stochastic_error": b.stochastic_error,
        });
        write_json(path, &json)?;
    }
    Ok(())
}

/// The views, then one row per (view, shading, cliffs) renderer.
fn print_views_and_rows(b: &ShadeBench) {
    for v in &b.views {
        println!(
            "view {:<14} camera {} (x,y,z,yaw,pitch); CPU estimate: {:.0}% terrain, {:.0}% of it cliff",
            format!("\"{}\":", v.name),
            v.camera,
            100.0 * v.terrain_fraction,
            100.0 * v.cliff_fraction
        );
    }
    println!(
        "{:<12} {:<27} {:<10} {:>11} {:>9} {:>10} {:>9} {:>9} {:>9}",
        "view", "shading", "cliffs", "classify ms", "draws ms", "shading ms", "classify", "/ every", "/ branch"
    );
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    for r in &b.rows {
        println!(
            "{:<12} {:<27} {:<10} {:>11.3} {:>9.3} {:>10.3} {:>9} {:>9.3} {:>9.3}",
            r.view,
            r.shading.name(),
            if r.stochastic_cliffs { "stochastic" } else { "blended" },
            r.classify_ms,
            r.draws_ms,
            r.shading_ms,
            opt(r.classify_fraction),
            r.vs_every_flavour,
            r.vs_branching
        );
    }
    println!("shading ms = classify + draws (tiled), draws only (one shader: it needs no classification); classify = its share of shading");
}

/// Tiled shading's tiles per variant, and what stochastic cliffs cost in FLIP.
fn print_tiles_and_stochastic_error(b: &ShadeBench) {
    println!("tiles per variant (tiled, stochastic cliffs), with each draw's median ms:");
    for r in b.rows.iter().filter(|r| r.shading == Shading::Tiled && r.stochastic_cliffs) {
        let v: Vec<String> = r
            .variants
            .iter()
            .filter(|v| v.tiles > 0)
            .map(|v| format!("{} {} ({:.3})", v.variant, v.tiles, v.median_ms))
            .collect();
        println!("  {:<12} {}", r.view, if v.is_empty() { "no terrain tiles".into() } else { v.join(", ") });
    }
    println!("stochastic vs fully blended cliffs, tiled (FLIP mean / p99):");
    for e in &b.stochastic_error {
        println!(
            "  {:<12} whole image {:.4} / {:.4}; cliff pixels ({}) {:.4} / {:.4}",
            e.view,
            e.whole_image.mean,
            e.whole_image.p99,
            e.cliff_pixels.pixels,
            e.cliff_pixels.mean,
            e.cliff_pixels.p99
        );
    }
}

/// Says whether the measured figures meet the floors (a benchmark
/// reports; it does not fail).
fn floors(rows: &[vista::bench::ShadeRow]) {
    let verdict = |ok: bool| if ok { "met" } else { "NOT met" };
    for r in rows.iter().filter(|r| r.shading == Shading::Tiled && r.stochastic_cliffs) {
        let f = r.classify_fraction.unwrap_or(f64::NAN);
        println!(
            "floor: classification <= {CLASSIFY_FLOOR} of shading on view {}: {f:.3}, {}",
            r.view,
            verdict(f <= CLASSIFY_FLOOR)
        );
        if r.view != "no cliffs" {
            println!(
                "floor: tiled <= {TILED_FLOOR} x one shader (every flavour) on view {}: {:.3}, {}",
                r.view,
                r.vs_every_flavour,
                verdict(r.vs_every_flavour <= TILED_FLOOR)
            );
        }
    }
}
