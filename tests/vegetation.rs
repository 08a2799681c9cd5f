//! The vegetation generator (`vista::world::vegetation`): resource flow and
//! sun exposure against independent twins on analytic surfaces, tiles
//! equal to the whole grid, reruns and shards equal to one run, the
//! occurrence maps equal to the cells they summarise, masks removing what
//! grows and nothing else.

use std::path::{Path, PathBuf};

use glam::DVec3;
use vista::world::vegetation::{
    flow, generate, lit_share, trajectory, write_outputs, Flow, Generated, HeightField, MaskMap, Masks, Occurrence,
    Request, VegetationParams, Window,
};
use vista::world::{GridSource, Hole, MaterialRules, WorldDesc};

fn field_of(size: [usize; 2], cell_m: f64, f: impl Fn(f64, f64) -> f64) -> HeightField {
    let z = (0..size[0] * size[1])
        .map(|k| f(((k % size[0]) as f64 + 0.5) * cell_m, ((k / size[0]) as f64 + 0.5) * cell_m) as f32)
        .collect();
    HeightField::from_heights(cell_m, size, z)
}

/// The test's own iteration, written as a scatter: each cell sends `rate`
/// of its resource (less under a gradient of `full`) to its lower
/// neighbours by drop over distance.
fn twin_flow(field: &HeightField, iterations: u32, rate: f64, full: f64) -> Vec<f64> {
    let [w, h] = field.size;
    let z = |i: usize, j: usize| f64::from(field.z[j * w + i]);
    let mut r: Vec<f64> = field.hole.iter().map(|h| if *h { 0.0 } else { 1.0 }).collect();
    for _ in 0..iterations {
        let mut next = r.clone();
        for j in 0..h {
            for i in 0..w {
                if field.hole[j * w + i] {
                    continue;
                }
                let mut lower = Vec::new();
                for dj in -1i64..=1 {
                    for di in -1i64..=1 {
                        let (ni, nj) = (i as i64 + di, j as i64 + dj);
                        if (di, dj) == (0, 0) || ni < 0 || nj < 0 || ni >= w as i64 || nj >= h as i64 {
                            continue;
                        }
                        let (ni, nj) = (ni as usize, nj as usize);
                        let drop = (z(i, j) - z(ni, nj)) / ((di * di + dj * dj) as f64).sqrt();
                        if drop > 0.0 && !field.hole[nj * w + ni] {
                            lower.push((nj * w + ni, drop));
                        }
                    }
                }
                let sum: f64 = lower.iter().map(|l| l.1).sum();
                let gradient = lower.iter().map(|l| l.1).fold(0.0, f64::max) / field.cell_m;
                let share = rate * (gradient / full).min(1.0);
                for (n, drop) in lower {
                    let moved = r[j * w + i] * share * drop / sum;
                    next[j * w + i] -= moved;
                    next[n] += moved;
                }
            }
        }
        r = next;
    }
    r
}

#[test]
fn resource_collects_in_the_valley_and_is_never_made() {
    // A V valley running north-south, falling to the south, two holes.
    let mut field = field_of([48, 40], 4.0, |x, y| 0.3 * (x - 96.0).abs() + 0.05 * y);
    for k in [5 * 48 + 7, 30 * 48 + 40] {
        field.hole[k] = true;
    }
    let whole = Window { lo: [0, 0], size: field.size };
    let cells = field.hole.iter().filter(|h| !**h).count() as f64;
    let rule = Flow { share: 0.5, full_slope_deg: 20.0 };
    for iterations in [0, 1, 5, 32] {
        let got = flow(&field, whole, iterations, rule);
        let want = twin_flow(&field, iterations, 0.5, 20f64.to_radians().tan());
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() <= 1e-12 * w.abs().max(1.0), "{iterations} iterations: {g} against the twin's {w}");
        }
        let total: f64 = got.iter().sum();
        assert!((total - cells).abs() < 1e-9 * cells, "{iterations} iterations: total {total} of {cells}");
    }
    let r = flow(&field, whole, 32, rule);
    assert_eq!((r[5 * 48 + 7], r[30 * 48 + 40]), (0.0, 0.0), "holes hold none");
    let column = |i: usize| (0..40).map(|j| r[j * 48 + i]).sum::<f64>() / 40.0;
    let (floor, rims) = (column(23) + column(24), column(0) + column(1) + column(46) + column(47));
    eprintln!("after 32 iterations: valley floor {floor:.3}, rims {rims:.5} (two columns each, per row)");
    assert!(floor > 10.0 * rims.max(1e-3) && floor > 4.0, "floor {floor}, rims {rims}");
    // The floor's south end holds more than its north end: water runs down it.
    assert!(r[48 + 24] + r[48 + 23] > r[38 * 48 + 24] + r[38 * 48 + 23]);
}

#[test]
fn a_tile_with_its_halo_equals_the_whole_grid() {
    let field = field_of([160, 150], 2.0, |x, y| 20.0 * (x * 0.03).sin() * (y * 0.021).cos() + 0.1 * x);
    let rule = Flow { share: 0.6, full_slope_deg: 10.0 };
    let whole = flow(&field, Window { lo: [0, 0], size: field.size }, 20, rule);
    for core in [Window { lo: [64, 64], size: [64, 64] }, Window { lo: [0, 128], size: [64, 22] }] {
        let wide = Window::around(core, 20, field.size);
        let part = flow(&field, wide, 20, rule);
        for j in core.lo[1]..core.lo[1] + core.size[1] {
            for i in core.lo[0]..core.lo[0] + core.size[0] {
                let p = part[(j - wide.lo[1]) * wide.size[0] + i - wide.lo[0]];
                assert_eq!(p.to_bits(), whole[j * 160 + i].to_bits(), "cell {i}, {j} of {core:?}");
            }
        }
    }
}

#[test]
fn the_suns_day_is_the_textbooks() {
    // 46 N at the June solstice: noon elevation 90 - 46 + 23.44; day
    // length 15.5 h (sunrise azimuth ~55 degrees east of north).
    let path = trajectory(46.0, 172, 101);
    let noon = path[50];
    let elevation = noon.z.asin().to_degrees();
    assert!((elevation - 67.44).abs() < 0.1, "noon elevation {elevation}");
    assert!(noon.y < 0.0 && noon.x.abs() < 1e-9, "noon sun due south: {noon}");
    let first = path[0];
    assert!(first.x > 0.0 && first.z < 0.05, "the first sample just after sunrise, in the east: {first}");
    assert!(trajectory(80.0, 355, 16).is_empty(), "polar night: no sun");
    assert_eq!(trajectory(80.0, 172, 16).len(), 16, "polar day: sun all round");
}

/// The analytic surface of two east-west ridges and its gradient.
fn ridges(x: f64, y: f64) -> (f64, [f64; 2]) {
    let _ = x;
    let a = 150.0 * (-((y - 350.0) / 120.0).powi(2)).exp();
    let b = 120.0 * (-((y - 700.0) / 150.0).powi(2)).exp();
    let dy = a * -2.0 * (y - 350.0) / 14_400.0 + b * -2.0 * (y - 700.0) / 22_500.0;
    (a + b, [0.0, dy])
}

/// The test's own shadow ray: the exact surface in 1 m steps, the exact
/// normal.
fn twin_lit(x: f64, y: f64, sun: DVec3) -> bool {
    let (z, g) = ridges(x, y);
    if DVec3::new(-g[0], -g[1], 1.0).dot(sun) <= 0.0 {
        return false;
    }
    let flat = (sun.x * sun.x + sun.y * sun.y).sqrt();
    let mut t = 1.0;
    while t < 3000.0 {
        let (px, py) = (x + sun.x / flat * t, y + sun.y / flat * t);
        let ray = z + sun.z / flat * t;
        if ray > 300.0 || !(0.0..=960.0).contains(&py) || !(0.0..=1280.0).contains(&px) {
            return true;
        }
        if ridges(px, py).0 > ray {
            return false;
        }
        t += 1.0;
    }
    true
}

#[test]
fn the_north_faces_shadowed_share_matches_an_independent_march() {
    let field = field_of([128, 96], 10.0, |x, y| ridges(x, y).0);
    let path = trajectory(46.0, 80, 16);
    let (mut diff, mut n, mut face, mut twin_face, mut face_n, mut cast) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for j in 2..94 {
        for i in 2..126 {
            let got = f64::from(lit_share(&field, i, j, &path, 3000.0));
            let (x, y) = ((i as f64 + 0.5) * 10.0, (j as f64 + 0.5) * 10.0);
            let want = path.iter().filter(|s| twin_lit(x, y, **s)).count() as f64 / path.len() as f64;
            let g = ridges(x, y).1;
            let facing = path.iter().filter(|s| DVec3::new(-g[0], -g[1], 1.0).dot(**s) > 0.0).count() as f64;
            cast += facing / path.len() as f64 - want;
            diff += (got - want).abs();
            n += 1.0;
            if (380.0..500.0).contains(&y) {
                (face, twin_face, face_n) = (face + 1.0 - got, twin_face + 1.0 - want, face_n + 1.0);
            }
        }
    }
    let (face, twin_face) = (face / face_n, twin_face / face_n);
    eprintln!(
        "lit share: mean |generator - twin| {:.4}; north face shadowed {face:.4}, twin {twin_face:.4}; cast shadows \
         (facing the sun, shadowed by a ridge) {:.3} of the samples",
        diff / n,
        cast / n
    );
    assert!(cast / n > 0.005, "the case has cast shadows, not only faces turned away: {}", cast / n);
    // Tolerance: the generator marches bilinear heights between 10 m cells
    // and takes central differences for the normal; where a shadow edge
    // crosses a cell that flips one of 16 samples (1/16 = 0.0625) in a
    // few cells only.
    assert!(diff / n < 0.02, "mean |lit share - twin's| = {}", diff / n);
    assert!((face - twin_face).abs() < 0.02, "north face shadowed {face} against the twin's {twin_face}");
    assert!((0.2..0.8).contains(&twin_face), "the equinox north face is partly in shadow: {twin_face}");
}

fn grid_world(bump: bool) -> (WorldDesc, GridSource) {
    let n = 257;
    let heights: Vec<f32> = (0..n * n)
        .map(|k| {
            let (i, j) = ((k % n) as f64, (k / n) as f64);
            let mut z = 200.0 + 80.0 * (i * 0.05).sin() * (j * 0.04).cos() + 0.3 * i;
            if bump && i > 220.0 && j > 220.0 {
                z += 30.0;
            }
            z as f32
        })
        .collect();
    let source = GridSource::new(n, n, heights, [1024.0, 1024.0]);
    let world = WorldDesc {
        extent_m: [1024.0, 1024.0],
        height_range_m: [0.0, 500.0],
        spacing_m: 1.0,
        lod_count: 3,
        ..Default::default()
    };
    (world, source)
}

/// A whole run's request on the grid world: no holes, stamps, shard or region.
fn plain<'a>(
    world: &'a WorldDesc,
    source: &'a GridSource,
    rules: &'a MaterialRules,
    params: &'a VegetationParams,
    masks: &'a Masks,
) -> Request<'a> {
    Request { world, source, holes: &[], rules, params, masks, stamps: &[], shard: None, region: None, sun: None }
}

fn run(dir: &Path, bump: bool, shard: Option<(u32, u32)>) -> vista::world::vegetation::RunReport {
    run_part(dir, bump, shard, None)
}

fn run_part(
    dir: &Path,
    bump: bool,
    shard: Option<(u32, u32)>,
    region: Option<[f64; 4]>,
) -> vista::world::vegetation::RunReport {
    let (world, source) = grid_world(bump);
    let params = VegetationParams { cell_m: 4.0, reach_m: 150.0, occurrence_cell_m: 8.0, ..Default::default() };
    let rules = MaterialRules::default();
    let masks = Masks::default();
    let req = Request { shard, region, ..plain(&world, &source, &rules, &params, &masks) };
    let report = generate(&req, dir).unwrap();
    if let Some(g) = &report.result {
        write_outputs(dir, &params, g).unwrap();
    }
    report
}

fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    ["instances.bin", "vegetation.json", "occurrence-meadow.bin"]
        .iter()
        .map(|f| (f.to_string(), std::fs::read(dir.join(f)).unwrap()))
        .collect()
}

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vista-vegetation-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn reruns_shards_and_edits_give_what_one_run_gives() {
    let (one, sharded, edited, fresh) = (temp("one"), temp("sharded"), temp("edited"), temp("fresh"));
    let first = run(&one, false, None);
    assert_eq!((first.tiles, first.computed, first.reused, first.missing), (16, 16, 0, 0));
    assert!(first.result.as_ref().unwrap().instances.len() > 100);
    let again = run(&one, false, None);
    assert_eq!((again.computed, again.reused), (0, 16), "a rerun reuses every tile");
    let a = run(&sharded, false, Some((0, 3)));
    assert!(a.result.is_none() && a.missing == 10 && a.computed == 6, "{a:?}");
    run(&sharded, false, Some((2, 3)));
    let last = run(&sharded, false, Some((1, 3)));
    assert!(last.result.is_some(), "the shard that completes the tiles gathers them");
    assert_eq!(outputs(&one), outputs(&sharded), "three shards write what one run writes");
    // An edit in the north-east corner: only the tiles within reach of it
    // are made again, and the result is a fresh run's.
    for f in std::fs::read_dir(one.join("tiles")).unwrap() {
        let f = f.unwrap().path();
        std::fs::create_dir_all(edited.join("tiles")).unwrap();
        std::fs::copy(&f, edited.join("tiles").join(f.file_name().unwrap())).unwrap();
    }
    let edit = run(&edited, true, None);
    eprintln!("the edit: {} of {} tiles made again", edit.computed, edit.tiles);
    assert!(edit.computed > 0 && edit.computed <= 4, "{} tiles made again", edit.computed);
    run(&fresh, true, None);
    assert_eq!(outputs(&edited), outputs(&fresh), "the incremental run writes what a full one does");
    assert_ne!(outputs(&edited), outputs(&one));
    for d in [one, sharded, edited, fresh] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// A region makes only the tiles it overlaps (of 256 m, here one: cells
/// 75..125 lie in tile 1 both ways), the outputs wait for the rest, and a
/// whole run after it reuses the region's tile and writes what one run does.
#[test]
fn a_region_makes_its_tiles_and_the_rest_completes_the_run() {
    let (one, part) = (temp("region-one"), temp("region-part"));
    let r = run_part(&part, false, None, Some([300.0, 300.0, 500.0, 500.0]));
    assert_eq!((r.computed, r.reused, r.missing), (1, 0, 15), "{r:?}");
    assert!(r.result.is_none());
    let rest = run(&part, false, None);
    assert_eq!((rest.computed, rest.reused), (15, 1));
    run(&one, false, None);
    assert_eq!(outputs(&one), outputs(&part), "a region then the rest writes what one run writes");
    let (world, source) = grid_world(false);
    let (params, rules, masks) = (VegetationParams::default(), MaterialRules::default(), Masks::default());
    let req = |region| Request { region: Some(region), ..plain(&world, &source, &rules, &params, &masks) };
    let err = vista::world::vegetation::check(&req([2000.0, 0.0, 2100.0, 10.0])).unwrap_err().to_string();
    assert!(err.contains("does not overlap the world"), "{err}");
    assert!(vista::world::vegetation::check(&req([10.0, 0.0, 5.0, 10.0])).is_err(), "min over max");
    for d in [one, part] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn occurrence_bits_say_exactly_where_a_grass_may_grow() {
    let dir = temp("occurrence");
    let g = run(&dir, false, None).result.unwrap();
    let map = Occurrence::of(&g, 3, 2);
    assert_eq!(map.size, [128, 128]);
    for oj in 0..128 {
        for oi in 0..128 {
            let any = (0..4).any(|k| g.grass[(oj * 2 + k / 2) * 256 + oi * 2 + k % 2] & (1 << 3) != 0);
            assert_eq!(map.get(oi, oj), any, "occurrence cell {oi}, {oj}");
        }
    }
    assert!(map.set_cells() > 0 && map.set_cells() < 128 * 128, "{} set", map.set_cells());
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn masks_remove_what_grows_and_leave_water_and_sun() {
    let (world, source) = grid_world(false);
    let params = VegetationParams { cell_m: 4.0, reach_m: 150.0, occurrence_cell_m: 8.0, ..Default::default() };
    let rules = MaterialRules::default();
    // A mask map whose west half (x < 256 m) is white, a disc and a polygon.
    let png = temp("mask").with_extension("png");
    image::GrayImage::from_fn(64, 64, |x, _| image::Luma([if x < 16 { 255 } else { 0 }])).save(&png).unwrap();
    let masks = Masks {
        shapes: vec![
            Hole::Circle { center_m: [600.0, 600.0], radius_m: 60.0 },
            Hole::Polygon(vec![[700.0, 100.0], [900.0, 120.0], [800.0, 300.0]]),
        ],
        map: Some(MaskMap::load(&png, world.extent_m).unwrap()),
    };
    let none = Masks::default();
    let gen = |masks: &Masks, name: &str| {
        let req = Request {
            world: &world,
            source: &source,
            holes: &[],
            rules: &rules,
            params: &params,
            masks,
            stamps: &[],
            shard: None,
            region: None,
            sun: None,
        };
        generate(&req, &temp(name)).unwrap().result.unwrap()
    };
    let (open, masked) = (gen(&none, "open"), gen(&masks, "masked"));
    let inside =
        |p: [f64; 2]| p[0] < 256.0 || (p[0] - 600.0).hypot(p[1] - 600.0) < 60.0 || masks.shapes[1].contains(p[0], p[1]);
    let at = |t: &vista::world::vegetation::Instance| [f64::from(t.position[0]), f64::from(t.position[1])];
    assert!(masked.instances.iter().all(|t| !inside(at(t))), "an instance inside a mask");
    // A cell whose centre a mask holds grows nothing either.
    let centre = |t: &vista::world::vegetation::Instance| {
        let c = t.cell as usize;
        [((c % 256) as f64 + 0.5) * 4.0, ((c / 256) as f64 + 0.5) * 4.0]
    };
    let kept: Vec<_> = open.instances.iter().filter(|t| !inside(at(t)) && !inside(centre(t))).copied().collect();
    assert!(
        masked.instances == kept,
        "outside the masks, what grows is unchanged ({} against {})",
        masked.instances.len(),
        kept.len()
    );
    assert!(open.instances.len() > kept.len() + 100, "the masks removed something");
    for k in 0..masked.grass.len() {
        let c = [((k % 256) as f64 + 0.5) * 4.0, ((k / 256) as f64 + 0.5) * 4.0];
        assert_eq!(masked.grass[k], if inside(c) { 0 } else { open.grass[k] }, "cell {c:?}");
    }
    assert!(masked.resource == open.resource && masked.sun == open.sun, "water and sun pass through a mask");
}

/// A stamp's own vegetation folder: a bowl 256 m across, generated.
fn stamp_folder(params: &VegetationParams, rules: &MaterialRules) -> (PathBuf, Generated) {
    let n = 65;
    let bowl: Vec<f32> = (0..n * n)
        .map(|k| {
            let (i, j) = ((k % n) as f64 - 32.0, (k / n) as f64 - 32.0);
            (220.0 + 0.02 * (i * i + j * j) + 3.0 * (i * 0.4).sin()) as f32
        })
        .collect();
    let small = WorldDesc {
        extent_m: [256.0, 256.0],
        height_range_m: [0.0, 500.0],
        spacing_m: 1.0,
        lod_count: 2,
        ..Default::default()
    };
    let dir = temp("stamp-own");
    let (none, own) = (Masks::default(), GridSource::new(n, n, bowl, [256.0, 256.0]));
    let req = Request {
        world: &small,
        source: &own,
        holes: &[],
        rules,
        params,
        masks: &none,
        stamps: &[],
        shard: None,
        region: None,
        sun: None,
    };
    let g = generate(&req, &dir).unwrap().result.unwrap();
    write_outputs(&dir, params, &g).unwrap();
    (dir, g)
}

/// The 1 024 m grid world with the stamp's folder pasted at `center`,
/// turned `rotation_deg`.
fn pasted(
    params: &VegetationParams,
    rules: &MaterialRules,
    folder: &Path,
    center: [f64; 2],
    rotation_deg: f64,
) -> Generated {
    use vista::world::{StampBlend, StampPlacement};
    let placement = StampPlacement {
        center_m: center,
        size_m: 256.0,
        rotation_deg,
        height_m: 10.0,
        offset_m: 0.0,
        blend: StampBlend::Add,
        falloff_m: 0.0,
    };
    let stamps = [vista::world::vegetation::StampVegetation::load(folder, placement, params).unwrap()];
    let (world, source) = grid_world(false);
    let none = Masks::default();
    let req = Request {
        world: &world,
        source: &source,
        holes: &[],
        rules,
        params,
        masks: &none,
        stamps: &stamps,
        shard: None,
        region: None,
        sun: None,
    };
    generate(&req, &temp(&format!("paste-{}", center[0]))).unwrap().result.unwrap()
}

/// The points (sorted) of `instances` within the 256 m square about `c`.
fn points_in_square(instances: &[vista::world::vegetation::Instance], c: [f64; 2]) -> Vec<[f64; 2]> {
    let mut v: Vec<[f64; 2]> = instances
        .iter()
        .map(|i| [f64::from(i.position[0]), f64::from(i.position[1])])
        .filter(|p| (p[0] - c[0]).abs() < 128.0 && (p[1] - c[1]).abs() < 128.0)
        .collect();
    v.sort_by(|p, q| p.partial_cmp(q).unwrap());
    v
}

/// Seed 004's stamps carry their vegetation: a stamp's own folder pasted at
/// two places, the second turned a quarter: inside its square every
/// instance is the stamp's, put where the test's own transform puts it, and
/// the grass bits turn with it.
#[test]
fn a_stamps_vegetation_moves_with_the_stamp() {
    let params = VegetationParams { cell_m: 4.0, reach_m: 150.0, occurrence_cell_m: 4.0, ..Default::default() };
    let rules = MaterialRules::default();
    let (folder, own) = stamp_folder(&params, &rules);
    assert!(own.instances.len() > 50, "the stamp grows {} instances", own.instances.len());
    let a = pasted(&params, &rules, &folder, [400.0, 400.0], 0.0);
    let b = pasted(&params, &rules, &folder, [700.0, 600.0], 90.0);
    for (run, c, quarter) in [(&a, [400.0, 400.0], false), (&b, [700.0, 600.0], true)] {
        // The test's own transform: (u, v) from the stamp's centre, a
        // quarter turn taking it to (-v, u).
        let mut want: Vec<[f64; 2]> = own
            .instances
            .iter()
            .map(|i| {
                let (u, w) = (f64::from(i.position[0]) - 128.0, f64::from(i.position[1]) - 128.0);
                let (x, y) = if quarter { (-w, u) } else { (u, w) };
                [c[0] + x, c[1] + y]
            })
            .collect();
        want.sort_by(|p, q| p.partial_cmp(q).unwrap());
        let got = points_in_square(&run.instances, c);
        assert_eq!(got.len(), want.len(), "instances inside the stamp at {c:?}");
        for (p, q) in got.iter().zip(&want) {
            assert!((p[0] - q[0]).abs() < 1e-3 && (p[1] - q[1]).abs() < 1e-3, "{p:?} against {q:?}");
        }
    }
    // Grass: the cell at (u, v) from A's centre is the cell at (-v, u) from B's.
    let bit =
        |run: &Generated, x: f64, y: f64| run.grass[(y / 4.0).floor() as usize * 256 + (x / 4.0).floor() as usize];
    let mut set = 0;
    for j in 0..64 {
        for i in 0..64 {
            let (u, v) = (-126.0 + 4.0 * i as f64, -126.0 + 4.0 * j as f64);
            let ga = bit(&a, 400.0 + u, 400.0 + v);
            assert_eq!(ga, bit(&b, 700.0 - v, 600.0 + u), "cell ({u}, {v}) of the stamp");
            set += usize::from(ga != 0);
        }
    }
    assert!(set > 100 && set < 64 * 64, "{set} of the stamp's cells grow grass");
}
