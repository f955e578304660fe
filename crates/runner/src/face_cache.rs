//! The face-cluster hierarchy cache: the runner's side of method `face-cluster` (the solver crate reads and
//! writes no file). A hierarchy (Garland, Willmott & Heckbert 2001's greedy contraction, O(k log k)) depends
//! only on the mesh and its build parameters, so it is stored once per digest of both
//! ([`radlab_face_cluster::digest`]) as `<cache_dir>/<digest hex>.fch` and read back bit-identical by later
//! runs. A file that exists but does not read back (truncated, corrupt, another format version, another mesh)
//! is an error naming the file and the fix (delete it): a damaged cache is never silently replaced, so a run's
//! setup time always says what it did. New files are written to a temporary name in the same directory and
//! renamed, so a run stopped mid-write or a concurrent run never leaves a partial file under the final name.

use std::path::{Path, PathBuf};

use radlab_face_cluster::{
    FaceClusterParams, FaceClusterSolveParams, FaceClusterSolver, FaceClusterTree, digest,
    digest_hex,
};
use radlab_method::{MethodParams, SolveError, Solver};
use radlab_scene::Scene;
use radlab_visibility::Accel;

/// Where the hierarchy of `scene` built with `params` is cached under `dir`.
pub fn cache_path(dir: &Path, scene: &Scene, params: &FaceClusterParams) -> PathBuf {
    dir.join(format!("{}.fch", digest_hex(&digest(scene, params))))
}

/// Whether a cached hierarchy was read or built (and written, when a cache directory is set).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CacheOutcome {
    /// Read from the cache.
    Loaded,
    /// Built and written to the cache.
    Built,
    /// Built; no cache directory.
    Uncached,
}

/// The hierarchy of `scene`: read from `dir` when cached there, else built and written there atomically
/// (`dir` empty: built, nothing written).
pub fn load_or_build(
    scene: &Scene,
    dir: &str,
) -> Result<(FaceClusterTree, CacheOutcome), SolveError> {
    let params = FaceClusterParams::default();
    let build = || {
        FaceClusterTree::build(scene, &params)
            .map_err(|e| SolveError::param("scene", e.to_string()))
    };
    if dir.is_empty() {
        return Ok((build()?, CacheOutcome::Uncached));
    }
    let dir = Path::new(dir);
    let path = cache_path(dir, scene, &params);
    let io = |what: &str, p: &Path, e: std::io::Error| {
        SolveError::param(
            "cache_dir",
            format!(
                "{what} {} failed ({e}); fix the directory's permissions, or set cache_dir = \"\" to run without a cache",
                p.display()
            ),
        )
    };
    match std::fs::read(&path) {
        Ok(bytes) => {
            let want = digest(scene, &params);
            let tree = FaceClusterTree::from_bytes(&bytes, Some(&want)).map_err(|e| {
                SolveError::param(
                    "cache_dir",
                    format!(
                        "the cached face-cluster hierarchy {} is unusable: {e} (delete {} and the next run rebuilds it)",
                        path.display(),
                        path.display()
                    ),
                )
            })?;
            if tree.face_order().len() != scene.face_count() {
                return Err(SolveError::param(
                    "cache_dir",
                    format!(
                        "the cached face-cluster hierarchy {} covers {} faces but the scene has {}; delete it and \
                         the next run rebuilds it",
                        path.display(),
                        tree.face_order().len(),
                        scene.face_count()
                    ),
                ));
            }
            Ok((tree, CacheOutcome::Loaded))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let tree = build()?;
            let bytes = tree
                .to_bytes()
                .map_err(|e| SolveError::param("cache_dir", e.to_string()))?;
            std::fs::create_dir_all(dir).map_err(|e| io("creating", dir, e))?;
            let tmp = path.with_extension(format!("fch.tmp{}", std::process::id()));
            std::fs::write(&tmp, &bytes).map_err(|e| io("writing", &tmp, e))?;
            std::fs::rename(&tmp, &path).map_err(|e| {
                let _ = std::fs::remove_file(&tmp);
                io("renaming into", &path, e)
            })?;
            Ok((tree, CacheOutcome::Built))
        }
        Err(e) => Err(io("reading", &path, e)),
    }
}

/// Builds method `face-cluster` from a parameter table: the hierarchy through the cache, then the solver.
pub fn build_solver<'a>(
    scene: &'a Scene,
    accel: &'a Accel,
    table: toml::Table,
    seed: u64,
) -> Result<Box<dyn Solver + 'a>, SolveError> {
    let params = FaceClusterSolveParams::from_table(table)?;
    params.validate()?;
    let (tree, _) = load_or_build(scene, &params.cache_dir)?;
    Ok(Box::new(FaceClusterSolver::with_tree(
        scene, accel, &params, seed, tree,
    )?))
}
