//! Argument groups shared by several commands, and their conversion into the
//! library's typed options. Keeping them here (not in one command's module)
//! keeps the commands free of imports between each other.

use std::path::PathBuf;

use anyhow::{Context, bail};
use serde::Serialize;

use crate::formats::fem_csv::{self, CsvOptions, SignConvention};
use crate::formats::fem_vtu::{self, StressRule, VtuOptions};
use crate::pipeline::fem::{FemOptions, LoadedFem};
use crate::pipeline::start::StateSource;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
pub enum SignArg {
    /// Stresses compression positive, pwp positive below the water table (CSV and .gsz default).
    Geostudio,
    /// Anura3D's: tension positive, pwp negative in compression.
    TensionPositive,
    /// OpenGeoSys: pressure positive in compression, stresses tension positive (.vtu/.pvd default).
    Ogs,
}

impl From<SignArg> for SignConvention {
    fn from(s: SignArg) -> SignConvention {
        match s {
            SignArg::Geostudio => SignConvention::GeoStudio,
            SignArg::TensionPositive => SignConvention::TensionPositive,
            SignArg::Ogs => SignConvention::Ogs,
        }
    }
}

/// Options shared by every command that reads FEM node files.
#[derive(Debug, Clone, clap::Args)]
pub struct FemArgs {
    /// FEM node file(s): CSV node tables, a GeoStudio node.csv with --fem-mesh, a .gsz project, or VTK results (.vtu, .pvd time series: OpenGeoSys, ParaView). Several files are joined by node id or coordinates.
    #[arg(long = "fem", value_name = "FILE")]
    pub fem: Vec<PathBuf>,
    /// Explicit column mapping, e.g. `x=X (m),y=Y (m),pwp=PWP`; for .vtu/.pvd, arrays by role: `pwp=p,stress=sigma,saturation=S,region=MaterialIDs`.
    #[arg(long, value_name = "FIELD=HEADER,…")]
    pub columns: Option<String>,
    /// Unit overrides, e.g. `length=ft,pressure=psf` (.vtu/.pvd: m and Pa unless given).
    #[arg(long, value_name = "length=…,pressure=…")]
    pub fem_units: Option<String>,
    /// Sign convention of the FEM file [default: geostudio; ogs for .vtu/.pvd].
    #[arg(long, value_enum)]
    pub fem_sign: Option<SignArg>,
    /// .vtu/.pvd: whether the stress array is effective (made total with σ + α·χ·pwp) or total [default: effective when a pressure array is read, as OGS's HydroMechanics and RichardsMechanics write `sigma`].
    #[arg(
        long,
        value_name = "effective[,biot=α][,chi=1|saturation|saturation^m]|total"
    )]
    pub fem_sigma: Option<String>,
    /// GeoStudio mesh (`Mesh.ply`) giving the coordinates of a `node.csv` without X, Y columns.
    #[arg(long, value_name = "PLY")]
    pub fem_mesh: Option<PathBuf>,
    /// Analysis of a `.gsz` project: its name or 1-based index (needed when there are several).
    #[arg(long, value_name = "NAME|INDEX")]
    pub analysis: Option<String>,
    /// Saved step of a `.gsz` analysis: a step number, `last`, or `time=<seconds>`.
    #[arg(long, default_value = "last", value_name = "k|last|time=T")]
    pub step: String,
}

impl FemArgs {
    /// The defaults for these files (GeoStudio signs, last step, no overrides).
    pub fn files(paths: Vec<PathBuf>) -> FemArgs {
        FemArgs {
            fem: paths,
            columns: None,
            fem_units: None,
            fem_sign: None,
            fem_sigma: None,
            fem_mesh: None,
            analysis: None,
            step: "last".into(),
        }
    }

    /// The library options these arguments describe.
    pub fn options(&self) -> anyhow::Result<FemOptions> {
        if self.fem.is_empty() {
            bail!("give the FEM node file(s) with --fem FILE");
        }
        // `--columns` names table headers, or VTU arrays when every file is one.
        let all_vtu = self.fem.iter().all(|p| fem_vtu::is_vtk_path(p));
        let (columns, arrays) = match &self.columns {
            Some(s) if all_vtu => (
                Vec::new(),
                fem_vtu::parse_arrays_option(s).map_err(|e| anyhow::anyhow!("--columns: {e}"))?,
            ),
            Some(s) => (
                fem_csv::parse_columns_option(s).map_err(|e| anyhow::anyhow!("--columns: {e}"))?,
                Vec::new(),
            ),
            None => (Vec::new(), Vec::new()),
        };
        let stress = match &self.fem_sigma {
            Some(s) => {
                fem_vtu::parse_stress_option(s).map_err(|e| anyhow::anyhow!("--fem-sigma: {e}"))?
            }
            None => StressRule::Auto,
        };
        let units = match &self.fem_units {
            Some(s) => {
                fem_csv::parse_units_option(s).map_err(|e| anyhow::anyhow!("--fem-units: {e}"))?
            }
            None => Default::default(),
        };
        Ok(FemOptions {
            paths: self.fem.clone(),
            csv: CsvOptions {
                columns,
                units: units.clone(),
                sign: self.fem_sign.map_or(SignConvention::GeoStudio, Into::into),
            },
            vtu: VtuOptions {
                arrays,
                units,
                sign: self.fem_sign.map(Into::into),
                stress,
            },
            mesh: self.fem_mesh.clone(),
            analysis: self.analysis.clone(),
            step: self
                .step
                .parse()
                .map_err(|e| anyhow::anyhow!("--step {e}"))
                .context("reading the FEM files")?,
        })
    }

    /// Reads and joins the FEM files.
    pub fn load(&self) -> anyhow::Result<LoadedFem> {
        Ok(crate::pipeline::fem::load(&self.options()?)?)
    }
}

/// Where `verify`, `run` and `fos` take a mapped state from: a folder written
/// by `map`, or a model with a state table.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct StateInputs {
    /// A folder written by `map` (model and mps.csv are taken from it).
    pub dir: Option<PathBuf>,
    /// Anura3D model (GOM, CPS or folder), when not using a map folder.
    #[arg(long)]
    pub mpm: Option<PathBuf>,
    /// MP state table (mps.csv written by `map`).
    #[arg(long)]
    pub state: Option<PathBuf>,
}

impl StateInputs {
    /// A folder written by `map`.
    pub fn folder(dir: PathBuf) -> StateInputs {
        StateInputs {
            dir: Some(dir),
            ..StateInputs::default()
        }
    }

    /// The source the arguments name; an error unless exactly one way is given.
    pub fn source(&self) -> anyhow::Result<StateSource> {
        match (&self.dir, &self.mpm, &self.state) {
            (Some(dir), None, None) => Ok(StateSource::Folder(dir.clone())),
            (None, Some(model), Some(state)) => Ok(StateSource::Table {
                model: model.clone(),
                state: state.clone(),
            }),
            _ => bail!("give a folder written by `map`, or --mpm MODEL --state mps.csv"),
        }
    }
}
