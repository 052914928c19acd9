//! The settings a caller chooses, by the words the library's messages use
//! for them. Library errors and warnings name concepts ("the column
//! mapping", "the outside policy"), never a front end's spelling; a front end
//! adds its own (`--columns` on the command line, `columns=` in Python) with
//! [`spell_settings`].

/// A setting the library's messages name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Setting {
    /// Which header or array holds which field.
    Columns,
    /// The length and pressure units of the FEM files.
    FemUnits,
    /// The sign convention of the FEM files.
    FemSign,
    /// The GeoStudio mesh that gives a node table its coordinates.
    FemMesh,
    /// Which analysis of a `.gsz` project.
    Analysis,
    /// A generated default CPS when the model has none.
    GeneratedCps,
    /// Replacing an existing output folder or file.
    Replace,
    /// The kernel's smoothing length h.
    SmoothingLength,
    /// What happens to MPs with no FEM node in reach.
    Outside,
    /// Where the MPs' stresses come from.
    StressSource,
    /// How MPM-MIXED elements get their state.
    MixedState,
}

impl Setting {
    /// Every setting.
    pub const ALL: [Setting; 11] = [
        Setting::Columns,
        Setting::FemUnits,
        Setting::FemSign,
        Setting::FemMesh,
        Setting::Analysis,
        Setting::GeneratedCps,
        Setting::Replace,
        Setting::SmoothingLength,
        Setting::Outside,
        Setting::StressSource,
        Setting::MixedState,
    ];

    /// The words the library's messages name this setting by.
    pub fn concept(self) -> &'static str {
        match self {
            Setting::Columns => "the column mapping",
            Setting::FemUnits => "the FEM units",
            Setting::FemSign => "the FEM sign convention",
            Setting::FemMesh => "the FEM mesh",
            Setting::Analysis => "the analysis choice",
            Setting::GeneratedCps => "the generated CPS",
            Setting::Replace => "replacing an output",
            Setting::SmoothingLength => "the smoothing length h",
            Setting::Outside => "the outside policy",
            Setting::StressSource => "the stress source",
            Setting::MixedState => "the mixed-state policy",
        }
    }
}

/// `message` with `spelling(setting)` in parentheses after the first mention
/// of each setting it names: "choose one with the column mapping" becomes
/// "choose one with the column mapping (--columns)" for the command line.
pub fn spell_settings(message: &str, spelling: impl Fn(Setting) -> &'static str) -> String {
    let mut marks: Vec<(usize, Setting)> = Setting::ALL
        .iter()
        .filter_map(|&s| {
            message
                .find(s.concept())
                .map(|at| (at + s.concept().len(), s))
        })
        .collect();
    marks.sort_unstable_by_key(|&(end, _)| end);
    let mut out = String::with_capacity(message.len() + 16 * marks.len());
    let mut from = 0;
    for (end, setting) in marks {
        out.push_str(&message[from..end]);
        out.push_str(" (");
        out.push_str(spelling(setting));
        out.push(')');
        from = end;
    }
    out.push_str(&message[from..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_named_setting_gets_its_spelling_once() {
        let flag = |s: Setting| match s {
            Setting::FemSign => "--fem-sign",
            Setting::FemUnits => "--fem-units",
            _ => "?",
        };
        assert_eq!(
            spell_settings(
                "check the FEM sign convention and the FEM units; the FEM units again",
                flag
            ),
            "check the FEM sign convention (--fem-sign) and the FEM units (--fem-units); the FEM units again"
        );
        assert_eq!(spell_settings("nothing named", flag), "nothing named");
    }

    #[test]
    fn no_concept_contains_another() {
        for a in Setting::ALL {
            for b in Setting::ALL {
                assert!(
                    a == b || !a.concept().contains(b.concept()),
                    "{a:?} holds {b:?}"
                );
            }
        }
    }
}
