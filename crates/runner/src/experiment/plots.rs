//! Plots of an experiment (plotters, PNG and SVG), drawn from `runs.csv` and `trace.csv` only, so
//! `radlab plot DIR` redraws them anywhere: per scene, relative L1 error against wall time of every run
//! (convergence), final error against time across each method's sweep (the speed/accuracy frontier), and final
//! error against rays cast and against memory held. Log-log axes with ticks at 1-2-5 (or 1-3 for errors, shown as
//! percentages: 1%, 3%, 10%) times powers of ten, each label once; the reference's noise floor as a dashed line
//! labelled with its value; the legend beside the plot area, never over data. Series take twelve colours, then
//! the same colours again with triangles instead of circles, then with crosses, so that no two of 36 look
//! alike. PNG and SVG come from one drawing routine, so they hold the same content. Time is the time to answer
//! at the experiment's points: the solver's set-up, its steps and one answering pass (a final gather's cost).
//! Text uses DejaVu Sans embedded in the binary, so no system font library is needed.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Once;

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::coord::combinators::BindKeyPoints;
use plotters::prelude::*;

use super::execute::{RunResult, TraceRow};
use crate::output::atomic::write_via_temp;

static FONT: Once = Once::new();

/// Registers the embedded font as "sans-serif" (once).
pub fn ensure_font() {
    FONT.call_once(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

/// Colour of the k-th method.
pub fn colour(k: usize) -> RGBColor {
    const C: [RGBColor; 12] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(23, 190, 207),
        RGBColor(188, 189, 34),
        RGBColor(0, 0, 0),
        RGBColor(127, 127, 127),
        RGBColor(255, 187, 120),
    ];
    C[k % C.len()]
}

/// The k-th series' marker: circles for the first twelve series (one per [`colour`]), triangles for the next
/// twelve, crosses after, so that series sharing a colour stay apart.
#[derive(Clone, Copy)]
enum Marker {
    Circle,
    Triangle,
    Cross,
}

fn marker(k: usize) -> Marker {
    match (k / 12) % 3 {
        0 => Marker::Circle,
        1 => Marker::Triangle,
        _ => Marker::Cross,
    }
}

/// One series of a plot.
pub struct Series {
    /// Legend label (`None` for no legend entry).
    pub label: Option<String>,
    /// Colour index.
    pub colour: usize,
    /// Points (only positive finite coordinates are drawn on log axes).
    pub points: Vec<(f64, f64)>,
}

/// A log-log plot.
pub struct Plot {
    /// Title.
    pub title: String,
    /// X axis label.
    pub x_label: String,
    /// Y axis label.
    pub y_label: String,
    /// Series.
    pub series: Vec<Series>,
    /// A dashed horizontal line with its label (the noise floor).
    pub hline: Option<(f64, String)>,
    /// Whether y is a relative error (ticks at 1-3 steps, labelled as percentages).
    pub y_is_error: bool,
}

/// Tick values for a log axis over [lo, hi]: `mantissas` × 10^k inside the range (1-2-5 or 1-3 steps), thinned to
/// powers of ten when there would be more than 12.
pub fn log_ticks(lo: f64, hi: f64, mantissas: &[f64]) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && lo.is_finite() && hi.is_finite()) {
        return Vec::new();
    }
    let ticks = |ms: &[f64]| -> Vec<f64> {
        let mut out = Vec::new();
        for k in (lo.log10().floor() as i32 - 1)..=(hi.log10().ceil() as i32 + 1) {
            for m in ms {
                let v = m * 10f64.powi(k);
                // Round to 12 significant digits so 3 × 10^-2 prints as 0.03, not 0.030000000000000002.
                let v = format!("{v:.11e}").parse::<f64>().unwrap_or(v);
                if v >= lo && v <= hi {
                    out.push(v);
                }
            }
        }
        out
    };
    let t = ticks(mantissas);
    if t.len() > 12 { ticks(&[1.0]) } else { t }
}

/// A number with at most 3 significant digits and no trailing zeros: 0.03, 1.5, 200, 2e+06.
pub fn fmt_number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let e = v.abs().log10().floor() as i32;
    if !(-4..6).contains(&e) {
        let s = format!("{v:.2e}");
        let (m, x) = s.split_once('e').unwrap_or((&s, "0"));
        let m = m.trim_end_matches('0').trim_end_matches('.');
        return format!("{m}e{x}");
    }
    let decimals = (2 - e).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A relative error as a percentage: 0.03 → "3%", 0.005 → "0.5%".
pub fn fmt_percent(v: f64) -> String {
    format!("{}%", fmt_number(v * 100.0))
}

fn bounds(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo.is_finite() {
        Some((lo / 1.5, if hi > lo { hi * 1.5 } else { lo * 3.0 }))
    } else {
        None
    }
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, plot: &Plot) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("{e:?}");
    root.fill(&WHITE).map_err(e)?;
    let pts = || plot.series.iter().flat_map(|s| s.points.iter());
    let Some(xr) = bounds(pts().map(|p| p.0)) else {
        return Ok(());
    };
    let Some(yr) = bounds(pts().map(|p| p.1).chain(plot.hline.iter().map(|h| h.0))) else {
        return Ok(());
    };
    // The legend gets its own column on the right, so it never covers data.
    let labelled: Vec<&Series> = plot.series.iter().filter(|s| s.label.is_some()).collect();
    let (w, _) = root.dim_in_pixel();
    let legend_w = if labelled.is_empty() {
        0
    } else {
        210.min(w / 3)
    };
    let (plot_area, legend_area) = root.split_horizontally(w - legend_w);
    let y_mantissas: &[f64] = if plot.y_is_error {
        &[1.0, 3.0]
    } else {
        &[1.0, 2.0, 5.0]
    };
    let x_ticks = log_ticks(xr.0, xr.1, &[1.0, 2.0, 5.0]);
    let y_ticks = log_ticks(yr.0, yr.1, y_mantissas);
    let mut chart = ChartBuilder::on(&plot_area)
        .caption(&plot.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (xr.0..xr.1).log_scale().with_key_points(x_ticks),
            (yr.0..yr.1).log_scale().with_key_points(y_ticks),
        )
        .map_err(e)?;
    let y_fmt = |v: &f64| {
        if plot.y_is_error {
            fmt_percent(*v)
        } else {
            fmt_number(*v)
        }
    };
    chart
        .configure_mesh()
        .x_desc(&plot.x_label)
        .y_desc(&plot.y_label)
        .x_label_formatter(&|v| fmt_number(*v))
        .y_label_formatter(&y_fmt)
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(e)?;
    for s in &plot.series {
        let c = colour(s.colour);
        let points: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite())
            .collect();
        chart
            .draw_series(LineSeries::new(points.clone(), c.stroke_width(2)))
            .map_err(e)?;
        match marker(s.colour) {
            Marker::Circle => chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 3, c.filled())))
                .map(|_| ()),
            Marker::Triangle => chart
                .draw_series(
                    points
                        .iter()
                        .map(|&p| TriangleMarker::new(p, 5, c.filled())),
                )
                .map(|_| ()),
            Marker::Cross => chart
                .draw_series(points.iter().map(|&p| Cross::new(p, 4, c.stroke_width(2))))
                .map(|_| ()),
        }
        .map_err(e)?;
    }
    if let Some((y, label)) = &plot.hline
        && *y > 0.0
    {
        let dashes: Vec<(f64, f64)> = (0..60)
            .filter(|i| i % 2 == 0)
            .flat_map(|i| {
                let t = |k: f64| (xr.0.ln() + k / 60.0 * (xr.1.ln() - xr.0.ln())).exp();
                [(t(i as f64), *y), (t(i as f64 + 1.0), *y)]
            })
            .collect();
        for seg in dashes.chunks(2) {
            chart
                .draw_series(LineSeries::new(seg.to_vec(), BLACK.stroke_width(1)))
                .map_err(e)?;
        }
        let value = if plot.y_is_error {
            fmt_percent(*y)
        } else {
            fmt_number(*y)
        };
        chart
            .draw_series(std::iter::once(Text::new(
                format!("{label} {value}"),
                (xr.0 * 1.1, *y * 1.12),
                ("sans-serif", 12),
            )))
            .map_err(e)?;
    }
    // Legend: one line and name per labelled series, top-aligned with the plot area.
    for (k, s) in labelled.iter().enumerate() {
        let c = colour(s.colour);
        let y = 50 + 22 * k as i32;
        legend_area
            .draw(&PathElement::new(vec![(8, y), (32, y)], c.stroke_width(2)))
            .map_err(e)?;
        match marker(s.colour) {
            Marker::Circle => legend_area.draw(&Circle::new((20, y), 3, c.filled())),
            Marker::Triangle => legend_area.draw(&TriangleMarker::new((20, y), 5, c.filled())),
            Marker::Cross => legend_area.draw(&Cross::new((20, y), 4, c.stroke_width(2))),
        }
        .map_err(e)?;
        legend_area
            .draw(&Text::new(
                s.label.clone().unwrap_or_default(),
                (38, y - 7),
                ("sans-serif", 13),
            ))
            .map_err(e)?;
    }
    root.present().map_err(e)?;
    Ok(())
}

/// Writes `stem.png` and `stem.svg`; returns the PNG's path.
pub fn write_plot(stem: &Path, plot: &Plot) -> Result<PathBuf> {
    ensure_font();
    let png = stem.with_extension("png");
    write_via_temp(&png, |tmp| {
        draw(
            BitMapBackend::new(tmp, (900, 600)).into_drawing_area(),
            plot,
        )
    })?;
    write_via_temp(&stem.with_extension("svg"), |tmp| {
        draw(SVGBackend::new(tmp, (900, 600)).into_drawing_area(), plot)
    })?;
    Ok(png)
}

/// The figures of one scene, drawn from its runs and traces. Returns the PNG paths written.
pub fn scene_plots(
    dir: &Path,
    scene: &str,
    runs: &[RunResult],
    trace: &[TraceRow],
) -> Result<Vec<PathBuf>> {
    let runs: Vec<&RunResult> = runs.iter().filter(|r| r.scene == scene).collect();
    let mut labels: Vec<String> = Vec::new();
    for r in &runs {
        if !labels.contains(&r.label) {
            labels.push(r.label.clone());
        }
    }
    let idx = |l: &str| labels.iter().position(|x| x == l).unwrap_or(0);
    let floor = runs
        .iter()
        .map(|r| r.floor_l1)
        .find(|f| *f > 0.0)
        .map(|f| (f, "reference noise floor".to_string()));
    let points = runs.iter().map(|r| r.points).max().unwrap_or(0);
    let time_label = if points > 0 {
        format!("time to answer at {points} points (s)")
    } else {
        "time to answer (s)".to_string()
    };
    let figs = dir.join("figures");
    let mut written = Vec::new();

    // Convergence: every run's trace.
    let mut series = Vec::new();
    let mut seen = std::collections::HashSet::new();
    let mut by_run: BTreeMap<&str, Vec<(f64, f64)>> = BTreeMap::new();
    for t in trace.iter().filter(|t| t.scene == scene) {
        by_run
            .entry(t.id.as_str())
            .or_default()
            .push((t.time_to_answer(), t.l1));
    }
    for r in &runs {
        if let Some(points) = by_run.remove(r.id.as_str()) {
            let label = seen.insert(r.label.clone()).then(|| r.label.clone());
            series.push(Series {
                label,
                colour: idx(&r.label),
                points,
            });
        }
    }
    written.push(write_plot(
        &figs.join(format!("convergence-{scene}")),
        &Plot {
            title: format!("{scene}: error against time"),
            x_label: time_label.clone(),
            y_label: "relative L1 error".into(),
            series,
            hline: floor.clone(),
            y_is_error: true,
        },
    )?);

    // Final error against time, rays and memory: one line per method across its sweep.
    let finals = |x: &dyn Fn(&RunResult) -> f64| -> Vec<Series> {
        labels
            .iter()
            .map(|l| {
                let mut points: Vec<(f64, f64)> = runs
                    .iter()
                    .filter(|r| &r.label == l && r.l1.is_finite())
                    .map(|r| (x(r), r.l1))
                    .collect();
                points.sort_by(|a, b| a.0.total_cmp(&b.0));
                Series {
                    label: Some(l.clone()),
                    colour: idx(l),
                    points,
                }
            })
            .collect()
    };
    for (name, title, x_label, x) in [
        (
            "frontier",
            "speed/accuracy frontier",
            time_label.as_str(),
            (&RunResult::time_to_answer) as &dyn Fn(&RunResult) -> f64,
        ),
        (
            "error-vs-rays",
            "error against rays cast",
            "rays (solving and answering)",
            &|r: &RunResult| (r.rays + r.answer_rays) as f64,
        ),
        (
            "error-vs-memory",
            "error against memory held",
            "bytes held by the solver",
            &|r: &RunResult| r.bytes as f64,
        ),
    ] {
        written.push(write_plot(
            &figs.join(format!("{name}-{scene}")),
            &Plot {
                title: format!("{scene}: {title}"),
                x_label: x_label.into(),
                y_label: "final relative L1 error".into(),
                series: finals(x),
                hline: floor.clone(),
                y_is_error: true,
            },
        )?);
    }
    Ok(written)
}

/// Outcomes whose time and memory measure a finished solve (a run stopped by its time limit does not).
pub fn finished(r: &RunResult) -> bool {
    matches!(
        r.outcome.as_str(),
        "converged" | "step-limit" | "target-error"
    )
}

/// Least-squares slope of ln y against ln x (points with positive coordinates), if at least two distinct x.
pub fn loglog_slope(points: &[(f64, f64)]) -> Option<f64> {
    let p: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = p.len() as f64;
    let (mx, my) = (
        p.iter().map(|q| q.0).sum::<f64>() / n,
        p.iter().map(|q| q.1).sum::<f64>() / n,
    );
    let sxx: f64 = p.iter().map(|q| (q.0 - mx).powi(2)).sum();
    if p.len() < 2 || sxx <= 0.0 {
        return None;
    }
    Some(p.iter().map(|q| (q.0 - mx) * (q.1 - my)).sum::<f64>() / sxx)
}

/// One scaling series: (family, method label, [(faces, wall seconds, peak RSS bytes)]) of finished runs.
pub type ScalingSeries = (String, String, Vec<(f64, f64, f64)>);

/// The scaling series of an experiment: per family and method, its finished runs against face count.
pub fn scaling_series(runs: &[RunResult]) -> Vec<ScalingSeries> {
    let mut out: Vec<ScalingSeries> = Vec::new();
    for r in runs.iter().filter(|r| !r.family.is_empty() && finished(r)) {
        let point = (r.faces as f64, r.wall_s, r.peak_rss_bytes as f64);
        match out.iter_mut().find(|s| s.0 == r.family && s.1 == r.label) {
            Some(s) => s.2.push(point),
            None => out.push((r.family.clone(), r.label.clone(), vec![point])),
        }
    }
    for s in &mut out {
        s.2.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    out
}

/// Time and memory against input faces, one line per (family, method), log-log. Returns the PNG paths.
pub fn scaling_plots(dir: &Path, runs: &[RunResult]) -> Result<Vec<PathBuf>> {
    let series = scaling_series(runs);
    if series.is_empty() {
        return Ok(Vec::new());
    }
    let mut labels: Vec<&str> = Vec::new();
    for s in &series {
        if !labels.contains(&s.1.as_str()) {
            labels.push(&s.1);
        }
    }
    let mk = |f: &dyn Fn(&(f64, f64, f64)) -> f64| -> Vec<Series> {
        series
            .iter()
            .map(|(fam, label, pts)| Series {
                label: Some(format!("{label} ({fam})")),
                colour: labels.iter().position(|l| l == label).unwrap_or(0),
                points: pts.iter().map(|p| (p.0, f(p))).collect(),
            })
            .collect()
    };
    let figs = dir.join("figures");
    Ok(vec![
        write_plot(
            &figs.join("scaling-time"),
            &Plot {
                title: "time against input faces".into(),
                x_label: "input faces k".into(),
                y_label: "wall time of steps (s)".into(),
                series: mk(&|p| p.1),
                hline: None,
                y_is_error: false,
            },
        )?,
        write_plot(
            &figs.join("scaling-memory"),
            &Plot {
                title: "peak memory against input faces".into(),
                x_label: "input faces k".into(),
                y_label: "peak resident memory (bytes)".into(),
                series: mk(&|p| p.2),
                hline: None,
                y_is_error: false,
            },
        )?,
    ])
}

#[cfg(test)]
mod tests {
    #[test]
    fn slope_of_a_power_law() {
        let pts: Vec<(f64, f64)> = [1e3, 1e4, 1e5]
            .iter()
            .map(|&k: &f64| (k, 3.0 * k.powf(1.5)))
            .collect();
        assert!((super::loglog_slope(&pts).expect("slope") - 1.5).abs() < 1e-12);
        assert!(super::loglog_slope(&[(1.0, 2.0)]).is_none());
    }

    #[test]
    fn tick_labels_are_distinct_and_errors_read_as_percentages() {
        for (lo, hi, m) in [
            (0.004, 0.2, &[1.0, 3.0][..]),
            (0.08, 0.12, &[1.0, 3.0][..]),
            (1e-3, 1e4, &[1.0, 2.0, 5.0][..]),
            (0.05, 7.0, &[1.0, 2.0, 5.0][..]),
        ] {
            let t = super::log_ticks(lo, hi, m);
            let labels: Vec<String> = t.iter().map(|&v| super::fmt_number(v)).collect();
            let mut unique = labels.clone();
            unique.dedup();
            assert_eq!(unique, labels, "{lo}..{hi}");
            assert!(t.iter().all(|&v| v >= lo && v <= hi));
        }
        let t = super::log_ticks(0.004, 0.2, &[1.0, 3.0]);
        let p: Vec<String> = t.iter().map(|&v| super::fmt_percent(v)).collect();
        assert_eq!(p, ["1%", "3%", "10%"]);
        assert_eq!(super::fmt_number(0.03), "0.03");
        assert_eq!(super::fmt_number(2e6), "2e6");
        assert_eq!(super::fmt_percent(0.0065), "0.65%");
    }
}
