//! Composite slip surfaces: a trial circle that dips below a material
//! interface follows the interface instead (the "composite" surfaces of
//! SLOPE/W, the weak-layer surfaces of Slide2). A block sliding along a thin
//! weak layer is reached neither by circles nor by moving a circle's
//! vertices one at a time; clipping the best circles at each interface
//! reaches it directly, and the vertex moves then refine it. No I/O.

use std::collections::HashMap;

use super::geometry::{Domain, polyline_y};
use super::surface::{Circle, Surface};

/// Most interface paths kept (a mesh with many material changes could
/// otherwise branch without bound).
const MAX_PATHS: usize = 64;

/// A quantised point.
type Key = (i64, i64);
/// An edge, left end first.
type Edge = [[f64; 2]; 2];

/// The material interfaces of `domain` as x-monotone polylines, left to
/// right: chains of the edges that two regions of different materials
/// share (vertical edges are left out; a chain branches where edges do).
pub fn interfaces(domain: &Domain) -> Vec<Vec<[f64; 2]>> {
    let (x0, x1) = domain.x_range();
    let quantum = 1e-9 * (x1 - x0).max(f64::MIN_POSITIVE);
    let key = |p: [f64; 2]| {
        (
            (p[0] / quantum).round() as i64,
            (p[1] / quantum).round() as i64,
        )
    };
    // Edge (left, right) → (points, materials seen).
    let mut edges: HashMap<(Key, Key), (Edge, Vec<usize>)> = HashMap::new();
    for r in domain.regions() {
        let n = r.polygon.len();
        for i in 0..n {
            let (p, q) = (r.polygon[i], r.polygon[(i + 1) % n]);
            let (a, b) = if p[0] <= q[0] { (p, q) } else { (q, p) };
            let (ka, kb) = (key(a), key(b));
            if ka.0 == kb.0 {
                continue; // vertical
            }
            edges
                .entry((ka, kb))
                .or_insert_with(|| ([a, b], Vec::new()))
                .1
                .push(r.material);
        }
    }
    let mut outgoing: HashMap<Key, Vec<(Key, Edge)>> = HashMap::new();
    let mut has_incoming: std::collections::HashSet<Key> = Default::default();
    let mut kept: Vec<_> = edges
        .into_iter()
        .filter(|(_, (_, m))| m.len() == 2 && m[0] != m[1])
        .collect();
    // Deterministic order whatever the hash map's.
    kept.sort_by_key(|(k, _)| *k);
    for ((ka, kb), (pts, _)) in kept {
        outgoing.entry(ka).or_default().push((kb, pts));
        has_incoming.insert(kb);
    }
    let mut starts: Vec<Key> = outgoing
        .keys()
        .filter(|k| !has_incoming.contains(k))
        .copied()
        .collect();
    starts.sort();
    let mut paths = Vec::new();
    for s in starts {
        let mut stack: Vec<(Key, Vec<[f64; 2]>)> = vec![(s, Vec::new())];
        while let Some((at, path)) = stack.pop() {
            if paths.len() >= MAX_PATHS {
                return paths;
            }
            match outgoing.get(&at) {
                None => {
                    if path.len() >= 2 {
                        paths.push(path);
                    }
                }
                Some(next) => {
                    for (kb, [a, b]) in next.iter().rev() {
                        let mut p = path.clone();
                        if p.is_empty() {
                            p.push(*a);
                        }
                        p.push(*b);
                        stack.push((*kb, p));
                    }
                }
            }
        }
    }
    paths
}

/// The circle's surface (`traced`, from [`Circle::trace`]) held up at the
/// interface `line` lowered by `drop` (≥ 0: 0 slides on the interface with
/// the strength of the region above it, a small drop with that of the
/// region below): y = max(circle, line − drop). `None` when the circle
/// stays above the line, or would have to step vertically onto it (the line
/// ends where the circle is below it), or the result touches the ground.
pub fn clip(
    circle: &Circle,
    traced: &Surface,
    line: &[[f64; 2]],
    drop: f64,
    domain: &Domain,
) -> Option<Surface> {
    let n = traced.points.len();
    let (xa, xb) = (traced.points[0][0], traced.points[n - 1][0]);
    let (l0, l1) = (line[0][0], line[line.len() - 1][0]);
    let (lo, hi) = (xa.max(l0), xb.min(l1));
    if lo >= hi {
        return None;
    }
    // Positive where the circle is below the lowered line.
    let g = |x: f64| polyline_y(line, x).map(|y| y - drop - circle.lower(x));
    let mut xs: Vec<f64> = traced.points.iter().map(|p| p[0]).collect();
    xs.extend(line.iter().map(|p| p[0]).filter(|&x| x > lo && x < hi));
    xs.push(lo);
    xs.push(hi);
    xs.sort_by(f64::total_cmp);
    xs.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * (xb - xa));
    let inside: Vec<f64> = xs.iter().copied().filter(|&x| x >= lo && x <= hi).collect();
    let gv: Vec<f64> = inside.iter().map(|&x| g(x).unwrap_or(f64::MIN)).collect();
    if gv.iter().all(|&v| v <= 0.0) {
        return None;
    }
    // A positive value at an end of the line inside the circle's span would
    // need a vertical step.
    if (l0 > xa && gv[0] > 0.0) || (l1 < xb && gv[gv.len() - 1] > 0.0) {
        return None;
    }
    // The crossings, by bisection on each sign change.
    for w in inside.windows(2).zip(gv.windows(2)) {
        let ([a, b], [ga, gb]) = (w.0, w.1) else {
            continue;
        };
        if (*ga > 0.0) != (*gb > 0.0) {
            let (mut a, mut b, mut fa) = (*a, *b, *ga);
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                let fm = g(m).unwrap_or(f64::MIN);
                if (fm > 0.0) == (fa > 0.0) {
                    a = m;
                    fa = fm;
                } else {
                    b = m;
                }
            }
            xs.push(0.5 * (a + b));
        }
    }
    xs.sort_by(f64::total_cmp);
    xs.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * (xb - xa));
    let mut points = Vec::with_capacity(xs.len());
    for (i, &x) in xs.iter().enumerate() {
        let mut y = circle.lower(x);
        if i == 0 || i == xs.len() - 1 {
            y = traced.points[if i == 0 { 0 } else { n - 1 }][1];
        } else if let Some(v) = g(x).filter(|v| *v > 0.0) {
            y += v;
        }
        points.push([x, y]);
    }
    let below_ground = points[1..points.len() - 1]
        .iter()
        .all(|p| domain.ground_y(p[0]).is_some_and(|gy| p[1] < gy));
    below_ground.then_some(Surface {
        points,
        axis: [circle.xc, circle.yc],
        circle: None,
    })
}

#[cfg(test)]
mod tests {
    use super::super::geometry::Region;
    use super::*;

    /// A block of soil 0 over a band of soil 1 over soil 0: two horizontal
    /// interfaces, y = 4 and y = 5, under a flat ground at y = 10.
    fn layered() -> Domain {
        let r = |y0: f64, y1: f64, m: usize| Region {
            polygon: vec![[0.0, y0], [20.0, y0], [20.0, y1], [0.0, y1]],
            material: m,
            unit_weight: 20.0,
        };
        Domain::from_polygons(vec![r(0.0, 4.0, 0), r(4.0, 5.0, 1), r(5.0, 10.0, 0)]).unwrap()
    }

    #[test]
    fn interfaces_are_the_edges_between_materials() {
        let mut found = interfaces(&layered());
        found.sort_by(|a, b| a[0][1].total_cmp(&b[0][1]));
        assert_eq!(
            found,
            vec![vec![[0.0, 4.0], [20.0, 4.0]], vec![[0.0, 5.0], [20.0, 5.0]]]
        );
        // The same material on both sides is no interface.
        let r = |y0: f64, y1: f64| Region {
            polygon: vec![[0.0, y0], [20.0, y0], [20.0, y1], [0.0, y1]],
            material: 0,
            unit_weight: 20.0,
        };
        let d = Domain::from_polygons(vec![r(0.0, 5.0), r(5.0, 10.0)]).unwrap();
        assert!(interfaces(&d).is_empty());
    }

    #[test]
    fn a_circle_below_an_interface_follows_it() {
        let d = layered();
        let c = Circle {
            xc: 10.0,
            yc: 12.0,
            r: 9.0,
        };
        let traced = c.trace(&d, 20).unwrap();
        let line = [[0.0, 5.0], [20.0, 5.0]];
        let s = clip(&c, &traced, &line, 0.0, &d).unwrap();
        assert_eq!(s.points[0], traced.points[0]);
        assert_eq!(s.points[s.points.len() - 1], traced.points[20]);
        for p in &s.points {
            let want = c.lower(p[0]).max(5.0);
            if p[0] > s.points[0][0] && p[0] < s.points[s.points.len() - 1][0] {
                assert!((p[1] - want).abs() < 1e-9, "{p:?} vs {want}");
            }
        }
        // Both crossings x = 10 ± √(81 − 49) are vertices.
        let x = 32.0_f64.sqrt();
        for xc in [10.0 - x, 10.0 + x] {
            assert!(s.points.iter().any(|p| (p[0] - xc).abs() < 1e-9));
        }
        // A circle that stays above the line is left alone.
        let shallow = Circle {
            xc: 10.0,
            yc: 14.0,
            r: 6.0,
        };
        let t = shallow.trace(&d, 20).unwrap();
        assert!(clip(&shallow, &t, &line, 0.0, &d).is_none());
    }
}
