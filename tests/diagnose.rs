//! `mbgc diagnose` on exact synthetic models (fast): a hidden cohesion in five sieve fractions
//! and a hidden rolling resistance are ranked first, the error falls at least 5-fold once the
//! effect is added and its fitted strength brackets the truth; a control set comes out
//! consistent; bad measurement sets are refused naming the file, the sample and the field.

use mbgc::dem::contact::ModelClass;
use mbgc::diagnose::{diagnose, Diagnosis, MeasurementSet, Options, Surrogate};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// Shear-box-like responses: cohesion matters as ced / sqrt(d50) (more for small particles),
/// rolling friction the same at every size.
fn truth(mu: f64, mu_r: f64, ced: f64, d50: f64) -> [f64; 2] {
    let bond = ced / 1e4 / d50.sqrt();
    let angle = 12.0 + 16.0 * (2.0 * mu).tanh() + 25.0 * (3.0 * mu_r).tanh() + 9.0 * bond;
    let density = 1520.0 - 60.0 * mu - 90.0 * mu_r - 25.0 * bond + 4.0 * d50.ln();
    [angle, density]
}

const MODEL_ERROR: [(&str, f64); 2] = [("shear_angle", 0.3), ("bulk_density", 1.5)];

/// A model of hertz,mindlin,epsd2 over mu_pp, mu_r_pp and d50 that misses the truth by `miss`
/// (per response) everywhere.
fn base_model(label: &str, error: &[(&str, f64)], miss: [f64; 2]) -> Surrogate {
    Surrogate::from_fn(
        label,
        ModelClass::parse("hertz,mindlin,epsd2").unwrap(),
        Some("shear-box"),
        &[
            ("mu_pp", [0.05, 1.0]),
            ("mu_r_pp", [0.0, 1.0]),
            ("d50", [1.0, 30.0]),
        ],
        &[("mu_r_pw", 0.0), ("sigma_ln", 0.1)],
        error,
        move |r, x| truth(x[0], x[1], 0.0, x[2])[r] + miss[r],
    )
}

/// A model of hertz,mindlin,epsd2 (as the shipped one) and a local one with cohesion that holds
/// the wall values fixed.
fn models() -> Vec<Surrogate> {
    let base = base_model("rolling.json", &MODEL_ERROR, [0.0, 0.0]);
    let cohesion = Surrogate::from_fn(
        "cohesion.json",
        ModelClass::parse("hertz,mindlin,epsd2,sjkr").unwrap(),
        Some("shear-box"),
        &[
            ("mu_pp", [0.05, 1.0]),
            ("mu_r_pp", [0.0, 1.0]),
            ("ced_pp", [0.0, 4e4]),
            ("d50", [1.0, 30.0]),
        ],
        &[("mu_r_pw", 0.0), ("ced_pw", 0.0), ("sigma_ln", 0.1)],
        &MODEL_ERROR,
        |r, x| truth(x[0], x[1], x[2], x[3])[r],
    );
    vec![base, cohesion]
}

const SD: [f64; 2] = [1.0, 3.8];

/// A measurement set of five sieve fractions measured with noise of the given sd.
fn set(class: &str, extra: &str, mu: f64, mu_r: f64, ced: f64, seed: u64) -> MeasurementSet {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut t = format!(
        "name = \"synthetic\"\n[model]\nclass = \"{class}\"\n[fixed]\nmu_r_pw = 0\n{extra}\n\
         [candidates.sjkr]\nfixed = {{ ced_pw = 0 }}\n"
    );
    if !class.contains("epsd2") {
        // Without rolling resistance in the class, the walls' rolling friction is the
        // candidate's to fix (the models hold it at 0).
        t = t.replace("mu_r_pw = 0\n", "");
        t += "[candidates.epsd2]\nfixed = { mu_r_pw = 0 }\n";
    }
    t += &samples(mu, mu_r, ced, SD, &mut rng);
    MeasurementSet::from_toml_str(&t, "synthetic.toml").unwrap()
}

/// Five sieve fractions of the material, each response measured with noise of sd `sd`.
fn samples(mu: f64, mu_r: f64, ced: f64, sd: [f64; 2], rng: &mut impl rand::Rng) -> String {
    let mut t = String::new();
    for d in [1.5, 3.0, 6.0, 12.0, 24.0] {
        let y = truth(mu, mu_r, ced, d);
        let n: Vec<f64> = sd
            .iter()
            .map(|s| Normal::new(0.0, *s).unwrap().sample(rng))
            .collect();
        t += &format!(
            "[[sample]]\nname = \"{d} mm\"\nexperiment = \"shear-box\"\n\
             psd = {{ d50_mm = {d}, sigma_ln = 0.1 }}\n\
             measured.shear_angle = {{ value = {}, sd = {} }}\n\
             measured.bulk_density = {{ value = {}, sd = {} }}\n",
            y[0] + n[0],
            sd[0],
            y[1] + n[1],
            sd[1]
        );
    }
    t
}

fn run(s: &MeasurementSet) -> Diagnosis {
    let opts = Options {
        samples: 1000,
        ..Options::default()
    };
    let d = diagnose(s, &models(), &opts).unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&d.ranking).unwrap());
    eprintln!("verdict: {}", d.verdict);
    d
}

#[test]
fn hidden_cohesion_is_ranked_first_and_its_strength_recovered() {
    let ced = 1.5e4;
    let d = run(&set("hertz,mindlin,epsd2", "", 0.5, 0.3, ced, 1));
    assert!(d.chi2_dof > 5.0, "the base class must fail: {}", d.chi2_dof);
    // The miss grows as particles get smaller: a trend against ln d50 is found.
    assert!(
        d.base
            .structured
            .iter()
            .any(|t| t.kind == "trend" && t.against.as_deref() == Some("ln d50")),
        "{:?}",
        d.base.structure
    );
    let best = &d.ranking[0];
    assert_eq!(best.effect, "sjkr");
    assert!(best.log_bayes_factor > 2.3);
    assert!(
        best.chi2_ratio >= 5.0,
        "chi^2 fell only {}x",
        best.chi2_ratio
    );
    let s = best.strength.iter().find(|p| p.name == "ced_pp").unwrap();
    assert!(s.q05 <= ced && ced <= s.q95, "{s:?}");
    assert!(d.verdict.starts_with("sjkr explains it"), "{}", d.verdict);
    // Rolling resistance is in the class already: it is no candidate, and cdt (the other
    // rolling law) has no slot free.
    assert!(d.ranking.iter().all(|r| r.effect != "epsd2"));
}

#[test]
fn hidden_rolling_resistance_is_ranked_first_over_cohesion() {
    let d = run(&set("hertz,mindlin", "", 0.5, 0.3, 0.0, 2));
    assert!(d.chi2_dof > 5.0, "{}", d.chi2_dof);
    assert_eq!(d.ranking[0].effect, "epsd2", "{:?}", d.ranking);
    assert!(d.ranking[0].chi2_ratio >= 5.0);
    let s = &d.ranking[0].strength[0];
    assert_eq!(s.name, "mu_r_pp");
    assert!(s.q05 <= 0.3 && 0.3 <= s.q95, "{s:?}");
    // Cohesion was evaluated (from the cohesion model with its rolling friction off) and loses.
    let coh = d
        .ranking
        .iter()
        .find(|r| r.effect == "sjkr")
        .expect("sjkr evaluated");
    assert!(coh.log_bayes_factor < d.ranking[0].log_bayes_factor);
    // cdt: no model of it was given, and the report says so.
    assert!(d
        .unavailable
        .iter()
        .any(|u| u.effect == "cdt" && u.reason.contains("no model")));
    // And the verdict carries it as a caveat although another effect explains the data.
    assert!(
        d.verdict.starts_with("epsd2 explains it")
            && d.verdict.contains("not evaluated for want of a model: cdt"),
        "{}",
        d.verdict
    );
}

#[test]
fn a_set_without_a_hidden_effect_is_consistent_and_needs_none() {
    let d = run(&set("hertz,mindlin,epsd2", "", 0.5, 0.3, 0.0, 3));
    assert!(d.p_value > 0.01, "{}", d.p_value);
    assert!(d.base.structured.is_empty());
    assert!(
        d.verdict.starts_with("consistent, no effect needed"),
        "{}",
        d.verdict
    );
    assert!(d.ranking.iter().all(|r| r.log_bayes_factor < 2.3));
}

#[test]
fn a_model_holding_a_searched_value_is_not_used_and_the_reason_is_given() {
    // Without `[candidates.sjkr] fixed = { ced_pw = 0 }` the cohesion model (which holds ced_pw
    // at 0) cannot stand for a class that searches ced_pw.
    let mut s = set("hertz,mindlin,epsd2", "", 0.5, 0.3, 0.0, 3);
    s.candidates.clear();
    let d = diagnose(
        &s,
        &models(),
        &Options {
            samples: 500,
            ..Options::default()
        },
    )
    .unwrap();
    let u = d.unavailable.iter().find(|u| u.effect == "sjkr").unwrap();
    assert!(u.reason.contains("holds ced_pw at 0"), "{}", u.reason);
}

fn error_of(text: &str) -> String {
    MeasurementSet::from_toml_str(text, "set.toml")
        .unwrap_err()
        .to_string()
}

const SAMPLE: &str = "[[sample]]\nname = \"2 mm\"\nexperiment = \"shear-box\"\n\
    psd = { d50_mm = 2, sigma_ln = 0.1 }\nmeasured.shear_angle = { value = 30, sd = 1 }\n";

#[test]
fn bad_measurement_sets_name_the_file_the_sample_and_the_field() {
    let class = "[model]\nclass = \"hertz,mindlin,epsd2\"\n";
    let cases: Vec<(String, &str)> = vec![
        (SAMPLE.to_string(), "model.class"),
        (class.to_string(), "sample"),
        (
            format!("{class}{}", SAMPLE.replace("sd = 1", "sd = -1")),
            "sample[\"2 mm\"].measured.shear_angle.sd",
        ),
        (
            format!(
                "{class}{}",
                SAMPLE.replace("experiment = \"shear-box\"\n", "")
            ),
            "sample[\"2 mm\"].experiment",
        ),
        (
            format!("{class}{}", SAMPLE.replace("d50_mm = 2", "d50_mm = -2")),
            "sample[\"2 mm\"].psd.d50_mm",
        ),
        (format!("{class}{SAMPLE}{SAMPLE}"), "sample[2].name"),
        (
            format!("{class}[fixed]\nced_pp = 1\n{SAMPLE}"),
            "fixed.ced_pp",
        ),
        (
            format!("per_sample = [\"mu_pp\", \"mu_pp\"]\n{class}{SAMPLE}"),
            "per_sample[1]",
        ),
        (
            format!("{class}[candidates.epsd2]\n{SAMPLE}"),
            "candidates.epsd2",
        ),
        (
            format!("{class}[candidates.sjkr]\nfixed = {{ mu_pp = 1 }}\n{SAMPLE}"),
            "candidates.sjkr.fixed.mu_pp",
        ),
        (
            format!("{class}[candidates.magic]\n{SAMPLE}"),
            "candidates.magic",
        ),
        (
            format!("{class}[model_error]\nshear_angle = -1\n{SAMPLE}"),
            "model_error.shear_angle",
        ),
        (
            format!(
                "{class}{}",
                SAMPLE.replace("measured.shear_angle = { value = 30, sd = 1 }\n", "")
            ),
            "sample[\"2 mm\"].measured",
        ),
        (format!("{class}{SAMPLE}colour = 1\n"), "sample"),
    ];
    for (text, field) in cases {
        let e = error_of(&text);
        assert!(e.contains("set.toml"), "{e}");
        assert!(e.contains(field), "expected {field} in: {e}");
    }
    // What the file gives must be read by the models: a fixed value no model reads is refused.
    let text = format!(
        "[model]\nclass = \"hertz,mindlin,epsd2\"\n[fixed]\nmu_r_pw = 0\ne_pp = 0.5\n{SAMPLE}"
    );
    let s = MeasurementSet::from_toml_str(&text, "set.toml").unwrap();
    let e = diagnose(&s, &models(), &Options::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("fixed.e_pp") && e.contains("set.toml"), "{e}");
}

/// A measurement set whose fixed values put a sample's stiffness group beyond the model's
/// training runs is answered by the model's rigid limit when the stiffness lines reach it, and
/// one beyond the space is told which input, its value and the range (it used to end in
/// "tmcmc: the likelihood is zero (-inf) at all 2000 prior samples").
#[test]
fn a_group_beyond_the_training_runs_is_answered_by_the_rigid_limit_or_named() {
    let dir = tempfile::tempdir().unwrap();
    let control = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/measurements/control.toml"
    ))
    .unwrap()
    .replace("mu_r_pw = 0\n", "mu_r_pw = 0.3\n");
    let run = |set: String| {
        let path = dir.path().join("stiff.toml");
        std::fs::write(&path, set).unwrap();
        std::process::Command::new(env!("CARGO_BIN_EXE_mbgc"))
            .args([
                "diagnose",
                "--measurements",
                path.to_str().unwrap(),
                "--model",
                "models/shear_box.json",
                "--samples",
                "300",
            ])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap()
    };
    // Ten times stiffer (K_p 2.5e5 to 9.8e5, beyond the runs' 1.94e5): answered.
    let o = run(control
        .replace("E_p = 5e6", "E_p = 5e7")
        .replace("E_w = 5e6", "E_w = 5e7"));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(text.contains("chi^2/dof"), "{text}");
    // A hundred times stiffer and finer (K_p 3.9e7 at 0.5 mm, seed 004's E of 5e8): answered
    // too, the lines reach 5.2e8.
    let o = run(control
        .replace("E_p = 5e6", "E_p = 5e8")
        .replace("E_w = 5e6", "E_w = 5e8")
        .replace("d50_mm = 2,", "d50_mm = 0.5,"));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(text.contains("chi^2/dof"), "{text}");
    // Ten times stiffer still, beyond seed 004's space (E 5e9): named, with the range.
    let o = run(control
        .replace("E_p = 5e6", "E_p = 5e9")
        .replace("E_w = 5e6", "E_w = 5e9")
        .replace("d50_mm = 2,", "d50_mm = 0.5,"));
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("E_p = 5000000000") && e.contains("[2500000, 500000000]"),
        "{e}"
    );
    assert!(!e.contains("likelihood is zero"), "{e}");
}

/// The model's own error where the material lies, not its average: a cohesion model whose error
/// model says 0.1 deg and 0.5 kg/m3 at low cohesion and 3 deg and 12 kg/m3 at high. A material
/// without cohesion is judged with the small errors; the set's `[model_error]` still overrides.
#[test]
fn the_model_error_is_taken_at_the_best_fit_where_the_model_knows_it() {
    let varying = |models: Vec<Surrogate>| -> Vec<Surrogate> {
        models
            .into_iter()
            .map(|m| {
                let ced = m.input("ced_pp");
                m.with_error_at(move |r, x| {
                    let strong = ced.is_some_and(|k| x[k] > 2e4);
                    Some(match (r, strong) {
                        (0, false) => 0.1,
                        (0, true) => 3.0,
                        (_, false) => 0.5,
                        (_, true) => 12.0,
                    })
                })
            })
            .collect()
    };
    let s = set("hertz,mindlin,epsd2", "", 0.5, 0.3, 0.0, 4);
    let opts = Options {
        samples: 500,
        starts: 4,
        ..Options::default()
    };
    let d = diagnose(&s, &varying(models()), &opts).unwrap();
    for r in &d.base.residuals {
        let e = if r.response == "shear_angle" {
            0.1
        } else {
            0.5
        };
        assert!((r.sigma - r.sd.hypot(e)).abs() < 1e-9, "{r:?}");
    }
    assert!(
        d.base
            .notes
            .iter()
            .any(|n| n.contains("own error at the first best fit")),
        "{:?}",
        d.base.notes
    );
    let given = set(
        "hertz,mindlin,epsd2",
        "[model_error]\nshear_angle = 2.0\n",
        0.5,
        0.3,
        0.0,
        4,
    );
    assert_eq!(given.model_error, vec![("shear_angle".to_string(), 2.0)]);
    let d = diagnose(&given, &varying(models()), &opts).unwrap();
    for r in d
        .base
        .residuals
        .iter()
        .filter(|r| r.response == "shear_angle")
    {
        assert!((r.sigma - r.sd.hypot(2.0)).abs() < 1e-9, "{r:?}");
    }
}

/// A model that misses the material by 2 of its own errors at every size (the usual way a
/// metamodel is wrong: systematically, where the material lies), and measurements four times
/// more precise than the model. Taken as independent, the miss would be averaged over the five
/// samples and the intervals would exclude the truth; shared between the samples (the default
/// correlation), it is one miss of the model and the truth stays inside.
#[test]
fn a_systematic_model_miss_is_shared_between_samples_and_the_truth_stays_inside() {
    let error = [("shear_angle", 1.0), ("bulk_density", 4.0)];
    let biased = base_model("biased.json", &error, [2.0, -8.0])
        // Its validation error is all the equations' (no DEM noise in it): all of it is shared.
        .with_noise(&[0.0, 0.0]);
    let (mu, mu_r) = (0.5, 0.3);
    let text = |rho: &str| {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut t = format!(
            "name = \"biased model\"\n{rho}\n[model]\nclass = \"hertz,mindlin,epsd2\"\n\
             [fixed]\nmu_r_pw = 0\n"
        );
        t += &samples(mu, mu_r, 0.0, [0.25, 1.0], &mut rng);
        MeasurementSet::from_toml_str(&t, "biased.toml").unwrap()
    };
    let opts = Options {
        samples: 1000,
        ..Options::default()
    };
    let covers = |d: &Diagnosis| {
        let p = &d.base.parameters;
        let inside = |n: &str, v: f64| {
            let q = p.iter().find(|q| q.name == n).unwrap();
            q.q05 <= v && v <= q.q95
        };
        inside("mu_pp", mu) && inside("mu_r_pp", mu_r)
    };
    let shared = text("");
    assert_eq!(shared.model_error_correlation, 0.8);
    let d = diagnose(&shared, std::slice::from_ref(&biased), &opts).unwrap();
    assert!(covers(&d), "{:?}", d.base.parameters);
    assert!(d.p_value > 0.01, "{}", d.verdict);
    let independent = text("model_error_correlation = 0");
    let d = diagnose(&independent, std::slice::from_ref(&biased), &opts).unwrap();
    assert!(!covers(&d), "{:?}", d.base.parameters);
    // A model that does not know its noise cannot say how much of its error is its equations':
    // it shares none, and says so.
    let mut unknown = biased;
    unknown.noise = vec![None, None];
    let d = diagnose(&shared, std::slice::from_ref(&unknown), &opts).unwrap();
    assert!(!covers(&d), "{:?}", d.base.parameters);
    assert!(
        d.base
            .notes
            .iter()
            .any(|n| n.contains("records no replicate noise")),
        "{:?}",
        d.base.notes
    );
    let e = error_of(&format!(
        "model_error_correlation = 1\n[model]\nclass = \"hertz,mindlin,epsd2\"\n{SAMPLE}"
    ));
    assert!(
        e.contains("set.toml") && e.contains("model_error_correlation") && e.contains("[0, 1)"),
        "{e}"
    );
}

/// A cohesion stronger than the cohesion model covers (5e4 against its 4e4): the fit stops at
/// the model's edge, and the verdict says the interval is cut there instead of presenting it as
/// a measurement.
#[test]
fn a_strength_beyond_the_models_is_reported_as_cut_at_their_edge() {
    let d = run(&set("hertz,mindlin,epsd2", "", 0.5, 0.3, 5e4, 6));
    let best = &d.ranking[0];
    assert_eq!(best.effect, "sjkr");
    let s = best.strength.iter().find(|p| p.name == "ced_pp").unwrap();
    assert_eq!(s.at_edge.as_deref(), Some("upper"), "{s:?}");
    assert!(s.q95 < 5e4, "{s:?}");
    assert!(
        d.verdict
            .contains("lies at the upper end of what the models cover"),
        "{}",
        d.verdict
    );
    // Inside the models' range the same strength is not flagged.
    let d = run(&set("hertz,mindlin,epsd2", "", 0.5, 0.3, 2e4, 6));
    let s = d.ranking[0]
        .strength
        .iter()
        .find(|p| p.name == "ced_pp")
        .unwrap();
    assert_eq!(s.at_edge, None, "{s:?}");
    assert!(!d.verdict.contains("upper end"), "{}", d.verdict);
}

/// A sample's size spread must reach the model: one trained on monosized runs (no sigma_ln
/// among its inputs or constants) is refused for graded samples, with the reason.
#[test]
fn a_model_without_the_size_spread_is_refused_for_graded_samples() {
    let monosized = Surrogate::from_fn(
        "monosized.json",
        ModelClass::parse("hertz,mindlin,epsd2").unwrap(),
        Some("shear-box"),
        &[
            ("mu_pp", [0.05, 1.0]),
            ("mu_r_pp", [0.0, 1.0]),
            ("d50", [1.0, 30.0]),
        ],
        &[("mu_r_pw", 0.0)],
        &MODEL_ERROR,
        |r, x| truth(x[0], x[1], 0.0, x[2])[r],
    );
    let s = set("hertz,mindlin,epsd2", "", 0.5, 0.3, 0.0, 3);
    let err = match diagnose(&s, &[monosized], &Options::default()) {
        Ok(_) => panic!("a graded set on a monosized model must be refused"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("sigma_ln = 0.1") && err.contains("monosized"),
        "{err}"
    );
}

/// The intervals beside those of exact models tell a limiting model from limiting measurements:
/// the same set and predictions, once with a model error well below the measurement sd and once
/// with one three times above it. The exact-model widths are the same in both (only the sds
/// enter them); the fitted ones are about as wide with the precise model and wider with the
/// imprecise one.
#[test]
fn the_intervals_with_exact_models_say_whether_the_model_limits_them() {
    let s = set("hertz,mindlin,epsd2", "", 0.5, 0.3, 0.0, 3);
    let opts = Options {
        samples: 1000,
        ..Options::default()
    };
    let width = |p: &mbgc::diagnose::Parameter| {
        let [lo, hi] = p.exact_models.expect("every value has an sd");
        (p.q95 - p.q05, hi - lo)
    };
    let precise = diagnose(
        &s,
        &[base_model("precise.json", &MODEL_ERROR, [0.0; 2])],
        &opts,
    )
    .unwrap()
    .base;
    let rough = [("shear_angle", 3.0), ("bulk_density", 11.4)];
    let imprecise = diagnose(&s, &[base_model("rough.json", &rough, [0.0; 2])], &opts)
        .unwrap()
        .base;
    for (p, q) in precise.parameters.iter().zip(&imprecise.parameters) {
        let ((fit_p, exact_p), (fit_q, exact_q)) = (width(p), width(q));
        eprintln!(
            "{}: precise {fit_p} / {exact_p}, rough {fit_q} / {exact_q}",
            p.name
        );
        assert!(
            (exact_p / exact_q - 1.0).abs() < 0.1,
            "{}: {exact_p} vs {exact_q}",
            p.name
        );
        // Measured: 1.04 (both parameters) and 1.40 / 1.42; the searched range (mu_pp 0.05-1)
        // and the ridge between the two frictions keep the rough model's intervals from growing
        // with its error.
        assert!(fit_p / exact_p < 1.15, "{}: {fit_p} / {exact_p}", p.name);
        assert!(fit_q / exact_q > 1.3, "{}: {fit_q} / {exact_q}", q.name);
    }
}
