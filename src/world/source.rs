//! The height source abstraction and the shared bicubic grid sampler used
//! by the image-backed sources.

use super::hash::Fnv64;

/// Anything that can answer "how high is the ground here". Sampled from
/// many bake threads at once, hence `Send + Sync`.
pub trait HeightSource: Send + Sync {
    /// Height in metres at a world position. Positions outside the source's
    /// extent clamp to its edge.
    fn sample(&self, x_m: f64, y_m: f64) -> f32;

    /// Changes whenever the content or parameters change; part of the
    /// cache key, so stale baked nodes are never reused.
    fn id_hash(&self) -> u64;

    /// Whether the source has no data at this point (a DEM's no-data
    /// samples): the bake cuts a hole there, as for a hole shape.
    fn is_hole(&self, _x_m: f64, _y_m: f64) -> bool {
        false
    }

    /// Whether any point is a hole (the renderer then builds its hole path).
    fn has_holes(&self) -> bool {
        false
    }

    /// A hash of everything that decides [`Self::sample`] and
    /// [`Self::is_hole`] inside `bounds_m` ([min x, min y, max x, max y],
    /// metres): two sources that agree there hash alike, so a node's cache
    /// key changes only with what touches it (an edit elsewhere rebakes
    /// nothing here). The default, the whole source's [`Self::id_hash`], is
    /// right for sources with no locality (a procedural function).
    fn region_hash(&self, _bounds_m: [f64; 4]) -> u64 {
        self.id_hash()
    }

    /// The id of the source before its edits (a [`super::StampedSource`]'s
    /// base): caches keep one folder per base, so edits share it.
    fn base_id_hash(&self) -> u64 {
        self.id_hash()
    }

    /// Bounds (lo, hi metres) of every height [`Self::sample`] returns
    /// inside `bounds_m`, where the source can say without sampling; `None`:
    /// only that they lie in the world's height range.
    fn range_in(&self, _bounds_m: [f64; 4]) -> Option<[f32; 2]> {
        None
    }

    /// What shaped the ground at a point, for the materials: a source that
    /// knows its water and rockfall says so (the procedural generator's
    /// erosion); the default knows nothing.
    fn ground(&self, _x_m: f64, _y_m: f64) -> Ground {
        Ground::default()
    }

    /// `out[i] = sample(xs[i], y_m)`, bit for bit; a source may share work
    /// between the neighbouring points of a row.
    fn sample_row(&self, xs: &[f64], y_m: f64, out: &mut [f32]) {
        for (x, o) in xs.iter().zip(out) {
            *o = self.sample(*x, y_m);
        }
    }
}

/// What water and gravity left at a point, each 0..1.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ground {
    /// How much ground drains through here: 0 on a ridge, 1 on a valley's
    /// floor.
    pub wet: f32,
    /// How much rock slid here from steeper ground above (scree).
    pub talus: f32,
}

/// A grid of heights covering a world rectangle, sampled with Catmull-Rom
/// bicubic interpolation. Pixel (i, j) is an area sample whose centre lies at
/// `((i + 0.5) * extent_x / w, extent_y - (j + 0.5) * extent_y / h)`: row 0
/// is the north edge, as in every image format. Catmull-Rom interpolates, so
/// sampling at a pixel centre returns the pixel exactly.
#[derive(Clone, Debug)]
pub struct GridSource {
    width: usize,
    height: usize,
    heights: Samples,
    extent_m: [f64; 2],
    id: u64,
    /// One bit per pixel with no data (a hole), if any pixel has none.
    no_data: Option<Vec<u64>>,
}

/// 16-bit maps stay 16-bit: a 16384² map is 512 MiB as read, 1 GiB as f32,
/// and each height is decoded where it is sampled.
#[derive(Clone, Debug)]
enum Samples {
    F32(Vec<f32>),
    /// Metres = `lo + value * scale`, the PNG16 mapping of 0..65535.
    U16 {
        values: Vec<u16>,
        lo: f32,
        scale: f32,
    },
}

impl Samples {
    #[inline]
    fn get(&self, k: usize) -> f32 {
        match self {
            Samples::F32(v) => v[k],
            Samples::U16 { values, lo, scale } => lo + f32::from(values[k]) * scale,
        }
    }
}

fn grid_hash(width: usize, height: usize, extent_m: [f64; 2]) -> Fnv64 {
    Fnv64::new().u64(width as u64).u64(height as u64).f64(extent_m[0]).f64(extent_m[1])
}

impl GridSource {
    /// `heights` holds `width * height` finite values, row 0 north. The
    /// loaders validate their input before calling this, so a mismatch here
    /// is a programmer error.
    pub fn new(width: usize, height: usize, heights: Vec<f32>, extent_m: [f64; 2]) -> Self {
        assert!(width > 0 && height > 0, "empty height grid");
        assert_eq!(heights.len(), width * height, "height grid size mismatch");
        let mut h = grid_hash(width, height, extent_m);
        for v in &heights {
            h = h.bytes(&v.to_le_bytes());
        }
        GridSource { width, height, id: h.finish(), heights: Samples::F32(heights), extent_m, no_data: None }
    }

    /// 16-bit `values` (row 0 north) whose 0..65535 map linearly onto
    /// `range_m`; kept as they are, decoded per sample.
    pub fn from_u16(width: usize, height: usize, values: Vec<u16>, range_m: [f32; 2], extent_m: [f64; 2]) -> Self {
        assert!(width > 0 && height > 0, "empty height grid");
        assert_eq!(values.len(), width * height, "height grid size mismatch");
        let [lo, hi] = range_m;
        let scale = (hi - lo) / 65535.0;
        let h = grid_hash(width, height, extent_m).f64(f64::from(lo)).f64(f64::from(scale));
        // Hashed 2 bytes at a time (as the values are stored): half the
        // work of the f32 copy this replaces.
        let id = values.iter().fold(h, |h, v| h.bytes(&v.to_le_bytes())).finish();
        GridSource { width, height, id, heights: Samples::U16 { values, lo, scale }, extent_m, no_data: None }
    }

    /// Marks the pixels whose bit is set in `mask` (row-major, 64 a word)
    /// as holes; their heights should already be filled from valid
    /// neighbours, which the resampler then reads near the hole's edge.
    pub fn with_no_data(mut self, mask: Vec<u64>) -> Self {
        assert_eq!(mask.len(), (self.width * self.height).div_ceil(64), "no-data mask size mismatch");
        if mask.iter().all(|&w| w == 0) {
            return self;
        }
        self.id = mask.iter().fold(Fnv64::new().u64(self.id), |h, w| h.u64(*w)).finish();
        self.no_data = Some(mask);
        self
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    /// Raw value of pixel (i, j), row 0 north.
    pub fn pixel(&self, i: usize, j: usize) -> f32 {
        self.heights.get(j * self.width + i)
    }

    /// World position of the centre of pixel (i, j).
    pub fn pixel_center_m(&self, i: usize, j: usize) -> [f64; 2] {
        let [dx, dy] = self.pixel_size_m();
        [(i as f64 + 0.5) * dx, self.extent_m[1] - (j as f64 + 0.5) * dy]
    }

    /// Metres per pixel along x and y: the distance between posts.
    pub fn pixel_size_m(&self) -> [f64; 2] {
        [self.extent_m[0] / self.width as f64, self.extent_m[1] / self.height as f64]
    }

    /// Pixel columns and rows (inclusive, clamped) whose values
    /// [`HeightSource::sample`] or [`HeightSource::is_hole`] read anywhere in
    /// `bounds_m`: the Catmull-Rom taps one pixel before and two after.
    pub fn pixels_under(&self, bounds_m: [f64; 4]) -> [usize; 4] {
        let [dx, dy] = self.pixel_size_m();
        let ey = self.extent_m[1];
        let clamp_i = |v: f64, n: usize| (v.max(0.0) as usize).min(n - 1);
        let i0 = clamp_i((bounds_m[0] / dx - 0.5).floor() - 1.0, self.width);
        let i1 = clamp_i((bounds_m[2] / dx).floor() + 2.0, self.width);
        let j0 = clamp_i(((ey - bounds_m[3]) / dy - 0.5).floor() - 1.0, self.height);
        let j1 = clamp_i(((ey - bounds_m[1]) / dy).floor() + 2.0, self.height);
        [i0, j0, i1, j1]
    }

    fn at(&self, i: isize, j: isize) -> f32 {
        let i = i.clamp(0, self.width as isize - 1) as usize;
        let j = j.clamp(0, self.height as isize - 1) as usize;
        self.heights.get(j * self.width + i)
    }
}

/// Catmull-Rom weights for the 4 taps around fractional position `t`.
pub(super) const fn catmull_rom(t: f64) -> [f64; 4] {
    let t2 = t * t;
    let t3 = t2 * t;
    [0.5 * (-t3 + 2.0 * t2 - t), 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0), 0.5 * (-3.0 * t3 + 4.0 * t2 + t), 0.5 * (t3 - t2)]
}

impl HeightSource for GridSource {
    fn sample(&self, x_m: f64, y_m: f64) -> f32 {
        let [dx, dy] = self.pixel_size_m();
        // Continuous pixel coordinates, clamped to the outermost centres so
        // outside points take the edge value.
        let u = (x_m / dx - 0.5).clamp(0.0, (self.width - 1) as f64);
        let v = ((self.extent_m[1] - y_m) / dy - 0.5).clamp(0.0, (self.height - 1) as f64);
        let (u0, v0) = (u.floor(), v.floor());
        let (wu, wv) = (catmull_rom(u - u0), catmull_rom(v - v0));
        let (iu, iv) = (u0 as isize, v0 as isize);
        let mut sum = 0.0;
        for (b, wy) in wv.iter().enumerate() {
            let j = iv + b as isize - 1;
            let row: f64 = wu.iter().enumerate().map(|(a, wx)| wx * f64::from(self.at(iu + a as isize - 1, j))).sum();
            sum += wy * row;
        }
        sum as f32
    }

    fn id_hash(&self) -> u64 {
        self.id
    }

    /// The pixel containing the point (pixels are areas around their posts).
    fn is_hole(&self, x_m: f64, y_m: f64) -> bool {
        let Some(mask) = &self.no_data else { return false };
        let [dx, dy] = self.pixel_size_m();
        let i = ((x_m / dx).floor().max(0.0) as usize).min(self.width - 1);
        let j = (((self.extent_m[1] - y_m) / dy).floor().max(0.0) as usize).min(self.height - 1);
        let k = j * self.width + i;
        mask[k / 64] >> (k % 64) & 1 == 1
    }

    fn has_holes(&self) -> bool {
        self.no_data.is_some()
    }

    /// The pixels (and no-data bits) under the region, with the grid's
    /// geometry and encoding.
    fn region_hash(&self, bounds_m: [f64; 4]) -> u64 {
        let [i0, j0, i1, j1] = self.pixels_under(bounds_m);
        let mut h = grid_hash(self.width, self.height, self.extent_m);
        if let Samples::U16 { lo, scale, .. } = &self.heights {
            h = h.f64(f64::from(*lo)).f64(f64::from(*scale));
        }
        h = [i0, j0, i1, j1].iter().fold(h, |h, v| h.u64(*v as u64));
        for j in j0..=j1 {
            for i in i0..=i1 {
                let k = j * self.width + i;
                h = match &self.heights {
                    Samples::F32(v) => h.bytes(&v[k].to_le_bytes()),
                    Samples::U16 { values, .. } => h.bytes(&values[k].to_le_bytes()),
                };
                if let Some(mask) = &self.no_data {
                    h = h.u64(mask[k / 64] >> (k % 64) & 1);
                }
            }
        }
        h.finish()
    }

    fn range_in(&self, bounds_m: [f64; 4]) -> Option<[f32; 2]> {
        let [i0, j0, i1, j1] = self.pixels_under(bounds_m);
        Some(self.resampled_range_of([i0, j0, i1, j1]))
    }
}
