//! `a3d-init demo`: the seed paper's application end to end on the shipped
//! slope, as the library runs it ([`a3d_init::pipeline::demo`]): the lines of its
//! account printed as they come, then the folders it wrote and the failure
//! time it measured.

use std::path::PathBuf;

use super::print::wrote;
use a3d_init::pipeline::demo::{self, DemoCommand, DemoLine, DemoOptions};

#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "a3d-init-demo")]
    pub out: PathBuf,
    /// Replace an existing output folder.
    #[arg(long)]
    pub force: bool,
    /// A quick look: skip step 6 (the factors of safety of the mapped state)
    /// and stop verify after 2,000 explicit steps.
    #[arg(long)]
    pub no_fos: bool,
}

pub fn run(args: DemoArgs) -> anyhow::Result<()> {
    let options = DemoOptions {
        out: args.out,
        force: args.force,
        no_fos: args.no_fos,
    };
    let report = demo::demo(&options, &mut |line| match line {
        DemoLine::Text(text) => say!("{text}"),
        DemoLine::Command(command) => say!("{}", spelled_command(&command)),
    })?;
    say!("\nfiles ({:.1} s):", report.seconds);
    for folder in &report.folders {
        let names: Vec<&str> = folder.files.iter().map(String::as_str).collect();
        say!("  {}", wrote(&folder.path, &names));
    }
    say!(
        "failure time: {:.3} h measured (OpenGeoSys rain, {} FS(t)) against the paper's 1.56 h ({:+.0} %; docs/slope.md)",
        report.failure_time_h,
        report.method,
        100.0 * (report.failure_time_h / 1.56 - 1.0)
    );
    Ok(())
}

/// A command the demo suggests, as this command line spells it.
fn spelled_command(command: &DemoCommand) -> String {
    match command {
        DemoCommand::MapAtFailure { fem, model } => format!(
            "             the same MAPF in one step: a3d-init map --fem {} --step failure --mpm {} --h auto --stress equilibrium --material-map mat0=silty_sand",
            fem.display(),
            model.display()
        ),
        DemoCommand::RunFlume { folder } => format!(
            "             run it: a3d-init run {} --time 3 --snapshots 0.3,0.8,1.2,3.0   (the monitored MPs A–E, the time to rest, snapshots; docs/slope.md compares them with the kernel and the paper)",
            folder.display()
        ),
    }
}
