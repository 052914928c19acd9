//! The region → material map (`region=material,…`, the CLI's
//! `--material-map`): which GOM material each FEM region (the FEM file's
//! region column) belongs to. A material is given by its 1-based index or its
//! name (any ASCII case).
//!
//! Strict, in two steps. Reading the text ([`MaterialMap`]'s `FromStr`)
//! refuses an empty entry list, a pair without exactly one `=`, an empty side
//! and a region named twice; [`MaterialMap::resolve`] then refuses a region the
//! FEM file does not have, a material the GOM does not have, and a map given
//! for a FEM file without regions. Every error carries the column of the
//! offending entry. Resolving the regions the map does not name stays with the
//! caller.

use std::fmt;
use std::str::FromStr;

use a3d_model::Material;
use a3d_model::material::lookup;

/// A problem in the map's text, at a 1-based character column.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("column {column}: {message}")]
pub struct MaterialMapError {
    pub column: usize,
    pub message: String,
}

/// A GOM material as a user names it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MaterialRef {
    /// Its 1-based index in the GOM's material block.
    Index(u32),
    /// Its name (any ASCII case).
    Name(String),
}

impl MaterialRef {
    /// Reads `text` (trimmed): an unsigned integer is an index, anything else
    /// a name.
    pub fn parse(text: &str) -> MaterialRef {
        let text = text.trim();
        text.parse::<u32>()
            .map_or_else(|_| MaterialRef::Name(text.to_string()), MaterialRef::Index)
    }

    /// The index of the material this names among `materials`: an index in
    /// range, else a material of that name.
    pub fn resolve(&self, materials: &[Material]) -> Option<u32> {
        let text = self.to_string();
        lookup::by_number(materials, &text).or_else(|| lookup::by_name(materials, &text))
    }
}

impl fmt::Display for MaterialRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MaterialRef::Index(i) => write!(f, "{i}"),
            MaterialRef::Name(name) => f.write_str(name),
        }
    }
}

/// One `region=material` pair.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MaterialMapEntry {
    /// The FEM region, as its region column spells it.
    pub region: String,
    pub material: MaterialRef,
    /// The 1-based character column where the pair starts in the text it was
    /// read from (for messages).
    pub column: usize,
}

/// FEM region → GOM material, in the order given; no region twice.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MaterialMap {
    pub entries: Vec<MaterialMapEntry>,
}

fn err(column: usize, message: String) -> MaterialMapError {
    MaterialMapError { column, message }
}

impl FromStr for MaterialMap {
    type Err = MaterialMapError;

    /// Reads `region=material,…`; empty pairs (`a=1,,b=2`) are skipped.
    fn from_str(spec: &str) -> Result<MaterialMap, MaterialMapError> {
        let mut entries = Vec::new();
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
            entries.push((r, m, column));
        }
        MaterialMap::from_entries(entries)
    }
}

impl MaterialMap {
    /// A map from (region, material) pairs, a front end's structured form:
    /// names may hold `,` and `=`, and an entry's column is its 1-based place
    /// in the list.
    pub fn from_pairs<K: AsRef<str>, V: AsRef<str>>(
        pairs: &[(K, V)],
    ) -> Result<MaterialMap, MaterialMapError> {
        let mut entries = Vec::with_capacity(pairs.len());
        for (k, (r, m)) in pairs.iter().enumerate() {
            let (r, m) = (r.as_ref().trim(), m.as_ref().trim());
            if r.is_empty() || m.is_empty() {
                return Err(err(
                    k + 1,
                    format!("`{r}`: `{m}`: expected a region and a material, both given"),
                ));
            }
            entries.push((r, m, k + 1));
        }
        MaterialMap::from_entries(entries)
    }

    /// The map of (region, material, column) entries: a region mapped twice,
    /// or none at all, is an error.
    fn from_entries(given: Vec<(&str, &str, usize)>) -> Result<MaterialMap, MaterialMapError> {
        let mut entries: Vec<MaterialMapEntry> = Vec::with_capacity(given.len());
        for (r, m, column) in given {
            if entries.iter().any(|e| e.region == r) {
                return Err(err(column, format!("region `{r}` is mapped twice")));
            }
            entries.push(MaterialMapEntry {
                region: r.to_string(),
                material: MaterialRef::parse(m),
                column,
            });
        }
        if entries.is_empty() {
            return Err(err(1, "no region=material pair".into()));
        }
        Ok(MaterialMap { entries })
    }

    /// Checks the map against the GOM `materials` and the FEM `regions`
    /// (`None` when the FEM file has no region column). Returns (region,
    /// material index) pairs in the map's order.
    pub fn resolve(
        &self,
        materials: &[Material],
        regions: Option<&[String]>,
    ) -> Result<Vec<(String, u32)>, MaterialMapError> {
        let Some(regions) = regions else {
            return Err(err(
                1,
                "the FEM file has no region column, so there is nothing to map".into(),
            ));
        };
        let mut out: Vec<(String, u32)> = Vec::with_capacity(self.entries.len());
        for entry in &self.entries {
            let r = &entry.region;
            if !regions.iter().any(|x| x == r) {
                let mut known: Vec<&str> = regions.iter().map(String::as_str).collect();
                known.sort_unstable();
                known.dedup();
                known.truncate(20);
                return Err(err(
                    entry.column,
                    format!(
                        "the FEM file has no region `{r}` (regions: {})",
                        known.join(", ")
                    ),
                ));
            }
            let index = entry.material.resolve(materials).ok_or_else(|| {
                err(
                    entry.column,
                    format!(
                        "no GOM material `{}` (materials: {})",
                        entry.material,
                        lookup::list(materials)
                    ),
                )
            })?;
            out.push((r.clone(), index));
        }
        Ok(out)
    }
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

    fn resolve(spec: &str) -> Result<Vec<(String, u32)>, MaterialMapError> {
        let regions = vec!["a".to_string(), "b".to_string()];
        spec.parse::<MaterialMap>()?
            .resolve(&materials(), Some(&regions))
    }

    #[test]
    fn good_maps_resolve_by_index_or_name() {
        let map: MaterialMap = "a=2, b=CLAY".parse().unwrap();
        assert_eq!(
            map.entries,
            [
                MaterialMapEntry {
                    region: "a".into(),
                    material: MaterialRef::Index(2),
                    column: 1
                },
                MaterialMapEntry {
                    region: "b".into(),
                    material: MaterialRef::Name("CLAY".into()),
                    column: 5
                },
            ]
        );
        assert_eq!(
            resolve("a=2, b=CLAY").unwrap(),
            [("a".to_string(), 2), ("b".to_string(), 1)]
        );
    }

    /// Every refusal names its column: text that is not a map (when parsed),
    /// and regions or materials that do not exist (when resolved).
    #[test]
    fn refusals_name_their_column() {
        let parsed = [
            ("", 1, "no region=material pair"),
            (",,", 1, "no region=material pair"),
            ("a", 1, "expected region=material"),
            ("a=1,=2", 5, "both sides"),
            ("a=1,b=", 5, "both sides"),
            ("a=1=2", 1, "expected region=material"),
            ("a=1,a=2", 5, "mapped twice"),
            ("a=1, é=2,é=1", 10, "region `é` is mapped twice"),
        ];
        let resolved = [
            ("a=1,zz=2", 5, "no region `zz`"),
            ("b=0", 1, "no GOM material `0`"),
            ("b=3", 1, "no GOM material `3`"),
            ("b=\u{0}\u{ff}", 1, "no GOM material"),
        ];
        let parse = |spec: &str| spec.parse::<MaterialMap>().unwrap_err();
        let cases = parsed.iter().map(|c| (c, parse(c.0)));
        for ((spec, column, text), e) in
            cases.chain(resolved.iter().map(|c| (c, resolve(c.0).unwrap_err())))
        {
            assert_eq!(e.column, *column, "{spec}: {e}");
            assert!(e.message.contains(text), "{spec}: {e}");
        }
        let map: MaterialMap = "a=1".parse().unwrap();
        assert_eq!(map.resolve(&materials(), None).unwrap_err().column, 1);
    }
}
