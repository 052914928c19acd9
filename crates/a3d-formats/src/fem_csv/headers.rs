//! Column roles ([`Field`]) and how a header is understood: normalisation,
//! the synonym table, units written in the header and their factors to m and
//! kPa.

use a3d_model::{Quantity, StressComponent};

/// What a column holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Field {
    X,
    Y,
    Z,
    Node,
    Region,
    Value(Quantity),
}

impl Field {
    /// Name used by `--columns` and reports: x, y, z, node, region, pwp, sxx, …, esxx, …
    pub fn name(self) -> String {
        match self {
            Field::X => "x".into(),
            Field::Y => "y".into(),
            Field::Z => "z".into(),
            Field::Node => "node".into(),
            Field::Region => "region".into(),
            Field::Value(q) => q.name(),
        }
    }

    pub fn from_name(s: &str) -> Option<Field> {
        match s {
            "x" => Some(Field::X),
            "y" => Some(Field::Y),
            "z" => Some(Field::Z),
            "node" | "id" => Some(Field::Node),
            "region" | "material" => Some(Field::Region),
            other => Quantity::from_name(other).map(Field::Value),
        }
    }

    pub(super) fn is_pressure(self) -> bool {
        matches!(self, Field::Value(_))
    }

    pub(super) fn is_length(self) -> bool {
        matches!(self, Field::X | Field::Y | Field::Z)
    }
}

/// Normalises a header for matching: drops units in () or [], lower-cases and
/// keeps letters and digits only, with σ spelt `sig`, τ `tau` and a prime
/// (`'`, `′`, `’`: effective) `prime`, so that `σ'xx [kN/m²]` reads as
/// `sigprimexx` and `τxy` as `tauxy`.
pub fn normalise(header: &str) -> String {
    let mut out = String::new();
    let mut depth = 0;
    for c in header.chars() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth = (depth as i32 - 1).max(0) as usize,
            _ if depth > 0 => {}
            'σ' | 'Σ' => out.push_str("sig"),
            'τ' => out.push_str("tau"),
            '\'' | '′' | '’' => out.push_str("prime"),
            c if c.is_alphanumeric() && c.is_ascii() => out.push(c.to_ascii_lowercase()),
            _ => {}
        }
    }
    out
}

/// The unit written in a header: inside () or [], or an `_unit` suffix.
pub(super) fn header_unit(header: &str) -> Option<String> {
    if let Some(start) = header.find(['(', '[']) {
        let rest = &header[start + 1..];
        if let Some(end) = rest.find([')', ']']) {
            return Some(rest[..end].trim().to_string());
        }
    }
    let (_, suffix) = header.rsplit_once('_')?;
    let s = suffix.to_ascii_lowercase();
    (["m", "ft", "mm", "cm", "kpa", "pa", "mpa", "psf", "psi"].contains(&s.as_str()))
        .then(|| suffix.to_string())
}

pub(super) fn strip_unit_suffix(normalised: &str, header: &str) -> String {
    match header.rsplit_once('_') {
        Some((_, suffix)) if header_unit(header).as_deref() == Some(suffix) => normalised
            .trim_end_matches(&suffix.to_ascii_lowercase())
            .to_string(),
        _ => normalised.to_string(),
    }
}

/// The field a normalised header stands for.
pub fn synonym(n: &str) -> Option<Field> {
    use StressComponent::*;
    let t = |c| Some(Field::Value(Quantity::TotalStress(c)));
    let e = |c| Some(Field::Value(Quantity::EffectiveStress(c)));
    match n {
        "x" | "xcoordinate" | "xcoord" | "xm" | "pointsx" | "points0" => Some(Field::X),
        "y" | "ycoordinate" | "ycoord" | "ym" | "pointsy" | "points1" | "elevation" => {
            Some(Field::Y)
        }
        "z" | "zcoordinate" | "zcoord" | "zm" | "pointsz" | "points2" => Some(Field::Z),
        "node" | "nodenum" | "nodeid" | "nodenumber" | "id" | "nodeno" => Some(Field::Node),
        "material" | "region" | "materialid" | "soil" | "materialname" | "zone" | "regionid" => {
            Some(Field::Region)
        }
        "porewaterpressure"
        | "pwp"
        | "porepressure"
        | "waterpressure"
        | "u"
        | "pwater"
        | "porewaterpressurekpa" => Some(Field::Value(Quantity::Pwp)),
        "xtotalstress" | "sigmax" | "sigx" | "sxx" | "sigxxt" | "sigmaxx" | "totalstressx"
        | "sigxx" | "s11" => t(Xx),
        "ytotalstress" | "sigmay" | "sigy" | "syy" | "sigyyt" | "sigmayy" | "totalstressy"
        | "sigyy" | "s22" => t(Yy),
        "ztotalstress" | "sigmaz" | "sigz" | "szz" | "sigzzt" | "sigmazz" | "totalstressz"
        | "sigzz" | "s33" => t(Zz),
        "xyshearstress" | "tauxy" | "sxy" | "sigxy" | "sigmaxy" | "shearstressxy" | "xyshear"
        | "s12" | "yxshearstress" => t(Xy),
        "yzshearstress" | "tauyz" | "syz" | "sigyz" | "sigmayz" | "shearstressyz" | "s23"
        | "zyshearstress" => t(Yz),
        "xzshearstress" | "tauxz" | "sxz" | "sigxz" | "sigmaxz" | "shearstressxz"
        | "zxshearstress" | "tauzx" | "s13" => t(Xz),
        "xeffectivestress" | "sigxxe" | "esxx" | "effectivestressx" | "sigmaxeff"
        | "sigmaxprime" | "sigprimexx" | "sigxxprime" | "sigmaprimexx" | "sigmaxxprime" => e(Xx),
        "yeffectivestress" | "sigyye" | "esyy" | "effectivestressy" | "sigmayeff"
        | "sigmayprime" | "sigprimeyy" | "sigyyprime" | "sigmaprimeyy" | "sigmayyprime" => e(Yy),
        "zeffectivestress" | "sigzze" | "eszz" | "effectivestressz" | "sigmazeff"
        | "sigmazprime" | "sigprimezz" | "sigzzprime" | "sigmaprimezz" | "sigmazzprime" => e(Zz),
        // An effective shear stress is the total one (the pore pressure has
        // no shear part).
        "sigprimexy" | "sigxyprime" | "sigmaprimexy" | "tauprimexy" => t(Xy),
        "sigprimeyz" | "sigyzprime" | "sigmaprimeyz" | "tauprimeyz" => t(Yz),
        "sigprimexz" | "sigxzprime" | "sigmaprimexz" | "tauprimexz" | "sigprimezx" => t(Xz),
        _ => None,
    }
}

/// Factor from a header unit to kPa (pressure) or m (length).
pub fn unit_factor(unit: &str, length: bool) -> Option<f64> {
    let u: String = unit
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect::<String>()
        .to_ascii_lowercase();
    if length {
        match u.as_str() {
            "m" => Some(1.0),
            "ft" | "feet" => Some(0.3048),
            "mm" => Some(1e-3),
            "cm" => Some(1e-2),
            _ => None,
        }
    } else {
        match u.as_str() {
            "kpa" | "kn/m2" | "kn/m²" | "kn/m^2" => Some(1.0),
            "pa" | "n/m2" | "n/m²" => Some(1e-3),
            "mpa" => Some(1e3),
            "psf" | "lbf/ft2" | "lb/ft2" => Some(0.047880258980335),
            "psi" | "lbf/in2" => Some(6.894757293168361),
            _ => None,
        }
    }
}
