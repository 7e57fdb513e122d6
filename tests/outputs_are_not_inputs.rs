//! No command writes a figure, a report or a result over one of its inputs, whatever the
//! spelling (a symlink, `..`), and inputs reached through a material file (its sieve analysis)
//! count as inputs. Each refusal must leave the input byte for byte as it was.

mod common;

use std::path::Path;

use common::{fails, s};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Copies the example material and its sieve file into `dir`.
fn gravel(dir: &Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let material = dir.join("gravel.toml");
    let sieve = dir.join("sieve_gravel_8_16.csv");
    std::fs::copy(root().join("examples/gravel.toml"), &material).unwrap();
    std::fs::copy(root().join("examples/sieve_gravel_8_16.csv"), &sieve).unwrap();
    (material, sieve)
}

fn unchanged(path: &Path, before: &[u8]) {
    assert_eq!(
        std::fs::read(path).unwrap(),
        before,
        "{} changed",
        path.display()
    );
}

#[test]
fn psd_fit_never_draws_over_its_sieve_file() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("s.svg");
    std::fs::copy(root().join("examples/sieve_gravel_8_16.csv"), &data).unwrap();
    let before = std::fs::read(&data).unwrap();
    let e = fails(&["psd", "fit", s(&data), "--plot", s(&data)]);
    assert!(
        e.contains("--plot") && e.contains("never overwrites"),
        "{e}"
    );
    let link = dir.path().join("link.svg");
    std::os::unix::fs::symlink(&data, &link).unwrap();
    fails(&["psd", "fit", s(&data), "--plot", s(&link)]);
    // A hard link is the same file under another name.
    let hard = dir.path().join("hard.svg");
    std::fs::hard_link(&data, &hard).unwrap();
    let e = fails(&["psd", "fit", s(&data), "--plot", s(&hard)]);
    assert!(e.contains("never overwrites"), "{e}");
    unchanged(&data, &before);
}

/// A figure is drawn beside its target and renamed over it, so that even a path no check knows
/// as an input (a hard link made to some other file) is replaced, not written through.
#[test]
fn a_figure_replaces_its_target_instead_of_writing_through_it() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("s.csv");
    std::fs::copy(root().join("examples/sieve_gravel_8_16.csv"), &data).unwrap();
    let keep = dir.path().join("keep.txt");
    std::fs::write(&keep, "not a figure\n").unwrap();
    let plot = dir.path().join("plot.svg");
    std::fs::hard_link(&keep, &plot).unwrap();
    common::ok(&["psd", "fit", s(&data), "--plot", s(&plot)]);
    unchanged(&keep, b"not a figure\n");
    assert!(std::fs::read_to_string(&plot).unwrap().contains("<svg"));
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp."))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

#[test]
fn validate_never_draws_over_its_parameters_or_its_material() {
    let dir = tempfile::tempdir().unwrap();
    let (material, sieve) = gravel(dir.path());
    let params = dir.path().join("params.svg");
    std::fs::write(&params, "[parameters]\nmu_pp = 0.3\n").unwrap();
    let link = dir.path().join("m.svg");
    std::os::unix::fs::symlink(&material, &link).unwrap();
    let sieve_link = dir.path().join("sieve.svg");
    std::os::unix::fs::symlink(&sieve, &sieve_link).unwrap();
    let saved: Vec<(&Path, Vec<u8>)> = [params.as_path(), &material, &sieve]
        .into_iter()
        .map(|p| (p, std::fs::read(p).unwrap()))
        .collect();
    for picture in [&params, &link, &sieve_link] {
        let e = fails(&[
            "validate",
            "--material",
            s(&material),
            "--params",
            s(&params),
            "--picture",
            s(picture),
        ]);
        assert!(
            e.contains("--picture") && e.contains("never overwrites"),
            "{e}"
        );
    }
    for (p, b) in saved {
        unchanged(p, &b);
    }
}

#[test]
fn calibrate_never_writes_over_the_sieve_file_its_material_names() {
    let dir = tempfile::tempdir().unwrap();
    let (material, sieve) = gravel(dir.path());
    let before = std::fs::read(&sieve).unwrap();
    let e = fails(&["calibrate", "--material", s(&material), "--out", s(&sieve)]);
    assert!(e.contains("the sieve analysis of"), "{e}");
    // A figure directory whose figure would land on an input: a sieve file that has the name
    // of the posterior figure of the model `shear_box`.
    let figure_named = dir.path().join("shear_box_posterior.svg");
    std::fs::copy(&sieve, &figure_named).unwrap();
    let text = std::fs::read_to_string(&material)
        .unwrap()
        .replace("sieve_gravel_8_16.csv", "shear_box_posterior.svg");
    std::fs::write(&material, text).unwrap();
    let e = fails(&[
        "calibrate",
        "--material",
        s(&material),
        "--plot",
        s(dir.path()),
    ]);
    assert!(
        e.contains("--plot") && e.contains("the sieve analysis of"),
        "{e}"
    );
    unchanged(&figure_named, &before);
    unchanged(&sieve, &before);
}

#[test]
fn a_bench_report_never_replaces_its_data() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("hop.csv");
    std::fs::copy(
        root().join("docs/data/sensitivity/seed000_hopper.csv"),
        &data,
    )
    .unwrap();
    let before = std::fs::read(&data).unwrap();
    let e = fails(&[
        "bench",
        "sensitivity",
        "--data",
        s(&data),
        "--report",
        s(&data),
    ]);
    assert!(
        e.contains("--report") && e.contains("never overwrites"),
        "{e}"
    );
    unchanged(&data, &before);
    // The model it reads is an input too, and so is an input in the folder of figures.
    let model = dir.path().join("m.json");
    std::fs::copy(root().join("models/shear_box.json"), &model).unwrap();
    let model_before = std::fs::read(&model).unwrap();
    let e = fails(&[
        "bench",
        "sensitivity",
        "--data",
        s(&data),
        "--model",
        s(&model),
        "--report",
        s(&model),
        "--figures",
        s(&dir.path().join("figs")),
    ]);
    assert!(e.contains("--report") && e.contains("--model"), "{e}");
    let svg_data = dir.path().join("exponents.svg");
    std::fs::copy(&data, &svg_data).unwrap();
    let e = fails(&[
        "bench",
        "sensitivity",
        "--data",
        s(&svg_data),
        "--report",
        s(&dir.path().join("r.md")),
        "--figures",
        s(dir.path()),
    ]);
    assert!(e.contains("--figures") && e.contains("--data"), "{e}");
    unchanged(&svg_data, &before);
    unchanged(&model, &model_before);
}
