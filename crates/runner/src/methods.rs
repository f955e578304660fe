//! The method registry: every solver radlab can run, by name, with its parameters and defaults. A new solver
//! crate plugs in here with one entry; nothing else in the runner changes.

use radlab_method::{EvalPoint, MethodParams, SolveError, Solver};
use radlab_scene::Scene;
use radlab_visibility::Accel;

/// Builds a solver from the scene, its accelerator, a parameter table, a seed and the points it will be asked
/// about. Only methods that answer per point (path tracing) use the points: they trace there in their steps.
/// Finite-element methods solve the whole scene and ignore them.
pub type BuildFn = for<'a> fn(
    &'a Scene,
    &'a Accel,
    toml::Table,
    u64,
    &[EvalPoint],
) -> Result<Box<dyn Solver + 'a>, SolveError>;

/// One declared parameter (name, kind, range, default, help), as `radlab methods` prints it.
pub type ParamLine = radlab_method::ParamDecl;

/// A registered method.
pub struct MethodInfo {
    /// Name for `--method`.
    pub name: &'static str,
    /// One paragraph: what it is and when to use it.
    pub summary: &'static str,
    /// Its parameters.
    pub params: fn() -> Vec<ParamLine>,
    /// Builds the solver.
    pub build: BuildFn,
    /// Checks a parameter table without a scene (config validation).
    pub validate: fn(toml::Table) -> Result<(), SolveError>,
}

/// The parameter lines of a params type: its declarations.
pub fn param_lines<P: MethodParams>() -> Vec<ParamLine> {
    P::declarations()
}

macro_rules! method {
    ($name:literal, $summary:expr, $params:ty, $solver:path) => {
        MethodInfo {
            name: $name,
            summary: $summary,
            params: param_lines::<$params>,
            build: |scene, accel, table, seed, _points| {
                let params = <$params as MethodParams>::from_table(table)?;
                Ok(Box::new(<$solver>::new(scene, accel, params, seed)?))
            },
            validate: |table| <$params as MethodParams>::from_table(table).map(|_| ()),
        }
    };
}

/// Every registered solver method.
pub fn methods() -> Vec<MethodInfo> {
    vec![
        method!(
            "matrix",
            "Full form-factor matrix over a fixed element mesh; Jacobi, Gauss-Seidel or conjugate gradient. \
             O(n^2) memory and assembly: the accuracy reference among finite-element methods for small meshes.",
            radlab_matrix::MatrixParams,
            radlab_matrix::MatrixSolver
        ),
        method!(
            "progressive",
            "Progressive refinement (Southwell shooting) with substructuring and adaptive subdivision: O(n) \
             memory, a usable image after a few shots; the classic choice for simple scenes.",
            radlab_progressive::ProgressiveParams,
            radlab_progressive::ProgressiveSolver
        ),
        method!(
            "hierarchical",
            "Hierarchical radiosity (Hanrahan, Salzman & Aupperle 1991): quadtrees per input face, links refined by \
             an oracle to a threshold epsilon, gather and push-pull, two-stage/interleaved/scheduled solution.",
            radlab_hierarchical::HierarchicalParams,
            radlab_hierarchical::HierarchicalSolver
        ),
        method!(
            "volume-cluster",
            "Volume-clustered hierarchical radiosity (Smits, Arvo & Greenberg 1994; Sillion 1995): a loose octree of \
             clusters above the input faces, one root self-link refined by the hierarchical oracles; transfer = \
             isotropic | alpha | directional. No k^2 initial links: for scenes with many input faces.",
            radlab_volume_cluster::VolumeClusterParams,
            radlab_volume_cluster::VolumeClusterSolver
        ),
        MethodInfo {
            name: "face-cluster",
            summary: "Face cluster radiosity (Willmott, Heckbert & Garland 1999): face-cluster hierarchies from \
                 dual-graph contraction (cached per mesh digest in cache_dir), irradiance and power vectors per \
                 node, a volume octree above the hierarchies' roots, one self-link refined by the hierarchical \
                 oracles; gather, push and pull never read an input face; answers Gouraud-interpolated by default, \
                 or a final gather over the tree (reconstruction = final-gather). For detailed meshes.",
            params: param_lines::<radlab_face_cluster::FaceClusterSolveParams>,
            build: |scene, accel, table, seed, _points| {
                crate::face_cache::build_solver(scene, accel, table, seed)
            },
            validate: |table| {
                radlab_face_cluster::FaceClusterSolveParams::from_table(table).map(|_| ())
            },
        },
        method!(
            "mc-radiosity",
            "Mesh-based Monte Carlo radiosity: particles shot from the emitters and deposited on a fixed element \
             mesh, a batch per step; error falls as N^(-1/2). The Monte Carlo counterpart of matrix and progressive.",
            radlab_pathtrace::McRadiosityParams,
            radlab_pathtrace::McRadiositySolver
        ),
        MethodInfo {
            name: crate::pathtraced::NAME,
            summary: crate::pathtraced::SUMMARY,
            params: crate::pathtraced::params,
            build: |scene, accel, table, seed, points| {
                let params = radlab_pathtrace::PathTraceParams::from_table(table)?;
                let points = points
                    .iter()
                    .map(radlab_pathtrace::SurfacePoint::from)
                    .collect();
                Ok(Box::new(radlab_pathtrace::PathTraceSolver::new(
                    scene, accel, params, seed, points,
                )?))
            },
            validate: |table| radlab_pathtrace::PathTraceParams::from_table(table).map(|_| ()),
        },
    ]
}

/// The method of that name, or an error listing the methods.
pub fn find(name: &str) -> anyhow::Result<MethodInfo> {
    let all = methods();
    let names: Vec<&str> = all.iter().map(|m| m.name).collect();
    all.into_iter().find(|m| m.name == name).ok_or_else(|| {
        anyhow::anyhow!(
            "unknown method '{name}'; methods are: {} (see `radlab methods`)",
            names.join(", ")
        )
    })
}

/// Checks that `method` exists and `table` holds valid parameters for it.
pub fn validate_params(method: &str, table: toml::Table) -> anyhow::Result<()> {
    let m = find(method)?;
    (m.validate)(table)?;
    Ok(())
}
