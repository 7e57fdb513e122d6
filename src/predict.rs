//! `mbgc predict`: evaluate a saved metamodel on the rows of a table.

use mbgc::outputs::refuse_overwriting_inputs;
use mbgc_output::say;
use mbgc_output::Output;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use mbgc::error::write_atomic;
use mbgc::metamodel::{table::read_columns, Metamodel};

#[derive(Debug, Args)]
pub struct PredictArgs {
    /// Model file written by `mbgc fit`.
    #[arg(long)]
    pub model: PathBuf,
    /// Table with (at least) the model's input columns.
    #[arg(long)]
    pub data: PathBuf,
    /// Output CSV: the input rows with, per response, its prediction (and with --errors its
    /// error).
    #[arg(long)]
    pub out: PathBuf,
    /// Also write `<response>_error` after each prediction, where the model states its error:
    /// the prediction's standard error in the response's unit (its error model or validation
    /// RMSE; beyond its stiffness data, the rigid limit's scatter added).
    #[arg(long)]
    pub errors: bool,
    /// Standard output holds one JSON object; text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: &PredictArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    refuse_overwriting_inputs(
        "--out",
        &a.out,
        &[("--model", &a.model), ("--data", &a.data)],
    )?;
    let model = Metamodel::load(&a.model)?;
    let mut names = model.input_names();
    let n_in = names.len();
    // Parameters the campaign held fixed: a data column of that name must hold that value, or
    // the row lies outside what the model describes. They are read with the inputs.
    let (_, header) = mbgc::error::csv_open(&a.data)?;
    let held: Vec<&mbgc::metamodel::Constant> = model
        .constants
        .iter()
        .filter(|c| header.iter().any(|h| h == &c.name) && !names.contains(&c.name))
        .collect();
    names.extend(held.iter().map(|c| c.name.clone()));
    let cols = read_columns(&a.data, &names)?;
    let (inputs, held_cols) = cols.values.split_at(n_in);
    let rows = cols.records.len();
    let preds: Vec<Vec<f64>> = model
        .responses
        .iter()
        .map(|r| model.predict(r, inputs))
        .collect();
    let mut outside = Vec::new();
    for row in 0..rows {
        let x: Vec<f64> = inputs.iter().map(|c| c[row]).collect();
        if let Some((name, v, d)) = model.outside_domain(&x).first() {
            outside.push(format!(
                "line {}: {name} = {v} outside [{}, {}]",
                row + 2,
                d[0],
                d[1]
            ));
        } else if let Some(c) = model.violated_constraint(&x) {
            outside.push(format!(
                "line {}: outside the model's limit {c} (its training runs stayed inside)",
                row + 2
            ));
        } else if let Some((c, v)) = held
            .iter()
            .zip(held_cols)
            .map(|(c, col)| (c, col[row]))
            .find(|(c, v)| v.is_nan() || (v - c.value).abs() > 1e-9 * c.value.abs())
        {
            outside.push(format!(
                "line {}: {} = {v}, but the model holds only at {} = {} (its campaign held it \
                 fixed)",
                row + 2,
                c.name,
                c.name,
                c.value
            ));
        }
    }
    // The error each prediction carries (the response's unit), where the model states one:
    // its error model or validation RMSE, and beyond its stiffness data the rigid limit's
    // scatter too.
    let errors: Vec<Option<Vec<f64>>> = model
        .responses
        .iter()
        .map(|r| {
            let e: Vec<Option<f64>> = (0..rows)
                .map(|row| {
                    let x: Vec<f64> = inputs.iter().map(|c| c[row]).collect();
                    model.prediction_error(r, &x)
                })
                .collect();
            (a.errors && e.iter().any(Option::is_some))
                .then(|| e.iter().map(|v| v.unwrap_or(f64::NAN)).collect())
        })
        .collect();
    let mut header = cols.header.clone();
    for (r, e) in model.responses.iter().zip(&errors) {
        let mut name = r.name.clone();
        while header.contains(&name) {
            name = format!("{name}_predicted");
        }
        header.push(name.clone());
        if e.is_some() {
            let mut err = format!("{name}_error");
            while header.contains(&err) {
                err = format!("{err}_predicted");
            }
            header.push(err);
        }
    }
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&header)?;
    for (row, rec) in cols.records.iter().enumerate() {
        let mut fields = rec.clone();
        for (p, e) in preds.iter().zip(&errors) {
            fields.push(format!("{:?}", p[row]));
            if let Some(e) = e {
                fields.push(format!("{:?}", e[row]));
            }
        }
        w.write_record(&fields)?;
    }
    let bytes = w.into_inner().context("writing CSV")?;
    write_atomic(&a.out, &bytes)?;
    let nan = preds.iter().flatten().filter(|v| !v.is_finite()).count();
    // Rows beyond the stiffness data that the rigid limit answers: worth knowing, since their
    // error is the limit's scatter on top of the equation's.
    let limited = (0..rows)
        .filter(|&row| {
            let x: Vec<f64> = inputs.iter().map(|c| c[row]).collect();
            model
                .responses
                .iter()
                .any(|r| model.beyond(r, &x).is_some_and(|b| b.value.is_finite()))
        })
        .count();
    if limited > 0 {
        eprintln!(
            "note: {limited} of {rows} rows lie beyond the model's stiffness data and are answered \
             by its rigid limit (the equation on the data's edge plus a measured shift){}",
            if a.errors {
                ""
            } else {
                "; --errors writes each prediction's error"
            }
        );
    }
    if !outside.is_empty() {
        eprintln!(
            "warning: {} of {rows} rows lie outside the model's valid domain (extrapolation); first: {}",
            outside.len(),
            outside[0]
        );
    }
    if nan > 0 {
        eprintln!("warning: {nan} predictions are not finite (written as NaN)");
    }
    say!(out, "wrote {} ({rows} rows)", a.out.display());
    out.object(&serde_json::json!({
        "out": a.out,
        "rows": rows,
        "responses": model.responses.iter().map(|r| r.name.as_str()).collect::<Vec<_>>(),
        "outside_domain": outside.len(),
        "rigid_limit": limited,
        "non_finite": nan,
    }))
}
