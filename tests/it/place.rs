//! Material-point placement against Anura3D: the worked 12-MP table of the
//! format notes, the MP totals of the 11 samples, MP positions printed in a
//! shipped Anura3D run, and property tests over random elements for every
//! supported count (inside the element, volumes sum to its measure).

use crate::common;
use common::*;

use a3d_init::element::{LocalPoint, mesh_element};
use a3d_init::formats::gom::GomDocument;
use a3d_init::model::{AnuraModel, Dimension, ElementType, Mesh};
use a3d_init::place::{PlaceError, place_material_points};
use proptest::prelude::*;

fn point_in_element(mesh: &Mesh, e: usize, p: [f64; 3], tol: f64) -> bool {
    mesh_element(mesh.element_type).contains(mesh, e, p, tol)
}

fn element_measure(mesh: &Mesh, e: usize) -> f64 {
    mesh_element(mesh.element_type).measure(mesh, e)
}

fn local_points(et: ElementType, count: u32) -> Option<&'static [LocalPoint]> {
    mesh_element(et).local_points(count)
}

fn model_of(rel: &str) -> AnuraModel {
    GomDocument::read(&fixture(rel)).unwrap().model().unwrap().0
}

#[test]
fn two_material_block_matches_the_worked_table() {
    let model = model_of("anura3d-mini/TwoMat.GOM");
    let mps = place_material_points(&model).unwrap();
    let expected = [
        (1, 1, 1, 0.333333, 0.166667),
        (2, 1, 1, 0.833333, 0.166667),
        (3, 1, 1, 0.833333, 0.666667),
        (4, 2, 1, 0.166667, 0.333333),
        (5, 2, 1, 0.666667, 0.833333),
        (6, 2, 1, 0.166667, 0.833333),
        (7, 3, 2, 1.333333, 0.166667),
        (8, 3, 2, 1.833333, 0.166667),
        (9, 3, 2, 1.833333, 0.666667),
        (10, 4, 2, 1.166667, 0.333333),
        (11, 4, 2, 1.666667, 0.833333),
        (12, 4, 2, 1.166667, 0.833333),
    ];
    assert_eq!(mps.len(), 12);
    for (mp, (id, el, mat, x, y)) in mps.iter().zip(expected) {
        assert_eq!((mp.id, mp.element + 1, mp.material), (id, el, mat));
        assert!(
            (mp.position[0] - x).abs() < 5e-7 && (mp.position[1] - y).abs() < 5e-7,
            "MP {id}: {:?}",
            mp.position
        );
        assert!(
            (mp.volume - 1.0 / 6.0).abs() < 1e-12,
            "MP {id} volume {}",
            mp.volume
        );
    }
}

#[test]
fn sample_mp_totals_match_the_sample_readme() {
    for (rel, total) in [
        ("test-1001/test-1001.GOM", 60),
        ("test-1005_3D/test-1005_3D.GOM", 240),
        ("test-3072/test-3072.GOM", 1680),
        ("ColumCollapse/ColumCollapse.GOM_stage0", 2400),
        (
            "4001_foundation_k0_movingmesh_prescribedveloMP_step/4001_foundation_k0_movingmesh_prescribedveloMP_step.GOM",
            3996,
        ),
        (
            "CC_Plane_MC_2Phase_K0_MIXED/CC_Plane_MC_2Phase_K0_MIXED.GOM",
            600,
        ),
        (
            "CC_AXI_MC_2Phase_K0_MPM-MP/CC_AXI_MC_2Phase_K0_MPM-MP.GOM",
            600,
        ),
        ("K0_phreaticSurf_Geom/K0_phreaticSurf_Geom.GOM", 993),
        ("K0_phreaticSurf_File/K0_phreaticSurf_File.GOM", 945),
        ("Oedo_LE_2D_v2_2/Oedo_LE_2D_v2_2.GOM", 40),
        ("Oedo_LE_2D_v2_3/Oedo_LE_2D_v2_3-2.dat", 10),
    ] {
        let model = model_of(&format!("anura3d/{rel}"));
        let mps = place_material_points(&model).unwrap();
        assert_eq!(mps.len(), total, "{rel}");
        // Ids are contiguous and every MP lies in its element; volumes sum to the element measure.
        let mut per_element = vec![0.0; model.mesh.n_elements()];
        for (i, mp) in mps.iter().enumerate() {
            assert_eq!(mp.id as usize, i + 1);
            assert!(
                point_in_element(&model.mesh, mp.element as usize, mp.position, 1e-9),
                "{rel}: MP {}",
                mp.id
            );
            per_element[mp.element as usize] += mp.volume;
        }
        for (e, v) in per_element.iter().enumerate() {
            if model.element_material[e] > 0 {
                // Axisymmetric: Σ w·det J·x = ∫x dA = area × centroid radius
                // (every rule integrates linear functions exactly).
                let m = match model.mesh.dimension {
                    Dimension::Axisymmetric => {
                        let c = model.mesh.corner_coords(e);
                        let n = model.mesh.element_type.n_corners();
                        let centroid_x = (0..n).map(|i| c[i][0]).sum::<f64>() / n as f64;
                        element_measure(&model.mesh, e) * centroid_x
                    }
                    _ => element_measure(&model.mesh, e),
                };
                assert!(
                    (v - m).abs() <= 1e-12 * m.abs().max(1e-300) * 10.0,
                    "{rel}: element {} sum {v} vs {m}",
                    e + 1
                );
            }
        }
    }
}

#[test]
fn column_collapse_mps_match_anura3d_par_output() {
    // ColumCollapse.PAR_1084/_1138/_1198 (4 significant digits) from the shipped Anura3D run.
    let model = model_of("anura3d/ColumCollapse/ColumCollapse.GOM_stage0");
    let mps = place_material_points(&model).unwrap();
    for (id, x, y) in [
        (1084, 0.98333, 2.13333),
        (1138, 0.98333, 1.23333),
        (1198, 0.98333, 0.23333),
    ] {
        let p = mps[id - 1].position;
        assert!(
            (p[0] - x).abs() < 1e-4 && (p[1] - y).abs() < 1e-4,
            "MP {id} at {p:?}"
        );
    }
    assert_eq!(
        [
            mps[1083].element + 1,
            mps[1137].element + 1,
            mps[1197].element + 1
        ],
        [382, 400, 420]
    );
}

#[test]
fn tetrahedral_old_uses_the_permuted_shape_functions() {
    let nodes = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let mut all = nodes.clone();
    for (a, b) in [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)] {
        let (p, q): ([f64; 3], [f64; 3]) = (nodes[a], nodes[b]);
        all.push([
            (p[0] + q[0]) / 2.0,
            (p[1] + q[1]) / 2.0,
            (p[2] + q[2]) / 2.0,
        ]);
    }
    let mesh = Mesh {
        dimension: Dimension::Cartesian3D,
        element_type: ElementType::TetOld,
        nodes: all,
        connectivity: (0..10).collect(),
    };
    let a = (5.0 - 5f64.sqrt()) / 20.0;
    let b = (5.0 + 3.0 * 5f64.sqrt()) / 20.0;
    // Point 2 of the 4-point rule: ξ = A, η = A, ζ = B ⇒ x = x1(1−2A−B) + x2·B + x3·A + x4·A.
    let tet = mesh_element(ElementType::TetOld);
    let p = tet.global_position(&mesh, 0, [a, a, b]);
    let expected = [b, a, a];
    for k in 0..3 {
        assert!((p[k] - expected[k]).abs() < 1e-15);
    }
    let centroid = tet.global_position(
        &mesh,
        0,
        local_points(ElementType::TetOld, 1).unwrap()[0].xi,
    );
    for v in centroid {
        assert!((v - 0.25).abs() < 1e-15);
    }
}

#[test]
fn bad_elements_are_all_reported_with_their_ids() {
    let mut model = model_of("anura3d-mini/TwoMat.GOM");
    // Make elements 2 and 4 clockwise by swapping two nodes.
    for e in [1usize, 3] {
        model.mesh.connectivity.swap(e * 3 + 1, e * 3 + 2);
    }
    model.mp_counts[2] = (5, 0);
    let errors = place_material_points(&model).unwrap_err().0;
    let ids: Vec<usize> = errors
        .iter()
        .filter_map(PlaceError::element)
        .map(|e| e + 1)
        .collect();
    assert_eq!(ids, [2, 3, 4]);
    assert!(
        errors[0]
            .to_string()
            .starts_with("element 2: clockwise or degenerate triangle"),
        "{}",
        errors[0]
    );
    assert!(
        errors[1]
            .to_string()
            .contains("5 MPs per element is not allowed")
    );
}

#[test]
fn inactive_elements_are_skipped_and_ids_stay_contiguous() {
    let mut model = model_of("anura3d-mini/TwoMat.GOM");
    model.element_material[1] = 0;
    let mps = place_material_points(&model).unwrap();
    assert_eq!(mps.len(), 9);
    assert_eq!(
        mps.iter().map(|m| m.id).collect::<Vec<_>>(),
        (1..=9).collect::<Vec<_>>()
    );
    assert!(mps.iter().all(|m| m.element != 1));
}

#[test]
fn every_rule_has_the_reference_weight_and_points_inside() {
    for et in [ElementType::Tri3, ElementType::TetOld, ElementType::Quad4] {
        for &count in et.allowed_mp_counts() {
            let table = local_points(et, count).unwrap();
            assert_eq!(table.len(), count as usize, "{et:?} {count}");
            let sum: f64 = table.iter().map(|p| p.weight).sum();
            let reference = mesh_element(et).reference_measure();
            assert!(
                (sum - reference).abs() < 1e-12 * reference.max(1.0) * 10.0,
                "{et:?} {count}: {sum}"
            );
            for p in table {
                let [x, y, z] = p.xi;
                let inside = match et {
                    ElementType::Tri3 => x >= 0.0 && y >= 0.0 && x + y <= 1.0,
                    ElementType::TetOld => x >= 0.0 && y >= 0.0 && z >= 0.0 && x + y + z <= 1.0,
                    ElementType::Quad4 => x.abs() <= 1.0 && y.abs() <= 1.0,
                    ElementType::Hex8 => x.abs() <= 1.0 && y.abs() <= 1.0 && z.abs() <= 1.0,
                };
                assert!(inside, "{et:?} {count}: {:?}", p.xi);
            }
        }
    }
}

/// One random element of each type, positively oriented.
fn element_mesh(et: ElementType, coords: &[f64]) -> Option<Mesh> {
    let (dimension, nodes): (Dimension, Vec<[f64; 3]>) = match et {
        ElementType::Tri3 => {
            let mut n: Vec<[f64; 3]> = (0..3)
                .map(|i| [coords[2 * i], coords[2 * i + 1], 0.0])
                .collect();
            let det = (n[1][0] - n[0][0]) * (n[2][1] - n[0][1])
                - (n[2][0] - n[0][0]) * (n[1][1] - n[0][1]);
            if det.abs() < 1e-3 {
                return None;
            }
            if det < 0.0 {
                n.swap(1, 2);
            }
            (Dimension::PlaneStrain, n)
        }
        ElementType::Quad4 => {
            // A convex quad: a parallelogram-ish jitter of the unit square scaled.
            let (cx, cy, s) = (coords[0], coords[1], 0.5 + coords[2].abs());
            let j = |k: usize| coords[3 + k] / 10.0 * 0.2 * s;
            let n = vec![
                [cx - s + j(0), cy - s + j(1), 0.0],
                [cx + s + j(2), cy - s + j(3), 0.0],
                [cx + s + j(4), cy + s + j(5), 0.0],
                [cx - s + j(6), cy + s + j(7), 0.0],
            ];
            (Dimension::PlaneStrain, n)
        }
        ElementType::TetOld => {
            let mut n: Vec<[f64; 3]> = (0..4)
                .map(|i| [coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]])
                .collect();
            let sub = |u: [f64; 3], v: [f64; 3]| [u[0] - v[0], u[1] - v[1], u[2] - v[2]];
            let (u, v, w) = (sub(n[1], n[0]), sub(n[2], n[0]), sub(n[3], n[0]));
            let t = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
                + u[2] * (v[0] * w[1] - v[1] * w[0]);
            if t.abs() < 1e-2 {
                return None;
            }
            if t < 0.0 {
                n.swap(2, 3);
            }
            for (a, b) in [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)] {
                let (p, q) = (n[a], n[b]);
                n.push([
                    (p[0] + q[0]) / 2.0,
                    (p[1] + q[1]) / 2.0,
                    (p[2] + q[2]) / 2.0,
                ]);
            }
            (Dimension::Cartesian3D, n)
        }
        // CB-Geo's hexahedron: Anura3D places no MPs in it.
        ElementType::Hex8 => return None,
    };
    let connectivity = (0..nodes.len() as u32).collect();
    Some(Mesh {
        dimension,
        element_type: et,
        nodes,
        connectivity,
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn random_elements_hold_their_mps(coords in prop::collection::vec(-10.0f64..10.0, 12), pick in 0usize..3) {
        let et = [ElementType::Tri3, ElementType::TetOld, ElementType::Quad4][pick];
        let Some(mesh) = element_mesh(et, &coords) else { return Ok(()) };
        let measure = element_measure(&mesh, 0);
        prop_assert!(measure > 0.0);
        for &count in et.allowed_mp_counts() {
            let model = AnuraModel {
                mesh: mesh.clone(),
                materials: vec![],
                element_material: vec![1],
                mp_counts: vec![(count, 0)],
                solid_fixity: vec![[false; 3]; mesh.n_nodes()],
                liquid_fixity: vec![[false; 3]; mesh.n_nodes()],
                damping: None,
            };
            let mps = place_material_points(&model).unwrap();
            prop_assert_eq!(mps.len(), count as usize);
            let sum: f64 = mps.iter().map(|m| m.volume).sum();
            prop_assert!((sum - measure).abs() <= 1e-12 * measure * 10.0, "{:?} {}: {} vs {}", et, count, sum, measure);
            for mp in &mps {
                prop_assert!(point_in_element(&mesh, 0, mp.position, 1e-9), "{:?} {}: {:?}", et, count, mp.position);
            }
        }
    }
}

/// One hand-made TRI3 with corners (2, 0), (5, 0), (2, 4): det J = 12.
fn axisymmetric_triangle(dimension: Dimension, x_shift: f64, count: u32) -> AnuraModel {
    let mesh = Mesh {
        dimension,
        element_type: ElementType::Tri3,
        nodes: vec![
            [2.0 + x_shift, 0.0, 0.0],
            [5.0 + x_shift, 0.0, 0.0],
            [2.0 + x_shift, 4.0, 0.0],
        ],
        connectivity: vec![0, 1, 2],
    };
    AnuraModel {
        solid_fixity: vec![[false; 3]; 3],
        liquid_fixity: vec![[false; 3]; 3],
        mesh,
        materials: vec![],
        element_material: vec![1],
        mp_counts: vec![(count, 0)],
        damping: None,
    }
}

/// #13: in 2D-axisymmetric models Anura3D's MP volume is weight × det J × x
/// (per radian), checked on the running kernel; plane strain keeps weight × det J.
#[test]
fn axisymmetric_volume_is_weight_times_det_j_times_radius() {
    for &count in ElementType::Tri3.allowed_mp_counts() {
        let table = local_points(ElementType::Tri3, count).unwrap();
        let axi =
            place_material_points(&axisymmetric_triangle(Dimension::Axisymmetric, 0.0, count))
                .unwrap();
        let plane =
            place_material_points(&axisymmetric_triangle(Dimension::PlaneStrain, 0.0, count))
                .unwrap();
        assert_eq!(axi.len(), count as usize);
        for ((a, p), lp) in axi.iter().zip(&plane).zip(table) {
            assert_eq!(a.position, p.position);
            let x = 2.0 + 3.0 * lp.xi[0];
            assert!((a.position[0] - x).abs() < 1e-12);
            let expected = lp.weight * 12.0 * x;
            assert!(
                (a.volume - expected).abs() <= 1e-13 * expected,
                "{count} MPs: {} vs {expected}",
                a.volume
            );
            assert!((p.volume - lp.weight * 12.0).abs() <= 1e-13 * p.volume);
        }
        // Σ w·det J·x = ∫ x dA = area × centroid radius = 6 × 3.
        let sum: f64 = axi.iter().map(|m| m.volume).sum();
        assert!((sum - 18.0).abs() < 1e-12, "{count} MPs: Σ V = {sum}");
    }
}

#[test]
fn axisymmetric_points_left_of_the_axis_are_reported() {
    let model = axisymmetric_triangle(Dimension::Axisymmetric, -4.0, 3);
    let errors = place_material_points(&model).unwrap_err().0;
    assert!(
        matches!(errors[..], [PlaceError::NonPositiveRadius { element: 0, x }] if x < 0.0),
        "{errors:?}"
    );
    assert!(errors[0].to_string().starts_with("element 1: "));
}
