//! The reference solution at the evaluation points, computed once per (scene, points, reference settings) and
//! cached under `results/references/<digest>.csv`:
//! - `furnace`: B = E/(1−ρ) (a closed surface with one material: the furnace);
//! - `direct`: B(x) = E(x) + ρ(x) Σ_e E_e F_{dx→e} V(x, e), the exact point-to-polygon factor times a
//!   visibility fraction from 8 × 8 stratified rays (exact for scenes where light bounces once, e.g. the plates);
//! - `pathtrace`: radlab-pathtrace's per-point estimator, whose standard error is the noise floor.
//!
//! `auto` picks `furnace` for a closed one-material scene (every edge shared by exactly two faces, matched by
//! position) and `pathtrace` otherwise.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use radlab_kernels::form_factor;
use radlab_method::EvalPoint;
use radlab_scene::{FaceId, Rgb, Scene, sampling};
use radlab_visibility::{Accel, Segment};
use rayon::prelude::*;

use super::config::{ReferenceConfig, ReferenceKind};
use super::digest;
use crate::output::atomic::write_bytes;

/// Reference values at the evaluation points.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The kind actually used (never `Auto`).
    pub kind: ReferenceKind,
    /// Radiosity per point.
    pub values: Vec<Rgb>,
    /// Standard error per point (zero for analytic references).
    pub std_error: Vec<Rgb>,
    /// Wall seconds it took (0 when read from the cache).
    pub seconds: f64,
    /// The cache file holding it (what child runs read).
    pub file: PathBuf,
}

/// Whether the scene is a closed surface with a single material: the furnace applies.
pub fn is_furnace(scene: &Scene) -> bool {
    let m0 = scene.faces[0].material;
    scene.faces.iter().all(|f| f.material == m0) && scene.is_closed()
}

/// Resolves `Auto`.
pub fn resolve(kind: ReferenceKind, scene: &Scene) -> ReferenceKind {
    match kind {
        ReferenceKind::Auto if is_furnace(scene) => ReferenceKind::Furnace,
        ReferenceKind::Auto => ReferenceKind::Pathtrace,
        k => k,
    }
}

fn furnace(scene: &Scene, points: &[EvalPoint]) -> Result<Vec<Rgb>> {
    if !is_furnace(scene) {
        bail!(
            "reference 'furnace' needs a closed surface with a single material; scene '{}' is not one",
            scene.name
        );
    }
    Ok(points
        .iter()
        .map(|p| scene.emission(p.face) / (Rgb::ONE - scene.reflectance(p.face)))
        .collect())
}

fn direct(scene: &Scene, accel: &Accel, points: &[EvalPoint], seed: u64) -> Vec<Rgb> {
    let emitters: Vec<FaceId> = scene.emitters();
    points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let mut h = Rgb::ZERO;
            for &e in &emitters {
                let poly = scene.polygon(e);
                let f = form_factor::point_polygon(p.point, p.normal, &poly);
                if f <= 0.0 {
                    continue;
                }
                let mut r = sampling::rng(seed, (i * emitters.len() + e) as u64);
                const N: usize = 8;
                let mut segments = [Segment {
                    p: p.point,
                    fp: p.face,
                    q: p.point,
                    fq: e,
                }; N * N];
                for (j, s) in segments.iter_mut().enumerate() {
                    let u = ((j % N) as f64 + sampling::uniform(&mut r)) / N as f64;
                    let v = ((j / N) as f64 + sampling::uniform(&mut r)) / N as f64;
                    s.q = poly.point_at(u, v);
                }
                let mut visible = [false; N * N];
                accel.visible_many(&segments, &mut visible);
                let seen = visible.iter().filter(|&&v| v).count();
                h += scene.emission(e) * f * (seen as f64 / (N * N) as f64);
            }
            scene.emission(p.face) + scene.reflectance(p.face) * h
        })
        .collect()
}

/// The cache file for a reference.
fn cache_path(
    dir: &Path,
    scene: &Scene,
    scene_digest: &str,
    points: &[EvalPoint],
    cfg: &ReferenceConfig,
    kind: ReferenceKind,
) -> PathBuf {
    let mut key = format!(
        "{}|{}|{:?}|{}|{}|",
        scene_digest,
        points.len(),
        kind,
        cfg.samples,
        cfg.seed
    );
    for p in points.iter().take(64) {
        key.push_str(&format!("{:?}", p.point));
    }
    dir.join(format!(
        "{}-{}.csv",
        crate::experiment::config::label_from_spec(&scene.name),
        &digest::hex(key.as_bytes())[..16]
    ))
}

/// Computes (or reads from the cache) the reference at `points`; `scene_digest` is [`digest::scene`] of
/// `scene`, computed once by the caller (it hashes every vertex), which also keys its runs and images by it.
#[allow(clippy::too_many_arguments)]
pub fn reference(
    scene: &Scene,
    scene_digest: &str,
    accel: &Accel,
    points: &[EvalPoint],
    cfg: &ReferenceConfig,
    kind: ReferenceKind,
    cache_dir: &Path,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Reference> {
    let kind = resolve(kind, scene);
    let path = cache_path(cache_dir, scene, scene_digest, points, cfg, kind);
    if let Ok(r) = read_cache(&path, points.len()) {
        return Ok(Reference {
            kind,
            values: r.0,
            std_error: r.1,
            seconds: 0.0,
            file: path,
        });
    }
    let t0 = std::time::Instant::now();
    let (values, std_error) = match kind {
        ReferenceKind::Furnace => (furnace(scene, points)?, vec![Rgb::ZERO; points.len()]),
        ReferenceKind::Direct => (
            direct(scene, accel, points, cfg.seed),
            vec![Rgb::ZERO; points.len()],
        ),
        _ => {
            let params = radlab_pathtrace::PointParams {
                samples: cfg.samples,
                ..Default::default()
            };
            let pts: Vec<radlab_pathtrace::SurfacePoint> = points.iter().map(Into::into).collect();
            let est = radlab_pathtrace::estimate_points_with_progress(
                scene, accel, &pts, &params, cfg.seed, progress,
            );
            (
                est.iter().map(|e| e.mean).collect(),
                est.iter().map(|e| e.std_error).collect(),
            )
        }
    };
    let seconds = t0.elapsed().as_secs_f64();
    write_cache(&path, &values, &std_error)?;
    Ok(Reference {
        kind,
        values,
        std_error,
        seconds,
        file: path,
    })
}

fn write_cache(path: &Path, values: &[Rgb], se: &[Rgb]) -> Result<()> {
    write_bytes(path, |w| {
        let mut out = csv::Writer::from_writer(w);
        out.write_record(["r", "g", "b", "se_r", "se_g", "se_b"])?;
        for (v, s) in values.iter().zip(se) {
            out.write_record([v.x, v.y, v.z, s.x, s.y, s.z].map(|x| format!("{x:e}")))?;
        }
        out.flush()?;
        Ok(())
    })
}

/// Reads a cached reference (values, standard errors), checking its length.
pub fn read_cache(path: &Path, n: usize) -> Result<(Vec<Rgb>, Vec<Rgb>)> {
    let mut rdr = csv::Reader::from_path(path).with_context(|| format!("{}", path.display()))?;
    let mut values = Vec::with_capacity(n);
    let mut se = Vec::with_capacity(n);
    for rec in rdr.records() {
        let rec = rec?;
        let x: Vec<f64> = rec
            .iter()
            .map(|s| s.parse::<f64>())
            .collect::<Result<_, _>>()?;
        if x.len() != 6 {
            bail!("{}: malformed reference row", path.display());
        }
        values.push(Rgb::new(x[0], x[1], x[2]));
        se.push(Rgb::new(x[3], x[4], x[5]));
    }
    if values.len() != n {
        bail!(
            "{}: has {} rows, expected {n}",
            path.display(),
            values.len()
        );
    }
    Ok((values, se))
}
