//! Test and benchmark support (feature `testkit`, not part of the default
//! library API): for the MPM check,
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
//! * [`inclined_layer_tri3`]: a periodic layer parallel to a slope of angle β
//!   on a fixed base (its two ends tied node to node), with
//!   [`infinite_slope_states`], the exact infinite-slope stresses with
//!   optional seepage parallel to the surface.
//! * [`vertical_cut_tri3`]: a vertical cut on a foundation, each square cell
//!   split into four triangles through its centre, with
//!   [`cut_geostatic_states`].
//!
//! Nothing here reads files; it is plain data construction.

pub mod generate;
pub mod slopes;

use a3d_element::{Element, Simplex, TetOld, Tri3};
use a3d_model::{AnuraModel, Dimension, ElementType, Material, MaterialPoint, Mesh, MpState};

/// A dry linear elastic material (ρs in kg/m³, E in kPa).
pub fn elastic_material(young: f64, poisson: f64, density_solid: f64, porosity: f64) -> Material {
    Material {
        model: Some("linear_elasticity".into()),
        porosity: Some(porosity),
        density_solid: Some(density_solid),
        k0: Some(poisson / (1.0 - poisson)),
        young_modulus: Some(young),
        poisson_ratio: Some(poisson),
        ..Material::new(1, "elastic", "dry_material")
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

/// Turns a material into `saturated_material_coupled` (Anura3D's two-phase
/// single point): water of 1000 kg/m³, intrinsic permeability `kappa` (m²),
/// liquid bulk modulus `bulk` (kPa), viscosity 1e-6 kPa·s (water).
pub fn coupled(material: Material, kappa: f64, bulk: f64) -> Material {
    let mut m = material;
    generate::make_coupled(&mut m, kappa, bulk, 1e-6);
    m
}

/// The liquid held where the solid is (impermeable sides and base) and free
/// elsewhere (a free surface drains).
pub fn impermeable_where_fixed(model: &mut AnuraModel) {
    model.liquid_fixity = model.solid_fixity.clone();
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
    finish_tri3(nodes, connectivity, material, fixity)
}

/// A 3D `tetrahedral_old` column `width` (x) × `height` (y) × `depth` (z)
/// with `nx` × `ny` × `nz` cells of 6 Kuhn tetrahedra each
/// ([`generate::structured_tet_mesh`]); x and z sides on rollers, base fixed.
pub fn column_tet(
    width: f64,
    height: f64,
    depth: f64,
    nx: usize,
    ny: usize,
    nz: usize,
    material: Material,
) -> AnuraModel {
    let mesh = generate::structured_tet_mesh(width, 0.0, height, depth, nx, ny, nz);
    let fixity = generate::box_fixities(&mesh);
    let n_elements = mesh.n_elements();
    finish(mesh, material, fixity, n_elements, 4)
}

/// A plane-strain TRI3 model of one material with 3 MPs per element.
fn finish_tri3(
    nodes: Vec<[f64; 3]>,
    connectivity: Vec<u32>,
    material: Material,
    fixity: Vec<[bool; 3]>,
) -> AnuraModel {
    let n_elements = connectivity.len() / 3;
    let mesh = Mesh {
        dimension: Dimension::PlaneStrain,
        element_type: ElementType::Tri3,
        nodes,
        connectivity,
    };
    finish(mesh, material, fixity, n_elements, 3)
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
        liquid_fixity: vec![[false; 3]; fixity.len()],
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
                    let x = Tri3::global_position(&corners, &[xi, eta]);
                    push(k as u32 + 1, [x[0], x[1], 0.0], area / 3.0);
                }
            }
            ElementType::TetOld => {
                let corners = [c[0], c[1], c[2], c[3]];
                let volume = Simplex::<3, 4>::from_corners(&corners).map_or(0.0, |s| s.measure());
                let table = [(a, a, a), (a, a, b), (b, a, a), (a, b, a)];
                for (k, (xi, eta, zeta)) in table.into_iter().enumerate() {
                    let x = TetOld::global_position(&corners, &[xi, eta, zeta]);
                    push(k as u32 + 1, x, volume / 4.0);
                }
            }
            ElementType::Quad4 | ElementType::Hex8 => {}
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
    let gamma_w = a3d_model::gamma_water(gravity);
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

/// A layer of thickness `thickness` (measured normal to the surface) and
/// length `length` along a slope of angle `beta_deg` (falling towards +x),
/// meshed with `nx` × `ny` cells of two TRI3 each in the slope's own frame.
/// The base is fixed; the end columns of nodes are tied node to node (mesh
/// node (nx, j) to (0, j)), which makes the layer periodic: an infinite
/// slope. Returns the model and the tied pairs (0-based mesh nodes).
pub fn inclined_layer_tri3(
    beta_deg: f64,
    thickness: f64,
    length: f64,
    nx: usize,
    ny: usize,
    material: Material,
) -> (AnuraModel, Vec<(u32, u32)>) {
    let (sin, cos) = beta_deg.to_radians().sin_cos();
    let mut model = column_tri3(length, thickness, nx, ny, material);
    // Map (s, n) of the rectangle to x = s·e_s + n·e_n with e_s = (cos β, −sin β)
    // and e_n = (sin β, cos β): a rotation, so orientation is kept.
    for (node, fixity) in model.mesh.nodes.iter_mut().zip(&mut model.solid_fixity) {
        let (s, n) = (node[0], node[1]);
        *node = [s * cos + n * sin, -s * sin + n * cos, 0.0];
        *fixity = if n == 0.0 {
            [true, true, false]
        } else {
            [false; 3]
        };
    }
    let tied = (0..=ny)
        .map(|j| ((j * (nx + 1)) as u32, (j * (nx + 1) + nx) as u32))
        .collect();
    (model, tied)
}

/// The exact stress of an infinite slope of angle `beta_deg` whose surface
/// passes through (0, `surface_y0`) (falling towards +x): at depth d normal
/// to the surface, σnn = −γ·d·cos β and τ = γ·d·sin β (γ at S = 1), the
/// effective stress along the slope and out of plane K·σ′nn. With
/// `seepage`, flow parallel to the surface with the water table at the
/// surface: p = −γw·z·cos²β (z the vertical depth), otherwise p = 0.
pub fn infinite_slope_states(
    model: &AnuraModel,
    points: &[MaterialPoint],
    beta_deg: f64,
    surface_y0: f64,
    k: f64,
    gravity: f64,
    seepage: bool,
) -> Vec<MpState> {
    let (sin, cos) = beta_deg.to_radians().sin_cos();
    let gamma_w = a3d_model::gamma_water(gravity);
    let e_s = [cos, -sin];
    let e_n = [sin, cos];
    points
        .iter()
        .map(|p| {
            let gamma = model.materials[p.material as usize - 1].gamma_at_saturation(1.0, gravity);
            let (x, y) = (p.position[0], p.position[1]);
            let z = (surface_y0 - x * sin / cos - y).max(0.0);
            let d = z * cos;
            let pwp = if seepage {
                -gamma_w * z * cos * cos
            } else {
                0.0
            };
            let normal = -gamma * d * cos;
            let shear = gamma * d * sin;
            let along = k * (normal - pwp) + pwp;
            // σ = σss e_s⊗e_s + σnn e_n⊗e_n + τ (e_s⊗e_n + e_n⊗e_s)
            let t = |a: usize, b: usize| {
                along * e_s[a] * e_s[b]
                    + normal * e_n[a] * e_n[b]
                    + shear * (e_s[a] * e_n[b] + e_n[a] * e_s[b])
            };
            MpState {
                pwp,
                total: [t(0, 0), t(1, 1), along, t(0, 1), 0.0, 0.0],
                saturation: 1.0,
            }
        })
        .collect()
}

/// A vertical cut of height `height` in plane strain: ground at y = height
/// for x < `behind`, at y = 0 for `behind` < x < `behind` + `front`, on a
/// foundation down to y = −`depth`. Square cells of size `cell` (the
/// lengths must be multiples of it), each split into four TRI3 through its
/// centre (crossed diagonals, free of volumetric locking in plane strain);
/// the cells above the ground in front of the cut are material 0, so the
/// mechanism can move into them. Base fixed, sides on rollers.
pub fn vertical_cut_tri3(
    height: f64,
    behind: f64,
    front: f64,
    depth: f64,
    cell: f64,
    material: Material,
) -> AnuraModel {
    let count = |l: f64| (l / cell).round() as usize;
    let (nb, nf, nh, nd) = (count(behind), count(front), count(height), count(depth));
    let (nx, ny) = (nb + nf, nd + nh);
    let width = cell * nx as f64;
    let corner = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut nodes = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            nodes.push([cell * i as f64, cell * j as f64 - depth, 0.0]);
        }
    }
    let mut connectivity = Vec::new();
    let mut element_material = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let centre = nodes.len() as u32;
            nodes.push([
                cell * (i as f64 + 0.5),
                cell * (j as f64 + 0.5) - depth,
                0.0,
            ]);
            let (a, b, c, d) = (
                corner(i, j),
                corner(i + 1, j),
                corner(i + 1, j + 1),
                corner(i, j + 1),
            );
            let active = i < nb || j < nd;
            for (p, q) in [(a, b), (b, c), (c, d), (d, a)] {
                connectivity.extend_from_slice(&[p, q, centre]);
                element_material.push(u32::from(active));
            }
        }
    }
    let fixity = nodes
        .iter()
        .map(|p| {
            let base = p[1] <= -depth + 1e-9 * cell;
            let side = p[0] <= 1e-9 * cell || p[0] >= width - 1e-9 * cell;
            [side || base, base, false]
        })
        .collect();
    let mut model = finish_tri3(nodes, connectivity, material, fixity);
    for (e, &m) in element_material.iter().enumerate() {
        model.element_material[e] = m;
        model.mp_counts[e] = (if m == 0 { 0 } else { 3 }, 0);
    }
    model
}

/// Geostatic state of [`vertical_cut_tri3`]: σv = −γ·(ground − y) with the
/// ground at `height` for x < `behind` and at 0 beyond, σh = K0·σv, dry.
pub fn cut_geostatic_states(
    model: &AnuraModel,
    points: &[MaterialPoint],
    height: f64,
    behind: f64,
    k0: f64,
    gravity: f64,
) -> Vec<MpState> {
    points
        .iter()
        .map(|p| {
            let gamma = model.materials[p.material as usize - 1].gamma_at_saturation(1.0, gravity);
            let ground = if p.position[0] < behind { height } else { 0.0 };
            let v = -gamma * (ground - p.position[1]).max(0.0);
            MpState {
                pwp: 0.0,
                total: [k0 * v, v, k0 * v, 0.0, 0.0, 0.0],
                saturation: 1.0,
            }
        })
        .collect()
}
