//! From a `.vtu`'s arrays to FEM nodes in the model's convention: which array
//! plays which role, units (a VTU has none: m and Pa unless told), signs (OGS:
//! pressure positive in compression, stresses tension positive), the
//! Taylor–Hood pressure (corners only), effective stress made total, and
//! `MaterialIDs` as regions (a node on a material interface is a data point
//! of each material it touches, so nothing is smoothed across materials).

use std::collections::BTreeMap;
use std::path::Path;

use super::decode::values;
use super::mesh::{self, Mesh};
use super::options::{Chi, Role, StressRule};
use super::xml::{self, ArrayTag, VtuXml};
use super::{ArrayInfo, VtuOptions, VtuReport};
use crate::error::{FormatError, ParseError};
use crate::extent::{far_outlier, first_coincident};
use crate::fem::{ColumnReport, FemReadReport, SignConvention};
use crate::fem_csv::unit_factor;
use a3d_model::{FemNodes, Quantity, StressComponent};

/// The arrays of `xml` with where they are, for the report.
fn array_list(xml: &VtuXml) -> Vec<(&ArrayTag, &'static str)> {
    xml.point_data
        .iter()
        .map(|t| (t, "point"))
        .chain(xml.cell_data.iter().map(|t| (t, "cell")))
        .collect()
}

/// The array for `role`: the one named in `explicit`, else OGS's name.
fn find<'a>(
    path: &Path,
    xml: &'a VtuXml,
    role: Role,
    explicit: &[(Role, String)],
) -> Result<Option<&'a ArrayTag>, ParseError> {
    let list = if role == Role::Region {
        &xml.cell_data
    } else {
        &xml.point_data
    };
    if let Some((_, name)) = explicit.iter().find(|(r, _)| *r == role) {
        return match list.iter().find(|t| &t.name == name) {
            Some(t) => Ok(Some(t)),
            None => Err(ParseError::new(
                path,
                xml.points.at,
                format!(
                    "no {} array `{name}` for {} (arrays: {})",
                    if role == Role::Region {
                        "cell"
                    } else {
                        "point"
                    },
                    role.name(),
                    names(list)
                ),
            )),
        };
    }
    Ok(role
        .ogs_names()
        .iter()
        .find_map(|n| list.iter().find(|t| t.name == *n)))
}

fn names(list: &[ArrayTag]) -> String {
    if list.is_empty() {
        return "none".into();
    }
    list.iter()
        .map(|t| format!("`{}`", t.name))
        .collect::<Vec<_>>()
        .join(", ")
}

fn factor(unit: &Option<String>, length: bool, default: &str) -> (f64, String, bool) {
    match unit {
        Some(u) => (unit_factor(u, length).unwrap_or(1.0), u.clone(), false),
        None => (
            unit_factor(default, length).unwrap_or(1.0),
            default.into(),
            true,
        ),
    }
}

/// The stress components of `tag`'s tuples, in the model's order
/// (xx, yy, zz, xy, yz, xz; 2D: the first four).
fn stress_layout(path: &Path, tag: &ArrayTag, dim: usize) -> Result<Vec<usize>, ParseError> {
    // Index into the tuple for each of xx, yy, zz, xy, yz, xz.
    let full = |n: usize| match n {
        // OGS (no Kelvin factor in its output): [xx, yy, zz, xy] and
        // [xx, yy, zz, xy, yz, xz].
        4 => Some(vec![0, 1, 2, 3]),
        6 => Some(vec![0, 1, 2, 3, 4, 5]),
        // A full 3×3 tensor, row-major.
        9 => Some(vec![0, 4, 8, 1, 5, 2]),
        _ => None,
    };
    let layout = full(tag.components).filter(|l| dim == 2 || l.len() == 6);
    layout.map(|l| l[..if dim == 2 { 4 } else { 6 }].to_vec()).ok_or_else(|| {
        ParseError::new(
            path,
            tag.at,
            format!(
                "stress array `{}` has {} components; expected {} ([xx, yy, zz, xy{}]) or 9 (a 3×3 tensor)",
                tag.name,
                tag.components,
                if dim == 2 { 4 } else { 6 },
                if dim == 2 { "" } else { ", yz, xz" }
            ),
        )
    })
}

fn scalar_array(path: &Path, tag: &ArrayTag, role: Role) -> Result<(), ParseError> {
    if tag.components == 1 {
        return Ok(());
    }
    Err(ParseError::new(
        path,
        tag.at,
        format!(
            "{} array `{}` has {} components; expected 1",
            role.name(),
            tag.name,
            tag.components
        ),
    ))
}

/// Reads the FEM nodes of one `.vtu` held in `bytes`.
pub fn read(
    path: &Path,
    bytes: &[u8],
    options: &VtuOptions,
) -> Result<(FemNodes, FemReadReport), FormatError> {
    let xml = xml::parse(path, bytes)?;
    let (length, length_unit, length_assumed) = factor(&options.units.length, true, "m");
    let (pressure, pressure_unit, pressure_assumed) = factor(&options.units.pressure, false, "Pa");
    let sign = options.sign.unwrap_or(SignConvention::Ogs);
    let mesh = mesh::read(path, bytes, &xml, length)?;
    let dim = mesh.dim;
    let n = xml.n_points;
    let explicit = &options.arrays;
    let mut used: BTreeMap<String, String> = BTreeMap::new();
    let mut columns = Vec::new();
    let mut notes = mesh.notes.clone();
    let mut warnings = Vec::new();

    // Pore pressure.
    let mut pwp: Option<Vec<f64>> = None;
    if let Some(tag) = find(path, &xml, Role::Pwp, explicit)? {
        scalar_array(path, tag, Role::Pwp)?;
        let mut p = values(path, bytes, &xml, tag, n)?;
        if tag.name == "pressure_interpolated" {
            notes.push(
                "pwp from `pressure_interpolated` (OGS's pressure interpolated to every node)"
                    .into(),
            );
        }
        taylor_hood(&mesh, &mut p, &tag.name, &mut notes);
        let f = pressure * sign.pwp_sign();
        p.iter_mut().for_each(|v| *v *= f);
        used.insert(tag.name.clone(), "pwp".into());
        columns.push(column(
            &tag.name,
            "pwp",
            &pressure_unit,
            pressure_assumed,
            pressure,
            sign.pwp_sign(),
        ));
        pwp = Some(p);
    }

    // Saturation (for Bishop's χ).
    let saturation = match find(path, &xml, Role::Saturation, explicit)? {
        Some(tag) => {
            scalar_array(path, tag, Role::Saturation)?;
            Some((tag.name.clone(), values(path, bytes, &xml, tag, n)?))
        }
        None => None,
    };

    // Stress, made total.
    let mut stress: Vec<(StressComponent, Vec<f64>)> = Vec::new();
    let mut stress_rule = None;
    if let Some(tag) = find(path, &xml, Role::Stress, explicit)? {
        let layout = stress_layout(path, tag, dim)?;
        let raw = values(path, bytes, &xml, tag, n)?;
        let f = pressure * sign.stress_sign();
        for (k, &c) in layout.iter().enumerate() {
            let comp = StressComponent::ALL[k];
            let v: Vec<f64> = (0..n).map(|i| raw[i * tag.components + c] * f).collect();
            stress.push((comp, v));
        }
        let rule = match options.stress {
            StressRule::Auto if pwp.is_some() => StressRule::Effective {
                biot: 1.0,
                chi: Chi::Auto,
            },
            StressRule::Auto => StressRule::Total,
            rule => rule,
        };
        let text = make_total(
            path,
            tag,
            rule,
            &mut stress,
            pwp.as_deref(),
            saturation.as_ref(),
            n,
        )?;
        used.insert(tag.name.clone(), "stress".into());
        columns.push(column(
            &tag.name,
            "stress",
            &pressure_unit,
            pressure_assumed,
            pressure,
            sign.stress_sign(),
        ));
        stress_rule = Some(text);
    }
    if let Some((name, _)) = &saturation {
        used.insert(name.clone(), "saturation (Bishop's χ)".into());
    }
    if let Some(tag) = find(path, &xml, Role::Displacement, explicit)? {
        used.insert(tag.name.clone(), "displacement (listed; not mapped)".into());
    }
    if pwp.is_none() && stress.is_empty() {
        return Err(ParseError::new(
            path,
            xml.points.at,
            format!(
                "no pressure or stress array (point arrays: {}); name them in the column mapping (pwp=…, stress=…)",
                names(&xml.point_data)
            ),
        )
        .into());
    }

    // Regions from the material of each cell.
    let (materials, around) = regions(path, bytes, &xml, &mesh, explicit, &mut used)?;

    // The data points: every node of every cell, once per material around it.
    let mut nodes = FemNodes {
        dim,
        ..FemNodes::default()
    };
    let (order, regions) = data_points(path, &xml, &mesh, around.as_deref(), &mut notes)?;
    nodes.ids = order.iter().map(|&i| i as i64 + 1).collect();
    nodes.positions = order.iter().map(|&i| mesh.points[i]).collect();
    if around.is_some() {
        nodes.region = Some(regions);
    }
    if let Some(p) = &pwp {
        nodes
            .fields
            .push((Quantity::Pwp, order.iter().map(|&i| p[i]).collect()));
    }
    for (comp, v) in &stress {
        nodes.fields.push((
            Quantity::TotalStress(*comp),
            order.iter().map(|&i| v[i]).collect(),
        ));
    }
    if let Some(w) = magnitude_warning(&nodes, pressure_assumed, &pressure_unit) {
        warnings.push(w);
    }
    let vtu = VtuReport {
        units: units_text(
            &length_unit,
            length_assumed,
            &pressure_unit,
            pressure_assumed,
        ),
        stress_rule,
        notes,
        ..report(path, &xml, &mesh, &used, materials)
    };
    let report = vtu_fem_report(path, columns, &nodes, sign, warnings, vtu);
    Ok((nodes, report))
}

/// The `MaterialIDs` of the cells the mesh kept, as integers.
fn kept_cell_ids(
    path: &Path,
    tag: &ArrayTag,
    ids: &[f64],
    mesh: &Mesh,
) -> Result<Vec<i64>, ParseError> {
    if ids.len() != mesh.cells.len() {
        return Err(ParseError::new(
            path,
            tag.at,
            "one material per cell expected",
        ));
    }
    ids.iter()
        .enumerate()
        .map(|(c, &v)| {
            if v.fract() == 0.0 && v.abs() < 9e15 {
                Ok(v as i64)
            } else {
                Err(ParseError::new(
                    path,
                    tag.at,
                    format!("cell {}: material `{v}` is not an integer", c + 1),
                ))
            }
        })
        .collect()
}

/// The Taylor–Hood rule: on quadratic cells, a pressure that is exactly zero
/// on every node that is no cell's corner (and not everywhere) was only
/// computed on the corners; those nodes get the corners' linear interpolation.
fn taylor_hood(mesh: &Mesh, p: &mut [f64], name: &str, notes: &mut Vec<String>) {
    if !mesh.has_quadratic() {
        return;
    }
    let corner = mesh.corners();
    let used = mesh.used();
    let mid: Vec<usize> = (0..p.len()).filter(|&i| used[i] && !corner[i]).collect();
    let all_zero = mid.iter().all(|&i| p[i] == 0.0);
    let some_corner = (0..p.len()).any(|i| corner[i] && p[i] != 0.0);
    if !mid.is_empty() && all_zero && some_corner {
        let filled = mesh.fill_linear(p, &corner);
        notes.push(format!(
            "`{name}` is zero on all {filled} mid-edge nodes of the quadratic cells (Taylor–Hood: OGS computes the pressure on the corners); they take the linear interpolation of their cell's corners"
        ));
    }
}

/// χ per node for the rule, and its description.
fn chi_of(
    chi: Chi,
    saturation: Option<&(String, Vec<f64>)>,
    n: usize,
) -> Result<(Option<Vec<f64>>, String), String> {
    let of_s = |m: f64, s: &(String, Vec<f64>)| -> Vec<f64> {
        s.1.iter().map(|v| v.clamp(0.0, 1.0).powf(m)).collect()
    };
    let needs = || "χ from the saturation, but there is no saturation array".to_string();
    Ok(match chi {
        Chi::One => (None, "1".into()),
        Chi::Auto => match saturation {
            Some(s) => (
                Some(of_s(1.0, s)),
                format!("S from `{}` (OGS's BishopsPowerLaw, exponent 1)", s.0),
            ),
            None => (None, "1 (no saturation array: saturated)".into()),
        },
        Chi::Saturation => {
            let s = saturation.ok_or_else(needs)?;
            (Some(of_s(1.0, s)), format!("S from `{}`", s.0))
        }
        Chi::SaturationPower(m) => {
            let s = saturation.ok_or_else(needs)?;
            (Some(of_s(m, s)), format!("S^{m} from `{}`", s.0))
        }
    })
    .map(|(v, t)| (v.filter(|v| v.len() == n), t))
}

fn column(
    name: &str,
    role: &str,
    unit: &str,
    assumed: bool,
    factor: f64,
    sign: f64,
) -> ColumnReport {
    ColumnReport {
        header: name.to_string(),
        understood_as: role.to_string(),
        unit: Some(if assumed {
            format!("{unit} (assumed)")
        } else {
            unit.to_string()
        }),
        factor,
        sign_flipped: sign < 0.0,
    }
}

fn units_text(
    length: &str,
    length_assumed: bool,
    pressure: &str,
    pressure_assumed: bool,
) -> String {
    let tag = |assumed: bool| if assumed { "assumed" } else { "given" };
    format!(
        "length {length} ({}), pressure and stress {pressure} ({}); a VTU carries no units (give the FEM units)",
        tag(length_assumed),
        tag(pressure_assumed)
    )
}

/// A warning when the pressures and stresses are far from what gravity makes
/// over the model's height (ρw·g·H): 100 times smaller suggests the file is
/// in kPa though Pa was taken, 100 times larger the other way round.
fn magnitude_warning(nodes: &FemNodes, assumed: bool, unit: &str) -> Option<String> {
    let (lo, hi) = nodes
        .positions
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p[1]), b.max(p[1]))
        });
    let height = hi - lo;
    let largest = nodes
        .fields
        .iter()
        .flat_map(|(_, v)| v.iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let scale = a3d_model::gamma_water(a3d_model::DEFAULT_GRAVITY) * height;
    if !(height > 0.0 && largest > 0.0) {
        return None;
    }
    let how = if assumed { "assumed" } else { "given" };
    if largest < 1e-2 * scale {
        Some(format!(
            "the largest |pressure| or |stress| is {largest:.3e} kPa with the file in {unit} ({how}), 100× below ρw·g·H = {scale:.3} kPa over the model's {height:.3} m: is the file in kPa? (the FEM units pressure=kPa)"
        ))
    } else if largest > 1e2 * scale && unit.eq_ignore_ascii_case("kPa") {
        Some(format!(
            "the largest |pressure| or |stress| is {largest:.3e} kPa with the file in kPa ({how}), 100× above ρw·g·H = {scale:.3} kPa over the model's {height:.3} m: is the file in Pa? (drop pressure=kPa from the FEM units)"
        ))
    } else {
        None
    }
}

fn info(tag: &ArrayTag, location: &'static str, used_as: Option<String>) -> ArrayInfo {
    ArrayInfo {
        name: tag.name.clone(),
        location,
        components: tag.components,
        scalar: tag.scalar.name(),
        used_as: used_as.unwrap_or_else(|| "not used".into()),
    }
}

/// What `inspect` shows of one `.vtu` (nothing converted).
pub fn describe(path: &Path, bytes: &[u8]) -> Result<VtuReport, FormatError> {
    let xml = xml::parse(path, bytes)?;
    let mesh = mesh::read(path, bytes, &xml, 1.0)?;
    let mut used: BTreeMap<String, String> = BTreeMap::new();
    for role in Role::ALL {
        if let Some(tag) = find(path, &xml, role, &[])? {
            used.insert(tag.name.clone(), role.name().to_string());
        }
    }
    let mut materials = Vec::new();
    if let Some(tag) = find(path, &xml, Role::Region, &[])? {
        let ids = values(path, bytes, &xml, tag, xml.n_cells)?;
        let ids = kept_cell_ids(path, tag, &ids, &mesh)?;
        materials = material_counts(&ids);
    }
    Ok(VtuReport {
        units: units_text("m", true, "Pa", true),
        notes: mesh.notes.clone(),
        ..report(path, &xml, &mesh, &used, materials)
    })
}

/// Cell counts per `MaterialIDs` value, by value.
fn material_counts(ids: &[i64]) -> Vec<(i64, usize)> {
    let mut counts: BTreeMap<i64, usize> = BTreeMap::new();
    for &id in ids {
        *counts.entry(id).or_default() += 1;
    }
    counts.into_iter().collect()
}

/// What the file holds (encoding, cells, materials, arrays and the role each
/// was read as); units, stress rule and notes left for the caller.
fn report(
    path: &Path,
    xml: &VtuXml,
    mesh: &Mesh,
    used: &BTreeMap<String, String>,
    materials: Vec<(i64, usize)>,
) -> VtuReport {
    VtuReport {
        file: path.to_path_buf(),
        series: None,
        encoding: xml.encoding.clone(),
        cells: mesh
            .kinds
            .iter()
            .map(|(k, c)| (k.name().to_string(), *c))
            .collect(),
        materials,
        arrays: array_list(xml)
            .into_iter()
            .map(|(t, location)| info(t, location, used.get(&t.name).cloned()))
            .collect(),
        units: String::new(),
        stress_rule: None,
        notes: Vec::new(),
    }
}

/// The data points of the mesh: every node that a cell uses, once per
/// material around it (`around`: the materials of the cells at each node),
/// as (node index, region) in node order; a node far outside the others or
/// two at one place are errors.
fn data_points(
    path: &Path,
    xml: &VtuXml,
    mesh: &mesh::Mesh,
    around: Option<&[Vec<i64>]>,
    notes: &mut Vec<String>,
) -> Result<(Vec<usize>, Vec<String>), ParseError> {
    let n = xml.n_points;
    let in_cells = mesh.used();
    let mut order = Vec::new();
    let mut regions = Vec::new();
    let mut shared = 0;
    for i in (0..n).filter(|&i| in_cells[i]) {
        match around {
            Some(around) => {
                if around[i].len() > 1 {
                    shared += 1;
                }
                for id in &around[i] {
                    order.push(i);
                    regions.push(format!("mat{id}"));
                }
            }
            None => order.push(i),
        }
    }
    if shared > 0 {
        notes.push(format!(
            "{shared} nodes lie on an interface between materials: each is a data point of every material it touches"
        ));
    }
    let distinct: Vec<[f64; 3]> = (0..n)
        .filter(|&i| in_cells[i])
        .map(|i| mesh.points[i])
        .collect();
    if let Some(far) = far_outlier(&distinct) {
        return Err(ParseError::new(path, xml.points.at, far.to_string()));
    }
    if let Some((a, _)) = first_coincident(&distinct) {
        let p = distinct[a];
        return Err(ParseError::new(
            path,
            xml.points.at,
            format!(
                "two mesh nodes at the same place ({}, {}, {}): a3d-init takes each node as one data point",
                p[0], p[1], p[2]
            ),
        ));
    }
    Ok((order, regions))
}

/// The count of cells of each material id, and the material ids around each
/// node (`None` without a material array).
type CellRegions = (Vec<(i64, usize)>, Option<Vec<Vec<i64>>>);

/// The regions of the cells from their material array (`mat<id>`): the
/// count of cells of each material, and the materials around each node.
fn regions(
    path: &Path,
    bytes: &[u8],
    xml: &VtuXml,
    mesh: &mesh::Mesh,
    explicit: &[(Role, String)],
    used: &mut BTreeMap<String, String>,
) -> Result<CellRegions, ParseError> {
    let Some(tag) = find(path, xml, Role::Region, explicit)? else {
        return Ok((Vec::new(), None));
    };
    scalar_array(path, tag, Role::Region)?;
    let ids = values(path, bytes, xml, tag, xml.n_cells)?;
    let ids = kept_cell_ids(path, tag, &ids, mesh)?;
    used.insert(tag.name.clone(), "region (mat<id>)".into());
    Ok((material_counts(&ids), Some(mesh.around(&ids))))
}

/// The reader's report of a `.vtu`: no CSV dialect, coordinates always.
fn vtu_fem_report(
    path: &Path,
    columns: Vec<ColumnReport>,
    nodes: &FemNodes,
    sign: SignConvention,
    warnings: Vec<String>,
    vtu: VtuReport,
) -> FemReadReport {
    FemReadReport {
        path: path.to_path_buf(),
        delimiter: String::new(),
        decimal_comma: false,
        bom: false,
        header_line: 0,
        columns,
        nodes: nodes.len(),
        dim: nodes.dim,
        sign,
        has_coordinates: true,
        warnings,
        vtu: Some(vtu),
    }
}

/// Makes the stress `stress` total by `rule`: an effective stress gains
/// α·χ·pwp on its normal components (χ from `saturation` or as given); a
/// total one is taken as it is. Returns the rule in words for the report.
fn make_total(
    path: &Path,
    tag: &ArrayTag,
    rule: StressRule,
    stress: &mut [(StressComponent, Vec<f64>)],
    pwp: Option<&[f64]>,
    saturation: Option<&(String, Vec<f64>)>,
    n: usize,
) -> Result<String, ParseError> {
    let text = match rule {
        StressRule::Effective { biot, chi } => {
            let Some(p) = pwp else {
                return Err(ParseError::new(
                    path,
                    tag.at,
                    format!(
                        "`{}` is an effective stress, but there is no pressure array to make it total",
                        tag.name
                    ),
                ));
            };
            let (chi_values, chi_text) =
                chi_of(chi, saturation, n).map_err(|m| ParseError::new(path, tag.at, m))?;
            for (_, v) in stress.iter_mut().filter(|(c, _)| c.is_normal()) {
                for i in 0..n {
                    v[i] += biot * chi_values.as_ref().map_or(1.0, |c| c[i]) * p[i];
                }
            }
            format!(
                "`{}` is effective (OGS's HydroMechanics and RichardsMechanics write σ′): total σ = σ′ − α·χ·p·I in OGS's signs, i.e. σ′ + α·χ·pwp on the normal components in Anura3D's, with α = {biot} and χ = {chi_text}",
                tag.name
            )
        }
        _ => format!("`{}` is taken as total stress", tag.name),
    };
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn column(largest_kpa: f64) -> FemNodes {
        FemNodes {
            dim: 2,
            ids: vec![1, 2],
            positions: vec![[0.0; 3], [0.0, 10.0, 0.0]],
            region: None,
            fields: vec![(Quantity::Pwp, vec![0.0, -largest_kpa])],
        }
    }

    #[test]
    fn magnitudes_far_from_the_weight_of_water_are_questioned() {
        // 10 m of model: ρw·g·H ≈ 98 kPa.
        assert_eq!(magnitude_warning(&column(98.1), true, "Pa"), None);
        // A file in kPa read as Pa: 0.098 kPa.
        let w = magnitude_warning(&column(0.0981), true, "Pa").unwrap();
        assert!(
            w.contains("is the file in kPa?") && w.contains("(assumed)"),
            "{w}"
        );
        // A file in Pa read as kPa: 98 100 kPa.
        let w = magnitude_warning(&column(98_100.0), false, "kPa").unwrap();
        assert!(w.contains("is the file in Pa?"), "{w}");
        // All zero (an initial state): nothing to judge.
        assert_eq!(magnitude_warning(&column(0.0), true, "Pa"), None);
    }
}
