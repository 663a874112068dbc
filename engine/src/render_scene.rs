//! The flat, read-only scene that integrators render: extracted from the ECS world after the
//! systems have run, never queried in a hot loop.

use crate::camera::Camera;
use crate::environment::{EnvSample, EnvironmentMap};
use crate::geometry::{Geometry, Hit};
use crate::instances::Instances;
use crate::lights::LightTable;
use crate::material::Material;
use crate::math::Ray;
use crate::media::Media;
use crate::shape::SurfacePoint;
use crate::texture::{MaterialTextures, Textures};
use glam::{Vec2, Vec3, Vec3A};
use std::sync::Arc;

/// A rectangle of pixels: columns `x0..x0 + w`, rows `y0..y0 + h`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelWindow {
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// Width (>= 1).
    pub w: u32,
    /// Height (>= 1).
    pub h: u32,
}

impl PixelWindow {
    /// The crop window `(x0, x1, y0, y1)`, fractions of the image as pbrt-v4's `cropwindow`
    /// (pixels from `ceil(x0 width)` up to `ceil(x1 width)`, the same for rows); `None` when it
    /// holds no pixel.
    pub fn crop(width: u32, height: u32, [x0, x1, y0, y1]: [f32; 4]) -> Option<Self> {
        // In f32, as pbrt-v4 computes it: 0.1 * 40 rounds to 4 exactly (in f64 it is above 4).
        let px = |f: f32, n: u32| ((f * n as f32).ceil() as u32).min(n);
        let (a, b, c, d) = (px(x0, width), px(x1, width), px(y0, height), px(y1, height));
        (b > a && d > c).then_some(Self { x0: a, y0: c, w: b - a, h: d - c })
    }

    /// The index of image pixel (x, y) in a film of this window (row-major).
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        ((y - self.y0) * self.w + (x - self.x0)) as usize
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.w as usize * self.h as usize
    }

    /// True when it holds no pixel (never, for a window made by [`Self::crop`]).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Image size and sampling settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Width in pixels (of the whole image: the camera's).
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The pixels to render: the crop window, or the whole image. Films and the images
    /// written have its size; every pixel has the bits it has in the whole image.
    pub window: PixelWindow,
    /// Samples per pixel.
    pub spp: u32,
    /// Maximum number of bounces.
    pub max_depth: u32,
    /// Bounces before Russian roulette may end a path.
    pub rr_depth: u32,
    /// Seed of all random numbers.
    pub seed: u64,
    /// Largest sample component before scaling down (None: no clamping, unbiased).
    pub clamp: Option<f32>,
    /// How the random numbers of the samples are made.
    pub sampler: SamplerKind,
}

/// How the samples' random numbers are made (see the integrator's `sampler` module).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize)]
pub enum SamplerKind {
    /// Owen-scrambled Sobol in every 1D and 2D dimension (extensible: the first N samples of a
    /// pixel are those of an N-spp render).
    #[default]
    Sobol,
    /// Correlated multi-jittered in every 2D dimension, jittered strata in every 1D one (the
    /// pattern depends on the sample count).
    Stratified,
    /// Independent uniform numbers.
    Independent,
}

impl SamplerKind {
    /// The names, as the command line and scene files spell them.
    pub const NAMES: [(&'static str, SamplerKind); 3] = [
        ("sobol", SamplerKind::Sobol),
        ("stratified", SamplerKind::Stratified),
        ("independent", SamplerKind::Independent),
    ];
}

impl std::str::FromStr for SamplerKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::NAMES
            .iter()
            .find(|(n, _)| *n == s)
            .map(|&(_, k)| k)
            .ok_or_else(|| format!("no sampler '{s}': there are sobol, stratified and independent"))
    }
}

/// Radiance arriving from outside the scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Background {
    /// The same radiance in every direction (black is `Constant(0)`).
    Constant(Vec3),
    /// `(1 - a) * bottom + a * top`, `a = 0.5 * (dir.y + 1)`.
    Sky {
        /// Radiance straight down.
        bottom: Vec3,
        /// Radiance straight up.
        top: Vec3,
    },
    /// A lat-long HDR map, sampled as a light.
    Environment(Arc<EnvironmentMap>),
}

impl Background {
    /// Radiance arriving along `-dir` (seen by a ray travelling along `dir`).
    #[inline]
    pub fn radiance(&self, dir: Vec3A) -> Vec3 {
        match *self {
            Background::Constant(c) => c,
            Background::Sky { bottom, top } => {
                let a = 0.5 * (dir.y / dir.length() + 1.0);
                bottom.lerp(top, a)
            }
            Background::Environment(ref map) => map.radiance(dir),
        }
    }

    /// True when it is sampled as a light: environment maps. Constant and sky backgrounds are
    /// smooth enough for BSDF sampling alone (sampling the sky gradient as a light cut
    /// spheres-sky's relMSE by 10% for 78% more time; see benches/RESULTS.md).
    #[inline]
    pub fn is_sampled(&self) -> bool {
        match self {
            Background::Constant(_) | Background::Sky { .. } => false,
            Background::Environment(map) => map.sampler().is_some(),
        }
    }

    /// A direction sampled from `u` (see [`Self::is_sampled`]), its radiance and density.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<EnvSample> {
        match self {
            Background::Constant(_) | Background::Sky { .. } => None,
            Background::Environment(map) => map.sample(u),
        }
    }

    /// [`Self::radiance`] and [`Self::pdf`] of one direction (a map looks it up once).
    #[inline]
    pub fn radiance_pdf(&self, dir: Vec3A) -> (Vec3, f32) {
        match self {
            Background::Environment(map) => map.radiance_pdf(dir),
            _ => (self.radiance(dir), 0.0),
        }
    }

    /// The solid-angle density with which [`Self::sample`] gives `dir`.
    #[inline]
    pub fn pdf(&self, dir: Vec3A) -> f32 {
        match self {
            Background::Constant(_) | Background::Sky { .. } => 0.0,
            Background::Environment(map) => map.pdf(dir),
        }
    }
}

/// What the scene contains, so that integrators pick code specialised for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Features {
    /// Some volume holds a medium: rays sample free-flight distances and shadow rays
    /// transmittance. Off, no medium code runs.
    pub media: bool,
    /// Something (or the camera) moves while the shutter is open: camera rays sample a time.
    /// Off, every ray is at the shutter's opening and no time is drawn.
    pub motion: bool,
    /// Some material that a primitive uses takes a colour from a texture. Off, materials are
    /// used as they are.
    pub textures: bool,
    /// Some mesh is instanced: rays also traverse the TLAS. Off, only the primitive BVH (or
    /// the flat lists of small scenes) is traced.
    pub instances: bool,
}

impl Features {
    /// Detects the features of extracted geometry.
    pub fn detect(geometry: &Geometry, instances: &Instances, media: &Media, camera: &Camera) -> Self {
        Self {
            media: !media.is_empty(),
            motion: (geometry.velocity.is_some()
                || instances.list.iter().any(|i| i.velocity != Vec3A::ZERO || i.motion.is_some())
                || camera.moves())
                && camera.shutter.0 != camera.shutter.1,
            textures: false,
            instances: !instances.is_empty(),
        }
    }

    /// Sets `textures` from what the primitives' materials use.
    pub fn with_textures(
        mut self,
        geometry: &Geometry,
        instances: &Instances,
        per_material: &[MaterialTextures],
    ) -> Self {
        let mut used = vec![false; per_material.len()];
        for &m in geometry.material.iter().chain(instances.list.iter().map(|i| &i.material)) {
            used[m as usize] = true;
        }
        self.textures = per_material.iter().zip(&used).any(|(t, u)| *u && t.any());
        self
    }
}

/// Everything an integrator needs, in flat arrays.
pub struct RenderScene {
    /// What the scene contains.
    pub features: Features,
    /// Camera for the configured image size.
    pub camera: Camera,
    /// Image and sampling settings.
    pub settings: RenderSettings,
    /// Light from outside.
    pub background: Background,
    /// Materials indexed by the primitives' material ids.
    pub materials: Vec<Material>,
    /// Primitives and BVH.
    pub geometry: Arc<Geometry>,
    /// Mesh instances and their TLAS.
    pub instances: Arc<Instances>,
    /// Emitters for next-event estimation.
    pub lights: Arc<LightTable>,
    /// Participating media.
    pub media: Arc<Media>,
    /// Textures.
    pub textures: Arc<Textures>,
    /// Per material: which colours come from textures.
    pub material_textures: Vec<MaterialTextures>,
}

impl RenderScene {
    /// Closest hit with `t` in `(0, tmax)` among primitives and instances.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmax: f32) -> Option<Hit> {
        let hit = self.geometry.intersect_uv(ray, tmax, self.features.textures);
        if !self.features.instances {
            return hit;
        }
        self.instances.intersect(ray, hit.map_or(tmax, |h| h.t)).or(hit)
    }

    /// True when a primitive or an instance lies on the ray with `t` in `(0, tmax)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, tmax: f32) -> bool {
        self.geometry.occluded(ray, tmax) || (self.features.instances && self.instances.occluded(ray, tmax))
    }

    /// Material `id` with its textured colours evaluated at `sp`.
    #[inline(always)]
    pub fn material_at(&self, id: u32, sp: &SurfacePoint) -> Material {
        let id = id as usize;
        if !self.features.textures {
            return self.materials[id];
        }
        self.textured_material(id, sp)
    }

    /// `f` of material `id` with its textured colours evaluated at `sp`: without textures `f`
    /// reads the material in place, where [`Self::material_at`] copies it out (the copy goes
    /// through the stack; see [`Self::albedo_at`]).
    #[inline(always)]
    pub fn with_material<R>(&self, id: u32, sp: &SurfacePoint, f: impl FnOnce(&Material) -> R) -> R {
        match self.features.textures {
            false => f(&self.materials[id as usize]),
            true => f(&self.textured_material(id as usize, sp)),
        }
    }

    /// The reflectance ([`Material::albedo`]) of material `id` at `sp`. Without textures it is
    /// read in place: copying the material out first cost the Lambertian stage 3% (the copy
    /// went through the stack, and its read-back stalled store forwarding).
    #[inline(always)]
    pub fn albedo_at(&self, id: u32, sp: &SurfacePoint) -> Vec3 {
        match self.features.textures {
            false => self.materials[id as usize].albedo(),
            true => self.textured_material(id as usize, sp).albedo(),
        }
    }

    /// [`Self::material_at`] for scenes with textures (kept out of line).
    #[inline(never)]
    fn textured_material(&self, id: usize, sp: &SurfacePoint) -> Material {
        let mut m = self.materials[id];
        for (slot, t) in self.material_textures[id].0.iter().enumerate() {
            if let Some(t) = *t {
                m.set_color(slot, self.textures.at(t, sp));
            }
        }
        m
    }
}
