//! World selection shared by every command that needs terrain: a scene file,
//! a height map, or (nothing given) the default procedural world.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{bail, Context as _, Result};
use clap::Args;
use vista::render::Effects;
use vista::world::{
    BakeSettings, GeoTiffInfo, GeoTiffSource, HeightSource, Hole, Limits, PayloadFormat, WorldDesc, WorldError,
    DEFAULT_MAX_SECTORS_PER_SIDE, MAX_LOD_COUNT, MAX_SECTORS_PER_SIDE,
};

use crate::heightmap_files::*;
use crate::scene::{Scene, SceneSource, SceneWorld};
use crate::world_spec::{note_holes_outside, SpecSource, WorldSpec};

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
    /// Set by a command that derives a world from the user's (not an
    /// option): it says itself what it changed, so the "replaces the
    /// scene's" notes would name options the user never gave.
    #[arg(skip)]
    pub derived: bool,
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
    /// Each stamp's id and box, in order: what a scene edit compares (in
    /// `vista view`, so unread in a build without the window).
    #[cfg_attr(not(feature = "view"), allow(dead_code))]
    pub stamps: Vec<(u64, [f64; 4])>,
    /// The scene's decals (world metres) with their textures read.
    pub decals: vista::effects::virtual_texture::decals::DecalSet,
    /// The scene's assets (world metres).
    pub assets: Vec<vista::effects::assets::Asset>,
}

/// Refuses a slot budget the renderer cannot use for `world`, in the
/// option's terms and before any GPU work: slots are 11-bit (at most
/// `MAX_SLOTS`), and the roots, always resident, may hold at most a quarter
/// of them (the plan's rule).
pub fn check_slots(slots: u32, world: &WorldDesc) -> Result<()> {
    let max = vista::terrain::quadtree::MAX_SLOTS;
    let [x, y] = world.grid(world.root_lod());
    let roots = u64::from(x) * u64::from(y);
    let min = (4 * roots).max(1);
    if !(min..=u64::from(max)).contains(&u64::from(slots)) {
        let why = if u64::from(slots) > u64::from(max) {
            format!("slots are {}-bit", vista::shaders::consts::SLOT_BITS)
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
        let (heightmap, geotiff) = self.heightmap_file(w)?;
        let extent = self.extent.or(w.extent.map(|e| e.xy())).or(geotiff.as_ref().and_then(GeoTiffInfo::extent_m));
        let height_range = match (&self.height_range, w.height_range) {
            (Some(v), _) => Some(GivenRange::new([v[0], v[1]], "--height-range")),
            (None, Some(r)) => Some(GivenRange::new(r, "the scene's height_range")),
            (None, None) => None,
        };
        let clamp = self.clamp_heights || w.clamp_heights;
        let clamp_name = if self.clamp_heights { "--clamp-heights" } else { "the scene's clamp_heights" };
        if self.scene.is_some() && !self.derived {
            self.note_overrides(&scene);
        }
        let defaults = WorldDesc::default();
        // A GeoTIFF's posts are its samples: its pixel size is the spacing
        // that draws them (as a PNG world at its pixel size), not 0.5 m
        // over a 90 m DEM, which would plan thousands of times the nodes.
        // A map under a node's 128 quads a side halves it until one fits
        // (the vertices still include every post).
        let geotiff_spacing = geotiff.as_ref().and_then(|g| Some((g.pixel_m?, extent?))).map(|(p, e)| {
            let mut s = p[0].min(p[1]);
            while e[0].min(e[1]) < s * f64::from(vista::world::NODE_QUADS) && s > f64::MIN_POSITIVE {
                s *= 0.5;
            }
            s
        });
        let spacing_m = self.spacing.or(w.spacing).or(geotiff_spacing).unwrap_or(defaults.spacing_m);
        let seed = self.seed.or(w.seed).unwrap_or(1);
        let origin_m = self.origin_m(&scene, geotiff.as_ref())?;
        let names = self.field_names(w, height_range);
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

        let given = DescInputs {
            extent,
            lods: self.lods.or(w.lods),
            height_range,
            spacing_m,
            names: &names,
            clamp,
            clamp_name,
        };
        let (desc, source) = match heightmap {
            None => given.procedural(seed, w.terraces)?,
            Some((path, what)) => given.heightmap(path, what, geotiff.is_some())?,
        };
        let origin_name = if self.origin.is_some() { "--origin" } else { "the scene's origin" };
        crate::world_notes::check_far_corner(&desc, origin_m, origin_name)?;
        if let SpecSource::Heightmap { path, kind, .. } = &source {
            crate::world_notes::note_spacing_beyond_map(path, *kind, geotiff.as_ref(), &desc);
        }
        note_holes_outside(&holes, &desc, origin_m);
        if let Some(path) = &self.scene {
            crate::placements::check_inside(path, &stamps, &decals.decals, &assets, &desc, origin_m)?;
        }
        if let Some(map) = &scene.effects.control_map {
            crate::placements::note_coarse_control_map(map, &desc);
        }
        let max_sectors_per_side = self.max_sectors.unwrap_or(DEFAULT_MAX_SECTORS_PER_SIDE);
        let limits = Limits { max_sectors_per_side, ..Limits::default() };
        let bake = BakeSettings { format: self.payload, materials: scene.material_rules, control: None };
        Ok(WorldSpec { desc, source, holes, stamps, decals, assets, effects: scene.effects, origin_m, limits, bake })
    }

    /// The height map file (and who named it), with a GeoTIFF's header.
    fn heightmap_file(&self, w: &SceneWorld) -> Result<(Option<HeightmapFile>, Option<GeoTiffInfo>)> {
        let heightmap = match (&self.heightmap, &w.source) {
            (Some(p), _) => Some((p.clone(), "--heightmap")),
            (None, SceneSource::Path(p)) => Some((p.clone(), "the scene's source")),
            (None, SceneSource::Procedural) => None,
        };
        if let (true, Some((path, _))) = (w.terraces, &heightmap) {
            let path = path.display();
            bail!("the scene's terraces shape the procedural world; {path} has its own ground: drop terraces");
        }
        // A GeoTIFF places itself: extent and origin from its tags unless given.
        let geotiff = match &heightmap {
            Some((p, _)) if magic(p).is_some_and(|m| TIFF_MAGIC.contains(&m)) => Some(GeoTiffSource::read_header(p)?),
            _ => None,
        };
        Ok((heightmap, geotiff))
    }

    fn field_names(&self, w: &SceneWorld, height_range: Option<GivenRange>) -> FieldNames {
        FieldNames {
            extent: given_as(self.extent.is_none() && w.extent.is_some(), "--extent", "extent"),
            spacing: given_as(self.spacing.is_none() && w.spacing.is_some(), "--spacing", "spacing"),
            lods: given_as(self.lods.is_none() && w.lods.is_some(), "--lods", "lods"),
            height_range: height_range.map(|r| r.to_string()),
        }
    }

    /// Where the world's corner lies: given, the scene's or a GeoTIFF's.
    fn origin_m(&self, scene: &Scene, geotiff: Option<&GeoTiffInfo>) -> Result<[f64; 2]> {
        let w = &scene.world;
        let origin_m = self.origin.or(w.origin).or(geotiff.and_then(|g| g.origin_m)).unwrap_or([0.0, 0.0]);
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
        Ok(origin_m)
    }
}

/// A height map's path and who named it (an option or the scene).
type HeightmapFile = (PathBuf, &'static str);

/// The world's geometry as given, before a height source is chosen.
struct DescInputs<'a> {
    extent: Option<[f64; 2]>,
    lods: Option<u32>,
    height_range: Option<GivenRange>,
    spacing_m: f64,
    names: &'a FieldNames,
    clamp: bool,
    clamp_name: &'static str,
}

impl DescInputs<'_> {
    /// Without a count, the extent decides (a small number of roots).
    fn lods_for_extent(&self, e: Option<[f64; 2]>) -> u32 {
        WorldDesc::lods_for(e.unwrap_or(WorldDesc::default().extent_m), self.spacing_m)
    }

    /// The default procedural world's geometry.
    fn procedural(&self, seed: u64, terraces: bool) -> Result<(WorldDesc, SpecSource)> {
        let defaults = WorldDesc::default();
        let (extent, height_range, spacing_m, clamp_name) =
            (self.extent, self.height_range, self.spacing_m, self.clamp_name);
        let extent_m = extent.unwrap_or(defaults.extent_m);
        let lod_count = self.lods.unwrap_or_else(|| self.lods_for_extent(extent));
        let height_range_m = height_range.map_or(defaults.height_range_m, |r| r.range);
        let desc = WorldDesc { extent_m, height_range_m, spacing_m, lod_count, ..WorldDesc::default() };
        check_desc(&desc, self.names)?;
        if self.clamp {
            bail!("{clamp_name} clamps an EXR or GeoTIFF height map's data; the procedural world has none: drop it");
        }
        Ok((desc, SpecSource::Procedural { seed, terraces }))
    }

    /// A height map's geometry, checked before the file is opened.
    fn heightmap(&self, path: PathBuf, what: &str, geotiff: bool) -> Result<(WorldDesc, SpecSource)> {
        let (extent, height_range, spacing_m, clamp, clamp_name) =
            (self.extent, self.height_range, self.spacing_m, self.clamp, self.clamp_name);
        let Some(extent_m) = extent else {
            let untagged = if geotiff { " (the GeoTIFF has no pixel scale tag)" } else { "" };
            bail!("{what} {} needs --extent METRES (the world size it covers){untagged}", path.display());
        };
        let height_range_m = height_range.map_or([0.0, 1.0], |r| r.range);
        let lod_count = self.lods.unwrap_or_else(|| self.lods_for_extent(Some(extent_m)));
        let desc = WorldDesc { extent_m, height_range_m, spacing_m, lod_count, ..WorldDesc::default() };
        // An absurd world fails before the file is opened.
        check_desc(&desc, self.names)?;
        let kind = heightmap_kind(&path, what, height_range)?;
        if kind == MapKind::Png {
            // Its header and chunk list (no pixels): commands that never
            // decode it (memory, plans) refuse a broken file as render does.
            vista::world::Png16Source::header(&path).map_err(input_error)?;
        }
        if clamp && kind == MapKind::Png {
            // (a GeoTIFF's data is clamped like an EXR's)
            bail!(
                "{clamp_name} clamps an EXR or GeoTIFF height map's data; {} is a PNG, whose 0..65535 always \
                 maps into its height range: drop it",
                path.display()
            );
        }
        Ok((desc, SpecSource::Heightmap { path, kind, height_range, clamp }))
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

/// A library error; a world over the device's limits (found when the
/// renderer is made) is the user's to fix, like any other plan refusal.
pub fn plan_error_is_input(e: vista::Error) -> anyhow::Error {
    match e {
        vista::Error::World(WorldError::Plan(p)) => anyhow::Error::new(crate::InputError(p.to_string())),
        e => e.into(),
    }
}

pub(crate) fn input_error(e: impl Into<anyhow::Error>) -> anyhow::Error {
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
    use vista::world::GridSource;

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
