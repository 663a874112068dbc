//! Light sampling at a path's vertex: the light picked and the point on it seen from the vertex
//! (the sample that becomes a shadow ray), and what a shadow ray lets through (surfaces with a
//! null lobe, media).

use super::{PathState, ShadowRay};
use crate::plain::{dot, offset, sel3};
use crate::sampler::{Dims, Sampler};
use glam::{Vec2, Vec3, Vec3A};
use pathwave_engine::lighting::lights::OtherLight;
use pathwave_engine::lighting::punctual_light::PunctualLight;
use pathwave_engine::math::Ray;
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
    /// The light's index in the light table.
    pub light: u32,
}

/// Picks a light with `u_pick` and a point on it with `u` as seen from `p` (of shading normal
/// `n`, zero in a medium: the light tree weighs lights by it); `None` when it sends nothing
/// towards `p`.
#[inline]
pub(crate) fn pick_light(
    scene: &RenderScene,
    p: Vec3A,
    n: Vec3A,
    time: f32,
    u_pick: f32,
    u: Vec2,
) -> Option<LightPick> {
    sample_light(scene, scene.lights.pick(u_pick, p, n), p, time, u)
}

/// [`pick_light`]'s sample of the light it picked, `(light, pmf)` (the lanes pick for several
/// points at once: `LightTable::pick_lanes`).
#[inline]
pub(crate) fn sample_light(
    scene: &RenderScene,
    (light, pmf): (usize, f32),
    p: Vec3A,
    time: f32,
    u: Vec2,
) -> Option<LightPick> {
    let geo = &*scene.geometry;
    let lights = &*scene.lights;
    if let Some(other) = lights.other(light) {
        return pick_other(scene, other, (light as u32, pmf), p, u);
    }
    let ls = lights.sample(geo, light, p, u, time);
    let prim = lights.prims[light];
    // A light's primitive emits: its material id is in the emission table.
    let emission = lights.emission[geo.material[prim as usize] as usize].as_ref()?;
    let emit = |cos| emission.emitted(&scene.textures, cos, || geo.surface(prim, ls.p, time));
    let s = seen_from(ls.p.into(), ls.n.into(), ls.pdf, ls.err, pmf, p.into(), emit);
    let (wi, target, light) = (s.wi.into(), s.target.into(), light as u32);
    s.ok.then_some(LightPick { wi, le: s.le, pdf: s.pdf, target, delta: false, light })
}

/// What a light sample gives a shading point, before the choice of `ok`: the direction to it,
/// the radiance arriving, the density with the light's choice, and the target off the light.
pub(crate) struct SeenFrom {
    /// Whether the sample counts: the point is off the light, sends radiance and has density.
    pub ok: bool,
    pub wi: Vec3,
    pub le: Vec3,
    pub pdf: f32,
    pub target: Vec3,
}

/// What a sample of a light picked with probability `pmf` (the point `lp` with unit normal
/// `n`, error bound `err`, density `pdf_solid` in solid angle) gives the point `from`; `emit`
/// is the light's radiance towards a direction at cosine `cos` from `n`. The one definition
/// for [`pick_light`] and the lanes' kernels (`light_lanes.rs`, which select by `ok` without
/// branches): operation by operation on the components, so it vectorises across lanes and
/// gives both the same bits.
#[inline(always)]
pub(crate) fn seen_from(
    lp: Vec3,
    n: Vec3,
    pdf_solid: f32,
    err: f32,
    pmf: f32,
    from: Vec3,
    emit: impl FnOnce(f32) -> Vec3,
) -> SeenFrom {
    let d = Vec3::new(lp.x - from.x, lp.y - from.y, lp.z - from.z);
    let dist = dot(d, d).sqrt();
    let wi = Vec3::new(d.x / dist, d.y / dist, d.z / dist);
    let le = emit(dot(n, Vec3::new(-wi.x, -wi.y, -wi.z)));
    let pdf = pdf_solid * pmf;
    let ok = dist > 0.0 && (le.x != 0.0 || le.y != 0.0 || le.z != 0.0) && pdf > 0.0;
    let side = sel3(dot(n, wi) < 0.0, n, Vec3::new(-n.x, -n.y, -n.z));
    SeenFrom { ok, wi, le, pdf, target: offset(lp, err, side) }
}

/// [`pick_light`] for a light that is not a primitive, chosen with probability `pmf`.
#[inline(never)]
fn pick_other(
    scene: &RenderScene,
    other: &OtherLight,
    (light, pmf): (u32, f32),
    p: Vec3A,
    u: Vec2,
) -> Option<LightPick> {
    match other {
        OtherLight::Punctual(l) => punctual_pick(scene, l, (light, pmf), p),
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
                light,
            })
        }
    }
}

/// The point, spot, directional or projector light `l`, chosen with probability `pmf`, seen
/// from `p`.
#[inline]
fn punctual_pick(
    scene: &RenderScene,
    l: &PunctualLight,
    (light, pmf): (u32, f32),
    p: Vec3A,
) -> Option<LightPick> {
    let (wi, dist, le) = l.illuminate(p, &scene.textures);
    if le == Vec3::ZERO || !(dist > 0.0) || !(pmf > 0.0) {
        return None;
    }
    let target = if dist.is_finite() { p + wi * dist } else { scene.lights.beyond(p, wi) };
    Some(LightPick { wi, le, pdf: pmf, target, delta: true, light })
}

/// The light sample seen from `p` with the numbers `u` of the light sampled apart from the
/// choice among the others (`LightTable::apart`: with probability 1, at every
/// vertex that samples a light); `None` elsewhere, or when it sends nothing.
#[inline]
pub(crate) fn apart_light(scene: &RenderScene, p: Vec3A, u: Vec2) -> Option<LightPick> {
    let index = scene.lights.apart()?;
    let light = index as u32;
    match scene.lights.other(index)? {
        // A sun, in line (`pick_other` is a call and a match on every kind of light).
        OtherLight::Punctual(l) => punctual_pick(scene, l, (light, 1.0), p),
        other => pick_other(scene, other, (light, 1.0), p, u),
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
