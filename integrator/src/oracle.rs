//! The reference path tracer: one path at a time, recursion unrolled into a loop. It defines
//! the estimator every other integrator must match in expectation: next-event estimation on
//! every kind of light combined with BSDF sampling by MIS (power heuristic), free-flight
//! sampling in media, Russian roulette, pixel samples from the scene's sampler (Owen-scrambled
//! Sobol by default, stratified or independent: `crate::sampler`) filtered as the scene says
//! (splatted or not: `PixelFilter::splats`), rayon over tiles.

use crate::film::{Film, PixelAccumulator, PixelSums, SplatFilm, clamp_sample};
use crate::lambert_vertex;
use crate::path::{self, PathState};
use crate::sampler::Sampler;
use crate::tile;
use glam::{Vec3, Vec3A};
use pathwave_engine::material::Shading;
use pathwave_engine::math::Ray;
use pathwave_engine::render_scene::RenderScene;
use std::ops::Range;

/// Renders the whole image. `progress(done, total)` is called after each tile, from any thread.
pub fn render(scene: &RenderScene, progress: &(dyn Fn(usize, usize) + Sync)) -> Film {
    render_samples(scene, 0..scene.settings.spp, progress)
}

/// Renders the samples `samples` (indices into the scene's `spp` per pixel) of every pixel:
/// films of disjoint ranges merge into the film of their union, bit for bit.
pub fn render_samples(
    scene: &RenderScene,
    samples: Range<u32>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Film {
    let s = scene.settings;
    let _span =
        tracing::info_span!("oracle_render", width = s.width, height = s.height, spp = s.spp).entered();
    let mut film = Film::new(s.window.w, s.window.h);
    film.spp = samples.len() as u32;
    if let Some(plan) = &scene.light_paths {
        film.light = Some(crate::light_tracer::trace(scene, plan, samples.clone()));
    }
    if let Some(filter) = s.filter.splat() {
        tile::splat_tiles(
            &s.window,
            (s.width, s.height),
            s.filter.margin(),
            &mut film.pixels,
            progress,
            || (),
            |_, tile, rect| {
                let mut sums = SplatFilm::new(filter, *rect);
                for i in 0..tile.len() {
                    let (x, y) = tile.pixel(i);
                    for k in samples.clone() {
                        let (ray, tmax, sampler) = path::camera_ray(scene, x, y, k);
                        let l = clamp_sample(radiance(scene, ray, tmax, &sampler), s.clamp);
                        sums.splat((x, y), path::pixel_numbers(&sampler), l);
                    }
                }
                (sums.into_pixels(), ())
            },
            PixelSums::add,
        );
        return film;
    }
    tile::render_tiles(
        &s.window,
        &mut film.pixels,
        progress,
        || (),
        |_, tile, mut rows| {
            for i in 0..tile.len() {
                let (x, y) = tile.pixel(i);
                rows.set(i as usize, PixelSums::from(&render_pixel(scene, x, y, samples.clone())));
            }
        },
    );
    film
}

/// Samples `samples` of one pixel.
pub fn render_pixel(scene: &RenderScene, x: u32, y: u32, samples: Range<u32>) -> PixelAccumulator {
    let mut acc = PixelAccumulator::default();
    for i in samples {
        let (ray, tmax, sampler) = path::camera_ray(scene, x, y, i);
        acc.add(clamp_sample(radiance(scene, ray, tmax, &sampler), scene.settings.clamp));
    }
    acc
}

/// Radiance arriving at the ray origin along the ray (unit direction), which sees surfaces
/// closer than `tmax` (the camera's far clip plane; beyond it the ray misses); the path's later
/// rays reach infinitely far.
pub fn radiance(scene: &RenderScene, ray: Ray, tmax: f32, sampler: &Sampler) -> Vec3 {
    radiance_witnessed(scene, ray, tmax, sampler, &mut ())
}

/// Where radiance a path adds comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// A surface of material `material` (its id) that the path's ray met.
    Emitter(u32),
    /// The light sampled at the path's last vertex ([`sampled_light`] says which).
    LightSample,
    /// The light sampled apart from the choice among the others at the path's last vertex.
    ApartSample,
    /// The background, met by the path's ray.
    Background,
    /// A glowing medium the path's ray scattered in.
    Medium,
}

/// The light (its index in the scene's light table) that a path's vertex `depth`, at the point
/// `at[0]` of shading normal `at[1]` (zero in a medium), samples with `sampler`'s numbers.
pub fn sampled_light(scene: &RenderScene, sampler: &Sampler, depth: u32, at: [Vec3A; 2]) -> usize {
    scene.lights.pick(path::light_choice(scene, sampler, depth), at[0], at[1]).0
}

/// What a path tells an observer as it goes ([`radiance_witnessed`]): where it scatters, and
/// each radiance it adds with where that came from. `()` listens to nothing.
pub trait Witness {
    /// The path scattered at its vertex `depth` (its vertices before it), the point `at` of
    /// shading normal `n` (zero in a medium): off a surface whose material is `material` (the
    /// id the surface names, before a wrapper resolves it), or in a medium (`None`), by a delta
    /// lobe if `delta`. Told before what light sampling there adds.
    fn scatters(&mut self, depth: u32, at: [Vec3A; 2], material: Option<u32>, delta: bool);
    /// The path adds `l` (its throughput included) from `source`, arriving along `-dir` (any
    /// length); met along its ray, it came by a delta lobe (or is the camera's ray) if `delta`.
    fn adds(&mut self, l: Vec3, source: Source, dir: Vec3A, delta: bool);
}

impl Witness for () {
    #[inline(always)]
    fn scatters(&mut self, _: u32, _: [Vec3A; 2], _: Option<u32>, _: bool) {}
    #[inline(always)]
    fn adds(&mut self, _: Vec3, _: Source, _: Vec3A, _: bool) {}
}

/// [`radiance`], telling `witness` where the path scatters and what it adds.
#[inline]
pub fn radiance_witnessed(
    scene: &RenderScene,
    mut ray: Ray,
    tmax: f32,
    sampler: &Sampler,
    witness: &mut impl Witness,
) -> Vec3 {
    let mut st = PathState::new(ray.origin);
    // Spectral MIS ratios in coloured media (see `path::chromatic_flight`).
    let mut ratio = Vec3::ONE;
    let mut reach = tmax;
    'path: loop {
        let hit = scene.intersect(&ray, reach);
        reach = f32::INFINITY;
        // Each vertex yields an optional shadow ray and the next ray (None: the path ends).
        // The vertex's depth and material (None: a medium), for the witness.
        let vertex;
        let (shadows, next) = 'vertex: {
            if scene.features.media {
                let tmax = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
                let before = st.l;
                let flight = path::Flight { l: &mut st.l, beta: &mut st.beta, ratio: &mut ratio };
                let scattered = path::sample_medium(
                    scene,
                    flight,
                    &ray,
                    tmax,
                    sampler.get_1d(path::medium_dim(st.depth)),
                    st.depth,
                    || sampler.get_1d(path::medium_dim(0)),
                );
                // What a glowing medium gave where the path scattered (nothing elsewhere).
                witness.adds(st.l - before, Source::Medium, ray.dir, st.delta);
                if let Some((p, g)) = scattered {
                    if path::at_max_depth(scene, st.bounces()) {
                        break 'path;
                    }
                    vertex = (st.depth, [p, Vec3A::ZERO], None);
                    break 'vertex path::scatter_in_medium(scene, &mut st, p, ray.dir, g, ray.time, sampler);
                }
            }
            let Some(mut hit) = hit else {
                let before = st.l;
                path::escape(scene, &mut st, ray.dir);
                witness.adds(st.l - before, Source::Background, ray.dir, st.delta);
                break 'path;
            };
            let named = hit.material;
            // A wrapper: the plain material it stands for here, or the ray goes on through.
            if scene.features.wrappers
                && let Some(through) = path::resolve(scene, &mut st, &mut hit, ray.dir, ray.time, sampler)
            {
                ray = through;
                continue 'path;
            }
            let mat = &scene.material_at(hit.material, &hit.surface);
            let wo = -ray.dir;
            if mat.is_emissive() {
                let before = st.l;
                path::emit(scene, &mut st, &hit, wo, ray.time);
                witness.adds(st.l - before, Source::Emitter(named), ray.dir, st.delta);
                break 'path;
            }
            // A surface that emits and reflects: its emission, then it scatters.
            if scene.features.emitting_surfaces && scene.lights.emits(hit.material) {
                let before = st.l;
                path::emit(scene, &mut st, &hit, wo, ray.time);
                witness.adds(st.l - before, Source::Emitter(named), ray.dir, st.delta);
            }
            // A surface with a null lobe is sampled at the limit too (only a null sample goes on).
            if path::at_max_depth(scene, st.bounces()) && !mat.has_null_lobe() {
                break 'path;
            }
            if let Some(lp) = &scene.light_paths {
                path::divide_for_light_paths(&mut st, lp.class(mat), &hit.surface);
            }
            vertex = (st.depth, [hit.surface.p, hit.surface.ns], Some(named));
            match mat.shading() {
                // A tilted normal: a Lambertian shaded as the glossy kinds are.
                Shading::Diffuse if scene.features.tilts && path::tilted(&hit.surface) => {
                    let u = path::GlossySamples::draw(scene, sampler, st.depth);
                    path::shade_glossy(scene, &mut st, &hit.surface, wo, mat, ray.time, &u)
                }
                Shading::Diffuse => {
                    if path::black_behind(mat, &hit.surface, wo) {
                        break 'path;
                    }
                    let u = lambert_vertex::VertexSamples::draw(scene, sampler, st.depth);
                    let input = lambert_vertex::gather(
                        scene,
                        (&st).into(),
                        &hit.surface,
                        wo,
                        mat.albedo(),
                        ray.time,
                        &u,
                    );
                    let out = match scene.guide.as_deref() {
                        Some(g) => crate::guided::lambert_guided(g, &input),
                        None => lambert_vertex::lambert(&input),
                    };
                    let apart = lambert_vertex::apart_shadow(scene, &input, ray.time, u.apart);
                    let (light, next) = lambert_vertex::apply(&input, &out, &mut st, ray.time);
                    (path::Shadows { light, apart }, next)
                }
                Shading::Sampled => (
                    path::Shadows::default(),
                    path::scatter(scene, &mut st, &hit.surface, wo, mat, ray.time, sampler),
                ),
                Shading::Glossy => {
                    let u = path::GlossySamples::draw(scene, sampler, st.depth);
                    path::shade_glossy(scene, &mut st, &hit.surface, wo, mat, ray.time, &u)
                }
                Shading::Emitter => unreachable!("emitters end the path above"),
            }
        };
        witness.scatters(vertex.0, vertex.1, vertex.2, st.delta);
        for (s, source) in [(shadows.light, Source::LightSample), (shadows.apart, Source::ApartSample)] {
            if let Some(s) = s {
                let before = st.l;
                path::trace_shadow(scene, &mut st, &s);
                witness.adds(st.l - before, source, s.ray.dir, false);
            }
        }
        match next {
            Some(r) => ray = r,
            None => break,
        }
    }
    st.l
}
