//! Smoke tests that assert real outcomes against CPU references.

mod common;

use common::diamond_patch::DiamondPatch;
use common::smoke_triangle::{SmokeTriangle, TARGET_FORMAT};
use common::{gpu_test, Rng};
use vista::gpu::{vk, Buffer, BufferDesc, Context, Image, ImageDesc, MemoryLocation};
use vista::passes::prefix_sum::PrefixSum;

fn storage(ctx: &Context, name: &str, bytes: u64) -> Buffer {
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC;
    Buffer::new(ctx, &BufferDesc { name, size: bytes, usage, location: MemoryLocation::GpuOnly }).unwrap()
}

#[test]
fn prefix_sum_in_one_workgroup_equals_cpu() {
    gpu_test(|ctx| {
        let scan = PrefixSum::new(ctx).unwrap();
        let cap = PrefixSum::capacity();
        let input = storage(ctx, "scan_in", u64::from(cap) * 4);
        let output = storage(ctx, "scan_out", u64::from(cap) * 4);
        let mut rng = Rng(0x5eed);
        for count in [1, 7, 255, 256, 1000, cap] {
            let values: Vec<u32> = (0..cap).map(|_| rng.below(1 << 20)).collect();
            ctx.upload(&input, bytemuck::cast_slice(&values)).unwrap();
            ctx.submit_and_wait(|rec| scan.record(rec, &input, &output, count)).unwrap();
            let got: Vec<u32> = bytemuck::cast_slice(&ctx.read_buffer(&output).unwrap()).to_vec();
            let mut expect = Vec::new();
            let mut acc = 0u32;
            for v in &values[..count as usize] {
                expect.push(acc);
                acc += v;
            }
            assert_eq!(&got[..count as usize], &expect[..], "count {count}");
        }
        let err = ctx.submit_and_wait(|rec| scan.record(rec, &input, &output, cap + 1));
        assert!(matches!(err, Err(vista::Error::BadInput(_))));
    });
}

fn target(ctx: &Context, size: u32) -> Image {
    let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
    Image::new(
        ctx,
        &ImageDesc {
            name: "smoke_target",
            format: TARGET_FORMAT,
            extent: [size, size],
            mip_levels: 1,
            array_layers: 1,
            usage,
        },
    )
    .unwrap()
}

/// Alpha of each pixel after `draw`, row-major from the top row.
fn covered(ctx: &Context, img: &Image, draw: impl FnOnce(&mut vista::gpu::Recorder)) -> Vec<bool> {
    ctx.submit_and_wait(|rec| {
        rec.discard_to(img, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        draw(rec);
        Ok(())
    })
    .unwrap();
    let px = ctx.read_image(img, 0, 0, 4).unwrap();
    px.chunks(4).map(|p| p[3] == 255).collect()
}

#[test]
fn triangle_covers_exactly_the_expected_pixels() {
    const N: u32 = 64;
    // Corners in pixels, multiples of 1/16 so they sit exactly on the
    // rasterizer's subpixel grid and every edge function below is exact.
    let corners_px = [[3.0625, 5.1875], [60.3125, 20.4375], [22.5625, 58.9375]];
    let ndc =
        |p: [f64; 2]| [(p[0] / f64::from(N) * 2.0 - 1.0) as f32, (p[1] / f64::from(N) * 2.0 - 1.0) as f32, 0.0, 1.0];
    let corners = [ndc(corners_px[0]), ndc(corners_px[1]), ndc(corners_px[2])];
    // CPU reference: a pixel is covered when its centre is strictly inside.
    // No centre may lie exactly on an edge, so the tie rule cannot matter.
    let edge = |a: [f64; 2], b: [f64; 2], p: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
    let mut expect = Vec::new();
    for y in 0..N {
        for x in 0..N {
            let p = [f64::from(x) + 0.5, f64::from(y) + 0.5];
            let e = [
                edge(corners_px[0], corners_px[1], p),
                edge(corners_px[1], corners_px[2], p),
                edge(corners_px[2], corners_px[0], p),
            ];
            assert!(e.iter().all(|v| *v != 0.0), "pixel ({x},{y}) centre on an edge: pick other corners");
            expect.push(e.iter().all(|v| *v > 0.0) || e.iter().all(|v| *v < 0.0));
        }
    }
    gpu_test(|ctx| {
        let tri = SmokeTriangle::new(ctx).unwrap();
        let img = target(ctx, N);
        let got = covered(ctx, &img, |rec| tri.record(rec, &img, corners));
        let diff: Vec<(u32, u32)> =
            (0..N * N).filter(|&i| got[i as usize] != expect[i as usize]).map(|i| (i % N, i / N)).collect();
        assert!(
            diff.is_empty(),
            "{} pixels differ from the CPU reference, e.g. {:?}",
            diff.len(),
            &diff[..diff.len().min(8)]
        );
        assert!(expect.iter().filter(|c| **c).count() > 1000, "triangle too small to prove anything");
    });
}

#[test]
fn diamond_patch_with_nan_centre_draws_nothing() {
    gpu_test(|ctx| {
        let patch = DiamondPatch::new(ctx, 2).unwrap();
        let img = target(ctx, 64);
        let full = covered(ctx, &img, |rec| patch.record(rec, &img, None));
        assert!(full.iter().all(|c| *c), "without NaN the 3x3-vertex patch covers the whole target");
        let holed = covered(ctx, &img, |rec| patch.record(rec, &img, Some(patch.vertex(1, 1))));
        assert_eq!(holed.iter().filter(|c| **c).count(), 0, "a NaN centre vertex must drop all 8 triangles");
    });
}

#[test]
fn diamond_hole_removes_exactly_its_eight_triangles() {
    gpu_test(|ctx| {
        let n = 16;
        let patch = DiamondPatch::new(ctx, n).unwrap();
        let img = target(ctx, 64);
        let (hx, hy) = (5, 7);
        let got = covered(ctx, &img, |rec| patch.record(rec, &img, Some(patch.vertex(hx, hy))));
        let quad = 64 / n;
        for (i, c) in got.iter().enumerate() {
            let (x, y) = (i as u32 % 64, i as u32 / 64);
            let in_hole = (x / quad + 1 == hx || x / quad == hx) && (y / quad + 1 == hy || y / quad == hy);
            assert_eq!(*c, !in_hole, "pixel ({x},{y})");
        }
    });
}
