//! An Anura3D project as Anura3D will run it: its files, the lossless GOM and
//! CPS documents, the typed model, the computation method and the material
//! points Anura3D creates at load step 1.

use std::path::Path;

use super::PipelineError;
use crate::formats::cps::CpsDocument;
use crate::formats::gom::{GomDocument, GomInfo};
use crate::formats::project::{self, ProjectFiles};
use crate::model::{AnuraModel, ComputationMethod, MaterialPoint};

/// A loaded Anura3D project: files, documents, typed model and predicted MPs.
pub struct Project {
    pub files: ProjectFiles,
    /// The GOM's version header (`2023`, `2025`, …). The document itself is
    /// not kept: the GOM is copied to the output byte for byte from its file.
    pub gom_version: String,
    pub cps: Option<CpsDocument>,
    pub model: AnuraModel,
    pub info: GomInfo,
    /// The CPS `$$COMPUTATION_METHOD` (MPM-MIXED when there is no CPS).
    pub method: ComputationMethod,
    /// The MPs Anura3D creates, in its order (for a CB-Geo model: its
    /// particles, in its order).
    pub points: Vec<MaterialPoint>,
    /// A CB-Geo model instead of an Anura3D one (`map --mpm mpm.json`): the
    /// model as read; `files.gom` is then its run file and there is no CPS.
    pub cbgeo: Option<Box<crate::pipeline::cbgeo::CbGeoTarget>>,
}

impl Project {
    /// The MPs' positions, in MP order (a copy: steps that need them as a
    /// slice take it when the kernel's index is gone).
    pub fn mp_positions(&self) -> Vec<[f64; 3]> {
        self.points.iter().map(|p| p.position).collect()
    }

    /// Per material of the model (in GOM order), whether any MP is of it.
    pub fn materials_with_mps(&self) -> Vec<bool> {
        let mut has_mps = vec![false; self.model.materials.len()];
        for p in &self.points {
            if let Some(slot) = (p.material as usize)
                .checked_sub(1)
                .and_then(|i| has_mps.get_mut(i))
            {
                *slot = true;
            }
        }
        has_mps
    }

    /// Reads a project (a GOM, CPS, GiD `-2.dat` or folder) and places its MPs
    /// for its computation method; errors are positioned.
    pub fn load(path: &Path) -> Result<Project, PipelineError> {
        if crate::formats::cbgeo::is_run_file(path) {
            return crate::pipeline::cbgeo::load(path);
        }
        if path.is_dir()
            && let Some(json) = crate::pipeline::cbgeo::run_file_in(path)
        {
            return crate::pipeline::cbgeo::load(&json);
        }
        let files = project::discover(path)?;
        let gom = GomDocument::read(&files.gom)?;
        let cps = files.cps.as_deref().map(CpsDocument::read).transpose()?;
        let (model, mut info) = gom.model()?;
        // Gravity must point along −y for the geostatic stress and the runner.
        if let Some(cps) = &cps {
            cps.check_gravity_vector(model.mesh.dimension.n_dim())?;
        }
        // File-naming problems come first among the warnings.
        info.warnings.splice(0..0, files.warnings.iter().cloned());
        let method = match &cps {
            Some(cps) => {
                let text = cps.computation_method();
                ComputationMethod::parse(&text).ok_or_else(|| {
                    PipelineError::Input(format!(
                        "{}: unknown $$COMPUTATION_METHOD `{text}` (Anura3D knows MPM-MIXED, MPM-MP, FEM, UL-FEM)",
                        files.cps.as_deref().unwrap_or(path).display()
                    ))
                })?
            }
            None => ComputationMethod::default(),
        };
        let points = crate::place::place_material_points_for(&model, method).map_err(|errors| {
            let lines: Vec<String> = errors
                .0
                .iter()
                .take(20)
                .map(|e| {
                    let lines = match e {
                        crate::place::PlaceError::ActiveWithoutPoints { .. }
                        | crate::place::PlaceError::UnsupportedCount { .. }
                            if !info.mp_count_lines.is_empty() =>
                        {
                            &info.mp_count_lines
                        }
                        _ => &info.element_lines,
                    };
                    let line = e
                        .element()
                        .and_then(|el| lines.get(el))
                        .copied()
                        .unwrap_or(0);
                    format!("{}:{}:1: {}", files.gom.display(), line, e)
                })
                .collect();
            let more = errors.0.len().saturating_sub(20);
            PipelineError::Positioned(format!(
                "{}{}",
                lines.join("\n"),
                if more > 0 {
                    format!("\n… and {more} more")
                } else {
                    String::new()
                }
            ))
        })?;
        Ok(Project {
            files,
            gom_version: gom.version().to_string(),
            cps,
            model,
            info,
            method,
            points,
            cbgeo: None,
        })
    }

    /// The gravitational acceleration along −y (m/s²): the CPS's (the
    /// default without one), or a CB-Geo run file's.
    pub fn gravity(&self) -> f64 {
        match (&self.cbgeo, &self.cps) {
            // + 0.0: no −0 printed for a model without gravity.
            (Some(cb), _) => -cb.model.gravity[1] + 0.0,
            (None, Some(cps)) => cps.gravity(),
            (None, None) => crate::model::DEFAULT_GRAVITY,
        }
    }

    /// Dimension count (2 or 3).
    pub fn n_dim(&self) -> usize {
        self.model.mesh.dimension.n_dim()
    }
}
