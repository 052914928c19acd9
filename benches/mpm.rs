//! Throughput of the explicit MPM solver (particle-steps per second) with
//! Mohr–Coulomb soil on about 10⁵ material points: a collapsing cohesionless
//! block (φ = 30°, K0 = 0.5 start, free right face, so a large share of the
//! MPs is plastic) in 2D plane strain (TRI3) and in 3D (`tetrahedral_old`).
//! Run with `RAYON_NUM_THREADS=1` or `=2` to compare thread counts; criterion
//! reports the rate as elements/s, one element being one particle-step.
//!
//! The `affine_setup` group times the grid's per-element setup of the affine
//! shape functions: the hand-written Gauss–Jordan inverse it keeps
//! ([`Simplex::from_corners`]) against the same gradients and det J through
//! [`Element`]'s nalgebra path (elements/s, one element being one setup).

use std::time::Duration;

use a3d_init::element::{self, Element, Simplex, TetOld, Tri3};
use a3d_init::model::{AnuraModel, MaterialPoint, Mesh, MpState};
use a3d_init::mpm::{RunSettings, Simulation};
use a3d_testkit::{column_tet, column_tri3, geostatic_states, mohr_coulomb_material, place_points};
use criterion::{Criterion, SamplingMode, Throughput, criterion_group, criterion_main};

/// Steps per measured iteration.
const STEPS: usize = 4;

/// Keeps only the elements whose centroid lies left of x = 2 m active.
fn block(mut model: AnuraModel) -> (AnuraModel, Vec<MaterialPoint>, Vec<MpState>) {
    for e in 0..model.mesh.n_elements() {
        let corners = model.mesh.corners(e).to_vec();
        let x = corners
            .iter()
            .map(|&n| model.mesh.nodes[n as usize][0])
            .sum::<f64>()
            / corners.len() as f64;
        if x > 2.0 {
            model.element_material[e] = 0;
            model.mp_counts[e] = (0, 0);
        }
    }
    let points = place_points(&model);
    let states = geostatic_states(&model, &points, 9.81, 0.5, None);
    (model, points, states)
}

fn bench_case(c: &mut Criterion, name: &str, model: AnuraModel) {
    let (model, points, states) = block(model);
    let settings = RunSettings {
        damping: 0.05,
        ..RunSettings::verify()
    };
    let mut simulation = match Simulation::new(&model, &points, &states, &settings) {
        Ok(s) => s,
        Err(e) => panic!("benchmark model is invalid: {e}"),
    };
    // Let the collapse start so that the plastic share is representative.
    for _ in 0..5 {
        simulation.step();
    }
    let mut group = c.benchmark_group("mpm");
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Elements((points.len() * STEPS) as u64));
    group.bench_function(format!("{name}_{}_mps", points.len()), |b| {
        b.iter(|| {
            for _ in 0..STEPS {
                std::hint::black_box(simulation.step());
            }
        })
    });
    group.finish();
}

fn mohr_coulomb_2d(c: &mut Criterion) {
    let material = mohr_coulomb_material(1e4, 0.3, 2650.0, 0.3, 30.0, 0.0, 0.0);
    // 2 m × 3 m block of 0.02 m cells: 100 × 150 × 2 triangles × 3 MPs.
    bench_case(c, "tri3_2d", column_tri3(6.0, 3.0, 300, 150, material));
}

fn mohr_coulomb_3d(c: &mut Criterion) {
    let material = mohr_coulomb_material(1e4, 0.3, 2650.0, 0.3, 30.0, 0.0, 0.0);
    // 2 m × 3 m × 1 m block of 1/9 m cells: 18 × 27 × 9 × 6 tets × 4 MPs.
    bench_case(c, "tet_3d", column_tet(6.0, 3.0, 1.0, 54, 27, 9, material));
}

/// Both setups of every element of `mesh`, of type `E`.
fn bench_setup<const D: usize, const NC: usize, E: Element<D, NC>>(
    c: &mut Criterion,
    name: &str,
    mesh: &Mesh,
) {
    let corners: Vec<[[f64; D]; NC]> = (0..mesh.n_elements())
        .map(|e| element::corners(mesh, e))
        .collect();
    let mut group = c.benchmark_group("affine_setup");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(corners.len() as u64));
    group.bench_function(format!("{name}_gauss_jordan"), |b| {
        b.iter(|| {
            for c in &corners {
                std::hint::black_box(Simplex::from_corners(c));
            }
        })
    });
    group.bench_function(format!("{name}_nalgebra"), |b| {
        b.iter(|| {
            for c in &corners {
                let grad = E::global_gradients(c, &E::CENTROID);
                std::hint::black_box((grad, E::det_jacobian(c, &E::CENTROID)));
            }
        })
    });
    group.finish();
}

fn affine_setup(c: &mut Criterion) {
    let material = mohr_coulomb_material(1e4, 0.3, 2650.0, 0.3, 30.0, 0.0, 0.0);
    let tri = column_tri3(6.0, 3.0, 300, 150, material.clone());
    bench_setup::<2, 3, Tri3>(c, "tri3", &tri.mesh);
    let tet = column_tet(6.0, 3.0, 1.0, 54, 27, 9, material);
    bench_setup::<3, 4, TetOld>(c, "tet", &tet.mesh);
}

criterion_group!(benches, mohr_coulomb_2d, mohr_coulomb_3d, affine_setup);
criterion_main!(benches);
