//! `a3d-init diff A B`: arguments and printing around [`pipeline::diff::diff`],
//! the semantic diff of Anura3D inputs and a3d-init outputs. Exit code 0 when
//! equal within tolerance, 1 when different, 2 on error.

use std::path::PathBuf;

use super::Verdict;
use a3d_init::pipeline::{self, diff::DiffOptions};

#[derive(Debug, clap::Args)]
pub struct DiffArgs {
    /// First file or project folder.
    pub a: PathBuf,
    /// Second file or project folder.
    pub b: PathBuf,
    /// Relative tolerance for numbers.
    #[arg(long, default_value_t = 1e-9)]
    pub rtol: f64,
    /// Absolute tolerance for numbers.
    #[arg(long, default_value_t = 1e-12)]
    pub atol: f64,
    /// Match table rows by this id column (e.g. `id` in mps.csv) instead of by position.
    #[arg(long, value_name = "COLUMN")]
    pub by: Option<String>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: DiffArgs) -> anyhow::Result<()> {
    let options = DiffOptions {
        rtol: args.rtol,
        atol: args.atol,
        by: args.by.clone(),
    };
    let report = pipeline::diff::diff(&args.a, &args.b, &options)?;
    // say!: a closed stdout must not turn a verdict into an error.
    if args.json {
        say!("{}", pipeline::json_text(&report)?);
    } else {
        for n in &report.notes {
            say!("{n}");
        }
        for d in &report.files {
            if d.equal {
                say!(
                    "= {} ({}): equal within rtol {} / atol {}",
                    d.b.display(),
                    d.kind,
                    args.rtol,
                    args.atol
                );
            } else {
                say!("≠ {} vs {} ({}):", d.a.display(), d.b.display(), d.kind);
                for f in &d.findings {
                    say!("    {f}");
                }
            }
        }
    }
    Verdict::check(report.equal, "differences found")
}
