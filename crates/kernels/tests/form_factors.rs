//! Form factors against answers nobody here chose: Howell's closed forms (C-11, C-14, C-41, B-3 and the
//! perpendicular-wall contour result), reciprocity A_i F_ij = A_j F_ji, row sums Σ_j F_ij = 1 in closed scenes,
//! the far-field limit of the cheap estimate, and visibility fractions behind blockers of known shadow.
//!
//! Tolerances follow from the quadrature's order, stated beside each check:
//! - `polygon_polygon_unoccluded` uses an m × m product Gauss–Legendre rule. Where the source lies wholly
//!   above the receiver's horizon the point kernel is analytic over the receiver and the rule converges
//!   exponentially: at m = 32, aspect ratios up to 10 between extent and distance are integrated to rounding.
//!   Where source and receiver share an edge the kernel's derivatives are singular at the edge's ends and the
//!   error falls as m⁻⁴ (checked); where the source crosses the horizon the kernel has a kink and it falls as
//!   m⁻².
//! - The independent check integrates `point_polygon` with the test's own rule: composite midpoint on N × N
//!   and 2N × 2N cells, Richardson-extrapolated (fourth order in the cell size).

use std::f64::consts::PI;

use glam::{DVec3, dvec3};
use radlab_kernels::form_factor::{
    VisibilitySampling, closed_form as cf, form_factor_estimate, point_polygon, polygon_polygon,
    polygon_polygon_unoccluded, visibility_fraction,
};
use radlab_scene::sampling::{self, Rng};
use radlab_scene::{Material, Polygon, SceneBuilder, builtin};
use radlab_visibility::Accel;

/// Receiver and source of Howell C-11: an a × b rectangle at z = 0 facing up, its copy at z = c facing down.
fn parallel_pair(a: f64, b: f64, c: f64) -> (Polygon, Polygon) {
    (
        Polygon::quad(
            dvec3(0., 0., 0.),
            dvec3(a, 0., 0.),
            dvec3(a, b, 0.),
            dvec3(0., b, 0.),
        ),
        Polygon::quad(
            dvec3(0., 0., c),
            dvec3(0., b, c),
            dvec3(a, b, c),
            dvec3(a, 0., c),
        ),
    )
}

/// Receiver and source of Howell C-14: w × l in z = 0 facing up, h × l in x = 0 facing +x, sharing the edge
/// along y. The source starts `below` under the receiver's plane (0 for the catalogue's configuration).
fn perpendicular_pair(w: f64, h: f64, l: f64, below: f64) -> (Polygon, Polygon) {
    (
        Polygon::quad(
            dvec3(0., 0., 0.),
            dvec3(w, 0., 0.),
            dvec3(w, l, 0.),
            dvec3(0., l, 0.),
        ),
        Polygon::quad(
            dvec3(0., 0., -below),
            dvec3(0., l, -below),
            dvec3(0., l, h),
            dvec3(0., 0., h),
        ),
    )
}

/// Sizes over two decades of aspect ratio: every (X, Y) in {0.1, 0.3, 1, 3, 10}², at a distance (or shared
/// edge length) that changes with the case, so absolute size varies too.
fn cases() -> Vec<(f64, f64, f64)> {
    let ratios = [0.1, 0.3, 1.0, 3.0, 10.0];
    let mut out = Vec::new();
    for (i, &x) in ratios.iter().enumerate() {
        for (j, &y) in ratios.iter().enumerate() {
            let d = [0.5, 1.0, 2.0, 7.0][(i + 2 * j) % 4];
            out.push((x * d, y * d, d));
        }
    }
    out
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The test's own receiver quadrature of the point kernel over a parallelogram receiver (edges u from v0 to
/// v1, v from v0 to v3): composite midpoint, optionally graded (s = u² toward v0's edge along v, and
/// t = (1 − cos πv)/2 toward both ends of that edge), Richardson-extrapolated from N and 2N cells a side.
fn midpoint_richardson(recv: &Polygon, src: &Polygon, n: usize, graded: bool) -> f64 {
    let v = recv.vertices();
    let (o, eu, ev, normal) = (v[0], v[1] - v[0], v[3] - v[0], recv.normal());
    let rule = |k: usize| {
        let mut sum = 0.0;
        for j in 0..k {
            for i in 0..k {
                let (u, w) = ((i as f64 + 0.5) / k as f64, (j as f64 + 0.5) / k as f64);
                let (s, ds) = if graded { (u * u, 2.0 * u) } else { (u, 1.0) };
                let (t, dt) = if graded {
                    (0.5 * (1.0 - (PI * w).cos()), 0.5 * PI * (PI * w).sin())
                } else {
                    (w, 1.0)
                };
                sum += ds * dt * point_polygon(o + s * eu + t * ev, normal, src);
            }
        }
        sum / (k * k) as f64
    };
    (4.0 * rule(2 * n) - rule(n)) / 3.0
}

#[test]
fn parallel_rectangles_match_howell_c11() {
    let cases = cases();
    assert!(cases.len() >= 20);
    for &(a, b, c) in &cases {
        let exact = cf::parallel_rectangles(a, b, c);
        let (r, s) = parallel_pair(a, b, c);
        // Analytic kernel, m = 32: converged to rounding (largest error seen 1e-13).
        let f = polygon_polygon_unoccluded(&r, &s, 32);
        assert!(rel(f, exact) < 1e-12, "C-11 {a} {b} {c}: {f} vs {exact}");
        // The rule's error falls fast: m = 4 is visibly worse wherever the plates are not small.
        if a.max(b) >= c {
            let coarse = polygon_polygon_unoccluded(&r, &s, 4);
            assert!(
                rel(coarse, exact) > 1e-9,
                "C-11 {a} {b} {c}: m = 4 already exact?"
            );
        }
        // Reciprocity of the symmetric configuration: F from the top plate down equals F up.
        let down = polygon_polygon_unoccluded(&s, &r, 32);
        assert!(rel(down, exact) < 1e-12);
        // Independent rule: fourth order in h = extent/64, extents ≤ 10 c: error ≲ (10/64)⁴/4! ≈ 2.5e-5 times
        // a kernel derivative below 1; largest seen 1.3e-7.
        let g = midpoint_richardson(&r, &s, 64, false);
        assert!(
            rel(g, exact) < 1e-6,
            "C-11 midpoint {a} {b} {c}: {g} vs {exact}"
        );
    }
    // Howell's tabulated value for unit squares at distance 1.
    let (r, s) = parallel_pair(1.0, 1.0, 1.0);
    assert!((polygon_polygon_unoccluded(&r, &s, 16) - 0.199825).abs() < 5e-7);
}

#[test]
fn perpendicular_rectangles_match_howell_c14() {
    let mut worst = 0.0f64;
    for &(w, h, l) in &cases() {
        let exact = cf::perpendicular_rectangles(w, h, l);
        let (r, s) = perpendicular_pair(w, h, l, 0.0);
        let f16 = polygon_polygon_unoccluded(&r, &s, 16);
        let f32 = polygon_polygon_unoccluded(&r, &s, 32);
        let (e16, e32) = (rel(f16, exact), rel(f32, exact));
        worst = worst.max(e32);
        // m⁻⁴ convergence: halving the spacing divides the error by 16 (≥ 12 required, order ≥ 3.6) unless
        // both are at rounding already (w = l makes the edge-end singularity vanish: exponential there).
        assert!(
            e32 < 1e-12 || e32 * 12.0 <= e16,
            "C-14 {w} {h} {l}: errors {e16:e} → {e32:e}"
        );
        // The m⁻⁴ constant grows with the aspect ratios (the rule must resolve features of size min(h, l)
        // across a receiver w × l): largest seen 4e-4 (w = 100 h), 3e-6 with all sides within a factor 3.
        let (lo, hi) = (w.min(h).min(l), w.max(h).max(l));
        let bound = if hi <= 3.0 * lo { 1e-5 } else { 1e-3 };
        assert!(e32 < bound, "C-14 {w} {h} {l}: {f32} vs {exact} ({e32:e})");
        // Independent rule, graded toward the shared edge and its ends (where the kernel goes like x log x):
        // largest error seen 3e-6.
        let g = midpoint_richardson(&r, &s, 64, true);
        assert!(
            rel(g, exact) < 1e-5,
            "C-14 midpoint {w} {h} {l}: {g} vs {exact}"
        );
        // Reciprocity: A_w F_w→h = A_h F_h→w, with the reverse factor from the catalogue.
        let back = cf::perpendicular_rectangles(h, w, l);
        assert!(rel(w * exact, h * back) < 1e-12);
    }
    assert!(worst > 1e-9, "the m⁻⁴ cases should show");
    let (r, s) = perpendicular_pair(1.0, 1.0, 1.0, 0.0);
    assert!((polygon_polygon_unoccluded(&r, &s, 16) - 0.200044).abs() < 5e-7);
}

/// A regular n-gon of radius r at height z as a fan of n triangles around its centre, facing up or down.
fn disk_fan(r: f64, z: f64, n: usize, up: bool) -> Vec<Polygon> {
    let c = dvec3(0., 0., z);
    let p = |k: usize| {
        let a = 2.0 * PI * k as f64 / n as f64;
        dvec3(r * a.cos(), r * a.sin(), z)
    };
    (0..n)
        .map(|k| {
            if up {
                Polygon::triangle(c, p(k), p(k + 1))
            } else {
                Polygon::triangle(c, p(k + 1), p(k))
            }
        })
        .collect()
}

/// Exchange area A₁F₁₂ between coaxial disks (Howell C-41).
fn disk_exchange(r1: f64, r2: f64, h: f64) -> f64 {
    PI * r1 * r1 * cf::coaxial_disks(r1, r2, h)
}

#[test]
fn coaxial_disks_match_howell_c41_up_to_tessellation() {
    // Disks as regular n-gons (fans of n triangles). The exchange area A₁F₁₂ = ∫∫ G is monotone in both
    // surfaces here (G ≥ 0 between coaxial facing plates), and the n-gon lies between the disks of radius
    // r cos(π/n) and r: a rigorous bracket. Tighter: the n-gon loses ΔA/A = 1 − sin(2π/n)/(2π/n) of its
    // disk's area in n slivers at most d = r(1 − cos π/n) deep; by symmetry the kernel is constant around the
    // rim, so to first order the n-gon acts as the disk of equal area; what is left is second order,
    // (ΔA/A)(d/r) times the kernel's relative radial gradient at the rim (below 1 in these cases), and must
    // fall as n⁻⁴.
    for (r1, r2, h) in [
        (1.0, 1.0, 1.0),
        (0.5, 2.0, 1.0),
        (2.0, 0.3, 0.5),
        (1.0, 1.0, 0.25),
    ] {
        let mut prev: Option<f64> = None;
        for n in [32usize, 64, 128] {
            let recv = disk_fan(r1, 0.0, n, true);
            let src = disk_fan(r2, h, n, false);
            // Every receiver triangle is a rotation of the first: integrate one (m = 16 Gauss points a side,
            // converged to ~1e-9 here) against every source triangle.
            let f0: f64 = src
                .iter()
                .map(|s| polygon_polygon_unoccluded(&recv[0], s, 16))
                .sum();
            let f1: f64 = src
                .iter()
                .map(|s| polygon_polygon_unoccluded(&recv[n / 3], s, 16))
                .sum();
            assert!(rel(f1, f0) < 1e-12, "coaxial symmetry");
            let k = n as f64 * recv[0].area() * f0;
            let c = (PI / n as f64).cos();
            let (lo, hi) = (disk_exchange(r1 * c, r2 * c, h), disk_exchange(r1, r2, h));
            assert!(
                lo < k && k < hi,
                "C-41 {r1} {r2} {h} n {n}: {k} outside [{lo}, {hi}]"
            );
            let keep = (2.0 * PI / n as f64).sin() / (2.0 * PI / n as f64);
            let eq = disk_exchange(r1 * keep.sqrt(), r2 * keep.sqrt(), h);
            let second_order = (1.0 - keep) * (1.0 - c);
            let e = k / eq - 1.0;
            assert!(
                e.abs() < second_order,
                "C-41 {r1} {r2} {h} n {n}: {e:e} vs {second_order:e}"
            );
            if let Some(p) = prev {
                assert!(
                    e.abs() < p.abs() / 8.0,
                    "C-41 {r1} {r2} {h}: n⁻⁴ expected, {p:e} → {e:e}"
                );
            }
            prev = Some(e);
        }
    }
    assert!((cf::coaxial_disks(1.0, 1.0, 1.0) - (3.0 - 5f64.sqrt()) / 2.0).abs() < 1e-15);
}

fn u(r: &mut Rng) -> f64 {
    sampling::uniform(r)
}

/// A random triangle or convex trapezoid, 0.3–1.3 across, anywhere in [−2, 2]³, facing anywhere.
fn random_polygon(r: &mut Rng) -> Polygon {
    let c = dvec3(u(r), u(r), u(r)) * 4.0 - 2.0;
    let side = if u(r) < 0.5 { 1.0 } else { -1.0 };
    let n = side * sampling::cosine_hemisphere(DVec3::Z, u(r), u(r));
    let (t, b) = sampling::basis(n);
    let size = 0.3 + u(r);
    let p = |x: f64, y: f64| c + size * (x * t + y * b);
    if u(r) < 0.5 {
        Polygon::triangle(p(0.0, 0.0), p(1.0, 0.1 * u(r)), p(0.3 * u(r), 1.0))
    } else {
        let k = 0.2 + 0.6 * u(r);
        Polygon::quad(
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(0.5 + 0.5 * k, 0.7),
            p(0.5 - 0.5 * k, 0.7),
        )
    }
}

/// Every vertex of `q` at least `margin` in front of `p`'s plane.
fn wholly_in_front(p: &Polygon, q: &Polygon, margin: f64) -> bool {
    let n = p.normal();
    q.vertices()
        .iter()
        .all(|&v| (v - p.vertices()[0]).dot(n) > margin)
}

#[test]
fn reciprocity_between_random_polygons() {
    let mut r = sampling::rng(1, 2);
    let (mut smooth, mut straddling) = (0, 0);
    let mut tries = 0;
    while smooth < 30 || straddling < 10 {
        tries += 1;
        assert!(tries < 100_000);
        let (a, b) = (random_polygon(&mut r), random_polygon(&mut r));
        let facing = wholly_in_front(&a, &b, 0.05) && wholly_in_front(&b, &a, 0.05);
        let partial = !facing
            && a.vertices()
                .iter()
                .any(|&v| (v - b.vertices()[0]).dot(b.normal()) > 0.0)
            && b.vertices()
                .iter()
                .any(|&v| (v - a.vertices()[0]).dot(a.normal()) > 0.0);
        if facing && smooth < 30 {
            smooth += 1;
            // Both kernels analytic, every vertex at least 0.05 (about a tenth of a polygon) clear of the
            // other's plane: m = 32 converges to rounding.
            let ab = a.area() * polygon_polygon_unoccluded(&a, &b, 32);
            let ba = b.area() * polygon_polygon_unoccluded(&b, &a, 32);
            assert!(ab > 0.0 && rel(ab, ba) < 1e-12, "{a:?} {b:?}: {ab} vs {ba}");
        } else if partial && straddling < 10 {
            let ab = a.area() * polygon_polygon_unoccluded(&a, &b, 64);
            let ba = b.area() * polygon_polygon_unoccluded(&b, &a, 64);
            if ab.max(ba) < 1e-5 {
                continue; // a sliver of visibility: nothing to compare
            }
            straddling += 1;
            // A kink where the source crosses the receiver's horizon: m⁻² convergence, whose constant is
            // the share of the receiver beyond the kink; at m = 64 that is below 1e-3 (largest seen 1e-4).
            assert!(rel(ab, ba) < 1e-3, "{a:?} {b:?}: {ab} vs {ba}");
        }
    }
}

#[test]
fn row_sums_are_one_in_a_closed_cube() {
    // The point kernel is exact and the faces of a closed polygonal enclosure tile every receiver point's
    // hemisphere, so Σ_j F_{x→j} = 1 to rounding at every point, and so is any quadrature of it whose weights
    // sum to one, whatever its order. Coplanar neighbours contribute exactly 0.
    for (tess, m) in [(1, 1), (2, 3), (3, 2), (5, 1)] {
        let scene = builtin(&format!("furnace-cube?tessellation={tess}&size=2.5")).expect("cube");
        let polys: Vec<Polygon> = (0..scene.faces.len()).map(|f| scene.polygon(f)).collect();
        for (i, pi) in polys.iter().enumerate() {
            let sum: f64 = polys
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, pj)| polygon_polygon_unoccluded(pi, pj, m))
                .sum();
            assert!(
                (sum - 1.0).abs() < 1e-10,
                "tessellation {tess} m {m} face {i}: {sum}"
            );
        }
    }
    // Points anywhere on the surface, including on shared edges and at corners.
    let scene = builtin("furnace-cube?tessellation=3").expect("cube");
    let mut r = sampling::rng(4, 0);
    for k in 0..300 {
        let f = k % scene.faces.len();
        let p = scene.polygon(f);
        let (s, t) = match k % 3 {
            0 => (0.0, u(&mut r)),
            1 => (u(&mut r).round(), u(&mut r).round()),
            _ => (u(&mut r), u(&mut r)),
        };
        let x = p.point_at(s, t);
        let sum: f64 = (0..scene.faces.len())
            .filter(|&j| j != f)
            .map(|j| point_polygon(x, scene.faces[f].normal, &scene.polygon(j)))
            .sum();
        // On an edge shared with a perpendicular face the point lies in that face's plane, which it then
        // does not see (one-sided convention); the faces beyond still fill the hemisphere only if the point
        // is not on the cube's edge.
        let on_cube_edge = [x.x, x.y, x.z]
            .iter()
            .filter(|&&c| c == 0.0 || c == 1.0)
            .count()
            >= 2;
        if !on_cube_edge {
            assert!((sum - 1.0).abs() < 1e-12, "point {x:?} on face {f}: {sum}");
        } else {
            assert!(sum.is_finite() && sum <= 1.0 + 1e-12);
        }
    }
}

#[test]
fn visibility_inside_a_convex_cube_never_occludes() {
    // The same row sums through `polygon_polygon`: every visibility estimate inside a convex enclosure is 1,
    // for rays between points on neighbouring, perpendicular and opposite faces alike.
    let scene = builtin("furnace-cube?tessellation=2").expect("cube");
    let accel = Accel::new(&scene);
    for how in [
        VisibilitySampling::Centre,
        VisibilitySampling::Jittered2x2,
        VisibilitySampling::Jittered4x4,
        VisibilitySampling::Jittered8x8,
    ] {
        for i in 0..scene.faces.len() {
            let pi = scene.polygon(i);
            let sum: f64 = (0..scene.faces.len())
                .filter(|&j| j != i)
                .map(|j| {
                    polygon_polygon(
                        &accel,
                        &pi,
                        i,
                        &scene.polygon(j),
                        j,
                        2,
                        how,
                        7,
                        (i * 100 + j) as u64,
                    )
                })
                .sum();
            assert!((sum - 1.0).abs() < 1e-10, "{how:?} face {i}: {sum}");
        }
    }
}

#[test]
fn horizon_clipping_is_exact() {
    // A wall in x = c facing the receiver at the origin (normal +z), spanning y ∈ [0, b] and z ∈ [−d, a]:
    // only the part above the horizon counts, whatever d.
    for (a, b, c) in [
        (1.0, 1.0, 1.0),
        (0.3, 2.0, 0.5),
        (4.0, 0.2, 1.5),
        (1e-3, 1.0, 1.0),
        (10.0, 10.0, 0.1),
    ] {
        let exact = cf::point_to_perpendicular_rectangle(a, b, c);
        for d in [0.0, 1e-9, 0.5, 3.0] {
            let wall = Polygon::quad(
                dvec3(c, 0., -d),
                dvec3(c, 0., a),
                dvec3(c, b, a),
                dvec3(c, b, -d),
            );
            let f = point_polygon(DVec3::ZERO, DVec3::Z, &wall);
            assert!(
                rel(f, exact) < 1e-12,
                "a {a} b {b} c {c} d {d}: {f} vs {exact}"
            );
        }
    }
    // A tilted receiver: rotate the whole configuration; the answer cannot change.
    let rot = glam::DQuat::from_axis_angle(dvec3(1.0, 2.0, -0.5).normalize(), 0.8);
    let wall = Polygon::quad(
        rot * dvec3(1., 0., -2.),
        rot * dvec3(1., 0., 1.),
        rot * dvec3(1., 1., 1.),
        rot * dvec3(1., 1., -2.),
    );
    let f = point_polygon(rot * DVec3::ZERO, rot * DVec3::Z, &wall);
    assert!(rel(f, cf::point_to_perpendicular_rectangle(1.0, 1.0, 1.0)) < 1e-12);
    // Area to area: a wall reaching below the floor gives C-14 for the part above (the clip line is the
    // shared edge for every receiver point, so the convergence is C-14's).
    for (w, h, l) in [(1.0, 1.0, 1.0), (0.5, 2.0, 1.0), (2.0, 0.7, 1.3)] {
        let (r, s) = perpendicular_pair(w, h, l, 0.8);
        let f = polygon_polygon_unoccluded(&r, &s, 32);
        assert!(
            rel(f, cf::perpendicular_rectangles(w, h, l)) < 1e-5,
            "{w} {h} {l}: {f}"
        );
    }
}

#[test]
fn points_on_edges_and_touching_surfaces_give_finite_correct_factors() {
    // The receiver point approaches the edge it shares with a perpendicular unit wall (y ∈ [0, 1],
    // z ∈ [0, 1], at x = 0) at the edge's middle: two corner configurations of the perpendicular-wall result,
    // tending to 1/2 (the wall fills a quarter of the sphere, half the projected hemisphere).
    let wall = Polygon::quad(
        dvec3(0., 0., 0.),
        dvec3(0., 1., 0.),
        dvec3(0., 1., 1.),
        dvec3(0., 0., 1.),
    );
    for eps in [1e-2, 1e-6, 1e-9, 1e-12] {
        let f = point_polygon(dvec3(eps, 0.5, 0.0), DVec3::Z, &wall);
        let exact = 2.0 * cf::point_to_perpendicular_rectangle(1.0, 0.5, eps);
        assert!(rel(f, exact) < 1e-9, "eps {eps}: {f} vs {exact}");
        assert!(f < 0.5 && (eps > 1e-6 || f > 0.5 - 1e-6));
    }
    // Exactly on the wall's plane the point sees the wall edge-on: 0, finite (the one-sided convention).
    let on_edge = point_polygon(dvec3(0.0, 0.5, 0.0), DVec3::Z, &wall);
    assert_eq!(on_edge, 0.0);
    assert_eq!(point_polygon(dvec3(0.0, 0.0, 0.0), DVec3::Z, &wall), 0.0); // at its vertex
    // A receiver under the corner of a parallel rectangle at vanishing height: B-3 → 1/4.
    for h in [1e-3, 1e-9] {
        let rect = Polygon::quad(
            dvec3(0., 0., h),
            dvec3(0., 2., h),
            dvec3(3., 2., h),
            dvec3(3., 0., h),
        );
        let f = point_polygon(DVec3::ZERO, DVec3::Z, &rect);
        assert!(rel(f, cf::point_to_parallel_rectangle_corner(3.0, 2.0, h)) < 1e-12);
        assert!((f - 0.25).abs() < 2.0 * h);
    }
    // A receiver almost touching the middle of a source's front sees nothing else: F → 1, never above.
    let src = Polygon::quad(
        dvec3(-1., -1., 0.),
        dvec3(-1., 1., 0.),
        dvec3(1., 1., 0.),
        dvec3(1., -1., 0.),
    );
    for gap in [1e-3, 1e-8, 1e-14] {
        let f = point_polygon(dvec3(0.1, 0.2, -gap), DVec3::Z, &src);
        assert!(f <= 1.0 && f > 1.0 - 2.0 * gap, "gap {gap}: {f}");
    }
    // Area to area with touching plates (the C-14 edge) was checked above; a receiver whose edge touches a
    // coplanar source sees none of it.
    let (r, _) = parallel_pair(1.0, 1.0, 1.0);
    let beside = Polygon::quad(
        dvec3(1., 0., 0.),
        dvec3(1., 1., 0.),
        dvec3(2., 1., 0.),
        dvec3(2., 0., 0.),
    );
    assert_eq!(polygon_polygon_unoccluded(&r, &beside, 4), 0.0);
}

#[test]
fn the_estimate_converges_to_the_true_factor_far_away() {
    // F ≈ A_j cosθi cosθj / (π r² + A_j) errs by O((size/r)²): the kernel's variation over both polygons and
    // the A_j in the denominator. Coaxial squares (Howell C-11) and random tilted pairs (Gauss rule, exact
    // to rounding at these distances).
    for c in [10.0, 20.0, 40.0, 80.0] {
        let (r, s) = parallel_pair(1.0, 1.0, c);
        let est =
            form_factor_estimate(r.centroid(), r.normal(), s.centroid(), s.normal(), s.area());
        let e = rel(est, cf::parallel_rectangles(1.0, 1.0, c));
        // For coaxial unit squares the kernel's variation gives −2⟨ρ²⟩/c² = −(2/3)/c² (ρ the horizontal
        // distance between two points of the squares) and the A_j in the denominator −(1/π)/c²: relative
        // error ≈ 0.35/c².
        assert!(e < 2.0 / (c * c), "c {c}: {e}");
        assert!(
            e > 0.1 / (c * c),
            "c {c}: {e} (the error should be second order, not smaller)"
        );
    }
    let mut r = sampling::rng(6, 0);
    for _ in 0..20 {
        let a = random_polygon(&mut r);
        let b0 = random_polygon(&mut r);
        let dir = sampling::cosine_hemisphere(a.normal(), u(&mut r), u(&mut r));
        let mut last = f64::INFINITY;
        for dist in [20.0, 40.0, 80.0] {
            // Move b along a direction in front of a, turned to face a's centroid at least partly.
            let shift = a.centroid() + dist * dir - b0.centroid();
            let v: Vec<DVec3> = b0.vertices().iter().map(|&p| p + shift).collect();
            let mut b = Polygon::from_slice(&v).expect("3 or 4 vertices");
            if b.normal().dot(-dir) < 0.0 {
                let w: Vec<DVec3> = v.iter().rev().copied().collect();
                b = Polygon::from_slice(&w).expect("3 or 4 vertices");
            }
            let exact = polygon_polygon_unoccluded(&a, &b, 8);
            let est =
                form_factor_estimate(a.centroid(), a.normal(), b.centroid(), b.normal(), b.area());
            let diam = a.diameter().max(b.diameter());
            // Relative error second order in diameter/distance, relative to the cosines (small cosines
            // amplify it): bounded by (diam/dist)² / (cos θi cos θj) with a factor 4.
            let d = (b.centroid() - a.centroid()).normalize();
            let cosines = a.normal().dot(d) * -b.normal().dot(d);
            if cosines < 0.05 {
                continue;
            }
            let e = rel(est, exact);
            assert!(
                e < 4.0 * (diam / dist).powi(2) / cosines,
                "dist {dist}: {est} vs {exact}"
            );
            assert!(e < last, "error must fall with distance");
            last = e;
        }
    }
}

/// Two parallel unit squares (z = 0 facing up, z = 1 facing down) with a blocker at z = 1/2 spanning
/// x ∈ [x0, x1], y ∈ [−1, 2]. A ray from (x₁, y₁, 0) to (x₂, y₂, 1) crosses z = 1/2 at x = (x₁ + x₂)/2.
/// `turned` starts the source's vertex list at another corner, so its first parameter runs along x (against
/// the receiver's) instead of along y: an estimator that pairs the two elements' strata in a fixed order is
/// biased in one of the two.
fn shadow_scene(x0: f64, x1: f64, turned: bool) -> radlab_scene::Scene {
    let mut b = SceneBuilder::new("shadow");
    let m = b
        .add_material(Material::new("grey", DVec3::splat(0.5), DVec3::ZERO).expect("valid"))
        .expect("material");
    let (r, s) = parallel_pair(1.0, 1.0, 1.0);
    b.add_polygon_points(r.vertices(), m, "receiver")
        .expect("quad");
    let mut sv = s.vertices().to_vec();
    if turned {
        sv.rotate_right(1);
    }
    b.add_polygon_points(&sv, m, "source").expect("quad");
    let z = 0.5;
    b.add_polygon_points(
        &[
            dvec3(x0, -1., z),
            dvec3(x1, -1., z),
            dvec3(x1, 2., z),
            dvec3(x0, 2., z),
        ],
        m,
        "blocker",
    )
    .expect("quad");
    b.build().expect("scene")
}

/// Simpson's rule for ∫ f over [a, b] with `n` (even) intervals.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let mut sum = f(a) + f(b);
    for k in 1..n {
        sum += f(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    sum * h / 3.0
}

/// For the shadow scene's plates (unit squares 1 apart) with the blocker over x ∈ [x0, x1] at mid-height:
/// the kernel-weighted visible fraction V = ∫∫ G v / ∫∫ G (G = cos θ cos θ' / r² = 1/(t² + u² + 1)² with
/// t = x₁ − x₂, u = y₁ − y₂), and the first-order bound on the bias of the ratio estimate Σ w v / Σ w from n
/// pairs, σ_w √E[w²] / (n E[w]²) (the delta method; |v − V| ≤ 1). With s = x₁ + x₂ the ray is blocked when
/// s ∈ [2 x0, 2 x1]; (s, t) is uniform on the diamond |t| ≤ min(s, 2 − s) with density 1/2, and u has the
/// triangular density 1 − |u|, so everything reduces to integrals in t of K_k(t) = ∫ (1 − |u|) G^k du.
/// `p` = 1 weights by the kernel; `p` = 0 weights every pair alike (the plain visible fraction).
fn kernel_weighted_visibility(x0: f64, x1: f64, p: i32) -> (f64, impl Fn(usize) -> f64) {
    let g = |t: f64, u: f64| 1.0 / (t * t + u * u + 1.0).powi(2);
    let k = |t: f64, q: i32| {
        simpson(|u| (1.0 - u.abs()) * g(t, u).powi(q), -1.0, 0.0, 200)
            + simpson(|u| (1.0 - u.abs()) * g(t, u).powi(q), 0.0, 1.0, 200)
    };
    // Length of s ∈ [|t|, 2 − |t|] outside the blocker's [2 x0, 2 x1].
    let visible_length = |t: f64| {
        let (lo, hi) = (t.abs(), 2.0 - t.abs());
        let overlap = (hi.min(2.0 * x1) - lo.max(2.0 * x0)).max(0.0);
        (hi - lo) - overlap
    };
    // Integrate over t ≥ 0 (every integrand is even in t) in pieces split at the kinks of visible_length.
    let mut cuts = vec![0.0, 1.0];
    for c in [2.0 * x0, 2.0 - 2.0 * x0, 2.0 * x1, 2.0 - 2.0 * x1] {
        if c > 0.0 && c < 1.0 {
            cuts.push(c);
        }
    }
    cuts.sort_by(f64::total_cmp);
    let integrate = |f: &dyn Fn(f64) -> f64| {
        cuts.windows(2)
            .map(|w| simpson(f, w[0], w[1], 400))
            .sum::<f64>()
    };
    let mean_w = integrate(&|t| (1.0 - t) * k(t, p));
    let mean_w2 = integrate(&|t| (1.0 - t) * k(t, 2 * p));
    let visible = integrate(&|t| k(t, p) * visible_length(t) / 2.0);
    let sd_w = (mean_w2 - mean_w * mean_w).max(0.0).sqrt();
    (visible / mean_w, move |n: usize| {
        sd_w * mean_w2.sqrt() / (n as f64 * mean_w * mean_w)
    })
}

#[test]
fn visibility_fraction_behind_blockers_of_known_shadow() {
    // The estimate is the kernel-weighted visible fraction; for a blocker at mid-height between parallel
    // plates it is known by one-dimensional integrals (above). With a uniform kernel it would be the plain
    // visible fraction, 1 − P((x₁ + x₂)/2 ∈ [x0, x1]) with the triangular density of x₁ + x₂: check the
    // integrals reproduce that first, so they are tested independently of the estimator.
    let tri_cdf = |s: f64| {
        if s <= 1.0 {
            s * s / 2.0
        } else {
            1.0 - (2.0 - s).powi(2) / 2.0
        }
    };
    for (x0, x1, turned) in [
        (0.25_f64, 0.75_f64, false),
        (0.25, 0.75, true),
        (-1.0, 0.5, true),
        (0.4, 0.45, false),
        (0.1, 0.3, true),
    ] {
        let plain =
            1.0 - (tri_cdf((2.0 * x1).clamp(0.0, 2.0)) - tri_cdf((2.0 * x0).clamp(0.0, 2.0)));
        let (uniform, _) = kernel_weighted_visibility(x0, x1, 0);
        assert!(
            (uniform - plain).abs() < 1e-9,
            "integrals: {uniform} vs {plain}"
        );
        let (want, bias_bound) = kernel_weighted_visibility(x0, x1, 1);
        assert!(want.is_finite() && (0.0..=1.0).contains(&want), "{want}");
        let scene = shadow_scene(x0, x1, turned);
        let accel = Accel::new(&scene);
        let (r, s) = (scene.polygon(0), scene.polygon(1));
        for how in [
            VisibilitySampling::Jittered2x2,
            VisibilitySampling::Jittered4x4,
            VisibilitySampling::Jittered8x8,
        ] {
            let trials = 400;
            let v: Vec<f64> = (0..trials)
                .map(|k| visibility_fraction(&accel, &r, 0, &s, 1, how, 3, k))
                .collect();
            let mean = v.iter().sum::<f64>() / trials as f64;
            let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (trials - 1) as f64;
            let se = (var / trials as f64).sqrt();
            // The ratio estimate is consistent, biased by at most the first-order bound at n pairs: the mean
            // of 400 independent estimates lies within that plus 5 standard errors of the truth.
            let n = how.rays() as usize;
            assert!(
                (mean - want).abs() < 5.0 * se + bias_bound(n) + 1e-12,
                "blocker [{x0}, {x1}] turned {turned} {how:?}: mean {mean} ± {se} vs {want} (bias ≤ {})",
                bias_bound(n)
            );
            // Same seed and stream, same answer.
            assert_eq!(v[7], visibility_fraction(&accel, &r, 0, &s, 1, how, 3, 7));
        }
        // The form factor with visibility is the unoccluded one times the fraction.
        let f = polygon_polygon(
            &accel,
            &r,
            0,
            &s,
            1,
            4,
            VisibilitySampling::Jittered8x8,
            3,
            0,
        );
        let fu = polygon_polygon_unoccluded(&r, &s, 4);
        let frac = visibility_fraction(&accel, &r, 0, &s, 1, VisibilitySampling::Jittered8x8, 3, 0);
        assert!((f - fu * frac).abs() < 1e-15);
    }
    // The centre ray crosses at x = 1/2.
    let scene = shadow_scene(0.25, 0.75, false);
    let accel = Accel::new(&scene);
    let (r, s) = (scene.polygon(0), scene.polygon(1));
    assert_eq!(
        visibility_fraction(&accel, &r, 0, &s, 1, VisibilitySampling::Centre, 0, 0),
        0.0
    );
    assert_eq!(
        visibility_fraction(&accel, &r, 0, &s, 1, VisibilitySampling::Unoccluded, 0, 0),
        1.0
    );
    let scene = shadow_scene(0.6, 0.9, false);
    let accel = Accel::new(&scene);
    assert_eq!(
        visibility_fraction(&accel, &r, 0, &s, 1, VisibilitySampling::Centre, 0, 0),
        1.0
    );
}
