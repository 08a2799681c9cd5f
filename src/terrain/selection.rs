//! What the LOD selection is asked for and what it returns: the views that
//! want detail, the error target, and the f32 inputs exactly as the GPU
//! traversal sees them. Shared by the `traverse` pass, the renderer, the
//! streaming want and the CPU reference.

use crate::world::{NodeId, WorldDesc};

/// Up to this many cameras refine one node list.
pub const MAX_CAMERAS: usize = crate::shaders::consts::MAX_CAMERAS as usize;

pub use crate::world::TraverseCamera;

/// The accuracy knob and the views it applies to.
#[derive(Debug, Clone, PartialEq)]
pub struct TraverseParams {
    pub cameras: Vec<TraverseCamera>,
    /// Largest accepted projected vertical error, in pixels (default 1).
    pub target_error_px: f32,
}

/// f32 inputs exactly as the GPU sees them (the push constants).
#[derive(Debug, Clone, Copy)]
pub struct GpuInputs {
    pub cameras: [[f32; 4]; MAX_CAMERAS],
    /// Forward axis (xyz) and `widest` (w) of each camera.
    pub forwards: [[f32; 4]; MAX_CAMERAS],
    pub camera_count: u32,
    pub target_error_px: f32,
    pub sector_size_m: f32,
    pub height_lo: f32,
    pub height_scale: f32,
    /// Added around each node's square, in node sides (0 but for the
    /// per-triangle rule, whose vertices' boxes reach a cell past it).
    pub box_pad: f32,
}

impl GpuInputs {
    pub fn new(world: &WorldDesc, params: &TraverseParams) -> Self {
        assert!((1..=MAX_CAMERAS).contains(&params.cameras.len()), "1..={MAX_CAMERAS} cameras");
        let mut cameras = [[0.0; 4]; MAX_CAMERAS];
        let mut forwards = [[0.0; 4]; MAX_CAMERAS];
        // Node boxes are in grid coordinates (metres from LOD-0 sample (0, 0)).
        let [ox, oy] = world.grid_origin_m;
        for (c, cam) in cameras.iter_mut().zip(&params.cameras) {
            let p = cam.position_m;
            *c = [(p[0] - ox) as f32, (p[1] - oy) as f32, p[2] as f32, cam.pixels_per_tan as f32];
        }
        for (f, cam) in forwards.iter_mut().zip(&params.cameras) {
            let a = cam.forward;
            *f = [a[0] as f32, a[1] as f32, a[2] as f32, cam.widest as f32];
        }
        let [lo, hi] = world.height_range_m;
        GpuInputs {
            cameras,
            forwards,
            camera_count: params.cameras.len() as u32,
            target_error_px: params.target_error_px,
            sector_size_m: world.sector_size_m() as f32,
            height_lo: lo,
            height_scale: (hi - lo) / 65535.0,
            box_pad: 0.0,
        }
    }
}

#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TraverseResult {
    /// (node, slot), sorted.
    pub nodes: Vec<(NodeId, u32)>,
    pub lod_counts: [u32; 16],
    pub overflow: u32,
    pub missing_roots: u32,
}
