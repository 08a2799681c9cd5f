//! Proves the harness itself: the layer is loaded and synchronization
//! validation reports a hazard (canaries), sync validation runs clean on
//! the smoke frame, and teardown accounting works.

mod common;

use common::{gpu_test, gpu_test_with, validated};
use vista::gpu::{vk, Buffer, BufferDesc, Context, ContextOptions, MemoryLocation};

#[test]
fn canary_validation_layer_reports_a_provoked_error() {
    let ctx = Context::headless(&validated()).expect("validated context");
    let log = ctx.validation_log();
    ctx.provoke_validation_error();
    let msgs = log.messages();
    assert!(
        msgs.iter().any(|m| m.id_name.contains("VUID-VkBufferCreateInfo-size")),
        "the validation layer did not report the provoked error; got {msgs:#?}"
    );
}

/// What the syncval tests (tests/syncval.rs) rely on: a missing barrier
/// is reported.
#[test]
fn canary_synchronization_validation_reports_a_provoked_hazard() {
    let ctx = Context::headless(&ContextOptions { sync_validation: true, ..validated() }).expect("validated context");
    let log = ctx.validation_log();
    let buffer = |name| {
        let usage = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
        Buffer::new(&ctx, &BufferDesc { name, size: 256, usage, location: MemoryLocation::GpuOnly }).unwrap()
    };
    let (a, b) = (buffer("written"), buffer("copied_to"));
    ctx.submit_and_wait(|rec| {
        rec.fill_buffer(&a, 7);
        // No barrier: the copy reads what the fill may still be writing.
        rec.copy_buffer(&a, &b, 256);
        Ok(())
    })
    .unwrap();
    drop((a, b));
    ctx.wait_idle().unwrap();
    let msgs = log.messages();
    assert!(
        msgs.iter().any(|m| m.id_name == "SYNC-HAZARD-READ-AFTER-WRITE"),
        "synchronization validation did not report the provoked hazard; got {msgs:#?}"
    );
}

#[test]
fn smoke_frames_are_clean_under_synchronization_validation() {
    let options = ContextOptions { sync_validation: true, ..validated() };
    gpu_test_with(&options, |ctx| {
        let out = common::smoke::render(ctx, [64, 64], 3).expect("smoke render");
        assert_eq!(out.image.len(), 64 * 64 * 4);
    });
}

#[test]
fn live_object_counters_follow_deferred_destruction() {
    gpu_test(|ctx| {
        let desc = BufferDesc {
            name: "counted",
            size: 256,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::GpuOnly,
        };
        let a = Buffer::new(ctx, &desc).unwrap();
        let b = Buffer::new(ctx, &desc).unwrap();
        assert_eq!(ctx.live_objects().buffers, 2);
        // A frame "in flight": the dropped buffer must wait for it.
        let frame = ctx.frame_submitted();
        drop(a);
        assert_eq!(ctx.live_objects().buffers, 2, "destroyed while its frame was in flight");
        ctx.frame_completed(frame);
        assert_eq!(ctx.live_objects().buffers, 1);
        drop(b);
        assert_eq!(ctx.live_objects().buffers, 0);
    });
}

#[test]
fn bad_resource_sizes_are_errors_not_panics() {
    gpu_test(|ctx| {
        let zero = BufferDesc {
            name: "zero",
            size: 0,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::GpuOnly,
        };
        assert!(matches!(Buffer::new(ctx, &zero), Err(vista::Error::BadInput(_))));
        let huge = vista::gpu::ImageDesc {
            name: "huge",
            format: vk::Format::R8_UNORM,
            extent: [1 << 20, 4],
            mip_levels: 1,
            array_layers: 1,
            usage: vk::ImageUsageFlags::SAMPLED,
        };
        let err = vista::gpu::Image::new(ctx, &huge).err().expect("a 2^20-wide image must be rejected");
        assert!(err.to_string().contains("huge"), "error names the image: {err}");
    });
}
