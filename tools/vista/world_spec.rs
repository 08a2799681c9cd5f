//! A world resolved from the arguments and the scene ([`WorldSpec`]), its
//! height map not yet read, and its loading into a [`LoadedWorld`].

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::Result;
use vista::render::Effects;
use vista::world::{
    BakeSettings, GeoTiffSource, HeightSource, Hole, Limits, Png16Source, ProceduralSource, WorldDesc, WorldPlan,
};

use crate::heightmap_files::{auto_range, open_heightmap, GivenRange, MapKind, TIMING_CORNER};
use crate::world_args::{input_error, LoadedWorld};

/// A world resolved from the arguments, its height map not yet read: enough
/// for the plan; nothing but the scene file has been read.
pub struct WorldSpec {
    /// Geometry; a height map's height range is settled when it is opened.
    pub desc: WorldDesc,
    pub(crate) source: SpecSource,
    pub(crate) holes: Vec<Hole>,
    /// The scene's stamps, placed relative to the world's corner.
    pub(crate) stamps: Vec<crate::scene::SceneStampSpec>,
    /// The scene's decals, relative to the world's corner (textures unread).
    pub(crate) decals: crate::scene::SceneDecals,
    pub(crate) assets: Vec<vista::effects::assets::Asset>,
    pub(crate) effects: Effects,
    pub(crate) origin_m: [f64; 2],
    pub limits: Limits,
    /// Payload format and the scene's material rules.
    pub bake: BakeSettings,
}

pub(crate) enum SpecSource {
    Procedural { seed: u64, terraces: bool },
    Heightmap { path: PathBuf, kind: MapKind, height_range: Option<GivenRange>, clamp: bool },
}

/// A hole that misses the world cuts nothing: one line each, in the
/// user's coordinates, so a typo in a hole is not silently dropped.
pub(crate) fn note_holes_outside(holes: &[Hole], desc: &WorldDesc, origin_m: [f64; 2]) {
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
            SpecSource::Procedural { seed, terraces } => procedural_label(*seed, *terraces),
            SpecSource::Heightmap { path, .. } => path.display().to_string(),
        }
    }

    /// Whether the heights come from the procedural generator.
    pub fn is_procedural(&self) -> bool {
        matches!(self.source, SpecSource::Procedural { .. })
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
            SpecSource::Procedural { seed, terraces } => {
                let d = self.desc;
                let source = ProceduralSource::new(*seed, d.extent_m, d.height_range_m).map_err(input_error)?;
                (d, Arc::new(source.with_terraces(*terraces)), procedural_label(*seed, *terraces))
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

/// Reads each decal texture once.
pub(crate) fn load_decals(d: &crate::scene::SceneDecals) -> Result<vista::effects::virtual_texture::decals::DecalSet> {
    use vista::effects::virtual_texture::decals::{DecalSet, DecalTexture};
    let textures = d.textures.iter().map(|p| DecalTexture::load(p)).collect::<Result<Vec<_>, _>>()?;
    let set = DecalSet { textures: textures.into(), decals: d.decals.clone() };
    set.check()?;
    Ok(set)
}

/// How a procedural world names itself in what vista prints.
fn procedural_label(seed: u64, terraces: bool) -> String {
    let terraced = if terraces { ", terraced" } else { "" };
    format!("procedural (seed {seed}{terraced})")
}
