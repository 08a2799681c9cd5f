//! The command synopsis (docs/commands.md) names the options `--help`
//! lists, no more and no fewer, per command: a new option appears in both,
//! a renamed one is renamed in both. The README's command table names every
//! command, its links reach every chapter, and its embedding snippet is the
//! library's front-page doctest (so `cargo test --doc` compiles it).

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

/// The synopsis block, split by command: each `vista CMD` entry runs to
/// the next one.
fn readme_sections() -> Vec<(String, String)> {
    let readme = include_str!("../../../docs/commands.md");
    let start = readme.find("# Command line").expect("docs/commands.md has its title");
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
                "vista {cmd}: --help has {missing:?} docs/commands.md lacks; it has {extra:?} --help lacks"
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

const README: &str = include_str!("../../../README.md");

/// `vista --help`'s commands.
fn commands() -> BTreeSet<String> {
    let out = vista_cmd::vista_cmd().arg("--help").output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let list = &text[text.find("Commands:").expect("clap lists the commands")..];
    let list = &list[..list.find("\n\n").unwrap_or(list.len())];
    list.lines()
        .skip(1)
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(String::from)
        .collect()
}

#[test]
fn the_readme_names_every_command_and_links_every_chapter() {
    let table: BTreeSet<String> =
        README.lines().filter_map(|l| l.strip_prefix("| `vista ")?.split('`').next().map(String::from)).collect();
    assert_eq!(table, commands(), "the README's command table against `vista --help`");
    let docs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs");
    let chapters: BTreeSet<String> = std::fs::read_dir(&docs)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".md"))
        .collect();
    let linked: BTreeSet<String> = README
        .match_indices("](docs/")
        .filter_map(|(i, _)| README[i + "](docs/".len()..].split(')').next().map(String::from))
        .collect();
    let pages: BTreeSet<String> = linked.iter().filter(|l| l.ends_with(".md")).cloned().collect();
    assert_eq!(pages, chapters, "the README links every chapter in docs/ and no other page");
    for l in &linked {
        assert!(docs.join(l).exists(), "the README links docs/{l}, which is missing");
    }
    assert!(README.lines().count() <= 300, "the README is {} lines", README.lines().count());
}

#[test]
fn the_readme_snippet_is_the_librarys_front_page_doctest() {
    let start = README.find("```rust\n").expect("the README has an embedding snippet") + 8;
    let snippet = &README[start..start + README[start..].find("```").unwrap()];
    let lib = include_str!("../../../src/lib.rs");
    let doc: String = lib
        .lines()
        .filter_map(|l| l.strip_prefix("//!"))
        .map(|l| format!("{}\n", l.strip_prefix(' ').unwrap_or(l)))
        .collect();
    let block = doc.find("```no_run\n").expect("src/lib.rs has the doctest") + 10;
    let doctest = &doc[block..block + doc[block..].find("```").unwrap()];
    assert_eq!(snippet, doctest, "README's snippet and src/lib.rs's doctest differ");
}
