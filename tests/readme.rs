//! The README's promises: it opens with the two commands a newcomer needs, and the first one
//! works; it and the guide state the Rust version `Cargo.toml` declares; and the guide's table of
//! effects is `mbgc effects`' output, so it cannot drift from the registry. (The guide's and the
//! README's other snippets are tested by `tests/guide.rs`.)

use std::process::Command;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The guide's chapter that holds the table of effects.
const EFFECTS_CHAPTER: &str = "docs/guide/src/dem-engine.md";

#[test]
fn the_guide_lists_every_effect_as_the_registry_does() {
    let chapter = std::fs::read_to_string(format!("{ROOT}/{EFFECTS_CHAPTER}")).unwrap();
    let table = mbgc_cli::effects::table();
    assert!(
        chapter.contains(&table),
        "{EFFECTS_CHAPTER}'s table of effects differs from `mbgc effects`; paste its output:\n{table}"
    );
    for e in mbgc::dem::contact::all_effects() {
        assert!(table.contains(&format!("`{}`", e.name)), "{}", e.name);
    }
}

#[test]
fn the_readme_opens_with_the_two_commands_a_newcomer_needs_and_the_first_works() {
    let readme = std::fs::read_to_string(format!("{ROOT}/README.md")).unwrap();
    let mut lines = readme.lines().skip_while(|l| !l.starts_with("```"));
    assert_eq!(lines.next(), Some("```"), "README.md: no code block");
    let block: Vec<&str> = lines.take_while(|l| !l.starts_with("```")).collect();
    assert_eq!(
        block,
        [
            "cargo run --release -- calibrate --material examples/gravel.toml",
            "cargo test --workspace"
        ],
        "README.md's first code block"
    );
    // The first command, as the binary of this build, from the repository's root (it writes
    // nothing): the shipped model calibrates the shipped material.
    let args: Vec<&str> = block[0]
        .strip_prefix("cargo run --release -- ")
        .unwrap()
        .split_whitespace()
        .collect();
    let out = Command::new(env!("CARGO_BIN_EXE_mbgc"))
        .args(&args)
        .current_dir(ROOT)
        .output()
        .expect("run mbgc");
    assert!(
        out.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("mu_pp"),
        "the calibration names the sliding friction it found"
    );
}

#[test]
fn the_readme_and_the_guide_state_the_workspace_rust_version() {
    let manifest = std::fs::read_to_string(format!("{ROOT}/Cargo.toml")).unwrap();
    let manifest: toml::Table = toml::from_str(&manifest).unwrap();
    let version = manifest["workspace"]["package"]["rust-version"]
        .as_str()
        .expect("[workspace.package] rust-version");
    for doc in ["README.md", "docs/guide/src/installation.md"] {
        let text = std::fs::read_to_string(format!("{ROOT}/{doc}")).unwrap();
        assert!(
            text.contains(&format!("{version} or newer")),
            "{doc} does not say that Rust {version} or newer is needed (Cargo.toml's rust-version)"
        );
    }
}
