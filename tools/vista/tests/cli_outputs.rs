//! Outputs appear whole or not at all. A full disk is simulated at each file
//! a render, a bake and a render's cache write (`VISTA_FAIL_WRITE=N`: the
//! Nth file write fails with "no space left on device" after writing half
//! of its first buffer, `vista::output`'s fault injector), and each time no
//! partial or temporary file remains and earlier contents are intact.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
mod vista_cmd;

/// A world whose error tree and nodes take well under a second.
const WORLD: [&str; 4] = ["--extent", "1024", "--spacing", "2"];

struct Run {
    code: Option<i32>,
    stderr: String,
}

fn vista(args: &[&str], fail_at: Option<u64>, cache: &Path) -> Run {
    vista_failing(args, fail_at.map(|n| ("VISTA_FAIL_WRITE", n)), cache)
}

/// `vista ARGS` whose Nth operation of one kind fails (`VISTA_FAIL_WRITE`,
/// `VISTA_FAIL_SYNC`, `VISTA_FAIL_CLOSE` or `VISTA_FAIL_RENAME`).
fn vista_failing(args: &[&str], fail: Option<(&str, u64)>, cache: &Path) -> Run {
    let mut c = vista_cmd::vista_cmd();
    // This test's own error-tree cache, filled by the first (unfaulted) run,
    // so the faulted runs write only what they are asked to.
    c.env("VISTA_CACHE", cache).args(args).args(WORLD);
    if let Some((var, n)) = fail {
        c.env(var, n.to_string());
    }
    let out = c.output().expect("run vista");
    Run { code: out.status.code(), stderr: String::from_utf8_lossy(&out.stderr).into() }
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vista-cli-outputs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// Every file under `dir` (relative path -> bytes).
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_string_lossy().into_owned();
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

fn temporaries(files: &BTreeMap<String, Vec<u8>>) -> Vec<&String> {
    files.keys().filter(|k| vista::output::is_temporary(k) || k.contains("tmp")).collect()
}

/// The last stderr line is the error, naming a file under `dir` and the
/// disk being full.
fn assert_full_disk_error(run: &Run, dir: &Path, what: &str) {
    assert_disk_error(run, dir, "No space left", what);
}

/// The last stderr line is the error, naming a file under `dir` and `says`.
fn assert_disk_error(run: &Run, dir: &Path, says: &str, what: &str) {
    assert_eq!(run.code, Some(1), "{what}: {}", run.stderr);
    let last = run.stderr.trim_end().lines().last().unwrap_or("");
    assert!(
        last.starts_with("error: ") && last.contains(&dir.display().to_string()) && last.contains(says),
        "{what}: {}",
        run.stderr
    );
}

#[test]
fn a_render_writes_all_its_files_or_none() {
    let root = temp_dir("render");
    let cache = root.join("trees");
    let out = root.join("out");
    let render = |dir: &Path, fail_at| {
        let args = ["--validation", "render", "--size", "64x48", "--frames", "1", "--out", dir.to_str().unwrap()];
        vista(&args, fail_at, &cache)
    };
    let first = render(&out, None);
    assert_eq!(first.code, Some(0), "{}", first.stderr);
    let before = snapshot(&out);
    assert_eq!(before.len(), 8, "{:?}", before.keys());
    // A failure at each of the 8 files: the previous render's files stay as
    // they were, and a new folder is not created at all.
    for k in 0..8 {
        let run = render(&out, Some(k));
        assert_full_disk_error(&run, &out, &format!("file {k} over an earlier render"));
        assert!(snapshot(&out) == before, "file {k}: the earlier render's files changed");
        let fresh = root.join(format!("fresh{k}"));
        let run = render(&fresh, Some(k));
        assert_full_disk_error(&run, &fresh, &format!("file {k} into a new folder"));
        assert!(!fresh.exists(), "file {k}: {fresh:?} was left behind");
    }
    // The 9th write does not exist: the 8 above were every file.
    let run = render(&out, Some(8));
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let after = snapshot(&out);
    assert_eq!(after.keys().collect::<Vec<_>>(), before.keys().collect::<Vec<_>>());
    let _ = std::fs::remove_dir_all(&root);
}

/// A network disk or a quota that reports only at fsync or at close, and a
/// rename that fails, at every such operation of a render: the previous render's files
/// stay all old (a commit that fails part-way puts back what it moved), no
/// temporary remains, and the error names the file. Then a bake whose
/// fsync fails names the node file and keeps every earlier one.
#[test]
fn fsync_and_rename_failures_keep_the_previous_set_whole_and_name_the_file() {
    let root = temp_dir("fsync");
    let cache = root.join("trees");
    let out = root.join("out");
    let args = ["--validation", "render", "--size", "64x48", "--frames", "1", "--out", out.to_str().unwrap()];
    let first = vista(&args, None, &cache);
    assert_eq!(first.code, Some(0), "{}", first.stderr);
    let mut before = snapshot(&out);
    let mut failed = Vec::new();
    let steps = [
        ("VISTA_FAIL_SYNC", "Disk quota exceeded"),
        ("VISTA_FAIL_CLOSE", "Input/output error"),
        ("VISTA_FAIL_RENAME", "Input/output error"),
    ];
    for (var, says) in steps {
        let mut k = 0;
        loop {
            let run = vista_failing(&args, Some((var, k)), &cache);
            if run.code == Some(0) {
                // Timings differ between renders: the new set is the old one now.
                before = snapshot(&out);
                break;
            }
            assert_disk_error(&run, &out, says, &format!("{var}={k}"));
            assert!(snapshot(&out) == before, "{var}={k}: the earlier render's files changed");
            k += 1;
            assert!(k < 64, "{var}: every run failed");
        }
        failed.push((var, k));
    }
    // 8 files and the folder are fsynced, the 8 files closed; 8 old files
    // go aside, 8 new come in.
    assert_eq!(failed, [("VISTA_FAIL_SYNC", 9), ("VISTA_FAIL_CLOSE", 8), ("VISTA_FAIL_RENAME", 16)]);

    let nodes = root.join("nodes");
    let bake = ["bake", "--out", nodes.to_str().unwrap(), "--no-progress", "--region", "0,0,64,64"];
    let ok = vista(&bake, None, &cache);
    assert_eq!(ok.code, Some(0), "{}", ok.stderr);
    let baked = snapshot(&nodes);
    std::fs::remove_dir_all(&nodes).unwrap();
    let run = vista_failing(&bake, Some(("VISTA_FAIL_SYNC", 2)), &cache);
    assert_disk_error(&run, &nodes, "Disk quota exceeded", "bake, fsync 2");
    let now = snapshot(&nodes);
    assert!(temporaries(&now).is_empty(), "{:?}", temporaries(&now));
    assert!(now.iter().all(|(name, bytes)| baked.get(name) == Some(bytes)), "a partial file was left");
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn a_bake_on_a_full_disk_leaves_only_whole_node_files() {
    let root = temp_dir("bake");
    let cache = root.join("trees");
    let out = root.join("nodes");
    let bake = |region: Option<&str>, fail_at| {
        let mut args = vec!["bake", "--out", out.to_str().unwrap(), "--no-progress"];
        if let Some(r) = region {
            args.extend(["--region", r]);
        }
        vista(&args, fail_at, &cache)
    };
    let first = bake(Some("0,0,64,64"), None);
    assert_eq!(first.code, Some(0), "{}", first.stderr);
    let before = snapshot(&out);
    // The corner's 3 nodes (one per LOD) and its root's error tile.
    assert_eq!(before.len(), 4, "{:?}", before.keys());
    for k in [0, 3, 7] {
        let run = bake(None, Some(k));
        assert_full_disk_error(&run, &out, &format!("bake, write {k}"));
        let now = snapshot(&out);
        assert!(temporaries(&now).is_empty(), "write {k}: {:?}", temporaries(&now));
        for (name, bytes) in &before {
            assert!(now.get(name) == Some(bytes), "write {k}: {name} changed");
        }
    }
    // Every node file left is whole: a bake without faults reads each one
    // back (a partial file would fail its checksum and be baked again).
    let files = snapshot(&out).keys().filter(|k| k.ends_with(".vnode")).count();
    let args = ["bake", "--out", out.to_str().unwrap(), "--no-progress"];
    let mut c = vista_cmd::vista_cmd();
    let done = c.env("VISTA_CACHE", &cache).args(args).args(WORLD).output().unwrap();
    let text = String::from_utf8_lossy(&done.stdout);
    assert!(done.status.success(), "{}", String::from_utf8_lossy(&done.stderr));
    assert!(text.contains(&format!(" {files} reused")), "{files} whole files expected to be read back:\n{text}");
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn a_render_whose_cache_cannot_be_written_says_so_once_and_goes_on() {
    let root = temp_dir("cache");
    let trees = root.join("trees");
    for k in [0, 1, 2] {
        let cache = root.join(format!("cache{k}"));
        let args = ["--validation", "render", "--size", "64x48", "--frames", "1", "--cache", cache.to_str().unwrap()];
        let run = vista(&args, Some(k), &trees);
        assert_eq!(run.code, Some(0), "write {k}: {}", run.stderr);
        let warnings: Vec<&str> = run.stderr.lines().filter(|l| l.contains("No space left")).collect();
        assert_eq!(warnings.len(), 1, "write {k}: one line expected:\n{}", run.stderr);
        assert!(warnings[0].contains("without caching") || warnings[0].contains("not cached"), "{}", warnings[0]);
        let files = snapshot(&cache);
        assert!(temporaries(&files).is_empty(), "write {k}: {:?}", temporaries(&files));
        assert!(files.values().all(|b| !b.is_empty()), "write {k}: an empty file");
    }
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn a_json_report_on_a_full_disk_keeps_the_previous_one() {
    let root = temp_dir("json");
    let trees = root.join("trees");
    let json = root.join("report.json");
    std::fs::write(&json, "previous").unwrap();
    for args in [["memory", "--json"], ["bake", "--dry-run"]] {
        let mut args = args.to_vec();
        if args[0] == "bake" {
            args.push("--json");
        }
        args.push(json.to_str().unwrap());
        let run = vista(&args, Some(0), &trees);
        assert_full_disk_error(&run, &root, &format!("{args:?}"));
        let files = snapshot(&root);
        assert!(temporaries(&files).is_empty(), "{args:?}: {:?}", temporaries(&files));
        assert_eq!(std::fs::read_to_string(&json).unwrap(), "previous", "{args:?}");
    }
    let _ = std::fs::remove_dir_all(&root);
}
