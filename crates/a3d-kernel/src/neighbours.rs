//! The only place that touches kiddo and squared distances. Callers pass a
//! physical radius and get physical distances back, sorted by (distance, index)
//! so every sum over neighbours runs in a fixed order.

use kiddo::{ImmutableKdTree, SquaredEuclidean};

enum Tree {
    Two(ImmutableKdTree<f64, 2>),
    Three(ImmutableKdTree<f64, 3>),
    /// Fewer than one point: kiddo cannot build an empty tree.
    Empty,
}

/// A k-d tree over a fixed point cloud in 2D (x, y) or 3D (x, y, z).
pub struct NeighbourIndex {
    tree: Tree,
    len: usize,
}

impl NeighbourIndex {
    /// Builds the index. `dim` is 2 (z ignored) or 3.
    pub fn new(points: &[[f64; 3]], dim: usize) -> NeighbourIndex {
        let tree = if points.is_empty() {
            Tree::Empty
        } else if dim == 2 {
            let pts: Vec<[f64; 2]> = points.iter().map(|p| [p[0], p[1]]).collect();
            ImmutableKdTree::new_from_slice(&pts).map_or(Tree::Empty, Tree::Two)
        } else {
            ImmutableKdTree::new_from_slice(points).map_or(Tree::Empty, Tree::Three)
        };
        NeighbourIndex {
            tree,
            len: points.len(),
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// All points within `radius` of `q` (inclusive) as (index, distance),
    /// sorted by distance then index. `out` is cleared first.
    pub fn within(&self, q: [f64; 3], radius: f64, out: &mut Vec<(u32, f64)>) {
        out.clear();
        let r2 = radius * radius;
        match &self.tree {
            Tree::Two(t) => {
                for item in t
                    .query(&[q[0], q[1]])
                    .within::<SquaredEuclidean<f64>>(r2)
                    .unsorted()
                    .execute()
                {
                    out.push((item.item, item.distance.sqrt()));
                }
            }
            Tree::Three(t) => {
                for item in t
                    .query(&q)
                    .within::<SquaredEuclidean<f64>>(r2)
                    .unsorted()
                    .execute()
                {
                    out.push((item.item, item.distance.sqrt()));
                }
            }
            Tree::Empty => {}
        }
        out.sort_unstable_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    }

    /// The distance from `q` to its second-nearest point (the nearest *other*
    /// point when `q` is one of the indexed points; 0 for a duplicate). `None`
    /// with fewer than two points.
    pub fn second_nearest_distance(&self, q: [f64; 3]) -> Option<f64> {
        let two = std::num::NonZeroUsize::new(2)?;
        let d2 = match &self.tree {
            Tree::Two(t) => t
                .query(&[q[0], q[1]])
                .nearest_n::<SquaredEuclidean<f64>>(two)
                .execute()
                .get(1)
                .map(|r| r.distance),
            Tree::Three(t) => t
                .query(&q)
                .nearest_n::<SquaredEuclidean<f64>>(two)
                .execute()
                .get(1)
                .map(|r| r.distance),
            Tree::Empty => None,
        };
        d2.map(f64::sqrt)
    }

    /// The nearest point to `q`: (index, distance).
    pub fn nearest(&self, q: [f64; 3]) -> Option<(u32, f64)> {
        match &self.tree {
            Tree::Two(t) => {
                let r = t
                    .query(&[q[0], q[1]])
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute();
                Some((r.item, r.distance.sqrt()))
            }
            Tree::Three(t) => {
                let r = t.query(&q).nearest_one::<SquaredEuclidean<f64>>().execute();
                Some((r.item, r.distance.sqrt()))
            }
            Tree::Empty => None,
        }
    }
}

/// Brute-force oracle for tests: the same contract as [`NeighbourIndex::within`].
pub fn within_brute_force(
    points: &[[f64; 3]],
    dim: usize,
    q: [f64; 3],
    radius: f64,
) -> Vec<(u32, f64)> {
    let mut out: Vec<(u32, f64)> = points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| {
            let d2: f64 = (0..dim).map(|k| (p[k] - q[k]) * (p[k] - q[k])).sum();
            (d2 <= radius * radius).then(|| (i as u32, d2.sqrt()))
        })
        .collect();
    out.sort_unstable_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    out
}
