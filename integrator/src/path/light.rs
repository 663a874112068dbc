//! Light sampling at a path's vertex: the light picked and the point on it seen from the vertex
//! (the sample that becomes a shadow ray), and what a shadow ray lets through (surfaces with a
//! null lobe, media).

use super::{PathState, ShadowRay};
use crate::sampler::{Dims, Sampler};
use glam::{Vec2, Vec3, Vec3A};
use pathwave_engine::lighting::lights::OtherLight;
use pathwave_engine::math::{Ray, offset_ray_origin};
use pathwave_engine::render_scene::RenderScene;

/// A light sample seen from a point: the direction to it, the emitted radiance arriving, the
/// density (solid angle, light choice included) and the offset point on the light to aim at.
/// For a point, spot or directional light (`delta`), `le / pdf` is its estimate and `pdf` the
/// choice's probability alone: BSDF sampling cannot reach it, so there is no MIS weight.
pub(crate) struct LightPick {
    pub wi: Vec3A,
    pub le: Vec3,
    pub pdf: f32,
    pub target: Vec3A,
    pub delta: bool,
}

/// Picks a light with `u_pick` and a point on it with `u` as seen from `p`; `None` when it
/// sends nothing towards `p`.
#[inline]
pub(crate) fn pick_light(
    scene: &RenderScene,
    p: Vec3A,
    time: f32,
    u_pick: f32,
    u: Vec2,
) -> Option<LightPick> {
    let geo = &*scene.geometry;
    let lights = &*scene.lights;
    let (light, pmf) = lights.pick(u_pick);
    if let Some(other) = lights.other(light) {
        return pick_other(scene, other, pmf, p, u);
    }
    let ls = lights.sample(geo, light, p, u, time);
    let to = ls.p - p;
    let dist = to.length();
    if !(dist > 0.0) {
        return None;
    }
    let wi = to / dist;
    let prim = lights.prims[light];
    // A light's primitive emits: its material id is in the emission table.
    let emission = lights.emission[geo.material[prim as usize] as usize].as_ref()?;
    let le = emission.emitted(&scene.textures, ls.n.dot(-wi), || geo.surface(prim, ls.p, time));
    let pdf = ls.pdf * pmf;
    if le == Vec3::ZERO || !(pdf > 0.0) {
        return None;
    }
    let target = offset_ray_origin(ls.p, ls.err, if ls.n.dot(wi) < 0.0 { ls.n } else { -ls.n });
    Some(LightPick { wi, le, pdf, target, delta: false })
}

/// [`pick_light`] for a light that is not a primitive, chosen with probability `pmf`.
#[inline(never)]
fn pick_other(scene: &RenderScene, light: &OtherLight, pmf: f32, p: Vec3A, u: Vec2) -> Option<LightPick> {
    match light {
        OtherLight::Punctual(l) => {
            let (wi, dist, le) = l.illuminate(p, &scene.textures);
            if le == Vec3::ZERO || !(dist > 0.0) {
                return None;
            }
            let target = if dist.is_finite() { p + wi * dist } else { scene.lights.beyond(p, wi) };
            Some(LightPick { wi, le, pdf: pmf, target, delta: true })
        }
        OtherLight::Environment => {
            // The MIS-compensated density of a map (`Background::sample`): every caller, at
            // surfaces of every shading kind and in media, weighs this sample by MIS against
            // BSDF or phase sampling, which reaches the directions it leaves out.
            let s = scene.background.sample(u)?;
            let pdf = s.pdf * pmf;
            if s.radiance == Vec3::ZERO || !(pdf > 0.0) {
                return None;
            }
            Some(LightPick {
                wi: s.dir,
                le: s.radiance,
                pdf,
                target: scene.lights.beyond(p, s.dir),
                delta: false,
            })
        }
    }
}

/// The number that chooses the light at the vertex after `depth` bounces (one light needs
/// none).
#[inline]
pub(crate) fn light_choice(scene: &RenderScene, sampler: &Sampler, depth: u32) -> f32 {
    if scene.lights.len() > 1 { sampler.get_1d(Dims::vertex(depth, Dims::LIGHT_PICK)) } else { 0.0 }
}

/// The fraction of a shadow ray's contribution that gets through, per channel: `None` when
/// something blocks it (what surfaces with a null lobe let through,
/// [`RenderScene::null_transmittance`], in scenes that have them), times
/// [`media_transmittance`].
#[inline]
pub fn shadow_transmittance(scene: &RenderScene, ray: &Ray) -> Option<Vec3> {
    let surfaces = match scene.occluded(ray, 1.0) {
        false => 1.0,
        true if scene.features.null_surfaces => scene.null_transmittance(ray),
        true => 0.0,
    };
    (surfaces > 0.0).then(|| media_transmittance(scene, ray) * surfaces)
}

/// What the media let through along a shadow ray that nothing blocks, from its origin to the
/// light point at `t = 1`, per channel (1 without media).
#[inline]
pub fn media_transmittance(scene: &RenderScene, ray: &Ray) -> Vec3 {
    match scene.features.media {
        true => scene.media.transmittance(ray, 1.0),
        false => Vec3::ONE,
    }
}

/// Traces a shadow ray at once (one path at a time) and adds what gets through.
#[inline]
pub fn trace_shadow(scene: &RenderScene, st: &mut PathState, s: &ShadowRay) {
    if let Some(tr) = shadow_transmittance(scene, &s.ray) {
        st.l += s.contribution * tr;
    }
}
