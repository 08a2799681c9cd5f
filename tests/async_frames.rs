//! The async-compute scheme and frame-late data: frames split into a
//! compute and a graphics command buffer (joined by a timeline semaphore)
//! run clean under synchronization validation, render what one command
//! buffer renders, and report where their passes ran; GPU counters come
//! back at most frames-in-flight + 1 frames late and equal a waiting
//! readback of the same frame; the upload ring follows the frame number;
//! a resource dropped while a frame is recorded outlives that frame.

mod common;

use common::terrain::{small_world as world, view, Rig, Surface};
use common::{gpu_test, gpu_test_with};
use std::collections::HashMap;
use vista::frame::QueueKind;
use vista::gpu::{vk, Buffer, BufferDesc, ContextOptions, FrameRing, MemoryLocation, QueueMode};
use vista::passes::cull_patches::CullStages;
use vista::render::offscreen::Offscreen;
use vista::render::telemetry::FrameCounters;

const SIZE: [u32; 2] = [96, 64];

/// Frame `i` of a camera flying north over the hills while turning.
fn moving(i: u32) -> vista::render::View {
    let t = f64::from(i);
    view([300.0 + 4.0 * t, 100.0 + 15.0 * t, 520.0], 10.0 * t, -25.0, SIZE, 2.0)
}

#[test]
fn split_submission_is_clean_under_synchronization_validation() {
    let options = ContextOptions { validation: true, sync_validation: true, ..Default::default() };
    gpu_test_with(&options, |ctx| {
        let mut images = Vec::new();
        for mode in [QueueMode::Single, QueueMode::SplitOneQueue] {
            let mut rig = Rig::new(ctx, world(), Surface::Hills, vec![], SIZE, false);
            rig.off = Offscreen::with_mode(ctx, SIZE, 2, common::terrain::MAGENTA, mode).unwrap();
            for i in 0..30 {
                rig.off.frame(ctx, &mut rig.renderer, &moving(i)).unwrap();
            }
            assert_eq!(rig.renderer.queue_mode(), Some(mode));
            // Only the graphics queue exists on lavapipe: every pass ran there.
            let t = rig.renderer.poll_timings(ctx).cloned().expect("timings came back");
            assert_eq!(t.mode, mode);
            if !ctx.info().async_compute {
                assert!(t.passes.iter().all(|p| p.queue == QueueKind::Graphics), "{t:?}");
            }
            images.push(rig.shot(ctx, &moving(29), CullStages::ALL).rgba);
        }
        assert!(images[0] == images[1], "split submission renders another image");
    });
}

#[test]
fn counters_arrive_frames_late_and_equal_a_waiting_readback() {
    gpu_test(|ctx| {
        let mut rig = Rig::new(ctx, world(), Surface::Hills, vec![], SIZE, false);
        // The world's error tree first (the root waits for it): counters of
        // frames that draw nothing would all be equal.
        let s = rig.off.settle(ctx, &mut rig.renderer, &moving(0), std::time::Duration::from_secs(300)).unwrap();
        assert!(s.settled);
        let in_flight = 2u64;
        let mut waited: HashMap<u64, FrameCounters> = HashMap::new();
        let mut compared = 0;
        for i in 0..40 {
            rig.off.frame(ctx, &mut rig.renderer, &moving(i)).unwrap();
            let frame = rig.renderer.frames_recorded();
            // The upload ring slot follows the frame, whatever was uploaded.
            assert_eq!(rig.renderer.terrain.tree.upload_slot() as u64, frame % in_flight);
            if let Some(c) = rig.renderer.latest_counters() {
                assert!(frame - c.frame <= in_flight + 1, "frame {frame}: newest counters are of frame {}", c.frame);
                if let Some(w) = waited.get(&c.frame) {
                    assert_eq!(c, w, "frame {}: ring and waiting readback differ", c.frame);
                    compared += 1;
                }
            } else {
                assert!(frame <= in_flight + 1, "no counters by frame {frame}");
            }
            // A waiting readback of the same frame (its own submission: the
            // ring's fences, which bring the counters back, are not waited).
            waited.insert(frame, rig.renderer.read_counters(ctx).unwrap());
        }
        assert!(compared >= 30, "only {compared} frames compared");
        // Apart from the frame number, the counters must have changed while
        // the camera moved (else equal values prove little).
        let unnumbered: Vec<FrameCounters> = waited.values().map(|c| FrameCounters { frame: 0, ..c.clone() }).collect();
        assert!(unnumbered.iter().any(|c| *c != unnumbered[0]), "the counters never changed: a weak comparison");
    });
}

#[test]
fn a_buffer_dropped_while_its_frame_is_recorded_outlives_the_frame() {
    gpu_test(|ctx| {
        let mut ring = FrameRing::new(ctx, 2).unwrap();
        for _ in 0..3 {
            ring.record(ctx, |rec| {
                let b = Buffer::new(
                    ctx,
                    &BufferDesc {
                        name: "dropped_mid_frame",
                        size: 256,
                        usage: vk::BufferUsageFlags::TRANSFER_DST,
                        location: MemoryLocation::GpuOnly,
                    },
                )
                .unwrap();
                rec.fill_buffer(&b, 7);
                // Dropped before the frame is submitted: destroying it now
                // would leave the command buffer naming a dead buffer (the
                // validation layer reports it at submission).
                drop(b);
                assert!(ctx.live_objects().buffers >= 1, "destroyed while its frame was recorded");
                Ok(())
            })
            .unwrap();
        }
        ring.wait_all(ctx).unwrap();
        assert_eq!(ctx.live_objects().buffers, 0, "freed once the frames completed");
    });
}
