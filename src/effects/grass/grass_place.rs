//! `grass_place` (effect `grass`): one thread per world cell of the square
//! around the camera places at most one tuft on the terrain (material
//! rules, holes, the cell's hash, and with variant `DECALS` the decals'
//! coverage), culls it by the frustum and, variant `HIZ` (effect
//! `occlusion`, on this frame), the depth pyramid, and appends it to
//! `grass_draw`'s one indirect draw; with variant `OCCURRENCE` (a
//! vegetation folder's maps) it skips the cells whose bit is off before
//! reading the terrain. Its header holds the draw's arguments and the
//! frame's counters.

use crate::effects::virtual_texture::decal_gpu::DecalResources;
use crate::error::Result;
use crate::gpu::{vk, Binding, Buffer, Context, Image, Pipeline, Recorder, Resource, Sampler};
use crate::passes::cull_patches::nearest_sampler;
use crate::passes::terrain_query::VistaTerrain;
use crate::shaders::{grass_place as sh, structs};
use crate::terrain::gpu_quadtree::{GpuQuadtree, ATLAS_ALBEDO, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL, ATLAS_SPLAT};

/// Host twin of `GrassPlacePush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GrassPlacePush {
    pub terrain: VistaTerrain,
    pub cell0: [i32; 2],
    pub side: u32,
    /// GRASS_FLAG_* bits.
    pub flags: u32,
    pub cell_m: f32,
    pub radius_m: f32,
    pub fade_m: f32,
    pub height_m: f32,
    pub depth_size: [u32; 2],
    pub seed: u32,
    /// How far a blade reaches sideways per metre of its height.
    pub reach_m: f32,
    /// DECALS: the decals touching the square (the grass decal list's first).
    pub decal_count: u32,
    /// OCCURRENCE: 1 / an occurrence cell's side, and the map's cells.
    pub occ_per_m: f32,
    pub occ_size: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<GrassPlacePush>() == structs::GRASS_PLACE_PUSH);

/// What one placement writes and reads besides the terrain.
pub struct PlaceBuffers<'a> {
    pub view: &'a Buffer,
    pub rules: &'a Buffer,
    /// Reset by the caller before the dispatch.
    pub header: &'a Buffer,
    pub instances: &'a Buffer,
    /// The pyramid (GENERAL layout), for the HIZ variant.
    pub hiz: Option<&'a Image>,
    /// The decals and the grass decal list, for the DECALS variant.
    pub decals: Option<GrassDecals<'a>>,
    /// The occurrence words, for the OCCURRENCE variant.
    pub occurrence: Option<&'a Buffer>,
}

/// The decals grass reads (effect `decals`): their GPU objects and the
/// indices of those touching each grass pass's square.
#[derive(Clone, Copy)]
pub struct GrassDecals<'a> {
    pub gpu: &'a DecalResources,
    pub list: &'a Buffer,
}

impl GrassDecals<'_> {
    /// The bindings both grass compute passes give them (same names).
    pub fn bindings(&self) -> [(Binding, Resource<'_>); 6] {
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        [
            (sh::DECALS, Resource::Buffer(&self.gpu.list)),
            (sh::DECAL_POINTS, Resource::Buffer(&self.gpu.points)),
            (sh::DECAL_TEXTURES, Resource::Image(&self.gpu.textures, read)),
            (sh::DECAL_CLAMP, Resource::Sampler(self.gpu.clamp.raw())),
            (sh::DECAL_REPEAT, Resource::Sampler(self.gpu.repeat.raw())),
            (sh::GRASS_DECALS, Resource::Buffer(self.list)),
        ]
    }
}

pub struct GrassPlace {
    /// (variant bits, pipeline): with and without HIZ, DECALS as built.
    pipelines: Vec<(u32, Pipeline)>,
    nearest: Sampler,
}

impl GrassPlace {
    pub const NAME: &'static str = sh::PASS;

    /// `hiz`: also the variant that culls by the depth pyramid; `decals`,
    /// `occurrence`: every variant reads the decals, the occurrence map.
    pub fn new(ctx: &Context, hiz: bool, decals: bool, occurrence: bool) -> Result<Self> {
        let base = if decals { sh::VARIANT_DECALS } else { 0 } | if occurrence { sh::VARIANT_OCCURRENCE } else { 0 };
        let variants = if hiz { vec![base, base | sh::VARIANT_HIZ] } else { vec![base] };
        let pipelines = Pipeline::compute_variants(ctx, Self::NAME, &variants, sh::variant)?;
        Ok(GrassPlace { pipelines, nearest: nearest_sampler(ctx, "grass_place_nearest")? })
    }

    pub fn pipeline_labels(&self) -> impl Iterator<Item = &str> {
        self.pipelines.iter().map(|(_, p)| p.label.as_str())
    }

    pub fn record(
        &self,
        rec: &mut Recorder,
        out: &PlaceBuffers,
        push: &GrassPlacePush,
        sector_data: &Buffer,
        tree: &GpuQuadtree,
    ) {
        let want = if out.hiz.is_some() { sh::VARIANT_HIZ } else { 0 }
            | if out.decals.is_some() { sh::VARIANT_DECALS } else { 0 }
            | if out.occurrence.is_some() { sh::VARIANT_OCCURRENCE } else { 0 };
        let (_, pipeline) = self
            .pipelines
            .iter()
            .find(|(v, _)| *v == want)
            .expect("grass_place built for the frame's pyramid, decals and occurrence map");
        rec.bind_pipeline(pipeline);
        let mut bindings = vec![
            (sh::VIEW, Resource::Buffer(out.view)),
            (sh::SECTOR_DATA, Resource::Buffer(sector_data)),
            (sh::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
            (sh::NORMAL_ATLAS, Resource::Image(tree.required_atlas(ATLAS_NORMAL), ATLAS_LAYOUT)),
            (sh::SPLAT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_SPLAT), ATLAS_LAYOUT)),
            (sh::ALBEDO_ATLAS, Resource::Image(tree.required_atlas(ATLAS_ALBEDO), ATLAS_LAYOUT)),
            (sh::NEAREST, Resource::Sampler(self.nearest.raw())),
            (sh::RULES, Resource::Buffer(out.rules)),
            (sh::HEADER, Resource::Buffer(out.header)),
            (sh::INSTANCES, Resource::Buffer(out.instances)),
        ];
        if let Some(hiz) = out.hiz {
            bindings.push((sh::HIZ, Resource::Image(hiz, vk::ImageLayout::GENERAL)));
        }
        if let Some(d) = &out.decals {
            bindings.extend(d.bindings());
        }
        if let Some(o) = out.occurrence {
            bindings.push((sh::OCCURRENCE, Resource::Buffer(o)));
        }
        rec.push_descriptors(pipeline, &bindings);
        rec.push_constants(pipeline, push);
        let [gx, gy, _] = sh::WORKGROUP_SIZE;
        rec.dispatch(push.side.div_ceil(gx), push.side.div_ceil(gy), 1);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::ALL_COMMANDS);
    }
}
