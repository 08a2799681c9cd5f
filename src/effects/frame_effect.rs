//! The built side of an effect: [`FrameEffect`], which the renderer holds
//! one of per effect folder that is on and drives each frame: it plans on
//! the CPU, records its passes at named [`FramePoint`]s, lends the core
//! passes what they sample (material bindings, the resolve's inputs), and
//! reports its pipelines, memory, pass work, counters and stats.

use super::requested::Effects;
pub use super::shadows::sun_shadows::Canopy;
use crate::error::Result;
use crate::frame::Frame;
use crate::gpu::{Buffer, Context, Image};
use crate::passes::counters::FrameCounters;
use crate::passes::gbuffer_tiles::MaterialBindings;
use crate::passes::lighting_resolve::ResolveInputs;
use crate::passes::sector_data::SectorData;
use crate::passes::terrain_query::VistaTerrain;
use crate::scene::effect::{Effect, EffectDecision, FrameSwitches};
pub use crate::scene::graph::FramePoint;
use crate::scene::graph::{FrameLog, FramePass, PassGraph, PassWork};
use crate::scene::shading::ShadeRules;
use crate::scene::view::View;
use crate::targets::gbuffer::GBuffer;
use crate::targets::{DepthOptions, GbufferLayout, RenderTargets};
use crate::terrain::gpu_quadtree::GpuQuadtree;
use crate::terrain::Terrain;
use crate::world::WorldDesc;
use std::any::Any;

/// What an effect is built from.
pub struct BuildInputs<'a> {
    pub ctx: &'a Context,
    pub world: &'a WorldDesc,
    pub effects: &'a Effects,
    pub decisions: &'a [EffectDecision],
    pub depth: DepthOptions,
    /// Output `gbuffer`: the engine's G-buffer its draws write.
    pub layout: Option<&'a GbufferLayout>,
    /// Effect `occlusion` is built (its depth pyramid exists).
    pub occlusion: bool,
    pub frames_in_flight: usize,
    /// Resident node slots, the reload slots included.
    pub slot_capacity: u32,
    /// Effect `decals`: the decals and their textures.
    pub decals: &'a super::virtual_texture::decals::DecalSet,
    /// Effect `assets`: the assets.
    pub assets: &'a [super::assets::Asset],
    /// A pass of an effect that is on with nothing to do for this scene is
    /// marked here (`PassGraph::not_built`).
    pub graph: &'a mut PassGraph,
}

impl BuildInputs<'_> {
    pub fn on(&self, effect: Effect) -> bool {
        self.decisions.iter().any(|d| d.effect == effect && d.on)
    }
}

/// What an effect plans from, each frame before recording.
pub struct PlanInputs<'a> {
    pub ctx: &'a Context,
    /// The renderer's frame number and the context's.
    pub frame: [u64; 2],
    pub view: &'a View,
    /// The camera, world-relative (the f32 the GPU reads).
    pub camera_world: [f32; 3],
    pub terrain: &'a Terrain,
    pub vista_terrain: VistaTerrain,
    /// The frame's shading rules (its flavours less those switched off).
    pub shade: &'a ShadeRules,
    pub effects: &'a Effects,
    pub switches: FrameSwitches,
    /// Holes are cut this frame; the depth pyramid is built this frame.
    pub holes: bool,
    pub hiz: bool,
    pub depth_size: [u32; 2],
    /// The resident terrain changed this frame (what was made from it is
    /// made again).
    pub terrain_changed: bool,
}

/// What effects tell each other before planning (filled by
/// [`FrameEffect::share`] in registry order, read by `plan`).
#[derive(Debug, Default)]
pub struct SharedPlan {
    /// Effect `decals`: the decals an earlier frame uploaded (None while an
    /// edit waits for its upload).
    pub decals: Option<Vec<super::virtual_texture::decals::Decal>>,
    /// The tallest of an effect's canopy ([`FrameEffect::canopy`]), m.
    pub canopy_top_m: Option<f32>,
}

/// What an effect records against.
pub struct RecordInputs<'a> {
    pub tree: &'a GpuQuadtree,
    pub world: &'a WorldDesc,
    pub terrain: VistaTerrain,
    pub sector_data: &'a SectorData,
    pub view_buffer: &'a Buffer,
    pub targets: &'a RenderTargets<'a>,
    pub gbuffer: &'a GBuffer,
    /// The material effects' bindings (with the virtual texture's once
    /// its pages are recorded).
    pub materials: Option<&'a MaterialBindings<'a>>,
    /// The frame's depth pyramid (effect `occlusion` built and on).
    pub hiz: Option<&'a Image>,
    /// Every built effect, to find another's resources.
    pub effects: &'a [Box<dyn FrameEffect>],
}

impl RecordInputs<'_> {
    /// The built effect of type `T`, if any.
    pub fn find<T: FrameEffect>(&self) -> Option<&T> {
        find(self.effects)
    }
}

/// The built effect of type `T` among `effects`.
pub fn find<T: FrameEffect>(effects: &[Box<dyn FrameEffect>]) -> Option<&T> {
    effects.iter().find_map(|e| e.as_any().downcast_ref::<T>())
}

/// The built effect of type `T` among `effects`, to change.
pub fn find_mut<T: FrameEffect>(effects: &mut [Box<dyn FrameEffect>]) -> Option<&mut T> {
    effects.iter_mut().find_map(|e| e.as_any_mut().downcast_mut::<T>())
}

/// What a pass did, for the report: its work and, when it had none, why.
pub type Work = (PassWork, Option<&'static str>);

/// An effect's numbers after a frame: `stats.json`'s key and value, and
/// the lines `vista render` prints.
#[derive(Debug, Clone)]
pub struct EffectStats {
    pub key: &'static str,
    pub value: serde_json::Value,
    pub lines: Vec<String>,
}

/// One built effect, as the renderer drives it.
pub trait FrameEffect: Any {
    /// The effect it was built for (an effect folder may serve several:
    /// the virtual texture with its decals).
    fn effect(&self) -> Effect;

    /// Tells the effects planned after it what they need to know.
    fn share(&self, shared: &mut SharedPlan) {
        let _ = shared;
    }

    /// The frame's CPU work before recording.
    fn plan(&mut self, p: &PlanInputs, shared: &SharedPlan) -> Result<()> {
        let _ = (p, shared);
        Ok(())
    }

    /// Records its passes at `point` (each logged in `log`, graph order).
    fn record(&self, point: FramePoint, frame: &mut Frame<'_, '_>, log: &mut FrameLog, r: &RecordInputs) {
        let _ = (point, frame, log, r);
    }

    /// The cells where its surface replaces the height field
    /// (terrain_sink.glsl), written before the terrain's draws; the
    /// terrain's fragments there are pushed behind it (at most one effect).
    fn terrain_sink(&self) -> Option<&Buffer> {
        None
    }

    /// Its canopy, which the sun's shadows march over (at most one effect).
    fn canopy(&self) -> Option<Canopy<'_>> {
        None
    }

    /// A render waits for the picture to settle (`on`) or goes on at its
    /// own pace: an effect may spend more a frame to settle in fewer.
    fn catch_up(&mut self, on: bool) {
        let _ = on;
    }

    /// Its material bindings (the material effects make them, the virtual
    /// texture adds its own for the tile shading and what follows it:
    /// `shading`; the passes before it read the materials alone).
    fn bind_materials<'a>(&'a self, m: &mut Option<MaterialBindings<'a>>, shading: bool) {
        let _ = (m, shading);
    }

    /// Its inputs of the lighting resolve.
    fn bind_resolve<'a>(&'a self, r: &mut ResolveInputs<'a>) {
        let _ = r;
    }

    /// Whether its result shows this frame (false while it catches up).
    fn shown(&self) -> bool {
        true
    }

    /// Every resource is current: more frames would show nothing new.
    fn settled(&self) -> bool {
        true
    }

    fn pipelines(&self) -> Vec<String>;

    /// (name, bytes, the effects it exists for) of every GPU object.
    fn memory(&self) -> Vec<(String, u64, Vec<Effect>)>;

    /// The work `pass` (one of its own) did in the last frame; `cpu_work`
    /// is what the frame log holds, `size` the view's.
    fn work(&self, pass: FramePass, cpu_work: Option<u64>, c: &FrameCounters, size: [u32; 2]) -> Option<Work> {
        let _ = (pass, cpu_work, c, size);
        None
    }

    /// A buffer whose first bytes the telemetry copies each frame (its
    /// GPU counters) and how many.
    fn counters(&self) -> Option<(&Buffer, u64)> {
        None
    }

    /// Its numbers after the last frame (reads back: waits).
    fn stats(&self, ctx: &Context, c: &FrameCounters) -> Result<Option<EffectStats>> {
        let _ = (ctx, c);
        Ok(None)
    }

    fn as_any(&self) -> &dyn Any;
    fn as_any_mut(&mut self) -> &mut dyn Any;
}
