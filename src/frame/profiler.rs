//! Pass timings as files: JSON (one object per frame) and a Chrome trace
//! (chrome://tracing, ui.perfetto.dev), plus medians for reports.

use crate::frame::{pass_label, FrameTimings, PassCounters, PassTiming, QueueKind};
use serde::Serialize;
use serde_json::json;

#[derive(Debug, Clone, Serialize)]
pub struct PassSummary {
    pub name: &'static str,
    /// Phase 2 of occlusion culling.
    pub late: bool,
    pub queue: QueueKind,
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    pub samples: usize,
    /// Each pipeline statistic's median over the frames that counted it.
    pub counters: Option<PassCounters>,
}

fn median_u64(mut v: Vec<u64>) -> u64 {
    v.sort_unstable();
    v[v.len() / 2]
}

/// Each counter's median (counts can vary from frame to frame: a list
/// order that atomics decide changes which fragments early depth drops).
fn median_counters(c: &[PassCounters]) -> Option<PassCounters> {
    if c.is_empty() {
        return None;
    }
    let m = |f: fn(&PassCounters) -> u64| median_u64(c.iter().map(f).collect());
    Some(PassCounters {
        input_primitives: m(|c| c.input_primitives),
        vertex_invocations: m(|c| c.vertex_invocations),
        clipped_primitives: m(|c| c.clipped_primitives),
        fragment_invocations: m(|c| c.fragment_invocations),
        compute_invocations: m(|c| c.compute_invocations),
    })
}

/// Median, min and max of each pass over `frames`, in first-seen order.
pub fn summarize(frames: &[FrameTimings]) -> Vec<PassSummary> {
    let mut names: Vec<(&'static str, bool, QueueKind)> = Vec::new();
    for f in frames {
        for p in &f.passes {
            if !names.iter().any(|(n, late, _)| *n == p.name && *late == p.late) {
                names.push((p.name, p.late, p.queue));
            }
        }
    }
    names
        .into_iter()
        .map(|(name, late, queue)| {
            let mut v: Vec<f64> = frames
                .iter()
                .flat_map(|f| f.passes.iter().filter(|p| p.name == name && p.late == late).map(|p| p.gpu_ms))
                .collect();
            v.sort_by(f64::total_cmp);
            let median = if v.len() % 2 == 1 { v[v.len() / 2] } else { 0.5 * (v[v.len() / 2 - 1] + v[v.len() / 2]) };
            let (min_ms, max_ms, samples) = (v[0], v[v.len() - 1], v.len());
            let counted: Vec<PassCounters> = frames
                .iter()
                .flat_map(|f| f.passes.iter().filter(|p| p.name == name && p.late == late).filter_map(|p| p.counters))
                .collect();
            let counters = median_counters(&counted);
            PassSummary { name, late, queue, median_ms: median, min_ms, max_ms, samples, counters }
        })
        .collect()
}

pub fn to_json(frames: &[FrameTimings]) -> String {
    serde_json::to_string_pretty(&json!({ "frames": frames, "summary": summarize(frames) })).unwrap_or_default()
}

/// Chrome trace-event JSON: one complete ("X") event per pass, one track per
/// queue the passes actually ran on.
pub fn to_chrome_trace(frames: &[FrameTimings]) -> String {
    let origin = frames.first().map_or(0.0, |f| f.start_ns);
    let mut events = Vec::new();
    for f in frames {
        for p in &f.passes {
            events.push(json!({
                "name": pass_label(p.name, p.late), "cat": "gpu", "ph": "X", "pid": 1,
                "tid": match p.queue { QueueKind::Graphics => 1, QueueKind::Compute => 2 },
                "ts": (f.start_ns - origin) / 1e3 + p.start_ms * 1e3,
                "dur": p.gpu_ms * 1e3,
                "args": { "frame": f.frame },
            }));
        }
    }
    events.push(json!({"name": "thread_name", "ph": "M", "pid": 1, "tid": 1, "args": {"name": "graphics queue"}}));
    if frames.iter().any(|f| f.passes.iter().any(|p| p.queue == QueueKind::Compute)) {
        events.push(json!({"name": "thread_name", "ph": "M", "pid": 1, "tid": 2, "args": {"name": "compute queue"}}));
    }
    serde_json::to_string(&json!({ "traceEvents": events, "displayTimeUnit": "ms" })).unwrap_or_default()
}

/// How long frame `next`'s compute-queue passes ran while frame `prev`'s
/// graphics-queue passes did (async compute's overlap): the length of the
/// intersection of the two sets of intervals, in ms, in the device's one
/// timestamp domain; and the same against `prev`'s passes named `geometry`
/// alone. None unless `next` directly follows `prev` and ran split.
pub fn overlap_ms(prev: &FrameTimings, next: &FrameTimings, geometry: &str) -> Option<(f64, f64)> {
    if next.frame != prev.frame + 1 || !next.mode.is_split() {
        return None;
    }
    let spans = |f: &FrameTimings, keep: &dyn Fn(&PassTiming) -> bool| -> Vec<[f64; 2]> {
        let t0 = f.start_ns / 1e6;
        f.passes.iter().filter(|p| keep(p)).map(|p| [t0 + p.start_ms, t0 + p.start_ms + p.gpu_ms]).collect()
    };
    let compute = spans(next, &|p| p.queue == QueueKind::Compute);
    let graphics = spans(prev, &|p| p.queue == QueueKind::Graphics);
    let geometry = spans(prev, &|p| p.queue == QueueKind::Graphics && p.name == geometry);
    Some((intersection_ms(&compute, &graphics), intersection_ms(&compute, &geometry)))
}

/// Length of the intersection of two unions of intervals.
fn intersection_ms(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    let (a, b) = (union(a), union(b));
    a.iter().flat_map(|x| b.iter().map(move |y| (x[1].min(y[1]) - x[0].max(y[0])).max(0.0))).sum()
}

/// Disjoint, sorted intervals covering the same points.
fn union(spans: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut s = spans.to_vec();
    s.sort_by(|x, y| x[0].total_cmp(&y[0]));
    let mut out: Vec<[f64; 2]> = Vec::new();
    for x in s {
        match out.last_mut() {
            Some(last) if x[0] <= last[1] => last[1] = last[1].max(x[1]),
            _ => out.push(x),
        }
    }
    out
}

#[cfg(test)]
mod overlap_tests {
    use super::*;
    use crate::gpu::QueueMode;

    fn pass(name: &'static str, queue: QueueKind, start_ms: f64, gpu_ms: f64) -> PassTiming {
        PassTiming { name, late: false, queue, start_ms, gpu_ms, counters: None }
    }

    #[test]
    fn overlap_is_the_intersection_of_next_computes_and_prev_graphics() {
        let prev = FrameTimings {
            frame: 1,
            start_ns: 0.0,
            mode: QueueMode::AsyncCompute,
            passes: vec![
                pass("traverse", QueueKind::Compute, 0.0, 1.0),
                pass("terrain_geometry", QueueKind::Graphics, 2.0, 3.0),
                pass("lighting_resolve", QueueKind::Graphics, 5.0, 2.0),
            ],
            cpu_ms: 0.0,
            query_ms: 0.0,
        };
        // Frame 2's compute from 4 ms to 6.5 ms (two overlapping passes).
        let next = FrameTimings {
            frame: 2,
            start_ns: 4e6,
            mode: QueueMode::AsyncCompute,
            passes: vec![
                pass("traverse", QueueKind::Compute, 0.0, 2.0),
                pass("cull_patches", QueueKind::Compute, 1.0, 1.5),
            ],
            cpu_ms: 0.0,
            query_ms: 0.0,
        };
        let (all, geometry) = overlap_ms(&prev, &next, "terrain_geometry").unwrap();
        assert!((all - 2.5).abs() < 1e-9, "{all}");
        assert!((geometry - 1.0).abs() < 1e-9, "{geometry}");
        let single = FrameTimings { mode: QueueMode::Single, ..next.clone() };
        assert!(overlap_ms(&prev, &single, "terrain_geometry").is_none());
        let later = FrameTimings { frame: 3, ..next };
        assert!(overlap_ms(&prev, &later, "terrain_geometry").is_none());
    }
}
