//! `GltfImage(file: "scene.glb", image: 2, wrap: Repeat, filter: Bilinear, raw: false,
//! uv_transform: ..)`: an image stored inside a glTF file (in a buffer view, as `.glb` files
//! keep them, or a `data:` URI) or named by it, read as the `Image` kind reads image files.

use super::{Filter, Texture, TextureId, TextureImage, TextureModel, UvTransform, Wrap};
use crate::format::gltf::GltfFile;
use crate::format::{Color, Rgb, context};
use serde::{Deserialize, Deserializer};
use std::sync::Arc;

/// Image `image` (its index) of the glTF file `file` (relative to the scene file), PNG or JPEG,
/// inside it (a buffer view, as `.glb` files keep images, or a `data:` URI) or beside it; otherwise
/// as `Image` (sRGB unless `raw: true`; a bump map may read it). What a converted glTF scene names
/// its embedded images with.
#[derive(serde::Deserialize, Debug, Clone, PartialEq)]
#[serde(try_from = "GltfImageFields")]
pub struct GltfImage {
    /// The glTF file, relative to the scene file, as written.
    pub file: std::path::PathBuf,
    /// The image's index in the file's `images`.
    pub image: u32,
    /// The decoded image.
    pub texels: Arc<TextureImage>,
    /// `Repeat` (default), `Clamp` or `Mirror`.
    pub wrap: Wrap,
    /// `Bilinear` (default) or `Nearest`.
    pub filter: Filter,
    /// Applied to the surface's uv before the lookup (default: none).
    pub uv_transform: Option<UvTransform>,
}

/// The fields as written.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields, rename = "GltfImage")]
struct GltfImageFields {
    file: GltfPath,
    image: u32,
    #[serde(default)]
    wrap: Wrap,
    #[serde(default)]
    filter: Filter,
    /// The 8-bit image's codes / 255, without the sRGB decoding (default false).
    #[serde(default)]
    raw: bool,
    #[serde(default)]
    uv_transform: Option<UvTransform>,
}

/// A glTF file's path as written and the file (`None` in the parse's first pass, which reads
/// no files).
struct GltfPath(std::path::PathBuf, Option<(std::path::PathBuf, Arc<GltfFile>)>);

impl<'de> Deserialize<'de> for GltfPath {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let path = std::path::PathBuf::from(String::deserialize(d)?);
        let Some(dir) = context::scene_dir() else { return Ok(GltfPath(path, None)) };
        let full = dir.join(&path);
        let file = GltfFile::read(&full).map_err(serde::de::Error::custom)?;
        Ok(GltfPath(path, Some((full, file))))
    }
}

impl TryFrom<GltfImageFields> for GltfImage {
    type Error = String;
    fn try_from(f: GltfImageFields) -> Result<Self, String> {
        let texels = match &f.file.1 {
            None => Arc::default(),
            Some((full, file)) => {
                // Decoded once however many textures name the image (raw or not).
                let key = full.join(format!("#image{}", f.image));
                let texels = match context::read_before::<TextureImage>(&key) {
                    Some(t) => t,
                    None => {
                        let bytes = file.image_bytes(f.image as usize, full)?;
                        let image = crate::format::files::decode_image_bytes(
                            bytes,
                            &key,
                            crate::format::files::MAX_IMAGE_SIDE,
                        )?;
                        let t = Arc::new(TextureImage::from_image(image, &key).map_err(|e| e.to_string())?);
                        context::keep(key, t.clone());
                        t
                    }
                };
                match f.raw && texels.srgb8() {
                    true => Arc::new(texels.undecoded()),
                    false => texels,
                }
            }
        };
        Ok(GltfImage {
            file: f.file.0,
            image: f.image,
            texels,
            wrap: f.wrap,
            filter: f.filter,
            uv_transform: f.uv_transform,
        })
    }
}

impl TextureModel for GltfImage {
    fn build(&self, _color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::Image {
            image: self.texels.clone(),
            wrap: self.wrap,
            filter: self.filter,
            transform: self.uv_transform,
        }
    }
}
