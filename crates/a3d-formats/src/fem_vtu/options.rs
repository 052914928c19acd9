//! The options of the VTU reader that are its own: which array plays which
//! role (`--columns pwp=…,stress=…`) and whether the stress array is effective
//! or total, with the Biot coefficient and Bishop's χ that make it total
//! (`--fem-sigma`).

/// What an array is read as.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Role {
    /// Pore-water pressure (OGS: `pressure_interpolated`, else `pressure`).
    Pwp,
    /// Stress tensor (OGS: `sigma`).
    Stress,
    /// Degree of saturation (OGS: `saturation`), for Bishop's χ.
    Saturation,
    /// Displacement (OGS: `displacement`): listed, not mapped.
    Displacement,
    /// Material per cell (OGS: `MaterialIDs`).
    Region,
}

impl Role {
    pub const ALL: [Role; 5] = [
        Role::Pwp,
        Role::Stress,
        Role::Saturation,
        Role::Displacement,
        Role::Region,
    ];

    /// The name in `--columns` and reports.
    pub fn name(self) -> &'static str {
        match self {
            Role::Pwp => "pwp",
            Role::Stress => "stress",
            Role::Saturation => "saturation",
            Role::Displacement => "displacement",
            Role::Region => "region",
        }
    }

    /// OGS's array names for this role, in order of preference.
    pub fn ogs_names(self) -> &'static [&'static str] {
        match self {
            Role::Pwp => &["pressure_interpolated", "pressure"],
            Role::Stress => &["sigma"],
            Role::Saturation => &["saturation"],
            Role::Displacement => &["displacement"],
            Role::Region => &["MaterialIDs"],
        }
    }
}

/// Bishop's χ in σ = σ′ − α·χ·p·I (OGS signs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Chi {
    /// The saturation array when there is one (OGS RichardsMechanics with
    /// `BishopsPowerLaw` exponent 1), else 1 (HydroMechanics: saturated).
    #[default]
    Auto,
    One,
    /// χ = S.
    Saturation,
    /// χ = Sᵐ (`BishopsPowerLaw` exponent m).
    SaturationPower(f64),
}

/// What the stress array holds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum StressRule {
    /// Effective (with α = 1, χ by [`Chi::Auto`]) when a pressure array is
    /// read, as OGS's HydroMechanics and RichardsMechanics write `sigma`;
    /// total otherwise (SmallDeformation).
    #[default]
    Auto,
    Total,
    Effective {
        biot: f64,
        chi: Chi,
    },
}

/// Parses `pwp=p,stress=sigma_total,saturation=S,region=mat` (array names).
pub fn parse_arrays_option(s: &str) -> Result<Vec<(Role, String)>, String> {
    let pairs = crate::lex::key_value_pairs(s, "role=array")?;
    arrays_from_pairs(&pairs)
}

/// Array names by role from (role, array) pairs (a front end's structured
/// form); a role given twice is an error.
pub fn arrays_from_pairs<K: AsRef<str>, V: AsRef<str>>(
    pairs: &[(K, V)],
) -> Result<Vec<(Role, String)>, String> {
    let mut out: Vec<(Role, String)> = Vec::new();
    for (k, v) in pairs {
        let k = k.as_ref();
        let role = Role::ALL
            .into_iter()
            .find(|r| r.name() == k)
            .ok_or_else(|| {
                format!(
                    "`{k}`: unknown role for a VTU array (known: pwp stress saturation displacement region)"
                )
            })?;
        let name = v.as_ref().to_string();
        if let Some((_, first)) = out.iter().find(|(r, _)| *r == role) {
            return Err(format!(
                "{} is given twice (`{first}` and `{name}`)",
                role.name()
            ));
        }
        out.push((role, name));
    }
    Ok(out)
}

/// Parses `total`, `effective`, or `effective,biot=0.9,chi=saturation`
/// (chi: `1`, `saturation`, `saturation^m`, `auto`).
pub fn parse_stress_option(s: &str) -> Result<StressRule, String> {
    let mut parts = s.split(',').map(str::trim);
    match parts.next() {
        None | Some("auto") | Some("") => Ok(StressRule::Auto),
        Some("total") => match parts.next() {
            None => Ok(StressRule::Total),
            Some(extra) => Err(format!("`{extra}`: a total stress takes no biot or chi")),
        },
        Some("effective") => {
            let (mut biot, mut chi) = (1.0, Chi::Auto);
            for part in parts {
                let (k, v) = part
                    .split_once('=')
                    .ok_or_else(|| format!("`{part}`: expected biot=… or chi=…"))?;
                match k.trim() {
                    "biot" => {
                        biot = v
                            .trim()
                            .parse::<f64>()
                            .ok()
                            .filter(|b| b.is_finite() && (0.0..=1.0).contains(b))
                            .ok_or_else(|| format!("biot `{v}`: expected a number in [0, 1]"))?;
                    }
                    "chi" => chi = parse_chi(v.trim())?,
                    other => return Err(format!("`{other}`: expected biot or chi")),
                }
            }
            Ok(StressRule::Effective { biot, chi })
        }
        Some(other) => Err(format!(
            "`{other}`: expected effective[,biot=α][,chi=…] or total"
        )),
    }
}

fn parse_chi(v: &str) -> Result<Chi, String> {
    match v {
        "auto" => Ok(Chi::Auto),
        "1" | "one" => Ok(Chi::One),
        "saturation" | "S" => Ok(Chi::Saturation),
        _ => v
            .strip_prefix("saturation^")
            .or_else(|| v.strip_prefix("S^"))
            .and_then(|m| m.parse::<f64>().ok())
            .filter(|m| m.is_finite() && *m > 0.0)
            .map(Chi::SaturationPower)
            .ok_or_else(|| format!("chi `{v}`: expected 1, saturation or saturation^m")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_option_reads_roles_and_refuses_repeats() {
        assert_eq!(
            parse_arrays_option("pwp=p_L, stress=sigma_total").unwrap(),
            vec![
                (Role::Pwp, "p_L".into()),
                (Role::Stress, "sigma_total".into())
            ]
        );
        assert!(
            parse_arrays_option("pwp=a,pwp=b")
                .unwrap_err()
                .contains("twice")
        );
        assert!(
            parse_arrays_option("sxx=a")
                .unwrap_err()
                .contains("unknown role")
        );
    }

    #[test]
    fn stress_option_reads_the_rules() {
        assert_eq!(parse_stress_option("total"), Ok(StressRule::Total));
        assert_eq!(
            parse_stress_option("effective,biot=0.8,chi=saturation^2"),
            Ok(StressRule::Effective {
                biot: 0.8,
                chi: Chi::SaturationPower(2.0)
            })
        );
        assert_eq!(
            parse_stress_option("effective"),
            Ok(StressRule::Effective {
                biot: 1.0,
                chi: Chi::Auto
            })
        );
        assert!(parse_stress_option("effective,biot=2").is_err());
        assert!(parse_stress_option("total,biot=1").is_err());
    }
}
