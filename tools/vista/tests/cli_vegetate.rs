//! `vista vegetate` as users and schedulers run it: two processes write
//! the same bytes; shards run at once into one folder write what one run
//! writes; moving a stamp remakes only the tiles within reach of it and
//! gives a fresh run's outputs; mistakes are one line. No GPU.

use std::path::{Path, PathBuf};
use std::process::Command;

mod vista_cmd;

use vista_cmd::vista_cmd;

const OUTPUTS: [&str; 6] =
    ["instances.bin", "vegetation.json", "occurrence-meadow.bin", "resource.png", "sun.png", "vegetation.png"];

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vista-cli-vegetate-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// A 1 024 m procedural world whose vegetation reaches 150 m, with a
/// crater stamped at `stamp_x` (metres east) in the south-west.
fn scene(dir: &Path, stamp_x: f64) -> PathBuf {
    let crater = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/stamps/crater.png");
    let text = format!(
        "[world]\nextent = 1024\nheight_range = [0, 500]\nspacing = 1\nlods = 3\n\n\
         [vegetation]\ncell_m = 4\nreach_m = 150\noccurrence_cell_m = 8\n\n\
         [[stamps]]\nsource = \"{}\"\ncenter = [{stamp_x}, 150]\nsize = 120\nheight = 40\noffset = 100\n",
        crater.display()
    );
    let path = dir.join(format!("scene-{stamp_x}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

fn vegetate(scene: &Path, out: &Path, extra: &[&str]) -> Command {
    let mut c = vista_cmd();
    c.arg("vegetate").arg("--scene").arg(scene).arg("--out").arg(out).args(extra);
    c
}

fn run(mut c: Command) -> (bool, String, String) {
    let out = c.output().expect("run vista");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

fn outputs(dir: &Path) -> Vec<(&'static str, Vec<u8>)> {
    OUTPUTS.iter().map(|f| (*f, std::fs::read(dir.join(f)).unwrap_or_else(|e| panic!("{f}: {e}")))).collect()
}

/// "tiles...: C computed, R reused" of a run's output.
fn tiles(stdout: &str) -> (usize, usize) {
    let line = stdout.lines().find(|l| l.starts_with("tiles")).expect("a tiles line");
    let words: Vec<&str> = line.split_whitespace().collect();
    let at = |w: &str| words[words.iter().position(|x| *x == w).unwrap() - 1].parse().unwrap();
    (at("computed,"), at("reused"))
}

#[test]
fn processes_shards_and_a_moved_stamp_write_what_one_run_writes() {
    let dir = temp_dir("runs");
    let first = scene(&dir, 150.0);
    let (a, b, shards) = (dir.join("a"), dir.join("b"), dir.join("shards"));
    let (ok, out, err) = run(vegetate(&first, &a, &[]));
    assert!(ok, "{err}");
    assert_eq!(tiles(&out), (16, 0), "{out}");
    assert!(out.contains("instances.bin (") && out.contains("meadow"), "{out}");
    assert!(run(vegetate(&first, &b, &[])).0);
    assert_eq!(outputs(&a), outputs(&b), "two processes, the same bytes");
    // Two shards at once into one folder.
    let mut kids: Vec<_> =
        ["0/2", "1/2"].iter().map(|s| vegetate(&first, &shards, &["--shard", s]).output().unwrap()).collect();
    kids.retain(|k| !k.status.success());
    assert!(kids.is_empty(), "a shard failed");
    assert_eq!(outputs(&a), outputs(&shards), "two shards write what one run writes");
    // Move the stamp 80 m east: the tiles within 150 m of either place
    // are made again (the south-west's), the others are kept.
    let moved = scene(&dir, 230.0);
    let (ok, out, err) = run(vegetate(&moved, &a, &[]));
    assert!(ok, "{err}");
    let (computed, reused) = tiles(&out);
    eprintln!("the moved stamp: {computed} tiles made again, {reused} kept");
    assert!(computed > 0 && reused > 0 && computed + reused == 16, "{out}");
    let fresh = dir.join("fresh");
    assert!(run(vegetate(&moved, &fresh, &[])).0);
    assert_eq!(outputs(&a), outputs(&fresh), "the incremental run writes what a full one does");
    assert_ne!(outputs(&a), outputs(&b), "the stamp moved the vegetation");
    let _ = std::fs::remove_dir_all(dir);
}

/// `--sun gpu` (under the validation layer) makes every tile again over a
/// CPU run's folder (the key names the marcher), reports the GPU's time,
/// and grows what the CPU grows within a few instances (a grazing ray);
/// a second GPU run reuses every tile.
#[test]
fn the_sun_on_the_gpu_keys_its_tiles_and_grows_what_the_cpu_grows() {
    let dir = temp_dir("gpu-sun");
    let first = scene(&dir, 150.0);
    let (cpu, gpu) = (dir.join("cpu"), dir.join("gpu"));
    assert!(run(vegetate(&first, &cpu, &[])).0);
    let gpu_run = |out: &Path| {
        let mut c = vista_cmd();
        c.arg("--validation").arg("vegetate").arg("--scene").arg(&first).arg("--out").arg(out).args(["--sun", "gpu"]);
        run(c)
    };
    std::fs::create_dir_all(&gpu).unwrap();
    for f in std::fs::read_dir(cpu.join("tiles")).unwrap() {
        let f = f.unwrap().path();
        std::fs::create_dir_all(gpu.join("tiles")).unwrap();
        std::fs::copy(&f, gpu.join("tiles").join(f.file_name().unwrap())).unwrap();
    }
    let (ok, out, err) = gpu_run(&gpu);
    assert!(ok, "{err}");
    assert_eq!(tiles(&out), (16, 0), "the CPU's tiles are not the GPU's: {out}");
    assert!(out.contains("sun: marched on the GPU ("), "{out}");
    let count = |d: &Path| std::fs::metadata(d.join("instances.bin")).unwrap().len() as i64 / 32;
    let (c, g) = (count(&cpu), count(&gpu));
    assert!((c - g).abs() <= c / 1000 + 2, "{c} instances on the CPU, {g} with the GPU's sun");
    let (ok, out, err) = gpu_run(&gpu);
    assert!(ok, "{err}");
    assert_eq!(tiles(&out), (0, 16), "a second GPU run reuses them: {out}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn mistakes_are_one_line_before_any_work() {
    let dir = temp_dir("mistakes");
    let good = scene(&dir, 150.0);
    let text = std::fs::read_to_string(&good).unwrap();
    let cases = [
        (text.replace("cell_m = 4", "cel_m = 4"), "unknown field `cel_m`"),
        (text.replace("reach_m = 150", "reach_m = 150\nflow = 2"), "flow must be in 0..=1"),
        (
            text.replace("occurrence_cell_m = 8", "occurrence_cell_m = 8\n[[vegetation.brushes]]\nname = \"b\"\nmaterials = [\"grass\"]\ntypes = [{ type = \"oak\", density = 0.1, scale = [1, 2] }]"),
            "type \"oak\" is not one of",
        ),
    ];
    for (i, (scene_text, want)) in cases.iter().enumerate() {
        let path = dir.join(format!("bad{i}.toml"));
        std::fs::write(&path, scene_text).unwrap();
        let out = vegetate(&path, &dir.join("out"), &[]).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{want}: {err}");
        assert!(err.contains(want) && err.trim().lines().count() == 1, "{want}: {err}");
    }
    for (args, want) in [
        (&["--cell", "0.01"][..], "raise cell_m"),
        (&["--shard", "2/2"][..], "--shard"),
        (&["--shard", "all/2"][..], "give I/2"),
        (&["--region", "5000,0,6000,100"][..], "does not overlap the world"),
        (&["--region", "10,0,5,100"][..], "needs MINX < MAXX"),
    ] {
        let out = vegetate(&good, &dir.join("out"), args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(want) && err.trim().lines().count() == 1, "{args:?}: {err}");
    }
    assert!(!dir.join("out").exists(), "nothing written for a refused run");
    let _ = std::fs::remove_dir_all(dir);
}

/// Seed 004's masks: a road decal with `clear_vegetation` and a
/// `[[vegetation_masks]]` disc keep every tree and bush off their
/// footprints (checked with the test's own geometry), and only there.
#[test]
fn a_cleared_road_and_a_mask_grow_nothing() {
    let dir = temp_dir("masks");
    let road = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/decals/road.png");
    let text = format!(
        "[world]\nextent = 1024\nheight_range = [0, 500]\nspacing = 1\nlods = 3\n\n\
         [vegetation]\ncell_m = 4\nreach_m = 150\noccurrence_cell_m = 8\n\n\
         [[vegetation_masks]]\ncircle = [500, 800, 50]\n\n\
         [[decals]]\ntexture = \"{}\"\nroad = {{ points = [[100, 500], [900, 520]], width = 12, repeat = 20 }}\n\
         clear_vegetation = true\n",
        road.display()
    );
    let scene = dir.join("masks.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let (ok, stdout, err) = run(vegetate(&scene, &out, &[]));
    assert!(ok, "{err}");
    let bytes = std::fs::read(out.join("instances.bin")).unwrap();
    let xy: Vec<[f64; 2]> = bytes
        .chunks_exact(32)
        .map(|c| [0, 4].map(|o| f64::from(f32::from_le_bytes(c[o..o + 4].try_into().unwrap()))))
        .collect();
    // Distance to the road's centre line (one segment, square at its
    // ends: nothing past them) and to the disc's centre.
    let to_road = |p: [f64; 2]| {
        let (a, b) = ([100.0, 500.0], [900.0, 520.0]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let t = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy);
        if (0.0..=1.0).contains(&t) {
            (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
        } else {
            f64::INFINITY
        }
    };
    let to_disc = |p: [f64; 2]| (p[0] - 500.0).hypot(p[1] - 800.0);
    let bad: Vec<_> = xy.iter().filter(|p| to_road(**p) <= 6.0 || to_disc(**p) <= 50.0).take(5).collect();
    assert!(bad.is_empty(), "instances on the road or in the mask: {bad:?} ({} in all)", xy.len());
    let beside = xy.iter().filter(|p| to_road(**p) < 20.0 || (to_disc(**p) < 70.0)).count();
    println!("{} instances, {beside} within 14 m of the road or 20 m of the disc; {stdout}", xy.len());
    assert!(beside > 20, "vegetation grows right beside them ({beside})");
    let _ = std::fs::remove_dir_all(dir);
}
