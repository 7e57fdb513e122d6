//! A session as the text report `mbgc calibrate` prints: the material and its measurements, the
//! distinct optima and which fit, what the data cannot decide, and the posterior.

use std::fmt::Write;

use super::session::Session;

/// Appends one formatted line (writing to a `String` cannot fail).
macro_rules! line {
    ($out:expr, $($arg:tt)*) => {{
        let _ = writeln!($out, $($arg)*);
    }};
}

/// The report of `s`, one line per `\n`. It lists the first ten optima; `rest` names where the
/// caller keeps the others (`--json` for the command line).
pub fn text(s: &Session, rest: &str) -> String {
    let mut out = String::new();
    let cal = &s.calibration;
    let names = &s.free;
    line!(out, "{} ({}) with {}", s.material, s.source, s.model);
    for n in &s.notes {
        line!(out, "  {n}");
    }
    for (n, v) in &s.fixed {
        line!(out, "  {n} = {v} fixed");
    }
    let meas: Vec<String> = s
        .measured
        .iter()
        .map(|t| format!("{} {} +- {}", t.name, t.value, t.sd))
        .collect();
    line!(out, "  measured: {}", meas.join(", "));
    let fitting = s.fitting().len();
    let others = cal.optima.len() - fitting;
    line!(
        out,
        "{fitting} of {} distinct optima from {} starts in {:.3} s fit the measurements (chi2 <= \
         {:.2}, the 95 % level for {} measurement{}):",
        cal.optima.len(),
        cal.starts,
        cal.seconds,
        s.fit_threshold(),
        s.measured.len(),
        if s.measured.len() == 1 { "" } else { "s" }
    );
    for (i, o) in cal.optima.iter().enumerate().take(10) {
        if i == fitting && others > 0 {
            line!(out, "  local minima that do not fit:");
        }
        let params: Vec<String> = names
            .iter()
            .zip(&o.x)
            .map(|(n, v)| format!("{n} = {v:.4}"))
            .collect();
        let fits: Vec<String> = s
            .measured
            .iter()
            .zip(o.predictions.iter().zip(&o.residuals))
            .map(|(t, (p, r))| format!("{} {p:.4} ({r:+.2} sd)", t.name))
            .collect();
        line!(
            out,
            "  #{} chi2 {:.3e} ({} starts): {}\n      predicted {}",
            i + 1,
            o.chi2,
            o.starts,
            params.join(", "),
            fits.join(", ")
        );
    }
    if cal.optima.len() > 10 {
        line!(out, "  ... {} more (see {rest})", cal.optima.len() - 10);
    }
    if !s.unused.is_empty() {
        line!(
            out,
            "Not in any equation of the measured responses (any value in range fits equally): {}",
            s.unused.join(", ")
        );
    }
    if cal.excess_parameters > 0 {
        let equal = s.equally_good().len();
        if equal > 1 {
            line!(
                out,
                "{equal} of the optima are equally good points of one continuous solution set, \
                 not separate answers."
            );
        }
        line!(
            out,
            "{} free parameters but {} measurements: the data fix at most {} combinations; the \
             solutions form a set of dimension >= {}.",
            names.len(),
            s.measured.len(),
            s.measured.len(),
            cal.excess_parameters
        );
    }
    if !cal.flat_directions.is_empty() {
        line!(
            out,
            "Directions at the best optimum along which the predictions do not change (unit-box \
             steps):"
        );
        for d in &cal.flat_directions {
            let comp: Vec<String> = names
                .iter()
                .zip(&d.components)
                .filter(|(_, c)| c.abs() >= 0.05)
                .map(|(n, c)| format!("{c:+.2} {n}"))
                .collect();
            line!(
                out,
                "  {}  (singular value {:.1e})",
                comp.join(" "),
                d.singular_value
            );
        }
        line!(
            out,
            "Range of each parameter over the equally good optima (-2 ln L within 1 of the best):"
        );
        for r in &cal.solution_ranges {
            line!(out, "  {} in [{:.4}, {:.4}]", r.name, r.min, r.max);
        }
    }
    if let Some(post) = &s.posterior {
        line!(
            out,
            "Posterior (TMCMC, {} samples, {} stages): log evidence {:.3}",
            post.samples,
            post.stages,
            post.ln_evidence
        );
        for p in &post.parameters {
            line!(
                out,
                "  {:>12}: mean {:.4}, COV {:.3}, 5 % {:.4}, 95 % {:.4}",
                p.name,
                p.mean,
                p.cov,
                p.q05,
                p.q95
            );
        }
        line!(
            out,
            "Posterior-robust predictions (mean +- sd over the posterior):"
        );
        for r in &post.responses {
            line!(out, "  {:>12}: {:.4} +- {:.4}", r.name, r.mean, r.sd);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::session::{run, SessionOptions};
    use crate::material::Material;
    use crate::shipped;

    /// The shipped model and example: the report's lines, with where the other optima are.
    #[test]
    fn the_report_names_the_material_the_optima_and_the_caller_s_place_for_the_rest() {
        let (model, label) = shipped::model(shipped::SHEAR_BOX).unwrap();
        let material = Material::from_file(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../..")
                .join(shipped::GRAVEL),
        )
        .unwrap();
        let mut s = run(&material, &model, &label, &SessionOptions::default()).unwrap();
        let report = text(&s, "--json");
        let first = report.lines().next().unwrap();
        assert!(
            first.starts_with("Gravel 8/16 (") && first.ends_with(") with models/shear_box.json"),
            "{first}"
        );
        assert!(
            report.contains("distinct optima from 64 starts"),
            "{report}"
        );
        assert!(report.ends_with('\n') && !report.contains("more (see"));
        let optimum = s.calibration.optima[0].clone();
        s.calibration.optima = vec![optimum; 12];
        assert!(text(&s, ".solutions").contains("  ... 2 more (see .solutions)\n"));
    }
}
