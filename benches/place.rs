//! Throughput of material-point placement (`place`): MPs per second on a
//! generated 2D TRI3 model (3 and 12 MPs per element) and a 3D
//! `tetrahedral_old` model (4 MPs per element), as `Project::load` runs it.
//! Criterion reports the rate as elements/s, one element being one MP.

use a3d_init::model::AnuraModel;
use a3d_init::place::place_material_points;
use a3d_testkit::generate::{self, MaterialSpec};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

fn bench_case(c: &mut Criterion, name: &str, model: &AnuraModel) {
    let n_points: usize = model.mp_counts.iter().map(|c| c.0 as usize).sum();
    // Timed: the placement that succeeds, not an early error.
    assert_eq!(place_material_points(model).map(|p| p.len()), Ok(n_points));
    let mut group = c.benchmark_group("place");
    group.sample_size(20);
    group.throughput(Throughput::Elements(n_points as u64));
    group.bench_function(format!("{name}_{n_points}_mps"), |b| {
        b.iter(|| std::hint::black_box(place_material_points(model).map(|p| p.len())))
    });
    group.finish();
}

fn placement(c: &mut Criterion) {
    let spec = MaterialSpec::dry_soil("soil");
    let tri = |count| {
        let mesh = generate::structured_tri_mesh(0.0, 0.0, 400.0, 100.0, 400, 100);
        generate::single_material_model(mesh, &spec, count)
    };
    bench_case(c, "tri3_3", &tri(3));
    bench_case(c, "tri3_12", &tri(12));
    let mesh = generate::structured_tet_mesh(40.0, 0.0, 20.0, 20.0, 40, 20, 20);
    bench_case(c, "tet_4", &generate::single_material_model(mesh, &spec, 4));
}

criterion_group!(benches, placement);
criterion_main!(benches);
