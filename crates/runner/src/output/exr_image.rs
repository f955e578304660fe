//! OpenEXR output of linear RGB images (32-bit float channels), written atomically.

use std::path::Path;

use anyhow::{Context, Result};
use radlab_answer::Image;

use super::atomic::write_via_temp;

/// Writes `image` as a linear RGB EXR: run-length-encoded 64 × 64 tiles, stored in increasing order. The
/// exr crate compresses tiles in parallel and, with its default unspecified order, stores them as they finish,
/// so the same image gave files that differed from run to run (the tile table); in increasing order the file
/// is the same bytes on any number of threads.
pub fn write_exr(path: &Path, image: &Image) -> Result<()> {
    use exr::prelude::*;
    write_via_temp(path, |tmp| {
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            let p = image.get(x as u32, y as u32);
            (p.x as f32, p.y as f32, p.z as f32)
        });
        let encoding = Encoding {
            line_order: LineOrder::Increasing,
            ..Encoding::FAST_LOSSLESS
        };
        let size = (image.width as usize, image.height as usize);
        Image::from_encoded_channels(size, encoding, channels)
            .write()
            .to_file(tmp)
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
    Ok(radlab_answer::Image {
        width: size.width() as u32,
        height: size.height() as u32,
        pixels: img.layer_data.channel_data.pixels.1,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use radlab_scene::Rgb;

    /// A 300 × 200 image (20 tiles) with a different value in every pixel.
    fn ramp() -> Image {
        let (width, height) = (300u32, 200u32);
        let pixels = (0..width * height)
            .map(|i| {
                let (x, y) = ((i % width) as f64, (i / width) as f64);
                Rgb::new(x / 7.0, y / 3.0, (x * y).sqrt())
            })
            .collect();
        Image {
            width,
            height,
            pixels,
        }
    }

    /// The same image gives the same file on 1 and 4 threads, written again and again (the tiles used to be
    /// stored in the order their compression finished), and reads back to the same pixels in f32.
    #[test]
    fn the_same_image_writes_the_same_bytes_on_any_number_of_threads() {
        let dir = tempfile::tempdir().expect("temporary directory");
        let image = ramp();
        let write = |threads: usize, name: &str| {
            let path = dir.path().join(name);
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            pool.install(|| write_exr(&path, &image)).expect("written");
            std::fs::read(&path).expect("read back")
        };
        let one = write(1, "one.exr");
        for round in 0..4 {
            assert!(
                write(4, &format!("four-{round}.exr")) == one,
                "round {round}: the file differs"
            );
        }
        let back = read_exr(&dir.path().join("one.exr")).expect("read");
        assert_eq!((back.width, back.height), (image.width, image.height));
        for (a, b) in back.pixels.iter().zip(&image.pixels) {
            let f = |v: f64| v as f32 as f64;
            assert_eq!(*a, Rgb::new(f(b.x), f(b.y), f(b.z)));
        }
    }
}
