//! The `a3d-init` binary: the command line over the `a3d_init` library
//! (crates/a3d-init-lib). It parses, calls and prints; see [`cli`].

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
