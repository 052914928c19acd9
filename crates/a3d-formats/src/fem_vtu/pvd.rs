//! ParaView data collections (`.pvd`): a time series of `.vtu` files, one
//! `<DataSet timestep=… file=…>` per output. A step is chosen by its 0-based
//! place in the series (step 0 is the first output, OGS's initial state), as
//! the last, or by its time with a unit (`time=1.56h`); a time between two
//! outputs is an error naming both: a3d-init never interpolates in time.

use crate::fem::SeriesStep;
use std::path::{Path, PathBuf};

use crate::error::{FormatError, ParseError, Position};
use crate::fem::StepChoice;

/// One output of the series.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Output {
    /// Time in s (the `timestep` attribute).
    pub time: f64,
    /// The `.vtu`, relative to the PVD's folder as written, resolved.
    pub file: PathBuf,
}

/// A time series read from a `.pvd`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Series {
    pub outputs: Vec<Output>,
}

/// `5616 s (1.56 h)`: a time for messages.
pub fn time_text(t: f64) -> String {
    let hours = t / 3600.0;
    if t.abs() >= 360.0 {
        format!("{t} s ({} h)", (hours * 1e4).round() / 1e4)
    } else {
        format!("{t} s")
    }
}

/// Reads the series of a `.pvd`. The files listed are not opened, but each
/// is protected as an input ([`crate::input::protect`]): no output
/// folder may hold or replace one.
pub fn read(path: &Path) -> Result<Series, FormatError> {
    let text = crate::input::read_text(path)?;
    let series = parse(path, &text)?;
    for output in &series.outputs {
        crate::input::protect(&output.file);
    }
    Ok(series)
}

/// Parses the text of a `.pvd` at `path`.
pub fn parse(path: &Path, text: &str) -> Result<Series, FormatError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        let p = e.pos();
        ParseError::new(
            path,
            Position::new(p.row as usize, p.col as usize),
            format!("XML: {e}"),
        )
    })?;
    let at = |node: roxmltree::Node| Position::of_byte(text, node.range().start);
    let root = doc.root_element();
    if root.tag_name().name() != "VTKFile" || root.attribute("type") != Some("Collection") {
        return Err(ParseError::new(
            path,
            at(root),
            "expected <VTKFile type=\"Collection\"> (a ParaView .pvd)",
        )
        .into());
    }
    let collection = root
        .children()
        .find(|n| n.has_tag_name("Collection"))
        .ok_or_else(|| ParseError::new(path, at(root), "no <Collection>"))?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut outputs: Vec<Output> = Vec::new();
    // Each output is its own file: a file listed twice would be read (and
    // held by `fos-time`) once per listing.
    let mut listed: std::collections::HashMap<PathBuf, f64> = std::collections::HashMap::new();
    // The same by file identity, where the file exists: a hard link or a
    // symlink is another spelling of one output (1000 hard links of one
    // file made `fos-time` analyse it 1000 times).
    let mut identities: std::collections::HashMap<(u64, u64), (PathBuf, f64)> =
        std::collections::HashMap::new();
    for node in collection.children().filter(|n| n.has_tag_name("DataSet")) {
        let time = node
            .attribute("timestep")
            .unwrap_or("0")
            .trim()
            .parse::<f64>()
            .ok()
            .filter(|t| t.is_finite())
            .ok_or_else(|| {
                ParseError::new(path, at(node), "DataSet without a finite `timestep`")
            })?;
        let file = node
            .attribute("file")
            .filter(|f| !f.trim().is_empty())
            .ok_or_else(|| ParseError::new(path, at(node), "DataSet without a `file`"))?;
        let part = node.attribute("part").unwrap_or("0");
        if let Some(prev) = outputs.last() {
            if time == prev.time {
                return Err(ParseError::new(
                    path,
                    at(node),
                    format!(
                        "a second DataSet at t = {} (part `{part}`): a3d-init reads one piece per time; merge the parts into one .vtu",
                        time_text(time)
                    ),
                )
                .into());
            }
            if time < prev.time {
                return Err(ParseError::new(
                    path,
                    at(node),
                    format!(
                        "t = {} comes after t = {}: the outputs are not in time order",
                        time_text(time),
                        time_text(prev.time)
                    ),
                )
                .into());
            }
        }
        let file = dir.join(file.trim());
        if let Some(first) = listed.insert(file.clone(), time) {
            return Err(ParseError::new(
                path,
                at(node),
                format!(
                    "`{}` is listed at t = {} and again at t = {}: each output of a series is its own file",
                    file.display(),
                    time_text(first),
                    time_text(time)
                ),
            )
            .into());
        }
        // Where the file can be read (a missing output is reported where it
        // is opened).
        if let Some(id) = std::fs::metadata(&file)
            .ok()
            .and_then(|m| crate::input::identity(&m))
            && let Some((first, first_time)) = identities.insert(id, (file.clone(), time))
        {
            return Err(ParseError::new(
                path,
                at(node),
                format!(
                    "`{}` (t = {}) is the file `{}` listed at t = {} (a link to it): each output of a series is its own file",
                    file.display(),
                    time_text(time),
                    first.display(),
                    time_text(first_time)
                ),
            )
            .into());
        }
        outputs.push(Output { time, file });
    }
    if outputs.is_empty() {
        return Err(
            ParseError::new(path, at(collection), "the collection lists no DataSet").into(),
        );
    }
    Ok(Series { outputs })
}

impl Series {
    /// The output `step` names; a time between outputs is an error naming the
    /// nearest before and after.
    pub fn choose(&self, pvd: &Path, step: &StepChoice) -> Result<SeriesStep, FormatError> {
        let n = self.outputs.len();
        let chosen = |k: usize| SeriesStep {
            pvd: pvd.to_path_buf(),
            step: k,
            steps: n,
            time: self.outputs[k].time,
            file: self.outputs[k].file.clone(),
        };
        match *step {
            StepChoice::Failure => Err(FormatError::file(pvd, crate::fem::FAILURE_NEEDS_MODEL)),
            StepChoice::Last => Ok(chosen(n - 1)),
            StepChoice::Number(k) => {
                let k = k as usize;
                if k < n {
                    Ok(chosen(k))
                } else {
                    Err(FormatError::file(
                        pvd,
                        format!(
                            "no step {k}: the series has {n} outputs, steps 0 to {} (t = {} to {})",
                            n - 1,
                            time_text(self.outputs[0].time),
                            time_text(self.outputs[n - 1].time)
                        ),
                    ))
                }
            }
            StepChoice::Time(t) => {
                let span = (self.outputs[n - 1].time - self.outputs[0].time).abs();
                let tol = 1e-9 * span.max(t.abs()).max(1.0);
                if let Some(k) = self.outputs.iter().position(|o| (o.time - t).abs() <= tol) {
                    return Ok(chosen(k));
                }
                let before = self.outputs.iter().rposition(|o| o.time < t);
                let after = self.outputs.iter().position(|o| o.time > t);
                let name =
                    |k: usize| format!("step {k} at t = {}", time_text(self.outputs[k].time));
                let nearest = match (before, after) {
                    (Some(b), Some(a)) => format!("between {} and {}", name(b), name(a)),
                    (Some(b), None) => format!("after the last output, {}", name(b)),
                    (None, Some(a)) => format!("before the first output, {}", name(a)),
                    (None, None) => String::new(),
                };
                Err(FormatError::file(
                    pvd,
                    format!(
                        "no output at t = {}: it lies {nearest}; give one of them (a3d-init does not interpolate in time)",
                        time_text(t)
                    ),
                ))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series() -> Series {
        let text = r#"<?xml version="1.0"?>
<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">
  <Collection>
    <DataSet timestep="0" group="" part="0" file="r_t_0.vtu"/>
    <DataSet timestep="5580" group="" part="0" file="r_t_5580.vtu"/>
    <DataSet timestep="5760" group="" part="0" file="r_t_5760.vtu"/>
  </Collection>
</VTKFile>"#;
        parse(Path::new("d/r.pvd"), text).unwrap()
    }

    /// Regression: 1000 hard links of one output passed the check on
    /// the listed names, and `fos-time` analysed the file 1000 times.
    #[cfg(unix)]
    #[test]
    fn a_link_to_a_listed_file_is_refused_at_its_listing() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a.vtu"), "x").unwrap();
        std::fs::hard_link(dir.path().join("a.vtu"), dir.path().join("b.vtu")).unwrap();
        std::os::unix::fs::symlink("a.vtu", dir.path().join("c.vtu")).unwrap();
        std::fs::write(dir.path().join("d.vtu"), "x").unwrap();
        let pvd = dir.path().join("r.pvd");
        let text = |second: &str| {
            format!(
                "<VTKFile type=\"Collection\"><Collection>\n<DataSet timestep=\"0\" file=\"a.vtu\"/>\n<DataSet timestep=\"1\" file=\"{second}\"/>\n</Collection></VTKFile>"
            )
        };
        for link in ["b.vtu", "c.vtu"] {
            let e = parse(&pvd, &text(link)).unwrap_err().to_string();
            assert!(e.contains(":3:") && e.contains("a link to it"), "{e}");
        }
        // Two files with the same bytes are two outputs.
        assert_eq!(parse(&pvd, &text("d.vtu")).unwrap().outputs.len(), 2);
    }

    #[test]
    fn a_file_listed_twice_is_refused_at_its_second_listing() {
        let text = "<VTKFile type=\"Collection\"><Collection>\n<DataSet timestep=\"0\" file=\"a.vtu\"/>\n<DataSet timestep=\"1\" file=\"a.vtu\"/>\n</Collection></VTKFile>";
        let e = parse(Path::new("r.pvd"), text).unwrap_err().to_string();
        assert!(
            e.starts_with("r.pvd:3:1: `a.vtu` is listed at t = 0 s and again at t = 1 s"),
            "{e}"
        );
    }

    #[test]
    fn steps_are_chosen_by_place_last_and_time() {
        let s = series();
        let pvd = Path::new("d/r.pvd");
        assert_eq!(s.choose(pvd, &StepChoice::Last).unwrap().step, 2);
        assert_eq!(
            s.choose(pvd, &StepChoice::Number(1)).unwrap().file,
            Path::new("d/r_t_5580.vtu")
        );
        assert_eq!(s.choose(pvd, &StepChoice::Time(5760.0)).unwrap().step, 2);
        assert!(
            s.choose(pvd, &StepChoice::Number(3))
                .unwrap_err()
                .to_string()
                .contains("steps 0 to 2")
        );
    }

    #[test]
    fn a_time_between_outputs_names_both() {
        let e = series()
            .choose(Path::new("d/r.pvd"), &StepChoice::Time(5616.0))
            .unwrap_err()
            .to_string();
        assert!(e.contains("5616 s (1.56 h)"), "{e}");
        assert!(
            e.contains("step 1 at t = 5580 s (1.55 h) and step 2 at t = 5760 s (1.6 h)"),
            "{e}"
        );
    }

    #[test]
    fn outputs_out_of_order_are_refused_at_their_line() {
        let text = "<VTKFile type=\"Collection\"><Collection>\n<DataSet timestep=\"2\" file=\"a.vtu\"/>\n<DataSet timestep=\"1\" file=\"b.vtu\"/>\n</Collection></VTKFile>";
        let e = parse(Path::new("r.pvd"), text).unwrap_err().to_string();
        assert!(e.starts_with("r.pvd:3:1:"), "{e}");
    }
}
