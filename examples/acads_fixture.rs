//! Builds `fixtures/acads-1a/`: ACADS problem 1(a) (Giam & Donald 1989, the
//! referee's factor 1.00), the published slope with c′ > 0 on which #39 sets
//! the four stability measures side by side, as an Anura3D project: ground
//! (20,25)–(30,25)–(50,35)–(70,35), base y = 20, c′ = 3 kPa, φ′ = 19.6°,
//! γ = 20 kN/m³, dry, and a FEM node file of zero pore pressure to map.
//! Deterministic; run `cargo run --example acads_fixture`. The choices are in
//! `fixtures/acads-1a/README.md`.
#![allow(clippy::print_stdout)]

use std::fmt::Write as _;
use std::path::Path;

use a3d_init::formats::gom::write::model_to_text;
use a3d_init::model::AnuraModel;
use a3d_testkit::generate::{self, MaterialSpec};

/// The ground of ACADS 1(a) (m).
fn ground(x: f64) -> f64 {
    25.0 + 10.0 * ((x - 30.0) / 20.0).clamp(0.0, 1.0)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/acads-1a");
    std::fs::create_dir_all(&out)?;
    // 50 columns of 1 m, 15 rows between the base and the ground.
    let mut mesh = generate::structured_tri_mesh(0.0, 0.0, 50.0, 15.0, 50, 15);
    generate::slope_profile(&mut mesh, 15.0, 5.0, 15.0, 10.0, 30.0);
    for p in &mut mesh.nodes {
        p[0] += 20.0;
        p[1] += 20.0;
    }
    // γ = (1 − n)·ρs·g = 0.7 × 2.9127 × 9.81 = 20.0 kN/m³.
    let soil = MaterialSpec {
        name: "acads_1a".into(),
        porosity: 0.3,
        density_solid: 2912.7,
        density_liquid: None,
        // Jaky: K0 = 1 − sin φ′ (0.5 would put flat ground at yield).
        k0: 0.6645,
        young_modulus: 1e5,
        poisson_ratio: 0.3,
        mohr_coulomb: Some((19.6, 3.0, 0.0)),
        retention: None,
        permeability: 0.0,
    };
    let model: AnuraModel = generate::single_material_model(mesh, &soil, 3);
    std::fs::write(out.join("acads1a.GOM"), model_to_text(&model, "2023"))?;
    std::fs::write(
        out.join("acads1a.CPS_001"),
        "### Anura3D_2023 ###\n$$NUMBER_OF_LOADSTEPS\n1\n$$TIME_PER_LOADSTEP\n0.5\n$$COMPUTATION_METHOD\nMPM-MIXED\n$$GRAVITY_ACCELERATION\n9.81\n$$GRAVITY_VECTOR\n0.0 -1.0\n$$GRAVITY_LOAD\nstep 1.0 1.0\n$$QUASISTATIC_CONVERGENCE\n1\n$$HOMOGENEOUS_LOCAL_DAMPING\n1 0.75\n$$K0_PROCEDURE\n1\n$$VISUALIZATION_OPTION\nParaview\n$$END\n",
    )?;
    // A dry FEM result: zero pore pressure on a 0.5 m grid over the section.
    let mut csv = String::from("Node,X (m),Y (m),Pore-Water Pressure (kPa)\n");
    let mut k = 0;
    for i in 0..=100 {
        let x = 20.0 + 0.5 * i as f64;
        let rows = ((ground(x) - 20.0) / 0.5).round() as usize;
        for j in 0..=rows {
            let y = (20.0 + 0.5 * j as f64).min(ground(x));
            k += 1;
            writeln!(csv, "{k},{x},{y},0")?;
        }
    }
    std::fs::write(out.join("nodes.csv"), csv)?;
    println!(
        "acads1a.GOM: {} nodes, {} elements; nodes.csv: {k} nodes",
        model.mesh.n_nodes(),
        model.mesh.n_elements()
    );
    Ok(())
}
