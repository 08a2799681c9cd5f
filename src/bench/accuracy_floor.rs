//! The fewest triangles any LOD choice on vista's grids could draw for a
//! target: lower bounds printed beside each frame's triangles by
//! `vista bench accuracy`, so a table says how far the selection is from
//! the best a choice on these grids could do.
//!
//! Every triangle vista draws is one of some level's diamond-split grid (a
//! node's level, or a refinement below LOD 0), drawn in whole patches, and
//! the promise keeps every visible point's projected vertical error against
//! the finest surface within twice the target. Take, for each visible point
//! (each pixel's hit), the coarsest unit (a triangle, or a patch) holding
//! it whose visible points all keep that: any unit a drawing covers the
//! point with lies inside it. These largest units are disjoint, so a
//! drawing puts at least one unit in each, and at least as many as its
//! visible area (each pixel's ground footprint, summed) over a unit's area.
//!
//! Left out, so the numbers stay below what any drawing needs: triangles
//! outside the view or hidden, seams, slots, the promise's p99 (only its
//! maximum is asked), errors between pixel centres (the bench measures at
//! them; a renderer that guarantees its bound must cover the whole area),
//! and the footprint of pixels next to a depth edge. They are bounds for
//! these grids only: an irregular triangulation is not limited to them.

use crate::reference::{FinestSurface, ReferenceImage};
use crate::scene::view::View;
use crate::shaders::consts::REFINE_LEVELS;
use crate::world::{HeightSource, WorldDesc, PATCH_QUADS};
use glam::DVec3;
use serde::Serialize;
use std::collections::HashMap;

/// Neighbouring hits further apart in depth than this are different
/// surfaces: the footprint between them is unknown.
const SAME_SURFACE: f64 = 0.03;

/// Lower bounds of the triangles per screen pixel any LOD choice on the
/// grids draws for `view` at its target error (see the module docs).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Floors {
    /// Choosing the level per triangle.
    pub triangles: f64,
    /// Choosing it per patch, as vista does (PATCH_QUADS x PATCH_QUADS
    /// quads of one level, drawn whole): what the patch size costs.
    pub patches: f64,
    /// Not a floor: what the per-triangle rule (a restricted bintree with
    /// saturated errors, [`super::accuracy_rule`]) is expected to draw,
    /// counted the same way; None where the world's finest lattice is too
    /// large to bound on the CPU here.
    pub rule: Option<super::accuracy_rule::RuleFigure>,
}

/// A unit of one level's grid: level, cell, and for a triangle which half
/// of its diamond-split quad.
type UnitKey = (i32, i64, i64, bool);

/// A unit of LOD choice: one triangle, or one patch.
#[derive(Clone, Copy)]
enum Unit {
    Triangle,
    Patch,
}

impl Unit {
    /// Triangles drawn for it and its area in level-side-squared units.
    fn cost(self) -> (f64, f64) {
        let q = f64::from(PATCH_QUADS);
        match self {
            Unit::Triangle => (1.0, 0.5),
            Unit::Patch => (2.0 * q * q, q * q),
        }
    }

    /// The unit of `level`'s grid holding p's x and y.
    fn at(self, world: &WorldDesc, level: i32, p: DVec3) -> UnitKey {
        let side = world.spacing_m * 2f64.powi(level);
        let [ox, oy] = world.grid_origin_m;
        let (u, v) = ((p.x - ox) / side, (p.y - oy) / side);
        let (qx, qy) = (u.floor() as i64, v.floor() as i64);
        match self {
            Unit::Triangle => {
                let (fu, fv) = (u - qx as f64, v - qy as f64);
                let half = if (qx + qy).rem_euclid(2) == 0 { fv <= fu } else { fu + fv <= 1.0 };
                (level, qx, qy, half)
            }
            Unit::Patch => {
                let q = i64::from(PATCH_QUADS);
                (level, qx.div_euclid(q), qy.div_euclid(q), false)
            }
        }
    }
}

/// A visible pixel: its ground footprint (m^2; `None` next to a depth
/// edge), its hit, and its projected error (px) at each level.
pub(super) struct Seen {
    pub(super) area: Option<f64>,
    pub(super) p: DVec3,
    errors: Vec<f64>,
}

/// The floors of `view` at its target (see the module docs).
pub fn grid_floors(reference: &ReferenceImage, view: &View, world: &WorldDesc, source: &dyn HeightSource) -> Floors {
    let [w, h] = reference.size;
    assert_eq!(view.size, reference.size, "view and reference sizes differ");
    let finest = FinestSurface::new(world, source);
    let levels: Vec<i32> = (1 - REFINE_LEVELS as i32..world.lod_count as i32).collect();
    let mut seen = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            if reference.depth_m[i] <= 0.0 {
                continue;
            }
            let p = DVec3::from(reference.position_m[i]);
            let errors = levels.iter().map(|&l| projected_error_px(&finest, view, p, l)).collect();
            seen.push(Seen { area: footprint_m2(reference, view, x, y), p, errors });
        }
    }
    let limit = 2.0 * f64::from(view.target_error_px);
    let pixels = f64::from(w) * f64::from(h);
    let floor = |unit| need(&seen, world, &levels, unit, limit) / pixels;
    let rule = super::accuracy_rule::rule_triangles(&seen, view, world, source)
        .map(|r| super::accuracy_rule::RuleFigure { per_pixel: r.per_pixel / pixels, ..r });
    Floors { triangles: floor(Unit::Triangle), patches: floor(Unit::Patch), rule }
}

/// Triangles a unit of `unit_m2` holding `points` visible points whose
/// footprints add up to `seen_m2` stands for: once when it is larger than
/// their footprints (attributed whole to the unit their centre is in, they
/// would count it more than its visible area), else its seen share.
pub(super) fn units_for(unit_m2: f64, points: u32, seen_m2: f64) -> f64 {
    if unit_m2 * f64::from(points) >= seen_m2 {
        1.0
    } else {
        seen_m2 / unit_m2
    }
}

/// Triangles needed to draw `seen` in units whose visible points are all
/// within `limit` px. Each point's largest such unit (the coarsest level's
/// that fits) holds every unit a drawing could cover the point with, and
/// these largest units are disjoint (units nest, and a unit fits or not
/// for all its points): so each needs at least one unit drawn in it, and
/// at least its visible area over its own.
fn need(seen: &[Seen], world: &WorldDesc, levels: &[i32], unit: Unit, limit: f64) -> f64 {
    // Per level, the largest error of any visible point of each unit.
    let worst: Vec<HashMap<UnitKey, f64>> = levels
        .iter()
        .enumerate()
        .map(|(k, &l)| {
            let mut m = HashMap::new();
            for s in seen {
                let e = m.entry(unit.at(world, l, s.p)).or_insert(0.0f64);
                *e = e.max(s.errors[k]);
            }
            m
        })
        .collect();
    // Each point's largest fitting unit: its visible area (m^2) and the
    // points in it.
    let mut chosen: HashMap<UnitKey, (f64, u32)> = HashMap::new();
    for s in seen {
        let fits = |k: usize| worst[k][&unit.at(world, levels[k], s.p)] <= limit;
        // The finest surface itself (below every listed level) always fits.
        let level = (0..levels.len()).rev().find(|&k| fits(k)).map_or(levels[0] - 1, |k| levels[k]);
        let c = chosen.entry(unit.at(world, level, s.p)).or_insert((0.0, 0));
        *c = (c.0 + s.area.unwrap_or(0.0), c.1 + 1);
    }
    let (triangles, area) = unit.cost();
    chosen
        .iter()
        .map(|(&(level, ..), &(seen_m2, points))| {
            let side = world.spacing_m * 2f64.powi(level);
            triangles * units_for(area * side * side, points, seen_m2)
        })
        .sum()
}

/// Screen length (px) of the vertical segment at p's x and y between
/// `level`'s surface and the finest one; infinite where it does not project.
fn projected_error_px(finest: &FinestSurface, view: &View, p: DVec3, level: i32) -> f64 {
    let (z, zl) = (f64::from(finest.sample(p.x, p.y)), finest.level(level, p.x, p.y));
    match (view.project([p.x, p.y, zl]), view.project([p.x, p.y, z])) {
        (Some((a, _)), Some((b, _))) => (a[0] - b[0]).hypot(a[1] - b[1]),
        _ => f64::INFINITY,
    }
}

/// Area (m^2, on the xy plane) of the ground pixel (x, y) sees: the
/// parallelogram of its hit to the hits right and below, and no more than
/// the tangent plane's footprint; `None` where a neighbour is missing or on
/// another surface.
fn footprint_m2(reference: &ReferenceImage, view: &View, x: u32, y: u32) -> Option<f64> {
    let [w, h] = reference.size;
    if x + 1 >= w || y + 1 >= h {
        return None;
    }
    let i = (y * w + x) as usize;
    let d = f64::from(reference.depth_m[i]);
    let same = |j: usize| {
        let dj = f64::from(reference.depth_m[j]);
        dj > 0.0 && (dj - d).abs() <= SAME_SURFACE * d
    };
    let (r, b) = (i + 1, i + w as usize);
    if !same(r) || !same(b) {
        return None;
    }
    let p = DVec3::from(reference.position_m[i]);
    let (pr, pb) = (DVec3::from(reference.position_m[r]) - p, DVec3::from(reference.position_m[b]) - p);
    let parallelogram = (pr.x * pb.y - pr.y * pb.x).abs();
    // Tangent plane: a pixel's solid angle cos^3 / f^2 at distance
    // depth / cos, on a surface of normal n seen along ray r, covers
    // depth^2 cos n_z / (f^2 |r.n|) of the xy plane.
    let ray = view.ray([f64::from(x) + 0.5, f64::from(y) + 0.5]);
    let cos = ray.dot(view.camera.basis()[0]);
    let n = DVec3::from(reference.normal[i].map(f64::from));
    let f = view.focal() * f64::from(h) / 2.0;
    let facing = ray.dot(n).abs();
    let tangent = if facing > 0.0 { d * d * cos * n.z.abs() / (f * f * facing) } else { f64::INFINITY };
    Some(parallelogram.min(tangent))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::{RayCaster, RaycastConfig};
    use crate::render::Lighting;
    use crate::scene::view::{Camera, DEFAULT_NEAR_M};

    struct Plane;
    impl HeightSource for Plane {
        fn sample(&self, _: f64, _: f64) -> f32 {
            100.0
        }
        fn id_hash(&self) -> u64 {
            7
        }
    }

    fn world() -> WorldDesc {
        WorldDesc {
            extent_m: [4096.0, 4096.0],
            height_range_m: [0.0, 400.0],
            spacing_m: 1.0,
            lod_count: 4,
            ..WorldDesc::default()
        }
    }

    fn view(camera: Camera, target: f32) -> View {
        View { camera, fov_y_deg: 60.0, size: [64, 48], target_error_px: target, near_m: DEFAULT_NEAR_M }
    }

    fn reference(source: &dyn HeightSource, world: &WorldDesc, v: &View) -> ReferenceImage {
        let cfg = RaycastConfig { colour_samples: 1, ..RaycastConfig::default() };
        RayCaster::new(source, world, cfg).image(v, &Lighting::default(), 0.4, [0.0; 4])
    }

    /// Rough hills: 8 m at 150 m, 3 m at 37 m and 0.6 m at 9 m
    /// wavelengths, so coarse levels miss them by metres.
    struct Hills;
    impl HeightSource for Hills {
        fn sample(&self, x: f64, y: f64) -> f32 {
            let wave = |a: f64, l: f64, k: f64| a * ((x + k) / l).sin() * ((y - 2.0 * k) / l).cos();
            (100.0 + wave(8.0, 24.0, 0.0) + wave(3.0, 5.9, 13.0) + wave(0.6, 1.43, 7.0)) as f32
        }
        fn id_hash(&self) -> u64 {
            8
        }
    }

    #[test]
    fn a_plane_seen_from_above_needs_its_area_in_the_coarsest_triangles() {
        // 200 m above a plane at 1 cm quads, looking straight down: every
        // level fits, its coarsest triangles (8 cm quads) are far smaller
        // than a pixel (3.6 m), so the bound is the seen area over theirs,
        // without the last row and column of pixels (no neighbour to
        // measure their footprint).
        let w = WorldDesc { spacing_m: 0.01, ..world() };
        let cam = Camera { position_m: [2048.0, 2048.0, 300.0], yaw_deg: 0.0, pitch_deg: -90.0 };
        let v = view(cam, 1.0);
        let floors = grid_floors(&reference(&Plane, &w, &v), &v, &w, &Plane);
        let half_h = 200.0 * (30f64).to_radians().tan();
        let seen = (2.0 * half_h) * (2.0 * half_h * 64.0 / 48.0);
        let measured_share = (63.0 * 47.0) / (64.0 * 48.0);
        let triangle = 0.5 * 0.08 * 0.08;
        let expected = seen * measured_share / triangle / (64.0 * 48.0);
        let floor = floors.triangles;
        assert!((floor / expected - 1.0).abs() < 0.01, "floor {floor} against {expected}");
        // A patch of the coarsest level holds as many triangles per area.
        assert!((floors.patches / floor - 1.0).abs() < 0.01, "{floors:?}");
    }

    #[test]
    fn units_larger_than_pixels_count_once() {
        // The same view at 64 m quads: coarsest quads of 512 m, patches of
        // PATCH_QUADS of them (4 km or more), and the view 231 x 308 m around (2048, 2048), a
        // corner of four 512 m quads: their triangles that hold it (2 per
        // quad, by the diamond pattern's diagonals all meeting at the
        // corner, 8 in all) and one patch, (0, 0).
        let w = WorldDesc { spacing_m: 64.0, extent_m: [16384.0, 16384.0], ..world() };
        let cam = Camera { position_m: [2048.0, 2048.0, 300.0], yaw_deg: 0.0, pitch_deg: -90.0 };
        let v = view(cam, 1.0);
        let floors = grid_floors(&reference(&Plane, &w, &v), &v, &w, &Plane);
        let pixels = 64.0 * 48.0;
        assert_eq!(floors.triangles * pixels, 8.0, "{floors:?}");
        const { assert!(PATCH_QUADS * 512 >= 4096, "the comment's patch size") };
        assert_eq!(floors.patches * pixels, f64::from(2 * PATCH_QUADS * PATCH_QUADS), "{floors:?}");
    }

    #[test]
    fn the_rule_draws_more_the_finer_the_target_and_fewer_than_whole_patches() {
        // 512 m of the rough hills at 1 m samples, 3 LODs: a finest lattice
        // the rule is computed for.
        let w = WorldDesc { extent_m: [512.0, 512.0], lod_count: 3, ..world() };
        let cam = Camera { position_m: [256.0, -20.0, 160.0], yaw_deg: 5.0, pitch_deg: -30.0 };
        let floors: Vec<Floors> = [8.0, 4.0, 2.0, 1.0]
            .iter()
            .map(|&t| {
                let v = View { size: [256, 192], ..view(cam, t) };
                grid_floors(&reference(&Hills, &w, &v), &v, &w, &Hills)
            })
            .collect();
        let rule: Vec<f64> =
            floors.iter().map(|f| f.rule.expect("a small world has the rule's figure").per_pixel).collect();
        assert!(rule.windows(2).all(|r| r[1] >= r[0]), "{floors:?}");
        // Measured: 0.036 to 0.34 tri/px; the fewest any choice of whole
        // patches could draw is 0.49 at every target.
        assert!(floors.iter().all(|f| f.rule.unwrap().per_pixel < f.patches), "{floors:?}");
    }

    #[test]
    fn a_finer_target_never_needs_fewer_triangles() {
        let w = WorldDesc { lod_count: 6, ..world() };
        let cam = Camera { position_m: [2048.0, 1500.0, 180.0], yaw_deg: 10.0, pitch_deg: -25.0 };
        let floors: Vec<Floors> = [8.0, 4.0, 2.0, 1.0, 0.5]
            .iter()
            .map(|&t| {
                let v = View { size: [256, 192], ..view(cam, t) };
                grid_floors(&reference(&Hills, &w, &v), &v, &w, &Hills)
            })
            .collect();
        let finer = |a: f64, b: f64| b >= a * (1.0 - 1e-12);
        assert!(floors.windows(2).all(|f| finer(f[0].triangles, f[1].triangles)), "{floors:?}");
        assert!(floors.windows(2).all(|f| finer(f[0].patches, f[1].patches)), "{floors:?}");
        assert!(floors[4].triangles > 2.0 * floors[0].triangles, "the hills hardly matter: {floors:?}");
        // Whole patches can only need more than free triangles.
        assert!(floors.iter().all(|f| f.patches >= f.triangles), "{floors:?}");
    }
}
