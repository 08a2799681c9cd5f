//! World selection shared by every command that needs terrain: a scene file,
//! a height map, or (nothing given) the default procedural world.

use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{bail, Context as _, Result};
use clap::Args;
use vista::render::Effects;
use vista::world::{ExrSource, HeightSource, Hole, Png16Source, ProceduralSource, WorldDesc};

use crate::scene::{Scene, SceneSource};

/// First bytes of a PNG and an OpenEXR file: files are told apart by
/// content, so a misnamed file still loads (or fails naming its real kind).
const PNG_MAGIC: [u8; 4] = [0x89, b'P', b'N', b'G'];
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// WORLD: `--scene FILE.toml` | `--heightmap FILE --extent M --height-range LO HI`
/// | nothing (the default procedural world). Values given on the command line
/// override the scene file's.
#[derive(Args, Clone, Debug, Default)]
pub struct WorldArgs {
    /// Scene file (TOML): [world] source/extent/height_range/spacing/lods/seed,
    /// [[holes]] circle = [x, y, r] or polygon = [[x, y], ...], [effects].
    #[arg(long, value_name = "FILE.toml", help_heading = "World")]
    pub scene: Option<PathBuf>,
    /// Height map: 16-bit grayscale PNG or single-channel float EXR (told
    /// apart by content). Needs --extent and, for PNG, --height-range.
    #[arg(long, value_name = "FILE", help_heading = "World")]
    pub heightmap: Option<PathBuf>,
    /// World size in metres: one number (square) or X,Y.
    #[arg(long, value_name = "METRES", value_parser = parse_extent, allow_negative_numbers = true, help_heading = "World")]
    pub extent: Option<[f64; 2]>,
    /// Heights in metres that the PNG's 0..65535 maps to; also the range of
    /// the 16-bit height encoding. Optional for EXR (taken from the data).
    #[arg(long, num_args = 2, value_names = ["LO", "HI"], allow_negative_numbers = true, help_heading = "World")]
    pub height_range: Option<Vec<f32>>,
    /// Distance between LOD-0 samples in metres [default: 0.5].
    #[arg(long, value_name = "METRES", allow_negative_numbers = true, help_heading = "World")]
    pub spacing: Option<f64>,
    /// Number of quadtree levels (1..=10) [default: 6].
    #[arg(long, value_name = "N", help_heading = "World")]
    pub lods: Option<u32>,
    /// Seed of the procedural world [default: 1].
    #[arg(long, value_name = "N", help_heading = "World")]
    pub seed: Option<u64>,
    /// Cut a circular hole into the terrain (repeatable): centre X,Y and
    /// radius R, metres.
    #[arg(long, value_name = "X,Y,R", value_parser = parse_hole_circle, allow_hyphen_values = true, help_heading = "World")]
    pub hole_circle: Vec<Hole>,
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
}

impl WorldArgs {
    /// Resolves the arguments (and the scene file, if any) into a validated
    /// world. Every failure is a one-line message naming the culprit, marked
    /// as the user's input (exit code 2).
    pub fn load(&self) -> Result<LoadedWorld> {
        self.load_inner().map_err(|e| anyhow::Error::new(crate::InputError(format!("{e:#}"))))
    }

    fn load_inner(&self) -> Result<LoadedWorld> {
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
        let extent = self.extent.or(w.extent.map(|e| e.xy()));
        let height_range = match &self.height_range {
            Some(v) => Some([v[0], v[1]]),
            None => w.height_range,
        };
        let defaults = WorldDesc::default();
        let spacing_m = self.spacing.or(w.spacing).unwrap_or(defaults.spacing_m);
        let lod_count = self.lods.or(w.lods).unwrap_or(defaults.lod_count);
        let seed = self.seed.or(w.seed).unwrap_or(1);
        let mut holes = scene.holes()?;
        holes.extend(self.hole_circle.iter().cloned());

        let (desc, source, label): (WorldDesc, Arc<dyn HeightSource>, String) = match heightmap {
            None => {
                let extent_m = extent.unwrap_or(defaults.extent_m);
                let height_range_m = height_range.unwrap_or(defaults.height_range_m);
                let desc = WorldDesc { extent_m, height_range_m, spacing_m, lod_count };
                check_desc(&desc)?;
                let source = ProceduralSource::new(seed, extent_m, height_range_m)?;
                (desc, Arc::new(source), format!("procedural (seed {seed})"))
            }
            Some((path, what)) => {
                let Some(extent_m) = extent else {
                    bail!("{what} {} needs --extent METRES (the world size it covers)", path.display());
                };
                let (desc, source) = open_heightmap(&path, what, extent_m, height_range, spacing_m, lod_count)?;
                (desc, source, path.display().to_string())
            }
        };
        Ok(LoadedWorld { desc, source, holes, effects: scene.effects, label })
    }
}

/// Validates before any file is read, so an absurd size fails at once.
fn check_desc(desc: &WorldDesc) -> Result<()> {
    let [x, y] = desc.extent_m;
    desc.validate()
        .with_context(|| format!("world of {x} x {y} m at {} m spacing with {} LODs", desc.spacing_m, desc.lod_count))
}

fn open_heightmap(
    path: &Path,
    what: &str,
    extent_m: [f64; 2],
    height_range: Option<[f32; 2]>,
    spacing_m: f64,
    lod_count: u32,
) -> Result<(WorldDesc, Arc<dyn HeightSource>)> {
    // The EXR range is only known after reading; a placeholder lets the
    // geometry be validated first.
    let probe = WorldDesc { extent_m, height_range_m: height_range.unwrap_or([0.0, 1.0]), spacing_m, lod_count };
    check_desc(&probe)?;
    let mut magic = [0u8; 4];
    let mut file = std::fs::File::open(path).with_context(|| format!("heightmap file {}", path.display()))?;
    file.read_exact(&mut magic).with_context(|| format!("heightmap file {} is too short", path.display()))?;
    if magic == PNG_MAGIC {
        let Some(range) = height_range else {
            bail!("{what} {} is a PNG: give --height-range LO HI (metres of 0 and 65535)", path.display());
        };
        let source = Png16Source::open(path, extent_m, range)?;
        Ok((probe, Arc::new(source)))
    } else if magic == EXR_MAGIC {
        let source = ExrSource::open(path, extent_m)?;
        let range = height_range.unwrap_or_else(|| data_range(&source));
        let desc = WorldDesc { height_range_m: range, ..probe };
        check_desc(&desc)?;
        Ok((desc, Arc::new(source)))
    } else {
        bail!("{what} {} is neither a PNG nor an OpenEXR file (by its first bytes)", path.display())
    }
}

/// Min..max of an EXR's heights, widened for a flat map so lo < hi.
fn data_range(source: &ExrSource) -> [f32; 2] {
    let g = source.grid();
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for j in 0..g.height() {
        for i in 0..g.width() {
            lo = lo.min(g.pixel(i, j));
            hi = hi.max(g.pixel(i, j));
        }
    }
    if hi - lo < 1.0 {
        [lo - 0.5, lo + 0.5]
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
    fn default_world_and_conflicts() {
        let w = WorldArgs::default().load().unwrap();
        assert_eq!(w.desc, WorldDesc::default());
        let both = WorldArgs { scene: Some("a.toml".into()), heightmap: Some("b.png".into()), ..Default::default() };
        assert!(both.load().is_err());
        let no_extent = WorldArgs { heightmap: Some("b.png".into()), ..Default::default() };
        assert!(format!("{:#}", no_extent.load().err().unwrap()).contains("--extent"));
    }
}
