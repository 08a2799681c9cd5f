//! The frame executor returns per-pass GPU timings as data, late, and they
//! export as JSON and Chrome trace.

mod common;

use common::gpu_test;

#[test]
fn smoke_frames_report_every_pass_in_order() {
    gpu_test(|ctx| {
        let out = common::smoke::render(ctx, [64, 64], 6).unwrap();
        assert!(out.frames.len() >= 3, "timings came back for {} of 6 frames", out.frames.len());
        for f in &out.frames {
            let names: Vec<&str> = f.passes.iter().map(|p| p.name).collect();
            assert_eq!(names, ["prefix_sum", "smoke_triangle", "diamond_patch"]);
            for p in &f.passes {
                assert!(p.gpu_ms.is_finite() && p.gpu_ms >= 0.0 && p.start_ms >= 0.0, "{p:?}");
            }
            assert!(f.passes.windows(2).all(|w| w[1].start_ms >= w[0].start_ms));
        }
        let frames: Vec<u64> = out.frames.iter().map(|f| f.frame).collect();
        assert!(frames.windows(2).all(|w| w[1] > w[0]), "frames arrive in order: {frames:?}");
        let json: serde_json::Value = serde_json::from_str(&vista::profiler::to_json(&out.frames)).unwrap();
        assert_eq!(json["summary"].as_array().unwrap().len(), 3);
        let trace: serde_json::Value = serde_json::from_str(&vista::profiler::to_chrome_trace(&out.frames)).unwrap();
        let events = trace["traceEvents"].as_array().unwrap();
        assert_eq!(events.iter().filter(|e| e["ph"] == "X").count(), out.frames.len() * 3);
    });
}
