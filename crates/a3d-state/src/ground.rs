//! Is the ground surface flat? The question `--stress auto` asks before it
//! trusts the geostatic column formula, which is in equilibrium on flat ground
//! only.
//!
//! The ground surface is read from the mesh's top boundary: the faces (edges
//! in 2D, triangles in 3D) of active elements that no other active element
//! shares and whose outward normal points upwards (n_y > 0). The ground is flat
//! when every such face is horizontal (its normal within 1e-6 of +y) and all of
//! them lie at one elevation (within 1e-6 of the model's height); a slope, a
//! bench, a cut or a step is not. Vertical sides and bottoms are not ground.
//! Pure geometry on [`a3d_model`] data.

use std::collections::HashMap;

use a3d_model::Mesh;

/// What [`ground_surface`] found.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct GroundSurface {
    pub flat: bool,
    /// Upward-facing boundary faces.
    pub faces: usize,
    /// Of those, faces that are not horizontal.
    pub inclined_faces: usize,
    /// Lowest and highest elevation of the horizontal faces (m).
    pub elevation_range: (f64, f64),
    /// Largest inclination of a face from the horizontal (degrees).
    pub steepest_deg: f64,
}

impl GroundSurface {
    /// One sentence on the finding, for reports.
    pub fn describe(&self) -> String {
        if self.flat {
            format!(
                "the ground surface is flat ({} horizontal faces at y = {:.4} m)",
                self.faces, self.elevation_range.0
            )
        } else if self.inclined_faces > 0 {
            format!(
                "the ground surface is not flat: {} of its {} faces are inclined, up to {:.1}°",
                self.inclined_faces, self.faces, self.steepest_deg
            )
        } else {
            format!(
                "the ground surface is not flat: its horizontal faces lie at y = {:.4} .. {:.4} m",
                self.elevation_range.0, self.elevation_range.1
            )
        }
    }
}

/// The ground surface of `mesh`'s elements for which `active(e)` holds.
pub fn ground_surface(mesh: &Mesh, active: impl Fn(usize) -> bool) -> GroundSurface {
    let dim = mesh.dimension.n_dim();
    // Each face (sorted corner ids) with the element's remaining corner, or
    // None once a second element shares it.
    let mut faces: HashMap<Vec<u32>, Option<(Vec<u32>, u32)>> = HashMap::new();
    let mut low = f64::INFINITY;
    let mut high = f64::NEG_INFINITY;
    for e in 0..mesh.n_elements() {
        if !active(e) {
            continue;
        }
        let corners = mesh.corners(e);
        for &n in corners {
            let y = mesh.nodes[n as usize][1];
            low = low.min(y);
            high = high.max(y);
        }
        // Each face with a corner off it, which says which side is inside.
        for local in mesh.element_type.faces() {
            let face: Vec<u32> = local.iter().map(|&k| corners[k]).collect();
            let inner = (0..corners.len())
                .find(|k| !local.contains(k))
                .map_or(corners[0], |k| corners[k]);
            insert(&mut faces, face, inner);
        }
    }
    let height = (high - low).max(f64::MIN_POSITIVE);
    let mut out = GroundSurface {
        flat: true,
        faces: 0,
        inclined_faces: 0,
        elevation_range: (f64::INFINITY, f64::NEG_INFINITY),
        steepest_deg: 0.0,
    };
    let mut keys: Vec<&Vec<u32>> = faces.keys().collect();
    keys.sort();
    for key in keys {
        let Some((face, inner)) = &faces[key] else {
            continue;
        };
        let p = |n: u32| mesh.nodes[n as usize];
        let normal = outward_normal(
            dim,
            &face.iter().map(|&n| p(n)).collect::<Vec<_>>(),
            p(*inner),
        );
        let length = normal.iter().map(|v| v * v).sum::<f64>().sqrt();
        if length.is_nan() || length <= 0.0 {
            continue;
        }
        let ny = normal[1] / length;
        if ny <= 1e-9 {
            continue;
        }
        out.faces += 1;
        if ny < 1.0 - 1e-12 && (1.0 - ny * ny).sqrt() > 1e-6 {
            out.inclined_faces += 1;
            out.steepest_deg = out
                .steepest_deg
                .max(ny.clamp(-1.0, 1.0).acos().to_degrees());
            continue;
        }
        for &n in face {
            let y = p(n)[1];
            out.elevation_range.0 = out.elevation_range.0.min(y);
            out.elevation_range.1 = out.elevation_range.1.max(y);
        }
    }
    let (lo, hi) = out.elevation_range;
    out.flat = out.faces > 0 && out.inclined_faces == 0 && hi - lo <= 1e-6 * height;
    out
}

fn insert(faces: &mut HashMap<Vec<u32>, Option<(Vec<u32>, u32)>>, face: Vec<u32>, inner: u32) {
    let mut key = face.clone();
    key.sort_unstable();
    faces
        .entry(key)
        .and_modify(|v| *v = None)
        .or_insert(Some((face, inner)));
}

/// A normal of the face with corners `face` pointing away from `inner`.
fn outward_normal(dim: usize, face: &[[f64; 3]], inner: [f64; 3]) -> [f64; 3] {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let mut n = if dim == 2 || face.len() == 2 {
        let t = sub(face[1], face[0]);
        [t[1], -t[0], 0.0]
    } else {
        let (a, b) = (sub(face[1], face[0]), sub(face[2], face[0]));
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let to_inner = sub(inner, face[0]);
    if n[0] * to_inner[0] + n[1] * to_inner[1] + n[2] * to_inner[2] > 0.0 {
        n = [-n[0], -n[1], -n[2]];
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use a3d_testkit::generate;

    #[test]
    fn a_box_is_flat_and_a_slope_is_not() {
        let mesh = generate::structured_tri_mesh(0.0, 0.0, 4.0, 2.0, 8, 4);
        let g = ground_surface(&mesh, |_| true);
        assert!(g.flat, "{g:?}");
        assert_eq!(g.faces, 8);
        let tet = generate::structured_tet_mesh(2.0, 0.0, 1.0, 1.0, 2, 2, 2);
        assert!(ground_surface(&tet, |_| true).flat);

        // Raise the top-right node: two top faces tilt.
        let mut sloped = mesh.clone();
        let top_right = sloped
            .nodes
            .iter()
            .position(|p| p[0] == 4.0 && p[1] == 2.0)
            .unwrap();
        sloped.nodes[top_right][1] = 2.5;
        let g = ground_surface(&sloped, |_| true);
        assert!(!g.flat);
        assert_eq!(g.inclined_faces, 1);
        assert!(g.describe().contains("inclined"));

        // A step: the top row's right half is inactive (two elements per cell).
        let stepped = ground_surface(&mesh, |e| !(e >= 2 * 8 * 3 && (e / 2) % 8 >= 4));
        assert!(!stepped.flat, "{stepped:?}");
        assert!(stepped.describe().contains("horizontal faces lie at"));
    }
}
