//! The `vista bench` kinds from the command line: each writes its table
//! and JSON, measured against the reference where it has one.

mod vista_cmd;

use vista_cmd::vista_cmd;

/// The small world most kinds are run on here: 2 km at 2 m, 4 LODs.
const SMALL_WORLD: [&str; 6] = ["--extent", "2048", "--spacing", "2", "--lods", "4"];

fn vista(args: &[&str]) -> (bool, String, String) {
    let out = vista_cmd().args(args).output().expect("run vista");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

#[test]
fn bench_traverse_writes_a_table_and_json() {
    let json = std::env::temp_dir().join(format!("vista-bench-{}.json", std::process::id()));
    let (ok, out, err) = vista(&[
        "--validation",
        "bench",
        "traverse",
        "--sets",
        "64",
        "--targets",
        "1,8",
        "--frames",
        "2",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    // The printed table, parsed into numbers, says what the JSON says:
    // requested resident target final one ms per-level ms ratio.
    let table: Vec<Vec<f64>> = out
        .lines()
        .map(|l| l.split_whitespace().filter(|f| *f != "ms").map(|f| f.parse::<f64>()).collect::<Result<Vec<_>, _>>())
        .filter_map(|r| r.ok().filter(|r| r.len() == 7))
        .collect();
    assert_eq!(table.len(), 2, "two numeric rows in:\n{out}");
    for (t, r) in table.iter().zip(rows) {
        assert_eq!(t[2], r["target_error_px"].as_f64().unwrap(), "{out}");
        assert_eq!(t[3], r["final_nodes"].as_f64().unwrap(), "{out}");
        let (one, per) = (r["single_dispatch_ms"].as_f64().unwrap(), r["multi_dispatch_ms"].as_f64().unwrap());
        assert!(
            (t[4] - one).abs() <= 5e-5 + 1e-9 && (t[5] - per).abs() <= 5e-5 + 1e-9,
            "printed to 4 decimals: {t:?} vs {r}"
        );
        assert!(
            (t[6] - r["ratio"].as_f64().unwrap()).abs() <= 5e-4 + 1e-9,
            "ratio printed to 3 decimals: {t:?} vs {r}"
        );
    }
    for r in rows {
        assert!(
            r["single_dispatch_ms"].as_f64().unwrap() > 0.0 && r["multi_dispatch_ms"].as_f64().unwrap() > 0.0,
            "{r}"
        );
        assert!(r["final_nodes"].as_u64().unwrap() > 0);
    }
}

/// The reduced form of `vista bench accuracy` (two targets, one view,
/// 128x128) so its plumbing cannot rot; the full sweep is a command.
#[test]
fn bench_accuracy_sweeps_targets_and_culling_against_the_reference() {
    let dir = std::env::temp_dir().join(format!("vista-bench-accuracy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (json, plot) = (dir.join("acc.json"), dir.join("acc.png"));
    let args = ["--size", "128x128", "--frames", "1", "--targets", "1,4", "--views", "high-flight"];
    let extra = ["--json", json.to_str().unwrap(), "--plot", plot.to_str().unwrap(), "--images", dir.to_str().unwrap()];
    let (ok, out, err) = vista(&[&["bench", "accuracy"][..], &SMALL_WORLD, &args, &extra].concat());
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let points = v["bench"]["points"].as_array().unwrap();
    // Two targets x culling on/off; no shading rows (no splat, no cliffs).
    assert_eq!(points.len(), 4, "{out}");
    assert!(v["bench"]["shading_skipped"].as_str().is_some(), "{out}");
    for p in points {
        assert_eq!(p["view"], "high flight");
        let e = &p["error"];
        assert!(p["gpu_ms"].as_f64().unwrap() > 0.0 && p["triangles_drawn"].as_u64().unwrap() > 0, "{p}");
        // A high view of a 2 km world: almost every pixel is terrain, and
        // the frame agrees with the reference on nearly all of them.
        assert!(e["terrain_pixels"].as_u64().unwrap() > 128 * 128 * 9 / 10, "{p}");
        assert!(e["depth_within_2pct"].as_f64().unwrap() > 0.95, "{p}");
        assert!(e["flip_mean"].as_f64().unwrap() < 0.2 && e["psnr_db"].as_f64().unwrap() > 20.0, "{p}");
        if p["family"] == "culling off" {
            assert_eq!(p["differs_from_culled_px"], 0, "culling changed the picture: {p}");
        }
    }
    let drawn = |t: f64| points.iter().find(|p| p["target_error_px"] == t && p["family"] == "culling off").unwrap();
    assert!(drawn(4.0)["triangles_drawn"].as_u64() <= drawn(1.0)["triangles_drawn"].as_u64(), "{out}");
    let png = image::open(&plot).expect("the plot is a PNG").to_rgb8();
    assert_eq!(png.dimensions(), (1400, 1000));
    for f in ["high_flight_reference.png", "high_flight_frame.png", "high_flight_flip.png"] {
        assert!(dir.join(f).is_file(), "{f} missing: {out}");
    }
    // Bad names fail before any work, naming the option.
    let (ok, _, err) = vista(&["bench", "accuracy", "--views", "sideways", "--extent", "2048", "--spacing", "2"]);
    assert!(!ok && err.contains("--views") && err.contains("facing-ridge"), "{err}");
    let (ok, _, err) = vista(&["bench", "accuracy", "--plot", "/nonexistent-dir/a.png"]);
    assert!(!ok && err.contains("--plot"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--fly`: popping rows only, per rule and target, under the validation
/// layer (the LOD camera's frames too).
#[test]
fn bench_accuracy_fly_measures_popping_per_rule_and_target() {
    let json = std::env::temp_dir().join(format!("vista-bench-fly-{}.json", std::process::id()));
    let args = ["--size", "96x64", "--targets", "1,4", "--views", "high-flight", "--lod-rules", "patch,triangle"];
    let extra = ["--fly", "20,2", "--json", json.to_str().unwrap()];
    let (ok, out, err) = vista(&[&["--validation", "bench", "accuracy"][..], &SMALL_WORLD, &args, &extra].concat());
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(v["bench"]["points"].as_array().unwrap().is_empty(), "--fly measures popping only: {out}");
    let rows = v["bench"]["popping"].as_array().unwrap();
    assert_eq!(rows.len(), 4, "two rules x two targets: {out}");
    for r in rows {
        assert_eq!(r["step_max_px"].as_array().unwrap().len(), 2, "{r}");
        let (p99, max) = (r["p99_px"].as_f64().unwrap(), r["max_px"].as_f64().unwrap());
        assert!(r["pixels"].as_u64().unwrap() > 96 * 64 && p99 >= 0.0 && p99 <= max && max.is_finite(), "{r}");
    }
    assert!(out.contains("popping: per step") && out.contains("triangle"), "{out}");
    // A malformed flight fails before any work, naming the option.
    let (ok, _, err) = vista(&["bench", "accuracy", "--fly", "2"]);
    assert!(!ok && err.contains("--fly") && err.contains("STEP,STEPS"), "{err}");
    let _ = std::fs::remove_file(&json);
}

#[test]
fn bench_shade_measures_every_shading_mode_per_view() {
    let json = std::env::temp_dir().join(format!("vista-bench-shade-{}.json", std::process::id()));
    let args =
        ["bench", "shade", "--extent", "2048", "--spacing", "2", "--lods", "4", "--size", "64x48", "--frames", "1"];
    let (ok, out, err) = vista(&[&args[..], &["--json", json.to_str().unwrap()]].concat());
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let views: Vec<&str> = v["views"].as_array().unwrap().iter().map(|w| w["name"].as_str().unwrap()).collect();
    assert!(views.first() == Some(&"cliff wall") && views.last() == Some(&"no cliffs"), "{views:?}");
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 4 * views.len(), "{out}");
    for r in rows {
        let shading = r["shading"].as_str().unwrap();
        assert!(r["shading_ms"].as_f64().unwrap() > 0.0, "{r}");
        // A one-pipeline shader has one draw and no classification share.
        let variants = r["variants"].as_array().unwrap().len();
        if shading == "tiled" {
            assert!(r["classify_fraction"].as_f64().is_some(), "{r}");
        } else {
            assert!(variants == 1 && r["classify_fraction"].is_null(), "{r}");
        }
    }
    assert!(out.contains("floor: classification <= 0.1"), "{out}");
    assert_eq!(v["stochastic_error"].as_array().unwrap().len(), views.len());
    let _ = std::fs::remove_file(&json);
}

#[test]
fn bench_cull_writes_a_row_per_view() {
    let json = std::env::temp_dir().join(format!("vista-bench-cull-{}.json", std::process::id()));
    let args =
        ["bench", "cull", "--extent", "2048", "--spacing", "2", "--lods", "4", "--size", "64x48", "--frames", "1"];
    let (ok, out, err) = vista(&[&args[..], &["--json", json.to_str().unwrap()]].concat());
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = v["rows"].as_array().unwrap();
    let views: Vec<&str> = rows.iter().map(|r| r["view"].as_str().unwrap()).collect();
    assert_eq!(views, ["ground", "low flight", "high flight", "facing ridge"], "{out}");
    for r in rows {
        let (all, none) = (&r["all"]["counters"], &r["none"]["counters"]);
        // Culling off draws every selected patch; on, never more.
        assert_eq!(none["drawn"], none["patches_in"], "{r}");
        assert!(all["drawn"].as_u64() <= all["patches_in"].as_u64(), "{r}");
        assert!(r["all"]["geometry_ms"].as_f64().unwrap() > 0.0, "{r}");
    }
    let _ = std::fs::remove_file(&json);
}

/// `bench cpu` on two small worlds (a 32 km far world at 16 m, so its error
/// tree is quick): one row each, the table saying what the JSON says, the
/// ratio the rows' own quotient, both renderers within the slots.
#[test]
fn bench_cpu_compares_a_world_with_a_larger_one() {
    let json = std::env::temp_dir().join(format!("vista-bench-cpu-{}.json", std::process::id()));
    let args = [
        &["--validation", "bench", "cpu"][..],
        &SMALL_WORLD,
        &[
            "--far-extent",
            "32768",
            "--far-spacing",
            "16",
            "--slots",
            "64",
            "--size",
            "64x48",
            "--frames",
            "2",
            "--json",
            json.to_str().unwrap(),
        ],
    ]
    .concat();
    let (ok, out, err) = vista(&args);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2, "{out}");
    assert_eq!(rows[0]["extent_m"][0].as_f64(), Some(2048.0));
    assert_eq!((rows[1]["extent_m"][0].as_f64(), rows[1]["spacing_m"].as_f64()), (Some(32768.0), Some(16.0)));
    // extent km, spacing, lods, roots, resident, cpu ms, p90 ms, query ms, ratio.
    let table: Vec<Vec<f64>> = out
        .lines()
        .map(|l| l.split_whitespace().take(9).map(str::parse::<f64>).collect::<Result<Vec<_>, _>>())
        .filter_map(|r| r.ok().filter(|r| r.len() == 9))
        .collect();
    assert_eq!(table.len(), 2, "two numeric rows in:\n{out}");
    for (t, r) in table.iter().zip(rows) {
        assert_eq!(t[3], r["roots"].as_f64().unwrap(), "{out}");
        assert_eq!(t[4], r["resident"].as_f64().unwrap(), "{out}");
        assert!(r["resident"].as_u64().unwrap() <= 64 && r["slots"].as_u64() == Some(64), "{r}");
        assert!((t[5] - r["cpu_ms"].as_f64().unwrap()).abs() <= 5e-4 + 1e-9, "{t:?} vs {r}");
        assert!(r["cpu_ms"].as_f64().unwrap() > 0.0 && r["samples"].as_u64() == Some(6), "3 rounds of 2: {r}");
    }
    let (a, b) = (rows[0]["cpu_ms"].as_f64().unwrap(), rows[1]["cpu_ms"].as_f64().unwrap());
    assert!((rows[1]["ratio"].as_f64().unwrap() - b / a).abs() < 1e-9 && rows[0]["ratio"].as_f64() == Some(1.0));
    let _ = std::fs::remove_file(&json);
}
