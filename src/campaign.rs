//! `mbgc campaign`: merge campaign tables, report their progress, import runs made elsewhere
//! from decks mbgc wrote.

use mbgc_output::say;
use mbgc_output::Output;
use std::path::PathBuf;

use clap::{Args, Subcommand};

use anyhow::Context as _;
use mbgc::campaign::decks::{ready_runs, stray_dirs, DeckCampaign, CAMPAIGN_FILE, DESIGN_FILE};
use mbgc::campaign::registry::experiment_for_import;
use mbgc::campaign::{merge, run_campaign, status, CampaignOptions};
use mbgc::outputs::refuse_overwriting_inputs;

#[derive(Debug, Args)]
pub struct CampaignArgs {
    #[command(subcommand)]
    pub command: CampaignCommand,
}

#[derive(Debug, Subcommand)]
pub enum CampaignCommand {
    /// Merge tables of one campaign (shards, reruns): deduplicated by run id, sorted by row.
    Merge(MergeArgs),
    /// Count done, failed and remaining runs of a table.
    Status(StatusArgs),
    /// Read the runs of decks written by `mbgc simulate --backend liggghts --write-decks DIR`
    /// and run elsewhere into a campaign table; decks not run yet are left for the next import.
    Import(ImportArgs),
}

#[derive(Debug, Args)]
pub struct ImportArgs {
    /// The directory the decks were written to (it holds campaign.json and design.csv).
    #[arg(long, value_name = "DIR")]
    pub decks: PathBuf,
    /// Campaign table; an existing one is resumed (runs already in it are not read again).
    #[arg(long, value_name = "CSV")]
    pub out: PathBuf,
    /// Threads reading and measuring runs [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// The MPI processes the decks ran on (recorded in the table's backend column, e.g.
    /// liggghts-np2); a run on another number is recorded as failed.
    #[arg(long, value_name = "N")]
    pub mpi: Option<usize>,
    /// Read again the runs recorded as failed (a deck rerun or rewritten since).
    #[arg(long)]
    pub retry_failed: bool,
    /// Standard output holds one JSON object; the text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Tables written by `mbgc simulate`, all with the same header.
    #[arg(required = true, value_name = "CSV")]
    pub tables: Vec<PathBuf>,
    /// Merged table (written atomically; may be one of the inputs).
    #[arg(long, value_name = "CSV")]
    pub out: PathBuf,
    /// Standard output holds one JSON object; the text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct StatusArgs {
    /// Table written by `mbgc simulate`.
    #[arg(value_name = "CSV")]
    pub table: PathBuf,
    /// Design to count remaining rows against [default: the one recorded in <CSV>.meta.json].
    #[arg(long, value_name = "CSV")]
    pub design: Option<PathBuf>,
    /// Standard output holds one JSON object; the text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: &CampaignArgs) -> anyhow::Result<()> {
    match &a.command {
        CampaignCommand::Merge(m) => run_merge(m),
        CampaignCommand::Status(s) => run_status(s),
        CampaignCommand::Import(i) => run_import(i),
    }
}

fn run_import(a: &ImportArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    let design = a.decks.join(DESIGN_FILE);
    refuse_overwriting_inputs("--out", &a.out, &[("the decks' design", &design)])?;
    let campaign = DeckCampaign::read(&a.decks)?;
    // Values from campaign.json would otherwise be reported as options the user never gave.
    let file = a.decks.join(CAMPAIGN_FILE);
    let context = || format!("{} (written by --write-decks)", file.display());
    let settings = campaign.settings(&a.decks, a.mpi).with_context(context)?;
    let experiment =
        experiment_for_import(&campaign.experiment, &settings).with_context(context)?;
    let plan = campaign
        .plan(&a.decks, experiment.as_ref(), &settings)
        .with_context(context)?;
    let (ready, missing) = ready_runs(&plan, &a.decks);
    let stray = stray_dirs(&plan, &a.decks)?;
    // Run directories none of which the campaign names: campaign.json or design.csv changed
    // after the decks were written (each run id hashes the row, seed and settings).
    if !stray.is_empty() && ready.is_empty() {
        anyhow::bail!(
            "{}: {} run directories belong to no run of the campaign that {} and {} describe now, \
             and no run of it has a result (the run ids differ: were the files edited after \
             --write-decks?); restore them, or write the decks again",
            a.decks.display(),
            stray.len(),
            CAMPAIGN_FILE,
            DESIGN_FILE
        );
    }
    if !stray.is_empty() {
        eprintln!(
            "{}: {} directories are no run of this campaign and were not read: {}",
            a.decks.display(),
            stray.len(),
            stray.join(", ")
        );
    }
    let threads = match a.threads {
        Some(0) => anyhow::bail!("--threads: expected at least 1"),
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let s = run_campaign(
        experiment.as_ref(),
        &plan,
        &CampaignOptions {
            work_dir: Some(a.decks.clone()),
            only: Some(ready),
            retry_failed: a.retry_failed,
            ..CampaignOptions::new(a.out.clone(), threads)
        },
    )?;
    let shown: Vec<String> = missing.iter().take(10).map(|r| r.to_string()).collect();
    say!(
        out,
        "{}: imported {} runs from {} ({} done, {} failed in LIGGGHTS or unreadable); {} already \
         in the table; {} of {} decks not run yet{}",
        a.out.display(),
        s.done + s.failed,
        a.decks.display(),
        s.done,
        s.failed,
        s.skipped,
        missing.len(),
        plan.selected().count(),
        if missing.is_empty() {
            String::new()
        } else {
            format!(
                " (rows {}{})",
                shown.join(", "),
                if missing.len() > shown.len() {
                    ", ..."
                } else {
                    ""
                }
            )
        }
    );
    out.object(&serde_json::json!({
        "out": a.out,
        "decks": a.decks,
        "imported": s.done + s.failed,
        "done": s.done,
        "failed": s.failed,
        "skipped": s.skipped,
        "not_run": missing,
    }))?;
    let failed = s.failed + s.failed_before;
    if failed > 0 {
        anyhow::bail!(
            "{failed} imported runs failed: they have status=failed and their reason in the error \
             column of {}; after rerunning or rewriting their decks, import with --retry-failed",
            a.out.display()
        );
    }
    Ok(())
}

fn run_merge(a: &MergeArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    let s = merge(&a.tables, &a.out)?;
    for p in &s.partial_lines {
        eprintln!(
            "{}: left out an incomplete last line (an interrupted write; rerun that campaign to \
             redo the run)",
            p.display()
        );
    }
    say!(
        out,
        "{}: {} runs from {} tables ({} duplicates dropped, {} failed runs superseded by their \
         reruns)",
        a.out.display(),
        s.rows,
        a.tables.len(),
        s.duplicates,
        s.superseded_failures
    );
    out.object(&serde_json::json!({
        "out": a.out,
        "tables": a.tables,
        "summary": s,
    }))
}

fn run_status(a: &StatusArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    let s = status(&a.table, a.design.as_deref())?;
    let opt = |v: Option<usize>| v.map_or("unknown (pass --design)".to_string(), |v| v.to_string());
    say!(
        out,
        "{}{}",
        s.out,
        s.experiment
            .as_deref()
            .map(|e| format!(" ({e})"))
            .unwrap_or_default()
    );
    say!(out, "  done       {}", s.done);
    if let Some(n) = s.no_value.filter(|&n| n > 0) {
        say!(out, "    of them without a value of some response: {n}");
    }
    say!(out, "  failed     {}", s.failed);
    say!(out, "  remaining  {}", opt(s.remaining));
    say!(out, "  total      {}", opt(s.total));
    if s.partial_line {
        say!(
            out,
            "  (an incomplete last line: its run counts as remaining)"
        );
    }
    out.object(&s)
}
