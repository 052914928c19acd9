//! The Shepard-normalised kernel mapper (paper Eq. 1):
//! f(x) = Σ w(dᵢ/h)·fᵢ / Σ w(dᵢ/h) over the nodes inside the kernel support.
//!
//! Parallel over query points with rayon. Each point's sums run over its
//! neighbours in the order of its group's cell grid (cell by cell, x
//! fastest, then node index within a cell): an order fixed by the data
//! structure and the point's coordinates alone, with no per-query sort, so
//! the output is bit-identical for any thread count ([`map_points_with`] run
//! serially is the oracle) and equals a brute-force sum in any other order
//! to rounding. Groups keep materials
//! apart: a point only takes nodes of its own group ("no smoothing across
//! material boundaries").
//!
//! Every group keeps its nodes in a cell grid, with the node values in the
//! grid's order, and queries run group by group and cell by cell (a counting
//! sort). Neighbours come from the grid ([`Search::Grid`]: the blocks of
//! nodes a cell's support reaches, found once per cell, tested per query;
//! the grid answers the `--outside nearest` fallback too) or from the kiddo
//! tree ([`Search::KdTree`], the reference, its hits named by their grid
//! positions and put in that order); both give the same lists, so the
//! results are bit-identical. Results are scattered back batch by batch to bound memory;
//! progress is counted in `a3d_progress::MAP`.

use rayon::prelude::*;

use super::grid::{self, Grid, Hits};
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
        "{count} material point(s) have no FEM node inside the kernel support (2h = {support:.4} m) or a Shepard ratio below {threshold}; first MP ids: {first_ids:?}. Use the outside policy nearest or skip, a larger smoothing length h, or check that the FEM covers the model"
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
    /// Uniform cell grid, queries processed cell by cell (the default), its
    /// distance test and weights in AVX-512 where the processor has it.
    Grid,
    /// [`Search::Grid`] in portable code only: the oracle of the vector path
    /// (the same bits) and what a processor without AVX-512 runs.
    GridPortable,
    /// The kiddo k-d tree, one query at a time (the reference).
    KdTree,
}

/// One group's nodes and their neighbour search.
struct Indexed {
    group: u32,
    /// The group's nodes, sorted cell by cell: a point's sums run over its
    /// neighbours in this order (see the module documentation).
    grid: Grid,
    /// The rows of cells the kernel support reaches around a cell.
    stencil: grid::Stencil,
    /// The node values in the grid's order (n_fields per node).
    values: Vec<f64>,
    /// [`Search::KdTree`]: the tree over the group's nodes (in their own
    /// order) and each node's position in the grid's order.
    tree: Option<(NeighbourIndex, Vec<u32>)>,
}

/// Grid cells per kernel support: half-support cells hold about 3.7 times the
/// support sphere's nodes in a query cell's runs (whole-support cells 6.4).
const CELLS_PER_SUPPORT: u32 = 2;

fn build_indices(nodes: &NodeCloud<'_>, search: Search, radius: f64) -> Vec<Indexed> {
    // `members`: the group's nodes, `None` for all of them (no copy).
    let make = |group: u32, members: Option<Vec<u32>>| {
        let node = |local: u32| members.as_ref().map_or(local, |m| m[local as usize]) as usize;
        let copied: Vec<[f64; 3]>;
        let positions = match &members {
            None => nodes.positions,
            Some(m) => {
                copied = m.iter().map(|&i| nodes.positions[i as usize]).collect();
                &copied
            }
        };
        let mut grid = Grid::with_cells(positions, nodes.dim, radius, CELLS_PER_SUPPORT);
        if search == Search::GridPortable {
            grid.portable();
        }
        let nf = nodes.n_fields;
        let mut values = Vec::with_capacity(grid.order().len() * nf);
        for &local in grid.order() {
            let at = node(local) * nf;
            values.extend_from_slice(&nodes.values[at..at + nf]);
        }
        // A coarse grid (a radius tiny against the cloud, a node far from the
        // rest) would test most nodes for every point: its group is searched
        // with the k-d tree, which gives the same lists.
        let tree = (search == Search::KdTree || grid.is_coarse()).then(|| {
            let mut rank = vec![0u32; positions.len()];
            for (pos, &local) in grid.order().iter().enumerate() {
                rank[local as usize] = pos as u32;
            }
            (NeighbourIndex::new(positions, nodes.dim), rank)
        });
        Indexed {
            group,
            stencil: grid.stencil(radius),
            grid,
            values,
            tree,
        }
    };
    match nodes.group {
        None => vec![make(u32::MAX, None)],
        Some(groups) => {
            // Each group's nodes in their order, in one pass over the nodes.
            let mut ids: Vec<u32> = groups.to_vec();
            ids.sort_unstable();
            ids.dedup();
            let mut members: Vec<Vec<u32>> = vec![Vec::new(); ids.len()];
            for (i, g) in groups.iter().enumerate() {
                if let Ok(at) = ids.binary_search(g) {
                    members[at].push(i as u32);
                }
            }
            ids.into_iter()
                .zip(members)
                .map(|(g, members)| make(g, Some(members)))
                .collect()
        }
    }
}

/// One point to map: its position, its neighbours (their positions in the
/// grid's order, ascending, and their distances) and a buffer for their
/// weights.
struct Query<'a> {
    p: [f64; 3],
    pos: &'a [u32],
    d: Distances<'a>,
    ws: &'a mut Vec<f64>,
}

/// A point's neighbour distances: squared as the grid finds them, or as the
/// k-d tree gives them.
#[derive(Clone, Copy)]
enum Distances<'a> {
    Squared(&'a [f64]),
    Plain(&'a [f64]),
}

/// Σ w·v and Σ w over the neighbours with a positive weight, in their
/// order, for `NF` fields: the sums (into `out`), the count and Σ w.
#[inline(always)]
fn accumulate<const NF: usize>(
    pos: &[u32],
    ws: &[f64],
    values: &[f64],
    out: &mut [f64],
) -> (u32, f64) {
    let (mut acc, mut sum_w, mut count) = ([0.0f64; NF], 0.0, 0);
    for (&k, &w) in pos.iter().zip(ws) {
        if w <= 0.0 {
            continue;
        }
        count += 1;
        sum_w += w;
        let at = k as usize * NF;
        let v: &[f64; NF] = values[at..at + NF].try_into().unwrap_or(&[0.0; NF]);
        for f in 0..NF {
            acc[f] += w * v[f];
        }
    }
    out.copy_from_slice(&acc);
    (count, sum_w)
}

/// [`accumulate`] for any number of fields, summing in `out`.
fn accumulate_any(pos: &[u32], ws: &[f64], values: &[f64], out: &mut [f64]) -> (u32, f64) {
    let nf = out.len();
    let (mut sum_w, mut count) = (0.0, 0);
    out.iter_mut().for_each(|v| *v = 0.0);
    for (&k, &w) in pos.iter().zip(ws) {
        if w <= 0.0 {
            continue;
        }
        count += 1;
        sum_w += w;
        let at = k as usize * nf;
        for (o, v) in out.iter_mut().zip(&values[at..at + nf]) {
            *o += w * v;
        }
    }
    (count, sum_w)
}

/// Maps one point into `out` (n_fields values) from its neighbours; returns
/// (neighbours, ratio, status).
#[inline(always)]
fn map_one(
    nodes: &NodeCloud<'_>,
    idx: &Indexed,
    settings: &MapSettings,
    Query { p, pos, d, ws }: Query<'_>,
    out: &mut [f64],
) -> (u32, f64, PointStatus) {
    let alpha = settings.kernel.alpha(nodes.dim, settings.h);
    match d {
        Distances::Squared(d2) => {
            settings
                .kernel
                .weights_squared(d2, settings.h, idx.grid.simd(), ws)
        }
        Distances::Plain(d) => settings.kernel.weights(d, settings.h, ws),
    }
    // The sums in registers for the usual field counts (the same operations
    // in the same order for every count, so the same bits).
    let (count, sum_w) = match out.len() {
        1 => accumulate::<1>(pos, ws, &idx.values, out),
        2 => accumulate::<2>(pos, ws, &idx.values, out),
        3 => accumulate::<3>(pos, ws, &idx.values, out),
        4 => accumulate::<4>(pos, ws, &idx.values, out),
        5 => accumulate::<5>(pos, ws, &idx.values, out),
        6 => accumulate::<6>(pos, ws, &idx.values, out),
        7 => accumulate::<7>(pos, ws, &idx.values, out),
        8 => accumulate::<8>(pos, ws, &idx.values, out),
        _ => accumulate_any(pos, ws, &idx.values, out),
    };
    let nf = out.len();
    let row = |k: u32| &idx.values[k as usize * nf..(k as usize + 1) * nf];
    let ratio = sum_w * alpha * nodes.node_volume;
    if count > 0 && ratio >= settings.min_shepard {
        out.iter_mut().for_each(|v| *v /= sum_w);
        return (count, ratio, PointStatus::Mapped);
    }
    match settings.outside {
        OutsidePolicy::Nearest => {
            // The nearest node of the group, as a position in the grid's order.
            let near = match &idx.tree {
                Some((tree, rank)) => tree.nearest(p).map(|(i, d)| (rank[i as usize], d)),
                None => idx.grid.nearest(p),
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

/// The points to map: a slice of positions, or the positions inside a
/// caller's own records (a material point table), read where they are
/// instead of copied out.
#[derive(Clone, Copy)]
pub enum Points<'a> {
    Slice(&'a [[f64; 3]]),
    /// `len` records, record `i` at `at(i)`.
    Records {
        len: usize,
        at: &'a (dyn Fn(usize) -> [f64; 3] + Sync),
    },
}

impl Points<'_> {
    pub fn len(&self) -> usize {
        match self {
            Points::Slice(s) => s.len(),
            Points::Records { len, .. } => *len,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Point `i`'s position.
    #[inline(always)]
    pub fn at(&self, i: usize) -> [f64; 3] {
        match self {
            Points::Slice(s) => s[i],
            Points::Records { at, .. } => at(i),
        }
    }
}

/// What every chunk of queries reads.
struct Chunk<'a> {
    nodes: &'a NodeCloud<'a>,
    indices: &'a [Indexed],
    settings: &'a MapSettings,
    points: Points<'a>,
    /// The points' groups where groups separate.
    point_group: Option<&'a [u32]>,
    support: f64,
}

impl Chunk<'_> {
    /// The position in `indices` of group `g`'s nodes (`indices` is sorted
    /// by group, see `build_indices`); 0 where groups do not separate.
    #[inline(always)]
    fn group_at(&self, g: u32) -> Result<usize, MapError> {
        match self.point_group {
            None => Ok(0),
            Some(_) => self
                .indices
                .binary_search_by_key(&g, |ix| ix.group)
                .map_err(|_| MapError::EmptyGroup(g)),
        }
    }

    /// The group of point `i` (`u32::MAX` where groups do not separate).
    #[inline(always)]
    fn group_of(&self, i: usize) -> u32 {
        self.point_group.map_or(u32::MAX, |gs| gs[i])
    }

    /// The nodes and search of group `g` (checked by `run` before any query).
    #[inline(always)]
    fn lookup(&self, g: u32) -> &Indexed {
        &self.indices[self.group_at(g).unwrap_or(0)]
    }

    /// Maps the points `idx` (in query order): their values and per-point
    /// (neighbours, ratio, status). Inlined into
    /// [`crate::simd::Avx512::run`] where the processor has it.
    #[inline(always)]
    fn work(&self, idx: &[u32]) -> ChunkResult {
        let (nodes, settings, support) = (self.nodes, self.settings, self.support);
        let nf = nodes.n_fields;
        let points = self.points;
        let mut blocks = grid::Blocks::default();
        let mut blocks_of: Option<(u32, grid::Cell)> = None;
        let mut hits = Hits::default();
        let mut found = Vec::with_capacity(128);
        let (mut tree_pos, mut tree_d) = (Vec::with_capacity(128), Vec::with_capacity(128));
        let mut ws = Vec::with_capacity(128);
        let mut values = vec![0.0; idx.len() * nf];
        let mut meta = Vec::with_capacity(idx.len());
        // The chunk's points gathered first: loads that do not wait on each other.
        let gathered: Vec<([f64; 3], u32)> = idx
            .iter()
            .map(|&i| (points.at(i as usize), self.group_of(i as usize)))
            .collect();
        for (k, &(p, g)) in gathered.iter().enumerate() {
            let ix = self.lookup(g);
            let (pos, d) = match &ix.tree {
                None => {
                    let cell = ix.grid.cell(p);
                    if blocks_of != Some((g, cell)) {
                        ix.grid.blocks(&ix.stencil, cell, &mut blocks);
                        blocks_of = Some((g, cell));
                    }
                    ix.grid.collect(&blocks, p, support, &mut hits);
                    let (pos, d2) = hits.in_grid_order();
                    (pos, Distances::Squared(d2))
                }
                Some((tree, rank)) => {
                    // The reference: the tree's hits by their positions in
                    // the grid's order, in that order.
                    tree.within(p, support, &mut found);
                    for e in found.iter_mut() {
                        e.0 = rank[e.0 as usize];
                    }
                    found.sort_unstable_by_key(|e| e.0);
                    tree_pos.clear();
                    tree_d.clear();
                    tree_pos.extend(found.iter().map(|e| e.0));
                    tree_d.extend(found.iter().map(|e| e.1));
                    (&tree_pos[..], Distances::Plain(&tree_d[..]))
                }
            };
            let query = Query {
                p,
                pos,
                d,
                ws: &mut ws,
            };
            meta.push(map_one(
                nodes,
                ix,
                settings,
                query,
                &mut values[k * nf..(k + 1) * nf],
            ));
        }
        (values, meta)
    }
}

/// How [`run`] is called: the search, in parallel or not, and node values
/// the caller hands over (they replace `nodes.values` and are freed once the
/// grid holds its own copy: one copy fewer at the peak).
struct RunOptions {
    search: Search,
    parallel: bool,
    owned: Handed,
}

fn run(
    given: &NodeCloud<'_>,
    points: Points<'_>,
    point_group: Option<&[u32]>,
    settings: &MapSettings,
    options: RunOptions,
) -> Result<MapResult, MapError> {
    let RunOptions {
        search,
        parallel,
        owned,
    } = options;
    if !(settings.h > 0.0 && settings.h.is_finite()) {
        return Err(MapError::BadSmoothingLength(settings.h));
    }
    // Groups separate only when both sides carry them.
    let grouped = given.group.is_some() && point_group.is_some();
    let support = settings.kernel.support() * settings.h;
    let indices = {
        let cloud = NodeCloud {
            values: owned.values.as_deref().unwrap_or(given.values),
            positions: owned.positions.as_deref().unwrap_or(given.positions),
            group: if grouped { given.group } else { None },
            ..*given
        };
        build_indices(&cloud, search, support)
    };
    // Every group holds its own copy of the positions and values: what was
    // handed over goes now.
    drop(owned);
    let nodes = &NodeCloud {
        values: &[],
        positions: &[],
        ..*given
    };
    let ctx = Chunk {
        nodes,
        indices: &indices,
        settings,
        points,
        point_group: if grouped { point_group } else { None },
        support,
    };
    if let Some(groups) = ctx.point_group {
        for &g in groups {
            ctx.group_at(g)?;
        }
    }
    let nf = nodes.n_fields;
    let chunk = 512;
    // Queries run group by group, cell by cell, so that the points of a cell
    // share its runs and neighbouring cells their nodes in cache; results are
    // scattered back to the input order. The order depends only on the
    // coordinates, so the output is the same for any thread count.
    let key_of = |i: usize| -> (usize, u64) {
        let at = ctx.group_at(ctx.group_of(i)).unwrap_or(0);
        (
            at,
            indices[at]
                .grid
                .cell_key(indices[at].grid.cell(points.at(i))),
        )
    };
    let order = query_order(points.len(), &indices, key_of);
    // Every group's grid made the same choice (see `build_indices`).
    let simd = indices.first().and_then(|ix| ix.grid.simd());
    let work = |idx: &[u32]| match simd {
        Some(simd) => simd.run(|| ctx.work(idx)),
        None => ctx.work(idx),
    };
    let mut result = MapResult {
        values: vec![0.0; points.len() * nf],
        n_neighbours: vec![0; points.len()],
        shepard: vec![0.0; points.len()],
        status: vec![PointStatus::Mapped; points.len()],
    };
    // Batches of chunks bound the memory of results not yet scattered.
    let batch = chunk * 64;
    a3d_progress::MAP.start(points.len() as u64);
    for (b, batch_order) in order.chunks(batch).enumerate() {
        a3d_progress::MAP.add(batch_order.len() as u64);
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
        owned: Handed::default(),
    };
    run(nodes, Points::Slice(points), point_group, settings, options)
}

/// Node data a caller hands over to [`map_points_from`] in place of the
/// cloud's own (`None`: the cloud's): the mapper frees it as soon as its grid
/// holds its own copy, which lowers the peak memory of a large mapping by one
/// copy of the values and one of the positions.
#[derive(Default)]
pub struct Handed {
    /// Row-major node values (as `NodeCloud::values`).
    pub values: Option<Vec<f64>>,
    /// Node positions (as `NodeCloud::positions`).
    pub positions: Option<Vec<[f64; 3]>>,
}

/// [`map_points`] on [`Points`] (positions read inside the caller's
/// records), with node data the caller may hand over ([`Handed`]).
pub fn map_points_from(
    nodes: &NodeCloud<'_>,
    owned: Handed,
    points: Points<'_>,
    point_group: Option<&[u32]>,
    settings: &MapSettings,
) -> Result<MapResult, MapError> {
    let options = RunOptions {
        search: Search::Grid,
        parallel: true,
        owned,
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
    // A grid whose cells hold most points (one point far from the rest)
    // would compare them all pairwise: the k-d tree answers then.
    let n = positions.len() as u64;
    let grid = (cell.is_finite() && cell > 0.0).then(|| Grid::new(positions, dim, cell));
    let mut found = match grid {
        Some(g) if !g.is_coarse() && g.crowding() <= 64 * n + 4096 => g.nearest_others(cell),
        _ => vec![None; positions.len()],
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

/// The points `0..n` sorted by (group, cell key, index), `key_of` giving a
/// point's group (a position in `indices`) and cell key (below the group
/// grid's [`Grid::cell_keys`]): a counting sort where the keys are few enough,
/// a comparison sort otherwise.
fn query_order(
    n: usize,
    indices: &[Indexed],
    key_of: impl Fn(usize) -> (usize, u64) + Sync,
) -> Vec<u32> {
    let mut offset = Vec::with_capacity(indices.len());
    let mut total = 0u64;
    for ix in indices {
        offset.push(total);
        total = total.saturating_add(ix.grid.cell_keys());
    }
    let keys: Vec<u64> = (0..n)
        .into_par_iter()
        .map(|i| {
            let (at, key) = key_of(i);
            offset[at] + key
        })
        .collect();
    if total > 8 * n as u64 + 4096 {
        let mut keyed: Vec<(u64, u32)> = keys.into_iter().zip(0..n as u32).collect();
        keyed.par_sort_unstable();
        return keyed.into_iter().map(|(_, i)| i).collect();
    }
    let mut start = vec![0u32; total as usize + 1];
    for &k in &keys {
        start[k as usize + 1] += 1;
    }
    for k in 0..total as usize {
        start[k + 1] += start[k];
    }
    let mut order = vec![0u32; n];
    for (i, &k) in keys.iter().enumerate() {
        let slot = &mut start[k as usize];
        order[*slot as usize] = i as u32;
        *slot += 1;
    }
    order
}
