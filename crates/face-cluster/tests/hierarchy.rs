//! Face-cluster hierarchies against answers nobody chose: the M identity at every node, tessellation
//! invariance of M and p_E on a planar quad, roots of non-manifold and disconnected meshes, layout
//! invariants, bounds that hold their faces, scale invariance, thread-count determinism, the cache round trip.

use glam::{DVec3, dvec3};
use radlab_face_cluster::{
    FaceClusterError, FaceClusterParams, FaceClusterTree, bounds::angle_between, digest,
};
use radlab_scene::{Material, Scene, SceneBuilder, builtin, sampling};
use radlab_testkit::scaled;

fn build(scene: &Scene) -> FaceClusterTree {
    FaceClusterTree::build(scene, &FaceClusterParams::default()).expect("builds")
}

fn bumpy() -> Scene {
    builtin("bumpy-sphere?faces=2000").expect("builtin")
}

fn terrain() -> Scene {
    builtin("terrain?faces=2000").expect("builtin")
}

/// Per node: first face, face count, first child, parent.
type NodeShape = (usize, usize, usize, Option<usize>);

/// The tree's shape: every node's [`NodeShape`] and the face order.
fn shape(t: &FaceClusterTree) -> (Vec<NodeShape>, Vec<u32>) {
    let nodes = t
        .nodes()
        .iter()
        .map(|n| {
            (
                n.faces().start,
                n.faces().len(),
                n.children().start,
                n.parent(),
            )
        })
        .collect();
    (nodes, t.face_order().to_vec())
}

/// Checks layout invariants: the roots' face ranges tile 0..k, children tile their parent's range in
/// order, parents precede children, leaves are single faces, the face order is a permutation.
fn assert_layout(scene: &Scene, t: &FaceClusterTree) {
    let k = scene.face_count();
    let mut seen = vec![false; k];
    for &f in t.face_order() {
        assert!(
            !std::mem::replace(&mut seen[f as usize], true),
            "face {f} twice"
        );
    }
    assert!(seen.iter().all(|&s| s));
    let mut at = 0;
    for r in t.roots() {
        let n = t.node(r);
        assert_eq!(n.parent(), None);
        assert_eq!(n.faces().start, at);
        at = n.faces().end;
    }
    assert_eq!(at, k);
    for (i, n) in t.nodes().iter().enumerate() {
        if i >= t.roots().end {
            let p = n.parent().expect("non-root has a parent");
            assert!(p < i && t.node(p).children().contains(&i));
        }
        if n.is_leaf() {
            assert_eq!(n.faces().len(), 1);
            assert_eq!(t.leaf_of_face(t.faces_of(i)[0] as usize), i);
            continue;
        }
        assert_eq!(n.children().len(), 2);
        assert!(n.children().start > i);
        let mut at = n.faces().start;
        for c in n.children() {
            assert_eq!(t.node(c).faces().start, at, "node {i} child {c}");
            at = t.node(c).faces().end;
        }
        assert_eq!(at, n.faces().end);
    }
}

#[test]
fn layout_is_contiguous_and_nested() {
    for scene in [bumpy(), terrain()] {
        let t = build(&scene);
        assert_layout(&scene, &t);
        assert_eq!(t.nodes().len(), 2 * scene.face_count() - t.roots().len());
    }
}

/// Greedy contraction is not balanced by construction, but regions growing in step keep the depth growing
/// like log k; a region taking in its neighbours one face at a time (the failure the balance and planarity
/// normalisation prevent) makes it grow like √k or k instead. From 10³ to 3.2·10⁴ faces log₂ k grows 1.5-fold
/// and √k 5.7-fold; the depth must grow by less than their geometric mean, 2.9 (measured: bumpy sphere 14 → 24,
/// terrain 18 → 31, concentric spheres 13 → 19). At a few thousand faces an absolute bound cannot tell the
/// two apart (4 log₂ k and √k are both about 44 at 2,000 faces).
/// Tree depths of `builtin:QUERY&faces=k` at 10³ and 3.2·10⁴ faces, their ratio, and the bound that ratio must
/// stay under: the geometric mean of log₂ k's growth and √k's between the two face counts.
fn depth_growth(query: &str) -> (f64, f64, f64) {
    let depth = |k: usize| {
        let scene = builtin(&format!("{query}&faces={k}")).expect("builtin");
        (build(&scene).depth() as f64, scene.face_count() as f64)
    };
    let ((d0, k0), (d1, k1)) = (depth(1_000), depth(32_000));
    let (log_growth, sqrt_growth) = (k1.log2() / k0.log2(), (k1 / k0).sqrt());
    (d0, d1, (log_growth * sqrt_growth).sqrt())
}

#[test]
fn trees_stay_shallow() {
    for family in ["bumpy-sphere", "terrain", "concentric-spheres"] {
        let (d0, d1, bound) = depth_growth(&format!("{family}?"));
        assert!(
            d1 / d0 < bound,
            "{family}: depth {d0} → {d1}, {:.2}-fold against {bound:.2}",
            d1 / d0
        );
    }
}

/// Stranded regions (every neighbour at least four times larger) merge as soon as they are stranded, not at the
/// top of the tree: the 10⁵-face terrain stays within 4 log₂ k = 66 levels (34 measured; 104 when its stranded
/// pairs and quads were left to the queue and the last regions took them in one at a time).
#[test]
fn stranded_regions_do_not_pile_up_at_the_top() {
    let scene = builtin("terrain?faces=100000").expect("builtin");
    let t = build(&scene);
    let bound = 4.0 * (scene.face_count() as f64).log2();
    assert!(
        (t.depth() as f64) <= bound,
        "depth {} for {} faces, bound {bound:.1}",
        t.depth(),
        scene.face_count()
    );
}

/// Known failure, kept to be fixed: on a gently rolling surface (the terrain at a tenth of its relief) the
/// contraction still degenerates as [`trees_stay_shallow`] describes: depth 22 at 10³ faces and 94 at
/// 3.2·10⁴, 4.3-fold where √k gives 5.7 (285 before stranded regions were merged early). Near the top of the
/// tree regions of tens to thousands of faces are taken in one at a time by the largest; neither scaling the
/// balance term by the fit nor clamping or re-basing the shape term helped (measured 2026-12-01).
#[test]
#[ignore = "known failure: the contraction degenerates on gently rolling terrain (depth 94 at 3.2e4 faces)"]
fn trees_stay_shallow_on_gentle_terrain() {
    let (d0, d1, bound) = depth_growth("terrain?octaves=4&relief=0.1");
    assert!(d1 / d0 < bound, "depth {d0} → {d1}, bound {bound:.2}-fold");
}

/// Σ (E_i + ρ_i n_i·e) A_i n_i over a node's faces equals p_E + M e when every n_i·e ≥ 0 (Willmott et al.
/// 1999), at every node whose normal cone is narrower than a hemisphere, for random such e.
#[test]
fn power_vector_identity_holds_at_every_node() {
    let scene = bumpy();
    let t = build(&scene);
    let mut r = sampling::rng(7, 0);
    let mut checked = 0;
    for (i, n) in t.nodes().iter().enumerate() {
        let spare = std::f64::consts::FRAC_PI_2 - n.cone.half_angle;
        if spare <= 0.0 {
            continue;
        }
        // e within the cone's dual: at most `spare` from the axis, random magnitude per channel.
        let (b1, b2) = sampling::basis(n.cone.axis);
        let e: [DVec3; 3] = std::array::from_fn(|_| {
            let th = spare * sampling::uniform(&mut r);
            let ph = std::f64::consts::TAU * sampling::uniform(&mut r);
            let d = n.cone.axis * th.cos() + (b1 * ph.cos() + b2 * ph.sin()) * th.sin();
            d * (10.0 * sampling::uniform(&mut r))
        });
        let got = n.power_vector(e);
        for c in 0..3 {
            let (mut sum, mut scale) = (DVec3::ZERO, 0.0);
            for &f in t.faces_of(i) {
                let face = &scene.faces[f as usize];
                let (rho, em) = (
                    scene.reflectance(f as usize)[c],
                    scene.emission(f as usize)[c],
                );
                let cos = face.normal.dot(e[c]);
                assert!(
                    cos >= -1e-12 * e[c].length(),
                    "e outside the cone's dual at node {i}"
                );
                let b = em + rho * cos.max(0.0);
                sum += face.normal * (b * face.area);
                scale += b.abs() * face.area;
            }
            assert!(
                (got[c] - sum).length() <= 1e-12 * scale.max(f64::MIN_POSITIVE),
                "node {i} channel {c}: {} vs {sum}",
                got[c]
            );
        }
        checked += 1;
    }
    assert!(checked > scene.face_count(), "only {checked} nodes checked");
}

fn quad_scene(n: usize) -> Scene {
    // A tilted 2 × 1 rectangle, n × n cells, each split into two triangles (2n² faces).
    let o = dvec3(0.3, -1.0, 2.0);
    let (u, v) = (dvec3(2.0, 0.0, 0.0), dvec3(0.0, 0.6, 0.8));
    let mut b = SceneBuilder::new("quad");
    let m = Material::new("m", dvec3(0.3, 0.5, 0.7), dvec3(1.0, 2.0, 3.0)).expect("valid");
    let m = b.add_material(m).expect("valid");
    for j in 0..=n {
        for i in 0..=n {
            b.add_vertex(
                o + u * (i as f64 / n as f64) + v * (j as f64 / n as f64),
                "quad",
            )
            .expect("finite");
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            b.add_polygon(&[id(i, j), id(i + 1, j), id(i + 1, j + 1)], m, "quad")
                .expect("valid");
            b.add_polygon(&[id(i, j), id(i + 1, j + 1), id(i, j + 1)], m, "quad")
                .expect("valid");
        }
    }
    b.build().expect("faces")
}

/// M and p_E do not depend on how a planar quad is split (Willmott et al. 1999): 2, 200 and 20,000
/// triangles give one root equal to the single quad's ρ A n nᵀ and E A n.
#[test]
fn planar_quad_root_does_not_depend_on_its_tessellation() {
    let (rho, e) = (dvec3(0.3, 0.5, 0.7), dvec3(1.0, 2.0, 3.0));
    let n = dvec3(0.0, 0.6, 0.8).cross(dvec3(1.0, 0.0, 0.0)) * -1.0;
    let area = 2.0;
    for cells in [1, 10, 100] {
        let scene = quad_scene(cells);
        assert_eq!(scene.face_count(), 2 * cells * cells);
        let t = build(&scene);
        assert_eq!(t.roots().len(), 1, "{} triangles", scene.face_count());
        let root = t.node(0);
        assert!((root.area - area).abs() <= 1e-9 * area);
        assert!(root.cone.half_angle < 1e-9 && (root.cone.axis - n).length() < 1e-9);
        // λ_min of the scatter is known to about ε‖S‖, so its square root, the rms distance, to √ε × size.
        assert!(root.plane_rms <= 4.0 * f64::EPSILON.sqrt() * scene.diagonal());
        for c in 0..3 {
            let want = radlab_face_cluster::SymMat3::outer(n, rho[c] * area);
            for (x, y) in root.m[c].e.iter().zip(want.e) {
                assert!(
                    (x - y).abs() <= 1e-9 * rho[c] * area,
                    "{cells}: M {:?}",
                    root.m[c]
                );
            }
            assert!((root.p_e[c] - n * (e[c] * area)).length() <= 1e-9 * e[c] * area);
        }
    }
}

/// A triangle mesh of three quad "wings" hinged on one edge (a non-manifold edge used by three faces) and,
/// apart, a closed tetrahedron: each wing and the tetrahedron end as their own root, four in all.
#[test]
fn non_manifold_edges_and_components_make_separate_roots() {
    let mut b = SceneBuilder::new("wings");
    let m = b
        .add_material(Material::new("m", DVec3::splat(0.5), DVec3::ZERO).expect("valid"))
        .expect("valid");
    let h0 = b.add_vertex(DVec3::ZERO, "w").expect("finite");
    let h1 = b.add_vertex(DVec3::Z, "w").expect("finite");
    for k in 0..3 {
        let a = std::f64::consts::TAU * k as f64 / 3.0;
        let d = dvec3(a.cos(), a.sin(), 0.0);
        let p0 = b.add_vertex(d, "w").expect("finite");
        let p1 = b.add_vertex(d + DVec3::Z, "w").expect("finite");
        b.add_polygon(&[h0, p0, p1], m, "w").expect("valid");
        b.add_polygon(&[h0, p1, h1], m, "w").expect("valid");
    }
    let o = dvec3(5.0, 0.0, 0.0);
    let t: Vec<u32> = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z]
        .iter()
        .map(|&p| b.add_vertex(o + p, "t").expect("finite"))
        .collect();
    for f in [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]] {
        b.add_polygon(&f.map(|i| t[i]), m, "t").expect("valid");
    }
    let scene = b.build().expect("faces");
    let tree = build(&scene);
    assert_eq!(tree.stats().non_manifold_edges, 1);
    assert_eq!(tree.stats().dual_edges, 3 + 6);
    assert_eq!(tree.roots().len(), 4);
    assert_layout(&scene, &tree);
    // The tetrahedron is closed: its root's vector area vanishes and its cone is the whole sphere.
    let tet = tree
        .roots()
        .find(|&r| tree.node(r).faces().len() == 4)
        .expect("the tetrahedron's root");
    assert!(tree.node(tet).vector_area.length() < 1e-12);
    assert!(tree.node(tet).cone.half_angle > std::f64::consts::FRAC_PI_2);
}

/// Normal cones hold their faces' normals; boxes and spheres their faces' vertices; samples are points of
/// the node's own faces, with those faces' normals.
#[test]
fn bounds_hold_their_faces() {
    for scene in [bumpy(), terrain()] {
        let t = build(&scene);
        let tol = 1e-9 * scene.diagonal();
        for (i, n) in t.nodes().iter().enumerate() {
            let leaf_samples: Vec<DVec3> = t
                .faces_of(i)
                .iter()
                .flat_map(|&f| t.samples(t.leaf_of_face(f as usize)).to_vec())
                .collect();
            for &f in t.faces_of(i) {
                let face = &scene.faces[f as usize];
                assert!(
                    n.cone.contains(face.normal, 1e-9),
                    "node {i}: normal {} is {} from the axis, cone {}",
                    face.normal,
                    angle_between(n.cone.axis, face.normal),
                    n.cone.half_angle
                );
                for &v in scene.polygon(f as usize).vertices() {
                    assert!(
                        n.obb.contains(v, tol),
                        "node {i}: box {:?} misses {v}",
                        n.obb
                    );
                    assert!(n.sphere.contains(v, tol), "node {i}: sphere misses {v}");
                }
            }
            let leaf_normals: Vec<DVec3> = t
                .faces_of(i)
                .iter()
                .flat_map(|&f| t.sample_normals(t.leaf_of_face(f as usize)).to_vec())
                .collect();
            for (p, nrm) in t.samples(i).iter().zip(t.sample_normals(i)) {
                let at = leaf_samples.iter().position(|q| q == p);
                assert!(at.is_some(), "node {i}: sample {p} is not on its faces");
                assert_eq!(
                    leaf_normals[at.unwrap_or(0)],
                    *nrm,
                    "node {i}: sample {p} carries another face's normal"
                );
            }
            if n.is_leaf() {
                let f = t.faces_of(i)[0] as usize;
                let poly = scene.polygon(f);
                for (&p, &nrm) in t.samples(i).iter().zip(t.sample_normals(i)) {
                    assert!(poly.distance_to(p) <= tol);
                    assert_eq!(nrm, scene.faces[f].normal);
                }
            }
        }
    }
}

#[test]
fn the_tree_is_the_same_at_any_scale() {
    for scene in [bumpy(), terrain()] {
        let want = shape(&build(&scene));
        for s in [1e-4, 1e4] {
            assert!(
                shape(&build(&scaled(&scene, s))) == want,
                "{} at scale {s}",
                scene.name
            );
        }
    }
}

#[test]
fn one_and_two_threads_build_the_same_bits() {
    let scene = bumpy();
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| build(&scene))
    };
    let (one, two) = (on(1), on(2));
    assert!(one == two);
    assert_eq!(
        one.to_bytes().expect("encodes"),
        two.to_bytes().expect("encodes")
    );
}

#[test]
fn cache_round_trip_is_bit_identical_and_refuses_other_meshes() {
    let scene = terrain();
    let params = FaceClusterParams::default();
    let t = build(&scene);
    let key = digest(&scene, &params);
    assert_eq!(t.digest(), &key);
    let bytes = t.to_bytes().expect("encodes");
    let mut file = Vec::new();
    t.write_to(&mut file).expect("writes");
    assert_eq!(file, bytes);
    let back = FaceClusterTree::read_from(&mut file.as_slice(), Some(&key)).expect("reads");
    assert!(back == t);
    assert_eq!(back.to_bytes().expect("encodes"), bytes);

    // Another mesh, other parameters, damaged bytes.
    let other = scaled(&scene, 2.0);
    let other_key = digest(&other, &params);
    assert_ne!(other_key, key);
    let seeded = FaceClusterParams {
        seed: 2,
        ..params.clone()
    };
    assert_ne!(digest(&scene, &seeded), key);
    assert!(matches!(
        FaceClusterTree::from_bytes(&bytes, Some(&other_key)),
        Err(FaceClusterError::CacheStale { .. })
    ));
    assert!(matches!(
        FaceClusterTree::from_bytes(&bytes[..bytes.len() / 2], None),
        Err(FaceClusterError::CacheFormat { .. })
    ));
    let mut bad = bytes.clone();
    bad[0] ^= 1;
    let e = FaceClusterTree::from_bytes(&bad, None).expect_err("bad magic");
    assert!(e.to_string().contains("delete the cache file"), "{e}");
}

#[test]
fn bad_parameters_say_what_to_change() {
    let scene = quad_scene(1);
    let p = FaceClusterParams {
        samples_per_node: 0,
        ..FaceClusterParams::default()
    };
    let e = FaceClusterTree::build(&scene, &p).expect_err("0 samples");
    assert!(e.to_string().contains("samples-per-node"), "{e}");
    let p = FaceClusterParams {
        shape_weight: f64::NAN,
        ..FaceClusterParams::default()
    };
    assert!(FaceClusterTree::build(&scene, &p).is_err());
}

/// For straddled clusters, the fit from the moments against the faces' own mean clamped cosine, and the
/// cone range's fit beside it: (signed error of the moments' fit, its mean absolute error, the cone's signed
/// error), relative to the total, over nodes of at least 4 faces and random directions that straddle their
/// cones.
fn straddled_fit_errors(scene: &Scene) -> (f64, f64, f64, usize) {
    use radlab_face_cluster::clamped_irradiance::CosineFit;
    let t = build(scene);
    let mut r = sampling::rng(11, 0);
    let (mut signed, mut abs, mut cone, mut total, mut count) = (0.0, 0.0, 0.0, 0.0, 0);
    for (i, n) in t.nodes().iter().enumerate() {
        if t.faces_of(i).len() < 4 || n.cone.half_angle < 1e-6 {
            continue;
        }
        for _ in 0..8 {
            let u = sampling::cosine_hemisphere(
                DVec3::Z,
                sampling::uniform(&mut r),
                sampling::uniform(&mut r),
            );
            let u = if sampling::uniform(&mut r) < 0.5 {
                u
            } else {
                -u
            };
            let u = dvec3(u.x, u.z, u.y).normalize();
            let (alpha, theta) = (angle_between(n.cone.axis, u), n.cone.half_angle);
            if alpha + theta <= std::f64::consts::FRAC_PI_2
                || alpha - theta >= std::f64::consts::FRAC_PI_2
            {
                continue;
            }
            let exact: f64 = t
                .faces_of(i)
                .iter()
                .map(|&f| {
                    let face = &scene.faces[f as usize];
                    face.area * face.normal.dot(u).max(0.0)
                })
                .sum();
            let m = n.vector_area.dot(u) / n.area;
            let fit = CosineFit::of_node(n, u);
            let by_cone = CosineFit::over(
                (alpha + theta).min(std::f64::consts::PI).cos(),
                (alpha - theta).max(0.0).cos(),
            );
            let got = n.area * (fit.offset + fit.slope * m);
            signed += got - exact;
            abs += (got - exact).abs();
            cone += n.area * (by_cone.offset + by_cone.slope * m) - exact;
            total += exact;
            count += 1;
        }
    }
    (signed / total, abs / total, cone / total, count)
}

/// A cluster whose normal cone straddles a link's direction takes (and sends) the least-squares line of the
/// clamped cosine over the spread of its faces' cosines, from its normal moments: its total must be the
/// faces' own Σ A_i max(0, n_i·u), which nobody chose. Measured on the 2,000-face bumpy sphere and terrain
/// over 1,448 and 1,313 node-directions: signed errors −1.8% and −0.4%, mean absolute errors 2.8% and 0.8%;
/// the cone's range alone (the faces' cosines spread evenly between its bounds) was +9.9% and +8.8% on the
/// same nodes, so the bounds below (3% and 5%) tell the two apart.
#[test]
fn straddled_clusters_fit_their_faces_clamped_cosines() {
    for (scene, name) in [(bumpy(), "bumpy sphere"), (terrain(), "terrain")] {
        let (signed, abs, cone, count) = straddled_fit_errors(&scene);
        assert!(count > 1000, "{name}: only {count} straddled nodes");
        assert!(
            signed.abs() <= 0.03,
            "{name}: signed error {signed} (the cone's fit: {cone})"
        );
        assert!(abs <= 0.05, "{name}: mean absolute error {abs}");
    }
}
