//! `mbgc bench`: benchmarks and reproduction reports that regenerate the files under `docs/`.

use clap::{Args, Subcommand};

use mbgc_studies::{
    cell_metamodel_report, clogging_silo_report, cohesive_metamodel_report, dem_throughput,
    diagnose_report, gp_vs_gplearn, liggghts_backend, metamodel_benchmark, metamodel_report,
    rest_detection, rest_validation, restitution, rigid_limit_report, sampling_quality,
    sensitivity_report, shear_box_check, shear_box_vs_liggghts, shear_cell_report,
    stiffness_dependence, stiffness_validation,
};

#[derive(Debug, Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub what: BenchCommand,
}

#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// Seed 004 Figs. 7-8 (MID and COV of every method, 2-D and 10-D, many seeds), the
    /// extension check and design generation times; writes a Markdown report and a figure.
    Sampling(sampling_quality::Args),
    /// DEM throughput on a settled polydisperse box, per core, against LIGGGHTS on the identical
    /// scene (`--vs liggghts`), with packing fraction and coordination number of both.
    Dem(dem_throughput::Args),
    /// Shear box: mbgc against LIGGGHTS replaying the identical runs (low, mid and high
    /// friction, several seeds), and the cost of a run for several PSDs and moduli.
    ShearBox(shear_box_vs_liggghts::Args),
    /// Shear box checked independently: against a LIGGGHTS deck that fills itself (3 frictions x
    /// 2 PSDs), seed 004's Gravel 8/16 point, box scale, replicate noise, whole-run cost.
    ShearBoxCheck(shear_box_check::Args),
    /// docs/shear_cell.md: the shear cell's noise at two cell sizes, its cohesionless yield
    /// locus against the origin, its cohesion intercept against the SJKR energy density and an
    /// order-of-magnitude estimate, and its cost, from the tables under docs/data/shear_cell.
    ShearCell(shear_cell_report::Args),
    /// docs/metamodel_shear_cell.md: the shear-cell metamodel: its space, the cost of its
    /// runs, each response's validation RMSE against the replicate noise, its equations.
    CellMetamodel(cell_metamodel_report::Args),
    /// Symbolic regression against gplearn on Feynman equations (data and gplearn results from
    /// `benches/gp/`): test R^2, exact recovery, size, wall time, node-evaluations per second.
    Gp(gp_vs_gplearn::Args),
    /// The shipped metamodel (docs/metamodel.md): space, campaign cost, validation against seed
    /// 004 and the noise floor, equations, Gravel 8/16 calibrated and validated in DEM.
    Metamodel(metamodel_report::Args),
    /// docs/metamodel_sjkr.md: the shipped cohesive metamodel: what it extends, its space and
    /// the limit where the shear box stops measuring, the cost of its new runs, its validation
    /// on both faces against each one's replicate noise, beside the base model.
    CohesiveMetamodel(cohesive_metamodel_report::Args),
    /// docs/metamodel_benchmark.md: mbgc's GP at several length limits against PyOperon at the
    /// same limits, a Gaussian process and a quadratic surface, on the shipped campaign's
    /// columns; validation RMSE against the replicate noise, equation length, fit time.
    Metamodels(metamodel_benchmark::Args),
    /// docs/rest_detection.md: shear-box runs of a campaign table rerun with their seeds, their
    /// per-chunk traces, and the steps each rest rule saves against the response shift it costs.
    Rest(rest_detection::Args),
    /// docs/clogging_silo.md: the clogging silo's avalanche sizes at several orifices against
    /// the published trend (exponential sizes, a mean growing steeply with the orifice), their
    /// run-to-run scatter and cost; runs kept in a table, so a killed study resumes.
    CloggingSilo(clogging_silo_report::Args),
    /// docs/rest_validation.md: the shipped campaign's validation design rerun with its seeds
    /// under the candidate rest rule: cost against the recorded runs, and the shipped model's
    /// validation RMSE on both.
    RestValidation(rest_validation::Args),
    /// Seed 003 Table 4 on DEM impacts: TMCMC of the three normal-force classes (Tsuji,
    /// Kuwabara-Kono, free exponent) on measured restitution of steel; posteriors, evidences.
    Restitution(restitution::Args),
    /// docs/diagnose.md: hidden cohesion, hidden rolling resistance and a control, each
    /// diagnosed from its measurement file to the error ladder, the strength checked against
    /// the truth.
    Diagnose(diagnose_report::Args),
    /// docs/sensitivity.md: seed 000's power laws, PCA and sensitivity matrix on the hopper's
    /// 36-run design (from its campaign table), each finding checked; Sobol indices of a model.
    Sensitivity(sensitivity_report::Args),
    /// docs/liggghts_backend.md: the shear box of seed 004's size as a campaign on mbgc's
    /// engine, LIGGGHTS on 1 process and LIGGGHTS on 2 MPI processes; means and time per run.
    LiggghtsBackend(liggghts_backend::Args),
    /// docs/stiffness.md: the shear box along lines of K_p = E_p / (rho_p g d50), with and
    /// without cohesion, seed means, cost per run, and where each response stops changing.
    Stiffness(stiffness_dependence::Args),
    /// docs/rigid_limit.md: from the stiffness lines, how a shear-box model answers beyond its
    /// stiffness range (the rigid limit), written into a copy of the model.
    RigidLimit(rigid_limit_report::Args),
    /// docs/stiffness_validation.md: a random design over seed 004's box of E, rho_p and d50
    /// (log-uniform in K_p), run once each and scored against a model, by band of K_p.
    StiffnessValidation(stiffness_validation::Args),
}

pub fn run(a: &BenchArgs) -> anyhow::Result<()> {
    match &a.what {
        BenchCommand::Sampling(s) => sampling_quality::run(s),
        BenchCommand::Dem(d) => dem_throughput::run(d),
        BenchCommand::ShearBox(b) => shear_box_vs_liggghts::run(b),
        BenchCommand::ShearBoxCheck(b) => shear_box_check::run(b),
        BenchCommand::ShearCell(c) => shear_cell_report::run(c),
        BenchCommand::CellMetamodel(c) => cell_metamodel_report::run(c),
        BenchCommand::Gp(g) => gp_vs_gplearn::run(g),
        BenchCommand::Metamodel(m) => metamodel_report::run(m),
        BenchCommand::CohesiveMetamodel(m) => cohesive_metamodel_report::run(m),
        BenchCommand::Metamodels(m) => metamodel_benchmark::run(m),
        BenchCommand::Rest(r) => rest_detection::run(r),
        BenchCommand::RestValidation(r) => rest_validation::run(r),
        BenchCommand::Restitution(r) => restitution::run(r),
        BenchCommand::Diagnose(d) => diagnose_report::run(d),
        BenchCommand::Sensitivity(s) => sensitivity_report::run(s),
        BenchCommand::LiggghtsBackend(l) => liggghts_backend::run(l),
        BenchCommand::Stiffness(s) => stiffness_dependence::run(s),
        BenchCommand::RigidLimit(r) => rigid_limit_report::run(r),
        BenchCommand::CloggingSilo(c) => clogging_silo_report::run(c),
        BenchCommand::StiffnessValidation(v) => stiffness_validation::run(v),
    }
}
