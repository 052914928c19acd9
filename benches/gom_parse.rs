//! GOM parsing throughput on a generated model with 10⁶ TRI3 elements
//! (issue #3 target: ≥ 150 MB/s). Reports MB/s through criterion's throughput.

use std::path::Path;

use a3d_init::formats::gom::GomDocument;
use a3d_init::formats::gom::write::model_to_text;
use a3d_testkit::generate::{self, MaterialSpec};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

fn big_gom() -> String {
    let mesh = generate::structured_tri_mesh(0.0, 0.0, 1000.0, 500.0, 1000, 500);
    let spec = MaterialSpec::dry_soil("soil");
    model_to_text(&generate::single_material_model(mesh, &spec, 3), "2023")
}

fn bench(c: &mut Criterion) {
    let text = big_gom();
    let mut group = c.benchmark_group("gom");
    group.sample_size(10);
    group.throughput(Throughput::Bytes(text.len() as u64));
    group.bench_function("document+typed view, 1e6 TRI3 elements", |b| {
        b.iter(|| {
            let doc = GomDocument::parse(Path::new("big.GOM"), text.clone()).unwrap();
            doc.model().unwrap()
        })
    });
    group.bench_function("document only (lossless layer)", |b| {
        b.iter(|| GomDocument::parse(Path::new("big.GOM"), text.clone()).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
