//! Running the real Anura3D kernel (the oracle) on a folder written by `map`
//! and reading what it wrote: the binary legacy VTK of the material points
//! (`<project>_MPVector_001.vtk`, big-endian doubles).

use std::path::{Path, PathBuf};

/// Runs the kernel undamped for `time` s on a copy of the map folder `out`
/// (GOM, CPS, MAPF, OPD; the project is named `slope`) in `run`, and returns
/// the VTK of its material points at the end.
pub fn run_kernel(bin: &Path, out: &Path, run: &Path, time: f64) -> PathBuf {
    std::fs::create_dir_all(run).unwrap();
    for entry in std::fs::read_dir(out).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        if name.contains(".GOM") || name.ends_with(".MAPF") || name.contains(".OPD") {
            std::fs::copy(&path, run.join(&name)).unwrap();
        }
        if name.ends_with(".CPS_001") {
            let cps = std::fs::read_to_string(&path).unwrap();
            let edited = edit_cps(&cps, time);
            std::fs::write(run.join(&name), edited).unwrap();
        }
    }
    run_in_place(bin, run)
}

/// Runs the kernel on the project `slope` in `dir` as it is; the VTK of its
/// material points at the end.
pub fn run_in_place(bin: &Path, dir: &Path) -> PathBuf {
    let status = std::process::Command::new(bin)
        .arg("slope")
        .current_dir(dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .unwrap();
    let vtk = dir.join("slope_MPVector_001.vtk");
    assert!(
        status.success() || vtk.is_file(),
        "the kernel failed in {}",
        dir.display()
    );
    vtk
}

/// Runs the kernel (as [`run_kernel`]) and returns the largest MP
/// displacement it reports.
pub fn kernel_displacement(bin: &Path, out: &Path, run: &Path, time: f64) -> f64 {
    let vtk = run_kernel(bin, out, run, time);
    vtk_vectors(&vtk, "displacement_solid")
        .iter()
        .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
        .fold(0.0, f64::max)
}

/// The CPS with `$$TIME_PER_LOADSTEP` `time`, no damping and a dynamic load
/// step.
pub fn edit_cps(cps: &str, time: f64) -> String {
    let mut lines: Vec<String> = Vec::new();
    let mut it = cps.lines();
    while let Some(line) = it.next() {
        let value = match line.trim() {
            "$$TIME_PER_LOADSTEP" => Some(time.to_string()),
            "$$QUASISTATIC_CONVERGENCE" => Some("0".into()),
            "$$HOMOGENEOUS_LOCAL_DAMPING" => Some("0 0.0".into()),
            _ => None,
        };
        lines.push(line.to_string());
        if let Some(v) = value {
            it.next();
            lines.push(v);
        }
    }
    let mut text = lines.join("\n") + "\n";
    if !text.contains("$$TIME_PER_LOADSTEP") {
        text = text.replace("$$END", &format!("$$TIME_PER_LOADSTEP\n{time}\n$$END"));
    }
    text
}

/// The bytes of the VTK, the number of points and where the data of the
/// array `header` (e.g. `VECTORS displacement_solid`) starts.
fn vtk_array(path: &Path, header: &str) -> (Vec<u8>, usize, usize) {
    let data = std::fs::read(path).unwrap();
    let find = |key: &[u8]| {
        data.windows(key.len())
            .position(|w| w == key)
            .unwrap_or_else(|| panic!("{} in {}", String::from_utf8_lossy(key), path.display()))
    };
    let line_after = |at: usize| at + data[at..].iter().position(|&b| b == b'\n').unwrap();
    let points = find(b"POINTS");
    let line = std::str::from_utf8(&data[points..line_after(points)]).unwrap();
    let count: usize = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    let mut start = line_after(find(header.as_bytes())) + 1;
    if header.starts_with("SCALARS") {
        // A LOOKUP_TABLE line follows.
        start = line_after(start) + 1;
    }
    (data, count, start)
}

/// The vectors of `name`, as three big-endian doubles per point.
pub fn vtk_vectors(path: &Path, name: &str) -> Vec<[f64; 3]> {
    let (data, count, start) = vtk_array(path, &format!("VECTORS {name} "));
    data[start..start + count * 24]
        .chunks(24)
        .map(|c| {
            let v: Vec<f64> = c
                .chunks(8)
                .map(|b| f64::from_be_bytes(b.try_into().unwrap()))
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

/// The scalars of `name` (big-endian doubles, one per point).
pub fn vtk_scalars(path: &Path, name: &str) -> Vec<f64> {
    let (data, count, start) = vtk_array(path, &format!("SCALARS {name} "));
    data[start..start + count * 8]
        .chunks(8)
        .map(|b| f64::from_be_bytes(b.try_into().unwrap()))
        .collect()
}
