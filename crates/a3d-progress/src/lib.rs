//! Progress counters of the long-running library work (FEM reading, kernel
//! mapping, table writing), so that the CLI can show progress bars without the
//! library printing anything. Each counter has a total and a done count, both
//! set with relaxed atomics; the library only counts, `cli` polls and draws.
//! Counting never changes results.

use std::sync::atomic::{AtomicU64, Ordering};

/// One phase's progress: `done` of `total` units (bytes, points or rows).
pub struct Counter {
    name: &'static str,
    done: AtomicU64,
    total: AtomicU64,
}

impl Counter {
    const fn new(name: &'static str) -> Counter {
        Counter {
            name,
            done: AtomicU64::new(0),
            total: AtomicU64::new(0),
        }
    }

    /// What the phase does, for a label.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Starts the phase with `total` units to do.
    pub fn start(&self, total: u64) {
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
    }

    /// Counts `n` more units done.
    pub fn add(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }

    /// (done, total).
    pub fn get(&self) -> (u64, u64) {
        (
            self.done.load(Ordering::Relaxed),
            self.total.load(Ordering::Relaxed),
        )
    }
}

/// Bytes of FEM CSV data rows parsed.
pub static READ_FEM: Counter = Counter::new("reading FEM table");
/// Points mapped by the kernel mapper.
pub static MAP: Counter = Counter::new("kernel mapping");
/// Rows of MAPF or mps.csv formatted.
pub static WRITE_TABLE: Counter = Counter::new("writing tables");

/// Every counter, in pipeline order.
pub fn all() -> [&'static Counter; 3] {
    [&READ_FEM, &MAP, &WRITE_TABLE]
}
