//! The parsers of every user file under arbitrary and mutated input: each must return a value
//! or an error naming the file, never panic. A fixed budget of cases per parser (proptest with a
//! fixed seed, so a failure reproduces).

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::path::Path;

use mbgc::material::Material;
use mbgc::metamodel::Metamodel;
use mbgc::psd::sieve::SieveData;
use mbgc::sampling::Design;
use mbgc::space::Space;

const CASES: u32 = 2000;

fn runner() -> TestRunner {
    TestRunner::new_with_rng(
        Config {
            cases: CASES,
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]),
    )
}

/// A valid text with a few characters replaced, inserted or deleted: close enough to the format
/// to reach deep into the parser.
fn mutated(valid: &'static str) -> impl Strategy<Value = String> {
    let edits = prop::collection::vec((any::<prop::sample::Index>(), 0u8..3, any::<char>()), 1..6);
    edits.prop_map(move |edits| {
        let mut c: Vec<char> = valid.chars().collect();
        for (at, kind, ch) in edits {
            let i = at.index(c.len().max(1));
            match kind {
                0 if !c.is_empty() => {
                    let last = c.len() - 1;
                    c[i.min(last)] = ch;
                }
                1 => c.insert(i.min(c.len()), ch),
                _ if !c.is_empty() => {
                    c.remove(i.min(c.len() - 1));
                }
                _ => {}
            }
        }
        c.into_iter().collect()
    })
}

/// Arbitrary text drawn from the characters the formats use, plus anything.
fn texts(valid: &'static str) -> impl Strategy<Value = String> {
    prop_oneof![
        mutated(valid),
        "[\\[\\]{}=,.\"a-z_0-9 \\n+\\-*<>#e]{0,200}",
        any::<String>(),
    ]
}

/// Writes `text` to a file and parses it with `parse`; a panic fails the property.
fn no_panic_on_file(ext: &str, text: &str, parse: impl Fn(&Path)) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join(format!("input.{ext}"));
    std::fs::write(&p, text).unwrap();
    parse(&p);
}

const SPACE: &str = "name = \"s\"\n[parameters]\nE_p = { unit = \"Pa\", min = 5e6, max = 5e8, scale = \"log\" }\nmu_pp = { min = 0.0, max = 1.0, fixed = 0.5 }\n";
const MATERIAL: &str = "name = \"g\"\n[psd]\nd50_mm = 11.2\nsigma_ln = 0.26\n[measured]\nshear_angle = { value = 35.5, sd = 0.5 }\n[fixed]\ne_pp = 0.6\n[bounds]\nrho_p = [2500, 2800]\n[constraints]\nexpr = [\"e_pw <= e_pp\", \"mu_pp + 0.5*mu_r_pp >= 3e-1\"]\n";
const DESIGN: &str = "E_p,mu_pp\n1e7,0.5\n2e8,0.5\n";
const SIEVE: &str = "size_mm,passing_pct\n4,0\n8,5\n11.2,55\n16,97\n22.4,100\n";

#[test]
fn space_files_never_panic() {
    runner()
        .run(&texts(SPACE), |t| {
            let _ = Space::from_toml_str(&t, "s.toml");
            Ok(())
        })
        .unwrap();
}

#[test]
fn material_files_and_constraints_never_panic() {
    runner()
        .run(&texts(MATERIAL), |t| {
            let _ = Material::from_toml_str(&t, "m.toml");
            Ok(())
        })
        .unwrap();
    // Constraint expressions on their own.
    let exprs = prop_oneof![
        mutated("mu_pp + 0.5*mu_r_pp >= 3e-1"),
        "[a-z_0-9.eE+\\-* <>=]{0,40}",
    ];
    runner()
        .run(&exprs, |e| {
            let text = format!(
                "[measured]\ny = {{ value = 1, sd = 0.1 }}\n[constraints]\nexpr = [{e:?}]\n"
            );
            let _ = Material::from_toml_str(&text, "m.toml");
            Ok(())
        })
        .unwrap();
}

#[test]
fn design_and_sieve_csvs_never_panic() {
    let space = Space::from_toml_str(SPACE, "s.toml").unwrap();
    runner()
        .run(&texts(DESIGN), |t| {
            no_panic_on_file("csv", &t, |p| {
                let _ = Design::read(p, Some(&space));
                let _ = Design::read(p, None);
            });
            Ok(())
        })
        .unwrap();
    runner()
        .run(&texts(SIEVE), |t| {
            no_panic_on_file("csv", &t, |p| {
                let _ = SieveData::read(p);
            });
            Ok(())
        })
        .unwrap();
}

#[test]
fn model_files_never_panic() {
    // A real model file as the seed of the mutations.
    let model: &'static str = Box::leak(
        std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/tiny_model.json"),
        )
        .unwrap()
        .into_boxed_str(),
    );
    runner()
        .run(&texts(model), |t| {
            no_panic_on_file("json", &t, |p| {
                if let Ok(m) = Metamodel::load(p) {
                    // A model that loads must also evaluate and export without panicking.
                    let x: Vec<Vec<f64>> = m.inputs.iter().map(|_| vec![0.5]).collect();
                    for r in &m.responses {
                        let _ = m.predict(r, &x);
                    }
                    for f in [
                        mbgc::export::Format::Rust,
                        mbgc::export::Format::Latex,
                        mbgc::export::Format::Sympy,
                    ] {
                        let _ = mbgc::export::export(&m, f);
                    }
                }
            });
            Ok(())
        })
        .unwrap();
}
