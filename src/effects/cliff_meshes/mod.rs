//! Effect `cliff_meshes` (seed 000's procedural cliff pipeline): near the
//! camera, cells of a world grid whose ground is steeper than a threshold
//! get a mesh of the height field pushed out along its normal by a
//! world-anchored noise: shape the height field cannot hold, drawn into the
//! geometry pass so the tile passes shade it with the cliff flavours, like
//! the height field's own cliffs. `cliff_mesh_build` makes the meshes on
//! the GPU from the resident terrain, around a centre snapped to an eighth
//! of the radius and out to the radius plus that step, so it runs again only
//! when the camera leaves its step or the terrain changes; `cliff_meshes`
//! draws them in one indexed indirect draw. The build runs before the
//! terrain's draws and marks the meshed cells in the terrain's sink
//! (passes/terrain_sink.rs): the height field there is pushed `sink_m`
//! behind its mesh, so the mesh's unpushed parts, which lie on the height
//! field at another triangulation, do not fight it.
//!
//! ```toml
//! [effects]
//! cliff_meshes = { slope_deg = 40, band_deg = 10, amplitude_m = 0.8, radius_m = 100, cell_m = 2, sink_m = 0.5 }
//! ```

pub mod cliff_mesh_build;
pub mod frame;
pub mod kind;
// The pass file keeps its shader's and timer label's name.
#[allow(clippy::module_inception)]
pub mod cliff_meshes;

use crate::effects::cliff_meshes::cliff_mesh_build::{CliffBuildPush, CliffMeshBuild};
use crate::effects::cliff_meshes::cliff_meshes::CliffMeshDraw;
use crate::error::{Error, Result};
use crate::gpu::{vk, Buffer, BufferDesc, Context, MemoryLocation, Recorder};
use crate::passes::terrain_geometry::{DepthOptions, RenderTargets};
use crate::passes::terrain_query::VistaTerrain;
use crate::passes::terrain_sink::{TerrainSink, TerrainSinkHeader};
use crate::shaders::consts::CLIFF_CELL_QUADS;
use crate::shaders::structs;
use crate::targets::gbuffer::GBuffer;
use crate::terrain::gpu_quadtree::GpuQuadtree;
use serde::Serialize;

/// Effect `cliff_meshes`' parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CliffMeshParams {
    /// Ground steeper than this (degrees) starts to be pushed out.
    pub slope_deg: f32,
    /// The push grows to full over this many degrees more.
    pub band_deg: f32,
    /// The largest push along the normal (m).
    pub amplitude_m: f32,
    /// Cells whose centre lies within this distance of the camera.
    pub radius_m: f32,
    pub cell_m: f32,
    /// How far the height field under a meshed cell is pushed behind its
    /// mesh, along its normal (m; 0: not pushed, the two may fight).
    pub sink_m: f32,
    pub seed: u32,
}

impl Default for CliffMeshParams {
    fn default() -> Self {
        CliffMeshParams {
            slope_deg: 40.0,
            band_deg: 10.0,
            amplitude_m: 0.8,
            radius_m: 100.0,
            cell_m: 2.0,
            sink_m: 0.5,
            seed: 7,
        }
    }
}

/// Most cells a side of the square (the vertex buffer is sized for it).
pub const MAX_SIDE: u32 = 512;

impl CliffMeshParams {
    pub const PARAMETERS: [&'static str; 6] = ["slope_deg", "band_deg", "amplitude_m", "radius_m", "cell_m", "sink_m"];

    /// The step the build's centre snaps to: an eighth of the radius.
    pub fn step_m(&self) -> f32 {
        self.radius_m / 8.0
    }

    /// How far from the centre cells are built: the radius around any
    /// camera within the step.
    pub fn reach_m(&self) -> f32 {
        self.radius_m + self.step_m() * std::f32::consts::FRAC_1_SQRT_2
    }

    /// The build's centre for a camera at `xy` (world m).
    pub fn centre(&self, xy: [f32; 2]) -> [f32; 2] {
        xy.map(|c| ((c / self.step_m()).floor() + 0.5) * self.step_m())
    }

    pub fn side(&self) -> u32 {
        (2.0 * self.reach_m() / self.cell_m).ceil() as u32 + 1
    }

    /// Cells the vertex buffer holds: those of the disc, with margin.
    pub fn capacity(&self) -> u32 {
        let disc = std::f32::consts::PI * (self.reach_m() / self.cell_m + 1.0).powi(2);
        (disc.ceil() as u32).min(self.side() * self.side())
    }

    /// Normal z where the push starts and where it is full.
    pub fn cos_range(&self) -> [f32; 2] {
        let full = (self.slope_deg + self.band_deg).min(90.0);
        [self.slope_deg.to_radians().cos(), full.to_radians().cos()]
    }

    pub fn validate(&self) -> Result<()> {
        if self.side() > MAX_SIDE {
            return Err(Error::Scene(format!(
                "effects.cliff_meshes: radius_m {} over cell_m {} makes {} cells a side; at most {MAX_SIDE}",
                self.radius_m,
                self.cell_m,
                self.side()
            )));
        }
        Ok(())
    }

    pub(crate) fn read(&mut self, key: &str, name: &str, v: &toml::Value) -> Result<()> {
        use crate::scene::params::number;
        match name {
            "slope_deg" => self.slope_deg = number(key, v, 0.0, 89.0)? as f32,
            "band_deg" => self.band_deg = number(key, v, 0.1, 45.0)? as f32,
            "amplitude_m" => self.amplitude_m = number(key, v, 0.0, 20.0)? as f32,
            "radius_m" => self.radius_m = number(key, v, 1.0, 2000.0)? as f32,
            "cell_m" => self.cell_m = number(key, v, 0.25, 50.0)? as f32,
            "sink_m" => self.sink_m = number(key, v, 0.0, 20.0)? as f32,
            _ => unreachable!("{key} is a cliff_meshes parameter but not read"),
        }
        Ok(())
    }
}

/// Vertices of one cell's patch.
pub const CELL_VERTICES: u32 = (CLIFF_CELL_QUADS + 1) * (CLIFF_CELL_QUADS + 1);

/// Host twin of `CliffHeader` (cliff_mesh.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CliffHeaderGpu {
    pub index_count: u32,
    pub instance_count: u32,
    pub first_index: u32,
    pub vertex_offset: i32,
    pub first_instance: u32,
    pub tested: u32,
    pub overflow: u32,
    pub pad: u32,
}

/// The cliff meshes of the last build.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct CliffCounters {
    /// Cells within the radius.
    pub tested: u32,
    /// Cells with a mesh (drawn).
    pub cells: u32,
    /// Cliff cells past the capacity (not drawn).
    pub overflow: u32,
    pub triangles: u64,
}

/// One cell's patch: two counter-clockwise triangles per quad (seen from
/// above), indices into its (CLIFF_CELL_QUADS + 1)^2 vertices.
pub fn cell_indices() -> Vec<u32> {
    let (n, side) = (CLIFF_CELL_QUADS, CLIFF_CELL_QUADS + 1);
    let mut out = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * side + i;
            out.extend([a, a + 1, a + side + 1, a, a + side + 1, a + side]);
        }
    }
    out
}

/// The passes and what they share. Teardown: fields drop in declaration
/// order, each retired until the frames using it completed.
pub struct CliffMeshes {
    pub params: CliffMeshParams,
    pub build: CliffMeshBuild,
    pub draw: CliffMeshDraw,
    header: Buffer,
    vertices: Buffer,
    indices: Buffer,
    /// The meshed cells, where the terrain's draws push the height field behind.
    sink: TerrainSink,
    /// The centre last built around.
    built_at: Option<[f32; 2]>,
    /// This frame's build (None: the last one holds).
    pub(super) planned: Option<CliffBuildPush>,
}

impl CliffMeshes {
    pub fn new(ctx: &Context, params: CliffMeshParams, depth: DepthOptions) -> Result<Self> {
        params.validate()?;
        let buffer =
            |name, size, usage| Buffer::new(ctx, &BufferDesc { name, size, usage, location: MemoryLocation::GpuOnly });
        let rw = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let readable = rw | vk::BufferUsageFlags::TRANSFER_SRC;
        let idx = cell_indices();
        let indices = buffer(
            "cliff_mesh_indices",
            (idx.len() * 4) as u64,
            vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
        )?;
        ctx.upload(&indices, bytemuck::cast_slice(&idx))?;
        let vertex_bytes = u64::from(params.capacity()) * u64::from(CELL_VERTICES) * structs::CLIFF_VERTEX as u64;
        Ok(CliffMeshes {
            params,
            build: CliffMeshBuild::new(ctx)?,
            draw: CliffMeshDraw::new(ctx, depth)?,
            header: buffer(
                "cliff_mesh_header",
                structs::CLIFF_HEADER as u64,
                readable | vk::BufferUsageFlags::INDIRECT_BUFFER,
            )?,
            vertices: buffer("cliff_mesh_vertices", vertex_bytes, readable)?,
            indices,
            sink: TerrainSink::new(ctx, "cliff_mesh_sink", params.side())?,
            built_at: None,
            planned: None,
        })
    }

    /// The frame's build, or None when the last one still holds (the
    /// camera in the same step, the same terrain).
    pub fn plan(
        &mut self,
        camera_world: [f32; 3],
        terrain: VistaTerrain,
        terrain_changed: bool,
    ) -> Option<CliffBuildPush> {
        let p = &self.params;
        let centre = p.centre([camera_world[0], camera_world[1]]);
        if !terrain_changed && self.built_at == Some(centre) {
            return None;
        }
        self.built_at = Some(centre);
        let cell0 = centre.map(|c| ((c - p.reach_m()) / p.cell_m).floor() as i32);
        let [cos_start, cos_full] = p.cos_range();
        Some(CliffBuildPush {
            terrain,
            cell0,
            side: p.side(),
            capacity: p.capacity(),
            cell_m: p.cell_m,
            reach_m: p.reach_m(),
            cos_start,
            cos_full,
            amplitude_m: p.amplitude_m,
            // Half the LOD-0 spacing: the finest slope the samples hold.
            step_m: 0.5 * terrain.spacing_m,
            seed: p.seed,
            pad: 0,
            centre,
        })
    }

    pub fn record_build(&self, rec: &mut Recorder, push: &CliffBuildPush, sector: &Buffer, tree: &GpuQuadtree) {
        let index_count = 6 * CLIFF_CELL_QUADS * CLIFF_CELL_QUADS;
        let reset = CliffHeaderGpu { index_count, ..CliffHeaderGpu::default() };
        rec.update_buffer(&self.header, 0, bytemuck::bytes_of(&reset));
        let sink = TerrainSinkHeader {
            cell0: push.cell0,
            side: push.side,
            cell_m: push.cell_m,
            sink_m: self.params.sink_m,
            pad: [0; 3],
        };
        self.sink.reset(rec, &sink);
        rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::COMPUTE_SHADER);
        self.build.record(rec, push, sector, tree, &self.header, &self.vertices, self.sink.buffer());
    }

    /// The sink the terrain's draws read, where the height field is pushed at all.
    pub fn sink(&self) -> Option<&TerrainSink> {
        (self.params.sink_m > 0.0).then_some(&self.sink)
    }

    pub fn record_draw(&self, rec: &mut Recorder, targets: &RenderTargets, gb: &GBuffer, view: &Buffer) {
        self.draw.record(rec, targets, gb, view, &self.vertices, &self.indices, &self.header);
    }

    /// The centre the last build was made around.
    pub fn built_centre(&self) -> Option<[f32; 2]> {
        self.built_at
    }

    /// The last build's counters and vertices (waits for the GPU; tools
    /// and tests): per listed cell, CELL_VERTICES (world position, normal).
    pub fn read(&self, ctx: &Context) -> Result<(CliffCounters, Vec<[f32; 4]>)> {
        let h: CliffHeaderGpu = bytemuck::pod_read_unaligned(&ctx.read_buffer(&self.header)?[..structs::CLIFF_HEADER]);
        let bytes = ctx.read_buffer(&self.vertices)?;
        let n = (h.instance_count * CELL_VERTICES) as usize;
        let vertices: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes[..n * 16]);
        let triangles = u64::from(h.instance_count) * u64::from(2 * CLIFF_CELL_QUADS * CLIFF_CELL_QUADS);
        Ok((CliffCounters { tested: h.tested, cells: h.instance_count, overflow: h.overflow, triangles }, vertices))
    }

    pub fn pipeline_labels(&self) -> [String; 2] {
        [self.build.pipeline_label().to_string(), self.draw.pipeline_label().to_string()]
    }

    pub fn memory(&self) -> Vec<(String, u64)> {
        let mut m: Vec<(String, u64)> =
            [&self.header, &self.vertices, &self.indices].iter().map(|b| (b.name.clone(), b.memory_bytes())).collect();
        m.push(self.sink.memory());
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twins_have_the_shader_sizes() {
        assert_eq!(std::mem::size_of::<CliffHeaderGpu>(), structs::CLIFF_HEADER);
        assert_eq!(std::mem::size_of::<CliffBuildPush>(), structs::CLIFF_BUILD_PUSH);
        assert_eq!(structs::CLIFF_VERTEX, 16);
    }

    #[test]
    fn the_capacity_covers_the_disc_and_limits_hold() {
        let p = CliffMeshParams::default();
        assert!(p.capacity() as f32 >= std::f32::consts::PI * (p.reach_m() / p.cell_m).powi(2));
        // Any camera within a step has its radius inside the build's reach.
        let c = p.centre([101.3, 57.9]);
        assert!(((101.3 - c[0]).powi(2) + (57.9 - c[1]).powi(2)).sqrt() + p.radius_m <= p.reach_m() + 1e-4);
        assert_eq!(cell_indices().len() as u32, 6 * CLIFF_CELL_QUADS * CLIFF_CELL_QUADS);
        let big = CliffMeshParams { radius_m: 2000.0, cell_m: 1.0, ..p };
        assert!(big.validate().unwrap_err().to_string().contains("cells a side"));
        let [start, full] = p.cos_range();
        assert!(start > full && (start - 40f32.to_radians().cos()).abs() < 1e-6);
    }
}
