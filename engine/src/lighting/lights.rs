//! The emitter table used for next-event estimation: which lights can be sampled and with what
//! probability. Emitting primitives, point and spot lights and projectors share one share of
//! the choices, half in proportion to their power and half evenly among emitting objects and
//! those lights, an object's primitives splitting its part by power (a defensive mixture: power
//! alone starves a large dim light near the camera, an even choice wastes samples on irrelevant
//! ones; measured in benches/results/sampling.md); each light at infinity (the environment, a
//! directional light) takes a share of its own, as pbrt-v4's `BVHLightSampler` does: a power
//! estimate for them depends on a scene radius and would starve the finite lights of a large
//! scene.

use crate::accel::geometry::Geometry;
use crate::lighting::area::AreaEmission;
use crate::lighting::tree::LightSamplerKind;
use crate::lighting::tree::{FEW_LIGHTS, LightBounds, LightTree, choose_lanes, importance_sums};
use crate::math::luminance;
use crate::shape::{EllipsoidLight, LightSample, Primitive, QuadLight, SphereLight};

use glam::{Vec2, Vec3A};

pub use crate::lighting::punctual_light::{LightTexture, PunctualLight, SpotFalloff, SpotTexture};

/// Marks a primitive that is not in the light table.
pub const NO_LIGHT: u32 = u32::MAX;

/// [`LightSamplerKind::Auto`] chooses by the light tree where a scene has more lights with
/// bounds than this; a scene with one keeps the table, whose choice is the same (bit for bit).
/// Measured (benches/results/sampling.md, "A light tree" and "A few lights"): small lights
/// spread over a floor, 4 of them, a third of the table's relMSE for 15% more time per sample,
/// 8 a sixth for 20% more; with up to [`crate::lighting::tree::FEW_LIGHTS`] lights weighed
/// across lanes, a room under 6 ceiling panels 0.63x the variance for 1.1x the time, the
/// Cycles interior (2 lights) 0.70x for 1.08x, veach-bidir (2) 0.79x for 1.13x, veach-mis
/// (4) 0.85x for 1.11x, `scenes/lights.ron` (a spot and a point) 0.84x for 1.03x.
pub const TREE_MIN_LIGHTS: usize = 1;

/// The least share of the choices that the tree's lights and the lights at infinity each keep
/// at a point where both send light ([`LightTable::infinite_share`]).
pub const INFINITE_MIN_SHARE: f32 = 0.1;

/// A directional light's importance at a point of normal `n` (zero in a medium), in the light
/// tree's units (a point light's: 4 times the irradiance it gives a surface facing it): `power`
/// (4 times its irradiance) times the cosine to the normal's line; `power` itself for a light
/// from every direction (`to_light` zero) or in a medium.
#[inline]
fn infinite_importance(to_light: Vec3A, power: f32, n: Vec3A) -> f32 {
    match n == Vec3A::ZERO || to_light == Vec3A::ZERO {
        true => power,
        false => power * to_light.dot(n).abs(),
    }
}

/// The bounds of an emitting primitive of power `phi` for the light tree (pbrt-v4's
/// `DiffuseAreaLight::Bounds`): its box, and its normal where it is flat (a quad, a triangle, a
/// disk: the side it emits from), else every direction; light leaves within `pi / 2` of them.
fn prim_bounds(prim: &Primitive, phi: f32, two_sided: bool) -> LightBounds {
    let b = prim.aabb();
    let (w, cos_theta_o) = match prim {
        Primitive::Quad(q) => (q.n, 1.0),
        Primitive::Triangle(t) => (t.normal(), 1.0),
        Primitive::Disk(d) => (d.n, 1.0),
        _ => (Vec3A::Z, -1.0),
    };
    LightBounds { lo: b.min, hi: b.max, phi, w, cos_theta_o, cos_theta_e: 0.0, two_sided }
}

/// A light of the table that is not a primitive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OtherLight {
    /// A point, spot or directional light.
    Punctual(PunctualLight),
    /// The background, sampled by its own distribution.
    Environment,
}

/// What next-event estimation samples.
#[derive(Default, Debug)]
pub struct LightTable {
    /// Primitive index of each emitting primitive: lights `0..prims.len()`.
    pub prims: Vec<u32>,
    /// The other lights: lights `prims.len()..`.
    pub others: Vec<OtherLight>,
    /// Centre of a sphere that holds the scene (shadow rays to lights at infinity end beyond it).
    pub center: Vec3A,
    /// Its radius.
    pub radius: f32,
    /// The light index of the environment, when it is sampled.
    pub environment: Option<u32>,
    /// Probability of picking each light.
    pub pmf: Vec<f32>,
    cdf: Vec<f32>,
    /// For each primitive, its light index or [`NO_LIGHT`].
    pub light_of_prim: Vec<u32>,
    /// Each light (indexed like the lights) as plain numbers where it is of a kind the
    /// integrator samples across lanes, in scenes where nothing moves.
    pub plain: Vec<PlainLight>,
    /// What the surfaces of each material id emit ([`crate::lighting::area`]).
    pub emission: Vec<Option<AreaEmission>>,
    /// The light tree over the lights with bounds, where it chooses them
    /// ([`LightSamplerKind`]); then [`Self::pick`] and the densities ask it and the importances
    /// of the lights at infinity (`infinite_bounds`), and `pmf` holds only the probability of
    /// the light sampled apart (1).
    pub tree: Option<LightTree>,
    /// The lights at infinity that the choice takes, in order, with the tree (directional
    /// lights other than the one sampled apart; the environment beside other lights is always
    /// apart).
    infinite: Vec<u32>,
    /// Each one's unit direction towards it and the importance it has on a surface facing it
    /// ([`Self::infinite_share`]).
    infinite_bounds: Vec<(Vec3A, f32)>,
    /// The light sampled apart ([`Self::apart`]).
    apart: Option<u32>,
}

/// A light as plain numbers for the integrator's lane kernels.
#[derive(Clone, Copy, Debug)]
pub enum PlainLight {
    /// An emitting quad.
    Quad(QuadLight),
    /// An emitting sphere.
    Sphere(SphereLight),
    /// An emitting ellipsoid.
    Ellipsoid(EllipsoidLight),
    /// Another kind (a triangle, a punctual light, the background), a textured emitter, or
    /// anything in a scene with motion: sampled one point at a time.
    Other,
}

/// When next-event estimation samples the background as a light.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BackgroundSampling {
    /// Never: it is black, or a map without a distribution.
    #[default]
    Never,
    /// Always: an environment map, whose light can be concentrated (a sun).
    Always,
    /// When nothing else lights the scene: a constant or sky background. Alone, it takes
    /// every light sample (spheres-sky: relMSE 19% lower for 15% more time). Beside other
    /// lights it is left to BSDF sampling and takes no share of their light samples: the
    /// choice among lights does not weigh a background against lamps (a share of one half,
    /// as a map gets, would halve a lamp's samples for a dim ambient).
    Alone,
}

/// What [`LightTable::build`] reads besides the geometry.
#[derive(Clone, Copy, Debug, Default)]
pub struct LightInputs<'a> {
    /// The point, spot and directional lights.
    pub punctual: &'a [PunctualLight],
    /// Whether the background is sampled as a light.
    pub environment: BackgroundSampling,
    /// A box that holds the scene (primitives and instances).
    pub bounds: Option<(Vec3A, Vec3A)>,
    /// For each primitive of the geometry, the object it belongs to: the primitives of one
    /// object share one even share of the light choices (`None`: each primitive is an object).
    pub objects: Option<&'a [u32]>,
    /// How lights are chosen.
    pub sampler: LightSamplerKind,
    /// The shutter interval: the light tree bounds a moving light by its sweep over it.
    pub shutter: (f32, f32),
}

impl LightTable {
    /// Collects the emitting primitives of `geometry` (those whose material id `emission`
    /// holds) and the lights of `inputs`.
    pub fn build(geometry: &Geometry, emission: Vec<Option<AreaEmission>>, inputs: LightInputs) -> Self {
        let mut t = LightTable { light_of_prim: vec![NO_LIGHT; geometry.prims.len()], ..Default::default() };
        if let Some((lo, hi)) = inputs.bounds {
            t.center = (lo + hi) * 0.5;
            t.radius = (hi - lo).length() * 0.5;
        }
        // Each finite light's group (its object, or itself) for the even share.
        let (mut power, mut group) = (Vec::new(), Vec::new());
        let mut groups = std::collections::HashMap::new();
        for (i, (prim, &m)) in geometry.prims.iter().zip(&geometry.material).enumerate() {
            let Some(AreaEmission { radiance, two_sided, .. }) = emission[m as usize] else {
                continue;
            };
            let area = prim.area();
            let p = luminance(radiance) * area * if two_sided { 2.0 } else { 1.0 };
            if p > 0.0 {
                t.light_of_prim[i] = t.prims.len() as u32;
                t.prims.push(i as u32);
                power.push(p);
                let object = inputs.objects.map_or(i as u32, |o| o[i]);
                let next = groups.len();
                group.push(*groups.entry(object).or_insert(next));
            }
        }
        let mut infinite = Vec::new();
        let mut count = groups.len();
        for l in inputs.punctual {
            let p = l.power_over_pi();
            if p > 0.0 {
                infinite.push(l.infinite());
                t.others.push(OtherLight::Punctual(*l));
                power.push(p);
                // Lights at infinity have shares of their own, outside the groups.
                group.push(if l.infinite() { usize::MAX } else { count });
                count += !l.infinite() as usize;
            }
        }
        let alone = t.prims.is_empty() && t.others.is_empty();
        let environment = match inputs.environment {
            BackgroundSampling::Never => false,
            BackgroundSampling::Always => true,
            BackgroundSampling::Alone => alone,
        };
        if environment {
            t.environment = Some((t.prims.len() + t.others.len()) as u32);
            t.others.push(OtherLight::Environment);
            infinite.push(true);
            power.push(1.0);
            group.push(usize::MAX);
        }
        // Beside other lights, the environment, else the brightest directional light, is
        // sampled at every vertex besides the choice among them (see `apart`).
        let sun = (0..t.others.len())
            .filter(|&k| matches!(t.others[k], OtherLight::Punctual(PunctualLight::Directional { .. })))
            .max_by(|&a, &b| power[t.prims.len() + a].total_cmp(&power[t.prims.len() + b]))
            .map(|k| (t.prims.len() + k) as u32);
        let beside_others = t.prims.len() + t.others.len() > 1;
        t.apart = t.environment.or(sun).filter(|_| beside_others);
        // Finite lights share one share, half in proportion to power and half evenly among
        // objects (a mesh's triangles share its part by power, as Mitsuba picks an emitter
        // and then a point on it by area); each infinite one has a share.
        infinite.splice(0..0, std::iter::repeat_n(false, t.prims.len()));
        let apart = |k: usize| t.apart == Some(k as u32);
        let chosen = |k: &usize| !apart(*k);
        let shares = (0..infinite.len()).filter(chosen).filter(|&k| infinite[k]).count()
            + infinite.iter().any(|&i| !i) as usize;
        let finite: f32 = power.iter().zip(&infinite).filter(|(_, i)| !**i).map(|(p, _)| p).sum();
        let mut group_power = vec![0.0f32; count];
        for (k, (p, inf)) in power.iter().zip(&infinite).enumerate() {
            if !inf {
                group_power[group[k]] += p;
            }
        }
        let count = count as f32;
        let mut acc = 0.0;
        for (k, (&p, &inf)) in power.iter().zip(&infinite).enumerate() {
            // The light's part of its group's even share: 1 for a light alone in its group.
            let even = if inf { 0.0 } else { (p / group_power[group[k]]) / count };
            let pmf = match (inf, shares, count == 1.0) {
                _ if apart(k) => 1.0,
                (false, 1, true) => p / finite,
                (false, 1, false) => 0.5 * (p / finite) + 0.5 * even,
                (false, _, _) => (0.5 * (p / finite) + 0.5 * even) / shares as f32,
                (true, _, _) => 1.0 / shares as f32,
            };
            t.pmf.push(pmf);
            // The light apart takes no part of the choice: its CDF step is empty.
            acc += if apart(k) { 0.0 } else { pmf };
            t.cdf.push(acc);
        }
        // The last light chosen, and any after it, end the CDF at 1 exactly.
        if let Some(last) = (0..t.cdf.len()).rfind(|k| !apart(*k)) {
            t.cdf[last..].fill(1.0);
        }
        let bounded = infinite.iter().filter(|&&i| !i).count();
        let chosen_infinite = (0..infinite.len()).filter(|&k| infinite[k] && !apart(k)).count();
        let tree = match inputs.sampler {
            LightSamplerKind::Power => false,
            LightSamplerKind::Tree => bounded > 0,
            // A light at infinity beside one bounded light: the tree's importance at the point
            // shares the choices between them (`infinite_share`).
            LightSamplerKind::Auto => bounded > TREE_MIN_LIGHTS || (bounded > 0 && chosen_infinite > 0),
        };
        if tree {
            // A primitive at time t lies translated by velocity * t: over the shutter its box
            // sweeps between the two ends' (its normals do not turn).
            let (t0, t1) = inputs.shutter;
            let sweep = |i: usize| {
                geometry.velocity.as_ref().map_or((Vec3A::ZERO, Vec3A::ZERO), |v| {
                    let (a, b) = (v[i] * t0, v[i] * t1);
                    (a.min(b), a.max(b))
                })
            };
            let bounds: Vec<(u32, LightBounds)> = (0..t.pmf.len())
                .filter_map(|l| {
                    let b = match t.other(l) {
                        None => {
                            let i = t.prims[l] as usize;
                            let two_sided =
                                emission[geometry.material[i] as usize].is_some_and(|e| e.two_sided);
                            let b = prim_bounds(&geometry.prims[i], power[l], two_sided);
                            let (lo, hi) = sweep(i);
                            LightBounds { lo: b.lo + lo, hi: b.hi + hi, ..b }
                        }
                        Some(OtherLight::Punctual(p)) => p.bounds()?,
                        Some(OtherLight::Environment) => return None,
                    };
                    Some((l as u32, b))
                })
                .collect();
            t.infinite =
                (0..t.pmf.len() as u32).filter(|&l| infinite[l as usize] && !apart(l as usize)).collect();
            t.infinite_bounds = (t.infinite.iter())
                .map(|&l| match t.other(l as usize) {
                    Some(OtherLight::Punctual(PunctualLight::Directional { to_light, irradiance })) => {
                        (*to_light, 4.0 * luminance(*irradiance))
                    }
                    // Not reached (the environment beside other lights is sampled apart): a
                    // light from every direction, of importance 1 everywhere.
                    _ => (Vec3A::ZERO, 1.0),
                })
                .collect();
            t.tree = Some(LightTree::build(&bounds, t.pmf.len()));
        }
        // The lights of the kinds the integrator samples across lanes, as plain numbers.
        let still = geometry.velocity.is_none();
        t.plain = (t.prims.iter())
            .map(|&prim| match emission[geometry.material[prim as usize] as usize] {
                Some(AreaEmission { radiance, texture: None, two_sided }) if still => {
                    let emit = radiance.to_array();
                    match &geometry.prims[prim as usize] {
                        Primitive::Quad(q) => PlainLight::Quad(q.light(emit, two_sided)),
                        Primitive::Sphere(s) => PlainLight::Sphere(s.light(emit, two_sided)),
                        Primitive::TransformedSphere(e) => PlainLight::Ellipsoid(e.light(emit, two_sided)),
                        _ => PlainLight::Other,
                    }
                }
                _ => PlainLight::Other,
            })
            .chain(t.others.iter().map(|_| PlainLight::Other))
            .collect();
        t.emission = emission;
        t
    }

    /// Whether surfaces of material `id` emit.
    #[inline]
    pub fn emits(&self, id: u32) -> bool {
        self.emission[id as usize].is_some()
    }

    /// True when there is nothing to sample.
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// How many lights there are.
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// The light `light` when it is not a primitive.
    #[inline]
    pub fn other(&self, light: usize) -> Option<&OtherLight> {
        self.others.get(light.wrapping_sub(self.prims.len()))
    }

    /// The probability of choosing the environment (0 when it is not sampled, 1 when it is
    /// sampled apart).
    #[inline]
    pub fn environment_pmf(&self) -> f32 {
        self.environment.map_or(0.0, |l| self.pmf[l as usize])
    }

    /// The light index of the light sampled apart from the others: beside other lights,
    /// next-event estimation takes one sample of the environment (where it is sampled), else
    /// of the brightest directional light, at every vertex besides its choice among the others
    /// ([`Self::pick`] never picks it; its probability is 1), where a choice among all would
    /// give it a share of the samples and the lights the rest. Each technique then takes every
    /// sample: on materials-env (a map with a sun and a point light) the variance per sample of
    /// a choice between the two with even shares is 1.8x that of the map sampled alone; on a
    /// sun beside a spot (the glTF shot of `scenes/cycles`), the choice by importance at the
    /// point left 1.4x the variance of the sun apart, whose shadow ray is the cheapest there is
    /// (`benches/results/sampling.md`). `None` where there is no such light or it is the only
    /// light (then the choice always picks it).
    #[inline]
    pub fn apart(&self) -> Option<usize> {
        self.apart.map(|l| l as usize)
    }

    /// Whether the light sampled apart draws a point of its own (the environment does; a
    /// directional light has one direction).
    #[inline]
    pub fn apart_samples(&self) -> bool {
        self.apart.is_some() && self.apart == self.environment
    }

    /// The end of a shadow ray from `from` towards a light at infinity in direction `wi`: a
    /// point beyond everything in the scene.
    #[inline]
    pub fn beyond(&self, from: Vec3A, wi: Vec3A) -> Vec3A {
        from + wi * (2.0 * ((from - self.center).length() + self.radius) + 1.0)
    }

    /// Picks a light for the point `from` of shading normal `n` (zero in a medium) with `u` in
    /// [0, 1): (light index, probability). The table's choice ignores the point; the tree's
    /// weighs the lights by their importance there,
    /// after giving each light at infinity its share first (pbrt-v4's `pInfinite`), and its
    /// probability is 0 (the light meaningless) where no light of the tree reaches `from`.
    #[inline]
    pub fn pick(&self, u: f32, from: Vec3A, n: Vec3A) -> (usize, f32) {
        let Some(tree) = &self.tree else {
            let i = self.cdf.partition_point(|&c| c <= u).min(self.cdf.len() - 1);
            return (i, self.pmf[i]);
        };
        let total = if self.infinite.is_empty() { 0.0 } else { tree.importance_total(from, n) };
        match self.infinite_or_tree(u, total, n) {
            Err(picked) => picked,
            Ok((u, finite)) => {
                let (l, pmf) = tree.pick(u, from, n);
                (l as usize, finite * pmf)
            }
        }
    }

    /// [`Self::pick`] for the points `from` of normals `n` in lanes, with `u` per lane: the
    /// same bits, the importances of a tree of few lights computed across the lanes.
    #[inline]
    pub fn pick_lanes<const N: usize>(
        &self,
        u: &[f32; N],
        from: &[[f32; N]; 3],
        n: &[[f32; N]; 3],
    ) -> [(usize, f32); N] {
        let at = |a: &[[f32; N]; 3], l: usize| Vec3A::new(a[0][l], a[1][l], a[2][l]);
        let Some((tree, few)) = self.tree.as_ref().and_then(|t| Some((t, t.few()?))) else {
            return std::array::from_fn(|l| self.pick(u[l], at(from, l), at(n, l)));
        };
        // Into a local of the closure: written through a captured reference, the loop could
        // alias the inputs for all the compiler knew, and it kept it scalar in some builds.
        let importance = crate::simd::lanes(
            #[inline(always)]
            || {
                let mut importance = [[0.0; N]; FEW_LIGHTS];
                tree.importances_lanes(from, n, &mut importance);
                importance
            },
        );
        let total = importance_sums(&importance, few);
        let split: [_; N] = std::array::from_fn(|l| self.infinite_or_tree(u[l], total[l], at(n, l)));
        let u_tree = split.map(|s| s.map_or(0.0, |(u, _)| u));
        let (k, pmf) = crate::simd::lanes(
            #[inline(always)]
            || choose_lanes(&importance, few, &u_tree),
        );
        std::array::from_fn(|l| match split[l] {
            Err(picked) => picked,
            Ok((_, finite)) => (tree.leaf_light(k[l] as usize) as usize, finite * pmf[l]),
        })
    }

    /// The first step of a choice by the tree at a point of normal `n` where its lights'
    /// importance is `total` ([`LightTree::importance_total`]): a light at infinity, with its
    /// probability, as `Err((light, probability))`; else `Ok` of the number rescaled for the
    /// tree's choice and the tree's share ([`Self::infinite_share`]).
    #[inline]
    fn infinite_or_tree(&self, u: f32, total: f32, n: Vec3A) -> Result<(f32, f32), (usize, f32)> {
        if self.infinite.is_empty() {
            return Ok((u.min(1.0 - f32::EPSILON / 2.0), 1.0));
        }
        let (p_infinite, importances) = self.infinite_share(total, n);
        if u < p_infinite {
            // Among the lights at infinity by their parts (the last where rounding leaves `v`
            // beyond their sum).
            let v = u / p_infinite;
            let mut k = self.infinite.len() - 1;
            let mut acc = 0.0;
            for j in 0..self.infinite.len() {
                acc += self.infinite_part(j, importances, n);
                if v < acc {
                    k = j;
                    break;
                }
            }
            return Err((self.infinite[k] as usize, p_infinite * self.infinite_part(k, importances, n)));
        }
        let finite = 1.0 - p_infinite;
        Ok((((u - p_infinite) / finite).min(1.0 - f32::EPSILON / 2.0), finite))
    }

    /// The share of the choices that go to the lights at infinity at a point of normal `n`
    /// where the tree's lights' importance is `total`, and the lights at infinity's importance
    /// there. In proportion to the importances, as Cycles' light tree weighs its distant lights
    /// against the others at each point: where the tree's lights cannot reach (outside a spot's
    /// cone) all the choices go to the sun, where a fixed share (pbrt-v4's) leaves half of them
    /// to a light that sends nothing. Where both send light, each keeps at least
    /// [`INFINITE_MIN_SHARE`]: the importances know nothing of shadows (a sun outside a room lit
    /// by lamps). Where neither has importance, the fixed shares (one each).
    #[inline]
    fn infinite_share(&self, total: f32, n: Vec3A) -> (f32, f32) {
        let importances: f32 =
            (self.infinite_bounds.iter()).map(|&(w, power)| infinite_importance(w, power, n)).sum();
        let p = match (importances > 0.0, total > 0.0) {
            (true, true) => {
                (importances / (importances + total)).clamp(INFINITE_MIN_SHARE, 1.0 - INFINITE_MIN_SHARE)
            }
            (true, false) => 1.0,
            (false, true) => 0.0,
            (false, false) => 1.0 - 1.0 / (self.infinite.len() + 1) as f32,
        };
        (p, importances)
    }

    /// The part of the `k`-th light at infinity in their share: its importance over theirs,
    /// `importances` (evenly where that is 0).
    #[inline]
    fn infinite_part(&self, k: usize, importances: f32, n: Vec3A) -> f32 {
        let (to_light, power) = self.infinite_bounds[k];
        match importances > 0.0 {
            true => infinite_importance(to_light, power, n) / importances,
            false => 1.0 / self.infinite.len() as f32,
        }
    }

    /// The probability that [`Self::pick`] picks `light` for the point `from` of normal `n`:
    /// the same bits.
    #[inline]
    pub fn pmf_from(&self, light: usize, from: Vec3A, n: Vec3A) -> f32 {
        let Some(tree) = &self.tree else { return self.pmf[light] };
        let at_infinity = self.at_infinity(light);
        if self.infinite.is_empty() {
            return if at_infinity { self.pmf[light] } else { tree.pmf(light as u32, from, n) };
        }
        let (p_infinite, importances) = self.infinite_share(tree.importance_total(from, n), n);
        match self.infinite.iter().position(|&l| l as usize == light) {
            Some(k) => p_infinite * self.infinite_part(k, importances, n),
            None if at_infinity => self.pmf[light],
            None => (1.0 - p_infinite) * tree.pmf(light as u32, from, n),
        }
    }

    /// Whether light `light` is at infinity (the environment or a directional light).
    #[inline]
    fn at_infinity(&self, light: usize) -> bool {
        match self.other(light) {
            Some(OtherLight::Environment) => true,
            Some(OtherLight::Punctual(l)) => l.infinite(),
            None => false,
        }
    }

    /// Samples a point on light `light` (a primitive), where it is at `time`, as seen from
    /// `from`.
    #[inline]
    pub fn sample(&self, geometry: &Geometry, light: usize, from: Vec3A, u: Vec2, time: f32) -> LightSample {
        let prim = self.prims[light];
        // A moving light is sampled at rest, from where `from` is relative to it.
        let off = geometry.offset(prim, time);
        let from = from - off;
        let mut ls = geometry.prims[prim as usize].sample_solid_angle(from, u);
        ls.p += off;
        ls
    }

    /// Solid-angle density (including the pick probability) with which NEE from `from` (of
    /// shading normal `from_n`, zero in a medium) at `time` would have produced the point `p`
    /// (normal `n`) on primitive `prim`; 0 for unsampled emitters.
    #[inline]
    #[expect(
        clippy::too_many_arguments,
        reason = "the two points, their normals, the primitive and the time"
    )]
    pub fn pdf(
        &self,
        geometry: &Geometry,
        prim: u32,
        from: Vec3A,
        from_n: Vec3A,
        p: Vec3A,
        n: Vec3A,
        time: f32,
    ) -> f32 {
        // Instance hits (prim out of range) are never sampled.
        let light = self.light_of_prim.get(prim as usize).copied().unwrap_or(NO_LIGHT);
        if light == NO_LIGHT {
            return 0.0;
        }
        let pmf = self.pmf_from(light as usize, from, from_n);
        let off = geometry.offset(prim, time);
        let (from, p) = (from - off, p - off);
        let pdf = geometry.prims[prim as usize].pdf_solid_angle(from, p, n);
        pdf * pmf
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::Textures;
    use glam::Vec3;

    fn point(x: f32, i: f32) -> PunctualLight {
        PunctualLight::Point { position: Vec3A::new(x, 1.0, 0.0), intensity: Vec3::splat(i) }
    }

    /// A sun beside other lights is sampled apart (the brightest, where there are several),
    /// the environment before it; alone, it is the choice. (Fails with the sun in the choice.)
    #[test]
    fn a_sun_beside_other_lights_is_sampled_apart() {
        let sun = |e: f32| PunctualLight::Directional { to_light: Vec3A::Y, irradiance: Vec3::splat(e) };
        let build = |punctual: &[PunctualLight], environment| {
            LightTable::build(
                &Geometry::default(),
                Vec::new(),
                LightInputs { punctual, environment, ..Default::default() },
            )
        };
        let table = build(&[point(0.0, 1.0), sun(1.0), sun(2.0)], BackgroundSampling::Never);
        assert_eq!((table.apart(), table.pmf[2]), (Some(2), 1.0));
        for u in [0.0, 0.3, 0.6, 0.999] {
            assert_ne!(table.pick(u, Vec3A::ZERO, Vec3A::Y).0, 2, "{u}");
        }
        let beside_a_spot = build(&[point(0.0, 1.0), sun(1.0)], BackgroundSampling::Never);
        assert_eq!(beside_a_spot.apart(), Some(1));
        assert_eq!(beside_a_spot.pick(0.7, Vec3A::ZERO, Vec3A::Y), (0, 1.0));
        assert_eq!(build(&[sun(1.0)], BackgroundSampling::Never).apart(), None);
        assert_eq!(build(&[sun(1.0), point(0.0, 1.0)], BackgroundSampling::Always).apart(), Some(2));
    }

    /// A second sun beside a spot, the first sampled apart: `Auto` takes the tree, and the
    /// second sun's share follows the importances at the point. Outside the spot's cone it
    /// takes every choice; under the spot the two share them, each at least
    /// `INFINITE_MIN_SHARE`; in a medium the sun is weighed without a cosine; `pick` and
    /// `pmf_from` agree. (Fails with the fixed share, pbrt-v4's, of one half: outside the cone
    /// the sun has 0.5.)
    #[test]
    fn a_sun_beside_a_spot_takes_the_choices_the_spot_cannot_use() {
        let spot = PunctualLight::Spot {
            position: Vec3A::new(0.0, 4.0, 0.0),
            axis: -Vec3A::Y,
            intensity: Vec3::splat(30.0),
            cos_falloff: 0.95,
            cos_total: 0.9,
            falloff: SpotFalloff::Smoothstep,
            texture: None,
        };
        let sun =
            PunctualLight::Directional { to_light: Vec3A::new(0.6, 0.8, 0.0), irradiance: Vec3::splat(3.0) };
        let apart = PunctualLight::Directional { to_light: Vec3A::Y, irradiance: Vec3::splat(5.0) };
        let inputs = LightInputs {
            punctual: &[spot, apart, sun],
            environment: BackgroundSampling::Never,
            ..Default::default()
        };
        let table = LightTable::build(&Geometry::default(), Vec::new(), inputs);
        assert!(table.tree.is_some(), "Auto takes the tree for a sun beside a spot");
        assert_eq!(table.apart(), Some(1));
        let up = Vec3A::Y;
        let share = |p: Vec3A, n: Vec3A| {
            let sun = table.pmf_from(2, p, n);
            assert!((sun + table.pmf_from(0, p, n) - 1.0).abs() < 1e-6, "at {p}");
            sun
        };
        // Outside the cone (the spot's axis is straight down; 45 degrees off it).
        assert_eq!(share(Vec3A::new(4.0, 0.0, 0.0), up), 1.0);
        // Under the spot: the spot's importance 4 * 30 / 16 = 7.5, the sun's 4 * 3 * 0.8 = 9.6.
        let under = share(Vec3A::ZERO, up);
        assert!((under - 9.6 / (9.6 + 7.5)).abs() < 0.02, "{under}");
        // Nearly edge-on to the sun, facing the spot: the floor of the share; edge-on, none.
        assert_eq!(share(Vec3A::ZERO, Vec3A::new(0.8, -0.59, 0.0).normalize()), INFINITE_MIN_SHARE);
        assert_eq!(share(Vec3A::ZERO, Vec3A::new(0.8, -0.6, 0.0)), 0.0);
        // In a medium: the sun's 12 against the spot's 7.5.
        let medium = share(Vec3A::ZERO, Vec3A::ZERO);
        assert!((medium - 12.0 / 19.5).abs() < 0.02, "{medium}");
        for (p, n) in [(Vec3A::ZERO, up), (Vec3A::new(4.0, 0.0, 0.0), up), (Vec3A::ZERO, Vec3A::ZERO)] {
            for u in [0.0, 0.3, 0.55, 0.7, 0.999] {
                let (l, pmf) = table.pick(u, p, n);
                assert_eq!(pmf.to_bits(), table.pmf_from(l, p, n).to_bits(), "{u} at {p}");
            }
        }
    }

    /// The table's choice: finite lights half by power, half evenly; each light at infinity a
    /// share of its own.
    #[test]
    fn choices_mix_power_and_even_shares() {
        let geo = Geometry::default();
        let table = |punctual: &[PunctualLight], environment| {
            let sampler = LightSamplerKind::Power;
            LightTable::build(
                &geo,
                Vec::new(),
                LightInputs { punctual, environment, sampler, ..Default::default() },
            )
        };
        use BackgroundSampling::{Alone, Always, Never};
        let one = table(&[point(0.0, 5.0)], Never);
        assert_eq!(one.pmf, [1.0]);
        let two = table(&[point(0.0, 1.0), point(1.0, 3.0)], Never);
        assert_eq!(two.pmf, [0.375, 0.625]);
        let sun = PunctualLight::Directional { to_light: Vec3A::Y, irradiance: Vec3::ONE };
        // The environment beside other lights is sampled apart: probability 1, never picked.
        let three = table(&[point(0.0, 1.0), point(1.0, 3.0), sun], Always);
        assert_eq!(three.pmf, [0.375 / 2.0, 0.625 / 2.0, 1.0 / 2.0, 1.0]);
        assert_eq!((three.environment, three.apart()), (Some(3), Some(3)));
        assert_eq!(three.pick(0.99, Vec3A::ZERO, Vec3A::ZERO), (2, 1.0 / 2.0));
        assert_eq!(three.pick(1.0 - f32::EPSILON / 2.0, Vec3A::ZERO, Vec3A::ZERO).0, 2);
        assert!(matches!(three.other(2), Some(OtherLight::Punctual(PunctualLight::Directional { .. }))));
        assert!(three.other(0).is_some() && LightTable::default().other(0).is_none());
        // A light that sends nothing is not in the table.
        assert!(table(&[point(0.0, 0.0)], Never).is_empty());
        // A smooth background is a light only where nothing else is.
        assert_eq!(table(&[point(0.0, 5.0)], Alone).environment, None);
        let sky = table(&[point(0.0, 0.0)], Alone);
        assert_eq!((sky.environment, sky.pmf.as_slice()), (Some(0), [1.0].as_slice()));
        assert_eq!((sky.apart(), sky.pick(0.5, Vec3A::ZERO, Vec3A::ZERO)), (None, (0, 1.0)));
    }

    /// The even half of the choices goes to objects alike, an object's primitives splitting
    /// its part by power: two emitting objects (one made of spheres of radius 1 and 2, one of a
    /// sphere of radius 1) and a point light take a third each of that half.
    #[test]
    fn an_objects_primitives_share_its_even_part() {
        use crate::shape::Sphere;
        let sphere = |x: f32, r: f32| Primitive::Sphere(Sphere::new(Vec3A::new(x, 0.0, 0.0), r));
        let geo = Geometry::build(vec![sphere(0.0, 1.0), sphere(5.0, 2.0), sphere(10.0, 1.0)], vec![0; 3]);
        let objects: Vec<u32> = geo.source.iter().map(|&i| [0, 0, 1][i as usize]).collect();
        let emission = vec![Some(AreaEmission { radiance: Vec3::ONE, texture: None, two_sided: false })];
        let point = [point(0.0, 1.0)];
        let inputs = LightInputs {
            punctual: &point,
            environment: BackgroundSampling::Never,
            bounds: None,
            objects: Some(&objects),
            ..Default::default()
        };
        let table = LightTable::build(&geo, emission, inputs);
        let area = |r: f32| 4.0 * std::f32::consts::PI * r * r * luminance(Vec3::ONE);
        let total = 2.0 * area(1.0) + area(2.0) + point[0].power_over_pi();
        for (l, &prim) in table.prims.iter().enumerate() {
            let (r, object_power) = match objects[prim as usize] {
                0 => (if geo.prims[prim as usize].area() > 20.0 { 2.0 } else { 1.0 }, area(1.0) + area(2.0)),
                _ => (1.0, area(1.0)),
            };
            let want = 0.5 * area(r) / total + 0.5 * (area(r) / object_power) / 3.0;
            assert!((table.pmf[l] - want).abs() < 1e-6, "light {l}: {} against {want}", table.pmf[l]);
        }
        let want = 0.5 * point[0].power_over_pi() / total + 0.5 / 3.0;
        assert!((table.pmf[3] - want).abs() < 1e-6, "{} against {want}", table.pmf[3]);
    }

    /// A spot light is full inside its falloff angle, dark beyond its cone, smooth between.
    #[test]
    fn spot_falloff_is_a_smoothstep_of_the_cosine() {
        let (cos_total, cos_falloff) = (30f32.to_radians().cos(), 20f32.to_radians().cos());
        let spot = PunctualLight::Spot {
            position: Vec3A::ZERO,
            axis: -Vec3A::Y,
            intensity: Vec3::ONE,
            cos_falloff,
            cos_total,
            falloff: SpotFalloff::Smoothstep,
            texture: None,
        };
        let at = |deg: f32| {
            let r = deg.to_radians();
            spot.illuminate(Vec3A::new(r.sin(), -r.cos(), 0.0), &Textures::default()).2.x
        };
        assert_eq!(at(0.0), 1.0);
        assert_eq!(at(19.9), 1.0);
        assert_eq!(at(30.1), 0.0);
        let mid = at(25.0);
        assert!(mid > 0.0 && mid < 1.0 && at(22.0) > mid && mid > at(28.0));
    }

    fn spot(falloff: SpotFalloff, texture: Option<SpotTexture>) -> PunctualLight {
        let (cos_total, cos_falloff) = (30f32.to_radians().cos(), 15f32.to_radians().cos());
        PunctualLight::Spot {
            position: Vec3A::ZERO,
            axis: Vec3A::Z,
            intensity: Vec3::ONE,
            cos_falloff,
            cos_total,
            falloff,
            texture,
        }
    }

    /// Mitsuba's spot: full within 15 degrees, none beyond 30, linear in the angle between; its
    /// power is the integral of that over the sphere.
    #[test]
    fn linear_spot_falloff_is_linear_in_the_angle() {
        let total = 30f32.to_radians();
        let light = spot(SpotFalloff::Linear { total, inv_width: 1.0 / (total - 15f32.to_radians()) }, None);
        let at = |deg: f32| {
            let r = deg.to_radians();
            light.illuminate(Vec3A::new(r.sin(), 0.0, r.cos()), &Textures::default()).2.x
        };
        assert_eq!((at(0.0), at(14.9), at(30.1)), (1.0, 1.0, 0.0));
        for (deg, want) in [(22.5, 0.5), (26.0, 4.0 / 15.0), (16.0, 14.0 / 15.0)] {
            assert!((at(deg) - want).abs() < 1e-5, "{deg} degrees: {} against {want}", at(deg));
        }
        // 2 pi times the integral of the falloff over theta, by the midpoint rule, over pi.
        let n = 100_000;
        let integral: f64 = (0..n)
            .map(|k| {
                let t = (k as f64 + 0.5) / n as f64 * std::f64::consts::PI;
                at((t as f32).to_degrees()) as f64 * t.sin() * std::f64::consts::PI / n as f64
            })
            .sum();
        assert!((light.power_over_pi() as f64 - 2.0 * integral).abs() < 1e-4, "{}", light.power_over_pi());
    }

    /// A texture over a spot's cone reads Mitsuba's uv: u grows along the frame's x, v
    /// against its y, and the cone's edge along x is u = 1.
    #[test]
    fn a_spot_texture_reads_the_directions_uv() {
        let checker = |u: f32, v: f32| Textures {
            list: vec![
                crate::texture::Texture::Solid(Vec3::ONE),
                crate::texture::Texture::Solid(Vec3::ZERO),
                crate::texture::Texture::UvChecker { u, v, even: 0, odd: 1, transform: None },
            ],
        };
        let texture = |x: Vec3A| SpotTexture {
            texture: LightTexture { id: 2, mean: Vec3::splat(0.5) },
            x,
            y: Vec3A::Y,
            inv_tan: 1.0 / 30f32.to_radians().tan(),
        };
        let light = spot(SpotFalloff::Smoothstep, Some(texture(Vec3A::X)));
        let lit = |t: &Textures, x: f32, y: f32| light.illuminate(Vec3A::new(x, y, 1.0), t).2.x > 0.0;
        // Two cells along u: x > 0 is u > 1/2, odd (dark).
        let (along_u, along_v) = (checker(2.0, 1.0), checker(1.0, 2.0));
        assert!(lit(&along_u, -0.1, 0.05) && !lit(&along_u, 0.1, 0.05));
        // Two along v: y > 0 is v < 1/2, even (lit).
        assert!(lit(&along_v, 0.05, 0.1) && !lit(&along_v, 0.05, -0.1));
        // Four along u: the cell boundary at u = 3/4 lies halfway to the edge of the cone.
        let quarters = checker(4.0, 1.0);
        let half = 0.5 * 30f32.to_radians().tan();
        assert!(lit(&quarters, half - 0.01, 0.0) && !lit(&quarters, half + 0.01, 0.0));
    }

    /// A projector lights the plane at unit distance facing it with pi times its irradiance
    /// wherever its image reaches, and nothing beyond the image or behind it; u grows against
    /// the frame's x and v along its y.
    #[test]
    fn a_projector_gives_pi_irradiance_on_the_unit_plane() {
        let light = |texture| PunctualLight::Projector {
            position: Vec3A::ZERO,
            frame: [Vec3A::X, Vec3A::Y, Vec3A::Z],
            tan_x: 1.0,
            tan_y: 0.5,
            irradiance: Vec3::splat(2.0),
            texture,
        };
        let none = Textures::default();
        for (x, y) in [(0.0, 0.0), (0.9, 0.4), (-0.5, -0.45)] {
            let p = Vec3A::new(x, y, 1.0);
            let (wi, _, le) = light(None).illuminate(p, &none);
            let e = le.x * -wi.z;
            assert!((e - 2.0 * std::f32::consts::PI).abs() < 1e-5, "({x}, {y}): {e}");
        }
        for p in [Vec3A::new(1.1, 0.0, 1.0), Vec3A::new(0.0, 0.6, 1.0), Vec3A::new(0.0, 0.0, -1.0)] {
            assert_eq!(light(None).illuminate(p, &none).2, Vec3::ZERO, "{p}");
        }
        let textures = Textures {
            list: vec![
                crate::texture::Texture::Solid(Vec3::ONE),
                crate::texture::Texture::Solid(Vec3::ZERO),
                crate::texture::Texture::UvChecker { u: 2.0, v: 2.0, even: 0, odd: 1, transform: None },
            ],
        };
        let textured = light(Some(LightTexture { id: 2, mean: Vec3::splat(0.5) }));
        let lit = |x: f32, y: f32| textured.illuminate(Vec3A::new(x, y, 1.0), &textures).2.x > 0.0;
        // x > 0, y > 0: u < 1/2, v > 1/2: odd (dark); the other quadrants alternate.
        assert!(!lit(0.5, 0.2) && lit(-0.5, 0.2) && lit(0.5, -0.2) && !lit(-0.5, -0.2));
        assert!((textured.power_over_pi() - luminance(Vec3::ONE) * 4.0 * 0.5).abs() < 1e-6);
    }
}
