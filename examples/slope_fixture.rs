//! Builds `fixtures/slope/`: the paper's rainfall-loaded model slope (Lora et al.
//! 2016, paper §3) as an Anura3D project plus a FEM node file of the sand layer
//! with a **stand-in** pore-pressure field at failure (SEEP/W cannot run here);
//! and `fixtures/flume/`: the paper's MPM model of the same slope (Fig. 8), with
//! empty elements above the ground and in front of the toe wall for the slide
//! to run into, and the monitored MPs A–E (#39).
//! Deterministic; run `cargo run --example slope_fixture`. The geometry, the
//! materials and the stand-in field are documented in `fixtures/slope/README.md`
//! and `fixtures/flume/README.md`.
#![allow(clippy::print_stdout)]

use std::fmt::Write as _;
use std::path::Path;

use a3d_init::formats::gom::write::model_to_text;
use a3d_init::model::{AnuraModel, Dimension, ElementType, Material, Mesh, RetentionCurve};
use a3d_init::place::place_material_points;
use a3d_testkit::generate::slope_fixture_clay_top as clay_top;
use a3d_testkit::generate::{self, MaterialSpec};

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

/// Paper Table 1's silty sand.
fn sand() -> MaterialSpec {
    MaterialSpec {
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
    }
}

/// The stiff dry base of compacted sandy clay.
fn clay() -> MaterialSpec {
    MaterialSpec {
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
    }
}

/// Rows of the flume's mesh: clay, sand (0.1 m) and free space above the
/// ground (`FREE_ROW` m each).
const FLUME_ROWS: (usize, usize, usize) = (4, 6, 4);
/// Height of a row of free space (m): 4 × 0.15 = 0.6 m above the ground,
/// room for the undamped slide's heap (0.4 m above the old surface at 3 s).
const FREE_ROW: f64 = 0.15;
/// The floor in front of the toe wall: its length (m) in 0.1 m columns.
const FLOOR_COLUMNS: usize = 10;
/// Monitored points A–E: x (m) along the slope, 0.05 m below the ground.
const MONITORED_X: [f64; 5] = [1.0, 2.0, 3.0, 4.0, 5.0];

/// The paper's MPM model (Fig. 8): the slope of [`mesh`] with 0.1 m columns,
/// a coarser clay, `FLUME_ROWS.2` rows of empty elements above the ground,
/// and past the toe wall (x = 6 m, from the base up to the sand's surface at
/// y = 0.6 m) an empty box over a floor at y = 0 (the clay's top at the toe),
/// `FLOOR_COLUMNS` × 0.1 m long, as high as the free space at the wall. The
/// wall is a slit: below its top the box has nodes of its own. Returns the
/// mesh, the element materials (0 = empty) and the solid fixities.
fn flume_mesh() -> (Mesh, Vec<u32>, Vec<[bool; 3]>) {
    let (ny_clay, ny_sand, ny_free) = FLUME_ROWS;
    let (nx, ny) = (60, ny_clay + ny_sand + ny_free);
    let dy = SAND / ny_sand as f64;
    let mut nodes = Vec::new();
    let mut fixity = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let x = 6.0 * i as f64 / nx as f64;
            let top = clay_top(x);
            let y = if j <= ny_clay {
                BASE + (top - BASE) * j as f64 / ny_clay as f64
            } else if j <= ny_clay + ny_sand {
                top + dy * (j - ny_clay) as f64
            } else {
                top + SAND + FREE_ROW * (j - ny_clay - ny_sand) as f64
            };
            nodes.push([x, y, 0.0]);
            let wall = i == nx && j <= ny_clay + ny_sand;
            fixity.push([j == 0 || i == 0 || wall, j == 0, false]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut connectivity = Vec::new();
    let mut material = Vec::new();
    let mut quad = |a: u32, b: u32, c: u32, d: u32, m: u32| {
        // Diagonal chosen so the triangles stay well shaped on the slope.
        connectivity.extend_from_slice(&[a, b, c, a, c, d]);
        material.extend([m, m]);
    };
    for j in 0..ny {
        for i in 0..nx {
            let m = if j < ny_clay {
                2
            } else if j < ny_clay + ny_sand {
                1
            } else {
                0
            };
            quad(id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1), m);
        }
    }
    // The box in front of the wall: rows k = 0..=ny_sand + ny_free from the
    // floor (y = 0); column 0 is the wall's other face (own nodes below its
    // top, the slope's nodes from its top up).
    let rows = ny_sand + ny_free;
    let mut floor = vec![vec![0u32; rows + 1]; FLOOR_COLUMNS + 1];
    for (c, column) in floor.iter_mut().enumerate() {
        for (k, node) in column.iter_mut().enumerate() {
            if c == 0 && k >= ny_sand {
                *node = id(nx, ny_clay + k);
                continue;
            }
            *node = nodes.len() as u32;
            let y = if k <= ny_sand {
                dy * k as f64
            } else {
                SAND + FREE_ROW * (k - ny_sand) as f64
            };
            nodes.push([6.0 + 0.1 * c as f64, y, 0.0]);
            fixity.push([c == 0 || c == FLOOR_COLUMNS || k == 0, k == 0, false]);
        }
    }
    for c in 0..FLOOR_COLUMNS {
        for k in 0..rows {
            let (a, b) = (floor[c][k], floor[c + 1][k]);
            let (cc, d) = (floor[c + 1][k + 1], floor[c][k + 1]);
            quad(a, b, cc, d, 0);
        }
    }
    let mesh = Mesh {
        dimension: Dimension::PlaneStrain,
        element_type: ElementType::Tri3,
        nodes,
        connectivity,
    };
    (mesh, material, fixity)
}

/// `$$HYDR_CONDUCTIVITY_CURVE mualem` in place of `constant`, with the
/// retention curve's Smin, Smax, P0 and λ (Mualem–van Genuchten, as the FEM).
fn with_mualem(mut material: Material) -> Material {
    let props = &mut material.properties;
    let at = props
        .iter()
        .position(|(k, _)| k == "$$HYDR_CONDUCTIVITY_CURVE")
        .expect("an unsaturated material has a conductivity curve");
    let retention: Vec<(String, String)> = ["$$Smin", "$$Smax", "$$P0", "$$lambda"]
        .iter()
        .map(|k| {
            props
                .iter()
                .find(|(key, _)| key == k)
                .cloned()
                .expect("the van Genuchten parameters")
        })
        .collect();
    props[at].1 = "mualem".into();
    for (n, p) in retention.into_iter().enumerate() {
        props.insert(at + 1 + n, p);
    }
    material
}

/// Writes `fixtures/flume/`: the GOM, the run-out CPS (3 s in 30 load steps
/// of 0.1 s, dynamic, the monitored MPs A–E) and prints the monitored MPs.
fn flume() -> Result<(), Box<dyn std::error::Error>> {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/flume");
    std::fs::create_dir_all(&out)?;
    let (mesh, element_material, solid_fixity) = flume_mesh();
    let mp_counts = element_material
        .iter()
        .map(|&m| if m == 0 { (0, 0) } else { (3, 0) })
        .collect();
    let model = AnuraModel {
        mesh,
        materials: vec![
            with_mualem(generate::material(1, &sand())),
            generate::material(2, &clay()),
        ],
        element_material,
        mp_counts,
        liquid_fixity: vec![[false; 3]; solid_fixity.len()],
        solid_fixity,
        damping: None,
    };
    let points = place_material_points(&model).map_err(|e| format!("{e:?}"))?;
    let mut monitored = Vec::new();
    for x in MONITORED_X {
        let target = [x, clay_top(x) + SAND - 0.05];
        let p = points
            .iter()
            .filter(|p| p.material == 1)
            .min_by(|a, b| {
                let d = |p: &a3d_init::model::MaterialPoint| {
                    (p.position[0] - target[0]).hypot(p.position[1] - target[1])
                };
                d(a).total_cmp(&d(b))
            })
            .expect("sand MPs");
        monitored.push(p.id);
        println!(
            "monitored MP {} at ({:.4}, {:.4}), element {}",
            p.id,
            p.position[0],
            p.position[1],
            p.element + 1
        );
    }
    // The seepage face: the toe wall (x = 6 m) from the clay up to the
    // sand's surface, the bottom and the left side impermeable (no block).
    let gom = model_to_text(&model, "2023").replace(
        "$$FINISH",
        "$$BOUNDARY_SEEPAGE_AREA\n5.95 6.05\n-0.01 0.61\n$$FINISH",
    );
    std::fs::write(out.join("flume.GOM"), gom)?;
    let mut cps = String::from(
        "### Anura3D_2023 ###\n$$NUMBER_OF_LOADSTEPS\n30\n$$TIME_PER_LOADSTEP\n0.1\n\
         $$COMPUTATION_METHOD\nMPM-MIXED\n$$GRAVITY_ACCELERATION\n9.81\n$$GRAVITY_VECTOR\n0.0 -1.0\n\
         $$GRAVITY_LOAD\nstep 1.0 1.0\n$$QUASISTATIC_CONVERGENCE\n0\n$$HOMOGENEOUS_LOCAL_DAMPING\n1 0.05\n\
         $$K0_PROCEDURE\n1\n$$APPLY_SEEPAGE_FACE\n1\n",
    );
    writeln!(
        cps,
        "$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\n{}\n$$OUTPUT_MATERIAL_POINTS",
        monitored.len()
    )?;
    for id in &monitored {
        writeln!(cps, "{id}")?;
    }
    cps.push_str("$$VISUALIZATION_OPTION\nParaview\n$$END\n");
    std::fs::write(out.join("flume.CPS_001"), cps)?;
    let active = model.element_material.iter().filter(|&&m| m != 0).count();
    println!(
        "flume.GOM: {} nodes, {} elements ({} with MPs, {} empty), {} MPs",
        model.mesh.n_nodes(),
        model.mesh.n_elements(),
        active,
        model.mesh.n_elements() - active,
        points.len()
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/slope");
    std::fs::create_dir_all(&out)?;
    let (mesh, element_material) = mesh(60, 8, 6);
    let (sand, clay) = (sand(), clay());
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
    flume()?;
    println!(
        "slope.GOM: {} nodes, {} elements; sand-nodes.csv: {k} nodes",
        model.mesh.n_nodes(),
        n_el
    );
    Ok(())
}
