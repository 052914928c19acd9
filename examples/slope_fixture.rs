//! Builds `fixtures/slope/`: the paper's rainfall-loaded model slope (Lora et al.
//! 2016, paper §3) as an Anura3D project plus a FEM node file of the sand layer
//! with a **stand-in** pore-pressure field at failure (SEEP/W cannot run here).
//! Deterministic; run `cargo run --example slope_fixture`. The geometry, the
//! materials and the stand-in field are documented in `fixtures/slope/README.md`.
#![allow(clippy::print_stdout)]

use std::fmt::Write as _;
use std::path::Path;

use a3d_init::formats::gom::write::model_to_text;
use a3d_init::model::generate::slope_fixture_clay_top as clay_top;
use a3d_init::model::generate::{self, MaterialSpec};
use a3d_init::model::{AnuraModel, Dimension, ElementType, Mesh, RetentionCurve};

const SAND: f64 = 0.6;
const BASE: f64 = -0.5;
const GAMMA_W: f64 = 9.81;

/// Stand-in perched water table height above the clay (m): 0.05 m at the crest
/// rising quadratically to 0.5 m at the right end (water collects at the toe).
fn perched_height(x: f64) -> f64 {
    let t = ((x - 0.5) / 5.5).clamp(0.0, 1.0);
    0.05 + 0.45 * t * t
}

/// Stand-in pore-water pressure in GeoStudio sign (kPa, positive below the water
/// table): hydrostatic below the perched table, suction above it growing with
/// height at γw per metre but capped at 1.5 kPa (the wetted zone after 1.56 h of
/// 150 mm/h rain is close to saturation throughout the 0.6 m layer).
fn pwp(x: f64, y: f64) -> f64 {
    let table = clay_top(x) + perched_height(x);
    if y <= table {
        GAMMA_W * (table - y)
    } else {
        -(GAMMA_W * (y - table)).min(1.5)
    }
}

/// A two-layer TRI3 mesh: `nx` columns over [0, 6] m; clay from the base to the
/// clay top in `ny_clay` rows, sand from there 0.6 m up in `ny_sand` rows.
fn mesh(nx: usize, ny_clay: usize, ny_sand: usize) -> (Mesh, Vec<u32>) {
    let ny = ny_clay + ny_sand;
    let mut nodes = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let x = 6.0 * i as f64 / nx as f64;
            let top = clay_top(x);
            let y = if j <= ny_clay {
                BASE + (top - BASE) * j as f64 / ny_clay as f64
            } else {
                top + SAND * (j - ny_clay) as f64 / ny_sand as f64
            };
            nodes.push([x, y, 0.0]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut connectivity = Vec::new();
    let mut material = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            // Diagonal chosen so the triangles stay well shaped on the slope.
            connectivity.extend_from_slice(&[a, b, c, a, c, d]);
            let m = if j < ny_clay { 2 } else { 1 };
            material.extend([m, m]);
        }
    }
    let mesh = Mesh {
        dimension: Dimension::PlaneStrain,
        element_type: ElementType::Tri3,
        nodes,
        connectivity,
    };
    (mesh, material)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/slope");
    std::fs::create_dir_all(&out)?;
    let (mesh, element_material) = mesh(60, 8, 6);
    let sand = MaterialSpec {
        name: "silty_sand".into(),
        porosity: 0.58,
        density_solid: 2718.0,
        density_liquid: Some(1000.0),
        k0: 1.0 - 33f64.to_radians().sin(),
        young_modulus: 2500.0,
        poisson_ratio: 0.3,
        mohr_coulomb: Some((33.0, 0.0, 0.0)),
        // Anura3D's van Genuchten: P0 = 1/α = 1/0.51 kPa, λ = 1 − 1/n with n = 2.73.
        retention: Some(RetentionCurve::VanGenuchten {
            s_min: 0.1,
            s_max: 1.0,
            p0: 1.0 / 0.51,
            lambda: 1.0 - 1.0 / 2.73,
        }),
        // κ = k·μ/(ρw·g) with k = 2.047e-4 m/s, μ = 1e-3 Pa·s.
        permeability: 2.047e-4 * 1e-3 / (1000.0 * 9.81),
    };
    let clay = MaterialSpec {
        name: "compacted_clay".into(),
        porosity: 0.35,
        density_solid: 2700.0,
        density_liquid: None,
        k0: 0.5,
        young_modulus: 5e4,
        poisson_ratio: 0.3,
        mohr_coulomb: None,
        retention: None,
        permeability: 0.0,
    };
    let n_el = mesh.n_elements();
    let solid_fixity = generate::box_fixities(&mesh);
    let model = AnuraModel {
        mesh,
        materials: vec![generate::material(1, &sand), generate::material(2, &clay)],
        element_material,
        mp_counts: vec![(3, 0); n_el],
        liquid_fixity: vec![[false; 3]; solid_fixity.len()],
        solid_fixity,
        damping: None,
    };
    std::fs::write(out.join("slope.GOM"), model_to_text(&model, "2023"))?;
    std::fs::write(
        out.join("slope.CPS_001"),
        "### Anura3D_2023 ###\n$$NUMBER_OF_LOADSTEPS\n1\n$$TIME_PER_LOADSTEP\n0.5\n$$COMPUTATION_METHOD\nMPM-MIXED\n$$GRAVITY_ACCELERATION\n9.81\n$$GRAVITY_VECTOR\n0.0 -1.0\n$$GRAVITY_LOAD\nstep 1.0 1.0\n$$QUASISTATIC_CONVERGENCE\n1\n$$HOMOGENEOUS_LOCAL_DAMPING\n1 0.75\n$$K0_PROCEDURE\n1\n$$VISUALIZATION_OPTION\nParaview\n$$END\n",
    )?;
    // FEM nodes of the sand layer: 0.05 m spacing along x, 0.05 m across the layer.
    let mut csv = String::from("Node,X (m),Y (m),Pore-Water Pressure (kPa),Material\n");
    let (nx, ny) = (120, 12);
    let mut k = 0;
    for j in 0..=ny {
        for i in 0..=nx {
            let x = 6.0 * i as f64 / nx as f64;
            let y = clay_top(x) + SAND * j as f64 / ny as f64;
            k += 1;
            writeln!(csv, "{k},{x},{y},{},silty_sand", pwp(x, y))?;
        }
    }
    std::fs::write(out.join("sand-nodes.csv"), csv)?;
    println!(
        "slope.GOM: {} nodes, {} elements; sand-nodes.csv: {k} nodes",
        model.mesh.n_nodes(),
        n_el
    );
    Ok(())
}
