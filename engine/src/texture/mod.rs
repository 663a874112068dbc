//! Textures: colours that vary over a surface (by its uv) or through space (by the world-space
//! hit point). Plain data in one flat list; a texture refers to others (checker squares) by
//! index, and only to textures defined before it, so evaluation always terminates.
//!
//! Each kind a scene writes lives in its own file as its RON description implementing
//! [`TextureModel`] (its conversion into the runtime [`Texture`]). The `registry!` invocation
//! below is the one list of kinds: it generates [`TextureDesc`] (the RON enum the scene parser
//! fills, `Kind(field: value, ...)`) and [`TextureKind`]. A kind whose runtime form exists (the
//! noise kinds share [`Texture::Noise`]) is its file, its `mod` line and its line in the list; a
//! kind that evaluates differently also adds its variant to [`Texture`] and its arms to
//! [`Textures::eval`] and [`Textures::mean`], the runtime that shading reads.
//!
//! Conventions: u runs along a quad's `u` edge and around a sphere eastwards (see the README);
//! v runs up. An image's row 0 is its top: v = 1 (Mitsuba 3 puts row 0 at its v = 0 and flips
//! an OBJ file's v on load, so the two agree on meshes, and a converted Mitsuba shape's v is
//! 1 - Mitsuba's). Solid textures (checker, noise) use world coordinates.

pub mod blocky_noise;
pub mod checker;
pub mod gltf_image;
pub mod image;
pub mod marble;
pub mod mesh_attribute;
pub mod noise;
pub mod solid;
#[cfg(feature = "test-texture")]
pub mod test_stripes;
pub mod turbulence;
pub mod uv_checker;

use crate::accel::mesh::{MeshBlas, MeshData};
use crate::format::registry::{fields, registry, value};
use crate::format::{Color, Rgb};
use crate::shape::{MeshPoint, SurfacePoint};
use glam::{Vec2, Vec3, Vec3A};
use std::path::Path;
use std::sync::{Arc, OnceLock};

registry! {
    /// A texture as written in the scene; colours inside may name textures defined before it.
    #[derive(Debug, Clone, PartialEq)]
    pub enum TextureDesc, TextureKind: dyn TextureModel, "Texture",
        "a texture such as Solid((0.5, 0.5, 0.5))", fields {
        Solid(solid::Solid) = value,
        Checker(checker::Checker),
        UvChecker(uv_checker::UvChecker),
        Image(image::Image),
        GltfImage(gltf_image::GltfImage),
        Noise(noise::Noise),
        BlockyNoise(blocky_noise::BlockyNoise),
        Turbulence(turbulence::Turbulence),
        Marble(marble::Marble),
        MeshAttribute(mesh_attribute::MeshAttribute),
        #[cfg(feature = "test-texture")]
        TestStripes(test_stripes::TestStripes),
    }
}

/// One kind of texture, as its RON description (a struct that denies unknown fields, or one
/// value read by `format::registry::value`).
pub trait TextureModel {
    /// The runtime texture. `color` gives the id of a colour written inside it (the texture
    /// it names, or a solid texture added for a colour written out), to be called in the order
    /// of the fields.
    fn build(&self, color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture;
}

/// Index into [`Textures::list`].
pub type TextureId = u32;

/// How image lookups outside [0, 1] wrap.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Deserialize)]
pub enum Wrap {
    /// Tile the image (default).
    #[default]
    Repeat,
    /// Repeat the edge texels.
    Clamp,
    /// Tile with every other copy mirrored.
    Mirror,
}

/// How an image is read between texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Deserialize)]
pub enum Filter {
    /// Bilinear interpolation between the four nearest texel centres (default).
    #[default]
    Bilinear,
    /// The texel the point falls in.
    Nearest,
}

/// An affine map of the uv plane, applied to a surface's uv before a texture reads it (Mitsuba's
/// `to_uv`): `u' = m[0][0] u + m[0][1] v + m[0][2]`, `v' = m[1][0] u + m[1][1] v + m[1][2]`.
/// RON: `((a, b, c), (d, e, f))`, rows, finite numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform(pub [[f32; 3]; 2]);

impl UvTransform {
    /// The transformed uv (products and sums in this order, no fused multiply-add).
    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let [a, b] = self.0;
        Vec2::new(a[0] * uv.x + a[1] * uv.y + a[2], b[0] * uv.x + b[1] * uv.y + b[2])
    }
}

impl<'de> serde::Deserialize<'de> for UvTransform {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let ((a, b, c), (e, f, g)) = <((f32, f32, f32), (f32, f32, f32))>::deserialize(d)?;
        let m = [[a, b, c], [e, f, g]];
        match m.iter().flatten().all(|x| x.is_finite()) {
            true => Ok(Self(m)),
            false => Err(serde::de::Error::custom(format!(
                "expected a uv transform of finite numbers, found (({a}, {b}, {c}), ({e}, {f}, {g}))"
            ))),
        }
    }
}

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

/// The noise functions of Shirley's "Ray Tracing: The Next Week" (Perlin noise, turbulence).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
pub enum NoiseKind {
    /// Random values at lattice points, no interpolation: blocky, in [0, 1].
    Blocky,
    /// Perlin gradient noise: random unit vectors at lattice points, Hermite-smoothed trilinear
    /// interpolation; mapped from [-1, 1] to [0, 1] (default).
    Smooth,
    /// Sum of `depth` octaves of |noise|, weights halving, frequencies doubling: in [0, 2).
    Turbulence,
    /// Marble veins: 0.5 (1 + sin(scale z + 10 turbulence(p))), in [0, 1].
    Marble,
}

/// One texture.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// One colour everywhere.
    Solid(Vec3),
    /// 3-D checker: cells of side `scale`, `even` where floor(x/s) + floor(y/s) + floor(z/s) is
    /// even.
    Checker {
        /// Cell size in world units.
        scale: f32,
        /// Texture of even cells.
        even: TextureId,
        /// Texture of odd cells.
        odd: TextureId,
    },
    /// Checker in uv: `u` by `v` cells over the [0, 1]^2 square (of the transformed uv).
    UvChecker {
        /// Cells along u.
        u: f32,
        /// Cells along v.
        v: f32,
        /// Texture of even cells.
        even: TextureId,
        /// Texture of odd cells.
        odd: TextureId,
        /// Applied to the surface's uv first (`None`: the identity).
        transform: Option<UvTransform>,
    },
    /// An image.
    Image {
        /// The texels.
        image: Arc<TextureImage>,
        /// Wrap mode.
        wrap: Wrap,
        /// Filter.
        filter: Filter,
        /// Applied to the surface's uv first (`None`: the identity).
        transform: Option<UvTransform>,
    },
    /// Noise of world position times `scale`, times `color`.
    Noise {
        /// Which function.
        kind: NoiseKind,
        /// Frequency: the noise of `scale * p`.
        scale: f32,
        /// Octaves for turbulence and marble.
        depth: u32,
        /// Colour the grey value multiplies.
        color: Vec3,
    },
    /// The values of the hit mesh's attribute `name` times `scale` (black off meshes).
    MeshAttribute {
        /// The attribute's name (`vertex_color`, `face_weight`).
        name: String,
        /// Multiplies the values.
        scale: f32,
    },
}

/// All textures of a scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Textures {
    /// Textures; one refers only to textures before it.
    pub list: Vec<Texture>,
}

impl Textures {
    /// The bytes the images' texels take (an image two textures share counted once).
    pub fn texel_bytes(&self) -> usize {
        let mut seen: Vec<*const TextureImage> = Vec::new();
        let mut bytes = 0;
        for t in &self.list {
            if let Texture::Image { image, .. } = t
                && !seen.contains(&Arc::as_ptr(image))
            {
                seen.push(Arc::as_ptr(image));
                bytes += image.texel_bytes();
            }
        }
        bytes
    }

    /// The colour of texture `id` at a surface point that is not on a mesh (mesh attributes
    /// read black).
    pub fn eval(&self, id: TextureId, uv: Vec2, p: Vec3A) -> Vec3 {
        self.eval_on(id, uv, p, None)
    }

    /// [`Self::eval`] at the point `on` of the mesh `mesh`, when it is on one.
    fn eval_on(&self, id: TextureId, uv: Vec2, p: Vec3A, mesh: Option<(&MeshData, MeshPoint)>) -> Vec3 {
        match &self.list[id as usize] {
            Texture::Solid(c) => *c,
            Texture::Checker { scale, even, odd } => {
                let c = (p / *scale).floor();
                let parity = (c.x + c.y + c.z).rem_euclid(2.0);
                self.eval_on(if parity < 1.0 { *even } else { *odd }, uv, p, mesh)
            }
            Texture::UvChecker { u, v, even, odd, transform } => {
                let t = transform.map_or(uv, |m| m.apply(uv));
                let parity = ((t.x * u).floor() + (t.y * v).floor()).rem_euclid(2.0);
                self.eval_on(if parity < 1.0 { *even } else { *odd }, uv, p, mesh)
            }
            Texture::Image { image, wrap, filter, transform } => {
                image.lookup(transform.map_or(uv, |m| m.apply(uv)), *wrap, *filter)
            }
            Texture::Noise { kind, scale, depth, color } => {
                let q = Vec3::from(p) * *scale;
                let perlin = Perlin::shared();
                let grey = match kind {
                    NoiseKind::Blocky => perlin.blocky(q),
                    NoiseKind::Smooth => 0.5 * (1.0 + perlin.noise(q)),
                    NoiseKind::Turbulence => perlin.turbulence(q, *depth),
                    // RTNW's marble: the turbulence of the unscaled point distorts the phase.
                    NoiseKind::Marble => {
                        0.5 * (1.0 + crate::math::sin(q.z + 10.0 * perlin.turbulence(p.into(), *depth)))
                    }
                };
                *color * grey
            }
            Texture::MeshAttribute { name, scale } => {
                let Some((m, on)) = mesh else { return Vec3::ZERO };
                let (Some(a), Some(&v)) =
                    (m.attributes.iter().find(|a| a.name == *name), m.triangles.get(on.triangle as usize))
                else {
                    return Vec3::ZERO;
                };
                a.at(on.triangle, v, on.b) * *scale
            }
        }
    }

    /// The colour at a surface point; `meshes` are the scene's (a point on one names its index,
    /// [`MeshPoint::mesh`]).
    #[inline]
    pub fn at(&self, id: TextureId, sp: &SurfacePoint, meshes: &[Arc<MeshBlas>]) -> Vec3 {
        let mesh = meshes.get(sp.on.mesh as usize).map(|b| (&*b.mesh, sp.on));
        self.eval_on(id, sp.uv, sp.p, mesh)
    }

    /// The derivatives along u and v of texture `id`'s value ([`scalar`] of its colour) at a
    /// surface point: an image's bilinear lookup's ([`TextureImage::bilinear_gradient`],
    /// through its uv transform); zero for a nearest lookup and for the other kinds (scenes
    /// ask it of images: a bump map's heights).
    pub fn gradient(&self, id: TextureId, sp: &SurfacePoint) -> Vec2 {
        match &self.list[id as usize] {
            Texture::Image { image, wrap, filter: Filter::Bilinear, transform } => {
                let t = transform.map_or(sp.uv, |m| m.apply(sp.uv));
                let g = image.bilinear_gradient(t, *wrap);
                match transform {
                    None => g,
                    // d/duv = transposed Jacobian of uv -> t, times d/dt.
                    Some(UvTransform([a, b])) => Vec2::new(a[0] * g.x + b[0] * g.y, a[1] * g.x + b[1] * g.y),
                }
            }
            _ => Vec2::ZERO,
        }
    }

    /// The width and height of texture `id`'s image, for one that is an image.
    pub fn resolution(&self, id: TextureId) -> Option<(u32, u32)> {
        match &self.list[id as usize] {
            Texture::Image { image, .. } => Some((image.width, image.height)),
            _ => None,
        }
    }

    /// A representative mean colour (light power estimates, statistics).
    pub fn mean(&self, id: TextureId) -> Vec3 {
        match &self.list[id as usize] {
            Texture::Solid(c) => *c,
            Texture::Checker { even, odd, .. } | Texture::UvChecker { even, odd, .. } => {
                0.5 * (self.mean(*even) + self.mean(*odd))
            }
            Texture::Image { image, .. } => image.mean(),
            Texture::Noise { kind, color, .. } => {
                *color * if *kind == NoiseKind::Turbulence { 0.3 } else { 0.5 }
            }
            // Unknown until a mesh is hit: half the scale (uniformly random values' mean).
            Texture::MeshAttribute { scale, .. } => Vec3::splat(0.5 * scale),
        }
    }
}

/// The most colours one material may take from textures.
pub const MAX_TEXTURED_COLORS: usize = 2;

/// The most numbers one material may take from textures (Principled's eleven).
pub const MAX_TEXTURED_SCALARS: usize = 12;

/// The number a colour texture's value stands for where a material takes a number: its Rec. 709
/// luminance, as Mitsuba's `eval_1` reads an RGB texture, and exactly the value for a grey
/// (where the luminance's rounding could move it by an ulp).
#[inline]
pub fn scalar(c: Vec3) -> f32 {
    if c.x == c.y && c.y == c.z { c.x } else { crate::math::luminance(c) }
}

/// Which of a material's colours and numbers come from textures, by colour slot and by number
/// slot (see [`crate::material::Colors`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MaterialTextures {
    /// Per colour slot.
    pub colors: [Option<TextureId>; MAX_TEXTURED_COLORS],
    /// Per number slot: the texture's [`scalar`] stands for the number.
    pub scalars: [Option<TextureId>; MAX_TEXTURED_SCALARS],
    /// The material takes the surface's tangent at each hit
    /// ([`crate::material::MaterialModel::set_tangent`]).
    pub tangent: bool,
}

impl MaterialTextures {
    /// True when a hit sets something of the material: a colour or number from a texture, or
    /// the tangent.
    pub fn any(&self) -> bool {
        self.tangent || self.colors.iter().chain(&self.scalars).any(Option::is_some)
    }
}

/// Ken Perlin's lattice noise with random unit gradients (RTNW ch. 5), from a fixed seed.
#[derive(Debug)]
pub struct Perlin {
    values: [f32; 256],
    gradients: [Vec3; 256],
    perm: [[u8; 256]; 3],
}

impl Perlin {
    /// The table every texture uses (built once).
    pub fn shared() -> &'static Perlin {
        static P: OnceLock<Perlin> = OnceLock::new();
        P.get_or_init(|| Perlin::new(0x5eed))
    }

    /// Tables from a seed (splitmix64).
    pub fn new(seed: u64) -> Self {
        let mut state = seed;
        let mut next = move || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        };
        let values = std::array::from_fn(|_| next());
        let gradients = std::array::from_fn(|_| {
            loop {
                let v = Vec3::new(2.0 * next() - 1.0, 2.0 * next() - 1.0, 2.0 * next() - 1.0);
                let l = v.length();
                if l > 0.1 && l <= 1.0 {
                    break v / l;
                }
            }
        });
        let perm = std::array::from_fn(|_| {
            let mut p: [u8; 256] = std::array::from_fn(|i| i as u8);
            for i in (1..256).rev() {
                let j = ((next() * (i + 1) as f32) as usize).min(i);
                p.swap(i, j);
            }
            p
        });
        Self { values, gradients, perm }
    }

    #[inline]
    fn hash(&self, i: i32, j: i32, k: i32) -> usize {
        (self.perm[0][(i & 255) as usize]
            ^ self.perm[1][(j & 255) as usize]
            ^ self.perm[2][(k & 255) as usize]) as usize
    }

    /// The value of the lattice cell containing `p`, in [0, 1).
    pub fn blocky(&self, p: Vec3) -> f32 {
        let c = p.floor();
        self.values[self.hash(c.x as i32, c.y as i32, c.z as i32)]
    }

    /// Gradient noise, in [-1, 1] (in fact within sqrt(3)/2).
    pub fn noise(&self, p: Vec3) -> f32 {
        let c = p.floor();
        let f = p - c;
        let (i, j, k) = (c.x as i32, c.y as i32, c.z as i32);
        // Hermite smoothing of the interpolation weights.
        let s = f * f * (3.0 - 2.0 * f);
        let mut acc = 0.0;
        for di in 0..2 {
            for dj in 0..2 {
                for dk in 0..2 {
                    let g = self.gradients[self.hash(i + di, j + dj, k + dk)];
                    let w = Vec3::new(f.x - di as f32, f.y - dj as f32, f.z - dk as f32);
                    let wx = if di == 1 { s.x } else { 1.0 - s.x };
                    let wy = if dj == 1 { s.y } else { 1.0 - s.y };
                    let wz = if dk == 1 { s.z } else { 1.0 - s.z };
                    acc += wx * wy * wz * g.dot(w);
                }
            }
        }
        acc
    }

    /// Sum over `depth` octaves of |noise|, weights 1, 1/2, 1/4, ..: in [0, 2).
    pub fn turbulence(&self, p: Vec3, depth: u32) -> f32 {
        let (mut acc, mut weight, mut q) = (0.0, 1.0, p);
        for _ in 0..depth {
            acc += weight * self.noise(q).abs();
            weight *= 0.5;
            q *= 2.0;
        }
        acc
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points() -> impl Iterator<Item = Vec3> {
        (0..20_000).map(|i| {
            let f = |a: f32| ((0.5 + i as f32 * a).fract() - 0.5) * 40.0;
            Vec3::new(f(0.754_877_7), f(0.569_840_3), f(0.362_229_6))
        })
    }

    #[test]
    fn noise_values_stay_in_their_documented_ranges() {
        let p = Perlin::shared();
        let (mut lo, mut hi) = (f32::MAX, f32::MIN);
        for q in points() {
            let n = p.noise(q);
            (lo, hi) = (lo.min(n), hi.max(n));
            assert!(n.abs() <= 3f32.sqrt() / 2.0, "noise {n}");
            assert!((0.0..1.0).contains(&p.blocky(q)));
            let t = p.turbulence(q, 7);
            assert!((0.0..2.0).contains(&t), "turbulence {t}");
        }
        // Not degenerate: it uses a good part of its range.
        assert!(lo < -0.4 && hi > 0.4, "noise spans only [{lo}, {hi}]");
        let textures = Textures {
            list: vec![Texture::Noise { kind: NoiseKind::Marble, scale: 4.0, depth: 7, color: Vec3::ONE }],
        };
        for q in points() {
            let c = textures.eval(0, Vec2::ZERO, q.into());
            assert!((0.0..=1.0).contains(&c.x), "marble {c}");
        }
    }

    #[test]
    fn noise_is_continuous_and_zero_on_the_lattice() {
        let p = Perlin::shared();
        assert_eq!(p.noise(Vec3::new(3.0, -2.0, 7.0)), 0.0);
        let q = Vec3::new(1.3, 2.7, -0.4);
        assert!((p.noise(q) - p.noise(q + Vec3::splat(1e-4))).abs() < 1e-3);
    }

    #[test]
    fn checkers_alternate() {
        let t = Textures {
            list: vec![
                Texture::Solid(Vec3::ZERO),
                Texture::Solid(Vec3::ONE),
                Texture::Checker { scale: 2.0, even: 0, odd: 1 },
                Texture::UvChecker { u: 4.0, v: 2.0, even: 0, odd: 1, transform: None },
            ],
        };
        assert_eq!(t.eval(2, Vec2::ZERO, Vec3A::new(0.5, 0.5, 0.5)), Vec3::ZERO);
        assert_eq!(t.eval(2, Vec2::ZERO, Vec3A::new(2.5, 0.5, 0.5)), Vec3::ONE);
        assert_eq!(t.eval(2, Vec2::ZERO, Vec3A::new(-0.5, 0.5, 0.5)), Vec3::ONE);
        assert_eq!(t.eval(3, Vec2::new(0.1, 0.1), Vec3A::ZERO), Vec3::ZERO);
        assert_eq!(t.eval(3, Vec2::new(0.3, 0.1), Vec3A::ZERO), Vec3::ONE);
        assert_eq!(t.eval(3, Vec2::new(0.3, 0.6), Vec3A::ZERO), Vec3::ZERO);
    }

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

    /// The gradient of the bilinear lookup is its finite difference inside each texel square,
    /// along u and v (v up, rows down), through a uv transform and across a wrapped edge, for a
    /// grey image and a coloured one (luminance). A gradient with v's sign flipped, or the
    /// transform applied untransposed, fails.
    #[test]
    fn gradients_are_the_lookups_slopes() {
        let mut r = crate::testing::signed(3);
        let grey: Vec<Vec3> = (0..35).map(|_| Vec3::splat(0.5 + 0.5 * r())).collect();
        let colour: Vec<Vec3> = (0..35).map(|_| Vec3::new(r(), r(), r()) * 0.5 + 0.5).collect();
        let m = UvTransform([[1.5, 0.5, 0.1], [-0.25, 2.0, 0.3]]);
        for texels in [grey, colour] {
            let image = Arc::new(TextureImage::linear(7, 5, texels));
            for (wrap, transform) in [(Wrap::Repeat, None), (Wrap::Mirror, Some(m)), (Wrap::Clamp, None)] {
                let t = Textures {
                    list: vec![Texture::Image {
                        image: image.clone(),
                        wrap,
                        filter: Filter::Bilinear,
                        transform,
                    }],
                };
                let value = |uv: Vec2| scalar(t.eval(0, uv, Vec3A::ZERO)) as f64;
                for k in 0..200 {
                    let uv = Vec2::new(0.5 * r() + 0.45, 0.5 * r() + 0.45);
                    let sp = SurfacePoint::flat(Vec3A::Z, uv);
                    let g = t.gradient(0, &sp);
                    // One-sided slopes: where they disagree the step crossed a texel edge (a
                    // kink of the interpolation); elsewhere their mean is the slope.
                    let h = 1e-3f32;
                    let slope = |d: Vec2| {
                        let (f0, fp, fm) = (value(uv), value(uv + d), value(uv - d));
                        let (fwd, bwd) = ((fp - f0) / h as f64, (f0 - fm) / h as f64);
                        ((fwd - bwd).abs() < 1e-2 * (1.0 + fwd.abs())).then_some(0.5 * (fwd + bwd))
                    };
                    let (Some(du), Some(dv)) = (slope(Vec2::new(h, 0.0)), slope(Vec2::new(0.0, h))) else {
                        continue;
                    };
                    let tol = 2e-2 * (1.0 + du.abs().max(dv.abs()));
                    assert!((g.x as f64 - du).abs() < tol, "{k} {wrap:?}: d/du {} vs {du}", g.x);
                    assert!((g.y as f64 - dv).abs() < tol, "{k} {wrap:?}: d/dv {} vs {dv}", g.y);
                }
            }
        }
    }

    /// A 4 x 2 image whose texel in column i, row j (from the top) is (i, j, 0).
    fn grid() -> TextureImage {
        let texels = (0..2).flat_map(|j| (0..4).map(move |i| Vec3::new(i as f32, j as f32, 0.0))).collect();
        TextureImage::linear(4, 2, texels)
    }

    /// Mitsuba's nearest lookup (Dr.Jit's `tex_eval`): texel (floor(u w), floor(v h)) of its uv,
    /// whose v is 1 - pathwave's, each index wrapped (`tex_wrap`: repeat is the Euclidean
    /// remainder, mirror reflects every other period, clamp clamps).
    #[test]
    fn nearest_takes_the_texel_the_point_falls_in() {
        let img = grid();
        let at = |u: f32, v: f32, wrap| img.nearest(Vec2::new(u, v), wrap);
        // Mitsuba's uv (0.3, 0.2): texel (floor(1.2), floor(0.4)) = (1, 0), the top row.
        assert_eq!(at(0.3, 0.8, Wrap::Repeat), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(at(0.99, 0.01, Wrap::Repeat), Vec3::new(3.0, 1.0, 0.0));
        // u = -0.1: column -1; u = 1.1: column 4; u = -0.3: column -2.
        for (u, repeat, mirror, clamp) in [(-0.1, 3.0, 0.0, 0.0), (1.1, 0.0, 3.0, 3.0), (-0.3, 2.0, 1.0, 0.0)]
        {
            assert_eq!(at(u, 0.8, Wrap::Repeat).x, repeat, "repeat at u = {u}");
            assert_eq!(at(u, 0.8, Wrap::Mirror).x, mirror, "mirror at u = {u}");
            assert_eq!(at(u, 0.8, Wrap::Clamp).x, clamp, "clamp at u = {u}");
        }
        // v = 1.3 (Mitsuba's -0.3): row -1, which mirror and clamp read as row 0, repeat as 1.
        assert_eq!(at(0.3, 1.3, Wrap::Repeat).y, 1.0);
        assert_eq!(at(0.3, 1.3, Wrap::Mirror).y, 0.0);
        assert_eq!(at(0.3, 1.3, Wrap::Clamp).y, 0.0);
        // Far away and NaN stay in the image.
        assert!(at(1e30, f32::NAN, Wrap::Mirror).is_finite());
    }

    /// Mitsuba's bilinear lookup: x = u w - 1/2, the texels floor(x) and floor(x) + 1 weighted
    /// 1 - frac(x) and frac(x), each index wrapped; the same in v.
    #[test]
    fn bilinear_wraps_texel_indices_as_mitsuba() {
        let img = grid();
        let at = |u: f32, wrap| img.lookup(Vec2::new(u, 0.75), wrap, Filter::Bilinear).x;
        // u = 0.05: x = -0.3, texels -1 (weight 0.3) and 0 (0.7).
        assert!((at(0.05, Wrap::Repeat) - 0.3 * 3.0).abs() < 1e-6);
        assert!(at(0.05, Wrap::Mirror).abs() < 1e-6 && at(0.05, Wrap::Clamp).abs() < 1e-6);
        // u = 0.95: x = 3.3, texels 3 (0.7) and 4 (0.3): repeat reads column 0 for 4.
        assert!((at(0.95, Wrap::Repeat) - 0.7 * 3.0).abs() < 1e-6);
        assert!((at(0.95, Wrap::Mirror) - 3.0).abs() < 1e-6 && (at(0.95, Wrap::Clamp) - 3.0).abs() < 1e-6);
        // The filter switch: nearest there is column 3.
        assert_eq!(img.lookup(Vec2::new(0.95, 0.75), Wrap::Repeat, Filter::Nearest).x, 3.0);
    }

    #[test]
    fn uv_transforms_apply_before_the_lookup() {
        let m = UvTransform([[2.0, 0.0, -0.5], [0.0, 2.0, -0.5]]);
        assert_eq!(m.apply(Vec2::new(0.5, 0.25)), Vec2::new(0.5, 0.0));
        let swap = UvTransform([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]);
        let t = Textures {
            list: vec![
                Texture::Image {
                    image: Arc::new(grid()),
                    wrap: Wrap::Clamp,
                    filter: Filter::Nearest,
                    transform: None,
                },
                Texture::Image {
                    image: Arc::new(grid()),
                    wrap: Wrap::Clamp,
                    filter: Filter::Nearest,
                    transform: Some(swap),
                },
                Texture::Solid(Vec3::ZERO),
                Texture::Solid(Vec3::ONE),
                Texture::UvChecker { u: 2.0, v: 2.0, even: 2, odd: 3, transform: Some(m) },
            ],
        };
        let uv = Vec2::new(0.9, 0.2);
        assert_eq!(t.eval(1, uv, Vec3A::ZERO), t.eval(0, Vec2::new(0.2, 0.9), Vec3A::ZERO));
        // (0.3, 0.3) becomes (0.1, 0.1): cell (0, 0); (0.6, 0.3) becomes (0.7, 0.1): cell (1, 0).
        assert_eq!(t.eval(4, Vec2::new(0.3, 0.3), Vec3A::ZERO), Vec3::ZERO);
        assert_eq!(t.eval(4, Vec2::new(0.6, 0.3), Vec3A::ZERO), Vec3::ONE);
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
