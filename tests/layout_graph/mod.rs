//! The library's module graph, read from `src/` as text: every `crate::`
//! and `super::` path a file names (use lines and paths in code, braces
//! expanded) resolved to the module file it lands in, and the floor each
//! folder stands on. A light tokenizer, not a parser: strings, chars and
//! comments are blanked first, so braces and paths inside them never count.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The floors from the bottom up: a folder may import its own floor's and
/// the lower floors' folders, never a higher one (docs/architecture.md).
const FLOORS: &[&[&str]] = &[
    &["output", "shaders"],
    &["world"],
    &["error"],
    &["gpu"],
    &["frame"],
    &["terrain"],
    &["targets", "scene"],
    &["passes"],
    &["effects"],
    &["reference"],
    &["render"],
    &["bench", "stability"],
];

/// The folder a module lives in: its first segment, or `effects/<name>`
/// for an effect (each effect is a folder of its own).
pub fn folder(module: &str) -> String {
    let mut parts = module.split("::");
    let first = parts.next().unwrap_or("");
    match (first, parts.next()) {
        ("effects", Some(name)) => format!("effects/{name}"),
        _ => first.to_string(),
    }
}

/// The floor of a folder (higher stands higher); `usize::MAX` if none.
pub fn rank(folder: &str) -> usize {
    let top = folder.split('/').next().unwrap_or("");
    FLOORS.iter().position(|f| f.contains(&top)).unwrap_or(usize::MAX)
}

pub struct Graph {
    /// module path -> the modules it names
    edges: BTreeMap<String, BTreeSet<String>>,
}

impl Graph {
    pub fn read(src: &Path) -> Graph {
        let mut files = Vec::new();
        collect(src, src, &mut files);
        let modules: BTreeSet<String> = files.iter().map(|(m, _)| m.clone()).collect();
        let mut edges = BTreeMap::new();
        for (module, text) in &files {
            let mut to = BTreeSet::new();
            for path in paths(&blank(text), module) {
                if let Some(target) = resolve(&path, &modules) {
                    if &target != module && !target.is_empty() && !module.is_empty() {
                        to.insert(target);
                    }
                }
            }
            edges.insert(module.clone(), to);
        }
        Graph { edges }
    }

    pub fn modules(&self) -> usize {
        self.edges.len()
    }

    pub fn names(&self) -> impl Iterator<Item = &String> {
        self.edges.keys().filter(|m| !m.is_empty())
    }

    pub fn edges(&self) -> Vec<(&str, &str)> {
        self.edges.iter().flat_map(|(a, bs)| bs.iter().map(move |b| (a.as_str(), b.as_str()))).collect()
    }

    /// Strongly connected groups of two or more modules (Tarjan's).
    pub fn circles(&self) -> Vec<Vec<String>> {
        let names: Vec<&String> = self.edges.keys().collect();
        let index: BTreeMap<&String, usize> = names.iter().enumerate().map(|(i, n)| (*n, i)).collect();
        let adj: Vec<Vec<usize>> =
            names.iter().map(|n| self.edges[*n].iter().filter_map(|b| index.get(b).copied()).collect()).collect();
        let mut t = Tarjan { adj: &adj, index: vec![None; adj.len()], low: vec![0; adj.len()], ..Default::default() };
        for v in 0..adj.len() {
            if t.index[v].is_none() {
                t.visit(v);
            }
        }
        let mut out: Vec<Vec<String>> = t
            .groups
            .into_iter()
            .filter(|g| g.len() > 1)
            .map(|g| {
                let mut g: Vec<String> = g.into_iter().map(|i| names[i].clone()).collect();
                g.sort();
                g
            })
            .collect();
        out.sort();
        out
    }
}

#[derive(Default)]
struct Tarjan<'a> {
    adj: &'a [Vec<usize>],
    index: Vec<Option<usize>>,
    low: Vec<usize>,
    stack: Vec<usize>,
    on_stack: BTreeSet<usize>,
    next: usize,
    groups: Vec<Vec<usize>>,
}

impl Tarjan<'_> {
    fn visit(&mut self, v: usize) {
        self.index[v] = Some(self.next);
        self.low[v] = self.next;
        self.next += 1;
        self.stack.push(v);
        self.on_stack.insert(v);
        for &w in &self.adj[v] {
            match self.index[w] {
                None => {
                    self.visit(w);
                    self.low[v] = self.low[v].min(self.low[w]);
                }
                Some(iw) if self.on_stack.contains(&w) => self.low[v] = self.low[v].min(iw),
                _ => {}
            }
        }
        if Some(self.low[v]) == self.index[v] {
            let mut group = Vec::new();
            while let Some(w) = self.stack.pop() {
                self.on_stack.remove(&w);
                group.push(w);
                if w == v {
                    break;
                }
            }
            self.groups.push(group);
        }
    }
}

/// (module path, text) of every `.rs` file under `src/`.
fn collect(src: &Path, dir: &Path, out: &mut Vec<(String, String)>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            collect(src, &p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            let rel = p.strip_prefix(src).unwrap().with_extension("");
            let mut parts: Vec<String> = rel.iter().map(|s| s.to_string_lossy().into_owned()).collect();
            if matches!(parts.last().map(String::as_str), Some("mod" | "lib")) {
                parts.pop();
            }
            out.push((parts.join("::"), std::fs::read_to_string(&p).unwrap()));
        }
    }
}

/// The deepest module a path lands in (`a::b::Thing` -> `a::b`).
fn resolve(path: &[String], modules: &BTreeSet<String>) -> Option<String> {
    (1..=path.len()).rev().map(|n| path[..n].join("::")).find(|m| modules.contains(m))
}

/// Every path from `crate::` or `super::` the text names, as segments
/// from the crate root, braces expanded.
fn paths(text: &str, module: &str) -> Vec<Vec<String>> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let rest = &text[i..];
        let boundary =
            i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_' || bytes[i - 1] == b':');
        let base: Option<(Vec<String>, usize)> = if boundary && rest.starts_with("crate::") {
            Some((Vec::new(), 7))
        } else if boundary && rest.starts_with("super::") {
            let mut base: Vec<String> = module.split("::").filter(|s| !s.is_empty()).map(String::from).collect();
            let mut n = 0;
            while text[i + n..].starts_with("super::") {
                base.pop();
                n += 7;
            }
            Some((base, n))
        } else {
            None
        };
        match base {
            Some((base, skip)) => {
                let mut j = i + skip;
                tree(text, &mut j, base, &mut out);
                i = j.max(i + 1);
            }
            None => i += 1,
        }
    }
    out
}

/// Parses a use tree at `*j` (`a::b`, `a::{b, c::d}`, `a::*`), pushing
/// each full path.
fn tree(text: &str, j: &mut usize, mut prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
    let bytes = text.as_bytes();
    loop {
        while *j < bytes.len() && bytes[*j].is_ascii_whitespace() {
            *j += 1;
        }
        if *j < bytes.len() && bytes[*j] == b'{' {
            *j += 1;
            loop {
                while *j < bytes.len() && (bytes[*j].is_ascii_whitespace() || bytes[*j] == b',') {
                    *j += 1;
                }
                if *j >= bytes.len() || bytes[*j] == b'}' {
                    *j += 1;
                    return;
                }
                let before = *j;
                tree(text, j, prefix.clone(), out);
                if *j == before {
                    *j += 1;
                }
            }
        }
        let start = *j;
        while *j < bytes.len() && (bytes[*j].is_ascii_alphanumeric() || bytes[*j] == b'_') {
            *j += 1;
        }
        if *j > start && &text[start..*j] != "self" {
            prefix.push(text[start..*j].to_string());
        }
        if text[*j..].starts_with("::") {
            *j += 2;
        } else {
            out.push(prefix);
            return;
        }
    }
}

/// The text with comments, strings and char literals blanked (kept the
/// same length, newlines kept), so braces and paths in them never count.
pub fn blank(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = b.to_vec();
    let mut i = 0;
    let wipe = |out: &mut Vec<u8>, from: usize, to: usize| {
        for c in &mut out[from..to.min(b.len())] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    };
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            let end = text[i..].find('\n').map_or(b.len(), |n| i + n);
            wipe(&mut out, i, end);
            i = end;
        } else if b[i..].starts_with(b"/*") {
            let end = text[i + 2..].find("*/").map_or(b.len(), |n| i + 2 + n + 2);
            wipe(&mut out, i, end);
            i = end;
        } else if b[i] == b'r' && (b[i + 1..].starts_with(b"\"") || b[i + 1..].starts_with(b"#\"")) {
            let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
            let close = format!("\"{}", "#".repeat(hashes));
            let body = i + 2 + hashes;
            let end = text[body..].find(&close).map_or(b.len(), |n| body + n + close.len());
            wipe(&mut out, i, end);
            i = end;
        } else if b[i] == b'"' {
            let mut k = i + 1;
            while k < b.len() && b[k] != b'"' {
                k += if b[k] == b'\\' { 2 } else { 1 };
            }
            wipe(&mut out, i, k + 1);
            i = k + 1;
        } else if b[i] == b'\'' && char_literal_len(&b[i..]) > 0 {
            let n = char_literal_len(&b[i..]);
            wipe(&mut out, i, i + n);
            i += n;
        } else {
            i += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Length of a char literal at the start of `b` (`'x'`, `'\n'`, `'{'`),
/// 0 for a lifetime.
fn char_literal_len(b: &[u8]) -> usize {
    if b.len() >= 4 && b[1] == b'\\' {
        return b[2..].iter().position(|&c| c == b'\'').map_or(0, |n| n + 3);
    }
    if b.len() >= 3 && b[2] == b'\'' {
        return 3;
    }
    // a multi-byte UTF-8 char
    let n = b.iter().skip(1).position(|&c| c == b'\'').unwrap_or(usize::MAX);
    if (2..=4).contains(&n) && b[1] >= 0x80 {
        n + 2
    } else {
        0
    }
}

/// (name, first line, length in lines) of every `fn` with a body.
pub fn functions(text: &str) -> Vec<(String, usize, usize)> {
    let clean = blank(text);
    let b = clean.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(n) = clean[i..].find("fn ") {
        let at = i + n;
        i = at + 3;
        if at > 0 && (b[at - 1].is_ascii_alphanumeric() || b[at - 1] == b'_') {
            continue;
        }
        let name: String = clean[at + 3..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        if name.is_empty() {
            continue;
        }
        // the body opens at the first `{` before any `;` (a declaration)
        let Some(open) = clean[at..].find(['{', ';']).map(|k| at + k) else { break };
        if b[open] == b';' {
            continue;
        }
        let mut depth = 0;
        let mut close = open;
        for (k, &c) in b[open..].iter().enumerate() {
            depth += (c == b'{') as i32 - (c == b'}') as i32;
            if depth == 0 {
                close = open + k;
                break;
            }
        }
        let first = clean[..at].matches('\n').count() + 1;
        let last = clean[..close].matches('\n').count() + 1;
        out.push((name, first, last - first + 1));
    }
    out
}
