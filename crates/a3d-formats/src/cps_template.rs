//! Complete default CPS (and 2025 OPD) files for a model that comes without
//! one, written only when the user asks (`map --generate-cps`). Spec:
//! `formats/cps.md` ("Generated CPS").
//!
//! "Complete" means every keyword a kernel-written CPS holds: the kernel writes
//! the CPS of the next load step itself with all its parameters, and that list
//! is the reference. The list below is the union of what the 2025 kernel writes
//! (the same list for every header version, plus `$$STAGE` for 2025) and the
//! extra keywords of the upstream 2024 template (`SKIP_CONVECTION_TIME_STEPS`,
//! `AUTOMATIC_SKIP_CONVECTION`, `PERMEABILITY_UPDATE`, `INTRINSIC_PERMEABILITY`,
//! `INITIAL_VERTICAL_LOAD_K0`, `NODE_NORMAL_DATA`). A kernel that does not know a
//! keyword only warns. Values are the kernel defaults, except the switches of an
//! equilibrium stage started from a MAPF: gravity on, quasi-static convergence,
//! local damping 0.75, K0 off, MAPF initialisation on.
//! This module does not read files; [`super::cps::CpsDocument`] parses the text.

/// Keyword and value lines of the generated CPS, in the kernel's order.
/// `{GRAVITY}` and `{ACTIVE}` are filled in by [`generate_cps`].
const KEYWORDS: &[(&str, &[&str])] = &[
    ("$$NUMBER_OF_LOADSTEPS", &["1"]),
    ("$$TIME_PER_LOADSTEP", &["0.5"]),
    ("$$TOTAL_TIME", &["0.0"]),
    ("$$COURANT_NUMBER", &["0.98"]),
    ("$$COMPUTATION_METHOD", &["MPM-MIXED"]),
    ("$$GRAVITY_ACCELERATION", &["9.81"]),
    ("$$GRAVITY_VECTOR", &["{GRAVITY}"]),
    ("$$GRAVITY_LOAD", &["step 1.0 1.0"]),
    ("$$SOLID_TRACTION", &["off 0.0 1.0"]),
    ("$$SOLID_TRACTION_B", &["off 0.0 1.0"]),
    ("$$LIQUID_PRESSURE", &["off 0.0 1.0"]),
    ("$$LIQUID_PRESSURE_B", &["off 0.0 1.0"]),
    ("$$GAS_PRESSURE", &["off 0.0 1.0"]),
    ("$$GAS_PRESSURE_B", &["off 0.0 1.0"]),
    ("$$HYDRAULIC_HEAD", &["off 0.0"]),
    ("$$APPLY_SEEPAGE_FACE", &["0"]),
    ("$$APPLY_INFILTRATION", &["0"]),
    ("$$PRESCRIBED_VELOCITY", &["off 0.0 1.0"]),
    ("$$QUASISTATIC_CONVERGENCE", &["1"]),
    ("$$TOLERATED_ERROR_SOLID", &["0.01 0.01"]),
    ("$$TOLERATED_ERROR_LIQUID", &["0.01 0.01"]),
    ("$$MAXIMUM_TIME_STEPS", &["10000"]),
    ("$$APPLY_IMPLICIT_QUASISTATIC", &["0"]),
    ("$$QS_MIN_ITER", &["6"]),
    ("$$QS_MAX_ITER", &["15"]),
    ("$$QS_UPSCALE_FACTOR", &["2.0"]),
    ("$$QS_DOWNSCALE_FACTOR", &["0.5"]),
    ("$$QS_MAX_ITERATIONS", &["60"]),
    ("$$APPLY_ZLS", &["0"]),
    ("$$APPLY_ARC_LENGTH_CONTROL", &["0"]),
    ("$$APPLY_ENHANCED_STIFFNESS", &["0"]),
    ("$$QS_STIFFNESS_INCREASE_FACTOR", &["0.0"]),
    ("$$QS_DANGLING_ELEMENT_FACTOR", &["0.0"]),
    ("$$APPLY_STEP_EXTRAPOLATION", &["0"]),
    ("$$APPLY_JACOBIAN_CHECK", &["0"]),
    ("$$LIMIT_JACOBIAN_CHANGE", &["0.0"]),
    ("$$APPLY_AUTOMATIC_LOADSTEPPING", &["0"]),
    ("$$INCR_MULTIPLIER_SOILA", &["0.0"]),
    ("$$INCR_MULTIPLIER_GRAVITY", &["0.0"]),
    ("$$INCR_MULTIPLIER_WATERA", &["0.0"]),
    ("$$INCR_MULTIPLIER_GASA", &["0.0"]),
    ("$$MASS_SCALING", &["0 1.0"]),
    ("$$HOMOGENEOUS_LOCAL_DAMPING", &["1 0.75"]),
    ("$$BULK_VISCOSITY_DAMPING", &["0 0.0 0.0"]),
    ("$$APPLY_DIVERGENCE_CHECK", &["0"]),
    ("$$SKIP_CONVECTION_TIME_STEPS", &["1"]),
    ("$$AUTOMATIC_SKIP_CONVECTION", &["0"]),
    ("$$MINIMUM_DETERMINANT_RATIO", &["0.75"]),
    ("$$NUMBER_OF_THREADS", &["1"]),
    ("$$APPLY_NODE_DATA_AB", &["0"]),
    ("$$CONTACT_FORMULATION", &["0"]),
    ("$$APPLY_CONTACT_MESH_BOUNDARY", &["0"]),
    ("$$APPLY_TRACTION_CONTACT", &["0"]),
    ("$$MONOPILE_SLICE_CONTACT", &["0"]),
    ("$$APPLY_CONTACT_VELOCITY_SCALING", &["0"]),
    ("$$VELOCITY_SCALING_FACTOR", &["0.0"]),
    ("$$APPLY_CONTACT_NORMAL_CORRECTION", &["0"]),
    ("$$NUMBER_OF_CORRECTED_NORMALS", &["0"]),
    // With 0 corrected normals the reader reads no vector lines here.
    ("$$NODE_NORMAL_DATA", &["0"]),
    ("$$EXCAVATION", &["0"]),
    ("$$CONSTRUCTION", &["0"]),
    ("$$FILL_EMPTY_ELEMENTS", &["0"]),
    ("$$FIX_SOLID_SKELETON", &["0"]),
    ("$$STRAIN_SMOOTHING", &["0"]),
    ("$$APPLY_STRAIN_SMOOTHING_LIQUID_TWOLAYERFORM", &["0"]),
    ("$$LIQUID_CAVITATION", &["0.0"]),
    ("$$UPDATE_PERMEABILITY_DARCY_ERGUN", &["0 0"]),
    ("$$PERMEABILITY_UPDATE", &["CONSTANT_PERMEABILITY"]),
    ("$$INTRINSIC_PERMEABILITY", &["0"]),
    ("$$GRAIN_SIZE_DIAMETER", &["0.0 0.0"]),
    ("$$ERGUN_CONSTANTS", &["0.0 0.0"]),
    ("$$NO_TENSILE_STRESS_LIQUID_MP_WITH_LIQUID_STATUS", &["0"]),
    ("$$MAXIMUM_POROSITY", &["0.0"]),
    ("$$DETECT_FREE_SURFACE", &["0 0.0"]),
    ("$$RESET_DISPLACEMENTS", &["0"]),
    ("$$REMOVE_FIXITIES", &["0 0 0"]),
    ("$$MP_STRESS_INITIALIZATION_FROMFILE", &["1"]),
    ("$$K0_PROCEDURE", &["0"]),
    ("$$K0_MAX_SUCTION", &["1.0E10"]),
    ("$$SURFACE_ELEVATION", &["0.0 0.0"]),
    ("$$INITIAL_VERTICAL_LOAD_K0", &["0.0"]),
    ("$$NUMBER_SOIL_LAYERS", &["1"]),
    ("$$THICKNESS_SOIL_LAYERS", &["0.0"]),
    ("$$LIQUID_SURFACE", &["0.0 0.0"]),
    ("$$CONSIDERED_LOAD_K0", &["0.0"]),
    ("$$INITIAL_WATER_PRESSURE", &["0.0"]),
    ("$$APPLY_MATERIAL_UPDATE", &["0"]),
    ("$$APPLY_POROSITY_UPDATE", &["0"]),
    ("$$SUBMERGED_CALCULATION", &["0 1"]),
    ("$$INITIAL_VELOCITY", &["0"]),
    ("$$APPLY_OBJECTIVE_STRESS", &["0"]),
    ("$$DEGREE_OF_FILLING", &["0.9"]),
    ("$$NUMBER_OF_ACTIVE_ELEMENTS", &["{ACTIVE}"]),
    ("$$APPLY_EMPTY_ELEMENTS", &["0"]),
    ("$$MASS_FACTOR_VIRTUAL_PARTICLES", &["1.0"]),
    ("$$GROUP_THRESHOLD", &["40"]),
    ("$$VISUALIZATION_OPTION", &["Paraview"]),
    ("$$OUTPUT_NUMBER_OF_MATERIAL_POINTS", &["0"]),
    ("$$OUTPUT_MATERIAL_POINTS", &["-1"]),
    ("$$OUTPUT_BASIC_DATA", &["0"]),
    ("$$OUTPUT_CURVES_INTERVAL", &["1"]),
    ("$$OUTPUT_NUMBER_OF_NODES", &["-1"]),
    ("$$OUTPUT_NODES", &["-1 -1 -1 -1 -1 -1", "-1 -1 -1 -1"]),
    ("$$OUTPUT_DEBUG_DATA", &["0"]),
    ("$$OUTPUT_EACH_LOAD_STEP", &["1"]),
    ("$$QUICK_CHECK_OUTPUT", &["1"]),
    ("$$FILE_COUNTER", &["0"]),
    ("$$PARTICLE_FILE_COUNTER", &["1"]),
    ("$$FEEDBACK_LEVEL", &["-1"]),
    ("$$APPLY_SMOOTHENING_LIQUID_PRESSURE_INCREMENT", &["0"]),
];

/// Output variables of a 2025 OPD, all switched on (the kernel's defaults).
const OPD_VARIABLES: &[&str] = &[
    "$$MASS_MIXTURE",
    "$$WEIGHT_MIXTURE",
    "$$POROSITY",
    "$$MEAN_EFFECTIVE_STRESS",
    "$$DEVIATORIC_STRESS",
    "$$DEVIATORIC_STRAIN",
    "$$DEGREE_OF_SATURATION",
    "$$STATE_VARIABLES",
    "$$DAMPING",
    "$$MASS_SOLID",
    "$$WEIGHT_SOLID",
    "$$VOLUMETRIC_STRAIN_SOLID",
    "$$MASS_LIQUID",
    "$$WEIGHT_LIQUID",
    "$$VOLUMETRIC_STRAIN_LIQUID",
    "$$PRESSURE_LIQUID",
    "$$MASS_GAS",
    "$$WEIGHT_GAS",
    "$$PRESSURE_GAS",
    "$$VOLUMETRIC_STRAIN_GAS",
    "$$GLOBAL_POSITION",
    "$$LOCAL_POSITION",
    "$$BODY_FORCE_MIXTURE",
    "$$BODY_FORCE_SOLID",
    "$$EXTERNAL_FORCE_SOLID",
    "$$ACCELERATION_SOLID",
    "$$VELOCITY_SOLID",
    "$$DISPLACEMENT_SOLID",
    "$$BODY_FORCE_LIQUID",
    "$$EXTERNAL_FORCE_LIQUID",
    "$$VELOCITY_LIQUID",
    "$$DISPLACEMENT_LIQUID",
    "$$BODY_FORCE_GAS",
    "$$EXTERNAL_FORCE_GAS",
    "$$VELOCITY_GAS",
    "$$DISPLACEMENT_GAS",
    "$$TOTAL_STRESS",
    "$$EFFECTIVE_STRESS",
    "$$STRAIN",
];

/// The version headers Anura3D accepts.
pub const VERSIONS: &[&str] = &["2025", "2024", "2023", "2022", "2021", "2019.2"];

/// The keywords of a generated CPS for `version`, in order (without `$$END`).
pub fn keywords(version: &str) -> Vec<&'static str> {
    let stage = (version == "2025").then_some("$$STAGE");
    stage
        .into_iter()
        .chain(KEYWORDS.iter().map(|(k, _)| *k))
        .collect()
}

/// A complete CPS for a model with header `version` (`2025` adds `$$STAGE 0`),
/// `dim` 2 or 3 and `active_elements` active elements. Lines end with `\n`.
pub fn generate_cps(version: &str, dim: usize, active_elements: usize) -> String {
    let gravity = if dim == 3 { "0.0 -1.0 0.0" } else { "0.0 -1.0" };
    let active = active_elements.to_string();
    let mut out = format!("### Anura3D_{version} ###\n");
    if version == "2025" {
        out.push_str("$$STAGE\n0\n");
    }
    for (keyword, lines) in KEYWORDS {
        out.push_str(keyword);
        out.push('\n');
        for line in *lines {
            out.push_str(match *line {
                "{GRAVITY}" => gravity,
                "{ACTIVE}" => &active,
                other => other,
            });
            out.push('\n');
        }
    }
    out.push_str("$$END\n");
    out
}

/// A 2025 OPD with every output variable on, output after every step.
pub fn generate_opd() -> String {
    let mut out = String::from("$$CALCULATION_STEPS_BETWEEN_OUTPUTS\n1\n");
    for v in OPD_VARIABLES {
        out.push_str(v);
        out.push_str("\n1\n");
    }
    out.push_str("$$END\n");
    out
}

/// The CPS of the ready-to-run project: the model's own CPS with only
/// `$$K0_PROCEDURE 0` and `$$MP_STRESS_INITIALIZATION_FROMFILE 1` changed (every
/// other byte as read), or, without one, a generated CPS for the model's header
/// `gom_version`.
pub fn ready_to_run_cps(
    own: Option<&super::cps::CpsDocument>,
    gom_version: &str,
    dim: usize,
    active_elements: usize,
) -> Result<String, super::FormatError> {
    let mut cps = match own {
        Some(doc) => doc.clone(),
        None => super::cps::CpsDocument::parse(
            std::path::Path::new("generated.CPS_001"),
            generate_cps(gom_version, dim, active_elements),
        )?,
    };
    cps.set("$$K0_PROCEDURE", &["0"]);
    cps.set("$$MP_STRESS_INITIALIZATION_FROMFILE", &["1"]);
    Ok(cps.to_text())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cps::CpsDocument;
    use std::path::Path;

    /// Keywords of the kernel-written 2021 CPS sample (`K0_phreaticSurf_File.CPS_002`).
    const KERNEL_2021: &str = "NUMBER_OF_LOADSTEPS TIME_PER_LOADSTEP TOTAL_TIME COURANT_NUMBER COMPUTATION_METHOD GRAVITY_ACCELERATION GRAVITY_VECTOR GRAVITY_LOAD SOLID_TRACTION SOLID_TRACTION_B LIQUID_PRESSURE LIQUID_PRESSURE_B HYDRAULIC_HEAD APPLY_SEEPAGE_FACE APPLY_INFILTRATION PRESCRIBED_VELOCITY QUASISTATIC_CONVERGENCE TOLERATED_ERROR_SOLID TOLERATED_ERROR_LIQUID MAXIMUM_TIME_STEPS APPLY_IMPLICIT_QUASISTATIC QS_MIN_ITER QS_MAX_ITER QS_UPSCALE_FACTOR QS_DOWNSCALE_FACTOR QS_MAX_ITERATIONS APPLY_ZLS APPLY_ARC_LENGTH_CONTROL APPLY_ENHANCED_STIFFNESS QS_STIFFNESS_INCREASE_FACTOR QS_DANGLING_ELEMENT_FACTOR APPLY_STEP_EXTRAPOLATION APPLY_JACOBIAN_CHECK LIMIT_JACOBIAN_CHANGE APPLY_AUTOMATIC_LOADSTEPPING INCR_MULTIPLIER_SOILA INCR_MULTIPLIER_GRAVITY INCR_MULTIPLIER_WATERA INCR_MULTIPLIER_GASA MASS_SCALING HOMOGENEOUS_LOCAL_DAMPING BULK_VISCOSITY_DAMPING APPLY_DIVERGENCE_CHECK MINIMUM_DETERMINANT_RATIO NUMBER_OF_THREADS APPLY_NODE_DATA_AB CONTACT_FORMULATION APPLY_CONTACT_MESH_BOUNDARY APPLY_TRACTION_CONTACT MONOPILE_SLICE_CONTACT APPLY_CONTACT_VELOCITY_SCALING VELOCITY_SCALING_FACTOR APPLY_CONTACT_NORMAL_CORRECTION NUMBER_OF_CORRECTED_NORMALS EXCAVATION FIX_SOLID_SKELETON STRAIN_SMOOTHING APPLY_STRAIN_SMOOTHING_LIQUID_TWOLAYERFORM LIQUID_CAVITATION UPDATE_PERMEABILITY_DARCY_ERGUN GRAIN_SIZE_DIAMETER ERGUN_CONSTANTS NO_TENSILE_STRESS_LIQUID_MP_WITH_LIQUID_STATUS MAXIMUM_POROSITY DETECT_FREE_SURFACE RESET_DISPLACEMENTS REMOVE_FIXITIES K0_PROCEDURE K0_MAX_SUCTION SURFACE_ELEVATION NUMBER_SOIL_LAYERS THICKNESS_SOIL_LAYERS LIQUID_SURFACE CONSIDERED_LOAD_K0 INITIAL_WATER_PRESSURE APPLY_MATERIAL_UPDATE APPLY_POROSITY_UPDATE SUBMERGED_CALCULATION INITIAL_VELOCITY APPLY_OBJECTIVE_STRESS DEGREE_OF_FILLING NUMBER_OF_ACTIVE_ELEMENTS APPLY_EMPTY_ELEMENTS MASS_FACTOR_VIRTUAL_PARTICLES GROUP_THRESHOLD VISUALIZATION_OPTION OUTPUT_NUMBER_OF_MATERIAL_POINTS OUTPUT_MATERIAL_POINTS OUTPUT_BASIC_DATA OUTPUT_CURVES_INTERVAL OUTPUT_NUMBER_OF_NODES OUTPUT_NODES OUTPUT_DEBUG_DATA OUTPUT_EACH_LOAD_STEP QUICK_CHECK_OUTPUT FILE_COUNTER PARTICLE_FILE_COUNTER FEEDBACK_LEVEL APPLY_SMOOTHENING_LIQUID_PRESSURE_INCREMENT";

    /// Keywords of the upstream `template_v2024.CPS_001`.
    const TEMPLATE_2024: &str = "NUMBER_OF_LOADSTEPS TIME_PER_LOADSTEP TOTAL_TIME COURANT_NUMBER COMPUTATION_METHOD GRAVITY_ACCELERATION GRAVITY_VECTOR GRAVITY_LOAD SOLID_TRACTION SOLID_TRACTION_B LIQUID_PRESSURE LIQUID_PRESSURE_B GAS_PRESSURE GAS_PRESSURE_B HYDRAULIC_HEAD APPLY_SEEPAGE_FACE APPLY_INFILTRATION PRESCRIBED_VELOCITY QUASISTATIC_CONVERGENCE TOLERATED_ERROR_SOLID TOLERATED_ERROR_LIQUID MAXIMUM_TIME_STEPS APPLY_IMPLICIT_QUASISTATIC QS_MIN_ITER QS_MAX_ITER QS_UPSCALE_FACTOR QS_DOWNSCALE_FACTOR QS_MAX_ITERATIONS APPLY_ZLS APPLY_ARC_LENGTH_CONTROL APPLY_ENHANCED_STIFFNESS QS_STIFFNESS_INCREASE_FACTOR QS_DANGLING_ELEMENT_FACTOR APPLY_STEP_EXTRAPOLATION APPLY_JACOBIAN_CHECK LIMIT_JACOBIAN_CHANGE APPLY_AUTOMATIC_LOADSTEPPING INCR_MULTIPLIER_SOILA INCR_MULTIPLIER_GRAVITY INCR_MULTIPLIER_WATERA INCR_MULTIPLIER_GASA MASS_SCALING HOMOGENEOUS_LOCAL_DAMPING BULK_VISCOSITY_DAMPING APPLY_DIVERGENCE_CHECK SKIP_CONVECTION_TIME_STEPS AUTOMATIC_SKIP_CONVECTION MINIMUM_DETERMINANT_RATIO NUMBER_OF_THREADS APPLY_NODE_DATA_AB CONTACT_FORMULATION APPLY_CONTACT_MESH_BOUNDARY APPLY_TRACTION_CONTACT MONOPILE_SLICE_CONTACT APPLY_CONTACT_VELOCITY_SCALING VELOCITY_SCALING_FACTOR APPLY_CONTACT_NORMAL_CORRECTION NUMBER_OF_CORRECTED_NORMALS NODE_NORMAL_DATA EXCAVATION CONSTRUCTION FILL_EMPTY_ELEMENTS FIX_SOLID_SKELETON STRAIN_SMOOTHING APPLY_STRAIN_SMOOTHING_LIQUID_TWOLAYERFORM LIQUID_CAVITATION PERMEABILITY_UPDATE INTRINSIC_PERMEABILITY GRAIN_SIZE_DIAMETER ERGUN_CONSTANTS NO_TENSILE_STRESS_LIQUID_MP_WITH_LIQUID_STATUS MAXIMUM_POROSITY DETECT_FREE_SURFACE RESET_DISPLACEMENTS REMOVE_FIXITIES K0_PROCEDURE MP_STRESS_INITIALIZATION_FROMFILE K0_MAX_SUCTION SURFACE_ELEVATION INITIAL_VERTICAL_LOAD_K0 NUMBER_SOIL_LAYERS THICKNESS_SOIL_LAYERS LIQUID_SURFACE CONSIDERED_LOAD_K0 INITIAL_WATER_PRESSURE APPLY_MATERIAL_UPDATE APPLY_POROSITY_UPDATE SUBMERGED_CALCULATION INITIAL_VELOCITY APPLY_OBJECTIVE_STRESS DEGREE_OF_FILLING NUMBER_OF_ACTIVE_ELEMENTS APPLY_EMPTY_ELEMENTS MASS_FACTOR_VIRTUAL_PARTICLES GROUP_THRESHOLD VISUALIZATION_OPTION OUTPUT_NUMBER_OF_MATERIAL_POINTS OUTPUT_MATERIAL_POINTS OUTPUT_BASIC_DATA OUTPUT_CURVES_INTERVAL OUTPUT_NUMBER_OF_NODES OUTPUT_NODES OUTPUT_DEBUG_DATA OUTPUT_EACH_LOAD_STEP QUICK_CHECK_OUTPUT FILE_COUNTER PARTICLE_FILE_COUNTER FEEDBACK_LEVEL APPLY_SMOOTHENING_LIQUID_PRESSURE_INCREMENT";

    fn has_all(version: &str, reference: &str) {
        let text = generate_cps(version, 2, 10);
        let doc = CpsDocument::parse(Path::new("g.CPS_001"), text).unwrap();
        assert_eq!(doc.version(), version);
        for k in reference.split_whitespace() {
            assert!(
                doc.get(&format!("$${k}")).is_some(),
                "{version}: ${k} missing"
            );
        }
    }

    #[test]
    fn generated_cps_holds_every_keyword_of_a_kernel_written_cps() {
        for v in VERSIONS {
            has_all(v, KERNEL_2021);
            has_all(v, TEMPLATE_2024);
        }
        let doc = CpsDocument::parse(Path::new("g"), generate_cps("2025", 3, 7)).unwrap();
        assert!(doc.is_staged());
        assert_eq!(doc.stage(), 0);
        assert_eq!(doc.get_token("$$NUMBER_OF_ACTIVE_ELEMENTS", 0), Some("7"));
        assert_eq!(doc.get("$$GRAVITY_VECTOR"), Some(vec!["0.0 -1.0 0.0"]));
        assert_eq!(
            doc.get_token("$$MP_STRESS_INITIALIZATION_FROMFILE", 0),
            Some("1")
        );
        assert_eq!(doc.get_token("$$K0_PROCEDURE", 0), Some("0"));
        assert!(keywords("2024").iter().all(|k| *k != "$$STAGE"));
    }

    #[test]
    fn own_cps_changes_only_the_two_switches() {
        let own = "### Anura3D_2024 ###\r\n$$K0_PROCEDURE\r\n1\r\n$$TIME_PER_LOADSTEP\r\n  0.25 \r\n$$END\r\n";
        let doc = CpsDocument::parse(Path::new("x-1.dat"), own.into()).unwrap();
        let text = ready_to_run_cps(Some(&doc), "2023", 2, 1).unwrap();
        assert_eq!(
            text,
            "### Anura3D_2024 ###\r\n$$K0_PROCEDURE\r\n0\r\n$$TIME_PER_LOADSTEP\r\n  0.25 \r\n$$MP_STRESS_INITIALIZATION_FROMFILE\r\n1\r\n$$END\r\n"
        );
        let generated = ready_to_run_cps(None, "2024", 2, 1).unwrap();
        assert!(generated.starts_with("### Anura3D_2024 ###\n"));
    }

    #[test]
    fn generated_opd_parses_as_written() {
        let text = generate_opd();
        let doc = crate::keyword_doc::KeywordDocument::parse_with(
            Path::new("g.OPD_stage0"),
            text.clone(),
            "$$END",
            true,
            false,
        )
        .unwrap();
        assert_eq!(doc.to_text(), text);
        assert!(doc.find("$$TOTAL_STRESS", true).is_some());
    }
}
