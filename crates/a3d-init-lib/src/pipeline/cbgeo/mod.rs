//! A CB-Geo mpm model as a [`Project`]: its particles placed as CB-Geo places
//! them (`"file"` coordinates in file order; `"gauss"` points by
//! [`crate::element::cbgeo`]), each in its cell, with its material and
//! volume, and its materials and gravity in a3d-init's units, so that one
//! mapping serves Anura3D and CB-Geo. The writer is [`write::write_model`].
//!
//! What is translated, and how:
//! - particle ids: CB-Geo counts from 0 over all generators in order; the
//!   MP id is that + 1;
//! - volumes: CB-Geo's default, the cell's measure shared equally among the
//!   particles in it;
//! - materials: `density` (kg/m³), `porosity`, `youngs_modulus` and
//!   `cohesion` (Pa → kPa), `poisson_ratio`, `friction` and `dilation`
//!   (degrees), `tension_cutoff` (Pa → kPa). A single-phase material is dry
//!   (its `density` is the bulk density; stresses are total); the solid of a
//!   two-phase generator is a saturated, coupled material with the liquid's
//!   density.
//! - K0 (for `--stress geostatic`; CB-Geo has none): ν/(1 − ν) for an
//!   elastic material (the state its own gravity loading reaches under
//!   lateral restraint), Jaky's 1 − sin φ for Mohr–Coulomb;
//! - gravity: `external_loading_conditions.gravity`, which must point along
//!   −y (or be zero).

use std::path::Path;

use crate::element::cbgeo::{CbGeoCell, gauss_points};
use crate::formats::cbgeo::{self, CbGeoModel, Particles};
use crate::formats::gom::GomInfo;
use crate::formats::project::ProjectFiles;
use crate::model::{
    AnuraModel, ComputationMethod, Dimension, ElementType, Material, MaterialPoint, Mesh,
};
use crate::pipeline::{PipelineError, Project};

pub mod write;

/// A CB-Geo model behind a [`Project`]: the model as read, and the particles
/// (ids from 0) each of its generators made, in order.
#[derive(Clone, Debug)]
pub struct CbGeoTarget {
    pub model: CbGeoModel,
    pub generated: Vec<std::ops::Range<usize>>,
}

impl CbGeoTarget {
    /// Particles in all.
    pub fn particles(&self) -> usize {
        self.generated.last().map_or(0, |r| r.end)
    }

    /// Per particle, in order: whether its generator makes two-phase particles.
    pub fn two_phase(&self) -> Vec<bool> {
        let mut flags = Vec::with_capacity(self.particles());
        for (g, r) in self.model.generators.iter().zip(&self.generated) {
            flags.resize(r.end, g.two_phase());
        }
        flags
    }

    /// How many particles are two-phase.
    pub fn two_phase_particles(&self) -> usize {
        let two = self.model.generators.iter().map(|g| g.two_phase());
        two.zip(&self.generated)
            .filter(|(t, _)| *t)
            .map(|(_, r)| r.len())
            .sum()
    }
}

/// Loads the CB-Geo model of the run file `path` and places its particles.
pub fn load(path: &Path) -> Result<Project, PipelineError> {
    let cb = cbgeo::read(path)?;
    let (element_type, dimension) = match cb.cell {
        CbGeoCell::Quad4 => (ElementType::Quad4, Dimension::PlaneStrain),
        CbGeoCell::Tri3 => (ElementType::Tri3, Dimension::PlaneStrain),
        CbGeoCell::Hex8 => (ElementType::Hex8, Dimension::Cartesian3D),
    };
    if cb.gravity[0] != 0.0 || cb.gravity[1] > 0.0 || cb.gravity[2] != 0.0 {
        return Err(PipelineError::Input(format!(
            "{}: gravity ({:?}, {:?}, {:?}) m/s²: a3d-init's stresses take gravity along −y (y up, in 3D too, as Anura3D); a model with z up has to be turned",
            path.display(),
            cb.gravity[0],
            cb.gravity[1],
            cb.gravity[2]
        )));
    }
    let materials = materials(&cb);
    let mesh = Mesh {
        dimension,
        element_type,
        nodes: cb.mesh.nodes.clone(),
        connectivity: cb.mesh.cells.iter().flatten().copied().collect(),
    };
    let (points, generated) = particles(&cb, &mesh)?;
    let n_cells = cb.mesh.cells.len();
    let mut element_material = vec![0u32; n_cells];
    let mut counts = vec![(0u32, 0u32); n_cells];
    for p in &points {
        let e = p.element as usize;
        element_material[e] = p.material;
        counts[e].0 += 1;
    }
    let name = path
        .file_stem()
        .map_or_else(|| "mpm".into(), |s| s.to_string_lossy().into_owned());
    let mut files = ProjectFiles {
        name,
        dir: cb.dir.clone(),
        gom: path.to_path_buf(),
        cps: None,
        cps_version: None,
        opd: None,
        stage: None,
        notes: vec![format!(
            "CB-Geo model for {}: {}",
            cb.branch.name(),
            cb.branch_because
        )],
        warnings: Vec::new(),
    };
    let (solid_fixity, liquid_fixity, fixity_warnings) = fixities(&cb);
    files.warnings.extend(fixity_warnings);
    let model = AnuraModel {
        solid_fixity,
        liquid_fixity,
        mesh,
        materials,
        element_material,
        mp_counts: counts,
        damping: None,
    };
    Ok(Project {
        files,
        gom_version: String::new(),
        cps: None,
        model,
        info: GomInfo::default(),
        method: ComputationMethod::MpmMp,
        points,
        cbgeo: Some(Box::new(CbGeoTarget {
            model: cb,
            generated,
        })),
    })
}

/// The state CB-Geo will hold at t = 0 for the project `target` (what `verify`
/// and `fos` start from): the stresses file and pore-pressure file its run
/// file names, read as CB-Geo reads them, back in a3d-init's units and signs
/// (kPa; for a two-phase particle the total σ′ − p·I and pwp = −p). A run
/// file that names no stresses file starts from zero stress, as CB-Geo does.
pub fn held_state(target: &CbGeoTarget) -> Result<Vec<crate::model::MpState>, PipelineError> {
    use crate::formats::cbgeo::text;
    use crate::model::MpState;
    let m = &target.model;
    let n = target.particles();
    let mut states = vec![
        MpState {
            saturation: 1.0,
            ..MpState::default()
        };
        n
    ];
    if let Some(name) = m.stresses_file() {
        let path = m.dir.join(name);
        let t = crate::formats::input::read_text(&path)?;
        let stresses = text::read_stresses(&path, &t).map_err(crate::formats::FormatError::from)?;
        if stresses.len() != n {
            return Err(PipelineError::Input(format!(
                "{}: {} stress lines for {n} particles: CB-Geo would set no stress at all",
                path.display(),
                stresses.len()
            )));
        }
        for (s, v) in states.iter_mut().zip(&stresses) {
            s.total = v.map(|x| x / 1000.0);
        }
    }
    if let Some(name) = m.pore_pressures_file.as_deref().filter(|_| m.two_phase()) {
        let path = m.dir.join(name);
        let t = crate::formats::input::read_text(&path)?;
        let values = text::read_id_values(&path, &t).map_err(crate::formats::FormatError::from)?;
        for (id, p) in values {
            let Some(s) = states.get_mut(id as usize) else {
                return Err(PipelineError::Input(format!(
                    "{}: particle {id}: the model has {n} particles (ids 0 to {})",
                    path.display(),
                    n.saturating_sub(1)
                )));
            };
            s.pwp = -p / 1000.0;
        }
    }
    for (s, two) in states.iter_mut().zip(target.two_phase()) {
        if two {
            for c in s.total.iter_mut().take(3) {
                *c += s.pwp;
            }
        } else {
            s.pwp = 0.0;
        }
    }
    Ok(states)
}

/// The run file in folder `dir` (`mpm.json`), when the folder is a CB-Geo
/// project rather than an Anura3D one (it holds no GOM).
pub fn run_file_in(dir: &Path) -> Option<std::path::PathBuf> {
    let json = dir.join("mpm.json");
    let gom = std::fs::read_dir(dir).ok()?.flatten().any(|e| {
        let name = e.file_name().to_string_lossy().to_ascii_uppercase();
        name.contains(".GOM") || name.ends_with("-2.DAT")
    });
    (json.is_file() && !gom).then_some(json)
}

/// Per node, the fixed directions of the solid and of the liquid: the
/// velocity constraints of zero velocity (direction d < Tdim the solid's,
/// Tdim ≤ d < 2·Tdim the fork's liquid), node set −1 every node; and a
/// warning for each constraint of non-zero velocity, which the built-in
/// runner does not prescribe.
fn fixities(cb: &CbGeoModel) -> (Vec<[bool; 3]>, Vec<[bool; 3]>, Vec<String>) {
    let n = cb.mesh.nodes.len();
    let dim = cb.n_dim();
    let (mut solid, mut liquid) = (vec![[false; 3]; n], vec![[false; 3]; n]);
    let mut warnings = Vec::new();
    for &(set, dir, velocity) in &cb.velocity_constraints {
        if velocity != 0.0 {
            warnings.push(format!(
                "velocity constraint {velocity} m/s on node set {set}, direction {dir}: the built-in runner (verify, fos) does not prescribe velocities and leaves these nodes free"
            ));
            continue;
        }
        let nodes: Vec<usize> = if set == -1 {
            (0..n).collect()
        } else {
            cb.node_sets
                .iter()
                .find(|(id, _)| *id == set)
                .map(|(_, s)| s.iter().map(|&k| k as usize).collect())
                .unwrap_or_default()
        };
        let (phase, k) = (dir as usize / dim, dir as usize % dim);
        let target = if phase == 0 { &mut solid } else { &mut liquid };
        for node in nodes {
            target[node][k] = true;
        }
    }
    (solid, liquid, warnings)
}

/// The model's materials in a3d-init's terms, in run-file order (index =
/// position + 1).
fn materials(cb: &CbGeoModel) -> Vec<Material> {
    cb.materials
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let two_phase_solid = cb
                .generators
                .iter()
                .find(|g| g.two_phase() && g.material_ids.first() == Some(&m.id));
            let kind = if two_phase_solid.is_some() {
                "saturated_material_coupled"
            } else {
                "dry_material"
            };
            let name = m
                .name
                .clone()
                .unwrap_or_else(|| format!("material {}", m.id));
            let mut mat = Material::new(i as u32 + 1, name, kind);
            let kpa = |v: f64| v / 1000.0;
            mat.model = Some(
                if m.kind.starts_with("LinearElastic") {
                    "linear_elasticity"
                } else if m.kind.starts_with("MohrCoulomb") {
                    "mohr_coulomb"
                } else {
                    m.kind.as_str()
                }
                .to_string(),
            );
            mat.density_solid = m.number("density");
            mat.porosity = if two_phase_solid.is_some() {
                m.number("porosity")
            } else {
                None
            };
            mat.density_liquid = two_phase_solid
                .and_then(|g| g.material_ids.get(1))
                .and_then(|id| cb.material(*id))
                .and_then(|w| w.number("density"));
            mat.young_modulus = m.number("youngs_modulus").map(kpa);
            mat.poisson_ratio = m.number("poisson_ratio");
            mat.friction_angle = m.number("friction");
            mat.dilatancy_angle = m.number("dilation");
            mat.cohesion = m.number("cohesion").map(kpa);
            mat.tensile_strength = m.number("tension_cutoff").map(kpa);
            // CB-Geo holds no K0: the at-rest value its own gravity loading
            // gives under lateral restraint (ν/(1 − ν), elastic), or Jaky's
            // 1 − sin φ for a frictional material.
            mat.k0 = match (mat.friction_angle, mat.poisson_ratio) {
                (Some(phi), _) if mat.model.as_deref() == Some("mohr_coulomb") => {
                    Some(1.0 - phi.to_radians().sin())
                }
                (_, Some(nu)) if nu < 1.0 => Some(nu / (1.0 - nu)),
                _ => None,
            };
            mat.properties = m
                .numbers
                .iter()
                .map(|(k, v)| (k.clone(), v.to_string()))
                .collect();
            mat
        })
        .collect()
}

/// Every particle in CB-Geo's order (its cell, material and volume), and
/// the particles each generator made.
fn particles(
    cb: &CbGeoModel,
    mesh: &Mesh,
) -> Result<(Vec<MaterialPoint>, Vec<std::ops::Range<usize>>), PipelineError> {
    let index_of = |id: u32| {
        cb.materials
            .iter()
            .position(|m| m.id == id)
            .map_or(0, |i| i as u32 + 1)
    };
    let corners = |c: usize| -> Vec<[f64; 3]> {
        cb.mesh.cells[c]
            .iter()
            .map(|&n| cb.mesh.nodes[n as usize])
            .collect()
    };
    let locator = Locator::new(mesh);
    let mut points: Vec<MaterialPoint> = Vec::new();
    let mut generated = Vec::new();
    for g in &cb.generators {
        let first = points.len();
        let material = index_of(g.material_ids[0]);
        match &g.particles {
            Particles::Gauss { per_dir, cset_id } => {
                let cells: Vec<usize> = if *cset_id == -1 {
                    (0..cb.mesh.cells.len()).collect()
                } else {
                    cb.cell_sets
                        .iter()
                        .find(|(id, _)| id == cset_id)
                        .map(|(_, s)| s.iter().map(|&c| c as usize).collect())
                        .unwrap_or_default()
                };
                for c in cells {
                    for (k, x) in gauss_points(cb.cell, *per_dir, &corners(c))
                        .into_iter()
                        .enumerate()
                    {
                        points.push(MaterialPoint {
                            id: points.len() as u32 + 1,
                            element: c as u32,
                            material,
                            local: k as u32 + 1,
                            position: x,
                            volume: 0.0,
                        });
                    }
                }
            }
            Particles::File {
                path,
                coordinates,
                lines,
            } => {
                for (i, x) in coordinates.iter().enumerate() {
                    let c = locator.find(mesh, *x).ok_or_else(|| {
                        PipelineError::Positioned(format!(
                            "{}:{}:1: particle {i} at ({:?}, {:?}) lies in no cell of the mesh: CB-Geo drops it, and the stresses file would no longer match its particles",
                            path.display(),
                            lines[i],
                            x[0],
                            x[1]
                        ))
                    })?;
                    points.push(MaterialPoint {
                        id: points.len() as u32 + 1,
                        element: c as u32,
                        material,
                        local: 0,
                        position: *x,
                        volume: 0.0,
                    });
                }
            }
        }
        generated.push(first..points.len());
    }
    if points.len() > u32::MAX as usize - 1 {
        return Err(PipelineError::Input(
            "more particles than a3d-init numbers".into(),
        ));
    }
    // CB-Geo's default volume: the cell's measure over its particle count.
    let mut per_cell = vec![0u32; cb.mesh.cells.len()];
    for p in &points {
        per_cell[p.element as usize] += 1;
    }
    let element = crate::element::mesh_element(mesh.element_type);
    let share: Vec<f64> = (0..per_cell.len())
        .map(|c| element.measure(mesh, c).abs() / f64::from(per_cell[c].max(1)))
        .collect();
    let mut local = vec![0u32; cb.mesh.cells.len()];
    for p in &mut points {
        let c = p.element as usize;
        p.volume = share[c];
        if p.local == 0 {
            local[c] += 1;
            p.local = local[c];
        }
    }
    Ok((points, generated))
}

/// Finding the cell that holds a point: a uniform grid of the cells'
/// bounding boxes (x, y and, in 3D, z), then the element's own containment
/// test.
struct Locator {
    lo: [f64; 3],
    size: f64,
    dims: [usize; 3],
    buckets: Vec<Vec<u32>>,
}

impl Locator {
    /// The grid over `mesh`: about one bucket per cell, at most 4 per cell
    /// (and never more than 2²⁴); a mesh whose cells overlap so that the
    /// buckets would hold more than 64 entries per cell (a crafted or broken
    /// mesh) gets one bucket, searched cell by cell.
    fn new(mesh: &Mesh) -> Locator {
        let (lo, hi) = mesh.bounding_box();
        let dim = mesh.dimension.n_dim();
        let n = mesh.n_elements().max(1);
        let span: [f64; 3] = std::array::from_fn(|k| if k < dim { hi[k] - lo[k] } else { 0.0 });
        let content = span[..dim].iter().product::<f64>().max(f64::MIN_POSITIVE);
        let size = (content / n as f64).powf(1.0 / dim as f64).max(1e-12);
        let most = (4 * n).min(1 << 24) as f64;
        // In f64 first: a huge span or a NaN never overflows the counts.
        let side = |w: f64| (w / size).min(most).max(0.0) as usize + 1;
        let mut dims = span.map(side);
        while (dims[0] * dims[1] * dims[2]) as f64 > most.max(1.0) {
            dims = dims.map(|d| d.div_ceil(2));
        }
        let size = (0..3)
            .map(|k| span[k] / dims[k] as f64)
            .fold(1e-12, f64::max);
        let one_bucket = || Locator {
            lo,
            size: f64::INFINITY,
            dims: [1, 1, 1],
            buckets: vec![(0..mesh.n_elements() as u32).collect()],
        };
        if !size.is_finite() {
            return one_bucket();
        }
        let mut buckets = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        let mut entries = 0usize;
        for e in 0..mesh.n_elements() {
            let (mut a, mut b) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for &node in mesh.element_nodes(e) {
                for k in 0..3 {
                    a[k] = a[k].min(mesh.nodes[node as usize][k]);
                    b[k] = b[k].max(mesh.nodes[node as usize][k]);
                }
            }
            let cell = |v: f64, k: usize| {
                (((v - lo[k]) / size).floor().max(0.0) as usize).min(dims[k] - 1)
            };
            let (from, to): ([usize; 3], [usize; 3]) = (
                std::array::from_fn(|k| cell(a[k], k)),
                std::array::from_fn(|k| cell(b[k], k)),
            );
            entries += (0..3).map(|k| to[k] - from[k] + 1).product::<usize>();
            if entries > 64 * n + 1024 {
                return one_bucket();
            }
            for i in from[0]..=to[0] {
                for j in from[1]..=to[1] {
                    for l in from[2]..=to[2] {
                        buckets[(l * dims[1] + j) * dims[0] + i].push(e as u32);
                    }
                }
            }
        }
        Locator {
            lo,
            size,
            dims,
            buckets,
        }
    }

    /// The first cell (mesh order) that holds `x`, on its boundary included.
    fn find(&self, mesh: &Mesh, x: [f64; 3]) -> Option<usize> {
        let at = |k: usize| {
            if self.dims[k] == 1 {
                return Some(0);
            }
            let v = ((x[k] - self.lo[k]) / self.size).floor();
            (v >= -1.0 && v <= self.dims[k] as f64)
                .then(|| (v.max(0.0) as usize).min(self.dims[k] - 1))
        };
        let (i, j, l) = (at(0)?, at(1)?, at(2)?);
        let element = crate::element::mesh_element(mesh.element_type);
        self.buckets[(l * self.dims[1] + j) * self.dims[0] + i]
            .iter()
            .map(|&e| e as usize)
            .filter(|&e| element.contains(mesh, e, x, 1e-9))
            .min()
    }
}
