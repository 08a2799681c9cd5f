//! The shader bank, `$OUT_DIR/shaders.rs`. With feature `shader-compiler`
//! (the library's own tests turn it on) every shader in `shaders_glsl/` is
//! compiled with glslang, validated and reflected with naga
//! (`build/shader_compiler.rs`), and the snapshot is refreshed; without it
//! the module comes from the snapshot its inputs made (`build/bank.rs`), so
//! an engine's build and `tools/demo` compile neither. A broken shader stops
//! the build with its file and line.

// The compiling build writes the snapshot, the other reads it.
#[allow(dead_code)]
#[path = "build/bank.rs"]
mod bank;
#[cfg(feature = "shader-compiler")]
#[path = "build/shader_compiler.rs"]
mod shader_compiler;

use std::path::Path;

fn main() {
    let root = Path::new("shaders_glsl");
    let generator = Path::new("build/shader_compiler.rs");
    println!("cargo:rerun-if-changed={}", generator.display());
    println!("cargo:rerun-if-changed=build/bank.rs");
    println!("cargo:rerun-if-env-changed=VISTA_SHADER_BANK_CHECK");
    watch(root);
    let hash = bank::inputs_hash(root, &[generator]);
    let code = module(root, &hash);
    let out = Path::new(&std::env::var("OUT_DIR").expect("OUT_DIR")).join("shaders.rs");
    std::fs::write(&out, code).expect("cannot write generated shader module");
}

/// Every folder and file under `dir` reruns the build when it changes.
fn watch(dir: &Path) {
    println!("cargo:rerun-if-changed={}", dir.display());
    for e in std::fs::read_dir(dir).expect("shaders_glsl/ is missing").flatten() {
        let p = e.path();
        if p.is_dir() {
            watch(&p);
        } else {
            println!("cargo:rerun-if-changed={}", p.display());
        }
    }
}

#[cfg(not(feature = "shader-compiler"))]
fn module(_: &Path, hash: &str) -> String {
    println!("cargo:rerun-if-changed={}", bank::SNAPSHOT);
    bank::from_snapshot(hash).unwrap_or_else(|e| panic!("{e}"))
}

/// Compiles every shader, then refreshes the snapshot (or, checking,
/// refuses a stale one). The snapshot is not watched: the build writes it.
#[cfg(feature = "shader-compiler")]
fn module(root: &Path, hash: &str) -> String {
    let code = compile(root);
    let fresh = bank::snapshot_text(hash, &code);
    if std::fs::read_to_string(bank::SNAPSHOT).ok().as_deref() != Some(fresh.as_str()) {
        if std::env::var_os("VISTA_SHADER_BANK_CHECK").is_some() {
            panic!(
                "{} is not what the shaders make: build once with `cargo build --release -p vista --features \
                 shader-compiler` to refresh it, then commit it",
                bank::SNAPSHOT
            );
        }
        std::fs::write(bank::SNAPSHOT, fresh).expect("cannot refresh the shader bank's snapshot");
        println!("cargo:warning=refreshed {} (commit it with the shaders)", bank::SNAPSHOT);
    }
    code
}

#[cfg(feature = "shader-compiler")]
fn compile(root: &Path) -> String {
    let include_dir = root.join("common");
    let (mut files, mut headers) = (Vec::new(), Vec::new());
    shader_compiler::walk(root, &mut files, &mut headers);
    let mut shaders = Vec::new();
    let mut errors = Vec::new();
    for path in &files {
        match shader_compiler::compile_file(path, &include_dir) {
            Ok(s) => shaders.extend(s),
            Err(e) => errors.push(e),
        }
    }
    if !errors.is_empty() {
        // cargo shows build-script stderr on failure; one block per shader.
        for e in &errors {
            eprintln!("error: {e}\n");
        }
        panic!("{} shader(s) failed to compile: see the messages above", errors.len());
    }
    let constants_file = include_dir.join("constants.glsl");
    let text = std::fs::read_to_string(&constants_file).expect("shaders_glsl/common/constants.glsl is missing");
    let constants = shader_compiler::parse_constants(&text, &constants_file.display().to_string())
        .unwrap_or_else(|e| panic!("{e}"));
    shader_compiler::generate_module(&shaders, &constants).unwrap_or_else(|e| panic!("{e}"))
}
