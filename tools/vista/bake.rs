//! `vista bake` and `vista memory`: node payloads to disk, with the figures
//! needed to size a whole world from a small region.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use clap::Args;
use serde::Serialize;
use vista::world::human_bytes as bytes;
use vista::world::{
    bake_shard, bake_world, uncompressed_file_bytes, BakeStats, Limits, MemoryReport, NodeCache, PayloadFormat,
    PayloadSize, Progress, ShardManifest, ShardPlan, ShardSplit, WorldDesc, WorldPlan, DEFAULT_MAX_BAKE_DISK_BYTES,
};

use crate::bake_shard::ShardArg;
use crate::world_args::{parse_f64, parse_list, LoadedWorld, WorldArgs};
use crate::world_spec::WorldSpec;

/// Resident slots the bake's memory report assumes (the streamer's default
/// budget order of magnitude).
const REPORT_SLOTS: usize = 512;
/// Nodes per timed batch of a plan (half at LOD 0, half at LOD 1); levels
/// bake batches until 50 ms have passed (`WorldPlan::measure_bake`): about
/// 0.25 s in all, and the default world's estimate within about 10 % of its
/// full bake (8 nodes along the diagonal were 35 % high).
const PLAN_SAMPLES: usize = 16;
// `--max-disk`'s default, in GiB as the option takes it.
const _: () = assert!(DEFAULT_MAX_BAKE_DISK_BYTES == 64 << 30);

#[derive(Args)]
pub struct BakeArgs {
    #[command(flatten)]
    pub world: WorldArgs,
    /// Cache folder for the node files (DIR/lod{k}/{x}_{y}.vnode); files
    /// already there and valid for this world are reused, not rebaked.
    /// Not needed with --dry-run.
    #[arg(long, value_name = "DIR", required_unless_present_any = ["dry_run", "verify"])]
    pub out: Option<PathBuf>,
    /// Bake shard I of N (0-based) of the whole world: a deterministic,
    /// cost-balanced share that needs no other shard's output; N shards
    /// baking into one folder (at once or not) make the whole bake, each
    /// writing DIR/manifest/shard-I-of-N.json. `auto/N` reads the index from
    /// SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX; `all/N` (with --dry-run)
    /// prints every shard's plan.
    #[arg(long, value_name = "I/N", value_parser = crate::bake_shard::parse_shard, conflicts_with = "region", allow_hyphen_values = true)]
    pub shard: Option<ShardArg>,
    /// Check the bake in DIR against the plan of this world (give the same
    /// world and options as the bake): every node present and valid, every
    /// shard manifest's files unchanged; names the shards to rerun.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["out", "dry_run", "shard", "region", "json"])]
    pub verify: Option<PathBuf>,
    /// Bake only nodes (of every LOD) overlapping this rectangle, metres;
    /// the report then extrapolates time and disk size to the whole world.
    #[arg(long, value_name = "MINX,MINY,MAXX,MAXY", value_parser = parse_region, allow_hyphen_values = true)]
    pub region: Option<[f64; 4]>,
    /// No progress: neither the bar (on a terminal) nor the plain line
    /// printed every few seconds otherwise.
    #[arg(long)]
    pub no_progress: bool,
    /// Print the plan (sectors, nodes per LOD, disk and GPU bytes, the
    /// estimated time) and exit without baking; exits 2 if the bake would
    /// be refused.
    #[arg(long)]
    pub dry_run: bool,
    /// Bake even if the estimated disk size is over --max-disk.
    #[arg(long)]
    pub yes: bool,
    /// Largest estimated disk size a bake may have without --yes, GiB.
    #[arg(long, value_name = "GIB", value_parser = parse_gib, default_value = "64", allow_negative_numbers = true)]
    pub max_disk: u64,
    /// Seconds between plain progress lines when stderr is not a terminal
    /// (also forces them on a terminal); for tests and logs.
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds, hide = true, allow_negative_numbers = true)]
    pub progress_every: Option<f64>,
    /// Also write the figures as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

#[derive(Args)]
pub struct MemoryArgs {
    #[command(flatten)]
    pub world: WorldArgs,
    /// Resident node slots to account for: what `vista render --slots` takes
    /// for this world (at most 2047: slots are 11-bit).
    #[arg(long, default_value_t = REPORT_SLOTS as u32, value_parser = crate::numbers::whole_u32, allow_negative_numbers = true)]
    pub slots: u32,
    /// Also write the figures as JSON to this file (`cpu_bytes_per_node`,
    /// `gpu_bytes_per_node`, totals, and every payload kind).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

#[derive(Serialize)]
struct MemoryFile<'a> {
    world_nodes: usize,
    payload_format: PayloadFormat,
    #[serde(flatten)]
    resident: MemoryJson,
    kinds: &'a [PayloadSize],
    every_node_resident: MemoryJson,
}

fn parse_gib(s: &str) -> Result<u64, String> {
    let v = parse_f64(s, "--max-disk")?;
    if v < 0.0 {
        return Err(format!("--max-disk {s:?} must not be negative"));
    }
    Ok((v * f64::from(1u32 << 30)) as u64)
}

fn parse_seconds(s: &str) -> Result<f64, String> {
    parse_f64(s, "--progress-every").and_then(|v| {
        if v < 0.0 {
            Err(format!("--progress-every {s:?} must not be negative"))
        } else {
            Ok(v)
        }
    })
}

pub(crate) fn parse_region(s: &str) -> Result<[f64; 4], String> {
    let v = parse_list(s, 4, "region")?;
    if v[0] >= v[2] || v[1] >= v[3] {
        return Err(format!("region {s:?} needs MINX < MAXX and MINY < MAXY"));
    }
    Ok([v[0], v[1], v[2], v[3]])
}

#[derive(Serialize)]
struct BakeReport {
    source: String,
    world: WorldDesc,
    out: PathBuf,
    region: Option<[f64; 4]>,
    nodes_per_lod: Vec<usize>,
    nodes: usize,
    baked: usize,
    /// Of `baked`, nodes whose file was stale (an edit touched its area) or
    /// damaged; the rest were new.
    rebaked: usize,
    cached: usize,
    seconds: f64,
    bytes_on_disk: u64,
    bytes_per_node: f64,
    /// Uncompressed node files over the bytes on disk (zstd's ratio).
    compression_ratio: f64,
    full_world_nodes: usize,
    /// `[index, count]` of a `--shard` bake.
    shard: Option<[u32; 2]>,
    /// The manifest written (a shard or a whole-world bake).
    manifest: Option<PathBuf>,
    /// The error tree of the region's roots, made before the nodes (not in
    /// `seconds`).
    error_tree: ErrorTreeJson,
    /// Only for a region: per-node figures times the full node count, and
    /// the error tree's seconds per LOD-0 sample times the world's.
    extrapolated: Option<Extrapolation>,
    memory: MemoryJson,
}

#[derive(Serialize)]
struct ErrorTreeJson {
    roots: usize,
    /// Tiles of a shard's units in roots other shards own (computed).
    unit_tiles: usize,
    read: usize,
    seconds: f64,
    /// LOD-0 quads under those roots, inside the world.
    quads: u64,
}

#[derive(Serialize)]
struct Extrapolation {
    seconds: f64,
    bytes_on_disk: f64,
}

#[derive(Serialize)]
struct MemoryJson {
    slots: usize,
    cpu_bytes_per_node: usize,
    gpu_bytes_per_node: usize,
    cpu_total: usize,
    gpu_total: usize,
}

impl MemoryJson {
    fn new(r: &MemoryReport) -> Self {
        MemoryJson {
            slots: r.nodes,
            cpu_bytes_per_node: r.cpu_bytes_per_node(),
            gpu_bytes_per_node: r.gpu_bytes_per_node(),
            cpu_total: r.cpu_total(),
            gpu_total: r.gpu_total(),
        }
    }
}

/// A bake's shard split and index, if it leaves a manifest.
type ShardChoice = Option<(ShardSplit, Option<u32>)>;

pub fn bake(args: BakeArgs) -> Result<()> {
    let spec = args.world.resolve()?;
    if let Some(dir) = &args.verify {
        return crate::bake_shard::run_verify(&spec.open()?, dir);
    }
    check_bake_args(&args, &spec)?;
    // A whole-world bake is shard 0 of 1: it too leaves a manifest.
    let shard = match (args.shard, args.region) {
        (Some(s), _) => Some((crate::bake_shard::split(&spec.desc, s.count())?, s.index()?)),
        (None, None) if !args.dry_run => Some((crate::bake_shard::split(&spec.desc, 1)?, Some(0))),
        _ => None,
    };
    let mut plan = spec.plan(args.region).with_slots(REPORT_SLOTS as u32);
    let cap = (!args.yes).then_some(args.max_disk);
    // A shard's cap is on what it writes.
    let whole_cap = if args.shard.is_some() { None } else { cap };
    let limits = Limits { max_bake_disk_bytes: whole_cap, ..spec.limits.clone() };
    if let Some(json) = &args.json {
        crate::out_path::check_out_file(json, "--json")?;
    }
    if args.dry_run {
        return dry_run(&args, spec, &mut plan, &limits, &shard, cap);
    }
    spec.check(&plan, &limits)?;
    if let (Some((split, Some(i))), Some(_)) = (&shard, args.shard) {
        check_shard_disk(&split.shard_plan(*i, &plan), cap)?;
    }
    // clap asks for --out unless --dry-run.
    let dir = args.out.clone().context("--out DIR is needed to bake")?;
    crate::out_path::prepare_out_dir(&dir, "--out", "the node cache: lod{k}/{x}_{y}.vnode")?;
    let w = spec.open()?;
    if let (Some((_, Some(i))), Some(s)) = (&shard, args.shard) {
        claim_folder(&w, &dir, *i, s.count())?;
    }
    let progress = match (args.no_progress, args.progress_every) {
        (true, _) => Progress::Hidden,
        (false, Some(s)) => Progress::Lines { every: std::time::Duration::from_secs_f64(s) },
        (false, None) => crate::progress::auto(),
    };
    if !progress.is_hidden() {
        announce_bake(&w, &mut plan, &shard, &args);
    }
    let baked = run_bake(&w, &shard, args.region, &dir, progress)?;
    let memory = MemoryReport::for_format(REPORT_SLOTS, w.bake.format);
    let report = bake_report(&args, &w, &plan, &shard, dir, baked, &memory);
    // The JSON first: a closed stdout (`| head`) must not lose the file.
    if let Some(path) = &args.json {
        write_json(path, &report)?;
    }
    let mut out = String::new();
    print_bake(&mut out, &w, &report)?;
    write!(out, "\nmemory for {REPORT_SLOTS} resident nodes:\n{memory}")?;
    if let Some(path) = &args.json {
        writeln!(out, "wrote {}", path.display())?;
    }
    emit(&out)
}

/// Option combinations clap cannot refuse by itself.
fn check_bake_args(args: &BakeArgs, spec: &WorldSpec) -> Result<()> {
    if let Some(r) = args.region {
        let [ex, ey] = spec.desc.extent_m;
        if r[2] <= 0.0 || r[3] <= 0.0 || r[0] >= ex || r[1] >= ey {
            let message = format!(
                "--region {},{},{},{} does not overlap the world (0..{ex} x 0..{ey} m)",
                r[0], r[1], r[2], r[3]
            );
            return Err(crate::InputError(message).into());
        }
    }
    if matches!(args.shard, Some(ShardArg::All { .. })) && !args.dry_run {
        let message = "--shard all/N prints every shard's plan: only with --dry-run".to_string();
        return Err(crate::InputError(message).into());
    }
    Ok(())
}

/// `bake --dry-run`: prints the plan (and writes its JSON) without baking.
fn dry_run(
    args: &BakeArgs,
    spec: WorldSpec,
    plan: &mut WorldPlan,
    limits: &Limits,
    shard: &ShardChoice,
    cap: Option<u64>,
) -> Result<()> {
    // The plan even of a refused world: what it would cost is the point.
    let mut out = format!("world:    {}\n", spec.label());
    if let Err(e) = spec.check(plan, limits) {
        write!(out, "{plan}")?;
        emit(&out)?;
        write_plan_json(args.json.as_deref(), &spec.label(), plan, Some(&e))?;
        return Err(e);
    }
    let w = spec.open_for_timing()?;
    plan.measure_bake(&*w.source, &w.holes, &w.bake, PLAN_SAMPLES);
    let mut out = String::new();
    writeln!(out, "{}", world_line(&w))?;
    write!(out, "{plan}")?;
    if let Some((split, index)) = shard {
        crate::bake_shard::write_plans(&mut out, split, *index, plan)?;
        if let Some(i) = index {
            check_shard_disk(&split.shard_plan(*i, plan), cap)?;
        }
    }
    writeln!(out, "dry run: nothing baked")?;
    emit(&out)?;
    write_plan_json(args.json.as_deref(), &w.label, plan, None)
}

/// The `baking ...` line on stderr before a bake with progress.
fn announce_bake(w: &LoadedWorld, plan: &mut WorldPlan, shard: &ShardChoice, args: &BakeArgs) {
    // Timed as the dry run times it, so both say the same.
    plan.measure_bake(&*w.source, &w.holes, &w.bake, PLAN_SAMPLES);
    let what = match (shard, args.shard) {
        (Some((split, Some(i))), Some(_)) => {
            let s = split.shard_plan(*i, plan);
            format!("shard {i} of {}: {} nodes, about {}", s.count, s.nodes(), minutes(s.seconds()))
        }
        _ => plan.summary(),
    };
    eprintln!("baking {what} (`vista bake --dry-run` prints the plan)");
}

/// Refuses a folder that holds another bake than this shard's (its world,
/// settings or shard count), before anything is written; else claims it.
fn claim_folder(w: &LoadedWorld, dir: &Path, index: u32, count: u32) -> Result<()> {
    let cache = NodeCache::with_settings(dir, w.desc, w.source.clone(), w.holes.clone(), w.bake.clone())?;
    vista::world::claim_folder(&cache, dir, index, count).map_err(|e| match e {
        vista::world::WorldError::ForeignBake(m) => crate::InputError(m).into(),
        other => other.into(),
    })
}

/// Bakes a shard (writing its manifest) or a region.
fn run_bake(
    w: &LoadedWorld,
    shard: &ShardChoice,
    region: Option<[f64; 4]>,
    dir: &Path,
    progress: Progress,
) -> Result<(BakeStats, Option<PathBuf>)> {
    Ok(match shard {
        Some((split, Some(i))) => {
            let stats = bake_shard(w.source.clone(), &w.desc, &w.holes, &w.bake, split, *i, dir, progress)
                .with_context(|| format!("baking into {}", dir.display()))?;
            let cache = NodeCache::with_settings(dir, w.desc, w.source.clone(), w.holes.clone(), w.bake.clone())?;
            let path = ShardManifest::new(&cache, split, *i, &stats).write(dir)?;
            (stats, Some(path))
        }
        _ => {
            let stats = bake_world(w.source.clone(), &w.desc, &w.holes, &w.bake, region, dir, progress)
                .with_context(|| format!("baking into {}", dir.display()))?;
            (stats, None)
        }
    })
}

/// The figures of a finished bake, as printed and written as JSON.
fn bake_report(
    args: &BakeArgs,
    w: &LoadedWorld,
    plan: &WorldPlan,
    shard: &ShardChoice,
    dir: PathBuf,
    (stats, manifest): (BakeStats, Option<PathBuf>),
    memory: &MemoryReport,
) -> BakeReport {
    let nodes = stats.baked + stats.cached;
    let per_node = |v: f64| if nodes == 0 { 0.0 } else { v / nodes as f64 };
    let full_world_nodes = plan.world_nodes as usize;
    BakeReport {
        source: w.label.clone(),
        world: w.desc,
        out: dir,
        region: args.region,
        nodes_per_lod: stats.nodes_per_lod.clone(),
        nodes,
        baked: stats.baked,
        rebaked: stats.rebaked,
        cached: stats.cached,
        seconds: stats.seconds,
        bytes_on_disk: stats.bytes_on_disk,
        bytes_per_node: per_node(stats.bytes_on_disk as f64),
        compression_ratio: (nodes as u64 * uncompressed_file_bytes(w.bake.format)) as f64
            / (stats.bytes_on_disk.max(1) as f64),
        full_world_nodes,
        shard: match (shard, args.shard) {
            (Some((split, Some(i))), Some(_)) => Some([*i, split.count()]),
            _ => None,
        },
        manifest,
        extrapolated: args.region.map(|_| {
            let e = &stats.errors;
            // Per LOD-0 sample of the tree made now (none computed: reads).
            let per_quad = e.seconds / stats.error_quads.max(1) as f64;
            let world_quads = vista::world::WorldPlan::new(&w.desc, None).error_quads as f64;
            Extrapolation {
                seconds: per_node(stats.seconds) * full_world_nodes as f64 + per_quad * world_quads,
                bytes_on_disk: per_node(stats.bytes_on_disk as f64) * full_world_nodes as f64,
            }
        }),
        error_tree: ErrorTreeJson {
            roots: stats.errors.roots,
            unit_tiles: stats.errors.below_roots,
            read: stats.errors.read,
            seconds: stats.errors.seconds,
            quads: stats.error_quads,
        },
        memory: MemoryJson::new(memory),
    }
}

/// A shard over `--max-disk` (unless --yes), naming the options.
fn check_shard_disk(s: &ShardPlan, cap: Option<u64>) -> Result<()> {
    match cap {
        Some(cap) if s.disk_bytes > cap => {
            let message = format!(
                "shard {} of {} would write about {} ({} nodes, about {}); the cap is {}: raise --max-disk GIB, \
                 use more shards or pass --yes",
                s.index,
                s.count,
                bytes(s.disk_bytes as f64),
                s.nodes(),
                minutes(s.seconds()),
                bytes(cap as f64)
            );
            Err(crate::InputError(message).into())
        }
        _ => Ok(()),
    }
}

fn minutes(s: f64) -> String {
    if s < 5400.0 {
        format!("{:.0} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}

/// `bake --dry-run --json FILE`: the plan as printed, and the refusal if
/// the plan was refused.
fn write_plan_json(path: Option<&Path>, source: &str, plan: &WorldPlan, refused: Option<&anyhow::Error>) -> Result<()> {
    let Some(path) = path else { return Ok(()) };
    let json = serde_json::json!({
        "dry_run": true,
        "source": source,
        "plan": plan,
        "estimated_seconds": plan.bake_seconds(),
        "refused": refused.map(|e| format!("{e:#}")),
    });
    write_json(path, &json)
}

/// Writes a report to stdout; a reader that went away early is not an error.
pub(crate) fn emit(text: &str) -> Result<()> {
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => r.context("writing to stdout"),
    }
}

/// `world:` and what it is, for the reports.
fn world_line(w: &LoadedWorld) -> String {
    let d = &w.desc;
    format!(
        "world:    {} ({} x {} m, heights {}..{} m, spacing {} m, {} LODs, {} holes)",
        w.label,
        d.extent_m[0],
        d.extent_m[1],
        d.height_range_m[0],
        d.height_range_m[1],
        d.spacing_m,
        d.lod_count,
        w.holes.len()
    )
}

fn print_bake(out: &mut String, w: &LoadedWorld, r: &BakeReport) -> Result<()> {
    writeln!(out, "{}", world_line(w))?;
    match (r.region, r.shard) {
        (Some(g), _) => writeln!(out, "region:   {},{} .. {},{} m", g[0], g[1], g[2], g[3]),
        (None, Some([i, n])) => {
            writeln!(out, "shard:    {i} of {n} (0-based), {} of the world's {} nodes", r.nodes, r.full_world_nodes)
        }
        (None, None) => writeln!(out, "region:   whole world"),
    }?;
    let per_lod: Vec<String> = r.nodes_per_lod.iter().enumerate().map(|(l, n)| format!("lod{l} {n}")).collect();
    writeln!(out, "nodes:    {} ({})", r.nodes, per_lod.join(", "))?;
    let new = r.baked - r.rebaked;
    writeln!(out, "          {} reused, {} rebaked, {} new", r.cached, r.rebaked, new)?;
    let e = &r.error_tree;
    writeln!(
        out,
        "time:     {:.2} s for the nodes ({:.2} ms per node), {:.2} s before them for the error tree ({} roots: {} read, {} computed{})",
        r.seconds,
        1000.0 * r.seconds / r.nodes.max(1) as f64,
        e.seconds,
        e.roots,
        e.read,
        e.roots - e.read,
        match e.unit_tiles {
            0 => String::new(),
            n => format!("; {n} tiles of its units in roots other shards own"),
        }
    )?;
    writeln!(
        out,
        "disk:     {} in {} ({} per node; zstd {:.2}:1)",
        bytes(r.bytes_on_disk as f64),
        r.out.display(),
        bytes(r.bytes_per_node),
        r.compression_ratio
    )?;
    if let Some(m) = &r.manifest {
        writeln!(out, "manifest: {} (`vista bake --verify DIR` checks the whole bake)", m.display())?;
    }
    if let Some(x) = &r.extrapolated {
        // Cached nodes only measure validation, so say which time this is.
        let basis = if r.baked == 0 && e.read == e.roots { "cache reads" } else { "this run" };
        writeln!(
            out,
            "extrapolated to the whole world ({} nodes, per-node figures of {basis}): {:.1} s, {}",
            r.full_world_nodes,
            x.seconds,
            bytes(x.bytes_on_disk)
        )?;
    }
    Ok(())
}

fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    Ok(vista::output::write(path, (text + "\n").as_bytes())?)
}

pub fn memory(args: MemoryArgs) -> Result<()> {
    if let Some(json) = &args.json {
        crate::out_path::check_out_file(json, "--json")?;
    }
    // Headers only: the figures depend on the world's geometry, not its
    // heights, so no map is read.
    let w = args.world.resolve()?;
    w.check(&w.plan(None), &w.limits)?;
    crate::world_args::check_slots(args.slots, &w.desc)?;
    let label = w.label();
    let mut out = String::new();
    // Counted, not listed: a huge world costs no memory to account for.
    let full = WorldPlan::new(&w.desc, None).world_nodes as usize;
    let slots = args.slots as usize;
    writeln!(out, "world:    {} ({} nodes over {} LODs)", label, full, w.desc.lod_count)?;
    writeln!(out, "memory for {slots} resident nodes:")?;
    // As a renderer of the scene's effects keeps them.
    let (effects, holes) = w.effects_and_holes();
    let source_holes = w.may_have_source_holes()?;
    let report = vista::render::memory_for(slots, w.bake.format, effects, &w.desc, holes, source_holes);
    write!(out, "{report}")?;
    let all = vista::render::memory_for(full, w.bake.format, effects, &w.desc, holes, source_holes);
    writeln!(
        out,
        "every node resident would take {} CPU / {} GPU",
        bytes(all.cpu_total() as f64),
        bytes(all.gpu_total() as f64)
    )?;
    if let Some(path) = &args.json {
        let file = MemoryFile {
            world_nodes: full,
            payload_format: w.bake.format,
            resident: MemoryJson::new(&report),
            kinds: &report.kinds,
            every_node_resident: MemoryJson::new(&all),
        };
        write_json(path, &file)?;
        writeln!(out, "wrote {}", path.display())?;
    }
    emit(&out)
}
