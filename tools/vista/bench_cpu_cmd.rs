//! `vista bench cpu [WORLD]`: the renderer's CPU milliseconds per frame on
//! the world and on a far larger one made by the same generator, through
//! the same view and slots; their ratio says whether per-frame CPU work
//! follows what is near or the world's size.

use crate::bench_cmd::write_json;
use crate::world_args::WorldArgs;
use anyhow::Result;
use std::time::Duration;
use vista::bench::{bench_cpu, CpuBenchConfig, CpuWorld};
use vista::gpu::Context;
use vista::render::{overview_camera, View, DEFAULT_NEAR_M};
use vista::world::WorldDesc;

/// What `bench cpu` takes beyond the world.
pub struct CpuArgs {
    pub far_extent_m: f64,
    pub far_spacing_m: f64,
    pub slots: u32,
    pub frames: u32,
    pub size: [u32; 2],
    pub target_error_px: f32,
}

/// The far world: the given scene's procedural world, `far_extent_m` wide
/// at `far_spacing_m` (its error tree must be made, so its posts are
/// coarser than a 0.5 m world's could be), with the fewest LODs from those
/// its extent suggests on whose roots the slots leave room to refine.
fn far_args(world: &WorldArgs, a: &CpuArgs) -> WorldArgs {
    let extent = [a.far_extent_m; 2];
    let fits = |lods: u32| {
        let d = WorldDesc { extent_m: extent, spacing_m: a.far_spacing_m, lod_count: lods, ..WorldDesc::default() };
        let [x, y] = d.grid(d.root_lod());
        4 * u64::from(x) * u64::from(y) <= u64::from(a.slots)
    };
    let first = WorldDesc::lods_for(extent, a.far_spacing_m);
    let lods = (first..=vista::world::MAX_LOD_COUNT).find(|&l| fits(l)).unwrap_or(first);
    WorldArgs { extent: Some(extent), spacing: Some(a.far_spacing_m), lods: Some(lods), derived: true, ..world.clone() }
}

pub fn cpu(ctx: &Context, world_args: &WorldArgs, a: &CpuArgs, json: Option<&std::path::Path>) -> Result<()> {
    // Resolved quietly here: `load` below says what the options replace.
    let quiet = WorldArgs { derived: true, ..world_args.clone() };
    if !quiet.resolve()?.is_procedural() {
        crate::bench_cmd::input_error(
            "vista bench cpu makes its far world with the procedural generator: give a procedural world (no --heightmap, a scene with source = \"procedural\")",
        )?;
    }
    let far = far_args(world_args, a);
    println!(
        "far world: the same generator, scene and effects at {} m, {} m spacing, {} LODs",
        crate::world_args::show_m(a.far_extent_m),
        crate::world_args::show_m(a.far_spacing_m),
        far.lods.unwrap_or(0)
    );
    let worlds = [world_args.load()?, far.load()?];
    for w in &worlds {
        w.require_unplaced("vista bench cpu")?;
        crate::world_args::check_slots(a.slots, &w.desc)?;
    }
    let near = &worlds[0];
    let view = View {
        camera: overview_camera(&near.desc, &*near.source),
        fov_y_deg: 60.0,
        size: a.size,
        target_error_px: a.target_error_px,
        near_m: DEFAULT_NEAR_M,
    };
    let mut inputs = Vec::new();
    for w in &worlds {
        inputs.push(CpuWorld {
            label: w.label.clone(),
            desc: w.desc,
            source: w.source.clone(),
            holes: w.holes.clone(),
            errors: Some(w.errors(ctx, None)?),
        });
    }
    let cache = std::env::temp_dir().join(format!("vista-bench-cpu-{}", std::process::id()));
    let cfg = CpuBenchConfig {
        view,
        slots: a.slots,
        effects: near.effects.clone(),
        decals: near.decals.clone(),
        assets: near.assets.clone(),
        warmup_frames: 3,
        frames: a.frames,
        rounds: 3,
        settle_timeout: Duration::from_secs(600),
        cache_dir: cache.clone(),
    };
    let rows = bench_cpu(ctx, &inputs, &cfg);
    let _ = std::fs::remove_dir_all(&cache);
    let rows = rows?;
    print_rows(ctx, a, &cfg, &rows);
    let c = cfg.view.camera;
    if let Some(path) = json {
        let json = serde_json::json!({
            "device": ctx.info().name, "slots": a.slots, "size": a.size, "target_error_px": a.target_error_px,
            "camera_m": c.position_m, "frames_per_world": cfg.rounds * a.frames, "rows": rows,
        });
        write_json(path, &json)?;
    }
    Ok(())
}

fn print_rows(ctx: &Context, a: &CpuArgs, cfg: &CpuBenchConfig, rows: &[vista::bench::CpuBenchRow]) {
    let c = cfg.view.camera;
    println!(
        "bench cpu: {} slots, camera ({:.0}, {:.0}, {:.0}) yaw {:.0} pitch {:.0}, {}x{}, target {} px, on {}; medians of {} frames per world ({} rounds of {} after {} warm-up), round-robin",
        a.slots,
        c.position_m[0],
        c.position_m[1],
        c.position_m[2],
        c.yaw_deg,
        c.pitch_deg,
        a.size[0],
        a.size[1],
        a.target_error_px,
        ctx.info().name,
        cfg.rounds * a.frames,
        cfg.rounds,
        a.frames,
        cfg.warmup_frames
    );
    println!(
        "{:>10} {:>9} {:>5} {:>7} {:>9} {:>8} {:>8} {:>9} {:>7}  world",
        "extent km", "spacing", "lods", "roots", "resident", "cpu ms", "p90 ms", "query ms", "ratio"
    );
    for r in rows {
        println!(
            "{:>10.1} {:>9} {:>5} {:>7} {:>9} {:>8.3} {:>8.3} {:>9.1} {:>7.2}  {}{}",
            r.extent_m[0].max(r.extent_m[1]) / 1000.0,
            crate::world_args::show_m(r.spacing_m),
            r.lod_count,
            r.roots,
            r.resident,
            r.cpu_ms,
            r.cpu_p90_ms,
            r.query_ms,
            r.ratio,
            r.world,
            if r.settled { "" } else { " (streaming NOT settled)" }
        );
    }
    println!(
        "cpu ms: the renderer's recording of a frame (streaming, plans, commands; no GPU wait); query ms: reading earlier frames' timestamps, apart (lavapipe drains the device there); ratio: over the first row"
    );
}
