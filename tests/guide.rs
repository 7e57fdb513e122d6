//! The snippets of the user guide (`docs/guide/src/*.md`, in `SUMMARY.md`'s order) and of
//! `README.md` are tested, so that a snippet that stops working fails here.
//!
//! Fence conventions (the guide's chapter "Extending mbgc" repeats them for writers):
//!
//! - ```` ```sh ````: commands, one per line; a trailing `\` continues a line, a line starting
//!   with `#` is a comment, and `  # ...` after a command is a comment too. Every command that
//!   starts with `mbgc ` or `cargo run --release -- ` is parsed by `mbgc_cli::Cli::try_parse_from`
//!   (the binary's own parser), in every ```` ```sh ````, ```` ```console ````, ```` ```text ````
//!   and bare fence. Placeholders (`<file>`, `[--json]`, `a|b`, `...`) are refused: snippets name
//!   real files. Other lines (`cargo test`, `apt-get ...`) are shown, not checked.
//! - ```` ```sh,run ````: also run, by the `mbgc` binary of this build, with `cargo run --release
//!   --` read as `mbgc`. Every command of such a block must be an mbgc command and must exit 0; a
//!   command with `--json` must print exactly one JSON object on standard output. The guide's
//!   blocks run in order, chapter after chapter, in one scratch directory that starts as a copy
//!   of `examples/`, `models/`, `training_data/`, `sampling/` and `docs/data/` (so a chapter may
//!   use what an earlier one made, as a reader following along would); the README's run in a
//!   scratch directory of their own. Only fast commands belong there.
//! - ```` ```toml ````: a space (it has `[parameters]`), a material (`[measured]`) or a
//!   measurement set (`[[sample]]`), read by the library's parser of that kind of file.
//!   ```` ```toml,file=NAME ```` also writes the block to `NAME` in the scratch directory, where
//!   it is when the next runnable block runs. ```` ```toml,other ```` (e.g. a Cargo.toml fragment)
//!   is only checked to be TOML.
//! - ```` ```rust ````: nothing but mdBook's include directive naming a program in `examples/`
//!   (which `cargo test` compiles), or ```` ```rust,ignore ```` whose first line is a `//`
//!   comment giving the reason.
//! - Include directives must name files that exist, every chapter file must be in `SUMMARY.md`,
//!   and relative links in the guide and the README must point at files that exist.

use std::path::{Path, PathBuf};
use std::process::Command;

use clap::Parser;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// A fenced code block of a Markdown file.
struct Block {
    file: PathBuf,
    /// 1-based line of the opening fence.
    line: usize,
    /// The language (first word of the info string), e.g. `sh`; empty for a bare fence.
    lang: String,
    /// The other comma-separated words of the info string, e.g. `run`, `file=x.toml`.
    attrs: Vec<String>,
    /// The lines inside the fence, with their 1-based line numbers, leading indentation removed.
    body: Vec<(usize, String)>,
}

impl Block {
    fn at(&self, line: usize) -> String {
        format!("{}:{line}", rel(&self.file))
    }

    fn has(&self, attr: &str) -> bool {
        self.attrs.iter().any(|a| a == attr)
    }

    fn file_attr(&self) -> Option<&str> {
        self.attrs.iter().find_map(|a| a.strip_prefix("file="))
    }

    fn text(&self) -> String {
        self.body.iter().map(|(_, l)| format!("{l}\n")).collect()
    }
}

fn rel(p: &Path) -> String {
    p.strip_prefix(ROOT).unwrap_or(p).display().to_string()
}

/// A fence line: three or more backticks and an info string without backticks (CommonMark).
fn fence(line: &str) -> Option<(usize, &str)> {
    let t = line.trim_start();
    let n = t.chars().take_while(|&c| c == '`').count();
    let info = &t[n..];
    (n >= 3 && !info.contains('`')).then_some((n, info.trim()))
}

fn blocks(file: &Path) -> Vec<Block> {
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", rel(file)));
    let mut out = Vec::new();
    let mut open: Option<(usize, Block)> = None;
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        match (&mut open, fence(line)) {
            (None, Some((ticks, info))) => {
                let mut words = info.split(',').map(|w| w.trim().to_string());
                let lang = words.next().unwrap_or_default();
                let attrs = words.filter(|w| !w.is_empty()).collect();
                let block = Block {
                    file: file.to_path_buf(),
                    line: n,
                    lang,
                    attrs,
                    body: Vec::new(),
                };
                open = Some((ticks, block));
            }
            (Some((ticks, _)), Some((closing, ""))) if closing >= *ticks => {
                out.push(open.take().unwrap().1);
            }
            (Some((_, block)), _) => block.body.push((n, line.trim().to_string())),
            (None, None) => {}
        }
    }
    assert!(
        open.is_none(),
        "{}: a code fence is never closed",
        rel(file)
    );
    out
}

/// The guide's chapters in `SUMMARY.md`'s order.
fn chapters() -> Vec<PathBuf> {
    let src = Path::new(ROOT).join("docs/guide/src");
    let summary =
        std::fs::read_to_string(src.join("SUMMARY.md")).expect("docs/guide/src/SUMMARY.md");
    let mut files: Vec<PathBuf> = Vec::new();
    for target in links(&summary) {
        let path = src.join(&target);
        assert!(
            path.is_file(),
            "SUMMARY.md lists {target}, which does not exist"
        );
        if !files.contains(&path) {
            files.push(path);
        }
    }
    assert!(
        files.len() >= 10,
        "SUMMARY.md lists only {} chapters",
        files.len()
    );
    files
}

/// The guide's chapters, then the README.
fn documents() -> Vec<PathBuf> {
    let mut docs = chapters();
    docs.push(Path::new(ROOT).join("README.md"));
    docs
}

/// Targets of the Markdown links `[text](target)` of a text.
fn links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        if let Some(j) = rest.find(')') {
            out.push(rest[..j].trim().to_string());
            rest = &rest[j..];
        }
    }
    out
}

/// The commands of a block: continuation lines joined, comments removed, a `$ ` prompt dropped.
fn commands(block: &Block) -> Vec<(usize, String)> {
    let mut out: Vec<(usize, String)> = Vec::new();
    let mut pending: Option<(usize, String)> = None;
    for (n, line) in &block.body {
        let line = line.strip_prefix("$ ").unwrap_or(line);
        let (start, mut text) = match pending.take() {
            Some((start, head)) => (start, format!("{head} {line}")),
            None if line.starts_with('#') || line.is_empty() => continue,
            None => (*n, line.to_string()),
        };
        if let Some(head) = text.strip_suffix('\\') {
            pending = Some((start, head.trim_end().to_string()));
            continue;
        }
        if let Some(i) = text.find(" #") {
            text.truncate(i);
        }
        out.push((start, text.trim().to_string()));
    }
    assert!(
        pending.is_none(),
        "{}: a command ends in `\\`",
        block.at(block.line)
    );
    out
}

/// The arguments after `mbgc` of an mbgc command, or None for another command.
fn mbgc_args(command: &str) -> Option<Vec<String>> {
    let rest = command
        .strip_prefix("mbgc ")
        .or_else(|| command.strip_prefix("cargo run --release -- "))?;
    Some(words(rest))
}

/// Shell words: split at spaces, with '...' and "..." quoting.
fn words(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut word = String::new();
    let mut quote: Option<char> = None;
    let mut in_word = false;
    for c in s.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), c) => word.push(c),
            (None, '\'' | '"') => {
                quote = Some(c);
                in_word = true;
            }
            (None, c) if c.is_whitespace() => {
                if in_word {
                    out.push(std::mem::take(&mut word));
                    in_word = false;
                }
            }
            (None, c) => {
                word.push(c);
                in_word = true;
            }
        }
    }
    assert!(quote.is_none(), "unclosed quote in `{s}`");
    if in_word {
        out.push(word);
    }
    out
}

/// Blocks whose mbgc commands are parsed: shell, console, text and bare fences.
fn is_command_block(b: &Block) -> bool {
    matches!(b.lang.as_str(), "sh" | "console" | "text" | "")
}

#[test]
fn every_command_in_the_guide_and_the_readme_parses() {
    let mut failures = Vec::new();
    let mut parsed = 0;
    for doc in documents() {
        for block in blocks(&doc).iter().filter(|b| is_command_block(b)) {
            for (line, command) in commands(block) {
                let Some(args) = mbgc_args(&command) else {
                    if block.has("run") {
                        failures.push(format!(
                            "{}: `{command}`: a runnable block holds only mbgc commands",
                            block.at(line)
                        ));
                    }
                    continue;
                };
                if let Some(p) = ["<", ">", "[", "]", "|", "..."]
                    .iter()
                    .find(|p| command.contains(*p))
                {
                    failures.push(format!(
                        "{}: `{command}`: a placeholder or shell syntax ({p}); name real files",
                        block.at(line)
                    ));
                    continue;
                }
                let argv = std::iter::once("mbgc".to_string()).chain(args);
                match mbgc_cli::Cli::try_parse_from(argv) {
                    Ok(_) => parsed += 1,
                    Err(e) => failures.push(format!("{}: `{command}`:\n{e}", block.at(line))),
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} commands fail:\n\n{}",
        failures.len(),
        failures.join("\n\n")
    );
    assert!(
        parsed >= 50,
        "only {parsed} mbgc commands found in the guide and the README"
    );
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).unwrap();
        }
    }
}

/// A scratch directory holding a copy of the data the snippets read.
fn scratch() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for d in [
        "examples",
        "models",
        "training_data",
        "sampling",
        "docs/data",
    ] {
        copy_dir(&Path::new(ROOT).join(d), &dir.path().join(d));
    }
    dir
}

/// Runs the runnable blocks of `docs` in order in `dir`; returns the failures.
fn run_blocks(docs: &[PathBuf], dir: &Path, ran: &mut usize) -> Vec<String> {
    let mut failures = Vec::new();
    for doc in docs {
        for block in blocks(doc) {
            if block.lang == "toml" {
                if let Some(name) = block.file_attr() {
                    std::fs::write(dir.join(name), block.text()).unwrap();
                }
                continue;
            }
            if !(block.lang == "sh" && block.has("run")) {
                continue;
            }
            for (line, command) in commands(&block) {
                let Some(args) = mbgc_args(&command) else {
                    continue;
                };
                let start = std::time::Instant::now();
                let out = Command::new(env!("CARGO_BIN_EXE_mbgc"))
                    .args(&args)
                    .current_dir(dir)
                    .output()
                    .expect("run mbgc");
                *ran += 1;
                eprintln!(
                    "{:6.2} s  {}: {command}",
                    start.elapsed().as_secs_f64(),
                    block.at(line)
                );
                if !out.status.success() {
                    failures.push(format!(
                        "{}: `{command}` exited with {}:\n{}",
                        block.at(line),
                        out.status,
                        String::from_utf8_lossy(&out.stderr)
                    ));
                } else if args.iter().any(|a| a == "--json") {
                    let stdout = String::from_utf8_lossy(&out.stdout);
                    let json: Result<serde_json::Value, _> = serde_json::from_str(&stdout);
                    if !json.as_ref().is_ok_and(|v| v.is_object()) {
                        failures.push(format!(
                            "{}: `{command}`: --json did not print one JSON object:\n{stdout}",
                            block.at(line)
                        ));
                    }
                }
            }
        }
    }
    failures
}

#[test]
fn the_runnable_commands_of_the_guide_and_the_readme_succeed() {
    let mut ran = 0;
    let guide = scratch();
    let mut failures = run_blocks(&chapters(), guide.path(), &mut ran);
    let readme = scratch();
    failures.extend(run_blocks(
        &[Path::new(ROOT).join("README.md")],
        readme.path(),
        &mut ran,
    ));
    assert!(
        failures.is_empty(),
        "{} commands fail:\n\n{}",
        failures.len(),
        failures.join("\n\n")
    );
    assert!(
        ran >= 30,
        "only {ran} runnable commands in the guide and the README"
    );
}

#[test]
fn every_toml_block_is_read_by_the_library() {
    let mut failures = Vec::new();
    let mut read = 0;
    for doc in documents() {
        for block in blocks(&doc).iter().filter(|b| b.lang == "toml") {
            let text = block.text();
            let source = block.at(block.line);
            let has = |header: &str| block.body.iter().any(|(_, l)| l.starts_with(header));
            // The library's errors name `source` themselves; the others get it here.
            let result: Result<(), String> = if block.has("other") {
                toml::from_str::<toml::Table>(&text)
                    .map(|_| ())
                    .map_err(|e| format!("{source}: {e}"))
            } else if has("[parameters]") {
                mbgc::space::Space::from_toml_str(&text, &source)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            } else if has("[measured]") {
                mbgc::material::Material::from_toml_str(&text, &source)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            } else if has("[[sample]]") {
                mbgc::diagnose::measurements::MeasurementSet::from_toml_str(&text, &source)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            } else {
                Err(format!(
                    "{source}: neither a space ([parameters]), a material ([measured]) nor a \
                     measurement set ([[sample]]); mark another kind of TOML `toml,other`"
                ))
            };
            match result {
                Ok(()) => read += 1,
                Err(e) => failures.push(e),
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(read >= 5, "only {read} TOML blocks found");
}

/// The include directives (`{{#include path}}`, `{{#rustdoc_include path}}`) of a text, with
/// their paths (without a `:lines` or `:anchor` suffix).
fn includes(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("{{#") {
        rest = &rest[i + 3..];
        let Some(j) = rest.find("}}") else { break };
        let directive = &rest[..j];
        let mut parts = directive.split_whitespace();
        if let (Some("include" | "rustdoc_include"), Some(path)) = (parts.next(), parts.next()) {
            out.push(path.split(':').next().unwrap().to_string());
        }
        rest = &rest[j..];
    }
    out
}

#[test]
fn every_rust_block_is_a_compiled_example_or_ignored_with_a_reason() {
    let examples = Path::new(ROOT).join("examples").canonicalize().unwrap();
    let mut failures = Vec::new();
    for doc in documents() {
        for block in blocks(&doc).iter().filter(|b| b.lang == "rust") {
            let lines: Vec<&str> = block
                .body
                .iter()
                .map(|(_, l)| l.as_str())
                .filter(|l| !l.is_empty())
                .collect();
            if block.has("ignore") {
                let reason = lines
                    .first()
                    .and_then(|l| l.strip_prefix("//"))
                    .map(str::trim);
                if reason.is_none_or(str::is_empty) {
                    failures.push(format!(
                        "{}: a `rust,ignore` block starts with a `//` comment giving the reason",
                        block.at(block.line)
                    ));
                }
                continue;
            }
            let included = includes(&lines.join("\n"));
            let only_an_include = lines.len() == 1 && included.len() == 1;
            let in_examples = included.first().is_some_and(|p| {
                doc.parent().unwrap().join(p).canonicalize().is_ok_and(|f| {
                    f.parent() == Some(examples.as_path())
                        && f.extension().is_some_and(|e| e == "rs")
                })
            });
            if !(only_an_include && in_examples) {
                failures.push(format!(
                    "{}: a `rust` block holds only an include of a program in examples/ \
                     (compiled by cargo test), or is `rust,ignore` with a reason",
                    block.at(block.line)
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn every_include_target_exists() {
    let mut failures = Vec::new();
    let mut found = 0;
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).unwrap();
        for path in includes(&text) {
            found += 1;
            if !doc.parent().unwrap().join(&path).is_file() {
                failures.push(format!(
                    "{}: includes {path}, which does not exist",
                    rel(&doc)
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        found >= 2,
        "the library chapter includes two example programs"
    );
}

#[test]
fn every_chapter_is_in_the_summary_and_every_relative_link_resolves() {
    let listed = chapters();
    let src = Path::new(ROOT).join("docs/guide/src");
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "md") && path.file_name().unwrap() != "SUMMARY.md"
        {
            assert!(
                listed.contains(&path),
                "{} is not in SUMMARY.md",
                rel(&path)
            );
        }
    }
    let mut failures = Vec::new();
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).unwrap();
        for target in links(&text) {
            if target.contains("://") || target.starts_with('#') || target.starts_with("mailto:") {
                continue;
            }
            let file = target.split('#').next().unwrap();
            if !doc.parent().unwrap().join(file).exists() {
                failures.push(format!(
                    "{}: link to {target}, which does not exist",
                    rel(&doc)
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
