//! Pass timings as files: JSON (one object per frame) and a Chrome trace
//! (chrome://tracing, ui.perfetto.dev), plus medians for reports.

use crate::frame::{pass_label, FrameTimings, QueueKind};
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
            PassSummary { name, late, queue, median_ms: median, min_ms, max_ms, samples }
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
