//! Surface primitives shared by the builtin generators and the TOML scene format: subdivided quads and
//! triangles, boxes, tessellated spheres (optionally with a radial displacement) and height fields, every one
//! emitted with shared vertices so meshes stay connected (the face-cluster hierarchy walks shared edges).
//!
//! - **Quad grid**: bilinear n_u × n_v grid over a planar convex quad; each cell is a planar convex quad.
//! - **Box**: the surface of the lattice [0, n]³ mapped onto [lo, hi], one vertex per lattice point (sides
//!   share their edge vertices), n² quads per side.
//! - **Triangle grid**: lattice a + (i/m)(b − a) + (j/m)(c − a), i + j ≤ m, giving m² triangles.
//! - **Sphere**: the "cube sphere" with the equal-angle map: the cube face point (±1, tan α, tan β) with α, β
//!   uniform in [−π/4, π/4], projected on the sphere (Ronchi, Iacono & Paolucci 1996, "The cubed sphere").
//!   A per-axis resolution (n_x, n_y, n_z) keeps the grids of neighbouring cube faces matched along their
//!   shared edge, so the surface is closed; there are 4 (n_x n_y + n_y n_z + n_z n_x) triangles (12 n² for a
//!   uniform n), each cell split along its shorter diagonal. The inscribed polyhedron's area falls short of
//!   4πr² by O(1/n²).
//! - **Height field**: (n_x + 1) × (n_z + 1) heights over a rectangle, 2 n_x n_z triangles, each cell split
//!   along its shorter diagonal, facing +y (or −y when flipped).
//! - **Fractal heights**: fractional Brownian motion from value noise: Σ_o g^o · noise(2^o · base · x), each
//!   octave's lattice of uniform values in [−1, 1] drawn from `sampling::rng(seed, octave)` and interpolated
//!   with the C¹ smoothstep (Musgrave's fBm, in Ebert et al., "Texturing and Modeling", ch. 16). Cost
//!   O(vertices × octaves), octaves capped so the finest lattice (2^octaves cells per side) is no finer than
//!   the grid.

use std::collections::HashMap;

use glam::{DVec3, dvec3};

use crate::{SceneBuilder, SceneError, sampling};

/// Adds a bilinear `nu` × `nv` grid of quads over the planar convex quad `c` (counter-clockwise seen from its
/// normal side, which the grid keeps). Returns the number of faces added.
pub fn add_quad_grid(
    b: &mut SceneBuilder,
    c: [DVec3; 4],
    nu: usize,
    nv: usize,
    material: u32,
    what: &str,
) -> Result<usize, SceneError> {
    let (nu, nv) = (nu.max(1), nv.max(1));
    let base = b.vertex_count() as u32;
    for j in 0..=nv {
        let t = j as f64 / nv as f64;
        let (l, r) = (c[0].lerp(c[3], t), c[1].lerp(c[2], t));
        for i in 0..=nu {
            b.add_vertex(l.lerp(r, i as f64 / nu as f64), what)?;
        }
    }
    let idx = |i: usize, j: usize| base + (j * (nu + 1) + i) as u32;
    let mut added = 0;
    for j in 0..nv {
        for i in 0..nu {
            added += b.add_polygon(
                &[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)],
                material,
                what,
            )?;
        }
    }
    Ok(added)
}

/// Adds the triangle `t` split into m² triangles of the same orientation (m segments per edge).
pub fn add_triangle_grid(
    b: &mut SceneBuilder,
    t: [DVec3; 3],
    m: usize,
    material: u32,
    what: &str,
) -> Result<usize, SceneError> {
    let m = m.max(1);
    let base = b.vertex_count() as u32;
    // Row j holds m + 1 − j lattice points; `starts[j]` is the index of its first one.
    let mut starts = Vec::with_capacity(m + 1);
    let mut count = 0usize;
    for j in 0..=m {
        starts.push(count);
        for i in 0..=(m - j) {
            let p = t[0]
                + (t[1] - t[0]) * (i as f64 / m as f64)
                + (t[2] - t[0]) * (j as f64 / m as f64);
            b.add_vertex(p, what)?;
            count += 1;
        }
    }
    let idx = |i: usize, j: usize| base + (starts[j] + i) as u32;
    let mut added = 0;
    for j in 0..m {
        for i in 0..m - j {
            added += b.add_polygon(&[idx(i, j), idx(i + 1, j), idx(i, j + 1)], material, what)?;
            if i + j + 1 < m {
                added += b.add_polygon(
                    &[idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)],
                    material,
                    what,
                )?;
            }
        }
    }
    Ok(added)
}

/// Adds a planar convex polygon given by its corners: quads as an n × n grid, triangles as n² triangles,
/// anything else through the builder as it is (fanned when larger than a quad).
pub fn add_subdivided(
    b: &mut SceneBuilder,
    corners: &[DVec3],
    n: usize,
    material: u32,
    what: &str,
) -> Result<usize, SceneError> {
    match *corners {
        [a, bb, c, d] if n > 1 => add_quad_grid(b, [a, bb, c, d], n, n, material, what),
        [a, bb, c] if n > 1 => add_triangle_grid(b, [a, bb, c], n, material, what),
        _ => b.add_polygon_points(corners, material, what),
    }
}

/// The six faces of the axis-aligned box [lo, hi] as counter-clockwise corner lists seen from outside
/// (normals pointing out of the box).
pub fn box_faces(lo: DVec3, hi: DVec3) -> [[DVec3; 4]; 6] {
    let p = |x: bool, y: bool, z: bool| {
        dvec3(
            if x { hi.x } else { lo.x },
            if y { hi.y } else { lo.y },
            if z { hi.z } else { lo.z },
        )
    };
    let (f, t) = (false, true);
    [
        [p(t, f, f), p(t, t, f), p(t, t, t), p(t, f, t)], // +x
        [p(f, f, f), p(f, f, t), p(f, t, t), p(f, t, f)], // -x
        [p(f, t, f), p(f, t, t), p(t, t, t), p(t, t, f)], // +y
        [p(f, f, f), p(t, f, f), p(t, f, t), p(f, f, t)], // -y
        [p(f, f, t), p(t, f, t), p(t, t, t), p(f, t, t)], // +z
        [p(f, f, f), p(f, t, f), p(t, t, f), p(t, f, f)], // -z
    ]
}

/// Adds the closed box [lo, hi], each side an n × n grid of quads, normals outward (or inward, for a room).
/// Sides share their edge vertices, so the surface is closed and connected.
pub fn add_box(
    b: &mut SceneBuilder,
    lo: DVec3,
    hi: DVec3,
    n: usize,
    inward: bool,
    material: u32,
    what: &str,
) -> Result<usize, SceneError> {
    let n = n.max(1);
    let at = |k: usize, l: f64, h: f64| {
        if k == n {
            h
        } else {
            l + (h - l) * (k as f64 / n as f64)
        }
    };
    let (verts, quads) = cube_surface([n; 3], inward, &|l| {
        dvec3(
            at(l[0], lo.x, hi.x),
            at(l[1], lo.y, hi.y),
            at(l[2], lo.z, hi.z),
        )
    });
    let base = b.vertex_count() as u32;
    for &p in &verts {
        b.add_vertex(p, what)?;
    }
    let mut added = 0;
    for q in quads {
        added += b.add_polygon(&q.map(|i| base + i), material, what)?;
    }
    Ok(added)
}

/// The surface of the lattice box [0, n_x] × [0, n_y] × [0, n_z] as unit quads, counter-clockwise seen from
/// outside (from inside when `inward`), with one vertex per lattice point placed by `place`.
fn cube_surface(
    n: [usize; 3],
    inward: bool,
    place: &dyn Fn([usize; 3]) -> DVec3,
) -> (Vec<DVec3>, Vec<[u32; 4]>) {
    let mut verts = Vec::new();
    let mut quads = Vec::with_capacity(2 * (n[0] * n[1] + n[1] * n[2] + n[2] * n[0]));
    let mut index: HashMap<[usize; 3], u32> = HashMap::new();
    for axis in 0..3 {
        let (ua, va) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [0usize, 1] {
            // (u × v) points along +axis for this (ua, va) order: outward on side 1, inward on side 0.
            let flip = (side == 0) != inward;
            for j in 0..n[va] {
                for i in 0..n[ua] {
                    let mut q = [0u32; 4];
                    for (k, (di, dj)) in [(0, 0), (1, 0), (1, 1), (0, 1)].into_iter().enumerate() {
                        let mut l = [0usize; 3];
                        l[axis] = side * n[axis];
                        l[ua] = i + di;
                        l[va] = j + dj;
                        q[k] = *index.entry(l).or_insert_with(|| {
                            verts.push(place(l));
                            (verts.len() - 1) as u32
                        });
                    }
                    if flip {
                        q.reverse();
                    }
                    quads.push(q);
                }
            }
        }
    }
    (verts, quads)
}

/// Number of triangles of a cube sphere with per-axis resolution `n`.
pub fn cube_sphere_faces(n: [usize; 3]) -> usize {
    4 * (n[0] * n[1] + n[1] * n[2] + n[2] * n[0])
}

/// The per-axis resolution whose cube sphere has the face count closest to `target` (resolutions within a
/// factor 1.5 of each other, so cells stay near square).
pub fn cube_sphere_resolution(target: usize) -> [usize; 3] {
    let n0 = ((target as f64 / 12.0).sqrt().floor() as usize).max(1);
    let mut best = [n0; 3];
    let mut best_err = usize::MAX;
    for a in n0.saturating_sub(2).max(1)..=n0 + 2 {
        for bb in a..=a + 3 {
            for c in bb..=bb + 3 {
                if 2 * c > 3 * a {
                    continue;
                }
                let err = cube_sphere_faces([a, bb, c]).abs_diff(target);
                if err < best_err {
                    best_err = err;
                    best = [a, bb, c];
                }
            }
        }
    }
    best
}

/// Vertices and triangles built locally (so cell splits can look at positions), then added to a builder.
#[derive(Default)]
struct LocalMesh {
    verts: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
}

impl LocalMesh {
    /// Adds a cell (corners counter-clockwise) as two triangles split along its shorter diagonal, reversed
    /// when `flip`.
    fn cell(&mut self, q: [u32; 4], flip: bool) {
        let p = |k: usize| self.verts[q[k] as usize];
        let (d02, d13) = (
            (p(2) - p(0)).length_squared(),
            (p(3) - p(1)).length_squared(),
        );
        let tris = if d02 <= d13 {
            [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
        } else {
            [[q[0], q[1], q[3]], [q[1], q[2], q[3]]]
        };
        for mut t in tris {
            if flip {
                t.reverse();
            }
            self.tris.push(t);
        }
    }

    fn emit(&self, b: &mut SceneBuilder, material: u32, what: &str) -> Result<usize, SceneError> {
        let base = b.vertex_count() as u32;
        for &p in &self.verts {
            b.add_vertex(p, what)?;
        }
        let mut added = 0;
        for t in &self.tris {
            added += b.add_polygon(&t.map(|i| base + i), material, what)?;
        }
        Ok(added)
    }
}

/// Adds a cube sphere of the given centre and radius with per-axis resolution `n` (see the module doc),
/// normals outward or inward. `displace(u)` scales the radius along the unit direction u (1 for a sphere);
/// it must stay positive. The surface stays star-shaped about the centre (every vertex lies on its own
/// ray from the centre), so a smooth displacement cannot make it intersect itself.
#[allow(clippy::too_many_arguments)]
pub fn add_cube_sphere(
    b: &mut SceneBuilder,
    center: DVec3,
    radius: f64,
    n: [usize; 3],
    inward: bool,
    material: u32,
    displace: &dyn Fn(DVec3) -> f64,
    what: &str,
) -> Result<usize, SceneError> {
    let n = n.map(|k| k.max(1));
    // tan of equally spaced angles, exactly ±1 at the ends (cube edges); each lattice point becomes one
    // vertex, shared by every cube face that reaches it.
    let params: Vec<Vec<f64>> = n
        .iter()
        .map(|&k| {
            (0..=k)
                .map(|i| {
                    let s = 2.0 * i as f64 / k as f64 - 1.0; // in [-1, 1]
                    if i == 0 {
                        -1.0
                    } else if i == k {
                        1.0
                    } else if 2 * i == k {
                        0.0
                    } else {
                        (std::f64::consts::FRAC_PI_4 * s).tan()
                    }
                })
                .collect()
        })
        .collect();
    let (verts, quads) = cube_surface(n, inward, &|l| {
        let u = dvec3(params[0][l[0]], params[1][l[1]], params[2][l[2]]).normalize();
        center + u * (radius * displace(u))
    });
    let mut mesh = LocalMesh {
        verts,
        tris: Vec::with_capacity(2 * quads.len()),
    };
    for q in quads {
        mesh.cell(q, false);
    }
    mesh.emit(b, material, what)
}

/// Adds a height field over x ∈ [corner.x, corner.x + size.0], z ∈ [corner.z, corner.z + size.1] with
/// heights `h` (row-major, (n_z + 1) rows of (n_x + 1) values, row index along z) added to corner.y.
/// Triangles face +y, or −y when `flip`.
#[allow(clippy::too_many_arguments)]
pub fn add_height_field(
    b: &mut SceneBuilder,
    corner: DVec3,
    size: (f64, f64),
    nx: usize,
    nz: usize,
    h: &[f64],
    flip: bool,
    material: u32,
    what: &str,
) -> Result<usize, SceneError> {
    debug_assert_eq!(h.len(), (nx + 1) * (nz + 1));
    let mut mesh = LocalMesh::default();
    for j in 0..=nz {
        for i in 0..=nx {
            mesh.verts.push(
                corner
                    + dvec3(
                        size.0 * i as f64 / nx as f64,
                        h[j * (nx + 1) + i],
                        size.1 * j as f64 / nz as f64,
                    ),
            );
        }
    }
    let idx = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    for j in 0..nz {
        for i in 0..nx {
            // (i,j) → (i,j+1) → (i+1,j+1) → (i+1,j) is counter-clockwise seen from +y (z × x = +y).
            mesh.cell(
                [idx(i, j), idx(i, j + 1), idx(i + 1, j + 1), idx(i + 1, j)],
                flip,
            );
        }
    }
    mesh.emit(b, material, what)
}

/// Parameters of a fractal (fBm value-noise) height field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fractal {
    /// Peak-to-mean scale of the heights (the first octave's amplitude).
    pub amplitude: f64,
    /// Amplitude ratio between successive octaves (the gain g; 0.5 gives a fractal dimension near 2.5).
    pub roughness: f64,
    /// Number of octaves (capped so the finest lattice is no finer than the grid).
    pub octaves: usize,
    /// Seed of the lattice values.
    pub seed: u64,
}

/// Heights of an (n_x + 1) × (n_z + 1) grid over the unit square (row-major, row index along z).
pub fn fractal_heights(nx: usize, nz: usize, f: &Fractal) -> Vec<f64> {
    let n = nx.max(nz).max(1);
    // The finest lattice, 2^octaves cells per side, no finer than the grid's n cells: finer octaves would be
    // sampled below their lattice spacing and alias into face-to-face jitter.
    let max_octaves = n.ilog2() as usize;
    let octaves = f.octaves.clamp(1, max_octaves.max(1));
    let mut h = vec![0.0; (nx + 1) * (nz + 1)];
    let smooth = |t: f64| t * t * (3.0 - 2.0 * t);
    let mut amp = f.amplitude;
    for o in 0..octaves {
        let g = 2usize << o; // lattice cells per unit length: 2, 4, 8, ...
        let mut r = sampling::rng(f.seed, o as u64);
        let lattice: Vec<f64> = (0..(g + 1) * (g + 1))
            .map(|_| 2.0 * sampling::uniform(&mut r) - 1.0)
            .collect();
        let at = |i: usize, j: usize| lattice[j * (g + 1) + i];
        for j in 0..=nz {
            let z = j as f64 / nz.max(1) as f64 * g as f64;
            let j0 = (z.floor() as usize).min(g - 1);
            let tz = smooth(z - j0 as f64);
            for i in 0..=nx {
                let x = i as f64 / nx.max(1) as f64 * g as f64;
                let i0 = (x.floor() as usize).min(g - 1);
                let tx = smooth(x - i0 as f64);
                let a = at(i0, j0) + (at(i0 + 1, j0) - at(i0, j0)) * tx;
                let c = at(i0, j0 + 1) + (at(i0 + 1, j0 + 1) - at(i0, j0 + 1)) * tx;
                h[j * (nx + 1) + i] += amp * (a + (c - a) * tz);
            }
        }
        amp *= f.roughness;
    }
    h
}

/// The grid (n_x, n_z), n_z ∈ [n_x, n_x + 2], whose 2 n_x n_z triangles come closest to `target`.
pub fn height_field_resolution(target: usize) -> (usize, usize) {
    let n0 = ((target as f64 / 2.0).sqrt().floor() as usize).max(1);
    let mut best = (n0, n0);
    let mut best_err = usize::MAX;
    for a in n0.saturating_sub(2).max(1)..=n0 + 2 {
        for c in a..=a + 2 {
            let err = (2 * a * c).abs_diff(target);
            if err < best_err {
                best_err = err;
                best = (a, c);
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Material;

    fn builder() -> (SceneBuilder, u32) {
        let mut b = SceneBuilder::new("t");
        let m = b
            .add_material(Material::new("m", DVec3::splat(0.5), DVec3::ZERO).expect("valid"))
            .expect("added");
        (b, m)
    }

    #[test]
    fn triangle_grid_has_m_squared_faces_and_keeps_area() {
        let (mut b, m) = builder();
        let t = [DVec3::ZERO, DVec3::X * 2.0, DVec3::Y * 3.0];
        assert_eq!(add_triangle_grid(&mut b, t, 5, m, "t").expect("ok"), 25);
        let s = b.build().expect("builds");
        assert!((s.total_area() - 3.0).abs() < 1e-12);
        assert!(s.faces.iter().all(|f| f.normal.z > 0.999));
        assert_eq!(s.vertices.len(), 21);
    }

    #[test]
    fn sphere_resolution_hits_targets() {
        for target in [100, 130, 1000, 12345, 100_000, 1_000_000] {
            let n = cube_sphere_resolution(target);
            let got = cube_sphere_faces(n) as f64;
            assert!((got / target as f64 - 1.0).abs() < 0.1, "{target}: {got}");
        }
    }

    #[test]
    fn fractal_is_deterministic_and_seeded() {
        let f = Fractal {
            amplitude: 1.0,
            roughness: 0.5,
            octaves: 6,
            seed: 3,
        };
        let a = fractal_heights(16, 16, &f);
        assert_eq!(a, fractal_heights(16, 16, &f));
        assert_ne!(a, fractal_heights(16, 16, &Fractal { seed: 4, ..f }));
        assert!(a.iter().all(|h| h.abs() <= 2.0));
    }

    #[test]
    fn fractal_octaves_stop_where_the_lattice_would_be_finer_than_the_grid() {
        let f = |octaves, n| {
            let f = Fractal {
                amplitude: 1.0,
                roughness: 0.5,
                octaves,
                seed: 3,
            };
            fractal_heights(n, n, &f)
        };
        // 22 cells: the 16-cell lattice (4 octaves) is the finest the grid resolves.
        assert_ne!(f(3, 22), f(4, 22));
        assert_eq!(f(4, 22), f(5, 22));
        assert_eq!(f(4, 22), f(16, 22));
        // 32 cells resolve the 32-cell lattice.
        assert_ne!(f(4, 32), f(5, 32));
        assert_eq!(f(5, 32), f(6, 32));
    }
}
