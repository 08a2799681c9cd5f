//! The procedural generator: deterministic across processes, bounded, and
//! its erosion's water runs downhill to the world's border.

use std::process::Command;

use vista::world::{bake_node, FlowNetwork, HeightSource, NodeId, ProceduralSource, WorldDesc};

/// Set in the child process this test starts.
const CHILD: &str = "VISTA_PROCEDURAL_CHILD";

/// A hash of the default world's bytes in a few nodes: a valley floor and a
/// flank at LOD 0, a coarse node over mountains and lowlands.
fn baked_nodes_hash() -> u64 {
    let (world, source) = ProceduralSource::default_world(1);
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for id in [NodeId::new(0, 20, 20), NodeId::new(0, 75, 40), NodeId::new(3, 3, 2), NodeId::new(5, 0, 0)] {
        for b in bake_node(&source, &world, &[], id).to_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// The child's half of the next test: prints its hash (a no-op when run
/// by the harness itself).
#[test]
fn child_prints_the_baked_nodes_hash() {
    if std::env::var_os(CHILD).is_some() {
        println!("nodes-hash {:016x}", baked_nodes_hash());
    }
}

#[test]
fn two_processes_bake_the_default_world_bit_for_bit_alike() {
    let out = Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "child_prints_the_baked_nodes_hash", "--nocapture", "--test-threads", "1"])
        .env(CHILD, "1")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let theirs = text.lines().find_map(|l| l.split("nodes-hash ").nth(1)).expect("the child prints its hash");
    assert_eq!(theirs.trim(), format!("{:016x}", baked_nodes_hash()), "another process baked other bytes");
}

/// Follows every node's water to its end.
fn check_water_runs_downhill_to_the_border(net: &FlowNetwork) {
    let [nx, ny] = net.nodes;
    let border = |k: usize| [k % nx, k / nx].contains(&0) || k % nx == nx - 1 || k / nx == ny - 1;
    for start in 0..nx * ny {
        let mut at = start;
        for _ in 0..nx * ny {
            let r = net.receivers[at] as usize;
            if r == at {
                break;
            }
            let [x0, y0, x1, y1] = [at % nx, at / nx, r % nx, r / nx].map(|v| v as isize);
            assert!((x0 - x1).abs() <= 1 && (y0 - y1).abs() <= 1, "{at} flows to {r}, not a neighbour");
            assert!(net.heights_m[r] <= net.heights_m[at], "water at node {at} climbs to {r}");
            at = r;
        }
        assert!(border(at), "water from node {start} ends at inner node {at}");
    }
}

#[test]
fn erosion_stays_in_the_height_range_and_its_water_runs_downhill_to_the_border() {
    let (extent_m, range) = ([3000.0, 2000.0], [-100.0f32, 700.0]);
    let src = ProceduralSource::new(11, extent_m, range).unwrap();
    let net = src.flow_network();
    assert_eq!(net.nodes, [151, 101], "20 m nodes over 3 000 x 2 000 m");
    check_water_runs_downhill_to_the_border(&net);
    let inner = net.heights_m.iter().all(|h| (range[0]..=range[1]).contains(h));
    assert!(inner, "an eroded height left {range:?}");
    // The samples are the eroded grid plus fine octaves (at most 2^-6 of
    // the range: the octaves below 80 m): never more, and always in range.
    let fine_bound = (range[1] - range[0]) / 64.0;
    let [nx, _] = net.nodes;
    for (k, grid_h) in net.heights_m.iter().enumerate().step_by(7) {
        let (x, y) = ((k % nx) as f64 * net.spacing_m, (k / nx) as f64 * net.spacing_m);
        if x > extent_m[0] || y > extent_m[1] {
            continue;
        }
        let h = src.sample(x, y);
        assert!((range[0]..=range[1]).contains(&h), "{h} m at ({x}, {y})");
        assert!((h - grid_h).abs() <= fine_bound + 0.01, "{h} m at ({x}, {y}) over the eroded {grid_h} m");
    }
    // The default world too (513 x 513 nodes).
    check_water_runs_downhill_to_the_border(&ProceduralSource::default_world(1).1.flow_network());
}

#[test]
fn the_terraces_are_an_option_with_their_cliffs() {
    let (_, eroded) = ProceduralSource::default_world(7);
    let terraced = eroded.clone().with_terraces(true);
    assert_ne!(eroded.id_hash(), terraced.id_hash());
    let steepest = |src: &ProceduralSource| {
        let mut steepest = 0f64;
        for j in 0..150 {
            for i in 0..150 {
                let (x, y) = (i as f64 * 68.3 + 3.0, j as f64 * 68.3 + 7.0);
                let h = src.sample(x, y);
                let dx = (src.sample(x + 0.5, y) - h) as f64 / 0.5;
                let dy = (src.sample(x, y + 0.5) - h) as f64 / 0.5;
                steepest = steepest.max(dx.hypot(dy).atan().to_degrees());
            }
        }
        steepest
    };
    let (plain, stepped) = (steepest(&eroded), steepest(&terraced));
    println!("steepest probe: eroded {plain:.1} deg, terraced {stepped:.1} deg");
    assert!(stepped > 60.0 && stepped > plain, "terraces make cliffs: {stepped} against {plain}");
    assert!(WorldDesc::default().validate().is_ok());
}
