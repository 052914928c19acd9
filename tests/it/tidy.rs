//! Repository hygiene: every Rust file opens with a `//!` paragraph saying what
//! it owns, no stub macros are left in the library, and the workspace's crate
//! graph keeps its layers (each crate depends only on the layers beneath it).

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

fn all_rust_files() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in ["src", "crates", "tests", "benches", "examples"] {
        if root.join(dir).exists() {
            rust_files(&root.join(dir), &mut files);
        }
    }
    files
}

#[test]
fn every_rust_file_opens_with_a_module_doc() {
    let missing: Vec<_> = all_rust_files()
        .into_iter()
        .filter(|p| {
            !std::fs::read_to_string(p)
                .unwrap()
                .trim_start()
                .starts_with("//!")
        })
        .collect();
    assert!(
        missing.is_empty(),
        "files without a leading //! paragraph: {missing:?}"
    );
}

#[test]
fn no_stub_macros_in_the_library() {
    let files = source_files();
    let stubs = ["todo!(", "unimplemented!(", "dbg!("];
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        for stub in stubs {
            assert!(!text.contains(stub), "{} contains {stub}", path.display());
        }
    }
}

/// `unsafe` lives in two files, the kernel's AVX-512 distance test and the
/// binary's one allocator setting: the workspace denies it, and only those
/// modules allow it back.
#[test]
fn unsafe_code_stays_in_the_simd_module() {
    let allowed = [
        Path::new("crates/a3d-kernel/src/simd.rs"),
        Path::new("src/memory.rs"),
    ];
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut seen = Vec::new();
    for path in source_files() {
        let text = std::fs::read_to_string(&path).unwrap();
        let code = text
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        if code.contains("unsafe") || code.contains("allow(unsafe_code)") {
            seen.push(path.strip_prefix(root).unwrap_or(&path).to_path_buf());
        }
    }
    seen.sort();
    let mut allowed = allowed.map(Path::to_path_buf).to_vec();
    allowed.sort();
    assert_eq!(seen, allowed, "files with unsafe code");
    let manifest = std::fs::read_to_string(root.join("Cargo.toml")).unwrap();
    assert!(manifest.contains("unsafe_code = \"deny\""));
}

/// The program's sources: the binary's `src/` and every crate's `src/`.
fn source_files() -> Vec<PathBuf> {
    let mut files = Vec::new();
    for src in source_roots() {
        rust_files(&src, &mut files);
    }
    files
}

/// The `src/` folders: the binary's and every crate's.
fn source_roots() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut roots = vec![root.join("src")];
    for krate in std::fs::read_dir(root.join("crates")).unwrap() {
        roots.push(krate.unwrap().path().join("src"));
    }
    roots
}

/// The modules `tests/it/main.rs` declares, in order.
fn test_modules() -> Vec<String> {
    let main = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/it/main.rs");
    std::fs::read_to_string(main)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("mod ")?.strip_suffix(';'))
        .filter(|m| *m != "common")
        .map(str::to_owned)
        .collect()
}

/// With one test binary, a file that `main.rs` does not declare is never
/// compiled and its tests never run, in silence.
#[test]
fn every_test_file_is_a_module_of_the_one_binary() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/it");
    let modules = test_modules();
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .filter(|s| s != "main")
        .collect();
    files.sort();
    let mut declared = modules.clone();
    declared.sort();
    assert_eq!(
        files, declared,
        "tests/it/*.rs against the mods of tests/it/main.rs"
    );
    let top: Vec<_> = std::fs::read_dir(dir.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .collect();
    assert!(
        top.is_empty(),
        "tests/*.rs would each be a binary of their own: {top:?}"
    );
}

/// ARCHITECTURE.md's test table names every module of the test binary, and
/// nothing else.
#[test]
fn the_architecture_test_table_matches_the_binary() {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("ARCHITECTURE.md"))
            .unwrap();
    let section = text
        .split_once("\n## Tests\n")
        .expect("ARCHITECTURE.md has a Tests section")
        .1;
    let section = section.split_once("\n## ").map_or(section, |(s, _)| s);
    let mut table: Vec<String> = section
        .lines()
        .filter_map(|l| l.strip_prefix("| `")?.split_once("` |"))
        .map(|(name, _)| name.to_owned())
        .collect();
    table.sort();
    let mut modules = test_modules();
    modules.sort();
    assert_eq!(
        table, modules,
        "ARCHITECTURE.md's test table against tests/it/main.rs"
    );
}

/// `src` comments stand alone: the issue a line came from is history, kept by
/// CHANGELOG.md and the tests, not by `(#NN)` tags in the code.
#[test]
fn no_issue_tags_in_library_comments() {
    let files = source_files();
    let mut tagged = Vec::new();
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        for (i, line) in text.lines().enumerate() {
            let Some((_, comment)) = line.split_once("//") else {
                continue;
            };
            let cites_issue = comment.match_indices('#').any(|(at, _)| {
                let digits = comment[at + 1..]
                    .chars()
                    .take_while(char::is_ascii_digit)
                    .count();
                // "Slide2 verification #1" names a published problem, not an issue.
                (1..=3).contains(&digits) && !comment[..at].ends_with("verification ")
            });
            if cites_issue {
                tagged.push(format!("{}:{}", path.display(), i + 1));
            }
        }
    }
    assert!(tagged.is_empty(), "issue tags in src comments: {tagged:?}");
}

/// The workspace's layers, lowest first. A crate's `[dependencies]` name only
/// crates before it; the test kit is a dev-dependency but for the benchmark
/// binary; `a3d-init` (the binary) comes last.
const LAYERS: [&str; 12] = [
    "a3d-progress",
    "a3d-model",
    "a3d-element",
    "a3d-kernel",
    "a3d-formats",
    "a3d-state",
    "a3d-mpm",
    "a3d-slope",
    "a3d-testkit",
    "a3d-init-lib",
    "a3d-bench",
    "a3d-init",
];

/// The dependencies a manifest names, as (section, crate): `dependencies`
/// (the target-specific tables included) or `dev-dependencies`.
fn manifest_dependencies(manifest: &Path) -> Vec<(String, String)> {
    let text = std::fs::read_to_string(manifest).unwrap();
    let mut section = String::new();
    let mut out = Vec::new();
    for line in text.lines().map(str::trim) {
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            let last = name.rsplit('.').next().unwrap_or_default();
            let own = name == last || name.starts_with("target.");
            section = match last {
                "dependencies" | "dev-dependencies" if own => last.to_string(),
                _ => String::new(),
            };
            continue;
        }
        if section.is_empty() || line.is_empty() || line.starts_with('#') {
            continue;
        }
        let name = line.split(['=', '.', ' ']).next().unwrap().trim();
        out.push((section.clone(), name.to_string()));
    }
    out
}

fn manifest_of(krate: &str) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    if krate == "a3d-init" {
        root.join("Cargo.toml")
    } else {
        root.join("crates").join(krate).join("Cargo.toml")
    }
}

#[test]
fn the_crate_graph_keeps_its_layers() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut folders: Vec<String> = std::fs::read_dir(root.join("crates"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    folders.sort();
    let mut layered: Vec<String> = LAYERS[..LAYERS.len() - 1]
        .iter()
        .map(|s| s.to_string())
        .collect();
    layered.sort();
    assert_eq!(folders, layered, "crates/ against the layer list");
    let mut wrong = Vec::new();
    for (rank, krate) in LAYERS.iter().enumerate() {
        assert!(
            root.join("crates").join(krate).join("README.md").exists() || *krate == "a3d-init",
            "{krate} has no README.md"
        );
        for (section, dep) in manifest_dependencies(&manifest_of(krate)) {
            let Some(dep_rank) = LAYERS.iter().position(|l| *l == dep) else {
                continue;
            };
            let test_kit = dep == "a3d-testkit" && section == "dev-dependencies";
            let self_with_features = dep == "a3d-init-lib" && *krate == "a3d-init";
            if dep_rank >= rank && !test_kit && !self_with_features {
                wrong.push(format!("{krate} -> {dep} ({section})"));
            }
            if dep == "a3d-testkit" && section == "dependencies" && *krate != "a3d-bench" {
                wrong.push(format!("{krate} ships the test kit"));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "dependencies against the layers: {wrong:?}"
    );
}

/// The heavy crates compile only where they are used, and the command line
/// is clap, anyhow and indicatif over the library (and libc for its one
/// allocator setting, `src/memory.rs`, which the benchmark binary shares;
/// ctrlc for its signal handler, which a library user does not get).
#[test]
fn heavy_and_front_end_crates_stay_where_they_are_used() {
    let users = |wanted: &str| -> Vec<&str> {
        LAYERS
            .iter()
            .copied()
            .filter(|k| {
                manifest_dependencies(&manifest_of(k))
                    .iter()
                    .any(|(section, dep)| section == "dependencies" && dep == wanted)
            })
            .collect()
    };
    assert_eq!(users("faer"), ["a3d-mpm"]);
    assert_eq!(users("plotters"), ["a3d-init-lib"]);
    assert_eq!(users("indicatif"), ["a3d-init"]);
    assert_eq!(users("clap"), ["a3d-bench", "a3d-init"]);
    let mut binary: Vec<String> = manifest_dependencies(&manifest_of("a3d-init"))
        .into_iter()
        .filter(|(section, _)| section == "dependencies")
        .map(|(_, dep)| dep)
        .collect();
    binary.sort();
    assert_eq!(
        binary,
        [
            "a3d-init-lib",
            "anyhow",
            "clap",
            "ctrlc",
            "indicatif",
            "libc"
        ]
    );
    assert_eq!(users("libc"), ["a3d-bench", "a3d-init"]);
    assert_eq!(users("ctrlc"), ["a3d-init"]);
}

/// The files of one source folder by module path (`lib.rs`, `main.rs` and
/// `mod.rs` stand for their folder's module).
fn modules_of(src: &Path) -> Vec<(Vec<String>, PathBuf)> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files
        .into_iter()
        .map(|file| {
            let rel = file.strip_prefix(src).unwrap().with_extension("");
            let mut parts: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if matches!(
                parts.last().map(String::as_str),
                Some("lib" | "main" | "mod")
            ) {
                parts.pop();
            }
            (parts, file)
        })
        .collect()
}

/// The modules a file's code names through `crate::…` or `super::…` paths
/// (comments and the inline test module left out), resolved to the longest
/// module path that is a file.
fn named_modules(
    module: &[String],
    text: &str,
    modules: &[(Vec<String>, PathBuf)],
) -> Vec<Vec<String>> {
    let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or(text);
    let code: String = code
        .lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n");
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let mut out = Vec::new();
    for start in ["crate::", "super::"] {
        for (at, _) in code.match_indices(start) {
            if code[..at]
                .chars()
                .next_back()
                .is_some_and(|c| ident(c) || c == ':')
            {
                continue;
            }
            let rest = &code[at..];
            let end = rest
                .find(|c: char| !(ident(c) || c == ':'))
                .unwrap_or(rest.len());
            let mut segments: Vec<&str> =
                rest[..end].split("::").filter(|s| !s.is_empty()).collect();
            let mut path: Vec<String> = if segments[0] == "crate" {
                segments.remove(0);
                Vec::new()
            } else {
                let mut base = module.to_vec();
                while segments.first() == Some(&"super") {
                    segments.remove(0);
                    base.pop();
                }
                base
            };
            path.extend(segments.iter().map(|s| s.to_string()));
            let target = (0..=path.len())
                .rev()
                .map(|k| &path[..k])
                .find(|prefix| modules.iter().any(|(m, _)| m == prefix))
                .map(<[String]>::to_vec);
            if let Some(target) = target
                && target != module
            {
                out.push(target);
            }
        }
    }
    out
}

/// No file imports its own caller: two files of a crate never name each
/// other (a shared type goes to a file both import).
#[test]
fn no_two_files_import_each_other() {
    let mut circles = Vec::new();
    for src in source_roots() {
        let modules = modules_of(&src);
        let mut edges = std::collections::BTreeSet::new();
        for (module, file) in &modules {
            let text = std::fs::read_to_string(file).unwrap();
            for target in named_modules(module, &text, &modules) {
                edges.insert((module.clone(), target));
            }
        }
        for (a, b) in &edges {
            if a < b && edges.contains(&(b.clone(), a.clone())) {
                circles.push(format!(
                    "{}: {} <-> {}",
                    src.display(),
                    a.join("::"),
                    b.join("::")
                ));
            }
        }
    }
    assert!(
        circles.is_empty(),
        "files importing each other: {circles:#?}"
    );
}

#[test]
fn a_mutual_import_is_seen() {
    let modules = vec![
        (vec!["step".to_string()], PathBuf::from("step.rs")),
        (
            vec!["liquid_grid".to_string()],
            PathBuf::from("liquid_grid.rs"),
        ),
    ];
    let step = named_modules(&modules[0].0, "use super::liquid_grid::Grid;", &modules);
    let grid = named_modules(
        &modules[1].0,
        "use crate::step::Particle; // crate::nothing",
        &modules,
    );
    assert_eq!(step, [vec!["liquid_grid".to_string()]]);
    assert_eq!(grid, [vec!["step".to_string()]]);
}
