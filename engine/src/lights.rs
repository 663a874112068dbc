//! The emitter table used for next-event estimation: which primitives can be sampled and with
//! what probability (proportional to emitted power).

use crate::geometry::{Geometry, Primitive};
use crate::material::{Emission, Material};
use crate::shape::LightSample;
use glam::{Vec2, Vec3, Vec3A};

/// Marks a primitive that is not in the light table.
pub const NO_LIGHT: u32 = u32::MAX;

/// Emissive primitives that next-event estimation samples.
#[derive(Default, Debug)]
pub struct LightTable {
    /// Primitive index of each light.
    pub prims: Vec<u32>,
    /// Probability of picking each light.
    pub pmf: Vec<f32>,
    cdf: Vec<f32>,
    /// For each primitive, its light index or [`NO_LIGHT`].
    pub light_of_prim: Vec<u32>,
    /// Each light as a [`QuadLight`] (indexed like `prims`) where it is a quad, in scenes where
    /// nothing moves: the integrator samples those across lanes.
    pub quads: Vec<Option<QuadLight>>,
}

/// A quad light as plain numbers, for sampling many points at once: what
/// [`crate::shape::quad::Quad::sample_solid_angle`] reads when it samples by area, and the
/// light's emission (without textures). Computed with the same operations as the quad's own
/// methods, so that a lane-wise sampler reproduces their bits.
#[derive(Clone, Copy, Debug)]
pub struct QuadLight {
    /// Corner.
    pub q: [f32; 3],
    /// Edges.
    pub u: [f32; 3],
    /// Second edge.
    pub v: [f32; 3],
    /// Unit normal.
    pub n: [f32; 3],
    /// `q + 0.5 (u + v)`, where the spherical-rectangle bound measures from.
    pub center: [f32; 3],
    /// Area.
    pub area: f32,
    /// `1 / area`.
    pub inv_area: f32,
    /// Error bound of its points.
    pub err: f32,
    /// The edges are perpendicular: points close to the light take the spherical rectangle.
    pub rect: bool,
    /// Emitted radiance.
    pub emit: [f32; 3],
    /// Emits on both sides.
    pub two_sided: bool,
}

impl LightTable {
    /// Collects the emitters of `geometry`.
    pub fn build(geometry: &Geometry, materials: &[Material]) -> Self {
        let mut t = LightTable { light_of_prim: vec![NO_LIGHT; geometry.prims.len()], ..Default::default() };
        let mut power = Vec::new();
        for (i, (prim, &m)) in geometry.prims.iter().zip(&geometry.material).enumerate() {
            let Some(Emission { emit, two_sided }) = materials[m as usize].emission() else {
                continue;
            };
            let area = match prim {
                Primitive::Sphere(s) => s.area(),
                Primitive::Quad(q) => q.area,
                Primitive::TransformedSphere(s) => s.area(),
                Primitive::Triangle(t) => t.area(),
            };
            let p = luminance(emit) * area * if two_sided { 2.0 } else { 1.0 };
            if p > 0.0 {
                t.light_of_prim[i] = t.prims.len() as u32;
                t.prims.push(i as u32);
                power.push(p);
            }
        }
        let total: f32 = power.iter().sum();
        let mut acc = 0.0;
        for p in power {
            t.pmf.push(p / total);
            acc += p / total;
            t.cdf.push(acc);
        }
        if let Some(last) = t.cdf.last_mut() {
            *last = 1.0;
        }
        let still = geometry.velocity.is_none();
        t.quads = t
            .prims
            .iter()
            .map(|&prim| {
                let emission = materials[geometry.material[prim as usize] as usize].emission();
                match (&geometry.prims[prim as usize], emission) {
                    (Primitive::Quad(q), Some(Emission { emit, two_sided })) if still => {
                        Some(q.light(emit.to_array(), two_sided))
                    }
                    _ => None,
                }
            })
            .collect();
        t
    }

    /// True when there is nothing to sample.
    pub fn is_empty(&self) -> bool {
        self.prims.is_empty()
    }

    /// Picks a light with `u` in [0, 1): (light index, probability).
    #[inline]
    pub fn pick(&self, u: f32) -> (usize, f32) {
        let i = self.cdf.partition_point(|&c| c <= u).min(self.cdf.len() - 1);
        (i, self.pmf[i])
    }

    /// Samples a point on light `light`, where it is at `time`, as seen from `from`.
    #[inline]
    pub fn sample(&self, geometry: &Geometry, light: usize, from: Vec3A, u: Vec2, time: f32) -> LightSample {
        let prim = self.prims[light];
        // A moving light is sampled at rest, from where `from` is relative to it.
        let off = geometry.offset(prim, time);
        let from = from - off;
        let mut ls = match &geometry.prims[prim as usize] {
            Primitive::Sphere(s) => s.sample_solid_angle(from, u),
            Primitive::Quad(q) => q.sample_solid_angle(from, u),
            Primitive::TransformedSphere(s) => s.sample_solid_angle(from, u),
            Primitive::Triangle(t) => t.sample_solid_angle(from, u),
        };
        ls.p += off;
        ls
    }

    /// Solid-angle density (including the pick probability) with which NEE from `from` at `time`
    /// would have produced the point `p` (normal `n`) on primitive `prim`; 0 for unsampled
    /// emitters.
    #[inline]
    pub fn pdf(&self, geometry: &Geometry, prim: u32, from: Vec3A, p: Vec3A, n: Vec3A, time: f32) -> f32 {
        // Instance hits (prim out of range) are never sampled.
        let light = self.light_of_prim.get(prim as usize).copied().unwrap_or(NO_LIGHT);
        if light == NO_LIGHT {
            return 0.0;
        }
        let off = geometry.offset(prim, time);
        let (from, p) = (from - off, p - off);
        let pdf = match &geometry.prims[prim as usize] {
            Primitive::Sphere(s) => s.pdf_solid_angle(from, p, n),
            Primitive::Quad(q) => q.pdf_solid_angle(from, p),
            Primitive::TransformedSphere(s) => s.pdf_solid_angle(from, p, n),
            Primitive::Triangle(t) => t.pdf_solid_angle(from, p),
        };
        pdf * self.pmf[light as usize]
    }
}

/// Rec. 709 luminance of a linear RGB colour.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}
