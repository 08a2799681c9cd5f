//! The generator's sun march on the GPU (`vista vegetate --sun gpu`,
//! effects/vegetation/vegetation_sun.rs) under synchronization validation: on
//! an analytic range of ridges and cones its shares equal the CPU's
//! (`world::vegetation::lit_share`, f64) but where a ray grazes a ridge.

mod common;

use common::gpu_test_with;
use vista::effects::vegetation::vegetation_sun::VegetationSun;
use vista::gpu::ContextOptions;
use vista::world::vegetation::{lit_share, trajectory, HeightField, SunMarch, Window};

/// 160 x 120 cells of 10 m: ridges running north-east, two cones, a pit.
fn field() -> HeightField {
    let size = [160, 120];
    let z = (0..size[0] * size[1])
        .map(|k| {
            let (x, y) = ((k % size[0]) as f64 * 10.0 + 5.0, (k / size[0]) as f64 * 10.0 + 5.0);
            let ridge = 180.0 * ((x + 0.6 * y) / 260.0).sin().abs();
            let cone = |cx: f64, cy: f64, r: f64, h: f64| h * (1.0 - ((x - cx).hypot(y - cy) / r)).max(0.0);
            (600.0 + ridge + cone(400.0, 700.0, 150.0, 250.0) + cone(1200.0, 300.0, 90.0, 160.0)
                - cone(900.0, 900.0, 120.0, 80.0)) as f32
        })
        .collect();
    HeightField::from_heights(10.0, size, z)
}

#[test]
fn the_gpus_sun_shares_are_the_cpus_but_where_a_ray_grazes() {
    let syncval = ContextOptions { validation: true, sync_validation: true, ..Default::default() };
    gpu_test_with(&syncval, |ctx| {
        let f = field();
        // A June day at 46 degrees north and a December one (a low sun:
        // long marches), 16 samples each.
        for day in [172, 355] {
            let path = trajectory(46.0, day, 16);
            // Two tiles and a window on the grid's edge.
            let windows = [
                Window { lo: [0, 0], size: [64, 64] },
                Window { lo: [70, 30], size: [64, 64] },
                Window { lo: [150, 100], size: [10, 20] },
            ];
            let gpu = VegetationSun::new(ctx).unwrap().march(&f, &windows, &path, 3000.0).unwrap();
            let (mut cells, mut same, mut worst, mut total, mut partial) = (0, 0, 0f32, 0f64, 0);
            for (w, shares) in windows.iter().zip(&gpu) {
                assert_eq!(shares.len(), w.size[0] * w.size[1]);
                for (n, got) in shares.iter().enumerate() {
                    let (i, j) = (w.lo[0] + n % w.size[0], w.lo[1] + n / w.size[0]);
                    let want = lit_share(&f, i, j, &path, 3000.0);
                    cells += 1;
                    partial += usize::from(want > 0.0 && want < 1.0);
                    same += usize::from(*got == want);
                    worst = worst.max((got - want).abs());
                    total += f64::from((got - want).abs());
                }
            }
            println!(
                "day {day}: {same} of {cells} cells equal ({partial} partly shaded), worst {worst}, mean {}",
                total / cells as f64
            );
            assert!(partial * 4 > cells, "day {day}: only {partial} cells partly shaded: too easy a field");
            // f32 against f64: a ray grazing a ridge within rounding may
            // fall either way, one sample of 16 in a cell, in few cells.
            assert!(worst <= 1.0 / 16.0 + 1e-6, "day {day}: a share differs by {worst}");
            assert!(same as f64 >= 0.99 * cells as f64, "day {day}: only {same} of {cells} cells equal");
        }
    });
}
