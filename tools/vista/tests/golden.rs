//! Golden images: `vista golden` renders the default world (overview and a
//! close cliff view) and Mont Blanc at 256x144 on the test device and
//! compares each with its reference in tests/golden with NVIDIA FLIP
//! (tolerance and its reason: `tools/vista/golden_cmd.rs`). A missing
//! reference fails; `vista golden --update` rewrites them and prints what
//! changed.

mod vista_cmd;

use vista_cmd::vista_cmd;

#[test]
fn golden_images_match_their_references_under_validation() {
    let out = vista_cmd()
        .args(["--validation", "golden", "--out"])
        .arg(std::env::temp_dir().join(format!("vista-golden-{}", std::process::id())))
        .output()
        .expect("run vista golden");
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{stdout}{stderr}");
    for name in ["default", "default-cliffs", "montblanc"] {
        let line = stdout.lines().find(|l| l.split_whitespace().next() == Some(name));
        assert!(line.is_some_and(|l| l.contains(" ok: ")), "{name} not checked:\n{stdout}");
    }
}

#[test]
fn a_missing_reference_fails_and_says_how_to_make_one() {
    let empty = std::env::temp_dir().join(format!("vista-golden-empty-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&empty);
    // A folder that does not exist is named at once, before any render.
    let out = vista_cmd().args(["golden", "--dir"]).arg(&empty).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("does not exist") && stderr.contains("vista golden --update"), "{stderr}");
    std::fs::create_dir_all(&empty).unwrap();
    let out = vista_cmd()
        .args(["golden", "--only", "montblanc", "--dir"])
        .arg(&empty)
        .arg("--out")
        .arg(empty.join("diff"))
        .output()
        .expect("run vista golden");
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(!out.status.success(), "{stdout}");
    assert!(stdout.contains("montblanc        FAILED: no reference"), "{stdout}");
    assert!(stderr.contains("vista golden --update"), "{stderr}");
    // The rendered image is left to look at.
    assert!(empty.join("diff/montblanc.png").exists());
    let _ = std::fs::remove_dir_all(&empty);
    // A typo in a view name is a one-line input error.
    let out = vista_cmd().args(["golden", "--only", "mont-blanc"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("no golden view \"mont-blanc\"") && stderr.lines().count() == 1, "{stderr}");
}

#[test]
fn bc_payloads_stay_near_rgba8_ones_on_a_lit_render() {
    // The default overview from BC3 / BC1 payloads against RGBA8 ones; the
    // tolerance and its reason: `PAYLOAD_MAX_*` in tools/vista/golden_cmd.rs.
    let out_dir = std::env::temp_dir().join(format!("vista-payload-diff-{}", std::process::id()));
    let out = vista_cmd()
        .args(["--validation", "golden", "--payload-diff", "--only", "default", "--out"])
        .arg(&out_dir)
        .output()
        .expect("run vista golden --payload-diff");
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{stdout}{stderr}");
    assert!(stdout.contains("default          ok: BC against RGBA8 payloads: FLIP mean"), "{stdout}");
    let _ = std::fs::remove_dir_all(&out_dir);
}
