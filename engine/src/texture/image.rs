//! `Image(file: "earth.png", wrap: Repeat)`: an image file, bilinearly filtered.

use super::{Texture, TextureId, TextureModel, Wrap};
use crate::format::{Color, Rgb};
use crate::scene::ImageFile;

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

impl TextureModel for Image {
    fn build(&self, _color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::Image { image: self.file.image.clone(), wrap: self.wrap }
    }
}
