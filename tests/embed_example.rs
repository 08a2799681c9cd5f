//! `examples/embed` in a real window under Xvfb (lavapipe presents to
//! it), under the validation layer: a deferred engine with vista inside.

use std::path::{Path, PathBuf};
use vista::reference::{flip_map, flip_stats};

fn dir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("embed-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn png(path: &Path) -> (Vec<u8>, [u32; 2]) {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8();
    let size = [img.width(), img.height()];
    (img.into_raw(), size)
}

/// `examples/embed`: a deferred engine with its own device, swapchain,
/// targets and frame loop (on a render thread) draws its building into the
/// depth vista loads, has vista write each output, lights or tonemaps it
/// itself and draws its marker. All three outputs give the same picture.
#[test]
fn the_embedding_example_lights_vistas_gbuffer_keeps_its_depth_and_vista_never_submits_itself() {
    // `cargo test` builds the examples beside the test binaries
    // (target/*/examples); with a target filter (`--test view`) it does not:
    // build them first (`cargo build --release --examples`).
    let exe = std::env::current_exe().unwrap();
    let example = exe.parent().unwrap().parent().unwrap().join("examples").join("embed");
    assert!(example.exists(), "{} was not built (cargo build --release --examples)", example.display());
    let mut shots = Vec::new();
    for output in ["gbuffer", "hdr", "lit"] {
        let shot = dir().join(format!("embed-{output}.png"));
        let out = std::process::Command::new("xvfb-run")
            .args(["-a", "-s", "-screen 0 800x600x24"])
            .arg(&example)
            .args(["--validation", "--output", output, "--frames", "30", "--screenshot"])
            .arg(&shot)
            .output()
            .expect("xvfb-run (tools/install-deps installs xvfb)");
        let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        assert!(out.status.success(), "embed --output {output} failed:\n{stdout}\n{stderr}");
        // Every vista submission went through the engine's submit function.
        let line = stdout.lines().find(|l| l.starts_with("vista submissions:")).expect("the submissions line");
        assert!(line.ends_with(", 0 of its own"), "{line}");
        assert!(!line.starts_with("vista submissions: 0 through"), "{line}");
        assert!(stdout.contains("validation messages: 0"), "{stdout}\n{stderr}");
        // The engine's building culled terrain patches through vista's pyramid.
        let depth = stdout.lines().find(|l| l.starts_with("engine depth: kept (")).expect("the engine depth line");
        let culled: u32 = depth["engine depth: kept (".len()..].split(' ').next().unwrap().parse().unwrap();
        assert!(culled > 100, "{depth}");
        let lighting = stdout.lines().find(|l| l.starts_with("engine lighting:")).expect("the engine lighting line");
        if output == "gbuffer" {
            assert!(lighting.starts_with("engine lighting: lit vista's G-buffer ("), "{lighting}");
        }
        let pixels: usize = lighting.split('(').nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
        assert!(pixels > 640 * 360 / 2, "{lighting}");
        let (rgba, size) = png(&shot);
        assert_eq!(size, [640, 360]);
        let px = |i: usize| [rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]];
        let n = (size[0] * size[1]) as usize;
        // The engine's markers are pure magenta (vista never draws it): one
        // 30 m above the ground, a 19 x 19 px quad (361 px), and one 100 m
        // under it, which the depth test against vista's depth hides.
        let magenta = (0..n).filter(|&i| px(i) == [255, 0, 255]).count();
        assert!((300..=450).contains(&magenta), "{output}: {magenta} marker pixels: one quad expected");
        // Terrain: the lower half is ground, not the background colour.
        let sky = [140, 173, 217];
        let ground = (n / 2..n).filter(|&i| px(i).iter().zip(sky).any(|(a, b)| a.abs_diff(b) > 8)).count();
        assert!(ground > n / 2 * 9 / 10, "{output}: {ground} ground pixels in the lower half");
        shots.push(rgba);
    }
    // The engine lights the G-buffer as vista lights it, and tonemaps vista's
    // radiance as vista does: the same picture but for a code here and there
    // (the G-buffer's 10-bit normal, f16 radiance), which FLIP scores about
    // 0.02 on average.
    for (i, name) in [(0, "gbuffer"), (1, "hdr")] {
        let stats = flip_stats(flip_map(&shots[2], &shots[i], [640, 360]));
        assert!(stats.mean < 0.03 && stats.p99 < 0.1, "{name} against lit: {stats:?}");
    }
}

/// Without a display the example says so in one line (exit 2), as `vista
/// view` does, instead of panicking with a backtrace.
#[test]
fn the_embedding_example_without_a_display_says_so_in_one_line() {
    let exe = std::env::current_exe().unwrap();
    let example = exe.parent().unwrap().parent().unwrap().join("examples").join("embed");
    assert!(example.exists(), "{} was not built (cargo build --release --examples)", example.display());
    let out = std::process::Command::new(&example)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .args(["--frames", "1"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.trim_end().lines().count() == 1 && err.contains("xvfb-run") && !err.contains("panicked"), "{err}");
    assert!(!err.contains(".rs:"), "winit's source position leaks: {err}");
    // Bad arguments: one line in the user's words (no Rust debug text).
    for (args, want) in [(&["--output", "jpg"][..], "--output jpg: use"), (&["--output"][..], "--output takes a value")]
    {
        let out = std::process::Command::new(&example).args(args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(want) && !err.contains("Some(") && !err.contains("None"), "{args:?}: {err}");
    }
}
