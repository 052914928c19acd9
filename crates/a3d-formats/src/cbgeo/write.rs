//! What `map` writes for CB-Geo: the particle stresses file, the pore
//! pressure file, and the run file pointing at them in the branch's form.

use std::io::Write;

use super::json;
use super::{Branch, CbGeoModel};
use crate::error::ParseError;
use crate::table_text::push_f64;

/// `n` then, per particle, σxx σyy σzz τxy τyz τxz (Pa, tension positive)
/// separated by tabs, in particle order: the file CB-Geo's
/// `read_particles_stresses` reads.
pub fn stresses(
    w: &mut dyn Write,
    n: usize,
    stress: &dyn Fn(usize) -> [f64; 6],
) -> std::io::Result<()> {
    let mut line = Vec::with_capacity(160);
    writeln!(w, "{n}")?;
    for i in 0..n {
        line.clear();
        for (k, v) in stress(i).iter().enumerate() {
            if k > 0 {
                line.push(b'\t');
            }
            push_f64(&mut line, *v);
        }
        line.push(b'\n');
        w.write_all(&line)?;
    }
    Ok(())
}

/// `id value` for each particle of `ids` (ids from 0 in particle order; a
/// pore pressure in Pa, compression positive): the fork's
/// `read_particles_scalar_properties`.
pub fn id_values_of(
    w: &mut dyn Write,
    ids: &[usize],
    value: &dyn Fn(usize) -> f64,
) -> std::io::Result<()> {
    let mut line = Vec::with_capacity(40);
    for &i in ids {
        line.clear();
        line.extend_from_slice(itoa::Buffer::new().format(i).as_bytes());
        line.push(b'\t');
        push_f64(&mut line, value(i));
        line.push(b'\n');
        w.write_all(&line)?;
    }
    Ok(())
}

/// The value of a file key in `branch`'s form.
pub fn file_key(branch: Branch, name: &str) -> String {
    match branch {
        Branch::Develop => json::quote(name),
        Branch::Fork => format!(
            "{{\"type\": \"file\", \"location\": {}}}",
            json::quote(name)
        ),
    }
}

/// The run file with `mesh.particles_stresses` set to `stresses` and, when
/// given, `mesh.particles_pore_pressures` to `pore_pressures` (the fork's
/// object form: only the fork reads it); every other byte as it was.
pub fn run_file(
    model: &CbGeoModel,
    stresses: &str,
    pore_pressures: Option<&str>,
) -> Result<String, ParseError> {
    let mut text = set_mesh(
        model,
        &model.json_text,
        "particles_stresses",
        &file_key(model.branch, stresses),
    )?;
    if let Some(pp) = pore_pressures {
        text = set_mesh(
            model,
            &text,
            "particles_pore_pressures",
            &file_key(Branch::Fork, pp),
        )?;
    }
    Ok(text)
}

fn set_mesh(model: &CbGeoModel, text: &str, key: &str, value: &str) -> Result<String, ParseError> {
    let root = json::parse(&model.json_path, text)?;
    let r = json::Reader {
        path: &model.json_path,
        text,
    };
    let mesh = r.object(&root, "mesh", "the run file")?;
    Ok(json::set_member(text, mesh, key, value))
}
