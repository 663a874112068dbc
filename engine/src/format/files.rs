//! Reading the files a scene names, within bounds: only regular files (not devices, pipes or
//! folders), at most a documented size, so that no path in a scene can make a load read
//! forever or exhaust memory.

use std::io::Read;
use std::path::Path;

/// The largest scene file read: 256 MiB.
pub const MAX_SCENE_BYTES: u64 = 256 << 20;
/// The largest mesh (OBJ) or image file read: 1 GiB.
pub const MAX_ASSET_BYTES: u64 = 1 << 30;
/// The largest image a texture may decode to, per side (and 1 GiB of pixels in all).
pub const MAX_IMAGE_SIDE: u32 = 32768;

/// The bytes of the regular file `path`, refused beyond `max` bytes; `what` names it in errors.
pub fn read_bounded(path: &Path, max: u64, what: &str) -> Result<Vec<u8>, String> {
    let fail = |e: std::io::Error| format!("cannot read the {what} {}: {e}", path.display());
    let meta = std::fs::metadata(path).map_err(fail)?;
    if !meta.is_file() {
        return Err(format!("the {what} {} is not a regular file", path.display()));
    }
    if meta.len() > max {
        return Err(format!(
            "the {what} {} has {} bytes, more than the {max} allowed",
            path.display(),
            meta.len()
        ));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // A file that grows while it is read stops at the bound too.
    std::fs::File::open(path).and_then(|f| f.take(max + 1).read_to_end(&mut bytes)).map_err(fail)?;
    if bytes.len() as u64 > max {
        return Err(format!("the {what} {} has more than the {max} bytes allowed", path.display()));
    }
    Ok(bytes)
}

/// Decodes an image file within [`MAX_IMAGE_SIDE`] and 1 GiB of decoded pixels (`image`'s
/// limits), so that a small file that expands to a huge image is refused.
pub fn decode_image(path: &Path) -> Result<image::DynamicImage, String> {
    decode_image_bytes(read_bounded(path, MAX_ASSET_BYTES, "image")?, path, MAX_IMAGE_SIDE)
}

/// Decodes the bytes of an image file (format guessed from them) within `max_side` pixels a
/// side and 1 GiB of decoded pixels; `path` names the file in errors.
pub fn decode_image_bytes(bytes: Vec<u8>, path: &Path, max_side: u32) -> Result<image::DynamicImage, String> {
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot read the image {}: {e}", path.display()))?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(max_side);
    limits.max_image_height = Some(max_side);
    limits.max_alloc = Some(MAX_ASSET_BYTES);
    reader.limits(limits);
    reader.decode().map_err(|e| format!("cannot read the image {}: {e}", path.display()))
}
