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
