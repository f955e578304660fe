//! OpenEXR output of linear RGB images (32-bit float channels), written atomically.

use std::path::Path;

use anyhow::{Context, Result};
use radlab_scene::Image;

use super::atomic::write_via_temp;

/// Writes `image` as a linear RGB EXR.
pub fn write_exr(path: &Path, image: &Image) -> Result<()> {
    write_via_temp(path, |tmp| {
        exr::prelude::write_rgb_file(tmp, image.width as usize, image.height as usize, |x, y| {
            let p = image.get(x as u32, y as u32);
            (p.x as f32, p.y as f32, p.z as f32)
        })
        .with_context(|| format!("cannot write EXR {}", tmp.display()))
    })
}

/// Reads the first RGB(A) layer of an EXR into an [`Image`] (for tests and `radlab plot`).
pub fn read_exr(path: &Path) -> Result<Image> {
    use exr::prelude::*;
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| {
            (
                res.width(),
                vec![radlab_scene::Rgb::ZERO; res.width() * res.height()],
            )
        },
        |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = radlab_scene::Rgb::new(r as f64, g as f64, b as f64);
        },
    )
    .with_context(|| format!("cannot read EXR {}", path.display()))?;
    let size = img.layer_data.size;
    Ok(radlab_scene::Image {
        width: size.width() as u32,
        height: size.height() as u32,
        pixels: img.layer_data.channel_data.pixels.1,
    })
}
