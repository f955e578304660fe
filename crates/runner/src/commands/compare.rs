//! `radlab compare A.points.csv B.points.csv …`: which of two runs is closer to the reference, and by more than
//! the evaluation points can tell. Each run's answers at the evaluation points (`runs/<id>.points.csv` of
//! `radlab run`) are measured with the runner's relative L1 (`radlab_method::error_metric`; the points carry
//! equal area weights), and every pair's difference L1(A) − L1(B) gets a 95% percentile bootstrap interval
//! over the points (Efron & Tibshirani 1993, ch. 13): the points are resampled with replacement, the same
//! resamples for every run, so the interval is that of the paired difference, in which what the runs share
//! (the points, the reference's noise at each point) largely cancels. A resample is a weighting of the points
//! by how often each was drawn, so each resample's errors are the same metric with those weights.
//!
//! Besides runs' points files, compare reads answers at points as `radlab probe` prints them and as the scripts
//! of `radlab export` write them (columns `x,y,z,r,g,b` and optionally `se_r,se_g,se_b`): such a file's values
//! are its own reference, and its standard errors are its own. Files are matched row by row at equal x, y, z.
//! When a run carries its own standard errors, its z uses both: z = (B − R) / √(s_R² + s_B²), so two
//! independent Monte Carlo answers that agree have mean z² about 1 (the cross-checks against Radiance and
//! Mitsuba: `radlab compare radiance.csv mitsuba.csv --reference radlab.csv`).
//!
//! `--reference R.points.csv` measures every run against R's reference instead of its own (the same points,
//! checked: the reference's cache is keyed by its path count, so a sharper reference for points already
//! answered is one `radlab run` of a quick method with more `[reference] samples`). Without it the runs must
//! share one reference.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use radlab_method::error_metric;
use radlab_scene::{Rgb, sampling};

use crate::experiment::execute::PointRow;

/// Options of `radlab compare`.
#[derive(Clone, Debug, clap::Args)]
pub struct CompareArgs {
    /// Two or more runs' `runs/<id>.points.csv` files, from the same evaluation points.
    #[arg(required = true, num_args = 2..)]
    pub runs: Vec<PathBuf>,
    /// Measure every run against this file's reference (`ref_*`, `se_*` columns) instead of its own.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Bootstrap resamples of the points.
    #[arg(long, default_value_t = 2000)]
    pub resamples: usize,
    /// Seed of the bootstrap's resampling.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// One evaluation point as a points file gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointAnswer {
    /// The face the point lies on.
    pub face: usize,
    /// Where it is.
    pub at: [f64; 3],
    /// The reference's value.
    pub reference: Rgb,
    /// The reference's standard error.
    pub std_error: Rgb,
    /// The run's answer.
    pub value: Rgb,
    /// The run's own standard error (zero for a runs/<id>.points.csv, whose answers are deterministic or
    /// whose error is the point of the comparison).
    pub own_std_error: Rgb,
}

/// The face of a point read from a file that does not name faces (probe and export answers).
pub const UNKNOWN_FACE: usize = usize::MAX;

/// Reads a points file. Errors name the file and the data row (1-based, header excluded).
pub fn read_points(path: &Path) -> Result<Vec<PointAnswer>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    let mut rdr = csv::Reader::from_reader(text.as_bytes());
    let header = rdr
        .headers()
        .with_context(|| format!("{}: cannot read the header", path.display()))?
        .clone();
    if !header.iter().any(|h| h == "ref_r") && header.iter().any(|h| h == "r") {
        return read_probe_answers(path, &text);
    }
    let mut out = Vec::new();
    for (i, rec) in rdr.deserialize::<PointRow>().enumerate() {
        let row = i + 1;
        let r = rec.with_context(|| {
            format!(
                "{}: row {row}: not a points file row (a run's runs/<id>.points.csv has columns \
                 point,face,x,y,z,ref_r,ref_g,ref_b,se_r,se_g,se_b,r,g,b,rel_error,z_score)",
                path.display()
            )
        })?;
        let numbers = [
            ("x", r.x),
            ("y", r.y),
            ("z", r.z),
            ("ref_r", r.ref_r),
            ("ref_g", r.ref_g),
            ("ref_b", r.ref_b),
            ("se_r", r.se_r),
            ("se_g", r.se_g),
            ("se_b", r.se_b),
            ("r", r.r),
            ("g", r.g),
            ("b", r.b),
        ];
        if let Some((name, v)) = numbers.iter().find(|(_, v)| !v.is_finite()) {
            bail!(
                "{}: row {row}: column {name} is {v}, not a finite number (a run that failed or was cut \
                 short has no answers to compare)",
                path.display()
            );
        }
        out.push(PointAnswer {
            face: r.face,
            at: [r.x, r.y, r.z],
            reference: Rgb::new(r.ref_r, r.ref_g, r.ref_b),
            std_error: Rgb::new(r.se_r, r.se_g, r.se_b),
            value: Rgb::new(r.r, r.g, r.b),
            own_std_error: Rgb::ZERO,
        });
    }
    if out.is_empty() {
        bail!("{}: no points", path.display());
    }
    Ok(out)
}

/// Reads answers at points (`x,y,z,r,g,b[,se_r,se_g,se_b]`: `radlab probe`'s output, the export scripts'):
/// each value is its own reference, with its own standard error (zero without `se_*` columns).
fn read_probe_answers(path: &Path, text: &str) -> Result<Vec<PointAnswer>> {
    let mut rdr = csv::Reader::from_reader(text.as_bytes());
    let header = rdr.headers()?.clone();
    let col = |name: &str| header.iter().position(|h| h == name);
    let need = ["x", "y", "z", "r", "g", "b"];
    let cols: Vec<usize> = need
        .iter()
        .map(|n| {
            col(n).ok_or_else(|| {
                anyhow::anyhow!(
                    "{}: column {n} is missing; an answers file has columns x,y,z,r,g,b[,se_r,se_g,se_b]",
                    path.display()
                )
            })
        })
        .collect::<Result<_>>()?;
    let se_cols = match (col("se_r"), col("se_g"), col("se_b")) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };
    let mut out = Vec::new();
    for (i, rec) in rdr.records().enumerate() {
        let row = i + 1;
        let rec = rec.with_context(|| format!("{}: row {row}: malformed CSV", path.display()))?;
        let num = |c: usize| -> Result<f64> {
            let s = rec.get(c).unwrap_or("");
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    anyhow::anyhow!(
                        "{}: row {row}: column {}: '{s}' is not a finite number",
                        path.display(),
                        header.get(c).unwrap_or("?")
                    )
                })
        };
        let v: Vec<f64> = cols.iter().map(|&c| num(c)).collect::<Result<_>>()?;
        let se = match se_cols {
            Some([a, b, c]) => Rgb::new(num(a)?, num(b)?, num(c)?),
            None => Rgb::ZERO,
        };
        let value = Rgb::new(v[3], v[4], v[5]);
        out.push(PointAnswer {
            face: UNKNOWN_FACE,
            at: [v[0], v[1], v[2]],
            reference: value,
            std_error: se,
            value,
            own_std_error: se,
        });
    }
    if out.is_empty() {
        bail!("{}: no points", path.display());
    }
    Ok(out)
}

/// One run measured against the common reference.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSummary {
    /// Relative L1 (the runner's metric).
    pub l1: f64,
    /// Signed mean error Σ Σ_c (B − R) / Σ Σ_c |R|: the L1 of a bias that is all one sign.
    pub signed: f64,
    /// Mean of ((B − R)/s)² over points and channels with s > 0; `None` if the reference has no standard
    /// errors (analytic). About 1 when the run's error is the reference's noise alone. Where the run has its own
    /// standard error s_B, s = √(s_R² + s_B²).
    pub mean_z2: Option<f64>,
    /// Relative L1 within each quarter of the points by reference radiosity (channel mean), darkest first.
    pub quartiles: [f64; 4],
}

/// A pair's difference of relative L1, with its bootstrap interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairedDifference {
    /// L1(a) − L1(b) over all points.
    pub diff: f64,
    /// 2.5th percentile over the resamples.
    pub low: f64,
    /// 97.5th percentile over the resamples.
    pub high: f64,
}

/// The runs' answers against one reference: `values[k][i]` is run k's answer at point i.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// The reference at each point.
    pub reference: Vec<Rgb>,
    /// Its standard errors.
    pub std_error: Vec<Rgb>,
    /// Each run's answers.
    pub values: Vec<Vec<Rgb>>,
    /// Each run's own standard errors (zero where it has none).
    pub own_std_error: Vec<Vec<Rgb>>,
}

impl Comparison {
    /// The reference's own noise floor (the L1 its standard errors alone would give).
    pub fn noise_floor(&self) -> f64 {
        let w = vec![1.0; self.reference.len()];
        error_metric::noise_floor(&self.reference, &self.std_error, &w).l1
    }

    /// Run `k` measured against the reference.
    pub fn summary(&self, k: usize) -> RunSummary {
        let (v, r) = (&self.values[k], &self.reference);
        let s: Vec<Rgb> = self
            .std_error
            .iter()
            .zip(&self.own_std_error[k])
            .map(|(a, b)| (*a * *a + *b * *b).map(f64::sqrt))
            .collect();
        let n = r.len();
        let ones = vec![1.0; n];
        let l1 = error_metric::errors(v, r, &ones).l1;
        let total: f64 = r.iter().map(|x| x.abs().element_sum()).sum();
        let signed = v
            .iter()
            .zip(r)
            .map(|(a, b)| (*a - *b).element_sum())
            .sum::<f64>()
            / total;
        let (mut z2, mut count) = (0.0, 0usize);
        for ((a, b), e) in v.iter().zip(r).zip(&s) {
            for c in 0..3 {
                if e[c] > 0.0 {
                    z2 += ((a[c] - b[c]) / e[c]).powi(2);
                    count += 1;
                }
            }
        }
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&i, &j| r[i].element_sum().total_cmp(&r[j].element_sum()));
        let quartiles = std::array::from_fn(|q| {
            let mut w = vec![0.0; n];
            for &i in &order[q * n / 4..(q + 1) * n / 4] {
                w[i] = 1.0;
            }
            error_metric::errors(v, r, &w).l1
        });
        RunSummary {
            l1,
            signed,
            mean_z2: (count > 0).then(|| z2 / count as f64),
            quartiles,
        }
    }

    /// Every pair (a, b), a < b, with L1(a) − L1(b) and its 95% percentile bootstrap interval from `resamples`
    /// resamples of the points drawn from `seed` (the same resamples for every pair).
    pub fn paired(&self, resamples: usize, seed: u64) -> Vec<((usize, usize), PairedDifference)> {
        let n = self.reference.len();
        let runs = self.values.len();
        let ones = vec![1.0; n];
        let l1 = |k: usize, w: &[f64]| error_metric::errors(&self.values[k], &self.reference, w).l1;
        let full: Vec<f64> = (0..runs).map(|k| l1(k, &ones)).collect();
        let mut rng = sampling::rng(seed, 0);
        let mut boot: Vec<Vec<f64>> = Vec::with_capacity(resamples);
        let mut w = vec![0.0; n];
        for _ in 0..resamples {
            w.fill(0.0);
            for _ in 0..n {
                let i = ((sampling::uniform(&mut rng) * n as f64) as usize).min(n - 1);
                w[i] += 1.0;
            }
            boot.push((0..runs).map(|k| l1(k, &w)).collect());
        }
        let mut out = Vec::new();
        for a in 0..runs {
            for b in a + 1..runs {
                let mut d: Vec<f64> = boot.iter().map(|x| x[a] - x[b]).collect();
                d.sort_by(f64::total_cmp);
                let at = |p: f64| {
                    if d.is_empty() {
                        f64::NAN
                    } else {
                        d[((p * d.len() as f64) as usize).min(d.len() - 1)]
                    }
                };
                out.push((
                    (a, b),
                    PairedDifference {
                        diff: full[a] - full[b],
                        low: at(0.025),
                        high: at(0.975),
                    },
                ));
            }
        }
        out
    }
}

/// Puts the runs' answers against one reference: `reference`'s, or the runs' own if they share it. Errors
/// name the files and the first point where they disagree.
pub fn assemble(
    runs: &[(String, Vec<PointAnswer>)],
    reference: Option<(&str, &[PointAnswer])>,
) -> Result<Comparison> {
    let (ref_name, refs) = match (reference, runs.first()) {
        (Some((name, points)), _) => (name, points),
        (None, Some((name, points))) => (name.as_str(), points.as_slice()),
        (None, None) => bail!("no runs to compare: give two or more runs' points files"),
    };
    for (name, points) in runs {
        if points.len() != refs.len() {
            bail!(
                "{name} and {ref_name} hold different numbers of points ({} and {}): compare runs of one \
                 experiment's evaluation points",
                points.len(),
                refs.len()
            );
        }
        for (i, (p, q)) in points.iter().zip(refs).enumerate() {
            let faces_differ = p.face != q.face && p.face != UNKNOWN_FACE && q.face != UNKNOWN_FACE;
            if faces_differ || p.at != q.at {
                bail!(
                    "{name} and {ref_name} differ at row {}: point on face {} at {:?} against face {} at \
                     {:?}; compare runs of the same `[evaluation]` points",
                    i + 1,
                    p.face,
                    p.at,
                    q.face,
                    q.at
                );
            }
            if reference.is_none() && (p.reference != q.reference || p.std_error != q.std_error) {
                bail!(
                    "{name} and {ref_name} were measured against different references (row {}); pass \
                     --reference FILE to measure both against one",
                    i + 1
                );
            }
        }
    }
    Ok(Comparison {
        reference: refs.iter().map(|p| p.reference).collect(),
        std_error: refs.iter().map(|p| p.std_error).collect(),
        values: runs
            .iter()
            .map(|(_, p)| p.iter().map(|x| x.value).collect())
            .collect(),
        own_std_error: runs
            .iter()
            .map(|(_, p)| p.iter().map(|x| x.own_std_error).collect())
            .collect(),
    })
}

/// A run's name: its file name without `.points.csv`.
fn label(path: &Path) -> String {
    let name = path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    );
    name.strip_suffix(".points.csv")
        .or_else(|| name.strip_suffix(".csv"))
        .map_or(name.clone(), str::to_owned)
}

/// Runs `radlab compare`.
pub fn run(args: &CompareArgs) -> Result<()> {
    if args.resamples < 40 {
        bail!(
            "--resamples {}: a 95% interval needs at least 40 resamples (the default is 2000)",
            args.resamples
        );
    }
    let runs: Vec<(String, Vec<PointAnswer>)> = args
        .runs
        .iter()
        .map(|p| Ok((label(p), read_points(p)?)))
        .collect::<Result<_>>()?;
    let reference = match &args.reference {
        Some(p) => Some((label(p), read_points(p)?)),
        None => None,
    };
    let cmp = assemble(
        &runs,
        reference.as_ref().map(|(n, p)| (n.as_str(), p.as_slice())),
    )?;
    let pct = |x: f64| format!("{:.4}%", 100.0 * x);
    let spct = |x: f64| format!("{:+.4}%", 100.0 * x);
    println!(
        "reference: {} ({} points, noise floor {})",
        reference
            .as_ref()
            .map_or("each run's own", |(n, _)| n.as_str()),
        cmp.reference.len(),
        pct(cmp.noise_floor())
    );
    println!();
    println!("| run | L1 | signed | mean z² | L1 by reference quartile, darkest first |");
    println!("|---|---|---|---|---|");
    for (k, (name, _)) in runs.iter().enumerate() {
        let s = cmp.summary(k);
        println!(
            "| {name} | {} | {} | {} | {} |",
            pct(s.l1),
            spct(s.signed),
            s.mean_z2.map_or("—".into(), |z| format!("{z:.2}")),
            s.quartiles.map(pct).join(" / ")
        );
    }
    println!();
    println!(
        "Paired differences L1(a) − L1(b), 95% bootstrap interval over the points ({} resamples, seed {}):",
        args.resamples, args.seed
    );
    println!();
    println!("| a | b | L1(a) − L1(b) | 95% interval | |");
    println!("|---|---|---|---|---|");
    for ((a, b), d) in cmp.paired(args.resamples, args.seed) {
        let verdict = if d.high < 0.0 {
            "a lower"
        } else if d.low > 0.0 {
            "b lower"
        } else {
            "level within the interval"
        };
        println!(
            "| {} | {} | {} | {} … {} | {verdict} |",
            runs[a].0,
            runs[b].0,
            spct(d.diff),
            spct(d.low),
            spct(d.high)
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(values: &[f64], reference: &[f64], se: f64) -> Vec<PointAnswer> {
        values
            .iter()
            .zip(reference)
            .enumerate()
            .map(|(i, (&v, &r))| PointAnswer {
                face: i,
                at: [i as f64, 0.0, 0.0],
                reference: Rgb::splat(r),
                std_error: Rgb::splat(se),
                value: Rgb::splat(v),
                own_std_error: Rgb::ZERO,
            })
            .collect()
    }

    #[test]
    fn summary_matches_the_metric_by_hand() {
        // Reference 1, 2, 3, 4; answers off by +0.1, −0.2, +0.3, 0.
        let r = [1.0, 2.0, 3.0, 4.0];
        let v = [1.1, 1.8, 3.3, 4.0];
        let runs = vec![("a".to_string(), points(&v, &r, 0.1))];
        let c = assemble(&runs, None).expect("same points");
        let s = c.summary(0);
        assert!((s.l1 - 0.6 / 10.0).abs() < 1e-12);
        assert!((s.signed - 0.2 / 10.0).abs() < 1e-12);
        // z = 1, −2, 3, 0 on every channel.
        assert!((s.mean_z2.expect("standard errors") - 14.0 / 4.0).abs() < 1e-12);
        // One point a quartile, darkest first: 0.1/1, 0.2/2, 0.3/3, 0/4.
        for (q, want) in s.quartiles.iter().zip([0.1, 0.1, 0.1, 0.0]) {
            assert!((q - want).abs() < 1e-12, "{q} against {want}");
        }
    }

    #[test]
    fn a_clear_difference_excludes_zero_and_a_relabelling_does_not() {
        // Points with reference 1 .. 2; a is off by 1% everywhere, b by 2% or 3%: a is lower at every resample.
        let n = 500;
        let r: Vec<f64> = (0..n).map(|i| 1.0 + i as f64 / n as f64).collect();
        let a: Vec<f64> = r.iter().map(|x| x * 1.01).collect();
        let b: Vec<f64> = r
            .iter()
            .enumerate()
            .map(|(i, x)| x * if i % 2 == 0 { 1.02 } else { 0.97 })
            .collect();
        let runs = vec![
            ("a".into(), points(&a, &r, 0.01)),
            ("b".into(), points(&b, &r, 0.01)),
        ];
        let c = assemble(&runs, None).expect("same points");
        let ((i, j), d) = c.paired(400, 1)[0];
        assert_eq!((i, j), (0, 1));
        assert!(d.diff < -0.01 && d.diff > -0.02, "{d:?}");
        assert!(d.high < 0.0, "{d:?}");
        assert!(d.low <= d.diff && d.diff <= d.high, "{d:?}");
        // b off by 2% at every other point and exact elsewhere: the same L1 as a's to within 1e-5, so the
        // interval holds zero.
        let b2: Vec<f64> = r
            .iter()
            .enumerate()
            .map(|(i, x)| x * if i % 2 == 0 { 1.02 } else { 1.0 })
            .collect();
        let runs = vec![
            ("a".into(), points(&a, &r, 0.01)),
            ("b".into(), points(&b2, &r, 0.01)),
        ];
        let d = assemble(&runs, None).expect("same points").paired(400, 1)[0].1;
        assert!(d.diff.abs() < 1e-5, "{d:?}");
        assert!(d.low < -1e-4 && 1e-4 < d.high, "{d:?}");
        // Deterministic for a seed.
        assert_eq!(
            assemble(&runs, None).expect("same points").paired(400, 1),
            assemble(&runs, None).expect("same points").paired(400, 1)
        );
    }

    #[test]
    fn another_reference_replaces_the_runs_own() {
        let r = [1.0, 2.0];
        let sharp = [1.1, 2.0];
        let runs = vec![("a".to_string(), points(&[1.1, 2.0], &r, 0.1))];
        let refp = points(&[0.0, 0.0], &sharp, 0.05);
        let c = assemble(&runs, Some(("sharp", &refp))).expect("same points");
        assert_eq!(c.summary(0).l1, 0.0);
        assert_eq!(c.std_error[0], Rgb::splat(0.05));
    }

    #[test]
    fn answers_files_are_their_own_reference_and_z_uses_both_errors() {
        let dir = tempfile::tempdir().expect("tmp");
        let a = dir.path().join("radiance.csv");
        let b = dir.path().join("radlab.csv");
        std::fs::write(
            &a,
            "x,y,z,r,g,b,se_r,se_g,se_b\n0,0,0,1.3,1,1,0.3,0,0\n1,0,0,2,2,2,0,0,0\n",
        )
        .expect("write");
        std::fs::write(
            &b,
            "x,y,z,r,g,b,se_r,se_g,se_b\n0,0,0,1,1,1,0.4,0,0\n1,0,0,2,2,2,0.1,0.1,0.1\n",
        )
        .expect("write");
        let (ra, rb) = (read_points(&a).expect("a"), read_points(&b).expect("b"));
        assert_eq!(ra[0].face, UNKNOWN_FACE);
        assert_eq!(ra[0].std_error, Rgb::new(0.3, 0.0, 0.0));
        let c = assemble(&[("radiance".into(), ra)], Some(("radlab", &rb))).expect("same points");
        let s = c.summary(0);
        // Point 1, red: z = 0.3 / √(0.4² + 0.3²) = 0.6; every other channel with s > 0 has z = 0.
        assert!(
            (s.mean_z2.expect("errors") - 0.36 / 4.0).abs() < 1e-12,
            "{s:?}"
        );
        assert!((s.l1 - 0.3 / 9.0).abs() < 1e-12);
        // A file without either format's columns is refused, naming them.
        std::fs::write(&a, "x,y,z,r,g\n0,0,0,1,1\n").expect("write");
        let e = read_points(&a).expect_err("refused").to_string();
        assert!(e.contains("column b is missing"), "{e}");
    }

    #[test]
    fn mismatched_points_and_references_are_refused() {
        let r = [1.0, 2.0];
        let a = ("a".to_string(), points(&[1.0, 2.0], &r, 0.1));
        let other_ref = ("b".to_string(), points(&[1.0, 2.0], &[1.0, 2.5], 0.1));
        let e = assemble(&[a.clone(), other_ref], None)
            .expect_err("refused")
            .to_string();
        assert!(
            e.contains("different references") && e.contains("--reference"),
            "{e}"
        );
        let mut moved = points(&[1.0, 2.0], &r, 0.1);
        moved[1].at[1] = 1.0;
        let e = assemble(&[a.clone(), ("c".into(), moved)], None)
            .expect_err("refused")
            .to_string();
        assert!(e.contains("row 2") && e.contains("[evaluation]"), "{e}");
        let short = ("d".to_string(), points(&[1.0], &[1.0], 0.1));
        let e = assemble(&[a, short], None)
            .expect_err("refused")
            .to_string();
        assert!(
            e.contains("(1 and 2)") && e.contains("evaluation points"),
            "{e}"
        );
    }
}
