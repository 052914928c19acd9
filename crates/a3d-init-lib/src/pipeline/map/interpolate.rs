//! Stage 4 of [`super::map`]: the kernel interpolation of the FEM fields at
//! the MPs. [`prepare`] copies the fields the stress source needs into the
//! [`FemCloud`] the kernel reads; [`interpolate`] (or [`interpolate_taking`],
//! which lets the mapper free the copy) maps the MPs; [`diagnostics`] and
//! [`null_points`] sum up how each MP was reached. The kernel itself lives in
//! [`crate::kernel::mapper`].

use std::path::PathBuf;

use super::{Outside, Placement, StressSource};
use crate::formats::mps_table::MpDiagnostics;
use std::borrow::Cow;

use crate::kernel::mapper::{self, Handed, MapResult, MapSettings, NodeCloud, PointStatus, Points};
use crate::model::{FemNodes, MaterialPoint, Quantity, StressComponent};
use crate::pipeline::PipelineError;

/// The FEM nodes as the kernel sees them: positions, groups, the values of
/// the mapped quantities and the kernel's settings.
pub struct FemCloud<'a> {
    /// The nodes' positions: borrowed from the nodes, or taken from them
    /// ([`KeepNodes::Nothing`]).
    pub positions: Cow<'a, [[f64; 3]]>,
    pub dim: usize,
    /// Each node's group (GOM material index), when MPs take only their own.
    pub groups: Option<&'a [u32]>,
    /// The mapped quantities, in column order.
    pub quantities: Vec<Quantity>,
    /// Row-major node values: node i's value of `quantities[k]` at
    /// `i * quantities.len() + k`.
    pub values: Vec<f64>,
    /// The volume one node stands for, l^dim (for the Shepard ratio).
    pub node_volume: f64,
    pub settings: MapSettings,
    /// Groups left out of the mapping: their points get zero values and
    /// status `mapped` with no neighbours.
    pub excluded: Vec<u32>,
}

/// The quantities the stress `source` maps: the pore-water pressure (when the
/// FEM has it) and, for `fem`, every total-stress component it has.
pub fn mapped_quantities(nodes: &FemNodes, source: StressSource) -> Vec<Quantity> {
    let mut quantities: Vec<Quantity> = Vec::new();
    if nodes.field(Quantity::Pwp).is_some() {
        quantities.push(Quantity::Pwp);
    }
    if source == StressSource::Fem {
        for c in StressComponent::ALL {
            if nodes.field(Quantity::TotalStress(c)).is_some() {
                quantities.push(Quantity::TotalStress(c));
            }
        }
    }
    quantities
}

/// What [`prepare`] leaves in the FEM nodes once the cloud holds what the
/// kernel reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeepNodes {
    /// Everything (`fem.vtu` is written from them).
    All,
    /// Their positions and ids; the fields go (the cloud has its copy).
    Positions,
    /// Nothing but their dimension: the positions go into the cloud (the
    /// mapper frees them once its grid holds them, see
    /// [`interpolate_taking`]), ids, regions and fields are dropped. For a
    /// mapping that is the nodes' last use.
    Nothing,
}

/// The cloud mapping `nodes` onto `placement`'s MPs with `settings`: the
/// quantities of [`mapped_quantities`] copied row-major; what `keep` does not
/// keep is taken out of the nodes (memory). `spacing` is the median node
/// spacing l.
pub fn prepare<'a>(
    nodes: &'a mut FemNodes,
    placement: &'a Placement,
    source: StressSource,
    settings: MapSettings,
    spacing: f64,
    keep: KeepNodes,
) -> FemCloud<'a> {
    let quantities = mapped_quantities(nodes, source);
    let n_fields = quantities.len();
    let mut values = vec![0.0; nodes.len() * n_fields];
    for (k, q) in quantities.iter().enumerate() {
        for (i, v) in nodes.field(*q).unwrap_or(&[]).iter().enumerate() {
            values[i * n_fields + k] = *v;
        }
    }
    if keep != KeepNodes::All {
        nodes.fields = Vec::new();
    }
    let dim = nodes.dim;
    let positions = if keep == KeepNodes::Nothing {
        nodes.ids = Vec::new();
        nodes.region = None;
        Cow::Owned(std::mem::take(&mut nodes.positions))
    } else {
        let nodes: &'a FemNodes = nodes;
        Cow::Borrowed(&nodes.positions[..])
    };
    FemCloud {
        positions,
        dim,
        groups: placement.node_groups.as_deref(),
        quantities,
        values,
        node_volume: spacing.powi(dim as i32),
        settings,
        excluded: placement.unmapped_materials.clone(),
    }
}

impl FemCloud<'_> {
    /// The column of `q` in the node values and in a mapping's rows.
    pub fn column(&self, q: Quantity) -> Option<usize> {
        self.quantities.iter().position(|x| *x == q)
    }

    /// Maps `points` (with `groups`, one per point, when the nodes have
    /// groups) with `settings`; the cloud keeps its values.
    pub fn map_with(
        &self,
        points: &[[f64; 3]],
        groups: Option<&[u32]>,
        settings: &MapSettings,
    ) -> Result<MapResult, PipelineError> {
        map_subset(
            self,
            Handed::default(),
            Points::Slice(points),
            groups,
            settings,
        )
    }
}

/// Maps the points whose group is not in `cloud.excluded`; excluded points get
/// zero values and status `Mapped` with no neighbours (they are dry and need
/// no pwp). `owned`: node values and positions handed over in place of the
/// cloud's (see [`mapper::map_points_from`]).
fn map_subset(
    cloud: &FemCloud<'_>,
    owned: Handed,
    points: Points<'_>,
    groups: Option<&[u32]>,
    settings: &MapSettings,
) -> Result<MapResult, PipelineError> {
    let nodes = NodeCloud {
        positions: &cloud.positions,
        dim: cloud.dim,
        values: &cloud.values,
        n_fields: cloud.quantities.len(),
        group: cloud.groups,
        node_volume: cloud.node_volume,
    };
    let map = |points: Points<'_>, groups: Option<&[u32]>| {
        mapper::map_points_from(&nodes, owned, points, groups, settings)
            .map_err(|e| PipelineError::Input(e.to_string()))
    };
    let excluded = &cloud.excluded;
    let left_out = |i: usize| groups.is_some_and(|g| excluded.contains(&g[i]));
    if !(0..points.len()).any(left_out) {
        return map(points, groups);
    }
    let keep: Vec<usize> = (0..points.len()).filter(|&i| !left_out(i)).collect();
    let sub_points: Vec<[f64; 3]> = keep.iter().map(|&i| points.at(i)).collect();
    let sub_groups: Option<Vec<u32>> = groups.map(|g| keep.iter().map(|&i| g[i]).collect());
    let sub = map(Points::Slice(&sub_points), sub_groups.as_deref())?;
    let nf = nodes.n_fields;
    let mut full = MapResult {
        values: vec![0.0; points.len() * nf],
        n_neighbours: vec![0; points.len()],
        shepard: vec![0.0; points.len()],
        status: vec![PointStatus::Mapped; points.len()],
    };
    for (k, &i) in keep.iter().enumerate() {
        full.values[i * nf..(i + 1) * nf].copy_from_slice(&sub.values[k * nf..(k + 1) * nf]);
        full.n_neighbours[i] = sub.n_neighbours[k];
        full.shepard[i] = sub.shepard[k];
        full.status[i] = sub.status[k];
    }
    Ok(full)
}

/// Maps the MPs `mps` (placed by `placement`) through `cloud`, which keeps
/// its values (for a second mapping, as the geostatic stress needs). A
/// failure names the FEM files `fem_paths` and both extents.
pub fn interpolate(
    cloud: &FemCloud<'_>,
    placement: &Placement,
    mps: &[MaterialPoint],
    fem_paths: &[PathBuf],
) -> Result<MapResult, PipelineError> {
    interpolate_owning(cloud, Handed::default(), (placement, mps), fem_paths)
}

/// [`interpolate`], handing the cloud's values (and its positions, when it
/// owns them) to the mapper, which frees them once its grid holds a copy.
pub fn interpolate_taking(
    mut cloud: FemCloud<'_>,
    placement: &Placement,
    mps: &[MaterialPoint],
    fem_paths: &[PathBuf],
) -> Result<MapResult, PipelineError> {
    let handed = Handed {
        values: Some(std::mem::take(&mut cloud.values)),
        positions: match &mut cloud.positions {
            Cow::Owned(p) => Some(std::mem::take(p)),
            Cow::Borrowed(_) => None,
        },
    };
    interpolate_owning(&cloud, handed, (placement, mps), fem_paths)
}

/// The MPs' positions are read inside the MP table, not copied out.
fn interpolate_owning(
    cloud: &FemCloud<'_>,
    owned: Handed,
    (placement, mps): (&Placement, &[MaterialPoint]),
    fem_paths: &[PathBuf],
) -> Result<MapResult, PipelineError> {
    let at = |i: usize| mps[i].position;
    let points = Points::Records {
        len: mps.len(),
        at: &at,
    };
    map_subset(
        cloud,
        owned,
        points,
        placement.point_groups.as_deref(),
        &cloud.settings,
    )
    .map_err(|e| match &placement.reach {
        Some(r) => PipelineError::Input(format!(
            "{}: {e} ({})",
            crate::diagnose::file_list(fem_paths),
            r.extents()
        )),
        None => e,
    })
}

/// Each MP's mapping diagnostics (neighbours, Shepard ratio, status) for
/// mps.csv.
pub fn diagnostics(result: &MapResult) -> Vec<MpDiagnostics> {
    (0..result.status.len())
        .map(|i| MpDiagnostics {
            neighbours: result.n_neighbours[i],
            shepard: Some(result.shepard[i]),
            status: match result.status[i] {
                PointStatus::Mapped => "mapped",
                PointStatus::Nearest => "nearest",
                PointStatus::Skipped => "skipped",
            },
        })
        .collect()
}

/// How many MPs no FEM node reached inside the support (status `nearest` or
/// `skipped`).
pub fn null_points(result: &MapResult) -> usize {
    result
        .status
        .iter()
        .filter(|s| **s != PointStatus::Mapped)
        .count()
}

/// The report's warning about `null_points` MPs handled by `outside`, if any.
pub fn null_point_warning(null_points: usize, outside: Outside) -> Option<String> {
    (null_points > 0).then(|| {
        format!("{null_points} mp(s) had no fem node inside the support: handled by the outside policy {outside}")
    })
}
