//! Decoded images for image textures and environment maps: 8-bit files kept as their codes and
//! read through a 256-entry table (sRGB-decoded or raw), float files as linear RGB; nearest and
//! bilinear lookups with Mitsuba's wrap modes.

use super::{Filter, Wrap, scalar};
use glam::{Vec2, Vec3};
use std::path::Path;
use std::sync::{Arc, OnceLock};

/// A decoded image, row 0 on top. An 8-bit file keeps its codes, 3 bytes a texel, read through
/// a 256-entry table ([`srgb8_table`], or code / 255 for a raw one): a 16384 x 16384 PNG holds
/// 768 MiB, not the 3 GiB of `f32` RGB, and its decoded and raw views share them. Float files
/// are linear RGB.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TextureImage {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    texels: Texels,
}

/// The texels of a [`TextureImage`], row-major.
#[derive(Clone, Debug, PartialEq)]
enum Texels {
    /// An 8-bit file's codes, R, G, B for each texel, and the linear value of each code.
    Codes { codes: Arc<Vec<u8>>, table: &'static [f32; 256] },
    /// Linear RGB.
    Linear(Vec<Vec3>),
}

impl Default for Texels {
    fn default() -> Self {
        Texels::Linear(Vec::new())
    }
}

/// The values code / 255 of the 256 8-bit codes (a raw image's).
fn unit8_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|i| i as f32 / 255.0))
}

/// The linear values of the 256 8-bit sRGB codes, strictly increasing.
pub fn srgb8_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0)))
}

/// Why an image texture cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// Reading or decoding failed (or the file or the image is beyond the bounds of
    /// [`crate::format::files`]).
    #[error("{0}")]
    Read(String),
    /// No pixels.
    #[error("the image {} is empty", .0.display())]
    Empty(std::path::PathBuf),
}

impl TextureImage {
    /// Reads PNG, JPEG, BMP, HDR or EXR. 8-bit images are sRGB-encoded: they are decoded to linear
    /// once, here, through a 256-entry table ([`srgb8_table`]); float images are already linear.
    pub fn load(path: &Path) -> Result<Self, TextureError> {
        Self::from_image(crate::format::files::decode_image(path).map_err(TextureError::Read)?, path)
    }

    /// A decoded image's texels (as [`Self::load`] reads them); `path` names it in errors.
    pub fn from_image(img: ::image::DynamicImage, path: &Path) -> Result<Self, TextureError> {
        let (width, height) = (img.width(), img.height());
        if width == 0 || height == 0 {
            return Err(TextureError::Empty(path.to_owned()));
        }
        let float =
            matches!(img, ::image::DynamicImage::ImageRgb32F(_) | ::image::DynamicImage::ImageRgba32F(_));
        let texels = match float {
            // A float file may hold NaN, infinities or negative values: they read as 0.
            true => Texels::Linear(
                img.into_rgb32f()
                    .pixels()
                    .map(|p| Vec3::from_array(p.0.map(|c| if c.is_finite() { c.max(0.0) } else { 0.0 })))
                    .collect(),
            ),
            false => Texels::Codes { codes: Arc::new(img.into_rgb8().into_raw()), table: srgb8_table() },
        };
        Ok(Self { width, height, texels })
    }

    /// A `width` x `height` image of linear RGB `texels` (row-major, the top row first).
    ///
    /// # Panics
    /// If `texels.len() != width * height`.
    pub fn linear(width: u32, height: u32, texels: Vec<Vec3>) -> Self {
        assert_eq!(texels.len(), width as usize * height as usize, "{width} x {height} texels expected");
        Self { width, height, texels: Texels::Linear(texels) }
    }

    /// Whether the texels are an 8-bit file's, sRGB-decoded.
    pub fn srgb8(&self) -> bool {
        matches!(self.texels, Texels::Codes { table, .. } if std::ptr::eq(table, srgb8_table()))
    }

    /// The image without the sRGB decoding of an 8-bit file: each texel the file's code / 255
    /// (Mitsuba's `raw`), sharing the codes. A float image is returned as it is.
    pub fn undecoded(&self) -> Self {
        let texels = match &self.texels {
            Texels::Codes { codes, .. } => Texels::Codes { codes: codes.clone(), table: unit8_table() },
            linear => linear.clone(),
        };
        Self { width: self.width, height: self.height, texels }
    }

    /// Texel `i` (row-major), linear RGB.
    #[inline]
    pub fn texel(&self, i: usize) -> Vec3 {
        match &self.texels {
            Texels::Codes { codes, table } => {
                let c = &codes[3 * i..3 * i + 3];
                Vec3::new(table[c[0] as usize], table[c[1] as usize], table[c[2] as usize])
            }
            Texels::Linear(t) => t[i],
        }
    }

    /// All texels, row-major, linear RGB.
    pub fn texels(&self) -> Vec<Vec3> {
        (0..self.len()).map(|i| self.texel(i)).collect()
    }

    /// The number of texels.
    pub fn len(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Whether the image has no texels (only the default one).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The bytes its texels take.
    pub fn texel_bytes(&self) -> usize {
        match &self.texels {
            Texels::Codes { codes, .. } => codes.len(),
            Texels::Linear(t) => std::mem::size_of_val(t.as_slice()),
        }
    }

    /// The image at `uv` read through `filter`.
    #[inline]
    pub fn lookup(&self, uv: Vec2, wrap: Wrap, filter: Filter) -> Vec3 {
        match filter {
            Filter::Bilinear => self.bilinear(uv, wrap),
            Filter::Nearest => self.nearest(uv, wrap),
        }
    }

    /// The texel that `uv` falls in: column floor(u w), row floor((1 - v) h) from the top, as
    /// Mitsuba's nearest filter (Dr.Jit's `texture.h`: the position times the resolution,
    /// without the half-texel shift of the bilinear lookup), wrapped by `wrap`.
    #[inline]
    pub fn nearest(&self, uv: Vec2, wrap: Wrap) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        // Bounded as in `bilinear`; NaN reads texel 0.
        let x = (uv.x * w as f32).clamp(-2.1e9, 2.1e9).floor() as i64;
        let y = ((1.0 - uv.y) * h as f32).clamp(-2.1e9, 2.1e9).floor() as i64;
        self.texel((wrap_index(y, h, wrap) * w + wrap_index(x, w, wrap)) as usize)
    }

    /// Bilinear lookup at `uv` (texel centres at (i + 0.5) / size).
    #[inline]
    pub fn bilinear(&self, uv: Vec2, wrap: Wrap) -> Vec3 {
        let ([c00, c10, c01, c11], fx, fy) = self.square(uv, wrap);
        let top = c00.lerp(c10, fx);
        let bottom = c01.lerp(c11, fx);
        top.lerp(bottom, fy)
    }

    /// The four texels around `uv` (top left, top right, bottom left, bottom right, wrapped
    /// by `wrap`) and `uv`'s place between their centres.
    #[inline]
    fn square(&self, uv: Vec2, wrap: Wrap) -> ([Vec3; 4], f32, f32) {
        let (w, h) = (self.width as i64, self.height as i64);
        // Within +-2^31 texels, so that the indices below cannot overflow (a uv of 1e38 or
        // infinity from a mesh file); NaN stays NaN and reads texel 0.
        let x = (uv.x * w as f32 - 0.5).clamp(-2.1e9, 2.1e9);
        let y = ((1.0 - uv.y) * h as f32 - 0.5).clamp(-2.1e9, 2.1e9);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let texel = |i: i64, j: i64| {
            let (i, j) = (wrap_index(i, w, wrap), wrap_index(j, h, wrap));
            self.texel((j * w + i) as usize)
        };
        ([texel(x0, y0), texel(x0 + 1, y0), texel(x0, y0 + 1), texel(x0 + 1, y0 + 1)], fx, fy)
    }

    /// The derivatives along u and v of the bilinear lookup's value ([`scalar`] of its colour)
    /// at `uv`: those of the interpolation in the texel square `uv` falls in (Mitsuba's
    /// bitmap's `eval_1_grad`), in value per unit of u and v.
    pub fn bilinear_gradient(&self, uv: Vec2, wrap: Wrap) -> Vec2 {
        let ([c00, c10, c01, c11], fx, fy) = self.square(uv, wrap);
        // Per texel along x and y (rows run down, v up).
        let dx = (c10 - c00) * (1.0 - fy) + (c11 - c01) * fy;
        let dy = (c01 - c00) * (1.0 - fx) + (c11 - c10) * fx;
        Vec2::new(scalar(dx) * self.width as f32, -scalar(dy) * self.height as f32)
    }

    /// Mean texel.
    pub fn mean(&self) -> Vec3 {
        (0..self.len()).map(|i| self.texel(i)).sum::<Vec3>() / self.len() as f32
    }
}

#[inline]
fn wrap_index(i: i64, n: i64, wrap: Wrap) -> i64 {
    match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Mirror => {
            let k = i.rem_euclid(2 * n);
            if k < n { k } else { 2 * n - 1 - k }
        }
    }
}

/// The sRGB transfer function, inverted; the power in `f64`, rounded: a C library's last bits
/// reach the texture only at a rounding tie (about one value in 2^29).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c as f64 + 0.055) / 1.055).powf(2.4) as f32 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::TextureDesc;

    #[test]
    fn bilinear_wraps_and_runs_v_upwards() {
        // 2 x 2: top row red, green; bottom row blue, white.
        let img = TextureImage::linear(2, 2, vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE]);
        // Texel centres: (0.25, 0.75) is the top-left texel.
        assert_eq!(img.bilinear(Vec2::new(0.25, 0.75), Wrap::Repeat), Vec3::X);
        assert_eq!(img.bilinear(Vec2::new(0.75, 0.25), Wrap::Repeat), Vec3::ONE);
        // Halfway between the top texels.
        assert_eq!(img.bilinear(Vec2::new(0.5, 0.75), Wrap::Clamp), Vec3::new(0.5, 0.5, 0.0));
        // At u = 0 Repeat blends with the right column, Clamp does not.
        assert_eq!(img.bilinear(Vec2::new(0.0, 0.75), Wrap::Repeat), Vec3::new(0.5, 0.5, 0.0));
        assert_eq!(img.bilinear(Vec2::new(0.0, 0.75), Wrap::Clamp), Vec3::X);
        assert_eq!(img.bilinear(Vec2::new(-0.25, 0.75), Wrap::Mirror), Vec3::X);
        assert_eq!(img.bilinear(Vec2::new(1.25, 0.75), Wrap::Repeat), Vec3::X);
    }

    #[test]
    fn raw_gives_back_the_eight_bit_codes() {
        let codes = ::image::RgbImage::from_fn(256, 1, |i, _| ::image::Rgb([i as u8, 255 - i as u8, 7]));
        let img = TextureImage::from_image(codes.into(), Path::new("codes.png")).unwrap();
        assert!(img.srgb8());
        let raw = img.undecoded();
        assert!(!raw.srgb8());
        for (i, t) in raw.texels().iter().enumerate() {
            assert_eq!(*t, Vec3::new(i as f32 / 255.0, (255 - i) as f32 / 255.0, 7.0 / 255.0), "code {i}");
        }
        // 3 bytes a texel, shared by the two views.
        assert_eq!((img.texel_bytes(), raw.texel_bytes()), (3 * 256, 3 * 256));
        // Float images are linear already.
        let hdr = TextureImage::linear(256, 1, img.texels());
        assert_eq!(hdr.undecoded(), hdr);
    }

    /// An image file named by several textures and the environment is read once: one copy of
    /// its codes serves them all, raw views included.
    #[test]
    fn an_image_named_many_times_is_read_once() {
        let dir = std::env::temp_dir().join(format!("pathwave-shared-tex-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        ::image::RgbImage::from_pixel(64, 32, ::image::Rgb([188, 128, 0])).save(dir.join("t.png")).unwrap();
        let path = dir.join("scene.ron");
        std::fs::write(
            &path,
            r#"Scene(
                camera: (look_from: (0, 0, 1), look_at: (0, 0, 0), vfov: 40),
                background: Environment(file: "t.png"),
                textures: {
                    "a": Image(file: "t.png"),
                    "b": Image(file: "./t.png", filter: Nearest),
                    "c": Image(file: "t.png", raw: true),
                },
                materials: { "m": Lambertian(albedo: "a"), "n": Lambertian(albedo: "b") },
                objects: [],
            )"#,
        )
        .unwrap();
        let desc = crate::scene::load(&path).unwrap();
        let images: Vec<&TextureImage> = desc
            .textures
            .0
            .iter()
            .map(|(_, t)| match t {
                TextureDesc::Image(i) => &*i.file.image,
                other => panic!("{other:?}"),
            })
            .collect();
        let crate::scene::BackgroundDesc::Environment { file, .. } = &desc.background else { panic!() };
        let codes = |i: &TextureImage| match &i.texels {
            Texels::Codes { codes, .. } => Arc::as_ptr(codes),
            Texels::Linear(_) => panic!("8-bit texels"),
        };
        for i in images.iter().chain([&&*file.image]) {
            assert_eq!(codes(i), codes(images[0]));
        }
        assert!(images[0].srgb8() && !images[2].srgb8());
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn eight_bit_images_are_srgb_decoded_once() {
        let dir = std::env::temp_dir().join(format!("pathwave-tex-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("grey.png");
        ::image::RgbImage::from_pixel(1, 1, ::image::Rgb([188, 128, 0])).save(&path).unwrap();
        let img = TextureImage::load(&path).unwrap();
        let t = img.texel(0);
        // sRGB 188/255 is linear 0.5029 (decoded twice it would be 0.2; not at all, 0.737).
        assert!((t.x - 0.502_886).abs() < 1e-4, "{t}");
        assert!((t.y - srgb_to_linear(128.0 / 255.0)).abs() < 1e-6 && t.z == 0.0);
        std::fs::remove_dir_all(dir).unwrap();
    }
}
