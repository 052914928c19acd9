//! `a3d-init demo` on the shipped slope: counts, no null points, the calibrated
//! h/l in the paper's range, one MAPF row per MP, readable plots, the two
//! factors of safety printed as measured, and a folder that `inspect` reads
//! back without warnings.

use crate::common;

use std::process::Command;

#[test]
fn demo_runs_the_whole_chain() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("demo");
    let o = Command::new(env!("CARGO_BIN_EXE_a3d-init"))
        .args(["demo", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        stdout.contains("OpenGeoSys") && stdout.contains("1.56 h"),
        "the OGS field and the paper's failure time are named: {stdout}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    // The first OGS output at or past the failure time FS(t) measured (#26, #39).
    assert_eq!(report["fem_nodes"], 793);
    let curve: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("fos_time.json")).unwrap()).unwrap();
    let crossing = curve["crossing"]["time_h"].as_f64().unwrap();
    assert!(
        stdout.contains(&format!("first FS ≤ 1 at t = {crossing:.3} h"))
            && stdout.contains(&format!("failure time: {crossing:.3} h measured")),
        "the measured failure time is printed: {stdout}"
    );
    assert_eq!(report["material_points"], 5040);
    assert_eq!(report["null_points"], 0);
    let h_over_l =
        report["smoothing_length"].as_f64().unwrap() / report["fem_spacing"].as_f64().unwrap();
    assert!((0.7..=1.0).contains(&h_over_l), "h/l = {h_over_l}");
    let mapf = a3d_init::formats::mapf::read(&out.join("slope.MAPF")).unwrap();
    assert_eq!(mapf.rows.len(), 5040);
    // Step 7 (#39): the same output mapped onto the paper's MPM model, and
    // the one command that runs it out.
    let flume = a3d_init::formats::mapf::read(&out.join("flume/flume.MAPF")).unwrap();
    assert_eq!(flume.rows.len(), 3600);
    let run_line = format!("run it: a3d-init run {}", out.join("flume").display());
    assert!(stdout.contains(&run_line), "{stdout}");
    for f in [
        "pwp.svg",
        "effective_stress_yy.svg",
        "total_stress_yy.svg",
        "calibration.svg",
        "fos_vs_time.svg",
        "fos_vs_time.csv",
        "fos_crossing.svg",
        "verify/verify.json",
        "verify/verify_history.svg",
        "fos_zero_pwp/fos.json",
        "fos_zero_pwp/fos_surface.svg",
        "fos_mapped/fos.json",
        "fos_mapped/fos_surface.svg",
    ] {
        let text = std::fs::read_to_string(out.join(f)).unwrap_or_default();
        assert!(text.len() > 1000, "{f} is written");
    }
    // Step 5 prints the two measured factors, the same as in fos.json (#18).
    for (name, label) in [("fos_zero_pwp", "zero pwp:"), ("fos_mapped", "mapped pwp:")] {
        let fos: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join(name).join("fos.json")).unwrap(),
        )
        .unwrap();
        let factor = fos["factor"].as_f64().unwrap();
        let line = stdout.lines().find(|l| l.contains(label)).unwrap_or("");
        assert!(
            line.contains(&format!("FS = {factor:.3}")),
            "{label} FS {factor} printed: {stdout}"
        );
    }
    docs_quote_the_run(tmp.path(), &out);
    map_step_failure_is_the_demos_map(tmp.path(), &out, &stdout);
    strength_reduction_on_the_dry_slope(tmp.path(), &out);
}

/// A JSON file the demo wrote.
fn json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// docs/slope.md quotes this run: its opening paragraph, FS(t), the
/// minimum-depth rule, and the dry slope against the infinite slope.
fn docs_quote_the_run(tmp: &std::path::Path, out: &std::path::Path) {
    let report = json(&out.join("report.json"));
    let curve = json(&out.join("fos_time.json"));
    // docs/slope.md's opening paragraph quotes this run (#39); line breaks
    // there are only layout.
    let slope_md = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/slope.md"),
    )
    .unwrap()
    .split_whitespace()
    .collect::<Vec<_>>()
    .join(" ");
    let points = curve["curve"].as_array().unwrap();
    let count = |kind: &str| points.iter().filter(|p| p["kind"] == kind).count();
    let solve = &report["equilibrium"];
    let factor_of = |name: &str| -> f64 {
        let fos: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join(name).join("fos.json")).unwrap(),
        )
        .unwrap();
        fos["factor"].as_f64().unwrap()
    };
    for quoted in [
        format!("FS = {:.3} at t = 0", points[0]["factor"].as_f64().unwrap()),
        format!(
            "over {} outputs and {} bisections",
            count("saved"),
            count("bisected")
        ),
        format!(
            "LOO R² = {:.3}",
            report["calibration"]["stats"]["r2"].as_f64().unwrap()
        ),
        format!(
            "(out-of-balance ratio {:.1e} after {} plastic iterations, {} MPs on their yield surface)",
            solve["residual_ratio"].as_f64().unwrap(),
            solve["plastic_iterations"],
            solve["yielding_points"]
        ),
        format!("Morgenstern–Price factor {:.3}", factor_of("fos_mapped")),
        format!("{:.3} with zero pwp", factor_of("fos_zero_pwp")),
    ] {
        assert!(
            slope_md.contains(&quoted),
            "docs/slope.md should quote the measured `{quoted}`"
        );
    }
    // FS(t) as docs/slope.md's *FS(t) by limit equilibrium* quotes it.
    let at = |hours: f64| {
        let point = points
            .iter()
            .find(|p| {
                p["kind"] == "saved" && (p["time"].as_f64().unwrap() - hours * 3600.0).abs() < 1.0
            })
            .unwrap_or_else(|| panic!("no saved output at {hours} h"));
        format!("{:.3}", point["factor"].as_f64().unwrap())
    };
    let quoted = format!(
        "FS = {} at 0 h, {} at 0.5 h, {} at 1.0 h, {} at 1.15 h, {} at 1.2 h, {} at 1.25 h, {} at 1.26 h, {} at 1.29 h, {} at 1.30 h, {} at 1.35 h",
        at(0.0),
        at(0.5),
        at(1.0),
        at(1.15),
        at(1.2),
        at(1.25),
        at(1.26),
        at(1.29),
        at(1.30),
        at(1.35)
    );
    assert!(
        slope_md.contains(&quoted),
        "docs/slope.md should quote `{quoted}`"
    );
    let quoted = format!(
        "1.26 h (FS = {}; the output before, 1.25 h, {})",
        at(1.26),
        at(1.25)
    );
    assert!(
        slope_md.contains(&quoted),
        "docs/slope.md should quote `{quoted}`"
    );
    let late: Vec<String> = points
        .iter()
        .filter(|p| p["kind"] == "saved" && p["time"].as_f64().unwrap() >= 1.6 * 3600.0 - 1.0)
        .map(|p| format!("{:.3}", p["factor"].as_f64().unwrap()))
        .collect();
    assert!(
        late.iter()
            .all(|f| slope_md.contains(&format!("{f} from 1.6 h on"))),
        "docs/slope.md says one factor from 1.6 h on: {late:?}"
    );
    // The minimum-depth rule on the dry slope, as docs/slope.md quotes it.
    let depths: Vec<String> = ["0.05", "0.145", "0.3", "0.6"]
        .iter()
        .map(|d| {
            let dir = tmp.join(format!("depth{d}"));
            let (_, fos) = common::fos(out, &dir, &["--zero-pwp", "--min-depth", d]);
            format!("{:.3}", fos["factor"].as_f64().unwrap())
        })
        .collect();
    let quoted = format!(
        "D = 0.05 m gives {}, 0.145 m (the default) {}, 0.3 m {}, 0.6 m (the sand layer) {}",
        depths[0], depths[1], depths[2], depths[3]
    );
    assert!(
        slope_md.contains(&quoted),
        "docs/slope.md should quote `{quoted}`"
    );
    // The dry sand layer is an infinite slope: long shallow surfaces approach
    // tan 33°/tan 32° = 1.039 from above (end effects), whatever the trial
    // count (#39).
    let dry: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("fos_zero_pwp/fos.json")).unwrap())
            .unwrap();
    let dry = dry["factor"].as_f64().unwrap();
    let infinite = 33f64.to_radians().tan() / 32f64.to_radians().tan();
    assert!(
        (infinite..infinite + 0.01).contains(&dry),
        "dry factor {dry} vs the infinite slope's {infinite}"
    );
}

/// `map --step failure` with the flags the demo prints writes the same MAPF
/// as the demo's map step, and its report names the step; the folder reads
/// back without warnings.
fn map_step_failure_is_the_demos_map(tmp: &std::path::Path, out: &std::path::Path, stdout: &str) {
    let line = stdout
        .lines()
        .find(|l| l.contains("--step failure"))
        .expect("the demo prints the one-step command");
    let args: Vec<&str> = line[line.find("map --fem").unwrap()..]
        .split_whitespace()
        .collect();
    let failure = tmp.join("failure");
    let o = Command::new(env!("CARGO_BIN_EXE_a3d-init"))
        .args(&args)
        .args(["--out", failure.to_str().unwrap()])
        .output()
        .unwrap();
    // 1: the slope cannot stand at the failure time (the folder is written).
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    assert_eq!(
        std::fs::read(failure.join("slope.MAPF")).unwrap(),
        std::fs::read(out.join("slope.MAPF")).unwrap(),
        "map --step failure writes the demo's MAPF"
    );
    let chosen: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(failure.join("report.json")).unwrap())
            .unwrap();
    let chosen = &chosen["failure"];
    assert_eq!(chosen["method"], "morgenstern-price");
    assert!(chosen["factor"].as_f64().unwrap() <= 1.0, "{chosen}");
    assert!(chosen["before"][1].as_f64().unwrap() > 1.0, "{chosen}");
    let t = chosen["time"].as_f64().unwrap();
    assert!(
        stdout.contains(&format!("OGS output t = {:.2} h", t / 3600.0)),
        "the demo maps the same output: {stdout}"
    );
    let svg = std::fs::read_to_string(out.join("pwp.svg")).unwrap();
    assert!(
        svg.contains("x (m)") && svg.contains("y (m)") && svg.contains("pwp (kPa)"),
        "axes and colour bar are labelled"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_a3d-init"))
        .args(["inspect", out.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert_eq!(o.status.code(), Some(0));
    assert!(text.contains("warnings   none"), "{text}");
}

/// Strength reduction on the dry slope, as docs/slope-stability.md runs it:
/// seconds again (not minutes), within 2 % of limit equilibrium, and the four
/// measures the table quotes; docs/slope.md's table of both states.
fn strength_reduction_on_the_dry_slope(tmp: &std::path::Path, out: &std::path::Path) {
    let dry = json(&out.join("fos_zero_pwp/fos.json"))["factor"]
        .as_f64()
        .unwrap();
    let srm = tmp.join("srm_dry");
    let (text, fos) = common::fos(out, &srm, &["--method", "srm", "--zero-pwp"]);
    let factor = fos["factor"].as_f64().unwrap();
    assert!(
        (factor / dry - 1.0).abs() < 0.02,
        "SRM {factor} against LE {dry}: {text}"
    );
    assert!(fos["iterations"].as_u64().unwrap() <= 8, "{text}");
    common::assert_four_measures_quoted("shipped slope, dry", &srm.join("fos.json"));
    // docs/slope.md's table of both states, the mapped one run here too.
    let mapped = tmp.join("srm_mapped");
    common::fos(out, &mapped, &["--method", "srm"]);
    let slope_md = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/slope.md"),
    )
    .unwrap();
    for (label, dir) in [
        ("zero pore pressure (σ′ = σ)", &srm),
        ("mapped pore pressures (1.26 h), held", &mapped),
    ] {
        let fos: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("fos.json")).unwrap()).unwrap();
        let c = &fos["comparison"];
        let quoted = format!(
            "| {label} | {:.3} | {:.3} | {:.3} | {:.3} |",
            fos["factor"].as_f64().unwrap(),
            c["limit_equilibrium"].as_f64().unwrap(),
            c["limit_equilibrium_davis"].as_f64().unwrap(),
            c["equilibrium_solve"]["holds"].as_f64().unwrap()
        );
        assert!(
            slope_md.contains(&quoted),
            "docs/slope.md should quote `{quoted}`"
        );
    }
}

/// The demo's figures the README quotes (h, h/l, MP count, the σ'zz defect's
/// count and size, the out-of-balance ratios of the geostatic and the
/// equilibrium maps) are what the demo measures (#24, #25): a README edit
/// that drifts from the code, or a code change that moves a figure, fails
/// here.
#[test]
fn readme_figures_are_the_demos_measurements() {
    let readme =
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md"))
            .unwrap();
    let (out, _) = common::demo_no_fos();
    let json = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(out.join(name)).unwrap()).unwrap()
    };
    let report = json("report.json");
    let verify = json("verify/verify.json");
    let h = report["smoothing_length"].as_f64().unwrap();
    let h_over_l = h / report["fem_spacing"].as_f64().unwrap();
    let mps = report["material_points"].as_u64().unwrap();
    let defect = &verify["anura3d"]["sigma_zz_defect"];
    let outside = defect["outside_because_of_defect"].as_u64().unwrap();
    let change_yy = defect["first_step_change"][1].as_f64().unwrap();
    let geostatic = json("geostatic/verify/verify.json")["run"]["initial_residual_ratio"]
        .as_f64()
        .unwrap();
    let equilibrium = verify["run"]["initial_residual_ratio"].as_f64().unwrap();
    // At the failure time the slope cannot stand: the solve says so, and its
    // best state is still far closer to balance than the geostatic map.
    let solve = &report["equilibrium"];
    assert_eq!(solve["equilibrium"], false);
    assert!(
        equilibrium < 0.5 * geostatic,
        "{equilibrium} vs {geostatic}"
    );
    let crossing = json("fos_time.json")["crossing"]["time_h"]
        .as_f64()
        .unwrap();
    // docs/slope.md's *What the chain gives* (#39).
    let slope_md = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/slope.md"),
    )
    .unwrap();
    let signed = |v: f64| {
        if v < 0.0 {
            format!("−{:.2}", -v)
        } else {
            format!("+{v:.2}")
        }
    };
    let pwp = &report["pwp_range"];
    let holds = solve["strength_factor"]["holds"].as_f64().unwrap();
    assert!(holds < 1.0, "no rest at F = 1: {holds}");
    let elements = verify["run"]["n_elements"].as_u64().unwrap();
    for quoted in [
        format!("| FEM nodes | {} (OGS output at", report["fem_nodes"]),
        format!("| h = {h:.4} m, h/l = {h_over_l:.2} |"),
        format!("| {elements} TRI3, {mps} MPs"),
        format!(
            "| {} … {} kPa (Anura3D sign) |",
            signed(pwp[0].as_f64().unwrap()),
            signed(pwp[1].as_f64().unwrap())
        ),
        format!("| initial out-of-balance force ratio {geostatic:.2} |"),
        format!(
            "| no state at rest: ratio {equilibrium:.3} left; rest only with the strengths divided by up to F = {holds:.3} |"
        ),
    ] {
        assert!(
            slope_md.contains(&quoted),
            "docs/slope.md should quote the measured `{quoted}`"
        );
    }
    for quoted in [
        format!("h = {h:.3} m, h/l = {h_over_l:.2}"),
        format!("onto the {mps} material"),
        format!("first falls to 1 at {crossing:.2} h"),
        format!("{outside} of {mps} MPs,\n  up to {change_yy:.1} kPa in σ'yy"),
        format!("(out-of-balance force ratio {geostatic:.2} there, {equilibrium:.2} for the"),
    ] {
        assert!(
            readme.contains(&quoted),
            "README.md should quote the measured `{quoted}`"
        );
    }
}
