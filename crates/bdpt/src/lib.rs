//! # radlab-bdpt: bidirectional path tracing
//!
//! Bidirectional path tracing (Lafortune & Willems 1993; Veach & Guibas 1995; Veach 1997, ch. 10) at the
//! points a method is asked about, on radlab-visibility's shared engine and radlab-pathtrace's emitter
//! sampling, query points and stepping.
//!
//! At a surface point x, B(x) = E(x) + ρ(x) H(x). Each sample traces a light subpath (a point on an emitter
//! chosen by power, then cosine-weighted bounces) and an eye subpath from x (cosine-weighted bounces), both
//! ended by Russian roulette, and joins every pair of prefixes — s light and t eye vertices, a path of
//! k = s + t − 1 segments — by one shadow ray (s = 1 draws a fresh emitter point, s = 0 is the eye subpath
//! reaching an emitter). The k + 1 strategies that can make a path of k segments are weighted by the balance
//! or power heuristic (Veach & Guibas 1995) computed from area densities ([`mis_weight`]). The query point
//! is a fixed eye vertex, like a pinhole: the strategy t = 0 (a light subpath hitting x exactly) has
//! probability zero and is left out of the weights, which over the others sum to 1 for every path.
//! Unbiased; its mean equals the path tracer's within their standard errors.
//!
//! | parameter | default | meaning |
//! |---|---|---|
//! | `samples` | 256 | samples per point; standard error ∝ 1/√samples |
//! | `initial_samples` | 16 | samples added by the first step; each later step doubles them |
//! | `max_depth` | 100000 | cap on path segments (a safety net; bias ≤ ρ_max^max_depth) |
//! | `max_light_vertices` | 4 | cap on light subpath vertices; strategies with more are not used (1: path tracing with MIS) |
//! | `heuristic` | `power` | `balance` (w = p/Σp) or `power` (w = p²/Σp²) |
//!
//! **Cost**: a light subpath of about min(1/(1 − ρ̄), `max_light_vertices`) rays, an eye subpath of
//! 1/(1 − ρ̄), and one shadow ray per joined pair (at most `max_light_vertices` + 1 per eye vertex): more
//! rays per sample than the path tracer's 2/(1 − ρ̄), which pays only where light arrives indirectly (through
//! a doorway, from behind a partition: light subpaths carry it to the surfaces it first lands on, which eye
//! subpaths then find). **Does badly**: in bright enclosures (ρ → 1) the connections cost about
//! `max_light_vertices` shadow rays per eye vertex for little gain; point queries do not share light
//! subpaths, so nothing is amortized over points; images are answered per pixel hit point (a fresh estimate
//! at each, through the runner's renderer).

mod bidirectional_estimator;
mod mis_weight;
mod params;
mod point_solver;

pub use bidirectional_estimator::BidirectionalEstimator;
pub use mis_weight::{Densities, Heuristic, mis_weight};
pub use params::BdptParams;
pub use point_solver::{BDPT_STREAM_TAG, BdptSolver};
