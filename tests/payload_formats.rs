//! The talk's payload formats: BC3 normals + smoothness and BC1 albedo with
//! a 1-bit hole alpha, checked against the same node baked as RGBA8.

use vista::world::*;

/// Nodes of the default procedural world where it is steep (terraced
/// cliffs), gentle and mixed, at several LODs, plus a partial node past
/// the world's edge with holes cut into it.
fn nodes() -> Vec<(WorldDesc, Vec<Hole>, NodeId)> {
    let (w, _) = ProceduralSource::default_world(1);
    let holes = vec![
        Hole::Circle { center_m: [5130.0, 5130.0], radius_m: 9.5 },
        Hole::Polygon(vec![[5100.0, 5100.0], [5121.3, 5100.0], [5110.0, 5127.7]]),
    ];
    let mut v: Vec<(WorldDesc, Vec<Hole>, NodeId)> = [
        NodeId::new(0, 80, 80),
        NodeId::new(0, 20, 20),
        NodeId::new(0, 150, 37),
        NodeId::new(1, 40, 40),
        NodeId::new(3, 5, 2),
        NodeId::new(5, 2, 2),
    ]
    .into_iter()
    .map(|id| (w, holes.clone(), id))
    .collect();
    let partial = WorldDesc { extent_m: [10_000.0, 10_000.0], ..w };
    v.push((partial, vec![], NodeId::new(0, 156, 156)));
    v
}

fn angle_deg(a: [f32; 3], b: [f32; 3]) -> f64 {
    let dot: f64 = (0..3).map(|k| f64::from(a[k]) * f64::from(b[k])).sum();
    let la = (0..3).map(|k| f64::from(a[k]).powi(2)).sum::<f64>().sqrt();
    let lb = (0..3).map(|k| f64::from(b[k]).powi(2)).sum::<f64>().sqrt();
    (dot / (la * lb)).clamp(-1.0, 1.0).acos().to_degrees()
}

#[test]
fn bc_blocks_stay_near_the_rgba8_source_and_holes_survive_exactly() {
    let (mut normal_max, mut normal_sum, mut albedo_max, mut albedo_sum, mut smooth_max, mut n) =
        (0f64, 0f64, 0u8, 0f64, 0u8, 0usize);
    let mut normal_errors = Vec::new();
    for (w, holes, id) in nodes() {
        let source = ProceduralSource::new(1, w.extent_m, w.height_range_m).unwrap();
        let bake =
            |format| bake_node_with(&source, &w, &holes, &BakeSettings { format, ..BakeSettings::default() }, id);
        let (bc, raw) = (bake(PayloadFormat::Bc), bake(PayloadFormat::Rgba8));
        // Only the texel layers differ between the two formats.
        assert_eq!((&bc.heights, &bc.splat, &bc.patch_holes), (&raw.heights, &raw.splat, &raw.patch_holes));
        assert_eq!(bc.normals.len(), 33 * 33 * 16);
        assert_eq!(bc.albedo.len(), 33 * 33 * 8);
        let (bn, rn) = (bc.normal_texels(), raw.normal_texels());
        let (ba, ra) = (bc.albedo_texels(), raw.albedo_texels());
        for k in 0..ATLAS_TEXELS {
            // The hole bit: exactly the source's, texel by texel.
            assert_eq!(ba[k][3], ra[k][3], "{id} texel {k}: hole alpha");
            let e = angle_deg(unpack_normal(bn[k]), unpack_normal(rn[k]));
            normal_max = normal_max.max(e);
            normal_sum += e;
            normal_errors.push(e);
            smooth_max = smooth_max.max(bn[k][NORMAL_SMOOTHNESS].abs_diff(rn[k][NORMAL_SMOOTHNESS]));
            if ra[k][3] == 255 {
                let d = (0..3).map(|c| ba[k][c].abs_diff(ra[k][c])).max().unwrap_or(0);
                albedo_max = albedo_max.max(d);
                albedo_sum += f64::from(d);
            }
            n += 1;
        }
        assert_eq!(bc.hole_mask(), raw.hole_mask(), "{id}");
    }
    let (normal_mean, albedo_mean) = (normal_sum / n as f64, albedo_sum / n as f64);
    normal_errors.sort_by(f64::total_cmp);
    let normal_p99 = normal_errors[normal_errors.len() * 99 / 100];
    println!(
        "over {n} texels: normal error max {normal_max:.2} deg, p99 {normal_p99:.2} deg, mean {normal_mean:.3} deg; \
         albedo max {albedo_max}, mean {albedo_mean:.2} (of 255); smoothness max {smooth_max}"
    );
    // Bounds, with the reason each is what it is (measured when they were
    // set: normal max 36.0, p99 11.6, mean 1.54 degrees; albedo max 44,
    // mean 4.05; smoothness max 36):
    // - normal y lives in BC3's green: a colour block has 4 levels on one
    //   line, so a block that holds both a terrace's tread and its riser
    //   (risers here are narrower than a 4-texel block) snaps y by up to a
    //   sixth of its range, tens of degrees at the riser. x, in the alpha
    //   block (8 levels), fares better. Most blocks are smooth: the mean
    //   and p99 stay small. Bounds about 1.25x the measured values.
    assert!(normal_max < 45.0 && normal_p99 < 15.0 && normal_mean < 2.0, "normal error {normal_max}");
    // - albedo: 5:6:5 endpoints lose up to 4 units per channel (8 for
    //   5-bit red and blue), and the 4-colour line of a block holding a
    //   material edge and a shade change snaps further.
    assert!(albedo_max <= 56 && albedo_mean < 5.0, "albedo error {albedo_max} / {albedo_mean}");
    // - smoothness is one value per material (25..150): a block holding
    //   two materials puts it on green's line, between them.
    assert!(smooth_max <= 48, "smoothness error {smooth_max}");
}

#[test]
fn the_layers_start_two_texels_before_the_node() {
    // A tilted plane: height grows 1 m per metre east. The normal layer's
    // texel (t, u) is sample (t - 2, u - 2), so every texel, the border
    // included, carries the plane's normal; the albedo alpha marks texels
    // west and south of the world (t or u < 2 in node (0, 0)) as holes.
    #[derive(Debug)]
    struct Tilt;
    impl HeightSource for Tilt {
        fn sample(&self, x: f64, _y: f64) -> f32 {
            100.0 + x as f32
        }
        fn id_hash(&self) -> u64 {
            7
        }
    }
    let w = WorldDesc {
        extent_m: [512.0, 512.0],
        height_range_m: [0.0, 800.0],
        spacing_m: 1.0,
        lod_count: 2,
        ..WorldDesc::default()
    };
    let node = bake_node_with(
        &Tilt,
        &w,
        &[],
        &BakeSettings { format: PayloadFormat::Rgba8, ..Default::default() },
        NodeId::new(0, 1, 1),
    );
    let expect = [-std::f32::consts::FRAC_1_SQRT_2, 0.0, std::f32::consts::FRAC_1_SQRT_2];
    for t in node.normal_texels() {
        assert!(angle_deg(unpack_normal(t), expect) < 0.6, "{t:?}");
    }
    assert!(node.albedo_texels().iter().all(|a| a[3] == 255), "node (1, 1) has neighbours on every side");
    let corner = bake_node_with(
        &Tilt,
        &w,
        &[],
        &BakeSettings { format: PayloadFormat::Rgba8, ..Default::default() },
        NodeId::new(0, 0, 0),
    );
    let a = corner.albedo_texels();
    for u in 0..ATLAS_SIDE {
        for t in 0..ATLAS_SIDE {
            let outside = t < ATLAS_BORDER || u < ATLAS_BORDER;
            assert_eq!(a[u * ATLAS_SIDE + t][3] == 0, outside, "texel ({t}, {u})");
        }
    }
}
