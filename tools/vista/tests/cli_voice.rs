//! One voice for bad input, across every command: exit code 2, exactly one
//! line on stderr, none of the parsers' own phrases (which name Rust types,
//! not what the option takes), and nothing written. No GPU work: every case
//! is refused before (or, for the few that need the device's limits, right
//! after) Vulkan starts.

use std::path::{Path, PathBuf};
mod vista_cmd;

const MONTBLANC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data/montblanc.png");

/// Phrases of the standard library's, serde's and clap's parsers that must
/// not reach a user.
const JARGON: [&str; 13] = [
    "invalid digit",
    "too large to fit",
    "cannot parse",
    "invalid float literal",
    "expected u",
    "expected f",
    "expected i",
    "did not match any variant",
    "untagged enum",
    "invalid type:",
    "panicked",
    "RUST_BACKTRACE",
    "Parse",
];

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vista-cli-voice-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

fn scene(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.push(p.clone());
            out.extend(files_under(&p));
        } else {
            out.push(p);
        }
    }
    out
}

#[test]
fn sixty_bad_inputs_each_get_one_line_and_exit_2() {
    let inputs = temp_dir("inputs");
    let cases: Vec<Vec<String>> = [render_option_cases(), render_world_cases(&inputs), other_command_cases()].concat();
    assert!(cases.len() >= 60);
    let mut failures = Vec::new();
    for (i, args) in cases.iter().enumerate() {
        failures.extend(refusal_failure(i, args));
    }
    assert!(failures.is_empty(), "{} of {} cases:\n{}", failures.len(), cases.len(), failures.join("\n"));
    let _ = std::fs::remove_dir_all(&inputs);
}

fn s(v: &[&str]) -> Vec<String> {
    v.iter().map(|a| a.to_string()).collect::<Vec<String>>()
}

/// `render` options each out of range or unreadable, on the default world.
fn render_option_cases() -> Vec<Vec<String>> {
    vec![
        s(&["render", "--frames", "abc"]),
        s(&["render", "--frames", "-1"]),
        s(&["render", "--frames", "0"]),
        s(&["render", "--frames", "99999999999"]),
        s(&["render", "--slots", ""]),
        s(&["render", "--slots", "2048"]),
        s(&["render", "--slots", "1"]),
        s(&["render", "--gpu-budget", "nan"]),
        s(&["render", "--gpu-budget", "1"]),
        s(&["render", "--gpu-budget", "64", "--slots", "200"]),
        s(&["render", "--fov", "x"]),
        s(&["render", "--fov", "0"]),
        s(&["render", "--fov", "180"]),
        s(&["render", "--target-error", "0"]),
        s(&["render", "--target-error", "-1"]),
        s(&["render", "--target-error", "abc"]),
        s(&["render", "--size", "0x10"]),
        s(&["render", "--size", "-160x120"]),
        s(&["render", "--size", "100"]),
        s(&["render", "--size", "20000x10"]),
        s(&["render", "--camera", "1,2"]),
        s(&["render", "--camera", "1,nan,3"]),
        s(&["render", "--camera", "1,2,3,0,-120"]),
        s(&["render", "--cull", "frustum,bogus"]),
        s(&["render", "--queues", "bogus"]),
        s(&["render", "--lod-rule", "triangles"]),
        s(&["render", "--settle-seconds", "-1"]),
        s(&["render", "--out", "shot.png"]),
        s(&["render", "--spacing", "-1"]),
        s(&["render", "--spacing", "abc"]),
        s(&["render", "--lods", "11"]),
        s(&["render", "--lods", "1.5"]),
        s(&["render", "--seed", "-1"]),
        s(&["render", "--extent", "0"]),
        s(&["render", "--extent", "abc"]),
        s(&["render", "--extent", "1,2,3"]),
        s(&["render", "--height-range", "5", "1"]),
        s(&["render", "--origin", "1"]),
        s(&["render", "--hole-circle", "1,2"]),
        s(&["render", "--hole-circle", "1,2,-3"]),
    ]
}

/// Bad height maps, scene files and degenerate worlds and views.
fn render_world_cases(inputs: &Path) -> Vec<Vec<String>> {
    let lods = scene(inputs, "lods.toml", "[world]\nlods = \"x\"\n");
    let extent = scene(inputs, "extent.toml", "[world]\nextent = \"big\"\n");
    let key = scene(inputs, "key.toml", "[world]\nlodz = 3\n");
    let circle = scene(inputs, "circle.toml", "[[holes]]\ncircle = [1, 2]\n");
    let rules = scene(inputs, "rules.toml", "[material_rules]\nsnow_line_m = \"high\"\n");
    let effect = scene(inputs, "effect.toml", "[effects]\nholes = 5\n");
    let syntax = scene(inputs, "syntax.toml", "[world\nlods = 3\n");
    // Placements that miss the world entirely (each would do nothing).
    let crater = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/stamps/crater.png");
    let far_stamp = format!("[[stamps]]\nsource = \"{crater}\"\ncenter = [900000, 900000]\nsize = 300\nheight = 50\n");
    let far_stamp = scene(inputs, "far_stamp.toml", &far_stamp);
    let far_asset = scene(inputs, "far_asset.toml", "[[assets]]\nkind = \"rock\"\nat = [99999, 99999]\n");
    let far_decal = "[[decals]]\ntexture = \"a.png\"\nquad = { center = [-5000, 10], size = [4, 2] }\n";
    let far_decal = scene(inputs, "far_decal.toml", far_decal);
    let truncated = inputs.join("truncated.png");
    std::fs::write(&truncated, &std::fs::read(MONTBLANC).unwrap()[..4000]).unwrap();
    let truncated = truncated.to_str().unwrap().to_string();
    let flight = scene(inputs, "flight.txt", "100,100,500,0,-20\nscene nope.toml\n");
    let cargo = concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.toml");
    let mb_range = ["--extent", "60000", "--height-range", "454", "4810", "--spacing", "8"];
    let with_mb = |v: &[&str]| [s(v), s(&mb_range)].concat();
    vec![
        s(&["render", "--heightmap", "/no/such.png", "--extent", "100", "--height-range", "0", "1"]),
        s(&["render", "--heightmap", cargo, "--extent", "100", "--height-range", "0", "1"]),
        s(&["render", "--heightmap", MONTBLANC, "--extent", "60000"]),
        s(&["render", "--heightmap", MONTBLANC]),
        with_mb(&["render", "--heightmap", MONTBLANC, "--lods", "1"]),
        with_mb(&["render", "--heightmap", MONTBLANC, "--clamp-heights"]),
        s(&["render", "--scene", "/no/such.toml"]),
        s(&["render", "--scene", &lods]),
        s(&["render", "--scene", &extent]),
        s(&["render", "--scene", &key]),
        s(&["render", "--scene", &circle]),
        s(&["render", "--scene", &rules]),
        s(&["render", "--scene", &effect]),
        s(&["render", "--scene", &syntax]),
        s(&["render", "--scene", &lods, "--heightmap", MONTBLANC]),
        s(&["render", "--clamp-heights"]),
        s(&["render", "--max-sectors", "10"]),
        s(&["render", "--payload", "foo"]),
        s(&["render", "--bogus-flag"]),
        // Degenerate worlds and views, refused with their ranges.
        s(&["render", "--extent", "1"]),
        s(&["render", "--spacing", "1e12"]),
        s(&["render", "--origin", "1e20,1e20"]),
        s(&["render", "--camera", "1e300,0,0"]),
        s(&["render", "--fov", "1e-9"]),
        s(&["render", "--fov", "179.95"]),
        s(&["render", "--origin", "1e7,5e6"]),
        s(&["render", "--scene", &far_stamp]),
        s(&["render", "--scene", &far_asset]),
        s(&["render", "--scene", &far_decal]),
        with_mb(&["memory", "--heightmap", &truncated]),
        s(&["view", "--frames", "1", "--screenshot", "shot.jpg"]),
        s(&["view", "--frames", "2", "--path", &flight]),
        s(&["bake", "--out", "nodes", "--shard", "-1/2"]),
    ]
}

/// Every other command's bad input.
fn other_command_cases() -> Vec<Vec<String>> {
    vec![
        s(&["bake"]),
        s(&["bake", "--out", "nodes", "--region", "1,2,3"]),
        s(&["bake", "--out", "nodes", "--region", "5,5,1,1"]),
        s(&["bake", "--out", "nodes", "--region", "99999,99999,100000,100000"]),
        s(&["bake", "--out", "nodes", "--max-disk", "-1"]),
        s(&["bake", "--out", "nodes", "--max-disk", "abc"]),
        s(&["bake", "--dry-run", "--json", "/nonexistent/plan.json"]),
        s(&["memory", "--slots", "0"]),
        s(&["memory", "--slots", "2048"]),
        s(&["memory", "--slots", "abc"]),
        s(&["memory", "--json", "/proc/memory.json"]),
        s(&["memory", "--extent", "1e30"]),
        s(&["bench", "nope"]),
        s(&["bench", "cull", "--camera", "1,2,3"]),
        s(&["bench", "traverse", "--size", "10x10"]),
        s(&["bench", "traverse", "--sets", "x"]),
        s(&["bench", "accuracy", "--targets", "x"]),
        s(&["bench", "accuracy", "--lod-rules", "patch,bogus"]),
        s(&["bench", "cull", "--lod-rules", "triangle"]),
        s(&["golden", "--dir", "/nonexistent"]),
        s(&["golden", "--only", "nope"]),
        s(&["stability", "--cases", "300"]),
        s(&["stability", "--cases", "x"]),
        s(&["stability", "--json", "/nonexistent/table.json"]),
        s(&["nonsense-command"]),
        s(&["--device"]),
    ]
}

/// Runs one case in an empty folder; what was wrong with its refusal, if anything.
fn refusal_failure(i: usize, args: &[String]) -> Option<String> {
    // Each in an empty folder, relative outputs landing there.
    let cwd = temp_dir(&format!("case{i}"));
    let out = vista_cmd::vista_cmd().args(args).current_dir(&cwd).output().expect("run vista");
    let err = String::from_utf8_lossy(&out.stderr);
    let lines = err.trim_end().lines().count();
    let mut jargon: Vec<&str> = JARGON.iter().copied().filter(|j| err.contains(j)).collect();
    // A negative number taken for an option by clap.
    if err.split("unexpected argument '-").skip(1).any(|rest| rest.starts_with(|c: char| c.is_ascii_digit())) {
        jargon.push("unexpected argument '-N'");
    }
    let written = files_under(&cwd);
    let failure =
        (out.status.code() != Some(2) || lines != 1 || !jargon.is_empty() || !written.is_empty()).then(|| {
            format!(
                "{args:?}: exit {:?}, {lines} lines, jargon {jargon:?}, wrote {written:?}:\n{err}",
                out.status.code()
            )
        });
    let _ = std::fs::remove_dir_all(&cwd);
    failure
}

#[test]
fn a_camera_under_the_ground_or_outside_the_world_renders_and_says_so() {
    let small = ["--extent", "1024", "--spacing", "2", "--size", "32x24", "--frames", "1"];
    for (camera, note) in [("500,500,-200", "below the ground"), ("-300,500,400", "outside the world")] {
        let out =
            vista_cmd::vista_cmd().args(["--validation", "render", "--camera", camera]).args(small).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{camera}: {err}");
        let notes: Vec<&str> = err.lines().filter(|l| l.starts_with("note:")).collect();
        assert!(notes.len() == 1 && notes[0].contains(note), "{camera}: {err}");
    }
}

#[test]
fn each_bench_kind_has_its_own_help() {
    let help = |kind: &str| {
        let out = vista_cmd::vista_cmd().args(["bench", kind, "--help"]).output().unwrap();
        assert!(out.status.success());
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let (traverse, cull, accuracy) = (help("traverse"), help("cull"), help("accuracy"));
    assert!(traverse.contains("Usage: vista bench traverse") && traverse.contains("--camera"), "{traverse}");
    assert!(!traverse.contains("--size") && !traverse.contains("--plot"), "{traverse}");
    assert!(cull.contains("Patch culling per view") && !cull.contains("--camera") && cull.contains("--size"), "{cull}");
    assert!(accuracy.contains("--plot") && accuracy.contains("--views") && !accuracy.contains("--sets"), "{accuracy}");
}

/// `vista ... | head`: a reader that leaves early ends vista quietly (the
/// shell's SIGPIPE status, 141), not with a panic's backtrace.
#[test]
fn a_closed_stdout_ends_the_run_quietly() {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let dir = temp_dir("closed-stdout");
    let out = vista_cmd::vista_cmd()
        .args(["render", "--extent", "1024", "--spacing", "2", "--lods", "3", "--size", "32x24", "--frames", "1"])
        .arg("--out")
        .arg(dir.join("out"))
        .stdout(writer)
        .stderr(std::process::Stdio::piped())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(141), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
