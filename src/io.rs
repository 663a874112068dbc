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
/// PNG clamped. The image is encoded in memory, then written with [`atomically`].
pub fn write(path: &Path, img: &LinearImage) -> Result<usize, String> {
    let (bytes, clamped) = encode(path, img)?;
    atomically(path, &bytes)?;
    Ok(clamped)
}

/// Writes `bytes` to `path` whole or not at all: to a temporary file beside it (`tempfile`),
/// synced to the disk and checked, then renamed over `path`. On any failure the previous file
/// is left as it was and the error names `path`.
pub fn atomically(path: &Path, bytes: &[u8]) -> Result<(), String> {
    use std::io::Write;
    let fail = |e: std::io::Error| format!("{}: cannot write: {e}", path.display());
    let mut tmp = temp_beside(path).map_err(fail)?;
    tmp.write_all(bytes).map_err(fail)?;
    tmp.as_file().sync_all().map_err(fail)?;
    tmp.persist(path).map_err(|e| fail(e.error))?;
    Ok(())
}

/// Checks an output before any work: a format `write` knows (`.png`, `.exr`; `.gif` too when
/// `gif`), a folder that exists and takes a new file, and not one of `inputs` (the scene, the
/// parts being merged), which it would replace.
pub fn check_output(path: &Path, inputs: &[&Path], gif: bool) -> Result<(), String> {
    let ext = extension(path);
    let known = ext == "png" || ext == "exr" || (gif && ext == "gif");
    if !known {
        let formats = if gif { ".png, .exr or .gif" } else { ".png or .exr" };
        return Err(format!("{}: unknown output format (use {formats})", path.display()));
    }
    if let Some(input) = inputs.iter().find(|i| same_file(path, i)) {
        return Err(format!("{}: the output would replace an input ({})", path.display(), input.display()));
    }
    // The folder must take a new file (a temporary one, removed at once).
    temp_beside(path).map(drop).map_err(|e| format!("{}: cannot write there: {e}", path.display()))
}

/// True when both paths exist and name the same file.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// A temporary file in `path`'s directory, named after it, created with the permissions a
/// new file gets (0o666 less the umask, not `tempfile`'s private 0o600), since it becomes
/// `path`.
pub fn temp_beside(path: &Path) -> std::io::Result<tempfile::NamedTempFile> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let prefix = format!(".{name}.");
    let mut b = tempfile::Builder::new();
    b.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    b.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    b.tempfile_in(dir)
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
    let err = |e: image::ImageError| format!("{}: {e}", path.display());
    let mut bytes = Vec::new();
    {
        let mut enc = GifEncoder::new_with_speed(&mut bytes, 10);
        enc.set_repeat(Repeat::Infinite).map_err(err)?;
        let delay = image::Delay::from_numer_denom_ms(1000, fps.max(1e-3).round().max(1.0) as u32);
        for f in frames {
            let (rgb, _) = srgb8(f);
            let rgba: Vec<u8> = rgb.chunks_exact(3).flat_map(|c| [c[0], c[1], c[2], 255]).collect();
            let buf = image::RgbaImage::from_raw(f.width, f.height, rgba).expect("size");
            enc.encode_frame(image::Frame::from_parts(buf, 0, 0, delay)).map_err(err)?;
        }
    }
    atomically(path, &bytes)
}

/// The file's bytes for `path`'s format, and how many pixels a PNG clamped.
fn encode(path: &Path, img: &LinearImage) -> Result<(Vec<u8>, usize), String> {
    let err = |e: image::ImageError| format!("{}: {e}", path.display());
    let mut bytes = std::io::Cursor::new(Vec::new());
    let clamped = match extension(path).as_str() {
        "exr" => {
            let data: Vec<f32> = img.pixels.iter().flat_map(|p| p.to_array()).collect();
            let buf: Rgb32FImage = ImageBuffer::from_raw(img.width, img.height, data).expect("size matches");
            buf.write_to(&mut bytes, image::ImageFormat::OpenExr).map_err(err)?;
            0
        }
        "png" => {
            let (data, clamped) = srgb8(img);
            let buf: RgbImage =
                ImageBuffer::<Rgb<u8>, _>::from_raw(img.width, img.height, data).expect("size");
            buf.write_to(&mut bytes, image::ImageFormat::Png).map_err(err)?;
            clamped
        }
        _ => return Err(format!("{}: unknown output format (use .png or .exr)", path.display())),
    };
    Ok((bytes.into_inner(), clamped))
}

/// The sRGB transfer function (linear to encoded).
pub fn srgb_oetf(c: f32) -> f32 {
    if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}
