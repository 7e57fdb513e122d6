//! One material measured in two experiments, fitted on both experiments' models at once (issue
//! 36), on exact synthetic models (fast). The shear box gives two responses for three unknowns
//! (sliding and rolling friction, particle density), so its solution set is a line; the shear
//! cell's responses weigh the frictions otherwise, and together they fix all three.

use mbgc::dem::contact::ModelClass;
use mbgc::diagnose::{diagnose, Diagnosis, MeasurementSet, Options, Surrogate};

const TRUTH: (f64, f64, f64) = (0.5, 0.3, 2650.0);

/// Shear box: two responses for three unknowns, so a one-dimensional solution set.
fn box_truth(mu: f64, mu_r: f64, rho: f64) -> [f64; 2] {
    let c = mu + 0.8 * mu_r;
    [
        12.0 + 30.0 * (1.5 * c).tanh(),
        rho * (0.62 - 0.05 * mu - 0.07 * mu_r),
    ]
}

/// Shear cell at pre-shear stress `s` (Pa): internal friction, bulk density and steady shear
/// ratio, led by the sliding friction (the rolling friction weighs less than in the box), and a
/// denser bed under more load.
fn cell_truth(mu: f64, mu_r: f64, rho: f64, s: f64) -> [f64; 3] {
    let load = (s / 1e4).ln();
    [
        20.0 + 28.0 * (2.0 * mu).tanh() + 4.0 * mu_r - 0.8 * load,
        rho * (0.60 - 0.03 * mu - 0.05 * mu_r + 0.004 * load),
        0.35 + 0.45 * (1.8 * mu).tanh() + 0.05 * mu_r,
    ]
}

fn models() -> Vec<Surrogate> {
    let class = || ModelClass::parse("hertz,mindlin,epsd2").unwrap();
    let shear_box = Surrogate::from_fn(
        "shear_box.json",
        class(),
        Some("shear-box"),
        &[
            ("mu_pp", [0.05, 1.0]),
            ("mu_r_pp", [0.0, 1.0]),
            ("rho_p", [2000.0, 3000.0]),
            ("d50", [1.0, 30.0]),
        ],
        &[("sigma_ln", 0.1)],
        &[("shear_angle", 0.2), ("bulk_density", 1.0)],
        |r, x| box_truth(x[0], x[1], x[2])[r],
    );
    let shear_cell = Surrogate::from_fn(
        "shear_cell.json",
        class(),
        Some("shear-cell"),
        &[
            ("mu_pp", [0.05, 1.0]),
            ("mu_r_pp", [0.0, 1.0]),
            ("rho_p", [2000.0, 3000.0]),
            ("d50", [1.0, 30.0]),
            ("normal_stress", [5e3, 6e4]),
        ],
        &[("sigma_ln", 0.1)],
        &[
            ("internal_friction", 0.3),
            ("bulk_density", 1.0),
            ("shear_ratio", 0.005),
        ],
        |r, x| cell_truth(x[0], x[1], x[2], x[4])[r],
    );
    vec![shear_box, shear_cell]
}

/// The measurement file: two shear-box samples and, with `cell`, the same material in the shear
/// cell at two pre-shear stresses (measured without noise: the test is about the solution set,
/// not the scatter). The cell's sds are those of a mean of three k = 12 runs
/// (docs/shear_cell.md).
fn set(cell: bool) -> MeasurementSet {
    let (mu, mu_r, rho) = TRUTH;
    let b = box_truth(mu, mu_r, rho);
    let mut t = String::from("name = \"gravel-like\"\n[model]\nclass = \"hertz,mindlin,epsd2\"\n");
    // Two sieve fractions: four measurements for three unknowns (a diagnosis needs a degree of
    // freedom), which these size-blind box responses leave on the line all the same.
    for d in [8, 16] {
        t += &format!(
            "[[sample]]\nname = \"box {d} mm\"\nexperiment = \"shear-box\"\n\
             psd = {{ d50_mm = {d}, sigma_ln = 0.1 }}\n\
             measured.shear_angle = {{ value = {}, sd = 0.5 }}\n\
             measured.bulk_density = {{ value = {}, sd = 4 }}\n",
            b[0], b[1]
        );
    }
    if cell {
        for s in [1e4, 3e4] {
            let c = cell_truth(mu, mu_r, rho, s);
            t += &format!(
                "[[sample]]\nname = \"cell {s} Pa\"\nexperiment = \"shear-cell\"\n\
                 psd = {{ d50_mm = 12, sigma_ln = 0.1 }}\nfixed = {{ normal_stress = {s} }}\n\
                 measured.internal_friction = {{ value = {}, sd = 1.3 }}\n\
                 measured.bulk_density = {{ value = {}, sd = 3.2 }}\n\
                 measured.shear_ratio = {{ value = {}, sd = 0.017 }}\n",
                c[0], c[1], c[2]
            );
        }
    }
    MeasurementSet::from_toml_str(&t, "gravel_like.toml").unwrap()
}

fn run(s: &MeasurementSet) -> Diagnosis {
    let opts = Options {
        samples: 1000,
        ..Options::default()
    };
    diagnose(s, &models(), &opts).unwrap()
}

#[test]
fn the_shear_cell_turns_the_shear_boxs_ridge_into_a_point() {
    let alone = run(&set(false));
    let joint = run(&set(true));
    // Each sample is predicted by the model of its own experiment.
    assert_eq!(joint.measurements, 2 * 2 + 2 * 3);
    assert!(joint.chi2_dof < 1.0, "{}", joint.chi2_dof);
    let truth = [("mu_pp", TRUTH.0), ("mu_r_pp", TRUTH.1), ("rho_p", TRUTH.2)];
    for (name, value) in truth {
        let get = |d: &Diagnosis| {
            d.base
                .parameters
                .iter()
                .find(|p| p.name == name)
                .unwrap_or_else(|| panic!("{name} not searched: {:?}", d.base.parameters))
                .clone()
        };
        let (a, j) = (get(&alone), get(&joint));
        eprintln!(
            "{name}: box alone [{:.4}, {:.4}], with the cell [{:.4}, {:.4}]",
            a.q05, a.q95, j.q05, j.q95
        );
        assert!(j.q05 <= value && value <= j.q95, "{name}: {j:?}");
        let shrink = (a.q95 - a.q05) / (j.q95 - j.q05);
        eprintln!("{name}: {shrink:.1}x narrower");
        assert!(
            shrink >= 3.0,
            "{name}: the interval shrank only {shrink:.2}x"
        );
    }
}
