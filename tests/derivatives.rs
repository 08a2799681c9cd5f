//! Derivatives and mip levels of the G-buffer shading on a plane viewed
//! from 0 to 89.9 degrees incidence. The GPU runs `reconstruct.glsl` (the
//! code `gbuffer_tiles` runs) on depths and 8-bit normal codes; the CPU
//! intersects the same eye rays with the same plane in f64. Beyond the
//! guard (89.95 to 89.995 degrees) the results must stay finite and within
//! the guard's bound.

mod common;

use common::gpu_test;
use glam::{DMat4, DVec3};
use vista::stability::grazing::{eye_ray, probe_gpu, setup, Probe, ALPHA, GRAZING_COS, LAST_MIP, TEXELS, UV_PER_M};

/// The CPU twin of `oct_decode8` (octahedral.glsl), in f64.
fn oct_decode8(code: [u32; 2]) -> DVec3 {
    DVec3::from(vista::reference::octahedral::oct_decode8(code))
}

/// The exact intersection of the eye ray through `px` with the plane
/// (p0, n): None where it runs parallel (within the guard) or meets the
/// plane behind the eye. Same definition as reconstruct.glsl, in f64.
fn hit(inv: &DMat4, px: [f64; 2], p0: DVec3, n: DVec3) -> Option<DVec3> {
    let d = eye_ray(inv, px);
    let cos = d.dot(n) / d.length();
    let t = p0.dot(n) / d.dot(n);
    (cos.abs() >= GRAZING_COS && t > 0.0).then_some(d * t)
}

/// The step to a neighbour, forward where it hits, else backward.
fn step(inv: &DMat4, px: [f64; 2], o: [f64; 2], p: DVec3, p0: DVec3, n: DVec3) -> Option<DVec3> {
    hit(inv, [px[0] + o[0], px[1] + o[1]], p0, n)
        .map(|q| q - p)
        .or_else(|| hit(inv, [px[0] - o[0], px[1] - o[1]], p0, n).map(|q| p - q))
}

/// The mip range the Vulkan spec allows for position steps `gx`, `gy` (m per
/// pixel): rho per axis between the larger component and the sum of both.
fn mip_range(gx: DVec3, gy: DVec3) -> [f64; 2] {
    let t = f64::from(TEXELS) * UV_PER_M;
    let lo = (gx.x.abs().max(gx.y.abs())).max(gy.x.abs().max(gy.y.abs())) * t;
    let hi = (gx.x.abs() + gx.y.abs()).max(gy.x.abs() + gy.y.abs()) * t;
    [lo.log2().clamp(0.0, LAST_MIP), hi.log2().clamp(0.0, LAST_MIP)]
}

#[test]
fn derivatives_and_mips_on_a_plane_from_0_to_89_9_degrees() {
    gpu_test(|ctx| {
        // Flat ground (code 127,127 is exactly +z) and a plane tilted about
        // 33 degrees: each plane is the one its code decodes to.
        let planes = [[127u32, 127], [170, 150]];
        let angles = [0.0, 10.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0, 88.0, 89.0, 89.5, 89.8, 89.9];
        let (mut checked, mut backward, mut worst_rel, mut worst_mip) = (0, 0, 0.0f64, 0.0f64);
        for code in planes {
            let n = oct_decode8(code);
            for upside_down in [false, true] {
                for &incidence in &angles {
                    let (vp, p0) = setup(n, incidence, upside_down);
                    let inv = vp.inverse();
                    // The centre pixel and a spread over the target.
                    let mut cases = Vec::new();
                    for j in [0.5, 36.5, 71.5, 72.5, 108.5, 143.5] {
                        for i in [0.5, 64.5, 128.5, 200.5, 255.5] {
                            let Some(p) = hit(&inv, [i, j], p0, n) else { continue };
                            let clip = vp * p.extend(1.0);
                            let (dx, dy) =
                                (step(&inv, [i, j], [1.0, 0.0], p, p0, n), step(&inv, [i, j], [0.0, 1.0], p, p0, n));
                            if let (Some(dx), Some(dy)) = (dx, dy) {
                                backward += usize::from(hit(&inv, [i, j + 1.0], p0, n).is_none());
                                cases.push((Probe { px: [i, j], depth: (clip.z / clip.w) as f32, code }, p, dx, dy));
                            }
                        }
                    }
                    assert!(!cases.is_empty() || incidence > 89.0, "{incidence}: no pixel on the plane");
                    let probes: Vec<Probe> = cases.iter().map(|c| Probe { ..c.0 }).collect();
                    let got = probe_gpu(ctx, &inv, &probes).unwrap();
                    for ((probe, p, dx, dy), g) in cases.iter().zip(&got) {
                        let what =
                            format!("code {code:?} incidence {incidence} flipped {upside_down} pixel {:?}", probe.px);
                        let gx = DVec3::new(g[0][0].into(), g[0][1].into(), g[0][2].into());
                        let gy = DVec3::new(g[1][0].into(), g[1][1].into(), g[1][2].into());
                        // f32 rounding: the plane's offset p.n is found to
                        // about 2^-24 |p| (components of |p| cancel for a
                        // tilted plane); the neighbour's hit, at |p| away,
                        // moves by that relative amount times |p|; divided by
                        // the step (at least |p| times the pixel angle alpha)
                        // the relative error is about 2^-24 / (cos(i) alpha)
                        // with cos(i) = p0.n / |p| the pixel's own incidence:
                        // 1e-5 straight on, 0.5 % at 89.9 degrees. Bound:
                        // 16 times that, plus 1e-5.
                        let cos_i = p0.dot(n).abs() / p.length();
                        let bound = 16.0 * f64::from(f32::EPSILON) * 0.5 / (cos_i * ALPHA) + 1e-5;
                        for (gpu, exact, axis) in [(gx, *dx, "x"), (gy, *dy, "y")] {
                            let rel = (gpu - exact).length() / exact.length();
                            assert!(
                                rel.is_finite() && rel <= bound,
                                "{what}: d/d{axis} {gpu} vs {exact} (|p| {:.1}), {rel:.2e} over {bound:.2e}",
                                p.length()
                            );
                            worst_rel = worst_rel.max(rel / bound);
                        }
                        // The sampler's mip (mip k holds k, filtered
                        // linearly between mips) within the spec's range
                        // for the exact gradients, plus 1/16 mip for the
                        // driver's fixed-point level-of-detail.
                        let lod = f64::from(g[0][3]);
                        // Widened by what the derivative's bound moves it.
                        let [lo, hi] = mip_range(*dx, *dy);
                        let slack = 0.0625 + (1.0 + bound).log2();
                        assert!(
                            lod >= lo - slack && lod <= hi + slack,
                            "{what}: mip {lod} outside {lo}..{hi} (+-{slack})"
                        );
                        worst_mip = worst_mip.max((lo - lod).max(lod - hi));
                        checked += 1;
                    }
                }
            }
        }
        eprintln!("{checked} probes; worst derivative error {worst_rel:.3} of its bound; worst mip outside the spec's range {worst_mip:.4}; {backward} backward steps");
        assert!(checked > 600 && backward >= 20, "{checked} probes, {backward} took the backward step");
    });
}

/// Stability case 4 (src/stability/grazing.rs): beyond the guard, up to
/// 89.995 degrees, and for every normal code, derivatives stay finite and
/// bounded and the mip within the chain; the bounds' reasons are there.
#[test]
fn beyond_the_guard_derivatives_stay_finite_and_bounded() {
    gpu_test(|ctx| {
        let r = vista::stability::grazing::run(ctx, vista::stability::Form::Quick).expect("the case ran");
        eprintln!("{}", r.details.join("\n"));
        assert!(r.pass, "{} over {}: {}", r.worst, r.bound, r.details.join("; "));
    });
}
