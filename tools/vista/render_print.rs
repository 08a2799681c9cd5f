//! What `vista render` prints: the device, world, stream and queue lines,
//! the counters, the virtual texture's pages along a fly-through, the
//! per-pass timing table, the output and the async overlap.

use vista::effects::virtual_texture::state::VtCounters;
use vista::frame::FrameTimings;
use vista::gpu::QueueMode;
use vista::passes::cull_patches::CullStages;
use vista::render::stats::RenderStats;
use vista::render::{Effect, TerrainRenderer};
use vista::targets::Output;

pub fn print_fly(m: f64, frames: u32, pages: &[VtCounters], budget: Option<u32>) {
    println!("fly-through: {frames} frames, {m} m a frame ({:.0} m)", m * f64::from(frames));
    let (Some(first), Some(last)) = (pages.first(), pages.last()) else { return };
    let n = pages.len() as f64;
    let mean = |f: &dyn Fn(&VtCounters) -> f64| pages.iter().map(f).sum::<f64>() / n;
    let max = |f: &dyn Fn(&VtCounters) -> u32| pages.iter().map(f).max().unwrap_or(0);
    let lowest = pages.iter().map(VtCounters::hit_rate).fold(1.0, f64::min);
    println!(
        "  virtual texture per frame: {:.1} pages sampled (read back; max {}), {:.1} rendered (max {}, budget {}), \
         {:.1} evicted, {:.1} waiting (max {}); hit rate {:.1} % mean, {:.1} % lowest; {} rendered in all",
        mean(&|c| f64::from(c.requested)),
        max(&|c| c.requested),
        mean(&|c| f64::from(c.rendered)),
        max(&|c| c.rendered),
        budget.map_or("-".to_string(), |b| b.to_string()),
        mean(&|c| f64::from(c.evicted)),
        mean(&|c| f64::from(c.waiting)),
        max(&|c| c.waiting),
        100.0 * mean(&VtCounters::hit_rate),
        100.0 * lowest,
        last.rendered_total - first.rendered_total + u64::from(first.rendered)
    );
}

/// The frame's bound: infinite where a root whose errors are pending is
/// drawn (roots made on demand, before a view refines into it).
pub fn bound_words(px: f32) -> String {
    match px.is_finite() {
        true => format!("{px:.2} px"),
        false => "unknown (a root whose error tree is not made yet is drawn)".to_string(),
    }
}

/// A bound of the per-triangle rule: unknown where a vertex or cell over a
/// hole is drawn (a hole under a vertex is an infinite error, which the
/// GPU counts as 3e38 px; samples past the world's edge are holes too).
fn triangle_bound_words(px: f32) -> String {
    match px < 1e37 {
        true => format!("{px:.2} px"),
        false => "unknown (drawn over a hole or the world's edge, which the rule does not bound)".to_string(),
    }
}

/// The per-triangle rule's lines (instead of the patches' and selection's).
fn print_triangles(s: &RenderStats, t: &vista::passes::emit_triangles::TriangleListHeader) {
    println!(
        "triangles: {} drawn by the per-triangle rule ({} emitted, {} past the list); not emitted: {} subtrees \
         outside the frustum, {} inside a patch of holes only, {} triangles facing away, {} outside the frustum; {} \
         splits forced by a finer neighbour's corner",
        t.drawn(),
        t.triangles,
        t.overflow,
        t.culled,
        t.holes,
        t.facing_away,
        t.outside,
        t.forced
    );
    println!(
        "lod:     error bound {} (target {} px): unsplit vertices {}, grid cells (the node's own error) {}; {} \
         vertices the rule splits drawn unsplit (a coarser node across lacks them)",
        triangle_bound_words(s.bound_px),
        s.target_px,
        triangle_bound_words(f32::from_bits(t.bound_bits)),
        triangle_bound_words(f32::from_bits(t.grid_bound_bits)),
        t.clamped
    );
    if let (true, Some(held)) = (t.overflow > 0, s.triangle_capacity) {
        println!(
            "note:    {} triangles past the list, which held {held}: the lists grow to hold them a few frames \
             later (from the telemetry's counts)",
            t.overflow
        );
    }
    if t.unrefined > 0 {
        println!(
            "note:    {} LOD-0 cell halves drawn whole: the fine list (emit_fine's) was full; their node's error \
             is in the bound",
            t.unrefined
        );
    }
}

pub fn print_stats(s: &RenderStats, stages: CullStages, occlusion: bool) {
    if let Some(t) = &s.triangles {
        print_triangles(s, t);
        print_nodes(s);
        return;
    }
    let p = &s.patches;
    let stage = |on: bool, name: &str, n: u32| if on { format!("{n} after {name}") } else { format!("{name} off") };
    println!(
        "patches: {} in, {}, {}, {}, {} drawn, {} of them with holes ({} triangles submitted)",
        p.patches_in,
        stage(stages.frustum, "frustum", p.after_frustum),
        stage(stages.cone, "cone", p.after_cone),
        stage(stages.hole, "hole", p.after_hole),
        p.drawn,
        p.drawn_with_holes,
        s.triangles_drawn
    );
    if occlusion {
        println!(
            "occlusion: {} drawn in phase 1 (visible last frame); {} tested against the depth pyramid, {} of them \
             drawn in phase 2, {} culled",
            p.drawn_phase1,
            p.occlusion_tested,
            p.drawn_phase2,
            p.occlusion_tested - p.drawn_phase2
        );
    }
    let sel = &s.select;
    println!(
        "lod:     error bound {} (target {} px); {} listed patches drawn from an ancestor, {} LOD-0 patches \
         refined below the samples ({} refused by the per-frame budget), {} seam conflicts, {} edges clamped",
        bound_words(s.bound_px),
        s.target_px,
        sel.coarsened,
        sel.refined - sel.refine_capped,
        sel.refine_capped,
        sel.conflicts,
        p.seam_overflow
    );
    print_nodes(s);
}

/// The nodes drawn, and each effect's lines.
fn print_nodes(s: &RenderStats) {
    let per_lod: Vec<String> = s
        .nodes_per_lod
        .iter()
        .zip(&s.wanted_finer_per_lod)
        .enumerate()
        .map(|(l, (n, w))| if *w > 0 { format!("LOD{l} {n} ({w} wanted finer)") } else { format!("LOD{l} {n}") })
        .collect();
    println!(
        "nodes:   {} drawn: {}; overflow {}, missing roots {}",
        s.node_count,
        per_lod.join(", "),
        s.overflow,
        s.missing_roots
    );
    println!("         ('wanted finer': the camera asks for more detail there but the children are not resident yet)");
    // Each effect's lines, as its folder words them.
    for line in &s.effect_lines {
        println!("{line}");
    }
    if let Some([one, two, three]) = s.plane_tiles {
        println!(
            "control map: tri-planar background tiles sampling 1 plane {one}, 2 planes {two}, 3 planes {three} \
             (the tightened blend)"
        );
    }
}

/// What the error tree did while streaming (roots made on demand).
pub fn print_error_tree(terrain: &vista::terrain::Terrain) {
    let tree = terrain.errors();
    if !tree.roots_on_demand() {
        return;
    }
    let c = tree.counts();
    let roots = terrain.world.roots().len();
    println!(
        "error tree: {} of {roots} roots' tiles computed in this run ({:.1} s of thread time, before the first \
         frame and while streaming), {} tile reads from the cache folder; {} roots no view refined into were never \
         made (their errors stay unknown)",
        c.computed,
        c.compute_seconds,
        c.read,
        terrain.pending_roots()
    );
}

pub fn print_timings(timed: &[FrameTimings]) {
    if timed.is_empty() {
        println!("no pass timings (timestamps unsupported or no frame finished)");
        return;
    }
    let summary = vista::frame::profiler::summarize(timed);
    let counted = summary.iter().any(|s| s.counters.is_some());
    print!("{:<44} {:<9} {:>10} {:>10} {:>10} {:>8}", "pass", "queue", "median ms", "min ms", "max ms", "frames");
    if counted {
        print!(" {:>12} {:>12} {:>12} {:>12}", "triangles in", "vertices", "clipped out", "fragments");
    }
    println!();
    let mut total = 0.0;
    for s in summary {
        total += s.median_ms;
        print!(
            "{:<44} {:<9} {:>10.4} {:>10.4} {:>10.4} {:>8}",
            vista::frame::pass_label(s.name, s.late),
            format!("{:?}", s.queue).to_lowercase(),
            s.median_ms,
            s.min_ms,
            s.max_ms,
            s.samples
        );
        if let Some(c) = s.counters.filter(|c| c.input_primitives + c.fragment_invocations > 0) {
            let (a, b, d, e) = (c.input_primitives, c.vertex_invocations, c.clipped_primitives, c.fragment_invocations);
            print!(" {a:>12} {b:>12} {d:>12} {e:>12}");
        }
        println!();
    }
    println!("{:<44} {:<9} {:>10.4}", "sum of medians", "", total);
    let median = |f: fn(&FrameTimings) -> f64| {
        let mut v: Vec<f64> = timed.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "cpu: {:.3} ms a frame recording (median of {}: streaming, plans and command recording, no GPU wait); \
         {:.3} ms more reading earlier frames' timestamps (the driver's: lavapipe drains the device there)",
        median(|t| t.cpu_ms),
        timed.len(),
        median(|t| t.query_ms)
    );
}

/// The output in words: its target(s), and what lit it.
pub fn describe_output(output: &Output, renderer: &TerrainRenderer) -> String {
    let lit = if renderer.effect_on(Effect::Lighting) { "sun and sky" } else { "unlit albedo" };
    match output {
        Output::Lit { format } => format!("lit ({lit}, tonemapped for display into {format:?})"),
        Output::Hdr { format, sky } => {
            let sky = if *sky && renderer.effect_on(Effect::Atmosphere) {
                "the atmosphere's sky in the background"
            } else {
                "the background kept"
            };
            format!("hdr ({lit}, linear radiance into {format:?}, no tonemap; {sky})")
        }
        Output::Gbuffer(layout) => {
            let images: Vec<String> =
                layout.attachments.iter().map(|a| format!("{} {:?} {:?}", a.name, a.format, a.channels)).collect();
            format!("gbuffer (no lighting: the engine lights; {:?} normal; {})", layout.normal, images.join(", "))
        }
    }
}

/// How long each frame's compute ran beside the previous frame's graphics
/// (async compute only; medians over the timed frames' consecutive pairs).
pub fn describe_overlap(mode: QueueMode, timed: &[FrameTimings]) -> String {
    if mode != QueueMode::AsyncCompute {
        return format!(
            "not measured: queue mode {} runs frame N+1's compute after frame N's graphics on one queue",
            mode.name()
        );
    }
    let geometry = vista::passes::terrain_geometry::TerrainGeometry::NAME;
    let mut pairs: Vec<(f64, f64)> =
        timed.windows(2).filter_map(|w| vista::frame::profiler::overlap_ms(&w[0], &w[1], geometry)).collect();
    if pairs.is_empty() {
        return "not measured: no two consecutive frames' timings came back".into();
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let mut all: Vec<f64> = pairs.iter().map(|p| p.0).collect();
    let mut geo: Vec<f64> = pairs.drain(..).map(|p| p.1).collect();
    format!(
        "{:.3} ms of frame N+1's compute ran beside frame N's graphics, {:.3} ms beside its {geometry} \
         (medians of {} frame pairs)",
        median(&mut all),
        median(&mut geo),
        all.len()
    )
}

/// The `device:` and `world:` lines.
pub fn print_device_and_world(
    ctx: &vista::gpu::Context,
    world: &crate::world_args::LoadedWorld,
    view: &vista::render::View,
    args: &crate::render_cmd::RenderArgs,
    timed: usize,
    warmup: usize,
) {
    let c = &view.camera;
    println!(
        "device: {}  ({} frames rendered: {warmup} warm-up, {} timed; {}x{})",
        ctx.info().name,
        args.frames,
        timed,
        view.size[0],
        view.size[1]
    );
    println!(
        "world:  {}  camera ({:.1}, {:.1}, {:.1}) m ({:.1} m above the height source), yaw {:.1}, pitch {:.1}, \
         fov {:.1}, target error {} px{}",
        world.label,
        c.position_m[0],
        c.position_m[1],
        c.position_m[2],
        c.position_m[2]
            - f64::from(world.source.sample(c.position_m[0] - world.origin_m[0], c.position_m[1] - world.origin_m[1])),
        c.yaw_deg,
        c.pitch_deg,
        view.fov_y_deg,
        view.target_error_px,
        if args.fly.is_some() { " (where the fly-through ended)" } else { "" }
    );
}

/// The `stream:`, `queues:`, `async overlap:` and `output:` lines.
pub fn print_stream_and_queues(
    ctx: &vista::gpu::Context,
    renderer: &vista::render::TerrainRenderer,
    args: &crate::render_cmd::RenderArgs,
    (settle, budget): (&vista::render::offscreen::Settle, &crate::budget::NodeBudget),
    timed: &[FrameTimings],
) {
    let st = renderer.terrain.stats();
    println!(
        "stream: {} resident of {} slots ({}), {} loading, {} waiting upload, {} failed loads ({} retried, {} nodes given up); {} after {} frames, {:.2} s (lazy bake)",
        st.resident,
        renderer.terrain.slots(),
        budget.describe(),
        st.loading,
        st.waiting_upload,
        st.failed,
        st.retried,
        st.gave_up,
        if settle.settled { "settled" } else { "NOT settled (--settle-seconds ran out)" },
        settle.frames,
        settle.seconds
    );
    if let Some(ran) = renderer.queue_mode() {
        println!("queues: {}", ran.describe(ctx.info()));
        println!("async overlap: {}", describe_overlap(ran, timed));
    }
    println!("output: {}", describe_output(&args.output, renderer));
}
