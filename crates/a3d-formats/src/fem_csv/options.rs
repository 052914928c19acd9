//! Options of the reader ([`CsvOptions`]: explicit columns, unit overrides,
//! sign convention) and the parsers of the `--columns` and `--fem-units`
//! command-line values.

use super::headers::{Field, unit_factor};

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

/// Options of the reader.
#[derive(Clone, Debug, Default)]
pub struct CsvOptions {
    /// Explicit field → header mapping; wins over the synonym table.
    pub columns: Vec<(Field, String)>,
    pub units: UnitOverride,
    pub sign: SignConvention,
}

/// Parses `x=X (m),y=Y,pwp=PWP` into a column mapping. A field given twice, or a
/// header given to two fields, is an error.
pub fn parse_columns_option(s: &str) -> Result<Vec<(Field, String)>, String> {
    let columns = s
        .split(',')
        .filter(|p| !p.trim().is_empty())
        .map(|pair| {
            let (k, v) = pair.split_once('=').ok_or_else(|| format!("`{pair}`: expected field=header"))?;
            let field = Field::from_name(k.trim()).ok_or_else(|| {
                format!("`{k}`: unknown field (known: x y z node region pwp sxx syy szz sxy syz sxz esxx esyy eszz)")
            })?;
            Ok((field, v.trim().to_string()))
        })
        .collect::<Result<Vec<_>, String>>()?;
    check_columns_option(&columns)?;
    Ok(columns)
}

/// Refuses a column mapping that names a field twice or a header twice.
pub(super) fn check_columns_option(columns: &[(Field, String)]) -> Result<(), String> {
    for (k, (field, header)) in columns.iter().enumerate() {
        for (other_field, other_header) in &columns[..k] {
            if other_field == field {
                return Err(format!(
                    "the column mapping gives {} twice (`{other_header}` and `{header}`): name one header per field",
                    field.name()
                ));
            }
            if other_header == header {
                return Err(format!(
                    "the column mapping gives header `{header}` to both {} and {}: a column holds one field",
                    other_field.name(),
                    field.name()
                ));
            }
        }
    }
    Ok(())
}

/// Parses `length=ft,pressure=psf`.
pub fn parse_units_option(s: &str) -> Result<UnitOverride, String> {
    let mut out = UnitOverride::default();
    for pair in s.split(',').filter(|p| !p.trim().is_empty()) {
        let (k, v) = pair
            .split_once('=')
            .ok_or_else(|| format!("`{pair}`: expected length=… or pressure=…"))?;
        match k.trim() {
            "length" if unit_factor(v, true).is_some() => out.length = Some(v.trim().into()),
            "pressure" if unit_factor(v, false).is_some() => out.pressure = Some(v.trim().into()),
            "length" | "pressure" => return Err(format!("unknown unit `{v}` for {k}")),
            other => return Err(format!("`{other}`: expected length or pressure")),
        }
    }
    Ok(out)
}
