//! `mbgc sensitivity`: which inputs matter for which response (seed 000's three levels, Sobol
//! indices on a metamodel, local sensitivities at a calibrated point).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use serde::Serialize;

use mbgc::experiments::hopper::FLOW_BIN_NAMES;
use mbgc::metamodel::table::read_columns_keeping_nan;
use mbgc::metamodel::{Metamodel, Transform};
use mbgc::plot::parity::{parity, Split};
use mbgc::plot::sensitivity::heat_map;
use mbgc::sensitivity::contact_derivatives::{Properties, State, PARAMETERS, PROPERTY_NAMES};
use mbgc::sensitivity::design_pca::{design_pca, varied};
use mbgc::sensitivity::figures::{exponent_bars, loading_bars, share_bars, sobol_bars};
use mbgc::sensitivity::norms::{summarise, NormSummary};
use mbgc::sensitivity::pca::Pca;
use mbgc::sensitivity::sensitivity_matrix::{over_grid, Equation, Grid, Scaling};
use mbgc::sensitivity::{flow_curve, local, power_law, sobol};
use mbgc_output::say;
use mbgc_output::Output;

#[derive(Debug, Args)]
pub struct SensitivityArgs {
    #[command(subcommand)]
    pub what: What,
}

#[derive(Debug, Subcommand)]
pub enum What {
    /// Level 1: power law y = A x1^b1 x2^b2 ... on the logarithms, every replicate kept; the
    /// exponents' 95 % intervals and the lack-of-fit test.
    PowerLaw(PowerLawArgs),
    /// The time-dependent flow rate FR0 / (1 + (t/K)^n) fitted to hopper runs' flow-rate bins.
    FlowCurve(FlowCurveArgs),
    /// Level 2: PCA of the autoscaled contact-law sensitivities at the design points joined with
    /// a bulk response, for the translational and the rotational equation of motion.
    Pca(PcaArgs),
    /// Level 3: norms and cross-correlations of the contact force's and torque's sensitivities
    /// over a grid of overlaps and velocities (seed 000: 3^4 = 81 states).
    Matrix(MatrixArgs),
    /// Sobol first and total indices of every response of a saved metamodel over its domain.
    Sobol(SobolArgs),
    /// Local sensitivities of a metamodel at one point: which response pins which parameter.
    Local(LocalArgs),
}

#[derive(Debug, Args)]
pub struct PowerLawArgs {
    /// Table (a campaign table or any CSV with a header).
    #[arg(long)]
    pub data: PathBuf,
    /// Input columns, comma-separated (positive values).
    #[arg(long, value_delimiter = ',', required = true)]
    pub inputs: Vec<String>,
    /// Target column; several comma-separated columns are replicates of one response (seed
    /// 000's four orthoslice angles of a run). Rows with equal inputs are replicates too.
    #[arg(long, value_delimiter = ',', required = true)]
    pub target: Vec<String>,
    /// Name of the response in the report (default: the first target column).
    #[arg(long)]
    pub name: Option<String>,
    /// Directory for the figures (parity, exponent bars).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct FlowCurveArgs {
    /// Hopper campaign table (columns flow_bin_width and flow_rate_t1 ..).
    #[arg(long)]
    pub data: PathBuf,
    /// Table rows to fit (0-based `row` column values); default all.
    #[arg(long, value_delimiter = ',')]
    pub rows: Vec<usize>,
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct PcaArgs {
    /// Design or campaign table with the contact-law parameters and the response.
    #[arg(long)]
    pub data: PathBuf,
    /// Bulk response column joined with the sensitivities.
    #[arg(long)]
    pub response: String,
    /// Values of properties the table lacks (E_p, nu_p, e_pp, mu_pp, mu_r_pp, rho_p, d50 in mm).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Contact state of the sensitivities: v_n, v_t (m/s), overlap (fraction of d50); default
    /// the centre of seed 000's levels (0.01 m/s, 0.01 m/s, 1 %).
    #[arg(long = "state", value_name = "NAME=VALUE")]
    pub state: Vec<String>,
    #[arg(long)]
    pub plot: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct MatrixArgs {
    /// A parameter point, `E_p=2e7,e_pp=0.45,mu_pp=0.25,mu_r_pp=0.25` (repeatable: one matrix
    /// per point).
    #[arg(long = "at", required = true)]
    pub at: Vec<String>,
    /// Values shared by every point (nu_p, rho_p, d50 in mm, or any of the four parameters).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// `relative`: p df/dp, comparable across units; `absolute`: df/dp as it stands (its size
    /// depends on each parameter's unit).
    #[arg(long, default_value = "relative")]
    pub scaling: String,
    #[arg(long)]
    pub plot: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct SobolArgs {
    #[arg(long)]
    pub model: PathBuf,
    /// Base points N (cost N (k + 2) model evaluations per response).
    #[arg(long, default_value_t = 4096)]
    pub samples: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Bootstrap resamples for the 95 % intervals.
    #[arg(long, default_value_t = 500)]
    pub bootstrap: usize,
    /// Responses (default all).
    #[arg(long, value_delimiter = ',')]
    pub responses: Vec<String>,
    #[arg(long)]
    pub plot: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct LocalArgs {
    #[arg(long)]
    pub model: PathBuf,
    /// The point, `name=value` for every input of the model (comma-separated or repeated).
    #[arg(long = "at", value_delimiter = ',', required = true)]
    pub at: Vec<String>,
    /// Uncertainty of a response, `name=sd` (default: the model's validation, else test, else
    /// training RMSE).
    #[arg(long = "sigma", value_delimiter = ',')]
    pub sigma: Vec<String>,
    /// Inputs known (held fixed), left out of the information matrix.
    #[arg(long, value_delimiter = ',')]
    pub fixed: Vec<String>,
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: &SensitivityArgs) -> anyhow::Result<()> {
    match &a.what {
        What::PowerLaw(a) => power_law_cmd(a),
        What::FlowCurve(a) => flow_curve_cmd(a),
        What::Pca(a) => pca_cmd(a),
        What::Matrix(a) => matrix_cmd(a),
        What::Sobol(a) => sobol_cmd(a),
        What::Local(a) => local_cmd(a),
    }
}

/// `name=value` pairs; the error names the option. A name given twice is refused: the last
/// value would otherwise win without a word.
fn pairs(option: &str, items: &[String]) -> anyhow::Result<Vec<(String, f64)>> {
    let list: Vec<(String, f64)> = pairs_as_given(option, items)?;
    unique(option, list.iter().map(|(n, _)| n.as_str()))?;
    Ok(list)
}

/// Each name once in a list option (`--target y,y` would count one column as two replicates).
fn unique<'a>(option: &str, names: impl IntoIterator<Item = &'a str>) -> anyhow::Result<()> {
    let mut seen: Vec<&str> = Vec::new();
    for n in names {
        if seen.contains(&n) {
            anyhow::bail!("{option}: {n} is given twice; expected each name once");
        }
        seen.push(n);
    }
    Ok(())
}

fn pairs_as_given(option: &str, items: &[String]) -> anyhow::Result<Vec<(String, f64)>> {
    items
        .iter()
        .flat_map(|s| s.split(','))
        .filter(|s| !s.trim().is_empty())
        .map(|s| {
            let (n, v) = s
                .split_once('=')
                .ok_or_else(|| anyhow::anyhow!("{option} {s}: expected NAME=VALUE"))?;
            let x: f64 = v
                .trim()
                .parse()
                .map_err(|_| anyhow::anyhow!("{option} {s}: {v} is not a number"))?;
            if !x.is_finite() {
                anyhow::bail!("{option} {s}: expected a finite number");
            }
            Ok((n.trim().to_string(), x))
        })
        .collect()
}

fn plot_dir(dir: &Option<PathBuf>) -> anyhow::Result<Option<&Path>> {
    if let Some(d) = dir {
        std::fs::create_dir_all(d).map_err(|e| anyhow::anyhow!("{}: {e}", d.display()))?;
    }
    Ok(dir.as_deref())
}

// ---------------------------------------------------------------------------------------------
// power-law

#[derive(Serialize)]
struct PowerLawReport {
    data: String,
    target: String,
    replicate_columns: Vec<String>,
    a: f64,
    a_ci95: [f64; 2],
    exponents: serde_json::Map<String, serde_json::Value>,
    observations: usize,
    groups: usize,
    dropped: usize,
    r2_log: f64,
    rmse: f64,
    lack_of_fit: serde_json::Value,
}

fn power_law_cmd(a: &PowerLawArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    unique("--inputs", a.inputs.iter().map(String::as_str))?;
    unique("--target", a.target.iter().map(String::as_str))?;
    if let Some(n) = a.target.iter().find(|t| a.inputs.contains(t)) {
        anyhow::bail!("--target {n}: also an input");
    }
    let mut names = a.inputs.clone();
    names.extend(a.target.iter().cloned());
    let cols = read_columns_keeping_nan(&a.data, &names, a.inputs.len())?;
    let rows = cols.values.first().map_or(0, Vec::len);
    let k = a.inputs.len();
    let x: Vec<Vec<f64>> = (0..rows)
        .map(|r| (0..k).map(|j| cols.values[j][r]).collect())
        .collect();
    let y: Vec<Vec<f64>> = (0..rows)
        .map(|r| (k..names.len()).map(|j| cols.values[j][r]).collect())
        .collect();
    let name = a.name.clone().unwrap_or_else(|| a.target[0].clone());
    let source = a.data.display().to_string();
    let groups = power_law::Groups::from_rows(&a.inputs, &name, &x, &y, &source)?;
    let fit = power_law::fit(&groups)?;
    say!(out, "power law for {name} on {source}: {} observations in {} groups ({} not finite, left out; {} rows not done)", fit.observations, fit.groups, fit.dropped, cols.skipped);
    say!(
        out,
        "  {name} = A * {}",
        a.inputs
            .iter()
            .map(|i| format!("{i}^b_{i}"))
            .collect::<Vec<_>>()
            .join(" * ")
    );
    say!(
        out,
        "  A = {:.4} [{:.4}, {:.4}]",
        fit.a,
        fit.a_ci95[0],
        fit.a_ci95[1]
    );
    for (n, e) in &fit.exponents {
        say!(
            out,
            "  exponent of {n:<10} {:+.4}  95 % [{:+.4}, {:+.4}]{}",
            e.value,
            e.ci95[0],
            e.ci95[1],
            if e.significant {
                ""
            } else {
                "  (interval holds 0: not significant)"
            }
        );
    }
    say!(out, "  R^2 (logs) {:.4}, RMSE {:.4}", fit.r2_log, fit.rmse);
    match &fit.lack_of_fit {
        Ok(l) => say!(
            out,
            "  lack of fit: F = {:.2} on ({}, {}) dof, F(0.95) = {:.2}, p = {:.2e}: {}",
            l.ratio,
            l.dof_lack_of_fit,
            l.dof_pure_error,
            l.f_critical_95,
            l.p_value,
            if l.significant {
                "the model's error exceeds the replicates' scatter (the power law misses structure)"
            } else {
                "the model's error is within the replicates' scatter"
            }
        ),
        Err(why) => say!(out, "  lack of fit: not tested ({why})"),
    }
    if let Some(dir) = plot_dir(&a.plot)? {
        let (o, p): (Vec<f64>, Vec<f64>) = fit.parity.iter().copied().unzip();
        let f1 = dir.join(format!("power_law_{name}_parity.svg"));
        parity(
            &f1,
            &name,
            &[Split {
                label: "power law",
                observed: &o,
                predicted: &p,
            }],
        )?;
        let f2 = dir.join(format!("power_law_{name}_exponents.svg"));
        exponent_bars(&f2, &name, &fit)?;
        say!(out, "  figures: {}, {}", f1.display(), f2.display());
    }
    let mut exps = serde_json::Map::new();
    for (n, e) in &fit.exponents {
        exps.insert(n.clone(), serde_json::to_value(e)?);
    }
    out.object(&PowerLawReport {
        data: source,
        target: name,
        replicate_columns: a.target.clone(),
        a: fit.a,
        a_ci95: fit.a_ci95,
        exponents: exps,
        observations: fit.observations,
        groups: fit.groups,
        dropped: fit.dropped,
        r2_log: fit.r2_log,
        rmse: fit.rmse,
        lack_of_fit: match &fit.lack_of_fit {
            Ok(l) => serde_json::to_value(l)?,
            Err(why) => serde_json::json!({ "tested": false, "reason": why }),
        },
    })
}

// ---------------------------------------------------------------------------------------------
// flow-curve

#[derive(Serialize)]
struct FlowCurveRow {
    row: usize,
    inputs: Vec<(String, f64)>,
    fit: Option<flow_curve::FlowCurveFit>,
    error: Option<String>,
}

fn flow_curve_cmd(a: &FlowCurveArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    let rows: Vec<String> = a.rows.iter().map(usize::to_string).collect();
    unique("--rows", rows.iter().map(String::as_str))?;
    let mut names = vec!["row".to_string(), "flow_bin_width".to_string()];
    names.extend(FLOW_BIN_NAMES.iter().map(|s| s.to_string()));
    let cols = read_columns_keeping_nan(&a.data, &names, 2)?;
    let header_inputs: Vec<String> = ["E_p", "e_pp", "mu_pp", "mu_r_pp"]
        .iter()
        .filter(|n| cols.header.iter().any(|h| h == *n))
        .map(|s| s.to_string())
        .collect();
    let idx: Vec<usize> = header_inputs
        .iter()
        .map(|n| cols.header.iter().position(|h| h == n).unwrap_or(0))
        .collect();
    let mut report = Vec::new();
    for (r, rec) in cols.records.iter().enumerate() {
        let row = cols.values[0][r] as usize;
        if !a.rows.is_empty() && !a.rows.contains(&row) {
            continue;
        }
        let w = cols.values[1][r];
        // Bin k covers [k w, (k + 1) w): a width of 0 puts every bin at t = 0.
        if !(w.is_finite() && w > 0.0) {
            anyhow::bail!(
                "{}: row {row}, column flow_bin_width: {w}; expected a positive bin width in \
                 seconds (the flow_rate_t* bins are consecutive windows of this width)",
                a.data.display()
            );
        }
        let t: Vec<f64> = (0..FLOW_BIN_NAMES.len())
            .map(|k| (k as f64 + 0.5) * w)
            .collect();
        let y: Vec<f64> = (0..FLOW_BIN_NAMES.len())
            .map(|k| cols.values[2 + k][r])
            .collect();
        let inputs: Vec<(String, f64)> = header_inputs
            .iter()
            .zip(&idx)
            .map(|(n, &i)| (n.clone(), rec[i].parse().unwrap_or(f64::NAN)))
            .collect();
        let fit = flow_curve::fit(&t, &y);
        let desc = inputs
            .iter()
            .map(|(n, v)| format!("{n}={v}"))
            .collect::<Vec<_>>()
            .join(" ");
        match &fit {
            Ok(f) => say!(
                out,
                "row {row} ({desc}): FR0 {:.4} kg/s [{:.4}, {:.4}], K {:.3} s [{:.3}, {:.3}], n {:.2} [{:.2}, {:.2}], RMSE {:.2e}",
                f.fr0.value, f.fr0.ci95[0], f.fr0.ci95[1], f.k.value, f.k.ci95[0], f.k.ci95[1],
                f.n.value, f.n.ci95[0], f.n.ci95[1], f.rmse
            ),
            Err(e) => say!(out, "row {row} ({desc}): not fitted: {e}"),
        }
        report.push(FlowCurveRow {
            row,
            inputs,
            error: fit.as_ref().err().map(|e| e.to_string()),
            fit: fit.ok(),
        });
    }
    if report.is_empty() {
        anyhow::bail!("{}: no done row matched --rows", a.data.display());
    }
    // A command whose every row failed has produced nothing: say so by the exit status too.
    if report.iter().all(|r| r.fit.is_none()) {
        out.object(&serde_json::json!({ "data": a.data.display().to_string(), "model": "FR(t) = FR0 / (1 + (t/K)^n)", "rows": report }))?;
        anyhow::bail!(
            "{}: no row's flow-rate curve could be fitted (reasons above)",
            a.data.display()
        );
    }
    out.object(&serde_json::json!({ "data": a.data.display().to_string(), "model": "FR(t) = FR0 / (1 + (t/K)^n)", "rows": report }))
}

// ---------------------------------------------------------------------------------------------
// pca

fn state_from(items: &[String], d50_m: f64) -> anyhow::Result<State> {
    let mut s = Grid::seed000().centre(d50_m);
    for (n, v) in pairs("--state", items)? {
        match n.as_str() {
            "v_n" => s.v_n = v,
            "v_t" => s.v_t = v,
            "overlap" => {
                s.delta_n = v * d50_m;
                s.delta_t = v * d50_m;
            }
            _ => anyhow::bail!("--state {n}: expected v_n, v_t or overlap"),
        }
        if v <= 0.0 {
            anyhow::bail!("--state {n}={v}: expected a positive value");
        }
    }
    Ok(s)
}

#[derive(Serialize)]
struct PcaReport {
    data: String,
    response: String,
    state: StateJson,
    dropped: usize,
    translational: Pca,
    rotational: Pca,
}

#[derive(Serialize)]
struct StateJson {
    v_n: f64,
    v_t: f64,
    overlap_m: f64,
}

fn pca_cmd(a: &PcaArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    let set: HashMap<String, f64> = pairs("--set", &a.set)?.into_iter().collect();
    for n in set.keys() {
        if !PROPERTY_NAMES.contains(&n.as_str()) {
            anyhow::bail!("--set {n}: expected one of {}", PROPERTY_NAMES.join(", "));
        }
    }
    let (_, header) = mbgc::error::csv_open(&a.data)?;
    let from_table: Vec<String> = PROPERTY_NAMES
        .iter()
        .filter(|n| header.iter().any(|h| h == *n))
        .map(|s| s.to_string())
        .collect();
    for n in &from_table {
        if set.contains_key(n) {
            anyhow::bail!("--set {n}: the table has a column {n} already");
        }
    }
    let mut names = from_table.clone();
    names.push(a.response.clone());
    let cols = read_columns_keeping_nan(&a.data, &names, from_table.len())?;
    let rows = cols.values[0].len();
    let source = a.data.display().to_string();
    let points = (0..rows)
        .map(|r| {
            Properties::from_named(
                |n| {
                    from_table
                        .iter()
                        .position(|c| c == n)
                        .map(|k| cols.values[k][r])
                        .or_else(|| set.get(n).copied())
                },
                &format!("{source} row {}", r + 1),
            )
        })
        .collect::<mbgc::error::Result<Vec<_>>>()?;
    let response = &cols.values[from_table.len()];
    let params = varied(&points);
    let d = 2.0 * points.first().map_or(1e-3, |p| p.radius);
    let state = state_from(&a.state, d)?;
    let mut result = Vec::new();
    for eq in Equation::BOTH {
        let d = design_pca(&points, &a.response, response, &state, eq, &params)?;
        let (p, dropped) = (d.pca, d.dropped);
        say!(
            out,
            "{} equation: PCA of [{}] over {} design points ({} without a response){}",
            eq.name(),
            p.columns.join(", "),
            p.rows,
            dropped,
            if d.constant.is_empty() {
                String::new()
            } else {
                format!(
                    "; left out, their sensitivity does not vary in this equation: {}",
                    d.constant.join(", ")
                )
            }
        );
        for (i, c) in p.components.iter().enumerate() {
            let l = c
                .loadings
                .iter()
                .map(|(n, v)| format!("{n} {v:+.3}"))
                .collect::<Vec<_>>()
                .join(", ");
            say!(
                out,
                "  PC{} eigenvalue {:.3} ({:.1} %): {l}",
                i + 1,
                c.eigenvalue,
                100.0 * c.explained
            );
        }
        result.push((p, dropped));
    }
    if let Some(dir) = plot_dir(&a.plot)? {
        for (eq, (p, _)) in Equation::BOTH.iter().zip(&result) {
            let f = dir.join(format!("pca_{}_{}.svg", a.response, eq.name()));
            loading_bars(
                &f,
                &format!("{}: {} equation, PCA loadings", a.response, eq.name()),
                p,
            )?;
            say!(out, "  figure: {}", f.display());
        }
    }
    let dropped = result[0].1;
    let mut it = result.into_iter().map(|(p, _)| p);
    out.object(&PcaReport {
        data: source,
        response: a.response.clone(),
        state: StateJson {
            v_n: state.v_n,
            v_t: state.v_t,
            overlap_m: state.delta_n,
        },
        dropped,
        translational: it.next().expect("two equations"),
        rotational: it.next().expect("two equations"),
    })
}

// ---------------------------------------------------------------------------------------------
// matrix

#[derive(Serialize)]
struct MatrixPoint {
    at: Vec<(String, f64)>,
    states: usize,
    translational: NormSummary,
    rotational: NormSummary,
    /// Fraction of the states in gross sliding / with the rolling torque at its cap.
    sliding_fraction: f64,
    rolling_cap_fraction: f64,
}

fn matrix_cmd(a: &MatrixArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    let set: HashMap<String, f64> = pairs("--set", &a.set)?.into_iter().collect();
    let scaling = Scaling::parse(&a.scaling)
        .ok_or_else(|| anyhow::anyhow!("--scaling {}: expected relative or absolute", a.scaling))?;
    let grid = Grid::seed000();
    let names: Vec<String> = PARAMETERS.iter().map(|s| s.to_string()).collect();
    let mut points = Vec::new();
    for (i, at) in a.at.iter().enumerate() {
        let mut vals = set.clone();
        for (n, v) in pairs("--at", std::slice::from_ref(at))? {
            if set.contains_key(&n) {
                anyhow::bail!(
                    "--at {n}: also given by --set; expected each value once (--set for what \
                     all points share, --at for what differs)"
                );
            }
            vals.insert(n, v);
        }
        for n in vals.keys() {
            if !PROPERTY_NAMES.contains(&n.as_str()) {
                anyhow::bail!(
                    "--at/--set {n}: expected one of {}",
                    PROPERTY_NAMES.join(", ")
                );
            }
        }
        let p = Properties::from_named(|n| vals.get(n).copied(), &format!("--at #{}", i + 1))?;
        let states = grid.states(2.0 * p.radius);
        let evals: Vec<_> = states
            .iter()
            .map(|s| mbgc::sensitivity::contact_derivatives::evaluate(&p, s))
            .collect();
        let frac = |f: &dyn Fn(&mbgc::sensitivity::contact_derivatives::Response) -> bool| {
            evals.iter().filter(|r| f(r)).count() as f64 / evals.len() as f64
        };
        let summary = |eq| {
            let m: Vec<Vec<f64>> = over_grid(&p, &grid, eq, scaling)
                .iter()
                .map(|r| r.to_vec())
                .collect();
            summarise(&names, &m)
        };
        let at: Vec<(String, f64)> = names.iter().cloned().zip(p.values()).collect();
        let (translational, rotational) = (
            summary(Equation::Translational),
            summary(Equation::Rotational),
        );
        // Norms must be finite; a correlation may be undefined (NaN: a parameter the equation
        // does not depend on) but never infinite, which only an overflow gives.
        let infinite = [&translational, &rotational].iter().any(|s| {
            s.norms.iter().chain(&s.shares).any(|v| !v.is_finite())
                || s.cross_correlation
                    .iter()
                    .flatten()
                    .any(|v| v.is_infinite())
        });
        if infinite {
            anyhow::bail!(
                "--at #{} ({}): the contact law's derivatives overflow or are undefined there \
                 (a norm, a share or a correlation is not finite); expected a physical point (E_p from about 1e3 to 1e12 Pa)",
                i + 1,
                at.iter()
                    .map(|(n, v)| format!("{n}={v:e}"))
                    .collect::<Vec<_>>()
                    .join(",")
            );
        }
        let point = MatrixPoint {
            at,
            states: states.len(),
            translational,
            rotational,
            sliding_fraction: frac(&|r| r.sliding),
            rolling_cap_fraction: frac(&|r| r.rolling_at_cap),
        };
        let desc = point
            .at
            .iter()
            .map(|(n, v)| format!("{n}={v}"))
            .collect::<Vec<_>>()
            .join(" ");
        say!(
            out,
            "point {} ({desc}): {} states, {:.0} % sliding, {:.0} % rolling torque at its cap",
            i + 1,
            point.states,
            100.0 * point.sliding_fraction,
            100.0 * point.rolling_cap_fraction
        );
        for (eq, s) in [
            ("translational", &point.translational),
            ("rotational", &point.rotational),
        ] {
            let shares = s
                .parameters
                .iter()
                .zip(&s.shares)
                .map(|(n, v)| format!("{n} {:.3}", v))
                .collect::<Vec<_>>()
                .join(", ");
            say!(out, "  {eq}: norm shares {shares}");
            for (n, row) in s.parameters.iter().zip(&s.cross_correlation) {
                say!(
                    out,
                    "    CC {n:<8} {}",
                    row.iter()
                        .map(|v| if v.is_nan() {
                            "   n/a".to_string()
                        } else {
                            format!("{v:+.3}")
                        })
                        .collect::<Vec<_>>()
                        .join(" ")
                );
            }
            let flat: Vec<&String> = s
                .parameters
                .iter()
                .zip(&s.norms)
                .filter(|(_, n)| **n == 0.0)
                .map(|(p, _)| p)
                .collect();
            if !flat.is_empty() {
                say!(
                    out,
                    "    n/a: the {eq} equation does not depend on {} at this point (sensitivity \
                     0), so its correlations are undefined",
                    flat.iter()
                        .map(|p| p.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                );
            }
        }
        points.push(point);
    }
    if let Some(dir) = plot_dir(&a.plot)? {
        for eq in ["translational", "rotational"] {
            let summaries: Vec<(String, &NormSummary)> = points
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let s = if eq == "translational" {
                        &p.translational
                    } else {
                        &p.rotational
                    };
                    (format!("point {}", i + 1), s)
                })
                .collect();
            let f = dir.join(format!("matrix_norms_{eq}.svg"));
            share_bars(
                &f,
                &format!(
                    "{eq} equation: normalised sensitivity norms ({} scaling)",
                    scaling.name()
                ),
                "norm share",
                &names,
                &summaries,
            )?;
            let s = if eq == "translational" {
                &points[0].translational
            } else {
                &points[0].rotational
            };
            let h = dir.join(format!("matrix_cross_correlation_{eq}.svg"));
            heat_map(
                &h,
                &format!("{eq} equation: cross-correlation (point 1)"),
                &names,
                &s.cross_correlation,
            )?;
            say!(out, "  figures: {}, {}", f.display(), h.display());
        }
    }
    out.object(&serde_json::json!({ "scaling": scaling.name(), "grid": "seed 000: v_n, v_t = 1e-4, 0.01, 1 m/s; w = 0.01, 1, 100 rad/s; delta_n = delta_t = 0.1, 1, 10 % of d", "points": points }))
}

// ---------------------------------------------------------------------------------------------
// sobol

#[derive(Serialize)]
struct SobolInput {
    first: f64,
    first_ci95: [f64; 2],
    total: f64,
    total_ci95: [f64; 2],
}

#[derive(Serialize)]
struct SobolResponse {
    variance: f64,
    mean: f64,
    samples: usize,
    dropped: usize,
    inputs: serde_json::Map<String, serde_json::Value>,
}

fn sobol_cmd(a: &SobolArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    let model = Metamodel::load(&a.model)?;
    // Before the model is evaluated, with the range the estimator itself enforces.
    sobol::check_bootstrap(a.bootstrap)?;
    unique("--responses", a.responses.iter().map(String::as_str))?;
    let responses: Vec<String> = if a.responses.is_empty() {
        model.responses.iter().map(|r| r.name.clone()).collect()
    } else {
        a.responses.clone()
    };
    let k = model.inputs.len();
    let names = model.input_names();
    say!(out, "Sobol indices of {} over its domain: N = {} base points, {} evaluations per response, {} bootstrap resamples (seed {})", a.model.display(), a.samples, a.samples.saturating_mul(k + 2), a.bootstrap, a.seed);
    for inp in &model.inputs {
        let how = if matches!(inp.transform, Transform::Log { .. }) {
            "log-uniform"
        } else {
            "uniform"
        };
        say!(
            out,
            "  {} {how} on [{}, {}]",
            inp.name,
            inp.domain[0],
            inp.domain[1]
        );
    }
    let mut report = serde_json::Map::new();
    let mut series = Vec::new();
    let all = sobol::model_indices(&model, &responses, a.samples, a.seed, a.bootstrap)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.model.display()))?;
    for (name, s) in &all {
        say!(
            out,
            "{name}: mean {:.4}, variance {:.4e}{}",
            s.mean,
            s.variance,
            if s.dropped > 0 {
                format!(
                    " ({} of {} base points dropped: not finite)",
                    s.dropped, s.samples
                )
            } else {
                String::new()
            }
        );
        let mut inputs = serde_json::Map::new();
        for (n, x) in names.iter().zip(&s.inputs) {
            say!(
                out,
                "  {n:<10} first {:.3} [{:.3}, {:.3}]  total {:.3} [{:.3}, {:.3}]",
                x.first,
                x.first_ci95[0],
                x.first_ci95[1],
                x.total,
                x.total_ci95[0],
                x.total_ci95[1]
            );
            inputs.insert(
                n.clone(),
                serde_json::to_value(SobolInput {
                    first: x.first,
                    first_ci95: x.first_ci95,
                    total: x.total,
                    total_ci95: x.total_ci95,
                })?,
            );
        }
        series.push((name.clone(), s.inputs.clone()));
        report.insert(
            name.clone(),
            serde_json::to_value(SobolResponse {
                variance: s.variance,
                mean: s.mean,
                samples: s.samples,
                dropped: s.dropped,
                inputs,
            })?,
        );
    }
    if let Some(dir) = plot_dir(&a.plot)? {
        for (name, idx) in &series {
            let f = dir.join(format!("sobol_{name}.svg"));
            sobol_bars(
                &f,
                &format!("{name}: Sobol indices, 95 % bootstrap intervals"),
                &names,
                idx,
            )?;
            say!(out, "  figure: {}", f.display());
        }
    }
    out.object(&serde_json::json!({
        "model": a.model.display().to_string(),
        "samples": a.samples,
        "seed": a.seed,
        "bootstrap": a.bootstrap,
        "estimators": "first: Saltelli 2010; total: Jansen 1999",
        "responses": report,
    }))
}

// ---------------------------------------------------------------------------------------------
// local

fn local_cmd(a: &LocalArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    let model = Metamodel::load(&a.model)?;
    let at: HashMap<String, f64> = pairs("--at", &a.at)?.into_iter().collect();
    let names = model.input_names();
    for n in at.keys() {
        if !names.contains(n) {
            anyhow::bail!(
                "--at {n}: not an input of {} (inputs: {})",
                a.model.display(),
                names.join(", ")
            );
        }
    }
    let x: Vec<f64> = names
        .iter()
        .map(|n| {
            at.get(n).copied().ok_or_else(|| {
                anyhow::anyhow!("--at: no value of input {n} (every input of the model needs one)")
            })
        })
        .collect::<anyhow::Result<_>>()?;
    for (n, v, [lo, hi]) in model.outside_domain(&x) {
        say!(
            out,
            "warning: {n} = {v} lies outside the model's domain [{lo}, {hi}]"
        );
    }
    let given: HashMap<String, f64> = pairs("--sigma", &a.sigma)?.into_iter().collect();
    for n in given.keys() {
        if model.response(n).is_none() {
            anyhow::bail!("--sigma {n}: not a response of {}", a.model.display());
        }
    }
    let responses: Vec<String> = model.responses.iter().map(|r| r.name.clone()).collect();
    let sigma: Vec<f64> = model
        .responses
        .iter()
        .map(|r| {
            given.get(&r.name).copied().unwrap_or_else(|| {
                r.validation
                    .as_ref()
                    .or(r.test.as_ref())
                    .map_or(r.train.rmse, |m| m.rmse)
            })
        })
        .collect();
    unique("--fixed", a.fixed.iter().map(String::as_str))?;
    let l = local::at_point(&model, &x, &responses, &sigma, &a.fixed)?;
    say!(
        out,
        "local sensitivities of {} at {}",
        a.model.display(),
        l.point
            .iter()
            .map(|(n, v)| format!("{n}={v}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for r in &l.responses {
        say!(
            out,
            "  {} = {:.4} (sigma {:.4}); elasticities: {}",
            r.response,
            r.value,
            r.sigma,
            l.parameters
                .iter()
                .zip(&r.elasticity)
                .map(|(n, e)| format!("{n} {e:+.3}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    for (k, p) in l.parameters.iter().enumerate() {
        let shares = responses
            .iter()
            .zip(&l.information_share[k])
            .map(|(r, s)| format!("{r} {:.0} %", 100.0 * s))
            .collect::<Vec<_>>()
            .join(", ");
        let sd = l
            .parameter_sd
            .as_ref()
            .map_or("not identifiable".to_string(), |s| {
                format!("sd {:.4}", s[k])
            });
        say!(out, "  {p}: {sd}; information from {shares}");
    }
    if l.parameter_sd.is_none() {
        say!(out, "  the information matrix is singular: the responses cannot pin every free parameter (fix some with --fixed)");
    }
    out.object(&l)
}
