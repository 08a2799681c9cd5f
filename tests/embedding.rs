//! The embedding contract: a context wrapped around an engine's handles
//! (here: another context's) runs passes and destroys only what it created.

mod common;

use common::gpu_test;
use common::terrain::{view, Surface, MAGENTA, MAGENTA_RGBA};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use vista::gpu::{vk, Buffer, BufferDesc, Context, Image, ImageDesc, MemoryLocation, RawHandles, Recorder};
use vista::passes::prefix_sum::PrefixSum;
use vista::passes::terrain_geometry::{COLOR_FORMAT, DEPTH_FORMAT, DEPTH_LAYOUT};
use vista::render::{RenderTargets, RendererOptions, TerrainRenderer};
use vista::world::WorldDesc;

/// A context around `engine`'s handles, as an engine would make one.
fn wrap(engine: &Context) -> Context {
    wrap_with(engine, None)
}

/// The engine's queue as a test sees it: every vista submission goes through
/// this function, which counts it.
fn counting_submitter(engine: &Context) -> (vista::gpu::Submitter, Arc<AtomicU64>) {
    let count = Arc::new(AtomicU64::new(0));
    let (device, seen) = (engine.device().clone(), count.clone());
    let submit: vista::gpu::Submitter = Box::new(move |queue, info, fence| {
        seen.fetch_add(1, Ordering::AcqRel);
        // SAFETY (the engine's side): the test submits from one thread,
        // so the queue is externally synchronized.
        unsafe { device.queue_submit2(queue, std::slice::from_ref(info), fence) }
    });
    (submit, count)
}

fn wrap_with(engine: &Context, submit: Option<vista::gpu::Submitter>) -> Context {
    // SAFETY (the engine's side of the contract): the handles are live,
    // belong together, and `engine` outlives the wrapper.
    unsafe {
        Context::from_raw(RawHandles {
            entry: ash::Entry::load().expect("Vulkan loader"),
            instance: engine.instance().clone(),
            physical_device: engine.physical_device(),
            device: engine.device().clone(),
            graphics_queue_family: engine.graphics_queue().family,
            graphics_queue: engine.graphics_queue().raw,
            compute_queue_family: engine.compute_queue().family,
            compute_queue: engine.compute_queue().raw,
            debug_utils: true,
            submit,
        })
    }
    .expect("wrap the engine's handles")
}

#[test]
fn from_raw_wraps_an_engines_device_without_owning_it() {
    gpu_test(|engine| {
        let wrapped = wrap(engine);
        assert_eq!(wrapped.info().name, engine.info().name);
        assert_eq!(wrapped.info().async_compute, engine.info().async_compute);
        {
            let scan = PrefixSum::new(&wrapped).unwrap();
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC;
            let desc = |name| BufferDesc { name, size: 64 * 4, usage, location: MemoryLocation::GpuOnly };
            let (input, output) =
                (Buffer::new(&wrapped, &desc("in")).unwrap(), Buffer::new(&wrapped, &desc("out")).unwrap());
            wrapped.upload(&input, bytemuck::cast_slice(&[3u32; 64])).unwrap();
            wrapped.submit_and_wait(|rec| scan.record(rec, &input, &output, 64)).unwrap();
            let got: Vec<u32> = bytemuck::cast_slice(&wrapped.read_buffer(&output).unwrap()).to_vec();
            assert_eq!(got, (0..64).map(|i| 3 * i).collect::<Vec<u32>>());
        }
        wrapped.wait_idle().unwrap();
        assert_eq!(wrapped.live_objects().total(), 0);
        drop(wrapped);
        // The engine's device must still work after the wrapper is gone.
        let b = Buffer::new(
            engine,
            &BufferDesc {
                name: "after",
                size: 16,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER,
                location: MemoryLocation::GpuOnly,
            },
        );
        assert!(b.is_ok());
    });
}

/// An engine records vista's frame into a command buffer of its own, on its
/// own device (wrapped with `Context::from_raw`), submits it itself and
/// gets terrain in its colour target. vista's own submissions (uploads while
/// it is made and reads) go through the engine's submit function: vista
/// never calls vkQueueSubmit on the engine's queue.
#[test]
fn terrain_renderer_records_into_the_engines_command_buffer() {
    gpu_test(|engine| {
        let (submit, engine_submits) = counting_submitter(engine);
        let wrapped = wrap_with(engine, Some(submit));
        let device = engine.device();
        let size = [64, 64];
        {
            let world = WorldDesc {
                extent_m: [512.0, 512.0],
                height_range_m: [0.0, 100.0],
                spacing_m: 1.0,
                lod_count: 3,
                ..WorldDesc::default()
            };
            let source = std::sync::Arc::new(Surface::Tilted { z0: 10.0, gx: 0.05, gy: 0.02 });
            let mut renderer =
                TerrainRenderer::new(&wrapped, &world, source, Vec::new(), &RendererOptions::default()).unwrap();
            let (color, depth) = engine_targets(&wrapped, size);
            let v = view([256.0, 30.0, 200.0], 0.0, -30.0, size, 1.0);
            let (pool, cmd, fence) = engine_command_objects(engine);
            for frame in 0..400 {
                // SAFETY: the previous submission's fence was waited on, so
                // the command buffer is idle and may be re-recorded.
                unsafe {
                    device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).unwrap();
                }
                // SAFETY: `cmd` is recording, from a graphics+compute family,
                // and recorded nowhere else meanwhile.
                let mut rec = unsafe { Recorder::from_raw(&wrapped, cmd) };
                if frame == 0 {
                    rec.discard_to(&color, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
                    rec.discard_to(&depth, DEPTH_LAYOUT);
                }
                renderer.record(&mut rec, &v, &RenderTargets::color(&color, &depth, MAGENTA)).unwrap();
                // SAFETY: `cmd` is the recording begun above; the fence is unsignalled.
                unsafe { end_submit_and_wait(engine, &wrapped, cmd, fence) };
                if frame > 2 && renderer.terrain.settled() {
                    break;
                }
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
            check_terrain_through_the_engine(&wrapped, &renderer, &color, &engine_submits);
            // SAFETY: idle (waited above); these are the engine's objects.
            unsafe {
                device.destroy_fence(fence, None);
                device.destroy_command_pool(pool, None);
            }
        }
        wrapped.wait_idle().unwrap();
        assert_eq!(wrapped.live_objects().total(), 0);
    });
}

/// The engine's colour target and depth, made on the wrapped context.
fn engine_targets(wrapped: &Context, size: [u32; 2]) -> (Image, Image) {
    let image = |name, format, usage| {
        Image::new(wrapped, &ImageDesc { name, format, extent: size, mip_levels: 1, array_layers: 1, usage }).unwrap()
    };
    let color =
        image("engine_color", COLOR_FORMAT, vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC);
    let depth = image(
        "engine_depth",
        DEPTH_FORMAT,
        // Sampled: occlusion culling (on by default) reads it.
        vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::SAMPLED,
    );
    (color, depth)
}

/// The engine's own pool, command buffer and fence.
fn engine_command_objects(engine: &Context) -> (vk::CommandPool, vk::CommandBuffer, vk::Fence) {
    let device = engine.device();
    // SAFETY: plain object creation on the engine's live device.
    unsafe {
        let pool = device
            .create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(engine.graphics_queue().family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
            .unwrap();
        let cmd = device
            .allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1),
            )
            .unwrap()[0];
        (pool, cmd, device.create_fence(&vk::FenceCreateInfo::default(), None).unwrap())
    }
}

/// Ends the recording, submits it to the engine's queue and waits, so
/// nothing is in flight after; tells vista the frame is done.
///
/// # Safety
/// `cmd` is recording, `fence` unsignalled; both the engine's.
unsafe fn end_submit_and_wait(engine: &Context, wrapped: &Context, cmd: vk::CommandBuffer, fence: vk::Fence) {
    let device = engine.device();
    // SAFETY: as the caller promises.
    unsafe {
        device.end_command_buffer(cmd).unwrap();
        let cmds = [cmd];
        device
            .queue_submit(engine.graphics_queue().raw, &[vk::SubmitInfo::default().command_buffers(&cmds)], fence)
            .unwrap();
        let n = wrapped.frame_submitted();
        device.wait_for_fences(&[fence], true, u64::MAX).unwrap();
        device.reset_fences(&[fence]).unwrap();
        wrapped.frame_completed(n);
    }
}

/// Settled terrain in the engine's colour target, every vista submission
/// through the engine's function.
fn check_terrain_through_the_engine(
    wrapped: &Context,
    renderer: &TerrainRenderer,
    color: &Image,
    engine_submits: &AtomicU64,
) {
    assert!(renderer.terrain.settled(), "streaming never settled");
    assert!(renderer.latest_timings().is_some_and(|t| t.passes.iter().any(|p| p.name == "terrain_geometry")));
    let rgba = wrapped.read_image(color, 0, 0, 4).unwrap();
    let made = wrapped.submissions();
    assert_eq!(made.direct, 0, "vista submitted to the engine's queue itself");
    assert!(made.through_engine > 0, "vista made and read back without a submission?");
    assert_eq!(made.through_engine, engine_submits.load(Ordering::Acquire));
    let terrain_px = rgba.chunks(4).filter(|p| *p != MAGENTA_RGBA).count();
    // Looking 30 degrees down from 190 m over the tilted plane: the
    // lower half of the image at least is ground.
    assert!(terrain_px > 64 * 32, "only {terrain_px} terrain pixels");
}
