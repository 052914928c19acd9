//! Outputs are durable before they are visible, and no command deletes an
//! input (#24, #30): the order of syncs and publishing renames of `map --out`
//! (new folder, `--force` over an old one, the two-rename fallback), checked
//! with the library's recorded trace and, where the machine lets it run, with
//! `strace` on the real binary; an injected sync failure that leaves the old
//! output in place; and a closed pipe. (The `fos --state` data loss is pinned
//! in `tests/it/hardening.rs`, beside the other inputs-as-outputs cases.)

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use a3d_init::pipeline::ErrorKind;
use a3d_init::pipeline::fem::FemOptions;
use a3d_init::pipeline::io::output::Destination;
use a3d_init::pipeline::io::output::trace::{self, Event};
use a3d_init::pipeline::map::MapConfig;
use a3d_init::pipeline::map::job::{self, MapJob};
use common::{fixture, run_map};

/// `map` of the shipped slope into `out`, as arguments of the binary.
fn slope_map_args(out: &Path) -> Vec<String> {
    let path = |p: PathBuf| p.display().to_string();
    vec![
        "map".into(),
        "--fem".into(),
        path(fixture("slope/sand-nodes.csv")),
        "--mpm".into(),
        path(fixture("slope")),
        "--out".into(),
        path(out.to_path_buf()),
    ]
}

fn slope_job() -> MapJob {
    MapJob {
        model: fixture("slope"),
        fem: FemOptions::files(vec![fixture("slope/sand-nodes.csv")]),
        config: MapConfig::default(),
        generate_cps: false,
        fem_vtu: false,
    }
}

/// Every file of `target` was synced (in the staging folder) before the
/// publishing rename of `target`, the staging folder too, and `target`'s
/// parent folder after it.
#[track_caller]
fn assert_durable_order(events: &[Event], target: &Path) {
    let rename = events
        .iter()
        .position(|e| *e == Event::Rename(target.to_path_buf()))
        .unwrap_or_else(|| panic!("no rename onto {}: {events:#?}", target.display()));
    let synced_before: Vec<&PathBuf> = events[..rename]
        .iter()
        .filter_map(|e| match e {
            Event::SyncFile(p) | Event::SyncDir(p) => Some(p),
            Event::Rename(_) => None,
        })
        .collect();
    for entry in std::fs::read_dir(target).unwrap() {
        let name = entry.unwrap().file_name();
        assert!(
            synced_before
                .iter()
                .any(|p| p.file_name() == Some(name.as_os_str())
                    && p.parent().is_some_and(|d| d != target)),
            "{name:?} was not synced in the staging folder before the rename: {events:#?}"
        );
    }
    let staging = synced_before.iter().find(|p| {
        p.file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with(".a3d-init-staging-"))
    });
    assert!(
        staging.is_some(),
        "the staging folder was not synced: {events:#?}"
    );
    let parent = target.parent().unwrap();
    assert!(
        events[rename..].contains(&Event::SyncDir(parent.to_path_buf())),
        "the parent folder was not synced after the rename: {events:#?}"
    );
}

/// One test, so that the recorded trace (process-wide) holds one run at a time.
#[test]
fn map_outputs_are_synced_before_the_publishing_rename_and_a_failed_sync_keeps_the_old_output() {
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("out");
    let job = slope_job();

    // A new folder.
    trace::start();
    job::map(&job, Destination::new(Some(&target), false)).unwrap();
    assert_durable_order(&trace::take(), &target);

    // --force over the old one (RENAME_EXCHANGE).
    trace::start();
    job::map(&job, Destination::new(Some(&target), true)).unwrap();
    assert_durable_order(&trace::take(), &target);

    // The two-rename fallback.
    trace::disable_exchange(true);
    trace::start();
    let result = job::map(&job, Destination::new(Some(&target), true));
    trace::disable_exchange(false);
    result.unwrap();
    assert_durable_order(&trace::take(), &target);

    // An injected sync failure: an error of the run (kind Output, naming the
    // file), the old output intact, nothing left beside it.
    let before: Vec<(std::ffi::OsString, Vec<u8>)> = {
        let mut v: Vec<_> = std::fs::read_dir(&target)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                (e.file_name(), std::fs::read(e.path()).unwrap())
            })
            .collect();
        v.sort();
        v
    };
    std::fs::write(target.join("marker.txt"), "old output").unwrap();
    for (failing, exchange) in [
        ("mps.csv", true),
        (".a3d-init-staging-", true),
        ("mps.csv", false),
    ] {
        trace::disable_exchange(!exchange);
        trace::fail_sync_of(Some(failing));
        let result = job::map(&job, Destination::new(Some(&target), true));
        trace::fail_sync_of(None);
        trace::disable_exchange(false);
        let Err(e) = result else {
            panic!("a failed sync of {failing} must fail the run");
        };
        assert_eq!(e.kind(), ErrorKind::Output, "{e}");
        assert!(
            e.to_string().contains("syncing") && e.to_string().contains(failing),
            "{e}"
        );
        assert_eq!(
            std::fs::read_to_string(target.join("marker.txt")).unwrap(),
            "old output",
            "the old output was replaced although a sync failed ({failing})"
        );
        for (name, bytes) in &before {
            assert_eq!(
                &std::fs::read(target.join(name)).unwrap(),
                bytes,
                "{name:?}"
            );
        }
        let left: Vec<_> = std::fs::read_dir(tmp.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left, ["out"], "staging left behind ({failing})");
    }
}

/// An output error through the binary (here: an existing folder without
/// `--force`) exits 2, naming the path and the flag.
#[test]
fn an_output_error_exits_2_and_names_the_path() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let (fem, slope) = (fixture("slope/sand-nodes.csv"), fixture("slope"));
    assert_eq!(run_map(&slope, &fem, &out, &[]).0, 0);
    let (code, text) = run_map(&slope, &fem, &out, &[]);
    assert_eq!(code, 2, "{text}");
    assert!(
        text.contains(&format!("{} exists; pass --force", out.display())),
        "{text}"
    );
}

/// The same order seen from outside: `strace` on the real binary (where
/// ptrace is allowed), every file of the new folder `fsync`ed before the
/// `renameat2` that publishes it, and the parent folder after it.
#[test]
#[allow(clippy::print_stderr)] // a skip must be visible in the test output
fn strace_sees_every_output_synced_before_the_rename() {
    let works = Command::new("strace")
        .args(["-f", "-o", "/dev/null", "true"])
        .status()
        .is_ok_and(|s| s.success());
    if !works {
        eprintln!(
            "SKIPPED strace_sees_every_output_synced_before_the_rename: strace cannot run here (the recorded trace above covers the order)"
        );
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let log = tmp.path().join("strace.log");
    for force in [false, true] {
        let out = tmp.path().join("out");
        let mut args = vec![
            "-f".to_string(),
            "-y".into(),
            "-e".into(),
            "trace=fsync,fdatasync,rename,renameat,renameat2".into(),
            "-o".into(),
            log.display().to_string(),
            env!("CARGO_BIN_EXE_a3d-init").into(),
        ];
        args.extend(slope_map_args(&out));
        if force {
            args.push("--force".into());
        }
        let status = Command::new("strace").args(&args).status().unwrap();
        assert!(status.success());
        let text = std::fs::read_to_string(&log).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let out_name = out.display().to_string();
        let publish = lines
            .iter()
            .position(|l| {
                l.contains("renameat2(")
                    && l.contains(".a3d-init-staging-")
                    && l.contains(&format!("\"{out_name}\""))
            })
            .unwrap_or_else(|| panic!("no renameat2 onto {out_name}:\n{text}"));
        for entry in std::fs::read_dir(&out).unwrap() {
            let name = entry.unwrap().file_name().to_string_lossy().into_owned();
            assert!(
                lines[..publish].iter().any(|l| l.contains("fsync(")
                    && l.contains(".a3d-init-staging-")
                    && l.contains(&format!("/{name}>"))),
                "{name} not fsynced before the rename (force {force}):\n{text}"
            );
        }
        let parent = tmp.path().display().to_string();
        assert!(
            lines[publish..]
                .iter()
                .any(|l| l.contains("fsync(") && l.contains(&format!("<{parent}>"))),
            "the parent folder was not fsynced after the rename (force {force}):\n{text}"
        );
    }
}

/// A pipe whose reader is already gone: every write to it fails with EPIPE.
fn closed_pipe() -> std::process::Stdio {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    writer.into()
}

/// Regression (#30): `a3d-init inspect --fem f.csv 2>&1 | head -1` aborted
/// (SIGABRT, exit 134) when the reader had gone: writing the broken-pipe error
/// to the same closed pipe panicked, and the panic hook's own print panicked
/// again. Now output stops quietly and the command keeps its exit code.
#[test]
fn regression_a_closed_pipe_is_not_a_crash() {
    let fem = fixture("geostudio-csv/k0-slope-hydrostatic.csv");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let cases: [(Vec<String>, bool, bool); 5] = [
        // stdout closed, stderr read.
        (
            vec!["inspect".into(), "--fem".into(), fem.display().to_string()],
            true,
            false,
        ),
        (
            vec!["inspect".into(), fixture("slope").display().to_string()],
            true,
            false,
        ),
        (
            vec![
                "inspect".into(),
                "--fem".into(),
                fem.display().to_string(),
                "--json".into(),
            ],
            true,
            false,
        ),
        // Both closed, as with `2>&1 | head -1`.
        (
            vec!["inspect".into(), "--fem".into(), fem.display().to_string()],
            true,
            true,
        ),
        // map prints to stderr: closed; its output is complete.
        (slope_map_args(&out), true, true),
    ];
    for (args, close_out, close_err) in cases {
        let mut command = common::bin();
        command.args(&args).stdin(std::process::Stdio::null());
        command.stdout(if close_out {
            closed_pipe()
        } else {
            std::process::Stdio::piped()
        });
        command.stderr(if close_err {
            closed_pipe()
        } else {
            std::process::Stdio::piped()
        });
        let output = command.output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(
            output.status.code(),
            Some(0),
            "{args:?}: {:?} {stderr}",
            output.status
        );
        assert!(
            !stderr.contains("panicked") && !stderr.contains("internal error"),
            "{args:?}: {stderr}"
        );
    }
    assert!(out.join("report.json").is_file());
    // A negative verdict keeps its exit code with stdout closed.
    let (a, b) = (tmp.path().join("a.csv"), tmp.path().join("b.csv"));
    std::fs::write(&a, "x,y\n1,2\n").unwrap();
    std::fs::write(&b, "x,y\n1,3\n").unwrap();
    let output = common::bin()
        .args(["diff", a.to_str().unwrap(), b.to_str().unwrap()])
        .stdout(closed_pipe())
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1), "{output:?}");
}

/// Regression (#38): fuzzing stopped `run`, `verify`, `fos` and `map` with
/// Ctrl-C or SIGTERM and found their hidden staging folder left behind (for
/// `run` and `verify` inside the map folder), with the snapshots written so
/// far in it. Now the signal's handler deletes the unfinished output and
/// the command ends with 130, for SIGINT, SIGTERM and SIGHUP alike.
#[test]
fn an_interrupted_run_leaves_no_output_behind() {
    use std::time::{Duration, Instant};
    let tmp = tempfile::tempdir().unwrap();
    let map = tmp.path().join("m");
    let (fem, slope) = (fixture("slope/sand-nodes.csv"), fixture("slope"));
    assert_eq!(run_map(&slope, &fem, &map, &[]).0, 0);
    let names = |dir: &Path| -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    };
    let before = names(&map);
    for signal in ["INT", "TERM", "HUP"] {
        // `run` writes into a staging folder inside the map folder (its
        // default output is `m/run`) for the whole simulated time.
        let mut child = common::bin()
            .args(["run", map.to_str().unwrap(), "--time", "3"])
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let deadline = Instant::now() + Duration::from_secs(120);
        while !names(&map)
            .iter()
            .any(|n| n.starts_with(".a3d-init-staging-"))
        {
            assert!(
                child.try_wait().unwrap().is_none(),
                "run ended before SIG{signal} was sent"
            );
            assert!(Instant::now() < deadline, "no staging folder appeared");
            std::thread::sleep(Duration::from_millis(20));
        }
        let pid = child.id().to_string();
        let killed = Command::new("kill").args(["-s", signal, &pid]).status();
        assert!(killed.unwrap().success());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "SIG{signal}: {stderr}");
        assert!(
            stderr.contains("interrupted: removed the unfinished output"),
            "SIG{signal}: {stderr}"
        );
        assert_eq!(names(&map), before, "left behind after SIG{signal}");
    }
}
