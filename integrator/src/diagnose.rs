//! Where a render's noise comes from: the reference path tracer re-runs some of the render's
//! own samples of every pixel, with a witness ([`oracle::Witness`]) that splits each sample
//! into the contributions it added and their causes ([`Cause`]: the light, the material of the
//! vertex that found it, the bounce, and how it was found). Noise is measured as the relative
//! MSE measures error, in luminance: a pixel's variance weighted by `1 / (m^2 + 0.01)`, `m`
//! the render's mean there, so that a firefly on a dim wall counts for more than the edge of a
//! bright lamp (both white on screen). Two answers follow.
//! - Each light's and each material's share of that variance. A sample is the sum of its
//!   causes' parts, `L = sum_g X_g`, so its variance is `sum_g Cov(X_g, L)`: the shares of the
//!   groups add up to one (a part that cancels noise has a negative share).
//! - The outliers: the samples that stand out most over their pixel's mean (the top
//!   [`OUTLIER_FRACTION`] of the excesses `(L - m') / sqrt(m'^2 + 0.01)`, `m'` the mean of the
//!   render's other samples there, which a firefly has not raised), each with the cause of its
//!   largest part. A pixel that sees a light steadily has no excess; a firefly a big one.

use crate::film::clamp_sample;
use crate::oracle::{self, Source, Witness};
use crate::path;
use crate::sampler::Sampler;
use glam::{Vec3, Vec3A};
use pathwave_engine::lighting::lights::OtherLight;
use pathwave_engine::math::luminance;
use pathwave_engine::render_scene::{Background, RenderScene};
use rayon::prelude::*;
use std::collections::HashMap;
use std::ops::Range;

/// The share of the diagnosed samples counted as outliers.
pub const OUTLIER_FRACTION: f64 = 0.001;

/// A light, as a user names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Light {
    /// The surfaces of material `id` that emit.
    Emitter(u32),
    /// Point, spot or directional light `k` (in the order of the scene's lights that shine).
    Punctual(u32),
    /// The background (an environment map or a sky).
    Background,
    /// The directions of an environment map at least [`PEAK`] times its mean radiance: a sun.
    BackgroundPeak,
    /// Media that glow (their `emission`), which paths find where they scatter in them: they
    /// are not sampled as lights.
    Media,
}

impl Light {
    /// The light that entry `k` of the scene's light table belongs to (an environment map as a
    /// whole: its peak is told by direction).
    pub fn of(scene: &RenderScene, k: usize) -> Light {
        let lights = &scene.lights;
        match lights.other(k) {
            None => Light::Emitter(scene.geometry.material[lights.prims[k] as usize]),
            Some(OtherLight::Environment) => Light::Background,
            Some(OtherLight::Punctual(_)) => Light::Punctual((k - lights.prims.len()) as u32),
        }
    }
}

/// How much brighter than the map's mean a direction of an environment map must be to count
/// as its peak ([`Light::BackgroundPeak`]).
pub const PEAK: f32 = 100.0;

/// Where the path was when it found the light: at a surface of material `id`, in a medium, or
/// still on the camera's ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Vertex {
    /// The light was seen from the camera.
    Camera,
    /// A surface of this material id (the id the surface names).
    Material(u32),
    /// A medium.
    Medium,
}

/// How a path found a light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Event {
    /// Seen from the camera, or in mirrors and glass only.
    Direct,
    /// By light sampling (next-event estimation) at a vertex.
    LightSampling,
    /// Met by a direction the material sampled (MIS-weighted against light sampling).
    BsdfSampling,
    /// Met through a mirror or glass (a delta lobe) after a rough bounce: a caustic, which
    /// light sampling cannot find.
    Caustic,
}

impl Event {
    /// What a user reads.
    pub fn describe(self) -> &'static str {
        match self {
            Event::Direct => "seen directly (or in mirrors and glass only)",
            Event::LightSampling => "light sampling",
            Event::BsdfSampling => "a sampled direction met the light",
            Event::Caustic => "a caustic (through a mirror or glass after a rough bounce)",
        }
    }
}

/// What made a contribution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Cause {
    /// The light it came from.
    pub light: Light,
    /// Where the path was when it found the light (the vertex that sampled the light or the
    /// direction that met it).
    pub vertex: Vertex,
    /// Bounces before the light: 0 seen from the camera, 1 found at the first vertex, ...
    pub bounces: u32,
    /// How it was found.
    pub event: Event,
}

/// A sample that stands out over its pixel's mean.
#[derive(Clone, Copy, Debug)]
pub struct Outlier {
    /// Its weighted excess over the mean of its pixel's other samples (see the module's doc).
    pub excess: f64,
    /// Its part of [`Diagnosis::variance`].
    pub variance: f64,
    /// The cause of its largest part.
    pub cause: Cause,
}

/// What [`diagnose`] found.
#[derive(Clone, Debug, Default)]
pub struct Diagnosis {
    /// Pixels diagnosed.
    pub pixels: u64,
    /// Samples diagnosed (finite ones).
    pub samples: u64,
    /// The sum over the pixels of their samples' weighted variance (see the module's doc).
    pub variance: f64,
    /// Each light's part of [`Self::variance`].
    pub by_light: HashMap<Light, f64>,
    /// Each vertex's (material's) part of [`Self::variance`].
    pub by_vertex: HashMap<Vertex, f64>,
    /// The outliers, largest excess first.
    pub outliers: Vec<Outlier>,
}

/// Diagnoses samples `samples` of every pixel of the render window, as the render made them;
/// `mean` is the render's mean luminance of each pixel of the window (row-major), over its
/// `spp` samples (`samples` among them).
pub fn diagnose(scene: &RenderScene, samples: Range<u32>, mean: &[f32], spp: u32) -> Diagnosis {
    let w = scene.settings.window;
    assert_eq!(mean.len(), w.len(), "a mean for each pixel of the window");
    let keep = ((w.len() as f64 * samples.len() as f64 * OUTLIER_FRACTION).ceil() as usize).max(1);
    let mut d = (0..w.h)
        .into_par_iter()
        .map(|j| {
            let mut d = Diagnosis::default();
            for i in 0..w.w {
                let m = f64::from(mean[(j * w.w + i) as usize]);
                pixel(scene, w.x0 + i, w.y0 + j, samples.clone(), (m, spp), &mut d);
            }
            prune(&mut d.outliers, keep);
            d
        })
        .reduce(Diagnosis::default, |mut a, b| {
            a.pixels += b.pixels;
            a.samples += b.samples;
            a.variance += b.variance;
            for (k, v) in b.by_light {
                *a.by_light.entry(k).or_default() += v;
            }
            for (k, v) in b.by_vertex {
                *a.by_vertex.entry(k).or_default() += v;
            }
            a.outliers.extend(b.outliers);
            prune(&mut a.outliers, keep);
            a
        });
    d.outliers.sort_by(|a, b| b.excess.total_cmp(&a.excess));
    d
}

/// Keeps the `keep` largest excesses (and only positive ones).
fn prune(outliers: &mut Vec<Outlier>, keep: usize) {
    outliers.retain(|o| o.excess > 0.0);
    if outliers.len() > keep {
        outliers.select_nth_unstable_by(keep - 1, |a, b| b.excess.total_cmp(&a.excess));
        outliers.truncate(keep);
    }
}

/// One pixel's samples into `d`; `mean` is the render's mean there over `spp` samples.
fn pixel(
    scene: &RenderScene,
    x: u32,
    y: u32,
    samples: Range<u32>,
    (mean, spp): (f64, u32),
    d: &mut Diagnosis,
) {
    // Per sample: its value and the cause of its largest part; per group, the sums of its
    // parts and of its parts times the sample's value.
    let mut values: Vec<(f64, Option<Cause>)> = Vec::with_capacity(samples.len());
    let mut lights: Vec<(Light, f64, f64)> = Vec::new();
    let mut vertices: Vec<(Vertex, f64, f64)> = Vec::new();
    for index in samples {
        let (ray, tmax, sampler) = path::camera_ray(scene, x, y, index);
        let mut rec = Recorder::new(scene, &sampler);
        let l = oracle::radiance_witnessed(scene, ray, tmax, &sampler, &mut rec);
        let kept = clamp_sample(l, scene.settings.clamp);
        let value = f64::from(luminance(kept));
        if !value.is_finite() {
            continue;
        }
        // The clamp scales every part alike.
        let clamped = if luminance(l) > 0.0 { value / f64::from(luminance(l)) } else { 1.0 };
        let mut largest: Option<(f64, Cause)> = None;
        for &(part, cause) in &rec.parts {
            let part = part * clamped;
            add(&mut lights, cause.light, part, part * value);
            add(&mut vertices, cause.vertex, part, part * value);
            if largest.is_none_or(|(v, _)| part > v) {
                largest = Some((part, cause));
            }
        }
        values.push((value, largest.map(|(_, c)| c)));
    }
    let n = values.len() as f64;
    d.pixels += 1;
    d.samples += values.len() as u64;
    let sum: f64 = values.iter().map(|v| v.0).sum();
    let scale = 1.0 / (mean * mean + 0.01).sqrt();
    // A sample's part of the variance (none with a single sample).
    let weight = if n < 2.0 { 0.0 } else { scale * scale / (n - 1.0) };
    let own_mean = sum / n;
    let others = |v: f64| match spp > 1 {
        true => ((mean * spp as f64 - v) / (spp - 1) as f64).max(0.0),
        false => mean,
    };
    d.outliers.extend(values.iter().filter_map(|&(v, c)| {
        let excess = (v - others(v)) / (others(v).powi(2) + 0.01).sqrt();
        Some(Outlier { excess, variance: (v - own_mean).powi(2) * weight, cause: c? })
    }));
    let cov = |sx: f64, sxl: f64| (sxl - sx * sum / n) * weight;
    d.variance += values.iter().map(|v| (v.0 - own_mean).powi(2)).sum::<f64>() * weight;
    for (k, sx, sxl) in lights {
        *d.by_light.entry(k).or_default() += cov(sx, sxl);
    }
    for (k, sx, sxl) in vertices {
        *d.by_vertex.entry(k).or_default() += cov(sx, sxl);
    }
}

/// Adds a part and a part times its sample's value to `key`'s sums.
fn add<K: PartialEq>(sums: &mut Vec<(K, f64, f64)>, key: K, part: f64, product: f64) {
    match sums.iter_mut().find(|s| s.0 == key) {
        Some(s) => (s.1, s.2) = (s.1 + part, s.2 + product),
        None => sums.push((key, part, product)),
    }
}

/// The witness of one sample: its parts (luminance) and their causes.
struct Recorder<'a> {
    scene: &'a RenderScene,
    sampler: &'a Sampler,
    /// The last vertex: its depth, what it was, its point and shading normal.
    last: Option<(u32, Vertex, [Vec3A; 2])>,
    /// Whether some vertex scattered by a lobe that is not a delta.
    rough: bool,
    parts: Vec<(f64, Cause)>,
}

impl<'a> Recorder<'a> {
    fn new(scene: &'a RenderScene, sampler: &'a Sampler) -> Self {
        Self { scene, sampler, last: None, rough: false, parts: Vec::new() }
    }

    /// The light a vertex at `depth`, at the point and normal `at`, sampled.
    fn sampled(&self, depth: u32, at: [Vec3A; 2]) -> Light {
        Light::of(self.scene, oracle::sampled_light(self.scene, self.sampler, depth, at))
    }
}

impl Witness for Recorder<'_> {
    fn scatters(&mut self, depth: u32, at: [Vec3A; 2], material: Option<u32>, delta: bool) {
        self.last = Some((depth, material.map_or(Vertex::Medium, Vertex::Material), at));
        self.rough |= !delta;
    }

    fn adds(&mut self, l: Vec3, source: Source, dir: Vec3A, delta: bool) {
        let part = f64::from(luminance(l));
        if part == 0.0 {
            return;
        }
        let (bounces, vertex) = self.last.map_or((0, Vertex::Camera), |(d, v, _)| (d + 1, v));
        let peak = |light: Light| match (light, &self.scene.background) {
            (Light::Background, Background::Environment(map))
                if luminance(map.radiance(dir))
                    >= PEAK * map.power_estimate() / (4.0 * std::f32::consts::PI) =>
            {
                Light::BackgroundPeak
            }
            _ => light,
        };
        // How a light met along the ray was found.
        let met = match (delta, self.rough) {
            (false, _) => Event::BsdfSampling,
            (true, true) => Event::Caustic,
            (true, false) => Event::Direct,
        };
        let (light, event) = match source {
            Source::LightSample => {
                let (depth, at) = self.last.map_or((0, [Vec3A::ZERO; 2]), |(d, _, at)| (d, at));
                (self.sampled(depth, at), Event::LightSampling)
            }
            Source::ApartSample => {
                let apart = self.scene.lights.apart();
                (apart.map_or(Light::Background, |l| Light::of(self.scene, l)), Event::LightSampling)
            }
            Source::Emitter(m) => (Light::Emitter(m), met),
            Source::Background => (Light::Background, met),
            Source::Medium => (Light::Media, met),
        };
        let cause = Cause { light: peak(light), vertex, bounces, event };
        self.parts.push((part, cause));
    }
}
