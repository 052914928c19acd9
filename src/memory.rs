//! The process's allocator setting. glibc's malloc hands blocks of 128 KiB
//! and more back to the system when they are freed, but by default it raises
//! that threshold each time such a block is freed (up to 32 MiB); blocks
//! below the raised threshold then come from its arenas, and what is freed
//! there mostly stays resident. On the 10⁶-node `map` that kept 40–150 MB
//! more resident than the heap ever held at once, varying from run to run
//! with the threads' timing. A fixed threshold keeps the peak resident
//! memory within about 20 MB of the heap's peak, at no measured cost in time
//! (README, Performance).

/// Fixes glibc's threshold for returning freed blocks to the system at its
/// default, 128 KiB (no effect elsewhere). Called first thing in `main`.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[allow(unsafe_code)]
pub fn return_freed_memory() {
    // SAFETY: mallopt sets one malloc parameter and touches no Rust memory;
    // it is called before any other thread exists. A refusal (0) leaves the
    // default, which is only slower to release memory.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 128 * 1024);
    }
}

/// Nothing to set outside glibc.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn return_freed_memory() {}
