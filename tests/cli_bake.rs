//! `vista bake` / `vista memory` and the world arguments: small bakes of the
//! procedural world, Mont Blanc and a scene file; every bad input exits
//! non-zero with a one-line message naming the problem. No GPU needed.

use std::path::{Path, PathBuf};
use std::process::Command;

const MONTBLANC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/montblanc.png");

fn vista(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vista")).args(args).output().expect("run vista");
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
    // One node of each of the 6 LODs covers the 64 m corner.
    assert!(text.contains("nodes:    6 (lod0 1, lod1 1"), "{text}");
    assert!(text.contains("6 baked, 0 cached"), "{text}");
    assert!(text.contains("extrapolated") && text.contains("34125 nodes"), "{text}");
    assert!(text.contains("total for 512 nodes"), "{text}");
    assert_eq!(node_files(&out), 6);
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["nodes"], 6);
    assert_eq!(v["full_world_nodes"], 34125);
    assert!(v["extrapolated"]["bytes_on_disk"].as_f64().unwrap() > 0.0);

    // A second run finds every node in the cache.
    let (ok, text, err) = vista(&["bake", "--out", o, "--region", "0,0,64,64"]);
    assert!(ok, "{err}");
    assert!(text.contains("0 baked, 6 cached"), "{text}");
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
    // 1024 m sectors: 59 per side, 6 LODs.
    assert!(text.contains("(4690 nodes"), "{text}");
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
    assert_fails_naming(&["bake", "--out", o, "--lods", "11"], &["lod count"]);
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
        &["heights.png", "neither a PNG nor"],
    );
    assert_eq!(node_files(Path::new(o)), 0, "nothing baked on bad input");
}
