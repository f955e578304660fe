//! Vertex-interpolated (Gouraud) output over each input face's quadtree, with T-vertices resolved
//! (Baum et al. 1991 anchor such vertices; Cohen & Wallace 1993, ch. 8).
//!
//! A corner shared by leaves takes their area-weighted mean radiosity, B_v = Σ A_i B_i / Σ A_i over the leaves of
//! the face that have v as a corner. A T-vertex — a corner of finer leaves lying inside an edge (P, Q) of a
//! coarser leaf — instead takes the value the coarser leaf interpolates there, B_v = (B_P + B_Q)/2 (it is that
//! edge's lattice midpoint; deeper ones recurse), assigned coarsest edge first. Inside a leaf, radiosity is
//! bilinear in the quad's parameters or linear in the triangle's, so it is continuous across every edge of the
//! face. Faces do not share vertices: radiosity may jump between input faces (as it does across creases).

use std::collections::HashMap;

use glam::DVec2;
use radlab_scene::Rgb;

use crate::hierarchy::Engine;
use crate::node::NodeKind;
use crate::transport::Transport;

type Key = [u32; 2];

fn mid(a: Key, b: Key) -> Option<Key> {
    let (x, y) = (a[0] as u64 + b[0] as u64, a[1] as u64 + b[1] as u64);
    (x % 2 == 0 && y % 2 == 0 && a != b).then_some([(x / 2) as u32, (y / 2) as u32])
}

/// Corner radiosities of every leaf of the subtree under `root`, the node that is a whole input face (pairs of
/// leaf id and corner values). Leaves that are not quadtree elements get none.
pub fn face_corner_values<N: NodeKind, T: Transport<N>>(
    engine: &Engine<N, T>,
    root: u32,
) -> Vec<(u32, [Rgb; 4])> {
    let mut leaves = Vec::new();
    let mut stack = vec![root];
    while let Some(i) = stack.pop() {
        if engine.is_leaf(i) {
            leaves.push(i);
        } else {
            stack.extend(engine.children(i));
        }
    }
    leaves.sort_unstable();
    leaves.retain(|&i| engine.nodes()[i as usize].patch().is_some());
    let patch = |i: u32| {
        engine.nodes()[i as usize]
            .patch()
            .expect("retained patches")
    };
    let b = engine.radiosity();
    // Area-weighted means at corners.
    let mut sums: HashMap<Key, (Rgb, f64)> = HashMap::new();
    for &i in &leaves {
        let p = patch(i);
        for k in 0..p.corners() {
            let e = sums.entry(p.uv[k]).or_insert((Rgb::ZERO, 0.0));
            e.0 += p.area * b[i as usize];
            e.1 += p.area;
        }
    }
    let mut value: HashMap<Key, Rgb> = sums
        .iter()
        .map(|(k, (s, a))| (*k, if *a > 0.0 { *s / *a } else { Rgb::ZERO }))
        .collect();
    // T-vertices: lattice midpoints of leaf edges that are corners of other leaves.
    let mut constraints: Vec<(u64, Key, Key, Key)> = Vec::new();
    for &i in &leaves {
        let p = patch(i);
        let n = p.corners();
        for k in 0..n {
            let mut edges = vec![(p.uv[k], p.uv[(k + 1) % n])];
            while let Some((a, c)) = edges.pop() {
                if let Some(m) = mid(a, c)
                    && sums.contains_key(&m)
                {
                    let len = (a[0].abs_diff(c[0]) as u64).max(a[1].abs_diff(c[1]) as u64);
                    constraints.push((len, m, a, c));
                    edges.push((a, m));
                    edges.push((m, c));
                }
            }
        }
    }
    // Coarsest first, so both ends are final when a midpoint is set.
    constraints.sort_unstable_by(|x, y| y.0.cmp(&x.0).then(x.1.cmp(&y.1)));
    for (_, m, a, c) in constraints {
        let (va, vc) = (
            value.get(&a).copied().unwrap_or_default(),
            value.get(&c).copied().unwrap_or_default(),
        );
        value.insert(m, 0.5 * (va + vc));
    }
    leaves
        .iter()
        .map(|&i| {
            let p = patch(i);
            let mut v = [Rgb::ZERO; 4];
            for (k, slot) in v.iter_mut().enumerate().take(p.corners()) {
                *slot = value.get(&p.uv[k]).copied().unwrap_or_default();
            }
            (i, v)
        })
        .collect()
}

/// Interpolates corner values at parameter point `q` inside a leaf with parameter corners `c`.
pub fn interpolate(c: &[DVec2], values: &[Rgb; 4], q: DVec2) -> Rgb {
    if c.len() == 4 {
        // Axis-aligned lattice square: corners (s0,t0), (s1,t0), (s1,t1), (s0,t1).
        let (ds, dt) = (c[2].x - c[0].x, c[2].y - c[0].y);
        let sig = if ds != 0.0 {
            ((q.x - c[0].x) / ds).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let tau = if dt != 0.0 {
            ((q.y - c[0].y) / dt).clamp(0.0, 1.0)
        } else {
            0.5
        };
        return (1.0 - sig) * (1.0 - tau) * values[0]
            + sig * (1.0 - tau) * values[1]
            + sig * tau * values[2]
            + (1.0 - sig) * tau * values[3];
    }
    let (a, b, cc) = (c[0], c[1], c[2]);
    let det = (b - a).perp_dot(cc - a);
    if det == 0.0 {
        return (values[0] + values[1] + values[2]) / 3.0;
    }
    let l1 = ((q - a).perp_dot(cc - a) / det).max(0.0);
    let l2 = ((b - a).perp_dot(q - a) / det).max(0.0);
    let l0 = (1.0 - l1 - l2).max(0.0);
    let s = l0 + l1 + l2;
    (l0 * values[0] + l1 * values[1] + l2 * values[2]) / s
}
