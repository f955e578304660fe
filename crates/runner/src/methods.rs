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

/// A method's test-sized settings, read by the conformance suite (`crates/runner/tests/conformance.rs`): small
/// enough that every case runs in seconds, with the energy-balance tolerance the method states at them.
#[derive(Clone, Copy)]
pub struct TestSettings {
    /// Parameters for a case whose input faces have edge `h` (scene units).
    pub params: fn(h: f64) -> toml::Table,
    /// Runs with independent seeds (1 for a deterministic method; Monte Carlo methods are judged on the mean of
    /// their runs plus three standard errors of it).
    pub seeds: u64,
    /// Relative energy imbalance |absorbed − emitted| / emitted the method states for a converged closed scene
    /// at these settings (0 for an unbiased estimator, whose imbalance is noise only).
    pub balance: f64,
}

/// A TOML table from (key, value) pairs.
pub fn table(pairs: &[(&str, toml::Value)]) -> toml::Table {
    pairs
        .iter()
        .map(|(k, v)| ((*k).to_string(), v.clone()))
        .collect()
}

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
    /// Its test-sized settings for the conformance suite.
    pub test: TestSettings,
}

/// The parameter lines of a params type: its declarations.
pub fn param_lines<P: MethodParams>() -> Vec<ParamLine> {
    P::declarations()
}

macro_rules! method {
    ($name:literal, $summary:expr, $params:ty, $solver:path, $test:expr) => {
        MethodInfo {
            name: $name,
            summary: $summary,
            params: param_lines::<$params>,
            build: |scene, accel, table, seed, _points| {
                let params = <$params as MethodParams>::from_table(table)?;
                Ok(Box::new(<$solver>::new(scene, accel, params, seed)?))
            },
            validate: |table| <$params as MethodParams>::from_table(table).map(|_| ()),
            test: $test,
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
            radlab_matrix::MatrixSolver,
            // Elements = input faces; tolerance 1e-4 on the relative L1 error of B. The matrix is symmetrised
            // and rows sum to 1 in a closed enclosure, so the balance is off only by that error: |imbalance| ≤
            // ((1 − ρ_min)/ρ_min) (ΣAB/Φ) 1e-4 ≤ 2.33 × 3.33 × 1e-4 in the suite's rooms (ρ ∈ [0.3, 0.7]).
            TestSettings {
                params: |h| table(&[("element_size", h.into())]),
                seeds: 1,
                balance: 7.8e-4,
            }
        ),
        method!(
            "progressive",
            "Progressive refinement (Southwell shooting) with adaptive subdivision (substructuring when \
             patch_size exceeds element_size): O(n) memory, a usable image after a few shots; the classic choice \
             for simple scenes.",
            radlab_progressive::ProgressiveParams,
            radlab_progressive::ProgressiveSolver,
            // Elements = patches = input faces, 2 × 2 receiver points. Its crate documentation states a
            // reciprocity error of 1.9e-3 at 2 × 2 points; the stop at an unshot fraction f = 2e-3 leaves an
            // error in the power norm of at most ρ_max/(1 − ρ_max) f Φ, which the absorption weight
            // (1 − ρ_min)/ρ_min turns into an imbalance of at most 2.33 × 2.33 × 2e-3 = 1.09e-2.
            TestSettings {
                params: |h| {
                    table(&[
                        ("element_size", h.into()),
                        ("patch_size", h.into()),
                        ("quadrature", 2.into()),
                    ])
                },
                seeds: 1,
                balance: 1.9e-3 + 1.09e-2,
            }
        ),
        method!(
            "hierarchical",
            "Hierarchical radiosity (Hanrahan, Salzman & Aupperle 1991): quadtrees per input face, links refined by \
             an oracle to a threshold epsilon, gather and push-pull, two-stage/interleaved/scheduled solution.",
            radlab_hierarchical::HierarchicalParams,
            radlab_hierarchical::HierarchicalSolver,
            // The settings under which its crate documentation and tests state the energy balance: the `f`
            // oracle at ε = 0.02 on a closed box conserves energy to about 1e-4 (its test bound is 3e-4);
            // leaves no smaller than 1/16 of an input face.
            TestSettings {
                params: |h| {
                    table(&[
                        ("oracle", "f".into()),
                        ("epsilon", 0.02.into()),
                        ("min_element_size", (h / 16.0).into()),
                    ])
                },
                seeds: 1,
                balance: 3e-4,
            }
        ),
        method!(
            "wavelet",
            "Wavelet radiosity (Gortler, Schroder, Cohen & Hanrahan 1993): hierarchical radiosity with M^2 \
             coefficients per element (basis = haar | f2 | f3 | m2 | m3) and M^4 per link by Gauss quadrature, \
             visibility per pair of quadrature nodes or per link, Bekaert & Willems's oracle; answers by a final \
             gather by default, from the basis itself, or smoothed. linkless = true shoots unshot radiosity \
             without storing links (Stamminger et al. 1998), with an optional bounded link cache \
             (link_cache_mib).",
            radlab_wavelet::WaveletParams,
            radlab_wavelet::WaveletSolver,
            // M2 with the F oracle at ε = 0.02, leaves no smaller than a quarter of an input face, the
            // default leaf gather (each link's tensor re-integrated at every leaf: exact form-factor sums, so
            // the furnaces hold to ~1e-6). The source side sends each inner node's pulled coefficients, not
            // its leaves weighted by what each sees (as hierarchical radiosity does), and tensors are stored in
            // f32: this suite measured an imbalance of 3.7e-5 (2026-12-05); the bound leaves a factor ~3.
            TestSettings {
                params: |h| {
                    table(&[
                        ("basis", "m2".into()),
                        ("oracle", "f".into()),
                        ("epsilon", 0.02.into()),
                        ("min_element_size", (h / 4.0).into()),
                    ])
                },
                seeds: 1,
                balance: 1e-4,
            }
        ),
        method!(
            "volume-cluster",
            "Volume-clustered hierarchical radiosity (Smits, Arvo & Greenberg 1994; Sillion 1995): a loose octree of \
             clusters above the input faces, one root self-link refined by the hierarchical oracles; transfer = \
             isotropic | alpha | directional. No k^2 initial links: for scenes with many input faces.",
            radlab_volume_cluster::VolumeClusterParams,
            radlab_volume_cluster::VolumeClusterSolver,
            // Defaults (α transfer, power norm, ε = 1e-4). Cluster links are point approximations whose row
            // sums are not exact; on the suite's small closed rooms the refinement reaches patch links almost
            // everywhere, so the generic 1% balance applies.
            TestSettings {
                params: |_| toml::Table::new(),
                seeds: 1,
                balance: 1e-2,
            }
        ),
        MethodInfo {
            name: "face-cluster",
            summary: "Face cluster radiosity (Willmott, Heckbert & Garland 1999): face-cluster hierarchies from \
                 dual-graph contraction (cached per mesh digest in cache_dir), irradiance and power vectors per \
                 node, a volume octree above the hierarchies' roots, one self-link refined by the hierarchical \
                 oracles; gather, push and pull never read an input face; answers by a final gather over the tree \
                 by default, or Gouraud-interpolated (reconstruction = gouraud). For detailed meshes.",
            params: param_lines::<radlab_face_cluster::FaceClusterSolveParams>,
            build: |scene, accel, table, seed, _points| {
                crate::face_cache::build_solver(scene, accel, table, seed)
            },
            validate: |table| {
                radlab_face_cluster::FaceClusterSolveParams::from_table(table).map(|_| ())
            },
            // Defaults (ε = 7e-5, final-gather answers). Deterministic; like volume clusters, its cluster links'
            // row sums are not exact, so the generic 1% balance applies.
            test: TestSettings {
                params: |_| toml::Table::new(),
                seeds: 1,
                balance: 1e-2,
            },
        },
        method!(
            "mc-radiosity",
            "Mesh-based Monte Carlo radiosity: particles shot from the emitters and deposited on a fixed element \
             mesh, a batch per step; error falls as N^(-1/2). The Monte Carlo counterpart of matrix and progressive.",
            radlab_pathtrace::McRadiosityParams,
            radlab_pathtrace::McRadiositySolver,
            // 4 runs of 5 × 4,000 particles on elements = input faces. Particle tracing conserves energy (every
            // particle is absorbed somewhere) and the collision estimator is unbiased for each element's mean,
            // so the balance is limited by noise only, which the suite adds.
            TestSettings {
                params: |h| {
                    table(&[
                        ("element_size", h.into()),
                        ("particles_per_step", 4000.into()),
                        ("max_steps", 5.into()),
                    ])
                },
                seeds: 4,
                balance: 0.0,
            }
        ),
        MethodInfo {
            name: crate::pathtraced::NAME,
            summary: crate::pathtraced::SUMMARY,
            params: crate::pathtraced::params,
            build: |scene, accel, table, seed, points| {
                let params = radlab_pathtrace::PathTraceParams::from_table(table)?;
                let points = radlab_pathtrace::surface_points(points);
                Ok(Box::new(radlab_pathtrace::PathTraceSolver::new(
                    scene, accel, params, seed, points,
                )?))
            },
            validate: |table| radlab_pathtrace::PathTraceParams::from_table(table).map(|_| ()),
            // 256 paths per point from 4 independent seeds: unbiased, so every bound is the noise the suite
            // adds (three standard errors of the seeds' mean), and the balance has no bias term.
            test: TestSettings {
                params: |_| table(&[("samples", 256.into())]),
                seeds: 4,
                balance: 0.0,
            },
        },
        MethodInfo {
            name: "irradiance-cache",
            summary: "Ward's irradiance cache (Ward, Rubinstein & Clear 1988; Ward & Heckbert 1992 gradients; \
                 Krivanek et al. 2006 neighbour clamping) at the points asked about: direct light by next-event \
                 estimation at every point, indirect irradiance from records gathered by stratified hemisphere \
                 sampling (paths continued by Russian roulette) and interpolated while Ward's error is below \
                 the accuracy a; built in deterministic passes over the points. Pays when the points are many.",
            params: param_lines::<radlab_irradiance_cache::IrradianceCacheParams>,
            build: |scene, accel, table, seed, points| {
                let params = radlab_irradiance_cache::IrradianceCacheParams::from_table(table)?;
                let points = radlab_pathtrace::surface_points(points);
                Ok(Box::new(
                    radlab_irradiance_cache::IrradianceCacheSolver::new(
                        scene, accel, params, seed, points,
                    )?,
                ))
            },
            validate: |table| {
                radlab_irradiance_cache::IrradianceCacheParams::from_table(table).map(|_| ())
            },
            // 4 runs, a = 0.2, 64 hemisphere directions per record, 16 direct samples per point. Records are
            // unbiased and interpolation is a normalised weighted mean, so furnaces and direct light are exact
            // up to noise (which the suite adds). The balance is not: interpolating a record's irradiance to a
            // point ε away errs by up to about ε < a relatively on Ward's split-sphere model (Ward, Rubinstein &
            // Clear 1988, §2.2), and only the indirect part (at most all of the absorbed power) is
            // interpolated: a.
            test: TestSettings {
                params: |_| {
                    table(&[
                        ("accuracy", 0.2.into()),
                        ("samples", 64.into()),
                        ("direct_samples", 16.into()),
                    ])
                },
                seeds: 4,
                balance: 0.2,
            },
        },
        MethodInfo {
            name: "photon-map",
            summary: "Photon maps (Jensen 1996; Christensen 1999) at the points asked about: photons from the \
                 emitters with Russian roulette, k-nearest-neighbour density estimates over a kiddo k-d tree; \
                 mode = final-gather (direct light by next-event estimation, one gather bounce reading \
                 precomputed irradiance) or progressive (Hachisuka, Ogaki & Jensen 2008: radius shrinking per \
                 pass, consistent). Biased by the density estimate near edges and on relief.",
            params: param_lines::<radlab_photon_map::PhotonMapParams>,
            build: |scene, accel, table, seed, points| {
                let params = radlab_photon_map::PhotonMapParams::from_table(table)?;
                let points = radlab_pathtrace::surface_points(points);
                Ok(Box::new(radlab_photon_map::PhotonMapSolver::new(
                    scene, accel, params, seed, points,
                )?))
            },
            validate: |table| radlab_photon_map::PhotonMapParams::from_table(table).map(|_| ()),
            // 4 runs of the final gather: 20,000 photons, 32 gather rays and 8 direct samples per point. The
            // density estimate is biased near edges, one bounce removed from the answer; no closed-form bound on
            // that bias is derived here, so the balance is held to the generic 1%.
            test: TestSettings {
                params: |_| {
                    table(&[
                        ("photons", 20000.into()),
                        ("gather_samples", 32.into()),
                        ("direct_samples", 8.into()),
                    ])
                },
                seeds: 4,
                balance: 1e-2,
            },
        },
        MethodInfo {
            name: "bdpt",
            summary: "Bidirectional path tracing (Lafortune & Willems 1993; Veach & Guibas 1995; Veach 1997) at \
                 the points asked about: per sample a light subpath from the emitters and an eye subpath from \
                 the point, joined by every strategy (the point is a pinhole: a light path hitting it exactly \
                 is impossible and left out) and weighted by multiple importance sampling, heuristic = balance \
                 or power; Russian roulette lengths. Unbiased; pays where light arrives indirectly.",
            params: param_lines::<radlab_bdpt::BdptParams>,
            build: |scene, accel, table, seed, points| {
                let params = radlab_bdpt::BdptParams::from_table(table)?;
                let points = radlab_pathtrace::surface_points(points);
                Ok(Box::new(radlab_bdpt::BdptSolver::new(
                    scene, accel, params, seed, points,
                )?))
            },
            validate: |table| radlab_bdpt::BdptParams::from_table(table).map(|_| ()),
            // 256 samples per point from 4 independent seeds: unbiased, so every bound is the noise the suite
            // adds (three standard errors of the seeds' mean), and the balance has no bias term.
            test: TestSettings {
                params: |_| table(&[("samples", 256.into())]),
                seeds: 4,
                balance: 0.0,
            },
        },
        method!(
            "radiosity-texture",
            "Adaptive radiosity textures (Heckbert 1990): particles from the emitters, reflected by Russian \
             roulette, deposit their power in a quadtree histogram per face (a rex) whose leaves split when \
             they hold more than split_threshold particles (split = count) and, under split = contrast, only \
             where the children's densities differ (shadow edges); B = E + rho Phi/(N_e A) per leaf, read at \
             points as constant, gouraud or final-gather.",
            radlab_radiosity_texture::RadiosityTextureParams,
            radlab_radiosity_texture::RadiosityTextureSolver,
            // 4 runs of 2 passes, 40,000 landings in all, the contrast rule at 64 particles a leaf (so a
            // uniformly lit face keeps large, less noisy leaves; the count rule's leaves of at most 64
            // landings are judged as well, by radlab-radiosity-texture's own furnace test). Each leaf's value is
            // an unbiased estimate of its mean and particle tracing conserves power (every particle is absorbed
            // somewhere), so the balance is limited by noise only, which the suite adds.
            TestSettings {
                params: |_| {
                    table(&[
                        ("particles", 40000.into()),
                        ("passes", 2.into()),
                        ("split", "contrast".into()),
                        ("split_threshold", 64.into()),
                    ])
                },
                seeds: 4,
                balance: 0.0,
            }
        ),
        method!(
            "density-estimation",
            "Density estimation (Shirley, Wade, Hubbard, Zareski, Walter & Greenberg 1995; Walter, Hubbard, \
             Shirley & Greenberg 1997): particles from the emitters with Russian roulette, every landing kept \
             per surface (edge-connected faces of one material within a normal cone), irradiance by an \
             Epanechnikov kernel estimate in the surface's plane with local linear boundary correction, \
             bandwidth c sqrt(A) n^(-1/6); answers at the point, over a Gouraud display mesh, by final gather \
             or as the per-face histogram. No shadow rays or gathers while solving.",
            radlab_density_estimation::DensityEstimationParams,
            radlab_density_estimation::DensityEstimationSolver,
            // 4 runs of 2 steps × 50,000 landings, display elements of the case's face size. The balance case
            // answers by the histogram (reconstruction = constant): every landing's power is counted on the
            // face it hits and particle tracing absorbs exactly what is emitted, so the balance is unbiased
            // (noise only, which the suite adds).
            TestSettings {
                params: |h| {
                    table(&[
                        ("particles", 50000.into()),
                        ("steps", 2.into()),
                        ("element_size", h.into()),
                    ])
                },
                seeds: 4,
                balance: 0.0,
            }
        ),
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
