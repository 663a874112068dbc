//! Light tracing's share of the paths: the caustics that lights throw onto rough surfaces
//! through sharp ones.
//!
//! A path from the camera to a rough surface and on to a light whose last vertex before the
//! light is sharp (a mirror, glass, a lobe narrower than [`SHARP_ALPHA`]) is a path the path
//! tracer finds only by chance: next-event estimation at the sharp vertex reaches the light
//! only where that vertex's narrow lobe happens to point at it (never for a point light behind
//! a delta lobe), and BSDF sampling reaches a small light as rarely. A light tracer (Veach
//! 1997, "Robust Monte Carlo Methods for Light Transport Simulation", section 10.2's particle
//! tracing; pbrt-v4's `LightPathIntegrator`) samples those same paths from the light's end: it
//! leaves the light, follows the lobes, and connects each rough vertex to the camera, where a
//! narrow lobe costs nothing.
//!
//! The two split the paths between them rather than weighing both by multiple importance
//! sampling: a path whose first vertex is [`VertexClass::Rough`], whose other vertices are all
//! rough or [`VertexClass::Sharp`], whose last vertex is sharp, and which ends on a light
//! light tracing emits from ([`LightPaths::traced`]: point, spot, directional and projector
//! lights, emitting spheres, quads and triangles) is the light tracer's alone (the path tracer
//! leaves out its light samples and emitter hits), and every other path is the path tracer's
//! alone. The class of a vertex is a function of its material there, the same from both ends,
//! so each estimator is unbiased for its part of the image's integral and their sum for the
//! whole, and neither needs the other's densities.

use crate::accel::geometry::Geometry;
use crate::lighting::area::AreaEmission;
use crate::lighting::lights::{LightTable, OtherLight};
use crate::lighting::punctual_light::PunctualLight;
use crate::material::Material;
use crate::material::lambertian::cosine_hemisphere;
use crate::math::{Frame, Ray, concentric_disk, luminance, offset_ray_origin, uniform_sphere};
use crate::texture::Textures;
use glam::{Vec2, Vec3, Vec3A};
use std::f32::consts::PI;

/// Whether a render traces light paths for the caustics of punctual lights (`render:
/// (light_tracing: On)`, `--light-tracing on`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize)]
pub enum LightTracing {
    /// The path tracer takes every path (default).
    #[default]
    Off,
    /// The light tracer takes the caustics of punctual lights where the scene has them
    /// ([`LightPaths::plan`]).
    On,
}

impl LightTracing {
    /// The names, as the command line spells them.
    pub const NAMES: [(&'static str, LightTracing); 2] =
        [("off", LightTracing::Off), ("on", LightTracing::On)];
}

impl std::str::FromStr for LightTracing {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        crate::format::by_name(&Self::NAMES, s, "light tracing")
    }
}

/// The microfacet width below which a lobe counts as sharp by default
/// ([`LightPaths::sharp`]): its caustics go to the light tracer.
pub const SHARP_ALPHA: f32 = 0.05;

/// How light tracing sees a vertex on a material.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexClass {
    /// No delta lobe and none narrower than [`LightPaths::sharp`]: light tracing connects it to
    /// the camera (its BSDF evaluates in full).
    Rough,
    /// A delta lobe or one narrower than [`LightPaths::sharp`]: light tracing scatters off it.
    Sharp,
    /// Neither ([`Material::sharpest_alpha`] is `None`): the path tracer's.
    Other,
}

/// A light light tracing emits from.
#[derive(Clone, Copy, Debug)]
pub enum Emitter {
    /// A point, spot, directional or projector light.
    Punctual(PunctualLight),
    /// An emitting primitive (by its index in the scene's geometry).
    Area {
        /// The primitive.
        prim: u32,
        /// What it emits.
        emission: AreaEmission,
    },
}

/// What light tracing needs of a scene: its lights, chosen by power, and which of the light
/// table's lights they are.
#[derive(Clone, Debug)]
pub struct LightPaths {
    /// The microfacet width below which a lobe is sharp ([`SHARP_ALPHA`]; [`Self::class`]).
    pub sharp: f32,
    /// The lights it emits from.
    pub emitters: Vec<Emitter>,
    /// Probability of choosing each.
    pub pmf: Vec<f32>,
    cdf: Vec<f32>,
    /// For each light of the scene's light table, whether it is one of [`Self::emitters`]: the
    /// path tracer leaves out the paths that end on such a light after a sharp vertex.
    pub traced: Vec<bool>,
    /// A sphere holding the scene, which directional lights' rays start from.
    center: Vec3A,
    radius: f32,
}

/// A light path's first ray and its throughput: emitted radiance over the densities of its
/// light, point and direction.
#[derive(Clone, Copy, Debug)]
pub struct Emitted {
    /// The ray leaving the light.
    pub ray: Ray,
    /// Its throughput.
    pub beta: Vec3,
}

impl LightPaths {
    /// Light tracing from the lights of `table` it can emit from (all but the environment and
    /// primitives of kinds without [`Primitive::sample_area`](crate::shape::primitive::Primitive::sample_area))
    /// in a scene of `geometry`; `None` where none sends anything.
    pub fn new(table: &LightTable, geometry: &Geometry) -> Option<Self> {
        let (center, radius) = (table.center, table.radius);
        let mut traced = vec![false; table.len()];
        let mut emitters = Vec::new();
        let mut power = Vec::new();
        for (light, &prim) in table.prims.iter().enumerate() {
            let shape = &geometry.prims[prim as usize];
            let emission = table.emission[geometry.material[prim as usize] as usize];
            let (Some(emission), Some(_)) = (emission, shape.sample_area(Vec2::splat(0.5))) else { continue };
            let sides = if emission.two_sided { 2.0 } else { 1.0 };
            power.push(luminance(emission.radiance) * shape.area() * PI * sides);
            emitters.push(Emitter::Area { prim, emission });
            traced[light] = true;
        }
        for (k, other) in table.others.iter().enumerate() {
            let OtherLight::Punctual(l) = *other else { continue };
            power.push(match l {
                PunctualLight::Directional { irradiance, .. } => luminance(irradiance) * PI * radius * radius,
                _ => l.power_over_pi() * PI,
            });
            emitters.push(Emitter::Punctual(l));
            traced[table.prims.len() + k] = true;
        }
        let total: f32 = power.iter().sum();
        if !(total > 0.0) || !total.is_finite() {
            return None;
        }
        let pmf: Vec<f32> = power.iter().map(|p| p / total).collect();
        let mut acc = 0.0;
        let cdf = pmf
            .iter()
            .map(|p| {
                acc += p;
                acc
            })
            .collect();
        Some(Self { sharp: SHARP_ALPHA, emitters, pmf, cdf, traced, center, radius })
    }

    /// The class of a vertex on material `m` (after its wrappers resolved).
    #[inline]
    pub fn class(&self, m: &Material) -> VertexClass {
        match m.sharpest_alpha() {
            Some(a) if a < self.sharp => VertexClass::Sharp,
            Some(_) => VertexClass::Rough,
            None => VertexClass::Other,
        }
    }

    /// Whether light `light` of the light table is one light tracing emits from.
    #[inline]
    pub fn traces(&self, light: u32) -> bool {
        self.traced.get(light as usize).copied().unwrap_or(false)
    }

    /// The emitter that `u` in [0, 1) chooses, and its probability.
    #[inline]
    pub fn pick(&self, u: f32) -> (usize, f32) {
        let i = self.cdf.partition_point(|&c| c <= u).min(self.emitters.len() - 1);
        (i, self.pmf[i])
    }

    /// A ray leaving emitter `i` (chosen with probability `pmf`) at time `time` for the numbers
    /// `u`: a directional light's from a disk across the scene's sphere; a point light's
    /// (spot's, projector's) from its point in a direction uniform over its sphere (a spot's
    /// over its cone), with the intensity there; an emitting primitive's from a point uniform
    /// over its area (where it is at `time`) in a cosine-weighted direction on a side it emits
    /// from. `None` where it sends nothing.
    pub fn emit(
        &self,
        i: usize,
        pmf: f32,
        u: [f32; 4],
        time: f32,
        geometry: &Geometry,
        textures: &Textures,
    ) -> Option<Emitted> {
        let (ray, beta) = match self.emitters[i] {
            Emitter::Area { prim, emission } => {
                let ls = geometry.prims[prim as usize].sample_area(Vec2::new(u[0], u[1]))?;
                let p = ls.p + geometry.offset(prim, time);
                let (side, v, sides) = match emission.two_sided {
                    false => (ls.n, u[2], 1.0),
                    true if u[2] < 0.5 => (ls.n, 2.0 * u[2], 2.0),
                    true => (-ls.n, 2.0 * u[2] - 1.0, 2.0),
                };
                let dir =
                    Frame::from_normal(side).to_world(cosine_hemisphere(Vec2::new(v.min(ONE_BELOW), u[3])));
                let le = emission.emitted(textures, dir.dot(ls.n), || geometry.surface(prim, p, time));
                let origin = offset_ray_origin(p, ls.err, side);
                (Ray { origin, dir, time }, le * (PI * sides / ls.pdf))
            }
            Emitter::Punctual(PunctualLight::Directional { to_light, irradiance }) => {
                let f = Frame::from_normal(to_light);
                let d = concentric_disk(Vec2::new(u[0], u[1])) * self.radius;
                let origin = self.center + to_light * self.radius + f.t * d.x + f.b * d.y;
                (Ray { origin, dir: -to_light, time }, irradiance * (PI * self.radius * self.radius))
            }
            Emitter::Punctual(ref l) => {
                let (position, (dir, inv_pdf)) = match *l {
                    PunctualLight::Spot { position, axis, cos_total, .. } => {
                        // Uniform over the cone's solid angle 2 pi (1 - cos_total).
                        let z = 1.0 - u[0] * (1.0 - cos_total);
                        let r = (1.0 - z * z).max(0.0).sqrt();
                        let (s, c) = (2.0 * PI * u[1]).sin_cos();
                        let dir = Frame::from_normal(axis).to_world(Vec3A::new(r * c, r * s, z));
                        (position, (dir, 2.0 * PI * (1.0 - cos_total)))
                    }
                    PunctualLight::Point { position, .. } | PunctualLight::Projector { position, .. } => {
                        (position, (uniform_sphere(Vec2::new(u[0], u[1])), 4.0 * PI))
                    }
                    // (Matched above.)
                    PunctualLight::Directional { .. } => return None,
                };
                // The intensity towards `dir`: what the light gives a point at distance 1.
                let (_, dist, le) = l.illuminate(position + dir, textures);
                (Ray { origin: position, dir, time }, le * (dist * dist) * inv_pdf)
            }
        };
        let beta = beta / pmf;
        (beta != Vec3::ZERO && beta.is_finite()).then_some(Emitted { ray, beta })
    }
}

/// The largest `f32` below 1.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lighting::lights::LightInputs;

    fn table(punctual: &[PunctualLight]) -> LightTable {
        LightTable::build(&Geometry::default(), Vec::new(), LightInputs { punctual, ..Default::default() })
    }

    #[test]
    fn lights_are_picked_by_power() {
        let p =
            |x: f32, i: f32| PunctualLight::Point { position: Vec3A::splat(x), intensity: Vec3::splat(i) };
        let lp = LightPaths::new(&table(&[p(0.0, 1.0), p(1.0, 3.0)]), &Geometry::default()).unwrap();
        assert_eq!(lp.pick(0.1), (0, 0.25));
        assert_eq!(lp.pick(0.3), (1, 0.75));
        assert_eq!(lp.pick(0.999_999_9), (1, 0.75));
        assert_eq!(lp.traced, [true, true]);
        assert!(LightPaths::new(&table(&[p(0.0, 0.0)]), &Geometry::default()).is_none());
    }

    #[test]
    fn a_point_light_sends_its_power() {
        // The mean throughput of a point light's rays is its power, 4 pi I.
        let point = PunctualLight::Point { position: Vec3A::ZERO, intensity: Vec3::splat(2.0) };
        let lp = LightPaths::new(&table(&[point]), &Geometry::default()).unwrap();
        let (geometry, textures) = (Geometry::default(), Textures::default());
        let n = 64;
        let mut sum = Vec3::ZERO;
        for i in 0..n {
            let u = [(i as f32 + 0.5) / n as f32, 0.37, 0.0, 0.0];
            sum += lp.emit(0, 1.0, u, 0.0, &geometry, &textures).unwrap().beta;
        }
        assert!((sum / n as f32 - Vec3::splat(8.0 * PI)).abs().max_element() < 1e-3);
    }
}
