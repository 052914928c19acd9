//! The `--material-map region=material,…` option: which GOM material each FEM
//! region (the FEM file's region column) belongs to. A material is given by its
//! 1-based index or its name (any ASCII case).
//!
//! Strict: an empty entry list, a pair without exactly one `=`, an empty side,
//! a region named twice, a region the FEM file does not have, a material the GOM
//! does not have, or a map given for a FEM file without regions are all errors
//! with the column of the offending entry. Resolving the regions the map does
//! not name stays with the caller.

use crate::model::Material;
use crate::model::material::lookup;

/// A problem in the option text, at a 1-based character column.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("column {column}: {message}")]
pub struct MaterialMapError {
    pub column: usize,
    pub message: String,
}

/// Parses `spec` against the GOM `materials` and the FEM `regions` (`None` when
/// the FEM file has no region column). Returns (region, material index) pairs.
pub fn parse(
    spec: &str,
    materials: &[Material],
    regions: Option<&[String]>,
) -> Result<Vec<(String, u32)>, MaterialMapError> {
    let err = |column: usize, message: String| MaterialMapError { column, message };
    let Some(regions) = regions else {
        return Err(err(
            1,
            "the FEM file has no region column, so there is nothing to map".into(),
        ));
    };
    let mut out: Vec<(String, u32)> = Vec::new();
    let mut offset = 0;
    for pair in spec.split(',') {
        let column = spec[..offset].chars().count() + 1;
        offset += pair.len() + 1;
        if pair.trim().is_empty() {
            continue;
        }
        let mut parts = pair.split('=');
        let (Some(r), Some(m), None) = (parts.next(), parts.next(), parts.next()) else {
            return Err(err(column, format!("`{pair}`: expected region=material")));
        };
        let (r, m) = (r.trim(), m.trim());
        if r.is_empty() || m.is_empty() {
            return Err(err(
                column,
                format!("`{pair}`: expected region=material, with both sides given"),
            ));
        }
        if out.iter().any(|(seen, _)| seen == r) {
            return Err(err(column, format!("region `{r}` is mapped twice")));
        }
        if !regions.iter().any(|x| x == r) {
            let mut known: Vec<&str> = regions.iter().map(String::as_str).collect();
            known.sort_unstable();
            known.dedup();
            known.truncate(20);
            return Err(err(
                column,
                format!(
                    "the FEM file has no region `{r}` (regions: {})",
                    known.join(", ")
                ),
            ));
        }
        let index = lookup::by_number(materials, m)
            .or_else(|| lookup::by_name(materials, m))
            .ok_or_else(|| {
                err(
                    column,
                    format!(
                        "no GOM material `{m}` (materials: {})",
                        lookup::list(materials)
                    ),
                )
            })?;
        out.push((r.to_string(), index));
    }
    if out.is_empty() {
        return Err(err(1, "no region=material pair".into()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn materials() -> Vec<Material> {
        ["clay", "sand"]
            .iter()
            .enumerate()
            .map(|(k, name)| Material::new(k as u32 + 1, *name, "dry_material"))
            .collect()
    }

    #[test]
    fn good_maps_resolve_by_index_or_name() {
        let regions = vec!["a".to_string(), "b".to_string()];
        assert_eq!(
            parse("a=2, b=CLAY", &materials(), Some(&regions)).unwrap(),
            [("a".to_string(), 2), ("b".to_string(), 1)]
        );
    }

    #[test]
    fn garbage_is_refused_with_its_column() {
        let regions = vec!["a".to_string(), "b".to_string()];
        for (spec, column, text) in [
            ("", 1, "no region=material pair"),
            (",,", 1, "no region=material pair"),
            ("a", 1, "expected region=material"),
            ("a=1,=2", 5, "both sides"),
            ("a=1,b=", 5, "both sides"),
            ("a=1=2", 1, "expected region=material"),
            ("a=1,a=2", 5, "mapped twice"),
            ("a=1,zz=2", 5, "no region `zz`"),
            ("b=0", 1, "no GOM material `0`"),
            ("b=3", 1, "no GOM material `3`"),
            ("b=\u{0}\u{ff}", 1, "no GOM material"),
        ] {
            let e = parse(spec, &materials(), Some(&regions)).unwrap_err();
            assert_eq!(e.column, column, "{spec}: {e}");
            assert!(e.message.contains(text), "{spec}: {e}");
        }
        assert!(parse("a=1", &materials(), None).is_err());
    }
}
