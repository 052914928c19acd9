//! Malformed GOMs shared by the library tests (`anura3d_documents`) and the
//! binary tests (`cli`): each case mutates the TwoMat fixture and names the
//! place its error must point at, whichever path reads it.

use super::fixture;

pub fn two_mat() -> String {
    std::fs::read_to_string(fixture("anura3d-mini/TwoMat.GOM")).unwrap()
}

/// Replaces the first occurrence of the whole line `from` with `to`.
pub fn replace_line(text: &str, from: &str, to: &str) -> String {
    let mut done = false;
    text.lines()
        .map(|l| {
            if !done && l == from {
                done = true;
                to.to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

/// Malformed GOMs: (name, text, the start of the error message).
pub fn gom_cases() -> Vec<(&'static str, String, &'static str)> {
    let base = two_mat();
    let lines: Vec<&str> = base.lines().collect();
    vec![
        ("empty_file", String::new(), "TwoMat.GOM:1:1: empty file"),
        ("truncated_in_nodes", lines[..14].join("\n"), "TwoMat.GOM:14:1: missing `$$FINISH`"),
        ("missing_finish", base.replace("$$FINISH\n", ""), "TwoMat.GOM:89:1: missing `$$FINISH`"),
        ("wrong_header", base.replacen("### Anura3D_2023 ###", "### Anura3D_2020 ###", 1), "TwoMat.GOM:1:1: expected a version header"),
        ("header_with_leading_blank", base.replacen("### Anura3D_2023 ###", " ### Anura3D_2023 ###", 1), "TwoMat.GOM:1:1: expected a version header"),
        ("counters_not_numbers", replace_line(&base, "4 6", "4 six"), "TwoMat.GOM:9:3: expected a count, found `six`"),
        ("counters_say_more_nodes", replace_line(&base, "4 6", "4 7"), "TwoMat.GOM:17:1: $$STARTNODES (line 10) expects 7 node lines ($$STARTCOUNTERS), found 6"),
        ("bad_number_in_node", replace_line(&base, "1.0 1.0", "1.0 1.O"), "TwoMat.GOM:15:5: expected a coordinate, found `1.O`"),
        ("node_with_one_coordinate", replace_line(&base, "2.0 1.0", "2.0"), "TwoMat.GOM:16:4: node 6 needs 2 coordinates"),
        ("node_id_out_of_range", replace_line(&base, "2 6 5", "2 9 5"), "TwoMat.GOM:21:3: element 4: node id 9 is out of range 1..=6"),
        ("node_id_zero", replace_line(&base, "1 2 5", "0 2 5"), "TwoMat.GOM:18:1: element 1: node id 0 is out of range 1..=6"),
        ("element_with_two_nodes", replace_line(&base, "1 5 4", "1 5"), "TwoMat.GOM:19:4: element 2 needs 3 node ids"),
        ("unsupported_element_type", replace_line(&base, "triangular_3-noded", "hexahedral_8-noded"), "TwoMat.GOM:5:1: element type `hexahedral_8-noded` is not supported"),
        ("unknown_element_type", replace_line(&base, "triangular_3-noded", "triangle"), "TwoMat.GOM:5:1: element type `triangle` is unknown"),
        ("dimension_mismatch", replace_line(&base, "2D-plane_strain", "3D-cartesian"), "TwoMat.GOM:5:1: element type triangular_3-noded is 2D but the model is 3D-cartesian"),
        ("unknown_dimension", replace_line(&base, "2D-plane_strain", "2D"), "TwoMat.GOM:3:1: unknown dimension `2D`"),
        ("missing_nodes_block", replace_line(&base, "$$STARTNODES", "$$STARTNODEZ"), "TwoMat.GOM:90:1: missing required block $$STARTNODES"),
        ("fixity_node_out_of_range", replace_line(&base, "6 1 0", "60 1 0"), "TwoMat.GOM:28:1: node id 60 is out of range 1..=6"),
        ("material_index_not_its_position", base.replacen("$$MATERIAL_INDEX\n2", "$$MATERIAL_INDEX\n3", 1), "TwoMat.GOM:58:1: material index 3 at position 2"),
        ("unknown_material_type", replace_line(&base, "dry_material", "wet_material"), "TwoMat.GOM:36:1: unknown material type `wet_material`"),
        ("bad_porosity", replace_line(&base, "0.4", "zero.four"), "TwoMat.GOM:38:1: expected a number for $$POROSITY_SOLID, found `zero.four`"),
        ("element_material_out_of_range", base.replacen("$$STARTELMMAT\n1\n1\n2\n2", "$$STARTELMMAT\n1\n1\n2\n3", 1), "TwoMat.GOM:79:1: element 4: material 3 does not exist (2 materials)"),
        ("mp_count_not_allowed", base.replacen("$$START_NUMBER_OF_MATERIAL_POINTS\n3 0", "$$START_NUMBER_OF_MATERIAL_POINTS\n4 0", 1), "TwoMat.GOM:86:1: element 1: 4 MPs per element is not allowed for triangular_3-noded"),
        ("mp_counts_short", base.replacen("3 0\n$$FINISH", "$$FINISH", 1), "TwoMat.GOM:89:1: $$START_NUMBER_OF_MATERIAL_POINTS (line 85) expects 4 MP count lines, found 3"),
        ("one_element_less", base.replacen("4 6\n", "3 6\n", 1), "TwoMat.GOM:21:1: $$STARTELEMCON (line 17) expects 3"),
        ("one_element_more", base.replacen("4 6\n", "5 6\n", 1), "TwoMat.GOM:22:1: $$STARTELEMCON (line 17) expects 5"),
        ("one_node_more_line", base.replacen("2.0 1.0\n", "2.0 1.0\n3.0 1.0\n", 1), "TwoMat.GOM:17:1: $$STARTNODES (line 10) expects 6"),
        ("zero_counts", base.replacen("4 6\n", "0 0\n", 1), "TwoMat.GOM:9:1: 0 elements and 0 nodes"),
        ("negative_count", base.replacen("4 6\n", "-4 6\n", 1), "TwoMat.GOM:9:1: expected a count"),
        ("fixity_count", base.replacen("$$START_FIXITY_LINE_SOLID\n5\n", "$$START_FIXITY_LINE_SOLID\n4\n", 1), "TwoMat.GOM:28:1: $$START_FIXITY_LINE_SOLID (line 22) expects 4 fixity lines, found more"),
        ("after_finish", format!("{base}stray line\n"), "TwoMat.GOM:91:1: data after `$$FINISH`"),
        ("overflowing_coordinate", base.replacen("2.0 1.0\n", "1e400 1.0\n", 1), "TwoMat.GOM:16:1: expected a coordinate, found `1e400`"),
        ("bad_number", base.replacen("1.0 1.0\n", "1.0 x\n", 1), "TwoMat.GOM:15:5: expected a coordinate, found `x`"),
    ]
    .into_iter()
    .collect()
}
