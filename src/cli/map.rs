//! `a3d-init map`: turns the arguments into a [`MapConfig`], runs the library
//! pipeline (load the project and the FEM nodes, [`pipeline::map::map`],
//! [`pipeline::write::write_project`] into an atomic output folder) and prints
//! a summary. The work itself lives in [`crate::pipeline`].

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::args::FemArgs;
use super::output::OutputDir;
use crate::kernel::KernelKind;
use crate::pipeline::map::{
    MapConfig, Mapped, MaterialMap, MixedState, Outside, SmoothingLength, StressSource,
};
use crate::pipeline::{self, Project};

/// A clap mirror of one of the library's plain enums: the same variants, with
/// their help, and the conversion into the library's type (the library does
/// not depend on clap).
macro_rules! value_enum_mirror {
    ($(#[$meta:meta])* $arg:ident => $lib:ident { $($(#[$vmeta:meta])* $variant:ident),+ $(,)? }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
        pub enum $arg {
            $($(#[$vmeta])* $variant),+
        }

        impl From<$arg> for $lib {
            fn from(arg: $arg) -> $lib {
                match arg {
                    $($arg::$variant => $lib::$variant),+
                }
            }
        }
    };
}

value_enum_mirror!(
    /// `--outside`: [`Outside`].
    OutsideArg => Outside { Error, Nearest, Skip }
);

value_enum_mirror!(
    /// `--stress`: [`StressSource`].
    StressArg => StressSource {
        /// `fem` when the FEM file has total stresses, otherwise `geostatic`.
        Auto,
        /// Map the FEM total stresses.
        Fem,
        /// Overburden of the GOM materials along the vertical, σh = K0·σ'v + S·p.
        Geostatic,
        /// Zero total stress (warned).
        Zero,
    }
);

value_enum_mirror!(
    /// `--mixed-state`: [`MixedState`].
    MixedStateArg => MixedState {
        /// Each fully filled element's volume-weighted mean state on all its MPs.
        Mean,
        /// Keep every MP's own mapped value (Anura3D MPM-MIXED keeps only MP 1's after the first step).
        PerMp,
    }
);

#[derive(Debug, clap::Args)]
pub struct MapArgs {
    #[command(flatten)]
    pub fem: FemArgs,
    /// Anura3D model: `.GOM`, `.GOM_stage<k>`, `-2.dat`, `.CPS_<nnn>` or a project folder.
    #[arg(long, value_name = "MODEL")]
    pub mpm: PathBuf,
    /// Kernel: cubic (paper Eq. 2), gaussian (Eq. 3, truncated at 3h) or wendland (C2).
    #[arg(long, default_value = "cubic")]
    pub kernel: String,
    /// Smoothing length: metres, or `auto` (leave-one-out calibration, paper Eq. 4); default: the paper's spacing rule (h = 1.0·l cubic/Wendland, 0.8·l Gaussian, l = median nearest-node spacing).
    #[arg(long, value_name = "METRES|auto")]
    pub h: Option<String>,
    /// Seed of the calibration's annealer (with --h auto).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// What to do with MPs that no FEM node reaches.
    #[arg(long, value_enum, default_value_t = OutsideArg::Error)]
    pub outside: OutsideArg,
    /// Null-point threshold on the Shepard ratio Σw·l^dim (≈ 1 inside, 0.5 on an edge).
    #[arg(long, default_value_t = 0.02)]
    pub min_shepard: f64,
    /// Where total stresses come from.
    #[arg(long, value_enum, default_value_t = StressArg::Auto)]
    pub stress: StressArg,
    /// FEM region → GOM material, e.g. `sand=1,clay=Base` (default: by name or index).
    #[arg(long, value_name = "REGION=MATERIAL,…")]
    pub material_map: Option<MaterialMap>,
    /// MPM-MIXED models: what the MPs of a fully filled element carry. Anura3D
    /// integrates such an element at one point and, after its first step, gives
    /// every MP the state of the element's first MP.
    #[arg(long, value_enum, default_value_t = MixedStateArg::Mean)]
    pub mixed_state: MixedStateArg,
    /// Output folder (default `<project>.a3d-init/` next to the model).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace an existing output folder.
    #[arg(long)]
    pub force: bool,
    /// Also write `fem.vtu` (the FEM nodes) when the FEM has more than 200 000 nodes;
    /// smaller FEMs always get one.
    #[arg(long)]
    pub fem_vtu: bool,
    /// Without a CPS beside the model, write a complete default CPS for the model's version (#14).
    #[arg(long)]
    pub generate_cps: bool,
}

impl MapArgs {
    /// The typed configuration these arguments describe (`dim` decides the
    /// Wendland variant).
    pub fn config(&self, dim: usize) -> anyhow::Result<MapConfig> {
        let kernel = KernelKind::parse(&self.kernel, dim).ok_or_else(|| {
            anyhow::anyhow!(
                "--kernel {}: expected cubic, gaussian or wendland",
                self.kernel
            )
        })?;
        let h = match self.h.as_deref() {
            None => SmoothingLength::SpacingRule,
            Some("auto") => SmoothingLength::Calibrate { seed: self.seed },
            Some(text) => match text.parse::<f64>() {
                Ok(h) if h > 0.0 && h.is_finite() => SmoothingLength::Metres(h),
                _ => anyhow::bail!(
                    "--h {text}: the smoothing length must be a positive number of metres, or auto"
                ),
            },
        };
        Ok(MapConfig {
            kernel,
            h,
            outside: self.outside.into(),
            min_shepard: self.min_shepard,
            stress: self.stress.into(),
            material_map: self.material_map.clone(),
            mixed_state: self.mixed_state.into(),
            keep_fem_fields: true,
        })
    }
}

/// Loads the project and the FEM files, maps (timing each phase).
pub fn compute(args: &MapArgs, h: Option<SmoothingLength>) -> anyhow::Result<Mapped> {
    // The model and the FEM files are independent: read side by side, so that
    // each fills the other's serial stretches (file reads, placement).
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    let (project, fem) = rayon::join(
        || {
            let t = Instant::now();
            Project::load(&args.mpm).map(|p| (p, ms(t)))
        },
        || {
            let t = Instant::now();
            args.fem.load().map(|f| (f, ms(t)))
        },
    );
    let (project, t_model) = project?;
    // No CPS → refuse unless --generate-cps (#14).
    if project.files.cps.is_none() && !args.generate_cps {
        anyhow::bail!(
            "{}",
            crate::formats::project::missing_cps_message(&project.files)
        );
    }
    let (fem, t_fem) = fem?;
    let mut config = args.config(project.n_dim())?;
    config.keep_fem_fields = args.fem_vtu || fem.nodes.len() <= pipeline::write::FEM_VTU_AUTO_MAX;
    if let Some(h) = h {
        config.h = h;
    }
    let mut mapped = pipeline::map::map(project, fem, &config)?;
    mapped.report.timings_ms.splice(
        0..0,
        [
            ("read model and place MPs".to_string(), t_model),
            ("read FEM".to_string(), t_fem),
        ],
    );
    Ok(mapped)
}

/// Writes the mapped project into the staging folder of `out`.
pub fn write(mapped: &Mapped, out: &OutputDir, fem_vtu: bool) -> anyhow::Result<Vec<String>> {
    Ok(pipeline::write::write_project(
        mapped,
        &out.path(""),
        fem_vtu,
    )?)
}

/// Default output folder: `<project>.a3d-init/` beside the model.
pub fn default_out(project_dir: &Path, name: &str) -> PathBuf {
    project_dir.join(format!("{name}.a3d-init"))
}

pub fn run(args: MapArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    let progress = super::progress::show();
    let mapped = compute(&args, None)?;
    let target = args
        .out
        .clone()
        .unwrap_or_else(|| default_out(&mapped.project.files.dir, &mapped.project.files.name));
    let mut inputs = super::args::project_inputs(&mapped.project.files);
    inputs.extend(args.fem.input_paths());
    let out = OutputDir::create(&target, args.force, &inputs)?;
    let written = write(&mapped, &out, args.fem_vtu)?;
    let target = out.commit()?;
    drop(progress);
    let r = &mapped.report;
    eprintln!(
        "a3d-init map: {} FEM nodes → {} MPs ({} kernel, h = {:.4} m; {})",
        r.fem_nodes,
        r.material_points,
        r.smoothing.kernel,
        r.smoothing.smoothing_length,
        r.smoothing.smoothing_length_rule
    );
    eprintln!(
        "  stress: {}; material separation: {}",
        r.stress_source, r.material_separation
    );
    eprintln!(
        "  pwp {:.3} .. {:.3} kPa, σyy {:.3} .. {:.3} kPa (Anura3D signs)",
        r.pwp_range.0, r.pwp_range.1, r.sigma_yy_range.0, r.sigma_yy_range.1
    );
    for n in &r.notes {
        eprintln!("  note: {n}");
    }
    for w in &r.warnings {
        eprintln!("  warning: {w}");
    }
    eprintln!(
        "  wrote {}/ : {} ({:.2} s)",
        target.display(),
        written.join(", "),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    /// Each mirror's command-line name is the library's name of the value it
    /// converts into.
    fn agrees<A: ValueEnum + Copy, L: From<A> + std::str::FromStr + PartialEq + std::fmt::Debug>()
    where
        L::Err: std::fmt::Debug,
    {
        for arg in A::value_variants() {
            let name = arg.to_possible_value().unwrap().get_name().to_string();
            assert_eq!(name.parse::<L>().unwrap(), L::from(*arg), "{name}");
        }
    }

    #[test]
    fn mirrors_agree_with_the_library_names() {
        agrees::<OutsideArg, Outside>();
        agrees::<StressArg, StressSource>();
        agrees::<MixedStateArg, MixedState>();
    }
}
