//! The Shepard-normalised kernel mapper (paper Eq. 1):
//! f(x) = Σ w(dᵢ/h)·fᵢ / Σ w(dᵢ/h) over the nodes inside the kernel support.
//!
//! Parallel over query points with rayon. Each point's sums run over its
//! neighbours sorted by (distance, index), and chunks are concatenated in
//! order, so the output is bit-identical for any thread count
//! ([`map_points_with`] run serially is the oracle). Groups keep materials
//! apart: a point only takes nodes of its own group ("no smoothing across
//! material boundaries").
//!
//! Neighbours come from the cell grid ([`Search::Grid`]: queries in Morton
//! order of their cells, each visiting the rows of cells its support reaches;
//! the grid keeps the node values in its own order and answers the
//! `--outside nearest` fallback too) or from the kiddo tree
//! ([`Search::KdTree`], the reference); both give the same sorted lists, so
//! the results are bit-identical. Results are scattered back batch by batch
//! to bound memory; progress is counted in `crate::progress::MAP`.

use rayon::prelude::*;

use super::grid::{self, Grid, Scratch};
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

/// How the mapper finds the nodes inside the kernel support.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Search {
    /// Uniform cell grid, queries processed cell by cell (the default).
    Grid,
    /// The kiddo k-d tree, one query at a time (the reference).
    KdTree,
}

/// One group's nodes and their neighbour search.
struct Indexed {
    group: u32,
    members: Vec<u32>,
    /// Built by [`Search::KdTree`] (the grid answers its own nearest-node fallbacks).
    tree: std::sync::OnceLock<NeighbourIndex>,
    grid: Option<Grid>,
    /// The node values in the grid's order (n_fields per node), so that the
    /// rows of a cell's candidates are gathered with them.
    grid_values: Vec<f64>,
}

impl Indexed {
    fn tree(&self, nodes: &NodeCloud<'_>) -> &NeighbourIndex {
        self.tree.get_or_init(|| {
            let positions: Vec<[f64; 3]> = self
                .members
                .iter()
                .map(|&i| nodes.positions[i as usize])
                .collect();
            NeighbourIndex::new(&positions, nodes.dim)
        })
    }
}

fn build_indices(nodes: &NodeCloud<'_>, search: Search, radius: f64) -> Vec<Indexed> {
    let make = |group: u32, members: Vec<u32>| {
        let positions: Vec<[f64; 3]> = members
            .iter()
            .map(|&i| nodes.positions[i as usize])
            .collect();
        let grid = (search == Search::Grid).then(|| Grid::new(&positions, nodes.dim, radius));
        let nf = nodes.n_fields;
        let grid_values = grid.as_ref().map_or_else(Vec::new, |g| {
            let mut v = Vec::with_capacity(g.order().len() * nf);
            for &local in g.order() {
                let node = members[local as usize] as usize;
                v.extend_from_slice(&nodes.values[node * nf..(node + 1) * nf]);
            }
            v
        });
        drop(positions);
        let ix = Indexed {
            group,
            members,
            grid,
            grid_values,
            tree: std::sync::OnceLock::new(),
        };
        if search == Search::KdTree {
            ix.tree(nodes);
        }
        ix
    };
    match nodes.group {
        None => vec![make(u32::MAX, (0..nodes.positions.len() as u32).collect())],
        Some(groups) => {
            let mut ids: Vec<u32> = groups.to_vec();
            ids.sort_unstable();
            ids.dedup();
            ids.into_iter()
                .map(|g| {
                    let members: Vec<u32> = (0..groups.len() as u32)
                        .filter(|&i| groups[i as usize] == g)
                        .collect();
                    make(g, members)
                })
                .collect()
        }
    }
}

/// One point to map: its position, its neighbours (sorted by distance, then
/// node index) and a buffer for their weights.
struct Query<'a> {
    p: [f64; 3],
    found: &'a [(u32, f64)],
    ws: &'a mut Vec<f64>,
}

/// Maps one point into `out` (n_fields values) from its neighbours (`row`
/// gives a neighbour's values); returns (neighbours, ratio, status).
fn map_one<'r>(
    nodes: &NodeCloud<'_>,
    idx: &Indexed,
    settings: &MapSettings,
    Query { p, found, ws }: Query<'_>,
    row: impl Fn(u32) -> &'r [f64],
    out: &mut [f64],
) -> (u32, f64, PointStatus) {
    let alpha = settings.kernel.alpha(nodes.dim, settings.h);
    out.iter_mut().for_each(|v| *v = 0.0);
    let mut sum_w = 0.0;
    let mut count = 0;
    settings.kernel.shapes(found, settings.h, ws);
    // Up to 8 fields sum in registers (the same operations in the same
    // order as in `out`, so the same bits).
    let mut acc = [0.0f64; 8];
    let nf = out.len();
    for (&(local, _), &w) in found.iter().zip(ws.iter()) {
        if w <= 0.0 {
            continue;
        }
        count += 1;
        sum_w += w;
        let v = row(local);
        if nf <= 8 {
            for (a, v) in acc[..nf].iter_mut().zip(v) {
                *a += w * v;
            }
        } else {
            for (o, v) in out.iter_mut().zip(v) {
                *o += w * v;
            }
        }
    }
    if nf <= 8 {
        out.copy_from_slice(&acc[..nf]);
    }
    let ratio = sum_w * alpha * nodes.node_volume;
    if count > 0 && ratio >= settings.min_shepard {
        out.iter_mut().for_each(|v| *v /= sum_w);
        return (count, ratio, PointStatus::Mapped);
    }
    match settings.outside {
        OutsidePolicy::Nearest => {
            // The nearest node of the group, indexed as `found` is (see `row`).
            let near = match &idx.grid {
                Some(grid) => grid.nearest(p),
                None => idx.tree(nodes).nearest(p),
            };
            match near {
                Some((k, _)) => {
                    out.copy_from_slice(row(k));
                    (count, ratio, PointStatus::Nearest)
                }
                None => {
                    out.iter_mut().for_each(|v| *v = f64::NAN);
                    (count, ratio, PointStatus::Skipped)
                }
            }
        }
        OutsidePolicy::Error | OutsidePolicy::Skip => {
            out.iter_mut().for_each(|v| *v = f64::NAN);
            (count, ratio, PointStatus::Skipped)
        }
    }
}

/// How [`run`] is called: the search, in parallel or not, and node values
/// the caller hands over (they replace `nodes.values` and are freed once the
/// grid holds its own copy: one copy fewer at the peak).
struct RunOptions {
    search: Search,
    parallel: bool,
    owned_values: Option<Vec<f64>>,
}

fn run(
    given: &NodeCloud<'_>,
    points: &[[f64; 3]],
    point_group: Option<&[u32]>,
    settings: &MapSettings,
    options: RunOptions,
) -> Result<MapResult, MapError> {
    let RunOptions {
        search,
        parallel,
        owned_values,
    } = options;
    if !(settings.h > 0.0 && settings.h.is_finite()) {
        return Err(MapError::BadSmoothingLength(settings.h));
    }
    // Groups separate only when both sides carry them.
    let grouped = given.group.is_some() && point_group.is_some();
    let support = settings.kernel.support() * settings.h;
    let indices = {
        let values = owned_values.as_deref().unwrap_or(given.values);
        let cloud = NodeCloud {
            values,
            group: if grouped { given.group } else { None },
            ..*given
        };
        build_indices(&cloud, search, support)
    };
    // The grid answers every query from its own copy of the values.
    let emptied = NodeCloud {
        values: &[],
        ..*given
    };
    let kept: Vec<f64>;
    let nodes = match (owned_values, search) {
        (Some(_), Search::Grid) => &emptied,
        (Some(v), Search::KdTree) => {
            kept = v;
            &NodeCloud {
                values: &kept,
                ..*given
            }
        }
        (None, _) => given,
    };
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
    let group_of = |i: usize| -> u32 {
        if grouped {
            point_group.map_or(u32::MAX, |gs| gs[i])
        } else {
            u32::MAX
        }
    };
    let order = match search {
        Search::KdTree => morton_order(points, nodes.dim),
        Search::Grid => {
            // Cell by cell in Morton order of the cells, group by group.
            let mut keyed: Vec<(u32, u64, u32)> = points
                .par_iter()
                .enumerate()
                .map(|(i, p)| {
                    let g = group_of(i);
                    let ix = lookup(g).unwrap_or(&indices[0]);
                    let key = ix
                        .grid
                        .as_ref()
                        .map_or(0, |grid| grid::morton(grid.cell(*p)));
                    (g, key, i as u32)
                })
                .collect();
            keyed.par_sort_unstable();
            keyed.into_iter().map(|(_, _, i)| i).collect()
        }
    };
    let work = |idx: &[u32]| {
        let mut found = Vec::with_capacity(128);
        let mut scratch = Scratch::default();
        let mut ws = Vec::with_capacity(128);
        let mut values = vec![0.0; idx.len() * nf];
        let mut meta = Vec::with_capacity(idx.len());
        for (k, &i) in idx.iter().enumerate() {
            let i = i as usize;
            let g = group_of(i);
            let ix = lookup(g).unwrap_or(&indices[0]);
            let out = &mut values[k * nf..(k + 1) * nf];
            let m = match &ix.grid {
                Some(grid) => {
                    grid.query(points[i], support, &mut found, &mut scratch);
                    let rows = &ix.grid_values;
                    let row = |pos: u32| &rows[pos as usize * nf..(pos as usize + 1) * nf];
                    let query = Query {
                        p: points[i],
                        found: &found,
                        ws: &mut ws,
                    };
                    map_one(nodes, ix, settings, query, row, out)
                }
                None => {
                    ix.tree(nodes).within(points[i], support, &mut found);
                    let row = |local: u32| {
                        let node = ix.members[local as usize] as usize;
                        &nodes.values[node * nf..(node + 1) * nf]
                    };
                    let query = Query {
                        p: points[i],
                        found: &found,
                        ws: &mut ws,
                    };
                    map_one(nodes, ix, settings, query, row, out)
                }
            };
            meta.push(m);
        }
        (values, meta)
    };
    let mut result = MapResult {
        values: vec![0.0; points.len() * nf],
        n_neighbours: vec![0; points.len()],
        shepard: vec![0.0; points.len()],
        status: vec![PointStatus::Mapped; points.len()],
    };
    // Batches of chunks bound the memory of results not yet scattered.
    let batch = chunk * 64;
    crate::progress::MAP.start(points.len() as u64);
    for (b, batch_order) in order.chunks(batch).enumerate() {
        crate::progress::MAP.add(batch_order.len() as u64);
        let parts: Vec<ChunkResult> = if parallel {
            batch_order.par_chunks(chunk).map(work).collect()
        } else {
            batch_order.chunks(chunk).map(work).collect()
        };
        for (c, (values, meta)) in parts.into_iter().enumerate() {
            for (k, (n, r, st)) in meta.into_iter().enumerate() {
                let i = order[b * batch + c * chunk + k] as usize;
                result.values[i * nf..(i + 1) * nf].copy_from_slice(&values[k * nf..(k + 1) * nf]);
                result.n_neighbours[i] = n;
                result.shepard[i] = r;
                result.status[i] = st;
            }
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

/// Maps the node fields onto `points` in parallel (deterministic), with the
/// cell grid.
pub fn map_points(
    nodes: &NodeCloud<'_>,
    points: &[[f64; 3]],
    point_group: Option<&[u32]>,
    settings: &MapSettings,
) -> Result<MapResult, MapError> {
    map_points_with(nodes, points, point_group, settings, Search::Grid, true)
}

/// [`map_points`] with a chosen neighbour search, in parallel or serially
/// (the oracle). Every choice gives bit-identical results.
pub fn map_points_with(
    nodes: &NodeCloud<'_>,
    points: &[[f64; 3]],
    point_group: Option<&[u32]>,
    settings: &MapSettings,
    search: Search,
    parallel: bool,
) -> Result<MapResult, MapError> {
    let options = RunOptions {
        search,
        parallel,
        owned_values: None,
    };
    run(nodes, points, point_group, settings, options)
}

/// [`map_points`] for a caller that hands over the node values (`nodes.values`
/// is ignored): they are freed as soon as the grid holds its own copy, which
/// lowers the peak memory of a large mapping by one copy of the values.
pub fn map_points_taking(
    nodes: &NodeCloud<'_>,
    values: Vec<f64>,
    points: &[[f64; 3]],
    point_group: Option<&[u32]>,
    settings: &MapSettings,
) -> Result<MapResult, MapError> {
    let options = RunOptions {
        search: Search::Grid,
        parallel: true,
        owned_values: Some(values),
    };
    run(nodes, points, point_group, settings, options)
}

/// Distance from each point to its nearest other point (0 for a duplicate),
/// in parallel.
pub fn nearest_other_distances(positions: &[[f64; 3]], dim: usize) -> Vec<f64> {
    if positions.len() < 2 {
        return vec![0.0; positions.len()];
    }
    // A grid with about two points per cell answers most points from the
    // cells around theirs, isolated points by rings of cells; the k-d tree
    // only a degenerate cloud.
    let (lo, hi) = bounds(positions);
    let volume: f64 = (0..dim).map(|k| (hi[k] - lo[k]).max(1e-300)).product();
    let cell = (2.0 * volume / positions.len() as f64).powf(1.0 / dim as f64);
    let mut found = if cell.is_finite() && cell > 0.0 {
        Grid::new(positions, dim, cell).nearest_others(cell)
    } else {
        vec![None; positions.len()]
    };
    if found.iter().any(Option::is_none) {
        let index = NeighbourIndex::new(positions, dim);
        found.par_iter_mut().enumerate().for_each(|(i, d)| {
            if d.is_none() {
                *d = index.second_nearest_distance(positions[i]);
            }
        });
    }
    found.into_iter().map(|d| d.unwrap_or(0.0)).collect()
}

/// Median distance from each node to its nearest other node: the reference
/// spacing l of the paper (h ≈ l for the cubic kernel on triangle meshes).
pub fn median_spacing(positions: &[[f64; 3]], dim: usize) -> f64 {
    if positions.len() < 2 {
        return 0.0;
    }
    let mut d = nearest_other_distances(positions, dim);
    let mid = d.len() / 2;
    *d.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// The smallest distance between two points (0 with fewer than two).
pub fn min_spacing(positions: &[[f64; 3]], dim: usize) -> f64 {
    nearest_other_distances(positions, dim)
        .into_iter()
        .fold(f64::INFINITY, f64::min)
        .min(if positions.len() < 2 {
            0.0
        } else {
            f64::INFINITY
        })
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
