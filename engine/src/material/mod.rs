//! Materials: what each kind is made of, how a scene writes it, and how it scatters light.
//!
//! Each kind lives in its own file as a type implementing [`MaterialModel`] (its parameters,
//! its RON description, its BSDF and its tests). The `registry!` invocation below is the one
//! list of kinds: it generates the [`Material`] enum the integrators read, the
//! [`MaterialDesc`] enum the scene parser fills (`Kind(field: value, ...)`), and
//! [`MaterialKind`], which names the shading queues, stages and statistics. Adding a material
//! means its file and one line in that list; its README row is its description type's doc
//! comment (`tests/readme_kinds.rs` checks it, and writes it with `PATHWAVE_BLESS=1`).
//!
//! Directions point away from the surface (`wo` towards the previous vertex, `wi` towards the
//! next); `n` is the unit shading normal.

pub mod chi2;
pub mod dielectric;
pub mod diffuse_light;
mod disney;
pub mod ggx_energy;
pub mod lambertian;
pub mod metal;
pub mod metallic_roughness;
pub mod microfacet;
pub mod plastic;
pub mod principled;
pub mod principled_thin;
pub mod rough_conductor;
pub mod rough_dielectric;
pub mod rough_plastic;
#[cfg(feature = "test-material")]
pub mod test_diffuse;
pub mod thin_dielectric;
pub mod wrap;

use crate::format::registry::{VariantName, fields};
use crate::texture::{MAX_TEXTURED_COLORS, MAX_TEXTURED_SCALARS, MaterialTextures, TextureId};
use glam::{Vec2, Vec3, Vec3A};

pub use dielectric::Fresnel;

registry! {
    Lambertian(lambertian::Lambertian),
    Metal(metal::Metal),
    Dielectric(dielectric::Dielectric),
    RoughConductor(rough_conductor::RoughConductor),
    RoughDielectric(rough_dielectric::RoughDielectric),
    Plastic(plastic::Plastic),
    RoughPlastic(rough_plastic::RoughPlastic),
    Principled(principled::Principled),
    MetallicRoughness(metallic_roughness::MetallicRoughness),
    PrincipledThin(principled_thin::PrincipledThin),
    ThinDielectric(thin_dielectric::ThinDielectric),
    DiffuseLight(diffuse_light::DiffuseLight),
    #[cfg(feature = "test-material")]
    TestDiffuse(test_diffuse::TestDiffuse),
}

/// How the integrators shade a hit on a material kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    /// An emitter with a black BSDF: the path adds its MIS-weighted emission and ends. No
    /// shading queue.
    Emitter,
    /// A Lambertian reflector of reflectance [`MaterialModel::albedo`]: the Lambertian lane
    /// kernel samples a light and the cosine lobe, weighted by multiple importance sampling.
    Diffuse,
    /// Only [`MaterialModel::sample`] is used: no light sampling, so an emitter that the sampled
    /// ray meets counts in full.
    Sampled,
    /// A BSDF that can be evaluated: the integrators sample a light and the BSDF and weight
    /// both by multiple importance sampling (power heuristic), using [`MaterialModel::eval`] for
    /// the light's direction and the pdf of [`MaterialModel::sample`] for the BSDF's. A BSDF
    /// sample marked [`BsdfSample::delta`] has no density: an emitter it meets counts in full.
    Glossy,
}

/// How the denoiser's guides see a material (see the integrator's `aov` module): perfect mirrors
/// and glass hand the guides on to what they show.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Specular {
    /// The guides record this surface's albedo.
    No,
    /// A perfect mirror tinted by [`MaterialModel::albedo`].
    Mirror,
    /// Glass with this index of refraction.
    Glass {
        /// Index of refraction inside.
        ior: f32,
    },
}

/// An emitter's radiance (see [`crate::lighting::area`], which holds it per material id).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    /// Emitted radiance.
    pub emit: Vec3,
    /// Emits on both sides; otherwise only on the side of the geometric normal.
    pub two_sided: bool,
    /// The colour slot (see [`Colors`]) the radiance was taken from: a texture there makes it
    /// vary over the surface.
    pub slot: usize,
}

/// A sampled scattering direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Unit direction of the next ray.
    pub wi: Vec3A,
    /// Throughput factor `f * |cos| / pdf`.
    pub weight: Vec3,
    /// Density of `wi` (for delta lobes: the discrete probability of the chosen lobe).
    pub pdf: f32,
    /// Relative index of refraction crossed (1 for reflection); Russian roulette divides it out.
    pub eta: f32,
    /// The sampled lobe is a delta (a mirror, a smooth refraction, or Metal's fuzzed mirror,
    /// whose density is not evaluated): `pdf` is then not a density in solid angle, and an
    /// emitter the ray meets gets no MIS weight (it counts in full). False for lobes with a
    /// density that [`MaterialModel::eval`] reproduces.
    pub delta: bool,
    /// A null lobe: the ray goes on unbent as if the surface were not there (a thin
    /// dielectric's transmission, Mitsuba's `Null` flag). The path keeps its MIS state (an
    /// emitter it meets is weighted as seen from the last scattering before), and the crossing
    /// is not a bounce of `max_depth`, though it takes the sampler's numbers of one.
    pub null: bool,
}

/// Which numbers [`MaterialModel::sample`] reads: `u` (the direction's two) and `uc` (the
/// lobe's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reads {
    /// `u`.
    pub dir: bool,
    /// `uc`.
    pub lobe: bool,
}

/// A BSDF evaluated for a pair of directions (see [`MaterialModel::eval`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfEval {
    /// `f(wo, wi) * |wi . n|`.
    pub f_cos: Vec3,
    /// Density in solid angle with which [`MaterialModel::sample`] would produce `wi` from
    /// `wo`, lobe choice included (0 where it never does, and for delta lobes).
    pub pdf: f32,
}

impl BsdfEval {
    /// No scattering, zero density.
    pub const ZERO: Self = Self { f_cos: Vec3::ZERO, pdf: 0.0 };
}

/// One kind of material. Colours are linear RGB.
pub trait MaterialModel: Copy + std::fmt::Debug + PartialEq + Send + Sync + 'static {
    /// Its parameters as a scene writes them, inside `Kind(...)`.
    type Desc: serde::de::DeserializeOwned + std::fmt::Debug + Clone;

    /// How the integrators shade it.
    const SHADING: Shading;

    /// The material of a description. Colours go through `colors`, which gives a texture's
    /// mean and remembers the texture: [`Self::set_color`] later sets the value at a hit.
    fn build(desc: &Self::Desc, colors: &mut Colors) -> Self;

    /// Sets the `slot`-th colour taken from `colors` in [`Self::build`] (a texture's value).
    fn set_color(&mut self, slot: usize, value: Vec3) {
        let _ = (slot, value);
    }

    /// Sets the `slot`-th number taken from `colors` in [`Self::build`] (a texture's luminance),
    /// limiting it to the parameter's range.
    fn set_scalar(&mut self, slot: usize, value: f32) {
        let _ = (slot, value);
    }

    /// Sets the surface's tangent at a hit, `dpdu` (not unit, not orthogonal to the unit
    /// shading normal `n`), for a material that asked for it ([`Colors::tangent`]).
    fn set_tangent(&mut self, n: Vec3A, dpdu: Vec3A) {
        let _ = (n, dpdu);
    }

    /// Samples the next direction from numbers `u` and `uc` in [0, 1); `None` when the path is
    /// absorbed. Emitters do not scatter.
    fn sample(&self, wo: Vec3A, n: Vec3A, u: Vec2, uc: f32) -> Option<BsdfSample> {
        let _ = (wo, n, u, uc);
        None
    }

    /// Which of [`Self::sample`]'s numbers it reads, so that the integrators draw only those
    /// (both by default).
    fn reads(&self) -> Reads {
        Reads { dir: true, lobe: true }
    }

    /// The BSDF's non-delta part for directions `wo` and `wi` about the unit shading normal `n`:
    /// `f |wi . n|` and the density of `wi` under [`Self::sample`]. Zero by default: kinds
    /// shaded [`Shading::Glossy`] implement it, and [`Shading::Diffuse`] ones for the hits a
    /// bump or normal map sends to the glossy shading.
    fn eval(&self, wo: Vec3A, wi: Vec3A, n: Vec3A) -> BsdfEval {
        let _ = (wo, wi, n);
        BsdfEval::ZERO
    }

    /// Reflectance: the [`Shading::Diffuse`] kernel's, the mirror's tint, and the denoiser's
    /// albedo guide.
    fn albedo(&self) -> Vec3;

    /// What light sampling needs of an emitter; `None` for everything else.
    fn emission(&self) -> Option<Emission> {
        None
    }

    /// Sets an emitter's radiance (keyframed emission).
    fn set_emission(&mut self, emit: Vec3) {
        let _ = emit;
    }

    /// How the denoiser's guides see it.
    fn specular(&self) -> Specular {
        Specular::No
    }

    /// The fraction of light that passes straight through the surface at `cos` from its normal
    /// (a null lobe's, [`BsdfSample::null`]): shadow rays cross such surfaces, attenuated by
    /// it. 0 by default: the surface blocks them.
    fn null_transmission(&self, cos: f32) -> f32 {
        let _ = cos;
        0.0
    }

    /// Some of its samples are null ([`BsdfSample::null`]): a path at `max_depth` that meets it
    /// still samples it, and goes on if the sample is null.
    fn has_null_lobe(&self) -> bool {
        false
    }

    /// A [`Shading::Diffuse`] kind that reflects only on the side its shading normal faces: a
    /// path that meets it from behind (`wo . n <= 0`) ends there, as Mitsuba's one-sided BSDFs
    /// are black seen from behind.
    fn one_sided(&self) -> bool {
        false
    }

    /// Its sharpest lobe's width for light tracing (0 delta, infinity diffuse, `None` ignored).
    fn sharpest_alpha(&self) -> Option<f32> {
        None
    }
}

/// The colours and numbers of one material being built: plain values, or textures whose mean
/// stands in until a hit evaluates them.
pub struct Colors<'a> {
    texture: &'a mut dyn FnMut(&str) -> (TextureId, Vec3),
    slots: MaterialTextures,
    next: usize,
    next_scalar: usize,
}

impl<'a> Colors<'a> {
    /// Colours resolved through `texture`, which returns a texture name's id and mean.
    pub fn new(texture: &'a mut dyn FnMut(&str) -> (TextureId, Vec3)) -> Self {
        Self { texture, slots: MaterialTextures::default(), next: 0, next_scalar: 0 }
    }

    /// The next colour slot's value: the colour written out, or the texture's mean.
    pub fn get<T: Copy + Into<Vec3>>(&mut self, c: &crate::format::Color<T>) -> Vec3 {
        let slot = self.next;
        assert!(slot < MAX_TEXTURED_COLORS, "a material has at most {MAX_TEXTURED_COLORS} colours");
        self.next += 1;
        match c {
            crate::format::Color::Value(v) => (*v).into(),
            crate::format::Color::Texture(name) => {
                let (id, mean) = (self.texture)(name);
                self.slots.colors[slot] = Some(id);
                mean
            }
        }
    }

    /// The next number slot's value: the number written out, or what the texture's mean stands
    /// for ([`crate::texture::scalar`]).
    pub fn scalar<T: Copy + Into<f32>>(&mut self, s: &crate::format::Scalar<T>) -> f32 {
        let slot = self.next_scalar;
        assert!(
            slot < MAX_TEXTURED_SCALARS,
            "a material has at most {MAX_TEXTURED_SCALARS} textured numbers"
        );
        self.next_scalar += 1;
        match s {
            crate::format::Scalar::Value(v) => (*v).into(),
            crate::format::Scalar::Texture(name) => {
                let (id, mean) = (self.texture)(name);
                self.slots.scalars[slot] = Some(id);
                crate::texture::scalar(mean)
            }
        }
    }

    /// The material needs the surface's tangent at each hit ([`MaterialModel::set_tangent`]).
    pub fn tangent(&mut self) {
        self.slots.tangent = true;
    }

    /// Which colour and number slots came from textures.
    pub fn textures(&self) -> MaterialTextures {
        self.slots
    }
}

/// Generates, from one list of `Variant(module::Type)`, the enums [`Material`], [`MaterialDesc`]
/// and [`MaterialKind`] with their dispatch.
macro_rules! registry {
    ($($(#[$attr:meta])* $variant:ident($module:ident::$ty:ident)),+ $(,)?) => {
        /// A material: one of the registered kinds.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum Material {
            $($(#[$attr])* #[doc = concat!("See [`", stringify!($module), "::", stringify!($ty), "`].")]
            $variant($module::$ty),)+
        }

        /// A material as written in the scene: `Kind(field: value, ...)`, or a wrapper around
        /// materials named before it ([`wrap`]).
        #[derive(Clone, Debug)]
        pub enum MaterialDesc {
            $($(#[$attr])* #[doc = concat!("`", stringify!($variant), "(...)`.")]
            $variant(<$module::$ty as MaterialModel>::Desc),)+
            /// `Mask(...)`, `Blend(...)`: see [`wrap`].
            Wrap(wrap::WrapDesc),
        }

        /// The registered kinds, in registry order.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        #[repr(u8)]
        pub enum MaterialKind {
            $($(#[$attr])* #[doc = concat!("[`", stringify!($module), "::", stringify!($ty), "`].")]
            $variant,)+
        }

        /// Counts the kinds (a variant per kind, then the count).
        enum KindCount {
            $($(#[$attr])* $variant,)+
            Count,
        }

        impl MaterialKind {
            /// How many kinds there are.
            pub const COUNT: usize = KindCount::Count as usize;

            /// Every kind, in registry order.
            pub const ALL: [MaterialKind; Self::COUNT] = {
                let mut all = [MaterialKind::from_index(0); Self::COUNT];
                let mut i = 0;
                while i < Self::COUNT {
                    all[i] = MaterialKind::from_index(i);
                    i += 1;
                }
                all
            };

            const fn from_index(i: usize) -> Self {
                $($(#[$attr])* if i == KindCount::$variant as usize {
                    return MaterialKind::$variant;
                })+
                panic!("no such material kind")
            }

            /// Its shading stage's (and trace span's) name, `shade_` and its module's name.
            pub const fn stage_name(self) -> &'static str {
                match self {
                    $($(#[$attr])* MaterialKind::$variant => concat!("shade_", stringify!($module)),)+
                }
            }

            /// The name a scene writes, `Lambertian` in `Lambertian(...)`.
            pub const fn variant_name(self) -> &'static str {
                match self {
                    $($(#[$attr])* MaterialKind::$variant => stringify!($variant),)+
                }
            }

            /// How the integrators shade it.
            pub const fn shading(self) -> Shading {
                match self {
                    $($(#[$attr])* MaterialKind::$variant => <$module::$ty as MaterialModel>::SHADING,)+
                }
            }
        }

        impl Material {
            /// Its kind.
            #[inline]
            pub const fn kind(&self) -> MaterialKind {
                match self {
                    $($(#[$attr])* Material::$variant(_) => MaterialKind::$variant,)+
                }
            }

            /// Builds the material of a description; `texture` resolves a texture name to its id
            /// and mean. Returns the material and which of its colours are textured.
            ///
            /// # Panics
            /// On a wrapper ([`MaterialDesc::Wrap`]), which names other materials: the scene
            /// lowers it into its table of wrappers ([`wrap::WrapDesc::lower`]).
            pub fn build(
                desc: &MaterialDesc,
                texture: &mut dyn FnMut(&str) -> (TextureId, Vec3),
            ) -> (Material, MaterialTextures) {
                let mut colors = Colors::new(texture);
                let m = match desc {
                    $($(#[$attr])* MaterialDesc::$variant(d) => {
                        Material::$variant(<$module::$ty as MaterialModel>::build(d, &mut colors))
                    })+
                    MaterialDesc::Wrap(_) => panic!("a wrapper is lowered by its scene, not built alone"),
                };
                (m, colors.textures())
            }

            /// See [`MaterialModel::set_color`].
            #[inline]
            pub fn set_color(&mut self, slot: usize, value: Vec3) {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.set_color(slot, value),)+
                }
            }

            /// See [`MaterialModel::set_scalar`].
            #[inline]
            pub fn set_scalar(&mut self, slot: usize, value: f32) {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.set_scalar(slot, value),)+
                }
            }

            /// See [`MaterialModel::set_tangent`].
            #[inline]
            pub fn set_tangent(&mut self, n: Vec3A, dpdu: Vec3A) {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.set_tangent(n, dpdu),)+
                }
            }

            /// See [`MaterialModel::sample`].
            #[inline]
            pub fn sample(&self, wo: Vec3A, n: Vec3A, u: Vec2, uc: f32) -> Option<BsdfSample> {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.sample(wo, n, u, uc),)+
                }
            }

            /// See [`MaterialModel::eval`].
            #[inline]
            pub fn eval(&self, wo: Vec3A, wi: Vec3A, n: Vec3A) -> BsdfEval {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.eval(wo, wi, n),)+
                }
            }

            /// See [`MaterialModel::albedo`].
            #[inline]
            pub fn albedo(&self) -> Vec3 {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.albedo(),)+
                }
            }

            /// See [`MaterialModel::emission`].
            #[inline]
            pub fn emission(&self) -> Option<Emission> {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.emission(),)+
                }
            }

            /// See [`MaterialModel::set_emission`].
            pub fn set_emission(&mut self, emit: Vec3) {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.set_emission(emit),)+
                }
            }

            /// See [`MaterialModel::reads`].
            #[inline]
            pub fn reads(&self) -> Reads {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.reads(),)+
                }
            }

            /// See [`MaterialModel::specular`].
            #[inline]
            pub fn specular(&self) -> Specular {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.specular(),)+
                }
            }

            /// See [`MaterialModel::null_transmission`].
            #[inline]
            pub fn null_transmission(&self, cos: f32) -> f32 {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.null_transmission(cos),)+
                }
            }

            /// See [`MaterialModel::has_null_lobe`].
            #[inline]
            pub fn has_null_lobe(&self) -> bool {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.has_null_lobe(),)+
                }
            }

            /// See [`MaterialModel::one_sided`].
            #[inline]
            pub fn one_sided(&self) -> bool {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.one_sided(),)+
                }
            }

            /// See [`MaterialModel::sharpest_alpha`].
            #[inline]
            pub fn sharpest_alpha(&self) -> Option<f32> {
                match self {
                    $($(#[$attr])* Material::$variant(m) => m.sharpest_alpha(),)+
                }
            }
        }

        $($(#[$attr])*
        impl From<$module::$ty> for Material {
            fn from(m: $module::$ty) -> Self {
                Material::$variant(m)
            }
        })+

        impl MaterialDesc {
            /// Its kind; `None` for a wrapper.
            pub fn kind(&self) -> Option<MaterialKind> {
                match self {
                    $($(#[$attr])* MaterialDesc::$variant(_) => Some(MaterialKind::$variant),)+
                    MaterialDesc::Wrap(_) => None,
                }
            }
        }

        impl<'de> serde::Deserialize<'de> for MaterialDesc {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                struct Kinds;
                impl<'de> serde::de::Visitor<'de> for Kinds {
                    type Value = MaterialDesc;
                    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                        f.write_str("a material such as Lambertian(albedo: (0.5, 0.5, 0.5))")
                    }
                    fn visit_enum<A: serde::de::EnumAccess<'de>>(self, data: A) -> Result<MaterialDesc, A::Error> {
                        let (VariantName(name), variant) = data.variant()?;
                        $($(#[$attr])* if name == stringify!($variant) {
                            return fields::<<$module::$ty as MaterialModel>::Desc, _>(variant)
                                .map(MaterialDesc::$variant);
                        })+
                        if let Some(w) = wrap::WrapDesc::from_variant(&name, variant) {
                            return w.map(MaterialDesc::Wrap);
                        }
                        Err(serde::de::Error::unknown_variant(&name, &VARIANT_NAMES))
                    }
                }
                d.deserialize_enum("Material", &VARIANT_NAMES, Kinds)
            }
        }
    };
}
use registry;

/// The names a scene may write (the kinds, then the wrappers), for parser messages.
static VARIANT_NAMES: [&str; MaterialKind::COUNT + wrap::NAMES.len()] = {
    let mut names = [""; MaterialKind::COUNT + wrap::NAMES.len()];
    let mut i = 0;
    while i < MaterialKind::COUNT {
        names[i] = MaterialKind::ALL[i].variant_name();
        i += 1;
    }
    while i < names.len() {
        names[i] = wrap::NAMES[i - MaterialKind::COUNT];
        i += 1;
    }
    names
};

impl Material {
    /// True for emitters (whose BSDF is black: a path that meets one ends there).
    #[inline]
    pub fn is_emissive(&self) -> bool {
        self.kind().shading() == Shading::Emitter
    }

    /// How the integrators shade it.
    #[inline]
    pub fn shading(&self) -> Shading {
        self.kind().shading()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_are_listed_once_in_registry_order() {
        for (i, k) in MaterialKind::ALL.iter().enumerate() {
            assert_eq!(*k as usize, i);
        }
        assert_eq!(MaterialKind::ALL[0].stage_name(), "shade_lambertian");
        assert_eq!(MaterialKind::DiffuseLight.stage_name(), "shade_diffuse_light");
        assert_eq!(MaterialKind::DiffuseLight.shading(), Shading::Emitter);
    }

    /// A material that says it does not read a number samples the same whatever that number
    /// is (the wavefront leaves such numbers at zero), and one that reads it depends on it.
    #[test]
    fn materials_read_the_numbers_they_say() {
        let mats = [
            Material::from(metal::Metal { albedo: Vec3::splat(0.8), fuzz: 0.0 }),
            Material::from(metal::Metal { albedo: Vec3::splat(0.8), fuzz: 0.3 }),
            Material::from(dielectric::Dielectric { ior: 1.5, fresnel: Fresnel::Exact }),
            Material::from(thin_dielectric::ThinDielectric { ior: 1.5 }),
            Material::from(lambertian::Lambertian { albedo: Vec3::splat(0.5), two_sided: true }),
            Material::from(plastic::Plastic::new(Vec3::splat(0.5), Vec3::ONE, 1.5, false, false)),
            Material::from(rough_plastic::RoughPlastic::new(
                Vec3::splat(0.5),
                Vec3::ONE,
                1.5,
                (0.2, microfacet::Distribution::Ggx),
                false,
                false,
            )),
        ];
        let n = Vec3A::Z;
        for m in mats {
            let reads = m.reads();
            let (mut dir_matters, mut lobe_matters) = (false, false);
            for k in 0..64 {
                let t = k as f32 / 64.0;
                let wo = Vec3A::new(0.6 * t - 0.3, 0.2, 1.0).normalize();
                let u = Vec2::new(t, (7.0 * t).fract());
                let uc = (13.0 * t).fract();
                let wi = |u: Vec2, uc: f32| m.sample(wo, n, u, uc).map(|s| (s.wi, s.pdf));
                let base = wi(u, uc);
                let (other_dir, other_lobe) = (wi(Vec2::new(0.93, 0.11), uc), wi(u, 0.97));
                dir_matters |= other_dir != base;
                lobe_matters |= other_lobe != base;
                if !reads.dir {
                    assert_eq!(other_dir, base, "{m:?} reads the direction's numbers");
                }
                if !reads.lobe {
                    assert_eq!(other_lobe, base, "{m:?} reads the lobe's number");
                }
            }
            assert_eq!((dir_matters, lobe_matters), (reads.dir, reads.lobe), "{m:?} says {reads:?}");
        }
    }

    /// The material is copied per hit and per path: a new kind or parameter must not make it
    /// larger without a measurement (benches/RESULTS.md).
    #[test]
    fn materials_stay_56_bytes() {
        assert_eq!(std::mem::size_of::<Material>(), 56);
    }
}
