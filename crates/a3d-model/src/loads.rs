//! Distributed loads a GOM puts on element sides (`$$START_LOAD_ON_NODES_…`,
//! `$$START_LOAD_ON_MATERIAL_POINTS_…`) and the CPS multipliers that scale
//! them in time (`$$SOLID_TRACTION[_B]`, `$$LIQUID_PRESSURE[_B]`), as the
//! Anura3D kernel reads them (`MeshInfo.FOR`, `ReadCalculationData.FOR`).
//! Plain data; the runner (`a3d_mpm::loads`) turns them into forces.

/// Which phase a load block acts on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum LoadPhase {
    /// A traction (kPa per component) on the solid / mixture.
    Solid,
    /// A liquid pressure (kPa, negative in compression) normal to the side,
    /// on the liquid phase of two-phase materials.
    Liquid,
}

/// Where the kernel puts the load.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum LoadTarget {
    /// Consistent nodal forces of the side's corner nodes, fixed in space.
    Nodes,
    /// Shared among the MPs next to the side when the run starts; they carry
    /// it as they move.
    MaterialPoints,
}

/// One loaded element side.
#[derive(Clone, Debug, PartialEq)]
pub struct SideLoad {
    /// 0-based mesh node ids of the side's corners (2 in 2D, 3 in 3D), in the
    /// file's order; mid-side nodes are dropped, as the kernel drops their
    /// values.
    pub corners: Vec<u32>,
    /// The load at each corner (x, y[, z]; unused components 0).
    pub values: Vec<[f64; 3]>,
    /// 1-based line of the side in the GOM.
    pub line: u32,
}

/// A GOM load block: its sides, the phase and target, and its load system
/// (0 = A, scaled by `$$SOLID_TRACTION` / `$$LIQUID_PRESSURE`; 1 = B, by
/// their `_B` variants).
#[derive(Clone, Debug, PartialEq)]
pub struct LoadBlock {
    pub keyword: String,
    pub phase: LoadPhase,
    pub target: LoadTarget,
    pub system: usize,
    pub sides: Vec<SideLoad>,
}

/// How a multiplier moves through the load steps (`$$SOLID_TRACTION step 0 1`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum MultiplierKind {
    Off,
    /// Jumps to each load step's value at its start.
    Step,
    /// Ramps linearly from the previous load step's value to this one's over
    /// the load step.
    Linear,
}

/// A CPS load multiplier: its kind, the value already realised and the final
/// value. Load step i of N aims at `realised + i/N·(final − realised)`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Multiplier {
    pub kind: MultiplierKind,
    pub realised: f64,
    pub final_value: f64,
}

impl Default for Multiplier {
    /// The kernel's default when the CPS names no multiplier: `step 0 1`.
    fn default() -> Multiplier {
        Multiplier {
            kind: MultiplierKind::Step,
            realised: 0.0,
            final_value: 1.0,
        }
    }
}

impl Multiplier {
    /// On in full from the start (`step 1 1`).
    pub const FULL: Multiplier = Multiplier {
        kind: MultiplierKind::Step,
        realised: 1.0,
        final_value: 1.0,
    };

    /// The multiplier at `time` (s) from the start of a calculation of
    /// `load_steps` load steps of `step_time` s each, as the kernel's
    /// `UpdateMultipliersForTimeDepencency` forms it for the step that ends
    /// at `time`. Past the last load step it stays at its final value.
    pub fn at(&self, time: f64, load_steps: usize, step_time: f64) -> f64 {
        if self.kind == MultiplierKind::Off {
            return 0.0;
        }
        let n = load_steps.max(1);
        let target =
            |i: usize| self.realised + (i as f64 / n as f64) * (self.final_value - self.realised);
        if !(step_time > 0.0 && step_time.is_finite()) {
            return target(n);
        }
        // The load step this time falls in (1-based); a step ending exactly
        // at a load step's end still belongs to it.
        let position = time / step_time;
        let i = (position.ceil() as usize).clamp(1, n);
        match self.kind {
            MultiplierKind::Off => 0.0,
            MultiplierKind::Step => target(i),
            MultiplierKind::Linear => {
                let within = (position - (i - 1) as f64).clamp(0.0, 1.0);
                target(i - 1) + (target(i) - target(i - 1)) * within
            }
        }
    }
}

/// A prescribed external water level (CPS `$$HYDRAULIC_HEAD file`): the
/// head h(t) of `<project>.HHBF` on the free-surface sides inside the GOM's
/// `$$BOUNDARY_HYDRAULIC_HEAD_AREA`, a water pressure γw·(h − y) below it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct HeadSeries {
    /// `[min, max]` per axis (x, y[, z]; unused axes unbounded).
    pub area: [[f64; 2]; 3],
    /// (time s, head m), times strictly increasing.
    pub points: Vec<(f64, f64)>,
}

impl HeadSeries {
    /// The head at `time` as the kernel's `GetHydraulicHeadForTimeStep`
    /// interpolates it: linear between the file's rows, the last value after
    /// the last time (and, here, the first before the first time).
    pub fn at(&self, time: f64) -> f64 {
        let Some(&(t_last, h_last)) = self.points.last() else {
            return 0.0;
        };
        if time > t_last {
            return h_last;
        }
        match self.points.iter().position(|&(t, _)| t > time) {
            Some(0) | None => self.points[0].1,
            Some(i) => {
                let (t0, h0) = self.points[i - 1];
                let (t1, h1) = self.points[i];
                h0 + (h1 - h0) / (t1 - t0) * (time - t0)
            }
        }
    }
}

/// The GOM's loads with the CPS's multipliers and load-step timing: what the
/// runner needs to apply them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ProjectLoads {
    pub blocks: Vec<LoadBlock>,
    /// `$$SOLID_TRACTION`, `$$SOLID_TRACTION_B`.
    pub solid: [Multiplier; 2],
    /// `$$LIQUID_PRESSURE`, `$$LIQUID_PRESSURE_B`.
    pub liquid: [Multiplier; 2],
    /// `$$GRAVITY_LOAD`: the multiplier of gravity (the kernel's `step 0 1`
    /// when absent, full gravity in a run of one load step).
    pub gravity: Multiplier,
    /// `$$NUMBER_OF_LOADSTEPS` (at least 1).
    pub load_steps: usize,
    /// `$$TIME_PER_LOADSTEP` (s).
    pub step_time: f64,
    /// A water level from a file, when the CPS prescribes one.
    pub head: Option<HeadSeries>,
}

/// Reports name each block with its number of sides (not every side), the
/// multipliers and the load-step timing.
impl serde::Serialize for ProjectLoads {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        #[derive(serde::Serialize)]
        struct Block<'a> {
            keyword: &'a str,
            sides: usize,
        }
        let blocks: Vec<Block> = self
            .blocks
            .iter()
            .map(|b| Block {
                keyword: &b.keyword,
                sides: b.sides.len(),
            })
            .collect();
        let mut s = serializer.serialize_struct("ProjectLoads", 7)?;
        s.serialize_field("blocks", &blocks)?;
        s.serialize_field("solid", &self.solid)?;
        s.serialize_field("liquid", &self.liquid)?;
        s.serialize_field("gravity", &self.gravity)?;
        s.serialize_field("load_steps", &self.load_steps)?;
        s.serialize_field("step_time", &self.step_time)?;
        s.serialize_field("head", &self.head)?;
        s.end()
    }
}

impl ProjectLoads {
    /// No block has a side and no water level is prescribed.
    pub fn is_empty(&self) -> bool {
        self.blocks.iter().all(|b| b.sides.is_empty()) && self.head.is_none()
    }

    /// The gravity multiplier at `time`.
    pub fn gravity_at(&self, time: f64) -> f64 {
        self.gravity.at(time, self.load_steps, self.step_time)
    }

    /// The multiplier of `phase`'s load system `system` at `time`.
    pub fn multiplier(&self, phase: LoadPhase, system: usize, time: f64) -> f64 {
        let m = match phase {
            LoadPhase::Solid => &self.solid[system.min(1)],
            LoadPhase::Liquid => &self.liquid[system.min(1)],
        };
        m.at(time, self.load_steps, self.step_time)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn m(kind: MultiplierKind, realised: f64, final_value: f64) -> Multiplier {
        Multiplier {
            kind,
            realised,
            final_value,
        }
    }

    #[test]
    fn step_multipliers_jump_at_each_load_step() {
        let s = m(MultiplierKind::Step, 0.0, 1.0);
        assert_eq!(s.at(1e-6, 1, 0.1), 1.0);
        assert_eq!(s.at(0.05, 4, 0.1), 0.25);
        assert_eq!(s.at(0.1, 4, 0.1), 0.25);
        assert_eq!(s.at(0.1000001, 4, 0.1), 0.5);
        assert_eq!(s.at(9.0, 4, 0.1), 1.0);
        assert_eq!(m(MultiplierKind::Off, 0.0, 1.0).at(0.05, 1, 0.1), 0.0);
    }

    #[test]
    fn heads_are_interpolated_between_rows_and_held_after_the_last() {
        let h = HeadSeries {
            area: [[0.0; 2]; 3],
            points: vec![(0.0, 2.0), (1.0, 1.0), (3.0, 1.0)],
        };
        assert_eq!(h.at(0.0), 2.0);
        assert!((h.at(0.25) - 1.75).abs() < 1e-12);
        assert_eq!(h.at(2.0), 1.0);
        assert_eq!(h.at(9.0), 1.0);
    }

    #[test]
    fn linear_multipliers_ramp_within_each_load_step() {
        let l = m(MultiplierKind::Linear, 0.0, 1.0);
        assert!((l.at(0.025, 1, 0.1) - 0.25).abs() < 1e-12);
        assert!((l.at(0.15, 2, 0.1) - 0.75).abs() < 1e-12);
        assert!((l.at(5.0, 2, 0.1) - 1.0).abs() < 1e-12);
        let from = m(MultiplierKind::Linear, 2.0, 4.0);
        assert!((from.at(0.05, 1, 0.1) - 3.0).abs() < 1e-12);
    }
}
