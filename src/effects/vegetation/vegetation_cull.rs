//! `vegetation_cull` (effect `vegetation`): one thread per cluster
//! (`clusters.rs`) tests its box; the workgroup then tests each instance
//! of its clusters not culled whole: by its type's draw distance, the frustum and, variant
//! `HIZ` (effect `occlusion`, on this frame), the depth pyramid, and
//! appends the rest to the indexed indirect draw of their mesh kind and
//! LOD. The header holds the six draws' arguments and the frame's counters.

use crate::error::Result;
use crate::gpu::{vk, Buffer, Context, Image, Pipeline, Recorder, Resource, Sampler};
use crate::passes::cull_patches::nearest_sampler;
use crate::shaders::{structs, vegetation_cull as sh};

/// Host twin of `VegetationCullPush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VegetationCullPush {
    /// Clusters.
    pub count: u32,
    /// VEG_FLAG_* bits.
    pub flags: u32,
    pub lod_m: [f32; 2],
    pub depth_size: [u32; 2],
    pub pad: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<VegetationCullPush>() == structs::VEGETATION_CULL_PUSH);

/// What one culling reads and writes.
pub struct CullBuffers<'a> {
    pub view: &'a Buffer,
    /// Sorted by cluster.
    pub instances: &'a Buffer,
    pub clusters: &'a Buffer,
    pub types: &'a Buffer,
    /// Reset by the caller before the dispatch.
    pub header: &'a Buffer,
    pub visible: &'a Buffer,
    /// The pyramid (GENERAL layout), for the HIZ variant.
    pub hiz: Option<&'a Image>,
}

pub struct VegetationCull {
    /// (variant bits, pipeline): without and, with occlusion, with HIZ.
    pipelines: Vec<(u32, Pipeline)>,
    nearest: Sampler,
}

impl VegetationCull {
    pub const NAME: &'static str = sh::PASS;

    pub fn new(ctx: &Context, hiz: bool) -> Result<Self> {
        let variants = if hiz { vec![0, sh::VARIANT_HIZ] } else { vec![0] };
        let pipelines = Pipeline::compute_variants(ctx, Self::NAME, &variants, sh::variant)?;
        Ok(VegetationCull { pipelines, nearest: nearest_sampler(ctx, "vegetation_cull_nearest")? })
    }

    pub fn pipeline_labels(&self) -> impl Iterator<Item = &str> {
        self.pipelines.iter().map(|(_, p)| p.label.as_str())
    }

    pub fn record(&self, rec: &mut Recorder, out: &CullBuffers, push: &VegetationCullPush) {
        let want = if out.hiz.is_some() { sh::VARIANT_HIZ } else { 0 };
        let (_, pipeline) =
            self.pipelines.iter().find(|(v, _)| *v == want).expect("vegetation_cull built for the frame's pyramid");
        rec.bind_pipeline(pipeline);
        let mut bindings = vec![
            (sh::VIEW, Resource::Buffer(out.view)),
            (sh::INSTANCES, Resource::Buffer(out.instances)),
            (sh::CLUSTERS, Resource::Buffer(out.clusters)),
            (sh::TYPES, Resource::Buffer(out.types)),
            (sh::HEADER, Resource::Buffer(out.header)),
            (sh::VISIBLE, Resource::Buffer(out.visible)),
        ];
        if let Some(hiz) = out.hiz {
            bindings.push((sh::HIZ, Resource::Image(hiz, vk::ImageLayout::GENERAL)));
            bindings.push((sh::NEAREST, Resource::Sampler(self.nearest.raw())));
        }
        rec.push_descriptors(pipeline, &bindings);
        rec.push_constants(pipeline, push);
        rec.dispatch(push.count.div_ceil(sh::WORKGROUP_SIZE[0]), 1, 1);
        // The draws read the header's arguments and the visible list.
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}
