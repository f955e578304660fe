//! Images of an experiment: each run's solution through the scene's camera (EXR, linear radiance B/π), the
//! path-traced reference image, a false-colour PNG of each method's per-pixel relative difference to the
//! reference (|L − L_ref| / max(L_ref, 2% of the mean), luminance, colour scale 0 → 50%), and a PNG contact
//! sheet of the reference and every method side by side (tone-mapped: the reference's 99th-percentile
//! luminance maps to white, sRGB-encoded).

use std::path::Path;

use anyhow::{Result, anyhow};
use plotters::prelude::*;
use radlab_answer::Image;
use radlab_scene::{Camera, Rgb, Scene};

use super::config::OutputsConfig;
use crate::output::atomic::write_via_temp;
use crate::output::ply_radiosity::srgb_byte;

/// The scene's camera with the experiment's size override, if the scene has one.
pub fn camera_for(scene: &Scene, outputs: &OutputsConfig) -> Option<Camera> {
    let mut c = scene.camera.clone()?;
    if outputs.image_width > 0 {
        c.width = outputs.image_width;
    }
    if outputs.image_height > 0 {
        c.height = outputs.image_height;
    }
    Some(c)
}

fn luminance(c: Rgb) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Exposure scale mapping the 99th-percentile luminance of `image` to 1.
pub fn exposure(image: &Image) -> f64 {
    let mut l: Vec<f64> = image
        .pixels
        .iter()
        .map(|&p| luminance(p))
        .filter(|x| x.is_finite())
        .collect();
    if l.is_empty() {
        return 1.0;
    }
    l.sort_by(f64::total_cmp);
    let p99 = l[((l.len() - 1) as f64 * 0.99) as usize];
    if p99 > 0.0 { 1.0 / p99 } else { 1.0 }
}

/// 8-bit sRGB bytes of an image at an exposure.
pub fn to_srgb(image: &Image, scale: f64) -> Vec<u8> {
    image
        .pixels
        .iter()
        .flat_map(|p| {
            [
                srgb_byte(p.x * scale),
                srgb_byte(p.y * scale),
                srgb_byte(p.z * scale),
            ]
        })
        .collect()
}

/// Writes RGB bytes as a PNG (atomically).
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    write_via_temp(path, |tmp| {
        image::save_buffer(tmp, rgb, width, height, image::ColorType::Rgb8)
            .map_err(|e| anyhow!("{}: {e}", tmp.display()))
    })
}

/// A perceptually ordered colour ramp (dark blue → teal → yellow) for t in [0, 1].
pub fn ramp(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [0.27, 0.00, 0.33],
        [0.23, 0.32, 0.55],
        [0.13, 0.57, 0.55],
        [0.37, 0.79, 0.38],
        [0.99, 0.91, 0.14],
    ];
    let t = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f64;
    let c = |k: usize| ((STOPS[i][k] * (1.0 - f) + STOPS[i + 1][k] * f) * 255.0).round() as u8;
    [c(0), c(1), c(2)]
}

/// Per-pixel relative difference image (false colour, 0 → 50%), and the image's mean relative difference.
pub fn difference_png(path: &Path, image: &Image, reference: &Image) -> Result<f64> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(anyhow!("image and reference sizes differ"));
    }
    let mean = reference.pixels.iter().map(|&p| luminance(p)).sum::<f64>()
        / reference.pixels.len().max(1) as f64;
    let floor = (0.02 * mean).max(f64::MIN_POSITIVE);
    let mut total = 0.0;
    let bytes: Vec<u8> = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .flat_map(|(&a, &r)| {
            let d = (luminance(a) - luminance(r)).abs() / luminance(r).max(floor);
            total += d;
            ramp(d / 0.5)
        })
        .collect();
    write_png(path, image.width, image.height, &bytes)?;
    Ok(total / image.pixels.len().max(1) as f64)
}

/// A contact sheet: tiles side by side at a common exposure, each under a two-line label (name; detail).
pub fn contact_sheet(path: &Path, tiles: &[(String, String, Image)], scale: f64) -> Result<()> {
    let Some((_, _, first)) = tiles.first() else {
        return Ok(());
    };
    let (w, h) = (first.width, first.height);
    let cols = (tiles.len() as u32).min(4);
    let rows = (tiles.len() as u32).div_ceil(cols);
    let label_h = 34;
    let (sw, sh) = (cols * w, rows * (h + label_h));
    super::plots::ensure_font();
    write_via_temp(path, |tmp| {
        let root = BitMapBackend::new(tmp, (sw, sh)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e:?}"))?;
        for (k, (label, detail, img)) in tiles.iter().enumerate() {
            let (x0, y0) = ((k as u32 % cols) * w, (k as u32 / cols) * (h + label_h));
            let bytes = to_srgb(img, scale);
            for y in 0..img.height.min(h) {
                for x in 0..img.width.min(w) {
                    let i = ((y * img.width + x) * 3) as usize;
                    root.draw_pixel(
                        ((x0 + x) as i32, (y0 + label_h + y) as i32),
                        &RGBColor(bytes[i], bytes[i + 1], bytes[i + 2]),
                    )
                    .map_err(|e| anyhow!("{e:?}"))?;
                }
            }
            for (line, text) in [label, detail].into_iter().enumerate() {
                let style = ("sans-serif", 13).into_font().color(&BLACK);
                root.draw_text(
                    text,
                    &style,
                    (x0 as i32 + 3, y0 as i32 + 2 + 15 * line as i32),
                )
                .map_err(|e| anyhow!("{e:?}"))?;
            }
        }
        root.present().map_err(|e| anyhow!("{e:?}"))
    })
}
