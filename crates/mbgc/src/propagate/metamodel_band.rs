//! The cheap path: the draws through a metamodel of the quantity instead of (or beside) DEM,
//! with and without the metamodel's own error, so that a user sees when it is good enough.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use super::band::Band;
use crate::error::{Error, Result};
use crate::metamodel::Metamodel;

/// Samples of the model error drawn per draw for the band with error.
pub const ERROR_SAMPLES: usize = 200;

/// A quantity's band through a metamodel.
#[derive(Debug, Clone, PartialEq)]
pub struct MetamodelBand {
    /// The response.
    pub response: String,
    /// The band of the equation's predictions at the draws.
    pub without_error: Band,
    /// The band of a single DEM run as the metamodel predicts it: each prediction plus its
    /// error (normal, sd from the error model, else the validation or test RMSE), so it
    /// compares with a DEM band of one run per draw. Its `scatter_sd` is that error. `None`
    /// when the model records no error for the response.
    pub with_error: Option<Band>,
    /// Where the error came from, in words (or why there is none).
    pub error_source: String,
    /// The prediction at each draw (NaN at a draw left out as outside the domain).
    pub predictions: Vec<f64>,
    /// The draws left out as outside the model's domain (with `skip_outside`): each draw's
    /// index and what lies outside. The band is then of the others, and biased where the
    /// quantity differs there (a hopper's runs above some friction clog and leave no rate).
    pub outside: Vec<(usize, String)>,
}

/// The draws `rows` (columns `header`) through `model`, for each of `responses` it predicts.
/// Refuses a model input that no column holds. An equation is not evaluated where it was never
/// fitted: a draw outside the model's domain is refused (naming the input, the value and the
/// domain), or with `skip_outside` left out of the band and listed in
/// [`MetamodelBand::outside`].
pub fn through_metamodel(
    model: &Metamodel,
    header: &[String],
    rows: &[Vec<f64>],
    responses: &[String],
    seed: u64,
    skip_outside: bool,
) -> Result<Vec<MetamodelBand>> {
    let columns = model
        .input_names()
        .iter()
        .map(|name| {
            header.iter().position(|h| h == name).ok_or_else(|| {
                Error::invalid(format!(
                    "--metamodel: its input {name} is neither a posterior column nor a --set \
                     constant (the draws hold {})",
                    header.join(", ")
                ))
            })
        })
        .collect::<Result<Vec<usize>>>()?;
    let points: Vec<Vec<f64>> = rows
        .iter()
        .map(|r| columns.iter().map(|&j| r[j]).collect())
        .collect();
    // What the model's campaign held fixed must hold at every draw too.
    for c in &model.constants {
        let Some(j) = header.iter().position(|h| h == &c.name) else {
            return Err(Error::invalid(format!(
                "--metamodel: its campaign held {} = {}, which the draws do not set; give --set \
                 {}={} (or a model of this setting)",
                c.name, c.value, c.name, c.value
            )));
        };
        if let Some(r) = rows
            .iter()
            .find(|r| (r[j] - c.value).abs() > 1e-9 * c.value.abs().max(1e-300))
        {
            return Err(Error::invalid(format!(
                "--metamodel: its campaign held {} = {}, the draws have {} = {}: the model \
                 does not describe them",
                c.name, c.value, c.name, r[j]
            )));
        }
    }
    let outside: Vec<(usize, String)> = points
        .iter()
        .enumerate()
        .filter_map(|(k, x)| {
            model
                .outside_domain(x)
                .first()
                .map(|(n, v, d)| (k, format!("{n} = {v} outside [{}, {}]", d[0], d[1])))
                .or_else(|| {
                    model.violated_constraint(x).map(|c| {
                        (
                            k,
                            format!("outside the model's limit {c} (its runs stayed inside)"),
                        )
                    })
                })
        })
        .collect();
    if let (Some((k, what)), false) = (outside.first(), skip_outside) {
        return Err(Error::invalid(format!(
            "--metamodel: {} of {} draws lie outside the model's domain (draw {k}: {what}); an \
             equation is not evaluated where it was never fitted. --metamodel-outside skip \
             leaves them out of the metamodel's band and lists them",
            outside.len(),
            points.len()
        )));
    }
    if !points.is_empty() && outside.len() == points.len() {
        return Err(Error::invalid(format!(
            "--metamodel: all {} draws lie outside the model's domain (draw 0: {}): no band",
            points.len(),
            outside.first().map_or("", |o| o.1.as_str())
        )));
    }
    let cols: Vec<Vec<f64>> = (0..columns.len())
        .map(|j| points.iter().map(|x| x[j]).collect())
        .collect();
    if !responses.iter().any(|r| model.response(r).is_some()) {
        return Err(Error::invalid(format!(
            "--metamodel: it predicts {}, none of the quantities propagated ({}); pass \
             --responses to choose others",
            model
                .responses
                .iter()
                .map(|r| r.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            responses.join(", ")
        )));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut bands = Vec::new();
    for r in responses {
        let Some(m) = model.response(r) else { continue };
        let mut predicted = model.predict(m, &cols);
        for (k, _) in &outside {
            predicted[*k] = f64::NAN;
        }
        let Some(without_error) = Band::of(&predicted.iter().map(|&p| vec![p]).collect::<Vec<_>>())
        else {
            continue;
        };
        let rmse = m.validation.or(m.test).map(|v| v.rmse);
        let (sds, error_source): (Option<Vec<f64>>, String) = if m.error_model.is_some() {
            (
                Some(
                    points
                        .iter()
                        .map(|x| model.error_at(m, x).unwrap_or(f64::NAN))
                        .collect(),
                ),
                "its error model (validation residuals as a function of the inputs)".into(),
            )
        } else if let Some(rmse) = rmse {
            (
                // The rigid limit's sd joins it at draws beyond the stiffness data.
                Some(
                    points
                        .iter()
                        .map(|x| model.prediction_error(m, x).unwrap_or(rmse))
                        .collect(),
                ),
                format!(
                    "its {} RMSE {}{}",
                    if m.validation.is_some() {
                        "validation"
                    } else {
                        "test"
                    },
                    crate::numeric::round_significant(rmse, 4),
                    if model.rigid_limit.is_some() {
                        " (beyond its stiffness data with the rigid limit's sd)"
                    } else {
                        ""
                    }
                ),
            )
        } else {
            (
                None,
                "none: the model records no validation or test error".into(),
            )
        };
        let with_error = sds.and_then(|sds| {
            let per_draw: Vec<Vec<f64>> = predicted
                .iter()
                .zip(&sds)
                .map(|(p, sd)| {
                    (0..ERROR_SAMPLES)
                        .map(|_| p + sd * rng.sample::<f64, _>(StandardNormal))
                        .collect()
                })
                .collect();
            Band::of(&per_draw)
        });
        bands.push(MetamodelBand {
            response: r.clone(),
            without_error,
            with_error,
            error_source,
            predictions: predicted,
            outside: outside.clone(),
        });
    }
    Ok(bands)
}
