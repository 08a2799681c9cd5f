//! The effects that put geometry beside the height field near the camera
//! (seed 000's "rocks, trees and grass grounded in the terrain"): `grass`,
//! `assets`, the displacement decals' meshes of `decals`, and
//! `cliff_meshes`. What each builds (nothing when off), what it plans on
//! the CPU each frame, its pipelines and memory. Teardown: fields drop in
//! declaration order, each object retired until the frames using it
//! completed.

use crate::effects::assets::asset_draw::AssetDraw;
use crate::effects::assets::AssetResources;
use crate::effects::cliff_meshes::cliff_mesh_build::CliffBuildPush;
use crate::effects::cliff_meshes::CliffMeshes;
use crate::effects::grass::gpu::{Grass, GrassFrame, GrassFrameInputs, UploadedDecals};
use crate::effects::virtual_texture::decal_mesh::DecalMeshes;
use crate::effects::virtual_texture::decal_meshes::DecalMeshPass;
use crate::effects::virtual_texture::decals::{Decal, DecalTexture};
use crate::effects::{Effect, MaterialsMode};
use crate::error::{Error, Result};
use crate::gpu::Context;
use crate::passes::terrain_geometry::DepthOptions;
use crate::render::renderer::RendererOptions;
use crate::scene::graph::{FramePass, PassGraph};
use crate::targets::GbufferLayout;

pub struct NearGeometry {
    /// Effect `grass`: its passes, tufts and pigment map.
    pub grass: Option<Grass>,
    /// Effect `assets`: the example asset pass and its meshes.
    pub assets: Option<(AssetDraw, AssetResources)>,
    /// Effect `decals` with a displacement decal: their meshes' pass.
    pub decal_meshes: Option<DecalMeshPass>,
    /// Effect `cliff_meshes`: its passes and meshes.
    pub cliff_meshes: Option<CliffMeshes>,
}

/// What the renderer was built with, for these effects.
pub struct NearBuild<'a> {
    pub options: &'a RendererOptions,
    pub on: &'a dyn Fn(Effect) -> bool,
    /// Effect `occlusion` is built (grass culls by its pyramid).
    pub occlusion: bool,
    /// The material resources exist (the assets' colour from the splat blend).
    pub materials: bool,
    pub depth: DepthOptions,
    /// Output `gbuffer`: the engine's G-buffer grass and assets draw into.
    pub layout: Option<&'a GbufferLayout>,
}

/// One frame's CPU plans.
#[derive(Default)]
pub struct NearFrame {
    pub grass: Option<GrassFrame>,
    /// Effect `cliff_meshes`' build (None: the last one holds).
    pub cliff_build: Option<CliffBuildPush>,
}

impl NearGeometry {
    /// Builds what is on; a scene with decals but none displacing has no
    /// `decal_meshes` pass (`graph` says why).
    pub fn new(ctx: &Context, b: &NearBuild, graph: &mut PassGraph) -> Result<NearGeometry> {
        let (o, on) = (b.options, b.on);
        let meshes = DecalMeshes::build(&o.decals.decals, &o.decals.textures);
        if on(Effect::Decals) && meshes.meshes == 0 {
            graph.not_built(FramePass::DecalMeshes, "no decal displaces the terrain (displace_m)".into());
        }
        let splat_colours = b.materials && o.effects.materials == MaterialsMode::Splat;
        Ok(NearGeometry {
            grass: match on(Effect::Grass) {
                true => Some(Grass::new(
                    ctx,
                    &o.effects.grass,
                    (b.occlusion, on(Effect::Decals)),
                    b.depth.format,
                    b.layout,
                )?),
                false => None,
            },
            assets: match on(Effect::Assets) {
                true => Some((
                    AssetDraw::new(ctx, b.depth.format, splat_colours, b.layout)?,
                    AssetResources::new(ctx, &o.assets, o.effects.assets)?,
                )),
                false => None,
            },
            decal_meshes: match on(Effect::Decals) && meshes.meshes > 0 {
                true => Some(DecalMeshPass::new(ctx, &meshes, b.depth)?),
                false => None,
            },
            cliff_meshes: match on(Effect::CliffMeshes) {
                true => Some(CliffMeshes::new(ctx, o.effects.cliff_meshes, b.depth)?),
                false => None,
            },
        })
    }

    /// The frame's plans: grass's cells, flags, decal lists and pigment;
    /// whether the cliff meshes are built again.
    pub fn plan(&mut self, f: &GrassFrameInputs, uploaded: UploadedDecals) -> NearFrame {
        NearFrame {
            grass: self.grass.as_mut().map(|g| g.begin_frame(f, uploaded)),
            cliff_build: self.cliff_meshes.as_mut().and_then(|c| c.plan(f.camera_world, f.terrain, f.terrain_changed)),
        }
    }

    /// A decal edit: the displacement meshes are made again (before the
    /// pages change, so a refused edit changes nothing).
    pub fn check_decals(&self, decals: &[Decal], textures: &[DecalTexture]) -> Result<DecalMeshes> {
        let meshes = DecalMeshes::build(decals, textures);
        if self.decal_meshes.is_none() && meshes.meshes > 0 {
            return Err(Error::BadInput(
                "a displacement decal (displace_m) added to a renderer made without one: give one at creation".into(),
            ));
        }
        Ok(meshes)
    }

    pub fn replace_decal_meshes(&mut self, ctx: &Context, meshes: &DecalMeshes) -> Result<()> {
        match &mut self.decal_meshes {
            Some(pass) => pass.replace(ctx, meshes),
            None => Ok(()),
        }
    }

    pub fn pipeline_labels(&self) -> Vec<String> {
        let mut out: Vec<String> = self.grass.iter().flat_map(Grass::pipeline_labels).collect();
        out.extend(self.assets.iter().map(|(p, _)| p.pipeline_label().to_string()));
        out.extend(self.decal_meshes.iter().map(|p| p.pipeline_label().to_string()));
        out.extend(self.cliff_meshes.iter().flat_map(CliffMeshes::pipeline_labels));
        out
    }

    /// (name, bytes, the effect it exists for) of every GPU object.
    pub fn memory(&self) -> Vec<(String, u64, Vec<Effect>)> {
        let tag = |e: Effect| move |(n, b): (String, u64)| (n, b, vec![e]);
        let mut out: Vec<_> = self.grass.iter().flat_map(Grass::memory).map(tag(Effect::Grass)).collect();
        out.extend(self.cliff_meshes.iter().flat_map(CliffMeshes::memory).map(tag(Effect::CliffMeshes)));
        out.extend(self.decal_meshes.iter().flat_map(DecalMeshPass::memory).map(tag(Effect::Decals)));
        out.extend(self.assets.iter().flat_map(|(_, a)| a.memory()).map(tag(Effect::Assets)));
        out
    }
}
