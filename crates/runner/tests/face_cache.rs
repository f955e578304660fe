//! The face-cluster hierarchy cache: a second run reads the hierarchy the first wrote and gives bit-identical
//! radiosity; a damaged cache file is an error naming the file and the fix.

use radlab_method::Step;
use radlab_runner::face_cache::{CacheOutcome, load_or_build};
use radlab_runner::methods;
use radlab_scene::builtin;
use radlab_visibility::Accel;

fn radiosity(scene: &radlab_scene::Scene, dir: &str) -> Vec<[u64; 3]> {
    let accel = Accel::new(scene);
    let mut table = toml::Table::new();
    table.insert("cache_dir".into(), toml::Value::String(dir.into()));
    table.insert("epsilon".into(), toml::Value::Float(1e-3));
    let build = methods::find("face-cluster").expect("method").build;
    let mut s = build(scene, &accel, table, 5, &[]).expect("solver");
    for _ in 0..200 {
        if s.step().expect("step") != Step::Continue {
            break;
        }
    }
    (0..scene.face_count())
        .map(|f| {
            s.solution()
                .radiosity_at(f, scene.faces[f].centroid)
                .to_array()
                .map(f64::to_bits)
        })
        .collect()
}

#[test]
fn second_run_loads_the_cache_and_gives_the_same_bits() {
    let scene = builtin("concentric-spheres?faces=200").expect("scene");
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path().to_str().expect("utf-8 path");
    let first = radiosity(&scene, d);
    let files: Vec<_> = std::fs::read_dir(dir.path())
        .expect("cache dir")
        .map(|e| e.expect("entry").path())
        .collect();
    assert_eq!(
        files.len(),
        1,
        "one cache file, no temporary left: {files:?}"
    );
    assert_eq!(
        load_or_build(&scene, d).expect("load").1,
        CacheOutcome::Loaded
    );
    let second = radiosity(&scene, d);
    assert_eq!(first, second);
    // Without a cache directory: built, and the same bits.
    assert_eq!(
        load_or_build(&scene, "").expect("build").1,
        CacheOutcome::Uncached
    );
    assert_eq!(radiosity(&scene, ""), first);
    // A truncated file: an error naming it and saying to delete it.
    let bytes = std::fs::read(&files[0]).expect("read");
    std::fs::write(&files[0], &bytes[..bytes.len() / 2]).expect("truncate");
    let err = load_or_build(&scene, d)
        .expect_err("truncated cache")
        .to_string();
    assert!(
        err.contains(&files[0].display().to_string()) && err.contains("delete"),
        "{err}"
    );
}
