//! Writing a new GOM from an [`AnuraModel`] (for generated fixtures, the demo and
//! benchmarks). Existing files are never re-rendered through this path: they keep
//! their bytes through the lossless document.
//!
//! Layout follows GiD's block order. Material records are written as their
//! verbatim (name, value) pairs: build materials with [`Material::properties`]
//! filled in the positional order of `formats/gom.md`.

use std::fmt::Write;

use crate::table_text::fmt_f64;
use a3d_model::{AnuraModel, Material};

/// Renders `model` as GOM text with header `### Anura3D_<version> ###` and LF endings.
pub fn model_to_text(model: &AnuraModel, version: &str) -> String {
    let mesh = &model.mesh;
    let n_dim = mesh.dimension.n_dim();
    let mut s = String::with_capacity(mesh.n_nodes() * 40 + mesh.n_elements() * 40 + 4096);
    let _ = writeln!(s, "### Anura3D_{version} ###");
    let _ = writeln!(s, "$$DIMENSION\n{}", mesh.dimension.gom_name());
    let _ = writeln!(s, "$$ELEMENTTYPE\n{}", mesh.element_type.gom_name());
    let _ = writeln!(s, "$$FORMULATION\nsingle-point");
    let _ = writeln!(
        s,
        "$$STARTCOUNTERS\n{} {}",
        mesh.n_elements(),
        mesh.n_nodes()
    );
    s.push_str("$$STARTNODES\n");
    for p in &mesh.nodes {
        for (k, v) in p.iter().take(n_dim).enumerate() {
            if k > 0 {
                s.push(' ');
            }
            s.push_str(&fmt_f64(*v));
        }
        s.push('\n');
    }
    s.push_str("$$STARTELEMCON\n");
    for e in 0..mesh.n_elements() {
        let ids: Vec<String> = mesh
            .element_nodes(e)
            .iter()
            .map(|n| (n + 1).to_string())
            .collect();
        s.push_str(&ids.join(" "));
        s.push('\n');
    }
    write_fixity(
        &mut s,
        "$$START_FIXITY_SURFACE_SOLID",
        &model.solid_fixity,
        n_dim,
    );
    if model.liquid_fixity.iter().flatten().any(|&b| b) {
        write_fixity(
            &mut s,
            "$$START_FIXITY_SURFACE_LIQUID",
            &model.liquid_fixity,
            n_dim,
        );
    }
    let _ = writeln!(s, "$$NUMBER_OF_MATERIALS\n{}", model.materials.len());
    for m in &model.materials {
        write_material(&mut s, m);
    }
    s.push_str("$$STARTELMMAT\n");
    for m in &model.element_material {
        let _ = writeln!(s, "{m}");
    }
    if let Some(damping) = &model.damping {
        s.push_str("$$STARTDAMPING\n");
        for d in damping {
            let _ = writeln!(s, "{}", fmt_f64(*d));
        }
    }
    s.push_str("$$START_NUMBER_OF_MATERIAL_POINTS\n");
    for (solid, liquid) in &model.mp_counts {
        let _ = writeln!(s, "{solid} {liquid}");
    }
    s.push_str("$$FINISH\n");
    s
}

fn write_material(s: &mut String, m: &Material) {
    let _ = writeln!(s, "$$MATERIAL_INDEX\n{}", m.index);
    let _ = writeln!(s, "$$MATERIAL_NAME\n{}", m.name);
    let _ = writeln!(s, "$$MATERIAL_TYPE\n{}", m.material_type);
    for (name, value) in &m.properties {
        let _ = writeln!(s, "{name}\n{value}");
    }
}

/// A fixity block: the count of nodes with any direction fixed, then
/// `node fx fy [fz]` for each.
fn write_fixity(s: &mut String, keyword: &str, fixity: &[[bool; 3]], n_dim: usize) {
    let fixed: Vec<(usize, &[bool; 3])> = fixity
        .iter()
        .enumerate()
        .filter(|(_, f)| f.iter().any(|&b| b))
        .collect();
    let _ = writeln!(s, "{keyword}\n{}", fixed.len());
    for (node, f) in fixed {
        let flags: Vec<&str> = f
            .iter()
            .take(n_dim)
            .map(|&b| if b { "1" } else { "0" })
            .collect();
        let _ = writeln!(s, "{} {}", node + 1, flags.join(" "));
    }
}
