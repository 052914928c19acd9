//! The `a3d-init` binary: the command line over the `a3d_init` library
//! (crates/a3d-init-lib). It parses, calls and prints; see [`cli`]. The
//! allocator setting of the process is in [`memory`].

mod cli;
mod memory;

fn main() -> std::process::ExitCode {
    memory::return_freed_memory();
    cli::main()
}
