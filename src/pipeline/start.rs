//! The state a check starts from, for `verify`, `run` and `fos` alike: from a
//! folder written by `map`, what Anura3D will hold at t = 0 (rebuilt from the
//! GOM, CPS and MAPF it reads, [`super::verify::judge_folder`], with the
//! MPM-MIXED collapse of its first step applied); or, from a model and a state
//! table, the table as given. One loader, so that the three commands judge the
//! same state.

use std::path::{Path, PathBuf};

use super::verify::KernelCheck;
use super::{PipelineError, Project};
use crate::formats::mps_table;
use crate::model::{MaterialPoint, MpState};

/// Where a mapped state comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum StateSource {
    /// A folder written by `map`: its GOM, CPS and MAPF, as Anura3D reads them.
    Folder(PathBuf),
    /// A model (GOM, CPS or folder) and an MP state table in `mps.csv`'s
    /// columns, taken as given.
    Table { model: PathBuf, state: PathBuf },
}

/// A project with the state its MPs start from.
pub struct Start {
    pub project: Project,
    /// The MPs (the model's own, in Anura3D's order).
    pub points: Vec<MaterialPoint>,
    /// The state the runner starts from: what Anura3D holds at t = 0 with the
    /// MPM-MIXED collapse of the first step applied, or the table's state.
    pub states: Vec<MpState>,
    /// The state at t = 0 as Anura3D holds it (before the MIXED collapse); the
    /// table's state for a table.
    pub at_zero: Vec<MpState>,
    /// What the files Anura3D reads give (a folder only).
    pub kernel: Option<KernelCheck>,
    /// Per MP: MAPF rows in reach (a folder only; empty for a table).
    pub rows_in_reach: Vec<u32>,
    /// The folder outputs go into by default: the map folder, or the state
    /// table's folder.
    pub home: PathBuf,
}

impl Start {
    /// Loads the state `source` names.
    pub fn load(source: &StateSource) -> Result<Start, PipelineError> {
        match source {
            StateSource::Folder(dir) => {
                let project = Project::load(dir)?;
                let judged = super::verify::judge_folder(&project)?;
                Ok(Start {
                    points: project.points.clone(),
                    home: project.files.dir.clone(),
                    project,
                    states: judged.run_start,
                    at_zero: judged.start,
                    kernel: Some(judged.check),
                    rows_in_reach: judged.rows_in_reach,
                })
            }
            StateSource::Table { model, state } => {
                let project = Project::load(model)?;
                let (points, states) = mps_table::read_states_for(state, &project.points)?;
                Ok(Start {
                    project,
                    points,
                    at_zero: states.clone(),
                    states,
                    kernel: None,
                    rows_in_reach: Vec::new(),
                    home: state.parent().unwrap_or(Path::new(".")).to_path_buf(),
                })
            }
        }
    }

    /// True when every MP's state is finite (the runner can start).
    pub fn runnable(&self) -> bool {
        self.states.iter().all(|s| {
            s.pwp.is_finite() && s.saturation.is_finite() && s.total.iter().all(|v| v.is_finite())
        })
    }
}
