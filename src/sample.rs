//! `mbgc sample`: a new design, or an existing one extended, written as CSV.

use mbgc::outputs::refuse_overwriting_inputs;
use mbgc_output::say;
use mbgc_output::Output;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use mbgc::sampling::{extend_design, fssf, lhs, metrics, mipt, Design, Method, Points, Sampler};
use mbgc::space::Space;

#[derive(Debug, Args)]
pub struct SampleArgs {
    /// Design method.
    #[arg(long, value_parser = crate::choice::choice::<Method>(Method::ALL.map(Method::name)))]
    pub method: Method,
    /// Points of a new design (as `train --n`: the design's size).
    #[arg(long, required_unless_present = "add", conflicts_with = "add")]
    pub n: Option<usize>,
    /// Points to add to the design of `--extend` (its size grows by this many).
    #[arg(long, requires = "extend")]
    pub add: Option<usize>,
    /// Parameter space (values written in physical units).
    #[arg(long, conflicts_with = "dim", required_unless_present = "dim")]
    pub space: Option<PathBuf>,
    /// Dimension of a bare unit-cube design (columns x0, x1, ...).
    #[arg(long)]
    pub dim: Option<usize>,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output CSV.
    #[arg(long)]
    pub out: PathBuf,
    /// Existing design to extend; its points stay first, unchanged and in order.
    #[arg(long)]
    pub extend: Option<PathBuf>,
    /// MIPT projected-distance tolerance alpha (Crombecq et al. 2011).
    #[arg(long, default_value_t = 0.5)]
    pub mipt_alpha: f64,
    /// FSSF candidate count (default 1000 d + 2 n_max).
    #[arg(long)]
    pub fssf_candidates: Option<usize>,
    /// Standard output holds one JSON object (the summary); text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

/// The largest design `sample` makes: beyond this the design file alone is gigabytes.
pub const MAX_VALUES: usize = 50_000_000;
/// Above this many points the summary skips the O(n^2) metrics (`mbgc metrics` computes them).
pub const SUMMARY_MAX_POINTS: usize = 20_000;

pub fn run(a: &SampleArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    // `--extend D --out D` is the documented in-place update: the old points stay first and
    // unchanged, and the file is replaced atomically.
    if let Some(space) = &a.space {
        refuse_overwriting_inputs("--out", &a.out, &[("--space", space)])?;
    }
    let space = a.space.as_deref().map(Space::from_file).transpose()?;
    let dim = match (&space, a.dim) {
        (Some(s), _) => s.dim(),
        (None, Some(0)) => anyhow::bail!("--dim: expected at least 1"),
        (None, Some(d)) => d,
        (None, None) => unreachable!("clap requires --space or --dim"),
    };
    // One meaning per name: --n is a design's size (here and in `train`), --add the points an
    // extension adds.
    let (flag, n) = match (a.n, a.add) {
        (Some(_), _) if a.extend.is_some() => anyhow::bail!(
            "--n with --extend: --n is the size of a new design; give the points to add to {} \
             with --add",
            a.extend
                .as_ref()
                .map_or(String::new(), |p| p.display().to_string())
        ),
        (Some(n), _) => ("--n", n),
        (None, Some(m)) => ("--add", m),
        (None, None) => unreachable!("clap requires --n or --add"),
    };
    if n == 0 {
        anyhow::bail!("{flag}: expected at least one new point");
    }
    if n.checked_mul(dim).is_none_or(|v| v > MAX_VALUES) {
        anyhow::bail!(
            "{flag} {n} in {dim} dimensions: expected at most {MAX_VALUES} values in all (n x dim)"
        );
    }
    if let Some(c) = a.fssf_candidates {
        // Each candidate is a point held in memory and compared with every new point.
        let most = MAX_VALUES / dim;
        if c < n || c > most {
            anyhow::bail!(
                "--fssf-candidates {c} in {dim} dimensions: expected {n} to {most} candidates (at \
                 least one per new point, at most {MAX_VALUES} values in all, candidates x dim)"
            );
        }
    }
    let mut design = match &a.extend {
        Some(path) => {
            let d = Design::read(path, space.as_ref())?;
            if d.unit.dim() != dim {
                anyhow::bail!(
                    "{}: has {} columns but --dim asks for {dim}",
                    path.display(),
                    d.unit.dim()
                );
            }
            d
        }
        None => Design::empty(space.as_ref(), dim),
    };
    let sampler: Box<dyn Sampler> = match a.method {
        Method::Mipt => Box::new(mipt::Mipt {
            alpha: a.mipt_alpha,
            ..Default::default()
        }),
        Method::FssfF | Method::FssfFr => Box::new(fssf::Fssf {
            candidates: a.fssf_candidates,
            ..if a.method == Method::FssfF {
                fssf::Fssf::forward()
            } else {
                fssf::Fssf::forward_reflected()
            }
        }),
        Method::LhsMaximin => Box::new(lhs::Lhs::maximin()),
        m => m.sampler(),
    };
    let n_old = design.len();
    let new: Points = extend_design(sampler.as_ref(), &design.unit, n, a.seed)
        .with_context(|| format!("sampling with {}", a.method.name()))?;
    design.append_unit(space.as_ref(), &new);
    design.write(&a.out)?;
    let m = (design.len() >= 2 && design.len() <= SUMMARY_MAX_POINTS)
        .then(|| metrics::metrics(&design.unit));
    say!(
        out,
        "{}: {} points ({} existing + {} new, {}, seed {}) in {} dimensions{}",
        a.out.display(),
        design.len(),
        n_old,
        n,
        a.method.name(),
        a.seed,
        dim,
        match &m {
            Some(m) => format!("; MID {:.4}, COV {:.4}", m.mid, m.cov),
            None if design.len() > SUMMARY_MAX_POINTS => {
                format!("; metrics skipped above {SUMMARY_MAX_POINTS} points (mbgc metrics)")
            }
            None => String::new(),
        }
    );
    // The box is sampled whole, so that a design extends the same way with or without
    // constraints; `train` runs only the rows inside them.
    let outside = space.as_ref().map_or(0, |s| {
        design
            .values
            .iter()
            .filter(|x| s.violated(x).is_some())
            .count()
    });
    if let Some(s) = space.as_ref().filter(|_| outside > 0) {
        say!(
            out,
            "{outside} of the {} points lie outside the space's constraints ({}): `mbgc train` \
             does not run them",
            design.len(),
            s.constraints
                .iter()
                .map(|c| c.text.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    out.object(&serde_json::json!({
        "out": a.out,
        "outside_constraints": outside,
        "method": a.method.name(),
        "seed": a.seed,
        "dim": dim,
        "existing": n_old,
        "new": n,
        "n": design.len(),
        "metrics": m,
    }))
}
