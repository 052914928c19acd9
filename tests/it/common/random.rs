//! Seeded random point clouds and thread pools for the kernel and calibration
//! tests.

use std::ops::Range;

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// A point drawn uniformly from `range` in each of `dim` coordinates; z = 0 in
/// 2D. Draws x, y, then z, in that order.
pub fn random_point(rng: &mut ChaCha8Rng, dim: usize, range: Range<f64>) -> [f64; 3] {
    let x = rng.random_range(range.clone());
    let y = rng.random_range(range.clone());
    let z = if dim == 3 {
        rng.random_range(range)
    } else {
        0.0
    };
    [x, y, z]
}

/// `n` points of [`random_point`].
pub fn random_points(
    rng: &mut ChaCha8Rng,
    dim: usize,
    n: usize,
    range: Range<f64>,
) -> Vec<[f64; 3]> {
    (0..n)
        .map(|_| random_point(rng, dim, range.clone()))
        .collect()
}

/// Runs `f` in a rayon pool of `threads` threads.
pub fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// The `n × n` nodes of a square grid of `spacing` from the origin in the
/// plane z = 0, x running fastest.
pub fn grid_nodes(n: usize, spacing: f64) -> Vec<[f64; 3]> {
    (0..n * n)
        .map(|k| [(k % n) as f64 * spacing, (k / n) as f64 * spacing, 0.0])
        .collect()
}
