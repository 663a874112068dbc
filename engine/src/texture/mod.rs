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
//!
//! Decoded images ([`TextureImage`]) are in `texels`, Perlin's lattice noise ([`Perlin`]) in
//! `perlin`.

pub mod blocky_noise;
pub mod checker;
pub mod gltf_image;
pub mod image;
pub mod marble;
pub mod mesh_attribute;
pub mod noise;
mod perlin;
pub mod solid;
#[cfg(feature = "test-texture")]
pub mod test_stripes;
mod texels;
pub mod turbulence;
pub mod uv_checker;

pub use perlin::Perlin;
pub use texels::{TextureError, TextureImage, srgb_to_linear, srgb8_table};

use crate::accel::mesh::{MeshBlas, MeshData};
use crate::format::registry::{fields, registry, value};
use crate::format::{Color, Rgb};
use crate::shape::{MeshPoint, SurfacePoint};
use glam::{Vec2, Vec3, Vec3A};
use std::sync::Arc;

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
