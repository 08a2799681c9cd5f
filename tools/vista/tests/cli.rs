//! The command line: `vista info` reports the device and the queue mode;
//! bad arguments exit non-zero with a one-line error.

mod vista_cmd;

use vista_cmd::vista_cmd;

fn vista(args: &[&str]) -> (bool, String, String) {
    let out = vista_cmd().args(args).output().expect("run vista");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

#[test]
fn info_reports_device_queues_and_limits() {
    let (ok, out, err) = vista(&["--validation", "info"]);
    assert!(ok, "{err}");
    for key in [
        "device:",
        "driver:",
        "vulkan:",
        "queue families:",
        "async compute:",
        "compute shared memory:",
        "subgroup size:",
        "timestamps:",
    ] {
        assert!(out.contains(key), "missing {key:?} in:\n{out}");
    }
    if out.contains("llvmpipe") {
        // One queue family: info must not claim async compute.
        assert!(out.contains("async compute: not available"), "lavapipe has one queue family:\n{out}");
        assert!(out.contains("32768 bytes"), "lavapipe shared memory:\n{out}");
    }
}

#[test]
fn render_prints_pass_timings_and_writes_every_output() {
    let dir = std::env::temp_dir().join(format!("vista-render-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let args = ["--validation", "render", "--size", "64x48", "--frames", "5", "--out", dir.to_str().unwrap()];
    let (ok, out, err) = vista(&args);
    assert!(ok, "{err}");
    // One table row per pass: name, queue, then a median in ms.
    // The default world: no holes (no terrain_holes), no splat or cliffs
    // (only the far atlas variant of gbuffer_tiles), and settled streaming
    // leaves quadtree_update idle.
    for pass in [
        "traverse",
        "lod_map",
        "sector_data",
        "cull_patches",
        "terrain_geometry",
        "classify_tiles",
        "gbuffer_tiles[far_atlas]",
        "lighting_resolve",
    ] {
        let row = out.lines().find(|l| l.split_whitespace().next() == Some(pass));
        let fields: Vec<&str> =
            row.unwrap_or_else(|| panic!("no timing row for {pass}:\n{out}")).split_whitespace().collect();
        assert!(fields[2].parse::<f64>().is_ok_and(|ms| ms > 0.0), "{pass}: no median in {fields:?}");
    }
    assert!(out.contains("patches:") && out.contains("triangles submitted"), "{out}");
    let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("stats.json")).unwrap()).unwrap();
    let p = &stats["patches"];
    let n = |k: &str| p[k].as_u64().unwrap_or_else(|| panic!("stats.json lacks patches.{k}"));
    assert!(n("patches_in") >= n("after_frustum") && n("after_frustum") >= n("after_cone"));
    // Occlusion (on by default) may cull survivors; both phases add up.
    assert!(n("after_cone") >= n("after_hole") && n("after_hole") >= n("drawn") && n("drawn") > 0, "{p}");
    assert_eq!(n("drawn"), n("drawn_phase1") + n("drawn_phase2"), "{p}");
    assert!(out.contains("queues: single: every pass in one command buffer"), "{out}");
    for absent in ["terrain_holes", "gbuffer_tiles[far_atlas+splat]", "gbuffer_tiles[near_cliff]"] {
        assert!(!out.lines().any(|l| l.split_whitespace().next() == Some(absent)), "{absent} ran:\n{out}");
    }
    // An 8 x 8-quad patch: 128 triangles.
    assert_eq!(stats["triangles_drawn"].as_u64(), Some(n("drawn") * 128));
    let img = image::open(dir.join("image.png")).unwrap();
    assert_eq!((img.width(), img.height()), (64, 48));
    let depth = exr::prelude::read_first_flat_layer_from_file(dir.join("depth.exr")).unwrap();
    assert_eq!(depth.layer_data.size.0, 64);
    let z = &depth.layer_data.channel_data.list;
    assert_eq!(z.len(), 1, "one channel");
    assert_eq!(z[0].name.to_string(), "Z");
    let values: Vec<f32> = z[0].sample_data.values_as_f32().collect();
    // The default view looks down over the world from its south edge: the
    // bottom row is ground a few hundred metres away, the top row sky.
    assert!(values[47 * 64..].iter().all(|&d| d > 50.0 && d < 5000.0), "bottom row depth");
    assert!(values[..64].iter().all(|&d| d == 0.0), "top row should be sky (0)");
    for f in ["timings.json", "trace.json", "report.json"] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    printed_timings_match_the_json(&out, &dir.join("timings.json"));
    // The lit image in HDR (R, G, B) and the classification view.
    let lit = exr::prelude::read_first_flat_layer_from_file(dir.join("lit.exr")).unwrap();
    let names: Vec<String> = lit.layer_data.channel_data.list.iter().map(|c| c.name.to_string()).collect();
    assert_eq!(names, ["B", "G", "R"], "lit.exr channels (sorted)");
    let r: Vec<f32> = lit.layer_data.channel_data.list[2].sample_data.values_as_f32().collect();
    assert!(r[47 * 64..].iter().all(|&v| v.is_finite() && v > 0.0), "lit ground row");
    let class = image::open(dir.join("classification.png")).unwrap().to_rgb8();
    assert_eq!(class.get_pixel(0, 0).0, [0, 0, 0], "sky: no flavour");
    assert_ne!(class.get_pixel(0, 47).0, [0, 0, 0], "ground: a flavour");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The frame count and every pass row printed are what timings.json holds:
/// `(... frames rendered: W warm-up, N timed; ...)` against its `frames`, and per pass the median
/// (printed to 4 decimals) and the sample count against its `summary`.
fn printed_timings_match_the_json(out: &str, json: &std::path::Path) {
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(json).unwrap()).unwrap();
    let header = out.lines().next().unwrap_or_default();
    let timed: usize = header
        .split(" timed;")
        .next()
        .and_then(|h| h.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no timed frame count in {header:?}"));
    assert_eq!(v["frames"].as_array().unwrap().len(), timed, "{header}");
    let summary = v["summary"].as_array().unwrap();
    assert!(!summary.is_empty());
    for pass in summary {
        let name = pass["name"].as_str().unwrap();
        let label = if pass["late"] == true { format!("{name} (phase 2)") } else { name.to_string() };
        // The label, then the queue column ("cull_patches" is not "cull_patches (phase 2)").
        fn cells<'a>(line: &'a str, label: &str) -> Option<Vec<&'a str>> {
            let f: Vec<&str> = line.strip_prefix(label)?.split_whitespace().collect();
            (f.len() == 5 && !f[0].starts_with('(')).then_some(f)
        }
        let fields = out.lines().find_map(|l| cells(l, &label)).unwrap_or_else(|| panic!("no row for {label}: {out}"));
        let median: f64 = fields[1].parse().unwrap();
        // Printed to 4 decimals: within half a unit of the last digit (plus
        // the binary representation's slack: 70.99305 prints as 70.9930).
        assert!((median - pass["median_ms"].as_f64().unwrap()).abs() <= 5e-5 + 1e-9, "{label}: {fields:?} vs {pass}");
        assert_eq!(fields[4].parse::<u64>().ok(), pass["samples"].as_u64(), "{label}: {fields:?} vs {pass}");
    }
}

#[test]
fn bad_views_fail_with_a_one_line_message() {
    for (args, needle) in [
        (&["render", "--camera", "1,2"][..], "X,Y,Z"),
        (&["render", "--camera", "1,2,3,4"][..], "X,Y,Z"),
        (&["render", "--camera", "1,2,3,0,-120"][..], "pitch"),
        (&["render", "--camera", "1,nan,3"][..], "camera"),
        (&["render", "--fov", "0"][..], "--fov"),
        (&["render", "--fov", "180"][..], "--fov"),
        (&["render", "--target-error", "0"][..], "--target-error"),
        (&["render", "--cull", "frustum,bogus"][..], "bogus"),
    ] {
        let (ok, _, err) = vista(args);
        assert!(!ok, "{args:?} succeeded");
        assert!(err.contains(needle) && err.trim().lines().count() == 1, "{args:?}: {err}");
    }
}

#[test]
fn bad_arguments_fail_with_a_clear_message() {
    let (ok, _, err) = vista(&["render", "--size", "0x10"]);
    assert!(!ok);
    assert!(err.contains("0x10") || err.contains("size"), "{err}");
    let (ok, _, err) = vista(&["render", "--frames", "0"]);
    assert!(!ok);
    assert!(err.contains("--frames"), "{err}");
    let (ok, _, err) = vista(&["--device", "no-such-gpu-xyz", "info"]);
    assert!(!ok);
    // Names what there is instead of an empty list of rejected devices.
    assert!(err.contains("no-such-gpu-xyz") && err.contains("usable: ") && !err.contains("[]"), "{err}");
}

/// A tiny world, so a check that needs the device stays quick.
const TINY: [&str; 10] = ["--extent", "2048", "--spacing", "2", "--lods", "4", "--size", "64x48", "--frames", "1"];

#[test]
fn negative_camera_coordinates_are_numbers() {
    // --fov 0 fails after the camera was parsed, before any rendering: the
    // error is about --fov, not an unexpected '-5'.
    for camera in [&["--camera", "-5,10,20"][..], &["--camera=-5,-10,20,-90,-45"][..]] {
        let (ok, _, err) = vista(&[&["render"][..], camera, &TINY[..], &["--fov", "0"][..]].concat());
        assert!(!ok && err.contains("--fov") && !err.contains("unexpected"), "{camera:?}: {err}");
    }
    // bench: --sets 0 is refused once the device is up, nothing measured.
    let args = ["bench", "traverse", "--camera", "-5,-10,20", "--sets", "0"];
    let (ok, _, err) = vista(&args);
    assert!(!ok && err.contains("--sets") && !err.contains("unexpected"), "{err}");
}

#[test]
fn negative_numbers_reach_their_option_check() {
    // Each is refused by its option's own check (exit 2, one line naming
    // the option), not taken for an unknown flag '-1'.
    for (args, needle) in [
        (&["render", "--target-error", "-1"][..], "--target-error"),
        (&["render", "--fov", "-5"][..], "--fov"),
        (&["render", "--frames", "-1"][..], "--frames"),
        (&["render", "--spacing", "-1"][..], "--spacing -1"),
        (&["render", "--lods", "-2"][..], "--lods"),
        (&["bake", "--out", "unused", "--max-disk", "-1"][..], "--max-disk"),
        (&["memory", "--slots", "-3"][..], "--slots"),
        (&["bench", "cull", "--target-error", "-2"][..], "--target-error"),
    ] {
        let (code, _, err) = vista_code(args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(err.contains(needle) && !err.contains("unexpected argument"), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    }
}

#[test]
fn world_fields_are_named_as_the_user_gave_them() {
    let scene = std::env::temp_dir().join(format!("vista-lods12-{}.toml", std::process::id()));
    std::fs::write(&scene, "[world]\nlods = 12\n").unwrap();
    for (args, needles) in [
        (&["render", "--lods", "11"][..], &["--lods 11", "1 to 10 LODs"][..]),
        (&["render", "--scene", scene.to_str().unwrap()][..], &["the scene's lods 12"][..]),
        (&["render", "--spacing", "nan"][..], &["--spacing NaN"][..]),
        (&["render", "--height-range", "5", "1"][..], &["--height-range 5 1", "LO must be below HI"][..]),
        // Beyond what any --max-sectors allows (2^20 a side, the GPU's fields).
        (&["memory", "--extent", "1e30"][..], &["1.56e28 sectors of 64 m", "raise --spacing", "lower --extent"][..]),
    ] {
        let (code, _, err) = vista_code(args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{n:?} missing for {args:?}: {err}");
        }
        assert!(!err.contains("invalid world description") && err.trim().lines().count() == 1, "{err}");
    }
    let _ = std::fs::remove_file(&scene);
}

#[test]
fn bench_options_a_kind_does_not_use_are_errors() {
    for (args, needles) in [
        (&["bench", "cull", "--camera", "1,2,3"][..], &["bench cull does not use --camera"][..]),
        (&["bench", "traverse", "--size", "10x10", "--target-error", "2"][..], &["--size, --target-error", "them"][..]),
        (&["bench", "shade", "--sets", "64", "--views", "ground"][..], &["--sets, --views"][..]),
        (&["bench", "effects", "--plot", "p.png", "--slots", "64"][..], &["--plot, --slots"][..]),
        (&["bench", "cull", "--frames", "0"][..], &["--frames must be at least 1"][..]),
    ] {
        let (code, stdout, err) = vista_code(args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(stdout.is_empty(), "nothing measured: {stdout}");
        for n in needles {
            assert!(err.contains(n), "{n:?} missing for {args:?}: {err}");
        }
    }
}

#[test]
fn a_world_too_large_for_the_device_says_so_in_world_terms() {
    // 62 500 sectors of 64 m per side: over the default --max-sectors, and
    // with it raised, wider than any device's 2D images (the plan's device
    // check in the library, before the quadtree is allocated).
    let (ok, _, err) = vista(&["render", "--extent", "4000000", "--size", "8x8", "--frames", "1"]);
    assert!(!ok && err.contains("62500 x 62500 sectors of 64 m") && err.contains("--max-sectors"), "{err}");
    let args = ["render", "--extent", "4000000", "--max-sectors", "100000", "--size", "8x8", "--frames", "1"];
    let (ok, _, err) = vista(&args);
    assert!(!ok);
    // 10 LODs (the most): roots of 512 sectors, ceil(62500 / 512) = 123 a
    // side, padded to 123 * 512 = 62976 texels.
    for n in ["node texture would be 62976 x 62976 texels", "62500 x 62500 sectors", "this device allows", "--spacing"]
    {
        assert!(err.contains(n), "{n:?} missing from: {err}");
    }
    assert!(!err.contains("quadtree_nodes") && !err.contains("image \""), "{err}");
}

#[test]
fn render_out_is_checked_before_rendering() {
    let dir = std::env::temp_dir().join(format!("vista-render-out-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("afile");
    std::fs::write(&file, "x").unwrap();
    let png = dir.join("shot.png");
    let under = file.join("sub");
    for (out, needles) in [
        (&file, &["--out", "afile is a file", "takes a folder"][..]),
        (&under, &["--out", "afile is a file, not a folder"][..]),
        (&png, &["--out", "shot.png looks like a .png file"][..]),
    ] {
        // Refused before Vulkan starts: the same answer with no Vulkan driver.
        let (code, stdout, err) =
            vista_without_vulkan(&[&["render", "--out", out.to_str().unwrap()][..], &TINY[..]].concat());
        assert_eq!(code, Some(2), "{out:?}: {err}");
        assert!(stdout.is_empty(), "nothing rendered: {stdout}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        for n in needles {
            assert!(err.contains(n), "{n:?} missing from: {err}");
        }
        assert!(!err.contains("File exists"), "{err}");
    }
    assert!(!png.exists(), "a refused --out is not created");
    let (code, _, err) = vista_code(&[&["render", "--cache", file.to_str().unwrap()][..], &TINY[..]].concat());
    assert!(code == Some(2) && err.contains("--cache") && err.contains("is a file"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// As [`vista_code`] with the Vulkan loader pointed at no driver: a command
/// that reaches Vulkan fails there (`vista_without_vulkan_fails_at_vulkan`
/// shows it), so an answer about the input proves it came before.
fn vista_without_vulkan(args: &[&str]) -> (Option<i32>, String, String) {
    let out = vista_cmd()
        .args(args)
        .env("VK_ICD_FILENAMES", "/nonexistent/vista-no-driver.json")
        .env("VK_DRIVER_FILES", "/nonexistent/vista-no-driver.json")
        .output()
        .expect("run vista");
    (out.status.code(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

#[test]
fn vista_without_vulkan_fails_at_vulkan() {
    // The control for the refusals checked with `vista_without_vulkan`.
    let (code, _, err) = vista_without_vulkan(&["info"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("Vulkan"), "{err}");
}

#[test]
fn gpu_budgets_that_cannot_hold_the_roots_are_refused_before_vulkan() {
    // The default world keeps 64 KiB a node on the GPU (its payload table):
    // 5 MiB hold 80 nodes, fewer than its 100 minimum.
    for (budget, says) in [
        ("0", "a budget is a positive number of MiB"),
        ("nan", "a budget is a positive number of MiB"),
        ("-3", "a budget is a positive number of MiB"),
        ("5", "--gpu-budget 5 MiB holds 80 nodes of 64 KiB each: use 100 to 2047"),
    ] {
        let (code, stdout, err) =
            vista_without_vulkan(&["render", "--gpu-budget", budget, "--size", "8x8", "--frames", "1"]);
        assert_eq!(code, Some(2), "--gpu-budget {budget}: {err}");
        assert!(stdout.is_empty(), "{stdout}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(says), "{says:?} missing from: {err}");
    }
    let (code, _, err) = vista_without_vulkan(&["render", "--gpu-budget", "64", "--slots", "200"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--slots") && err.contains("--gpu-budget"), "{err}");
}

#[test]
fn a_gpu_budget_buys_its_size_over_a_node_s_bytes_in_slots() {
    let (ok, out, err) = vista(&["--validation", "render", "--gpu-budget", "10", "--size", "64x48", "--frames", "1"]);
    assert!(ok, "{err}");
    // The payload table's total row: "total for N nodes  CPU B/node  GPU B/node ...".
    let total = out.lines().find(|l| l.starts_with("total for")).unwrap_or_else(|| panic!("no payload total:\n{out}"));
    let gpu_per_node: u64 = total.split_whitespace().nth(5).and_then(|v| v.parse().ok()).expect("GPU B/node");
    let slots = (10 << 20) / gpu_per_node;
    let stream = out.lines().find(|l| l.starts_with("stream:")).expect("stream line");
    let expected = format!(
        "of {slots} slots (GPU budget 10.0 MiB (--gpu-budget), {:.0} KiB a node)",
        gpu_per_node as f64 / 1024.0
    );
    assert!(stream.contains(&expected), "{expected:?} missing from: {stream}");
}

#[test]
fn slot_budgets_the_renderer_cannot_use_are_refused_before_vulkan() {
    // The default world: 5 x 5 roots of 2 048 m, which may hold at most a
    // quarter of the slots: 100 to 2047 (slots are 11-bit).
    for (slots, why) in [("0", "root nodes"), ("1", "root nodes"), ("99", "root nodes"), ("2048", "11-bit")] {
        let (code, stdout, err) = vista_without_vulkan(&["render", "--slots", slots, "--size", "8x8", "--frames", "1"]);
        assert_eq!(code, Some(2), "--slots {slots}: {err}");
        assert!(stdout.is_empty(), "{stdout}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        for n in [&format!("--slots {slots}"), "use 100 to 2047", why] {
            assert!(err.contains(n), "{n:?} missing from: {err}");
        }
    }
}

fn vista_code(args: &[&str]) -> (Option<i32>, String, String) {
    let out = vista_cmd().args(args).output().expect("run vista");
    (out.status.code(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

/// A small procedural world (1 km, 3 LODs) with `effects` as its [effects] table.
fn scene_file(name: &str, effects: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("vista-scenes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    let text =
        format!("[world]\nextent = 1024\nheight_range = [0, 200]\nspacing = 1\nlods = 3\n\n[effects]\n{effects}\n");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn scene_effect_errors_are_one_line_with_exit_code_2() {
    for (name, effects, needles) in [
        ("unknown.toml", "holse = true", &["effects.holse", "unknown effect"][..]),
        ("type.toml", "holes = 3", &["effects.holes", "true, false or a table", "an integer"][..]),
        ("param.toml", "lighting = { sun_color = \"red\" }", &["effects.lighting.sun_color", "a string"][..]),
        (
            "missing.toml",
            "splat = { materials = \"no-such-materials.toml\" }",
            &["effects.splat.materials", "no-such-materials.toml", "does not exist"][..],
        ),
    ] {
        let path = scene_file(name, effects);
        let (code, _, err) = vista_code(&["render", "--scene", path.to_str().unwrap()]);
        assert_eq!(code, Some(2), "{name}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{name}: {err}");
        assert!(err.contains(path.to_str().unwrap()), "{name}: the message names the file: {err}");
        for n in needles {
            assert!(err.contains(n), "{name}: {n:?} missing in {err}");
        }
    }
}

#[test]
fn an_effect_without_its_data_is_reported_off_with_the_reason() {
    let path = scene_file("no-holes.toml", "holes = true\nqueries = true");
    let out = std::env::temp_dir().join(format!("vista-report-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let args = ["--validation", "render", "--scene", path.to_str().unwrap(), "--size", "48x32", "--frames", "3"];
    let (code, stdout, err) = vista_code(&[&args[..], &["--report", "--out", out.to_str().unwrap()]].concat());
    assert_eq!(code, Some(0), "{err}");
    let line = stdout.lines().find(|l| l.trim_start().starts_with("holes ")).unwrap_or_else(|| panic!("{stdout}"));
    assert!(line.contains("off") && line.contains("no hole regions"), "{line}");
    assert!(stdout.contains("terrain_holes") && stdout.contains("not built"), "{stdout}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let holes = report["effects"].as_array().unwrap().iter().find(|e| e["effect"] == "holes").unwrap();
    assert_eq!(holes["on"], false);
    assert_eq!(holes["requested"], true);
    let sector = report["passes"].as_array().unwrap().iter().find(|p| p["name"] == "sector_data").unwrap();
    assert_eq!(sector["state"], "ran", "queries asked for: sector data runs");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn render_says_which_queue_mode_ran() {
    let (ok, out, err) = vista(&["--validation", "render", "--size", "48x32", "--frames", "3", "--queues", "split"]);
    assert!(ok, "{err}");
    assert!(out.contains("queues: split: compute passes in their own command buffer"), "{out}");
    let (_, info, _) = vista(&["info"]);
    if info.contains("async compute: not available") {
        // Asked for, not silently replaced by another mode.
        let (code, _, err) = vista_code(&["render", "--size", "48x32", "--frames", "1", "--queues", "async"]);
        assert!(code != Some(0) && err.contains("no compute-only queue family"), "{err}");
    }
}

/// `vista stability` prints the table and runs case 7's second processes
/// (as is and with LP_NUM_THREADS=1); a case that does not exist is an
/// input error.
#[test]
fn stability_prints_the_table_and_compares_processes() {
    let json = std::env::temp_dir().join(format!("vista-stability-{}.json", std::process::id()));
    let (ok, out, err) = vista(&["stability", "--cases", "2,7", "--json", json.to_str().unwrap()]);
    assert!(ok, "{out}\n{err}");
    assert!(out.contains("| 2 depth |") && out.contains("| 7 determinism |"), "{out}");
    assert!(out.contains("a second process: 0 of 36 frames differ"), "{out}");
    assert!(out.contains("a second process with LP_NUM_THREADS=1: 0 of 36 frames differ"), "{out}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let cases = v["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 2);
    assert!(cases.iter().all(|c| c["pass"] == true));
    let _ = std::fs::remove_file(&json);
    let (code, _, err) = vista_code(&["stability", "--cases", "12"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("there is no case 12") && err.lines().count() == 1, "{err}");
}

/// `--origin` places the world: a render at UTM-like coordinates with the
/// camera given in them sees the same terrain as the unplaced world;
/// benchmarks, whose views are world-relative, refuse it.
#[test]
fn origin_places_the_world_and_benchmarks_refuse_it() {
    let small = ["--extent", "2048", "--spacing", "2", "--lods", "4", "--size", "64x48", "--frames", "1"];
    let dir = std::env::temp_dir().join(format!("vista-origin-{}", std::process::id()));
    let render = |extra: &[&str], out: &str| {
        let out_dir = dir.join(out);
        let mut args = vec!["render", "--out", out_dir.to_str().unwrap()];
        args.extend(small);
        args.extend(extra);
        let (ok, stdout, err) = vista(&args);
        assert!(ok, "{stdout}\n{err}");
        std::fs::read(out_dir.join("image.png")).unwrap()
    };
    let local = render(&["--camera", "1000.25,600.5,300,20,-12"], "local");
    let placed = render(&["--origin", "340000,5080000", "--camera", "341000.25,5080600.5,300,20,-12"], "placed");
    assert!(local == placed, "the placed world's image differs from the unplaced one's");
    let (code, _, err) = vista_code(&["bench", "cull", "--origin", "1,2", "--extent", "2048"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("drop --origin"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
