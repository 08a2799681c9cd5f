//! `vista bake` / `vista memory` and the world arguments: small bakes of the
//! procedural world, Mont Blanc and a scene file; every bad input exits
//! non-zero with a one-line message naming the problem. No GPU needed.

use std::path::{Path, PathBuf};
mod vista_cmd;

use vista_cmd::vista_cmd;

const MONTBLANC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data/montblanc.png");

fn vista(args: &[&str]) -> (bool, String, String) {
    let out = vista_cmd().args(args).output().expect("run vista");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

/// A fresh, empty folder per test (tests run in parallel).
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vista-cli-bake-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

fn node_files(dir: &Path) -> usize {
    let Ok(lods) = std::fs::read_dir(dir) else { return 0 };
    lods.flatten()
        .filter_map(|l| std::fs::read_dir(l.path()).ok())
        .flat_map(|f| f.flatten())
        .filter(|f| f.path().extension().is_some_and(|e| e == "vnode"))
        .count()
}

/// Fails unless the command failed with exactly one stderr line that
/// contains every one of `needles`.
fn assert_fails_naming(args: &[&str], needles: &[&str]) {
    let (ok, _, err) = vista(args);
    assert!(!ok, "{args:?} should fail");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: not one line:\n{err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: {n:?} missing from: {err}");
    }
}

#[test]
fn bakes_a_region_of_the_default_world() {
    let dir = temp_dir("default");
    let out = dir.join("nodes");
    let json = dir.join("bake.json");
    let (o, j) = (out.to_str().unwrap(), json.to_str().unwrap());
    let (ok, text, err) = vista(&["bake", "--out", o, "--region", "0,0,64,64", "--no-progress", "--json", j]);
    assert!(ok, "{err}");
    // One node of each of the 6 LODs covers the 64 m corner; the world has
    // 160^2 + 80^2 + 40^2 + 20^2 + 10^2 + 5^2 = 34125 nodes.
    assert!(text.contains("nodes:    6 (lod0 1, lod1 1"), "{text}");
    assert!(text.contains("0 reused, 0 rebaked, 6 new"), "{text}");
    // The error tree of the one root over the corner comes first.
    assert!(text.contains("for the error tree (1 roots: 0 read, 1 computed)"), "{text}");
    assert!(text.contains("extrapolated") && text.contains("34125 nodes"), "{text}");
    assert!(text.contains("total for 512 nodes"), "{text}");
    assert_eq!(node_files(&out), 6);
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["nodes"], 6);
    assert_eq!(v["full_world_nodes"], 34125);
    assert_eq!(v["error_tree"]["roots"], 1);
    assert!(v["extrapolated"]["bytes_on_disk"].as_f64().unwrap() > 0.0);

    // A second run finds every node in the cache.
    let (ok, text, err) = vista(&["bake", "--out", o, "--region", "0,0,64,64"]);
    assert!(ok, "{err}");
    assert!(text.contains("6 reused, 0 rebaked, 0 new") && text.contains("(1 roots: 1 read, 0 computed)"), "{text}");
}

#[test]
fn bakes_a_region_of_montblanc() {
    let dir = temp_dir("montblanc");
    let o = dir.to_str().unwrap();
    let (ok, text, err) = vista(&[
        "bake",
        "--heightmap",
        MONTBLANC,
        "--extent",
        "60000",
        "--height-range",
        "454",
        "4810",
        "--spacing",
        "8",
        "--out",
        o,
        "--region",
        "30000,30000,31000,31000",
    ]);
    assert!(ok, "{err}");
    assert!(text.contains("montblanc.png") && text.contains("extrapolated"), "{text}");
    // 1024 m sectors: 59 per side, no exact tiling, so 6 LODs (2 x 2
    // roots): 59^2 + 30^2 + 15^2 + 8^2 + 4^2 + 2^2 = 4690 nodes.
    assert!(text.contains("6 LODs") && text.contains("(4690 nodes"), "{text}");
    assert!(node_files(&dir) >= 6, "{text}");
}

#[test]
fn scene_with_holes_parses_and_bakes() {
    let dir = temp_dir("scene");
    std::fs::copy(MONTBLANC, dir.join("mb.png")).unwrap();
    let scene = dir.join("alps.toml");
    // A relative source resolves against the scene file's folder.
    std::fs::write(
        &scene,
        "[world]\nsource = \"mb.png\"\nextent = 60000\nheight_range = [454, 4810]\nspacing = 16\nlods = 3\n\n\
         [[holes]]\ncircle = [100, 100, 50]\n[[holes]]\npolygon = [[0, 0], [300, 0], [0, 300]]\n\n\
         [effects]\nholes = true\ncliffs = false\n",
    )
    .unwrap();
    let out = dir.join("nodes");
    let (s, o) = (scene.to_str().unwrap(), out.to_str().unwrap());
    let (ok, text, err) =
        vista(&["bake", "--scene", s, "--out", o, "--region", "0,0,500,500", "--hole-circle", "1,1,2"]);
    assert!(ok, "{err}");
    assert!(text.contains("3 LODs, 3 holes"), "{text}");
    assert_eq!(node_files(&out), 3, "{text}");
}

#[test]
fn a_scene_asks_for_the_procedural_worlds_terraces() {
    let dir = temp_dir("terraces");
    let scene = dir.join("terraced.toml");
    std::fs::write(&scene, "[world]\nextent = 1024\nheight_range = [0, 400]\nspacing = 2\nterraces = true\n").unwrap();
    let out = dir.join("nodes");
    let (ok, text, err) = vista(&["bake", "--scene", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(text.contains("procedural (seed 1, terraced)"), "{text}");
    assert!(node_files(&out) > 0, "{text}");
}

#[test]
fn memory_prints_totals() {
    let (ok, text, err) = vista(&["memory", "--slots", "512"]);
    assert!(ok, "{err}");
    assert!(text.contains("total for 512 nodes") && text.contains("GPU MiB"), "{text}");
    assert!(text.contains("every node resident"), "{text}");
}

#[test]
fn bad_inputs_fail_with_one_line_naming_the_problem() {
    let dir = temp_dir("bad");
    let o = dir.join("out");
    let o = o.to_str().unwrap();
    let missing = dir.join("nope.png");
    let missing = missing.to_str().unwrap();
    assert_fails_naming(
        &["bake", "--out", o, "--heightmap", missing, "--extent", "100", "--height-range", "0", "1"],
        &["nope.png"],
    );
    assert_fails_naming(&["bake", "--out", o, "--heightmap", MONTBLANC], &["--extent"]);
    assert_fails_naming(&["bake", "--out", o, "--heightmap", MONTBLANC, "--extent", "60000"], &["--height-range"]);
    assert_fails_naming(&["bake", "--out", o, "--region", "1,2,3"], &["region"]);
    assert_fails_naming(&["bake", "--out", o, "--region", "5,5,1,1"], &["region"]);
    assert_fails_naming(&["bake", "--out", o, "--region", "a,b,c,d"], &["region"]);
    assert_fails_naming(&["bake", "--out", o, "--region", "20000,0,30000,10"], &["region", "overlap"]);
    assert_fails_naming(&["bake", "--out", o, "--extent", "1e12"], &["1000000000000", "sectors"]);
    assert_fails_naming(&["bake", "--out", o, "--extent", "-3"], &["extent"]);
    assert_fails_naming(&["bake", "--out", o, "--spacing", "0"], &["spacing"]);
    assert_fails_naming(&["bake", "--out", o, "--spacing", "-1"], &["spacing"]);
    assert_fails_naming(&["bake", "--out", o, "--region", "-9,-9,-1,-1"], &["region", "overlap"]);
    assert_fails_naming(&["bake", "--out", o, "--lods", "11"], &["--lods 11"]);
    assert_fails_naming(&["bake", "--out", o, "--hole-circle", "1,2,-1"], &["hole circle"]);
    assert_fails_naming(&["bake"], &["--out"]);
    assert_fails_naming(&["memory", "--slots", "0"], &["--slots"]);
    // render takes the same world arguments and validates them.
    assert_fails_naming(&["render", "--heightmap", MONTBLANC], &["--extent"]);

    let bad_scene = dir.join("bad.toml");
    std::fs::write(&bad_scene, "[world]\nextent = [1, 2\n").unwrap();
    assert_fails_naming(&["bake", "--out", o, "--scene", bad_scene.to_str().unwrap()], &["bad.toml"]);
    let typo = dir.join("typo.toml");
    std::fs::write(&typo, "[world]\nextents = 5\n").unwrap();
    assert_fails_naming(&["bake", "--out", o, "--scene", typo.to_str().unwrap()], &["typo.toml", "extents"]);
    assert_fails_naming(
        &["bake", "--out", o, "--scene", bad_scene.to_str().unwrap(), "--heightmap", MONTBLANC],
        &["--scene", "--heightmap"],
    );
    // Terraces shape the procedural world only.
    let terraced_map = dir.join("terraced.toml");
    std::fs::write(
        &terraced_map,
        format!("[world]\nsource = \"{MONTBLANC}\"\nextent = 60000\nheight_range = [454, 4810]\nterraces = true\n"),
    )
    .unwrap();
    assert_fails_naming(&["bake", "--out", o, "--scene", terraced_map.to_str().unwrap()], &["terraces"]);
    let not_image = dir.join("heights.png");
    std::fs::write(&not_image, "definitely not a png").unwrap();
    assert_fails_naming(
        &[
            "bake",
            "--out",
            o,
            "--heightmap",
            not_image.to_str().unwrap(),
            "--extent",
            "100",
            "--height-range",
            "0",
            "1",
        ],
        &["heights.png", "neither a PNG,"],
    );
    assert_eq!(node_files(Path::new(o)), 0, "nothing baked on bad input");
}

/// Writes a single-channel f32 EXR (row 0 north), as a user's tool would.
fn write_exr(path: &Path, w: usize, h: usize, heights: Vec<f32>) {
    use exr::prelude::*;
    let channel = AnyChannel::new("Y", FlatSamples::F32(heights));
    let layer = Layer::new(
        (w, h),
        LayerAttributes::named("height"),
        Encoding::UNCOMPRESSED,
        AnyChannels::sort(SmallVec::from_vec(vec![channel])),
    );
    Image::from_layer(layer).write().to_file(path).expect("write test EXR");
}

/// 8x8 heights 0..63 m, with three pixels far above 1000 m and two below 0:
/// five of 64 outside 0..1000.
fn exr_with_outliers(dir: &Path) -> PathBuf {
    let mut heights: Vec<f32> = (0..64).map(|k| k as f32).collect();
    heights[9] = 1500.0;
    heights[10] = 1200.0;
    heights[40] = 1000.5;
    heights[20] = -12.0;
    heights[50] = -0.25;
    let path = dir.join("outliers.exr");
    write_exr(&path, 8, 8, heights);
    path
}

/// One 512 m node per LOD (2 LODs) at 4 m spacing: quick to bake.
const SMALL: [&str; 8] = ["--extent", "512", "--spacing", "4", "--lods", "2", "--region", "0,0,10,10"];

#[test]
fn an_exr_height_range_that_clips_fails_naming_the_count() {
    let dir = temp_dir("exr-clip");
    let exr = exr_with_outliers(&dir);
    let (e, o) = (exr.to_str().unwrap(), dir.join("nodes"));
    let o = o.to_str().unwrap();
    let args = [&["bake", "--heightmap", e, "--out", o][..], &SMALL[..]].concat();
    let clip = [&args[..], &["--height-range", "0", "1000"][..]].concat();
    assert_fails_naming(
        &clip,
        &[
            "--height-range 0 1000 clips 5 of 64 samples",
            "outliers.exr",
            "min -12.0 m, max 1500.0 m",
            "--clamp-heights",
        ],
    );
    assert_eq!(node_files(Path::new(o)), 0, "nothing baked");

    // Asked for: clamped, and said how many.
    let (ok, text, err) = vista(&[&clip[..], &["--clamp-heights"][..]].concat());
    assert!(ok, "{err}");
    assert!(err.contains("5 of 64 samples") && err.contains("clamped"), "{err}");
    assert!(text.contains("heights 0..1000 m"), "{text}");

    // A range holding every pixel passes, but Catmull-Rom overshoots next
    // to the 1500 m spike (its negative lobe weighs a neighbour by down to
    // -0.074: about -100 m below the ground around it): said, not refused.
    let (ok, _, err) = vista(&[&args[..], &["--height-range", "-20", "1600"][..]].concat());
    assert!(ok && err.contains("warning") && err.contains("resampling between them reaches"), "{err}");
    // One holding the overshoot too passes without a word.
    let (ok, _, err) = vista(&[&args[..], &["--height-range", "-200", "1700", "--no-progress"][..]].concat());
    assert!(ok && err.is_empty(), "{err}");

    // The scene's height_range is held to the same rule, and says how to opt out there.
    let scene = dir.join("s.toml");
    let text = "[world]\nsource = \"outliers.exr\"\nextent = 512\nheight_range = [0, 1000]\nspacing = 4\nlods = 2\n";
    std::fs::write(&scene, text).unwrap();
    let s = scene.to_str().unwrap();
    let scene_args = ["bake", "--scene", s, "--out", o, "--region", "0,0,10,10"];
    assert_fails_naming(&scene_args, &["height_range [0, 1000] clips 5 of 64 samples", "clamp_heights = true"]);
    std::fs::write(&scene, format!("{text}clamp_heights = true\n")).unwrap();
    let (ok, _, err) = vista(&scene_args);
    assert!(ok && err.contains("5 of 64 samples"), "{err}");
}

#[test]
fn the_automatic_exr_range_holds_every_resampled_height() {
    // A 100 m cliff along x. The Catmull-Rom cubic through 0, 0, 0, 100 is
    // 50 (t³ - t²): it dips to -200/27 = -7.41 m at t = 2/3 (and mirrored
    // rises to 107.41 m), below and above every pixel.
    let dir = temp_dir("exr-auto");
    let (w, h) = (16, 8);
    let heights: Vec<f32> = (0..w * h).map(|k| if k % w < 8 { 0.0 } else { 100.0 }).collect();
    let exr = dir.join("cliff.exr");
    write_exr(&exr, w, h, heights);
    let json = dir.join("bake.json");
    let (e, o, j) = (exr.to_str().unwrap(), dir.join("nodes"), json.to_str().unwrap());
    let args = [&["bake", "--heightmap", e, "--out", o.to_str().unwrap(), "--json", j][..], &SMALL[..]].concat();
    let (ok, _, err) = vista(&args);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let range = &v["world"]["height_range_m"];
    let (lo, hi) = (range[0].as_f64().unwrap() as f32, range[1].as_f64().unwrap() as f32);
    let overshoot = 200.0 / 27.0;
    assert!(lo <= -overshoot && lo > -overshoot - 0.01, "low end {lo}");
    assert!(hi >= 100.0 + overshoot && hi < 100.0 + overshoot + 0.01, "high end {hi}");

    // Sampled between the pixel centres (32 steps per pixel), nothing
    // leaves the range, and the cliff does overshoot the pixels.
    use vista::world::HeightSource as _;
    let src = vista::world::ExrSource::open(&exr, [512.0, 512.0]).unwrap();
    let (mut mn, mut mx) = (f32::INFINITY, f32::NEG_INFINITY);
    for j in 0..=h * 32 {
        for i in 0..=w * 32 {
            let s = src.sample(512.0 * i as f64 / (w * 32) as f64, 512.0 * j as f64 / (h * 32) as f64);
            (mn, mx) = (mn.min(s), mx.max(s));
        }
    }
    assert!(lo <= mn && mx <= hi, "samples {mn}..{mx} outside {lo}..{hi}");
    assert!(mn < -7.0 && mx > 107.0, "the cliff overshoots: {mn}..{mx}");
}

#[test]
fn paths_of_the_wrong_kind_are_named_with_their_option() {
    let dir = temp_dir("paths");
    let file = dir.join("afile");
    std::fs::write(&file, "x").unwrap();
    let (f, d) = (file.to_str().unwrap(), dir.to_str().unwrap());
    let under = file.join("sub");
    let region = ["--region", "0,0,10,10"];
    for (args, needles) in [
        (vec!["bake", "--out", f], vec!["--out", "afile is a file", "choose another --out"]),
        (vec!["bake", "--out", under.to_str().unwrap()], vec!["--out", "afile is a file, not a folder"]),
        (vec!["bake", "--out", d, "--json", d], vec!["--json", "is a folder"]),
        (vec!["bake", "--out", d, "--heightmap", d, "--extent", "100"], vec!["--heightmap", "is a directory"]),
        (vec!["bake", "--out", d, "--scene", d], vec!["--scene", "is a directory"]),
    ] {
        let (ok, _, err) = vista(&[&args[..], &region[..]].concat());
        assert!(!ok && err.trim_end().lines().count() == 1, "{args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{args:?}: {n:?} missing from: {err}");
        }
        // Not the OS's words, twice or at all.
        for bad in ["File exists", "Is a directory", "Not a directory", "too short"] {
            assert!(!err.contains(bad), "{args:?}: {err}");
        }
    }
    let empty = dir.join("empty.exr");
    std::fs::write(&empty, "").unwrap();
    let args = ["bake", "--out", d, "--heightmap", empty.to_str().unwrap(), "--extent", "100"];
    assert_fails_naming(&args, &["--heightmap", "empty.exr", "too short to be a PNG, EXR or GeoTIFF file"]);
}

#[test]
fn repeated_single_valued_options_are_errors() {
    let dir = temp_dir("repeat");
    let o = dir.to_str().unwrap();
    for (args, option) in [
        (&["bake", "--out", o, "--extent", "100", "--extent", "200"][..], "--extent"),
        (&["bake", "--out", o, "--height-range", "0", "1", "--height-range", "2", "3"][..], "--height-range"),
        (&["bake", "--out", o, "--out", o][..], "--out"),
        (&["render", "--size", "64x48", "--size", "32x32"][..], "--size"),
        (&["render", "--camera", "1,2,3", "--camera", "4,5,6"][..], "--camera"),
    ] {
        assert_fails_naming(args, &[option, "multiple times"]);
    }
}

#[test]
fn memory_json_gives_the_bytes_per_node_of_each_payload_format() {
    let dir = temp_dir("memory-json");
    let small = ["--extent", "2048", "--spacing", "2", "--lods", "4"];
    let per_node = |payload: &str| {
        let json = dir.join(format!("{payload}.json"));
        let args = [&["memory", "--payload", payload, "--json", json.to_str().unwrap()][..], &small[..]].concat();
        let (ok, out, err) = vista(&args);
        assert!(ok, "{out}{err}");
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let kinds = v["kinds"].as_array().unwrap();
        let sum = |key: &str| kinds.iter().map(|k| k[key].as_u64().unwrap()).sum::<u64>();
        assert_eq!(v["cpu_bytes_per_node"].as_u64(), Some(sum("cpu_bytes")));
        assert_eq!(v["gpu_bytes_per_node"].as_u64(), Some(sum("gpu_bytes")));
        (v["cpu_bytes_per_node"].as_u64().unwrap(), v["gpu_bytes_per_node"].as_u64().unwrap())
    };
    // Derived by hand: heights 132 * 132 * 2 (a 2-sample border), normal BC3 33 * 33 blocks of
    // 16 bytes, albedo BC1 of 8, splat 65 * 65, patch min/max, holes and
    // errors 256 * (4 + 1 + 8), cones 64 * 16 (one per 2 x 2 patches), node
    // desc + error 12.
    let bc_gpu = 132 * 132 * 2 + 33 * 33 * 16 + 33 * 33 * 8 + 65 * 65 + 256 * 13 + 64 * 16 + 12;
    // The floor: at most 70 KB a resident node on the GPU.
    assert!(bc_gpu <= 70_000);
    // What the default effects keep: no splat (effect off) and no hole
    // bits (no holes), each baked but not uploaded.
    let not_kept = 65 * 65 + 256;
    assert_eq!(per_node("bc").1, bc_gpu - not_kept);
    // RGBA8 layers: 132 * 132 * 4 each.
    assert_eq!(per_node("rgba8").1, bc_gpu - not_kept - 33 * 33 * 24 + 2 * 132 * 132 * 4);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs vista, killing it if it has not exited after a minute: a hang is
/// the failure this guards against, not slowness (no timing is asserted).
fn vista_or_hang(args: &[&str]) -> (Option<i32>, String) {
    let mut child = vista_cmd()
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run vista");
    for _ in 0..1200 {
        if let Some(status) = child.try_wait().unwrap() {
            let mut err = String::new();
            std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
            return (status.code(), err);
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let _ = child.kill();
    panic!("{args:?} hung");
}

#[test]
fn inputs_that_are_not_regular_files_are_refused_without_opening_them() {
    let dir = temp_dir("fifo");
    let fifo = dir.join("map.png");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let f = fifo.to_str().unwrap();
    let scene = dir.join("fifo-source.toml");
    std::fs::write(&scene, format!("[world]\nsource = {f:?}\nextent = 1000\nheight_range = [0, 100]\n")).unwrap();
    let s = scene.to_str().unwrap();
    let map = ["--extent", "1000", "--height-range", "0", "100"];
    for (args, needle) in [
        (&[&["bake", "--dry-run", "--heightmap", f][..], &map[..]].concat(), "--heightmap"),
        (&[&["memory", "--heightmap", f][..], &map[..]].concat(), "--heightmap"),
        (&[&["render", "--heightmap", f][..], &map[..]].concat(), "--heightmap"),
        (&vec!["render", "--scene", f], "--scene"),
        (&vec!["bake", "--dry-run", "--scene", s], "source"),
        (&[&["memory", "--heightmap", "/dev/zero"][..], &map[..]].concat(), "a device"),
    ] {
        let (code, err) = vista_or_hang(args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle) && err.contains("not a regular file"), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_option_acts_or_is_refused() {
    let dir = temp_dir("nothing-ignored");
    // --clamp-heights has EXR data to clamp or nothing: refused otherwise.
    assert_fails_naming(&["bake", "--dry-run", "--clamp-heights"], &["--clamp-heights", "procedural", "drop it"]);
    let png = ["--heightmap", MONTBLANC, "--extent", "60000", "--height-range", "454", "4810", "--spacing", "8"];
    let args = [&["bake", "--dry-run", "--clamp-heights"][..], &png[..]].concat();
    assert_fails_naming(&args, &["--clamp-heights", "is a PNG", "drop it"]);

    // A dry run writes its plan as JSON when asked (and says so by exit 0).
    let json = dir.join("plan.json");
    let small = ["--extent", "2048", "--spacing", "2", "--lods", "4"];
    let args = [&["bake", "--dry-run", "--json", json.to_str().unwrap()][..], &small[..]].concat();
    let (ok, _, err) = vista(&args);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // 2048 m at 2 m spacing: LOD-0 nodes of 256 m, 8 x 8 of them, then 4 x 4, 2 x 2, 1.
    let nodes: Vec<u64> = v["plan"]["nodes_per_lod"].as_array().unwrap().iter().map(|n| n.as_u64().unwrap()).collect();
    assert_eq!(nodes, [64, 16, 4, 1]);
    assert!(v["refused"].is_null() && v["estimated_seconds"].as_f64().unwrap() > 0.0, "{v}");
    // A refused plan is written too, with the refusal.
    let args = [&["bake", "--dry-run", "--max-disk", "0", "--json", json.to_str().unwrap()][..]].concat();
    let (ok, _, _) = vista(&args);
    assert!(!ok);
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(v["refused"].as_str().is_some_and(|r| r.contains("disk")), "{v}");

    // A scene value replaced on the command line, and a hole that misses
    // the world: one line each, and the run goes on.
    let scene = dir.join("s.toml");
    std::fs::write(&scene, "[world]\nspacing = 2\nextent = 2048\nlods = 4\n[[holes]]\ncircle = [5000, 5000, 20]\n")
        .unwrap();
    let (ok, _, err) = vista(&["bake", "--dry-run", "--scene", scene.to_str().unwrap(), "--spacing", "4"]);
    assert!(ok, "{err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 2, "{err}");
    assert!(lines.contains(&"note: --spacing 4 replaces the scene's spacing 2"), "{err}");
    assert!(err.contains("hole 1 (circle at 5000,5000 radius 20) lies outside the world"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scene's stamps: baked on top of the world, a stamp added to a baked
/// scene rebakes only the nodes it touches (the bake says how many), and a
/// bad stamp is one line naming it.
#[test]
fn a_stamp_added_to_a_baked_scene_rebakes_only_what_it_touches() {
    let dir = temp_dir("stamps");
    let stamps = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/stamps");
    // The procedural world spans its whole height range: a stamp may only
    // raise the ground to within it (max), not add on top of its peaks.
    let world = "[world]\nsource = \"procedural\"\nextent = 2048\nheight_range = [0, 600]\nspacing = 2\nlods = 4\n";
    let plain = dir.join("plain.toml");
    std::fs::write(&plain, world).unwrap();
    let stamp = format!(
        "[[stamps]]\nsource = \"{stamps}/crater.png\"\ncenter = [500, 600]\nsize = 300\nheight = 80\noffset = 100\n\
         blend = \"max\"\nfalloff = 30\n"
    );
    let stamped = dir.join("stamped.toml");
    std::fs::write(&stamped, format!("{world}{stamp}")).unwrap();
    let out = dir.join("nodes");
    let o = out.to_str().unwrap();
    let (ok, text, err) = vista(&["bake", "--scene", plain.to_str().unwrap(), "--out", o, "--no-progress"]);
    assert!(ok, "{err}");
    assert!(text.contains("0 reused, 0 rebaked, 85 new"), "{text}");
    let (ok, text, err) = vista(&["bake", "--scene", stamped.to_str().unwrap(), "--out", o, "--no-progress"]);
    assert!(ok, "{err}");
    assert!(text.contains("with 1 stamp"), "{text}");
    // The crater covers 350..650 x 450..750 m: it straddles x = 512 and
    // y = 512, the edges of 2 x 2 LOD-0 nodes (256 m) and of 2 x 2 LOD-1
    // nodes (512 m), inside one node each of LOD 2 and 3: 10 of 85.
    assert!(text.contains("75 reused, 10 rebaked, 0 new"), "{text}");

    let bad = format!("{world}{}", stamp.replace("\"max\"", "\"ad\""));
    std::fs::write(&stamped, bad).unwrap();
    assert_fails_naming(
        &["bake", "--scene", stamped.to_str().unwrap(), "--out", o],
        &["stamp 1", "crater.png", "blend \"ad\" is not one of replace, add, max, min"],
    );
    std::fs::write(&stamped, format!("{world}{}", stamp.replace("height = 80", "height = 3000"))).unwrap();
    assert_fails_naming(
        &["bake", "--scene", stamped.to_str().unwrap(), "--out", o],
        &["stamp 1 (max at 500,600)", "outside the world's height range 0..600 m"],
    );
    std::fs::write(&stamped, format!("{world}{}", stamp.replace("crater.png", "missing.png"))).unwrap();
    assert_fails_naming(&["bake", "--scene", stamped.to_str().unwrap(), "--out", o], &["stamp 1", "missing.png"]);
    let _ = std::fs::remove_dir_all(&dir);
}
