//! The format pages are the users' contract (#30): every mechanical rule a
//! page states comes with an example in a `rule` block, and this test runs
//! each example through the reader the page describes, so a page and its
//! reader cannot drift apart.
//!
//! A rule block is a fenced code block whose info string is `rule`:
//!
//! ```text
//! reader: gom                       (gom, cps, mapf, mps-csv, fem-csv, ply, fem-vtu, fem-pvd, hhbf)
//! base: anura3d-mini/TwoMat.GOM     (a file under fixtures/, or `none`)
//! append: text after $$FINISH\n     (edits, in order; `\n` is a line break)
//! replace: old text => new text     (the first occurrence)
//! expect: ok | warning <text a warning holds> | error <text the message holds>
//! ```

use crate::common;

use std::path::{Path, PathBuf};

use a3d_init::formats::cps::CpsDocument;
use a3d_init::formats::gom::GomDocument;
use a3d_init::formats::{mapf, mps_table, ply};
use a3d_init::pipeline::fem::FemOptions;
use common::fixture;

/// One `rule` block of a page.
#[derive(Debug)]
struct Rule {
    page: String,
    line: usize,
    reader: String,
    base: Option<String>,
    edits: Vec<Edit>,
    /// Read, with a warning holding the text if one is given; or refused
    /// with a message holding the text.
    expect: Result<Option<String>, String>,
}

#[derive(Debug)]
enum Edit {
    Append(String),
    Replace(String, String),
}

fn unescape(s: &str) -> String {
    s.replace("\\n", "\n").replace("\\t", "\t")
}

/// Every rule block of `text` (the page `page`).
fn rules_of(page: &str, text: &str) -> Vec<Rule> {
    let mut rules = Vec::new();
    let mut lines = text.lines().enumerate();
    while let Some((i, line)) = lines.next() {
        if line.trim() != "```rule" {
            continue;
        }
        let mut rule = Rule {
            page: page.to_string(),
            line: i + 1,
            reader: String::new(),
            base: None,
            edits: Vec::new(),
            expect: Ok(None),
        };
        for (_, body) in lines.by_ref() {
            if body.trim() == "```" {
                break;
            }
            let (key, value) = body
                .split_once(':')
                .unwrap_or_else(|| panic!("{page}:{}: `key: value` expected in `{body}`", i + 1));
            let value = value.trim();
            match key.trim() {
                "reader" => rule.reader = value.to_string(),
                "base" => rule.base = (value != "none").then(|| value.to_string()),
                "append" => rule.edits.push(Edit::Append(unescape(value))),
                "replace" => {
                    let (old, new) = value.split_once(" => ").unwrap_or_else(|| {
                        panic!("{page}:{}: `replace: old => new` expected", i + 1)
                    });
                    rule.edits.push(Edit::Replace(unescape(old), unescape(new)));
                }
                "expect" => {
                    rule.expect = match value.split_once(' ') {
                        _ if value == "ok" => Ok(None),
                        Some(("warning", text)) => Ok(Some(text.to_string())),
                        Some(("error", text)) => Err(text.to_string()),
                        _ => panic!("{page}:{}: `expect: ok | warning TEXT | error TEXT`", i + 1),
                    }
                }
                other => panic!("{page}:{}: unknown key `{other}`", i + 1),
            }
        }
        rules.push(rule);
    }
    rules
}

/// The file name a reader expects (extension, as a user would name it).
fn file_name(reader: &str) -> &'static str {
    match reader {
        "gom" => "example.GOM",
        "cps" => "example.CPS_001",
        "mapf" => "example.MAPF",
        "mps-csv" => "mps.csv",
        "fem-csv" => "nodes.csv",
        "ply" => "Mesh.ply",
        "fem-vtu" => "result.vtu",
        "fem-pvd" => "series.pvd",
        "hhbf" => "example.HHBF",
        "cbgeo-json" => "mpm.json",
        "cbgeo-mesh" => "mesh.txt",
        "cbgeo-particles" => "particles.txt",
        "cbgeo-stresses" => "particles-stresses.txt",
        "cbgeo-pore-pressures" => "particles-pore-pressures.txt",
        other => panic!("unknown reader `{other}`"),
    }
}

/// Runs the reader on `path`: the warnings it reported, or the error's message.
fn read(reader: &str, path: &Path) -> Result<Vec<String>, String> {
    match reader {
        "fem-csv" | "fem-vtu" | "fem-pvd" => {
            a3d_init::pipeline::fem::load(&FemOptions::files(vec![path.to_path_buf()]))
                .map(|l| l.reports.into_iter().flat_map(|r| r.warnings).collect())
                .map_err(|x| x.to_string())
        }
        _ => read_quietly(reader, path).map(|()| Vec::new()),
    }
}

/// [`read`] for the readers that report no warnings.
fn read_quietly(reader: &str, path: &Path) -> Result<(), String> {
    let e = |e: &dyn std::fmt::Display| e.to_string();
    match reader {
        "gom" => {
            let doc = GomDocument::read(path).map_err(|x| e(&x))?;
            let (model, _) = doc.model().map_err(|x| e(&x))?;
            a3d_init::place::place_material_points(&model).map_err(|x| e(&x))?;
            Ok(())
        }
        // As a 2D project loads it: the gravity vector checked too.
        "cps" => {
            let cps = CpsDocument::read(path).map_err(|x| e(&x))?;
            cps.check_gravity_vector(2).map_err(|x| e(&x))
        }
        "mapf" => mapf::read(path).map(drop).map_err(|x| e(&x)),
        "mps-csv" => mps_table::read_table(path).map(drop).map_err(|x| e(&x)),
        "ply" => ply::read_ply_mesh(path).map(drop).map_err(|x| e(&x)),
        "cbgeo-json" => a3d_init::formats::cbgeo::read(path)
            .map(drop)
            .map_err(|x| e(&x)),
        "cbgeo-mesh" | "cbgeo-particles" | "cbgeo-stresses" | "cbgeo-pore-pressures" => {
            use a3d_init::formats::cbgeo::text;
            let t = std::fs::read_to_string(path).unwrap();
            match reader {
                "cbgeo-mesh" => text::read_mesh(path, &t, 2, 4).map(drop),
                "cbgeo-particles" => text::read_particles(path, &t, 2).map(drop),
                "cbgeo-stresses" => text::read_stresses(path, &t).map(drop),
                _ => text::read_id_values(path, &t).map(drop),
            }
            .map_err(|x| e(&x))
        }
        "hhbf" => a3d_init::formats::hhbf::read(path)
            .map(drop)
            .map_err(|x| e(&x)),
        other => panic!("unknown reader `{other}`"),
    }
}

fn pages() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("formats");
    let mut pages: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    pages
}

#[test]
fn every_rule_example_of_every_format_page_holds() {
    let tmp = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    let mut checked = 0;
    for page in pages() {
        let name = page.file_name().unwrap().to_string_lossy().into_owned();
        let text = std::fs::read_to_string(&page).unwrap();
        let rules = rules_of(&name, &text);
        // A page that states rules checks at least one of them here.
        if text.contains("## Errors") || text.contains("## Rules") {
            assert!(
                !rules.is_empty(),
                "{name} states rules but has no `rule` example"
            );
        }
        for (k, rule) in rules.iter().enumerate() {
            let mut bytes = match &rule.base {
                Some(base) => std::fs::read(fixture(base))
                    .unwrap_or_else(|e| panic!("{}:{}: base {base}: {e}", rule.page, rule.line)),
                None => Vec::new(),
            };
            for edit in &rule.edits {
                match edit {
                    Edit::Append(text) => bytes.extend_from_slice(text.as_bytes()),
                    Edit::Replace(old, new) => {
                        let at = bytes
                            .windows(old.len())
                            .position(|w| w == old.as_bytes())
                            .unwrap_or_else(|| {
                                panic!("{}:{}: `{old}` is not in the base", rule.page, rule.line)
                            });
                        bytes.splice(at..at + old.len(), new.bytes());
                    }
                }
            }
            let dir = tmp.path().join(format!("{name}-{k}"));
            std::fs::create_dir_all(&dir).unwrap();
            // A run file reads the files beside it: the base's folder comes along.
            if let (Some(base), "cbgeo-json") = (&rule.base, rule.reader.as_str()) {
                for f in std::fs::read_dir(fixture(base).parent().unwrap()).unwrap() {
                    let f = f.unwrap().path();
                    std::fs::copy(&f, dir.join(f.file_name().unwrap())).unwrap();
                }
            }
            let path = dir.join(file_name(&rule.reader));
            std::fs::write(&path, &bytes).unwrap();
            let warned = read(&rule.reader, &path);
            let ok = match (&rule.expect, &warned) {
                (Ok(None), Ok(_)) => true,
                (Ok(Some(want)), Ok(ws)) => ws.iter().any(|w| w.contains(want.as_str())),
                (Err(want), Err(message)) => message.contains(want.as_str()),
                _ => false,
            };
            if !ok {
                failures.push(format!(
                    "{}:{}: expected {:?}, the reader gave {:?}",
                    rule.page, rule.line, rule.expect, warned
                ));
            }
            checked += 1;
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(checked >= 20, "only {checked} rule examples in formats/");
}
