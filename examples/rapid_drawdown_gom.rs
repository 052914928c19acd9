//! Builds `fixtures/anura3d-rapid-drawdown/rapid_drawdown.GOM`: an Anura3D TRI3
//! model over the GeoStudio rapid-drawdown mesh (`Mesh.ply`), made by splitting
//! every FEM element into counter-clockwise triangles (quads along a diagonal).
//! The base is fixed and the sides are on rollers, found from the outline: a
//! node of a boundary side facing down (the embankment's base at y = 0, the
//! toe block's step and its base at y = −1) is fixed in x and y, a node of a
//! vertical side (the toe block's end at x = 50) in x.
//! Run: `cargo run --example rapid_drawdown_gom`. The output is deterministic.

#![allow(clippy::print_stdout)]

use std::path::Path;

use a3d_init::formats::gom::write::model_to_text;
use a3d_init::formats::ply::read_ply_mesh;
use a3d_init::model::{Dimension, ElementType, Mesh};
use a3d_testkit::generate::{self, MaterialSpec};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let ply =
        root.join("fixtures/geostudio-gsz-internal/rapid-drawdown/1-initial-steady-state_Mesh.ply");
    let (nodes, cells) = read_ply_mesh(&ply)?;
    let mut connectivity = Vec::new();
    let area = |a: u32, b: u32, c: u32| {
        let (p, q, r) = (nodes[a as usize], nodes[b as usize], nodes[c as usize]);
        (q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1])
    };
    let mut push = |a: u32, b: u32, c: u32| {
        let s = area(a, b, c);
        if s.abs() < 1e-12 {
            return;
        }
        if s > 0.0 {
            connectivity.extend([a, b, c])
        } else {
            connectivity.extend([a, c, b])
        }
    };
    for cell in &cells {
        // GeoStudio lists corner nodes first; higher-order nodes (if any) follow.
        match cell.len() {
            3 | 6 => push(cell[0], cell[1], cell[2]),
            4 | 8 => {
                push(cell[0], cell[1], cell[2]);
                push(cell[0], cell[2], cell[3]);
            }
            _ => {}
        }
    }
    let mesh = Mesh {
        dimension: Dimension::PlaneStrain,
        element_type: ElementType::Tri3,
        nodes,
        connectivity,
    };
    let spec = MaterialSpec {
        name: "embankment".into(),
        porosity: 0.4,
        density_solid: 2650.0,
        density_liquid: Some(1000.0),
        k0: 0.5,
        young_modulus: 2e4,
        poisson_ratio: 0.3,
        mohr_coulomb: Some((30.0, 5.0, 0.0)),
        retention: None,
        permeability: 1e-11,
    };
    let fixity = base_and_side_fixities(&mesh);
    let mut model = generate::single_material_model(mesh, &spec, 3);
    model.solid_fixity = fixity;
    let out = root.join("fixtures/anura3d-rapid-drawdown");
    std::fs::create_dir_all(&out)?;
    std::fs::write(
        out.join("rapid_drawdown.GOM"),
        model_to_text(&model, "2023"),
    )?;
    println!(
        "{} nodes, {} triangles, {} nodes fixed, {} on rollers",
        model.mesh.n_nodes(),
        model.mesh.n_elements(),
        model.solid_fixity.iter().filter(|f| f[0] && f[1]).count(),
        model.solid_fixity.iter().filter(|f| f[0] && !f[1]).count()
    );
    Ok(())
}

/// Per node: fixed in x and y on a boundary side whose outward normal points
/// down (n_y < 0), fixed in x on a vertical one (n_y = 0); free elsewhere.
fn base_and_side_fixities(mesh: &Mesh) -> Vec<[bool; 3]> {
    use std::collections::HashMap;
    let mut sides: HashMap<(u32, u32), usize> = HashMap::new();
    let triangles: Vec<[u32; 3]> = mesh
        .connectivity
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    for t in &triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *sides.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut fixity = vec![[false; 3]; mesh.nodes.len()];
    for t in &triangles {
        // Counter-clockwise: the outward normal of side a→b is (dy, −dx).
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if sides[&(a.min(b), a.max(b))] != 1 {
                continue;
            }
            let (p, q) = (mesh.nodes[a as usize], mesh.nodes[b as usize]);
            let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
            let (nx, ny) = (dy, -dx);
            let length = dx.hypot(dy);
            let fixed = if ny < -1e-9 * length {
                [true, true]
            } else if ny.abs() <= 1e-9 * length && nx.abs() > 0.0 {
                [true, false]
            } else {
                continue;
            };
            for n in [a, b] {
                let f = &mut fixity[n as usize];
                f[0] |= fixed[0];
                f[1] |= fixed[1];
            }
        }
    }
    fixity
}
