//! The contract every FEM reader keeps, whatever the format (CSV node tables,
//! GeoStudio `.gsz` steps, VTU/PVD results): the sign convention and unit
//! overrides it is given, the saved step it is asked for, and the report of
//! what it understood and converted ([`FemReadReport`]), which `inspect` and
//! `report.json` show. The readers (`fem_csv`, `gsz`, `fem_vtu`) import it;
//! none imports another for it.

use std::path::PathBuf;

/// Sign convention of the source.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, Default)]
pub enum SignConvention {
    /// Compression positive, pwp positive below the water table: every stress and
    /// the pwp are negated.
    #[default]
    GeoStudio,
    /// Already Anura3D's convention: kept.
    TensionPositive,
    /// OpenGeoSys: pore pressure positive in compression (negated), stresses
    /// tension positive (kept).
    Ogs,
}

impl SignConvention {
    /// The factor the pore pressure of a file in this convention is
    /// multiplied by (−1 or 1).
    pub fn pwp_sign(self) -> f64 {
        match self {
            SignConvention::GeoStudio | SignConvention::Ogs => -1.0,
            SignConvention::TensionPositive => 1.0,
        }
    }

    /// The factor its stresses are multiplied by (−1 or 1).
    pub fn stress_sign(self) -> f64 {
        match self {
            SignConvention::GeoStudio => -1.0,
            SignConvention::TensionPositive | SignConvention::Ogs => 1.0,
        }
    }
}

/// Unit overrides (`--fem-units length=ft,pressure=psf`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UnitOverride {
    pub length: Option<String>,
    pub pressure: Option<String>,
}

/// How one column was understood.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ColumnReport {
    pub header: String,
    /// Field name, or "ignored".
    pub understood_as: String,
    pub unit: Option<String>,
    pub factor: f64,
    pub sign_flipped: bool,
}

/// What the reader did, for `inspect --fem` and `report.json`.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FemReadReport {
    pub path: PathBuf,
    pub delimiter: String,
    pub decimal_comma: bool,
    pub bom: bool,
    /// 1-based line of the header.
    pub header_line: usize,
    pub columns: Vec<ColumnReport>,
    pub nodes: usize,
    pub dim: usize,
    pub sign: SignConvention,
    /// False for a GeoStudio `node.csv` (coordinates live in the mesh PLY).
    pub has_coordinates: bool,
    pub warnings: Vec<String>,
    /// What the VTU reader found (a `.vtu` or `.pvd`; the dialect fields
    /// above are then empty).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vtu: Option<VtuReport>,
}

/// Which step to read: a folder number, the last saved step, a time (s), or
/// the first saved step at which the slope fails.
#[derive(Clone, Debug, PartialEq)]
pub enum StepChoice {
    Number(u32),
    Last,
    Time(f64),
    /// The first saved step whose limit-equilibrium factor of safety is at
    /// most 1: found by `map` against the model
    /// (`a3d_init::pipeline::stability::failure`); a reader given it refuses it.
    Failure,
}

/// What a reader says of [`StepChoice::Failure`], which needs the model.
pub const FAILURE_NEEDS_MODEL: &str = "step `failure` is the first saved step at which the slope's factor of safety falls to 1: `map` finds it against the model; here give a step number, last or time=<time>";

impl std::str::FromStr for StepChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<StepChoice, String> {
        if s == "last" {
            return Ok(StepChoice::Last);
        }
        if s == "failure" {
            return Ok(StepChoice::Failure);
        }
        if let Some(t) = s.strip_prefix("time=") {
            // NaN, infinities and overflowing numbers (`1e400`) are refused:
            // no saved step is at such a time.
            return match parse_time(t) {
                Some(v) if v.is_finite() => Ok(StepChoice::Time(v)),
                Some(_) => Err(format!(
                    "`{s}`: the time must be a finite number of seconds"
                )),
                None => Err(format!(
                    "`{s}`: expected time=<number>[s|min|h|d] (seconds without a unit)"
                )),
            };
        }
        s.parse().map(StepChoice::Number).map_err(|_| {
            format!("`{s}`: expected a step number, last, time=<time>[s|min|h|d] or failure")
        })
    }
}

/// A time with an optional unit (`5616`, `5616s`, `93.6min`, `1.56h`, `0.065d`)
/// in seconds.
pub fn parse_time(text: &str) -> Option<f64> {
    let t = text.trim();
    if let Ok(seconds) = t.parse::<f64>() {
        return Some(seconds);
    }
    let split = t
        .find(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E')
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let factor = match unit.trim() {
        "" | "s" => 1.0,
        "min" => 60.0,
        "h" => 3600.0,
        "d" => 86400.0,
        _ => return None,
    };
    number.trim().parse::<f64>().ok().map(|v| v * factor)
}

/// One array of the file, as `inspect` and the report list it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ArrayInfo {
    pub name: String,
    /// `point` or `cell`.
    pub location: &'static str,
    pub components: usize,
    /// VTK's type name (`Float64`, …).
    pub scalar: &'static str,
    /// What a3d-init took it for (`pwp`, `stress`, …), or `not used`.
    pub used_as: String,
}

/// What the VTU reader found and did, in the FEM report.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct VtuReport {
    /// The `.vtu` read (the PVD's step file for a time series).
    pub file: PathBuf,
    /// The time series and the step taken from it, when read through a `.pvd`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub series: Option<SeriesStep>,
    /// How the arrays are encoded.
    pub encoding: String,
    /// Cell types and their counts.
    pub cells: Vec<(String, usize)>,
    /// `MaterialIDs` values and their cell counts.
    pub materials: Vec<(i64, usize)>,
    pub arrays: Vec<ArrayInfo>,
    /// The units taken for lengths and pressures, and whether they were assumed.
    pub units: String,
    /// The stress rule applied (effective → total), when a stress array was read.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stress_rule: Option<String>,
    /// What was derived or left out (Taylor–Hood, interface nodes, …).
    pub notes: Vec<String>,
}

/// The output taken from a `.pvd` time series.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SeriesStep {
    /// The `.pvd`.
    pub pvd: PathBuf,
    /// 0-based place in the series.
    pub step: usize,
    /// Outputs in the series.
    pub steps: usize,
    /// Time in s.
    pub time: f64,
    pub file: PathBuf,
}
