//! Repository hygiene: every Rust file opens with a `//!` paragraph saying what
//! it owns, and no stub macros are left in the library.

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
    for dir in ["src", "tests", "benches", "examples"] {
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
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    let stubs = ["todo!(", "unimplemented!(", "dbg!("];
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        for stub in stubs {
            assert!(!text.contains(stub), "{} contains {stub}", path.display());
        }
    }
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
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&root, &mut files);
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
