//! A path's steps inside media: free-flight sampling (chromatic in coloured media, with the
//! spectral MIS over the hero channel), and a scattering event with next-event estimation,
//! Henyey-Greenstein phase sampling and Russian roulette.

use super::{
    LightPick, PathState, ShadowRay, Shadows, apart_light, light_choice, pick_light, power_heuristic,
    roulette,
};
use crate::sampler::{Dims, Sampler};
use glam::{Vec2, Vec3, Vec3A};
use pathwave_engine::math::{Ray, uniform_sphere};
use pathwave_engine::media::phase::{hg, sample_hg};
use pathwave_engine::render_scene::RenderScene;

/// What a free flight reads and changes of a path, wherever the path is held (the oracle's
/// [`PathState`], the wavefront's arrays): the radiance it has gathered, its throughput, and
/// its spectral MIS ratios (see [`chromatic_flight`]).
pub struct Flight<'a> {
    /// The radiance gathered.
    pub l: &'a mut Vec3,
    /// The throughput.
    pub beta: &'a mut Vec3,
    /// The density ratios of coloured media.
    pub ratio: &'a mut Vec3,
}

/// Free-flight sampling through the media up to the closest surface at `tmax` (infinity for a
/// miss) with the number `u`, the path's [`medium_dim`] of its depth. When the ray scatters
/// first, the path gathers what the point emits (into `l`, in glowing media), the throughput
/// takes the medium's albedo and the scattering point is returned with the phase function's
/// asymmetry there; otherwise nothing changes. In coloured media see [`chromatic_flight`] (`ratio`, the path's
/// `depth` and its first number `u0` serve only there). Call only for scenes with media.
#[inline]
pub fn sample_medium(
    scene: &RenderScene,
    path: Flight,
    ray: &Ray,
    tmax: f32,
    u: f32,
    depth: u32,
    u0: impl FnOnce() -> f32,
) -> Option<(Vec3A, f32)> {
    if scene.media.chromatic() {
        let u0 = if depth == 0 { None } else { Some(u0()) };
        return chromatic_flight(scene, path, ray, tmax, u, u0);
    }
    let e = scene.media.sample(ray, tmax, u)?;
    *path.l += *path.beta * e.emitted;
    *path.beta *= e.albedo;
    Some((ray.at(e.t), e.g))
}

/// A free flight through coloured media ([`Media::sample_chromatic`]) with the number `u`: the
/// path's hero channel is `floor(3 u0)`, `u0` the number of its first flight (the camera ray's,
/// `None` on that flight, whose distance then takes `3 u - hero`, independent of the choice). `ratio` holds the path's density ratios
/// (each channel as hero over the actual hero) over their mean, and `beta` the throughput over
/// that mean, so that whatever the path gathers is already weighted by the spectral MIS over
/// whole paths: nothing else in the integrators changes.
///
/// [`Media::sample_chromatic`]: pathwave_engine::media::Media::sample_chromatic
#[inline(never)]
pub fn chromatic_flight(
    scene: &RenderScene,
    path: Flight,
    ray: &Ray,
    tmax: f32,
    u: f32,
    u0: Option<f32>,
) -> Option<(Vec3A, f32)> {
    let hero = ((u0.unwrap_or(u) * 3.0) as usize).min(2);
    // On the camera ray its distance takes the rest of the number.
    let u = match u0 {
        None => (u * 3.0 - hero as f32).clamp(0.0, 1.0 - f32::EPSILON / 2.0),
        Some(_) => u,
    };
    let f = scene.media.sample_chromatic(ray, tmax, u, hero);
    let Flight { l, beta, ratio } = path;
    let r = *ratio * f.ratio;
    let mean = r.element_sum() / 3.0;
    if !(mean > 0.0) {
        *beta = Vec3::ZERO;
        return None;
    }
    *l += *beta * f.emitted / mean;
    (*beta, *ratio) = (*beta * f.weight / mean, r / mean);
    f.t.map(|t| (ray.at(t), f.g))
}

/// The dimension of the free-flight number on the segment that leads to the vertex after
/// `depth` bounces.
#[inline]
pub fn medium_dim(depth: u32) -> u32 {
    Dims::vertex(depth, Dims::MEDIUM)
}

/// Density (and value) of the isotropic phase function.
const ISOTROPIC: f32 = 1.0 / (4.0 * std::f32::consts::PI);

/// A scattering event at `p` inside a medium (after [`sample_medium`]), reached along `dir`,
/// where the Henyey-Greenstein phase function has asymmetry `g` (0: isotropic): next-event
/// estimation, then phase sampling and Russian roulette. Returns the shadow rays and
/// the next ray (`None` when the path ends). The phase function's value is its density, so
/// sampling it leaves the throughput as it is.
#[inline]
pub fn scatter_in_medium(
    scene: &RenderScene,
    st: &mut PathState,
    p: Vec3A,
    dir: Vec3A,
    g: f32,
    time: f32,
    sampler: &Sampler,
) -> (Shadows, Option<Ray>) {
    if st.beta == Vec3::ZERO {
        return (Shadows::default(), None);
    }
    let depth = st.depth;
    let wo = -dir.normalize();
    let phase = |wi: Vec3A| if g == 0.0 { ISOTROPIC } else { hg(wo.dot(wi.normalize()), g) };
    let shadow = |lp: LightPick| {
        let f = phase(lp.target - p);
        let w = if lp.delta { 1.0 } else { power_heuristic(lp.pdf, f) };
        let contribution = st.beta * lp.le * (f * w / lp.pdf);
        ShadowRay { ray: Ray { origin: p, dir: lp.target - p, time }, contribution }
    };
    let light = if scene.lights.is_empty() {
        None
    } else {
        let u_pick = light_choice(scene, sampler, depth);
        let u = sampler.get_2d(Dims::vertex(depth, Dims::LIGHT));
        pick_light(scene, p, Vec3A::ZERO, time, u_pick, u).map(shadow)
    };
    let u_apart = match scene.lights.apart_samples() {
        true => sampler.get_2d(Dims::apart(depth)),
        false => Vec2::ZERO,
    };
    let apart = apart_light(scene, p, u_apart).map(shadow);
    let shadows = Shadows { light, apart };
    let u = sampler.get_2d(Dims::vertex(depth, Dims::BSDF));
    let (wi, pdf) = if g == 0.0 { (uniform_sphere(u), ISOTROPIC) } else { sample_hg(wo, g, u) };
    (st.delta, st.prev_pdf, st.prev_p, st.prev_n) = (false, pdf, p, Vec3A::ZERO);
    st.depth += 1;
    let u_rr = || sampler.get_1d(Dims::vertex(depth, Dims::ROULETTE));
    let next = roulette(scene, st, u_rr).then_some(Ray { origin: p, dir: wi, time });
    (shadows, next)
}
