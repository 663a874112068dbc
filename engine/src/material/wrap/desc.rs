//! The wrappers as a scene writes them (`Mask`, `Blend`, `Bump`, `NormalMap`), each checked
//! against the materials and textures named before it, and lowered into a [`Wrapper`].

use super::{Amount, Tilt, Wrapper};
use crate::format::context;
use crate::format::{Finite, MaterialRef};
use crate::texture::TextureId;
use serde::{Deserialize, Deserializer, de::Error};

/// The wrappers a scene may write, for parser messages.
pub const NAMES: [&str; 4] = ["Mask", "Blend", "Bump", "NormalMap"];

/// A number in [0, 1] written out, or the name of a texture of the scene (its luminance at
/// the hit, clamped to [0, 1]).
#[derive(Debug, Clone, PartialEq)]
pub enum AmountDesc {
    /// `0.5`.
    Value(f32),
    /// `"name"`.
    Texture(String),
}

impl<'de> Deserialize<'de> for AmountDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = AmountDesc;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number in [0, 1] or the name of a texture")
            }
            fn visit_f64<E: Error>(self, v: f64) -> Result<AmountDesc, E> {
                match (0.0..=1.0).contains(&v) {
                    true => Ok(AmountDesc::Value(v as f32)),
                    false => Err(E::custom(format!("expected a number in [0, 1] or a texture, found {v}"))),
                }
            }
            fn visit_i64<E: Error>(self, v: i64) -> Result<AmountDesc, E> {
                self.visit_f64(v as f64)
            }
            fn visit_u64<E: Error>(self, v: u64) -> Result<AmountDesc, E> {
                self.visit_f64(v as f64)
            }
            fn visit_str<E: Error>(self, name: &str) -> Result<AmountDesc, E> {
                crate::format::check_texture_name(name).map_err(E::custom)?;
                Ok(AmountDesc::Texture(name.to_owned()))
            }
        }
        d.deserialize_any(V)
    }
}

/// A material that a wrapper names: one defined before the wrapper (so wrappers nest without
/// cycles) that does not emit.
#[derive(Debug, Clone, PartialEq)]
pub struct Wrapped(pub String);

impl<'de> Deserialize<'de> for Wrapped {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let MaterialRef(name) = MaterialRef::deserialize(d)?;
        let before = context::materials_before();
        context::names(|n| {
            let Some(n) = n else { return Ok(()) };
            let at = n.materials.iter().position(|m| *m == name);
            if let (Some(at), Some(before)) = (at, before)
                && at >= before
            {
                return Err(D::Error::custom(format!(
                    "material \"{name}\" must be defined before the wrapper that names it"
                )));
            }
            if n.lights.contains(&name) {
                return Err(D::Error::custom(format!(
                    "material \"{name}\" is a DiffuseLight: wrappers go around materials that reflect"
                )));
            }
            Ok(())
        })?;
        Ok(Wrapped(name))
    }
}

/// The material that a bump or normal map tilts: a [`Wrapped`] material that is not a map and
/// wraps none (the shadowing term is of one tilt).
#[derive(Debug, Clone, PartialEq)]
pub struct Tilted(pub Wrapped);

impl<'de> Deserialize<'de> for Tilted {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Wrapped(name) = Wrapped::deserialize(d)?;
        context::names(|n| match n.is_some_and(|n| n.tilting.contains(&name)) {
            true => Err(D::Error::custom(format!(
                "material \"{name}\" is or holds a bump or normal map: maps do not nest"
            ))),
            false => Ok(()),
        })?;
        Ok(Tilted(Wrapped(name)))
    }
}

/// A texture that a bump map reads heights from: an `Image`, whose bilinear lookup has
/// derivatives along u and v.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightMap(pub String);

impl<'de> Deserialize<'de> for HeightMap {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let TextureName(name) = TextureName::deserialize(d)?;
        context::names(|n| match n.is_none_or(|n| n.images.contains(&name)) {
            true => Ok(()),
            false => Err(D::Error::custom(format!(
                "texture \"{name}\" is not an Image: a bump map reads the heights of an image"
            ))),
        })?;
        Ok(HeightMap(name))
    }
}

/// A texture's name.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureName(pub String);

impl<'de> Deserialize<'de> for TextureName {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        crate::format::check_texture_name(&name).map_err(D::Error::custom)?;
        Ok(TextureName(name))
    }
}

fn yes() -> bool {
    true
}

fn unit_scale() -> Finite {
    Finite(1.0)
}

/// A bump map (Mitsuba 3's `bumpmap`) around the material named `material` (defined before it, not
/// an emitter, and not a map or a wrapper holding one: maps do not nest): the surface displaced
/// along its normal by `scale` (default 1, finite) times the value of the `Image` texture `texture`
/// (its luminance; `raw: true` for heights stored linearly). The shading normal is that of the
/// displaced surface, from the image's bilinear slopes along the surface's `u` and `v` (Blinn
/// 1978): spheres, quads and meshes give the derivatives; other shapes keep their normal.
/// Directions must lie on the same side of the tilted and the untilted normal, and the BSDF is
/// darkened towards the terminator by the microfacet shadowing of Estevez et al. 2019 (as Mitsuba);
/// a normal facing away from the ray is mirrored towards it (`flip_invalid_normals`, default true).
/// Lambertians under a map are shaded path by path with the glossy kinds' MIS, not the lane kernel.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct BumpDesc {
    /// The image of heights (its value; a colour image's luminance).
    pub texture: HeightMap,
    /// Height in world units per unit of the image's value (default 1): the derivatives
    /// are taken along the surface's uv, so a mesh's uv scale matters too. Finite.
    #[serde(default = "unit_scale")]
    pub scale: Finite,
    /// The material that the bumped surface is made of.
    pub material: Tilted,
    /// Turn a normal that faces away from the ray towards it (default true).
    #[serde(default = "yes")]
    pub flip_invalid_normals: bool,
}

/// A normal map (Mitsuba 3's `normalmap`) around `material` (as for `Bump`): the texture's value
/// `c` gives the normal `2 c - 1` in the frame of `dp/du` projected on the tangent plane, the
/// normal's cross product with it, and the normal (read the image with `raw: true`, as normal maps
/// are stored; OpenGL's convention, green along `n x dp/du`). Same rules as `Bump` for directions,
/// shadowing and `flip_invalid_normals`. Scenes: `scenes/maps.ron` (images written by
/// `scenes/maps.py`).
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct NormalMapDesc {
    /// The normals, `(n + 1) / 2` in the frame of `dp/du`, its cross product and the normal
    /// (an image read `raw: true`, as normal maps are stored).
    pub texture: TextureName,
    /// The material whose normal it tilts.
    pub material: Tilted,
    /// Turn a normal that faces away from the ray towards it (default true).
    #[serde(default = "yes")]
    pub flip_invalid_normals: bool,
}

/// An alpha cut-out (Mitsuba 3's `mask`) around the material named `material`, which must be
/// defined before it and not be a `DiffuseLight`: `opacity` is a number in [0, 1] or a texture's
/// name (its luminance at the hit, clamped to [0, 1]). A ray meets the material with probability
/// `opacity` and otherwise goes on unbent, a null crossing as `ThinDielectric`'s (no bounce of
/// `max_depth`, the MIS state kept); shadow rays cross it attenuated by `1 - opacity` (where
/// Mitsuba's `path` stops them: the same in expectation, and light sampling sees through a leaf's
/// holes). Wrappers nest (a mask around a blend, ...); an object with `emit` cannot use one.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct MaskDesc {
    /// The probability that a ray meets the material (0: a hole, 1: solid), or a texture.
    pub opacity: AmountDesc,
    /// The material where the surface is opaque.
    pub material: Wrapped,
}

/// `(1 - weight) first + weight second` of `materials: ("first", "second")`, both defined before it
/// and not emitters (Mitsuba 3's `blendbsdf`); `weight` a number in [0, 1] or a texture's name (its
/// luminance, clamped). Two Lambertians that reflect on the same sides blend into the Lambertian of
/// the blended albedo (exact: no noise added); any other pair is sampled by picking the second with
/// probability `weight` at each hit (unbiased; each shaded by its own kernel, with light sampling
/// and MIS).
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct BlendDesc {
    /// The share of the second material (0: only the first, 1: only the second), or a texture.
    pub weight: AmountDesc,
    /// The first and the second material.
    pub materials: (Wrapped, Wrapped),
}

/// A wrapper as a scene writes it.
#[derive(Debug, Clone)]
pub enum WrapDesc {
    /// `Mask(...)`.
    Mask(MaskDesc),
    /// `Blend(...)`.
    Blend(BlendDesc),
    /// `Bump(...)`.
    Bump(BumpDesc),
    /// `NormalMap(...)`.
    NormalMap(NormalMapDesc),
}

impl WrapDesc {
    /// Reads the wrapper `name` (one of [`NAMES`]) from its fields; `None` for another name.
    pub(crate) fn from_variant<'de, A: serde::de::VariantAccess<'de>>(
        name: &str,
        variant: A,
    ) -> Option<Result<Self, A::Error>> {
        use crate::format::registry::fields;
        match name {
            "Mask" => Some(fields::<MaskDesc, _>(variant).map(WrapDesc::Mask)),
            "Blend" => Some(fields::<BlendDesc, _>(variant).map(WrapDesc::Blend)),
            "Bump" => Some(fields::<BumpDesc, _>(variant).map(WrapDesc::Bump)),
            "NormalMap" => Some(fields::<NormalMapDesc, _>(variant).map(WrapDesc::NormalMap)),
            _ => None,
        }
    }

    /// The materials it names, in order.
    pub fn wrapped(&self) -> Vec<&str> {
        match self {
            WrapDesc::Mask(m) => vec![&m.material.0],
            WrapDesc::Blend(b) => vec![&b.materials.0.0, &b.materials.1.0],
            WrapDesc::Bump(b) => vec![&b.material.0.0],
            WrapDesc::NormalMap(m) => vec![&m.material.0.0],
        }
    }

    /// Whether it tilts the normal (a bump or normal map).
    pub fn tilts(&self) -> bool {
        matches!(self, WrapDesc::Bump(_) | WrapDesc::NormalMap(_))
    }

    /// The textures it reads.
    pub fn textures(&self) -> Vec<&str> {
        let amount = match self {
            WrapDesc::Mask(m) => &m.opacity,
            WrapDesc::Blend(b) => &b.weight,
            WrapDesc::Bump(b) => return vec![&b.texture.0],
            WrapDesc::NormalMap(m) => return vec![&m.texture.0],
        };
        match amount {
            AmountDesc::Texture(t) => vec![t],
            AmountDesc::Value(_) => Vec::new(),
        }
    }

    /// The wrapper with material names turned into ids by `material` and texture names by
    /// `texture`.
    pub fn lower(&self, material: impl Fn(&str) -> u32, texture: impl Fn(&str) -> TextureId) -> Wrapper {
        let amount = |a: &AmountDesc| match a {
            AmountDesc::Value(v) => Amount::Value(*v),
            AmountDesc::Texture(t) => Amount::Texture(texture(t)),
        };
        match self {
            WrapDesc::Mask(m) => {
                Wrapper::Mask { opacity: amount(&m.opacity), material: material(&m.material.0) }
            }
            WrapDesc::Blend(b) => Wrapper::Blend {
                weight: amount(&b.weight),
                materials: [material(&b.materials.0.0), material(&b.materials.1.0)],
            },
            WrapDesc::Bump(b) => Wrapper::Tilt {
                map: Tilt::Bump { heights: texture(&b.texture.0), scale: b.scale.0 },
                flip: b.flip_invalid_normals,
                material: material(&b.material.0.0),
            },
            WrapDesc::NormalMap(m) => Wrapper::Tilt {
                map: Tilt::Normals { normals: texture(&m.texture.0) },
                flip: m.flip_invalid_normals,
                material: material(&m.material.0.0),
            },
        }
    }
}
