//! The Shepard-normalised kernel mapper (paper Eq. 1):
//! f(x) = Σ w(dᵢ/h)·fᵢ / Σ w(dᵢ/h) over the nodes inside the kernel support.
//!
//! Parallel over query points with rayon. Each point's sums run over its
//! neighbours sorted by (distance, index), and chunks are concatenated in order,
//! so the output is bit-identical for any thread count ([`map_points_serial`] is
//! the oracle). Groups keep materials apart: a point only takes nodes of its own
//! group ("no smoothing across material boundaries").

use rayon::prelude::*;

use super::neighbours::NeighbourIndex;
use super::{Kernel, KernelKind};

/// What to do with a point that has no node inside the kernel support, or whose
/// Shepard ratio is below the threshold ("null point").
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum OutsidePolicy {
    /// Fail, naming how many and the first ids.
    Error,
    /// Take the values of the nearest node of the point's group.
    Nearest,
    /// Leave the point unmapped (status `Skipped`; its values are NaN and must
    /// not be written).
    Skip,
}

/// Settings of one mapping.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MapSettings {
    pub kernel: KernelKind,
    /// Smoothing length h (m).
    pub h: f64,
    /// Null-point threshold on the Shepard ratio (see [`MapResult::shepard`]).
    pub min_shepard: f64,
    pub outside: OutsidePolicy,
}

/// The FEM side of a mapping.
#[derive(Clone, Copy)]
pub struct NodeCloud<'a> {
    pub positions: &'a [[f64; 3]],
    pub dim: usize,
    /// Row-major n_nodes × n_fields.
    pub values: &'a [f64],
    pub n_fields: usize,
    /// Group id per node (material/region); `None` = one group.
    pub group: Option<&'a [u32]>,
    /// Typical node volume (l^dim with l the median nearest-neighbour spacing);
    /// scales Σw into the Shepard ratio.
    pub node_volume: f64,
}

/// How a point got its values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum PointStatus {
    Mapped,
    Nearest,
    Skipped,
}

/// The mapped values and diagnostics per point.
#[derive(Clone, Debug, PartialEq)]
pub struct MapResult {
    /// Row-major n_points × n_fields.
    pub values: Vec<f64>,
    pub n_neighbours: Vec<u32>,
    /// Shepard ratio Σw·V_node: ≈ 1 inside a uniform cloud, ≈ 0.5 on a straight
    /// edge, → 0 where the support barely reaches a node.
    pub shepard: Vec<f64>,
    pub status: Vec<PointStatus>,
}

/// Why a mapping failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MapError {
    #[error(
        "{count} material point(s) have no FEM node inside the kernel support (2h = {support:.4} m) or a Shepard ratio below {threshold}; first MP ids: {first_ids:?}. Use --outside nearest|skip, a larger --h, or check that the FEM covers the model"
    )]
    NullPoints {
        count: usize,
        first_ids: Vec<usize>,
        support: f64,
        threshold: f64,
    },
    #[error("the smoothing length must be positive and finite, got {0}")]
    BadSmoothingLength(f64),
    #[error("group {0} of a material point has no FEM nodes")]
    EmptyGroup(u32),
}

/// Values and per-point (neighbours, Shepard ratio, status) of one chunk.
type ChunkResult = (Vec<f64>, Vec<(u32, f64, PointStatus)>);

struct Indexed {
    group: u32,
    members: Vec<u32>,
    index: NeighbourIndex,
}

fn build_indices(nodes: &NodeCloud<'_>) -> Vec<Indexed> {
    match nodes.group {
        None => vec![Indexed {
            group: u32::MAX,
            members: (0..nodes.positions.len() as u32).collect(),
            index: NeighbourIndex::new(nodes.positions, nodes.dim),
        }],
        Some(groups) => {
            let mut ids: Vec<u32> = groups.to_vec();
            ids.sort_unstable();
            ids.dedup();
            ids.into_iter()
                .map(|g| {
                    let members: Vec<u32> = (0..groups.len() as u32)
                        .filter(|&i| groups[i as usize] == g)
                        .collect();
                    let pts: Vec<[f64; 3]> = members
                        .iter()
                        .map(|&i| nodes.positions[i as usize])
                        .collect();
                    Indexed {
                        group: g,
                        members,
                        index: NeighbourIndex::new(&pts, nodes.dim),
                    }
                })
                .collect()
        }
    }
}

/// Maps one point into `out` (n_fields values); returns (neighbours, ratio, status).
fn map_one(
    nodes: &NodeCloud<'_>,
    idx: &Indexed,
    settings: &MapSettings,
    p: [f64; 3],
    scratch: &mut Vec<(u32, f64)>,
    out: &mut [f64],
) -> (u32, f64, PointStatus) {
    let support = settings.kernel.support() * settings.h;
    idx.index.within(p, support, scratch);
    let alpha = settings.kernel.alpha(nodes.dim, settings.h);
    out.iter_mut().for_each(|v| *v = 0.0);
    let mut sum_w = 0.0;
    let mut count = 0;
    for &(local, d) in scratch.iter() {
        let w = settings.kernel.shape(d / settings.h);
        if w <= 0.0 {
            continue;
        }
        count += 1;
        sum_w += w;
        let node = idx.members[local as usize] as usize;
        let row = &nodes.values[node * nodes.n_fields..(node + 1) * nodes.n_fields];
        for (o, v) in out.iter_mut().zip(row) {
            *o += w * v;
        }
    }
    let ratio = sum_w * alpha * nodes.node_volume;
    if count > 0 && ratio >= settings.min_shepard {
        out.iter_mut().for_each(|v| *v /= sum_w);
        return (count, ratio, PointStatus::Mapped);
    }
    match settings.outside {
        OutsidePolicy::Nearest => match idx.index.nearest(p) {
            Some((local, _)) => {
                let node = idx.members[local as usize] as usize;
                out.copy_from_slice(
                    &nodes.values[node * nodes.n_fields..(node + 1) * nodes.n_fields],
                );
                (count, ratio, PointStatus::Nearest)
            }
            None => {
                out.iter_mut().for_each(|v| *v = f64::NAN);
                (count, ratio, PointStatus::Skipped)
            }
        },
        OutsidePolicy::Error | OutsidePolicy::Skip => {
            out.iter_mut().for_each(|v| *v = f64::NAN);
            (count, ratio, PointStatus::Skipped)
        }
    }
}

fn run(
    nodes: &NodeCloud<'_>,
    points: &[[f64; 3]],
    point_group: Option<&[u32]>,
    settings: &MapSettings,
    parallel: bool,
) -> Result<MapResult, MapError> {
    if !(settings.h > 0.0 && settings.h.is_finite()) {
        return Err(MapError::BadSmoothingLength(settings.h));
    }
    // Groups separate only when both sides carry them.
    let grouped = nodes.group.is_some() && point_group.is_some();
    let ungrouped_nodes = NodeCloud {
        group: None,
        ..*nodes
    };
    let indices = build_indices(if grouped { nodes } else { &ungrouped_nodes });
    let lookup = |g: u32| -> Result<&Indexed, MapError> {
        if !grouped {
            return Ok(&indices[0]);
        }
        indices
            .iter()
            .find(|ix| ix.group == g)
            .ok_or(MapError::EmptyGroup(g))
    };
    if let Some(groups) = point_group {
        for &g in groups {
            lookup(g)?;
        }
    }
    let nf = nodes.n_fields;
    let chunk = 512;
    // Queries run in Morton (Z-curve) order of the points for cache locality in
    // the tree; results are scattered back to the input order. The order depends
    // only on the coordinates, so the output is the same for any thread count.
    let order = morton_order(points, nodes.dim);
    let work = |idx: &[u32]| {
        let mut scratch = Vec::with_capacity(128);
        let mut values = vec![0.0; idx.len() * nf];
        let mut meta = Vec::with_capacity(idx.len());
        for (k, &i) in idx.iter().enumerate() {
            let i = i as usize;
            let g = if grouped {
                point_group.map_or(u32::MAX, |gs| gs[i])
            } else {
                u32::MAX
            };
            let ix = lookup(g).unwrap_or(&indices[0]);
            meta.push(map_one(
                nodes,
                ix,
                settings,
                points[i],
                &mut scratch,
                &mut values[k * nf..(k + 1) * nf],
            ));
        }
        (values, meta)
    };
    let parts: Vec<ChunkResult> = if parallel {
        order.par_chunks(chunk).map(work).collect()
    } else {
        order.chunks(chunk).map(work).collect()
    };
    let mut result = MapResult {
        values: vec![0.0; points.len() * nf],
        n_neighbours: vec![0; points.len()],
        shepard: vec![0.0; points.len()],
        status: vec![PointStatus::Mapped; points.len()],
    };
    for (c, (values, meta)) in parts.into_iter().enumerate() {
        for (k, (n, r, st)) in meta.into_iter().enumerate() {
            let i = order[c * chunk + k] as usize;
            result.values[i * nf..(i + 1) * nf].copy_from_slice(&values[k * nf..(k + 1) * nf]);
            result.n_neighbours[i] = n;
            result.shepard[i] = r;
            result.status[i] = st;
        }
    }
    if settings.outside == OutsidePolicy::Error {
        let null: Vec<usize> = result
            .status
            .iter()
            .enumerate()
            .filter(|(_, s)| **s == PointStatus::Skipped)
            .map(|(i, _)| i + 1)
            .collect();
        if !null.is_empty() {
            return Err(MapError::NullPoints {
                count: null.len(),
                first_ids: null.into_iter().take(10).collect(),
                support: settings.kernel.support() * settings.h,
                threshold: settings.min_shepard,
            });
        }
    }
    Ok(result)
}

/// Maps the node fields onto `points` in parallel (deterministic).
pub fn map_points(
    nodes: &NodeCloud<'_>,
    points: &[[f64; 3]],
    point_group: Option<&[u32]>,
    settings: &MapSettings,
) -> Result<MapResult, MapError> {
    run(nodes, points, point_group, settings, true)
}

/// The serial oracle of [`map_points`].
pub fn map_points_serial(
    nodes: &NodeCloud<'_>,
    points: &[[f64; 3]],
    point_group: Option<&[u32]>,
    settings: &MapSettings,
) -> Result<MapResult, MapError> {
    run(nodes, points, point_group, settings, false)
}

/// Median distance from each node to its nearest other node: the reference
/// spacing l of the paper (h ≈ l for the cubic kernel on triangle meshes).
pub fn median_spacing(positions: &[[f64; 3]], dim: usize) -> f64 {
    if positions.len() < 2 {
        return 0.0;
    }
    let index = NeighbourIndex::new(positions, dim);
    let mut scratch = Vec::new();
    let (lo, hi) = bounds(positions);
    let diag = (0..3)
        .map(|k| (hi[k] - lo[k]).powi(2))
        .sum::<f64>()
        .sqrt()
        .max(1e-12);
    let r0 = diag / (positions.len() as f64).powf(1.0 / dim as f64) / 4.0;
    let mut d: Vec<f64> = positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            // Grow the radius until another node appears.
            let mut r = r0.max(1e-12);
            loop {
                index.within(*p, r, &mut scratch);
                if let Some(&(_, dist)) = scratch.iter().find(|(j, _)| *j as usize != i) {
                    return dist;
                }
                if r > 4.0 * diag {
                    return diag;
                }
                r *= 2.0;
            }
        })
        .collect();
    d.sort_by(f64::total_cmp);
    d[d.len() / 2]
}

fn bounds(positions: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Indices of `points` sorted along a Morton (Z-order) curve of their bounding box.
fn morton_order(points: &[[f64; 3]], dim: usize) -> Vec<u32> {
    let (lo, hi) = bounds(points);
    let bits = if dim == 3 { 21 } else { 31 };
    let scale: Vec<f64> = (0..3)
        .map(|k| {
            let span = hi[k] - lo[k];
            if span > 0.0 {
                ((1u64 << bits) - 1) as f64 / span
            } else {
                0.0
            }
        })
        .collect();
    let spread = |mut v: u64| -> u64 {
        // Interleave the bits of v with (dim − 1) zeros between them.
        let mut out = 0u64;
        for b in 0..bits {
            out |= (v & 1) << (b * dim);
            v >>= 1;
        }
        out
    };
    let mut keyed: Vec<(u64, u32)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut key = 0u64;
            for k in 0..dim {
                let q = (((p[k] - lo[k]) * scale[k]).max(0.0) as u64).min((1u64 << bits) - 1);
                key |= spread(q) << k;
            }
            (key, i as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}
