//! Pore pressure and degree of saturation where a slice base lies, behind one
//! trait ([`PoreField`]): none ([`Dry`]), a piezometric line
//! ([`WaterTable`], the published benchmarks), or the mapped state itself
//! ([`Raster`]: the MPs' or the FEM nodes' values interpolated with the
//! project's kernel onto a regular raster once, then bilinear between its
//! nodes, so that a trial surface costs no neighbour search).
//!
//! Pressures are in Anura3D's sign: `pwp` < 0 is water in compression,
//! `pwp` > 0 is suction. No I/O.

use std::collections::VecDeque;

use super::SlopeError;
use super::geometry::{Domain, polyline_y};
use a3d_kernel::KernelKind;
use a3d_kernel::mapper::{self, MapSettings, NodeCloud, OutsidePolicy};

/// Pore pressure (kPa, Anura3D sign) and degree of saturation at a point.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct PoreSample {
    pub pwp: f64,
    pub saturation: f64,
}

/// Where the pore pressure comes from.
pub trait PoreField: Sync {
    fn sample(&self, x: f64, y: f64) -> PoreSample;
}

/// No pore water: pwp = 0 everywhere (S = 0).
#[derive(Clone, Copy, Debug, Default)]
pub struct Dry;

impl PoreField for Dry {
    fn sample(&self, _x: f64, _y: f64) -> PoreSample {
        PoreSample::default()
    }
}

/// A piezometric line: hydrostatic water pressure γw·(h(x) − y) below it,
/// none above it (S = 1 below, 0 above). Beyond the line's ends its end
/// elevations hold.
#[derive(Clone, Debug, PartialEq)]
pub struct WaterTable {
    pub line: Vec<[f64; 2]>,
    /// Unit weight of water (kN/m³, or the benchmark's own units).
    pub gamma_w: f64,
}

impl PoreField for WaterTable {
    fn sample(&self, x: f64, y: f64) -> PoreSample {
        let (first, last) = (self.line[0], self.line[self.line.len() - 1]);
        let h = polyline_y(&self.line, x.clamp(first[0], last[0])).unwrap_or(first[1]);
        if y < h {
            PoreSample {
                pwp: -self.gamma_w * (h - y),
                saturation: 1.0,
            }
        } else {
            PoreSample::default()
        }
    }
}

/// Scattered values to interpolate: positions (z = 0), Anura3D-signed pore
/// pressure, optionally the degree of saturation, and the material slot of
/// each point (the kernel does not smooth across materials).
pub struct Scattered<'a> {
    pub positions: &'a [[f64; 3]],
    pub pwp: &'a [f64],
    pub saturation: Option<&'a [f64]>,
    pub material: &'a [u32],
}

/// The pore field on a regular raster: values at the nodes from the kernel
/// mapper, bilinear in between.
#[derive(Clone, Debug)]
pub struct Raster {
    x0: f64,
    y0: f64,
    spacing: f64,
    nx: usize,
    ny: usize,
    pwp: Vec<f64>,
    saturation: Vec<f64>,
}

/// How [`Raster::from_scattered`] interpolates.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RasterSettings {
    pub kernel: KernelKind,
    /// Smoothing length h (m).
    pub h: f64,
    /// Raster spacing (m).
    pub spacing: f64,
}

impl Raster {
    /// Interpolates `points` at the raster nodes inside `domain` (each node
    /// takes the points of its region's material; a node whose material has
    /// no points gets pwp = 0), fills the nodes outside the domain from their
    /// nearest inside node, and keeps the saturation of `points` or, without
    /// it, `saturation_of(material slot, pwp)`.
    pub fn from_scattered(
        domain: &Domain,
        points: &Scattered<'_>,
        settings: &RasterSettings,
        saturation_of: &(dyn Fn(usize, f64) -> f64 + Sync),
    ) -> Result<Raster, SlopeError> {
        let n = points.positions.len();
        if points.pwp.len() != n
            || points.material.len() != n
            || points.saturation.is_some_and(|s| s.len() != n)
        {
            return Err(SlopeError::Field(
                "the scattered pore-pressure arrays differ in length".into(),
            ));
        }
        if !(settings.h > 0.0 && settings.h.is_finite()) {
            return Err(SlopeError::Field(format!(
                "the smoothing length must be positive, got {}",
                settings.h
            )));
        }
        let (xa, xb) = domain.x_range();
        let ya = domain.bottom();
        let yb = domain
            .ground()
            .iter()
            .map(|p| p[1])
            .fold(f64::NEG_INFINITY, f64::max);
        // At most about 600 × 600 nodes whatever the spacing asked for.
        let extent = (xb - xa).max(yb - ya);
        let spacing = settings.spacing.max(extent / 600.0);
        let nx = ((xb - xa) / spacing).ceil() as usize + 1;
        let ny = ((yb - ya) / spacing).ceil() as usize + 1;
        let mut node_material: Vec<Option<usize>> = Vec::with_capacity(nx * ny);
        let mut queries = Vec::new();
        let mut query_group = Vec::new();
        let mut query_node = Vec::new();
        let has_points = |m: usize| points.material.contains(&(m as u32));
        let mut with_points: Vec<Option<bool>> = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (x, y) = (xa + i as f64 * spacing, ya + j as f64 * spacing);
                // A node on the ground or the base still belongs to the section.
                let region = domain
                    .region_at(x, y)
                    .or_else(|| domain.region_at(x, y - 1e-9 * spacing))
                    .or_else(|| domain.region_at(x, y + 1e-9 * spacing));
                let material = region.map(|k| domain.regions()[k].material);
                if let Some(m) = material {
                    if with_points.len() <= m {
                        with_points.resize(m + 1, None);
                    }
                    let known = *with_points[m].get_or_insert_with(|| has_points(m));
                    if known {
                        queries.push([x, y, 0.0]);
                        query_group.push(m as u32);
                        query_node.push(node_material.len());
                    }
                }
                node_material.push(material);
            }
        }
        let mut pwp = vec![f64::NAN; nx * ny];
        let mut saturation = vec![f64::NAN; nx * ny];
        for (k, m) in node_material.iter().enumerate() {
            if let Some(m) = *m {
                pwp[k] = 0.0;
                saturation[k] = saturation_of(m, 0.0);
            }
        }
        if !queries.is_empty() {
            let n_fields = if points.saturation.is_some() { 2 } else { 1 };
            let mut values = Vec::with_capacity(n * n_fields);
            for i in 0..n {
                values.push(points.pwp[i]);
                if let Some(s) = points.saturation {
                    values.push(s[i]);
                }
            }
            let l = mapper::median_spacing(points.positions, 2).max(1e-12);
            let cloud = NodeCloud {
                positions: points.positions,
                dim: 2,
                values: &values,
                n_fields,
                group: Some(points.material),
                node_volume: l * l,
            };
            let map = MapSettings {
                kernel: settings.kernel,
                h: settings.h,
                min_shepard: 0.0,
                outside: OutsidePolicy::Nearest,
            };
            let result = mapper::map_points(&cloud, &queries, Some(&query_group), &map)
                .map_err(|e| SlopeError::Field(e.to_string()))?;
            for (q, &node) in query_node.iter().enumerate() {
                let p = result.values[q * n_fields];
                pwp[node] = p;
                saturation[node] = if n_fields == 2 {
                    result.values[q * n_fields + 1]
                } else {
                    saturation_of(query_group[q] as usize, p)
                };
            }
        }
        fill_from_nearest(&mut pwp, &mut saturation, nx, ny);
        Ok(Raster {
            x0: xa,
            y0: ya,
            spacing,
            nx,
            ny,
            pwp,
            saturation,
        })
    }

    /// The raster spacing actually used (m).
    pub fn spacing(&self) -> f64 {
        self.spacing
    }
}

/// Nodes without a value take their nearest valued node's (breadth first over
/// the 4-neighbours, in index order: deterministic).
fn fill_from_nearest(pwp: &mut [f64], saturation: &mut [f64], nx: usize, ny: usize) {
    let mut queue: VecDeque<usize> = (0..pwp.len()).filter(|&k| !pwp[k].is_nan()).collect();
    if queue.is_empty() {
        pwp.fill(0.0);
        saturation.fill(0.0);
        return;
    }
    while let Some(k) = queue.pop_front() {
        let (i, j) = (k % nx, k / nx);
        let mut visit = |m: usize| {
            if pwp[m].is_nan() {
                pwp[m] = pwp[k];
                saturation[m] = saturation[k];
                queue.push_back(m);
            }
        };
        if i > 0 {
            visit(k - 1);
        }
        if i + 1 < nx {
            visit(k + 1);
        }
        if j > 0 {
            visit(k - nx);
        }
        if j + 1 < ny {
            visit(k + nx);
        }
    }
}

impl PoreField for Raster {
    fn sample(&self, x: f64, y: f64) -> PoreSample {
        let fx = ((x - self.x0) / self.spacing).clamp(0.0, (self.nx - 1) as f64);
        let fy = ((y - self.y0) / self.spacing).clamp(0.0, (self.ny - 1) as f64);
        let i = (fx.floor() as usize).min(self.nx.saturating_sub(2));
        let j = (fy.floor() as usize).min(self.ny.saturating_sub(2));
        let (tx, ty) = (fx - i as f64, fy - j as f64);
        let at =
            |v: &[f64], i: usize, j: usize| v[(j.min(self.ny - 1)) * self.nx + i.min(self.nx - 1)];
        let bilinear = |v: &[f64]| {
            (1.0 - ty) * ((1.0 - tx) * at(v, i, j) + tx * at(v, i + 1, j))
                + ty * ((1.0 - tx) * at(v, i, j + 1) + tx * at(v, i + 1, j + 1))
        };
        PoreSample {
            pwp: bilinear(&self.pwp),
            saturation: bilinear(&self.saturation),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn water_table_is_hydrostatic_below_and_dry_above() {
        let wt = WaterTable {
            line: vec![[0.0, 2.0], [10.0, 4.0]],
            gamma_w: 10.0,
        };
        let s = wt.sample(5.0, 1.0);
        assert!((s.pwp + 20.0).abs() < 1e-12);
        assert_eq!(s.saturation, 1.0);
        assert_eq!(wt.sample(5.0, 3.5).pwp, 0.0);
        // Beyond the ends the end elevation holds.
        assert!((wt.sample(20.0, 0.0).pwp + 40.0).abs() < 1e-12);
    }
}
