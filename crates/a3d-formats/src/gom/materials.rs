//! The GOM's positional material block (`$$NUMBER_OF_MATERIALS` …).
//!
//! Anura3D reads every property as two lines, a name line it does not check and
//! a value line, in an order fixed by the material type and model. This reader
//! does the same: it walks the lines by position, fills the typed fields of
//! [`Material`] by position, keeps every (name, value) pair verbatim, and warns
//! where a name line differs from the keyword GiD writes at that position.

use crate::error::ParseError;
use crate::keyword_doc::KeywordDocument;
use crate::lex;
use a3d_model::{Material, RetentionCurve};

/// What a material's type contributes, in order, after the common head.
fn type_properties(material_type: &str) -> Option<&'static [&'static str]> {
    const SAT: &[&str] = &[
        "POROSITY_SOLID",
        "DENSITY_SOLID",
        "DENSITY_LIQUID",
        "K0_VALUE_SOLID",
    ];
    const COUPLED: &[&str] = &[
        "POROSITY_SOLID",
        "DENSITY_SOLID",
        "DENSITY_LIQUID",
        "INTRINSIC_PERMEABILITY_LIQUID",
        "BULK_MODULUS_LIQUID",
        "DYNAMIC_VISCOSITY_LIQUID",
        "K0_VALUE_SOLID",
    ];
    Some(match material_type {
        "dry_material" => &["POROSITY_SOLID", "DENSITY_SOLID", "K0_VALUE_SOLID"],
        "saturated_material_drained"
        | "saturated_material_undrained_effective"
        | "saturated_material_undrained_total" => SAT,
        "saturated_material_coupled" | "unsaturated_material_2phase_suction" => COUPLED,
        "unsaturated_material_3phase_coupled" => &[
            "POROSITY_SOLID",
            "DENSITY_SOLID",
            "DENSITY_LIQUID",
            "DENSITY_GAS",
            "INTRINSIC_PERMEABILITY_LIQUID",
            "INTRINSIC_PERMEABILITY_GAS",
            "BULK_MODULUS_LIQUID",
            "BULK_MODULUS_GAS",
            "DYNAMIC_VISCOSITY_LIQUID",
            "DYNAMIC_VISCOSITY_GAS",
            "SWELLING_INDEX",
            "K0_VALUE_SOLID",
        ],
        "liquid" => &[
            "DENSITY_LIQUID",
            "BULK_MODULUS_LIQUID",
            "DYNAMIC_VISCOSITY_LIQUID",
            "LIQUID_CAVITATION",
            "APPLY_DETECT_LIQUID_SURFACE",
        ],
        _ => return None,
    })
}

const KNOWN_TYPES: &str = "dry_material, saturated_material_drained, saturated_material_undrained_effective, \
saturated_material_undrained_total, saturated_material_coupled, unsaturated_material_2phase_suction, \
unsaturated_material_3phase_coupled, liquid";

/// Parameters of a constitutive model, in order. `undrained` adds the undrained
/// Poisson ratio after ν (only for `saturated_material_undrained_effective`).
fn model_parameters(model: &str, undrained: bool) -> Option<Vec<&'static str>> {
    let elastic: Vec<&str> = if undrained {
        vec!["YOUNG_MODULUS", "POISSON_RATIO", "POISSON_RATIO_UNDRAINED"]
    } else {
        vec!["YOUNG_MODULUS", "POISSON_RATIO"]
    };
    let mut p = match model {
        "linear_elasticity" => elastic,
        "mohr_coulomb" => {
            let mut p = elastic;
            p.extend([
                "FRICTION_ANGLE",
                "COHESION",
                "DILATANCY_ANGLE",
                "TENSILE_STRENGTH",
            ]);
            p
        }
        "strain_softening_mohr_coulomb" => {
            let mut p = elastic;
            p.extend([
                "PEAK_COHESION",
                "RESIDUAL_COHESION",
                "PEAK_FRICTION_ANGLE",
                "RESIDUAL_FRICTION_ANGLE",
                "PEAK_DILATANCY_ANGLE",
                "RESIDUAL_DILATANCY_ANGLE",
                "SHAPE_FACTOR",
            ]);
            p
        }
        "newtonian_liquid" => vec![],
        "bingham_liquid" => vec![
            "BINGHAM_YIELD_STRESS",
            "BINGHAM_YOUNG_MODULUS",
            "BINGHAM_POISSON_RATIO",
        ],
        "frictional_liquid" => vec![
            "FRICTIONAL_FRICTION_ANGLE",
            "FRICTIONAL_YOUNG_MODULUS",
            "FRICTIONAL_POISSON_RATIO",
        ],
        _ => return None,
    };
    p.shrink_to_fit();
    Some(p)
}

/// Keywords that certainly start a non-material GOM block: where an unknown
/// material model's parameters end.
pub(super) fn is_structural_keyword(keyword: &str) -> bool {
    keyword.starts_with("$$START")
        || keyword == "$$MATERIAL_INDEX"
        || keyword == "$$FINISH"
        || keyword == "$$DIMENSION"
        || keyword == "$$ELEMENTTYPE"
        || keyword.starts_with("$$PRESCRIBED")
        || keyword.starts_with("$$ABSORBING")
        || keyword.starts_with("$$BOUNDARY")
        || keyword.starts_with("$$INITIAL_")
        || keyword.ends_with("_CORNER_NODES")
        || keyword.starts_with("$$MOVING_MESH")
}

/// Keywords a material type's properties may carry on their name lines.
fn is_type_property(name: &str) -> bool {
    [
        "dry_material",
        "saturated_material_drained",
        "saturated_material_coupled",
        "unsaturated_material_3phase_coupled",
        "liquid",
    ]
    .iter()
    .filter_map(|t| type_properties(t))
    .any(|props| props.contains(&name))
}

/// Keywords a constitutive model's parameters may carry on their name lines.
fn is_model_parameter(name: &str) -> bool {
    [
        "linear_elasticity",
        "mohr_coulomb",
        "strain_softening_mohr_coulomb",
        "bingham_liquid",
        "frictional_liquid",
    ]
    .iter()
    .filter_map(|m| model_parameters(m, true))
    .any(|params| params.contains(&name))
}

/// Refuses a value Anura3D's material reader would stop on (its `Assert`s):
/// porosity and K0 outside [0, 1], a solid density ≤ 0, a bulk modulus ≤ 0,
/// and anything non-finite.
fn check_range(
    doc: &KeywordDocument,
    context: &str,
    prop: &str,
    v: f64,
    line: usize,
) -> Result<(), ParseError> {
    let bad = match prop {
        _ if !v.is_finite() => Some("must be a finite number"),
        "POROSITY_SOLID" if !(0.0..1.0).contains(&v) => {
            Some("must lie in [0, 1) (at 1 there is no solid)")
        }
        "K0_VALUE_SOLID" if !(0.0..=1.0).contains(&v) => Some("must lie in [0, 1]"),
        "YOUNG_MODULUS" if v <= 0.0 => Some("must be > 0"),
        "POISSON_RATIO" | "POISSON_RATIO_UNDRAINED" if !(v > -1.0 && v < 0.5) => {
            Some("must lie in (−1, 0.5)")
        }
        "FRICTION_ANGLE"
        | "PEAK_FRICTION_ANGLE"
        | "RESIDUAL_FRICTION_ANGLE"
        | "DILATANCY_ANGLE"
        | "PEAK_DILATANCY_ANGLE"
        | "RESIDUAL_DILATANCY_ANGLE"
            if !(0.0..90.0).contains(&v) =>
        {
            Some("must lie in [0°, 90°)")
        }
        "COHESION" | "PEAK_COHESION" | "RESIDUAL_COHESION" if v < 0.0 => Some("must be ≥ 0"),
        "DENSITY_SOLID" if v <= 0.0 => Some("must be > 0"),
        "DENSITY_LIQUID" | "DENSITY_GAS" if v < 0.0 => Some("must be ≥ 0"),
        "BULK_MODULUS_LIQUID" | "BULK_MODULUS_GAS" if v <= 0.0 => Some("must be > 0"),
        _ => None,
    };
    match bad {
        Some(why) => Err(doc.error_at(
            line,
            0,
            format!("{context}: {prop} = {v} {why}; Anura3D refuses this value, so no state is computed from it"),
        )),
        None => Ok(()),
    }
}

/// Reads one group of properties (a type's, or a model's parameters).
///
/// GiD writes each property's keyword on its name line. When the name lines
/// ahead are all keywords of this group (`known`) and name every property in
/// `expected`, the values are taken **by name**: files seen in the wild put
/// `$$BULK_MODULUS_LIQUID` before `$$K0_VALUE_SOLID`, and reading them by
/// position would turn a bulk modulus into K0. A differing order or an extra
/// property is warned. Otherwise the properties are read by position, as the
/// kernel of this snapshot does, warning where a name line differs.
fn read_properties<G>(
    cur: &mut Cursor<'_>,
    expected: &[&'static str],
    known: fn(&str) -> bool,
    get: &mut G,
    warnings: &mut Vec<String>,
    context: &str,
) -> Result<Vec<(&'static str, Pair)>, ParseError>
where
    G: FnMut(&mut Cursor<'_>, &str, bool, &mut Vec<String>) -> Result<Pair, ParseError>,
{
    // Look ahead at the name lines (every other non-blank line).
    let mut ahead = Cursor {
        doc: cur.doc,
        next: cur.next,
        end: cur.end,
    };
    let mut names: Vec<(String, usize)> = Vec::new();
    while let Some((line_no, line)) = ahead.peek_line() {
        let name = line.trim().trim_start_matches("$$").to_string();
        if !known(&name) || names.iter().any(|(n, _)| *n == name) {
            break;
        }
        ahead.next_line();
        if ahead.next_line().is_none() {
            break;
        }
        names.push((name, line_no));
    }
    let by_name =
        !expected.is_empty() && expected.iter().all(|e| names.iter().any(|(n, _)| n == e));
    let in_order =
        names.len() == expected.len() && names.iter().zip(expected).all(|((n, _), e)| n == e);
    if !by_name || in_order {
        return expected
            .iter()
            .map(|&prop| Ok((prop, get(cur, prop, true, warnings)?)))
            .collect();
    }
    let mut out = Vec::with_capacity(names.len());
    for (name, _) in &names {
        let pair = get(cur, name, false, warnings)?;
        if let Some(&prop) = expected.iter().find(|e| *e == name) {
            out.push((prop, pair));
        }
    }
    let listed: Vec<&str> = names.iter().map(|(n, _)| n.as_str()).collect();
    warnings.push(format!(
        "{}:{}: {context}: properties read by the names on their name lines ({}), not by Anura3D's positional order ({}); check that your Anura3D version reads them in this order",
        cur.doc.path().display(),
        names.first().map_or(0, |(_, l)| l + 1),
        listed.join(", "),
        expected.join(", ")
    ));
    Ok(out)
}

/// A cursor over the non-blank lines of the document.
struct Cursor<'d> {
    doc: &'d KeywordDocument,
    next: usize,
    end: usize,
}

impl<'d> Cursor<'d> {
    fn next_line(&mut self) -> Option<(usize, &'d str)> {
        while self.next < self.end {
            let i = self.next;
            self.next += 1;
            let line = self.doc.line(i);
            if !line.trim().is_empty() {
                return Some((i, line));
            }
        }
        None
    }

    fn peek_line(&self) -> Option<(usize, &'d str)> {
        let mut copy = Cursor {
            doc: self.doc,
            next: self.next,
            end: self.end,
        };
        copy.next_line()
    }
}

/// A (name line, value line) pair read by position.
struct Pair {
    name: String,
    value: String,
    value_line: usize,
}

/// Result of reading the material block.
pub struct MaterialBlock {
    pub materials: Vec<Material>,
    pub warnings: Vec<String>,
}

/// Reads the material block that starts at the `$$NUMBER_OF_MATERIALS` line `start`.
pub fn read_materials(
    doc: &KeywordDocument,
    start: usize,
    end: usize,
) -> Result<MaterialBlock, ParseError> {
    let mut cur = Cursor {
        doc,
        next: start + 1,
        end,
    };
    let (count_line, count_text) = cur.next_line().ok_or_else(|| {
        doc.error_at(
            start,
            0,
            "expected the number of materials after $$NUMBER_OF_MATERIALS",
        )
    })?;
    let first = lex::tokens(count_text).next().map(|(_, t)| t).unwrap_or("");
    let n = lex::parse_uint(first).ok_or_else(|| {
        doc.error_at(
            count_line,
            0,
            format!(
                "expected the number of materials, found `{}`",
                count_text.trim()
            ),
        )
    })? as usize;
    let mut warnings = Vec::new();
    // The count is checked against the block's lines, not trusted for allocation.
    let mut materials = Vec::with_capacity(n.min(end.saturating_sub(start)));

    let read_pair = |cur: &mut Cursor<'_>,
                     expected: &str,
                     what: &str|
     -> Result<(usize, String, usize, String), ParseError> {
        let (name_line, name) = cur.next_line().ok_or_else(|| {
            doc.error_at(
                end.saturating_sub(1),
                0,
                format!("material block ends early: expected {expected} ({what})"),
            )
        })?;
        let (value_line, value) = cur.next_line().ok_or_else(|| {
            doc.error_at(
                name_line,
                0,
                format!("expected a value line after `{}`", name.trim()),
            )
        })?;
        Ok((
            name_line,
            name.trim_end().to_string(),
            value_line,
            value.trim().to_string(),
        ))
    };

    for position in 1..=n {
        let mut pairs: Vec<(String, String)> = Vec::new();
        let mut get = |cur: &mut Cursor<'_>,
                       expected: &str,
                       warn: bool,
                       warnings: &mut Vec<String>|
         -> Result<Pair, ParseError> {
            let (name_line, name, value_line, value) = read_pair(
                cur,
                &format!("$${expected}"),
                &format!("material {position}"),
            )?;
            if warn && name.trim_start_matches("$$").trim() != expected {
                warnings.push(format!(
                    "{}:{}: material {position}: expected $${expected} at this position, found `{name}` (Anura3D reads materials by position, so the value is taken as {expected})",
                    doc.path().display(),
                    name_line + 1
                ));
            }
            pairs.push((name.clone(), value.clone()));
            Ok(Pair {
                name,
                value,
                value_line,
            })
        };
        let index_pair = get(&mut cur, "MATERIAL_INDEX", true, &mut warnings)?;
        let index = lex::parse_uint(&index_pair.value).ok_or_else(|| {
            doc.error_at(
                index_pair.value_line,
                0,
                format!("expected a material index, found `{}`", index_pair.value),
            )
        })?;
        if index as usize != position {
            return Err(doc.error_at(
                index_pair.value_line,
                0,
                format!("material index {index} at position {position}: Anura3D refers to materials by position, so the index must equal {position}"),
            ));
        }
        let name = get(&mut cur, "MATERIAL_NAME", true, &mut warnings)?.value;
        let context = format!("material {position} `{name}`");
        let type_pair = get(&mut cur, "MATERIAL_TYPE", true, &mut warnings)?;
        let material_type = type_pair.value.clone();
        let Some(props) = type_properties(&material_type) else {
            return Err(doc.error_at(
                type_pair.value_line,
                0,
                format!("unknown material type `{material_type}` (known: {KNOWN_TYPES})"),
            ));
        };
        let mut material = Material::new(position as u32, name, material_type.clone());
        let type_pairs = read_properties(
            &mut cur,
            props,
            is_type_property,
            &mut get,
            &mut warnings,
            &context,
        )?;
        apply_type_properties(doc, &context, &type_pairs, &mut material)?;
        read_model(
            doc,
            &mut cur,
            &mut get,
            &mut warnings,
            &mut material,
            position,
            &context,
        )?;
        if material.is_unsaturated() {
            read_water_curves(doc, &mut cur, &mut get, &mut warnings, &mut material)?;
        }
        // Everything after the head is kept verbatim.
        material.properties = pairs.split_off(3.min(pairs.len()));
        materials.push(material);
    }
    Ok(MaterialBlock {
        materials,
        warnings,
    })
}

/// A property's value as a number; an error names the property and the line.
fn real(doc: &KeywordDocument, p: &Pair) -> Result<f64, ParseError> {
    let tok = lex::tokens(&p.value).next().map(|(_, t)| t).unwrap_or("");
    lex::parse_real(tok).ok_or_else(|| {
        doc.error_at(
            p.value_line,
            0,
            format!(
                "expected a number for {}, found `{}`",
                p.name.trim(),
                p.value
            ),
        )
    })
}

/// The material type's properties that a3d-init uses (porosity, densities,
/// K0), each checked against its range.
fn apply_type_properties(
    doc: &KeywordDocument,
    context: &str,
    type_pairs: &[(&'static str, Pair)],
    material: &mut Material,
) -> Result<(), ParseError> {
    for (prop, p) in type_pairs {
        if *prop == "APPLY_DETECT_LIQUID_SURFACE" || *prop == "LIQUID_CAVITATION" {
            continue;
        }
        let v = real(doc, p)?;
        check_range(doc, context, prop, v, p.value_line)?;
        match *prop {
            "POROSITY_SOLID" => material.porosity = Some(v),
            "DENSITY_SOLID" => material.density_solid = Some(v),
            "DENSITY_LIQUID" => material.density_liquid = Some(v),
            "K0_VALUE_SOLID" => material.k0 = Some(v),
            _ => {}
        }
    }
    Ok(())
}

/// The material model and its parameters (E, ν, φ′, c′, ψ, tension), or a
/// model a3d-init does not know, kept verbatim up to the next structural
/// keyword.
fn read_model<G>(
    doc: &KeywordDocument,
    cur: &mut Cursor<'_>,
    get: &mut G,
    warnings: &mut Vec<String>,
    material: &mut Material,
    position: usize,
    context: &str,
) -> Result<(), ParseError>
where
    G: FnMut(&mut Cursor<'_>, &str, bool, &mut Vec<String>) -> Result<Pair, ParseError>,
{
    let material_type = material.material_type.clone();
    let model_keyword = if material_type == "liquid" {
        "MATERIAL_MODEL_LIQUID"
    } else {
        "MATERIAL_MODEL_SOLID"
    };
    let model_pair = get(cur, model_keyword, true, warnings)?;
    let model = model_pair.value.clone();
    let undrained = material_type == "saturated_material_undrained_effective";
    match model_parameters(&model, undrained) {
        Some(params) => {
            let model_pairs =
                read_properties(cur, &params, is_model_parameter, get, warnings, context)?;
            for (prop, p) in &model_pairs {
                let v = real(doc, p)?;
                check_range(doc, context, prop, v, p.value_line)?;
                match *prop {
                    "YOUNG_MODULUS" => material.young_modulus = Some(v),
                    "POISSON_RATIO" => material.poisson_ratio = Some(v),
                    "FRICTION_ANGLE" | "PEAK_FRICTION_ANGLE" => material.friction_angle = Some(v),
                    "COHESION" | "PEAK_COHESION" => material.cohesion = Some(v),
                    "DILATANCY_ANGLE" | "PEAK_DILATANCY_ANGLE" => {
                        material.dilatancy_angle = Some(v)
                    }
                    "TENSILE_STRENGTH" => material.tensile_strength = Some(v),
                    _ => {}
                }
            }
        }
        None => {
            // Unknown or free-form model (external_soil_model, rigid_body): keep
            // its pairs verbatim up to the next structural keyword.
            warnings.push(format!(
                "{}:{}: material {position}: model `{model}` is kept verbatim; a3d-init's runner treats it as linear elastic only if E and ν are given",
                doc.path().display(),
                model_pair.value_line + 1
            ));
            while let Some((_, line)) = cur.peek_line() {
                let keyword = line.trim_end();
                if is_structural_keyword(keyword) || keyword == "$$NUMBER_OF_MATERIALS" {
                    break;
                }
                get(cur, "", false, warnings)?;
            }
        }
    }
    material.model = Some(model);
    Ok(())
}

/// An unsaturated material's water retention curve and hydraulic
/// conductivity curve, with their parameters.
fn read_water_curves<G>(
    doc: &KeywordDocument,
    cur: &mut Cursor<'_>,
    get: &mut G,
    warnings: &mut Vec<String>,
    material: &mut Material,
) -> Result<(), ParseError>
where
    G: FnMut(&mut Cursor<'_>, &str, bool, &mut Vec<String>) -> Result<Pair, ParseError>,
{
    let curve = get(cur, "WATER_RETENTION_CURVE", true, warnings)?;
    match curve.value.as_str() {
        "van_genuchten" => {
            let mut v = [0.0; 4];
            for slot in &mut v {
                let p = get(cur, "", false, warnings)?;
                *slot = real(doc, &p)?;
            }
            material.retention = Some(RetentionCurve::VanGenuchten {
                s_min: v[0],
                s_max: v[1],
                p0: v[2],
                lambda: v[3],
            });
        }
        "linear" => {
            let p = get(cur, "", false, warnings)?;
            material.retention = Some(RetentionCurve::Linear { av: real(doc, &p)? });
        }
        other => {
            return Err(doc.error_at(
                curve.value_line,
                0,
                format!("unknown water retention curve `{other}` (known: van_genuchten, linear)"),
            ));
        }
    }
    let conductivity = get(cur, "HYDR_CONDUCTIVITY_CURVE", true, warnings)?;
    let n_params = match conductivity.value.as_str() {
        "constant" => 0,
        "hillel" => 1,
        "mualem" => 4,
        other => {
            return Err(doc.error_at(
                conductivity.value_line,
                0,
                format!("unknown hydraulic conductivity curve `{other}` (known: constant, hillel, mualem)"),
            ));
        }
    };
    let mut v = [0.0; 4];
    for slot in v.iter_mut().take(n_params) {
        let p = get(cur, "", false, warnings)?;
        *slot = real(doc, &p)?;
    }
    // Anura3D stores Mualem's four parameters in the same slots as the
    // van Genuchten retention curve, so they are what its Sr uses.
    if n_params == 4
        && let Some(RetentionCurve::VanGenuchten {
            s_min,
            s_max,
            p0,
            lambda,
        }) = &mut material.retention
    {
        [*s_min, *s_max, *p0, *lambda] = v;
    }
    Ok(())
}
