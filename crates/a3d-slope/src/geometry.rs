//! The cross-section a limit-equilibrium analysis works on: regions (polygons,
//! each with a material and a unit weight), the ground surface (the upper
//! envelope of the regions' edges) and the two queries every slice makes, the
//! weight of the column above a base point and the region holding that point.
//!
//! Two constructors, one representation: [`Domain::from_polygons`] takes the
//! polygons directly (the published benchmarks), [`Domain::from_mesh`] makes
//! one polygon per active element of an Anura3D mesh (its element materials,
//! a unit weight per element). Everything below is the same code for both.
//! Plain geometry: no I/O.

use std::collections::HashMap;

use super::SlopeError;
use a3d_model::{ElementType, Mesh};

/// One region: a simple polygon (either orientation), the 0-based slot of its
/// material in the analysis' material list, and its unit weight (kN/m³).
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    pub polygon: Vec<[f64; 2]>,
    pub material: usize,
    pub unit_weight: f64,
}

/// What lies above a base point: the weight of the column per unit width
/// (kN/m per m) and the region that holds the point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Column {
    pub weight: f64,
    /// Index into [`Domain::regions`]; `None` outside the domain.
    pub region: Option<usize>,
}

/// Regions with an x-bin index and their ground surface.
#[derive(Clone, Debug)]
pub struct Domain {
    regions: Vec<Region>,
    /// Per region: (x_min, x_max).
    x_extent: Vec<(f64, f64)>,
    /// Regions overlapping each bin.
    bins: Vec<Vec<u32>>,
    bin_x0: f64,
    bin_width: f64,
    /// The ground surface, x non-decreasing (two points with the same x at a
    /// vertical step).
    ground: Vec<[f64; 2]>,
    /// Lowest point of the domain.
    bottom: f64,
}

impl Domain {
    /// A domain from polygons. Polygons must not overlap; the union must cover
    /// an x-interval without gaps.
    pub fn from_polygons(regions: Vec<Region>) -> Result<Domain, SlopeError> {
        if regions.is_empty() {
            return Err(SlopeError::Geometry("no region".into()));
        }
        for (k, r) in regions.iter().enumerate() {
            if r.polygon.len() < 3 {
                return Err(SlopeError::Geometry(format!(
                    "region {} has {} vertices; a polygon needs 3",
                    k + 1,
                    r.polygon.len()
                )));
            }
            if r.polygon.iter().flatten().any(|v| !v.is_finite()) || !r.unit_weight.is_finite() {
                return Err(SlopeError::Geometry(format!(
                    "region {} has a coordinate or unit weight that is not a number",
                    k + 1
                )));
            }
        }
        let edges = boundary_edges(&regions);
        let ground = upper_envelope(&edges)?;
        Ok(Domain::index(regions, ground))
    }

    /// A domain from a 2D mesh: one region per element whose entry in
    /// `element_region` is `Some((material slot, unit weight))`; `None` marks
    /// an inactive element. The element's corners are its polygon.
    pub fn from_mesh(
        mesh: &Mesh,
        element_region: &[Option<(usize, f64)>],
    ) -> Result<Domain, SlopeError> {
        if mesh.element_type.n_dim() != 2 {
            return Err(SlopeError::Geometry(format!(
                "limit equilibrium works on 2D sections; the mesh has {} elements",
                mesh.element_type.gom_name()
            )));
        }
        let mut regions = Vec::new();
        for (e, slot) in element_region.iter().enumerate() {
            let Some((material, unit_weight)) = *slot else {
                continue;
            };
            let corners = match mesh.element_type {
                ElementType::Tri3 | ElementType::Quad4 => mesh.corners(e),
                ElementType::TetOld | ElementType::Hex8 => {
                    unreachable!("3D types are refused above")
                }
            };
            regions.push(Region {
                polygon: corners
                    .iter()
                    .map(|&n| {
                        let p = mesh.nodes[n as usize];
                        [p[0], p[1]]
                    })
                    .collect(),
                material,
                unit_weight,
            });
        }
        Domain::from_polygons(regions)
    }

    fn index(regions: Vec<Region>, ground: Vec<[f64; 2]>) -> Domain {
        let x_extent: Vec<(f64, f64)> = regions
            .iter()
            .map(|r| {
                r.polygon
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                        (a.min(p[0]), b.max(p[0]))
                    })
            })
            .collect();
        let bottom = regions
            .iter()
            .flat_map(|r| r.polygon.iter().map(|p| p[1]))
            .fold(f64::INFINITY, f64::min);
        let x0 = ground[0][0];
        let x1 = ground[ground.len() - 1][0];
        let n_bins = (regions.len() / 8).clamp(1, 4096);
        let bin_width = ((x1 - x0) / n_bins as f64).max(f64::MIN_POSITIVE);
        let mut bins = vec![Vec::new(); n_bins];
        for (k, &(a, b)) in x_extent.iter().enumerate() {
            let lo = (((a - x0) / bin_width).floor().max(0.0) as usize).min(n_bins - 1);
            let hi = (((b - x0) / bin_width).floor().max(0.0) as usize).min(n_bins - 1);
            for bin in &mut bins[lo..=hi] {
                bin.push(k as u32);
            }
        }
        Domain {
            regions,
            x_extent,
            bins,
            bin_x0: x0,
            bin_width,
            ground,
            bottom,
        }
    }

    pub fn regions(&self) -> &[Region] {
        &self.regions
    }

    /// The ground surface, left to right.
    pub fn ground(&self) -> &[[f64; 2]] {
        &self.ground
    }

    /// (x_min, x_max) of the ground surface.
    pub fn x_range(&self) -> (f64, f64) {
        (self.ground[0][0], self.ground[self.ground.len() - 1][0])
    }

    /// The lowest point of the domain.
    pub fn bottom(&self) -> f64 {
        self.bottom
    }

    /// Ground elevation at `x` (the upper value at a vertical step); `None`
    /// outside the ground's x-range.
    pub fn ground_y(&self, x: f64) -> Option<f64> {
        polyline_y(&self.ground, x)
    }

    /// The regions whose x-extent may contain `x`.
    fn candidates(&self, x: f64) -> &[u32] {
        let k = ((x - self.bin_x0) / self.bin_width).floor();
        let last = self.bins.len() - 1;
        let k = if k.is_nan() || k < 0.0 {
            0
        } else {
            (k as usize).min(last)
        };
        &self.bins[k]
    }

    /// The weight above `(x, y)` per unit width and the region holding it
    /// (the region just above the point when it lies on an edge).
    pub fn column(&self, x: f64, y: f64) -> Column {
        let mut weight = 0.0;
        let mut region = None;
        let mut crossings: Vec<f64> = Vec::with_capacity(8);
        for &k in self.candidates(x) {
            let k = k as usize;
            let (a, b) = self.x_extent[k];
            if x < a || x > b {
                continue;
            }
            let r = &self.regions[k];
            vertical_crossings(&r.polygon, x, &mut crossings);
            for pair in crossings.chunks_exact(2) {
                let (lo, hi) = (pair[0], pair[1]);
                if hi > y {
                    weight += r.unit_weight * (hi - lo.max(y));
                }
                if lo <= y && y < hi {
                    region = Some(k);
                }
            }
        }
        Column { weight, region }
    }

    /// The region holding `(x, y)`, if any.
    pub fn region_at(&self, x: f64, y: f64) -> Option<usize> {
        let mut crossings: Vec<f64> = Vec::with_capacity(8);
        for &k in self.candidates(x) {
            let k = k as usize;
            let (a, b) = self.x_extent[k];
            if x < a || x > b {
                continue;
            }
            vertical_crossings(&self.regions[k].polygon, x, &mut crossings);
            if crossings.chunks_exact(2).any(|p| p[0] <= y && y < p[1]) {
                return Some(k);
            }
        }
        None
    }
}

/// The sorted y where the vertical line at `x` crosses the polygon's edges
/// (half-open in x, so a vertex is counted once); pairs bound the inside.
fn vertical_crossings(polygon: &[[f64; 2]], x: f64, out: &mut Vec<f64>) {
    out.clear();
    let n = polygon.len();
    for i in 0..n {
        let p = polygon[i];
        let q = polygon[(i + 1) % n];
        let (a, b) = if p[0] <= q[0] { (p, q) } else { (q, p) };
        if a[0] <= x && x < b[0] {
            let t = (x - a[0]) / (b[0] - a[0]);
            out.push(a[1] + t * (b[1] - a[1]));
        }
    }
    out.sort_by(f64::total_cmp);
    if out.len() % 2 == 1 {
        // A degenerate touch: drop the last crossing so the pairs stay inside.
        out.pop();
    }
}

/// y of a polyline (x non-decreasing) at `x`; the upper value at a vertical
/// step; `None` outside its range.
pub fn polyline_y(line: &[[f64; 2]], x: f64) -> Option<f64> {
    let n = line.len();
    if n == 0 || !(x >= line[0][0] && x <= line[n - 1][0]) {
        return None;
    }
    // First vertex with x ≥ the query.
    let k = line.partition_point(|p| p[0] < x);
    if k == 0 {
        return Some(
            line.iter()
                .take_while(|p| p[0] == x)
                .map(|p| p[1])
                .fold(f64::NEG_INFINITY, f64::max),
        );
    }
    if k == n {
        return Some(line[n - 1][1]);
    }
    let (a, b) = (line[k - 1], line[k]);
    if b[0] == x {
        let top = line[k..]
            .iter()
            .take_while(|p| p[0] == x)
            .map(|p| p[1])
            .fold(b[1], f64::max);
        return Some(top);
    }
    let t = (x - a[0]) / (b[0] - a[0]);
    Some(a[1] + t * (b[1] - a[1]))
}

type Edge = ([f64; 2], [f64; 2]);
/// An edge's endpoints by their coordinates' bits.
type EdgeKey = ((u64, u64), (u64, u64));

/// The edges that belong to one region only (shared edges are interior). A
/// polygon edge that is only partly shared stays in the list; the envelope
/// below does not need the list to be minimal, only to hold the outline.
fn boundary_edges(regions: &[Region]) -> Vec<Edge> {
    let key = |p: [f64; 2]| (p[0].to_bits(), p[1].to_bits());
    let mut count: HashMap<EdgeKey, (usize, Edge)> = HashMap::new();
    let mut order = Vec::new();
    for r in regions {
        let n = r.polygon.len();
        for i in 0..n {
            let (p, q) = (r.polygon[i], r.polygon[(i + 1) % n]);
            let (a, b) = if key(p) <= key(q) { (p, q) } else { (q, p) };
            let k = (key(a), key(b));
            let entry = count.entry(k).or_insert_with(|| {
                order.push(k);
                (0, (a, b))
            });
            entry.0 += 1;
        }
    }
    order
        .into_iter()
        .filter_map(|k| {
            let (c, e) = count[&k];
            (c == 1).then_some(e)
        })
        .collect()
}

/// The upper envelope of the edges: between consecutive vertex abscissae the
/// highest edge spanning the interval.
fn upper_envelope(edges: &[Edge]) -> Result<Vec<[f64; 2]>, SlopeError> {
    let mut xs: Vec<f64> = edges.iter().flat_map(|e| [e.0[0], e.1[0]]).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    if xs.len() < 2 {
        return Err(SlopeError::Geometry("the regions have no width".into()));
    }
    let mut ground: Vec<[f64; 2]> = Vec::new();
    for w in xs.windows(2) {
        let (a, b) = (w[0], w[1]);
        let mid = 0.5 * (a + b);
        let top = edges
            .iter()
            .filter(|e| {
                let (l, r) = (e.0[0].min(e.1[0]), e.0[0].max(e.1[0]));
                l <= a && r >= b && r > l
            })
            .map(|e| {
                let (p, q) = if e.0[0] <= e.1[0] {
                    (e.0, e.1)
                } else {
                    (e.1, e.0)
                };
                let at = |x: f64| p[1] + (x - p[0]) / (q[0] - p[0]) * (q[1] - p[1]);
                (at(mid), at(a), at(b))
            })
            .max_by(|u, v| u.0.total_cmp(&v.0));
        let Some((_, ya, yb)) = top else {
            return Err(SlopeError::Geometry(format!(
                "the regions leave a gap between x = {a} and x = {b}: the section must be one piece"
            )));
        };
        if ground.last() != Some(&[a, ya]) {
            ground.push([a, ya]);
        }
        ground.push([b, yb]);
    }
    // Drop interior vertices on straight runs.
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(ground.len());
    for p in ground {
        if out.len() >= 2 {
            let (a, b) = (out[out.len() - 2], out[out.len() - 1]);
            let cross = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
            let scale = (p[0] - a[0]).abs() + (p[1] - a[1]).abs();
            if b[0] > a[0] && p[0] > b[0] && cross.abs() <= 1e-12 * scale * scale {
                out.pop();
            }
        }
        out.push(p);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x0: f64, y0: f64, s: f64, material: usize, gamma: f64) -> Region {
        Region {
            polygon: vec![[x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]],
            material,
            unit_weight: gamma,
        }
    }

    #[test]
    fn ground_of_a_step_and_column_weights() {
        // Two columns of unit squares: left two high, right one high.
        let regions = vec![
            square(0.0, 0.0, 1.0, 0, 10.0),
            square(0.0, 1.0, 1.0, 1, 20.0),
            square(1.0, 0.0, 1.0, 0, 10.0),
        ];
        let d = Domain::from_polygons(regions).unwrap();
        assert_eq!(
            d.ground(),
            &[[0.0, 2.0], [1.0, 2.0], [1.0, 1.0], [2.0, 1.0]]
        );
        assert_eq!(d.ground_y(1.0), Some(2.0));
        assert_eq!(d.ground_y(1.5), Some(1.0));
        let c = d.column(0.5, 0.5);
        assert!((c.weight - (0.5 * 10.0 + 20.0)).abs() < 1e-12);
        assert_eq!(c.region, Some(0));
        assert_eq!(d.column(0.5, 1.0).region, Some(1));
        assert_eq!(d.column(1.5, 1.5).region, None);
        assert_eq!(d.region_at(0.25, 1.75), Some(1));
    }

    #[test]
    fn polyline_y_takes_the_upper_value_at_a_step() {
        let l = [[0.0, 2.0], [1.0, 2.0], [1.0, 1.0], [2.0, 0.0]];
        assert_eq!(polyline_y(&l, 1.0), Some(2.0));
        assert_eq!(polyline_y(&l, 1.5), Some(0.5));
        assert_eq!(polyline_y(&l, 2.5), None);
        assert_eq!(polyline_y(&l, 0.0), Some(2.0));
    }
}
