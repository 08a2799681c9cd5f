//! The frame executor returns per-pass GPU timings as data, late, in pass
//! order, and they measure the work: a pass with thousands of times more
//! triangles takes longer and starts after the tiny one ends. They export as
//! JSON (with medians) and Chrome trace.

mod common;

use common::diamond_patch::DiamondPatch;
use common::gpu_test;
use common::smoke_triangle::{SmokeTriangle, TARGET_FORMAT};
use vista::frame::{FrameExecutor, FrameTimings, QueueKind};
use vista::gpu::{vk, FrameRing, Image, ImageDesc};

#[test]
fn smoke_frames_report_every_pass_in_order() {
    gpu_test(|ctx| {
        let out = common::smoke::render(ctx, [64, 64], 6).unwrap();
        assert!(out.frames.len() >= 3, "timings came back for {} of 6 frames", out.frames.len());
        for f in &out.frames {
            let names: Vec<&str> = f.passes.iter().map(|p| p.name).collect();
            assert_eq!(names, ["prefix_sum", "smoke_triangle", "diamond_patch"]);
            assert!(f.passes.windows(2).all(|w| w[1].start_ms >= w[0].start_ms));
        }
        let frames: Vec<u64> = out.frames.iter().map(|f| f.frame).collect();
        assert!(frames.windows(2).all(|w| w[1] > w[0]), "frames arrive in order: {frames:?}");
        // The JSON summary's medians are the medians of the frames' numbers.
        let json: serde_json::Value = serde_json::from_str(&vista::frame::profiler::to_json(&out.frames)).unwrap();
        let summary = json["summary"].as_array().unwrap();
        assert_eq!(summary.len(), 3);
        for s in summary {
            let name = s["name"].as_str().unwrap();
            let mut v: Vec<f64> =
                out.frames.iter().flat_map(|f| f.passes.iter().filter(|p| p.name == name).map(|p| p.gpu_ms)).collect();
            v.sort_by(f64::total_cmp);
            let n = v.len();
            let median = if n % 2 == 1 { v[n / 2] } else { (v[n / 2 - 1] + v[n / 2]) / 2.0 };
            assert_eq!(s["median_ms"].as_f64(), Some(median), "{name}");
        }
        let trace: serde_json::Value =
            serde_json::from_str(&vista::frame::profiler::to_chrome_trace(&out.frames)).unwrap();
        let events = trace["traceEvents"].as_array().unwrap();
        assert_eq!(events.iter().filter(|e| e["ph"] == "X").count(), out.frames.len() * 3);
    });
}

#[test]
fn a_large_pass_times_longer_than_a_tiny_one_and_after_it() {
    gpu_test(|ctx| {
        let target = |name, side| {
            Image::new(
                ctx,
                &ImageDesc {
                    name,
                    format: TARGET_FORMAT,
                    extent: [side, side],
                    mip_levels: 1,
                    array_layers: 1,
                    usage: vk::ImageUsageFlags::COLOR_ATTACHMENT,
                },
            )
            .unwrap()
        };
        // One triangle into 8x8 pixels against 2 x 256^2 = 131072 triangles
        // into 512x512: over 10^5 times the vertex work, serial on lavapipe.
        let (small, large) = (target("tiny_target", 8), target("large_target", 512));
        let tri = SmokeTriangle::new(ctx).unwrap();
        let patch = DiamondPatch::new(ctx, 256).unwrap();
        let corners = [[-1.0, -1.0, 0.0, 1.0], [1.0, -1.0, 0.0, 1.0], [-1.0, 1.0, 0.0, 1.0]];
        let mut ring = FrameRing::new(ctx, 2).unwrap();
        let mut exec = FrameExecutor::new(ctx, 2, 2, false).unwrap();
        let mut frames: Vec<FrameTimings> = Vec::new();
        for _ in 0..4 {
            ring.record(ctx, |rec| {
                rec.discard_to(&small, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
                rec.discard_to(&large, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
                let mut frame = exec.begin(vista::gpu::FrameCommands::One(rec), vista::gpu::QueueMode::Single);
                frame.pass("tiny", false, QueueKind::Graphics, |r| tri.record(r, &small, corners));
                frame.pass("large", false, QueueKind::Graphics, |r| patch.record(r, &large, None));
                Ok(())
            })
            .unwrap();
            if let Some(t) = exec.latest() {
                if frames.last().is_none_or(|l| l.frame < t.frame) {
                    frames.push(t.clone());
                }
            }
        }
        ring.wait_all(ctx).unwrap();
        assert!(!frames.is_empty(), "no timings came back");
        for f in &frames {
            let [tiny, large] = [&f.passes[0], &f.passes[1]];
            assert_eq!((tiny.name, large.name), ("tiny", "large"));
            assert!(tiny.counters.is_none() && large.counters.is_none(), "counters only where asked for");
            assert!(large.gpu_ms > tiny.gpu_ms, "frame {}: large {large:?} vs tiny {tiny:?}", f.frame);
            // Passes run in order: the large one starts once the tiny one ended
            // (both timestamps come from the same clock).
            assert!(large.start_ms >= tiny.start_ms + tiny.gpu_ms - 1e-6, "frame {}: {f:?}", f.frame);
        }
    });
}

/// Pixels of a `side`-square target whose centres lie inside the triangle
/// of NDC `corners` (the top-left rule aside: no centre lies on an edge
/// here), and those of the 4x4 blocks that hold any (the most a
/// rasteriser shading whole blocks invokes the fragment shader for).
fn coverage(corners: [[f32; 4]; 3], side: u32) -> (u64, u64) {
    let p: Vec<glam::Vec2> = corners.iter().map(|c| (glam::Vec2::new(c[0], c[1]) * 0.5 + 0.5) * side as f32).collect();
    let edge = |a: glam::Vec2, b: glam::Vec2, q: glam::Vec2| (b - a).perp_dot(q - a);
    let inside = |x: u32, y: u32| {
        let q = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        let e = [edge(p[0], p[1], q), edge(p[1], p[2], q), edge(p[2], p[0], q)];
        e.iter().all(|&v| v > 0.0) || e.iter().all(|&v| v < 0.0)
    };
    let covered = (0..side).flat_map(|y| (0..side).map(move |x| (x, y))).filter(|&(x, y)| inside(x, y)).count();
    let blocks = (0..side / 4)
        .flat_map(|by| (0..side / 4).map(move |bx| (bx, by)))
        .filter(|&(bx, by)| (0..16).any(|i| inside(4 * bx + i % 4, 4 * by + i / 4)))
        .count();
    (covered as u64, 16 * blocks as u64)
}

#[test]
fn pass_counters_count_each_pass_s_own_work() {
    gpu_test(|ctx| {
        assert!(ctx.info().limits.pipeline_statistics, "lavapipe supports pipelineStatisticsQuery");
        let out = common::smoke::render(ctx, [64, 64], 6).unwrap();
        assert!(out.frames.len() >= 3, "timings came back for {} of 6 frames", out.frames.len());
        // smoke.rs's triangle and its 16x16-quad patch with one hole vertex.
        let corners = [[-0.8, -0.7, 0.0, 1.0], [0.9, -0.2, 0.0, 1.0], [-0.1, 0.85, 0.0, 1.0]];
        let (covered, block_pixels) = coverage(corners, 64);
        for f in &out.frames {
            let c: Vec<_> =
                f.passes.iter().map(|p| p.counters.expect("every pass ran on the graphics queue")).collect();
            let [scan, tri, patch] = [c[0], c[1], c[2]];
            // The compute pass: one workgroup, no graphics work.
            assert_eq!(scan.compute_invocations, u64::from(vista::shaders::prefix_sum::WORKGROUP_SIZE[0]));
            assert_eq!((scan.input_primitives, scan.vertex_invocations, scan.fragment_invocations), (0, 0, 0));
            assert_eq!((tri.input_primitives, tri.vertex_invocations, tri.clipped_primitives), (1, 3, 1));
            assert!(
                (covered..=block_pixels).contains(&tri.fragment_invocations),
                "frame {}: {} fragments for {covered} pixels covered ({block_pixels} in their 4x4 blocks)",
                f.frame,
                tri.fragment_invocations
            );
            assert_eq!(tri.compute_invocations, 0);
            // 512 triangles in; those with the NaN vertex are dropped.
            assert_eq!(patch.input_primitives, 2 * 16 * 16);
            assert!((17 * 17..=3 * 512).contains(&patch.vertex_invocations), "{patch:?}");
            assert!(patch.clipped_primitives < patch.input_primitives, "the hole's triangles are dropped: {patch:?}");
        }
    });
}
