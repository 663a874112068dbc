//! The flat, read-only scene that integrators render: extracted from the ECS world after the
//! systems have run, never queried in a hot loop.

use crate::accel::geometry::{Geometry, Hit};
use crate::accel::instances::Instances;
use crate::accel::queue::Aggregate;
use crate::camera::Camera;
use crate::lighting::area::AreaEmission;
use crate::lighting::environment::{EnvPdf, EnvSample, EnvironmentMap};
use crate::lighting::light_paths::LightPaths;
use crate::lighting::lights::{BackgroundSampling, LightTable};
use crate::material::Material;
use crate::material::wrap::{self, Amount, Resolved, Tilt, Wrapper, Wrappers, mix_lambertian};
use crate::math::Ray;
use crate::media::Media;
pub use crate::scene::SamplerKind;
use crate::shape::SurfacePoint;
use crate::texture::{MaterialTextures, Textures, scalar};
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

    /// Whether image pixel (x, y) is in the window.
    #[inline]
    pub fn contains(&self, x: u32, y: u32) -> bool {
        x.wrapping_sub(self.x0) < self.w && y.wrapping_sub(self.y0) < self.h
    }

    /// The window grown by `margin` pixels on every side, within an image `width` x `height`.
    pub fn grown(&self, margin: u32, width: u32, height: u32) -> Self {
        let (x0, y0) = (self.x0.saturating_sub(margin), self.y0.saturating_sub(margin));
        let (x1, y1) = ((self.x0 + self.w + margin).min(width), (self.y0 + self.h + margin).min(height));
        Self { x0, y0, w: x1.max(x0) - x0, h: y1.max(y0) - y0 }
    }

    /// The pixels of both windows (empty where they do not meet).
    pub fn meet(&self, o: &Self) -> Self {
        let (x0, y0) = (self.x0.max(o.x0), self.y0.max(o.y0));
        let x1 = (self.x0 + self.w).min(o.x0 + o.w);
        let y1 = (self.y0 + self.h).min(o.y0 + o.h);
        Self { x0, y0, w: x1.max(x0) - x0, h: y1.max(y0) - y0 }
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
    /// Where in the image a pixel's samples land (the box: uniform over the pixel).
    pub filter: crate::filter::PixelFilter,
    /// How next-event estimation chooses a light.
    pub light_sampler: crate::scene::LightSamplerKind,
    /// Whether the render learns a guide first ([`RenderScene::guide`]).
    pub guiding: crate::guiding::Guiding,
    /// Whether light tracing takes punctual lights' caustics ([`RenderScene::light_paths`]).
    pub light_tracing: crate::lighting::light_paths::LightTracing,
}

impl std::str::FromStr for SamplerKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        crate::format::by_name(&Self::NAMES, s, "sampler")
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

    /// Whether next-event estimation samples it as a light.
    #[inline]
    pub fn sampling(&self) -> BackgroundSampling {
        match *self {
            Background::Constant(c) if c != Vec3::ZERO => BackgroundSampling::Alone,
            Background::Sky { bottom, top } if bottom != Vec3::ZERO || top != Vec3::ZERO => {
                BackgroundSampling::Alone
            }
            Background::Constant(_) | Background::Sky { .. } => BackgroundSampling::Never,
            Background::Environment(ref map) if map.sampler(EnvPdf::Complete).is_some() => {
                BackgroundSampling::Always
            }
            Background::Environment(_) => BackgroundSampling::Never,
        }
    }

    /// A direction sampled from `u` (see [`Self::sampling`]), its radiance and density.
    ///
    /// The density is for next-event estimation weighted by MIS against BSDF or phase sampling,
    /// which every caller does (the integrators' surface and medium vertices): it leaves some
    /// directions with radiance to that sampling, a sky's lower half ([`Self::smooth_sample`])
    /// and a map's directions no brighter than its mean ([`EnvPdf::Compensated`]). An estimator
    /// that sampled the background alone would need the map's [`EnvPdf::Complete`] density.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<EnvSample> {
        match self {
            Background::Constant(c) => Self::smooth_sample(*c, *c, [u.x, u.y]),
            Background::Sky { bottom, top } => Self::smooth_sample(*bottom, *top, [u.x, u.y]),
            Background::Environment(map) => map.sample(u, EnvPdf::Compensated),
        }
    }

    /// [`Self::radiance`] and [`Self::pdf`] of one direction (a map looks it up once).
    #[inline]
    pub fn radiance_pdf(&self, dir: Vec3A) -> (Vec3, f32) {
        match self {
            Background::Environment(map) => map.radiance_pdf(dir, EnvPdf::Compensated),
            _ => (self.radiance(dir), self.pdf(dir)),
        }
    }

    /// The solid-angle density with which [`Self::sample`] gives `dir` (for MIS only, as
    /// there).
    #[inline]
    pub fn pdf(&self, dir: Vec3A) -> f32 {
        match self {
            Background::Constant(_) | Background::Sky { .. } => {
                (dir.y / dir.length()).max(0.0) * std::f32::consts::FRAC_1_PI
            }
            Background::Environment(map) => map.pdf(dir, EnvPdf::Compensated),
        }
    }

    /// The light sample of a constant or sky background (`bottom == top` for a constant):
    /// a direction cosine-weighted about the zenith (+y), density `y / pi`, drawn with the
    /// branch-free concentric map so that the lanes of
    /// the integrator compute the same bits. The zenith cosine is the distribution of the light
    /// a horizontal surface receives from the upper half: skies light the ground, which hides
    /// the lower half. Directions below the horizon are left to BSDF sampling (MIS weight 1
    /// there). On spheres-sky at 64 spp it cut relMSE by 19%, where a uniform density over the
    /// sphere cut it by 11% and a mixture of the two by 13-15% (benches/results/sampling.md).
    /// `None` at the disk's rim (density 0).
    #[inline(always)]
    pub fn smooth_sample(bottom: Vec3, top: Vec3, u: [f32; 2]) -> Option<EnvSample> {
        let (dir, radiance, pdf) = Self::smooth_sample_lane(bottom, top, u);
        (pdf > 0.0).then(|| EnvSample { dir: dir.into(), radiance, pdf })
    }

    /// [`Self::smooth_sample`] as plain numbers, branch-free (density 0 at the rim).
    #[inline(always)]
    pub fn smooth_sample_lane(bottom: Vec3, top: Vec3, u: [f32; 2]) -> (Vec3, Vec3, f32) {
        let (x, z) = crate::math::disk_branch_free(u);
        let y = (1.0 - (x * x + z * z)).max(0.0).sqrt();
        // `radiance`'s blend (a unit direction: no division by its length).
        let a = 0.5 * (y + 1.0);
        let radiance = Vec3::new(
            bottom.x + (top.x - bottom.x) * a,
            bottom.y + (top.y - bottom.y) * a,
            bottom.z + (top.z - bottom.z) * a,
        );
        (Vec3::new(x, y, z), radiance, y * std::f32::consts::FRAC_1_PI)
    }
}

/// The most surfaces with a null lobe that [`RenderScene::null_transmittance`] looks past.
pub const MAX_NULL_CROSSINGS: u32 = 256;

/// What the scene contains, so that integrators pick code specialised for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Features {
    /// Some volume holds a medium: rays sample free-flight distances and shadow rays
    /// transmittance. Off, no medium code runs.
    pub media: bool,
    /// Something (or the camera) moves while the shutter is open: camera rays sample a time.
    /// Off, every ray is at the shutter's opening and no time is drawn.
    pub motion: bool,
    /// Some material that a primitive uses takes a colour or a number from a texture or the
    /// surface's tangent (an anisotropic one), or some emitting surface its radiance. Off,
    /// materials and emission are used as they are.
    pub textures: bool,
    /// Some surface both emits and reflects (an object's `emit` over a material that is not an
    /// emitter): its hits add the emission and shade. Off, only emitters emit, and their
    /// paths end there.
    pub emitting_surfaces: bool,
    /// Some mesh is instanced: rays also traverse the TLAS. Off, only the primitive BVH (or
    /// the flat lists of small scenes) is traced.
    pub instances: bool,
    /// Some surface's material is one-sided ([`Material::one_sided`]): hits on it from behind
    /// end their paths. Off, the Lambertian stage looks at no side.
    pub one_sided: bool,
    /// Some surface's material has a null lobe ([`Material::has_null_lobe`], a thin
    /// dielectric, or a mask): shadow rays that something blocks look past such surfaces
    /// ([`RenderScene::null_transmittance`]). Off, any surface blocks them.
    pub null_surfaces: bool,
    /// Some surface's material is a wrapper (a mask, a blend: [`crate::material::wrap`]): hits
    /// are resolved to a plain material ([`RenderScene::resolve`]) before they are shaded.
    /// Off, a hit's material id is its material's.
    pub wrappers: bool,
    /// Some wrapper is a bump or normal map: resolving may tilt a hit's shading normal
    /// ([`SurfacePoint::ns`] apart from [`SurfacePoint::ns_base`]), and shading then judges
    /// directions by both and weighs them by [`crate::material::wrap::terminator_shadowing`].
    /// Off, the two normals are one.
    pub tilts: bool,
}

impl Features {
    /// Detects the features of extracted geometry.
    pub fn detect(geometry: &Geometry, instances: &Instances, media: &Media, camera: &Camera) -> Self {
        Self {
            media: !media.is_empty(),
            motion: (geometry.velocity.is_some() || !instances.still() || media.moving() || camera.moves())
                && camera.shutter.0 != camera.shutter.1,
            textures: false,
            emitting_surfaces: false,
            instances: !instances.is_empty(),
            one_sided: false,
            null_surfaces: false,
            wrappers: false,
            tilts: false,
        }
    }

    /// Sets `textures`, `emitting_surfaces`, `one_sided`, `null_surfaces`, `wrappers` and `tilts` from
    /// what the primitives' material ids use, and the materials the wrappers among them name:
    /// their materials, their textured colours (`per_material`), their emission (`emission`)
    /// and their wrappers (`wrappers`, all indexed like `materials`).
    pub fn with_materials(
        mut self,
        geometry: &Geometry,
        instances: &Instances,
        materials: &[Material],
        per_material: &[MaterialTextures],
        emission: &[Option<AreaEmission>],
        wrappers: &Wrappers,
    ) -> Self {
        let mut used = vec![false; per_material.len()];
        for &m in geometry.material.iter().chain(instances.list.iter().map(|i| &i.material)) {
            used[m as usize] = true;
        }
        wrappers.mark_wrapped(&mut used);
        let used = |id: &usize| used[*id];
        let wrapper = |id: usize| wrappers.get(id as u32);
        let textured = |id: usize| {
            per_material[id].any()
                || emission[id].is_some_and(|e| e.texture.is_some())
                || wrapper(id).is_some_and(|w| w.textured())
        };
        self.textures = (0..per_material.len()).filter(used).any(textured);
        self.wrappers = (0..materials.len()).filter(used).any(|id| wrapper(id).is_some());
        self.tilts =
            (0..materials.len()).filter(used).any(|id| matches!(wrapper(id), Some(Wrapper::Tilt { .. })));
        self.emitting_surfaces = (0..materials.len())
            .filter(used)
            .any(|id| emission[id].is_some() && !materials[id].is_emissive());
        self.one_sided = (0..materials.len()).filter(used).any(|id| materials[id].one_sided());
        // A wrapper's entry copies a material it names (used too), so only masks add to it.
        let mask = |id: usize| matches!(wrapper(id), Some(Wrapper::Mask { .. }));
        self.null_surfaces = (0..materials.len())
            .filter(used)
            .any(|id| if wrapper(id).is_some() { mask(id) } else { materials[id].has_null_lobe() });
        self
    }
}

/// Everything an integrator needs, in flat arrays (its large parts shared: a clone is cheap).
#[derive(Clone)]
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
    /// For each primitive of [`Self::geometry`], its object's place in the scene file's
    /// `objects` (`u32::MAX` for one spawned without a place), for what a user reads.
    pub objects: Arc<Vec<u32>>,
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
    /// Per material: whether a hit changes it ([`Self::material_at`] evaluates textures, sets
    /// the tangent or mixes its Lambertians); the others are read in place, in scenes with
    /// textures too ([`RenderScene::varying_materials`]).
    pub varies: Vec<bool>,
    /// Per material: its wrapper, for the ids of wrappers (see [`Features::wrappers`]).
    pub wrappers: Arc<Wrappers>,
    /// The distribution of incident light that Lambertian vertices draw part of their
    /// directions from (path guiding), once trained; `None` renders without.
    pub guide: Option<Arc<crate::guiding::Guide>>,
    /// Light tracing's lights, where it takes caustics' paths (planned where the world makes
    /// the scene); `None` renders every path by path tracing.
    pub light_paths: Option<Arc<LightPaths>>,
}

impl RenderScene {
    /// The surfaces as ray queries see them: one ray at a time, or a queue of them.
    #[inline(always)]
    pub fn aggregate(&self) -> Aggregate<'_> {
        Aggregate {
            geometry: &self.geometry,
            instances: self.features.instances.then_some(&*self.instances),
            uv: self.features.textures,
        }
    }

    /// Closest hit with `t` in `(0, tmax)` among primitives and instances.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmax: f32) -> Option<Hit> {
        self.aggregate().intersect(ray, tmax)
    }

    /// True when a primitive or an instance lies on the ray with `t` in `(0, tmax)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, tmax: f32) -> bool {
        self.aggregate().occluded(ray, tmax)
    }

    /// The fraction of light that gets along the shadow ray `ray` (from its origin to `t = 1`)
    /// through the surfaces on it, each letting through its [`Material::null_transmission`]
    /// (most let nothing through, a thin dielectric 1 - R'), as Mitsuba's volumetric path
    /// tracer looks past null lobes. A ray that crosses more than [`MAX_NULL_CROSSINGS`]
    /// surfaces counts as blocked.
    #[inline(never)]
    pub fn null_transmittance(&self, ray: &Ray) -> f32 {
        let target = ray.origin + ray.dir;
        let mut tr = 1.0f32;
        let mut r = *ray;
        for _ in 0..MAX_NULL_CROSSINGS {
            let Some(h) = self.intersect(&r, 1.0) else { return tr };
            let sp = &h.surface;
            let d = r.dir.normalize();
            tr *= match self.features.wrappers {
                false => self.material_at(h.material, sp).null_transmission(d.dot(sp.ns)),
                true => self.wrapped_transmission(h.material, sp, d.dot(sp.ns)),
            };
            if !(tr > 0.0) {
                return 0.0;
            }
            let side = if d.dot(sp.n) > 0.0 { sp.n } else { -sp.n };
            let origin = crate::math::offset_ray_origin(sp.p, sp.err, side);
            r = Ray { origin, dir: target - origin, time: r.time };
        }
        0.0
    }

    /// [`Wrappers::transmission`] of material `id` at `sp` for a shadow ray at `cos` from the
    /// shading normal (kept out of line: scenes without wrappers never call it).
    #[inline(never)]
    fn wrapped_transmission(&self, id: u32, sp: &SurfacePoint, cos: f32) -> f32 {
        let amount = |a| self.amount(a, sp);
        let plain = |id| self.material_at(id, sp).null_transmission(cos);
        self.wrappers.transmission(id, &amount, &plain)
    }

    /// An opacity or a weight of a wrapper at `sp`: a texture's luminance (Mitsuba's float
    /// read of an RGB texture), clamped to [0, 1].
    #[inline]
    pub fn amount(&self, a: Amount, sp: &SurfacePoint) -> f32 {
        match a {
            Amount::Value(v) => v,
            Amount::Texture(t) => {
                let c = self.textures.at(t, sp, &self.instances.blas);
                (0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z).clamp(0.0, 1.0)
            }
        }
    }

    /// Follows the material of a hit at `sp` with id `id`, seen from the unit direction `wo`,
    /// through its wrappers ([`Wrappers::resolve`], `u(level)` the number of the `level`-th
    /// wrapper that draws one); a bump or normal map on the way tilts `sp.ns` ([`Self::tilt`]).
    /// Call only when [`Features::wrappers`] is on.
    #[inline(never)]
    pub fn resolve(&self, id: u32, sp: &mut SurfacePoint, wo: Vec3A, u: impl FnMut(u32) -> f32) -> Resolved {
        let at = *sp;
        let mut tilted = None;
        let resolved = self.wrappers.resolve(
            id,
            |a| self.amount(a, &at),
            u,
            |map, flip| {
                tilted = self.tilt(&at, map, flip, wo);
            },
        );
        if let Some(ns) = tilted {
            sp.ns = ns;
        }
        resolved
    }

    /// The shading normal that `map` gives at `sp` (seen from `wo`, turned towards it if
    /// `flip`: [`wrap::flip_invalid`]), `None` where it gives none (a surface without
    /// derivatives under a bump map, a degenerate value).
    fn tilt(&self, sp: &SurfacePoint, map: Tilt, flip: bool, wo: Vec3A) -> Option<Vec3A> {
        let derivatives = self.derivatives(sp);
        let n = match map {
            Tilt::Bump { heights, scale } => {
                let (dpdu, dpdv) = derivatives?;
                let dh = scale * self.textures.gradient(heights, sp);
                wrap::bump_normal(sp.n, sp.ns, dpdu, dpdv, dh)?
            }
            Tilt::Normals { normals } => {
                let code = self.textures.at(normals, sp, &self.instances.blas);
                wrap::normal_map_normal(sp.ns, derivatives.map(|d| d.0), code)?
            }
        };
        Some(if flip { wrap::flip_invalid(sp.ns, n, wo) } else { n })
    }

    /// [`Self::varies`] of the materials with these texture slots and wrappers.
    pub fn varying_materials(per_material: &[MaterialTextures], wrappers: &Wrappers) -> Vec<bool> {
        let mix = |id: usize| matches!(wrappers.get(id as u32), Some(Wrapper::LambertianMix { .. }));
        per_material.iter().enumerate().map(|(id, slots)| slots.any() || mix(id)).collect()
    }

    /// Whether material `id` is changed by the hit it is met at (see [`Self::varies`]).
    #[inline(always)]
    fn changes_at_hits(&self, id: usize) -> bool {
        self.features.textures && self.varies[id]
    }

    /// Material `id` with its textured colours evaluated at `sp`.
    #[inline(always)]
    pub fn material_at(&self, id: u32, sp: &SurfacePoint) -> Material {
        let id = id as usize;
        if !self.changes_at_hits(id) {
            return self.materials[id];
        }
        self.textured_material(id, sp)
    }

    /// `f` of material `id` with its textured colours evaluated at `sp`: without textures `f`
    /// reads the material in place, where [`Self::material_at`] copies it out (the copy goes
    /// through the stack; see [`Self::albedo_at`]).
    #[inline(always)]
    pub fn with_material<R>(&self, id: u32, sp: &SurfacePoint, f: impl FnOnce(&Material) -> R) -> R {
        match self.changes_at_hits(id as usize) {
            false => f(&self.materials[id as usize]),
            true => f(&self.textured_material(id as usize, sp)),
        }
    }

    /// The reflectance ([`Material::albedo`]) of material `id` at `sp`. Without textures it is
    /// read in place: copying the material out first cost the Lambertian stage 3% (the copy
    /// went through the stack, and its read-back stalled store forwarding).
    #[inline(always)]
    pub fn albedo_at(&self, id: u32, sp: &SurfacePoint) -> Vec3 {
        match self.changes_at_hits(id as usize) {
            false => self.materials[id as usize].albedo(),
            true => self.textured_material(id as usize, sp).albedo(),
        }
    }

    /// The radiance that a surface of material `id` emits at `sp` towards a direction making
    /// cosine `cos_out` with its geometric normal (zero for surfaces that do not emit).
    #[inline]
    pub fn emitted(&self, id: u32, sp: &SurfacePoint, cos_out: f32) -> Vec3 {
        match &self.lights.emission[id as usize] {
            Some(e) => e.emitted(&self.textures, cos_out, || *sp),
            None => Vec3::ZERO,
        }
    }

    /// [`Self::material_at`] for scenes with textures (kept out of line).
    #[inline(never)]
    fn textured_material(&self, id: usize, sp: &SurfacePoint) -> Material {
        if self.features.wrappers
            && let Some(Wrapper::LambertianMix { weight, materials: [a, b] }) = self.wrappers.get(id as u32)
        {
            let (a, b) = (self.textured_material(a as usize, sp), self.textured_material(b as usize, sp));
            return mix_lambertian(&a, &b, self.amount(weight, sp)).expect("a mix of Lambertians");
        }
        let mut m = self.materials[id];
        let slots = &self.material_textures[id];
        for (slot, t) in slots.colors.iter().enumerate() {
            if let Some(t) = *t {
                m.set_color(slot, self.textures.at(t, sp, &self.instances.blas));
            }
        }
        for (slot, t) in slots.scalars.iter().enumerate() {
            if let Some(t) = *t {
                m.set_scalar(slot, scalar(self.textures.at(t, sp, &self.instances.blas)));
            }
        }
        if slots.tangent
            && let Some((dpdu, _)) = self.derivatives(sp)
        {
            m.set_tangent(sp.ns, crate::material::wrap::base_tangent(sp, dpdu));
        }
        m
    }

    /// The surface's `(dp/du, dp/dv)` at a hit: a placed mesh's, or a primitive's that gives
    /// them.
    fn derivatives(&self, sp: &SurfacePoint) -> Option<(Vec3A, Vec3A)> {
        match sp.on.instance {
            u32::MAX => self.geometry.prims.get(sp.on.triangle as usize)?.derivatives(sp),
            _ => self.instances.derivatives(sp),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::chi2::{chi2, chi2_critical};

    const SKY: Background = Background::Sky { bottom: Vec3::ONE, top: Vec3::new(0.5, 0.7, 1.0) };

    /// The sky's light samples follow their density (chi-square over the whole sphere), and
    /// carry the radiance and density the escape of a BSDF-sampled ray sees in their direction.
    #[test]
    fn sky_samples_match_their_density_and_radiance() {
        let (stat, dof) =
            chi2(|u, _| SKY.sample(u).map(|s| s.dir), |d| SKY.pdf(d), Vec3A::Y, -1.0, 1_000_000);
        assert!(stat < chi2_critical(dof), "chi2 {stat} dof {dof}");
        for k in 0..10_000 {
            let u = Vec2::new((k % 100) as f32 / 100.0 + 0.004, (k / 100) as f32 / 100.0 + 0.002);
            let s = SKY.sample(u).expect("inside the disk");
            let (le, pdf) = SKY.radiance_pdf(s.dir);
            assert!((s.radiance - le).abs().max_element() < 1e-6, "{u}");
            assert!((s.pdf - pdf).abs() < 1e-6 * pdf.max(1.0), "{u}");
        }
        // Black backgrounds are not lights; smooth ones are when alone; maps always.
        assert_eq!(Background::Constant(Vec3::ZERO).sampling(), BackgroundSampling::Never);
        assert_eq!(Background::Constant(Vec3::splat(0.1)).sampling(), BackgroundSampling::Alone);
        assert_eq!(SKY.sampling(), BackgroundSampling::Alone);
    }

    /// Light sampling integrates the sky's irradiance on an upward surface exactly: the
    /// estimate of `integral L cos` over the upper half is `pi (bottom / 6 + 5 top / 6)`.
    #[test]
    fn sky_samples_integrate_its_irradiance() {
        let (bottom, top) = (Vec3::ONE, Vec3::new(0.5, 0.7, 1.0));
        let n = 512;
        let mut sum = glam::DVec3::ZERO;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                if let Some(s) = SKY.sample(u) {
                    sum += (s.radiance * s.dir.y / s.pdf).as_dvec3();
                }
            }
        }
        let estimate = (sum / (n * n) as f64).as_vec3();
        let exact = std::f32::consts::PI * (bottom / 6.0 + top * (5.0 / 6.0));
        assert!((estimate - exact).abs().max_element() < 1e-4 * exact.max_element(), "{estimate} vs {exact}");
    }
}
