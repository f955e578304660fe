//! Where the face-cluster operator's light comes from, set beside the scene's own form factors. In a closed
//! scene every point's form factors sum to one (Goral, Torrance, Greenberg & Battaile 1984), and so should
//! every leaf's row of the discrete operator, the irradiance it gathers when every leaf sends B = 1
//! ([`radlab_hierarchical::Engine::row_sums_through`]). This solves a scene, then prints per receiving
//! material the area-weighted mean of its leaves' rows, split by the material of the links' sources (a
//! volume cluster, whose contents may mix materials, apart), and beside each part the form factor
//! F = P(a cosine-distributed ray from a uniform point of the receiving faces first meets the source's
//! faces), by the Nusselt analogy (Cohen & Wallace 1993, §4.9), with its standard error. A row part above
//! its form factor by more than the noise is light the operator invents.
//!
//! `cargo run --release -p radlab-face-cluster --example row_sums_by_source -- 'builtin:bumpy-sphere?faces=100000' epsilon=1e-5 [RAYS]`
//!
//! Further arguments are the method's parameters as `key=value`; a bare number is the rays per material
//! (default 10⁶).

use radlab_face_cluster::{FaceClusterSolveParams, FaceClusterSolver, FaceNode};
use radlab_hierarchical::NodeKind;
use radlab_method::{MethodParams, Solver, Step};
use radlab_scene::{AreaSampler, Scene, sampling};
use radlab_visibility::Accel;

/// The material of a node's faces (of its first face: a face cluster holds one connected mesh, and the
/// materials checked here do not change within one); `None` for a volume.
fn material(scene: &Scene, n: &FaceNode<'_>) -> Option<usize> {
    let f = match n {
        FaceNode::Volume(_) => return None,
        FaceNode::Cluster(c) => c.ctx.tree.faces_of(c.id as usize)[0] as usize,
        FaceNode::Patch(p) => p.face,
    };
    Some(scene.faces[f].material as usize)
}

/// Per source material (and one more for rays that leave the scene), the share of `rays` cosine-distributed
/// rays from uniform points of the faces of material `m` that first meet it.
fn traced_factors(scene: &Scene, accel: &Accel, m: usize, rays: usize) -> Vec<f64> {
    let faces: Vec<usize> = (0..scene.face_count())
        .filter(|&f| scene.faces[f].material as usize == m)
        .collect();
    let cdf: Vec<f64> = faces
        .iter()
        .scan(0.0, |a, &f| {
            *a += scene.faces[f].area;
            Some(*a)
        })
        .collect();
    let total = cdf.last().copied().unwrap_or(0.0);
    let mut hits = vec![0usize; scene.materials.len() + 1];
    let mut r = sampling::rng(7, m as u64);
    for _ in 0..rays {
        let at = sampling::uniform(&mut r) * total;
        let j = cdf.partition_point(|&c| c < at).min(faces.len() - 1);
        let f = faces[j];
        let p = AreaSampler::new(scene.polygon(f))
            .sample(sampling::uniform(&mut r), sampling::uniform(&mut r));
        let d = sampling::cosine_hemisphere(
            scene.faces[f].normal,
            sampling::uniform(&mut r),
            sampling::uniform(&mut r),
        );
        match accel.intersect_from(f, p, d) {
            Some(h) => hits[scene.faces[h.face].material as usize] += 1,
            None => hits[scene.materials.len()] += 1,
        }
    }
    hits.iter().map(|&h| h as f64 / rays as f64).collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let spec = args
        .first()
        .cloned()
        .unwrap_or_else(|| "builtin:bumpy-sphere?faces=100000".to_string());
    let mut rays = 1_000_000usize;
    let mut pairs = Vec::new();
    for a in args.iter().skip(1) {
        match a.split_once('=') {
            Some((k, v)) => pairs.push((k.to_string(), v.to_string())),
            None => rays = a.parse()?,
        }
    }
    let params = FaceClusterSolveParams::from_pairs(&pairs)?;
    let scene = radlab_formats::load_scene(&spec)?;
    let accel = Accel::new(&scene);
    let mut s = FaceClusterSolver::new(&scene, &accel, params, 1)?;
    for _ in 0..1000 {
        if s.step()? != Step::Continue {
            break;
        }
    }
    let e = s.engine();
    let nodes = e.nodes();
    let leaves: Vec<usize> = (0..nodes.len()).filter(|&i| e.is_leaf(i as u32)).collect();
    let mats = scene.materials.len();
    println!(
        "{spec}: {} links, {} leaves",
        e.link_count(),
        e.leaf_count()
    );
    // Row parts per (receiving material, source material or volume).
    let by_source: Vec<_> = (0..=mats)
        .map(|src| e.row_sums_through(&|_, s, _| material(&scene, s).unwrap_or(mats) == src))
        .collect();
    let mut parts = vec![vec![0.0; mats + 1]; mats];
    for &i in &leaves {
        if let Some(m) = material(&scene, &nodes[i]) {
            for (p, part) in parts[m].iter_mut().zip(&by_source) {
                *p += nodes[i].area() * part[i].x;
            }
        }
    }
    let mut area = vec![0.0; mats];
    for &i in &leaves {
        if let Some(m) = material(&scene, &nodes[i]) {
            area[m] += nodes[i].area();
        }
    }
    for m in 0..mats {
        if scene.materials[m].reflectance.x <= 0.0 || area[m] <= 0.0 {
            continue; // a row reads zero where nothing is reflected
        }
        let row: f64 = parts[m].iter().sum::<f64>() / area[m];
        println!(
            "receiver {:>8}: row {row:.5} ({:+.3}%)",
            scene.materials[m].name,
            (row - 1.0) * 100.0
        );
        let traced = traced_factors(&scene, &accel, m, rays);
        for (src, (part, f)) in parts[m].iter().zip(&traced).take(mats).enumerate() {
            let op = part / area[m];
            let se = (f * (1.0 - f) / rays as f64).sqrt();
            println!(
                "  from {:>8}: operator {op:.5}   traced {f:.5} ± {se:.5}   difference {:+.5}",
                scene.materials[src].name,
                op - f
            );
        }
        println!("  from  volumes: operator {:.5}", parts[m][mats] / area[m]);
        println!("  rays leaving the scene: {:.5}", traced[mats]);
    }
    Ok(())
}
