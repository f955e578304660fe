//! Builtin scenes with analytic answers: the furnace cube (closed, uniform ρ and E, so
//! B = E/(1−ρ) everywhere) and the plate pairs of Howell's catalogue (parallel coaxial rectangles; perpendicular
//! rectangles sharing an edge), where the receiver's radiosity is B = ρ E F.

use glam::{DVec3, dvec3};

use super::{Args, BuiltinInfo};
use crate::{Material, Scene, SceneBuilder, SceneError};

pub(super) fn infos() -> Vec<BuiltinInfo> {
    vec![
        BuiltinInfo {
            name: "furnace-cube",
            doc: "Closed cube, every face the same reflectance and emission: B = E/(1-rho) everywhere.",
            params: &[
                ("reflectance", "0.5", "rho in [0, 1), grey or r,g,b"),
                ("emission", "1", "E >= 0 (W/m^2), grey or r,g,b"),
                ("tessellation", "4", "quads per cube edge, 1..1000"),
                ("size", "1", "edge length (scene units)"),
            ],
            build: furnace_cube,
        },
        BuiltinInfo {
            name: "parallel-squares",
            doc: "Emitter above a parallel coaxial receiver (open scene): B_receiver = rho E F (Howell C-11).",
            params: &[
                ("width", "1", "rectangle width (x)"),
                ("depth", "1", "rectangle depth (y)"),
                ("distance", "1", "separation (z)"),
                ("emission", "1", "emitter's E"),
                ("reflectance", "0.5", "receiver's rho"),
                ("tessellation", "1", "quads per edge of each rectangle"),
            ],
            build: parallel_squares,
        },
        BuiltinInfo {
            name: "perpendicular-squares",
            doc: "Emitter perpendicular to a receiver, sharing an edge (open scene): B_receiver = rho E F (Howell C-14).",
            params: &[
                (
                    "width",
                    "1",
                    "receiver extent away from the shared edge (x)",
                ),
                (
                    "height",
                    "1",
                    "emitter extent away from the shared edge (z)",
                ),
                ("length", "1", "shared edge length (y)"),
                ("emission", "1", "emitter's E"),
                ("reflectance", "0.5", "receiver's rho"),
                ("tessellation", "1", "quads per edge of each rectangle"),
            ],
            build: perpendicular_squares,
        },
    ]
}

/// Adds an n × n grid of quads over the parallelogram `o + s·u + t·v`, normal along u × v.
pub(crate) fn add_grid(
    b: &mut SceneBuilder,
    o: DVec3,
    u: DVec3,
    v: DVec3,
    n: usize,
    mat: u32,
) -> Result<(), SceneError> {
    let base = b.vertex_count() as u32;
    for j in 0..=n {
        for i in 0..=n {
            b.add_vertex(
                o + u * (i as f64 / n as f64) + v * (j as f64 / n as f64),
                "grid",
            )?;
        }
    }
    let idx = |i: usize, j: usize| base + (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            b.add_polygon(
                &[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)],
                mat,
                "grid",
            )?;
        }
    }
    Ok(())
}

fn furnace_cube(a: &Args) -> Result<Scene, SceneError> {
    let rho = a.rgb("reflectance", DVec3::splat(0.5), 0.0, 1.0, true)?;
    let e = a.rgb("emission", DVec3::ONE, 0.0, f64::MAX, false)?;
    let n = a.usize("tessellation", 4, 1, 1000)?;
    let s = a.f64("size", 1.0, 1e-300, 1e300)?;
    let mut b = SceneBuilder::new("furnace-cube");
    let m = b.add_material(Material::new("furnace", rho, e)?)?;
    // Six faces with inward normals (u × v points into the cube).
    let faces = [
        (dvec3(0., 0., 0.), dvec3(s, 0., 0.), dvec3(0., s, 0.)), // z = 0, normal +z
        (dvec3(0., 0., s), dvec3(0., s, 0.), dvec3(s, 0., 0.)),  // z = s, normal -z
        (dvec3(0., 0., 0.), dvec3(0., s, 0.), dvec3(0., 0., s)), // x = 0, normal +x
        (dvec3(s, 0., 0.), dvec3(0., 0., s), dvec3(0., s, 0.)),  // x = s, normal -x
        (dvec3(0., 0., 0.), dvec3(0., 0., s), dvec3(s, 0., 0.)), // y = 0, normal +y
        (dvec3(0., s, 0.), dvec3(s, 0., 0.), dvec3(0., 0., s)),  // y = s, normal -y
    ];
    for (o, u, v) in faces {
        add_grid(&mut b, o, u, v, n, m)?;
    }
    b.build()
}

fn parallel_squares(a: &Args) -> Result<Scene, SceneError> {
    let w = a.f64("width", 1.0, 1e-300, 1e300)?;
    let d = a.f64("depth", 1.0, 1e-300, 1e300)?;
    let h = a.f64("distance", 1.0, 1e-300, 1e300)?;
    let e = a.rgb("emission", DVec3::ONE, 0.0, f64::MAX, false)?;
    let rho = a.rgb("reflectance", DVec3::splat(0.5), 0.0, 1.0, true)?;
    let n = a.usize("tessellation", 1, 1, 1000)?;
    let mut b = SceneBuilder::new("parallel-squares");
    let light = b.add_material(Material::new("emitter", DVec3::ZERO, e)?)?;
    let recv = b.add_material(Material::new("receiver", rho, DVec3::ZERO)?)?;
    // Receiver at z = 0 facing +z; emitter at z = h facing -z.
    add_grid(
        &mut b,
        DVec3::ZERO,
        dvec3(w, 0., 0.),
        dvec3(0., d, 0.),
        n,
        recv,
    )?;
    add_grid(
        &mut b,
        dvec3(0., 0., h),
        dvec3(0., d, 0.),
        dvec3(w, 0., 0.),
        n,
        light,
    )?;
    b.build()
}

fn perpendicular_squares(a: &Args) -> Result<Scene, SceneError> {
    let w = a.f64("width", 1.0, 1e-300, 1e300)?;
    let h = a.f64("height", 1.0, 1e-300, 1e300)?;
    let l = a.f64("length", 1.0, 1e-300, 1e300)?;
    let e = a.rgb("emission", DVec3::ONE, 0.0, f64::MAX, false)?;
    let rho = a.rgb("reflectance", DVec3::splat(0.5), 0.0, 1.0, true)?;
    let n = a.usize("tessellation", 1, 1, 1000)?;
    let mut b = SceneBuilder::new("perpendicular-squares");
    let light = b.add_material(Material::new("emitter", DVec3::ZERO, e)?)?;
    let recv = b.add_material(Material::new("receiver", rho, DVec3::ZERO)?)?;
    // Receiver in z = 0 (x ∈ [0, w], y ∈ [0, l]) facing +z; emitter in x = 0 (z ∈ [0, h]) facing +x.
    add_grid(
        &mut b,
        DVec3::ZERO,
        dvec3(w, 0., 0.),
        dvec3(0., l, 0.),
        n,
        recv,
    )?;
    add_grid(
        &mut b,
        DVec3::ZERO,
        dvec3(0., l, 0.),
        dvec3(0., 0., h),
        n,
        light,
    )?;
    b.build()
}

#[cfg(test)]
mod tests {
    use crate::builtin::builtin;

    #[test]
    fn furnace_cube_normals_point_inward() {
        let s = builtin("furnace-cube?tessellation=2&size=3").expect("builds");
        assert_eq!(s.faces.len(), 24);
        let c = glam::DVec3::splat(1.5);
        for f in &s.faces {
            assert!(f.normal.dot(c - f.centroid) > 0.0);
        }
        assert!((s.total_area() - 54.0).abs() < 1e-12);
    }

    #[test]
    fn plates_face_each_other() {
        let s = builtin("parallel-squares").expect("builds");
        assert_eq!(s.faces.len(), 2);
        assert!(s.faces[0].normal.z > 0.99 && s.faces[1].normal.z < -0.99);
        let s = builtin("perpendicular-squares").expect("builds");
        assert!(s.faces[0].normal.z > 0.99 && s.faces[1].normal.x > 0.99);
    }

    #[test]
    fn bad_specs_are_named() {
        let e = builtin("nope").expect_err("unknown").to_string();
        assert!(e.contains("furnace-cube"), "{e}");
        let e = builtin("furnace-cube?reflectance=1")
            .expect_err("rho=1")
            .to_string();
        assert!(e.contains("reflectance"), "{e}");
        let e = builtin("furnace-cube?colour=1")
            .expect_err("unknown key")
            .to_string();
        assert!(e.contains("colour") && e.contains("tessellation"), "{e}");
        let e = builtin("furnace-cube?size=nan")
            .expect_err("nan")
            .to_string();
        assert!(e.contains("size"), "{e}");
    }
}
