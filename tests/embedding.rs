//! The embedding contract: a context wrapped around an engine's handles
//! (here: another context's) runs passes and destroys only what it created.

mod common;

use common::gpu_test;
use vista::gpu::{vk, Buffer, BufferDesc, Context, MemoryLocation, RawHandles};
use vista::passes::prefix_sum::PrefixSum;

#[test]
fn from_raw_wraps_an_engines_device_without_owning_it() {
    gpu_test(|engine| {
        // SAFETY (the engine's side of the contract): the handles are live,
        // belong together, and `engine` outlives `wrapped`.
        let wrapped = unsafe {
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
            })
        }
        .expect("wrap the engine's handles");
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
