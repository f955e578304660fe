//! Row sums of volume-clustered radiosity's discrete operator on Christensen's (1995, §8.3) concentric
//! spheres: solve `concentric-spheres?faces=K&reflectance=R` with a transfer, then gather once with every leaf
//! sending B = 1 and report what the leaves receive (area-weighted mean, minimum, maximum, per sphere). In a
//! closed scene every row sums to one; a defect δ becomes δρ/(1 − ρ) in the furnace B = E/(1 − ρ), which is
//! printed beside it.
//!
//! Usage: `cargo run --release -p radlab-volume-cluster --example row_sums -- K R TRANSFER [key=value ...]`

use radlab_answer::Reconstruction;
use radlab_method::{MethodParams, Solver, Step};
use radlab_scene::builtin;
use radlab_visibility::Accel;
use radlab_volume_cluster::{ClusterSolver, TransferMode, VolumeClusterParams};

fn report<M: TransferMode>(
    scene: &radlab_scene::Scene,
    accel: &Accel,
    p: &VolumeClusterParams,
    rho: f64,
) {
    let mut s = ClusterSolver::<M>::new(scene, accel, p, 1).expect("solver");
    let mut steps = 0;
    while steps < 100_000 {
        steps += 1;
        if s.step().expect("step") == Step::Converged {
            break;
        }
    }
    let faces = s.face_radiosity();
    let area: f64 = faces.iter().map(|f| f.1).sum();
    let mean = faces.iter().map(|f| f.1 * f.2.x).sum::<f64>() / area;
    let rows = s.row_sums();
    for (name, inner) in [("inner", true), ("outer", false), ("all", false)] {
        let sel: Vec<_> = rows
            .iter()
            .filter(|r| name == "all" || (scene.faces[r.0].centroid.length() < 1.5) == inner)
            .collect();
        let a: f64 = sel.iter().map(|r| r.1).sum();
        let m = sel.iter().map(|r| r.1 * r.2.x).sum::<f64>() / a;
        let lo = sel.iter().map(|r| r.2.x).fold(f64::INFINITY, f64::min);
        let hi = sel.iter().map(|r| r.2.x).fold(f64::NEG_INFINITY, f64::max);
        println!(
            "{name:5} leaves {:6}  row sum mean {:.7} (δ {:+.2e}, δρ/(1−ρ) {:+.3}%)  min {:.5}  max {:.5}",
            sel.len(),
            m,
            m - 1.0,
            100.0 * (m - 1.0) * rho / (1.0 - rho),
            lo,
            hi
        );
    }
    let st = s.stats();
    println!(
        "solved B mean error {:+.4}%  links {}  form factors {}  steps {steps}",
        100.0 * (mean * (1.0 - rho) - 1.0),
        st.links,
        st.form_factors
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let k = args.first().map_or("600", String::as_str);
    let rho: f64 = args.get(1).and_then(|r| r.parse().ok()).unwrap_or(0.9);
    let transfer = args.get(2).map_or("alpha", String::as_str);
    let scene = builtin(&format!("concentric-spheres?faces={k}&reflectance={rho}")).expect("scene");
    let accel = Accel::new(&scene);
    let mut pairs = vec![("transfer".to_string(), transfer.to_string())];
    for kv in args.iter().skip(3) {
        if let Some((a, b)) = kv.split_once('=') {
            pairs.push((a.into(), b.into()));
        }
    }
    let mut p = VolumeClusterParams::from_pairs(&pairs).expect("parameters");
    p.engine.answer.reconstruction = Reconstruction::Constant;
    match p.transfer {
        radlab_volume_cluster::Transfer::Alpha => {
            report::<radlab_volume_cluster::Alpha>(&scene, &accel, &p, rho)
        }
        radlab_volume_cluster::Transfer::Isotropic => {
            report::<radlab_volume_cluster::Isotropic>(&scene, &accel, &p, rho)
        }
        radlab_volume_cluster::Transfer::Directional => {
            report::<radlab_volume_cluster::Directional>(&scene, &accel, &p, rho)
        }
    }
}
