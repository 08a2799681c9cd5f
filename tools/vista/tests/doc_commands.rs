//! Every command the README and the docs' chapters quote still works as
//! quoted: each `vista ...` (and `cargo run --release -- ...`) is run with
//! `VISTA_CHECK_ONLY=1`, which parses it and checks its inputs (scene,
//! height map, view, paths) as the command does before any GPU or long
//! work; each `--example NAME` names an example that exists. The synopsis
//! in docs/commands.md has its own test (`readme_synopsis.rs`).

use std::path::{Path, PathBuf};
mod vista_cmd;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The README and every chapter but the synopsis, with their names.
fn pages() -> Vec<(String, String)> {
    let mut out = vec![("README.md".to_string(), std::fs::read_to_string(repo().join("README.md")).unwrap())];
    let mut chapters: Vec<PathBuf> = std::fs::read_dir(repo().join("docs"))
        .unwrap()
        .filter_map(|e| Some(e.ok()?.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "md") && !p.ends_with("commands.md"))
        .collect();
    chapters.sort();
    for p in chapters {
        let name = format!("docs/{}", p.file_name().unwrap().to_string_lossy());
        out.push((name, std::fs::read_to_string(&p).unwrap()));
    }
    out
}

/// The inline code spans of `text` (a span may wrap over lines).
fn spans(text: &str) -> Vec<String> {
    let text = text.replace("```", "\u{0}");
    let mut out = Vec::new();
    let mut parts = text.split('`');
    parts.next();
    while let (Some(code), Some(_)) = (parts.next(), parts.next()) {
        if !code.contains('\u{0}') {
            out.push(code.split_whitespace().collect::<Vec<_>>().join(" "));
        }
    }
    out
}

/// A quoted command's arguments after `vista`, with the docs' placeholders
/// made concrete (`S` and `FILE` a scene, `WORLD` a world, `DIR` a folder,
/// `I/N` a shard); `None` for a span that is not a whole command. A bare
/// `vista CMD` names the command: its `--help` is what is checked.
fn arguments(span: &str, dir: &Path) -> Option<Vec<String>> {
    let rest = span.strip_prefix("vista ").or_else(|| span.strip_prefix("cargo run --release -- "))?;
    if rest.contains("...") || rest.contains('[') || rest.contains('|') {
        return None;
    }
    let mut args = Vec::new();
    if !rest.contains(' ') {
        return Some(vec![rest.to_string(), "--help".to_string()]);
    }
    for word in rest.split_whitespace() {
        match word {
            "S" | "FILE" => args.push("scenes/minimal.toml".to_string()),
            "WORLD" => args.extend(["--scene".to_string(), "scenes/minimal.toml".to_string()]),
            "DIR" => args.push(dir.display().to_string()),
            "I/N" => args.push("0/2".to_string()),
            w => args.push(w.to_string()),
        }
    }
    Some(args)
}

#[test]
fn every_quoted_command_parses_and_its_inputs_check_out() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("doc-commands");
    std::fs::create_dir_all(&dir).unwrap();
    let (mut checked, mut problems) = (0, Vec::new());
    for (page, text) in pages() {
        for span in spans(&text) {
            let Some(args) = arguments(&span, &dir) else { continue };
            let out = vista_cmd::vista_cmd().current_dir(repo()).env("VISTA_CHECK_ONLY", "1").args(&args).output();
            let out = out.unwrap();
            checked += 1;
            if !out.status.success() {
                problems.push(format!("{page}: `{span}`: {}", String::from_utf8_lossy(&out.stderr).trim()));
            }
        }
    }
    assert!(problems.is_empty(), "quoted commands that no longer work:\n{}", problems.join("\n"));
    assert!(checked >= 20, "only {checked} commands found: the extraction is broken");
}

#[test]
fn every_quoted_example_exists() {
    let mut found = 0;
    for (page, text) in pages() {
        for span in spans(&text) {
            let Some(name) = span.split("--example ").nth(1).and_then(|r| r.split_whitespace().next()) else {
                continue;
            };
            found += 1;
            let ex = repo().join("examples");
            assert!(
                ex.join(format!("{name}.rs")).is_file() || ex.join(name).join("main.rs").is_file(),
                "{page} runs example {name}, which is not in examples/"
            );
        }
    }
    assert!(found >= 2, "only {found} examples quoted: the extraction is broken");
}

#[test]
fn check_only_refuses_a_typo_in_a_quoted_command() {
    // The test above is only as good as the mode it runs: a bad option and
    // a missing scene are refused, not checked.
    for args in [&["render", "--scnee", "scenes/minimal.toml"][..], &["render", "--scene", "scenes/nope.toml"]] {
        let out = vista_cmd::vista_cmd().current_dir(repo()).env("VISTA_CHECK_ONLY", "1").args(args).output();
        assert_eq!(out.unwrap().status.code(), Some(2), "{args:?}");
    }
}
