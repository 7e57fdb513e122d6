//! The command-line contract scripts rely on: no command writes over one of its own inputs,
//! whatever the spelling of the path, and the input is left byte for byte as it was.

mod common;

use common::{fails, ok, s};
use std::path::{Path, PathBuf};

/// A small table (y = 2 x + z) and a quickly fitted model of it.
fn table_and_model(dir: &Path) -> (PathBuf, PathBuf) {
    let mut csv = String::from("x,z,y\n");
    for i in 0..40 {
        let (x, z) = (i as f64 / 40.0, ((i * 7) % 40) as f64 / 40.0);
        csv.push_str(&format!("{x},{z},{}\n", 2.0 * x + z));
    }
    let data = dir.join("train.csv");
    std::fs::write(&data, csv).unwrap();
    let model = dir.join("model.json");
    ok(&[
        "fit",
        "--data",
        s(&data),
        "--inputs",
        "x,z",
        "--targets",
        "y",
        "--out",
        s(&model),
        "--population",
        "200",
        "--generations",
        "3",
    ]);
    (data, model)
}

/// Runs `args`, which must fail naming `option`, and checks that `input` is unchanged.
fn refused(args: &[&str], option: &str, input: &Path) {
    let before = std::fs::read(input).unwrap();
    let e = fails(args);
    assert!(
        e.contains(option) && e.contains("never overwrites its own input"),
        "{args:?}: {e}"
    );
    assert_eq!(
        std::fs::read(input).unwrap(),
        before,
        "{args:?} changed its input"
    );
}

#[test]
fn no_command_overwrites_its_own_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (data, model) = table_and_model(d);
    // Another spelling of the same file must not slip through.
    std::fs::create_dir(d.join("sub")).unwrap();
    let data_alias = d.join("sub").join("..").join("train.csv");

    refused(
        &[
            "fit",
            "--data",
            s(&data),
            "--inputs",
            "x,z",
            "--targets",
            "y",
            "--out",
            s(&data_alias),
        ],
        "--data",
        &data,
    );
    refused(
        &[
            "predict",
            "--model",
            s(&model),
            "--data",
            s(&data),
            "--out",
            s(&data),
        ],
        "--data",
        &data,
    );
    refused(
        &[
            "predict",
            "--model",
            s(&model),
            "--data",
            s(&data),
            "--out",
            s(&model),
        ],
        "--model",
        &model,
    );
    refused(
        &[
            "export",
            "--model",
            s(&model),
            "--format",
            "rust",
            "--out",
            s(&model),
        ],
        "--model",
        &model,
    );

    let space = d.join("space.toml");
    std::fs::write(
        &space,
        "[parameters]\nx = { min = 0.0, max = 1.0 }\nz = { min = 0.0, max = 1.0 }\n",
    )
    .unwrap();
    refused(
        &[
            "sample",
            "--method",
            "sobol",
            "--n",
            "8",
            "--space",
            s(&space),
            "--seed",
            "1",
            "--out",
            s(&space),
        ],
        "--space",
        &space,
    );
    let design = d.join("design.csv");
    ok(&[
        "sample",
        "--method",
        "sobol",
        "--n",
        "8",
        "--space",
        s(&space),
        "--seed",
        "1",
        "--out",
        s(&design),
    ]);
    refused(
        &[
            "sample",
            "--method",
            "sobol",
            "--n",
            "4",
            "--space",
            s(&space),
            "--seed",
            "1",
            "--extend",
            s(&design),
            "--out",
            s(&design),
        ],
        "--extend",
        &design,
    );
    refused(
        &[
            "simulate",
            "--design",
            s(&design),
            "--experiment",
            "wall-impact",
            "--out",
            s(&design),
        ],
        "--design",
        &design,
    );

    let sieve = d.join("sieve.csv");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/sieve_gravel_8_16.csv"),
        &sieve,
    )
    .unwrap();
    refused(
        &[
            "psd",
            "draw",
            "--sieve",
            s(&sieve),
            "--n",
            "10",
            "--seed",
            "1",
            "--out",
            s(&sieve),
        ],
        "--sieve",
        &sieve,
    );

    let material = d.join("material.toml");
    std::fs::write(&material, "[measured]\ny = { value = 1.5, sd = 0.1 }\n").unwrap();
    refused(
        &[
            "calibrate",
            "--material",
            s(&material),
            "--model",
            s(&model),
            "--out",
            s(&material),
        ],
        "--material",
        &material,
    );
    refused(
        &[
            "calibrate",
            "--material",
            s(&material),
            "--model",
            s(&model),
            "--out",
            s(&model),
        ],
        "--model",
        &model,
    );
}
