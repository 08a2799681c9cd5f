//! The command line: `vista info` reports the device and the queue mode;
//! bad arguments exit non-zero with a one-line error.

use std::process::Command;

fn vista(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vista")).args(args).output().expect("run vista");
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
        "culling:",
        "compute shared memory:",
        "subgroup size:",
        "timestamps:",
    ] {
        assert!(out.contains(key), "missing {key:?} in:\n{out}");
    }
    if out.contains("llvmpipe") {
        assert!(out.contains("single-queue fallback"), "lavapipe has one queue family:\n{out}");
        assert!(out.contains("32768 bytes"), "lavapipe shared memory:\n{out}");
    }
}

#[test]
fn render_prints_pass_timings() {
    let (ok, out, err) = vista(&["--validation", "render", "--size", "64x64", "--frames", "5"]);
    assert!(ok, "{err}");
    for pass in
        ["quadtree_update", "traverse", "lod_map", "sector_data", "prefix_sum", "smoke_triangle", "diamond_patch"]
    {
        assert!(out.contains(pass), "no timing for {pass}:\n{out}");
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
    assert!(err.contains("no-such-gpu-xyz"), "{err}");
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
    assert!(out.contains("one/per-level"), "{out}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for r in rows {
        assert!(
            r["single_dispatch_ms"].as_f64().unwrap() > 0.0 && r["multi_dispatch_ms"].as_f64().unwrap() > 0.0,
            "{r}"
        );
        assert!(r["final_nodes"].as_u64().unwrap() > 0);
    }
    let (ok, _, err) = vista(&["bench", "cull"]);
    assert!(!ok && err.contains("traverse"), "{err}");
}
