//! Anura3D GOM files (geometry, mesh, conditions, materials, MP counts).
//! Spec: `formats/gom.md`.
//!
//! [`GomDocument`] is lossless: it wraps a [`KeywordDocument`] and reproduces the
//! file byte for byte unless a block is edited through the typed setters, which
//! re-render only the blocks they touch. [`GomDocument::model`] builds the typed
//! view ([`AnuraModel`]) and checks counts, ids and numbers, reporting
//! `path:line:col` errors. Material-point placement lives in `place`.

mod materials;
pub mod write;

use std::path::Path;

use super::error::{FormatError, ParseError};
use super::keyword_doc::KeywordDocument;
use super::lex;
use a3d_model::loads::{LoadBlock, LoadPhase, LoadTarget, SideLoad};
use a3d_model::{AnuraModel, Dimension, ElementType, Material, Mesh};

/// Element types Anura3D's readers accept but a3d-init cannot place MPs in.
const KNOWN_UNSUPPORTED_TYPES: [&str; 6] = [
    "triangular_6-noded",
    "quadrilateral_8-noded",
    "tetrahedral_4-noded",
    "tetrahedral_10-noded",
    "hexahedral_8-noded",
    "hexahedral_20-noded",
];

/// The nine solid/liquid/gas fixity blocks; only the solid ones enter the model.
const SOLID_FIXITY_BLOCKS: [&str; 3] = [
    "$$START_FIXITY_SURFACE_SOLID",
    "$$START_FIXITY_LINE_SOLID",
    "$$START_FIXITY_POINT_SOLID",
];

const LIQUID_FIXITY_BLOCKS: [&str; 3] = [
    "$$START_FIXITY_SURFACE_LIQUID",
    "$$START_FIXITY_LINE_LIQUID",
    "$$START_FIXITY_POINT_LIQUID",
];

/// Facts about a GOM beyond the plain model: version, formulation, where things
/// are in the file, and soft problems.
#[derive(Debug, Clone, Default)]
pub struct GomInfo {
    pub version: String,
    pub formulation: Option<String>,
    /// 1-based file line of each element's connectivity line.
    pub element_lines: Vec<u32>,
    /// 1-based file line of each element's MP-count line (empty without the block).
    pub mp_count_lines: Vec<u32>,
    /// Things that are legal for Anura3D but worth telling the user.
    pub warnings: Vec<String>,
    /// The hydraulic boundary areas of partially saturated analyses.
    pub hydraulic: HydraulicAreas,
    /// The load blocks present (`$$START_LOAD_ON_NODES_SOLID`, …), read as
    /// the kernel reads them; the CPS's `$$SOLID_TRACTION[_B]` /
    /// `$$LIQUID_PRESSURE[_B]` scale them in time.
    pub loads: Vec<LoadBlock>,
}

/// The GOM's load blocks and the CPS multiplier that scales each.
pub const LOAD_BLOCKS: [(&str, &str); 8] = [
    ("$$START_LOAD_ON_NODES_SOLID", "$$SOLID_TRACTION"),
    ("$$START_LOAD_ON_NODES_SOLID_B", "$$SOLID_TRACTION_B"),
    ("$$START_LOAD_ON_MATERIAL_POINTS_SOLID", "$$SOLID_TRACTION"),
    (
        "$$START_LOAD_ON_MATERIAL_POINTS_SOLID_B",
        "$$SOLID_TRACTION_B",
    ),
    ("$$START_LOAD_ON_NODES_LIQUID", "$$LIQUID_PRESSURE"),
    ("$$START_LOAD_ON_NODES_LIQUID_B", "$$LIQUID_PRESSURE_B"),
    (
        "$$START_LOAD_ON_MATERIAL_POINTS_LIQUID",
        "$$LIQUID_PRESSURE",
    ),
    (
        "$$START_LOAD_ON_MATERIAL_POINTS_LIQUID_B",
        "$$LIQUID_PRESSURE_B",
    ),
];

/// The phase, target and load system (0 = A, 1 = B) of the load block
/// `keyword` (one of [`LOAD_BLOCKS`]).
fn load_kind(keyword: &str) -> (LoadPhase, LoadTarget, usize) {
    let phase = if keyword.contains("LIQUID") {
        LoadPhase::Liquid
    } else {
        LoadPhase::Solid
    };
    let target = if keyword.contains("MATERIAL_POINTS") {
        LoadTarget::MaterialPoints
    } else {
        LoadTarget::Nodes
    };
    (phase, target, usize::from(keyword.ends_with("_B")))
}

/// The GOM's hydraulic boundary areas (`$$BOUNDARY_SEEPAGE_AREA`,
/// `$$BOUNDARY_INFILTRATION_AREA` with `$$INFILTRATION_RATE`,
/// `$$BOUNDARY_HYDRAULIC_HEAD_AREA`): bounding boxes `[min, max]` per axis
/// (x, y[, z]; unused axes are unbounded). The CPS switches them on.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HydraulicAreas {
    pub seepage: Option<[[f64; 2]; 3]>,
    pub infiltration: Option<[[f64; 2]; 3]>,
    /// m/s per axis, the infiltration velocity (pointing into the ground).
    pub infiltration_rate: Option<[f64; 3]>,
    pub hydraulic_head: Option<[[f64; 2]; 3]>,
}

/// A lossless GOM document.
#[derive(Debug, Clone)]
pub struct GomDocument {
    doc: KeywordDocument,
}

/// An element's MP counts: (solid, liquid).
type MpCount = (u32, u32);

impl GomDocument {
    /// Reads a GOM (`.GOM`, `.GOM_stage<k>` or a GiD `-2.dat` export).
    pub fn read(path: &Path) -> Result<GomDocument, FormatError> {
        Ok(GomDocument {
            doc: KeywordDocument::read(path, "$$FINISH", false)?,
        })
    }

    /// Parses GOM text; `path` is used in error messages.
    pub fn parse(path: &Path, text: String) -> Result<GomDocument, FormatError> {
        Ok(GomDocument {
            doc: KeywordDocument::parse(path, text, "$$FINISH", false)?,
        })
    }

    /// The underlying keyword document (blocks, lines).
    pub fn document(&self) -> &KeywordDocument {
        &self.doc
    }

    pub fn version(&self) -> &str {
        self.doc.version()
    }

    /// The text to write: byte-identical to the input unless edited.
    pub fn to_text(&self) -> String {
        self.doc.to_text()
    }

    fn block(&self, keyword: &str) -> Option<usize> {
        self.doc.find(keyword, false)
    }

    /// Non-blank data lines of block `b`: (0-based line index, text).
    fn rows(&self, b: usize) -> impl Iterator<Item = (usize, &str)> {
        let range = self.doc.blocks()[b].data.clone();
        range
            .map(|i| (i, self.doc.line(i)))
            .filter(|(_, l)| !l.trim().is_empty())
    }

    /// The 0-based lines of [`rows`](Self::rows), found in parallel (in order).
    fn data_lines(&self, b: usize) -> Vec<usize> {
        use rayon::prelude::*;
        let range = self.doc.blocks()[b].data.clone();
        range
            .into_par_iter()
            .filter(|&i| !self.doc.line(i).trim().is_empty())
            .collect()
    }

    /// Parses the first `n` non-blank data lines of block `b` with `parse`, in
    /// parallel. On failure the error of the earliest bad line is returned, so the
    /// result does not depend on scheduling; a block with fewer than `n` lines is a
    /// positioned error at the line where its data ends. Returns the values and
    /// their 0-based lines.
    fn parse_rows<T: Send + Default>(
        &self,
        b: usize,
        n: usize,
        what: &str,
        parse: impl Fn(usize, usize, &str) -> Result<T, ParseError> + Sync,
    ) -> Result<(Vec<T>, Vec<usize>), ParseError> {
        use rayon::prelude::*;
        use std::sync::atomic::{AtomicBool, Ordering};
        let mut rows = self.data_lines(b);
        if rows.len() < n {
            return Err(self.short_block(b, n, rows.len(), what));
        }
        if let Some(&i) = rows.get(n) {
            return Err(self.extra_row(b, i, n, what));
        }
        rows.truncate(n);
        // Straight into a vector of the right size (a collected `Result`
        // would grow one by appending); a failure only raises a flag.
        let failed = AtomicBool::new(false);
        let mut parsed = Vec::with_capacity(n);
        rows.par_iter()
            .enumerate()
            .with_min_len(4096)
            .map(|(k, &i)| {
                parse(k, i, self.doc.line(i)).unwrap_or_else(|_| {
                    failed.store(true, Ordering::Relaxed);
                    T::default()
                })
            })
            .collect_into_vec(&mut parsed);
        if !failed.into_inner() {
            return Ok((parsed, rows));
        }
        // Rare path: find the first failing line serially for a stable message.
        Err(rows
            .iter()
            .enumerate()
            .find_map(|(k, &i)| parse(k, i, self.doc.line(i)).err())
            .unwrap_or_else(|| self.doc.error_at(rows[0], 0, "parse error")))
    }

    /// The first non-blank data line of a block, trimmed.
    fn single_value(&self, keyword: &str) -> Option<(usize, &str)> {
        let b = self.block(keyword)?;
        self.rows(b).next().map(|(i, l)| (i, l.trim()))
    }

    fn required(&self, keyword: &str) -> Result<usize, ParseError> {
        self.block(keyword).ok_or_else(|| {
            let last = self.doc.terminator_block().line;
            self.doc
                .error_at(last, 0, format!("missing required block {keyword}"))
        })
    }

    /// A block with more non-blank data lines than its count: an error at the
    /// first line too many.
    fn extra_row(&self, b: usize, i: usize, n: usize, what: &str) -> ParseError {
        let block = &self.doc.blocks()[b];
        self.doc.error_at(
            i,
            0,
            format!(
                "{} (line {}) expects {n} {what}, found more: a count and its block disagree",
                block.keyword,
                block.line + 1
            ),
        )
    }

    /// Where a block's data ran out: the next keyword line (or the end of the file).
    fn short_block(&self, b: usize, expected: usize, found: usize, what: &str) -> ParseError {
        let block = &self.doc.blocks()[b];
        let at = block.data.end.min(self.doc.n_lines().saturating_sub(1));
        self.doc.error_at(
            at,
            0,
            format!(
                "{} (line {}) expects {expected} {what}, found {found}",
                block.keyword,
                block.line + 1
            ),
        )
    }

    /// The model's dimension and element type (Anura3D's defaults, with a
    /// warning, where the blocks are missing), which must agree.
    fn dimension_and_element_type(
        &self,
        warnings: &mut Vec<String>,
    ) -> Result<(Dimension, ElementType), FormatError> {
        let dimension = match self.single_value("$$DIMENSION") {
            Some((line, value)) => Dimension::from_gom(value).ok_or_else(|| {
                self.doc.error_at(line, 0, format!(
                    "unknown dimension `{value}` (known: 2D-plane_strain, 2D-axisymmetric, 3D-cartesian, 3D-cylindrical)"
                ))
            })?,
            None => {
                warnings.push("no $$DIMENSION block: Anura3D's default 3D-cartesian is used".into());
                Dimension::Cartesian3D
            }
        };
        let element_type = match self.single_value("$$ELEMENTTYPE") {
            Some((line, value)) => match ElementType::from_gom(value) {
                Some(t) => t,
                None => {
                    let why = if KNOWN_UNSUPPORTED_TYPES.contains(&value) {
                        "is not supported by a3d-init (nor run by the Anura3D kernel)"
                    } else {
                        "is unknown"
                    };
                    return Err(self.doc.error_at(line, 0, format!(
                        "element type `{value}` {why}; supported: triangular_3-noded, tetrahedral_old, quadrilateral_4-noded"
                    )).into());
                }
            },
            None => {
                warnings.push(
                    "no $$ELEMENTTYPE block: Anura3D's default tetrahedral_old is used".into(),
                );
                ElementType::TetOld
            }
        };
        if element_type.n_dim() != dimension.n_dim() {
            let line = self.single_value("$$ELEMENTTYPE").map_or(0, |(l, _)| l);
            return Err(self
                .doc
                .error_at(
                    line,
                    0,
                    format!(
                        "element type {} is {}D but the model is {}",
                        element_type.gom_name(),
                        element_type.n_dim(),
                        dimension.gom_name()
                    ),
                )
                .into());
        }
        if element_type == ElementType::Quad4 {
            warnings.push(
                "quadrilateral_4-noded runs only with the upstream Anura3D kernel (Anura3D/Anura3D_OpenSource)".into(),
            );
        }
        Ok((dimension, element_type))
    }

    /// `$$STARTCOUNTERS`: the counts of elements and nodes, at least one of
    /// each and fewer than 2³².
    fn counters(&self) -> Result<(usize, usize), FormatError> {
        let counters = self.required("$$STARTCOUNTERS")?;
        let (cline, ctext) = self
            .rows(counters)
            .next()
            .ok_or_else(|| self.short_block(counters, 1, 0, "line `NEl NNodes`"))?;
        let mut counts = [0u64; 2];
        lex::uints(ctext, &mut counts).map_err(|bad| {
            self.numbers_error(
                cline,
                bad,
                "a count",
                0,
                "expected `NEl NNodes` (number of elements, then nodes)",
            )
        })?;
        let (n_elements, n_nodes) = (counts[0] as usize, counts[1] as usize);
        if n_elements == 0 || n_nodes == 0 {
            return Err(self
                .doc
                .error_at(
                    cline,
                    0,
                    format!(
                        "{n_elements} elements and {n_nodes} nodes: a model needs at least one of each"
                    ),
                )
                .into());
        }
        if n_elements > u32::MAX as usize || n_nodes > u32::MAX as usize {
            return Err(self
                .doc
                .error_at(cline, 0, "more than 2^32 elements or nodes")
                .into());
        }

        Ok((n_elements, n_nodes))
    }

    /// Builds the typed view. Every count, id and number is checked; errors name
    /// the file, line and column.
    pub fn model(&self) -> Result<(AnuraModel, GomInfo), FormatError> {
        let mut info = GomInfo {
            version: self.version().to_string(),
            ..GomInfo::default()
        };
        let mut errors: Vec<ParseError> = Vec::new();

        let (dimension, element_type) = self.dimension_and_element_type(&mut info.warnings)?;
        info.formulation = self
            .single_value("$$FORMULATION")
            .map(|(_, v)| v.to_string());

        let (n_elements, n_nodes) = self.counters()?;

        let nodes = self.read_nodes(dimension.n_dim(), n_nodes)?;
        let (connectivity, element_lines) =
            self.read_connectivity(element_type, n_elements, n_nodes)?;
        info.element_lines = element_lines;

        let mut solid_fixity = vec![[false; 3]; n_nodes];
        for keyword in SOLID_FIXITY_BLOCKS {
            if let Some(b) = self.block(keyword)
                && let Err(e) = self.read_fixity(b, dimension.n_dim(), &mut solid_fixity)
            {
                errors.push(e);
            }
        }

        let mut liquid_fixity = vec![[false; 3]; n_nodes];
        for keyword in LIQUID_FIXITY_BLOCKS {
            if let Some(b) = self.block(keyword)
                && let Err(e) = self.read_fixity(b, dimension.n_dim(), &mut liquid_fixity)
            {
                errors.push(e);
            }
        }

        for (keyword, _) in LOAD_BLOCKS {
            if let Some(b) = self.block(keyword) {
                match self.read_load_block(b, keyword, dimension.n_dim(), n_nodes) {
                    Ok(block) => info.loads.push(block),
                    Err(e) => errors.push(e),
                }
            }
        }
        match self.read_hydraulic(dimension.n_dim()) {
            Ok(h) => info.hydraulic = h,
            Err(e) => errors.push(e),
        }

        let materials = match self.block("$$NUMBER_OF_MATERIALS") {
            Some(b) => {
                let start = self.doc.blocks()[b].line;
                let end = self.doc.terminator_block().line;
                let block = materials::read_materials(&self.doc, start, end)?;
                info.warnings.extend(block.warnings);
                block.materials
            }
            None => {
                info.warnings
                    .push("no $$NUMBER_OF_MATERIALS block: no materials".into());
                Vec::new()
            }
        };

        let element_material = self.read_element_materials(n_elements, &materials, &mut errors)?;
        let mp_counts = match self.block("$$START_NUMBER_OF_MATERIAL_POINTS") {
            Some(b) => {
                let (counts, lines) =
                    self.read_mp_counts(b, n_elements, element_type, &mut errors)?;
                info.mp_count_lines = lines.iter().map(|&i| i as u32 + 1).collect();
                counts
            }
            None => {
                info.warnings
                    .push("no $$START_NUMBER_OF_MATERIAL_POINTS block: no MPs are placed".into());
                vec![(0, 0); n_elements]
            }
        };
        let damping = match self.block("$$STARTDAMPING") {
            Some(b) => Some(self.read_per_element_reals(b, n_elements, "damping factors")?),
            None => None,
        };
        if let Some(e) = FormatError::from_list(errors) {
            return Err(e);
        }
        let mesh = Mesh {
            dimension,
            element_type,
            nodes,
            connectivity,
        };
        let model = AnuraModel {
            mesh,
            materials,
            element_material,
            mp_counts,
            solid_fixity,
            liquid_fixity,
            damping,
        };
        Ok((model, info))
    }

    /// The error for line `i` of numbers that [`lex::reals`] or [`lex::uints`]
    /// refused: at a bad token, `expected {what}, found `…``; with too few
    /// numbers, `short` at byte `short_at` of the line.
    fn numbers_error(
        &self,
        i: usize,
        bad: Option<lex::BadToken<'_>>,
        what: &str,
        short_at: usize,
        short: impl Into<String>,
    ) -> ParseError {
        match bad {
            Some(t) => {
                self.doc
                    .error_at(i, t.offset, format!("expected {what}, found `{}`", t.text))
            }
            None => self.doc.error_at(i, short_at, short),
        }
    }

    fn read_nodes(&self, n_dim: usize, n_nodes: usize) -> Result<Vec<[f64; 3]>, ParseError> {
        let b = self.required("$$STARTNODES")?;
        let (nodes, rows) =
            self.parse_rows(b, n_nodes, "node lines ($$STARTCOUNTERS)", |k, i, line| {
                let mut xyz = [0.0f64; 3];
                lex::reals(line, &mut xyz[..n_dim]).map_err(|bad| {
                    self.numbers_error(
                        i,
                        bad,
                        "a coordinate",
                        line.len(),
                        format!("node {} needs {n_dim} coordinates", k + 1),
                    )
                })?;
                Ok(xyz)
            })?;
        // A node far outside the others cannot be meant: refused at
        // its coordinate.
        if let Some(far) = super::extent::far_outlier(&nodes) {
            let i = rows[far.index];
            let offset = lex::tokens(self.doc.line(i))
                .nth(far.axis)
                .map_or(0, |(o, _)| o);
            return Err(self
                .doc
                .error_at(i, offset, format!("node {}: {far}", far.index + 1)));
        }
        Ok(nodes)
    }

    fn read_connectivity(
        &self,
        element_type: ElementType,
        n_elements: usize,
        n_nodes: usize,
    ) -> Result<(Vec<u32>, Vec<u32>), ParseError> {
        let b = self.required("$$STARTELEMCON")?;
        let per = element_type.nodes_per_element();
        let (rows, _) = self.parse_rows(
            b,
            n_elements,
            "element lines ($$STARTCOUNTERS)",
            |k, i, line| {
                let e = k + 1;
                let mut ids = [0u64; 10];
                lex::uints(line, &mut ids[..per]).map_err(|bad| {
                    self.numbers_error(
                        i,
                        bad,
                        "a node id",
                        line.len(),
                        format!(
                            "element {e} needs {per} node ids for {}",
                            element_type.gom_name()
                        ),
                    )
                })?;
                let mut out = [0u32; 10];
                for (slot, (k, &id)) in out.iter_mut().zip(ids[..per].iter().enumerate()) {
                    if id == 0 || id as usize > n_nodes {
                        let offset = lex::tokens(line).nth(k).map_or(0, |(o, _)| o);
                        return Err(self.doc.error_at(
                            i,
                            offset,
                            format!("element {e}: node id {id} is out of range 1..={n_nodes}"),
                        ));
                    }
                    *slot = (id - 1) as u32;
                }
                Ok((out, i as u32 + 1))
            },
        )?;
        let mut connectivity = Vec::with_capacity(n_elements * per);
        let mut lines = Vec::with_capacity(n_elements);
        for (ids, line) in rows {
            connectivity.extend_from_slice(&ids[..per]);
            lines.push(line);
        }
        Ok((connectivity, lines))
    }

    /// The hydraulic boundary areas and the infiltration rate, where given.
    fn read_hydraulic(&self, n_dim: usize) -> Result<HydraulicAreas, ParseError> {
        let area = |keyword: &str| -> Result<Option<[[f64; 2]; 3]>, ParseError> {
            let Some(b) = self.block(keyword) else {
                return Ok(None);
            };
            let mut area = [[f64::NEG_INFINITY, f64::INFINITY]; 3];
            let mut rows = self.rows(b);
            for (d, bounds) in area.iter_mut().enumerate().take(n_dim) {
                let Some((i, line)) = rows.next() else {
                    return Err(self.short_block(b, n_dim, d, "`min max` lines"));
                };
                let mut v = [0.0; 2];
                lex::reals(line, &mut v).map_err(|bad| {
                    self.numbers_error(
                        i,
                        bad,
                        "a bound",
                        line.len(),
                        String::from("expected `min max`"),
                    )
                })?;
                if v[0] > v[1] || v.iter().any(|x| x.is_nan()) {
                    return Err(self.doc.error_at(
                        i,
                        0,
                        format!("{keyword}: min {} is above max {}", v[0], v[1]),
                    ));
                }
                *bounds = v;
            }
            Ok(Some(area))
        };
        let infiltration_rate = match self.block("$$INFILTRATION_RATE") {
            None => None,
            Some(b) => {
                let Some((i, line)) = self.rows(b).next() else {
                    return Err(self.short_block(b, 1, 0, "rate line"));
                };
                let mut v = [0.0; 3];
                lex::reals(line, &mut v[..n_dim]).map_err(|bad| {
                    self.numbers_error(
                        i,
                        bad,
                        "a rate",
                        line.len(),
                        format!("expected {n_dim} velocity components (m/s)"),
                    )
                })?;
                Some(v)
            }
        };
        Ok(HydraulicAreas {
            seepage: area("$$BOUNDARY_SEEPAGE_AREA")?,
            infiltration: area("$$BOUNDARY_INFILTRATION_AREA")?,
            infiltration_rate,
            hydraulic_head: area("$$BOUNDARY_HYDRAULIC_HEAD_AREA")?,
        })
    }

    /// A block that starts with a count line (`N`, then N rows of `what`):
    /// the count and the rows after it. A missing or non-numeric count is an
    /// error at its line.
    fn counted_rows(
        &self,
        b: usize,
        what: &str,
    ) -> Result<(usize, impl Iterator<Item = (usize, &str)>), ParseError> {
        let mut rows = self.rows(b);
        let Some((cline, ctext)) = rows.next() else {
            return Err(self.short_block(b, 1, 0, "count line"));
        };
        let mut count = [0u64];
        lex::uints(ctext, &mut count).map_err(|_| {
            self.doc.error_at(
                cline,
                0,
                format!("expected the number of {what}, found `{}`", ctext.trim()),
            )
        })?;
        Ok((count[0] as usize, rows))
    }

    fn read_fixity(
        &self,
        b: usize,
        n_dim: usize,
        fixity: &mut [[bool; 3]],
    ) -> Result<(), ParseError> {
        let (count, rows) = self.counted_rows(b, "fixed nodes")?;
        let mut seen = 0;
        let mut values = [0u64; 4];
        for (i, line) in rows.take(count) {
            lex::uints(line, &mut values[..1 + n_dim]).map_err(|bad| {
                self.numbers_error(
                    i,
                    bad,
                    "a node id or a 0/1 flag",
                    line.len(),
                    format!(
                        "expected `node {}`",
                        if n_dim == 2 { "fx fy" } else { "fx fy fz" }
                    ),
                )
            })?;
            let node = values[0] as usize;
            if node == 0 || node > fixity.len() {
                return Err(self.doc.error_at(
                    i,
                    0,
                    format!("node id {node} is out of range 1..={}", fixity.len()),
                ));
            }
            for d in 0..n_dim {
                fixity[node - 1][d] |= values[1 + d] == 1;
            }
            seen += 1;
        }
        if seen < count {
            return Err(self.short_block(b, count, seen, "fixity lines"));
        }
        // The count line comes first, then exactly `count` node lines.
        if let Some((i, _)) = self.rows(b).nth(1 + seen) {
            let block = &self.doc.blocks()[b];
            return Err(self.doc.error_at(
                i,
                0,
                format!(
                    "{} (line {}) expects {seen} fixity lines, found more: the count and the block disagree",
                    block.keyword,
                    block.line + 1
                ),
            ));
        }
        Ok(())
    }

    /// A load block as the kernel reads it (`MeshInfo.FOR` 625-927): a count
    /// of loaded sides, then per side its node ids (2 in 2D; 6 in 3D, the
    /// three corners first) and the load at each node (n_dim values each).
    /// Only the corners' values count. Node ids must exist; every number is
    /// checked.
    fn read_load_block(
        &self,
        b: usize,
        keyword: &str,
        n_dim: usize,
        n_nodes: usize,
    ) -> Result<LoadBlock, ParseError> {
        let (phase, target, system) = load_kind(keyword);
        let (ids_per_side, corners) = if n_dim == 3 { (6, 3) } else { (2, 2) };
        let (count, mut rows) = self.counted_rows(b, "loaded sides")?;
        let mut sides = Vec::with_capacity(count.min(1 << 20));
        let width = ids_per_side * (1 + n_dim);
        let mut numbers = vec![0.0; width];
        let layout = if n_dim == 3 {
            "`c1 c2 c3 m12 m23 m31` and three values per node"
        } else {
            "`n1 n2 q1x q1y q2x q2y`"
        };
        for (i, line) in rows.by_ref().take(count) {
            lex::reals(line, &mut numbers).map_err(|bad| {
                self.numbers_error(
                    i,
                    bad,
                    "a node id or a load value",
                    line.len(),
                    format!("{keyword}: expected {width} numbers per side, {layout}"),
                )
            })?;
            let mut ids = Vec::with_capacity(corners);
            for (k, &v) in numbers[..ids_per_side].iter().enumerate() {
                if v.fract() != 0.0 || v < 1.0 || v > n_nodes as f64 {
                    let offset = lex::tokens(line).nth(k).map_or(0, |(o, _)| o);
                    return Err(self.doc.error_at(
                        i,
                        offset,
                        format!("{keyword}: node id {v} is out of range 1..={n_nodes}"),
                    ));
                }
                // The corners come first; mid-side nodes are only checked.
                if k < corners {
                    ids.push(v as u32 - 1);
                }
            }
            let values = (0..corners)
                .map(|k| {
                    let mut q = [0.0; 3];
                    q[..n_dim].copy_from_slice(
                        &numbers[ids_per_side + k * n_dim..ids_per_side + (k + 1) * n_dim],
                    );
                    q
                })
                .collect();
            sides.push(SideLoad {
                corners: ids,
                values,
                line: i as u32 + 1,
            });
        }
        if sides.len() < count {
            return Err(self.short_block(b, count, sides.len(), "loaded sides"));
        }
        if let Some((i, _)) = rows.next() {
            return Err(self.extra_row(b, i, count, "loaded sides"));
        }
        Ok(LoadBlock {
            keyword: keyword.to_string(),
            phase,
            target,
            system,
            sides,
        })
    }

    fn read_element_materials(
        &self,
        n_elements: usize,
        materials: &[Material],
        errors: &mut Vec<ParseError>,
    ) -> Result<Vec<u32>, ParseError> {
        let b = self.required("$$STARTELMMAT")?;
        let (out, lines) =
            self.parse_rows(b, n_elements, "element material lines", |_, i, line| {
                let mut value = [0u64];
                lex::uints(line, &mut value).map_err(|bad| {
                    self.numbers_error(i, bad, "a material index", 0, "expected a material index")
                })?;
                u32::try_from(value[0]).map_err(|_| {
                    self.doc
                        .error_at(i, 0, format!("material index {} is out of range", value[0]))
                })
            })?;
        for (e, (&m, &i)) in out.iter().zip(&lines).enumerate() {
            if m as usize > materials.len() {
                errors.push(self.doc.error_at(
                    i,
                    0,
                    format!(
                        "element {}: material {m} does not exist ({} materials)",
                        e + 1,
                        materials.len()
                    ),
                ));
            }
        }
        Ok(out)
    }

    /// Reads the MP counts per element (and the 0-based line of each).
    fn read_mp_counts(
        &self,
        b: usize,
        n_elements: usize,
        element_type: ElementType,
        errors: &mut Vec<ParseError>,
    ) -> Result<(Vec<MpCount>, Vec<usize>), ParseError> {
        let (out, lines) = self.parse_rows(b, n_elements, "MP count lines", |_, i, line| {
            let mut values = [0u64; 2];
            lex::uints(line, &mut values).map_err(|bad| {
                self.numbers_error(
                    i,
                    bad,
                    "an MP count",
                    line.len(),
                    "expected `nSolid nLiquid`",
                )
            })?;
            match (u32::try_from(values[0]), u32::try_from(values[1])) {
                (Ok(s), Ok(l)) => Ok((s, l)),
                _ => Err(self.doc.error_at(i, 0, "MP count out of range")),
            }
        })?;
        for (e, (&(solid, _), &i)) in out.iter().zip(&lines).enumerate() {
            if solid != 0 && !element_type.allowed_mp_counts().contains(&solid) {
                errors.push(self.doc.error_at(
                    i,
                    0,
                    format!(
                        "element {}: {solid} MPs per element is not allowed for {} (allowed: {:?})",
                        e + 1,
                        element_type.gom_name(),
                        element_type.allowed_mp_counts()
                    ),
                ));
            }
        }
        Ok((out, lines))
    }

    fn read_per_element_reals(
        &self,
        b: usize,
        n_elements: usize,
        what: &str,
    ) -> Result<Vec<f64>, ParseError> {
        let mut out = Vec::with_capacity(n_elements);
        let mut value = [0.0];
        for (i, line) in self.rows(b).take(n_elements) {
            lex::reals(line, &mut value)
                .map_err(|bad| self.numbers_error(i, bad, "a number", 0, "expected a number"))?;
            out.push(value[0]);
        }
        if out.len() < n_elements {
            return Err(self.short_block(b, n_elements, out.len(), what));
        }
        if let Some((i, _)) = self.rows(b).nth(n_elements) {
            return Err(self.extra_row(b, i, n_elements, what));
        }
        Ok(out)
    }

    /// Replaces `$$STARTELMMAT` with one material index per element.
    pub fn set_element_materials(&mut self, element_material: &[u32]) -> Result<(), FormatError> {
        let b = self.required("$$STARTELMMAT")?;
        self.doc
            .replace_block(b, element_material.iter().map(|m| m.to_string()).collect());
        Ok(())
    }

    /// Replaces `$$START_NUMBER_OF_MATERIAL_POINTS` with `nSolid nLiquid` per element.
    pub fn set_mp_counts(&mut self, counts: &[(u32, u32)]) -> Result<(), FormatError> {
        let b = self.required("$$START_NUMBER_OF_MATERIAL_POINTS")?;
        self.doc
            .replace_block(b, counts.iter().map(|(s, l)| format!("{s} {l}")).collect());
        Ok(())
    }
}
