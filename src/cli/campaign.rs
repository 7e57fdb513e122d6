//! `mbgc campaign`: merge campaign tables, report their progress.

use crate::cli::output::Output;
use crate::say;
use std::path::PathBuf;

use clap::{Args, Subcommand};

use crate::campaign::{merge, status};

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
    }
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
        "{}: {} runs from {} tables ({} duplicates dropped)",
        a.out.display(),
        s.rows,
        a.tables.len(),
        s.duplicates
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
