//! `vista bench cull [WORLD]`: the patch-culling table of one world.

use crate::bench_cmd::{write_json, ViewBench};
use anyhow::Result;
use std::time::Duration;
use vista::bench::{bench_cull, cull_views, CullBenchConfig, CullBenchRow};
use vista::gpu::Context;
use vista::render::{RendererOptions, TerrainRenderer};
use vista::terrain::TerrainOptions;

pub fn cull(ctx: &Context, b: &ViewBench) -> Result<()> {
    let (frames, size, target_error_px) = (b.frames, b.size, b.target_error_px);
    let world = b.world.load()?;
    world.require_unplaced("vista bench cull")?;
    let d = world.desc;
    let terrain = TerrainOptions { errors: Some(world.errors(ctx, None)?), ..TerrainOptions::default() };
    let options = RendererOptions { effects: world.effects.clone(), terrain, ..RendererOptions::default() };
    let mut renderer = TerrainRenderer::new(ctx, &d, world.source.clone(), world.holes.clone(), &options)?;
    let views = cull_views(&d, &*world.source);
    let cfg =
        CullBenchConfig { size, target_error_px, warmup_frames: 2, frames, settle_timeout: Duration::from_secs(300) };
    let rows = bench_cull(ctx, &mut renderer, &views, &cfg)?;
    println!(
        "bench cull: {} on {}, {}x{}, 60 deg, target {} px; median of {} frames per stage block after 2 warm-up",
        world.label,
        ctx.info().name,
        size[0],
        size[1],
        target_error_px,
        frames
    );
    print_stages(&rows);
    print_occlusion(&rows);
    print_pass_medians(&rows);
    if let Some(path) = b.json {
        let doc = serde_json::json!({
            "device": ctx.info().name, "world": world.label, "size": size,
            "target_error_px": target_error_px, "frames": frames, "rows": rows,
        });
        write_json(path, &doc)?;
    }
    Ok(())
}

/// Patches left after each culling stage, and what the cone test costs and saves.
fn print_stages(rows: &[CullBenchRow]) {
    println!(
        "{:<13} {:>6} {:>7} {:>8} {:>8} {:>8} {:>8} {:>10} {:>9} {:>9} {:>11} {:>11} {:>9}",
        "view",
        "nodes",
        "in",
        "frustum",
        "cone",
        "hole",
        "drawn",
        "tri/full",
        "drawn/sel",
        "(tr+cu)/g",
        "cone cost",
        "cone saves",
        "g off/on"
    );
    for r in rows {
        let c = &r.all.counters;
        println!(
            "{:<13} {:>6} {:>7} {:>8} {:>8} {:>8} {:>8} {:>10.2e} {:>9.3} {:>9.4} {:>8.3} ms {:>8.3} ms {:>9.2}",
            r.view,
            r.nodes,
            c.patches_in,
            c.after_frustum,
            c.after_cone,
            c.after_hole,
            c.drawn,
            r.triangles_vs_full_res,
            r.drawn_vs_selected,
            r.traverse_cull_vs_geometry,
            r.cone_cost_ms,
            r.cone_saves_ms,
            r.geometry_off_vs_on
        );
    }
}

/// Two-phase occlusion culling's figures, for the views that measured it.
fn print_occlusion(rows: &[CullBenchRow]) {
    if rows.iter().any(|r| r.no_occlusion.is_some()) {
        println!(
            "{:<13} {:>8} {:>8} {:>8} {:>12} {:>14} {:>12} {:>10}",
            "occlusion", "phase 1", "tested", "phase 2", "culled", "cost (hiz+p2)", "geom saves", "net"
        );
        for r in rows {
            let (Some(cost), Some(saves)) = (r.occlusion_cost_ms, r.occlusion_saves_ms) else { continue };
            let c = &r.all.counters;
            println!(
                "{:<13} {:>8} {:>8} {:>8} {:>12} {:>11.3} ms {:>9.3} ms {:>7.3} ms",
                r.view,
                c.drawn_phase1,
                c.occlusion_tested,
                c.drawn_phase2,
                c.occlusion_tested - c.drawn_phase2,
                cost,
                saves,
                saves - cost
            );
        }
    }
}

fn print_pass_medians(rows: &[CullBenchRow]) {
    println!("per-pass medians (ms), all stages / no cone / culling off:");
    for r in rows {
        let t =
            |x: &vista::bench::cull::CullTiming| format!("{:.3}+{:.3}+{:.2}", x.traverse_ms, x.cull_ms, x.geometry_ms);
        println!("  {:<13} traverse+cull+geometry  {}  /  {}  /  {}", r.view, t(&r.all), t(&r.no_cone), t(&r.none));
    }
}
