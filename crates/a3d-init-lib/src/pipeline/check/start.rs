//! The state a check starts from, for `verify`, `run` and `fos` alike: from a
//! folder written by `map`, what Anura3D will hold at t = 0 (rebuilt from the
//! GOM, CPS and MAPF it reads, [`crate::pipeline::check::folder::judge_folder`], with the
//! MPM-MIXED collapse of its first step applied); or, from a model and a state
//! table, the table as given. One loader, so that the three commands judge the
//! same state.

use std::path::{Path, PathBuf};

use crate::formats::mps_table;
use crate::model::{MaterialPoint, MpState};
use crate::pipeline::check::folder::{Judged, KernelCheck};
use crate::pipeline::{PipelineError, Project};

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
    /// The state and where it came from.
    pub state: StartState,
    /// The folder outputs go into by default: the map folder, or the state
    /// table's folder.
    pub home: PathBuf,
}

/// Where a start's state came from.
pub enum StartState {
    /// A map folder: what Anura3D will hold, judged from the files it reads.
    Anura3d(Box<Judged>),
    /// A state table, as given.
    Table(Vec<MpState>),
    /// A CB-Geo project folder: what CB-Geo will hold, read from the files
    /// its run file names ([`crate::pipeline::cbgeo::held_state`]).
    CbGeo(Vec<MpState>),
}

impl Start {
    /// Loads the state `source` names.
    pub fn load(source: &StateSource) -> Result<Start, PipelineError> {
        match source {
            StateSource::Folder(dir) => {
                let project = Project::load(dir)?;
                if let Some(target) = &project.cbgeo {
                    let states = crate::pipeline::cbgeo::held_state(target)?;
                    return Ok(Start {
                        points: project.points.clone(),
                        home: project.files.dir.clone(),
                        project,
                        state: StartState::CbGeo(states),
                    });
                }
                let judged = crate::pipeline::check::folder::judge_folder(&project)?;
                Ok(Start {
                    points: project.points.clone(),
                    home: project.files.dir.clone(),
                    project,
                    state: StartState::Anura3d(Box::new(judged)),
                })
            }
            StateSource::Table { model, state } => {
                let project = Project::load(model)?;
                let (points, states) = mps_table::read_states_for(state, &project.points)?;
                Ok(Start {
                    project,
                    points,
                    state: StartState::Table(states),
                    home: state.parent().unwrap_or(Path::new(".")).to_path_buf(),
                })
            }
        }
    }

    /// The state the runner starts from: what Anura3D holds at t = 0 with the
    /// MPM-MIXED collapse of its first step applied, or the table's state.
    pub fn states(&self) -> &[MpState] {
        match &self.state {
            StartState::Anura3d(judged) => &judged.run_start,
            StartState::Table(states) | StartState::CbGeo(states) => states,
        }
    }

    /// The state at t = 0 as Anura3D holds it (before the MIXED collapse), or
    /// the table's state.
    pub fn at_zero(&self) -> &[MpState] {
        match &self.state {
            StartState::Anura3d(judged) => &judged.start,
            StartState::Table(states) | StartState::CbGeo(states) => states,
        }
    }

    /// What the files Anura3D reads give (a map folder only).
    pub fn kernel(&self) -> Option<&KernelCheck> {
        match &self.state {
            StartState::Anura3d(judged) => Some(&judged.check),
            StartState::Table(_) | StartState::CbGeo(_) => None,
        }
    }

    /// Per MP: MAPF rows in reach (a map folder only; empty for a table).
    pub fn rows_in_reach(&self) -> &[u32] {
        match &self.state {
            StartState::Anura3d(judged) => &judged.rows_in_reach,
            StartState::Table(_) | StartState::CbGeo(_) => &[],
        }
    }

    /// True when every MP's state is finite (the runner can start).
    pub fn runnable(&self) -> bool {
        self.states().iter().all(|s| {
            s.pwp.is_finite() && s.saturation.is_finite() && s.total.iter().all(|v| v.is_finite())
        })
    }
}
