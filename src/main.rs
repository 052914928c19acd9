//! The `a3d-init` binary: a thin shell around [`a3d_init::cli::main`].

fn main() -> std::process::ExitCode {
    a3d_init::cli::main()
}
