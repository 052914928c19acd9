//! Checks on a set of node coordinates that the readers apply: a node far
//! outside the others, whose extent cannot be meant ([`far_outlier`]:
//! FEM tables, the mesh nodes a `node.csv` is joined to, GOM nodes), and
//! coincident nodes ([`first_coincident`]: FEM tables and joined mesh
//! nodes). Both take any finite coordinates (no overflow) and cost at most
//! O(n log n).

use rayon::prelude::*;

/// A pair of coincident points, within 1e-9 of the bounding-box diagonal on
/// every axis, as (earlier, later) indices; `None` when all points are apart.
/// Used for node tables and for the mesh nodes a `node.csv` is joined to.
///
/// The points are swept in the order of a skew coordinate x + φy + ψz (φ, ψ
/// irrational), so that the rows and columns of a structured mesh, which
/// share an x, do not all fall in one band of the sweep; the pair returned is
/// the first found in that order. Any finite coordinates work (the diagonal
/// and the sweep coordinate are computed without overflow).
pub fn first_coincident(positions: &[[f64; 3]]) -> Option<(usize, usize)> {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if positions.len() < 2 {
        return None;
    }
    let extent = [0, 1, 2].map(|k| (hi[k] - lo[k]).min(f64::MAX));
    let mut diag = (extent[0].powi(2) + extent[1].powi(2) + extent[2].powi(2)).sqrt();
    if !diag.is_finite() {
        // Scaled by the largest extent, so the squares cannot overflow.
        let m = extent[0].max(extent[1]).max(extent[2]);
        diag = (m * extent.iter().map(|e| (e / m).powi(2)).sum::<f64>().sqrt()).min(f64::MAX);
    }
    let tol = 1e-9 * diag.max(1e-300);
    const PHI: f64 = 0.754_877_666_246_692_7;
    const PSI: f64 = 0.569_840_290_998_053_2;
    // Eighths, so that neither the differences nor their sum can overflow.
    let skew = |p: &[f64; 3]| {
        (p[0] / 8.0 - lo[0] / 8.0)
            + PHI * (p[1] / 8.0 - lo[1] / 8.0)
            + PSI * (p[2] / 8.0 - lo[2] / 8.0)
    };
    let mut order: Vec<(f64, u32)> = positions
        .par_iter()
        .enumerate()
        .map(|(i, p)| (skew(p), i as u32))
        .collect();
    order.par_sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    // Coincident points differ by at most `band` in the skew coordinate
    // (widened for the rounding of the sums, a few ulps of the extent).
    let band = tol / 8.0 * (1.0 + PHI + PSI) + 4.0 * f64::EPSILON * diag;
    for (k, &(sa, a)) in order.iter().enumerate() {
        let pa = positions[a as usize];
        for &(sb, b) in &order[k + 1..] {
            let gap = sb - sa;
            if gap.is_nan() || gap > band {
                break;
            }
            let pb = positions[b as usize];
            if (pa[0] - pb[0]).abs() <= tol
                && (pa[1] - pb[1]).abs() <= tol
                && (pa[2] - pb[2]).abs() <= tol
            {
                let (a, b) = (a as usize, b as usize);
                return Some((a.min(b), a.max(b)));
            }
        }
    }
    None
}

/// A node far outside the others, from [`far_outlier`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FarNode {
    /// Index of the node.
    pub index: usize,
    /// The axis (0, 1, 2) and the coordinate on it.
    pub axis: usize,
    pub value: f64,
    /// The largest median absolute deviation of the nodes' coordinates (m):
    /// half the nodes lie within it of the median on that axis.
    pub spread: f64,
}

impl std::fmt::Display for FarNode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} = {:?} lies more than 10^6 times the spread of the nodes away from them (half of them lie within {:.4} m of their median): a coordinate that cannot be meant",
            ["x", "y", "z"][self.axis],
            self.value,
            self.spread
        )
    }
}

/// The first node (in the given order) farther from the median on some axis
/// than 10^6 times the spread of the nodes (the largest of the axes' median
/// absolute deviations, which one far node cannot inflate however few the
/// nodes are, unlike an interquartile range of four), or `None`. Such an extent cannot be meant (one
/// node at 1e308 beside a slope of 50 m): it would also make every other pair
/// of nodes coincident within 1e-9 of the diagonal, and a grid or bins sized
/// by the extent useless, so the readers refuse it first. The medians
/// come from at most about 4096 evenly strided nodes: O(n) with a small
/// constant, and deterministic.
pub fn far_outlier(positions: &[[f64; 3]]) -> Option<FarNode> {
    let n = positions.len();
    if n < 3 {
        return None;
    }
    let stride = n.div_ceil(4096);
    let mut median = [0.0; 3];
    // Half the largest median absolute deviation, from halves (no overflow).
    let mut half_spread = 0.0f64;
    for k in 0..3 {
        let mut v: Vec<f64> = positions.iter().step_by(stride).map(|p| p[k]).collect();
        let m = v.len();
        let mid = *v.select_nth_unstable_by(m / 2, f64::total_cmp).1;
        median[k] = mid;
        let mut deviations: Vec<f64> = v.iter().map(|x| (x / 2.0 - mid / 2.0).abs()).collect();
        half_spread = half_spread.max(*deviations.select_nth_unstable_by(m / 2, f64::total_cmp).1);
    }
    if !(half_spread > 0.0 && half_spread.is_finite()) {
        return None;
    }
    let limit = 1e6 * half_spread;
    positions.iter().enumerate().find_map(|(index, p)| {
        (0..3)
            .find(|&k| (p[k] / 2.0 - median[k] / 2.0).abs() > limit)
            .map(|axis| FarNode {
                index,
                axis,
                value: p[axis],
                spread: 2.0 * half_spread,
            })
    })
}
