//! `vista vegetate`: REDengine 3's offline vegetation generator over a
//! world (the scene's `[vegetation]` table, else its defaults), its tiles
//! kept in the output folder for reruns and shards, its outputs (instances,
//! occurrence maps, the maps' pictures) written once every tile is there.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context as _, Result};
use clap::Args;
use vista::world::vegetation::{
    generate, write_outputs, Generated, MaskMap, Masks, Occurrence, Request, StampVegetation, SunMarch,
    VegetationParams, MATERIAL_NAMES, TILE_CELLS,
};
use vista::world::Hole;

use crate::bake_shard::ShardArg;
use crate::scene::Scene;
use crate::world_args::{LoadedWorld, WorldArgs};
use crate::InputError;

#[derive(Args)]
pub struct VegetateArgs {
    #[command(flatten)]
    pub world: WorldArgs,
    /// Output folder: tiles/ (reused by a rerun whose inputs still match),
    /// then instances.bin, occurrence-NAME.bin per grass type,
    /// vegetation.json, resource.png, sun.png and vegetation.png.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Generate shard I of N (0-based): every N-th tile. N shards writing
    /// into one folder (at once or not) make the whole run; the one that
    /// completes the tiles writes the outputs. `auto/N` reads the index
    /// from SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX.
    #[arg(long, value_name = "I/N", value_parser = crate::bake_shard::parse_shard, allow_hyphen_values = true)]
    pub shard: Option<ShardArg>,
    /// Make only the tiles overlapping this rectangle (world metres, as
    /// `vista bake --region`); the outputs wait for the rest (a later run
    /// without it reuses these tiles), and the report extrapolates the
    /// tiles' time to the whole world.
    #[arg(long, value_name = "MINX,MINY,MAXX,MAXY", value_parser = crate::bake::parse_region, allow_hyphen_values = true)]
    pub region: Option<[f64; 4]>,
    /// Where the sun's march runs: `cpu` (f64, every core) or `gpu` (f32,
    /// the Vulkan device: --device picks it). A tile marched by one is not
    /// reused by a run with the other.
    #[arg(long, value_enum, default_value_t = SunOn::Cpu)]
    pub sun: SunOn,
    /// Side of a generator cell in metres (replaces the scene's cell_m).
    #[arg(long, value_name = "METRES", value_parser = crate::numbers::number_f64, allow_negative_numbers = true)]
    pub cell: Option<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SunOn {
    Cpu,
    Gpu,
}

fn scene(args: &VegetateArgs) -> Result<Option<Scene>> {
    match &args.world.scene {
        Some(path) => Ok(Some(Scene::load(path).map_err(|e| InputError(format!("{e:#}")))?)),
        None => Ok(None),
    }
}

/// The parameters: the scene's table (else the defaults) with `--cell`.
pub fn params(args: &VegetateArgs) -> Result<VegetationParams> {
    let mut p = scene(args)?.and_then(|s| s.vegetation).unwrap_or_default();
    if let Some(c) = args.cell {
        p.cell_m = c;
        // An occurrence cell of the default 10 m stays whole where it can.
        if (p.occurrence_cell_m / c).fract() != 0.0 {
            p.occurrence_cell_m = c * (p.occurrence_cell_m / c).round().max(1.0);
        }
    }
    p.validate().map_err(|e| InputError(e.to_string()))?;
    Ok(p)
}

fn shard(args: &VegetateArgs) -> Result<Option<(u32, u32)>> {
    match args.shard {
        None => Ok(None),
        Some(ShardArg::All { count }) => {
            Err(InputError(format!("--shard all/{count} is for `vista bake --dry-run`; give I/{count}")).into())
        }
        Some(s) => Ok(s.index()?.map(|i| (i, s.count()))),
    }
}

/// What keeps vegetation out: the scene's `[[vegetation_masks]]`, its
/// decals with `clear_vegetation`, the mask map (world metres).
fn masks(args: &VegetateArgs, params: &VegetationParams, world: &LoadedWorld) -> Result<Masks> {
    let Some(scene) = scene(args)? else { return Ok(Masks::default()) };
    let input = |e: anyhow::Error| InputError(format!("{e:#}"));
    let mut shapes: Vec<Hole> =
        scene.vegetation_masks().map_err(input)?.iter().map(|h| h.relative_to(world.origin_m)).collect();
    let decals = scene.decals(world.origin_m).map_err(input)?;
    for (d, clear) in decals.decals.iter().zip(&decals.clear_vegetation) {
        if *clear {
            shapes.extend(d.outline());
        }
    }
    let map = match &params.mask_map {
        Some(path) => Some(MaskMap::load(path, world.desc.extent_m).map_err(|e| InputError(e.to_string()))?),
        None => None,
    };
    Ok(Masks { shapes, map })
}

/// The scene's stamps that carry their own vegetation, placed in world metres.
fn stamp_vegetation(
    args: &VegetateArgs,
    params: &VegetationParams,
    world: &LoadedWorld,
) -> Result<Vec<StampVegetation>> {
    let Some(scene) = scene(args)? else { return Ok(Vec::new()) };
    let input = |e: String| anyhow::Error::from(InputError(e));
    let mut out = Vec::new();
    for st in scene.stamps().map_err(|e| input(format!("{e:#}")))? {
        if let Some(folder) = &st.vegetation {
            let mut placement = st.placement;
            placement.center_m = [0, 1].map(|a| placement.center_m[a] - world.origin_m[a]);
            out.push(StampVegetation::load(folder, placement, params).map_err(|e| input(e.to_string()))?);
        }
    }
    Ok(out)
}

/// Checks everything `vegetate` reads before it starts.
pub fn check(args: &VegetateArgs) -> Result<()> {
    let params = params(args)?;
    shard(args)?;
    let world = args.world.load()?;
    masks(args, &params, &world)?;
    stamp_vegetation(args, &params, &world)?;
    Ok(())
}

/// Runs the generator; with `ctx` the sun is marched on its device.
pub fn vegetate(args: &VegetateArgs, ctx: Option<&vista::gpu::Context>) -> Result<()> {
    let marcher = ctx.map(vista::effects::vegetation::vegetation_sun::VegetationSun::new).transpose()?;
    let params = params(args)?;
    let shard = shard(args)?;
    let world = args.world.load()?;
    let masks = masks(args, &params, &world)?;
    let stamps = stamp_vegetation(args, &params, &world)?;
    let request = Request {
        world: &world.desc,
        source: world.source.as_ref(),
        holes: &world.holes,
        rules: &world.bake.materials,
        params: &params,
        masks: &masks,
        stamps: &stamps,
        shard,
        region: args.region,
        sun: marcher.as_ref().map(|m| m as &(dyn SunMarch + Sync)),
    };
    let size = vista::world::vegetation::check(&request).map_err(|e| InputError(e.to_string()))?;
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    println!(
        "vegetation: {} over {} x {} cells of {} m ({} tiles of {TILE_CELLS} x {TILE_CELLS}); sun: {} samples of day \
         {} at latitude {}; {} resource iterations",
        world.label,
        size[0],
        size[1],
        params.cell_m,
        size[0].div_ceil(TILE_CELLS) * size[1].div_ceil(TILE_CELLS),
        params.sun_samples,
        params.day_of_year,
        params.latitude_deg,
        params.iterations
    );
    let start = Instant::now();
    let report = generate(&request, &args.out)?;
    let mut which = shard.map(|(i, n)| format!(" (shard {i}/{n})")).unwrap_or_default();
    if let Some(r) = args.region {
        which += &format!(" (region {},{} .. {},{} m)", r[0], r[1], r[2], r[3]);
    }
    println!("field: {:.1} s (heights, slopes, materials of every cell)", report.field_s);
    println!(
        "tiles{which}: {} computed, {} reused (inputs unchanged) in {:.1} s",
        report.computed, report.reused, report.tiles_s
    );
    if let (Some(m), true) = (&marcher, report.computed > 0) {
        println!("  sun: marched on the GPU ({}) in {:.1} s of them", m.name(), report.sun_s);
    }
    if args.region.is_some() && report.computed > 0 {
        let whole = report.tiles_s * report.tiles as f64 / report.computed as f64;
        println!("  at this rate the world's {} tiles take about {whole:.0} s (extrapolated)", report.tiles);
    }
    let Some(g) = &report.result else {
        println!(
            "outputs: not written: {} of {} tiles (other shards' or outside --region) are not in {} yet; the run \
             that completes them writes them",
            report.missing,
            report.tiles,
            args.out.display()
        );
        return Ok(());
    };
    let maps = print_and_write(args, &params, g)?;
    println!(
        "wrote {}: instances.bin ({} instances), {} occurrence map(s), vegetation.json, resource.png, sun.png, \
         vegetation.png; {:.1} s in all",
        args.out.display(),
        g.instances.len(),
        maps.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Prints the ground and what grew, writes the outputs; gives the
/// occurrence maps.
fn print_and_write(args: &VegetateArgs, params: &VegetationParams, g: &Generated) -> Result<Vec<Occurrence>> {
    let ground: Vec<String> = (0..5u8)
        .map(|m| {
            let n = g.material.iter().zip(&g.hole).filter(|(c, h)| **c == m && !**h).count();
            format!("{} {:.1} %", MATERIAL_NAMES[usize::from(m)], 100.0 * n as f64 / g.material.len() as f64)
        })
        .collect();
    println!("ground (the bake's material rules): {}", ground.join(", "));
    let maps = write_outputs(&args.out, params, g)?;
    for (ty, t) in params.types.iter().enumerate() {
        match maps.iter().find(|m| m.ty == ty) {
            Some(m) => {
                let all = m.size[0] * m.size[1];
                let set = m.set_cells();
                println!(
                    "  {:<10} grass: occurrence bit set in {set} of {all} cells of {} m ({:.1} %)",
                    t.name,
                    params.occurrence_cell_m,
                    100.0 * set as f64 / all.max(1) as f64
                );
            }
            None => {
                let n = g.instances.iter().filter(|i| i.ty as usize == ty).count();
                println!("  {:<10} {:?}: {n} instances", t.name, t.kind);
            }
        }
    }
    Ok(maps)
}
