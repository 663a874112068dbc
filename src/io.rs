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
/// PNG clamped.
pub fn write(path: &Path, img: &LinearImage) -> Result<usize, String> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let err = |e: image::ImageError| format!("{}: {e}", path.display());
    match ext.as_str() {
        "exr" => {
            let data: Vec<f32> = img.pixels.iter().flat_map(|p| p.to_array()).collect();
            let buf: Rgb32FImage = ImageBuffer::from_raw(img.width, img.height, data).expect("size matches");
            buf.save(path).map_err(err)?;
            Ok(0)
        }
        "png" => {
            let mut clamped = 0;
            let data: Vec<u8> = img
                .pixels
                .iter()
                .flat_map(|p| {
                    if p.max_element() > 1.0 {
                        clamped += 1;
                    }
                    p.to_array().map(|c| (srgb_oetf(c.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8)
                })
                .collect();
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
