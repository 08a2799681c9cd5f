//! Plans before work: `vista bake --dry-run` prints the plan; a world over a
//! limit is refused with one line naming the option to change, before
//! anything sized by the world is allocated; a bake whose stderr is not a
//! terminal prints plain progress lines.

use std::path::{Path, PathBuf};
mod vista_cmd;

use std::sync::atomic::{AtomicUsize, Ordering};
use vista_cmd::vista_cmd;

/// Peak resident memory a refused command may reach, KiB. The refusals
/// happen before anything sized by the world exists, so what remains is the
/// process itself: about 7 MiB for `bake`/`memory` here, bounded at 32 MiB
/// (a few MiB more for another allocator or libc); `render` refused by the
/// device's limits has started Vulkan (lavapipe: about 70 MiB, a real
/// driver more), bounded at 256 MiB. What they would allocate otherwise is
/// gigabytes: `memory --extent 60000000` grew to 24 GB before the change
/// and was killed; the node texture shadow of a 16500-sector world is
/// 700 MiB.
const PEAK_KIB: u64 = 32 * 1024;
const PEAK_KIB_WITH_DEVICE: u64 = 256 * 1024;

struct Run {
    ok: bool,
    out: String,
    err: String,
    /// VmHWM of the process at exit, KiB.
    peak_kib: u64,
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vista-cli-plan-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// Runs `vista`, which writes its VmHWM to the file named by
/// VISTA_PEAK_RSS_FILE as it exits (the kernel's high-water mark: a peak,
/// however short, is never missed as a sample from outside could miss it).
fn vista(args: &[&str]) -> Run {
    static RUNS: AtomicUsize = AtomicUsize::new(0);
    let rss = temp_dir(&format!("rss-{}", RUNS.fetch_add(1, Ordering::Relaxed)));
    let rss_file = rss.join("peak");
    let out = vista_cmd().args(args).env("VISTA_PEAK_RSS_FILE", &rss_file).output().expect("run vista");
    let status = std::fs::read_to_string(&rss_file).unwrap_or_default();
    let _ = std::fs::remove_dir_all(&rss);
    // "VmHWM:	    5724 kB"; absent off Linux, where 0 passes.
    let peak_kib = status.split_whitespace().nth(1).and_then(|v| v.parse().ok()).unwrap_or(0);
    Run {
        ok: out.status.success(),
        out: String::from_utf8_lossy(&out.stdout).into(),
        err: String::from_utf8_lossy(&out.stderr).into(),
        peak_kib,
    }
}

/// The command fails with exit code 2 and one stderr line holding every
/// needle, having stayed under [`PEAK_KIB`] ([`PEAK_KIB_WITH_DEVICE`] for
/// `render`, which starts Vulkan before the device's limits are known).
fn assert_refused(args: &[&str], needles: &[&str]) -> Run {
    let limit = if args[0] == "render" { PEAK_KIB_WITH_DEVICE } else { PEAK_KIB };
    let run = vista(args);
    assert!(!run.ok, "{args:?} should be refused:\n{}", run.out);
    assert_eq!(run.err.trim_end().lines().count(), 1, "{args:?}: not one line:\n{}", run.err);
    for n in needles {
        assert!(run.err.contains(n), "{args:?}: {n:?} missing from: {}", run.err);
    }
    assert!(run.peak_kib < limit, "{args:?}: peak {} KiB before refusing", run.peak_kib);
    run
}

/// The LOD rows of a printed plan: (lod, nodes, world nodes).
fn plan_rows(text: &str) -> Vec<(u32, u64, u64)> {
    text.lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            // "3    20 x 20    400    400"
            match f[..] {
                [lod, _, "x", _, nodes, world] => Some((lod.parse().ok()?, nodes.parse().ok()?, world.parse().ok()?)),
                _ => None,
            }
        })
        .collect()
}

fn node_files(dir: &Path) -> usize {
    let Ok(lods) = std::fs::read_dir(dir) else { return 0 };
    let files = lods.flatten().filter_map(|l| std::fs::read_dir(l.path()).ok()).flat_map(|f| f.flatten());
    files.filter(|f| f.path().extension().is_some_and(|e| e == "vnode")).count()
}

#[test]
fn dry_run_prints_the_plan_and_bakes_nothing() {
    let dir = temp_dir("dry");
    let out = dir.join("nodes");
    let o = out.to_str().unwrap();
    let world = ["--extent", "2048", "--spacing", "2", "--lods", "4"];
    let run = vista(&[&["bake", "--out", o, "--dry-run"][..], &world[..]].concat());
    assert!(run.ok, "{}", run.err);
    // 256 m sectors: 8 x 8; LOD k is ceil(8 / 2^k) a side.
    let side = |k: u32| 8u64.div_ceil(1 << k);
    let expected: Vec<(u32, u64, u64)> = (0..4).map(|k| (k, side(k) * side(k), side(k) * side(k))).collect();
    assert_eq!(plan_rows(&run.out), expected, "{}", run.out);
    assert!(run.out.contains("sectors:  8 x 8 of 256 m"), "{}", run.out);
    let total: u64 = expected.iter().map(|r| r.1).sum();
    assert!(run.out.lines().any(|l| l.split_whitespace().collect::<Vec<_>>() == ["total", "85", "85"]), "{}", run.out);
    assert_eq!(total, 85);
    for key in [
        "disk:",
        "GPU:",
        "512 resident slots",
        "bake:",
        "the error tree about",
        "sample nodes and sectors of errors computed now",
        "dry run: nothing baked",
    ] {
        assert!(run.out.contains(key), "{key:?} missing:\n{}", run.out);
    }
    assert!(!out.exists(), "a dry run creates no cache folder");
    // The error tree's memory: one LOD-3 root whose tile holds 128^2, 64^2,
    // 32^2 and 16^2 patches of 36 bytes (783 360 B), twice while computed.
    let errors = "the error tree's tiles are 765.00 KiB (1 root of 765.00 KiB each); computing holds about 1.49 MiB";
    assert!(run.out.contains(errors), "{errors:?} missing:\n{}", run.out);
    assert!(!run.out.contains("more than this machine may have"), "{}", run.out);

    // A region: cells of LOD k overlapping 0..300 m.
    let run = vista(&[&["bake", "--out", o, "--dry-run", "--region", "0,0,300,300"][..], &world[..]].concat());
    assert!(run.ok, "{}", run.err);
    let cells = |k: u32| (300.0f64 / (256.0 * f64::from(1u32 << k))).ceil() as u64;
    let rows = plan_rows(&run.out);
    for (k, nodes, world_nodes) in &rows {
        assert_eq!(*nodes, cells(*k) * cells(*k), "lod {k}:\n{}", run.out);
        assert_eq!(*world_nodes, side(*k) * side(*k));
    }
    assert_eq!(rows.len(), 4);
    assert_eq!(node_files(&out), 0);

    // A dry run needs no --out; a bake does.
    let run = vista(&[&["bake", "--dry-run"][..], &world[..]].concat());
    assert!(run.ok && run.out.contains("dry run: nothing baked"), "{}", run.err);
    let run = vista(&[&["bake"][..], &world[..]].concat());
    assert!(!run.ok && run.err.contains("--out") && run.err.trim().lines().count() == 1, "{}", run.err);
}

/// A 60 km world at 8 m with 10 LODs has one root 524 km a side: its tile
/// covers that whole area at every level (3 GiB; a render peaked at 5.3 GiB
/// computing it), which the plan says before any work.
#[test]
fn a_root_tile_beyond_a_gibibyte_is_said_in_the_plan() {
    let run = vista(&["bake", "--dry-run", "--extent", "60000", "--spacing", "8", "--lods", "10"]);
    assert!(run.ok, "{}", run.err);
    // (8192^2 + 4096^2 + ... + 16^2) patches of 36 bytes = 3 GiB.
    let per_root: u64 = (0..10).map(|k| (16u64 << (9 - k)).pow(2)).sum::<u64>() * 36;
    assert_eq!(per_root / (1 << 20), 3071, "about 3 GiB");
    for key in ["(1 root of 3.00 GiB each)", "about 6.00 GiB at once", "more than this machine may have: fewer --lods"]
    {
        assert!(run.out.contains(key), "{key:?} missing:\n{}", run.out);
    }
}

#[test]
fn each_limit_is_refused_before_allocating() {
    let dir = temp_dir("limits");
    let o = dir.join("nodes");
    let o = o.to_str().unwrap();
    // Sectors a side: 0.128 m sectors over the default 10 km.
    let sectors = ["80000 x 80000 sectors", "16384", "--spacing", "--max-sectors"];
    assert_refused(&["bake", "--out", o, "--spacing", "0.001"], &sectors);
    assert_refused(&["memory", "--extent", "60000000"], &["937500 x 937500 sectors", "--extent"]);
    // Refused before Vulkan starts, too.
    assert_refused(&["render", "--spacing", "0.001", "--size", "64x48", "--frames", "1"], &sectors);
    // The limit is an option.
    assert_refused(&["memory", "--max-sectors", "100"], &["160 x 160 sectors", "limit is 100"]);

    // The disk cap: 1563 sectors a side at 0.5 m, 10 LODs (no exact tiling;
    // the most there can be), sum of ceil(1563 / 2^k)^2 over k = 0..=9 =
    // 3 258 654 nodes of about 43 KiB (compressed BC payloads): over 130 GiB.
    let big = ["bake", "--out", o, "--extent", "100000"];
    let run = assert_refused(&big, &["GiB", "3258654 nodes", "64.00 GiB", "--yes", "--max-disk", "--region"]);
    assert!(run.out.is_empty(), "{}", run.out);
    // Its dry run prints the plan, then the same refusal.
    let run = assert_refused(&[&big[..], &["--dry-run"]].concat(), &["--yes"]);
    assert!(run.out.contains("1563 x 1563"), "{}", run.out);
    // A lower cap refuses what the default takes: 34 125 node files of
    // 65 062 bytes uncompressed with 8 x 8 patches (64 * (4 + 16 + 1) bytes
    // of min/max, cone and holes), now 16 x 16 patches (256 * (4 + 1)) with
    // 8 x 8 cones (64 * 16), plus the height layer's 2-sample border
    // ((132^2 - 129^2) * 2 bytes more), the patch errors (256 * 2 f32) and
    // the representation error (f32), at zstd's 1.49:1 of the default world.
    let patches = -64.0 * 21.0 + 256.0 * 5.0 + 64.0 * 16.0;
    let file = 65062.0 + patches + f64::from(132 * 132 - 129 * 129) * 2.0 + 256.0 * 8.0 + 4.0;
    let expect = format!("{:.2} GiB", 34125.0 * (file / 1.49f64).floor() / f64::from(1 << 30));
    assert_refused(&["bake", "--out", o, "--max-disk", "1"], &[&expect, "the cap is 1.00 GiB"]);
    assert_eq!(node_files(Path::new(o)), 0, "nothing baked");

    // The device's node texture, checked by the library as the renderer is
    // made: sectors beyond the device's image size, --max-sectors raised.
    let info = vista(&["info"]);
    assert!(info.ok, "{}", info.err);
    let max: u64 = info
        .out
        .lines()
        .find_map(|l| l.trim().strip_prefix("image 2D / layers:"))
        .and_then(|v| v.split('/').next()?.trim().parse().ok())
        .unwrap_or_else(|| panic!("no image size in:\n{}", info.out));
    let sectors = max + 100;
    let (extent, raised) = ((sectors * 64).to_string(), (sectors + 1).to_string());
    let args = ["render", "--extent", &extent, "--max-sectors", &raised, "--size", "64x48", "--frames", "1"];
    assert_refused(&args, &["node texture", &format!("allows {max} a side"), "--spacing"]);
    // One atlas layer per resident slot, and one reserved.
    let layers: u64 = info
        .out
        .lines()
        .find_map(|l| l.trim().strip_prefix("image 2D / layers:"))
        .and_then(|v| v.split('/').nth(1)?.trim().parse().ok())
        .unwrap_or_else(|| panic!("no layer count in:\n{}", info.out));
    let slots = layers.to_string();
    let args = ["render", "--slots", &slots, "--size", "64x48", "--frames", "1"];
    if layers > 2047 {
        // Slots are 11-bit: refused before the device is asked (lavapipe
        // allows 2048 layers).
        assert_refused(&args, &[&format!("--slots {layers}: use 100 to 2047"), "11-bit"]);
    } else {
        assert_refused(&args, &[&format!("{layers} resident slots need {} atlas layers", layers + 1), "--slots"]);
    }
}

#[test]
fn bakes_print_plain_progress_without_a_terminal() {
    let dir = temp_dir("progress");
    let o = dir.join("nodes");
    let args = [
        "bake",
        "--out",
        o.to_str().unwrap(),
        "--extent",
        "2048",
        "--spacing",
        "2",
        "--lods",
        "4",
        "--progress-every",
        "0",
    ];
    let run = vista(&args);
    assert!(run.ok, "{}", run.err);
    assert!(run.err.starts_with("baking 85 nodes, about "), "{}", run.err);
    // "baked 12/85 nodes (14.1 %), 40.2 nodes/s, eta 2 s"
    let lines: Vec<&str> = run.err.lines().filter(|l| l.starts_with("baked ")).collect();
    assert!(!lines.is_empty(), "no progress line:\n{}", run.err);
    for l in lines {
        let f: Vec<&str> = l.split_whitespace().collect();
        let (done, total) = f[1].split_once('/').unwrap();
        assert_eq!(total, "85", "{l}");
        let done: f64 = done.parse().unwrap();
        assert_eq!(f[3], format!("({:.1}", 100.0 * done / 85.0), "{l}");
        assert!(f[5].parse::<f64>().is_ok() && f[6] == "nodes/s," && f[7] == "eta", "{l}");
    }
    assert_eq!(node_files(&o), 85);
    // --no-progress: not a word.
    let run = vista(&[&args[..], &["--no-progress"]].concat());
    assert!(run.ok && run.err.is_empty(), "{}", run.err);
}

/// A 16384² PNG16, the largest side vista takes (a real DEM's size): 512
/// MiB of pixels in a file of a few MiB (runs of 64 equal values).
fn big_png(path: &Path) -> u64 {
    const SIDE: u32 = 16384;
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut enc = png::Encoder::new(file, SIDE, SIDE);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    enc.set_compression(png::Compression::Fast);
    enc.set_filter(png::Filter::NoFilter);
    let mut w = enc.write_header().unwrap().into_stream_writer().unwrap();
    let mut row = vec![0u8; SIDE as usize * 2];
    for j in 0..SIDE {
        for (i, px) in row.chunks_exact_mut(2).enumerate() {
            let v = ((i as u32 / 64 + j / 64) * 97 % 65536) as u16;
            px.copy_from_slice(&v.to_be_bytes());
        }
        std::io::Write::write_all(&mut w, &row).unwrap();
    }
    w.finish().unwrap();
    u64::from(SIDE) * u64::from(SIDE) * 2
}

/// A 16384² GeoTIFF of 16-bit metres, 1 m pixels (its extent comes from
/// the tags), deflated: a few MiB. Written whole (`write_data`): the `tiff`
/// crate's encoder writes broken strips through `write_strip` when
/// compressing; its decoder reads either.
fn big_geotiff(path: &Path) -> u64 {
    use tiff::encoder::{colortype, compression::DeflateLevel, Compression, TiffEncoder};
    const SIDE: u32 = 16384;
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut enc = TiffEncoder::new(file).unwrap().with_compression(Compression::Deflate(DeflateLevel::Fast));
    let mut img = enc.new_image::<colortype::Gray16>(SIDE, SIDE).unwrap();
    img.encoder().write_tag(tiff::tags::Tag::ModelPixelScaleTag, &[1.0f64, 1.0, 0.0][..]).unwrap();
    img.encoder().write_tag(tiff::tags::Tag::ModelTiepointTag, &[0.0f64, 0.0, 0.0, 0.0, 16384.0, 0.0][..]).unwrap();
    let side = u64::from(SIDE);
    let data: Vec<u16> = (0..side * side).map(|s| ((s % side / 64 + s / side / 64) % 8) as u16 * 257).collect();
    img.write_data(&data).unwrap();
    side * side * 2
}

#[test]
fn a_16384_map_is_planned_from_its_header_and_baked_within_its_own_size() {
    let dir = temp_dir("big-map");
    let map = dir.join("big.png");
    let map_bytes = big_png(&map);
    let m = map.to_str().unwrap();
    let world = ["--heightmap", m, "--extent", "16384", "--height-range", "0", "2000", "--spacing", "4"];
    assert_plans_small_and_bakes_within(&dir, &world, map_bytes);
    let tif = dir.join("big.tif");
    let tif_bytes = big_geotiff(&tif);
    std::fs::remove_file(&map).unwrap();
    let world = ["--heightmap", tif.to_str().unwrap(), "--spacing", "4"];
    assert_plans_small_and_bakes_within(&dir, &world, tif_bytes);
    let _ = std::fs::remove_dir_all(&dir);
}

fn assert_plans_small_and_bakes_within(dir: &Path, world: &[&str], map_bytes: u64) {
    // Plans read the header (memory) or a corner (a dry run's timing: a
    // PNG's 1024² corner, a GeoTIFF's first strip or tile).
    for cmd in [&["memory"][..], &["bake", "--dry-run"][..]] {
        let r = vista(&[cmd, world].concat());
        assert!(r.ok, "{cmd:?} {world:?}: {}", r.err);
        assert!(r.peak_kib <= 64 * 1024, "{cmd:?} {world:?} peaked at {} KiB", r.peak_kib);
        eprintln!("{cmd:?} {}: peak {} KiB", world[1], r.peak_kib);
        // 16384 m at 4 m spacing: 32 x 32 LOD-0 nodes of 512 m, 1365 in 6 LODs.
        let world_line = if cmd[0] == "memory" { "1365 nodes over 6 LODs" } else { "16384 x 16384 m" };
        assert!(r.out.contains(world_line), "{}", r.out);
    }
    // A bake keeps the map's 16-bit samples as they are (no float copy):
    // the map itself plus the error tree's working set (a 1024² root of
    // f32 samples per thread) and the process, bounded at the map's bytes
    // plus a quarter. Before, a whole-map f32 copy beside the decoded image
    // took 3x the map (1.58 GB measured).
    let out = dir.join("nodes");
    let _ = std::fs::remove_dir_all(&out);
    let args = [&["bake", "--out", out.to_str().unwrap(), "--region", "0,0,100,100", "--no-progress"][..], world];
    let r = vista(&args.concat());
    assert!(r.ok, "{}", r.err);
    let bound_kib = map_bytes * 5 / 4 / 1024;
    assert!(r.peak_kib <= bound_kib, "{world:?}: bake peaked at {} KiB, bound {bound_kib} KiB", r.peak_kib);
    assert!(r.peak_kib >= map_bytes / 1024, "the whole map is read to bake: {} KiB", r.peak_kib);
    eprintln!(
        "bake of a region of {}: peak {} KiB, the map's 16-bit samples {} KiB",
        world[1],
        r.peak_kib,
        map_bytes / 1024
    );
}

/// A spacing far finer than a height map's pixels says so before any work
/// (docs/world-pipeline.md's Mont Blanc at 92.7 m pixels: 2 m is 46 x finer); the
/// scenes' 8 m (12 x) gets no line.
#[test]
fn a_spacing_far_finer_than_the_map_is_noted_before_work() {
    let mb = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data/montblanc.png");
    let world = ["--heightmap", mb, "--extent", "60000", "--height-range", "454", "4810"];
    let fine = vista(&[&["bake", "--dry-run", "--spacing", "2"][..], &world].concat());
    assert!(fine.ok, "{}", fine.err);
    assert!(
        fine.err.contains("note: spacing 2 m is 46 x finer than") && fine.err.contains("--spacing 92.7"),
        "{}",
        fine.err
    );
    let scene = vista(&[&["bake", "--dry-run", "--spacing", "8"][..], &world].concat());
    assert!(scene.ok && !scene.err.contains("finer than"), "{}", scene.err);
}
