//! Wrappers: materials made of other materials, as Mitsuba 3's `mask` (`src/bsdfs/mask.cpp`:
//! an opacity, alpha cut-outs such as leaves) and `blendbsdf` (`src/bsdfs/blendbsdf.cpp`: two
//! BSDFs mixed by a weight). [`Material`](super::Material) is a `Copy` enum of kinds that cannot
//! hold another material, so a scene names the wrapped materials instead (`Mask(opacity: 0.5,
//! material: "leaf")`, each named before the wrapper), and loading lowers each wrapper into a
//! per-material-id table ([`Wrappers`]). At a hit, before the hit is binned by kind, the
//! integrators follow the hit's id through that table ([`Wrappers::resolve`]) with one number
//! per wrapper, down to a plain material (or through a mask's hole), and shade that material as
//! if the surface were made of it.
//!
//! - A mask is opaque with probability `opacity` (the inner material shades the hit) and
//!   otherwise a null event: the ray goes on unbent, as a thin dielectric's null lobe
//!   ([`BsdfSample::null`](super::BsdfSample::null)), not a bounce of `max_depth`. Both choices
//!   weigh 1 (the probability is the term's weight), so the estimate is the mask's BSDF
//!   `opacity f + (1 - opacity) null` in expectation. Shadow rays are let through with
//!   `1 - opacity` ([`Wrappers::transmission`]), where Mitsuba's `path` integrator stops them and
//!   lets only BSDF samples through: both agree in expectation, and light sampling then sees
//!   the light behind a leaf's hole.
//! - A blend of two Lambertians that reflect on the same sides is a Lambertian (a convex
//!   combination of cosine lobes is one), with the blended albedo: it is evaluated, not
//!   picked ([`Wrapper::LambertianMix`], folded into a plain Lambertian at load when nothing
//!   in it is textured), so it adds no noise. Mitsuba's test of a face-weighted blend of two
//!   diffuse BSDFs under a directional light (direct lighting only) fails with picking: its
//!   noise at the test's sample count is 30 times the reference's.
//! - Any other blend picks its second material with probability `weight`, its first
//!   otherwise: a one-sample estimator of `(1 - weight) f_a + weight f_b`, unbiased, with each
//!   material shaded by its own kernel (the Lambertian lanes, light sampling and MIS of glossy
//!   kinds). Evaluating both in general would need a kind that holds two materials, and every
//!   stage a path for it; picking costs noise only where the two differ much.
//!
//! Opacities and weights are numbers in [0, 1] or the scene's textures (a texture's luminance,
//! as Mitsuba's float textures read an RGB image, clamped to [0, 1] as Mitsuba clamps them).
//!
//! Bump and normal maps (Mitsuba's `bumpmap` and `normalmap`, `src/bsdfs/bumpmap.cpp` and
//! `normalmap.cpp`) tilt the shading normal of the material they wrap, and draw no number: at
//! the hit, [`Wrappers::resolve`] hands them to the scene, which writes the tilted normal into
//! the hit's [`SurfacePoint::ns`] and keeps the one before in [`SurfacePoint::ns_base`].
//! - A bump map displaces the surface along its normal by `scale` times an image's value:
//!   the tilted normal is that of `dp/du + (d h / d u) n` and `dp/dv + (d h / d v) n` (Blinn
//!   1978, "Simulation of Wrinkled Surfaces"; [`bump_normal`]), the height's derivatives those
//!   of the image's bilinear lookup.
//! - A normal map gives the normal in the frame of `dp/du` (projected onto the tangent plane),
//!   its cross product and the normal, encoded as `(n + 1) / 2` ([`normal_map_normal`]).
//!
//! Both then turn the tilted normal to where the ray comes from when it faces away
//! ([`flip_invalid`], Mitsuba's `flip_invalid_normals`, on by default). Shading uses the
//! tilted normal for the BSDF and the base normal for the rest, as Mitsuba does: a direction
//! must lie on the same side of both, and the ray leaves by the base normal's rules; the
//! BSDF's value takes the microfacet shadowing of Estevez et al. 2019, "A Microfacet-Based
//! Shadowing Function to Solve the Bump Terminator Problem" (Ray Tracing Gems, chapter 12;
//! [`terminator_shadowing`]), which darkens the terminator smoothly instead of cutting it.
//! A map may wrap masks and blends but no other map (the shadowing term is of one tilt).
//!
//! The wrappers as the scene writes them are in `desc`, the normals of bump and normal maps in
//! `tilt`.

mod desc;
mod tilt;

pub use desc::{
    AmountDesc, BlendDesc, BumpDesc, HeightMap, MaskDesc, NAMES, NormalMapDesc, TextureName, Tilted,
    WrapDesc, Wrapped,
};
pub use tilt::{base_tangent, bump_normal, flip_invalid, normal_map_normal, terminator_shadowing};

use super::Material;
use crate::texture::TextureId;

/// How a bump or normal map tilts the normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tilt {
    /// Heights: `scale` times texture `heights`' value.
    Bump {
        /// An image texture.
        heights: TextureId,
        /// World units per unit of value.
        scale: f32,
    },
    /// Normals in the tangent frame, encoded as `(n + 1) / 2`.
    Normals {
        /// The texture.
        normals: TextureId,
    },
}

/// An opacity or a weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Amount {
    /// A number in [0, 1].
    Value(f32),
    /// A texture's luminance at the hit, clamped to [0, 1].
    Texture(TextureId),
}

/// A wrapper with the ids of the materials it names.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Wrapper {
    /// Material `material` with probability `opacity`, else a hole.
    Mask {
        /// How opaque the surface is.
        opacity: Amount,
        /// The material where it is.
        material: u32,
    },
    /// `materials[1]` with probability `weight`, else `materials[0]`.
    Blend {
        /// The second material's share.
        weight: Amount,
        /// The two materials.
        materials: [u32; 2],
    },
    /// Material `material` with its shading normal tilted by `map` (turned towards the ray
    /// where it faces away, if `flip`).
    Tilt {
        /// The map.
        map: Tilt,
        /// Mitsuba's `flip_invalid_normals`.
        flip: bool,
        /// The material.
        material: u32,
    },
    /// A blend of two Lambertians that reflect on the same sides, some of it textured: the
    /// Lambertian of the blended albedo ([`mix_lambertian`]), which the wrapper's own id
    /// holds (the means blended) and shades.
    LambertianMix {
        /// The second material's share.
        weight: Amount,
        /// The two Lambertians.
        materials: [u32; 2],
    },
}

/// `(1 - w) a + w b` of two Lambertians that reflect on the same sides, a Lambertian; `None`
/// for other materials.
pub fn mix_lambertian(a: &Material, b: &Material, w: f32) -> Option<Material> {
    match (a, b) {
        (Material::Lambertian(a), Material::Lambertian(b)) if a.two_sided == b.two_sided => {
            let albedo = a.albedo * (1.0 - w) + b.albedo * w;
            Some(Material::Lambertian(super::lambertian::Lambertian { albedo, two_sided: a.two_sided }))
        }
        _ => None,
    }
}

impl Wrapper {
    /// The material its id's entry of the material list holds, so that what reads that list
    /// without resolving sees a material of the wrapper, and the wrapper as it is kept: a
    /// blend of two plain Lambertians becomes their mix, a plain one (`None`) when neither its
    /// weight nor either albedo is textured (`textured(id)` says whether material `id`'s
    /// colours are). `materials` and `wrappers` are those of the ids before it (a blend of
    /// wrappers stays a blend: their entries are not what they shade).
    pub fn settle(
        self,
        materials: &[Material],
        wrappers: &[Option<Wrapper>],
        textured: impl Fn(u32) -> bool,
    ) -> (Material, Option<Self>) {
        let (weight, [a, b]) = match self {
            Wrapper::Mask { material, .. } | Wrapper::Tilt { material, .. } => {
                return (materials[material as usize], Some(self));
            }
            Wrapper::Blend { weight, materials } | Wrapper::LambertianMix { weight, materials } => {
                (weight, materials)
            }
        };
        let mean = match weight {
            Amount::Value(v) => v,
            Amount::Texture(_) => 0.5,
        };
        let plain = |id: u32| wrappers[id as usize].is_none();
        match mix_lambertian(&materials[a as usize], &materials[b as usize], mean) {
            Some(_) if !(plain(a) && plain(b)) => (materials[a as usize], Some(self)),
            None => (materials[a as usize], Some(self)),
            Some(m) if matches!(weight, Amount::Value(_)) && !textured(a) && !textured(b) => (m, None),
            Some(m) => (m, Some(Wrapper::LambertianMix { weight, materials: [a, b] })),
        }
    }

    /// The materials it names.
    pub fn wrapped(&self) -> impl Iterator<Item = u32> {
        let (a, b) = match *self {
            Wrapper::Mask { material, .. } | Wrapper::Tilt { material, .. } => (material, None),
            Wrapper::Blend { materials, .. } | Wrapper::LambertianMix { materials, .. } => {
                (materials[0], Some(materials[1]))
            }
        };
        std::iter::once(a).chain(b)
    }

    /// Its amount (`None` for a map, which has none).
    pub fn amount(&self) -> Option<Amount> {
        match *self {
            Wrapper::Mask { opacity, .. } => Some(opacity),
            Wrapper::Blend { weight, .. } | Wrapper::LambertianMix { weight, .. } => Some(weight),
            Wrapper::Tilt { .. } => None,
        }
    }

    /// Whether it reads a texture at the hit.
    pub fn textured(&self) -> bool {
        match *self {
            Wrapper::Tilt { .. } => true,
            w => matches!(w.amount(), Some(Amount::Texture(_))),
        }
    }
}

/// Where a hit's material id leads through the wrappers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Resolved {
    /// The plain material with this id shades the hit.
    Material(u32),
    /// The ray goes through a mask's hole.
    Pass,
}

/// The wrapper of each material id (`None` for plain materials), indexed like the materials.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Wrappers(pub Vec<Option<Wrapper>>);

impl Wrappers {
    /// The wrapper of material `id`, if it is one.
    #[inline]
    pub fn get(&self, id: u32) -> Option<Wrapper> {
        self.0.get(id as usize).copied().flatten()
    }

    /// Follows material `id` through its wrappers at a hit: `amount` evaluates an opacity or a
    /// weight there (in [0, 1]), and `u(level)` is the number in [0, 1) of the `level`-th
    /// wrapper that draws one (0 for the first). A mask is opaque where its number is below the
    /// opacity; a blend takes its second material where its number is below the weight. A
    /// map draws none: `tilt` gets it (the hit's normal is tilted) on the way through. A
    /// Lambertian mix is its own material (shaded as the blended Lambertian).
    #[inline]
    pub fn resolve(
        &self,
        mut id: u32,
        amount: impl Fn(Amount) -> f32,
        mut u: impl FnMut(u32) -> f32,
        mut tilt: impl FnMut(Tilt, bool),
    ) -> Resolved {
        let mut level = 0;
        while let Some(w) = self.get(id) {
            let a = match w {
                Wrapper::LambertianMix { .. } => break,
                Wrapper::Tilt { map, flip, material } => {
                    tilt(map, flip);
                    id = material;
                    continue;
                }
                Wrapper::Mask { opacity: a, .. } | Wrapper::Blend { weight: a, .. } => amount(a),
            };
            let below = u(level) < a;
            id = match w {
                Wrapper::Mask { .. } if !below => return Resolved::Pass,
                Wrapper::Mask { material, .. } => material,
                Wrapper::Blend { materials, .. } => materials[below as usize],
                Wrapper::LambertianMix { .. } | Wrapper::Tilt { .. } => unreachable!("left above"),
            };
            level += 1;
        }
        Resolved::Material(id)
    }

    /// The fraction of light that a shadow ray gets straight through material `id`: a mask's
    /// `1 - opacity` plus `opacity` times its material's, a blend's weighted sum of its two
    /// materials', and `plain(id)` for a plain material (its null lobe's transmission).
    pub fn transmission(&self, id: u32, amount: &impl Fn(Amount) -> f32, plain: &impl Fn(u32) -> f32) -> f32 {
        match self.get(id) {
            // Lambertians let nothing through.
            None | Some(Wrapper::LambertianMix { .. }) => plain(id),
            Some(Wrapper::Mask { opacity, material }) => {
                let a = amount(opacity);
                (1.0 - a) + a * self.transmission(material, amount, plain)
            }
            Some(Wrapper::Blend { weight, materials: [m0, m1] }) => {
                let a = amount(weight);
                (1.0 - a) * self.transmission(m0, amount, plain) + a * self.transmission(m1, amount, plain)
            }
            // A null lobe goes straight on, whatever the normal.
            Some(Wrapper::Tilt { material, .. }) => self.transmission(material, amount, plain),
        }
    }

    /// Material ids `used` (indexed like the materials) with every material a used wrapper
    /// names marked used too.
    pub fn mark_wrapped(&self, used: &mut [bool]) {
        // A wrapper names only materials before it: one pass from the end reaches them all.
        for id in (0..used.len()).rev() {
            if let (true, Some(w)) = (used[id], self.get(id as u32)) {
                for m in w.wrapped() {
                    used[m as usize] = true;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Materials 0 and 1 are plain; 2 masks 0 with opacity 0.3; 3 blends 1 and 2 with weight
    /// 0.25 (textured: the texture reads 0.25); 4 masks 3 with opacity 0.5.
    fn table() -> Wrappers {
        Wrappers(vec![
            None,
            None,
            Some(Wrapper::Mask { opacity: Amount::Value(0.3), material: 0 }),
            Some(Wrapper::Blend { weight: Amount::Texture(7), materials: [1, 2] }),
            Some(Wrapper::Mask { opacity: Amount::Value(0.5), material: 3 }),
        ])
    }

    fn untilted(_: Tilt, _: bool) {
        panic!("no map");
    }

    fn amount(a: Amount) -> f32 {
        match a {
            Amount::Value(v) => v,
            Amount::Texture(7) => 0.25,
            Amount::Texture(t) => panic!("no texture {t}"),
        }
    }

    /// Each wrapper draws its own number; a mask is opaque below its opacity, a blend takes
    /// its second material below its weight; plain ids resolve to themselves without a number.
    #[test]
    fn resolve_follows_the_numbers() {
        let w = table();
        let never = |_| -> f32 { panic!("a plain material draws no number") };
        assert_eq!(w.resolve(1, amount, never, untilted), Resolved::Material(1));
        assert_eq!(w.resolve(2, amount, |_| 0.29, untilted), Resolved::Material(0));
        assert_eq!(w.resolve(2, amount, |_| 0.3, untilted), Resolved::Pass);
        // Through the outer mask (0.4 < 0.5), the blend's first material (0.6 >= 0.25).
        let numbers = [0.4, 0.6];
        assert_eq!(w.resolve(4, amount, |l| numbers[l as usize], untilted), Resolved::Material(1));
        // The blend's second material (0.1 < 0.25) is the inner mask: a hole (0.9 >= 0.3).
        let numbers = [0.4, 0.1, 0.9];
        assert_eq!(w.resolve(4, amount, |l| numbers[l as usize], untilted), Resolved::Pass);
        let numbers = [0.4, 0.1, 0.2];
        assert_eq!(w.resolve(4, amount, |l| numbers[l as usize], untilted), Resolved::Material(0));
    }

    /// Over evenly spread numbers, each outcome comes with its probability: the product of the
    /// opacities and weights along the way (a deliberate error, the blend's choice reversed
    /// or a mask's opacity ignored, moves these shares off).
    #[test]
    fn resolve_chooses_with_the_wrappers_probabilities() {
        let w = table();
        let n = 100;
        let mut counts = std::collections::HashMap::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    let u = [
                        (i as f32 + 0.5) / n as f32,
                        (j as f32 + 0.5) / n as f32,
                        (k as f32 + 0.5) / n as f32,
                    ];
                    *counts.entry(w.resolve(4, amount, |l| u[l as usize], untilted)).or_insert(0usize) += 1;
                }
            }
        }
        let share = |r| counts.get(&r).copied().unwrap_or(0) as f64 / (n * n * n) as f64;
        assert!((share(Resolved::Material(1)) - 0.5 * 0.75).abs() < 1e-9);
        assert!((share(Resolved::Material(0)) - 0.5 * 0.25 * 0.3).abs() < 1e-9);
        assert!((share(Resolved::Pass) - (0.5 + 0.5 * 0.25 * 0.7)).abs() < 1e-9);
    }

    /// A shadow ray gets through with the probability that a path passes (the same mixture
    /// as [`Wrappers::resolve`]), plain materials adding their own transmission.
    #[test]
    fn transmission_is_the_expected_pass_through() {
        let w = table();
        let plain = |id: u32| if id == 1 { 0.5 } else { 0.0 };
        assert_eq!(w.transmission(0, &amount, &plain), 0.0);
        assert!((w.transmission(2, &amount, &plain) - 0.7).abs() < 1e-6);
        let blend = 0.75 * 0.5 + 0.25 * 0.7;
        assert!((w.transmission(3, &amount, &plain) - blend).abs() < 1e-6);
        assert!((w.transmission(4, &amount, &plain) - (0.5 + 0.5 * blend)).abs() < 1e-6);
    }

    /// A blend of two Lambertians that reflect on the same sides is their mix: folded into a
    /// plain Lambertian when nothing in it is textured, kept as a mix otherwise; any other
    /// blend is picked per hit, and a mask holds its material.
    #[test]
    fn settle_mixes_lambertians_and_keeps_the_rest() {
        use crate::material::lambertian::Lambertian;
        let lambert = |a: f32, two_sided| Material::from(Lambertian { albedo: Vec3::splat(a), two_sided });
        let mats = [lambert(0.2, true), lambert(0.6, true), lambert(0.6, false), lambert(0.6, true)];
        let mask = Wrapper::Mask { opacity: Amount::Value(0.5), material: 1 };
        let wrappers = [None, None, None, Some(mask)];
        let blend = |weight, b| Wrapper::Blend { weight, materials: [0, b] };
        let untextured = |_| false;
        let (m, w) = blend(Amount::Value(0.25), 1).settle(&mats, &wrappers, untextured);
        assert_eq!((m, w), (lambert(0.2 * 0.75 + 0.6 * 0.25, true), None));
        let (m, w) = blend(Amount::Value(0.25), 1).settle(&mats, &wrappers, |id| id == 1);
        assert_eq!(m, lambert(0.2 * 0.75 + 0.6 * 0.25, true));
        assert_eq!(w, Some(Wrapper::LambertianMix { weight: Amount::Value(0.25), materials: [0, 1] }));
        let (m, w) = blend(Amount::Texture(7), 1).settle(&mats, &wrappers, untextured);
        assert_eq!(
            (m, w),
            (
                lambert(0.4, true),
                Some(Wrapper::LambertianMix { weight: Amount::Texture(7), materials: [0, 1] })
            )
        );
        // One-sided and two-sided differ: picked.
        let (m, w) = blend(Amount::Value(0.25), 2).settle(&mats, &wrappers, untextured);
        assert_eq!((m, w), (mats[0], Some(blend(Amount::Value(0.25), 2))));
        assert_eq!(mask.settle(&mats, &wrappers, untextured), (mats[1], Some(mask)));
        // A blend of a Lambertian and a mask around one is picked: the mask's entry is not
        // what it shades.
        let (m, w) = blend(Amount::Value(0.25), 3).settle(&mats, &wrappers, untextured);
        assert_eq!((m, w), (mats[0], Some(blend(Amount::Value(0.25), 3))));
        // A mix resolves to itself, without a number.
        let table = Wrappers(vec![
            None,
            None,
            w,
            Some(Wrapper::LambertianMix { weight: Amount::Value(0.5), materials: [0, 1] }),
        ]);
        assert_eq!(table.resolve(3, amount, |_| panic!("no number"), untilted), Resolved::Material(3));
    }

    #[test]
    fn used_wrappers_mark_what_they_name() {
        let w = table();
        let mut used = vec![false, false, false, false, true];
        w.mark_wrapped(&mut used);
        assert_eq!(used, vec![true; 5]);
        let mut used = vec![false, false, true, false, false];
        w.mark_wrapped(&mut used);
        assert_eq!(used, vec![true, false, true, false, false]);
    }

    /// A map in the table draws no number and reports its tilt on the way to its material,
    /// and a mask inside it still draws the first number.
    #[test]
    fn maps_tilt_on_the_way_without_a_number() {
        let bump = Tilt::Bump { heights: 3, scale: 0.5 };
        let table = Wrappers(vec![
            None,
            Some(Wrapper::Mask { opacity: Amount::Value(0.3), material: 0 }),
            Some(Wrapper::Tilt { map: bump, flip: true, material: 1 }),
        ]);
        let mut seen = Vec::new();
        let r = table.resolve(2, amount, |l| [0.1][l as usize], |m, f| seen.push((m, f)));
        assert_eq!((r, seen), (Resolved::Material(0), vec![(bump, true)]));
    }
}
