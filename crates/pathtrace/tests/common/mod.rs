//! Scenes and helpers shared by the integration tests.
#![allow(dead_code)]

use glam::{DVec3, dvec3};
use radlab_pathtrace::{McMethod, McRadiosityParams, PointEstimate, SurfacePoint};
use radlab_scene::{FaceId, Material, Rgb, Scene, SceneBuilder, sampling};

/// Adds an n × n grid of quads over the parallelogram o + s·u + t·v (normal along u × v).
pub fn add_grid(
    b: &mut SceneBuilder,
    o: DVec3,
    u: DVec3,
    v: DVec3,
    n: usize,
    mat: &dyn Fn(usize, usize) -> u32,
) {
    for j in 0..n {
        for i in 0..n {
            let p = |a: usize, c: usize| o + u * (a as f64 / n as f64) + v * (c as f64 / n as f64);
            b.add_polygon_points(
                &[p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)],
                mat(i, j),
                "grid",
            )
            .expect("grid quad");
        }
    }
}

/// The inside of an icosphere (20·4^subdivisions triangles facing the centre), uniform ρ and E.
pub fn furnace_icosphere(rho: f64, emission: f64, subdivisions: usize) -> Scene {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut verts: Vec<DVec3> = [
        (-1., t, 0.),
        (1., t, 0.),
        (-1., -t, 0.),
        (1., -t, 0.),
        (0., -1., t),
        (0., 1., t),
        (0., -1., -t),
        (0., 1., -t),
        (t, 0., -1.),
        (t, 0., 1.),
        (-t, 0., -1.),
        (-t, 0., 1.),
    ]
    .iter()
    .map(|&(x, y, z)| dvec3(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: usize, b: usize, verts: &mut Vec<DVec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                verts.push((verts[a] + verts[b]).normalize());
                verts.len() - 1
            })
        };
        let mut next = Vec::new();
        for [a, b, c] in tris {
            let (ab, bc, ca) = (
                midpoint(a, b, &mut verts),
                midpoint(b, c, &mut verts),
                midpoint(c, a, &mut verts),
            );
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let mut b = SceneBuilder::new("furnace-icosphere");
    let m = b
        .add_material(
            Material::new("furnace", DVec3::splat(rho), DVec3::splat(emission)).expect("material"),
        )
        .expect("add");
    for [x, y, z] in tris {
        let (p, q, r) = (verts[x], verts[y], verts[z]);
        // Face the centre: the normal (q − p) × (r − p) must point inward.
        let pts = if (q - p).cross(r - p).dot(p + q + r) < 0.0 {
            [p, q, r]
        } else {
            [p, r, q]
        };
        b.add_polygon_points(&pts, m, "icosphere")
            .expect("triangle");
    }
    b.build().expect("sphere")
}

/// A closed unit box, each wall 2 × 2 input quads, coloured walls, one ceiling quad a light (E = 4, ρ = 0).
pub fn lit_box() -> Scene {
    let mut b = SceneBuilder::new("lit-box");
    let mat = |b: &mut SceneBuilder, name: &str, rho: Rgb, e: Rgb| {
        b.add_material(Material::new(name, rho, e).expect("material"))
            .expect("add")
    };
    let white = mat(&mut b, "white", Rgb::splat(0.7), Rgb::ZERO);
    let red = mat(&mut b, "red", Rgb::new(0.7, 0.2, 0.2), Rgb::ZERO);
    let green = mat(&mut b, "green", Rgb::new(0.2, 0.6, 0.2), Rgb::ZERO);
    let grey = mat(&mut b, "grey", Rgb::splat(0.5), Rgb::ZERO);
    let light = mat(&mut b, "light", Rgb::ZERO, Rgb::new(4.0, 3.5, 3.0));
    let s = 1.0;
    add_grid(
        &mut b,
        dvec3(0., 0., 0.),
        dvec3(s, 0., 0.),
        dvec3(0., s, 0.),
        2,
        &|_, _| white,
    ); // floor z=0, +z
    add_grid(
        &mut b,
        dvec3(0., 0., s),
        dvec3(0., s, 0.),
        dvec3(s, 0., 0.),
        2,
        &|i, j| {
            if i == 0 && j == 1 { light } else { grey }
        },
    ); // ceiling z=1, −z
    add_grid(
        &mut b,
        dvec3(0., 0., 0.),
        dvec3(0., s, 0.),
        dvec3(0., 0., s),
        2,
        &|_, _| red,
    ); // x=0, +x
    add_grid(
        &mut b,
        dvec3(s, 0., 0.),
        dvec3(0., 0., s),
        dvec3(0., s, 0.),
        2,
        &|_, _| green,
    ); // x=1, −x
    add_grid(
        &mut b,
        dvec3(0., 0., 0.),
        dvec3(0., 0., s),
        dvec3(s, 0., 0.),
        2,
        &|_, _| grey,
    ); // y=0, +y
    add_grid(
        &mut b,
        dvec3(0., s, 0.),
        dvec3(s, 0., 0.),
        dvec3(0., 0., s),
        2,
        &|_, _| white,
    ); // y=1, −y
    b.build().expect("box")
}

/// `count` points spread over the scene's faces (uniform on each chosen face), plus one point 1e-6 of the
/// scene's size from a corner of face 0 (touching surfaces).
pub fn spread_points(scene: &Scene, count: usize, seed: u64) -> Vec<SurfacePoint> {
    let mut r = sampling::rng(seed, 0);
    let mut pts: Vec<SurfacePoint> = (0..count)
        .map(|i| {
            let f: FaceId = (i * 7919 + 13) % scene.faces.len();
            let p = scene
                .polygon(f)
                .sample_uniform(sampling::uniform(&mut r), sampling::uniform(&mut r));
            SurfacePoint {
                face: f,
                point: p,
                normal: scene.faces[f].normal,
            }
        })
        .collect();
    let poly = scene.polygon(0);
    let corner = poly.vertices()[0];
    let towards = (poly.centroid() - corner).normalize();
    pts.push(SurfacePoint {
        face: 0,
        point: corner + towards * (1e-6 * scene.diagonal()),
        normal: scene.faces[0].normal,
    });
    pts
}

/// Asserts |mean − exact| ≤ k · se per channel; `what` names the case.
pub fn assert_within(e: &PointEstimate, exact: Rgb, k: f64, what: &str) {
    for c in 0..3 {
        let (m, se, x) = (e.mean[c], e.std_error[c], exact[c]);
        assert!(
            (m - x).abs() <= k * se + 1e-12 * x.abs(),
            "{what}: channel {c}: estimate {m} ± {se} vs exact {x} ({:.2} standard errors)",
            (m - x) / se
        );
    }
}

/// Mesh Monte Carlo radiosity parameters: `element_size`, `particles` per step, `steps`, `method`; the rest
/// default.
pub fn mc_params(
    element_size: f64,
    particles: u64,
    steps: u64,
    method: McMethod,
) -> McRadiosityParams {
    McRadiosityParams {
        element_size: Some(element_size),
        particles_per_step: particles,
        max_steps: steps,
        method,
        ..Default::default()
    }
}

/// The step estimates x_k of a quantity recovered from its running means m_k = (1/k) Σ_{i≤k} x_i.
pub fn step_values(running: &[f64]) -> Vec<f64> {
    (0..running.len())
        .map(|i| {
            if i == 0 {
                running[0]
            } else {
                (i + 1) as f64 * running[i] - i as f64 * running[i - 1]
            }
        })
        .collect()
}

/// Mean and standard error of the mean of independent estimates.
pub fn mean_se(x: &[f64]) -> (f64, f64) {
    let k = x.len() as f64;
    let m = x.iter().sum::<f64>() / k;
    let var = x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (k - 1.0);
    (m, (var / k).sqrt())
}

/// `run` on a rayon pool of `n` threads.
pub fn on_threads<R: Send>(n: usize, run: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .expect("pool")
        .install(run)
}

/// Least-squares slope of ln y against ln x.
pub fn log_log_slope(xs: &[f64], ys: &[f64]) -> f64 {
    let lx: Vec<f64> = xs.iter().map(|x| x.ln()).collect();
    let ly: Vec<f64> = ys.iter().map(|y| y.ln()).collect();
    let n = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}
