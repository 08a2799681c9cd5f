//! The house's rules, read from the sources (docs/architecture.md):
//! no file over 600 lines, no function over 80, imports only run down the
//! floors and import circles stay inside one folder.
//!
//! `cargo test --release --test layout -- --nocapture` prints the figures
//! (back-up imports, circles, biggest files, longest functions).

mod layout_graph;

use layout_graph::{folder, rank, Graph};
use std::path::{Path, PathBuf};

const MAX_FILE_LINES: usize = 600;
const MAX_FN_LINES: usize = 80;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every source file of the workspace a person edits: Rust, GLSL, the
/// build script and the tools' shell scripts.
fn source_files() -> Vec<PathBuf> {
    let mut out = Vec::new();
    for dir in ["src", "shaders_glsl", "build", "tests", "examples", "tools"] {
        walk(&root().join(dir), &mut out);
    }
    out.push(root().join("build.rs"));
    out.sort();
    out
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if p.is_dir() {
            // reference images and scene data, not source
            if name != "golden" && name != "target" {
                walk(&p, out);
            }
        } else if [".rs", ".glsl", ".comp", ".vert", ".frag"].iter().any(|x| name.ends_with(x)) {
            out.push(p);
        }
    }
}

fn rel(p: &Path) -> String {
    p.strip_prefix(root()).unwrap_or(p).display().to_string()
}

#[test]
fn no_source_file_over_600_lines() {
    let mut sizes: Vec<(usize, String)> =
        source_files().iter().map(|p| (std::fs::read_to_string(p).unwrap().lines().count(), rel(p))).collect();
    sizes.sort_by(|a, b| b.cmp(a));
    println!("biggest files: {:?}", &sizes[..8.min(sizes.len())]);
    let over: Vec<_> = sizes.iter().filter(|(n, _)| *n > MAX_FILE_LINES).collect();
    assert!(over.is_empty(), "files over {MAX_FILE_LINES} lines (split by what changes together): {over:?}");
}

#[test]
fn no_function_over_80_lines() {
    let mut long = Vec::new();
    let mut longest = (0, String::new());
    for p in source_files().iter().filter(|p| p.extension().is_some_and(|e| e == "rs")) {
        let text = std::fs::read_to_string(p).unwrap();
        for (name, line, len) in layout_graph::functions(&text) {
            let at = format!("{}:{line} {name}", rel(p));
            if len > longest.0 {
                longest = (len, at.clone());
            }
            if len > MAX_FN_LINES {
                long.push((len, at));
            }
        }
    }
    println!("longest function: {} lines, {}", longest.0, longest.1);
    assert!(long.is_empty(), "functions over {MAX_FN_LINES} lines: {long:?}");
}

#[test]
fn imports_run_down_the_floors_and_circles_stay_in_one_folder() {
    let graph = Graph::read(&root().join("src"));
    let mut up = Vec::new();
    for (from, to) in graph.edges() {
        let (a, b) = (folder(from), folder(to));
        if a != b && rank(&a) < rank(&b) {
            up.push(format!("{from} -> {to}"));
        }
    }
    let circles = graph.circles();
    let spanning: Vec<_> = circles.iter().filter(|c| c.iter().any(|m| folder(m) != folder(&c[0]))).collect();
    println!("modules: {}, imports between modules: {}", graph.modules(), graph.edges().len());
    println!("imports up the floors: {}", up.len());
    println!("import circles: {} ({} spanning folders)", circles.len(), spanning.len());
    for c in &circles {
        println!("  circle: {}", c.join(" "));
    }
    assert!(up.is_empty(), "imports from a lower floor into a higher one:\n{}", up.join("\n"));
    assert!(spanning.is_empty(), "import circles across folders: {spanning:?}");
}

#[test]
fn every_folder_has_a_floor() {
    let graph = Graph::read(&root().join("src"));
    for m in graph.names() {
        let f = folder(m);
        assert!(rank(&f) != usize::MAX, "{m}: folder `{f}` has no floor in tests/layout_graph/mod.rs");
    }
}
