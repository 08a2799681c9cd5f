//! The README's command synopsis names the options `--help` lists, no more
//! and no fewer, per command: a new option appears in both, a renamed one
//! is renamed in both.

use std::collections::BTreeSet;
mod vista_cmd;

/// Every `--option` token in `text`.
fn options(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (i, _) in text.match_indices("--") {
        let rest = &text[i + 2..];
        let name: String = rest.chars().take_while(|c| c.is_ascii_lowercase() || *c == '-').collect();
        let before = text[..i].chars().last();
        if name.len() > 1 && !name.ends_with('-') && before.is_none_or(|c| c.is_whitespace() || "[(`,|".contains(c)) {
            out.insert(format!("--{name}"));
        }
    }
    out
}

/// The README's synopsis block, split by command: each `vista CMD` entry
/// runs to the next one.
fn readme_sections() -> Vec<(String, String)> {
    let readme = include_str!("../../../README.md");
    let start = readme.find("## Command line").expect("the README has a command line section");
    let block = &readme[start..];
    let block = &block[block.find("```").unwrap() + 3..];
    let block = &block[..block.find("```").unwrap()];
    let mut sections: Vec<(String, String)> = Vec::new();
    for line in block.lines() {
        if let Some(rest) = line.strip_prefix("vista ") {
            let cmd = rest.split_whitespace().next().unwrap_or("").trim_end_matches(':').to_string();
            sections.push((cmd, String::new()));
        }
        if let Some(last) = sections.last_mut() {
            last.1.push_str(line);
            last.1.push('\n');
        } else {
            sections.push((String::new(), format!("{line}\n")));
        }
    }
    // Lines before the first command or after the WORLD paragraph belong to
    // every command: the shared WORLD and global options.
    sections
}

fn help(cmd: &str) -> BTreeSet<String> {
    let out = vista_cmd::vista_cmd().args([cmd, "--help"]).output().unwrap();
    assert!(out.status.success());
    let mut o = options(&String::from_utf8_lossy(&out.stdout));
    o.remove("--help");
    o
}

#[test]
fn the_readme_synopsis_names_every_option_of_every_command_and_no_other() {
    let sections = readme_sections();
    let text_of = |cmd: &str| -> String {
        sections.iter().filter(|(c, _)| c == cmd).map(|(_, t)| t.as_str()).collect::<Vec<_>>().join("\n")
    };
    // The shared paragraphs (WORLD options, WORLD =, Global) sit inside
    // the memory and stability entries' text; take them from the whole block.
    let all: String = sections.iter().map(|(_, t)| t.as_str()).collect();
    let world_start = all.find("WORLD options shared").unwrap();
    let world_end = all[world_start..].find("vista bench").unwrap() + world_start;
    let tail_start = all.find("WORLD = --scene").unwrap();
    let shared = options(&format!("{}{}", &all[world_start..world_end], &all[tail_start..]));
    let mut problems = Vec::new();
    for cmd in ["info", "render", "bake", "memory", "bench", "golden", "stability"] {
        // The synopsis lines: `vista CMD ...` and their `[...]` continuations
        // (descriptions mention other commands' options in passing).
        let text = text_of(cmd);
        let synopsis: String = text
            .lines()
            .filter(|l| l.starts_with("vista ") || l.trim_start().starts_with('['))
            .collect::<Vec<_>>()
            .join("\n");
        let readme = options(&synopsis);
        let helped = help(cmd);
        let takes_world = helped.contains("--scene");
        let readme_all: BTreeSet<String> =
            if takes_world { readme.union(&shared).cloned().collect() } else { readme.clone() };
        let global = ["--validation", "--device"];
        let missing: Vec<_> =
            helped.iter().filter(|o| !readme_all.contains(*o) && !global.contains(&o.as_str())).collect();
        let extra: Vec<_> = readme.iter().filter(|o| !helped.contains(*o)).collect();
        if !missing.is_empty() || !extra.is_empty() {
            problems.push(format!(
                "vista {cmd}: --help has {missing:?} the README lacks; the README has {extra:?} --help lacks"
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
