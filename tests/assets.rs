//! Effect `assets` and terrain_blend.glsl: a rock's vertices at the ground
//! take the terrain's normal and colour there (read back through a probe
//! running the include as the asset pass does), those above the blend
//! height keep their own, the pass draws the rocks into the G-buffer, and
//! off nothing of it is built.

mod common;

use common::gpu_test;
use common::terrain::{small_world as world, view, Rig, Surface};
use glam::Vec3;
use vista::effects::assets::{rock_mesh, Asset, AssetKind};
use vista::gpu::{
    vk, Buffer, BufferDesc, ComputePipelineDesc, Context, MemoryLocation, Pipeline, Resource, Sampler, SamplerDesc,
};
use vista::passes::cull_patches::CullStages;
use vista::passes::terrain_query::VistaTerrain;
use vista::render::{Effect, Effects, RendererOptions, View};
use vista::shaders::consts::GBUFFER_ASSET;
use vista::shaders::terrain_blend_probe as sh;
use vista::terrain::gpu_quadtree::{ATLAS_ALBEDO, ATLAS_HEIGHT, ATLAS_LAYOUT, ATLAS_NORMAL};
use vista::world::{bake_node, texel_index, NodeId, TexelKind};

const SIZE: [u32; 2] = [256, 192];
/// A flat meadow: the terrain's normal is up and its baked colour the same
/// everywhere, so the expectation does not depend on where the GPU samples.
const GROUND: Surface = Surface::Plane(300.0);
const ROCK_AT: [f64; 2] = [500.0, 210.0];
const BLEND_M: f32 = 0.6;

fn rig(ctx: &Context, assets: Vec<Asset>, on: bool) -> Rig {
    let mut fx = Effects::default().with(Effect::Assets, on).with(Effect::Lighting, false);
    fx.assets.blend_height_m = BLEND_M;
    let options = RendererOptions { effects: fx, assets, ..RendererOptions::default() };
    Rig::with_options(ctx, world(), GROUND, vec![], SIZE, false, options)
}

fn rock() -> Asset {
    Asset { kind: AssetKind::Rock, at_m: ROCK_AT, scale: 1.5, yaw_deg: 0.0 }
}

fn low() -> View {
    view([500.0, 200.0, 302.0], 0.0, -10.0, SIZE, 1.0)
}

fn host(ctx: &Context, name: &str, bytes: &[u8], location: MemoryLocation) -> Buffer {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let mut b = Buffer::new(ctx, &BufferDesc { name, size: bytes.len() as u64, usage, location }).unwrap();
    if let Some(m) = b.mapped_mut() {
        m.copy_from_slice(bytes);
    }
    b
}

/// Runs terrain_blend_probe over `vertices` (world position, normal,
/// colour): per vertex the blended normal, the terrain's weight and colour.
fn probe(ctx: &Context, rig: &Rig, vertices: &[(Vec3, Vec3, Vec3)]) -> Vec<(Vec3, f32, Vec3)> {
    let input: Vec<[f32; 4]> = vertices
        .iter()
        .flat_map(|(p, n, c)| [p.extend(BLEND_M).to_array(), n.extend(0.0).to_array(), c.extend(1.0).to_array()])
        .collect();
    let points = host(ctx, "blend_probe_inputs", bytemuck::cast_slice(&input), MemoryLocation::CpuToGpu);
    let results = host(ctx, "blend_probe_results", &vec![0u8; vertices.len() * 32], MemoryLocation::GpuToCpu);
    let sampler = |name, filter| {
        Sampler::new(ctx, &SamplerDesc { name, filter, address_mode: vk::SamplerAddressMode::CLAMP_TO_EDGE }).unwrap()
    };
    let (nearest, linear) =
        (sampler("blend_probe_nearest", vk::Filter::NEAREST), sampler("blend_probe_linear", vk::Filter::LINEAR));
    let desc = ComputePipelineDesc { name: sh::PASS, shader: &sh::SHADER, specialization: &[] };
    let pipeline = Pipeline::compute(ctx, &desc).unwrap();
    let r = &rig.renderer;
    let tree = &r.terrain.tree;
    #[repr(C)]
    #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
    struct Push {
        terrain: VistaTerrain,
        count: u32,
        pad: [u32; 3],
    }
    let push =
        Push { terrain: VistaTerrain::new(&rig.world, &r.sector_data), count: vertices.len() as u32, pad: [0; 3] };
    ctx.submit_and_wait(|rec| {
        rec.bind_pipeline(&pipeline);
        rec.push_descriptors(
            &pipeline,
            &[
                (sh::SECTOR_DATA, Resource::Buffer(r.sector_data.buffer())),
                (sh::HEIGHT_ATLAS, Resource::Image(tree.required_atlas(ATLAS_HEIGHT), ATLAS_LAYOUT)),
                (sh::NORMAL_ATLAS, Resource::Image(tree.required_atlas(ATLAS_NORMAL), ATLAS_LAYOUT)),
                (sh::ALBEDO_ATLAS, Resource::Image(tree.required_atlas(ATLAS_ALBEDO), ATLAS_LAYOUT)),
                (sh::NEAREST, Resource::Sampler(nearest.raw())),
                (sh::LINEAR_CLAMP, Resource::Sampler(linear.raw())),
                (sh::INPUTS, Resource::Buffer(&points)),
                (sh::RESULTS, Resource::Buffer(&results)),
            ],
        );
        rec.push_constants(&pipeline, &push);
        rec.dispatch((vertices.len() as u32).div_ceil(sh::WORKGROUP_SIZE[0]), 1, 1);
        rec.barrier(vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::HOST);
        Ok(())
    })
    .unwrap();
    let out: &[[f32; 4]] = bytemuck::cast_slice(results.mapped().unwrap());
    out.chunks_exact(2).map(|c| (Vec3::from_slice(&c[0][..3]), c[0][3], Vec3::from_slice(&c[1][..3]))).collect()
}

/// The baked colour of the ground under the rock, decoded on the CPU from
/// the bake's own payload (the GPU samples the same texels, filtered).
fn ground_colour() -> Vec3 {
    let w = world();
    let node = w.node_size_m(0);
    let id = NodeId { lod: 0, x: (ROCK_AT[0] / node) as u32, y: (ROCK_AT[1] / node) as u32 };
    let baked = bake_node(&GROUND, &w, &[], id);
    let texels = baked.format.decode(TexelKind::Albedo, &baked.albedo);
    let t = texels[texel_index(64, 64)];
    Vec3::new(f32::from(t[0]), f32::from(t[1]), f32::from(t[2])) / 255.0
}

#[test]
fn a_rocks_foot_takes_the_terrains_normal_and_colour_and_its_top_keeps_its_own() {
    gpu_test(|ctx| {
        let mut rig = rig(ctx, vec![rock()], true);
        let cap = rig.shot(ctx, &low(), CullStages::default());
        let mesh = rock_mesh();
        let own = Vec3::new(0.5, 0.25, 0.75);
        let ground = GROUND.height(ROCK_AT[0], ROCK_AT[1]) as f32;
        let at = Vec3::new(ROCK_AT[0] as f32, ROCK_AT[1] as f32, ground);
        // The ground as the GPU reads it: the height quantised to R16.
        let [lo, hi] = world().height_range_m;
        let step = (hi - lo) / 65535.0;
        let ground = lo + ((ground - lo) / step).round() * step;
        let vertices: Vec<(Vec3, Vec3, Vec3)> =
            mesh.positions.iter().zip(&mesh.normals).map(|(p, n)| (at + *p * 1.5, *n, own)).collect();
        let out = probe(ctx, &rig, &vertices);
        let colour = ground_colour();
        let (mut foot, mut top, mut between) = (0, 0, 0);
        for ((p, n, _), (bn, w, bc)) in vertices.iter().zip(&out) {
            let above = p.z - ground;
            if above <= 0.0 {
                // The terrain's normal is up (8-bit octahedral: within 1e-2);
                // its colour the bake's (BC1: lavapipe's decoder and the
                // CPU's round the 5:6:5 endpoints apart by 1/255).
                assert!((*bn - Vec3::Z).length() < 1e-2 && *w == 1.0, "foot at {p}: normal {bn}, weight {w}");
                assert!((*bc - colour).abs().max_element() <= 1.5 / 255.0, "foot at {p}: colour {bc}, ground {colour}");
                foot += 1;
            } else if above >= BLEND_M {
                assert!(*w == 0.0 && (*bn - *n).length() < 1e-6 && *bc == own, "top at {p}: {bn} {w} {bc}");
                top += 1;
            } else {
                // Between: a mix, the terrain's share falling with height.
                let expect = 1.0 - {
                    let t = above / BLEND_M;
                    t * t * (3.0 - 2.0 * t)
                };
                // f32 heights at 300 m move the weight by up to 1e-4.
                assert!((w - expect).abs() < 2e-4, "at {above} m: weight {w}, smoothstep {expect}");
                between += 1;
            }
        }
        println!("{foot} vertices at or below the ground, {between} blending, {top} above {BLEND_M} m");
        assert!(foot > 20 && top > 20 && between > 20);

        // Drawn into the G-buffer: the rock's pixels are marked as an asset's.
        let gb = rig.renderer.gbuffer.as_ref().unwrap().capture(ctx).unwrap();
        let marked = gb.material.iter().filter(|m| m[1] == GBUFFER_ASSET as u8).count();
        println!("{marked} rock pixels of {}", cap.depth.len());
        assert!(marked > 300, "{marked} rock pixels");
    });
}

#[test]
fn off_nothing_is_built_and_the_image_is_the_one_without_it() {
    gpu_test(|ctx| {
        let mut without = rig(ctx, vec![], true);
        let d = without.renderer.effects().iter().find(|d| d.effect == Effect::Assets).unwrap().clone();
        assert!(!d.on && d.reason.contains("no assets"), "{}", d.reason);
        let mut off = rig(ctx, vec![rock()], false);
        let mut on = rig(ctx, vec![rock()], true);
        for r in [&without, &off] {
            assert!(r.renderer.effect::<vista::effects::assets::frame::Assets>().is_none());
            assert!(!r.renderer.pipelines().iter().any(|p| p.contains("asset")), "{:?}", r.renderer.pipelines());
        }
        let a = without.shot(ctx, &low(), CullStages::default());
        let b = off.shot(ctx, &low(), CullStages::default());
        let c = on.shot(ctx, &low(), CullStages::default());
        assert!(a.rgba == b.rgba && a.depth == b.depth, "assets off changed the image");
        let differs = a.rgba.chunks(4).zip(c.rgba.chunks(4)).filter(|(x, y)| x != y).count();
        assert!(differs > 300, "the rock changed {differs} pixels");
    });
}
