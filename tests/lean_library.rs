//! `cargo add vista` gets the renderer alone: with its default features the
//! library links none of the command line's, window's, plotting's or image
//! metrics' crates (they are the `vista-cli` package's, or features).

use std::collections::BTreeSet;

/// The crates `cargo tree` lists for the library's normal dependencies.
fn tree(args: &[&str]) -> BTreeSet<String> {
    let out = std::process::Command::new(env!("CARGO"))
        .args(["tree", "-p", "vista", "-e", "normal", "--prefix", "none", "--locked", "--offline"])
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo tree runs");
    assert!(out.status.success(), "cargo tree failed: {}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    text.lines().filter_map(|l| l.split_whitespace().next()).map(str::to_string).collect()
}

/// What a command line, a window or a benchmark needs, and the renderer not.
const TOOL_CRATES: [&str; 12] = [
    "clap",
    "winit",
    "egui",
    "egui-winit",
    "egui-ash-renderer",
    "plotters",
    "dejavu",
    "nv-flip",
    "anyhow",
    "env_logger",
    "indicatif",
    "ash-window",
];

#[test]
fn the_library_with_its_default_features_links_no_tool_crate() {
    let lean = tree(&[]);
    let found: Vec<&str> = TOOL_CRATES.iter().copied().filter(|c| lean.contains(*c)).collect();
    assert!(found.is_empty(), "the library's default features link {found:?}");
    // What it does link: the renderer's own crates (the listing is real).
    for c in ["vista", "ash", "gpu-allocator", "glam", "image"] {
        assert!(lean.contains(c), "{c} missing from {lean:?}");
    }
    // The features bring what they are for, and only then.
    let bench = tree(&["--features", "bench"]);
    assert!(bench.contains("nv-flip") && !bench.contains("clap"), "feature bench: {bench:?}");
    let window = tree(&["--features", "window"]);
    assert!(window.contains("ash-window") && !window.contains("winit"), "feature window: {window:?}");
    println!("the library links {} crates; with bench {}, with window {}", lean.len(), bench.len(), window.len());
}
