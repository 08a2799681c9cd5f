//! The accuracy reference and what the accuracy knob promises: the CPU
//! ray-caster against closed-form intersections; node and triangle counts
//! against the target error; the measured screen-space geometric error
//! against the target on analytic surfaces.

mod common;

use common::terrain::{view, Rig, Surface};
use common::{gpu_test, Rng};
use glam::DVec3;
use vista::bench::accuracy_error::geometric_error_px;
use vista::passes::cull_patches::CullStages;
use vista::reference::{RayCaster, RaycastConfig};
use vista::render::stats::collect;
use vista::world::WorldDesc;

fn world(spacing_m: f64) -> WorldDesc {
    WorldDesc {
        extent_m: [2048.0, 2048.0],
        height_range_m: [0.0, 600.0],
        spacing_m,
        lod_count: 5,
        ..WorldDesc::default()
    }
}

const CAP: Surface = Surface::SphereCap { z0: 50.0, c: [1024.0, 1100.0, -250.0], r: 600.0 };

#[test]
fn reference_matches_closed_form_intersections() {
    let w = world(1.0);
    let mut rng = Rng(0x5eed);
    for s in [Surface::Plane(37.5), Surface::Tilted { z0: 20.0, gx: 0.12, gy: -0.07 }, CAP] {
        let rc = RayCaster::new(&s, &w, RaycastConfig::default());
        let (mut worst, mut hits) = (0f64, 0);
        for _ in 0..2000 {
            let o = [200.0 + 1600.0 * rng.unit(), 200.0 + 1600.0 * rng.unit(), 420.0 + 100.0 * rng.unit()];
            // 5 to 80 degrees below the horizon, any heading.
            let (a, down) = (std::f64::consts::TAU * rng.unit(), (5.0 + 75.0 * rng.unit()).to_radians());
            let d = [a.cos() * down.cos(), a.sin() * down.cos(), -down.sin()];
            let exact = s.intersect(o, d).filter(|&t| {
                let (x, y) = (o[0] + t * d[0], o[1] + t * d[1]);
                (0.0..=2048.0).contains(&x) && (0.0..=2048.0).contains(&y)
            });
            let got = rc.trace(DVec3::from(o), DVec3::from(d), 1e-3).t;
            match (exact, got) {
                (Some(e), Some(g)) => {
                    worst = worst.max((e - g).abs() / e);
                    hits += 1;
                }
                (None, None) => {}
                (e, g) => panic!("{s:?}: exact {e:?}, traced {g:?} from {o:?} along {d:?}"),
            }
        }
        assert!(hits > 1000, "{s:?}: only {hits} rays hit");
        // Heights reach the ray-caster as f32 (ulp 3e-5 m at 400 m); at 5
        // degrees incidence that moves a hit by 3.5e-4 m over distances
        // of 100 m and more, so 1e-5 relative bounds every ray.
        assert!(worst < 1e-5, "{s:?}: worst relative distance error {worst:e}");
    }
}

#[test]
fn measured_geometric_error_keeps_the_target_on_analytic_surfaces() {
    let paraboloid = Surface::Paraboloid { z0: 100.0, a: 2e-4, c: [1024.0, 1024.0] };
    let cases = [
        (CAP, [1024.0, 150.0, 380.0], 0.0, -12.0),
        (CAP, [300.0, 300.0, 600.0], 45.0, -30.0),
        (paraboloid, [1024.0, 200.0, 320.0], 0.0, -15.0),
        (Surface::Tilted { z0: 100.0, gx: 0.05, gy: 0.1 }, [1024.0, 300.0, 400.0], 10.0, -20.0),
    ];
    gpu_test(|ctx| {
        for (surface, position, yaw, pitch) in cases {
            let mut rig = Rig::new(ctx, world(1.0), surface, Vec::new(), [256, 192], false);
            let v = view(position, yaw, pitch, [256, 192], 1.0);
            let capture = rig.shot(ctx, &v, CullStages::ALL);
            let mut e = geometric_error_px(&capture, &v, &surface, &rig.world);
            assert!(e.len() > 10_000, "{surface:?}: {} terrain pixels", e.len());
            e.sort_by(f64::total_cmp);
            let (max, p99) = (e[e.len() - 1], e[e.len() * 99 / 100]);
            println!("{surface:?} from {position:?}: max {max:.3} px, p99 {p99:.3} px over {} pixels", e.len());
            // The promise at 1 px, with no allowance: the criterion bounds a
            // patch's error at its worst screen position, and these smooth
            // surfaces lose next to nothing between the samples (the
            // representation part).
            assert!(p99 <= 1.0, "{surface:?}: p99 {p99:.3} px > 1 px");
            assert!(max <= 2.0, "{surface:?}: max {max:.3} px > 2 px");
        }
    });
}

#[test]
fn node_and_triangle_counts_never_increase_with_the_target() {
    let targets = [0.25f32, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0];
    gpu_test(|ctx| {
        let mut rig = Rig::new(ctx, world(1.0), Surface::Hills, Vec::new(), [256, 144], false);
        let mut rows = Vec::new();
        for t in targets {
            let v = view([1024.0, 300.0, 560.0], 0.0, -15.0, [256, 144], t);
            rig.shot(ctx, &v, CullStages::NONE);
            let off = collect(ctx, &rig.renderer, &v).expect("stats");
            // Two frames: occlusion's phase 1 draws what the previous frame
            // found visible, and the previous frame drew without culling.
            rig.again(ctx, &v, CullStages::ALL);
            rig.again(ctx, &v, CullStages::ALL);
            let on = collect(ctx, &rig.renderer, &v).expect("stats");
            assert_eq!(off.node_count, on.node_count, "culling never changes the selection");
            rows.push((t, off.node_count, off.triangles_drawn, on.triangles_drawn));
        }
        println!("target nodes triangles(culling off) triangles(culling on): {rows:?}");
        for w in rows.windows(2) {
            let (a, b) = (w[0], w[1]);
            assert!(
                b.1 <= a.1 && b.2 <= a.2,
                "target {} -> {}: nodes or triangles (culling off) grew: {rows:?}",
                a.0,
                b.0
            );
            // Culling on: a coarser node is bigger, so more of it can
            // survive the frustum and occlusion tests than of the finer
            // nodes it replaces; drawn triangles may grow by that margin.
            // Measured here: see the printed rows; a quarter bounds it.
            assert!(b.3 as f64 <= a.3 as f64 * 1.25, "target {} -> {}: culled triangles grew >25%: {rows:?}", a.0, b.0);
        }
    });
}
