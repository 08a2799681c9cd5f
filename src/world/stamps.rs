//! Stamps (REDengine 3's most used authoring tool): a height map pasted
//! onto the world at a position, with rotation, size, a height scale and
//! offset, a blend mode and a falloff, applied in order on top of the base
//! source. A [`StampedSource`] is itself a [`HeightSource`], so the bake,
//! the plan, the error tree, the reference ray-caster and (through the
//! baked payloads) `terrain_sample` all see the stamped world.
//!
//! A stamp's map is normalised to 0..1 (a PNG16 by 0..65535, an EXR by its
//! own lowest..highest pixel); its height at a point is `offset + height *
//! value`, sampled Catmull-Rom like every grid. Inside the stamp's square,
//! `falloff` metres from its edge, the blend weight rises from 0 to 1
//! (smoothstep); outside the square the stamp does nothing.

use std::sync::Arc;

use std::path::Path;

use super::error::{Result, WorldError};
use super::exr_source::ExrSource;
use super::hash::Fnv64;
use super::png16::Png16Source;
use super::source::{GridSource, HeightSource};

/// A stamp's map, normalised to 0..1 over a square `size_m` a side: a
/// 16-bit PNG by 0..65535, an EXR by its own lowest..highest pixel (a flat
/// one is 0 everywhere). Checked like any height map before it is decoded.
pub fn load_stamp_map(path: &Path, size_m: f64) -> Result<GridSource> {
    let extent = [size_m; 2];
    let mut magic = [0u8; 4];
    let read = std::fs::File::open(path).and_then(|mut f| std::io::Read::read_exact(&mut f, &mut magic));
    read.map_err(|e| WorldError::io(path, e))?;
    if magic == [0x76, 0x2f, 0x31, 0x01] {
        let exr = ExrSource::open(path, extent)?;
        let g = exr.grid();
        let fit = g.fit([0.0, 0.0]);
        let span = fit.max - fit.min;
        let (w, h) = (g.width(), g.height());
        let values =
            (0..w * h).map(|k| if span > 0.0 { (g.pixel(k % w, k / w) - fit.min) / span } else { 0.0 }).collect();
        return Ok(GridSource::new(w, h, values, extent));
    }
    Ok(Png16Source::open(path, extent, [0.0, 1.0])?.into_grid())
}

/// How a stamp's height `s` combines with the height `h` under it, at
/// blend weight `w` (0..1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StampBlend {
    /// `h + w (s - h)`: the stamp's terrain replaces the world's.
    Replace,
    /// `h + w s`: a mountain (or, with a negative offset, a crater) on top.
    Add,
    /// `h + w (max(h, s) - h)`: raises the ground to the stamp, never lowers it.
    Max,
    /// `h + w (min(h, s) - h)`: digs the ground to the stamp, never raises it.
    Min,
}

impl StampBlend {
    pub const ALL: [StampBlend; 4] = [StampBlend::Replace, StampBlend::Add, StampBlend::Max, StampBlend::Min];

    /// The scene-file word.
    pub fn name(self) -> &'static str {
        match self {
            StampBlend::Replace => "replace",
            StampBlend::Add => "add",
            StampBlend::Max => "max",
            StampBlend::Min => "min",
        }
    }

    pub fn from_name(name: &str) -> Option<StampBlend> {
        StampBlend::ALL.into_iter().find(|b| b.name() == name)
    }

    /// The blended height.
    pub fn apply(self, h: f64, s: f64, w: f64) -> f64 {
        match self {
            StampBlend::Replace => h + w * (s - h),
            StampBlend::Add => h + w * s,
            StampBlend::Max => h + w * (h.max(s) - h),
            StampBlend::Min => h + w * (h.min(s) - h),
        }
    }

    /// Bounds of [`Self::apply`] for `h` in `under` and `s` in `stamp`, over
    /// every weight in 0..1 (each result is monotone in h, s and w between
    /// their ends).
    fn range(self, under: [f64; 2], stamp: [f64; 2]) -> [f64; 2] {
        let mut out = [f64::INFINITY, f64::NEG_INFINITY];
        for h in under {
            for s in stamp {
                for w in [0.0, 1.0] {
                    let v = self.apply(h, s, w);
                    out = [out[0].min(v), out[1].max(v)];
                }
            }
        }
        out
    }
}

/// Where and how a stamp is pasted (world metres and degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StampPlacement {
    /// The centre of the stamp's square.
    pub center_m: [f64; 2],
    /// The square's side.
    pub size_m: f64,
    /// Counter-clockwise seen from above (x east, y north).
    pub rotation_deg: f64,
    /// Metres spanned by the map's full 0..1.
    pub height_m: f64,
    /// Metres added to every height of the stamp.
    pub offset_m: f64,
    pub blend: StampBlend,
    /// Width of the band inside the square's edge over which the weight
    /// rises from 0 to 1; 0: a hard edge.
    pub falloff_m: f64,
}

impl StampPlacement {
    /// One-line error for a placement that cannot be meant.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(WorldError::InvalidStamp(m));
        if !self.center_m.iter().all(|v| v.is_finite()) {
            return bad(format!("center {:?} must be two finite numbers (metres)", self.center_m));
        }
        if !(self.size_m.is_finite() && self.size_m > 0.0) {
            return bad(format!("size must be a positive number of metres, got {}", self.size_m));
        }
        for (name, v) in [("rotation_deg", self.rotation_deg), ("height", self.height_m), ("offset", self.offset_m)] {
            if !v.is_finite() {
                return bad(format!("{name} must be finite, got {v}"));
            }
        }
        if !(self.falloff_m.is_finite() && (0.0..=0.5 * self.size_m).contains(&self.falloff_m)) {
            return bad(format!(
                "falloff must be 0 to half the size ({} m), got {}",
                0.5 * self.size_m,
                self.falloff_m
            ));
        }
        Ok(())
    }

    /// A point's position in the stamp's square (metres from its
    /// south-west corner along its own axes, 0..size) and its blend weight
    /// there; `None` outside the square.
    pub fn local(&self, x_m: f64, y_m: f64) -> Option<([f64; 2], f64)> {
        self.local_rotated(x_m, y_m, self.rotation())
    }

    /// cos and sin of the rotation.
    fn rotation(&self) -> [f64; 2] {
        let a = self.rotation_deg.to_radians();
        [a.cos(), a.sin()]
    }

    /// [`Self::local`] with the rotation's cos and sin given.
    fn local_rotated(&self, x_m: f64, y_m: f64, [c, s]: [f64; 2]) -> Option<([f64; 2], f64)> {
        let (dx, dy) = (x_m - self.center_m[0], y_m - self.center_m[1]);
        // Into the square's frame: rotated back by the stamp's rotation.
        let (u, v) = (c * dx + s * dy, -s * dx + c * dy);
        let half = 0.5 * self.size_m;
        let edge = half - u.abs().max(v.abs());
        if edge < 0.0 {
            return None;
        }
        let w = if self.falloff_m > 0.0 {
            let t = (edge / self.falloff_m).min(1.0);
            t * t * (3.0 - 2.0 * t)
        } else {
            1.0
        };
        Some(([u + half, v + half], w))
    }

    /// The axis-aligned box ([min x, min y, max x, max y]) holding the
    /// rotated square: nothing outside it changes.
    pub fn bounds_m(&self) -> [f64; 4] {
        let [c, s] = self.rotation();
        let half = 0.5 * self.size_m * (c.abs() + s.abs());
        let [cx, cy] = self.center_m;
        [cx - half, cy - half, cx + half, cy + half]
    }

    /// Whether the square's box touches `b`.
    pub fn overlaps(&self, b: [f64; 4]) -> bool {
        let s = self.bounds_m();
        s[0] <= b[2] && s[2] >= b[0] && s[1] <= b[3] && s[3] >= b[1]
    }

    /// A hash of where and how the stamp is pasted.
    pub fn hash(&self) -> u64 {
        [
            self.center_m[0],
            self.center_m[1],
            self.size_m,
            self.rotation_deg,
            self.height_m,
            self.offset_m,
            self.falloff_m,
        ]
        .iter()
        .fold(Fnv64::new(), |h, v| h.f64(*v))
        .u64(self.blend as u64)
        .finish()
    }
}

/// One stamp: its placement and its map (values 0..1).
#[derive(Clone, Debug)]
pub struct Stamp {
    pub placement: StampPlacement,
    /// The map over its own square, `size_m` a side, values normalised.
    map: GridSource,
    /// The map's normalised range as the resampler can reach it.
    map_range: [f64; 2],
    /// cos and sin of the rotation, once (every sample needs them).
    rot: [f64; 2],
    id: u64,
}

impl Stamp {
    /// `map` holds the normalised values (0..1) over the stamp's square
    /// (extent `size_m` a side): [`load_stamp_map`] makes one.
    pub fn new(placement: StampPlacement, map: GridSource) -> Result<Stamp> {
        placement.validate()?;
        let extent = [map.pixel_size_m()[0] * map.width() as f64, map.pixel_size_m()[1] * map.height() as f64];
        let rel = |a: f64| (a - placement.size_m).abs() <= 1e-9 * placement.size_m;
        assert!(rel(extent[0]) && rel(extent[1]), "a stamp map of {extent:?} m for a {} m stamp", placement.size_m);
        let r = map.resampled_range();
        let id = Fnv64::new().u64(map.id_hash()).u64(placement.hash()).finish();
        let rot = placement.rotation();
        Ok(Stamp { placement, map, map_range: [f64::from(r[0]), f64::from(r[1])], rot, id })
    }

    /// A hash of the placement and the map.
    pub fn id_hash(&self) -> u64 {
        self.id
    }

    /// The axis-aligned box holding the rotated square.
    pub fn bounds_m(&self) -> [f64; 4] {
        self.placement.bounds_m()
    }

    pub fn overlaps(&self, b: [f64; 4]) -> bool {
        self.placement.overlaps(b)
    }

    /// The stamp's height and blend weight at a world point; `None` outside
    /// its square.
    pub fn at(&self, x_m: f64, y_m: f64) -> Option<(f64, f64)> {
        let p = &self.placement;
        let ([u, v], w) = p.local_rotated(x_m, y_m, self.rot)?;
        let value = f64::from(self.map.sample(u, v));
        Some((p.offset_m + p.height_m * value, w))
    }

    /// The heights the stamp itself can take (metres).
    fn height_range(&self) -> [f64; 2] {
        let p = &self.placement;
        let ends = self.map_range.map(|v| p.offset_m + p.height_m * v);
        [ends[0].min(ends[1]), ends[0].max(ends[1])]
    }
}

/// A base source with stamps applied in order.
pub struct StampedSource {
    base: Arc<dyn HeightSource>,
    stamps: Vec<Stamp>,
    id: u64,
}

impl StampedSource {
    pub fn new(base: Arc<dyn HeightSource>, stamps: Vec<Stamp>) -> StampedSource {
        let id = stamps.iter().fold(Fnv64::new().u64(base.id_hash()), |h, s| h.u64(s.id_hash())).finish();
        StampedSource { base, stamps, id }
    }

    pub fn stamps(&self) -> &[Stamp] {
        &self.stamps
    }

    pub fn base(&self) -> &Arc<dyn HeightSource> {
        &self.base
    }

    /// The stamped height over the base height `h` at a point.
    fn stamped(&self, x_m: f64, y_m: f64, mut h: f64) -> f64 {
        for s in &self.stamps {
            if let Some((value, w)) = s.at(x_m, y_m) {
                h = s.placement.blend.apply(h, value, w);
            }
        }
        h
    }

    /// Refuses a stamp that can take the world outside `range_m` (its
    /// heights are R16 over it and would clip): for each stamp, a bound of
    /// the stamped heights over its box, from the base's bound there (or
    /// the whole range) and every earlier stamp touching the box. `Err`
    /// names the stamp (1-based, as in the scene) and how far it reaches.
    pub fn check_range(&self, range_m: [f32; 2]) -> Result<()> {
        let world = [f64::from(range_m[0]), f64::from(range_m[1])];
        for (k, stamp) in self.stamps.iter().enumerate() {
            let b = stamp.bounds_m();
            let base = self.base.range_in(b).map_or(world, |r| [f64::from(r[0]), f64::from(r[1])]);
            let under = self.stamps[..k]
                .iter()
                .filter(|s| s.overlaps(b))
                .fold(base, |r, s| s.placement.blend.range(r, s.height_range()));
            let [lo, hi] = stamp.placement.blend.range(under, stamp.height_range());
            // Within half an R16 step of the range a height rounds into it:
            // only beyond does it clip (bounds of the base carry rounding).
            let half_step = (world[1] - world[0]) / 65535.0 * 0.5;
            if lo < world[0] - half_step || hi > world[1] + half_step {
                return Err(WorldError::InvalidStamp(format!(
                    "stamp {} ({} at {:.0},{:.0}) can take the ground to {lo:.1}..{hi:.1} m, outside the world's \
                     height range {}..{} m: widen height_range or lower the stamp's height or offset",
                    k + 1,
                    stamp.placement.blend.name(),
                    stamp.placement.center_m[0],
                    stamp.placement.center_m[1],
                    range_m[0],
                    range_m[1]
                )));
            }
        }
        Ok(())
    }
}

impl HeightSource for StampedSource {
    fn sample(&self, x_m: f64, y_m: f64) -> f32 {
        self.stamped(x_m, y_m, f64::from(self.base.sample(x_m, y_m))) as f32
    }

    fn sample_row(&self, xs: &[f64], y_m: f64, out: &mut [f32]) {
        self.base.sample_row(xs, y_m, out);
        let (Some(&x0), Some(&x1)) = (xs.first(), xs.last()) else { return };
        let row = [x0.min(x1), y_m, x0.max(x1), y_m];
        if !self.stamps.iter().any(|s| s.overlaps(row)) {
            return;
        }
        for (x, o) in xs.iter().zip(out) {
            *o = self.stamped(*x, y_m, f64::from(*o)) as f32;
        }
    }

    fn id_hash(&self) -> u64 {
        self.id
    }

    fn base_id_hash(&self) -> u64 {
        self.base.base_id_hash()
    }

    fn is_hole(&self, x_m: f64, y_m: f64) -> bool {
        self.base.is_hole(x_m, y_m)
    }

    fn has_holes(&self) -> bool {
        self.base.has_holes()
    }

    /// The base's water and rockfall: a stamp reshapes heights, not where
    /// the ground's material came from.
    fn ground(&self, x_m: f64, y_m: f64) -> super::source::Ground {
        self.base.ground(x_m, y_m)
    }

    /// The base's region and the stamps whose box touches it, in order;
    /// the base's own where none does (an untouched region keeps its key).
    fn region_hash(&self, bounds_m: [f64; 4]) -> u64 {
        let base = self.base.region_hash(bounds_m);
        let mut touching = self.stamps.iter().filter(|s| s.overlaps(bounds_m)).peekable();
        if touching.peek().is_none() {
            return base;
        }
        touching.fold(Fnv64::new().u64(base), |h, s| h.u64(s.id_hash())).finish()
    }
}
