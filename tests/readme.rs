//! The README's table of effects is `mbgc effects`' output, so it cannot drift from the registry.

#[test]
fn the_readme_lists_every_effect_as_the_registry_does() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let table = mbgc::cli::effects::table();
    assert!(
        readme.contains(&table),
        "README.md's table of effects differs from `mbgc effects`; paste its output:\n{table}"
    );
    for e in mbgc::dem::contact::all_effects() {
        assert!(table.contains(&format!("`{}`", e.name)), "{}", e.name);
    }
}
