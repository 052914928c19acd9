//! `a3d-bench`: speed figures of a3d-init's hot paths on generated data. A
//! binary of its own, built on the test kit's generators, so that neither the
//! workloads nor their generators ship in `a3d-init`:
//!
//! ```text
//! cargo run --release -p a3d-bench -- map|gom|loo|e2e|csv|equilibrium|fos|runner|kernel
//! ```

/// `println!` that never panics: a closed stdout ends the output quietly.
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::write_line(format_args!($($arg)*))
    };
}

mod bench;
mod bench_fos;
mod bench_kernel;
mod bench_runner;
/// The shipped binary's allocator setting, the same file, so that the peak
/// memory a benchmark reports is the one `a3d-init` would have.
#[path = "../../../src/memory.rs"]
mod memory;

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;

/// a3d-bench: speed figures of a3d-init's hot paths on generated data.
#[derive(Debug, Parser)]
#[command(name = "a3d-bench", version, about, long_about = None)]
struct Cli {
    #[command(flatten)]
    args: BenchArgs,
}

#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// What to measure.
    #[arg(value_enum)]
    pub what: BenchWhat,
    /// Spatial dimension for `map` (2 or 3).
    #[arg(long, default_value_t = 3)]
    pub dim: usize,
    /// FEM nodes (`map`).
    #[arg(long, default_value_t = 1_000_000)]
    pub nodes: usize,
    /// Query points / MPs (`map`).
    #[arg(long, default_value_t = 1_000_000)]
    pub points: usize,
    /// Mean number of nodes inside the kernel support (`map`).
    #[arg(long, default_value_t = 50.0)]
    pub neighbours: f64,
    /// Elements of the generated GOM (`gom`).
    #[arg(long, default_value_t = 1_000_000)]
    pub elements: usize,
    /// Neighbour search for `map`: the cell grid (default) or the k-d tree reference.
    #[arg(long, value_enum, default_value_t = SearchArg::Grid)]
    pub search: SearchArg,
    /// Folder for the generated case and the output of `e2e` (default: a
    /// temporary folder, removed afterwards); for `fos`, the slope's model
    /// folder with its `sand-nodes.csv` (default `fixtures/slope`).
    #[arg(long)]
    pub dir: Option<std::path::PathBuf>,
    /// Write `fem.vtu` in `e2e` too.
    #[arg(long)]
    pub fem_vtu: bool,
    /// `e2e`: also run the scipy peer (`benches/peer/scipy_map.py`) on the
    /// same case with this Python (numpy and scipy installed), and print the
    /// map's total against the peer's compute.
    #[arg(long)]
    pub peer: Option<std::path::PathBuf>,
    /// Repetitions; the best is reported (`kernel`: our runs, whose
    /// minimum and median are reported).
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// The real Anura3D kernel's binary (`kernel`;
    /// shared/anura3d-kernel/build.sh builds it).
    #[arg(long)]
    pub anura3d: Option<std::path::PathBuf>,
    /// The `a3d-init` binary that `kernel` times (default: the one next to
    /// this binary).
    #[arg(long)]
    pub a3d_init: Option<std::path::PathBuf>,
    /// Which model `kernel` runs.
    #[arg(long, value_enum, default_value_t = KernelCase::Both)]
    pub case: KernelCase,
    /// Runs of the kernel (`kernel`; one takes one to two minutes).
    #[arg(long, default_value_t = 1)]
    pub kernel_repeat: usize,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum KernelCase {
    /// The demo's slope, two-phase, 0.2 s undamped.
    Demo,
    /// A 3D tetrahedral box of about `--points` MPs, 4 s at damping 0.75.
    Tet,
    Both,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum SearchArg {
    Grid,
    /// The grid without AVX-512.
    GridPortable,
    Kdtree,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum BenchWhat {
    /// Kernel mapping throughput (queries/s), cubic kernel, uniform random clouds.
    Map,
    /// GOM parsing throughput (MB/s) on a generated TRI3 model.
    Gom,
    /// Leave-one-out objective at one h and a full calibration (`--nodes`, 2D hydrostatic field).
    Loo,
    /// The whole `map` on a generated 3D case (`--nodes` random FEM nodes with
    /// pwp and six stresses in a 100 m cube, a TET mesh with about `--points`
    /// MPs, h giving `--neighbours` nodes in reach), phase by phase.
    E2e,
    /// FEM CSV reading throughput (MB/s) on a generated 3D table of `--nodes` rows
    /// (x, y, z, pwp and six stresses, shortest round-trip decimals).
    Csv,
    /// The equilibrium solve (`map --stress equilibrium`) on a generated dry
    /// Mohr–Coulomb slope of about `--points` MPs (`--dim 2`: TRI3, 3 MPs per
    /// element; `--dim 3`: tetrahedral_old, 4 MPs per element): assembly,
    /// factorisation, elastic solve, plastic iterations, peak memory.
    Equilibrium,
    /// Limit equilibrium on the shipped slope (`--dir`, default
    /// `fixtures/slope`): one Morgenstern–Price factor with the default
    /// search, and FS(t) over 40 generated node tables.
    Fos,
    /// The explicit runner on a generated saturated column of about
    /// `--points` MPs: particle-steps/s drained and two-phase coupled, and
    /// the time step of each.
    Runner,
    /// The runner against the real Anura3D kernel (`--anura3d`), both as
    /// whole processes on one thread, on the demo's slope (two-phase, 0.2 s)
    /// and a 3D tetrahedral box (`--points`, 4 s; the README's figure takes
    /// 100 000, which the kernel runs in about a minute): particle-steps/s
    /// each.
    Kernel,
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    match args.what {
        BenchWhat::Map => bench::map(&args),
        BenchWhat::Loo => bench::loo(&args),
        BenchWhat::E2e => bench::e2e(&args),
        BenchWhat::Equilibrium => bench::equilibrium(&args),
        BenchWhat::Fos => bench_fos::fos(&args),
        BenchWhat::Runner => bench_runner::runner(&args),
        BenchWhat::Kernel => bench_kernel::kernel(&args),
        BenchWhat::Csv => bench::csv(&args),
        BenchWhat::Gom => bench::gom(&args),
    }
}

/// The folder a benchmark writes in: `dir` (created), or a temporary one,
/// removed when the returned guard drops.
pub fn work_dir(
    dir: Option<&std::path::Path>,
) -> anyhow::Result<(std::path::PathBuf, Option<tempfile::TempDir>)> {
    match dir {
        Some(d) => {
            std::fs::create_dir_all(d)?;
            Ok((d.to_path_buf(), None))
        }
        None => {
            let tmp = tempfile::tempdir()?;
            Ok((tmp.path().to_path_buf(), Some(tmp)))
        }
    }
}

fn write_line(args: std::fmt::Arguments) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_fmt(args).and_then(|()| out.write_all(b"\n"));
}

fn main() -> ExitCode {
    memory::return_freed_memory();
    let cli = Cli::parse();
    match run(cli.args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let _ = writeln!(std::io::stderr(), "error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
