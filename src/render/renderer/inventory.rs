//! What a renderer built: its pipelines and the device memory of every
//! resource, with the effects each exists for.

use super::{effect_atlases, TerrainRenderer};
use crate::effects::Effect;
use crate::passes::lighting_resolve::LightingResolve;
use crate::targets::gbuffer::GBuffer;

impl TerrainRenderer {
    /// Labels of every pipeline built (variant switches included).
    pub fn pipelines(&self) -> Vec<String> {
        let mut out = vec![
            self.update.pipeline_label().to_string(),
            self.traverse.pipeline_label().to_string(),
            self.lod_map.pipeline_label().to_string(),
        ];
        out.push(self.sector_data.pipeline_label().to_string());
        out.push(self.cull.pipeline_label().to_string());
        out.push(self.geometry.pipeline_label().to_string());
        if let Some(h) = &self.holes {
            out.push(h.pipeline_label().to_string());
        }
        if let Some(o) = &self.occlusion {
            out.push(o.hiz.pipeline_label().to_string());
            out.push(o.cull.pipeline_label().to_string());
        }
        out.push(self.classify.pipeline_label().to_string());
        out.extend(self.gbuffer_tiles.pipeline_labels());
        out.extend(self.built.iter().flat_map(|e| e.pipelines()));
        out.extend(self.resolve.iter().flat_map(LightingResolve::pipeline_labels));
        out.extend(self.debug_pass.as_ref().map(|p| p.pipeline_label().to_string()));
        out
    }

    /// Device memory of every resource the renderer owns, with the effects
    /// it exists for (empty: needed by any scene).
    pub fn memory(&self) -> Vec<(String, u64, Vec<Effect>)> {
        let atlas_users = |i: usize| -> Vec<Effect> {
            let pairs = effect_atlases(self.effects.materials);
            pairs.iter().filter(|(e, a)| *a == i && self.effect_on(*e)).map(|(e, _)| *e).collect()
        };
        let mut out: Vec<(String, u64, Vec<Effect>)> = self
            .terrain
            .tree
            .memory()
            .into_iter()
            .map(|(name, bytes, atlas)| (name, bytes, atlas.map(atlas_users).unwrap_or_default()))
            .collect();
        for (name, bytes) in self.traverse.memory() {
            out.push((name, bytes, Vec::new()));
        }
        // Per-frame copies (frame::per_frame) are listed one by one.
        let core = self
            .lod_map
            .images()
            .iter()
            .map(|i| (&i.name, i.memory_bytes()))
            .chain(self.cull.all_lists().iter().map(|l| (&l.list.name, l.list.memory_bytes())))
            .chain(self.view_buffer.all().iter().map(|b| (&b.name, b.memory_bytes())))
            .chain(self.lod_view_buffer.all().iter().map(|b| (&b.name, b.memory_bytes())))
            .chain([(&self.geometry.indices().name, self.geometry.indices().memory_bytes())])
            .chain(self.sector_data.buffers().iter().map(|b| (&b.name, b.memory_bytes())))
            .chain(self.select.all_levels().iter().map(|b| (&b.name, b.memory_bytes())));
        out.extend(core.map(|(n, b)| (n.clone(), b, Vec::new())));
        let (name, bytes) = self.telemetry.memory();
        out.push((name, bytes, Vec::new()));
        for h in self.cull.all_lists().iter().filter_map(|l| l.hole_list.as_ref()) {
            out.push((h.name.clone(), h.memory_bytes(), vec![Effect::Holes]));
        }
        if let Some(o) = &self.occlusion {
            out.push((o.cull.lists.list.name.clone(), o.cull.lists.list.memory_bytes(), vec![Effect::Occlusion]));
            if let Some(h) = &o.cull.lists.hole_list {
                out.push((h.name.clone(), h.memory_bytes(), vec![Effect::Holes, Effect::Occlusion]));
            }
            for v in o.cull.all_visibility() {
                out.push((v.name.clone(), v.memory_bytes(), vec![Effect::Occlusion]));
            }
            if let Some(p) = o.hiz.pyramid() {
                out.push((p.name.clone(), p.memory_bytes(), vec![Effect::Occlusion]));
            }
        }
        if let Some(t) = &self.triangles {
            out.extend(t.emit.memory().map(|b| (b.name.clone(), b.memory_bytes(), Vec::new())));
            let occlusion = t.emit.occlusion_memory().map(|b| (&b.name, b.memory_bytes()));
            let pyramid = t.hiz.iter().flat_map(|h| h.pyramid()).map(|p| (&p.name, p.memory_bytes()));
            out.extend(occlusion.chain(pyramid).map(|(n, b)| (n.clone(), b, vec![Effect::Occlusion])));
        }
        for img in self.gbuffer.iter().flat_map(GBuffer::images) {
            out.push((img.name.clone(), img.memory_bytes(), Vec::new()));
        }
        if let Some(l) = &self.classify.lists {
            out.push((l.buffer.name.clone(), l.buffer.memory_bytes(), Vec::new()));
        }
        out.extend(self.built.iter().flat_map(|e| e.memory()));
        out
    }
}
