//! World selection shared by every command that needs terrain: a scene file,
//! a height map, or (nothing given) the default procedural world.

use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{bail, Context as _, Result};
use clap::Args;
use vista::render::Effects;
use vista::world::{
    BakeSettings, ErrorTree, ExrSource, GeoTiffInfo, GeoTiffSource, GridSource, HeightSource, Hole, Limits,
    PayloadFormat, Png16Source, ProceduralSource, WorldDesc, WorldError, WorldPlan, DEFAULT_MAX_SECTORS_PER_SIDE,
    MAX_LOD_COUNT, MAX_SECTORS_PER_SIDE,
};

use crate::scene::{Scene, SceneSource};

/// First bytes of a PNG and an OpenEXR file: files are told apart by
/// content, so a misnamed file still loads (or fails naming its real kind).
const PNG_MAGIC: [u8; 4] = [0x89, b'P', b'N', b'G'];
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
/// TIFF and BigTIFF, little- and big-endian.
const TIFF_MAGIC: [[u8; 4]; 4] = [*b"II*\0", *b"MM\0*", *b"II+\0", *b"MM\0+"];

/// WORLD: `--scene FILE.toml` | `--heightmap FILE --extent M --height-range LO HI`
/// | nothing (the default procedural world). Values given on the command line
/// override the scene file's.
#[derive(Args, Clone, Debug, Default)]
pub struct WorldArgs {
    /// Scene file (TOML): [world] source/extent/height_range/spacing/lods/seed,
    /// [[holes]] circle = [x, y, r] or polygon = [[x, y], ...], [effects].
    #[arg(long, value_name = "FILE.toml", help_heading = "World")]
    pub scene: Option<PathBuf>,
    /// Height map: 16-bit grayscale PNG, single-channel float EXR or a
    /// one-band GeoTIFF (16-bit integer or 32-bit float metres), told apart
    /// by content. Needs --extent (a GeoTIFF's tags give it, and the
    /// origin) and, for PNG, --height-range.
    #[arg(long, value_name = "FILE", help_heading = "World")]
    pub heightmap: Option<PathBuf>,
    /// World size in metres: one number (square) or X,Y.
    #[arg(long, value_name = "METRES", value_parser = parse_extent, allow_negative_numbers = true, help_heading = "World")]
    pub extent: Option<[f64; 2]>,
    /// Heights in metres that the PNG's 0..65535 maps to; also the range of
    /// the 16-bit height encoding. Optional for EXR (taken from the data,
    /// resampling overshoot included); an EXR range that clips data is an
    /// error unless --clamp-heights is given.
    #[arg(long, num_args = 2, value_names = ["LO", "HI"], value_parser = crate::numbers::number_f32, allow_negative_numbers = true, help_heading = "World",
          action = clap::ArgAction::Set)]
    pub height_range: Option<Vec<f32>>,
    /// Clamp EXR heights outside --height-range (or the scene's height_range)
    /// to it instead of failing; prints how many samples were clamped.
    #[arg(long, help_heading = "World")]
    pub clamp_heights: bool,
    /// Distance between LOD-0 samples in metres [default: 0.5].
    #[arg(long, value_name = "METRES", value_parser = crate::numbers::number_f64, allow_negative_numbers = true, help_heading = "World")]
    pub spacing: Option<f64>,
    /// Number of quadtree levels (1..=10) [default: 6].
    #[arg(long, value_name = "N", value_parser = crate::numbers::whole_u32, allow_negative_numbers = true, help_heading = "World")]
    pub lods: Option<u32>,
    /// Seed of the procedural world [default: 1].
    #[arg(long, value_name = "N", value_parser = crate::numbers::whole_u64, allow_negative_numbers = true, help_heading = "World")]
    pub seed: Option<u64>,
    /// Cut a circular hole into the terrain (repeatable): centre X,Y and
    /// radius R, metres.
    #[arg(long, value_name = "X,Y,R", value_parser = parse_hole_circle, allow_hyphen_values = true, help_heading = "World")]
    pub hole_circle: Vec<Hole>,
    /// Where the world's south-west corner lies, E,N metres (e.g. UTM):
    /// cameras and holes are then given in these coordinates [default: 0,0].
    #[arg(long, value_name = "E,N", value_parser = parse_origin, allow_hyphen_values = true, help_heading = "World")]
    pub origin: Option<[f64; 2]>,
    /// Normal and albedo payloads: bc (the talk's BC3 + BC1) or rgba8 (the
    /// uncompressed reference, to measure what compression costs).
    #[arg(long, value_name = "bc|rgba8", default_value_t = PayloadFormat::Bc, help_heading = "World")]
    pub payload: PayloadFormat,
    /// Refuse worlds with more LOD-0 sectors than this along either side,
    /// checked before anything is read or allocated [default: 16384].
    #[arg(long, value_name = "N", value_parser = crate::numbers::whole_u64, allow_negative_numbers = true, help_heading = "World")]
    pub max_sectors: Option<u64>,
}

/// A resolved world, ready to bake or render.
pub struct LoadedWorld {
    pub desc: WorldDesc,
    pub source: Arc<dyn HeightSource>,
    pub holes: Vec<Hole>,
    /// The scene's `[effects]` (defaults without a scene).
    pub effects: Effects,
    /// What the terrain comes from, for reports.
    pub label: String,
    /// Where the world's south-west corner lies in the user's coordinates
    /// (`--origin`, the scene's `origin`); `holes` are already relative to it.
    pub origin_m: [f64; 2],
    /// Payload format and the scene's material rules.
    pub bake: BakeSettings,
    /// The limits it was planned against (the library checks them again
    /// with the device's).
    pub limits: Limits,
    /// Each stamp's id and box, in order: what a scene edit compares.
    pub stamps: Vec<(u64, [f64; 4])>,
    /// The scene's decals (world metres) with their textures read.
    pub decals: vista::effects::virtual_texture::decals::DecalSet,
    /// The scene's assets (world metres).
    pub assets: Vec<vista::effects::assets::Asset>,
}

/// Refuses a slot budget the renderer cannot use for `world`, in the
/// option's terms and before any GPU work: slots are 10-bit (at most
/// `MAX_SLOTS`), and the roots, always resident, may hold at most a quarter
/// of them (the plan's rule).
pub fn check_slots(slots: u32, world: &WorldDesc) -> Result<()> {
    let max = vista::terrain::quadtree::MAX_SLOTS;
    let [x, y] = world.grid(world.root_lod());
    let roots = u64::from(x) * u64::from(y);
    let min = (4 * roots).max(1);
    if !(min..=u64::from(max)).contains(&u64::from(slots)) {
        let why = if u64::from(slots) > u64::from(max) {
            "slots are 10-bit".to_string()
        } else {
            format!("the world's {x} x {y} root nodes stay resident and may hold at most a quarter of them")
        };
        if min > u64::from(max) {
            // No budget holds the roots: the world's plan says why (with the
            // device's limits, once the device is known).
            return Ok(());
        }
        return Err(anyhow::Error::new(crate::InputError(format!(
            "--slots {slots}: use {min} to {max} resident nodes for this world ({why})"
        ))));
    }
    Ok(())
}

impl LoadedWorld {
    /// The world's error tree (every node's error needs every LOD-0 sample
    /// under its root, so the whole tree is made before rendering), read
    /// from `cache/errors` (`--cache`, else [`vista::world::default_cache_dir`]) or
    /// computed there, with progress on stderr and one line saying which.
    /// The world is first checked against the device (as
    /// `TerrainRenderer::new` would), so a world no renderer can hold is
    /// refused before its tree is made.
    pub fn errors(&self, ctx: &vista::gpu::Context, cache: Option<&Path>) -> Result<Arc<ErrorTree>> {
        let terrain = vista::terrain::TerrainOptions {
            bake: self.bake.clone(),
            limits: self.limits.clone(),
            ..vista::terrain::TerrainOptions::default()
        };
        vista::terrain::check_plan(ctx, &self.desc, &terrain).map_err(plan_error_is_input)?;
        let dir = cache.map(Path::to_path_buf).or_else(vista::world::default_cache_dir);
        let tree = ErrorTree::new(&self.desc, Arc::clone(&self.source), dir.as_deref())?;
        let p = tree.prepare(crate::progress::auto());
        let place = match tree.dir() {
            Some(d) => format!("cached in {}", d.display()),
            None => "in memory only ($VISTA_CACHE is empty)".to_string(),
        };
        eprintln!(
            "error tree: {} roots, {} read, {} computed in {:.1} s; {place}",
            p.roots,
            p.read,
            p.roots - p.read,
            p.seconds
        );
        Ok(Arc::new(tree))
    }

    /// Commands whose views are chosen in world metres (benchmarks, golden)
    /// refuse a placed world rather than silently ignoring the placement.
    pub fn require_unplaced(&self, command: &str) -> Result<()> {
        if self.origin_m != [0.0, 0.0] {
            return Err(anyhow::Error::new(crate::InputError(format!(
                "{command} chooses its views in world metres (south-west corner at 0,0); drop --origin (or the scene's origin), which only `vista render` uses"
            ))));
        }
        Ok(())
    }
}

/// A world resolved from the arguments, its height map not yet read: enough
/// for the plan; nothing but the scene file has been read.
pub struct WorldSpec {
    /// Geometry; a height map's height range is settled when it is opened.
    pub desc: WorldDesc,
    source: SpecSource,
    holes: Vec<Hole>,
    /// The scene's stamps, placed relative to the world's corner.
    stamps: Vec<crate::scene::SceneStampSpec>,
    /// The scene's decals, relative to the world's corner (textures unread).
    decals: crate::scene::SceneDecals,
    assets: Vec<vista::effects::assets::Asset>,
    effects: Effects,
    origin_m: [f64; 2],
    pub limits: Limits,
    /// Payload format and the scene's material rules.
    pub bake: BakeSettings,
}

enum SpecSource {
    Procedural { seed: u64 },
    Heightmap { path: PathBuf, kind: MapKind, height_range: Option<GivenRange>, clamp: bool },
}

impl WorldArgs {
    /// Resolves the arguments (and the scene file, if any) into a validated
    /// world, refused before its source is read if its plan breaks a limit.
    /// Every failure is a one-line message naming the culprit, marked as the
    /// user's input (exit code 2).
    pub fn load(&self) -> Result<LoadedWorld> {
        let spec = self.resolve()?;
        spec.check(&spec.plan(None), &spec.limits)?;
        spec.open()
    }

    /// The world's geometry and where its heights come from, without
    /// reading them.
    pub fn resolve(&self) -> Result<WorldSpec> {
        self.resolve_inner().map_err(input_error)
    }

    fn resolve_inner(&self) -> Result<WorldSpec> {
        if let (Some(s), Some(h)) = (&self.scene, &self.heightmap) {
            bail!("--scene {} and --heightmap {} both choose the world; give one", s.display(), h.display());
        }
        let scene = match &self.scene {
            Some(path) => Scene::load(path)?,
            None => Scene::default(),
        };
        let w = &scene.world;
        let heightmap = match (&self.heightmap, &w.source) {
            (Some(p), _) => Some((p.clone(), "--heightmap")),
            (None, SceneSource::Path(p)) => Some((p.clone(), "the scene's source")),
            (None, SceneSource::Procedural) => None,
        };
        // A GeoTIFF places itself: extent and origin from its tags unless given.
        let geotiff = match &heightmap {
            Some((p, _)) if magic(p).is_some_and(|m| TIFF_MAGIC.contains(&m)) => Some(GeoTiffSource::read_header(p)?),
            _ => None,
        };
        let extent = self.extent.or(w.extent.map(|e| e.xy())).or(geotiff.as_ref().and_then(GeoTiffInfo::extent_m));
        let height_range = match (&self.height_range, w.height_range) {
            (Some(v), _) => Some(GivenRange::new([v[0], v[1]], "--height-range")),
            (None, Some(r)) => Some(GivenRange::new(r, "the scene's height_range")),
            (None, None) => None,
        };
        let clamp = self.clamp_heights || w.clamp_heights;
        let clamp_name = if self.clamp_heights { "--clamp-heights" } else { "the scene's clamp_heights" };
        if self.scene.is_some() {
            self.note_overrides(&scene);
        }
        let defaults = WorldDesc::default();
        let spacing_m = self.spacing.or(w.spacing).unwrap_or(defaults.spacing_m);
        // Without a count, the extent decides (a small number of roots).
        let lods_for_extent = |e: Option<[f64; 2]>| WorldDesc::lods_for(e.unwrap_or(defaults.extent_m), spacing_m);
        let seed = self.seed.or(w.seed).unwrap_or(1);
        let origin_m = self.origin.or(w.origin).or(geotiff.as_ref().and_then(|g| g.origin_m)).unwrap_or([0.0, 0.0]);
        if !origin_m.iter().all(|v| v.is_finite()) {
            bail!("the scene's origin {origin_m:?} must be two finite numbers");
        }
        let limit = crate::render_cmd::PROVEN_RANGE_M;
        if origin_m.iter().any(|v| v.abs() > limit) {
            let name = if self.origin.is_some() { "--origin" } else { "the scene's origin" };
            bail!(
                "{name} {},{}: placements beyond +-{limit:e} m are outside what `vista stability` case 1 proves exact",
                show_m(origin_m[0]),
                show_m(origin_m[1])
            );
        }
        let names = FieldNames {
            extent: given_as(self.extent.is_none() && w.extent.is_some(), "--extent", "extent"),
            spacing: given_as(self.spacing.is_none() && w.spacing.is_some(), "--spacing", "spacing"),
            lods: given_as(self.lods.is_none() && w.lods.is_some(), "--lods", "lods"),
            height_range: height_range.map(|r| r.to_string()),
        };
        let mut holes = scene.holes()?;
        holes.extend(self.hole_circle.iter().cloned());
        let holes: Vec<Hole> = holes.iter().map(|h| h.relative_to(origin_m)).collect();
        let decals = scene.decals(origin_m)?;
        let assets = scene.assets(origin_m)?;
        let mut stamps = scene.stamps()?;
        for st in &mut stamps {
            let c = &mut st.placement.center_m;
            *c = [c[0] - origin_m[0], c[1] - origin_m[1]];
        }

        let (desc, source) = match heightmap {
            None => {
                let extent_m = extent.unwrap_or(defaults.extent_m);
                let lod_count = self.lods.or(w.lods).unwrap_or_else(|| lods_for_extent(extent));
                let height_range_m = height_range.map_or(defaults.height_range_m, |r| r.range);
                let desc = WorldDesc { extent_m, height_range_m, spacing_m, lod_count, ..WorldDesc::default() };
                check_desc(&desc, &names)?;
                if clamp {
                    bail!("{clamp_name} clamps an EXR or GeoTIFF height map's data; the procedural world has none: drop it");
                }
                (desc, SpecSource::Procedural { seed })
            }
            Some((path, what)) => {
                let Some(extent_m) = extent else {
                    let untagged = if geotiff.is_some() { " (the GeoTIFF has no pixel scale tag)" } else { "" };
                    bail!("{what} {} needs --extent METRES (the world size it covers){untagged}", path.display());
                };
                let height_range_m = height_range.map_or([0.0, 1.0], |r| r.range);
                let lod_count = self.lods.or(w.lods).unwrap_or_else(|| lods_for_extent(Some(extent_m)));
                let desc = WorldDesc { extent_m, height_range_m, spacing_m, lod_count, ..WorldDesc::default() };
                // An absurd world fails before the file is opened.
                check_desc(&desc, &names)?;
                let kind = heightmap_kind(&path, what, height_range)?;
                if clamp && kind == MapKind::Png {
                    // (a GeoTIFF's data is clamped like an EXR's)
                    bail!(
                        "{clamp_name} clamps an EXR or GeoTIFF height map's data; {} is a PNG, whose 0..65535 always \
                         maps into its height range: drop it",
                        path.display()
                    );
                }
                (desc, SpecSource::Heightmap { path, kind, height_range, clamp })
            }
        };
        note_holes_outside(&holes, &desc, origin_m);
        let max_sectors_per_side = self.max_sectors.unwrap_or(DEFAULT_MAX_SECTORS_PER_SIDE);
        let limits = Limits { max_sectors_per_side, ..Limits::default() };
        let bake = BakeSettings { format: self.payload, materials: scene.material_rules, control: None };
        Ok(WorldSpec { desc, source, holes, stamps, decals, assets, effects: scene.effects, origin_m, limits, bake })
    }
}

impl WorldArgs {
    /// One line on stderr for each scene value a command-line option
    /// replaces with another.
    fn note_overrides(&self, scene: &Scene) {
        let w = &scene.world;
        let show = |v: Option<String>, s: Option<String>, option: &str, key: &str| {
            if let (Some(v), Some(s)) = (v, s) {
                if v != s {
                    eprintln!("note: {option} {v} replaces the scene's {key} {s}");
                }
            }
        };
        let pair = |v: [f64; 2]| format!("{},{}", v[0], v[1]);
        show(self.extent.map(pair), w.extent.map(|e| pair(e.xy())), "--extent", "extent");
        let range = |v: [f32; 2]| format!("{} {}", v[0], v[1]);
        show(
            self.height_range.as_ref().map(|v| range([v[0], v[1]])),
            w.height_range.map(range),
            "--height-range",
            "height_range",
        );
        show(self.spacing.map(|v| v.to_string()), w.spacing.map(|v| v.to_string()), "--spacing", "spacing");
        show(self.lods.map(|v| v.to_string()), w.lods.map(|v| v.to_string()), "--lods", "lods");
        show(self.seed.map(|v| v.to_string()), w.seed.map(|v| v.to_string()), "--seed", "seed");
        show(self.origin.map(pair), w.origin.map(pair), "--origin", "origin");
    }
}

/// A hole that misses the world cuts nothing: one line each, in the
/// user's coordinates, so a typo in a hole is not silently dropped.
fn note_holes_outside(holes: &[Hole], desc: &WorldDesc, origin_m: [f64; 2]) {
    let [ex, ey] = desc.extent_m;
    for (i, h) in holes.iter().enumerate() {
        let [x0, y0, x1, y1] = h.bounds();
        if x1 < 0.0 || y1 < 0.0 || x0 > ex || y0 > ey {
            let [ox, oy] = origin_m;
            let what = match h.relative_to([-ox, -oy]) {
                Hole::Circle { center_m, radius_m } => {
                    format!("circle at {},{} radius {radius_m}", center_m[0], center_m[1])
                }
                Hole::Polygon(p) => format!("polygon of {} points", p.len()),
            };
            eprintln!(
                "note: hole {} ({what}) lies outside the world ({ox}..{} x {oy}..{} m): it cuts nothing",
                i + 1,
                ox + ex,
                oy + ey
            );
        }
    }
}

impl WorldSpec {
    /// What the terrain comes from, before it is read.
    pub fn label(&self) -> String {
        match &self.source {
            SpecSource::Procedural { seed } => format!("procedural (seed {seed})"),
            SpecSource::Heightmap { path, .. } => path.display().to_string(),
        }
    }

    /// The scene's effects and the holes (world-relative).
    pub fn effects_and_holes(&self) -> (&Effects, &[Hole]) {
        (&self.effects, &self.holes)
    }

    /// Whether the source may cut holes of its own, from its header: a
    /// GeoTIFF that declares a no-data value (its pixels are not read).
    pub fn may_have_source_holes(&self) -> Result<bool> {
        Ok(match &self.source {
            SpecSource::Heightmap { path, kind: MapKind::Tiff, .. } => {
                GeoTiffSource::read_header(path).map_err(input_error)?.no_data.is_some()
            }
            _ => false,
        })
    }

    /// The plan of `region` (`None`: the whole world).
    pub fn plan(&self, region: Option<[f64; 4]>) -> WorldPlan {
        WorldPlan::new(&self.desc, region).with_format(self.bake.format)
    }

    /// The plan against `limits`, as the user's input error.
    pub fn check(&self, plan: &WorldPlan, limits: &Limits) -> Result<()> {
        plan.check(limits).map_err(|e| anyhow::Error::new(crate::InputError(e.to_string())))
    }

    /// A source to time the bake with, reading as little as it can: a
    /// 16-bit PNG's north-west corner (at most `TIMING_CORNER` pixels a
    /// side, decoded row by row) stretched over the world, so a plan of a
    /// map of any size stays small in memory; the per-sample work is the
    /// same. Other sources open whole. The label says which.
    pub fn open_for_timing(self) -> Result<LoadedWorld> {
        if let SpecSource::Heightmap { path, kind: MapKind::Tiff, height_range, .. } = &self.source {
            let corner = GeoTiffSource::open_corner(path, self.desc.extent_m).map_err(input_error)?;
            let (cw, ch) = (corner.grid().width(), corner.grid().height());
            let what = if height_range.is_some() { "bake" } else { "heights and bake" };
            let label = format!("{} ({what} from its first {cw} x {ch} strip or tile)", path.display());
            let range = height_range.map_or_else(|| auto_range(corner.grid()), |r| r.range);
            let mut world = self.with_source(Arc::new(corner), label)?;
            world.desc.height_range_m = range;
            return Ok(world);
        }
        let SpecSource::Heightmap { path, kind: MapKind::Png, height_range: Some(given), .. } = &self.source else {
            return self.open();
        };
        let corner =
            Png16Source::open_corner(path, TIMING_CORNER, self.desc.extent_m, given.range).map_err(input_error)?;
        let Some(corner) = corner else { return self.open() };
        let (cw, ch) = (corner.grid().width(), corner.grid().height());
        let label = format!("{} (bake timed on its {cw} x {ch} corner)", path.display());
        self.with_source(Arc::new(corner), label)
    }

    fn with_source(self, source: Arc<dyn HeightSource>, label: String) -> Result<LoadedWorld> {
        let decals = load_decals(&self.decals).map_err(input_error)?;
        let (desc, holes, effects, origin_m, limits, bake, assets) =
            (self.desc, self.holes, self.effects, self.origin_m, self.limits, self.bake, self.assets);
        let stamps = Vec::new();
        Ok(LoadedWorld { desc, source, holes, effects, label, origin_m, limits, bake, stamps, decals, assets })
    }

    /// The stamps' own control maps, in stamp order.
    fn stamp_controls(&self) -> Result<Vec<vista::world::StampControl>> {
        let mut out = Vec::new();
        for (i, st) in self.stamps.iter().enumerate() {
            let Some(path) = &st.control_map else { continue };
            let map = vista::world::ControlMap::open(path, [st.placement.size_m; 2])
                .map_err(|e| anyhow::anyhow!("stamp {} ({}): {e}", i + 1, path.display()))?;
            out.push(vista::world::StampControl { placement: st.placement, map: Arc::new(map) });
        }
        Ok(out)
    }

    /// The source with the scene's stamps on it (each map read now), checked
    /// to stay inside the world's height range, and each stamp's id and box.
    #[allow(clippy::type_complexity)]
    fn stamped(
        &self,
        base: Arc<dyn HeightSource>,
        desc: &WorldDesc,
    ) -> Result<(Arc<dyn HeightSource>, Vec<(u64, [f64; 4])>)> {
        if self.stamps.is_empty() {
            return Ok((base, Vec::new()));
        }
        let mut stamps = Vec::with_capacity(self.stamps.len());
        for (i, st) in self.stamps.iter().enumerate() {
            let at = |e: vista::world::WorldError| anyhow::anyhow!("stamp {} ({}): {e}", i + 1, st.source.display());
            let map = vista::world::load_stamp_map(&st.source, st.placement.size_m).map_err(at)?;
            stamps.push(vista::world::Stamp::new(st.placement, map).map_err(at)?);
        }
        // A stamp's own control map is part of what an edit compares.
        let control_id = |st: &crate::scene::SceneStampSpec| {
            st.control_map.as_ref().and_then(|p| std::fs::metadata(p).and_then(|m| m.modified()).ok())
        };
        let keys = stamps
            .iter()
            .zip(&self.stamps)
            .map(|(s, spec)| {
                let mut h = std::hash::DefaultHasher::new();
                std::hash::Hash::hash(&(s.id_hash(), &spec.control_map, control_id(spec)), &mut h);
                (std::hash::Hasher::finish(&h), s.bounds_m())
            })
            .collect();
        let stamped = vista::world::StampedSource::new(base, stamps);
        stamped.check_range(desc.height_range_m)?;
        Ok((Arc::new(stamped), keys))
    }

    /// Reads the height map (or makes the procedural source).
    pub fn open(self) -> Result<LoadedWorld> {
        let (desc, source, mut label): (WorldDesc, Arc<dyn HeightSource>, String) = match &self.source {
            SpecSource::Procedural { seed } => {
                let d = self.desc;
                let source = ProceduralSource::new(*seed, d.extent_m, d.height_range_m).map_err(input_error)?;
                (d, Arc::new(source), format!("procedural (seed {seed})"))
            }
            SpecSource::Heightmap { path, kind, height_range, clamp } => {
                let (desc, source) =
                    open_heightmap(path, *kind, self.desc, *height_range, *clamp).map_err(input_error)?;
                (desc, source, path.display().to_string())
            }
        };
        let (source, stamps) = self.stamped(source, &desc).map_err(input_error)?;
        let mut bake = self.bake.clone();
        bake.control = vista::effects::materials::control_bake(&self.effects, &desc, bake.materials)
            .map_err(|e| input_error(anyhow::anyhow!("{e}")))?;
        if let Some(control) = &mut bake.control {
            control.stamps = self.stamp_controls().map_err(input_error)?;
        }
        if !self.stamps.is_empty() {
            label += &format!(" with {} stamp{}", self.stamps.len(), if self.stamps.len() == 1 { "" } else { "s" });
        }
        let decals = load_decals(&self.decals).map_err(input_error)?;
        let (holes, effects, origin_m, limits, assets) =
            (self.holes, self.effects, self.origin_m, self.limits, self.assets);
        Ok(LoadedWorld { desc, source, holes, effects, label, origin_m, limits, bake, stamps, decals, assets })
    }
}

/// A library error; a world over the device's limits (found when the
/// renderer is made) is the user's to fix, like any other plan refusal.
pub fn plan_error_is_input(e: vista::Error) -> anyhow::Error {
    match e {
        vista::Error::World(WorldError::Plan(p)) => anyhow::Error::new(crate::InputError(p.to_string())),
        e => e.into(),
    }
}

/// Reads each decal texture once.
fn load_decals(d: &crate::scene::SceneDecals) -> Result<vista::effects::virtual_texture::decals::DecalSet> {
    use vista::effects::virtual_texture::decals::{DecalSet, DecalTexture};
    let textures = d.textures.iter().map(|p| DecalTexture::load(p)).collect::<Result<Vec<_>, _>>()?;
    let set = DecalSet { textures: textures.into(), decals: d.decals.clone() };
    set.check()?;
    Ok(set)
}

fn input_error(e: impl Into<anyhow::Error>) -> anyhow::Error {
    anyhow::Error::new(crate::InputError(format!("{:#}", e.into())))
}

/// A number of metres as a person reads it: digits up to a billion, then
/// scientific notation (a 1e300 input is not 300 digits).
pub fn show_m(v: f64) -> String {
    if v.abs() < 1e9 {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// How the user gave each world field: a command-line option or a scene
/// key, so a refusal names what to change.
struct FieldNames {
    extent: String,
    spacing: String,
    lods: String,
    /// `None`: the default range.
    height_range: Option<String>,
}

fn given_as(from_scene: bool, option: &str, key: &str) -> String {
    if from_scene {
        format!("the scene's {key}")
    } else {
        option.to_string()
    }
}

/// Validates before any file is read, so an absurd size fails at once;
/// what `WorldDesc::validate` refuses is said in the options' terms.
fn check_desc(desc: &WorldDesc, names: &FieldNames) -> Result<()> {
    let s = desc.spacing_m;
    if !(s.is_finite() && s > 0.0) {
        bail!("{} {s} must be a positive number of metres", names.spacing);
    }
    if !(1..=MAX_LOD_COUNT).contains(&desc.lod_count) {
        bail!("{} {}: a world has 1 to {MAX_LOD_COUNT} LODs", names.lods, desc.lod_count);
    }
    let [lo, hi] = desc.height_range_m;
    if let (Some(range), false) = (&names.height_range, lo < hi) {
        bail!("{range}: LO must be below HI");
    }
    let [x, y] = desc.extent_m;
    if !(x.is_finite() && y.is_finite() && x > 0.0 && y > 0.0) {
        bail!("{} {x},{y} must be positive metres", names.extent);
    }
    // Smaller than one LOD-0 node, nothing is drawn (a node is the unit
    // the quadtree streams and draws).
    let node_m = s * f64::from(vista::world::NODE_QUADS);
    if x.min(y) < node_m {
        bail!(
            "a world of {} x {} m is smaller than one node ({} quads of {} m = {} m a side): raise {} or lower {}",
            show_m(x),
            show_m(y),
            vista::world::NODE_QUADS,
            show_m(s),
            show_m(node_m),
            names.extent,
            names.spacing
        );
    }
    let sectors = x.max(y) / desc.sector_size_m();
    if sectors.ceil() > MAX_SECTORS_PER_SIDE as f64 {
        // Plain digits up to what a person reads at a glance.
        let short = |v: f64| if v < 1e15 { format!("{v}") } else { format!("{v:.2e}") };
        let (count, x, y) = (short(sectors.ceil()), short(x), short(y));
        bail!(
            "a world of {x} x {y} m would have {count} sectors of {} m a side; vista addresses at most \
             {MAX_SECTORS_PER_SIDE} (--max-sectors cannot raise that): raise {} or lower {}",
            desc.sector_size_m(),
            names.spacing,
            names.extent
        );
    }
    desc.validate().with_context(|| format!("world of {x} x {y} m at {s} m spacing with {} LODs", desc.lod_count))
}

/// A height range the user chose, and where: `--height-range` or the scene.
#[derive(Clone, Copy)]
struct GivenRange {
    range: [f32; 2],
    origin: &'static str,
}

impl GivenRange {
    fn new(range: [f32; 2], origin: &'static str) -> Self {
        GivenRange { range, origin }
    }
}

impl std::fmt::Display for GivenRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [lo, hi] = self.range;
        // As the user wrote it: two arguments, or a TOML array.
        if self.origin.starts_with("--") {
            write!(f, "{} {lo} {hi}", self.origin)
        } else {
            write!(f, "{} [{lo}, {hi}]", self.origin)
        }
    }
}

/// Pixels a side of the corner a plan times a PNG world's bake on: 2 MiB.
const TIMING_CORNER: u32 = 1024;

/// A height map's kind, by its first bytes.
#[derive(Clone, Copy, PartialEq)]
enum MapKind {
    Png,
    Exr,
    Tiff,
}

/// A regular file's first four bytes, if it has them (never opens a FIFO,
/// which would block: `heightmap_kind` then refuses it).
fn magic(path: &Path) -> Option<[u8; 4]> {
    vista::world::require_regular_file(path).ok()?;
    let mut m = [0u8; 4];
    std::fs::File::open(path).ok()?.read_exact(&mut m).ok()?;
    Some(m)
}

/// Reads the first bytes only: a wrong file or a missing argument is told
/// before the plan, and no pixel is read.
fn heightmap_kind(path: &Path, what: &str, height_range: Option<GivenRange>) -> Result<MapKind> {
    if path.is_dir() {
        bail!("{what} {} is a directory, expected a PNG, EXR or GeoTIFF height map file", path.display());
    }
    if let Err(e) = vista::world::require_regular_file(path) {
        if e.kind() != std::io::ErrorKind::NotFound {
            bail!("{what} {} {e}: give a PNG, EXR or GeoTIFF height map file", path.display());
        }
    }
    let mut magic = [0u8; 4];
    let mut file = std::fs::File::open(path).with_context(|| format!("heightmap file {}", path.display()))?;
    if let Err(e) = file.read_exact(&mut magic) {
        if e.kind() == std::io::ErrorKind::UnexpectedEof {
            bail!("{what} {} is too short to be a PNG, EXR or GeoTIFF file", path.display());
        }
        return Err(e).with_context(|| format!("reading {what} {}", path.display()));
    }
    match magic {
        PNG_MAGIC if height_range.is_none() => {
            bail!("{what} {} is a PNG: give --height-range LO HI (metres of 0 and 65535)", path.display())
        }
        PNG_MAGIC => Ok(MapKind::Png),
        EXR_MAGIC => Ok(MapKind::Exr),
        m if TIFF_MAGIC.contains(&m) => Ok(MapKind::Tiff),
        _ => bail!("{what} {} is neither a PNG, an OpenEXR nor a GeoTIFF file (by its first bytes)", path.display()),
    }
}

/// `geometry` was checked and planned; its height range is the given one
/// (a placeholder without one: an EXR's data decides it).
fn open_heightmap(
    path: &Path,
    kind: MapKind,
    geometry: WorldDesc,
    height_range: Option<GivenRange>,
    clamp: bool,
) -> Result<(WorldDesc, Arc<dyn HeightSource>)> {
    match (kind, height_range) {
        (MapKind::Png, Some(given)) => {
            let source = Png16Source::open(path, geometry.extent_m, given.range)?;
            Ok((geometry.with_posts(source.grid().pixel_size_m()), Arc::new(source)))
        }
        (MapKind::Png, None) => unreachable!("heightmap_kind refuses a PNG without a height range"),
        (MapKind::Tiff, _) => {
            let source = GeoTiffSource::open(path, geometry.extent_m)?;
            Ok((ranged(source.grid(), path, geometry, height_range, clamp)?, Arc::new(source)))
        }
        (MapKind::Exr, _) => {
            let source = ExrSource::open(path, geometry.extent_m)?;
            Ok((ranged(source.grid(), path, geometry, height_range, clamp)?, Arc::new(source)))
        }
    }
}

/// `geometry` with the height range of a map whose data decide it (EXR,
/// GeoTIFF): the given one, checked against the data, or one fitted to
/// them; its posts on the map's.
fn ranged(
    grid: &GridSource,
    path: &Path,
    geometry: WorldDesc,
    height_range: Option<GivenRange>,
    clamp: bool,
) -> Result<WorldDesc> {
    let range = match height_range {
        Some(given) => checked_range(grid, path, given, clamp)?,
        None => auto_range(grid),
    };
    let desc = WorldDesc { height_range_m: range, ..geometry }.with_posts(grid.pixel_size_m());
    // The geometry was checked; only the range is new here.
    desc.validate().with_context(|| format!("height range of {}", path.display()))?;
    Ok(desc)
}

/// The user's range for an EXR, refused if it would clip pixels (heights
/// are clamped to the range when encoded, silently) unless `clamp`.
fn checked_range(grid: &GridSource, path: &Path, given: GivenRange, clamp: bool) -> Result<[f32; 2]> {
    let [lo, hi] = given.range;
    let fit = grid.fit(given.range);
    let file = path.display();
    let (n, total) = (fit.outside, fit.total);
    if n > 0 && !clamp {
        let fix = if given.origin.starts_with("--") {
            "widen it or pass --clamp-heights"
        } else {
            "widen it, or set clamp_heights = true in [world] or pass --clamp-heights"
        };
        bail!("{given} clips {n} of {total} samples of {file} (min {:.1} m, max {:.1} m); {fix}", fit.min, fit.max);
    }
    if n > 0 {
        eprintln!("note: {n} of {total} samples of {file} lie outside {given} and are clamped to {lo}..{hi} m");
        return Ok(given.range);
    }
    // Every pixel fits, but Catmull-Rom may still overshoot between them.
    let [rlo, rhi] = grid.resampled_range();
    if rlo < lo || rhi > hi {
        eprintln!(
            "warning: {given} holds every sample of {file}, but resampling between them reaches {rlo:.1}..{rhi:.1} m, \
             which is clamped; leave the range out to have it fitted"
        );
    }
    Ok(given.range)
}

/// The range an EXR gets when none is given: every value the resampler can
/// produce, overshoot next to cliffs included (see
/// [`vista::world::GridSource::resampled_range`]), so no height is clamped;
/// a flat map is widened to 1 m around its middle so lo < hi.
fn auto_range(grid: &GridSource) -> [f32; 2] {
    let [lo, hi] = grid.resampled_range();
    if hi - lo < 1.0 {
        let mid = lo + (hi - lo) / 2.0;
        [mid - 0.5, mid + 0.5]
    } else {
        [lo, hi]
    }
}

/// A finite number; `what` names the argument in the error.
pub fn parse_f64(s: &str, what: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("{what}: {s:?} is not a finite number")),
    }
}

/// `N` or `X,Y` comma-separated finite numbers, exactly `n` of them.
pub fn parse_list(s: &str, n: usize, what: &str) -> Result<Vec<f64>, String> {
    let v = s.split(',').map(|p| parse_f64(p, what)).collect::<Result<Vec<_>, _>>()?;
    if v.len() != n {
        return Err(format!("{what} {s:?} needs {n} comma-separated numbers, got {}", v.len()));
    }
    Ok(v)
}

fn parse_extent(s: &str) -> Result<[f64; 2], String> {
    let v = if s.contains(',') { parse_list(s, 2, "extent")? } else { vec![parse_f64(s, "extent")?; 2] };
    if v.iter().any(|&e| e <= 0.0) {
        return Err(format!("extent {s:?} must be positive"));
    }
    Ok([v[0], v[1]])
}

fn parse_origin(s: &str) -> Result<[f64; 2], String> {
    let v = parse_list(s, 2, "origin")?;
    Ok([v[0], v[1]])
}

fn parse_hole_circle(s: &str) -> Result<Hole, String> {
    let v = parse_list(s, 3, "hole circle")?;
    if v[2] <= 0.0 {
        return Err(format!("hole circle {s:?}: radius must be positive"));
    }
    Ok(Hole::Circle { center_m: [v[0], v[1]], radius_m: v[2] })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parsers_reject_bad_numbers() {
        assert_eq!(parse_extent("100").unwrap(), [100.0, 100.0]);
        assert_eq!(parse_extent("100,50").unwrap(), [100.0, 50.0]);
        assert!(parse_extent("-5").is_err());
        assert!(parse_extent("nan").is_err());
        assert!(parse_extent("1,2,3").is_err());
        assert!(parse_hole_circle("1,2,0").is_err());
        assert!(parse_hole_circle("1,2").is_err());
    }

    #[test]
    fn the_automatic_range_holds_a_nearly_flat_map() {
        // 0.8 m of relief: widened to 1 m around its middle, 0.4 m, so both
        // ends stay inside (-0.1..0.9), not cut at lo + 0.5.
        let g = GridSource::new(2, 1, vec![0.0, 0.8], [10.0, 10.0]);
        let [lo, hi] = auto_range(&g);
        assert!((lo + 0.1).abs() < 1e-4 && (hi - 0.9).abs() < 1e-4, "{lo}..{hi}");
        // Real relief keeps its own range (a ramp does not overshoot).
        let g = GridSource::new(3, 1, vec![0.0, 50.0, 100.0], [10.0, 10.0]);
        let [lo, hi] = auto_range(&g);
        assert!(lo.abs() < 1e-3 && (hi - 100.0).abs() < 1e-3, "{lo}..{hi}");
    }

    #[test]
    fn default_world_and_conflicts() {
        let w = WorldArgs::default().load().unwrap();
        assert_eq!(w.desc, WorldDesc::default());
        let both = WorldArgs { scene: Some("a.toml".into()), heightmap: Some("b.png".into()), ..Default::default() };
        assert!(both.load().is_err());
        let no_extent = WorldArgs { heightmap: Some("b.png".into()), ..Default::default() };
        assert!(format!("{:#}", no_extent.load().err().unwrap()).contains("--extent"));
    }
}
