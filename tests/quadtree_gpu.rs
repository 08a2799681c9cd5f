//! After random add/remove sequences the GPU node texture, node description
//! buffer and payload atlases read back equal to the CPU shadow, bit for bit.

mod common;

use common::{fake_node, gpu_test, Rng};
use std::collections::BTreeSet;
use vista::passes::quadtree_update::QuadtreeUpdatePass;
use vista::terrain::gpu_quadtree::{AtlasSet, GpuQuadtree};
use vista::world::{NodeId, PayloadFormat, WorldDesc};

/// 8 x 6 sectors of 128 m, 4 LODs: a 1x1 root grid, texture padded to 8x8,
/// with invalid cells along the top rows.
fn small_world() -> WorldDesc {
    WorldDesc {
        extent_m: [1000.0, 700.0],
        height_range_m: [0.0, 100.0],
        spacing_m: 1.0,
        lod_count: 4,
        ..WorldDesc::default()
    }
}

fn all_valid(world: &WorldDesc) -> Vec<NodeId> {
    (0..world.lod_count as u8).flat_map(|l| world.nodes_at(l)).collect()
}

#[test]
fn node_texture_and_descriptions_match_the_shadow_after_random_updates() {
    gpu_test(|ctx| {
        let world = small_world();
        let slots = 20;
        let mut tree = GpuQuadtree::new(ctx, &world, slots, 2, AtlasSet::ALL, PayloadFormat::Bc).unwrap();
        let pass = QuadtreeUpdatePass::new(ctx, false).unwrap();
        // Each step waits for the GPU, so a freed slot may be reused at once:
        // same-frame reuse is the hardest case for the GPU mirror.
        tree.shadow.set_reuse_delay(0);
        let candidates = all_valid(&world);
        let mut rng = Rng(0xC0FFEE);
        let mut resident: BTreeSet<NodeId> = BTreeSet::new();
        for step in 0..24u16 {
            tree.begin_frame(u64::from(step) + 1);
            for _ in 0..rng.below(5) {
                if let Some(&id) = resident.iter().nth(rng.below(resident.len().max(1) as u32) as usize) {
                    tree.remove(id);
                    resident.remove(&id);
                    // Sometimes re-add in the same frame: the freed slot may be reused.
                    if rng.below(3) == 0 {
                        tree.add(fake_node(id, step), 0);
                        resident.insert(id);
                    }
                }
            }
            for _ in 0..rng.below(7) {
                let id = candidates[rng.below(candidates.len() as u32) as usize];
                if resident.insert(id) {
                    tree.add(fake_node(id, step), (rng.below(16) as i8) - 8);
                }
            }
            ctx.submit_and_wait(|rec| pass.record(rec, &mut tree, None).map(drop)).unwrap();
            // Over budget, the rest waits; mirror what became resident.
            resident.retain(|id| tree.shadow.slot_of(*id).is_some());
            for (lod, expect) in tree.shadow.mips.iter().enumerate() {
                let got = ctx.read_image(tree.node_texture(), lod as u32, 0, 2).unwrap();
                assert_eq!(bytemuck::cast_slice::<u8, u16>(&got), &expect[..], "step {step}: node texture mip {lod}");
            }
            let descs = ctx.read_buffer(&tree.node_descs).unwrap();
            let expect: Vec<u32> = tree.shadow.descs.iter().flatten().copied().collect();
            assert_eq!(bytemuck::cast_slice::<u8, u32>(&descs), &expect[..], "step {step}: node descriptions");
            let errors = ctx.read_buffer(&tree.node_errors).unwrap();
            let expect: Vec<u32> = tree.shadow.errors.iter().map(|e| e.to_bits()).collect();
            assert_eq!(bytemuck::cast_slice::<u8, u32>(&errors), &expect[..], "step {step}: node errors");
        }
        assert!(resident.len() as u32 >= slots / 2, "the sequence should fill a good part of the budget");
    });
}

#[test]
fn payloads_land_in_the_atlas_layer_of_their_slot() {
    gpu_test(|ctx| {
        let world = small_world();
        let mut tree = GpuQuadtree::new(ctx, &world, 8, 1, AtlasSet::ALL, PayloadFormat::Bc).unwrap();
        let pass = QuadtreeUpdatePass::new(ctx, false).unwrap();
        let nodes: Vec<NodeId> = all_valid(&world).into_iter().take(5).collect();
        for (i, id) in nodes.iter().enumerate() {
            tree.add(fake_node(*id, i as u16), 0);
        }
        ctx.submit_and_wait(|rec| pass.record(rec, &mut tree, None).map(drop)).unwrap();
        for (i, id) in nodes.iter().enumerate() {
            let slot = tree.shadow.slot_of(*id).expect("resident");
            let node = fake_node(*id, i as u16);
            let h = ctx.read_image(tree.required_atlas(0), 0, slot, 2).unwrap();
            assert_eq!(bytemuck::cast_slice::<u8, u16>(&h), &node.heights[..], "heights of {id} in layer {slot}");
            // Block-compressed layers copy as bytes: 8 per 4x4 BC1 block.
            let a = ctx.read_image(tree.required_atlas(2), 0, slot, 8).unwrap();
            assert_eq!(a, node.albedo, "albedo of {id}");
            let c = ctx.read_image(tree.required_atlas(5), 0, slot, 16).unwrap();
            assert_eq!(c, bytemuck::cast_slice::<[f32; 4], u8>(&node.patch_cones), "cones of {id}");
        }
    });
}

#[test]
fn budget_over_the_slot_limit_is_an_error() {
    gpu_test(|ctx| {
        assert!(matches!(
            GpuQuadtree::new(
                ctx,
                &small_world(),
                vista::terrain::quadtree::MAX_SLOTS + 1,
                1,
                AtlasSet::ALL,
                PayloadFormat::Bc
            ),
            Err(vista::Error::BadInput(_))
        ));
    });
}
