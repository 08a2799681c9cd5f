//! Compiles every shader in `shaders_glsl/` with glslang, validates and
//! reflects it with naga, and writes `$OUT_DIR/shaders.rs` (see
//! `build/shader_compiler.rs`). A broken shader stops the build with its file
//! and line.

#[path = "build/shader_compiler.rs"]
mod shader_compiler;

use std::path::Path;

fn main() {
    let root = Path::new("shaders_glsl");
    let include_dir = root.join("common");
    println!("cargo:rerun-if-changed=build/shader_compiler.rs");
    println!("cargo:rerun-if-changed={}", root.display());
    // The core passes' shaders at the top, each effect's in a folder of its
    // name (with its headers); `common/` holds only headers.
    let mut files = Vec::new();
    let mut headers = Vec::new();
    shader_compiler::walk(root, &mut files, &mut headers);
    for h in &headers {
        println!("cargo:rerun-if-changed={}", h.display());
    }
    let mut shaders = Vec::new();
    let mut errors = Vec::new();
    for path in &files {
        println!("cargo:rerun-if-changed={}", path.display());
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
    let code = shader_compiler::generate_module(&shaders, &constants).unwrap_or_else(|e| panic!("{e}"));
    let out = Path::new(&std::env::var("OUT_DIR").expect("OUT_DIR")).join("shaders.rs");
    std::fs::write(&out, code).expect("cannot write generated shader module");
}
