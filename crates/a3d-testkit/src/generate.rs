//! Builders for structured meshes and simple materials: the analytic test cases,
//! benchmarks, examples and generated fixtures. Pure data, no I/O.

use a3d_model::material::{Material, RetentionCurve};
use a3d_model::{AnuraModel, Dimension, ElementType, Mesh};

/// A rectangle [x0, x0+width] × [y0, y0+height] split into nx × ny cells, each
/// cut into two counter-clockwise triangles along alternating diagonals.
pub fn structured_tri_mesh(
    x0: f64,
    y0: f64,
    width: f64,
    height: f64,
    nx: usize,
    ny: usize,
) -> Mesh {
    let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            nodes.push([
                x0 + width * i as f64 / nx as f64,
                y0 + height * j as f64 / ny as f64,
                0.0,
            ]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut connectivity = Vec::with_capacity(nx * ny * 6);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i + j) % 2 == 0 {
                connectivity.extend_from_slice(&[a, b, c, a, c, d]);
            } else {
                connectivity.extend_from_slice(&[a, b, d, b, c, d]);
            }
        }
    }
    Mesh {
        dimension: Dimension::PlaneStrain,
        element_type: ElementType::Tri3,
        nodes,
        connectivity,
    }
}

/// A box [0, wx] × [y0, y0+height] × [0, wz] split into nx × ny × nz cubes, each cut
/// into six positive-volume tetrahedra (Kuhn subdivision), written as
/// `tetrahedral_old` with the six mid-edge nodes appended to the node list.
pub fn structured_tet_mesh(
    wx: f64,
    y0: f64,
    height: f64,
    wz: f64,
    nx: usize,
    ny: usize,
    nz: usize,
) -> Mesh {
    let mut nodes = Vec::new();
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                nodes.push([
                    wx * i as f64 / nx as f64,
                    y0 + height * j as f64 / ny as f64,
                    wz * k as f64 / nz as f64,
                ]);
            }
        }
    }
    let id = |i: usize, j: usize, k: usize| (k * (ny + 1) * (nx + 1) + j * (nx + 1) + i) as u32;
    let mut mid: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    let mut connectivity = Vec::new();
    // Kuhn: the six tetrahedra share the main diagonal 0 → 7 of the cube.
    const PATHS: [[usize; 3]; 6] = [
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
                for path in PATHS {
                    let mut c = [i, j, k];
                    let mut corners = [id(c[0], c[1], c[2]); 4];
                    for (step, &axis) in path.iter().enumerate() {
                        c[axis] += 1;
                        corners[step + 1] = id(c[0], c[1], c[2]);
                    }
                    // Orientation: make (x2−x1)·[(x3−x1)×(x4−x1)] > 0.
                    let p = |n: u32| nodes[n as usize];
                    let (a, b, cc, d) =
                        (p(corners[0]), p(corners[1]), p(corners[2]), p(corners[3]));
                    let sub = |u: [f64; 3], v: [f64; 3]| [u[0] - v[0], u[1] - v[1], u[2] - v[2]];
                    let (u, v, w) = (sub(b, a), sub(cc, a), sub(d, a));
                    let triple = u[0] * (v[1] * w[2] - v[2] * w[1])
                        - u[1] * (v[0] * w[2] - v[2] * w[0])
                        + u[2] * (v[0] * w[1] - v[1] * w[0]);
                    if triple < 0.0 {
                        corners.swap(2, 3);
                    }
                    let mut ids = corners.to_vec();
                    for (e1, e2) in [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)] {
                        let key = (corners[e1].min(corners[e2]), corners[e1].max(corners[e2]));
                        let m = *mid.entry(key).or_insert_with(|| {
                            let (pa, pb) = (nodes[key.0 as usize], nodes[key.1 as usize]);
                            nodes.push([
                                (pa[0] + pb[0]) / 2.0,
                                (pa[1] + pb[1]) / 2.0,
                                (pa[2] + pb[2]) / 2.0,
                            ]);
                            (nodes.len() - 1) as u32
                        });
                        ids.push(m);
                    }
                    connectivity.extend_from_slice(&ids);
                }
            }
        }
    }
    Mesh {
        dimension: Dimension::Cartesian3D,
        element_type: ElementType::TetOld,
        nodes,
        connectivity,
    }
}

/// Turns a box mesh of height `height` (base at y = 0) into a slope: every
/// node's y is scaled by h(x)/`height`, with the ground h(x) = `crest` for
/// x ≤ `x0`, `toe` for x ≥ `x1` and linear between (an embankment's or a
/// cut's face). Elements keep their orientation; the base and the sides stay
/// where they were, so [`box_fixities`] still holds the model.
pub fn slope_profile(mesh: &mut Mesh, height: f64, crest: f64, toe: f64, x0: f64, x1: f64) {
    for p in &mut mesh.nodes {
        let t = ((p[0] - x0) / (x1 - x0)).clamp(0.0, 1.0);
        let ground = crest + t * (toe - crest);
        p[1] *= ground / height;
    }
}

/// Solid fixities of a box: base (y = min) fixed in all directions, the lateral
/// faces (x = min/max, and z = min/max in 3D) on rollers.
pub fn box_fixities(mesh: &Mesh) -> Vec<[bool; 3]> {
    let (lo, hi) = mesh.bounding_box();
    let tol = 1e-9 * (hi[0] - lo[0]).abs().max(hi[1] - lo[1]).max(1.0);
    let three_d = mesh.dimension.n_dim() == 3;
    mesh.nodes
        .iter()
        .map(|p| {
            let base = (p[1] - lo[1]).abs() < tol;
            let side_x = (p[0] - lo[0]).abs() < tol || (p[0] - hi[0]).abs() < tol;
            let side_z = three_d && ((p[2] - lo[2]).abs() < tol || (p[2] - hi[2]).abs() < tol);
            [base || side_x, base, three_d && (base || side_z)]
        })
        .collect()
}

/// Parameters of a material built here.
#[derive(Clone, Debug)]
pub struct MaterialSpec {
    pub name: String,
    pub porosity: f64,
    pub density_solid: f64,
    /// `Some(ρw)` for a material with water (saturated_material_drained, or
    /// unsaturated_material_2phase_suction when `retention` is given).
    pub density_liquid: Option<f64>,
    pub k0: f64,
    pub young_modulus: f64,
    pub poisson_ratio: f64,
    /// `Some((φ', c', ψ))` for Mohr–Coulomb, `None` for linear elasticity.
    pub mohr_coulomb: Option<(f64, f64, f64)>,
    pub retention: Option<RetentionCurve>,
    pub permeability: f64,
}

impl MaterialSpec {
    /// A dry Mohr–Coulomb soil (n = 0.4, ρs = 2650, E = 10⁴ kPa, ν = 0.3, φ' = 30°,
    /// c' = 1 kPa): the material of generated benchmark models.
    pub fn dry_soil(name: &str) -> MaterialSpec {
        MaterialSpec {
            name: name.into(),
            porosity: 0.4,
            density_solid: 2650.0,
            density_liquid: None,
            k0: 0.5,
            young_modulus: 1e4,
            poisson_ratio: 0.3,
            mohr_coulomb: Some((30.0, 1.0, 0.0)),
            retention: None,
            permeability: 0.0,
        }
    }
}

/// Makes `material` Anura3D's two-phase `saturated_material_coupled`:
/// intrinsic permeability `kappa` (m²), liquid bulk modulus `bulk` (kPa) and
/// dynamic viscosity `viscosity` (kPa·s) written right after
/// `$$DENSITY_LIQUID`, where Anura3D reads them (it reads positionally);
/// earlier values of these keywords are replaced.
pub fn make_coupled(material: &mut Material, kappa: f64, bulk: f64, viscosity: f64) {
    const KEYS: [&str; 3] = [
        "$$INTRINSIC_PERMEABILITY_LIQUID",
        "$$BULK_MODULUS_LIQUID",
        "$$DYNAMIC_VISCOSITY_LIQUID",
    ];
    material.material_type = "saturated_material_coupled".into();
    if material.density_liquid.is_none() {
        material.density_liquid = Some(1000.0);
    }
    let props = &mut material.properties;
    props.retain(|(k, _)| !KEYS.contains(&k.as_str()));
    let at = match props.iter().position(|(k, _)| k == "$$DENSITY_LIQUID") {
        Some(i) => i + 1,
        None => {
            let after_solid = props
                .iter()
                .position(|(k, _)| k == "$$DENSITY_SOLID")
                .map_or(0, |i| i + 1);
            let rho = material.density_liquid.unwrap_or(1000.0);
            props.insert(after_solid, ("$$DENSITY_LIQUID".into(), rho.to_string()));
            after_solid + 1
        }
    };
    for (i, (k, v)) in KEYS.iter().zip([kappa, bulk, viscosity]).enumerate() {
        props.insert(at + i, (k.to_string(), v.to_string()));
    }
}

/// Builds a [`Material`] with its verbatim positional properties.
pub fn material(index: u32, spec: &MaterialSpec) -> Material {
    let mut props: Vec<(String, String)> = Vec::new();
    let mut push = |k: &str, v: String| props.push((format!("$${k}"), v));
    let material_type = match (spec.density_liquid, &spec.retention) {
        (None, _) => "dry_material",
        (Some(_), None) => "saturated_material_drained",
        (Some(_), Some(_)) => "unsaturated_material_2phase_suction",
    };
    push("POROSITY_SOLID", spec.porosity.to_string());
    push("DENSITY_SOLID", spec.density_solid.to_string());
    if let Some(rho_w) = spec.density_liquid {
        push("DENSITY_LIQUID", rho_w.to_string());
        if spec.retention.is_some() {
            push(
                "INTRINSIC_PERMEABILITY_LIQUID",
                spec.permeability.to_string(),
            );
            push("BULK_MODULUS_LIQUID", "45000".into());
            push("DYNAMIC_VISCOSITY_LIQUID", "1e-6".into());
        }
    }
    push("K0_VALUE_SOLID", spec.k0.to_string());
    let model = if spec.mohr_coulomb.is_some() {
        "mohr_coulomb"
    } else {
        "linear_elasticity"
    };
    push("MATERIAL_MODEL_SOLID", model.into());
    push("YOUNG_MODULUS", spec.young_modulus.to_string());
    push("POISSON_RATIO", spec.poisson_ratio.to_string());
    if let Some((phi, c, psi)) = spec.mohr_coulomb {
        push("FRICTION_ANGLE", phi.to_string());
        push("COHESION", c.to_string());
        push("DILATANCY_ANGLE", psi.to_string());
        push("TENSILE_STRENGTH", "0.0".into());
    }
    match &spec.retention {
        Some(RetentionCurve::VanGenuchten {
            s_min,
            s_max,
            p0,
            lambda,
        }) => {
            push("WATER_RETENTION_CURVE", "van_genuchten".into());
            push("Smin", s_min.to_string());
            push("Smax", s_max.to_string());
            push("P0", p0.to_string());
            push("lambda", lambda.to_string());
            push("HYDR_CONDUCTIVITY_CURVE", "constant".into());
        }
        Some(RetentionCurve::Linear { av }) => {
            push("WATER_RETENTION_CURVE", "linear".into());
            push("av", av.to_string());
            push("HYDR_CONDUCTIVITY_CURVE", "constant".into());
        }
        None => {}
    }
    Material {
        index,
        name: spec.name.clone(),
        material_type: material_type.into(),
        model: Some(model.into()),
        porosity: Some(spec.porosity),
        density_solid: Some(spec.density_solid),
        density_liquid: spec.density_liquid,
        k0: Some(spec.k0),
        young_modulus: Some(spec.young_modulus),
        poisson_ratio: Some(spec.poisson_ratio),
        friction_angle: spec.mohr_coulomb.map(|m| m.0),
        cohesion: spec.mohr_coulomb.map(|m| m.1),
        dilatancy_angle: spec.mohr_coulomb.map(|m| m.2),
        tensile_strength: spec.mohr_coulomb.map(|_| 0.0),
        retention: spec.retention,
        properties: props,
    }
}

/// A one-material model on `mesh`: every element active with `mps_per_element`
/// MPs, box fixities.
pub fn single_material_model(mesh: Mesh, spec: &MaterialSpec, mps_per_element: u32) -> AnuraModel {
    let n_el = mesh.n_elements();
    let solid_fixity = box_fixities(&mesh);
    let n_nodes = mesh.n_nodes();
    AnuraModel {
        mesh,
        materials: vec![material(1, spec)],
        element_material: vec![1; n_el],
        mp_counts: vec![(mps_per_element, 0); n_el],
        liquid_fixity: vec![[false; 3]; n_nodes],
        solid_fixity,
        damping: None,
    }
}

/// Node layout of an unstructured triangle mesh of the square [0, size]², as a
/// mesher would place them (the paper's §2.1 block): boundary nodes every `l`
/// along the four sides, interior nodes by seeded dart throwing with a minimum
/// distance of 0.75·l (a point is accepted when no node lies closer; the throw
/// stops after 60 consecutive rejections per accepted node on average).
pub fn unstructured_square_nodes(size: f64, l: f64, seed: u64) -> Vec<[f64; 3]> {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let n_side = (size / l).round().max(1.0) as usize;
    let step = size / n_side as f64;
    let mut nodes: Vec<[f64; 3]> = Vec::new();
    for k in 0..n_side {
        let t = k as f64 * step;
        nodes.push([t, 0.0, 0.0]);
        nodes.push([size, t, 0.0]);
        nodes.push([size - t, size, 0.0]);
        nodes.push([0.0, size - t, 0.0]);
    }
    let min_d = 0.75 * l;
    let cell = min_d / std::f64::consts::SQRT_2;
    let n_cells = (size / cell).ceil() as usize + 1;
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); n_cells * n_cells];
    let cell_of = |p: &[f64; 3]| {
        (
            ((p[0] / cell) as usize).min(n_cells - 1),
            ((p[1] / cell) as usize).min(n_cells - 1),
        )
    };
    for (i, p) in nodes.iter().enumerate() {
        let (cx, cy) = cell_of(p);
        grid[cy * n_cells + cx].push(i as u32);
    }
    let target = ((size / l).powi(2) * 1.2) as usize + 10;
    let mut misses = 0;
    while misses < 60 * target.max(1) && nodes.len() < 4 * target {
        let p = [
            rng.random_range(0.0..size),
            rng.random_range(0.0..size),
            0.0,
        ];
        let (cx, cy) = cell_of(&p);
        let mut ok = p[0] > 0.5 * min_d
            && p[0] < size - 0.5 * min_d
            && p[1] > 0.5 * min_d
            && p[1] < size - 0.5 * min_d;
        'scan: for gy in cy.saturating_sub(2)..=(cy + 2).min(n_cells - 1) {
            for gx in cx.saturating_sub(2)..=(cx + 2).min(n_cells - 1) {
                for &j in &grid[gy * n_cells + gx] {
                    let q = nodes[j as usize];
                    if (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) < min_d * min_d {
                        ok = false;
                        break 'scan;
                    }
                }
            }
        }
        if ok {
            grid[cy * n_cells + cx].push(nodes.len() as u32);
            nodes.push(p);
        } else {
            misses += 1;
        }
    }
    nodes
}

/// Nodes of a structured quadrilateral mesh of [0, size]² with spacing l.
pub fn structured_square_nodes(size: f64, l: f64) -> Vec<[f64; 3]> {
    let n = (size / l).round().max(1.0) as usize;
    let step = size / n as f64;
    (0..=n)
        .flat_map(|j| (0..=n).map(move |i| [i as f64 * step, j as f64 * step, 0.0]))
        .collect()
}

/// Top of the shipped slope's compacted clay (`fixtures/slope`, m): the crest
/// at 2.9 m for x ≤ 0.5 m, a 32° face, the toe at 0.
pub fn slope_fixture_clay_top(x: f64) -> f64 {
    let slope = 32f64.to_radians().tan();
    let x_toe = 0.5 + 2.9 / slope;
    if x <= 0.5 {
        2.9
    } else if x >= x_toe {
        0.0
    } else {
        2.9 - slope * (x - 0.5)
    }
}

/// A rising-rain series on the shipped slope's sand nodes (the text of
/// `fixtures/slope/sand-nodes.csv`: id, x, y, pwp, material): `n` node tables
/// over 2 h, each with its time in s. A water table perched on the clay rises
/// to 1.8 times its shape (0.05 + 0.45·t² of the way along the face), at most
/// to the ground (the highest node of each column), and the suction above it
/// is capped at 6 → 1.5 kPa; GeoStudio sign (positive in compression). The
/// pore pressures rise monotonically in time at every node. Errors name the
/// 1-based line.
pub fn rising_table_series(nodes_csv: &str, n: usize) -> Result<Vec<(f64, String)>, String> {
    const GAMMA_W: f64 = 9.81;
    let mut lines = nodes_csv.lines();
    let header = lines.next().unwrap_or_default();
    let mut rows = Vec::new();
    for (k, line) in lines.enumerate() {
        let r: Vec<&str> = line.split(',').collect();
        let num = |i: usize| -> Result<f64, String> {
            r.get(i)
                .and_then(|v| v.trim().parse().ok())
                .ok_or_else(|| format!("line {}: expected x and y", k + 2))
        };
        let rest = r
            .get(4..)
            .ok_or_else(|| format!("line {}: expected 5 columns", k + 2))?;
        rows.push((r[0], num(1)?, num(2)?, rest.join(",")));
    }
    let mut tops: Vec<(f64, f64)> = Vec::new();
    for &(_, x, y, _) in &rows {
        match tops.iter_mut().find(|t| (t.0 - x).abs() < 1e-9) {
            Some(t) => t.1 = t.1.max(y),
            None => tops.push((x, y)),
        }
    }
    let top = |x: f64| {
        tops.iter()
            .find(|t| (t.0 - x).abs() < 1e-9)
            .map_or(x, |t| t.1)
    };
    let steps = n.max(2) - 1;
    Ok((0..n)
        .map(|k| {
            let s = k as f64 / steps as f64;
            let (rise, cap) = (1.8 * s, 6.0 - 4.5 * (1.25 * s).min(1.0));
            let mut out = header.to_string();
            for (id, x, y, rest) in &rows {
                let t = ((x - 0.5) / 5.5).clamp(0.0, 1.0);
                let table =
                    (slope_fixture_clay_top(*x) + rise * (0.05 + 0.45 * t * t)).min(top(*x));
                let pwp = if *y <= table {
                    GAMMA_W * (table - y)
                } else {
                    -(GAMMA_W * (y - table)).min(cap)
                };
                out.push_str(&format!("\n{id},{x},{y},{pwp},{rest}"));
            }
            (2.0 * 3600.0 * s, out)
        })
        .collect())
}
