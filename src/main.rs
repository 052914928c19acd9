//! The `a3d-init` binary: a thin shell around [`a3d_init::cli::run`].
//!
//! mimalloc is the allocator: the parallel readers and writers free many
//! chunk-sized buffers from worker threads, which glibc's per-thread arenas
//! keep mapped (about 150 MB of the 10⁶-node case's peak); mimalloc returns
//! them to the system.

#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    a3d_init::cli::main()
}
