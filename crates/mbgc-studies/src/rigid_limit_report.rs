//! The rigid limit of a shear-box model (issue 40): from the stiffness lines
//! (`mbgc bench stiffness`, runs beyond the model's stiffness range through points of its
//! space), the curves by which the model answers for materials stiffer or softer than its
//! campaign ran, written into a copy of the model, with a report of the curves and how each form
//! predicts a left-out line.
//!
//! `mbgc bench rigid-limit --model models/shear_box.json --tables <stiffness tables> --out
//! <model.json> --report docs/rigid_limit.md`

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context as _;

use super::stiffness_dependence::{line_point, read_rows, Row};
use mbgc::metamodel::rigid_fit::{fit_cohesion, fit_rigid_limit, CohesionLine, Line, RigidFit};
use mbgc::metamodel::rigid_limit::Form;
use mbgc::metamodel::Metamodel;

/// `mbgc bench rigid-limit`.
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Args {
    /// The model to extend (a shear-box model fitted in K_p and K_w).
    #[cfg_attr(feature = "cli", arg(long))]
    pub model: PathBuf,
    /// Stiffness tables (`bench stiffness --table`), comma-separated.
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ',', required = true))]
    pub tables: Vec<PathBuf>,
    /// The lines' cohesion group Bo (0: the lines without cohesion, for a model without it).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 0.0))]
    pub bond: f64,
    /// Stiffness tables with cohesion lines (runs with C_pp on the edge and at the same
    /// C_pp K_p^(-2/3) beyond it), comma-separated: for a cohesive model, the scatter of
    /// reading its cohesion at the edge. The runs without cohesion come from `--tables`.
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ','))]
    pub cohesion_tables: Vec<PathBuf>,
    /// K_p where the model's cohesive runs stop, when below its edge (a cohesion correction
    /// that reads the stiffness only through the contact pull, fitted onto a wider base): the
    /// similarity's scatter then counts from there, inside the model's data as beyond it.
    #[cfg_attr(feature = "cli", arg(long))]
    pub cohesion_edge: Option<f64>,
    /// The largest E_p and E_w the model then takes (seed 004's top, Pa); K_p and K_w stay
    /// bounded by the lines' reach.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 5e8))]
    pub e_max: f64,
    /// A line's run this close to the model's edge of K_p (in decades, at most 0.05) stands for
    /// the edge. The lines were run at the shipped model's edges; a model whose campaign ends
    /// elsewhere (the widened one's 9.77e6, 0.0101 decades below the lines' 1e7) needs more.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = mbgc::metamodel::rigid_fit::EDGE_DECADES))]
    pub edge_decades: f64,
    /// The model with its rigid limit (never the input model).
    #[cfg_attr(feature = "cli", arg(long))]
    pub out: PathBuf,
    /// Markdown report.
    #[cfg_attr(feature = "cli", arg(long))]
    pub report: Option<PathBuf>,
    /// Standard output holds one JSON object (where the report went); text goes to standard
    /// error.
    #[cfg_attr(feature = "cli", arg(long))]
    pub json: bool,
}

/// The weight group of the lines' points (rho_p 2600, d50 8 mm): E = K_p times this.
const WEIGHT: f64 = 2600.0 * 9.81 * 8e-3;

/// Runs the study.
pub fn run(a: &Args) -> anyhow::Result<()> {
    mbgc::outputs::refuse_overwriting_inputs("--out", &a.out, &[("--model", &a.model)])?;
    let model = Metamodel::load(&a.model)?;
    let (all_rows, source) = read_tables(&a.tables)?;
    let rows: Vec<Row> = all_rows
        .iter()
        .filter(|r| r.job.bond == a.bond)
        .cloned()
        .collect();
    let lines = lines(&model, &rows, a.bond)?;
    let fit = RigidFit {
        group: "K_p",
        along: "E_p",
        wall: Some(("K_w", "E_w")),
        along_max: a.e_max,
        source: source.join(", "),
        edge_decades: a.edge_decades,
    };
    let mut extended = fit_rigid_limit(&model, &fit, &lines)?;
    if a.cohesion_edge.is_some() && a.cohesion_tables.is_empty() {
        anyhow::bail!(
            "--cohesion-edge without --cohesion-tables: the scatter it places is measured on \
             the cohesion lines"
        );
    }
    if !a.cohesion_tables.is_empty() {
        if a.bond != 0.0 {
            anyhow::bail!(
                "--cohesion-tables with --bond {}: the stiffness curves of a cohesive model are \
                 the lines without cohesion (--bond 0), its cohesion is carried to the edge",
                a.bond
            );
        }
        let (coh_rows, coh_source) = read_tables(&a.cohesion_tables)?;
        let mut both: Vec<Row> = all_rows
            .iter()
            .filter(|r| r.job.bond == 0.0)
            .cloned()
            .collect();
        both.extend(coh_rows.into_iter().filter(|r| r.job.bond > 0.0));
        let coh_lines = cohesion_lines(&model, &both)?;
        let measured = format!(
            "lines {} ({}; the runs without cohesion from {})",
            coh_lines
                .iter()
                .map(|l| l.label.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            coh_source.join(", "),
            source.join(", ")
        );
        let group_of = |ced: &str| {
            extended
                .group_of_input(ced)
                .map(|g| g.group.name.clone())
                .filter(|g| extended.along_input(g, ced).is_some())
        };
        let pp_group = group_of("ced_pp")
            .ok_or_else(|| anyhow::anyhow!("the model has no group that ced_pp alone moves"))?;
        let pp = fit_cohesion(
            &extended,
            &pp_group,
            "ced_pp",
            ["E_p", "E_p"],
            &coh_lines,
            measured,
            a.cohesion_edge,
        )?;
        let mut cohesion = vec![pp.clone()];
        if let Some(pw_group) = group_of("ced_pw") {
            // The lines' walls were not cohesive: the wall's similarity is the particles'
            // physics with the wall contact's modulus, its scatter taken over unmeasured. The
            // reference carries over: at E_w = E_p both groups have one value per ced.
            cohesion.push(mbgc::metamodel::rigid_limit::Cohesion {
                group: pw_group,
                along: "ced_pw".into(),
                contact: ["E_p".into(), "E_w".into()],
                measured: format!(
                    "not measured (the lines' walls were not cohesive): the scatter of {pp_group}"
                ),
                ..pp
            });
        }
        if let Some(l) = extended.rigid_limit.as_mut() {
            l.cohesion = cohesion;
        }
    }
    extended.save(&a.out)?;
    let text = report(a, &model, &extended);
    crate::emit_report(
        a.json,
        a.report.as_deref(),
        &text,
        serde_json::json!({ "model": a.out, "lines": lines.len() }),
    )
}

/// The rows of `tables` (a second row of the same run left out with a warning) and each
/// table's name and hash.
fn read_tables(tables: &[PathBuf]) -> anyhow::Result<(Vec<Row>, Vec<String>)> {
    let mut rows: Vec<Row> = Vec::new();
    let mut source = Vec::new();
    for t in tables {
        let bytes = std::fs::read(t).with_context(|| format!("reading {}", t.display()))?;
        source.push(format!(
            "{} ({:016x})",
            t.display(),
            mbgc::numeric::fnv1a64(&bytes)
        ));
        for r in read_rows(t)? {
            if rows.iter().any(|o| o.job == r.job) {
                eprintln!(
                    "warning: {}: a second row of {:?}; left out",
                    t.display(),
                    r.job
                );
                continue;
            }
            rows.push(r);
        }
    }
    Ok((rows, source))
}

/// The model's inputs at a line's point: any stiffness (the fits move it along the group),
/// the cohesion between particles `bond` times the weight, walls not cohesive.
fn point_inputs(model: &Metamodel, name: &str, bond: f64) -> anyhow::Result<Vec<f64>> {
    let p = line_point(name).with_context(|| format!("point {name}: not a known point"))?;
    model
        .inputs
        .iter()
        .map(|i| match i.name.as_str() {
            "E_p" | "E_w" => Ok(1e5 * WEIGHT),
            "ced_pp" => Ok(bond * WEIGHT),
            "ced_pw" => Ok(0.0),
            n => p
                .get(n)
                .with_context(|| format!("point {name} has no {n}, an input of the model")),
        })
        .collect()
}

/// The model's responses of one row (NaN for those the tables do not hold).
fn row_values(model: &Metamodel, r: &Row) -> Vec<f64> {
    model
        .responses
        .iter()
        .map(|resp| match resp.name.as_str() {
            "shear_angle" => r.angle,
            "bulk_density" => r.density,
            _ => f64::NAN,
        })
        .collect()
}

/// The cohesion lines of `rows` (with and without cohesion) as the fit takes them.
fn cohesion_lines(model: &Metamodel, rows: &[Row]) -> anyhow::Result<Vec<CohesionLine>> {
    let mut names: Vec<&str> = rows
        .iter()
        .filter(|r| r.job.bond > 0.0)
        .map(|r| r.job.point.as_str())
        .collect();
    names.sort();
    names.dedup();
    names
        .into_iter()
        .map(|name| {
            Ok(CohesionLine {
                label: name.to_string(),
                inputs: point_inputs(model, name, 0.0)?,
                runs: rows
                    .iter()
                    .filter(|r| r.job.point == name)
                    .map(|r| (r.job.k, r.job.bond * WEIGHT, row_values(model, r)))
                    .collect(),
            })
        })
        .collect()
}

/// The lines of `rows` as the fit takes them: the model's inputs at each point and its runs.
fn lines(model: &Metamodel, rows: &[Row], bond: f64) -> anyhow::Result<Vec<Line>> {
    let mut names: Vec<&str> = rows.iter().map(|r| r.job.point.as_str()).collect();
    names.sort();
    names.dedup();
    let mut out = Vec::new();
    for name in names {
        let inputs = point_inputs(model, name, bond)?;
        let runs = rows
            .iter()
            .filter(|r| r.job.point == name)
            .map(|r| (r.job.k, row_values(model, r)))
            .collect();
        out.push(Line {
            label: name.to_string(),
            inputs,
            runs,
        });
    }
    Ok(out)
}

fn report(a: &Args, before: &Metamodel, m: &Metamodel) -> String {
    let mut w = String::new();
    let Some(lim) = &m.rigid_limit else {
        return w;
    };
    let gd = before.groups.iter().find(|g| g.group.name == lim.group);
    let domain = gd.map_or([f64::NAN; 2], |g| g.domain);
    let _ = writeln!(
        w,
        "# The rigid limit of `{}`\n\nRegenerate with `cargo run --release -- bench rigid-limit \
         --model {} --tables {} --bond {}{}{} --out {}{}` (reads the stiffness tables, a second).\n",
        a.model.display(),
        a.model.display(),
        join(&a.tables),
        a.bond,
        if a.cohesion_tables.is_empty() {
            String::new()
        } else {
            format!(
                " --cohesion-tables {}{}",
                join(&a.cohesion_tables),
                a.cohesion_edge
                    .map_or(String::new(), |e| format!(" --cohesion-edge {e}"))
            )
        },
        if a.edge_decades == mbgc::metamodel::rigid_fit::EDGE_DECADES {
            String::new()
        } else {
            format!(" --edge-decades {}", a.edge_decades)
        },
        a.out.display(),
        a.report
            .as_ref()
            .map_or(String::new(), |r| format!(" --report {}", r.display()))
    );
    let _ = writeln!(
        w,
        "The model's campaign ran {} from {:.4e} to {:.4e}. Beyond, it now answers from {:.4e} \
         to {:.4e}: the equation on the edge of its range plus a curve measured along {} lines \
         of DEM runs that vary only the stiffness (E_p = E_w) through points of the space ({}; \
         rho_p 2600 kg/m3, d50 8 mm, the kinetic rest rule of the campaign). A knot's scatter is \
         the lines' rms deviation from the curve (n - 1 degrees of freedom); its sd is that \
         with the runs' own noise taken off (one run's variance from the model's replicate sd, \
         times 1 / runs at the edge + 1 / runs at the knot, at its 95 % lower bound), because a \
         prediction's error holds one run's noise already, plus the curve value's own \
         uncertainty (scatter^2 / lines). The lines all lie at rho_p 2600 and d50 8 mm: their \
         scatter says nothing of how the shift might depend on density or size beyond K_p. The \
         sd is added to the response's model error wherever the \
         curve is used. Source: {}.\n",
        lim.group,
        domain[0],
        domain[1],
        lim.reach[0],
        lim.reach[1],
        lim.lines.len(),
        lim.lines.join(", "),
        lim.source
    );
    if a.edge_decades != mbgc::metamodel::rigid_fit::EDGE_DECADES {
        let _ = writeln!(
            w,
            "The edge's value on a line is its run nearest the edge within {} decades (the \
             lines were run for another model's edge), so a curve's shifts count from that \
             run.\n",
            a.edge_decades
        );
    }
    let _ = writeln!(
        w,
        "Two forms are fitted per response and side; the one with the smaller error predicting \
         each line's shifts from the other lines (leave one line out) is kept:\n\n- `shift`: \
         the same shift for every material (the lines' mean);\n- `slope`: the equation's own \
         slope at the edge (per decade of {}) times a length in decades, so a material whose \
         response still moved at the edge moves on.\n\nThe bulk density is fitted as rho_p \
         times a solid fraction: its shift and sd are in solid fraction, shown here times rho_p \
         = 2600 kg/m3.\n",
        lim.group
    );
    for c in &lim.curves {
        let resp = m.responses.iter().find(|r| r.name == c.response);
        let scale = resp
            .and_then(|r| r.grouped.as_ref())
            .and_then(|g| g.factor.as_ref())
            .map_or(1.0, |_| 2600.0);
        let loo = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{:.3}", v * scale));
        let _ = writeln!(
            w,
            "## {}, {} than the data\n\nForm: **{}**. Leave-one-line-out error: shift {}, slope \
             {}.\n\n| {} | decades beyond | lines | {} | scatter | sd \
             |\n|---|---|---|---|---|---|",
            c.response,
            if c.stiff { "stiffer" } else { "softer" },
            match c.form {
                Form::Shift => "shift",
                Form::Slope => "slope",
            },
            loo(c.leave_one_out.shift),
            loo(c.leave_one_out.slope),
            lim.group,
            match c.form {
                Form::Shift => "shift",
                Form::Slope => "decades times the edge slope",
            }
        );
        let edge = if c.stiff { domain[1] } else { domain[0] };
        for k in &c.knots {
            let value = match c.form {
                Form::Shift => format!("{:+.3}", k.value * scale),
                Form::Slope => format!("{:+.3}", k.value),
            };
            let _ = writeln!(
                w,
                "| {:.3e} | {:+.3} | {} | {value} | {:.3} | {:.3} |",
                edge * 10f64.powf(k.decades),
                k.decades,
                k.lines,
                k.scatter * scale,
                k.sd * scale
            );
        }
        let _ = writeln!(w);
    }
    for c in &lim.cohesion {
        // The knots count from the effect's runs' edge where it lies below the model's.
        let origin = c.runs_edge.unwrap_or(domain[1]);
        if let Some(e) = c.runs_edge {
            let _ = writeln!(
                w,
                "## {} beyond its runs\n\nThe model's cohesive runs stop at K_p {e:.4e}, below \
                 its edge ({:.4e}): between the two it reads the cohesion through {} alone, as \
                 the similarity below carries it, so the similarity's scatter is added from \
                 K_p {e:.4e} on, inside the data as beyond it (the knots' decades count from \
                 there).\n",
                c.group, domain[1], c.group
            );
        }
        let _ = writeln!(
            w,
            "## {} beyond the stiffness edge\n\nA material beyond the edge is read on it with \
             {} times (E*_edge / E*)^(2/3), E* the modulus of a contact between {} and {}, \
             which holds the pull of a Hertz contact per particle weight, C K^(-2/3) \
             (docs/cohesion_stiffness.md). The scatter of that similarity was measured at {} = \
             {} on the edge: on each line, the cohesion effect (the run with cohesion minus the \
             run without) at K_p beyond the edge with the carried cohesion, minus the effect on \
             the edge. A knot's sd is the lines' rms difference with the four runs' noise taken \
             off, plus its own uncertainty (rms^2 / lines); it is added to a prediction's error \
             in proportion to the carried cohesion over {}, and beyond the last knot in \
             proportion to the decades. No shift is applied (the mean and its standard error are \
             shown for that). Source: {}.\n\n| response | K_p | decades beyond | lines | mean \
             difference | se | sd |\n|---|---|---|---|---|---|---|",
            c.group,
            c.along,
            c.contact[0],
            c.contact[1],
            c.group,
            c.reference,
            c.reference,
            c.measured
        );
        for cc in &c.curves {
            let scale = m
                .responses
                .iter()
                .find(|r| r.name == cc.response)
                .and_then(|r| r.grouped.as_ref())
                .and_then(|g| g.factor.as_ref())
                .map_or(1.0, |_| 2600.0);
            for k in &cc.knots {
                let _ = writeln!(
                    w,
                    "| {} | {:.3e} | {:+.3} | {} | {:+.3} | {:.3} | {:.3} |",
                    cc.response,
                    origin * 10f64.powf(k.decades),
                    k.decades,
                    k.lines,
                    k.mean * scale,
                    k.se * scale,
                    k.sd * scale
                );
            }
        }
        let _ = writeln!(w);
    }
    w
}

fn join(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|t| t.display().to_string())
        .collect::<Vec<_>>()
        .join(",")
}
