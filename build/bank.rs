//! The shader bank's snapshot: `build/shader_bank.snapshot` is the
//! generated module (`$OUT_DIR/shaders.rs`: the SPIR-V, its reflection and
//! the shared constants) as the shader compiler last made it, its first
//! line naming a hash of every input (each file under `shaders_glsl/` and
//! the compiler's own source). A build without feature `shader-compiler`
//! (an engine's, `tools/demo`'s) takes the module from the snapshot when
//! the hash matches and compiles no C++ (glslang) nor naga; it refuses a
//! stale one. A build with the feature compiles every shader and refreshes
//! the snapshot, or, with `VISTA_SHADER_BANK_CHECK` set (`tools/test`),
//! fails when it is stale, so CI never accepts a snapshot its shaders did
//! not make.

use std::path::{Path, PathBuf};

pub const SNAPSHOT: &str = "build/shader_bank.snapshot";
const HEADER: &str = "// shader bank inputs: ";

/// Every file under `dir`, sorted by path.
fn all_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            all_files(&p, out);
        } else {
            out.push(p);
        }
    }
}

/// FNV-1a, 64 bits: a fingerprint of the inputs, not a defence.
fn fnv(hash: &mut u64, bytes: &[u8]) {
    for b in bytes {
        *hash = (*hash ^ u64::from(*b)).wrapping_mul(0x100_0000_01b3);
    }
}

/// The hash of the inputs: every file under `shaders` (its path and
/// bytes) and each of `also`. Line endings are normalised, so a checkout
/// that converts them agrees.
pub fn inputs_hash(shaders: &Path, also: &[&Path]) -> String {
    let mut files = Vec::new();
    all_files(shaders, &mut files);
    files.extend(also.iter().map(|p| p.to_path_buf()));
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for f in &files {
        let text = std::fs::read(f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let text: Vec<u8> = text.into_iter().filter(|&b| b != b'\r').collect();
        fnv(&mut hash, f.to_string_lossy().replace('\\', "/").as_bytes());
        fnv(&mut hash, &[0]);
        fnv(&mut hash, &text);
        fnv(&mut hash, &[0]);
    }
    format!("{hash:016x} ({} files)", files.len())
}

/// The snapshot's text with `code` under a header naming `hash`.
pub fn snapshot_text(hash: &str, code: &str) -> String {
    format!("{HEADER}{hash}\n{code}")
}

/// The module from the snapshot, when it was made from these inputs.
pub fn from_snapshot(hash: &str) -> Result<String, String> {
    let text = std::fs::read_to_string(SNAPSHOT).map_err(|e| format!("{SNAPSHOT}: {e}"))?;
    let (first, code) = text.split_once('\n').unwrap_or((&text, ""));
    match first.strip_prefix(HEADER) {
        Some(h) if h == hash => Ok(code.to_string()),
        Some(h) => Err(format!(
            "{SNAPSHOT} was made from other shaders (inputs {h}; now {hash}): build once with \
             `cargo build --release -p vista --features shader-compiler` to compile them and refresh it, \
             then commit it"
        )),
        None => Err(format!("{SNAPSHOT}: no `{HEADER}` line")),
    }
}
