//! A vegetation folder written by hand in `vista vegetate`'s format
//! (docs/vegetation.md): a checkerboard occurrence map for the grass tests.

use std::path::Path;

use vista::effects::grass::occurrence::GrassOccurrence;

/// Writes into `dir` a meadow occurrence map over `extent_m` whose cell
/// (i, j) of `cell_m` is on when i + j is even, with the brushes' density
/// `density` on every material (grass, rock, snow, scree, sand), and loads it.
pub fn checkerboard(dir: &Path, extent_m: [f64; 2], cell_m: f64, density: [f64; 5]) -> GrassOccurrence {
    std::fs::create_dir_all(dir).unwrap();
    let [w, h] = extent_m.map(|e| (e / cell_m).ceil() as usize);
    let bytes = w.div_ceil(8);
    let mut bits = vec![0u8; bytes * h];
    for j in 0..h {
        for i in (j % 2..w).step_by(2) {
            bits[j * bytes + i / 8] |= 1 << (i % 8);
        }
    }
    std::fs::write(dir.join("occurrence-meadow.bin"), &bits).unwrap();
    let json = format!(
        "{{\"cell_m\": {cell_m}, \"cells\": [{w}, {h}], \"occurrence_cell_m\": {cell_m}, \"occurrence_cells\": [{w}, {h}], \
         \"types\": [{{\"name\": \"meadow\", \"kind\": \"grass\", \"instances\": 0, \
         \"occurrence_file\": \"occurrence-meadow.bin\", \"occurrence_set\": {}, \"material_density\": {density:?}}}]}}",
        bits.iter().map(|b| b.count_ones()).sum::<u32>()
    );
    std::fs::write(dir.join("vegetation.json"), json).unwrap();
    GrassOccurrence::load(dir).unwrap()
}

/// A fresh folder under the temp dir for one call: tests of one binary run
/// at once, and two writing one folder read each other's half-written files.
pub fn unique_dir(prefix: &str) -> std::path::PathBuf {
    static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    std::env::temp_dir().join(format!("{prefix}-{}-{n}", std::process::id()))
}

/// Writes into `dir` a vegetation folder of trees (type 0, "spruce") and
/// bushes (type 1, "juniper") at `trees` and `bushes` (x, y, ground z),
/// turned and scaled by their index, and loads it as effect vegetation's
/// folder.
pub fn forest(dir: &Path, trees: &[[f32; 3]], bushes: &[[f32; 3]]) -> vista::effects::vegetation::VegetationSet {
    std::fs::create_dir_all(dir).unwrap();
    let mut bytes = Vec::new();
    for (ty, list) in [(0u32, trees), (1, bushes)] {
        for (k, p) in list.iter().enumerate() {
            let words: [u32; 8] = [
                p[0].to_bits(),
                p[1].to_bits(),
                p[2].to_bits(),
                (k as f32 * 0.7).to_bits(),
                (0.8 + 0.05 * (k % 5) as f32).to_bits(),
                ty,
                0xFFD8_E8D8,
                k as u32,
            ];
            bytes.extend(words.iter().flat_map(|w| w.to_le_bytes()));
        }
    }
    std::fs::write(dir.join("instances.bin"), &bytes).unwrap();
    let json = format!(
        "{{\"instance_bytes\": 32, \"instances\": {}, \"types\": [{{\"name\": \"spruce\", \"kind\": \"tree\"}}, \
         {{\"name\": \"juniper\", \"kind\": \"bush\"}}]}}",
        trees.len() + bushes.len()
    );
    std::fs::write(dir.join("vegetation.json"), json).unwrap();
    vista::effects::vegetation::VegetationSet::load(dir).unwrap()
}
