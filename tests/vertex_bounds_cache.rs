//! The per-vertex bounds' disk cache (`world::vertex_bounds_cache`): a
//! second call reads back what the first computed, every sample's and every
//! node's numbers bit for bit; a damaged or cut file is recomputed (and
//! says so), other holes get their own file, and a folder that cannot be
//! written still gives the bounds.

use std::path::{Path, PathBuf};
use vista::world::vertex_bounds::VertexBoundsTree;
use vista::world::vertex_bounds_cache::{compute_cached, BoundsOrigin};
use vista::world::{Hole, NodeId, ProceduralSource, WorldDesc};

fn world() -> WorldDesc {
    WorldDesc {
        extent_m: [512.0, 512.0],
        height_range_m: [0.0, 400.0],
        spacing_m: 1.0,
        lod_count: 3,
        ..Default::default()
    }
}

fn holes() -> Vec<Hole> {
    vec![
        Hole::Circle { center_m: [60.0, 190.0], radius_m: 9.0 },
        Hole::Polygon(vec![[300.0, 40.0], [306.0, 40.0], [306.0, 90.0], [300.0, 90.0]]),
    ]
}

fn fresh_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vista-bounds-cache-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn bounds(dir: &Path, holes: &[Hole]) -> (VertexBoundsTree, BoundsOrigin) {
    let source = ProceduralSource::new(3, world().extent_m, [0.0, 400.0]).unwrap();
    compute_cached(&world(), &source, holes, Some(dir)).unwrap()
}

/// Every sample's height and numbers, and every node's grid values and
/// refinement bound, compared bit for bit.
fn assert_same(a: &VertexBoundsTree, b: &VertexBoundsTree) {
    let side = VertexBoundsTree::lattice_side(&world());
    for j in 0..side[1] as i64 {
        for i in 0..side[0] as i64 {
            let s = glam::I64Vec2::new(i, j);
            let ((za, na), (zb, nb)) = (a.at(s), b.at(s));
            assert_eq!(za.to_bits(), zb.to_bits(), "height at {s}");
            assert_eq!(
                (na.error_m.to_bits(), na.reach_m.to_bits(), na.empty),
                (nb.error_m.to_bits(), nb.reach_m.to_bits(), nb.empty),
                "numbers at {s}"
            );
        }
    }
    for lod in 0..world().lod_count as u8 {
        let [gx, gy] = world().grid(lod);
        for (x, y) in (0..gy).flat_map(|y| (0..gx).map(move |x| (x, y))) {
            let id = NodeId { lod, x, y };
            assert_eq!(a.node_values(id), b.node_values(id), "node {id}'s grid");
            let (ra, rb) = (a.node_refine(id), b.node_refine(id));
            assert_eq!(
                [ra.error_m, ra.z_lo_m, ra.z_hi_m].map(f32::to_bits),
                [rb.error_m, rb.z_lo_m, rb.z_hi_m].map(f32::to_bits),
                "node {id}'s bound"
            );
        }
    }
}

fn only_file(dir: &Path) -> PathBuf {
    let files: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(files.len(), 1, "{files:?}");
    files[0].clone()
}

#[test]
fn a_second_call_reads_the_first_one_s_numbers_bit_for_bit() {
    let dir = fresh_dir("same");
    let (computed, first) = bounds(&dir, &holes());
    assert!(!first.read && first.note.is_none(), "{first}");
    let file = only_file(&dir);
    assert_eq!(first.file.as_deref(), Some(file.as_path()));
    let (read, second) = bounds(&dir, &holes());
    assert!(second.read && second.note.is_none(), "{second}");
    assert!(second.to_string().starts_with("read in"), "{second}");
    assert_same(&computed, &read);
    // And the same as a tree computed without a folder.
    let source = ProceduralSource::new(3, world().extent_m, [0.0, 400.0]).unwrap();
    assert_same(&VertexBoundsTree::compute(&world(), &source, &holes()).unwrap(), &read);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_damaged_or_cut_file_is_recomputed_and_says_why() {
    let dir = fresh_dir("damaged");
    let (computed, _) = bounds(&dir, &holes());
    let file = only_file(&dir);
    let mut bytes = std::fs::read(&file).unwrap();
    let n = bytes.len();
    bytes[n - 100] ^= 0x40; // inside the last band
    std::fs::write(&file, &bytes).unwrap();
    let (again, origin) = bounds(&dir, &holes());
    assert!(!origin.read, "{origin}");
    assert!(origin.note.as_deref().unwrap().contains("checksum"), "{origin}");
    assert_same(&computed, &again);
    // Rewritten whole: read again.
    assert!(bounds(&dir, &holes()).1.read);
    let whole = std::fs::read(&file).unwrap();
    std::fs::write(&file, &whole[..whole.len() / 2]).unwrap();
    let (_, origin) = bounds(&dir, &holes());
    assert!(!origin.read && origin.note.as_deref().unwrap().contains("cut short"), "{origin}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn other_holes_get_their_own_file() {
    let dir = fresh_dir("holes");
    bounds(&dir, &holes());
    let (other, origin) = bounds(&dir, &holes()[..1]);
    assert!(!origin.read && origin.note.is_none(), "{origin}");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2);
    // The slot hole's samples are not holes in the tree with one hole.
    assert!(other.at(glam::I64Vec2::new(303, 60)).0.is_finite());
    assert!(bounds(&dir, &holes()).0.at(glam::I64Vec2::new(303, 60)).0.is_nan());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_folder_that_cannot_be_written_still_gives_the_bounds() {
    let dir = fresh_dir("blocked");
    std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
    std::fs::write(&dir, b"a file where the folder goes").unwrap();
    let (tree, origin) = bounds(&dir, &holes());
    assert!(!origin.read, "{origin}");
    assert!(origin.note.as_deref().unwrap().starts_with("not cached"), "{origin}");
    let source = ProceduralSource::new(3, world().extent_m, [0.0, 400.0]).unwrap();
    assert_same(&VertexBoundsTree::compute(&world(), &source, &holes()).unwrap(), &tree);
    std::fs::remove_file(&dir).unwrap();
}
