//! Effect `vegetation` in the frame: the culling before the tiles are
//! classified (beside grass_place, with the frame's pyramid), the six draws
//! after the tile shading, the counters. Teardown: fields drop in
//! declaration order, each object retired until the frames using it
//! completed.

use super::canopy::CanopyGrid;
use super::clusters::cluster;
use super::meshes::{bush, tree, VegMesh};
use super::vegetation_cull::{CullBuffers, VegetationCull, VegetationCullPush};
use super::vegetation_draw::{DrawBuffers, VegetationDraw, VegetationDrawPush};
use super::{VegetationDrawParams, VegetationSet};
use crate::effects::frame_effect::{
    BuildInputs, Canopy, EffectStats, FrameEffect, FramePoint, PlanInputs, RecordInputs, SharedPlan, Work,
};
use crate::error::{Error, Result};
use crate::frame::{Frame, QueueKind};
use crate::gpu::{vk, Buffer, BufferDesc, Context, MemoryLocation};
use crate::passes::counters::FrameCounters;
use crate::passes::terrain_query::VistaTerrain;
use crate::scene::effect::Effect;
use crate::scene::graph::{FrameLog, FramePass, PassWork};
use crate::shaders::consts::{VEG_FLAG_DISTANCE, VEG_FLAG_FRUSTUM, VEG_FLAG_HIZ, VEG_KINDS, VEG_LODS};
use crate::shaders::structs;
use crate::world::vegetation::VegetationKind;
use std::any::Any;
use std::sync::Arc;

pub const VEGETATION_CULL: FramePass = FramePass::new(crate::shaders::vegetation_cull::PASS);
pub const VEGETATION_DRAW: FramePass = FramePass::new(crate::shaders::vegetation_draw_vert::PASS);

const DRAWS: usize = (VEG_KINDS * VEG_LODS) as usize;

/// Host twin of `VegetationHeader` (vegetation.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VegetationHeaderGpu {
    /// `DRAWS` VkDrawIndexedIndirectCommands, kind-major.
    pub draws: [u32; 30],
    pub considered: u32,
    pub culled_distance: u32,
    pub culled_frustum: u32,
    pub culled_hiz: u32,
    /// Clusters culled whole, and their instances (never visited).
    pub clusters_culled: u32,
    pub skipped: u32,
    pub pad: [u32; 2],
}

const _: () = assert!(DRAWS * 5 == 30);

impl VegetationHeaderGpu {
    pub const BYTES: u64 = structs::VEGETATION_HEADER as u64;

    /// Instances drawn by draw `d` (kind-major: tree LOD 0..2, bush LOD 0..2).
    pub fn drawn(&self, d: usize) -> u32 {
        self.draws[d * 5 + 1]
    }
}

/// Host twin of `VegetationVertex`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VegetationVertexGpu {
    pub position: [f32; 4],
    /// xyz: unit; w: 1 on the crown.
    pub normal: [f32; 4],
}

pub struct Vegetation {
    pub params: VegetationDrawParams,
    set: Arc<VegetationSet>,
    cull: VegetationCull,
    draw: VegetationDraw,
    vertices: Buffer,
    /// Per draw: its mesh's indices (into `vertices`) and their count.
    indices: Vec<(Buffer, u32)>,
    /// Sorted by cluster; the clusters and their count.
    instances: Buffer,
    clusters: Buffer,
    cluster_count: u32,
    types: Buffer,
    header: Buffer,
    visible: Buffer,
    /// With effect `shadows`: the canopy's heights, its map and size.
    canopy: Option<(Buffer, [f32; 4], [u32; 2])>,
    /// The header as each frame starts it: the draws' index counts and
    /// regions of the visible list, no instance, no count.
    reset: VegetationHeaderGpu,
    /// This frame's culling and terrain (`plan`).
    frame: Option<(VegetationCullPush, VistaTerrain)>,
    /// Tests only (feature `test-hooks`): no distance, frustum or Hi-Z
    /// culling (every instance drawn).
    #[cfg(feature = "test-hooks")]
    pub no_culling: bool,
}

/// Builds effect `vegetation` when it is on.
pub fn build(b: &mut BuildInputs) -> Result<Option<Box<dyn FrameEffect>>> {
    if !b.on(Effect::Vegetation) {
        return Ok(None);
    }
    let v = Vegetation::new(b.ctx, &b.effects.vegetation, b.occlusion, b.depth.format, b.layout)?;
    Ok(Some(Box::new(if b.on(Effect::Shadows) { v.with_canopy(b.ctx)? } else { v })))
}

impl Vegetation {
    pub fn new(
        ctx: &Context,
        params: &VegetationDrawParams,
        hiz: bool,
        depth_format: vk::Format,
        layout: Option<&crate::targets::GbufferLayout>,
    ) -> Result<Self> {
        let set = params.set.clone().ok_or_else(|| Error::Scene("effects.vegetation: no folder".into()))?;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let with = |name: &str, bytes: &[u8], usage| Buffer::with_data(ctx, name, bytes, usage);
        let (vertices, indices) = meshes_gpu(ctx)?;
        let types = params.types_gpu(&set);
        let sorted = cluster(&set, &types, params.cluster_m);
        let n = set.instances.len().max(1) as u64;
        let mut reset = VegetationHeaderGpu::default();
        for (d, (_, count)) in indices.iter().enumerate() {
            let kind = if d < VEG_LODS as usize { VegetationKind::Tree } else { VegetationKind::Bush };
            // Each LOD's block of the visible list holds every instance;
            // a kind's region starts after the instances of the kinds before it.
            let before = if kind == VegetationKind::Tree { 0 } else { kind_count(&set, VegetationKind::Tree) };
            reset.draws[d * 5] = *count;
            reset.draws[d * 5 + 4] = ((d as u64 % u64::from(VEG_LODS)) * n) as u32 + before;
        }
        let buffer =
            |name, size, usage| Buffer::new(ctx, &BufferDesc { name, size, usage, location: MemoryLocation::GpuOnly });
        let indirect = storage | vk::BufferUsageFlags::INDIRECT_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        Ok(Vegetation {
            params: params.clone(),
            cull: VegetationCull::new(ctx, hiz)?,
            draw: VegetationDraw::new(ctx, depth_format, layout)?,
            vertices,
            indices,
            instances: with("vegetation_instances", bytemuck::cast_slice(&sorted.instances), storage)?,
            clusters: with("vegetation_clusters", bytemuck::cast_slice(&sorted.clusters), storage)?,
            cluster_count: sorted.clusters.len() as u32,
            types: with("vegetation_types", bytemuck::cast_slice(&types), storage)?,
            header: buffer(
                "vegetation_header",
                VegetationHeaderGpu::BYTES,
                indirect | vk::BufferUsageFlags::TRANSFER_SRC,
            )?,
            visible: buffer("vegetation_visible", n * u64::from(VEG_LODS) * 4, storage)?,
            canopy: None,
            reset,
            set,
            frame: None,
            #[cfg(feature = "test-hooks")]
            no_culling: false,
        })
    }

    /// Rasters and uploads the canopy (effect `shadows` marches over it).
    pub fn with_canopy(mut self, ctx: &Context) -> Result<Self> {
        let types = self.params.types_gpu(&self.set);
        if let Some(g) = CanopyGrid::raster(&self.set, &types, self.params.canopy_cell_m) {
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
            let buffer = Buffer::with_data(ctx, "vegetation_canopy", bytemuck::cast_slice(&g.packed()), usage)?;
            self.canopy = Some((buffer, g.map(), g.size));
        }
        Ok(self)
    }

    /// The header (draw arguments, then counters): telemetry copies it.
    pub fn header(&self) -> &Buffer {
        &self.header
    }

    fn triangles(&self, h: &VegetationHeaderGpu) -> u64 {
        (0..DRAWS).map(|d| u64::from(h.drawn(d)) * u64::from(self.indices[d].1 / 3)).sum()
    }
}

fn kind_count(set: &VegetationSet, kind: VegetationKind) -> u32 {
    set.instances.iter().filter(|i| set.types[i.ty as usize].1 == kind).count() as u32
}

/// Every mesh in one vertex buffer; per draw (tree LOD 0..2, bush LOD
/// 0..2) its indices, rebased.
fn meshes_gpu(ctx: &Context) -> Result<(Buffer, Vec<(Buffer, u32)>)> {
    let (mut vertices, mut indices) = (Vec::new(), Vec::new());
    let meshes: Vec<VegMesh> = (0..VEG_LODS).map(tree).chain((0..VEG_LODS).map(bush)).collect();
    for (d, m) in meshes.iter().enumerate() {
        let base = vertices.len() as u32;
        vertices.extend(m.positions.iter().zip(&m.normals).zip(&m.crown).map(|((p, n), c)| VegetationVertexGpu {
            position: p.extend(1.0).to_array(),
            normal: n.extend(if *c { 1.0 } else { 0.0 }).to_array(),
        }));
        let idx: Vec<u32> = m.indices.iter().map(|i| i + base).collect();
        let name = format!("vegetation_indices[{d}]");
        let b = Buffer::with_data(ctx, &name, bytemuck::cast_slice(&idx), vk::BufferUsageFlags::INDEX_BUFFER)?;
        indices.push((b, idx.len() as u32));
    }
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    Ok((Buffer::with_data(ctx, "vegetation_vertices", bytemuck::cast_slice(&vertices), storage)?, indices))
}

fn counters_of(c: &FrameCounters) -> Option<VegetationHeaderGpu> {
    c.of(Effect::Vegetation).map(bytemuck::pod_read_unaligned)
}

impl FrameEffect for Vegetation {
    fn effect(&self) -> Effect {
        Effect::Vegetation
    }

    fn share(&self, shared: &mut SharedPlan) {
        shared.canopy_top_m = self.canopy.as_ref().map(|c| c.1[3]);
    }

    fn canopy(&self) -> Option<Canopy<'_>> {
        self.canopy.as_ref().map(|(heights, map, size)| Canopy { heights, map: *map, size: *size })
    }

    fn plan(&mut self, p: &PlanInputs, _: &SharedPlan) -> Result<()> {
        #[cfg(feature = "test-hooks")]
        let culled = !self.no_culling;
        #[cfg(not(feature = "test-hooks"))]
        let culled = true;
        let flags =
            if culled { VEG_FLAG_DISTANCE | VEG_FLAG_FRUSTUM | if p.hiz { VEG_FLAG_HIZ } else { 0 } } else { 0 };
        let push = VegetationCullPush {
            count: self.cluster_count,
            flags,
            lod_m: self.params.lod_m,
            depth_size: p.depth_size,
            pad: [0; 2],
        };
        self.frame = Some((push, p.vista_terrain));
        Ok(())
    }

    fn record(&self, point: FramePoint, frame: &mut Frame<'_, '_>, log: &mut FrameLog, r: &RecordInputs) {
        let (push, terrain) = self.frame.expect("planned before recording");
        match point {
            FramePoint::BeforeClassify => {
                frame.pass(VEGETATION_CULL.name(), false, QueueKind::Graphics, |rec| {
                    rec.update_buffer(&self.header, 0, bytemuck::bytes_of(&self.reset));
                    rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
                    let hiz = r.hiz.filter(|_| push.flags & VEG_FLAG_HIZ != 0);
                    let out = CullBuffers {
                        view: r.view_buffer,
                        instances: &self.instances,
                        clusters: &self.clusters,
                        types: &self.types,
                        header: &self.header,
                        visible: &self.visible,
                        hiz,
                    };
                    self.cull.record(rec, &out, &push);
                });
                log.ran(VEGETATION_CULL, None);
            }
            FramePoint::AfterTiles => {
                frame.pass(VEGETATION_DRAW.name(), false, QueueKind::Graphics, |rec| {
                    let b = DrawBuffers {
                        view: r.view_buffer,
                        vertices: &self.vertices,
                        instances: &self.instances,
                        types: &self.types,
                        visible: &self.visible,
                        header: &self.header,
                        indices: &self.indices,
                        sector_data: r.sector_data.buffer(),
                    };
                    let push = VegetationDrawPush { terrain, blend_height_m: self.params.blend_height_m, pad: [0; 3] };
                    self.draw.record(rec, r.targets, r.gbuffer, &b, r.tree, push);
                });
                log.ran(VEGETATION_DRAW, None);
            }
            _ => {}
        }
    }

    fn pipelines(&self) -> Vec<String> {
        let mut out: Vec<String> = self.cull.pipeline_labels().map(str::to_string).collect();
        out.push(self.draw.pipeline_label().to_string());
        out
    }

    fn memory(&self) -> Vec<(String, u64, Vec<Effect>)> {
        [&self.vertices, &self.instances, &self.clusters, &self.types, &self.header, &self.visible]
            .into_iter()
            .chain(self.indices.iter().map(|(b, _)| b))
            .chain(self.canopy.iter().map(|c| &c.0))
            .map(|b| (b.name.clone(), b.memory_bytes(), vec![Effect::Vegetation]))
            .collect()
    }

    fn work(&self, pass: FramePass, _: Option<u64>, c: &FrameCounters, _: [u32; 2]) -> Option<Work> {
        let h = counters_of(c).unwrap_or_default();
        match pass {
            VEGETATION_CULL => {
                let work = PassWork {
                    dispatch_groups: Some(u64::from(self.cluster_count).div_ceil(64)),
                    instances: Some(u64::from(h.considered)),
                    ..PassWork::default()
                };
                Some((work, None))
            }
            VEGETATION_DRAW => {
                let drawn: u64 = (0..DRAWS).map(|d| u64::from(h.drawn(d))).sum();
                let work =
                    PassWork { instances: Some(drawn), triangles: Some(self.triangles(&h)), ..PassWork::default() };
                Some((work, (drawn == 0).then_some("no tree or bush in view (0 instances)")))
            }
            _ => None,
        }
    }

    fn counters(&self) -> Option<(&Buffer, u64)> {
        Some((&self.header, VegetationHeaderGpu::BYTES))
    }

    fn stats(&self, _: &Context, c: &FrameCounters) -> Result<Option<EffectStats>> {
        let Some(h) = counters_of(c) else { return Ok(None) };
        let lods = |k: usize| {
            (0..VEG_LODS as usize).map(|l| h.drawn(k * VEG_LODS as usize + l).to_string()).collect::<Vec<_>>()
        };
        let memory_bytes: u64 = self.memory().iter().map(|(_, b, _)| b).sum();
        let line = format!(
            "vegetation: {} instances in {} clusters, {} clusters ({} instances) culled whole; of the {} visited, {} \
             culled by distance, {} by the frustum, {} by the depth pyramid; drawn trees {} and bushes {} (LOD \
             0/1/2), {} triangles; {:.2} MiB",
            self.set.instances.len(),
            self.cluster_count,
            h.clusters_culled,
            h.skipped,
            h.considered,
            h.culled_distance,
            h.culled_frustum,
            h.culled_hiz,
            lods(0).join("/"),
            lods(1).join("/"),
            self.triangles(&h),
            memory_bytes as f64 / f64::from(1u32 << 20)
        );
        let value = serde_json::json!({
            "instances": self.set.instances.len(),
            "clusters": self.cluster_count,
            "clusters_culled": h.clusters_culled,
            "skipped": h.skipped,
            "considered": h.considered,
            "culled_distance": h.culled_distance,
            "culled_frustum": h.culled_frustum,
            "culled_hiz": h.culled_hiz,
            "trees_per_lod": lods(0),
            "bushes_per_lod": lods(1),
            "triangles": self.triangles(&h),
            "memory_bytes": memory_bytes,
        });
        Ok(Some(EffectStats { key: "vegetation", value, lines: vec![line] }))
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twins_have_the_shader_sizes() {
        assert_eq!(std::mem::size_of::<VegetationHeaderGpu>(), structs::VEGETATION_HEADER);
        assert_eq!(std::mem::size_of::<VegetationVertexGpu>(), structs::VEGETATION_VERTEX);
        assert_eq!(std::mem::size_of::<super::super::clusters::VegetationClusterGpu>(), structs::VEGETATION_CLUSTER);
        assert_eq!(std::mem::size_of::<super::super::VegetationTypeGpu>(), structs::VEGETATION_TYPE);
        assert_eq!(std::mem::size_of::<crate::world::vegetation::Instance>(), structs::VEGETATION_INSTANCE);
    }
}
