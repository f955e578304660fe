//! Density estimation as a method (Shirley, Wade, Hubbard, Zareski, Walter & Greenberg 1995, "Global
//! illumination via density estimation", EGWR; Walter, Hubbard, Shirley & Greenberg 1997, ACM TOG 16(3)).
//!
//! Phase 1, particle tracing: radlab-pathtrace's `trace_photons` sends particles from the emitters with
//! Russian roulette; every landing (point, face, power Φ_i, the photon map's unit: power before division by
//! the N_e particles emitted) is kept, on the surface of its face (surfaces.rs). Phase 2, density estimation:
//! the irradiance at x on surface s is the kernel estimate over s's landings in s's plane,
//!
//! H(x) = (1/(N_e h_s²)) Σ_{i ∈ s} Φ_i c_i K̃(ξ_i) (l₀ + l₁ξ_{i1} + l₂ξ_{i2}),  ξ_i = (P X_i − P x)/h_s,
//!
//! with c_i the projection's area factor and l the local linear weights (local_linear.rs), and the bandwidth
//! h_s = c √A_s n_s^(−1/6) from the n_s landings on s (or a fixed `bandwidth_size`). Negative estimates (local
//! linear weights change sign near boundaries, and dark regions are noisy) are clamped to 0. Phase 3, the
//! answer B(x) = E(x) + ρ(x) H(x): the estimate at x (`density`), Gouraud over a display mesh of the estimate
//! at its vertices (`mesh`, radlab-answer's `interpolate_corners`), a final gather from the display mesh's
//! elements valued at their centroids (`final-gather`, radlab-answer's `Reconstructor`), or the per-face
//! histogram Σ_{i on f} Φ_i / (N_e A_f) (`constant`).
//!
//! Each step traces `particles` more landings (streams never overlap between steps) and rebuilds each
//! touched surface's k-d tree (kiddo); the estimate is over every landing so far. Results are the same for
//! any thread count: tracing is chunked by stream, landings are appended in emission order, and every kernel
//! sum runs over the particles in index order. Rays (tracing) go through the shared `Accel`'s counter; bytes
//! count the landings, trees, surfaces, histogram, display mesh and whatever answering has built.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::{DVec2, DVec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use radlab_answer::gouraud::interpolate_corners;
use radlab_answer::{ElementMesh, Reconstruction, Reconstructor, element_size};
use radlab_method::{MethodParams, Solution, SolveError, Solver, Stats, Step};
use radlab_pathtrace::{EmitterSampler, trace_photons};
use radlab_scene::{FaceId, Rgb, Scene, sampling::mix64};
use radlab_visibility::Accel;
use rayon::prelude::*;

use crate::local_linear::epanechnikov;
use crate::params::{DensityEstimationParams, DensityReconstruction};
use crate::surfaces::Surfaces;

const PARTICLE_STREAM_TAG: u64 = 0x6465_6e73_6974_7931; // "density1"
/// Chunks of particles reserved per step (streams never overlap between steps).
const CHUNKS_PER_STEP: u64 = 1 << 32;

/// The landings on one surface.
#[derive(Debug, Default)]
struct SurfaceParticles {
    /// Positions in the surface's coordinates.
    points: Vec<[f64; 2]>,
    /// Φ_i c_i (not yet divided by N_e).
    power: Vec<Rgb>,
    tree: Option<ImmutableKdTree<f64, 2>>,
    /// h_s, scene units.
    bandwidth: f64,
}

impl SurfaceParticles {
    fn bytes(&self) -> usize {
        self.points.capacity() * size_of::<[f64; 2]>()
            + self.power.capacity() * size_of::<Rgb>()
            + self
                .tree
                .as_ref()
                .map_or(0, |_| self.points.len() * (16 + 8))
    }
}

/// Density estimation's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DensityCounts {
    /// Particles emitted so far (N_e).
    pub emitted: u64,
    /// Landings stored so far.
    pub landings: u64,
    /// Surfaces (face groups) the estimate is taken over.
    pub surfaces: u64,
    /// Surfaces holding at least one landing.
    pub lit_surfaces: u64,
    /// Kernel evaluations (a landing inside a kernel's disc) spent answering so far.
    pub kernel_evaluations: u64,
}

/// Density estimation over the whole scene (view-independent; the points asked about are answered from it).
pub struct DensityEstimationSolver<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    params: DensityEstimationParams,
    emitters: EmitterSampler,
    seed: u64,
    surfaces: Surfaces,
    particles: Vec<SurfaceParticles>,
    /// Σ Φ_i landing on each face (the histogram).
    face_power: Vec<Rgb>,
    emitted: u64,
    landings: u64,
    steps: u64,
    rays: u64,
    /// The display mesh (mesh and final-gather answers).
    mesh: Option<ElementMesh>,
    /// H at each display element's corners, built at the first mesh answer after a step.
    corners: OnceLock<Vec<[Rgb; 4]>>,
    output: Reconstructor,
    kernel_evaluations: AtomicU64,
}

impl std::fmt::Debug for DensityEstimationSolver<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DensityEstimationSolver")
            .field("counts", &self.counts())
            .field("params", &self.params)
            .finish()
    }
}

impl<'a> DensityEstimationSolver<'a> {
    /// Groups the scene's faces into surfaces (and meshes it for display if the answer needs it); nothing
    /// traced yet. Fails on invalid parameters.
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        params: DensityEstimationParams,
        seed: u64,
    ) -> Result<Self, SolveError> {
        params.validate()?;
        let mesh = match params.reconstruction {
            DensityReconstruction::Mesh | DensityReconstruction::FinalGather => Some(
                ElementMesh::new(scene, element_size(params.element_size, scene)?),
            ),
            _ => None,
        };
        let surfaces = Surfaces::new(scene, params.group_angle.to_radians().cos());
        let particles = (0..surfaces.surfaces.len())
            .map(|_| SurfaceParticles::default())
            .collect();
        Ok(Self {
            scene,
            accel,
            emitters: EmitterSampler::new(scene),
            seed,
            particles,
            surfaces,
            face_power: vec![Rgb::ZERO; scene.face_count()],
            emitted: 0,
            landings: 0,
            steps: 0,
            rays: 0,
            mesh,
            corners: OnceLock::new(),
            output: Reconstructor::new(Reconstruction::FinalGather, seed),
            kernel_evaluations: AtomicU64::new(0),
            params,
        })
    }

    /// The counters.
    pub fn counts(&self) -> DensityCounts {
        DensityCounts {
            emitted: self.emitted,
            landings: self.landings,
            surfaces: self.surfaces.surfaces.len() as u64,
            lit_surfaces: self
                .particles
                .iter()
                .filter(|p| !p.points.is_empty())
                .count() as u64,
            kernel_evaluations: self.kernel_evaluations.load(Ordering::Relaxed),
        }
    }

    /// The surfaces the estimate is taken over.
    pub fn surfaces(&self) -> &Surfaces {
        &self.surfaces
    }

    /// The bandwidth h_s of surface `s` (scene units; 0 while it holds no landing).
    pub fn bandwidth(&self, s: usize) -> f64 {
        self.particles[s].bandwidth
    }

    /// The histogram's irradiance on face `f`: Σ Φ_i / (N_e A_f).
    fn histogram(&self, f: FaceId) -> Rgb {
        if self.emitted == 0 {
            return Rgb::ZERO;
        }
        self.face_power[f] / (self.emitted as f64 * self.scene.faces[f].area)
    }

    /// The kernel estimate of the irradiance at `point` on `face` (clamped at 0).
    pub fn irradiance(&self, face: FaceId, point: DVec3) -> Rgb {
        let s = self.surfaces.of_face[face] as usize;
        let sp = &self.particles[s];
        let Some(tree) = &sp.tree else {
            return Rgb::ZERO;
        };
        let surface = &self.surfaces.surfaces[s];
        let x = surface.project(point);
        let h = sp.bandwidth;
        let Some(l) = surface.domain.weights(x, h, self.params.boundary) else {
            return self.histogram(face);
        };
        let mut idx: Vec<u64> = tree
            .within_unsorted::<SquaredEuclidean>(&[x.x, x.y], h * h)
            .iter()
            .map(|n| n.item)
            .collect();
        idx.sort_unstable();
        self.kernel_evaluations
            .fetch_add(idx.len() as u64, Ordering::Relaxed);
        let mut sum = Rgb::ZERO;
        for i in idx {
            let p = sp.points[i as usize];
            let xi = (DVec2::new(p[0], p[1]) - x) / h;
            let k = epanechnikov(xi.length_squared());
            sum += sp.power[i as usize] * (k * (l.x + l.y * xi.x + l.z * xi.y));
        }
        (sum / (h * h * self.emitted as f64)).max(Rgb::ZERO)
    }

    /// B = E + ρ H with H from the kernel estimate.
    fn density_radiosity(&self, face: FaceId, point: DVec3) -> Rgb {
        self.scene.emission(face) + self.scene.reflectance(face) * self.irradiance(face, point)
    }

    fn corner_values(&self, mesh: &ElementMesh) -> Vec<[Rgb; 4]> {
        mesh.elements
            .par_iter()
            .map(|e| {
                let mut c = [Rgb::ZERO; 4];
                for (k, &v) in e.polygon.vertices().iter().enumerate() {
                    c[k] = self.irradiance(e.face as FaceId, v);
                }
                c
            })
            .collect()
    }

    /// One step: `particles` more landings, sorted to their surfaces, trees and bandwidths rebuilt.
    fn trace(&mut self) {
        let batch = trace_photons(
            self.scene,
            self.accel,
            &self.emitters,
            self.params.particles,
            self.steps * CHUNKS_PER_STEP,
            mix64(self.seed ^ PARTICLE_STREAM_TAG),
            self.params.max_depth,
            &|_| true,
        );
        self.emitted += batch.emitted;
        self.landings += batch.photons.len() as u64;
        let mut touched = vec![false; self.particles.len()];
        for p in &batch.photons {
            let s = self.surfaces.of_face[p.face] as usize;
            let surface = &self.surfaces.surfaces[s];
            let x = surface.project(p.point);
            let c = p.normal.dot(surface.normal);
            let sp = &mut self.particles[s];
            sp.points.push([x.x, x.y]);
            sp.power.push(p.power * c);
            self.face_power[p.face] += p.power;
            touched[s] = true;
        }
        let fixed = self.params.bandwidth_size;
        let c = self.params.bandwidth;
        let surfaces = &self.surfaces.surfaces;
        self.particles
            .par_iter_mut()
            .enumerate()
            .filter(|(s, _)| touched[*s])
            .for_each(|(s, sp)| {
                sp.tree = Some(ImmutableKdTree::new_from_slice(&sp.points));
                let n = sp.points.len() as f64;
                sp.bandwidth = fixed
                    .unwrap_or_else(|| c * surfaces[s].domain.area().sqrt() * n.powf(-1.0 / 6.0));
            });
        self.corners = OnceLock::new();
        self.output.invalidate();
    }

    fn bytes(&self) -> u64 {
        (self.surfaces.bytes()
            + self
                .particles
                .iter()
                .map(SurfaceParticles::bytes)
                .sum::<usize>()
            + self.face_power.capacity() * size_of::<Rgb>()
            + self.mesh.as_ref().map_or(0, ElementMesh::bytes)
            + self
                .corners
                .get()
                .map_or(0, |c| c.capacity() * size_of::<[Rgb; 4]>())
            + self.output.bytes()) as u64
    }
}

impl Solver for DensityEstimationSolver<'_> {
    fn step(&mut self) -> Result<Step, SolveError> {
        if self.steps >= self.params.steps as u64 {
            return Ok(Step::Converged);
        }
        let rays0 = self.accel.rays_cast();
        self.trace();
        self.rays += self.accel.rays_cast() - rays0;
        self.steps += 1;
        Ok(if self.steps >= self.params.steps as u64 {
            Step::Converged
        } else {
            Step::Continue
        })
    }

    fn solution(&self) -> &dyn Solution {
        self
    }

    fn stats(&self) -> Stats {
        Stats {
            steps: self.steps,
            elements: self.landings,
            links: 0,
            form_factors: 0,
            rays: self.rays,
            bytes: self.bytes(),
            residual: None,
        }
    }

    fn counters(&self) -> Vec<(&'static str, u64)> {
        let c = self.counts();
        vec![
            ("emitted", c.emitted),
            ("landings", c.landings),
            ("surfaces", c.surfaces),
            ("lit_surfaces", c.lit_surfaces),
            ("kernel_evaluations", c.kernel_evaluations),
        ]
    }
}

impl Solution for DensityEstimationSolver<'_> {
    fn answer_kernel_evaluations(&self) -> u64 {
        self.output.gather_work().1
    }

    fn radiosity_at(&self, face: FaceId, point: DVec3) -> Rgb {
        if face >= self.scene.faces.len() {
            return Rgb::splat(f64::NAN);
        }
        let constant =
            || self.scene.emission(face) + self.scene.reflectance(face) * self.histogram(face);
        match (self.params.reconstruction, &self.mesh) {
            (DensityReconstruction::Density, _) => self.density_radiosity(face, point),
            (DensityReconstruction::Constant, _) => constant(),
            (DensityReconstruction::Mesh, Some(mesh)) => {
                let corners = self.corners.get_or_init(|| self.corner_values(mesh));
                let e = mesh.locate(face, point);
                let h = interpolate_corners(&mesh.elements[e].polygon, &corners[e], point);
                self.scene.emission(face) + self.scene.reflectance(face) * h.max(Rgb::ZERO)
            }
            (DensityReconstruction::FinalGather, Some(mesh)) => self.output.radiosity_at(
                self.scene,
                self.accel,
                face,
                point,
                constant,
                || Some(mesh.locate(face, point)),
                || {
                    let b: Vec<Rgb> = mesh
                        .elements
                        .par_iter()
                        .map(|e| self.density_radiosity(e.face as FaceId, e.centroid))
                        .collect();
                    mesh.values(&b)
                },
            ),
            _ => constant(),
        }
    }
}
