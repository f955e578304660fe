//! Builds one face-cluster hierarchy and prints its counts and held bytes, for measuring a single large
//! build from outside (e.g. `/usr/bin/time -v`, which gives wall time and peak memory):
//!
//! `cargo run --release -p radlab-face-cluster --example build_once -- 'builtin:bumpy-sphere?faces=1000000' [BALANCE_WEIGHT]`

use radlab_face_cluster::{FaceClusterParams, FaceClusterTree};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let spec = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "builtin:bumpy-sphere?faces=100000".to_string());
    let scene = radlab_formats::load_scene(&spec)?;
    // An optional second argument sets the balance weight.
    let mut params = FaceClusterParams::default();
    if let Some(w) = std::env::args().nth(2) {
        params.balance_weight = w.parse()?;
    }
    let tree = FaceClusterTree::build(&scene, &params)?;
    let s = tree.stats();
    println!(
        "{spec}: {} faces, {} nodes, {} roots, {} dual / {} boundary / {} non-manifold edges, {} queue pushes, \
         {} stale pops, depth {}, {:.1} MiB held, cache {:.1} MiB",
        scene.face_count(),
        tree.nodes().len(),
        tree.roots().len(),
        s.dual_edges,
        s.boundary_edges,
        s.non_manifold_edges,
        s.queue_pushes,
        s.stale_pops,
        tree.depth(),
        tree.bytes() as f64 / (1 << 20) as f64,
        tree.to_bytes()?.len() as f64 / (1 << 20) as f64,
    );
    Ok(())
}
