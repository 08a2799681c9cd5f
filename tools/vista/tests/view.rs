//! `vista view` in a real window under Xvfb (lavapipe presents to it),
//! under the validation layer: a scripted flight, minimised (openbox
//! manages the window), its surface lost (injected) and resized on the way,
//! exits cleanly with no message and no live object; its screenshot, read back from the
//! swapchain image, is `vista render`'s picture of the same camera; the
//! overlay is drawn over it when shown, folded in a small window.

mod vista_cmd;

use std::path::{Path, PathBuf};
use vista::reference::{flip_map, flip_stats};
use vista_cmd::vista_cmd;

/// A small procedural world: its error tree takes a second, and lavapipe
/// renders it at a few frames per second.
const WORLD: [&str; 6] = ["--extent", "2048", "--spacing", "2", "--lods", "4"];
const SIZE: &str = "256x144";
const CAMERA: &str = "1024,200,420,0,-25";

fn dir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("view-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `vista --validation ARGS` on a private X server (xvfb-run -a),
/// with openbox managing its windows when `window_manager` (minimising
/// needs one); returns stdout, failing the test with stderr on a non-zero
/// exit.
fn on_xvfb(window_manager: bool, args: &[&str]) -> String {
    on_xvfb_in(window_manager, args, &WORLD)
}

/// As `on_xvfb`, in the world `world` names.
fn on_xvfb_in(window_manager: bool, args: &[&str], world: &[&str]) -> String {
    let vista = vista_cmd();
    let mut c = std::process::Command::new("xvfb-run");
    c.args(["-a", "-s", "-screen 0 640x480x24"]);
    if window_manager {
        // The window manager gets a second to take the display before
        // vista's window maps (the context and world take longer).
        let wm = "openbox --sm-disable || echo 'openbox missing: run tools/install-deps' >&2 & sleep 1; exec \"$@\"";
        c.args(["sh", "-c", wm, "sh"]);
    }
    c.args([vista.get_program().to_str().unwrap(), "--validation"]);
    c.args(args).args(world);
    c.envs(vista.get_envs().filter_map(|(k, v)| v.map(|v| (k, v))));
    let out = c.output().expect("xvfb-run (tools/install-deps installs xvfb)");
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "vista {args:?} failed:\n{stdout}\n{stderr}");
    stdout.into_owned()
}

fn png(path: &Path) -> (Vec<u8>, [u32; 2]) {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8();
    let size = [img.width(), img.height()];
    (img.into_raw(), size)
}

#[test]
fn a_scripted_flight_exits_cleanly_and_its_screenshot_is_the_rendered_picture() {
    let d = dir();
    let flown = fly_the_scripted_flight(&d);
    let (flown_rgba, size) = png(&flown);
    assert_eq!(size, [256, 144]);
    screenshot_is_the_rendered_picture(&d);
    overlay_is_drawn(&flown_rgba, size);
}

/// Flies a path that minimises, resizes and loses the surface on the way;
/// checks the run said so and exited cleanly; returns the screenshot.
fn fly_the_scripted_flight(d: &Path) -> PathBuf {
    let path = d.join("flight.txt");
    // Minimised after the first leg (no frame while the window manager
    // has it minimised; restored, the swapchain comes back), resized
    // half-way (the swapchain, the targets and the G-buffer are remade
    // mid-flight), its surface lost (the next acquisition reports it, as a
    // window system may: surface and swapchain are remade from the
    // window's handles), back to its size for the screenshot.
    let flight = "# south edge, over the middle turning east, back\n1024,100,420,0,-20\n1024,500,400,30,-25\n\
                  minimise\nsize 200x100\n1024,900,380,60,-30\nlose-surface\n1024,750,390,45,-28\n\
                  size 256x144\n1024,600,400,30,-25\n";
    std::fs::write(&path, flight).unwrap();
    let flown = d.join("flown.png");
    let out = on_xvfb(
        true,
        &[
            "view",
            "--size",
            SIZE,
            "--frames",
            "60",
            "--path",
            path.to_str().unwrap(),
            "--screenshot",
            flown.to_str().unwrap(),
        ],
    );
    // Validation messages or live objects would have failed the run.
    assert!(out.contains("0 Vulkan objects alive at exit"), "{out}");
    let restored = out.lines().find(|l| l.starts_with("restored: presenting"));
    assert!(
        restored.is_some_and(|l| l.contains("after 10 redraws skipped")),
        "not minimised and back (openbox, from tools/install-deps, minimises it):\n{out}"
    );
    let lost = out.lines().find(|l| l.starts_with("surface lost after frame"));
    assert!(lost.is_some_and(|l| l.ends_with("remade, swapchain 200x100")), "the lost surface was not remade:\n{out}");
    for size in ["200x100", "256x144"] {
        assert!(out.contains(&format!("resized: swapchain {size}")), "no resize to {size}:\n{out}");
    }
    flown
}

/// The same camera without the overlay, and `vista render`'s picture of it.
fn screenshot_is_the_rendered_picture(d: &Path) {
    let shot = d.join("shot.png");
    on_xvfb(
        false,
        &[
            "view",
            "--size",
            SIZE,
            "--camera",
            CAMERA,
            "--frames",
            "3",
            "--no-overlay",
            "--screenshot",
            shot.to_str().unwrap(),
        ],
    );
    let rendered = d.join("render");
    let render = vista_cmd()
        .args(["--validation", "render", "--size", SIZE, "--camera", CAMERA, "--frames", "3", "--out"])
        .arg(&rendered)
        .args(WORLD)
        .output()
        .unwrap();
    assert!(render.status.success(), "{}", String::from_utf8_lossy(&render.stderr));
    let (shot_rgba, shot_size) = png(&shot);
    let (want, want_size) = png(&rendered.join("image.png"));
    assert_eq!(shot_size, want_size);
    // The golden images' tolerance (tools/vista/golden_cmd.rs): the same
    // renderer and view, so only rounding may differ; the blit into the
    // swapchain's BGRA UNORM image keeps every 8-bit value.
    let stats = flip_stats(flip_map(&want, &shot_rgba, want_size));
    assert!(stats.mean <= 0.005 && stats.p99 <= 0.05, "screenshot against vista render: {stats:?}");
}

fn overlay_is_drawn(flown_rgba: &[u8], size: [u32; 2]) {
    // The overlay (shown during the flight) is egui's dark window in the
    // top-left corner: grey pixels, darker than any sky or lit terrain.
    let grey_at = |i: usize| {
        let [r, g, b] = [flown_rgba[i], flown_rgba[i + 1], flown_rgba[i + 2]].map(i32::from);
        r < 70 && (r - g).abs() <= 4 && (r - b).abs() <= 4
    };
    let grey =
        (4..24).flat_map(|y| (4..24).map(move |x| ((y * size[0] + x) * 4) as usize)).filter(|&i| grey_at(i)).count();
    // The folded bar from (8, 8) holds 256 of the 400 (278 measured).
    assert!(grey > 200, "the overlay is missing from the flight's screenshot ({grey} of 400 pixels grey)");
    // At this size it starts folded (open, it covered the whole window).
    let pixels = (size[0] * size[1]) as usize;
    let share = (0..pixels).filter(|&k| grey_at(k * 4)).count() as f64 / pixels as f64;
    assert!(share < 0.15, "the overlay covers {:.0} % of a {}x{} window", 100.0 * share, size[0], size[1]);
}

/// A stamp added to the scene while `vista view` runs (a flight's `scene`
/// line, which is what an edit of the scene file does): the nodes it
/// touches reload without a restart, and the last picture is `vista
/// render`'s of the stamped scene.
#[test]
fn a_stamp_added_while_the_view_runs_shows_without_a_restart() {
    let d = dir();
    let world = "[world]\nsource = \"procedural\"\nextent = 2048\nspacing = 2\nlods = 4\n";
    let stamp = format!(
        "[[stamps]]\nsource = \"{}/../../scenes/stamps/mountain.png\"\ncenter = [1024, 700]\nsize = 400\nheight = 300\n\
         offset = 800\nblend = \"max\"\nfalloff = 40\n",
        env!("CARGO_MANIFEST_DIR")
    );
    let (plain, stamped) = (d.join("plain.toml"), d.join("stamped.toml"));
    std::fs::write(&plain, world).unwrap();
    std::fs::write(&stamped, format!("{world}{stamp}")).unwrap();
    let flight = d.join("edit.txt");
    let camera = "1024,200,420,0,-20";
    // Half-way, once the plain world is resident.
    std::fs::write(&flight, format!("{camera}\n{camera}\nscene stamped.toml\n{camera}\n")).unwrap();
    let shot = d.join("edited.png");
    let scene = ["--scene", plain.to_str().unwrap()];
    let flown = ["--path", flight.to_str().unwrap(), "--screenshot", shot.to_str().unwrap()];
    let args = [&["view", "--size", SIZE, "--frames", "20", "--no-overlay"][..], &flown[..]].concat();
    let out = on_xvfb_in(false, &args, &scene);
    let line = out.lines().find(|l| l.starts_with("scene ")).unwrap_or_else(|| panic!("no scene line:\n{out}"));
    assert!(line.contains("stamped.toml: stamps changed over 824,500 .. 1224,900 m (1 now)"), "{line}");
    let reloaded: u32 = line.split("; ").nth(1).and_then(|r| r.split(' ').next()?.parse().ok()).unwrap();
    assert!(reloaded > 0, "{line}");
    assert!(out.contains("0 Vulkan objects alive at exit"), "{out}");
    let rendered = d.join("stamped-render");
    let render = vista_cmd()
        .args(["--validation", "render", "--size", SIZE, "--camera", camera, "--frames", "3", "--out"])
        .arg(&rendered)
        .args(["--scene", stamped.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(render.status.success(), "{}", String::from_utf8_lossy(&render.stderr));
    let (got, size) = png(&shot);
    let (want, want_size) = png(&rendered.join("image.png"));
    assert_eq!(size, want_size);
    // The golden images' tolerance, as for the first test's screenshot.
    let stats = flip_stats(flip_map(&want, &got, size));
    assert!(
        stats.mean <= 0.005 && stats.p99 <= 0.05,
        "edited view against vista render of the stamped scene: {stats:?}"
    );
}

/// Without a display, or with a run that cannot end, one line before any
/// window or Vulkan device is made.
#[test]
fn view_refuses_what_it_cannot_do_in_one_line() {
    let run = |args: &[&str], display: Option<&str>| {
        let mut c = vista_cmd();
        c.arg("view").args(args);
        match display {
            Some(d) => c.env("DISPLAY", d),
            None => c.env_remove("DISPLAY"),
        };
        let out = c.output().unwrap();
        (out.status.code(), String::from_utf8_lossy(&out.stderr).trim().to_string())
    };
    let (code, err) = run(&["--frames", "1"], None);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("DISPLAY is not set") && !err.contains('\n'), "{err}");
    let (code, err) = run(&["--screenshot", "x.png"], Some(":0"));
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--screenshot needs --frames"), "{err}");
    let (code, err) = run(&["--frames", "2", "--path", "/nonexistent/flight.txt"], Some(":0"));
    assert_eq!(code, Some(2), "{err}");
    assert!(err.starts_with("error: --path /nonexistent/flight.txt"), "{err}");
}
