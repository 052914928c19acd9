//! The per-MP CSV table (`mps.csv`, `inspect --mps`). Spec: `formats/mps-csv.md`.
//!
//! Columns: `id,element,material,local,x,y,z,volume`, then, for a mapped state,
//! the pore pressure, total and effective stresses (Anura3D signs, kPa), the
//! degree of saturation and the mapping diagnostics. Ids are 1-based.

use std::io::Write;

use crate::model::MaterialPoint;

/// Formats a float so that it reads back to the same value (shortest round trip).
pub fn fmt_f64(v: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    format!("{v}")
}

/// Writes the placement table: one row per MP.
pub fn write_points(
    w: &mut dyn Write,
    points: &[MaterialPoint],
    n_dim: usize,
) -> std::io::Result<()> {
    let _ = n_dim;
    writeln!(w, "id,element,material,local,x,y,z,volume")?;
    for p in points {
        writeln!(
            w,
            "{},{},{},{},{},{},{},{}",
            p.id,
            p.element + 1,
            p.material,
            p.local,
            fmt_f64(p.position[0]),
            fmt_f64(p.position[1]),
            fmt_f64(p.position[2]),
            fmt_f64(p.volume)
        )?;
    }
    Ok(())
}
