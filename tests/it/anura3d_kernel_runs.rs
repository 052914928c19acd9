//! The longest runs of the real Anura3D kernel, in a module of their own
//! because libtest starts tests in the order of their names: a test here
//! starts first, so its single-threaded kernel run (minutes) overlaps the
//! rest of the suite instead of running alone at its end. Each test says
//! which comparison it belongs to.
//!
//! The two-phase demo slope (#27, #40): the coupled runner against the
//! kernel on the demo's mapped slope, beside `two_phase`'s column.

use crate::common;
use crate::two_phase::run_undamped;
use common::kernel_run::{run_kernel, vtk_scalars, vtk_vectors};
use common::{anura3d_kernel_or_skip, demo_no_fos};

/// The demo slope (the OpenGeoSys rain at the failure time, partially
/// saturated sand on a dry clay base, MPM-MIXED, 5,040 MPs) run undamped for
/// 0.2 s by the real kernel and by `run`, as a user runs it. The kernel runs
/// at Courant 0.5: at its default 0.98 its own saturated-zone pore pressures
/// are not settled in Δt (mean −0.73 kPa there vs −1.05 kPa at 0.5, while
/// this runner gives −1.067 / −1.042 kPa at Courant 0.9 / 0.2; docs/two-phase.md).
#[test]
#[allow(clippy::print_stderr)] // the measured values belong in the test output
fn anura3d_kernel_demo_slope_within_twenty_percent() {
    let Some(bin) = anura3d_kernel_or_skip("anura3d_kernel_demo_slope_within_twenty_percent")
    else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let (demo, _) = demo_no_fos();
    let time = 0.2;
    // The kernel's copy, at Courant 0.5.
    let project = tmp.path().join("kernel-project");
    std::fs::create_dir_all(&project).unwrap();
    for name in ["slope.GOM", "slope.MAPF"] {
        std::fs::copy(demo.join(name), project.join(name)).unwrap();
    }
    let cps = std::fs::read_to_string(demo.join("slope.CPS_001")).unwrap();
    assert!(!cps.contains("$$COURANT_NUMBER"));
    std::fs::write(
        project.join("slope.CPS_001"),
        cps.replace("$$END", "$$COURANT_NUMBER\n0.5\n$$END"),
    )
    .unwrap();
    let vtk = run_kernel(&bin, &project, &tmp.path().join("kernel"), time);
    let kernel_u = vtk_vectors(&vtk, "displacement_solid");
    let kernel_p = vtk_scalars(
        &vtk.with_file_name("slope_MPScalar_001.vtk"),
        "pressure_liquid",
    );
    let start_p = vtk_scalars(
        &vtk.with_file_name("slope_MPScalar_000.vtk"),
        "pressure_liquid",
    );

    let report = run_undamped(demo, &tmp.path().join("ours"), time);
    assert_eq!(
        report["formulations"][0],
        serde_json::json!([1, "coupled"]),
        "the sand runs two-phase"
    );
    let numbers = |v: &serde_json::Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let our_u: Vec<f64> = report["final_displacements"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| numbers(v).iter().map(|x| x * x).sum::<f64>().sqrt())
        .collect();
    let our_p = numbers(&report["final_pore_pressures"]);
    assert_eq!(our_p.len(), kernel_p.len());
    let kernel_max = kernel_u
        .iter()
        .map(|v| (v[0] * v[0] + v[1] * v[1]).sqrt())
        .fold(0.0, f64::max);
    let our_max = our_u.iter().copied().fold(0.0, f64::max);
    eprintln!("largest displacement: kernel {kernel_max:.4e} m, ours {our_max:.4e} m");
    assert!(
        (our_max / kernel_max - 1.0).abs() < 0.2,
        "largest displacement: kernel {kernel_max:.4e} m, ours {our_max:.4e} m"
    );

    let points = a3d_init::pipeline::Project::load(demo).unwrap().points;
    let sand = |k: usize| points[k].material == 1;
    // Monitored MPs in the suction zone: the sand MP nearest to each point
    // 0.15 m below the top of its column, from crest to toe (measured: within
    // 0.8 % of the kernel; docs/two-phase.md).
    for x in [0.5, 1.5, 2.5, 3.5, 4.5, 5.5] {
        let top = (0..points.len())
            .filter(|&k| sand(k) && (points[k].position[0] - x).abs() < 0.05)
            .map(|k| points[k].position[1])
            .fold(f64::NEG_INFINITY, f64::max);
        let k = (0..points.len())
            .filter(|&k| sand(k))
            .min_by(|&a, &b| {
                let d = |k: usize| {
                    let p = points[k].position;
                    (p[0] - x).powi(2) + (p[1] - (top - 0.15)).powi(2)
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        eprintln!(
            "MP {} at ({:.3}, {:.3}): p from {:.4} to kernel {:.4}, ours {:.4} kPa",
            points[k].id,
            points[k].position[0],
            points[k].position[1],
            start_p[k],
            kernel_p[k],
            our_p[k]
        );
        assert!(start_p[k] > 0.0, "MP {} is in suction", points[k].id);
        assert!(
            (our_p[k] / kernel_p[k] - 1.0).abs() < 0.2,
            "MP {}: pore pressure kernel {:.4} kPa, ours {:.4} kPa",
            points[k].id,
            kernel_p[k],
            our_p[k]
        );
    }
    // The saturated zone: its mean pore pressure (single MPs there carry the
    // undamped pressure waves, which differ between the kernel's own runs at
    // two Courant numbers as much as between the two codes).
    let saturated: Vec<usize> = (0..points.len())
        .filter(|&k| sand(k) && start_p[k] < 0.0)
        .collect();
    let mean = |p: &[f64]| saturated.iter().map(|&k| p[k]).sum::<f64>() / saturated.len() as f64;
    let (start, kernel, our) = (mean(&start_p), mean(&kernel_p), mean(&our_p));
    eprintln!(
        "saturated sand ({} MPs): mean p from {start:.4} to kernel {kernel:.4}, ours {our:.4} kPa",
        saturated.len()
    );
    assert!(
        (our / kernel - 1.0).abs() < 0.2,
        "saturated sand: mean p kernel {kernel:.4} kPa, ours {our:.4} kPa"
    );
}
