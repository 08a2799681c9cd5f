//! GPU test harness: every GPU test runs on the default device (lavapipe in
//! CI) under the Khronos validation layer and fails on any warning or error
//! it reports, at any time up to and including instance destruction, except
//! the allowlisted ids below. At teardown every live-object counter is zero.
#![allow(dead_code)]

use vista::gpu::{Context, ContextOptions};

/// (message id, why it is acceptable). Keep this list short and justified.
pub const ALLOWLIST: &[(&str, &str)] = &[];

pub fn validated() -> ContextOptions {
    ContextOptions { validation: true, sync_validation: false, device_name: None }
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
}
