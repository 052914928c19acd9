//! Argument groups shared by several commands, and their conversion into the
//! library's typed options. Keeping them here (not in one command's module)
//! keeps the commands free of imports between each other.

use std::path::PathBuf;

use a3d_init::formats::fem_csv::{self, CsvOptions};

use a3d_init::formats::fem::SignConvention;
use a3d_init::formats::fem_vtu::{self, StressRule, VtuOptions};
use a3d_init::pipeline::check::start::StateSource;
use a3d_init::pipeline::fem::FemOptions;
use anyhow::{Context, bail};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
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
    /// Saved step of a `.gsz` analysis or `.pvd` series: a step number, `last`, `time=<seconds>`, or (`map`) `failure`: the first saved step whose factor of safety FS(t) is at most 1.
    #[arg(long, default_value = "last", value_name = "k|last|time=T|failure")]
    pub step: String,
}

impl FemArgs {
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

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// Morgenstern & Price (1965), the seed paper's method (SLOPE/W).
    MorgensternPrice,
    /// Spencer (1967): parallel interslice forces.
    Spencer,
    /// Bishop's simplified method (1955).
    Bishop,
    /// Janbu's simplified method with his correction factor f₀.
    Janbu,
    /// The ordinary method of slices (Fellenius).
    Ordinary,
    /// Strength reduction on the built-in explicit MPM runner.
    Srm,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum IntersliceArg {
    HalfSine,
    Constant,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SuctionArg {
    /// Bishop's effective stress with χ = S (as the runner and Anura3D).
    Bishop,
    /// Fredlund's φᵇ (`--phi-b`, default φ′/2 of each material).
    PhiB,
    /// Suction ignored.
    None,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SearchArg {
    /// Circles through entry and exit points on the ground.
    EntryExit,
    /// Circles from a grid of centres and tangent radii.
    Grid,
}

/// Limit-equilibrium options shared by `fos` and `fos-time`.
#[derive(Debug, Clone, clap::Args)]
pub struct LeArgs {
    /// Interslice force function of Morgenstern–Price.
    #[arg(long, value_enum, default_value_t = IntersliceArg::HalfSine)]
    pub interslice: IntersliceArg,
    /// How suction adds to the strength.
    #[arg(long, value_enum, default_value_t = SuctionArg::Bishop)]
    pub suction: SuctionArg,
    /// φᵇ in degrees for `--suction phi-b` (default φ′/2 of each material).
    #[arg(long, value_name = "DEG")]
    pub phi_b: Option<f64>,
    /// How trial circles are generated.
    #[arg(long, value_enum, default_value_t = SearchArg::EntryExit)]
    pub search: SearchArg,
    /// Entry range on the ground (the higher end), `X1:X2` in m (default: the whole ground).
    #[arg(long, value_name = "X1:X2")]
    pub entry: Option<String>,
    /// Exit range on the ground (the lower end), `X1:X2` in m.
    #[arg(long, value_name = "X1:X2")]
    pub exit: Option<String>,
    /// Grid of centres for `--search grid`, `X1:X2:Y1:Y2` in m.
    #[arg(long, value_name = "X1:X2:Y1:Y2")]
    pub grid: Option<String>,
    /// Elevations the radii of `--search grid` reach down to, `Y1:Y2` in m.
    #[arg(long, value_name = "Y1:Y2")]
    pub tangents: Option<String>,
    /// About this many trial circles.
    #[arg(long, default_value_t = 5000)]
    pub trials: usize,
    /// Keep the best circle (no non-circular refinement).
    #[arg(long)]
    pub no_refine: bool,
    /// Slices per surface.
    #[arg(long, default_value_t = 30)]
    pub slices: usize,
    /// Shallowest surface in m (default 5 % of the ground's height range).
    #[arg(long, value_name = "M")]
    pub min_depth: Option<f64>,
    /// Smoothing length of the pore-pressure interpolation in m (default: the spacing rule).
    #[arg(long = "le-h", value_name = "M")]
    pub h: Option<f64>,
}

/// `a:b:…` as `n` numbers.
fn numbers<const N: usize>(text: &str, flag: &str) -> anyhow::Result<[f64; N]> {
    let v: Vec<f64> = text
        .split(':')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("{flag} `{text}`: expected {N} numbers separated by `:`"))?;
    let a: [f64; N] = v
        .try_into()
        .map_err(|_| anyhow::anyhow!("{flag} `{text}`: expected {N} numbers separated by `:`"))?;
    if a.iter().any(|x| !x.is_finite()) {
        bail!("{flag} `{text}`: the numbers must be finite");
    }
    Ok(a)
}

impl LeArgs {
    /// The method of slices `method` names with the half-sine interslice
    /// function (`None` for `srm`).
    pub fn method_of(method: MethodArg) -> Option<a3d_init::slope::Method> {
        Self::with_interslice(method, IntersliceArg::HalfSine)
    }

    /// The method of slices `method` names (`None` for `srm`).
    pub fn method(&self, method: MethodArg) -> Option<a3d_init::slope::Method> {
        Self::with_interslice(method, self.interslice)
    }

    fn with_interslice(
        method: MethodArg,
        interslice: IntersliceArg,
    ) -> Option<a3d_init::slope::Method> {
        use a3d_init::slope::{Interslice, Method};
        let interslice = match interslice {
            IntersliceArg::HalfSine => Interslice::HalfSine,
            IntersliceArg::Constant => Interslice::Constant,
        };
        Some(match method {
            MethodArg::MorgensternPrice => Method::MorgensternPrice(interslice),
            MethodArg::Spencer => Method::Spencer,
            MethodArg::Bishop => Method::Bishop,
            MethodArg::Janbu => Method::Janbu,
            MethodArg::Ordinary => Method::Ordinary,
            MethodArg::Srm => return None,
        })
    }

    /// The library's limit-equilibrium options (method: Morgenstern–Price
    /// unless `method` names another).
    pub fn options(
        &self,
        method: MethodArg,
    ) -> anyhow::Result<a3d_init::pipeline::stability::slope::LeOptions> {
        use a3d_init::slope::{CircleSearch, SearchSettings, Suction};
        let range = |t: &Option<String>, flag: &str| -> anyhow::Result<Option<(f64, f64)>> {
            t.as_deref()
                .map(|t| numbers::<2>(t, flag).map(|[a, b]| (a.min(b), a.max(b))))
                .transpose()
        };
        let circles = match self.search {
            SearchArg::EntryExit => CircleSearch::EntryExit {
                entry: range(&self.entry, "--entry")?,
                exit: range(&self.exit, "--exit")?,
            },
            SearchArg::Grid => CircleSearch::Grid {
                centres: self
                    .grid
                    .as_deref()
                    .map(|t| numbers::<4>(t, "--grid"))
                    .transpose()?,
                tangents: range(&self.tangents, "--tangents")?,
            },
        };
        if self.trials == 0 {
            bail!("--trials must be at least 1");
        }
        if self.phi_b.is_some() && self.suction != SuctionArg::PhiB {
            bail!("--phi-b applies with --suction phi-b");
        }
        let defaults = a3d_init::pipeline::stability::slope::LeOptions::default();
        Ok(a3d_init::pipeline::stability::slope::LeOptions {
            method: self.method(method).unwrap_or(defaults.method),
            suction: match self.suction {
                SuctionArg::Bishop => Suction::Bishop,
                SuctionArg::PhiB => Suction::PhiB(self.phi_b),
                SuctionArg::None => Suction::Ignored,
            },
            search: SearchSettings {
                circles,
                trials: self.trials,
                refine: !self.no_refine,
                ..SearchSettings::default()
            },
            n_slices: self.slices,
            min_depth: self.min_depth,
            h: self.h,
            ..defaults
        })
    }
}
