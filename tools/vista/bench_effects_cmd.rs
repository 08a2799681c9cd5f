//! `vista bench effects [WORLD]`: GPU frame time and GPU memory of the
//! minimal scene, the full scene and the full scene without each effect.

use crate::bench_cmd::{write_json, ViewBench};
use anyhow::Result;
use std::time::Duration;
use vista::bench::{bench_effects, EffectsBenchConfig};
use vista::gpu::Context;
use vista::render::{overview_camera, Effect, View, DEFAULT_NEAR_M};

pub fn effects(ctx: &Context, b: &ViewBench) -> Result<()> {
    let (frames, size, target_error_px) = (b.frames, b.size, b.target_error_px);
    let world = b.world.load()?;
    world.require_unplaced("vista bench effects")?;
    let d = world.desc;
    // The full scene: the scene's effects and parameters, every effect asked for.
    let mut full = world.effects.clone();
    for e in Effect::ALL {
        full.set(e, true);
    }
    let view = View {
        camera: overview_camera(&d, &*world.source),
        fov_y_deg: 60.0,
        size,
        target_error_px,
        near_m: DEFAULT_NEAR_M,
    };
    let cache = std::env::temp_dir().join(format!("vista-bench-effects-{}", std::process::id()));
    let cfg = EffectsBenchConfig {
        view,
        warmup_frames: 2,
        frames,
        rounds: 4,
        settle_timeout: Duration::from_secs(300),
        cache_dir: cache.clone(),
        errors: Some(world.errors(ctx, None)?),
        decals: world.decals.clone(),
        assets: world.assets.clone(),
    };
    let rows = bench_effects(ctx, &d, world.source.clone(), &world.holes, &full, &cfg);
    let _ = std::fs::remove_dir_all(&cache);
    let rows = rows?;
    println!(
        "bench effects: {} on {}, {}x{}, default view, target {} px; medians of {} frames per variant ({} rounds of {} after 2 warm-up), round-robin",
        world.label,
        ctx.info().name,
        size[0],
        size[1],
        target_error_px,
        cfg.rounds * frames,
        cfg.rounds,
        frames
    );
    println!(
        "{:<22} {:>9} {:>10} {:>11} {:>10} {:>11} {:>9}  effects on",
        "variant", "pipelines", "triangles", "frame ms", "cost ms", "GPU MiB", "cost MiB"
    );
    let mib = |b: f64| b / (1024.0 * 1024.0);
    for r in &rows {
        let on: Vec<&str> = r.effects_on.iter().map(|e| e.name()).collect();
        println!(
            "{:<22} {:>9} {:>10} {:>11.3} {:>10.3} {:>11.2} {:>9.2}  {}",
            r.variant,
            r.pipelines,
            r.triangles,
            r.frame_ms,
            r.cost_ms,
            mib(r.gpu_memory_bytes as f64),
            mib(r.cost_bytes as f64),
            on.join(", ")
        );
    }
    let off: Vec<String> =
        Effect::ALL.iter().filter(|e| !rows[1].effects_on.contains(e)).map(|e| e.name().to_string()).collect();
    if !off.is_empty() {
        println!("not measured (off in the full scene: not implemented, or no data in this world): {}", off.join(", "));
    }
    println!("cost = full minus the row (what the missing effect costs); minimal = geometry and lighting only");
    if let Some(path) = b.json {
        let json = serde_json::json!({
            "device": ctx.info().name, "world": world.label, "size": size, "target_error_px": target_error_px,
            "frames_per_variant": cfg.rounds * frames, "rows": rows, "not_measured": off,
        });
        write_json(path, &json)?;
    }
    Ok(())
}
