//! `Image(file: "earth.png", wrap: Repeat)`: an image file, bilinearly filtered.

use super::{Texture, TextureId, TextureImage, TextureModel, Wrap};
use crate::format::{Color, Rgb, context};
use serde::{Deserialize, Deserializer, de::Error};

/// PNG, JPEG, HDR or EXR, relative to the scene file; 8-bit images are sRGB, float ones linear.
#[derive(serde::Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Image {
    /// The file.
    pub file: ImageFile,
    /// `Repeat` (default), `Clamp` or `Mirror`.
    #[serde(default)]
    pub wrap: Wrap,
}

/// An image file, read when the scene is loaded (also an environment map's).
#[derive(Debug, Clone, PartialEq)]
pub struct ImageFile {
    /// The path as written.
    pub path: std::path::PathBuf,
    /// The decoded image.
    pub image: std::sync::Arc<TextureImage>,
}

impl<'de> Deserialize<'de> for ImageFile {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let path = std::path::PathBuf::from(String::deserialize(d)?);
        let image = match context::scene_dir() {
            Some(dir) => TextureImage::load(&dir.join(&path)).map_err(D::Error::custom)?,
            None => TextureImage::default(),
        };
        Ok(ImageFile { path, image: std::sync::Arc::new(image) })
    }
}

impl TextureModel for Image {
    fn build(&self, _color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::Image { image: self.file.image.clone(), wrap: self.wrap }
    }
}
