//! Effect `grass`'s GPU side: its three passes and what they share (the
//! rule table, the header with the draw's arguments and counters, the
//! instance list sized for every cell of the square, the pigment map),
//! and each frame's plan. Teardown: fields drop in declaration order, each
//! object retired to the context until the frames using it completed.

use super::{GrassCounters, GrassParams};
use crate::effects::grass::grass_draw::{DrawInputs, GrassDraw, GrassDrawPush};
use crate::effects::grass::grass_pigment::{GrassPigment, GrassPigmentPush};
use crate::effects::grass::grass_place::{GrassDecals, GrassPlace, GrassPlacePush, PlaceBuffers};
use crate::effects::virtual_texture::decal_gpu::DecalResources;
use crate::effects::virtual_texture::decals::Decal;
use crate::error::Result;
use crate::gpu::{vk, Buffer, BufferDesc, Context, Image, ImageDesc, MemoryLocation, Recorder};
use crate::passes::gbuffer_tiles::MaterialBindings;
use crate::passes::terrain_geometry::RenderTargets;
use crate::passes::terrain_query::VistaTerrain;
use crate::shaders::consts::{
    DECAL_MAX, GRASS_BLADES, GRASS_BLADE_VERTICES, GRASS_FLAG_FRUSTUM, GRASS_FLAG_HIZ, GRASS_FLAG_HOLES,
    GRASS_PIGMENT_TEXELS, GRASS_RULES,
};
use crate::shaders::structs;
use crate::targets::gbuffer::GBuffer;
use crate::targets::GbufferLayout;

/// Host twin of `GrassInstance` (grass.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GrassInstanceGpu {
    /// xyz where it stands (world m), w its height (m).
    pub position: [f32; 4],
    pub cell: [i32; 2],
    /// material | rotation << 8 | lean << 16.
    pub packed: u32,
    /// Octahedral 8-bit normal: x | y << 8.
    pub normal: u32,
}

/// Host twin of `GrassHeader`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GrassHeaderGpu {
    pub vertex_count: u32,
    pub instance_count: u32,
    pub first_vertex: u32,
    pub first_instance: u32,
    pub in_range: u32,
    pub placed: u32,
    pub culled_frustum: u32,
    pub culled_hiz: u32,
    pub skipped_occurrence: u32,
}

impl GrassHeaderGpu {
    pub const BYTES: u64 = structs::GRASS_HEADER as u64;

    fn reset() -> GrassHeaderGpu {
        GrassHeaderGpu { vertex_count: GRASS_BLADES * GRASS_BLADE_VERTICES, ..GrassHeaderGpu::default() }
    }

    pub fn counters(&self) -> GrassCounters {
        GrassCounters {
            in_range: self.in_range,
            placed: self.placed,
            culled_frustum: self.culled_frustum,
            culled_hiz: self.culled_hiz,
            skipped_occurrence: self.skipped_occurrence,
            drawn: self.instance_count,
        }
    }
}

/// One frame's grass work, planned on the CPU.
#[derive(Debug, Clone)]
pub struct GrassFrame {
    pub place: GrassPlacePush,
    /// The pigment map's square, and whether it is rendered this frame.
    pub pigment: GrassPigmentPush,
    pub pigment_due: bool,
    /// Effect `decals`: the decals touching the placement's and the
    /// pigment map's squares, in scene order.
    pub place_decals: Vec<u32>,
    pub pigment_decals: Vec<u32>,
}

/// What a frame's placement depends on beyond the parameters.
pub struct GrassFrameInputs {
    pub camera_world: [f32; 3],
    pub terrain: VistaTerrain,
    pub depth_size: [u32; 2],
    /// Holes cut this frame; the pyramid is built this frame.
    pub holes: bool,
    pub hiz: bool,
    /// The resident terrain changed this frame (the pigment is redone).
    pub terrain_changed: bool,
}

/// Effect `decals`: the decals an earlier frame uploaded (None while an
/// edit waits for its upload: grass keeps the list it had).
pub type UploadedDecals<'a> = Option<&'a [Decal]>;

pub struct Grass {
    pub params: GrassParams,
    pub pigment_pass: GrassPigment,
    pub place: GrassPlace,
    pub draw: GrassDraw,
    rules: Buffer,
    header: Buffer,
    instances: Buffer,
    /// The vegetation folder's occurrence words (scene key `vegetation`).
    occurrence: Option<Buffer>,
    pigment: Image,
    /// The pigment map's corner as last rendered.
    pigment_at: Option<[f32; 2]>,
    /// Effect `decals`: the decal list grass last planned with (a change
    /// redoes the pigment), and the indices of those touching its squares.
    decals: Option<(Vec<Decal>, Buffer)>,
    /// This frame's plan (`FrameEffect::plan`).
    pub(super) frame: Option<GrassFrame>,
    /// Tests only (feature `test-hooks`): no frustum or Hi-Z culling
    /// (every placed tuft drawn).
    #[cfg(feature = "test-hooks")]
    pub no_culling: bool,
}

impl Grass {
    /// `hiz`: effect occlusion is built (the HIZ variant too); `decals`:
    /// effect decals is (the DECALS variants); `layout`: the engine's
    /// G-buffer the blades are drawn into (output `gbuffer`), else vista's.
    pub fn new(
        ctx: &Context,
        params: &GrassParams,
        (hiz, decals): (bool, bool),
        depth_format: vk::Format,
        layout: Option<&GbufferLayout>,
    ) -> Result<Self> {
        params.validate()?;
        let buffer =
            |name, size, usage| Buffer::new(ctx, &BufferDesc { name, size, usage, location: MemoryLocation::GpuOnly });
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let cells = u64::from(params.side()).pow(2);
        let rules = buffer("grass_rules", u64::from(GRASS_RULES) * structs::GRASS_RULE as u64, storage)?;
        ctx.upload(&rules, bytemuck::cast_slice(&params.rules_gpu()))?;
        let readable = storage | vk::BufferUsageFlags::TRANSFER_SRC;
        let occurrence = match &params.occurrence {
            Some(o) => {
                let words = buffer("grass_occurrence", 4 * o.words.len() as u64, storage)?;
                ctx.upload(&words, bytemuck::cast_slice(&o.words))?;
                Some(words)
            }
            None => None,
        };
        Ok(Grass {
            params: params.clone(),
            pigment_pass: GrassPigment::new(ctx, decals)?,
            place: GrassPlace::new(ctx, hiz, decals, occurrence.is_some())?,
            draw: GrassDraw::new(ctx, depth_format, layout)?,
            rules,
            header: buffer("grass_header", GrassHeaderGpu::BYTES, readable | vk::BufferUsageFlags::INDIRECT_BUFFER)?,
            instances: buffer("grass_instances", cells * structs::GRASS_INSTANCE as u64, readable)?,
            occurrence,
            pigment: Image::new(
                ctx,
                &ImageDesc {
                    name: "grass_pigment",
                    format: vk::Format::R8G8B8A8_UNORM,
                    extent: [GRASS_PIGMENT_TEXELS; 2],
                    mip_levels: 1,
                    array_layers: 1,
                    usage: vk::ImageUsageFlags::STORAGE
                        | vk::ImageUsageFlags::SAMPLED
                        | vk::ImageUsageFlags::TRANSFER_SRC,
                },
            )?,
            pigment_at: None,
            decals: if decals {
                let size = 2 * u64::from(DECAL_MAX) * 4;
                Some((Vec::new(), buffer("grass_decals", size, storage)?))
            } else {
                None
            },
            frame: None,
            #[cfg(feature = "test-hooks")]
            no_culling: false,
        })
    }

    /// The step the pigment map's centre snaps to: it is rendered again
    /// when the camera crosses into another step (an eighth of the radius).
    fn pigment_step_m(&self) -> f32 {
        self.params.radius_m / 8.0
    }

    /// The pigment map's texel: its square covers the radius around any
    /// camera within its step, with two texels to spare each way.
    pub fn pigment_texel_m(&self) -> f32 {
        2.0 * (self.params.radius_m + self.pigment_step_m()) / (GRASS_PIGMENT_TEXELS - 4) as f32
    }

    /// The pigment map's south-west corner for a camera at `xy`: on the
    /// texel grid (texels stay put in the world), the map centred on the
    /// camera's step.
    pub fn pigment_origin(&self, xy: [f32; 2]) -> [f32; 2] {
        let (step, texel) = (self.pigment_step_m(), self.pigment_texel_m());
        let half = (GRASS_PIGMENT_TEXELS / 2) as f32;
        xy.map(|c| ((((c / step).floor() + 0.5) * step / texel).floor() - half) * texel)
    }

    /// Plans the frame: the cells, the flags, the decals touching each
    /// square, and whether the pigment map is redone (first frame, the
    /// camera crossed into another step, the terrain or the decals changed).
    pub fn begin_frame(&mut self, f: &GrassFrameInputs, uploaded: UploadedDecals) -> GrassFrame {
        let mut decals_changed = false;
        if let (Some((seen, _)), Some(now)) = (&mut self.decals, uploaded) {
            if seen[..] != *now {
                *seen = now.to_vec();
                decals_changed = true;
            }
        }
        let p = &self.params;
        let grid = p.grid([f.camera_world[0], f.camera_world[1]]);
        let mut flags = 0;
        if f.holes {
            flags |= GRASS_FLAG_HOLES;
        }
        #[cfg(feature = "test-hooks")]
        let culled = !self.no_culling;
        #[cfg(not(feature = "test-hooks"))]
        let culled = true;
        if culled {
            flags |= GRASS_FLAG_FRUSTUM | if f.hiz { GRASS_FLAG_HIZ } else { 0 };
        }
        let place = GrassPlacePush {
            terrain: f.terrain,
            cell0: grid.cell0,
            side: grid.side,
            flags,
            cell_m: p.cell_m,
            radius_m: p.radius_m,
            fade_m: p.fade_m,
            height_m: p.blade_height_m,
            depth_size: f.depth_size,
            seed: p.seed,
            // The vertex shader's widest lean (0.5 of the height) plus half a root width.
            reach_m: 0.5 + 0.5 * p.blade_width_m / p.blade_height_m,
            decal_count: 0,
            occ_per_m: p.occurrence.as_ref().map_or(0.0, |o| o.per_m()),
            occ_size: p.occurrence.as_ref().map_or([0; 2], |o| o.size),
        };
        let texel = self.pigment_texel_m();
        let origin = self.pigment_origin([f.camera_world[0], f.camera_world[1]]);
        let due = f.terrain_changed || decals_changed || self.pigment_at != Some(origin);
        self.pigment_at = Some(origin);
        let side = texel * GRASS_PIGMENT_TEXELS as f32;
        let cells = [0, 1].map(|i| grid.cell0[i] as f32 * p.cell_m);
        let span = grid.side as f32 * p.cell_m;
        let square = |o: [f32; 2], s: f32| [o[0], o[1], o[0] + s, o[1] + s].map(f64::from);
        let touching = |rect: [f64; 4]| -> Vec<u32> {
            let seen = self.decals.as_ref().map_or(&[][..], |(d, _)| &d[..]);
            (0..seen.len() as u32).filter(|&i| seen[i as usize].touches(rect, f64::from(p.cell_m))).collect()
        };
        let place_decals = touching(square(cells, span));
        let pigment_decals = touching(square(origin, side));
        let mut frame = GrassFrame {
            place,
            pigment: GrassPigmentPush { terrain: f.terrain, origin_m: origin, texel_m: texel, decal_count: 0 },
            pigment_due: due,
            place_decals,
            pigment_decals,
        };
        frame.place.decal_count = frame.place_decals.len() as u32;
        frame.pigment.decal_count = frame.pigment_decals.len() as u32;
        frame
    }

    /// The decal bindings (effect decals; the lists only hold decals an
    /// earlier frame uploaded, none before the first upload).
    fn decal_bindings<'a>(&'a self, gpu: Option<&'a DecalResources>) -> Option<GrassDecals<'a>> {
        let (_, list) = self.decals.as_ref()?;
        Some(GrassDecals { gpu: gpu.expect("the decals' objects of a renderer with effect decals"), list })
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record_pigment(
        &self,
        rec: &mut Recorder,
        f: &GrassFrame,
        sector_data: &Buffer,
        tree: &crate::terrain::gpu_quadtree::GpuQuadtree,
        m: &MaterialBindings,
        decal_gpu: Option<&DecalResources>,
    ) {
        let decals = self.decal_bindings(decal_gpu);
        if let Some(d) = &decals {
            let offset = u64::from(DECAL_MAX) * 4;
            write_list(rec, d.list, offset, &f.pigment_decals);
            // The list reaches the pass's reads (syncval: tests/syncval.rs).
            rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        }
        self.pigment_pass.record(rec, &self.pigment, f.pigment, sector_data, tree, m, decals);
    }

    /// Resets the header and places this frame's tufts; `hiz`: the
    /// pyramid, when the frame built one.
    #[allow(clippy::too_many_arguments)]
    pub fn record_place(
        &self,
        rec: &mut Recorder,
        f: &GrassFrame,
        view: &Buffer,
        hiz: Option<&Image>,
        sector_data: &Buffer,
        tree: &crate::terrain::gpu_quadtree::GpuQuadtree,
        decal_gpu: Option<&DecalResources>,
    ) {
        let decals = self.decal_bindings(decal_gpu);
        if let Some(d) = &decals {
            write_list(rec, d.list, 0, &f.place_decals);
        }
        rec.update_buffer(&self.header, 0, bytemuck::bytes_of(&GrassHeaderGpu::reset()));
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        let hiz = hiz.filter(|_| f.place.flags & GRASS_FLAG_HIZ != 0);
        let (rules, header, instances) = (&self.rules, &self.header, &self.instances);
        let occurrence = self.occurrence.as_ref();
        let out = PlaceBuffers { view, rules, header, instances, hiz, decals, occurrence };
        self.place.record(rec, &out, &f.place, sector_data, tree);
    }

    pub fn record_draw(
        &self,
        rec: &mut Recorder,
        f: &GrassFrame,
        view: &Buffer,
        targets: &RenderTargets,
        gb: &GBuffer,
    ) {
        let inputs = DrawInputs {
            view,
            header: &self.header,
            instances: &self.instances,
            rules: &self.rules,
            pigment: &self.pigment,
        };
        let push = GrassDrawPush {
            pigment_origin_m: f.pigment.origin_m,
            pigment_size_m: f.pigment.texel_m * GRASS_PIGMENT_TEXELS as f32,
            width_per_m: self.params.blade_width_m / self.params.blade_height_m,
        };
        self.draw.record(rec, targets, gb, &inputs, push);
    }

    /// The header (draw arguments, then counters): telemetry copies it.
    pub fn header(&self) -> &Buffer {
        &self.header
    }

    /// The tufts of the last frame, read back (waits for the GPU; tests).
    pub fn read_instances(&self, ctx: &Context) -> Result<Vec<GrassInstanceGpu>> {
        let h: GrassHeaderGpu =
            bytemuck::pod_read_unaligned(&ctx.read_buffer(&self.header)?[..GrassHeaderGpu::BYTES as usize]);
        let bytes = ctx.read_buffer(&self.instances)?;
        let all: Vec<GrassInstanceGpu> = bytemuck::pod_collect_to_vec(&bytes);
        Ok(all[..h.instance_count as usize].to_vec())
    }

    /// The pigment map (tests, pictures): RGBA8, the albedo's square root.
    pub fn pigment(&self) -> &Image {
        &self.pigment
    }

    pub fn pipeline_labels(&self) -> Vec<String> {
        let mut out = vec![self.pigment_pass.pipeline_label().to_string()];
        out.extend(self.place.pipeline_labels().map(str::to_string));
        out.push(self.draw.pipeline_label().to_string());
        out
    }

    pub fn memory(&self) -> Vec<(String, u64)> {
        let buffers = [&self.rules, &self.header, &self.instances]
            .into_iter()
            .chain(self.decals.as_ref().map(|d| &d.1))
            .chain(self.occurrence.as_ref());
        buffers
            .map(|b| (b.name.clone(), b.memory_bytes()))
            .chain([(self.pigment.name.clone(), self.pigment.memory_bytes())])
            .collect()
    }
}

/// Writes a decal index list at `offset` (a list may be empty: nothing to write).
fn write_list(rec: &mut Recorder, list: &Buffer, offset: u64, indices: &[u32]) {
    if !indices.is_empty() {
        rec.update_buffer(list, offset, bytemuck::cast_slice(indices));
    }
}
