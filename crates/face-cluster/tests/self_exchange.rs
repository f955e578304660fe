//! The traced self-exchange against closed forms: a convex body inside an enclosure sends all its light to the
//! enclosure (F = 1) and none onto itself, so by reciprocity the enclosure sends the share A_in/A_out to the
//! body and keeps 1 − A_in/A_out for itself (Siegel & Howell, enclosure and reciprocity relations).

use radlab_face_cluster::{FaceClusterParams, FaceClusterTree, Landing, SELF_RAYS, SelfExchange};
use radlab_method::MethodParams;
use radlab_scene::{Rgb, builtin};
use radlab_visibility::Accel;

/// The concentric-spheres scene's two roots, inner (facing out) first, with their traced self-shares.
fn concentric(threads: usize) -> (FaceClusterTree, SelfExchange) {
    let scene = builtin("concentric-spheres?faces=2000").expect("scene");
    let accel = Accel::new(&scene);
    let tree = FaceClusterTree::build(&scene, &FaceClusterParams::default()).expect("tree");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    let x = pool.install(|| SelfExchange::trace(&tree, &scene, &accel, 3, SELF_RAYS));
    (tree, x)
}

/// Σ_C A_C ratio_C over the children of node `p`: the area its traced light covers once pushed down by
/// `which` landing ratio (A_P when the total is kept).
fn kept_by(tree: &FaceClusterTree, x: &SelfExchange, which: Landing, p: usize) -> f64 {
    let a = tree.node(p).area;
    tree.node(p)
        .children()
        .map(|c| tree.node(c).area * x.landing_ratio(which, p, c, a, tree.node(c).area))
        .sum()
}

#[test]
fn an_enclosure_keeps_what_the_body_inside_does_not_take() {
    let (tree, x) = concentric(2);
    let roots: Vec<usize> = tree.roots().collect();
    assert_eq!(roots.len(), 2);
    let (inner, outer) = {
        let (a, b) = (roots[0], roots[1]);
        if tree.node(a).area < tree.node(b).area {
            (a, b)
        } else {
            (b, a)
        }
    };
    let (a_in, a_out) = (tree.node(inner).area, tree.node(outer).area);
    // No ray from a convex surface returns to it.
    assert_eq!(x.onto_itself[inner], 0.0);
    // F_out,out = 1 − A_in/A_out in expectation. Each face i casts n_i ≥ 65,536 A_i/A_total rays of weight
    // A_i/n_i, each a Bernoulli trial, so the estimate's variance is at most Σ A_i²/(4 n_i) ≤ A_out A_total /
    // (4 · 65,536), over A_out²: a standard deviation of at most √(A_total / (4 · 65,536 · A_out)).
    let f = x.onto_itself[outer] / a_out;
    let want = 1.0 - a_in / a_out;
    let sigma = ((a_in + a_out) / (4.0 * 65_536.0 * a_out)).sqrt();
    assert!(
        (f - want).abs() <= 4.0 * sigma,
        "F_out,out = {f}, want {want} ± {:.2e}",
        4.0 * sigma
    );
}

/// What lands on a node's faces from its own mesh: at a root that is everything the mesh sends onto itself
/// (the same rays as its self form factor, summed another way), at a convex root nothing, and below a root
/// the children's landings add up to their parent's, so pushing a traced exchange down by the landing ratio
/// keeps its total: Σ_C A_C ratio_C = A_P at every node that received any.
#[test]
fn landings_add_up_and_pushing_by_them_keeps_the_total() {
    let (tree, x) = concentric(2);
    for r in tree.roots() {
        let (l, f) = (x.landed[r], x.onto_itself[r]);
        assert!(
            (l - f).abs() <= 1e-9 * f.max(1e-300),
            "root {r}: {l} vs {f}"
        );
    }
    let mut checked = 0;
    for (p, node) in tree.nodes().iter().enumerate() {
        if node.is_leaf() || x.landed[p] <= 0.0 {
            continue;
        }
        let kept = kept_by(&tree, &x, Landing::Mesh, p);
        assert!(
            (kept - node.area).abs() <= 1e-9 * node.area,
            "node {p}: {kept} vs {}",
            node.area
        );
        checked += 1;
    }
    assert!(checked > 100, "only {checked} nodes received any light");
}

/// What a node's sibling sends onto it lands on its children: at every inner node that received any, the
/// children's shares of it add up to it (Σ_C U_C = S_P), so pushing by the sibling ratio keeps its total,
/// Σ_C A_C ratio_C = A_P; and nothing a sibling sends lands outside the pair (S of a root is zero).
#[test]
fn a_sibling_s_light_lands_on_the_children_and_is_kept() {
    let (tree, x) = concentric(2);
    for r in tree.roots() {
        assert_eq!(x.from_sibling[r], 0.0);
    }
    let mut checked = 0;
    for (p, node) in tree.nodes().iter().enumerate() {
        if node.is_leaf() || x.from_sibling[p] <= 0.0 {
            continue;
        }
        let landed: f64 = node.children().map(|c| x.from_uncle[c]).sum();
        let (s, a) = (x.from_sibling[p], node.area);
        assert!((landed - s).abs() <= 1e-9 * s, "node {p}: {landed} vs {s}");
        let kept = kept_by(&tree, &x, Landing::Sibling, p);
        assert!((kept - a).abs() <= 1e-9 * a, "node {p}: {kept} vs {a}");
        checked += 1;
    }
    assert!(
        checked > 100,
        "only {checked} nodes received light from a sibling"
    );
}

/// What lands on a node from beyond its parent (the rays whose deepest common node is above the parent:
/// L − A F_NN less what the sibling and the uncle sent) lands on its children from beyond their grandparent
/// or from their uncle: Σ_C (L_C − A_C F_CC − S_C − U_C) = L_P − A_P F_PP − S_P, so pushing by the outside
/// ratio keeps the total, Σ_C A_C ratio_C = A_P; and a root receives nothing from beyond itself.
#[test]
fn light_from_beyond_a_node_lands_on_its_children_and_is_kept() {
    let (tree, x) = concentric(2);
    let beyond = |n: usize| x.landed[n] - x.onto_itself[n];
    for r in tree.roots() {
        assert!(
            beyond(r).abs() <= 1e-9 * x.landed[r].max(1e-300),
            "root {r}"
        );
    }
    let mut checked = 0;
    for (p, node) in tree.nodes().iter().enumerate() {
        let from_beyond = beyond(p) - x.from_sibling[p];
        if node.is_leaf() || from_beyond <= 1e-6 * x.landed[p] {
            continue;
        }
        let landed: f64 = node
            .children()
            .map(|c| beyond(c) - x.from_sibling[c] - x.from_uncle[c])
            .sum();
        assert!(
            (landed - from_beyond).abs() <= 1e-9 * x.landed[p],
            "node {p}: {landed} vs {from_beyond}"
        );
        let a = node.area;
        let kept = kept_by(&tree, &x, Landing::Outside, p);
        assert!((kept - a).abs() <= 1e-6 * a, "node {p}: {kept} vs {a}");
        checked += 1;
    }
    assert!(
        checked > 100,
        "only {checked} nodes received light from beyond their parent"
    );
}

/// Inside a sphere every face receives the same share of what the sphere sends (F_ij = A_j/(4πR²); the
/// inner sphere of the concentric pair shades every part of the outer one alike), so the true landing ratio
/// of every child is one and what the trace's ratios depart from it is noise, about 1/√n for n rays landed.
/// Push hands light down by ratios shrunk toward one by that noise: they keep each node's total exactly and
/// depart from one by less than half as much as the raw ratios.
#[test]
fn inside_a_sphere_push_hands_light_down_evenly_despite_the_trace_s_noise() {
    let (tree, x) = concentric(2);
    let outer = tree
        .roots()
        .max_by(|&a, &b| tree.node(a).area.total_cmp(&tree.node(b).area))
        .expect("two roots");
    let (mut raw, mut shrunk, mut noise, mut area) = (0.0, 0.0, 0.0, 0.0);
    let mut stack = vec![outer];
    while let Some(p) = stack.pop() {
        let node = tree.node(p);
        if node.is_leaf() {
            continue;
        }
        let mut kept = 0.0;
        for c in node.children() {
            let ac = tree.node(c).area;
            let r = x.landing_ratio(Landing::Mesh, p, c, node.area, ac);
            let (s, _) = x.hand_down(c, [Rgb::ONE, Rgb::ZERO, Rgb::ZERO]);
            raw += ac * (r - 1.0).abs();
            // A ratio from n rays: relative standard deviation about 1/√n, mean absolute deviation √(2/π)
            // of that for a normal variable.
            let n = f64::from(x.landed_rays[c].max(1));
            noise += ac * (2.0 / std::f64::consts::PI).sqrt() / n.sqrt();
            shrunk += ac * (s.x - 1.0).abs();
            area += ac;
            kept += ac * s.x;
            stack.push(c);
        }
        assert!(
            (kept - node.area).abs() <= 1e-9 * node.area,
            "node {p}: {kept}"
        );
    }
    let (raw, shrunk, noise) = (raw / area, shrunk / area, noise / area);
    // The raw ratios depart from one by about their noise (the parent's own noise adds a little).
    assert!(
        raw > 0.5 * noise && raw < 2.0 * noise,
        "raw {raw} against noise {noise}"
    );
    assert!(shrunk < 0.5 * raw, "shrunk {shrunk} against raw {raw}");
}

#[test]
fn one_and_two_threads_trace_the_same_bits() {
    let (_, one) = concentric(1);
    let (_, two) = concentric(2);
    assert_eq!(one, two);
}

/// An unknown choice of `self_exchange` or `irradiance_field` is refused with the key and a value it takes.
#[test]
fn a_bad_choice_names_the_key() {
    for (key, value, allowed) in [
        ("self_exchange", "sometimes", "traced"),
        ("irradiance_field", "quadratic", "linear"),
    ] {
        let bad = radlab_face_cluster::FaceClusterSolveParams::from_pairs(&[(
            key.to_string(),
            value.to_string(),
        )]);
        let message = bad.expect_err("an unknown value").to_string();
        assert!(
            message.contains(key) && message.contains(allowed),
            "{message}"
        );
    }
}

/// `self_rays` outside 1..=1024, or not a whole number, is refused with the key and the range named.
#[test]
fn a_bad_ray_count_names_the_key() {
    for v in ["0", "2000", "2.5", "\"many\""] {
        let table: toml::Table = toml::from_str(&format!("self_rays = {v}")).expect("toml");
        let bad = radlab_face_cluster::FaceClusterSolveParams::from_table(table);
        let message = bad.expect_err("a bad ray count").to_string();
        assert!(
            message.contains("self_rays") && message.contains("1..=1024"),
            "{v}: {message}"
        );
    }
}
