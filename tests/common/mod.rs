//! GPU test harness: every GPU test runs on the default device (lavapipe in
//! CI) under the Khronos validation layer and fails on any warning or error
//! it reports, at any time up to and including instance destruction, except
//! the allowlisted ids below. At teardown every live-object counter is zero.
#![allow(dead_code)]

use vista::gpu::{Context, ContextOptions};
use vista::world::{
    texel_index, BakedNode, NodeId, PayloadFormat, TexelKind, ATLAS_TEXELS, CONE_BLOCKS_PER_NODE, PATCHES_PER_NODE,
    SPLAT_RES,
};

/// (message id, why it is acceptable). Keep this list short and justified.
pub const ALLOWLIST: &[(&str, &str)] = &[];

pub fn validated() -> ContextOptions {
    ContextOptions { validation: true, ..Default::default() }
}

/// Runs `f` on a fresh validated context and checks teardown.
pub fn gpu_test(f: impl FnOnce(&Context)) {
    gpu_test_with(&validated(), f)
}

pub fn gpu_test_with(options: &ContextOptions, f: impl FnOnce(&Context)) {
    let ctx = Context::headless(options).expect("creating a validated Vulkan context (run tools/install-deps)");
    let log = ctx.validation_log();
    f(&ctx);
    ctx.wait_idle().expect("wait idle");
    let live = ctx.live_objects();
    assert_eq!(live.total(), 0, "Vulkan objects still alive at teardown: {live:?}");
    drop(ctx);
    let bad = log.unexpected(ALLOWLIST);
    assert!(bad.is_empty(), "{} validation message(s):\n{:#?}", bad.len(), bad);
}

/// A tiny deterministic RNG (xorshift64*) so tests need no extra crate.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    pub fn below(&mut self, n: u32) -> u32 {
        (self.next_u64() % u64::from(n)) as u32
    }

    /// Uniform in 0..n (0 when n is 0).
    pub fn index(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A synthetic node whose payload bytes identify it (no bake needed).
pub fn fake_node(id: NodeId, salt: u16) -> BakedNode {
    let tag = (id.lod as u16) << 12 ^ (id.x as u16) << 6 ^ id.y as u16 ^ salt;
    BakedNode {
        id,
        heights: (0..ATLAS_TEXELS).map(|i| (i as u16).wrapping_mul(31) ^ tag).collect(),
        format: PayloadFormat::Bc,
        normals: PayloadFormat::Bc.encode(TexelKind::Normal, &vec![[tag as u8, 128, 255, 127]; ATLAS_TEXELS]),
        albedo: PayloadFormat::Bc.encode(
            TexelKind::Albedo,
            &(0..ATLAS_TEXELS)
                .map(|i| [tag as u8, (i % 251) as u8, 7, if i == texel_index(5, 0) && salt % 2 == 1 { 0 } else { 255 }])
                .collect::<Vec<_>>(),
        ),
        splat: (0..SPLAT_RES * SPLAT_RES).map(|i| (i % 4) as u8).collect(),
        control: Vec::new(),
        patch_min_max: (0..PATCHES_PER_NODE).map(|i| [i as u16, tag]).collect(),
        patch_cones: (0..CONE_BLOCKS_PER_NODE).map(|i| [0.0, 0.0, 1.0, i as f32 / 64.0]).collect(),
        patch_holes: (0..PATCHES_PER_NODE).map(|i| (i % 3) as u8).collect(),
        min_height: tag & 0x7FFF,
        max_height: tag | 0x8000,
        max_error_m: f32::from(tag) * 0.01,
        patch_errors: (0..PATCHES_PER_NODE).map(|i| [f32::from(tag) * 0.01, i as f32 * 0.001]).collect(),
        repr_error_m: 0.0,
        vertex_bounds: Vec::new(),
    }
}
pub mod diamond_patch;
pub mod finest;
pub mod occurrence;
pub mod smoke;
pub mod smoke_triangle;
pub mod terrain;
