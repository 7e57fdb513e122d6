//! The library as a program calls it, without the command line: a fit from columns in memory,
//! options checked by the library, errors a caller can match on, and `train` with an observer.

use std::cell::RefCell;
use std::path::Path;

use mbgc::calibrate::session::{self, SessionOptions};
use mbgc::gp::Config;
use mbgc::material::Material;
use mbgc::metamodel::{fit, FitSettings, Metamodel, TrainingTable};
use mbgc::train::{train, TrainObserver, TrainOutcome, TrainRequest, TrainStage};
use mbgc::Error;

/// y = 0.2 + 0.5 a + 0.3 b on a 6 x 6 grid of the unit square.
fn plane() -> TrainingTable {
    let (mut a, mut b, mut y) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..6 {
        for j in 0..6 {
            let (x1, x2) = (i as f64 / 5.0, j as f64 / 5.0);
            a.push(x1);
            b.push(x2);
            y.push(0.2 + 0.5 * x1 + 0.3 * x2);
        }
    }
    TrainingTable::from_columns(
        "plane",
        vec![("a".into(), a), ("b".into(), b), ("y".into(), y)],
    )
    .unwrap()
}

fn settings() -> FitSettings {
    FitSettings::new(vec!["a".into(), "b".into()], vec!["y".into()])
        .test_fraction(0.0)
        .config(Config {
            population: 300,
            generations: 10,
            seed: 3,
            ..Config::default()
        })
}

fn model() -> Metamodel {
    fit(&plane(), &settings(), |_, _| {}).unwrap().model
}

#[test]
fn a_fit_in_memory_equals_the_fit_of_the_same_table_read_from_a_file() {
    let table = plane();
    let fitted = fit(&table, &settings(), |_, _| {}).unwrap();
    assert!(
        fitted.model.responses[0].train.r2 > 0.999,
        "{:?}",
        fitted.model.responses[0]
    );
    assert_eq!(fitted.splits.len(), 1);
    assert_eq!(fitted.splits[0].train.observed.len(), 36);
    assert!(fitted.splits[0].test.is_none());
    // The same numbers through a CSV file: the same equation (only the data's name and
    // fingerprint differ).
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plane.csv");
    let mut csv = String::from("a,b,y\n");
    for r in 0..table.rows() {
        let v: Vec<String> = table.columns.iter().map(|c| c.1[r].to_string()).collect();
        csv.push_str(&(v.join(",") + "\n"));
    }
    std::fs::write(&path, csv).unwrap();
    let read = TrainingTable::read_csv(&path, &["a".into(), "b".into()], &["y".into()]).unwrap();
    let from_file = fit(&read, &settings(), |_, _| {}).unwrap();
    assert_eq!(
        from_file.model.responses[0].equation,
        fitted.model.responses[0].equation
    );
    assert_ne!(from_file.model.data.fnv1a64, fitted.model.data.fnv1a64);
}

#[test]
fn a_table_in_memory_is_checked_as_a_file_would_be() {
    let short = TrainingTable::from_columns(
        "t",
        vec![("a".into(), vec![1.0, 2.0]), ("y".into(), vec![1.0])],
    )
    .unwrap_err()
    .to_string();
    assert!(
        short.contains("t: column y") && short.contains("2 values"),
        "{short}"
    );
    let nan = TrainingTable::from_columns("t", vec![("a".into(), vec![1.0, f64::NAN])])
        .unwrap_err()
        .to_string();
    assert!(nan.contains("column a, row 2"), "{nan}");
    let missing = fit(
        &plane(),
        &FitSettings::new(vec!["a".into()], vec!["z".into()]),
        |_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(missing.contains("plane: column z"), "{missing}");
}

#[test]
fn settings_are_checked_by_the_library_before_anything_runs() {
    let e = fit(&plane(), &settings().test_fraction(0.95), |_, _| {}).unwrap_err();
    assert!(e.to_string().contains("--test-fraction"), "{e}");
    let e = settings().test_fraction(0.95).check().unwrap_err();
    assert!(matches!(e, Error::Invalid(_)));

    let m = model();
    let material =
        Material::from_toml_str("[measured]\ny = { value = 0.6, sd = 0.01 }\n", "m.toml").unwrap();
    // Zero starts from Rust is refused by name, not reported as a model without finite values.
    let e = session::run(&material, &m, "plane", &SessionOptions::default().starts(0))
        .unwrap_err()
        .to_string();
    assert!(e.contains("--starts 0"), "{e}");
    let e = session::run(
        &material,
        &m,
        "plane",
        &SessionOptions {
            bayes: true,
            samples: 3,
            ..SessionOptions::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("--samples 3"), "{e}");
}

#[test]
fn calibration_errors_say_what_went_wrong_by_their_kind() {
    let m = model();
    let measured = "[measured]\ny = { value = 0.6, sd = 0.01 }\n";
    // A fixed value outside the fitted domain [0, 1] of b.
    let outside =
        Material::from_toml_str(&format!("{measured}[fixed]\nb = 1.5\n"), "o.toml").unwrap();
    let e = session::run(&outside, &m, "plane", &SessionOptions::default()).unwrap_err();
    assert!(
        matches!(&e, Error::OutOfDomain { file, field, .. } if file == "o.toml" && field == "fixed.b"),
        "{e:?}"
    );
    // Constraints no point of the box meets.
    let impossible = Material::from_toml_str(
        &format!("{measured}[constraints]\nexpr = [\"a + b >= 3\"]\n"),
        "c.toml",
    )
    .unwrap();
    let e = session::run(&impossible, &m, "plane", &SessionOptions::default()).unwrap_err();
    assert!(matches!(e, Error::Infeasible(_)), "{e:?}");
    // A material the model fits: the best optimum reproduces the measurement.
    let fine = Material::from_toml_str(&format!("{measured}[fixed]\nb = 0.5\n"), "f.toml").unwrap();
    let s = session::run(&fine, &m, "plane", &SessionOptions::default()).unwrap();
    let a = s.best().x[0];
    assert!((a - 0.5).abs() < 0.02, "a = {a}");
}

/// Records what a train tells its observer.
#[derive(Default)]
struct Log {
    notes: RefCell<Vec<(TrainStage, String)>>,
    generations: RefCell<usize>,
}

impl TrainObserver for Log {
    fn note(&self, stage: TrainStage, text: &str) {
        self.notes.borrow_mut().push((stage, text.to_string()));
    }
    fn fit_progress(&self, _response: &str, _p: &mbgc::gp::Progress) {
        *self.generations.borrow_mut() += 1;
    }
}

#[test]
fn train_runs_as_a_library_call_and_reports_to_its_observer() {
    let dir = tempfile::tempdir().unwrap();
    let space = dir.path().join("space.toml");
    std::fs::write(
        &space,
        "name = \"t\"\n[parameters]\nx = { min = 0.0, max = 1.0 }\ny = { min = 0.0, max = 1.0 }\n",
    )
    .unwrap();
    let req = TrainRequest {
        out_dir: dir.path().to_path_buf(),
        responses: vec!["f".into()],
        validation: 4,
        figures: false,
        config: Config {
            population: 200,
            generations: 3,
            ..Config::default()
        },
        ..TrainRequest::new(space.clone(), "sleep-test", 10)
    };
    let log = Log::default();
    let TrainOutcome::Fitted {
        model,
        paths,
        figures,
        ..
    } = train(&req, &log).unwrap()
    else {
        panic!("expected a fitted model");
    };
    assert!(figures.is_empty());
    assert!(paths.model.exists() && paths.model.with_extension("rs").exists());
    assert!(
        !Path::new(&paths.figures).exists(),
        "figures were not asked for"
    );
    assert_eq!(model.data.rows, 10);
    assert!(model.responses[0].validation.is_some());
    let notes = log.notes.borrow();
    for stage in [TrainStage::Sample, TrainStage::Simulate] {
        assert_eq!(
            notes.iter().filter(|(s, _)| *s == stage).count(),
            2,
            "{stage}: {notes:?}"
        );
    }
    assert!(*log.generations.borrow() >= 3);
    // Options a train cannot honour are refused by the library.
    let bad = TrainRequest {
        threads: 0,
        ..req.clone()
    };
    assert!(train(&bad, &log)
        .unwrap_err()
        .to_string()
        .contains("--threads"));
    let few = TrainRequest { n: 3, ..req };
    assert!(train(&few, &log).unwrap_err().to_string().contains("--n 3"));
}

/// A material whose fixed values put the stiffness group outside the shipped model's range (its
/// training runs and the stiffness lines of its rigid limit) is told so by name, value and range
/// (it used to read "the constraints [] cannot be met"), and names the model lacks are said to
/// be missing, not listed as if expected.
#[test]
fn out_of_range_groups_and_unknown_names_are_explained() {
    let model = Metamodel::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/models/shear_box.json"
    )))
    .unwrap();
    let gravel =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/gravel.toml"))
            .unwrap()
            .replace(
                "sieve = \"sieve_gravel_8_16.csv\"",
                "d50_mm = 25.6\nsigma_ln = 0.26",
            )
            .replace("E_p = 4e7", "E_p = 2.5e6\nrho_p = 3000")
            .replace("E_w = 4e7", "E_w = 2.5e6");
    // K_p 3.3e3, the softest corner of the model's inputs: below the training runs (9.8e3) and
    // the softest stiffness line of the rigid limit (the lines reach the top of seed 004's box).
    let fine = Material::from_toml_str(&gravel, "coarse_soft.toml").unwrap();
    let e = session::run(&fine, &model, "shear_box", &SessionOptions::default()).unwrap_err();
    let text = e.to_string();
    assert!(matches!(e, Error::OutOfDomain { .. }), "{e:?}");
    let reach = model.group_range(&model.groups[0]);
    assert!(
        text.contains("K_p = 101.9 E_p / (rho_p d50)")
            && text.contains(&format!("[{:.4e}, {:.4e}]", reach[0], reach[1]))
            && text.contains("mbgc diagnose --build"),
        "{text}"
    );
    let unknown = Material::from_toml_str(
        "[measured]\nangle_of_repose = { value = 30, sd = 1 }\n",
        "u.toml",
    )
    .unwrap();
    let e = session::run(&unknown, &model, "shear_box", &SessionOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "measured.angle_of_repose: not a response of the model; expected one of: shear_angle"
        ),
        "{e}"
    );
}

/// Train refuses what would fail or mislead only after hours of DEM: GP settings that cannot
/// fit, cross-validation on too few runs, and a space other than the one the designs under
/// this name were made for.
#[test]
fn train_refuses_before_simulating_and_never_extends_a_design_of_another_space() {
    let dir = tempfile::tempdir().unwrap();
    let space = dir.path().join("space.toml");
    let text =
        "name = \"t\"\n[parameters]\nx = { min = 0.0, max = 1.0 }\ny = { min = 0.0, max = 1.0 }\n";
    std::fs::write(&space, text).unwrap();
    let req = TrainRequest {
        out_dir: dir.path().to_path_buf(),
        responses: vec!["f".into()],
        figures: false,
        config: Config {
            population: 200,
            generations: 3,
            ..Config::default()
        },
        ..TrainRequest::new(space.clone(), "sleep-test", 10)
    };
    let none = TrainRequest {
        config: Config {
            generations: 0,
            ..req.config.clone()
        },
        ..req.clone()
    };
    let e = train(&none, &mbgc::train::Silent).unwrap_err().to_string();
    assert!(e.contains("generations"), "{e}");
    let few = TrainRequest {
        n: 8,
        config: Config {
            selection: mbgc::gp::select::Selection::CrossValidation,
            ..req.config.clone()
        },
        ..req.clone()
    };
    let e = train(&few, &mbgc::train::Silent).unwrap_err().to_string();
    assert!(e.contains("--n 8") && e.contains("cross-validation"), "{e}");
    assert!(
        !dir.path().join("sampling").exists(),
        "nothing may be sampled before refusing"
    );

    train(&req, &mbgc::train::Silent).unwrap();
    std::fs::write(&space, text.replace("max = 1.0 }\ny", "max = 2.0 }\ny")).unwrap();
    let e = train(&TrainRequest { n: 12, ..req }, &mbgc::train::Silent)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("another space") && e.contains("x: 0.0..2.0"),
        "{e}"
    );
}

/// A group whose inputs the space all fixes (K_w when E_w, rho_p and d50 are fixed) is a
/// constant, not a fitting variable: it is dropped, and its inputs are no longer absorbed
/// unless another group or a scaled response needs them.
#[test]
fn a_group_of_fixed_inputs_is_a_constant() {
    use mbgc::experiments::shear_box::ShearBox;
    use mbgc::experiments::Experiment;
    let sim = ShearBox::default().similarity().unwrap();
    let fixed = ["E_w", "rho_p", "d50"];
    let kept = sim.without_constant_groups(|n| fixed.contains(&n));
    let names: Vec<&str> = kept.groups.iter().map(|g| g.name.as_str()).collect();
    assert_eq!(names, ["K_p"]);
    assert!(!kept.absorbed().contains(&"E_w".to_string()));
    // rho_p still scales the bulk density, so it stays an input the fit reads.
    assert!(kept.needed_inputs().contains(&"rho_p".to_string()));
}

/// A score on a handful of rows is flagged, and an equation with more constants than its rows
/// support is too.
#[test]
fn small_test_sets_and_constant_heavy_equations_are_warned_of() {
    let fitted = fit(&plane(), &settings().test_fraction(0.1), |_, _| {}).unwrap();
    assert_eq!(fitted.model.data.test_rows, 4);
    assert!(
        fitted
            .warnings
            .iter()
            .any(|w| w.contains("only 4 test rows")),
        "{:?}",
        fitted.warnings
    );
    // 12 rows and a noisy response: whatever equation comes out, each of its constants is
    // counted against the rows, and one with two or more is flagged.
    let x: Vec<f64> = (0..12).map(|i| i as f64 / 11.0).collect();
    let y: Vec<f64> = x
        .iter()
        .map(|v| (7.0 * v).sin() + 0.3 * (31.0 * v).cos())
        .collect();
    let table =
        TrainingTable::from_columns("noisy", vec![("a".into(), x), ("y".into(), y)]).unwrap();
    let f = fit(
        &table,
        &FitSettings::new(vec!["a".into()], vec!["y".into()])
            .test_fraction(0.0)
            .config(Config {
                population: 500,
                generations: 10,
                parsimony: 0.0,
                seed: 5,
                ..Config::default()
            }),
        |_, _| {},
    )
    .unwrap();
    let constants = f.model.responses[0]
        .program
        .iter()
        .filter(|n| matches!(n, mbgc::gp::Node::Const(_)))
        .count();
    let warned = f
        .warnings
        .iter()
        .any(|w| w.contains("constants fitted to 12 rows"));
    assert_eq!(
        warned,
        constants * 10 > 12,
        "{constants} constants: {:?}",
        f.warnings
    );
}

/// The shipped model's bulk density is rho_p times its fitted solid fraction, and its errors were
/// measured on runs at rho_p 2600 kg/m3: a material of half the density (with half the
/// stiffness, so every group is the same) gets half the prediction and half the stated error.
/// The shear angle, which has no factor, is the same at both.
#[test]
fn a_bulk_density_error_scales_with_the_particle_density() {
    let model = Metamodel::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/models/shear_box_wide.json"
    )))
    .unwrap();
    let names = model.input_names();
    let at = |scale: f64| -> Vec<f64> {
        names
            .iter()
            .map(|n| match n.as_str() {
                "E_p" | "E_w" => 4e7 * scale,
                "rho_p" => 2600.0 * scale,
                "d50" => 10.0,
                "sigma_ln" => 0.15,
                "nu_p" => 0.3,
                _ => 0.4,
            })
            .collect()
    };
    let (heavy, light) = (at(1.0), at(0.5));
    let r = |n: &str| model.responses.iter().find(|r| r.name == n).unwrap();
    let (density, angle) = (r("bulk_density"), r("shear_angle"));
    assert_eq!(density.error_reference, Some(2600.0));
    let ratio = |f: &dyn Fn(&[f64]) -> f64| f(&light) / f(&heavy);
    assert!((ratio(&|x| model.predict_point(density, x)) - 0.5).abs() < 1e-9);
    let e = |x: &[f64]| model.prediction_error(density, x).unwrap();
    assert!(
        (ratio(&e) - 0.5).abs() < 1e-9,
        "{} {}",
        e(&light),
        e(&heavy)
    );
    assert!(e(&heavy) > 1.0, "{}", e(&heavy));
    let a = |x: &[f64]| model.prediction_error(angle, x).unwrap();
    assert!((ratio(&a) - 1.0).abs() < 1e-9);
}
