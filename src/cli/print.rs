//! The text several commands print for the same library results: the
//! `wrote DIR/ (…)` line, `verify`'s outcome, the runner's figures and the
//! factor of safety. Commands share these through this module, never through
//! each other.

use std::path::Path;

use a3d_init::mpm;
use a3d_init::mpm::fos::FosReport;
use a3d_init::pipeline::check::VerifyOutcome;
use a3d_init::pipeline::stability::fos::FosAnalysis;

/// The `wrote      DIR/ (a, b, c)` line a command prints once its folder is written.
pub fn wrote(target: &Path, files: &[&str]) -> String {
    format!("wrote      {}/ ({})", target.display(), files.join(", "))
}

/// Prints the Anura3D-side checks, the run and the verdict with its causes.
pub fn verify_outcome(o: &VerifyOutcome, target: &Path) {
    if let Some(k) = &o.anura3d {
        say!(
            "Anura3D    {} ({}), MAPF {} rows, h = {:.3e} m{}",
            k.gom.display(),
            k.computation_method,
            k.mapf_rows,
            k.smoothing_length,
            if k.mapf_read {
                ""
            } else {
                " (not read: switch off)"
            }
        );
        if let Some(t) = &k.mps_csv {
            for line in table_comparison(t) {
                say!("           {line}");
            }
        }
        if let Some(m) = &k.mixed
            && m.elements > 0
            && (m.pwp > 0.0 || m.stress > 0.0)
        {
            say!(
                "           MPM-MIXED: the first step gives every MP of {} elements its element's first-MP state (spread up to {:.3} kPa pwp, {:.3} kPa stress)",
                m.elements,
                m.pwp,
                m.stress
            );
        }
        for n in &k.notes {
            say!("           {n}");
        }
    }
    if let Some(r) = &o.run {
        run_report(r);
    }
    if o.equilibrium {
        say!("verdict    IN EQUILIBRIUM");
    } else {
        say!("verdict    NOT IN EQUILIBRIUM");
        for c in &o.causes {
            say!("           - {c}");
        }
        if let Some(r) = &o.run
            && !r.verdict.is_equilibrium()
        {
            for e in r.worst_residual_elements.iter().take(5) {
                say!(
                    "           largest residual: element {} at ({:.3}, {:.3}): {:.3e}",
                    e.id,
                    e.centroid[0],
                    e.centroid[1],
                    e.value
                );
            }
            for e in r.plastic_elements.iter().take(5) {
                say!(
                    "           plastic flow: element {} at ({:.3}, {:.3}): {} MPs",
                    e.id,
                    e.centroid[0],
                    e.centroid[1],
                    e.value
                );
            }
        }
    }
    say!(
        "{}",
        wrote(target, &a3d_init::pipeline::check::file_names(o))
    );
}

/// The lines that say how mps.csv compares with the MAPF: counts of MPs
/// compared (never more than the model's), rows that match no MP, MPs
/// without a row, and the worst MPs where there are any.
pub fn table_comparison(t: &a3d_init::pipeline::check::folder::TableComparison) -> Vec<String> {
    let mut lines = Vec::new();
    if t.differing == 0 {
        lines.push(format!(
            "mps.csv agrees with what Anura3D reads from the MAPF ({} MPs compared)",
            t.compared
        ));
    } else {
        let worst: Vec<String> = t
            .worst
            .iter()
            .take(5)
            .map(|(id, d)| format!("MP {id} by {:.2}% of range", d * 100.0))
            .collect();
        lines.push(format!(
            "mps.csv and the MAPF disagree on {} of {} MPs compared{}",
            t.differing,
            t.compared,
            if worst.is_empty() {
                String::new()
            } else {
                format!(" (worst: {})", worst.join(", "))
            }
        ));
    }
    if t.unmatched_rows > 0 {
        lines.push(format!(
            "{} of the {} rows of mps.csv match no MP of the model (unknown id, another element or position, or a repeated row)",
            t.unmatched_rows, t.rows
        ));
    }
    if t.missing > 0 {
        lines.push(format!(
            "{} MPs of the model have no row in mps.csv",
            t.missing
        ));
    }
    lines
}

/// Names the formulation each material ran with (by its GOM index and name),
/// when any material has water that is not held.
pub fn formulations(list: &[(u32, mpm::Formulation)], names: &[String]) {
    use mpm::Formulation::{Coupled, Drained, Dry, UndrainedEffective};
    if list.iter().all(|(_, f)| matches!(f, Drained | Dry)) {
        return;
    }
    let words: Vec<String> = list
        .iter()
        .map(|(m, f)| {
            let how = match f {
                Dry => "dry",
                Drained => "drained (pwp held)",
                UndrainedEffective => "undrained effective (Δp = K_w/n·Δε_v)",
                Coupled => "two-phase coupled (the water flows)",
            };
            match (*m as usize).checked_sub(1).and_then(|i| names.get(i)) {
                Some(name) => format!("material {m} `{name}`: {how}"),
                None => format!("material {m}: {how}"),
            }
        })
        .collect();
    say!("water      {}", words.join("; "));
}

/// A bounding box as `x ∈ [a, b], y ∈ [c, d]` (unbounded axes left out).
fn area_words(area: &[[f64; 2]; 3]) -> String {
    let words: Vec<String> = ["x", "y", "z"]
        .iter()
        .zip(area)
        .filter(|(_, b)| b[0].is_finite() || b[1].is_finite())
        .map(|(axis, b)| format!("{axis} ∈ [{}, {}]", b[0], b[1]))
        .collect();
    words.join(", ")
}

/// The water of a run: each material's formulation, the seepage face and
/// infiltration applied, and what the run did not apply.
pub fn water(r: &mpm::RunReport) {
    formulations(&r.formulations, &r.material_names);
    if let Some(area) = &r.hydraulic.seepage_area {
        say!(
            "water      seepage face on the free surface in {}",
            area_words(area)
        );
    }
    if let Some((area, rate)) = &r.hydraulic.infiltration {
        say!(
            "water      infiltration at most ({:e}, {:e}, {:e}) m/s on the free surface in {}",
            rate[0],
            rate[1],
            rate[2],
            area_words(area)
        );
    }
    for note in &r.notes {
        say!("note       {note}");
    }
}

/// Prints the runner's figures (no verdict).
pub fn run_report(r: &mpm::RunReport) {
    say!(
        "MPM check  {} MPs on {} elements, dt = {:.3e} s, {} steps, t = {:.4} s ({:?})",
        r.n_points,
        r.n_elements,
        r.time_step,
        r.steps,
        r.time,
        r.stop
    );
    say!(
        "           g = {} m/s², local damping α = {}, Courant {}",
        r.gravity,
        r.damping,
        r.courant
    );
    water(r);
    say!(
        "residual   start {:.3e}, end {:.3e} (limit {:.0e})",
        r.initial_residual_ratio,
        r.final_residual_ratio,
        r.thresholds.residual_ratio
    );
    say!(
        "movement   max displacement {:.3e} m (limit {:.0e} × height {:.3} m)",
        r.max_displacement,
        r.thresholds.displacement_fraction,
        r.model_height
    );
    say!(
        "plastic    {} MPs start outside the yield surface, {} yielded during the run",
        r.inadmissible_points,
        r.plastic_points
    );
}

/// Prints a factor-of-safety analysis: the factor of the method asked, then
/// what limit equilibrium and strength reduction found, and their comparison.
pub fn fos_report(analysis: &FosAnalysis, target: &Path, elapsed: f64) {
    use a3d_init::pipeline::stability::fos::{factor_line, file_names};
    say!("factor     {}", factor_line(analysis));
    if let Some(le) = &analysis.limit_equilibrium {
        le_report(le);
    }
    if let Some(why) = &analysis.limit_equilibrium_skipped {
        say!("limit equilibrium not run: {why}");
    }
    if let Some(report) = &analysis.strength_reduction {
        srm_report(report);
    }
    if let Some(c) = &analysis.comparison {
        say!(
            "compare    strength reduction {:.3} / {} {:.3} = {:.3}; limit equilibrium on Davis-reduced strengths (non-associated flow, ψ < φ′) reaches 1 at F = {}",
            c.strength_reduction,
            c.limit_equilibrium_method,
            c.limit_equilibrium,
            c.ratio,
            c.limit_equilibrium_davis
                .map_or("(not computed)".to_string(), |f| format!("{f:.3}"))
        );
        match (&c.equilibrium_solve, &c.equilibrium_solve_skipped) {
            (Some(e), _) => say!(
                "equilibrium the implicit solve finds rest up to F = {} and none from F = {} ({} solves, {:.1} s)",
                e.holds
                    .map_or("(none, even the smallest)".to_string(), |f| format!(
                        "{f:.3}"
                    )),
                e.fails
                    .map_or("(none, even the largest)".to_string(), |f| format!(
                        "{f:.3}"
                    )),
                e.solves,
                e.seconds
            ),
            (None, Some(why)) => say!("equilibrium the implicit solve not run: {why}"),
            (None, None) => {}
        }
    }
    say!("{} in {elapsed:.1} s", wrote(target, &file_names(analysis)));
}

/// A limit-equilibrium analysis: method, search, suction, materials.
pub fn le_report(le: &a3d_init::pipeline::stability::slope::LeReport) {
    let a = &le.analysis;
    let counts = &a.search.counts;
    say!(
        "method     {} ({}), tolerance {:e} on F; {} slices, surfaces at least {:.3} m deep",
        le.method,
        le.interslice
            .map_or("no interslice function".to_string(), |f| format!(
                "interslice {f:?}"
            )),
        le.tolerance,
        a.n_slices,
        a.min_depth
    );
    say!(
        "search     {}: {} trial circles, {} solved, {} did not converge, {} rejected ({})",
        a.search.space,
        counts.generated,
        counts.solved,
        counts.not_converged,
        counts.rejected.iter().map(|r| r.1).sum::<usize>(),
        counts
            .rejected
            .iter()
            .map(|(why, n)| format!("{n} {why}"))
            .collect::<Vec<_>>()
            .join("; ")
    );
    if let Some(c) = &a.circular.circle {
        say!(
            "circle     FS = {:.4} at centre ({:.3}, {:.3}), R = {:.3}",
            a.circular.factor,
            c.xc,
            c.yc,
            c.r
        );
    }
    if let Some(r) = &a.search.polyline_refinement {
        say!(
            "refined    FS = {:.4} after {} surfaces moving {} polyline vertices",
            r.end_factor,
            r.evaluations,
            a.search.polyline_segments.map_or(0, |m| m + 1)
        );
    }
    say!("suction    {}", le.suction_rule);
    say!(
        "pwp        {} ({} points), {} kernel, h = {:.4} m, raster {:.4} m",
        le.pore_field.source,
        le.pore_field.points,
        le.pore_field.kernel,
        le.pore_field.h,
        le.pore_field.raster_spacing
    );
    let unbreakable: Vec<String> = le
        .materials
        .iter()
        .filter(|m| m.strength.is_none())
        .map(|m| format!("{} {} ({})", m.index, m.name, m.model))
        .collect();
    if !unbreakable.is_empty() {
        say!(
            "unbreakable {} (no Mohr–Coulomb strength: no surface crosses them)",
            unbreakable.join(", ")
        );
    }
    say!("runtime    {:.2} s", le.runtime_s);
    for w in &le.warnings {
        say_err!("  warning: {}", super::spelled(w));
    }
}

/// A strength-reduction analysis: the method, the materials, every trial and
/// the mechanism.
pub fn srm_report(report: &FosReport) {
    say!(
        "strength reduction: {}",
        a3d_init::pipeline::stability::fos::srm_factor_line(report)
    );
    say!(
        "method     strength reduction: tan φ′/F, c′/F, ψ ≤ φ′_F; {}; {} MPs, window {:.2} s per trial, dt = {:.3e} s, damping α = {}",
        if report.settings.run.frozen_pore_pressure {
            "pwp held"
        } else {
            "coupled materials run with their water"
        },
        report.n_points,
        report.window,
        report.time_step,
        report.settings.run.damping
    );
    let names = |v: &[a3d_init::mpm::fos::MaterialNote]| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.iter()
                .map(|m| format!("{} {} ({})", m.index, m.name, m.model))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    say!("reduced    {}", names(&report.reduced_materials));
    say!("unreduced  {}", names(&report.unreduced_materials));
    for t in &report.trials {
        say!(
            "  F = {:.4}  {:<17} max |u| = {:.3e} m after {:.2} s ({} steps), {} MPs yielded",
            t.factor,
            format!("{:?}", t.end),
            t.max_displacement,
            t.time,
            t.steps,
            t.plastic_points
        );
    }
    if let Some(m) = &report.mechanism {
        say!(
            "mechanism  F = {:.4}: {} MPs in motion (fos_mechanism.svg, fos_mechanism.vtu)",
            m.factor,
            m.points_in_motion
        );
    }
}
