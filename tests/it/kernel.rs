//! Kernels, neighbour search and the mapper against their oracles: analytic
//! normalisation, partition of unity, constant and linear fields, brute-force
//! neighbour search, and the serial mapper (bit for bit, any thread count).

use crate::common;
use common::random::*;

use a3d_init::kernel::grid::Grid;
use a3d_init::kernel::mapper::{self, MapSettings, NodeCloud, OutsidePolicy, PointStatus, Search};
use a3d_init::kernel::neighbours::{NeighbourIndex, within_brute_force};
use a3d_init::kernel::{Gaussian, Kernel, KernelKind};
use proptest::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const KERNELS: [KernelKind; 3] = [
    KernelKind::Cubic,
    KernelKind::Gaussian { cutoff: 3.0 },
    KernelKind::Wendland { dim1: false },
];

/// ∫ w over the line, plane or space, by the trapezoid rule in radial form.
fn integral(kernel: &KernelKind, dim: usize, h: f64) -> f64 {
    let n = 200_000;
    let r_max = kernel.support() * h;
    let dr = r_max / n as f64;
    let mut sum = 0.0;
    for i in 0..=n {
        let r = i as f64 * dr;
        let shell = match dim {
            1 => 2.0,
            2 => 2.0 * std::f64::consts::PI * r,
            _ => 4.0 * std::f64::consts::PI * r * r,
        };
        let f = kernel.weight(r, h, dim) * shell;
        sum += if i == 0 || i == n { 0.5 * f } else { f };
    }
    sum * dr
}

#[test]
fn kernels_integrate_to_one_with_the_papers_alpha() {
    for dim in 1..=3 {
        for kernel in KERNELS {
            let kernel = match kernel {
                KernelKind::Wendland { .. } => KernelKind::Wendland { dim1: dim == 1 },
                k => k,
            };
            for h in [0.3, 1.0, 4.2] {
                let expected = match kernel {
                    KernelKind::Gaussian { cutoff } => {
                        1.0 - Gaussian { cutoff }.truncated_mass(dim)
                    }
                    _ => 1.0,
                };
                let got = integral(&kernel, dim, h);
                assert!(
                    (got - expected).abs() < 1e-6,
                    "{} dim {dim} h {h}: {got} vs {expected}",
                    kernel.name()
                );
            }
        }
    }
}

#[test]
fn gaussian_truncated_mass_at_3h() {
    let g = Gaussian::default();
    assert!((g.truncated_mass(2) - (-9.0f64).exp()).abs() < 1e-15);
    assert!(g.truncated_mass(1) < 3e-5 && g.truncated_mass(3) < 5e-4);
}

#[test]
#[allow(clippy::print_stderr)] // the skip must be visible in the test output
fn cubic_weights_in_avx512_equal_the_scalar_shape_bit_for_bit() {
    let Some(simd) = a3d_init::kernel::simd::Avx512::detect() else {
        eprintln!("no AVX-512 here: the portable weights are the only path");
        return;
    };
    let mut rng = ChaCha8Rng::seed_from_u64(61);
    let (mut vector, mut scalar) = (Vec::new(), Vec::new());
    for round in 0..4000 {
        let h = 10f64.powf(rng.random_range(-4.0..4.0));
        // Lists of every length around the vector width, their distances up
        // to the support and past it.
        let n = round % 67;
        let mut d2: Vec<f64> = (0..n)
            .map(|_| (rng.random_range(0.0..2.2) * h).powi(2))
            .collect();
        if round % 5 == 0 {
            // r of exactly 0, 1 and 2, and the doubles beside 1 and 2.
            for r in [0.0, 1.0, 2.0] {
                for v in [
                    r,
                    f64::from_bits(f64::to_bits(r).wrapping_sub(1)),
                    r.next_up(),
                ] {
                    d2.push((v * h).powi(2));
                }
            }
            d2.retain(|v| v.is_finite() && *v >= 0.0);
        }
        simd.cubic(&d2, h, &mut vector);
        KernelKind::Cubic.weights_squared(&d2, h, None, &mut scalar);
        let want: Vec<u64> = d2
            .iter()
            .map(|v| a3d_init::kernel::CubicSpline.shape(v.sqrt() / h).to_bits())
            .collect();
        let bits = |w: &[f64]| w.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&vector), want, "h {h}, {n} distances");
        assert_eq!(bits(&scalar), want, "h {h}, {n} distances");
    }
    // The division by 6 without the divider, over the whole range of (2 − r)³.
    let mut w = Vec::new();
    for _ in 0..200 {
        let d2: Vec<f64> = (0..64)
            .map(|_| {
                let t = 2f64.powf(-rng.random_range(0.0..52.0)) * rng.random_range(0.5..1.0);
                (2.0 - t).powi(2)
            })
            .collect();
        simd.cubic(&d2, 1.0, &mut w);
        for (v, got) in d2.iter().zip(&w) {
            let t = 2.0 - v.sqrt();
            assert_eq!(got.to_bits(), (t * t * t / 6.0).to_bits(), "t {t}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn weights_are_nonnegative_zero_beyond_support_and_decreasing(r in 0.0f64..5.0, k in 0usize..3) {
        let kernel = KERNELS[k];
        let w = kernel.shape(r);
        prop_assert!(w >= 0.0);
        if r >= kernel.support() {
            prop_assert_eq!(w, 0.0);
        }
        prop_assert!(kernel.shape(r + 1e-3) <= w + 1e-15);
    }

    #[test]
    fn normalised_weights_sum_to_one_and_constants_are_exact(seed in 0u64..10_000, k in 0usize..3, c in -500.0f64..500.0) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let nodes = random_points(&mut rng, 2, 200, 0.0..10.0);
        let values = vec![c; nodes.len()];
        let cloud = NodeCloud { positions: &nodes, dim: 2, values: &values, n_fields: 1, group: None, node_volume: 0.5 };
        let points = random_points(&mut rng, 2, 50, 1.0..9.0);
        let settings = MapSettings { kernel: KERNELS[k], h: 1.2, min_shepard: 0.0, outside: OutsidePolicy::Skip };
        let r = mapper::map_points(&cloud, &points, None, &settings).unwrap();
        for (i, s) in r.status.iter().enumerate() {
            if *s == PointStatus::Mapped {
                prop_assert!((r.values[i] - c).abs() <= 1e-12 * c.abs().max(1.0), "{} vs {}", r.values[i], c);
            }
        }
    }
}

#[test]
fn linear_fields_are_exact_at_interior_points_of_a_uniform_grid() {
    let n = 21;
    let nodes = grid_nodes(n, 0.5);
    let f = |p: &[f64; 3]| 3.0 * p[0] - 2.0 * p[1] + 7.0;
    let values: Vec<f64> = nodes.iter().map(f).collect();
    let cloud = plane_cloud(&nodes, &values, 1, None, 0.25);
    // Interior grid points and cell centres: symmetric stencils.
    let points: Vec<[f64; 3]> = vec![
        [5.0, 5.0, 0.0],
        [3.5, 6.0, 0.0],
        [4.25, 4.25, 0.0],
        [6.0, 3.0, 0.0],
    ];
    for kernel in KERNELS {
        let settings = map_settings(kernel, 0.6, 0.0, OutsidePolicy::Error);
        let r = mapper::map_points(&cloud, &points, None, &settings).unwrap();
        for (p, v) in points.iter().zip(&r.values) {
            assert!(
                (v - f(p)).abs() < 1e-10,
                "{}: {v} vs {}",
                kernel.name(),
                f(p)
            );
        }
    }
}

#[test]
fn kiddo_search_equals_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for dim in [2usize, 3] {
        let mut pts = random_points(&mut rng, dim, 3000, -5.0..5.0);
        // Many duplicates and a tight cluster.
        for _ in 0..300 {
            pts.push([1.0, 1.0, if dim == 3 { 1.0 } else { 0.0 }]);
        }
        let index = NeighbourIndex::new(&pts, dim);
        let mut got = Vec::new();
        for _ in 0..200 {
            let q = random_point(&mut rng, dim, -6.0..6.0);
            let r = rng.random_range(0.0..2.5);
            index.within(q, r, &mut got);
            let want = within_brute_force(&pts, dim, q, r);
            assert_eq!(got.len(), want.len(), "dim {dim} q {q:?} r {r}");
            for (a, b) in got.iter().zip(&want) {
                assert_eq!(a.0, b.0);
                assert!((a.1 - b.1).abs() < 1e-12);
            }
        }
        let q = [1.0, 1.0, if dim == 3 { 1.0 } else { 0.0 }];
        index.within(q, 0.0, &mut got);
        assert_eq!(got.len(), 300, "duplicates at the query point");
    }
}

#[test]
fn parallel_map_equals_serial_map_bit_for_bit() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let nodes = random_points(&mut rng, 2, 20_000, 0.0..50.0);
    let values: Vec<f64> = nodes
        .iter()
        .flat_map(|p| [p[0].sin() * 100.0 + p[1], p[1] * p[1] * 0.3])
        .collect();
    let groups: Vec<u32> = nodes
        .iter()
        .map(|p| if p[1] < 20.0 { 1 } else { 2 })
        .collect();
    let cloud = plane_cloud(&nodes, &values, 2, Some(&groups), 0.125);
    let points = random_points(&mut rng, 2, 10_000, 0.0..50.0);
    let point_groups: Vec<u32> = points
        .iter()
        .map(|p| if p[1] < 20.0 { 1 } else { 2 })
        .collect();
    for kernel in KERNELS {
        let settings = map_settings(kernel, 0.5, 0.0, OutsidePolicy::Nearest);
        let serial = mapper::map_points_with(
            &cloud,
            &points,
            Some(&point_groups),
            &settings,
            Search::Grid,
            false,
        )
        .unwrap();
        for threads in [1, 2, 4] {
            let parallel = in_pool(threads, || {
                mapper::map_points(&cloud, &points, Some(&point_groups), &settings).unwrap()
            });
            assert!(
                serial
                    .values
                    .iter()
                    .zip(&parallel.values)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{} threads",
                threads
            );
            assert_eq!(serial.n_neighbours, parallel.n_neighbours);
        }
    }
}

#[test]
fn groups_keep_a_material_step_sharp() {
    // Two materials meeting at y = 5 with a jump in the field; no smoothing across.
    let n = 21;
    let nodes = grid_nodes(n, 0.5);
    let groups: Vec<u32> = nodes
        .iter()
        .map(|p| if p[1] <= 5.0 { 1 } else { 2 })
        .collect();
    let values: Vec<f64> = groups
        .iter()
        .map(|&g| if g == 1 { 10.0 } else { 100.0 })
        .collect();
    let cloud = plane_cloud(&nodes, &values, 1, Some(&groups), 0.25);
    let points = [[4.0, 4.9, 0.0], [4.0, 5.1, 0.0]];
    let settings = map_settings(KernelKind::Cubic, 1.0, 0.0, OutsidePolicy::Error);
    let r = mapper::map_points(&cloud, &points, Some(&[1, 2]), &settings).unwrap();
    assert!(
        (r.values[0] - 10.0).abs() < 1e-12 && (r.values[1] - 100.0).abs() < 1e-12,
        "{:?}",
        r.values
    );
    let mixed = mapper::map_points(&cloud, &points, None, &settings).unwrap();
    assert!(
        mixed.values[0] > 10.0 && mixed.values[1] < 100.0,
        "without groups the step is smoothed"
    );
}

#[test]
fn null_points_follow_the_policy() {
    let nodes = grid_nodes(10, 1.0);
    let values: Vec<f64> = nodes.iter().map(|p| p[0]).collect();
    let cloud = plane_cloud(&nodes, &values, 1, None, 1.0);
    let points = [[4.5, 4.5, 0.0], [30.0, 4.0, 0.0], [-20.0, 0.0, 0.0]];
    let mut settings = map_settings(KernelKind::Cubic, 1.0, 0.02, OutsidePolicy::Error);
    let err = mapper::map_points(&cloud, &points, None, &settings)
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("2 material point(s) have no FEM node") && err.contains("[2, 3]"),
        "{err}"
    );
    settings.outside = OutsidePolicy::Nearest;
    let r = mapper::map_points(&cloud, &points, None, &settings).unwrap();
    assert_eq!(
        r.status,
        vec![
            PointStatus::Mapped,
            PointStatus::Nearest,
            PointStatus::Nearest
        ]
    );
    assert_eq!(&r.values[1..], &[9.0, 0.0]);
    settings.outside = OutsidePolicy::Skip;
    let r = mapper::map_points(&cloud, &points, None, &settings).unwrap();
    assert!(r.values[1].is_nan() && r.status[2] == PointStatus::Skipped);
}

fn map_settings(
    kernel: KernelKind,
    h: f64,
    min_shepard: f64,
    outside: OutsidePolicy,
) -> MapSettings {
    MapSettings {
        kernel,
        h,
        min_shepard,
        outside,
    }
}

/// A node cloud in the plane (dim 2).
fn plane_cloud<'a>(
    nodes: &'a [[f64; 3]],
    values: &'a [f64],
    n_fields: usize,
    group: Option<&'a [u32]>,
    node_volume: f64,
) -> NodeCloud<'a> {
    NodeCloud {
        positions: nodes,
        dim: 2,
        values,
        n_fields,
        group,
        node_volume,
    }
}

/// Random clouds with duplicates and a tight cluster, in 2D and 3D.
fn cloud_with_duplicates(rng: &mut ChaCha8Rng, dim: usize, n: usize) -> Vec<[f64; 3]> {
    let mut pts = random_points(rng, dim, n, -5.0..5.0);
    for _ in 0..n / 10 {
        pts.push([1.0, 1.0, if dim == 3 { 1.0 } else { 0.0 }]);
    }
    pts
}

#[test]
fn grid_and_kiddo_searches_equal_brute_force_bit_for_bit() {
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    for dim in [2usize, 3] {
        let pts = cloud_with_duplicates(&mut rng, dim, 5000); // radius 30: more than 4096 candidates
        let index = NeighbourIndex::new(&pts, dim);
        for (radius, per_radius) in [
            (0.0, 1),
            (0.05, 1),
            (0.7, 1),
            (2.5, 1),
            (30.0, 1),
            (0.7, 2),
            (2.5, 2),
            (0.7, 3),
        ] {
            // Cells one radius wide, or a half or a third of it (the mapper's).
            let grid = Grid::with_cells(&pts, dim, radius, per_radius);
            let (mut a, mut b) = (Vec::new(), Vec::new());
            for _ in 0..300 {
                let q = random_point(&mut rng, dim, -7.0..7.0);
                let want = within_brute_force(&pts, dim, q, radius);
                grid.within(q, radius, &mut a);
                index.within(q, radius, &mut b);
                let bits = |v: &[(u32, f64)]| -> Vec<(u32, u64)> {
                    v.iter().map(|&(i, d)| (i, d.to_bits())).collect()
                };
                assert_eq!(bits(&a), bits(&want), "grid, dim {dim} q {q:?} r {radius}");
                assert_eq!(bits(&b), bits(&want), "kiddo, dim {dim} q {q:?} r {radius}");
            }
            let q = [1.0, 1.0, if dim == 3 { 1.0 } else { 0.0 }];
            grid.within(q, radius, &mut a);
            assert!(a.len() >= 300, "duplicates at the query point");
        }
    }
}

#[test]
fn grid_map_equals_kiddo_map_bit_for_bit() {
    let mut rng = ChaCha8Rng::seed_from_u64(19);
    for dim in [2usize, 3] {
        let nodes = cloud_with_duplicates(&mut rng, dim, 6000);
        // Duplicated nodes would be refused by the reader; the mapper takes them.
        let values: Vec<f64> = nodes
            .iter()
            .flat_map(|p| [p[0].sin() * 100.0 + p[1], p[2] * p[1] * 0.3])
            .collect();
        let groups: Vec<u32> = nodes.iter().map(|p| 1 + (p[1] > 0.5) as u32).collect();
        let cloud = NodeCloud {
            positions: &nodes,
            dim,
            values: &values,
            n_fields: 2,
            group: Some(&groups),
            node_volume: 0.05,
        };
        let mut points = cloud_with_duplicates(&mut rng, dim, 4000);
        // Far outside the cloud: only the nearest-node fallback reaches them.
        let z = |v: f64| if dim == 3 { v } else { 0.0 };
        points.extend([
            [20.0, 20.0, z(20.0)],
            [-30.0, 0.7, z(1.0)],
            [0.0, -12.0, z(-9.0)],
        ]);
        let point_groups: Vec<u32> = points.iter().map(|p| 1 + (p[1] > 0.5) as u32).collect();
        for kernel in KERNELS {
            for (h, outside) in [(0.3, OutsidePolicy::Nearest), (0.05, OutsidePolicy::Skip)] {
                let settings = map_settings(kernel, h, 0.01, outside);
                for groups in [None, Some(&point_groups[..])] {
                    let reference = mapper::map_points_with(
                        &cloud,
                        &points,
                        groups,
                        &settings,
                        Search::KdTree,
                        false,
                    )
                    .unwrap();
                    let grid = mapper::map_points(&cloud, &points, groups, &settings).unwrap();
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(
                        bits(&grid.values),
                        bits(&reference.values),
                        "{kernel:?} h {h}"
                    );
                    assert_eq!(grid.n_neighbours, reference.n_neighbours);
                    assert_eq!(bits(&grid.shepard), bits(&reference.shepard));
                    assert_eq!(grid.status, reference.status);
                    // Handing the values and positions over (freed once the
                    // grid holds a copy) and reading the points inside
                    // records change nothing, the nearest fallback included.
                    let bare = NodeCloud {
                        values: &[],
                        positions: &[],
                        ..cloud
                    };
                    let handed = mapper::Handed {
                        values: Some(values.clone()),
                        positions: Some(cloud.positions.to_vec()),
                    };
                    let at = |i: usize| points[i];
                    let records = mapper::Points::Records {
                        len: points.len(),
                        at: &at,
                    };
                    let taken =
                        mapper::map_points_from(&bare, handed, records, groups, &settings).unwrap();
                    assert_eq!(bits(&taken.values), bits(&reference.values));
                    assert_eq!(taken.status, reference.status);
                    if outside == OutsidePolicy::Nearest {
                        assert!(reference.status.contains(&PointStatus::Nearest));
                    }
                }
            }
        }
    }
}

/// The mapper against the brute force: every node tested, the neighbours
/// sorted by (distance, index), Eq. 1 summed in that order. The mapper sums
/// in its grid's order instead (no per-query sort), so the values agree to
/// rounding: within 1e-14 of the largest |value| the point's neighbours
/// carry (n·ε past 45 neighbours, the bound of a sum of n terms), and the
/// neighbour counts and statuses exactly. Then the same for
/// the portable path and every thread count, which must give the same bits.
#[test]
fn grid_map_equals_brute_force_map_to_1e_14() {
    let mut rng = ChaCha8Rng::seed_from_u64(29);
    let mut worst = 0.0f64;
    for dim in [2usize, 3] {
        let nodes = cloud_with_duplicates(&mut rng, dim, 3000);
        let nf = 3;
        let values: Vec<f64> = nodes
            .iter()
            .flat_map(|p| [p[0].sin() * 100.0 + p[1], p[2] * p[1] * 0.3, -7.0 * p[0]])
            .collect();
        let cloud = NodeCloud {
            positions: &nodes,
            dim,
            values: &values,
            n_fields: nf,
            group: None,
            node_volume: 0.05,
        };
        let points = random_points(&mut rng, dim, 2000, -6.0..6.0);
        for kernel in KERNELS {
            for h in [0.2, 0.45, 1.3] {
                let settings = map_settings(kernel, h, 0.01, OutsidePolicy::Skip);
                let got = mapper::map_points(&cloud, &points, None, &settings).unwrap();
                let alpha = kernel.alpha(dim, h);
                let mut ws = Vec::new();
                for (i, &q) in points.iter().enumerate() {
                    let found = within_brute_force(&nodes, dim, q, kernel.support() * h);
                    kernel.shapes(&found, h, &mut ws);
                    let (mut sum_w, mut acc, mut count) = (0.0, vec![0.0; nf], 0u32);
                    let mut scale = vec![0.0f64; nf];
                    for (&(node, _), &w) in found.iter().zip(&ws) {
                        if w <= 0.0 {
                            continue;
                        }
                        count += 1;
                        sum_w += w;
                        let row = &values[node as usize * nf..(node as usize + 1) * nf];
                        for k in 0..nf {
                            acc[k] += w * row[k];
                            scale[k] = scale[k].max(row[k].abs());
                        }
                    }
                    let ratio = sum_w * alpha * 0.05;
                    assert_eq!(got.n_neighbours[i], count, "{kernel:?} h {h} point {i}");
                    // 1e-14 of the scale; a sum of n terms in another order
                    // can differ by n·ε of it, more than 1e-14 only past 45
                    // neighbours (the 300 duplicates here).
                    let tol = 1e-14f64.max(count as f64 * f64::EPSILON);
                    let close = |a: f64, b: f64, s: f64| (a - b).abs() <= tol * s;
                    assert!(
                        close(got.shepard[i], ratio, ratio),
                        "{kernel:?} h {h} point {i}: {} vs {ratio}, {count} neighbours",
                        got.shepard[i]
                    );
                    if count > 0 && ratio >= 0.01 {
                        assert_eq!(got.status[i], PointStatus::Mapped);
                        for k in 0..nf {
                            let want = acc[k] / sum_w;
                            let have = got.values[i * nf + k];
                            worst = worst.max((have - want).abs() / scale[k].max(1e-300));
                            assert!(
                                close(have, want, scale[k]),
                                "{kernel:?} h {h} point {i} field {k}: {have} vs {want}"
                            );
                        }
                    } else if ratio < 0.01 * (1.0 - 1e-12) || count == 0 {
                        assert_eq!(got.status[i], PointStatus::Skipped);
                    }
                }
                // The vector path and the portable one, serial and on any
                // number of threads: the same bits.
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                let portable = mapper::map_points_with(
                    &cloud,
                    &points,
                    None,
                    &settings,
                    Search::GridPortable,
                    false,
                )
                .unwrap();
                assert_eq!(
                    bits(&portable.values),
                    bits(&got.values),
                    "{kernel:?} h {h}"
                );
                assert_eq!(bits(&portable.shepard), bits(&got.shepard));
                for threads in [1, 2, 3] {
                    let again = in_pool(threads, || {
                        mapper::map_points(&cloud, &points, None, &settings).unwrap()
                    });
                    assert_eq!(bits(&again.values), bits(&got.values), "{threads} threads");
                }
            }
        }
    }
    assert!(
        worst > 0.0,
        "the orders differ somewhere: the test must see it"
    );
}

#[test]
fn spacings_equal_brute_force_bit_for_bit() {
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    for dim in [2usize, 3] {
        let mut pts = cloud_with_duplicates(&mut rng, dim, 1500);
        // Outliers: no other point in the cells around theirs (rings of cells).
        let z = |v: f64| if dim == 3 { v } else { 0.0 };
        pts.extend([
            [12.0, 0.0, z(0.0)],
            [-11.0, 3.0, z(2.0)],
            [0.0, 14.0, z(-1.0)],
        ]);
        let brute: Vec<f64> = (0..pts.len())
            .map(|i| {
                within_brute_force(&pts, dim, pts[i], 20.0)
                    .into_iter()
                    .find(|&(j, _)| j as usize != i)
                    .map_or(f64::INFINITY, |(_, d)| d)
            })
            .collect();
        let got = mapper::nearest_other_distances(&pts, dim);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&got), bits(&brute));
        let mut sorted = brute.clone();
        sorted.sort_by(f64::total_cmp);
        assert_eq!(mapper::median_spacing(&pts, dim), sorted[sorted.len() / 2]);
        assert_eq!(mapper::min_spacing(&pts, dim), 0.0, "duplicates");
        let distinct = &pts[..1500];
        let brute_min = (0..distinct.len())
            .map(|i| {
                within_brute_force(distinct, dim, distinct[i], 20.0)
                    .into_iter()
                    .find(|&(j, _)| j as usize != i)
                    .map_or(f64::INFINITY, |(_, d)| d)
            })
            .fold(f64::INFINITY, f64::min);
        assert_eq!(mapper::min_spacing(distinct, dim), brute_min);
    }
    assert_eq!(mapper::median_spacing(&[[1.0; 3]], 3), 0.0);
    assert_eq!(mapper::min_spacing(&[[1.0; 3]], 3), 0.0);
}

/// A regular lattice puts many nodes at exactly the same distance from a
/// query at a lattice point or cell centre: the grid's bucket sort must break
/// those ties by index exactly as the brute force does.
#[test]
fn grid_breaks_distance_ties_on_a_lattice_like_brute_force() {
    for dim in [2usize, 3] {
        let side = if dim == 3 { 12 } else { 40 };
        let mut pts = Vec::new();
        for i in 0..side {
            for j in 0..side {
                for k in 0..if dim == 3 { side } else { 1 } {
                    pts.push([i as f64 * 0.5, j as f64 * 0.5, k as f64 * 0.5]);
                }
            }
        }
        for radius in [0.5, 1.0, 1.6] {
            let grid = Grid::new(&pts, dim, radius);
            let mut got = Vec::new();
            for q in [
                [2.0, 2.0, 2.0],
                [2.25, 2.25, 2.25],
                [2.25, 2.0, 2.25],
                [0.0, 0.0, 0.0],
            ] {
                let q = if dim == 3 { q } else { [q[0], q[1], 0.0] };
                let want = within_brute_force(&pts, dim, q, radius);
                grid.within(q, radius, &mut got);
                assert_eq!(got, want, "dim {dim} q {q:?} r {radius}");
            }
        }
    }
}

/// The grid's nearest point (the mapper's `--outside nearest` fallback) is the
/// brute-force nearest, the lowest index among equally near ones, for queries
/// inside, at the edge of and far outside the cloud.
#[test]
fn grid_nearest_equals_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    for dim in [2usize, 3] {
        let pts = cloud_with_duplicates(&mut rng, dim, 3000);
        for radius in [0.05, 0.7, 4.0] {
            let grid = Grid::new(&pts, dim, radius);
            for k in 0..400 {
                let span = if k % 4 == 0 { 1e4 } else { 8.0 };
                let q = random_point(&mut rng, dim, -span..span);
                let want = pts
                    .iter()
                    .enumerate()
                    .map(|(i, p)| {
                        let d2: f64 = (0..dim).map(|a| (p[a] - q[a]) * (p[a] - q[a])).sum();
                        (d2, i as u32)
                    })
                    .min_by(|a, b| a.partial_cmp(b).unwrap())
                    .map(|(d2, i)| (i, d2.sqrt()));
                let got = grid
                    .nearest(q)
                    .map(|(pos, d)| (grid.order()[pos as usize], d));
                assert_eq!(got, want, "dim {dim} r {radius} q {q:?}");
            }
            assert_eq!(grid.nearest([f64::NAN, 0.0, 0.0]), None);
        }
    }
}

/// A cloud whose extent is a whole number of cells: the points on the far
/// face stay in the last cell (1/cell rounding must not push them past it).
#[test]
fn grid_keeps_points_on_the_far_face() {
    for dim in [2usize, 3] {
        for (extent, radius) in [(10.0, 1.0), (0.3, 0.1), (7.0, 0.7), (1e5, 1e3)] {
            let mut pts = Vec::new();
            for i in 0..=20 {
                let v = extent * i as f64 / 20.0;
                pts.push([v, extent - v, if dim == 3 { v } else { 0.0 }]);
                pts.push([extent, extent, if dim == 3 { extent } else { 0.0 }]);
            }
            let grid = Grid::new(&pts, dim, radius / (1.0 + 1e-6));
            let mut got = Vec::new();
            for q in &pts {
                grid.within(*q, radius / (1.0 + 1e-6), &mut got);
                let want = within_brute_force(&pts, dim, *q, radius / (1.0 + 1e-6));
                assert_eq!(got, want, "dim {dim} extent {extent} q {q:?}");
            }
        }
    }
}

/// #30: one node at x = 1e308 (or z = 1e308, or nodes at ±1e308 on every
/// axis), or a radius of 1e-300, made the grid's stencil ask for about 10^9
/// rows of cells (a 3–6 GB allocation, then an abort). Whatever the
/// coordinates and the radius, the grid's cells and stencil stay proportional
/// to the points, its searches equal the brute force, the mapper gives the
/// k-d tree's bits and the spacing the brute force's.
#[test]
fn a_grid_no_input_can_blow_up() {
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let bits = |v: &[(u32, f64)]| -> Vec<(u32, u64)> {
        v.iter().map(|&(i, d)| (i, d.to_bits())).collect()
    };
    for dim in [2usize, 3] {
        let base = random_points(&mut rng, dim, 2000, -5.0..5.0);
        let z = |v: f64| if dim == 3 { v } else { 0.0 };
        let mut outliers = vec![
            vec![],
            vec![[1e308, 0.0, 0.0]],
            vec![[1e308, 1e308, z(1e308)], [-1e308, -1e308, z(-1e308)]],
        ];
        if dim == 3 {
            outliers.push(vec![[0.0, 0.0, 1e308]]);
        }
        for far in outliers {
            let pts: Vec<[f64; 3]> = base.iter().chain(&far).copied().collect();
            let n = pts.len() as u64;
            for (radius, per_radius) in [(1e-300, 2), (0.7, 2), (0.7, 1), (1e150, 2)] {
                let grid = Grid::with_cells(&pts, dim, radius, per_radius);
                assert!(grid.cell_keys() <= 125 * (4 * n + 64), "{far:?} r {radius}");
                let stencil = grid.stencil(radius);
                assert!(
                    stencil.len() as u64 <= 49 * grid.cell_keys(),
                    "{far:?} r {radius}"
                );
                let mut got = Vec::new();
                for _ in 0..50 {
                    let q = random_point(&mut rng, dim, -6.0..6.0);
                    grid.within(q, radius, &mut got);
                    let want = within_brute_force(&pts, dim, q, radius);
                    assert_eq!(bits(&got), bits(&want), "{far:?} r {radius} q {q:?}");
                }
            }
            let values: Vec<f64> = pts.iter().map(|p| p[0].sin() + p[1].cos()).collect();
            let cloud = NodeCloud {
                positions: &pts,
                dim,
                values: &values,
                n_fields: 1,
                group: None,
                node_volume: 0.05,
            };
            let points = random_points(&mut rng, dim, 500, -6.0..6.0);
            for (h, outside) in [(0.3, OutsidePolicy::Nearest), (1e-300, OutsidePolicy::Skip)] {
                let settings = map_settings(KernelKind::Cubic, h, 0.01, outside);
                let grid = mapper::map_points(&cloud, &points, None, &settings).unwrap();
                let tree = mapper::map_points_with(
                    &cloud,
                    &points,
                    None,
                    &settings,
                    Search::KdTree,
                    false,
                )
                .unwrap();
                let vbits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(vbits(&grid.values), vbits(&tree.values), "{far:?} h {h}");
                assert_eq!(grid.status, tree.status);
            }
            // The nearest other point of every point of the base cloud.
            let got = mapper::nearest_other_distances(&pts, dim);
            for i in 0..base.len() {
                let want = within_brute_force(&pts, dim, pts[i], 20.0)
                    .into_iter()
                    .find(|&(j, _)| j as usize != i)
                    .map(|(_, d)| d)
                    .unwrap();
                assert_eq!(got[i].to_bits(), want.to_bits(), "{far:?} point {i}");
            }
        }
    }
}
