//! The source layout's rules, checked on the tree itself so they cannot quietly erode:
//!
//! 1. In every crate of the workspace, no two files import each other, directly or through a
//!    longer cycle (a `mod.rs` that re-exports a child counts as importing it): a concept two
//!    files need gets a file of its own.
//! 2. No two top-level modules of a crate import each other either (`experiments -> psd ->
//!    sampling -> experiments` would be a cycle of modules made of acyclic files).
//! 3. The crates are the layering: the library crates never depend on clap or indicatif (the
//!    command line's), and only the command line depends on the studies.
//!
//! Imports are read from the source text: `use` trees and inline paths (`crate::a::b`,
//! `super::x`, `child::y`), outside comments, string literals and the `#[cfg(test)]` module at
//! the end of a file. Each path counts as an edge to the longest module prefix that is a file.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Module = Vec<String>;

fn source_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            source_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// `src/a/b.rs` -> [a, b]; `src/a/mod.rs` -> [a]; `src/lib.rs` and `src/main.rs` -> [].
fn module_of(src: &Path, file: &Path) -> Module {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut m: Module = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(m.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        m.pop();
    }
    m
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Ident(String),
    Sep,
    Open,
    Close,
    Comma,
    Semi,
    Dot,
    Other,
}

/// Tokens of Rust source with comments and literals dropped; the `#[cfg(test)] mod` at the end
/// of a file is cut off (tests may import anything).
fn tokens(text: &str) -> Vec<Tok> {
    let text = match text.find("#[cfg(test)]\nmod ") {
        Some(i) => &text[..i],
        None => text,
    };
    let c: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && c.get(i + 1) == Some(&'*') {
            i += 2;
            while i + 1 < c.len() && !(c[i] == '*' && c[i + 1] == '/') {
                i += 1;
            }
            i += 2;
        } else if ch == 'r' && (c.get(i + 1) == Some(&'"') || c.get(i + 1) == Some(&'#')) {
            // Raw string r"..." or r#"..."#.
            let mut j = i + 1;
            let mut hashes = 0;
            while c.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if c.get(j) != Some(&'"') {
                out.push(Tok::Ident("r".into()));
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= c.len() {
                    break;
                }
                if c[j] == '"' && (0..hashes).all(|k| c.get(j + 1 + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            i = j;
            out.push(Tok::Other);
        } else if ch == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
            out.push(Tok::Other);
        } else if ch == '\'' {
            // A char literal ('x', '\n') or a lifetime ('a).
            if c.get(i + 1) == Some(&'\\') {
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                i += 1;
            }
            out.push(Tok::Other);
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push(Tok::Ident(c[start..i].iter().collect()));
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch == ':' && c.get(i + 1) == Some(&':') {
            out.push(Tok::Sep);
            i += 2;
        } else {
            out.push(match ch {
                '{' => Tok::Open,
                '}' => Tok::Close,
                ',' => Tok::Comma,
                ';' => Tok::Semi,
                '.' => Tok::Dot,
                _ => Tok::Other,
            });
            i += 1;
        }
    }
    out
}

/// Expands a `use` tree starting at `t[*i]` (after `use`) into full paths, each with the name
/// it binds in the file (its last segment, or the `as` alias).
fn use_tree(t: &[Tok], i: &mut usize, prefix: &[String], out: &mut Vec<(Vec<String>, String)>) {
    let mut path = prefix.to_vec();
    let bind = |path: &Vec<String>| path.last().cloned().unwrap_or_default();
    loop {
        match t.get(*i) {
            Some(Tok::Ident(s)) if s == "as" => {
                let alias = match t.get(*i + 1) {
                    Some(Tok::Ident(a)) => a.clone(),
                    _ => bind(&path),
                };
                *i += 2;
                out.push((path, alias));
                return;
            }
            Some(Tok::Ident(s)) => {
                if s != "self" || path.is_empty() {
                    path.push(s.clone());
                }
                *i += 1;
            }
            Some(Tok::Sep) => *i += 1,
            Some(Tok::Open) => {
                *i += 1;
                loop {
                    use_tree(t, i, &path, out);
                    match t.get(*i) {
                        Some(Tok::Comma) => *i += 1,
                        Some(Tok::Close) => {
                            *i += 1;
                            return;
                        }
                        _ => return,
                    }
                    if t.get(*i) == Some(&Tok::Close) {
                        *i += 1;
                        return;
                    }
                }
            }
            _ => {
                let name = bind(&path);
                out.push((path, name));
                return;
            }
        }
    }
}

/// Every path the file names: `use` trees, and inline `a::b::c` chains with a first segment
/// that a `use` brought in expanded to its full path (`use crate::dem; dem::sim::f()` names
/// `crate::dem::sim`).
fn paths(t: &[Tok]) -> Vec<Vec<String>> {
    let mut uses = Vec::new();
    let mut chains = Vec::new();
    let mut i = 0;
    while i < t.len() {
        if let Tok::Ident(s) = &t[i] {
            if s == "use" {
                i += 1;
                use_tree(t, &mut i, &[], &mut uses);
                continue;
            }
            // Not after `::` (inside a chain) or `.` (a method call such as `x.parse::<f64>()`).
            let starts = i == 0 || !matches!(t[i - 1], Tok::Sep | Tok::Dot);
            if t.get(i + 1) == Some(&Tok::Sep) && starts {
                let mut p = vec![s.clone()];
                let mut j = i + 1;
                while t.get(j) == Some(&Tok::Sep) {
                    match t.get(j + 1) {
                        Some(Tok::Ident(n)) => {
                            p.push(n.clone());
                            j += 2;
                        }
                        _ => break,
                    }
                }
                chains.push(p);
                i = j;
                continue;
            }
        }
        i += 1;
    }
    let imported: std::collections::HashMap<String, Vec<String>> = uses
        .iter()
        .filter(|(p, name)| {
            !name.is_empty() && !["crate", "self", "super"].contains(&name.as_str()) && p.len() > 1
        })
        .map(|(p, name)| (name.clone(), p.clone()))
        .collect();
    let mut out: Vec<Vec<String>> = uses.into_iter().map(|(p, _)| p).collect();
    for c in chains {
        match imported.get(&c[0]) {
            Some(full) => out.push(full.iter().chain(&c[1..]).cloned().collect()),
            None => out.push(c),
        }
    }
    out
}

/// The file module a path in module `m` refers to, if it is one of the crate's files.
fn resolve(m: &Module, path: &[String], files: &BTreeSet<Module>) -> Option<Module> {
    let (first, rest) = path.split_first()?;
    let mut base: Module = match first.as_str() {
        "crate" => Vec::new(),
        "self" => m.clone(),
        "super" => m[..m.len().saturating_sub(1)].to_vec(),
        child if files.contains(&[m.as_slice(), &[child.to_string()]].concat()) => {
            let mut b = m.clone();
            b.push(child.to_string());
            b
        }
        _ => return None,
    };
    let mut rest = rest;
    while rest.first().map(String::as_str) == Some("super") {
        base.pop();
        rest = &rest[1..];
    }
    let full: Module = base.iter().chain(rest).cloned().collect();
    (0..=full.len())
        .rev()
        .map(|k| full[..k].to_vec())
        .find(|p| files.contains(p))
        .filter(|p| !p.is_empty() && p != m)
}

/// The workspace's crates: the command line at the root, the libraries under `crates/`.
const CRATES: [&str; 6] = [
    ".",
    "crates/mbgc-dem",
    "crates/mbgc-sr",
    "crates/mbgc",
    "crates/mbgc-output",
    "crates/mbgc-studies",
];

fn graph(krate: &str) -> BTreeMap<Module, BTreeSet<Module>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(krate)
        .join("src");
    let mut list = Vec::new();
    source_files(&src, &mut list);
    let files: BTreeSet<Module> = list.iter().map(|f| module_of(&src, f)).collect();
    let mut g = BTreeMap::new();
    for f in &list {
        let m = module_of(&src, f);
        let text = std::fs::read_to_string(f).unwrap();
        let edges: BTreeSet<Module> = paths(&tokens(&text))
            .iter()
            .filter_map(|p| resolve(&m, p, &files))
            .collect();
        g.entry(m).or_insert_with(BTreeSet::new).extend(edges);
    }
    g
}

/// Strongly connected components with more than one module (Tarjan).
fn cycles(g: &BTreeMap<Module, BTreeSet<Module>>) -> Vec<Vec<Module>> {
    struct State<'a> {
        g: &'a BTreeMap<Module, BTreeSet<Module>>,
        index: BTreeMap<&'a Module, usize>,
        low: BTreeMap<&'a Module, usize>,
        stack: Vec<&'a Module>,
        on: BTreeSet<&'a Module>,
        out: Vec<Vec<Module>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a Module) {
        let n = s.index.len();
        s.index.insert(v, n);
        s.low.insert(v, n);
        s.stack.push(v);
        s.on.insert(v);
        let g = s.g;
        for w in g.get(v).into_iter().flatten() {
            let Some((w, _)) = g.get_key_value(w) else {
                continue;
            };
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.on.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on.remove(w);
                comp.push(w.clone());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                s.out.push(comp);
            }
        }
    }
    let mut s = State {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in g.keys() {
        if !s.index.contains_key(v) {
            visit(&mut s, v);
        }
    }
    s.out
}

fn name(m: &Module) -> String {
    m.join("/")
}

fn describe(g: &BTreeMap<Module, BTreeSet<Module>>, cycles: &[Vec<Module>]) -> Vec<String> {
    cycles
        .iter()
        .map(|c| {
            let members: BTreeSet<&Module> = c.iter().collect();
            let edges: Vec<String> = c
                .iter()
                .flat_map(|a| {
                    g[a].iter()
                        .filter(|b| members.contains(b))
                        .map(move |b| format!("{} -> {}", name(a), name(b)))
                })
                .collect();
            edges.join(", ")
        })
        .collect()
}

#[test]
fn no_two_files_import_each_other() {
    let mut found = Vec::new();
    let mut modules = 0;
    for krate in CRATES {
        let g = graph(krate);
        modules += g.len();
        found.extend(
            describe(&g, &cycles(&g))
                .into_iter()
                .map(|c| format!("{krate}: {c}")),
        );
    }
    assert!(modules > 150, "only {modules} modules found");
    assert!(found.is_empty(), "import cycles:\n{}", found.join("\n"));
}

#[test]
fn no_two_top_level_modules_import_each_other() {
    let mut found = Vec::new();
    for krate in CRATES {
        let mut top: BTreeMap<Module, BTreeSet<Module>> = BTreeMap::new();
        for (m, to) in graph(krate) {
            let Some(first) = m.first() else { continue };
            let from = vec![first.clone()];
            let entry = top.entry(from.clone()).or_default();
            entry.extend(
                to.iter()
                    .filter_map(|t| t.first())
                    .map(|t| vec![t.clone()])
                    .filter(|t| *t != from),
            );
        }
        found.extend(
            describe(&top, &cycles(&top))
                .into_iter()
                .map(|c| format!("{krate}: {c}")),
        );
    }
    assert!(found.is_empty(), "module cycles:\n{}", found.join("\n"));
}

/// The `[dependencies]` table of a crate's manifest, as text.
fn dependencies(krate: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(krate)
        .join("Cargo.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let start = text
        .find("\n[dependencies]")
        .expect("a [dependencies] table");
    let rest = &text[start + 1..];
    let end = rest[1..].find("\n[").map_or(rest.len(), |k| k + 1);
    rest[..end].to_string()
}

#[test]
fn the_library_crates_know_no_command_line_and_no_study() {
    for krate in [
        "crates/mbgc-dem",
        "crates/mbgc-sr",
        "crates/mbgc",
        "crates/mbgc-output",
    ] {
        let deps = dependencies(krate);
        for name in [
            "clap",
            "indicatif",
            "mbgc-studies",
            "mbgc-cli",
            "mbgc-output",
        ] {
            let uses = deps
                .lines()
                .any(|l| l.split(['.', ' ', '=']).next() == Some(name));
            assert!(!uses, "{krate} depends on {name}");
        }
    }
    // The studies take clap only behind their `cli` feature, which the command line switches on.
    let studies = dependencies("crates/mbgc-studies");
    let clap = studies
        .lines()
        .find(|l| l.starts_with("clap"))
        .expect("clap");
    assert!(clap.contains("optional = true"), "{clap}");
    assert!(!studies.lines().any(|l| l.starts_with("indicatif")));
}

#[test]
fn the_checker_sees_cycles_and_nested_use_trees() {
    // A synthetic crate: a/mod.rs re-exports its child b, which imports a::c via super, and
    // c imports b back through a nested use tree.
    let files: BTreeSet<Module> = [vec![], vec!["a"], vec!["a", "b"], vec!["a", "c"]]
        .into_iter()
        .map(|m| m.into_iter().map(String::from).collect())
        .collect();
    let m = |s: &[&str]| -> Module { s.iter().map(|x| x.to_string()).collect() };
    let edges = |module: &Module, text: &str| -> BTreeSet<Module> {
        paths(&tokens(text))
            .iter()
            .filter_map(|p| resolve(module, p, &files))
            .collect()
    };
    let a = edges(&m(&["a"]), "pub mod b;\npub use b::Thing;\n");
    assert_eq!(a, [m(&["a", "b"])].into());
    let b = edges(
        &m(&["a", "b"]),
        "// use crate::a::c; in a comment\nlet s = \"crate::a::c\";\nuse super::c::X;",
    );
    assert_eq!(b, [m(&["a", "c"])].into());
    let c = edges(
        &m(&["a", "c"]),
        "use crate::{a::{b::{self, Y}, c::Z}, error};\n#[cfg(test)]\nmod tests { use super::super::b; }",
    );
    assert_eq!(c, [m(&["a", "b"])].into());
    // A module brought in by `use` (or under an alias) and then used by an inline path.
    let via_use = edges(
        &m(&["a"]),
        "use crate::a as top;\nfn f() { top::c::g(); let n = x.c::<u8>(); }",
    );
    assert_eq!(via_use, [m(&["a", "c"])].into());
    let mut g = BTreeMap::new();
    g.insert(m(&["a", "b"]), b);
    g.insert(m(&["a", "c"]), c);
    g.insert(m(&["a"]), a);
    let found = cycles(&g);
    assert_eq!(found.len(), 1);
    assert_eq!(found[0].len(), 2);
}
