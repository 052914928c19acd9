//! Options of the reader ([`CsvOptions`]: explicit columns, unit overrides,
//! sign convention) and the parsers of the `--columns` and `--fem-units`
//! command-line values.

use super::headers::{Field, unit_factor};
use crate::fem::{SignConvention, UnitOverride};

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
    let pairs = crate::lex::key_value_pairs(s, "field=header")?;
    columns_from_pairs(&pairs)
}

/// A column mapping from (field, header) pairs (a front end's structured
/// form: headers may hold `,` and `=`). A field given twice, or a header given
/// to two fields, is an error.
pub fn columns_from_pairs<K: AsRef<str>, V: AsRef<str>>(
    pairs: &[(K, V)],
) -> Result<Vec<(Field, String)>, String> {
    let columns = pairs
        .iter()
        .map(|(k, v)| {
            let k = k.as_ref();
            let field = Field::from_name(k).ok_or_else(|| {
                format!("`{k}`: unknown field (known: x y z node region pwp sxx syy szz sxy syz sxz esxx esyy eszz)")
            })?;
            Ok((field, v.as_ref().to_string()))
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
    let mut length = None;
    let mut pressure = None;
    for (k, v) in crate::lex::key_value_pairs(s, "length=… or pressure=…")? {
        match k {
            "length" => length = Some(v),
            "pressure" => pressure = Some(v),
            other => return Err(format!("`{other}`: expected length or pressure")),
        }
    }
    units_from(length, pressure)
}

/// Unit overrides from their parts; an unknown unit is an error.
pub fn units_from(length: Option<&str>, pressure: Option<&str>) -> Result<UnitOverride, String> {
    let mut out = UnitOverride::default();
    if let Some(v) = length {
        if unit_factor(v, true).is_none() {
            return Err(format!("unknown unit `{v}` for length"));
        }
        out.length = Some(v.trim().into());
    }
    if let Some(v) = pressure {
        if unit_factor(v, false).is_none() {
            return Err(format!("unknown unit `{v}` for pressure"));
        }
        out.pressure = Some(v.trim().into());
    }
    Ok(out)
}
