//! The live overlay of `vista view` (egui, drawn by egui-ash-renderer into
//! the swapchain image): per-pass GPU ms as bars with a short history,
//! culling, LOD and streaming counters, memory, and the per-frame switches
//! (target error, culling stages, sun) applied on the next frame.

use std::collections::VecDeque;
use vista::frame::FrameTimings;
use vista::passes::cull_patches::CullStages;
use vista::passes::debug_view::DebugView;
use vista::render::telemetry::FrameCounters;
use vista::render::{Effect, EffectDecision, FrameSwitches, Lighting};
use vista::terrain::TerrainStats;

/// Frames of history kept per pass.
const HISTORY: usize = 120;

/// Below this window size (points) the overlay starts folded.
const SMALL: [f32; 2] = [800.0, 450.0];

/// What the overlay may change; read by the viewer each frame.
pub struct Settings {
    pub target_error_px: f32,
    pub stages: CullStages,
    pub switches: FrameSwitches,
    pub lighting: Lighting,
    pub debug_view: Option<DebugView>,
}

/// What the overlay shows of one frame (all of it data the renderer
/// returned frames late, never waited for).
pub struct Shown<'a> {
    pub device: &'a str,
    pub fps: f64,
    pub camera: String,
    pub speed_mps: f64,
    pub size: [u32; 2],
    pub timings: Option<&'a FrameTimings>,
    pub counters: Option<&'a FrameCounters>,
    pub stream: TerrainStats,
    /// Per LOD, drawn nodes the camera wants finer whose children are not
    /// resident (a CPU traversal of this frame's view).
    pub wanted_finer: Vec<u32>,
    pub slots: u32,
    pub effects: &'a [EffectDecision],
    /// Culling stages the renderer built (a switch for the others would do nothing).
    pub built: CullStages,
    /// Built effects the last frame went without (switched off, or shadows
    /// still being redone after being switched back on).
    pub switched_off: Vec<Effect>,
    pub memory_mb: f64,
}

#[derive(Default)]
pub struct Overlay {
    /// Per pass label, the last frames' GPU ms (newest last).
    history: Vec<(String, VecDeque<f32>)>,
    last_frame: u64,
}

impl Overlay {
    /// Adds a finished frame's timings to the history (once per frame).
    pub fn observe(&mut self, t: &FrameTimings) {
        if t.frame <= self.last_frame {
            return;
        }
        self.last_frame = t.frame;
        for p in &t.passes {
            let label = vista::frame::pass_label(p.name, p.late);
            let i = match self.history.iter().position(|(l, _)| *l == label) {
                Some(i) => i,
                None => {
                    self.history.push((label, VecDeque::new()));
                    self.history.len() - 1
                }
            };
            let h = &mut self.history[i].1;
            h.push_back(p.gpu_ms as f32);
            if h.len() > HISTORY {
                h.pop_front();
            }
        }
    }

    pub fn ui(&mut self, ctx: &egui::Context, shown: &Shown, settings: &mut Settings) {
        // Taller than the window (many shading variants, a small window):
        // it scrolls rather than hiding the switches below the edge.
        let screen = ctx.content_rect();
        let max_height = (screen.height() - 48.0).max(120.0);
        // A small window (320x180, say) would be all overlay: there it
        // starts folded and narrower; its arrow opens it.
        let small = screen.width() < SMALL[0] || screen.height() < SMALL[1];
        let width = if small { (screen.width() * 0.45).max(120.0) } else { 360.0 };
        let window = egui::Window::new("vista").default_pos([8.0, 8.0]).default_width(width).default_open(!small);
        window.resizable(false).show(ctx, |ui| {
            egui::ScrollArea::vertical()
                .max_height(max_height)
                .min_scrolled_height(max_height)
                .show(ui, |ui| self.sections(ui, shown, settings));
        });
    }

    fn sections(&mut self, ui: &mut egui::Ui, shown: &Shown, settings: &mut Settings) {
        ui.label(format!("{}  {}x{}  {:.1} fps", shown.device, shown.size[0], shown.size[1], shown.fps));
        ui.label(format!("camera {}  speed {:.0} m/s", shown.camera, shown.speed_mps));
        ui.label("WASD/QE move, right drag looks, wheel speed, Shift fast, P prints camera, F1 hides, Esc quits");
        egui::CollapsingHeader::new("GPU ms per pass").default_open(true).show(ui, |ui| self.timings(ui, shown));
        egui::CollapsingHeader::new("culling and LOD").default_open(true).show(ui, |ui| counters(ui, shown));
        egui::CollapsingHeader::new("streaming and memory").default_open(false).show(ui, |ui| streaming(ui, shown));
        egui::CollapsingHeader::new("switches (next frame)")
            .default_open(true)
            .show(ui, |ui| switches(ui, shown, settings));
    }

    fn timings(&self, ui: &mut egui::Ui, shown: &Shown) {
        let Some(t) = shown.timings else {
            ui.label("no timings yet (they arrive frames late)");
            return;
        };
        let total: f64 = t.passes.iter().map(|p| p.gpu_ms).sum();
        ui.label(format!("frame {}: {total:.2} ms in {} passes ({})", t.frame, t.passes.len(), t.mode.name()));
        let scale = self.history.iter().flat_map(|(_, h)| h.iter().copied()).fold(0.1f32, f32::max);
        // The passes of the newest frame, in frame order: a pass that did
        // not run (e.g. no upload) is not listed.
        egui::Grid::new("passes").num_columns(3).show(ui, |ui| {
            for p in &t.passes {
                let label = vista::frame::pass_label(p.name, p.late);
                let Some((_, h)) = self.history.iter().find(|(l, _)| *l == label) else { continue };
                ui.label(label);
                ui.label(format!("{:7.2}", p.gpu_ms));
                bar_with_history(ui, h, scale);
                ui.end_row();
            }
        });
    }
}

/// A bar for the newest value over a sparkline of the history, both
/// scaled to `scale` ms.
fn bar_with_history(ui: &mut egui::Ui, h: &VecDeque<f32>, scale: f32) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(140.0, 14.0), egui::Sense::hover());
    let p = ui.painter();
    p.rect_filled(rect, 0.0, egui::Color32::from_gray(40));
    if let Some(now) = h.back() {
        let w = rect.width() * (now / scale).min(1.0);
        let bar = egui::Rect::from_min_size(rect.min, egui::vec2(w, rect.height()));
        p.rect_filled(bar, 0.0, egui::Color32::from_rgb(70, 130, 200));
    }
    let n = HISTORY as f32;
    let points: Vec<egui::Pos2> = h
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let x = rect.left() + rect.width() * (i as f32 + (n - h.len() as f32)) / n;
            egui::pos2(x, rect.bottom() - rect.height() * (v / scale).min(1.0))
        })
        .collect();
    p.add(egui::Shape::line(points, egui::Stroke::new(1.0, egui::Color32::from_rgb(240, 200, 80))));
}

fn counters(ui: &mut egui::Ui, shown: &Shown) {
    let Some(c) = shown.counters else {
        ui.label("no counters yet");
        return;
    };
    let p = &c.cull;
    ui.label(format!(
        "patches {} in, {} after frustum, {} after cone, {} after hole, {} drawn",
        p.patches_in, p.after_frustum, p.after_cone, p.after_hole, p.drawn
    ));
    if shown.built.occlusion {
        ui.label(format!(
            "occlusion: {} drawn in phase 1, {} tested, {} drawn in phase 2",
            p.drawn_phase1, p.occlusion_tested, p.drawn_phase2
        ));
    }
    let tri_per_px = c.triangles as f64 / f64::from(shown.size[0] * shown.size[1]);
    ui.label(format!("triangles {} ({tri_per_px:.2} per pixel)", c.triangles));
    let bound = crate::render_print::bound_words(p.bound_px);
    ui.label(format!("error bound {bound} (the largest projected error of any drawn patch)"));
    let lods: Vec<String> = c
        .traverse
        .nodes_per_lod
        .iter()
        .enumerate()
        .map(|(l, n)| match shown.wanted_finer.get(l) {
            Some(&w) if w > 0 => format!("LOD{l} {n} ({w}+)"),
            _ => format!("LOD{l} {n}"),
        })
        .collect();
    ui.label(format!("nodes {}: {}  (+: wanted finer)", c.traverse.nodes, lods.join(", ")));
    let s = &c.select;
    ui.label(format!(
        "{} patches from an ancestor, {} refined below the samples, {} seam conflicts",
        s.coarsened,
        s.refined - s.refine_capped,
        s.conflicts
    ));
}

fn streaming(ui: &mut egui::Ui, shown: &Shown) {
    let s = &shown.stream;
    ui.label(format!(
        "{} of {} slots resident, {} loading, {} waiting upload, {} arrived in all",
        s.resident, shown.slots, s.loading, s.waiting_upload, s.arrived_total
    ));
    if s.failed > 0 {
        ui.label(format!("{} failed loads, {} retried, {} given up", s.failed, s.retried, s.gave_up));
    }
    ui.label(format!("GPU memory {:.1} MiB (renderer's resources)", shown.memory_mb));
    for d in shown.effects {
        let state = if d.on { "on" } else { "off" };
        ui.label(format!("effect {} {state}: {}", d.effect.name(), d.reason));
    }
}

fn switches(ui: &mut egui::Ui, shown: &Shown, s: &mut Settings) {
    ui.add(egui::Slider::new(&mut s.target_error_px, 0.25..=16.0).logarithmic(true).text("target error px"));
    ui.horizontal(|ui| {
        let b = shown.built;
        ui.checkbox(&mut s.stages.frustum, "frustum");
        ui.add_enabled(b.cone, egui::Checkbox::new(&mut s.stages.cone, "cone"));
        ui.add_enabled(b.hole, egui::Checkbox::new(&mut s.stages.hole, "hole"));
        ui.add_enabled(b.occlusion, egui::Checkbox::new(&mut s.stages.occlusion, "occlusion"));
    });
    let built = |e: Effect| shown.effects.iter().any(|d| d.effect == e && d.on);
    // Every effect a frame can switch off; those the scene did not build
    // (or, for shadows and the atmosphere, with lighting off) are greyed.
    let lit = s.switches.lighting;
    ui.horizontal_wrapped(|ui| {
        for effect in FrameSwitches::SWITCHABLE {
            let needs_light = matches!(effect, Effect::Shadows | Effect::Atmosphere);
            let enabled = built(effect) && (lit || !needs_light);
            let on = s.switches.get_mut(effect).expect("switchable");
            ui.add_enabled(enabled, egui::Checkbox::new(on, effect.name()));
        }
    });
    if s.switches.shadows && shown.switched_off.contains(&Effect::Shadows) {
        ui.label("shadows: redoing every resident node before showing them");
    }
    let name = |v: Option<DebugView>| v.map_or("off (the picture)", DebugView::name);
    egui::ComboBox::from_label("debug view").selected_text(name(s.debug_view)).show_ui(ui, |ui| {
        for v in std::iter::once(None).chain(DebugView::ALL.map(Some)) {
            ui.selectable_value(&mut s.debug_view, v, name(v));
        }
    });
    ui.add(egui::Slider::new(&mut s.lighting.sun_elevation_deg, -5.0..=90.0).text("sun elevation"));
    ui.add(egui::Slider::new(&mut s.lighting.sun_azimuth_deg, 0.0..=360.0).text("sun azimuth"));
}
