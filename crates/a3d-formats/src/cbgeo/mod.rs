//! A CB-Geo mpm model (cb-geo/mpm and its two-phase fork geomechanics/mpm),
//! read as CB-Geo reads it: the run file `mpm.json` ([`json`]), the mesh, the
//! particle generators (`"file"` coordinates; `"gauss"` cells, placed by
//! [`a3d_element::cbgeo`]), the cell sets of `entity_sets`, the materials and
//! gravity, and which branch the file is written for ([`Branch`]).
//! Spec pages: `formats/cbgeo-mpm-json.md`, `formats/cbgeo-mesh.md`,
//! `formats/cbgeo-particles.md`, `formats/cbgeo-particle-stresses.md`,
//! `formats/cbgeo-pore-pressures.md`.
//!
//! Units are CB-Geo's (SI: m, Pa, kg/m³, m/s²) and signs its own (tension
//! positive; pore pressure positive in compression). The mapping converts
//! where it meets them.

use std::path::{Path, PathBuf};

use a3d_element::cbgeo::CbGeoCell;
use jsonc_parser::ast::{Object, Value};
use jsonc_parser::common::Ranged;

use crate::error::{FormatError, ParseError};
use crate::input::read_text;

pub mod json;
pub mod text;
pub mod write;

/// Which CB-Geo a run file is for: the two read the initial-stress key in
/// different forms, and each ignores the other's with a warning and exit 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Branch {
    /// cb-geo/mpm `develop`: `"particles_stresses": "file.txt"`; single phase.
    Develop,
    /// geomechanics/mpm: `"particles_stresses": {"type": "file", "location": …}`;
    /// single and two-phase, `"particles_pore_pressures"`.
    Fork,
}

impl Branch {
    /// The repository, for messages and the report.
    pub fn name(self) -> &'static str {
        match self {
            Branch::Develop => "cb-geo/mpm (develop)",
            Branch::Fork => "geomechanics/mpm (the two-phase fork)",
        }
    }
}

/// How a generator makes its particles.
#[derive(Clone, Debug, PartialEq)]
pub enum Particles {
    /// `"type": "file"`: the coordinates, in file order.
    File {
        path: PathBuf,
        coordinates: Vec<[f64; 3]>,
        /// Each particle's 1-based line in the file.
        lines: Vec<usize>,
    },
    /// `"type": "gauss"`: `per_dir` points per direction in each cell of the
    /// cell set (`-1`: every cell).
    Gauss { per_dir: u32, cset_id: i64 },
}

/// One entry of `particles[]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Generator {
    pub particles: Particles,
    /// `material_id`: the solid's, then (two-phase) the liquid's.
    pub material_ids: Vec<u32>,
    pub particle_type: String,
    pub pset_id: Option<i64>,
}

impl Generator {
    /// Two-phase particles (`P2D2PHASE`, `P3D2PHASE`).
    pub fn two_phase(&self) -> bool {
        self.particle_type.contains("2PHASE")
    }
}

/// One entry of `materials[]`: its id, type, name and every number.
#[derive(Clone, Debug, PartialEq)]
pub struct CbMaterial {
    pub id: u32,
    pub kind: String,
    pub name: Option<String>,
    /// Every numeric member in file order (SI units, as written).
    pub numbers: Vec<(String, f64)>,
}

impl CbMaterial {
    /// The number `name`, when given.
    pub fn number(&self, name: &str) -> Option<f64> {
        self.numbers
            .iter()
            .find(|(k, _)| k == name)
            .map(|&(_, v)| v)
    }

    /// A liquid (`Newtonian*`, `Bingham*`): the second material of a
    /// two-phase generator.
    pub fn is_fluid(&self) -> bool {
        self.kind.starts_with("Newtonian") || self.kind.starts_with("Bingham")
    }
}

/// How the run file names the initial stresses (`mesh.particles_stresses`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub enum StressKey {
    Absent,
    /// develop's form: the file name.
    Name(String),
    /// the fork's form: an object with a `"type"` (and, for `"file"`, a
    /// `"location"`).
    Object {
        kind: String,
        location: Option<String>,
    },
}

/// A CB-Geo model as CB-Geo will run it.
#[derive(Clone, Debug)]
pub struct CbGeoModel {
    /// The run file and its folder (CB-Geo's working directory).
    pub json_path: PathBuf,
    pub dir: PathBuf,
    /// The run file's bytes, kept for the lossless edit.
    pub json_text: String,
    pub title: Option<String>,
    pub cell: CbGeoCell,
    pub mesh_path: PathBuf,
    pub mesh: text::MeshText,
    /// `entity_sets`' cell sets: (id, cell indices) in file order.
    pub cell_sets: Vec<(i64, Vec<u64>)>,
    /// `entity_sets`' node sets: (id, node indices) in file order.
    pub node_sets: Vec<(i64, Vec<u64>)>,
    /// `mesh.boundary_conditions.velocity_constraints`: (node set, direction,
    /// velocity m/s); the direction counts `Tdim` per phase (the fork's
    /// liquid: `dir − Tdim`), node set −1 is every node.
    pub velocity_constraints: Vec<(i64, u32, f64)>,
    pub entity_sets_path: Option<PathBuf>,
    pub generators: Vec<Generator>,
    pub materials: Vec<CbMaterial>,
    /// `external_loading_conditions.gravity` (m/s²; zeros when absent).
    pub gravity: [f64; 3],
    pub analysis_type: String,
    pub stresses_key: StressKey,
    pub has_pore_pressures_key: bool,
    /// The `"location"` of a `"file"` pore-pressure key.
    pub pore_pressures_file: Option<String>,
    pub branch: Branch,
    /// Why [`CbGeoModel::branch`] was chosen, as a sentence.
    pub branch_because: String,
    /// Every file the run file names that exists beside it, in the order
    /// they appear.
    pub referenced: Vec<Referenced>,
}

impl CbGeoModel {
    /// The stresses file the run file names (either form), if any.
    pub fn stresses_file(&self) -> Option<&str> {
        match &self.stresses_key {
            StressKey::Name(n) => Some(n),
            StressKey::Object { kind, location } if kind == "file" => location.as_deref(),
            _ => None,
        }
    }

    /// 2 or 3.
    pub fn n_dim(&self) -> usize {
        self.cell.n_dim()
    }

    /// True when any generator makes two-phase particles (or the analysis is
    /// a two-phase one).
    pub fn two_phase(&self) -> bool {
        self.generators.iter().any(Generator::two_phase) || self.analysis_type.contains("TwoPhase")
    }

    /// The material with CB-Geo id `id`.
    pub fn material(&self, id: u32) -> Option<&CbMaterial> {
        self.materials.iter().find(|m| m.id == id)
    }
}

/// True when `path` names a CB-Geo run file (`.json`).
pub fn is_run_file(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
}

/// Reads a CB-Geo model from its run file.
pub fn read(json_path: &Path) -> Result<CbGeoModel, FormatError> {
    let text = read_text(json_path)?;
    let root = json::parse(json_path, &text)?;
    let r = json::Reader {
        path: json_path,
        text: &text,
    };
    let dir = json_path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    let mesh_obj = r.object(&root, "mesh", "the run file")?;
    let cell_name = r.required_string(mesh_obj, "cell_type", "\"mesh\"")?;
    let cell = CbGeoCell::from_name(&cell_name).ok_or_else(|| {
        r.error(
            mesh_obj.get("cell_type").map_or(0, |p| p.value.start()),
            format!("cell type `{cell_name}`: a3d-init places particles in ED2T3, ED2Q4 and ED3H8 cells only"),
        )
    })?;
    let dim = cell.n_dim();
    let file_in = |name: &str, at: usize| -> Result<PathBuf, ParseError> {
        if name.is_empty() {
            return Err(r.error(at, "an empty file name"));
        }
        Ok(dir.join(name))
    };
    let mesh_name = r.required_string(mesh_obj, "mesh", "\"mesh\"")?;
    let mesh_path = file_in(&mesh_name, mesh_obj.range.start)?;
    let mesh_text = read_text(&mesh_path)?;
    let mesh = text::read_mesh(&mesh_path, &mesh_text, dim, cell.n_nodes())?;
    let (cell_sets, node_sets, entity_sets_path) = match r.string(mesh_obj, "entity_sets")? {
        Some(name) => {
            let path = file_in(&name, mesh_obj.range.start)?;
            let cells = read_sets(&path, "cell_sets", mesh.cells.len())?;
            let nodes = read_sets(&path, "node_sets", mesh.nodes.len())?;
            (cells, nodes, Some(path))
        }
        None => (Vec::new(), Vec::new(), None),
    };
    let velocity_constraints = velocity_constraints(&r, mesh_obj, dim, &node_sets)?;
    let materials = read_materials(&r, &root)?;
    let generators = read_generators(&r, &root, &dir, dim, &materials, &cell_sets)?;
    let gravity = gravity(&r, &root, dim)?;
    let analysis_type = match root.get("analysis") {
        Some(p) => match &p.value {
            Value::Object(o) => r.string(o, "type")?.unwrap_or_default(),
            v => return Err(r.error(v.start(), "\"analysis\" must be an object").into()),
        },
        None => String::new(),
    };
    let stresses_key = match mesh_obj.get("particles_stresses").map(|p| &p.value) {
        None => StressKey::Absent,
        Some(Value::StringLit(s)) => StressKey::Name(s.value.to_string()),
        Some(Value::Object(o)) => StressKey::Object {
            kind: r.string(o, "type")?.unwrap_or_default(),
            location: r.string(o, "location")?,
        },
        Some(v) => {
            return Err(r
                .error(
                    v.start(),
                    "\"particles_stresses\" must be a file name or an object",
                )
                .into());
        }
    };
    let has_pore_pressures_key = mesh_obj.get("particles_pore_pressures").is_some();
    let pore_pressures_file = match mesh_obj.get("particles_pore_pressures").map(|p| &p.value) {
        Some(Value::Object(o)) if r.string(o, "type")?.as_deref() == Some("file") => {
            r.string(o, "location")?
        }
        _ => None,
    };
    let mut model = CbGeoModel {
        json_path: json_path.to_path_buf(),
        dir,
        title: r.string(&root, "title")?,
        cell,
        mesh_path,
        mesh,
        cell_sets,
        node_sets,
        velocity_constraints,
        entity_sets_path,
        generators,
        materials,
        gravity,
        analysis_type,
        stresses_key,
        has_pore_pressures_key,
        pore_pressures_file,
        branch: Branch::Develop,
        branch_because: String::new(),
        referenced: Vec::new(),
        json_text: String::new(),
    };
    (model.branch, model.branch_because) = branch_of(&model);
    model.referenced = referenced_files(&root, &model.dir);
    model.json_text = text;
    Ok(model)
}

/// Which branch the run file is for, and why.
fn branch_of(m: &CbGeoModel) -> (Branch, String) {
    match &m.stresses_key {
        StressKey::Name(_) => (
            Branch::Develop,
            "\"particles_stresses\" is a file name, the form cb-geo/mpm develop reads".into(),
        ),
        StressKey::Object { .. } => (
            Branch::Fork,
            "\"particles_stresses\" is an object, the form geomechanics/mpm reads".into(),
        ),
        StressKey::Absent if m.two_phase() => (
            Branch::Fork,
            "two-phase particles run only in geomechanics/mpm".into(),
        ),
        StressKey::Absent if m.has_pore_pressures_key => (
            Branch::Fork,
            "\"particles_pore_pressures\" is read only by geomechanics/mpm".into(),
        ),
        StressKey::Absent => (
            Branch::Develop,
            "a single-phase run file without \"particles_stresses\": written in cb-geo/mpm develop's form (give the key in the fork's object form to target the fork)".into(),
        ),
    }
}

fn read_materials(r: &json::Reader<'_>, root: &Object<'_>) -> Result<Vec<CbMaterial>, ParseError> {
    let Some(list) = r.array(root, "materials")? else {
        return Err(r.error(root.range.start, "the run file has no \"materials\""));
    };
    let mut out: Vec<CbMaterial> = Vec::new();
    for v in &list.elements {
        let Value::Object(o) = v else {
            return Err(r.error(v.start(), "a material must be an object"));
        };
        let id = r
            .uint(o, "id")?
            .ok_or_else(|| r.error(o.range.start, "a material has no \"id\""))?;
        if out.iter().any(|m| m.id == id) {
            return Err(r.error(o.range.start, format!("material id {id} again")));
        }
        let kind = r.required_string(o, "type", &format!("material {id}"))?;
        let mut numbers = Vec::new();
        for p in &o.properties {
            if let Value::NumberLit(_) = &p.value {
                let name = p.name.clone().into_string();
                numbers.push((
                    name.clone(),
                    r.number_value(&p.value, &format!("\"{name}\""))?,
                ));
            }
        }
        out.push(CbMaterial {
            id,
            kind,
            name: r.string(o, "name")?,
            numbers,
        });
    }
    Ok(out)
}

fn read_generators(
    r: &json::Reader<'_>,
    root: &Object<'_>,
    dir: &Path,
    dim: usize,
    materials: &[CbMaterial],
    cell_sets: &[(i64, Vec<u64>)],
) -> Result<Vec<Generator>, FormatError> {
    let Some(list) = r.array(root, "particles")? else {
        return Err(r
            .error(root.range.start, "the run file has no \"particles\"")
            .into());
    };
    let mut out = Vec::new();
    for v in &list.elements {
        let Value::Object(entry) = v else {
            return Err(r
                .error(v.start(), "a \"particles\" entry must be an object")
                .into());
        };
        let g = r.object(entry, "generator", "a \"particles\" entry")?;
        let kind = r.required_string(g, "type", "a generator")?;
        let material_ids: Vec<u32> = match g.get("material_id").map(|p| &p.value) {
            None => {
                return Err(r
                    .error(g.range.start, "a generator has no \"material_id\"")
                    .into());
            }
            Some(Value::Array(a)) => a
                .elements
                .iter()
                .map(|v| {
                    let id = r.int_value(v, "\"material_id\"")?;
                    u32::try_from(id).map_err(|_| r.error(v.start(), "\"material_id\" must be ≥ 0"))
                })
                .collect::<Result<_, _>>()?,
            Some(v) => {
                let id = r.int_value(v, "\"material_id\"")?;
                vec![
                    u32::try_from(id)
                        .map_err(|_| r.error(v.start(), "\"material_id\" must be ≥ 0"))?,
                ]
            }
        };
        let at = g
            .get("material_id")
            .map_or(g.range.start, |p| p.value.start());
        if material_ids.is_empty() {
            return Err(r.error(at, "\"material_id\" names no material").into());
        }
        for id in &material_ids {
            if !materials.iter().any(|m| m.id == *id) {
                return Err(r
                    .error(at, format!("\"material_id\" {id}: no material has this id"))
                    .into());
            }
        }
        let particle_type = r.string(g, "particle_type")?.unwrap_or_default();
        let particles = match kind.as_str() {
            "file" => {
                let name = r.required_string(g, "location", "a \"file\" generator")?;
                let path = dir.join(&name);
                let text = read_text(&path)?;
                let (coordinates, lines) = text::read_particles_with_lines(&path, &text, dim)?;
                Particles::File {
                    path,
                    coordinates,
                    lines,
                }
            }
            "gauss" => {
                let per_dir = r.uint(g, "nparticles_per_dir")?.ok_or_else(|| {
                    r.error(
                        g.range.start,
                        "a \"gauss\" generator has no \"nparticles_per_dir\"",
                    )
                })?;
                let cset_id = r.int(g, "cset_id")?.unwrap_or(-1);
                if cset_id != -1 && !cell_sets.iter().any(|(id, _)| *id == cset_id) {
                    let at = g.get("cset_id").map_or(g.range.start, |p| p.value.start());
                    return Err(r
                        .error(
                            at,
                            format!("\"cset_id\" {cset_id}: the entity sets have no such cell set"),
                        )
                        .into());
                }
                Particles::Gauss { per_dir, cset_id }
            }
            other => {
                return Err(r
                    .error(
                        g.get("type").map_or(g.range.start, |p| p.value.start()),
                        format!("generator type `{other}`: a3d-init reads \"file\" and \"gauss\" generators"),
                    )
                    .into());
            }
        };
        out.push(Generator {
            particles,
            material_ids,
            particle_type,
            pset_id: r.int(g, "pset_id")?,
        });
    }
    if out.is_empty() {
        return Err(r
            .error(root.range.start, "\"particles\" has no generator")
            .into());
    }
    Ok(out)
}

fn gravity(r: &json::Reader<'_>, root: &Object<'_>, dim: usize) -> Result<[f64; 3], ParseError> {
    let mut g = [0.0; 3];
    let Some(p) = root.get("external_loading_conditions") else {
        return Ok(g);
    };
    let Value::Object(o) = &p.value else {
        return Err(r.error(
            p.value.start(),
            "\"external_loading_conditions\" must be an object",
        ));
    };
    if let Some(v) = r.numbers(o, "gravity")? {
        if v.len() != dim {
            let at = o.get("gravity").map_or(o.range.start, |p| p.value.start());
            return Err(r.error(
                at,
                format!("\"gravity\" has {} components; the mesh is {dim}D", v.len()),
            ));
        }
        g[..dim].copy_from_slice(&v);
    }
    Ok(g)
}

/// `mesh.boundary_conditions.velocity_constraints`: `[{"nset_id": k, "dir":
/// d, "velocity": v}, …]`, each set known (or −1) and each direction below
/// `Tdim` × 2 phases.
fn velocity_constraints(
    r: &json::Reader<'_>,
    mesh: &Object<'_>,
    dim: usize,
    node_sets: &[(i64, Vec<u64>)],
) -> Result<Vec<(i64, u32, f64)>, ParseError> {
    let Some(bc) = mesh.get("boundary_conditions") else {
        return Ok(Vec::new());
    };
    let Value::Object(bc) = &bc.value else {
        return Err(r.error(
            bc.value.start(),
            "\"boundary_conditions\" must be an object",
        ));
    };
    let Some(list) = r.array(bc, "velocity_constraints")? else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    for v in &list.elements {
        let Value::Object(o) = v else {
            return Err(r.error(v.start(), "a velocity constraint must be an object"));
        };
        let set = r
            .int(o, "nset_id")?
            .ok_or_else(|| r.error(o.range.start, "a velocity constraint has no \"nset_id\""))?;
        if set != -1 && !node_sets.iter().any(|(id, _)| *id == set) {
            return Err(r.error(
                o.range.start,
                format!("\"nset_id\" {set}: the entity sets have no such node set"),
            ));
        }
        let dir = r
            .uint(o, "dir")?
            .ok_or_else(|| r.error(o.range.start, "a velocity constraint has no \"dir\""))?;
        if dir as usize >= 2 * dim {
            return Err(r.error(
                o.range.start,
                format!(
                    "\"dir\" {dir}: directions run from 0 to {} ({dim} per phase)",
                    2 * dim - 1
                ),
            ));
        }
        let velocity = r.number(o, "velocity")?.unwrap_or(0.0);
        out.push((set, dir, velocity));
    }
    Ok(out)
}

/// One kind of set of `entity_sets.json` (`"cell_sets"`, `"node_sets"`):
/// `[{"id": k, "set": [indices…]}, …]`, each index below `n`.
fn read_sets(path: &Path, kind: &str, n: usize) -> Result<Vec<(i64, Vec<u64>)>, FormatError> {
    let text = read_text(path)?;
    let root = json::parse(path, &text)?;
    let r = json::Reader { path, text: &text };
    let mut out = Vec::new();
    let Some(list) = r.array(&root, kind)? else {
        return Ok(out);
    };
    let what = if kind == "cell_sets" { "cell" } else { "node" };
    for v in &list.elements {
        let Value::Object(o) = v else {
            return Err(r
                .error(v.start(), format!("a {what} set must be an object"))
                .into());
        };
        let id = r
            .int(o, "id")?
            .ok_or_else(|| r.error(o.range.start, format!("a {what} set has no \"id\"")))?;
        let set = r
            .array(o, "set")?
            .ok_or_else(|| r.error(o.range.start, format!("{what} set {id} has no \"set\"")))?;
        let mut members = Vec::with_capacity(set.elements.len());
        for c in &set.elements {
            let k = r.int_value(c, &format!("a {what} index"))?;
            if k < 0 || k as usize >= n {
                let last = n.saturating_sub(1);
                let message =
                    format!("{what} set {id}: {what} {k} is not in the mesh (0 to {last})");
                return Err(r.error(c.start(), message).into());
            }
            members.push(k as u64);
        }
        out.push((id, members));
    }
    Ok(out)
}

/// The string values of the run file that name a file beside it (relative,
/// without `..`), in order, each once, with the `"mesh"` member they sit
/// under when it is one of the initial-state keys `map` may rewrite.
fn referenced_files(root: &Object<'_>, dir: &Path) -> Vec<Referenced> {
    fn walk(v: &Value<'_>, key: Option<&'static str>, dir: &Path, out: &mut Vec<Referenced>) {
        match v {
            Value::StringLit(s) => {
                let name = s.value.as_ref();
                let p = Path::new(name);
                let plain = !name.is_empty()
                    && p.is_relative()
                    && p.components()
                        .all(|c| matches!(c, std::path::Component::Normal(_)));
                if plain && dir.join(p).is_file() && !out.iter().any(|o| o.name == name) {
                    out.push(Referenced {
                        name: name.to_string(),
                        initial_state_key: key,
                    });
                }
            }
            Value::Object(o) => walk_object(o, key, dir, out),
            Value::Array(a) => a.elements.iter().for_each(|e| walk(e, key, dir, out)),
            _ => {}
        }
    }
    fn walk_object(
        o: &Object<'_>,
        key: Option<&'static str>,
        dir: &Path,
        out: &mut Vec<Referenced>,
    ) {
        for p in &o.properties {
            let n = p.name.clone().into_string();
            let key = key.or(INITIAL_STATE_KEYS.iter().copied().find(|k| *k == n));
            walk(&p.value, key, dir, out);
        }
    }
    let mut out = Vec::new();
    walk_object(root, None, dir, &mut out);
    out
}

/// The `"mesh"` members that carry an initial state.
pub const INITIAL_STATE_KEYS: [&str; 2] = ["particles_stresses", "particles_pore_pressures"];

/// A file the run file names.
#[derive(Clone, Debug, PartialEq)]
pub struct Referenced {
    /// As written in the run file (relative to its folder).
    pub name: String,
    /// The initial-state key it is the value of, if any.
    pub initial_state_key: Option<&'static str>,
}
