//! Image files: linear float EXR in and out, tone-clamped sRGB PNG out.

use glam::Vec3;
use image::{ImageBuffer, Rgb, Rgb32FImage, RgbImage};
use std::path::Path;

/// A linear RGB image, row 0 on top.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major pixels.
    pub pixels: Vec<Vec3>,
}

/// Reads any image `image` can decode (EXR stays linear; 8-bit files are returned as stored).
pub fn read_linear(path: &Path) -> Result<LinearImage, String> {
    let img = image::open(path).map_err(|e| format!("{}: {e}", path.display()))?.into_rgb32f();
    let pixels = img.pixels().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    Ok(LinearImage { width: img.width(), height: img.height(), pixels })
}

/// Writes `.exr` (linear float) or `.png` (clamped to [0, 1], sRGB); returns how many pixels a
/// PNG clamped. The file appears whole or not at all: it is written under a temporary name
/// beside it and renamed.
pub fn write(path: &Path, img: &LinearImage) -> Result<usize, String> {
    atomically(path, |tmp| write_now(tmp, img))
}

/// Runs `write` on a temporary path in `path`'s directory (same extension, so that encoders
/// picked by extension work) and renames the result to `path`; removes it on failure.
pub fn atomically<T>(path: &Path, write: impl FnOnce(&Path) -> Result<T, String>) -> Result<T, String> {
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| format!("{}: not a file name", path.display()))?;
    let tmp = path.with_file_name(format!(".{}.{}.tmp.{}", name, std::process::id(), extension(path)));
    let out = write(&tmp).and_then(|v| {
        std::fs::rename(&tmp, path).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(v)
    });
    if out.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    out
}

fn extension(path: &Path) -> String {
    path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase()
}

/// sRGB 8-bit pixels (clamped to [0, 1]) and how many were clamped.
fn srgb8(img: &LinearImage) -> (Vec<u8>, usize) {
    let mut clamped = 0;
    let data = img
        .pixels
        .iter()
        .flat_map(|p| {
            if p.max_element() > 1.0 {
                clamped += 1;
            }
            p.to_array().map(|c| (srgb_oetf(c.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8)
        })
        .collect();
    (data, clamped)
}

/// Writes an animated GIF (sRGB, clamped, 256 colours per frame) played at `fps`, atomically.
pub fn write_gif(path: &Path, frames: &[LinearImage], fps: f32) -> Result<(), String> {
    use image::codecs::gif::{GifEncoder, Repeat};
    atomically(path, |tmp| {
        let err = |e: image::ImageError| format!("{}: {e}", path.display());
        let file = std::fs::File::create(tmp).map_err(|e| format!("{}: {e}", tmp.display()))?;
        let mut enc = GifEncoder::new_with_speed(std::io::BufWriter::new(file), 10);
        enc.set_repeat(Repeat::Infinite).map_err(err)?;
        let delay = image::Delay::from_numer_denom_ms(1000, fps.max(1e-3).round().max(1.0) as u32);
        for f in frames {
            let (rgb, _) = srgb8(f);
            let rgba: Vec<u8> = rgb.chunks_exact(3).flat_map(|c| [c[0], c[1], c[2], 255]).collect();
            let buf = image::RgbaImage::from_raw(f.width, f.height, rgba).expect("size");
            enc.encode_frame(image::Frame::from_parts(buf, 0, 0, delay)).map_err(err)?;
        }
        Ok(())
    })
}

fn write_now(path: &Path, img: &LinearImage) -> Result<usize, String> {
    let ext = extension(path);
    let err = |e: image::ImageError| format!("{}: {e}", path.display());
    match ext.as_str() {
        "exr" => {
            let data: Vec<f32> = img.pixels.iter().flat_map(|p| p.to_array()).collect();
            let buf: Rgb32FImage = ImageBuffer::from_raw(img.width, img.height, data).expect("size matches");
            buf.save(path).map_err(err)?;
            Ok(0)
        }
        "png" => {
            let (data, clamped) = srgb8(img);
            let buf: RgbImage =
                ImageBuffer::<Rgb<u8>, _>::from_raw(img.width, img.height, data).expect("size");
            buf.save(path).map_err(err)?;
            Ok(clamped)
        }
        _ => Err(format!("{}: unknown output format (use .png or .exr)", path.display())),
    }
}

/// The sRGB transfer function (linear to encoded).
pub fn srgb_oetf(c: f32) -> f32 {
    if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}
