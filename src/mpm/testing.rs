//! Test and benchmark support for the MPM check (hidden from the docs):
//! structured column meshes with their [`AnuraModel`], a minimal MP placement
//! and analytic geostatic states.
//!
//! * [`column_tri3`]: a width × height rectangle of counter-clockwise TRI3
//!   pairs; sides on rollers (x fixed), base fixed.
//! * [`column_tet`]: a width × height × depth box of `tetrahedral_old`
//!   elements (6 Kuhn tetrahedra per cell, positively oriented in Anura3D's
//!   sense, with 10 node ids: 4 corners then the mid-edge nodes of edges 1-2,
//!   2-3, 3-1, 1-4, 2-4, 3-4); x and z sides on rollers, base fixed.
//! * [`place_points`]: 3 MPs per triangle at (1/6, 1/6), (2/3, 1/6),
//!   (1/6, 2/3) with volume area/3; 4 MPs per tetrahedron at Anura3D's A/B
//!   rule with volume V/4. A stand-in for the real placement module.
//! * [`geostatic_states`]: σ′v = −γ′·depth, σ′h = K0·σ′v, hydrostatic pore
//!   pressure below an optional water table.
//!
//! Nothing here reads files; it is plain data construction.

use std::collections::HashMap;

use super::shape::{Simplex, tet_old_local_to_global, tri3_local_to_global};
use crate::model::{AnuraModel, Dimension, ElementType, Material, MaterialPoint, Mesh, MpState};

/// A dry linear elastic material (ρs in kg/m³, E in kPa).
pub fn elastic_material(young: f64, poisson: f64, density_solid: f64, porosity: f64) -> Material {
    Material {
        index: 1,
        name: "elastic".into(),
        material_type: "dry_material".into(),
        model: Some("linear_elasticity".into()),
        porosity: Some(porosity),
        density_solid: Some(density_solid),
        density_liquid: None,
        k0: Some(poisson / (1.0 - poisson)),
        young_modulus: Some(young),
        poisson_ratio: Some(poisson),
        friction_angle: None,
        cohesion: None,
        dilatancy_angle: None,
        tensile_strength: None,
        retention: None,
        properties: Vec::new(),
    }
}

/// A dry Mohr–Coulomb material (angles in degrees, c and σt in kPa).
pub fn mohr_coulomb_material(
    young: f64,
    poisson: f64,
    density_solid: f64,
    porosity: f64,
    friction: f64,
    cohesion: f64,
    dilatancy: f64,
) -> Material {
    Material {
        name: "mohr_coulomb".into(),
        model: Some("mohr_coulomb".into()),
        k0: Some(1.0 - friction.to_radians().sin()),
        friction_angle: Some(friction),
        cohesion: Some(cohesion),
        dilatancy_angle: Some(dilatancy),
        tensile_strength: Some(0.0),
        ..elastic_material(young, poisson, density_solid, porosity)
    }
}

/// Turns a material into `saturated_material_drained` with water of 1000 kg/m³.
pub fn saturated(material: Material) -> Material {
    Material {
        material_type: "saturated_material_drained".into(),
        density_liquid: Some(1000.0),
        ..material
    }
}

/// A plane-strain TRI3 column `width` × `height` with `nx` × `ny` cells, each
/// split along its rising diagonal into two counter-clockwise triangles.
pub fn column_tri3(
    width: f64,
    height: f64,
    nx: usize,
    ny: usize,
    material: Material,
) -> AnuraModel {
    let node = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            nodes.push([
                width * i as f64 / nx as f64,
                height * j as f64 / ny as f64,
                0.0,
            ]);
        }
    }
    let mut connectivity = Vec::with_capacity(6 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (
                node(i, j),
                node(i + 1, j),
                node(i + 1, j + 1),
                node(i, j + 1),
            );
            connectivity.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    let fixity = nodes
        .iter()
        .map(|p| {
            let side = p[0] == 0.0 || p[0] == width;
            let base = p[1] == 0.0;
            [side || base, base, false]
        })
        .collect();
    let n_elements = connectivity.len() / 3;
    finish(
        Mesh {
            dimension: Dimension::PlaneStrain,
            element_type: ElementType::Tri3,
            nodes,
            connectivity,
        },
        material,
        fixity,
        n_elements,
        3,
    )
}

/// A 3D `tetrahedral_old` column `width` (x) × `height` (y) × `depth` (z)
/// with `nx` × `ny` × `nz` cells of 6 tetrahedra each.
pub fn column_tet(
    width: f64,
    height: f64,
    depth: f64,
    nx: usize,
    ny: usize,
    nz: usize,
    material: Material,
) -> AnuraModel {
    let node = |i: usize, j: usize, k: usize| (k * (ny + 1) * (nx + 1) + j * (nx + 1) + i) as u32;
    let mut nodes = Vec::new();
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                nodes.push([
                    width * i as f64 / nx as f64,
                    height * j as f64 / ny as f64,
                    depth * k as f64 / nz as f64,
                ]);
            }
        }
    }
    let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
    let mut connectivity = Vec::new();
    // The six monotone paths from corner (0,0,0) to (1,1,1) of a cell.
    let paths = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                for path in paths {
                    let mut at = [i, j, k];
                    let mut corners = [node(i, j, k); 4];
                    for (step, &axis) in path.iter().enumerate() {
                        at[axis] += 1;
                        corners[step + 1] = node(at[0], at[1], at[2]);
                    }
                    let p = |n: u32| nodes[n as usize];
                    let (a, b, c, d) = (p(corners[0]), p(corners[1]), p(corners[2]), p(corners[3]));
                    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                    let w = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
                    let triple = u[0] * (v[1] * w[2] - v[2] * w[1])
                        - u[1] * (v[0] * w[2] - v[2] * w[0])
                        + u[2] * (v[0] * w[1] - v[1] * w[0]);
                    if triple < 0.0 {
                        corners.swap(2, 3);
                    }
                    connectivity.extend_from_slice(&corners);
                    for (x, y) in [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)] {
                        let key = (corners[x].min(corners[y]), corners[x].max(corners[y]));
                        let id = *mid.entry(key).or_insert_with(|| {
                            let (q, r) = (nodes[key.0 as usize], nodes[key.1 as usize]);
                            nodes.push([
                                0.5 * (q[0] + r[0]),
                                0.5 * (q[1] + r[1]),
                                0.5 * (q[2] + r[2]),
                            ]);
                            (nodes.len() - 1) as u32
                        });
                        connectivity.push(id);
                    }
                }
            }
        }
    }
    let fixity = nodes
        .iter()
        .map(|p| {
            let base = p[1] == 0.0;
            [
                base || p[0] == 0.0 || p[0] == width,
                base,
                base || p[2] == 0.0 || p[2] == depth,
            ]
        })
        .collect();
    let n_elements = connectivity.len() / 10;
    finish(
        Mesh {
            dimension: Dimension::Cartesian3D,
            element_type: ElementType::TetOld,
            nodes,
            connectivity,
        },
        material,
        fixity,
        n_elements,
        4,
    )
}

fn finish(
    mesh: Mesh,
    material: Material,
    fixity: Vec<[bool; 3]>,
    n_elements: usize,
    mps: u32,
) -> AnuraModel {
    AnuraModel {
        mesh,
        materials: vec![Material {
            index: 1,
            ..material
        }],
        element_material: vec![1; n_elements],
        mp_counts: vec![(mps, 0); n_elements],
        solid_fixity: fixity,
        damping: None,
    }
}

/// Places MPs in every active element: 3 per TRI3, 4 per `tetrahedral_old`.
pub fn place_points(model: &AnuraModel) -> Vec<MaterialPoint> {
    let mesh = &model.mesh;
    let a = (5.0 - 5.0_f64.sqrt()) / 20.0;
    let b = (5.0 + 3.0 * 5.0_f64.sqrt()) / 20.0;
    let mut points = Vec::new();
    for e in 0..mesh.n_elements() {
        let material = model.element_material[e];
        if material == 0 {
            continue;
        }
        let c = mesh.corner_coords(e);
        let mut push = |local: u32, position: [f64; 3], volume: f64| {
            points.push(MaterialPoint {
                id: points.len() as u32 + 1,
                element: e as u32,
                material,
                local,
                position,
                volume,
            });
        };
        match mesh.element_type {
            ElementType::Tri3 => {
                let corners = [[c[0][0], c[0][1]], [c[1][0], c[1][1]], [c[2][0], c[2][1]]];
                let area = Simplex::<2, 3>::from_corners(&corners).map_or(0.0, |s| s.measure());
                let table = [
                    (1.0 / 6.0, 1.0 / 6.0),
                    (2.0 / 3.0, 1.0 / 6.0),
                    (1.0 / 6.0, 2.0 / 3.0),
                ];
                for (k, (xi, eta)) in table.into_iter().enumerate() {
                    let x = tri3_local_to_global(&corners, xi, eta);
                    push(k as u32 + 1, [x[0], x[1], 0.0], area / 3.0);
                }
            }
            ElementType::TetOld => {
                let corners = [c[0], c[1], c[2], c[3]];
                let volume = Simplex::<3, 4>::from_corners(&corners).map_or(0.0, |s| s.measure());
                let table = [(a, a, a), (a, a, b), (b, a, a), (a, b, a)];
                for (k, (xi, eta, zeta)) in table.into_iter().enumerate() {
                    let x = tet_old_local_to_global(&corners, xi, eta, zeta);
                    push(k as u32 + 1, x, volume / 4.0);
                }
            }
            ElementType::Quad4 => {}
        }
    }
    points
}

/// Geostatic state of a uniform column whose ground surface is the top of the
/// mesh: σv = −γ·depth (γ at S = 1 for materials with water), hydrostatic
/// pore pressure p = −γw·(y_w − y) below `water_table` (0 above, S = 1
/// everywhere), σ′v = σv − p, σ′h = K0·σ′v, total σh = σ′h + p.
pub fn geostatic_states(
    model: &AnuraModel,
    points: &[MaterialPoint],
    gravity: f64,
    k0: f64,
    water_table: Option<f64>,
) -> Vec<MpState> {
    let top = model.mesh.bounding_box().1[1];
    let gamma_w = crate::model::gamma_water(gravity);
    points
        .iter()
        .map(|p| {
            let gamma = model.materials[p.material as usize - 1].gamma_at_saturation(1.0, gravity);
            let y = p.position[1];
            let total_v = -gamma * (top - y);
            let pwp = water_table.map_or(0.0, |w| if y < w { -gamma_w * (w - y) } else { 0.0 });
            let effective_v = total_v - pwp;
            let total_h = k0 * effective_v + pwp;
            MpState {
                pwp,
                total: [total_h, total_v, total_h, 0.0, 0.0, 0.0],
                saturation: 1.0,
            }
        })
        .collect()
}

/// Zero stress, zero pore pressure, S = 1 for every MP.
pub fn zero_states(points: &[MaterialPoint]) -> Vec<MpState> {
    vec![
        MpState {
            pwp: 0.0,
            total: [0.0; 6],
            saturation: 1.0,
        };
        points.len()
    ]
}
