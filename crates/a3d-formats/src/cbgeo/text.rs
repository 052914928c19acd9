//! CB-Geo's ASCII files, read by its own line rules (`io_mesh_ascii.tcc`):
//! each line trimmed; a blank line, or one holding `#` or `!` anywhere, is
//! skipped; tokens are separated by blanks. Where CB-Geo reads on silently
//! (a count that does not match the lines, a short line, a bad number) these
//! readers stop with the place: CB-Geo would run a model other than the one
//! written.

use std::path::Path;

use crate::error::ParseError;

/// The lines CB-Geo reads, with their 1-based line numbers.
fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines().enumerate().filter_map(|(i, l)| {
        let t = l.trim();
        (!t.is_empty() && !t.contains('#') && !t.contains('!')).then_some((i + 1, l))
    })
}

/// Tokens of a line with their 1-based columns.
fn tokens(line: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut rest = line;
    let mut offset = 0;
    std::iter::from_fn(move || {
        let skip = rest.len() - rest.trim_start().len();
        rest = &rest[skip..];
        offset += skip;
        if rest.is_empty() {
            return None;
        }
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        let tok = &rest[..end];
        let col = line[..offset].chars().count() + 1;
        rest = &rest[end..];
        offset += end;
        Some((col, tok))
    })
}

/// A finite real as C++'s `>>` reads it (no `inf`/`nan`, no Fortran `D`).
fn real(tok: &str) -> Option<f64> {
    let ok = tok
        .bytes()
        .all(|b| b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.' | b'e' | b'E'));
    tok.parse::<f64>().ok().filter(|v| ok && v.is_finite())
}

/// The first `n` tokens of `line` as reals (more are ignored, as CB-Geo does).
fn reals<const N: usize>(
    path: &Path,
    (ln, line): (usize, &str),
    n: usize,
    what: &str,
) -> Result<[f64; N], ParseError> {
    let mut out = [0.0; N];
    let mut got = 0;
    for (col, tok) in tokens(line).take(n) {
        out[got] = real(tok).ok_or_else(|| {
            ParseError::at(
                path,
                ln,
                col,
                format!("{what}: `{tok}` is not a finite number"),
            )
        })?;
        got += 1;
    }
    if got < n {
        let col = line.trim_end().chars().count() + 1;
        return Err(ParseError::at(
            path,
            ln,
            col,
            format!("{what}: {n} numbers expected, {got} found"),
        ));
    }
    Ok(out)
}

/// A count line: one integer ≥ 0 (`what` names it).
fn count(path: &Path, (ln, line): (usize, &str), what: &str) -> Result<usize, ParseError> {
    let (col, tok) = tokens(line).next().unwrap_or((1, ""));
    tok.parse::<usize>()
        .map_err(|_| ParseError::at(path, ln, col, format!("{what}: `{tok}` is not a count")))
}

/// A CB-Geo mesh: node coordinates (z = 0 in 2D) and each cell's node
/// indices, in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshText {
    pub nodes: Vec<[f64; 3]>,
    pub cells: Vec<Vec<u32>>,
    /// The line of each cell, for errors about it.
    pub cell_lines: Vec<usize>,
}

/// Reads `mesh.txt` (`nnodes ncells`, the node lines, then one cell per
/// line) for `dim` coordinates and `per_cell` nodes per cell.
pub fn read_mesh(
    path: &Path,
    text: &str,
    dim: usize,
    per_cell: usize,
) -> Result<MeshText, ParseError> {
    let mut lines = data_lines(text);
    let head = lines.next().ok_or_else(|| {
        ParseError::at(
            path,
            1,
            1,
            "empty mesh: the first line gives the node and cell counts",
        )
    })?;
    let mut t = tokens(head.1);
    let mut two = [0usize; 2];
    for (k, what) in ["node count", "cell count"].iter().enumerate() {
        let (col, tok) = t.next().unwrap_or((head.1.chars().count() + 1, ""));
        two[k] = tok.parse::<usize>().map_err(|_| {
            ParseError::at(
                path,
                head.0,
                col,
                format!("the {what}: `{tok}` is not a count"),
            )
        })?;
    }
    let [n_nodes, n_cells] = two;
    let mut nodes = Vec::new();
    for _ in 0..n_nodes {
        let Some(line) = lines.next() else {
            return Err(ParseError::at(
                path,
                head.0,
                1,
                format!(
                    "the mesh declares {n_nodes} nodes but has {} node lines",
                    nodes.len()
                ),
            ));
        };
        let c: [f64; 3] = reals(path, line, dim, &format!("node {}", nodes.len()))?;
        nodes.push(c);
    }
    let mut cells = Vec::new();
    let mut cell_lines = Vec::new();
    for (ln, line) in lines {
        let mut ids = Vec::with_capacity(per_cell);
        for (col, tok) in tokens(line) {
            let id = tok
                .parse::<u32>()
                .ok()
                .filter(|&i| (i as usize) < n_nodes)
                .ok_or_else(|| {
                    ParseError::at(
                        path,
                        ln,
                        col,
                        format!(
                            "cell {}: `{tok}` is not a node index (0 to {})",
                            cells.len(),
                            n_nodes.saturating_sub(1)
                        ),
                    )
                })?;
            ids.push(id);
        }
        if ids.len() != per_cell {
            return Err(ParseError::at(
                path,
                ln,
                1,
                format!(
                    "cell {}: {} node indices, the cell type has {per_cell}",
                    cells.len(),
                    ids.len()
                ),
            ));
        }
        cells.push(ids);
        cell_lines.push(ln);
    }
    if cells.len() != n_cells {
        return Err(ParseError::at(
            path,
            head.0,
            1,
            format!(
                "the mesh declares {n_cells} cells but has {} cell lines",
                cells.len()
            ),
        ));
    }
    Ok(MeshText {
        nodes,
        cells,
        cell_lines,
    })
}

/// Reads a particles file: a count line, then `dim` coordinates per line.
pub fn read_particles(path: &Path, text: &str, dim: usize) -> Result<Vec<[f64; 3]>, ParseError> {
    read_particles_with_lines(path, text, dim).map(|(c, _)| c)
}

/// [`read_particles`], with each particle's 1-based line in the file.
pub fn read_particles_with_lines(
    path: &Path,
    text: &str,
    dim: usize,
) -> Result<(Vec<[f64; 3]>, Vec<usize>), ParseError> {
    counted_rows(path, text, dim, ("particles", "particle lines"))
}

/// Reads a particle stresses file: a count line, then σxx σyy σzz τxy τyz τxz
/// per particle (Pa, tension positive), in particle order.
pub fn read_stresses(path: &Path, text: &str) -> Result<Vec<[f64; 6]>, ParseError> {
    let what = (
        "stresses",
        "stress lines (CB-Geo then sets no stress at all)",
    );
    counted_rows(path, text, 6, what).map(|(rows, _)| rows)
}

/// A count line, then `n` numbers per line (more ignored), the count checked
/// against the lines; each row with its 1-based line. `what` names the file
/// and its lines for the messages.
fn counted_rows<const N: usize>(
    path: &Path,
    text: &str,
    n: usize,
    (file, rows): (&str, &str),
) -> Result<(Vec<[f64; N]>, Vec<usize>), ParseError> {
    let mut lines = data_lines(text);
    let head = lines.next().ok_or_else(|| {
        let message = format!("empty {file} file: the first line gives the count");
        ParseError::at(path, 1, 1, message)
    })?;
    let declared = count(path, head, "the particle count")?;
    let (mut out, mut at) = (Vec::new(), Vec::new());
    for line in lines {
        out.push(reals(path, line, n, &format!("particle {}", out.len()))?);
        at.push(line.0);
    }
    if out.len() != declared {
        let message = format!(
            "the file declares {declared} particles but has {} {rows}",
            out.len()
        );
        return Err(ParseError::at(path, head.0, 1, message));
    }
    Ok((out, at))
}

/// Reads an `id value` file (pore pressures, volumes): one particle per line,
/// any order; a repeated id is refused.
pub fn read_id_values(path: &Path, text: &str) -> Result<Vec<(u64, f64)>, ParseError> {
    let mut out: Vec<(u64, f64)> = Vec::new();
    let mut seen = std::collections::HashMap::new();
    for (ln, line) in data_lines(text) {
        let mut t = tokens(line);
        let (col, tok) = t.next().unwrap_or((1, ""));
        let id = tok
            .parse::<u64>()
            .map_err(|_| ParseError::at(path, ln, col, format!("`{tok}` is not a particle id")))?;
        if let Some(first) = seen.insert(id, ln) {
            return Err(ParseError::at(
                path,
                ln,
                col,
                format!("particle {id} again (first on line {first})"),
            ));
        }
        let (col, tok) = t
            .next()
            .unwrap_or((line.trim_end().chars().count() + 1, ""));
        let v = real(tok).ok_or_else(|| {
            ParseError::at(
                path,
                ln,
                col,
                format!("particle {id}: `{tok}` is not a finite number"),
            )
        })?;
        out.push((id, v));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mesh_lines_follow_cbgeos_rules_and_errors_have_places() {
        let p = Path::new("mesh.txt");
        let text = "! comment\n4 1\n0 0\n1 0 # skipped as a whole\n1 0\n1 1\n\n0 1\n0 1 2 3\n";
        let m = read_mesh(p, text, 2, 4).unwrap();
        assert_eq!(
            m.nodes,
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0]
            ]
        );
        assert_eq!(m.cells, vec![vec![0, 1, 2, 3]]);
        let e = read_mesh(p, "4 1\n0 0\n1 0\n1 1\n0 1\n0 1 2 9\n", 2, 4).unwrap_err();
        assert_eq!((e.position.line, e.position.column), (6, 7), "{e}");
        let e = read_mesh(p, "4 1\n0 0\n1 x\n", 2, 4).unwrap_err();
        assert_eq!((e.position.line, e.position.column), (3, 3), "{e}");
        let e = read_mesh(p, "4 2\n0 0\n1 0\n1 1\n0 1\n0 1 2 3\n", 2, 4).unwrap_err();
        assert!(e.message.contains("declares 2 cells"), "{e}");
        assert!(read_mesh(p, "4 1\n0 0\n1 0\n1 1\n0 inf\n0 1 2 3\n", 2, 4).is_err());
    }

    #[test]
    fn particles_stresses_and_id_values_round_the_real_samples() {
        let p = Path::new("p.txt");
        assert_eq!(
            read_particles(p, "2\n0.5\t0.5\n1.5\t0.5\n", 2)
                .unwrap()
                .len(),
            2
        );
        assert!(
            read_particles(p, "3\n0.5\t0.5\n", 2)
                .unwrap_err()
                .message
                .contains("declares 3")
        );
        let s = read_stresses(p, "1\n-0\t-14614.7\t-0\t0\t0\t0\t\n").unwrap();
        assert_eq!(s[0][1], -14614.7);
        let v = read_id_values(p, "1\t10000\n0\t5\n").unwrap();
        assert_eq!(v, vec![(1, 10000.0), (0, 5.0)]);
        assert!(
            read_id_values(p, "1 2\n1 3\n")
                .unwrap_err()
                .message
                .contains("again")
        );
    }
}
