//! VTK XML unstructured grids of vertices (`.vtu`) for ParaView: the MPs with
//! their mapped fields (`mps.vtu`) and the FEM input nodes (`fem.vtu`).
//! Spec: `formats/vtu.md`. ASCII data arrays, one `VTK_VERTEX` cell per point.

use std::io::Write;

use super::mps_table::fmt_f64;

/// A named point-data array: 1 (scalar), 3 (vector) or 9 (tensor) components.
pub struct PointArray {
    pub name: String,
    pub components: usize,
    pub values: Vec<f64>,
}

/// Writes points with their point-data arrays.
pub fn write_points(
    w: &mut dyn Write,
    points: &[[f64; 3]],
    arrays: &[PointArray],
) -> std::io::Result<()> {
    let n = points.len();
    writeln!(w, r#"<?xml version="1.0"?>"#)?;
    writeln!(
        w,
        r#"<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">"#
    )?;
    writeln!(w, "<UnstructuredGrid>")?;
    writeln!(w, r#"<Piece NumberOfPoints="{n}" NumberOfCells="{n}">"#)?;
    writeln!(w, "<PointData>")?;
    for a in arrays {
        writeln!(
            w,
            r#"<DataArray type="Float64" Name="{}" NumberOfComponents="{}" format="ascii">"#,
            a.name, a.components
        )?;
        for chunk in a.values.chunks(a.components.max(1)) {
            let line: Vec<String> = chunk.iter().map(|v| fmt_f64(*v)).collect();
            writeln!(w, "{}", line.join(" "))?;
        }
        writeln!(w, "</DataArray>")?;
    }
    writeln!(w, "</PointData>")?;
    writeln!(w, "<Points>")?;
    writeln!(
        w,
        r#"<DataArray type="Float64" NumberOfComponents="3" format="ascii">"#
    )?;
    for p in points {
        writeln!(w, "{} {} {}", fmt_f64(p[0]), fmt_f64(p[1]), fmt_f64(p[2]))?;
    }
    writeln!(w, "</DataArray>")?;
    writeln!(w, "</Points>")?;
    writeln!(w, "<Cells>")?;
    writeln!(
        w,
        r#"<DataArray type="Int64" Name="connectivity" format="ascii">"#
    )?;
    for i in 0..n {
        writeln!(w, "{i}")?;
    }
    writeln!(w, "</DataArray>")?;
    writeln!(
        w,
        r#"<DataArray type="Int64" Name="offsets" format="ascii">"#
    )?;
    for i in 1..=n {
        writeln!(w, "{i}")?;
    }
    writeln!(w, "</DataArray>")?;
    writeln!(w, r#"<DataArray type="UInt8" Name="types" format="ascii">"#)?;
    for _ in 0..n {
        writeln!(w, "1")?;
    }
    writeln!(w, "</DataArray>")?;
    writeln!(w, "</Cells>")?;
    writeln!(w, "</Piece>")?;
    writeln!(w, "</UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")?;
    Ok(())
}

/// Expands a 6-component stress (xx, yy, zz, xy, yz, xz) into a row-major 3×3 tensor.
pub fn tensor9(s: &[f64; 6]) -> [f64; 9] {
    [s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2]]
}
