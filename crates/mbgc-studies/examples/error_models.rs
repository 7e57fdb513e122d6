//! Fits the error models of a saved metamodel (its own error as a function of the inputs,
//! `mbgc::metamodel::ErrorModel`) to the residuals on its validation table, for a model trained
//! before `mbgc train` did so itself, and writes the model with them to a new file. Prints, per
//! response, the held-out likelihood of the chosen error model against the constant one and the
//! error's spread over the validation rows.
//!
//! ```text
//! cargo run --release -p mbgc-studies --example error_models -- \
//!     models/shear_box.json training_data/shear_box_validation.csv /tmp/shear_box.json
//! ```
use anyhow::Context;
use mbgc::metamodel::{Metamodel, TrainingTable};
use std::path::PathBuf;

fn main() -> anyhow::Result<()> {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [model, table, out] = args.as_slice() else {
        anyhow::bail!("usage: error_models MODEL.json VALIDATION.csv OUT.json");
    };
    if out == model {
        anyhow::bail!(
            "{}: the output would overwrite the input model",
            out.display()
        );
    }
    let mut m = Metamodel::load(model)?;
    let responses: Vec<String> = m.responses.iter().map(|r| r.name.clone()).collect();
    let t = TrainingTable::read_csv(table, &m.input_names(), &responses)
        .with_context(|| format!("reading {}", table.display()))?;
    m.fit_error_models(&t)?;
    for r in &m.responses {
        let Some(e) = &r.error_model else {
            println!("{}: too few validation rows for an error model", r.name);
            continue;
        };
        let cols: Vec<Vec<f64>> = m
            .input_names()
            .iter()
            .map(|n| t.column(n).map(<[f64]>::to_vec))
            .collect::<Result<_, _>>()?;
        let mut sd: Vec<f64> = (0..t.rows())
            .filter_map(|i| m.error_at(r, &cols.iter().map(|c| c[i]).collect::<Vec<_>>()))
            .collect();
        sd.sort_by(f64::total_cmp);
        let q = |p: f64| mbgc::numeric::quantile_sorted(&sd, p);
        println!(
            "{}: validation RMSE {:.4}; error model ridge {:?}, held-out NLL per residual {:.4} \
             (constant {:.4}); its sd over the validation rows: 5 % {:.4}, median {:.4}, 95 % {:.4}",
            r.name,
            r.validation.map_or(f64::NAN, |v| v.rmse),
            e.ridge,
            e.cv_nll[0],
            e.cv_nll[1],
            q(0.05),
            q(0.5),
            q(0.95)
        );
    }
    m.save(out)?;
    println!("wrote {}", out.display());
    Ok(())
}
