//! The recorder's safe methods check what they rely on: each misuse below
//! panics before any command reaches Vulkan (so the validation layer, which
//! fails the test on any message, sees nothing), and the tracked image
//! layout follows the transitions recorded.

mod common;

use common::gpu_test;
use common::smoke_triangle::{SmokeTriangle, TARGET_FORMAT};
use std::panic::{catch_unwind, AssertUnwindSafe};
use vista::gpu::{vk, Buffer, BufferDesc, ColorTarget, Image, ImageDesc, MemoryLocation, Recorder, Resource};
use vista::passes::prefix_sum::PrefixSum;

/// The panic message of `f`, which must panic.
fn panics(f: impl FnOnce()) -> String {
    let err = catch_unwind(AssertUnwindSafe(f)).expect_err("the misuse was not caught");
    err.downcast_ref::<String>().cloned().or(err.downcast_ref::<&str>().map(|s| s.to_string())).unwrap_or_default()
}

#[test]
fn misuse_panics_before_reaching_vulkan() {
    gpu_test(|ctx| {
        let target = Image::new(
            ctx,
            &ImageDesc {
                name: "checks_target",
                format: TARGET_FORMAT,
                extent: [8, 8],
                mip_levels: 1,
                array_layers: 1,
                usage: vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE,
            },
        )
        .unwrap();
        let args = Buffer::new(
            ctx,
            &BufferDesc {
                name: "checks_args",
                size: 16,
                usage: vk::BufferUsageFlags::INDIRECT_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER,
                location: MemoryLocation::GpuOnly,
            },
        )
        .unwrap();
        let plain = Buffer::new(
            ctx,
            &BufferDesc {
                name: "checks_plain",
                size: 64,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER,
                location: MemoryLocation::GpuOnly,
            },
        )
        .unwrap();
        let scan = PrefixSum::new(ctx).unwrap();
        let tri = SmokeTriangle::new(ctx).unwrap();
        assert_eq!(target.layout(), vk::ImageLayout::UNDEFINED);
        ctx.submit_and_wait(|rec: &mut Recorder| {
            let m = panics(|| rec.draw(3, 1));
            assert!(m.contains("outside a rendering scope"), "{m}");
            let m = panics(|| rec.dispatch(1, 1, 1));
            assert!(m.contains("no compute pipeline bound"), "{m}");
            let m = panics(|| rec.end_rendering());
            assert!(m.contains("without begin_rendering"), "{m}");
            // The target is still UNDEFINED: rendering into it is refused.
            let m = panics(|| rec.begin_rendering(&[ColorTarget { image: &target, clear: Some([0.0; 4]) }], None));
            assert!(m.contains("is not in COLOR_ATTACHMENT_OPTIMAL"), "{m}");
            // Binding a storage image in a layout it is not in.
            rec.bind_pipeline(scan.pipeline());
            let m = panics(|| {
                let b =
                    [(vista::shaders::prefix_sum::INPUT_VALUES, Resource::Image(&target, vk::ImageLayout::GENERAL))];
                rec.push_descriptors(scan.pipeline(), &b)
            });
            assert!(m.contains("bound as GENERAL"), "{m}");
            // Indirect arguments past the end, misaligned, or without the usage.
            let m = panics(|| rec.dispatch_indirect(&args, 8));
            assert!(m.contains("overrun checks_args"), "{m}");
            let m = panics(|| rec.dispatch_indirect(&args, 2));
            assert!(m.contains("overrun"), "{m}");
            let m = panics(|| rec.dispatch_indirect(&plain, 0));
            assert!(m.contains("lacks INDIRECT_BUFFER"), "{m}");
            // Layouts follow the transitions; a scope cannot hold a barrier.
            rec.discard_to(&target, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
            assert_eq!(target.layout(), vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
            tri.record(rec, &target, [[-1.0, -1.0, 0.0, 1.0], [3.0, -1.0, 0.0, 1.0], [-1.0, 3.0, 0.0, 1.0]]);
            rec.begin_rendering(&[ColorTarget { image: &target, clear: Some([0.0; 4]) }], None);
            let m = panics(|| rec.transition(&target, vk::ImageLayout::GENERAL));
            assert!(m.contains("inside a rendering scope"), "{m}");
            rec.end_rendering();
            rec.transition(&target, vk::ImageLayout::GENERAL);
            assert_eq!(target.layout(), vk::ImageLayout::GENERAL);
            Ok(())
        })
        .unwrap();
    });
}

/// A GPU write into a buffer the host reads stays "unpublished" until a
/// barrier to the host stage; the frame executor asserts every pass ends
/// with none (the virtual texture's readback once relied on telemetry's
/// later barrier: its tests trip that assert without its own).
#[test]
fn writes_the_host_reads_are_tracked_until_a_host_barrier() {
    gpu_test(|ctx| {
        let buffer = |name, usage, location| Buffer::new(ctx, &BufferDesc { name, size: 64, usage, location }).unwrap();
        let src = buffer("checks_src", vk::BufferUsageFlags::TRANSFER_SRC, MemoryLocation::GpuOnly);
        let readback = buffer("checks_readback", vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu);
        ctx.submit_and_wait(|rec: &mut Recorder| {
            assert!(rec.host_unpublished().is_empty());
            rec.copy_buffer_region(&src, 0, &readback, 0, 64);
            assert_eq!(rec.host_unpublished(), ["checks_readback"]);
            // A barrier that stops short of the host does not publish it.
            rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::ALL_COMMANDS);
            assert_eq!(rec.host_unpublished(), ["checks_readback"]);
            rec.transfer_to_host_barrier();
            assert!(rec.host_unpublished().is_empty());
            rec.copy_buffer_region(&src, 0, &readback, 0, 64);
            rec.barrier(vk::PipelineStageFlags2::ALL_TRANSFER, vk::PipelineStageFlags2::HOST);
            assert!(rec.host_unpublished().is_empty());
            Ok(())
        })
        .unwrap();
    });
}
