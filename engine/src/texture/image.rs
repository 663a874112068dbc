//! `Image(file: "earth.png", wrap: Repeat, filter: Bilinear, raw: false, uv_transform: ..)`:
//! an image file, bilinearly filtered or nearest.

use super::{Filter, Texture, TextureId, TextureImage, TextureModel, UvTransform, Wrap};
use crate::format::{Color, Rgb, context};
use serde::{Deserialize, Deserializer, de::Error};
use std::sync::Arc;

/// PNG, JPEG, BMP, HDR or EXR relative to the scene file; 8-bit files are sRGB (decoded once, at
/// load) unless `raw: true` (codes / 255), float files linear. Row 0 is at v = 1. `filter`:
/// `Bilinear` (default; between texel centres at ((i + 0.5) / width, 1 - (j + 0.5) / height)) or
/// `Nearest` (the texel floor(u width), floor((1 - v) height)); `wrap` of texel indices: `Repeat`
/// (default), `Clamp`, `Mirror` (every other copy reflected); `uv_transform` as `UvChecker`'s
/// (Mitsuba's `to_uv`).
#[derive(serde::Deserialize, Debug, Clone, PartialEq)]
#[serde(from = "ImageFields")]
pub struct Image {
    /// The file (its 8-bit texels left undecoded if the scene says `raw: true`).
    pub file: ImageFile,
    /// `Repeat` (default), `Clamp` or `Mirror`.
    pub wrap: Wrap,
    /// `Bilinear` (default) or `Nearest`.
    pub filter: Filter,
    /// Applied to the surface's uv before the lookup (default: none).
    pub uv_transform: Option<UvTransform>,
}

/// The fields as written; `raw` is applied to the file once it is read.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields, rename = "Image")]
struct ImageFields {
    file: ImageFile,
    #[serde(default)]
    wrap: Wrap,
    #[serde(default)]
    filter: Filter,
    /// The 8-bit file's codes / 255, without the sRGB decoding (default false).
    #[serde(default)]
    raw: bool,
    #[serde(default)]
    uv_transform: Option<UvTransform>,
}

impl From<ImageFields> for Image {
    fn from(f: ImageFields) -> Self {
        let mut file = f.file;
        if f.raw && file.image.srgb8() {
            file.image = Arc::new(file.image.undecoded());
        }
        Image { file, wrap: f.wrap, filter: f.filter, uv_transform: f.uv_transform }
    }
}

/// An image file, read when the scene is loaded (also an environment map's).
#[derive(Debug, Clone, PartialEq)]
pub struct ImageFile {
    /// The path as written.
    pub path: std::path::PathBuf,
    /// The decoded image.
    pub image: Arc<TextureImage>,
}

impl<'de> Deserialize<'de> for ImageFile {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let path = std::path::PathBuf::from(String::deserialize(d)?);
        let Some(dir) = context::scene_dir() else {
            context::want(&path, context::Wanted::Image);
            return Ok(ImageFile { path, image: Arc::default() });
        };
        // Read once however many textures and maps name the file.
        let full = dir.join(&path);
        let image = match context::read_before::<TextureImage>(&full) {
            Some(image) => image,
            None => {
                let image = Arc::new(TextureImage::load(&full).map_err(D::Error::custom)?);
                context::keep(full, image.clone());
                image
            }
        };
        Ok(ImageFile { path, image })
    }
}

impl TextureModel for Image {
    fn build(&self, _color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::Image {
            image: self.file.image.clone(),
            wrap: self.wrap,
            filter: self.filter,
            transform: self.uv_transform,
        }
    }
}
