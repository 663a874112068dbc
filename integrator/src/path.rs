//! The per-vertex steps of a path, shared by the reference path tracer and the wavefront
//! stages so that both compute every sample identically: what a ray that leaves the scene adds,
//! what an emitter hit adds (MIS-weighted), the light sample that becomes a shadow ray, and
//! BSDF sampling with Russian roulette.
//!
//! The light sample and shadow rays are in `light`, the steps in media in `medium`, the camera
//! rays that start paths in `camera`.

mod camera;
mod division;
mod light;
mod medium;

pub use camera::{camera_ray, camera_rays, camera_sampler, pixel_numbers};
pub use division::divide_for_light_paths;
pub(crate) use division::{emitter_traced, light_traced};
pub(crate) use light::{LightPick, apart_light, light_choice, pick_light, sample_light, seen_from};
pub use light::{media_transmittance, shadow_transmittance, trace_shadow};
pub use medium::{Flight, chromatic_flight, medium_dim, sample_medium, scatter_in_medium};

use crate::sampler::{Dims, Sampler, SamplerLanes};
use glam::{Vec2, Vec3, Vec3A};
use pathwave_engine::accel::geometry::Hit;
use pathwave_engine::material::wrap::{Resolved, terminator_shadowing};
use pathwave_engine::material::{BsdfEval, BsdfSample, Material, Reads, Specular};
use pathwave_engine::math::{Ray, offset_ray_origin};
use pathwave_engine::render_scene::RenderScene;
use pathwave_engine::shape::SurfacePoint;

/// The state a path carries from vertex to vertex.
#[derive(Clone, Copy, Debug)]
pub struct PathState {
    /// Radiance gathered so far.
    pub l: Vec3,
    /// Throughput.
    pub beta: Vec3,
    /// Product of squared relative IORs crossed (divided out of Russian roulette).
    pub eta_scale: f32,
    /// The last scattering was a delta lobe (or the path is a camera ray): no MIS on emitters.
    pub delta: bool,
    /// Last scattering point, for the light pdf of emitters hit by BSDF sampling.
    pub prev_p: Vec3A,
    /// Its shading normal (zero in a medium), which the light tree's choice there read.
    pub prev_n: Vec3A,
    /// BSDF pdf of the last scattering.
    pub prev_pdf: f32,
    /// Vertices so far: bounces and null crossings (each takes its sampler numbers).
    pub depth: u32,
    /// Null crossings so far ([`BsdfSample::null`](pathwave_engine::material::BsdfSample::null)):
    /// `depth - crossings` bounces count towards `max_depth`.
    pub crossings: u32,
    /// In a scene where light tracing takes punctual lights' caustics
    /// ([`RenderScene::light_paths`]; [`divide_for_light_paths`]): the path's first vertex was
    /// rough and none of its others is one light tracing leaves to the path tracer.
    pub caustic: bool,
    /// ... and the vertex being shaded is sharp: a punctual light sampled here ends a path the
    /// light tracer counts.
    pub traced_here: bool,
}

impl PathState {
    /// A camera path starting at `origin`.
    #[inline]
    pub fn new(origin: Vec3A) -> Self {
        Self {
            l: Vec3::ZERO,
            beta: Vec3::ONE,
            eta_scale: 1.0,
            delta: true,
            prev_p: origin,
            prev_n: Vec3A::ZERO,
            prev_pdf: 0.0,
            depth: 0,
            crossings: 0,
            caustic: false,
            traced_here: false,
        }
    }

    /// Bounces so far, the null crossings left out.
    #[inline(always)]
    pub fn bounces(&self) -> u32 {
        self.depth - self.crossings
    }
}

/// A shadow ray: if nothing lies on it with t in (0, 1), `contribution` is added to the path.
#[derive(Clone, Copy, Debug)]
pub struct ShadowRay {
    /// From the shading point to the light point (both offset), unnormalised.
    pub ray: Ray,
    /// Throughput times the MIS-weighted light estimate.
    pub contribution: Vec3,
}

/// The shadow rays of one vertex: the chosen light's, and the light's sampled apart from the
/// choice where there is one (`LightTable::apart`: the environment, or a directional light).
#[derive(Clone, Copy, Debug, Default)]
pub struct Shadows {
    /// Towards the light chosen.
    pub light: Option<ShadowRay>,
    /// Towards the light sampled apart.
    pub apart: Option<ShadowRay>,
}

impl Shadows {
    /// The chosen light's shadow ray alone.
    #[inline]
    pub fn one(light: Option<ShadowRay>) -> Self {
        Self { light, apart: None }
    }

    /// Those there are, the chosen light's first.
    #[inline]
    pub fn iter(&self) -> impl Iterator<Item = &ShadowRay> {
        self.light.iter().chain(self.apart.iter())
    }
}

/// Power heuristic (beta = 2) weight of the strategy with density `a` against `b` (Veach 1997).
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2.is_infinite() {
        return 1.0;
    }
    if a2 + b2 == 0.0 { 0.0 } else { a2 / (a2 + b2) }
}

/// A ray left the scene: add the background (MIS-weighted where it is sampled as a light).
///
/// The weight takes the density that next-event estimation samples the background with
/// ([`Background::pdf`](pathwave_engine::render_scene::Background::pdf): a map's MIS-compensated
/// one), so that the two techniques' weights sum to 1 wherever either can reach; where light
/// sampling cannot (a map's directions dimmer than its mean) BSDF sampling counts in full.
#[inline]
pub fn escape(scene: &RenderScene, st: &mut PathState, dir: Vec3A) {
    let pmf = scene.lights.environment_pmf();
    let (le, w) = match st.delta || pmf == 0.0 {
        false => {
            let (le, pdf) = scene.background.radiance_pdf(dir);
            (le, power_heuristic(st.prev_pdf, pmf * pdf))
        }
        true => (scene.background.radiance(dir), 1.0),
    };
    st.l += st.beta * le * w;
}

/// A ray hit a surface that emits (an emitter, whose path ends there, or an object's `emit`
/// over a material that then scatters): adds its emission, MIS-weighted against light sampling
/// unless the path came by a delta lobe (or is a camera ray).
#[inline]
pub fn emit(scene: &RenderScene, st: &mut PathState, hit: &Hit, wo: Vec3A, time: f32) {
    // After a sharp vertex of a caustic's path, a light that light tracing emits from is its.
    if st.traced_here && emitter_traced(scene, hit.prim) {
        return;
    }
    let sp = &hit.surface;
    let le = scene.emitted(hit.material, sp, sp.n.dot(wo));
    if le == Vec3::ZERO {
        return;
    }
    let w = if st.delta {
        1.0
    } else {
        let pdf = scene.lights.pdf(&scene.geometry, hit.prim, st.prev_p, st.prev_n, sp.p, sp.n, time);
        power_heuristic(st.prev_pdf, pdf)
    };
    st.l += st.beta * le * w;
}

/// A hit on a surface in a scene with wrappers ([`Features::wrappers`]): follows its material
/// through them ([`RenderScene::resolve`]) with the numbers of the vertex after `st.depth`
/// bounces ([`Dims::wrapper`]), and writes the plain material found into `hit`, its shading
/// normal tilted where a bump or normal map says (`None` returned: it shades the hit). Through a mask's hole, the ray along `dir` goes on unbent
/// from the far side: a null crossing as a null lobe's ([`scatter_with`]), the MIS state and
/// the throughput kept, not a bounce of `max_depth`; that ray is returned. Out of line: scenes
/// without wrappers never call it.
///
/// [`Features::wrappers`]: pathwave_engine::render_scene::Features::wrappers
#[inline(never)]
pub fn resolve(
    scene: &RenderScene,
    st: &mut PathState,
    hit: &mut Hit,
    dir: Vec3A,
    time: f32,
    sampler: &Sampler,
) -> Option<Ray> {
    let depth = st.depth;
    match scene
        .resolve(hit.material, &mut hit.surface, -dir, |level| sampler.get_1d(Dims::wrapper(depth, level)))
    {
        Resolved::Material(id) => {
            hit.material = id;
            None
        }
        Resolved::Pass => {
            let sp = &hit.surface;
            let side = if dir.dot(sp.n) > 0.0 { sp.n } else { -sp.n };
            (st.depth, st.crossings) = (st.depth + 1, st.crossings + 1);
            Some(Ray { origin: offset_ray_origin(sp.p, sp.err, side), dir, time })
        }
    }
}

/// The depth limit: a path that has made `max_depth` bounces ends where it meets a surface or
/// scatters in a medium, without scattering again (an emitter or the background it reached
/// still counts). Null crossings ([`PathState::crossings`]) are not bounces: a surface with a
/// null lobe is sampled at the limit too, and only a null sample goes on ([`scatter_with`]).
#[inline(always)]
pub fn at_max_depth(scene: &RenderScene, bounces: u32) -> bool {
    bounces == scene.settings.max_depth
}

/// A [`Shading::Diffuse`](pathwave_engine::material::Shading::Diffuse) material that is one-sided ([`Material::one_sided`]), met from behind
/// its shading normal (`wo` the unit direction back along the ray): it reflects nothing there
/// (Mitsuba's `diffuse`: black where cos theta of `wo` or `wi` is not positive), so the path
/// ends without a light sample or a next direction. The Lambertian kernel samples `wi` on
/// `wo`'s side, so on the front no other change is needed.
#[inline(always)]
pub fn black_behind(mat: &Material, sp: &SurfacePoint, wo: Vec3A) -> bool {
    mat.one_sided() && !(wo.dot(sp.ns) > 0.0)
}

/// Whether Russian roulette is played at the vertex that makes the path's bounce number
/// `depth_after` (its roulette number is drawn only there).
#[inline(always)]
pub fn plays_roulette(scene: &RenderScene, depth_after: u32) -> bool {
    depth_after >= scene.settings.rr_depth
}

/// The largest throughput component a path leaves Russian roulette with: a path whose
/// throughput (times its IOR scale) `b` is below it goes on with probability
/// `b / ROULETTE_WEIGHT` and then carries exactly this weight; one above it is not played.
///
/// This is a weight window's lower bound and survival weight (Booth 1982, "Importance
/// estimation in forward Monte Carlo calculations", MCNP's weight windows): pbrt-v4 and
/// Mitsuba 3 use 1, so that a survivor's throughput is raised back to 1, and a dim path that
/// survives a few bounces then carries a pixel's whole weight into whatever it meets next. In
/// a closed room those survivors, meeting the bright patch beside a lamp, were the fireflies:
/// with 1/4 they carry a quarter, and the paths that would have been killed with a throughput
/// between 1/4 and 1 go on. Measured at 32 spp, three seeds, rays traced times relMSE (the
/// glTF interior, cornell-diffuse, cornell): 1/4 0.79x, 0.86x, 0.68x of 1's; 1/2, 1/3 and 1/6
/// within a few per cent of 1/4 (`benches/results/sampling.md`).
pub const ROULETTE_WEIGHT: f32 = 0.25;

/// Russian roulette's rule for a path whose new throughput is `beta` and IOR scale
/// `eta_scale`, at a vertex where it `plays`: whether its number is drawn, and the probability
/// `q` that the path ends (it ends when the number is below `q`; survivors' throughput is
/// divided by `1 - q`, which leaves their largest component at [`ROULETTE_WEIGHT`]).
/// Branch-free, for the lane kernels too.
#[inline(always)]
pub fn roulette_rule(plays: bool, beta: Vec3, eta_scale: f32) -> (bool, f32) {
    let rr = (beta * eta_scale).max_element() * (1.0 / ROULETTE_WEIGHT);
    (plays && rr < 1.0, (1.0 - rr).max(0.0))
}

/// Russian roulette ([`roulette_rule`]) after the bounce that made `st.depth`, with the number
/// `u()` (drawn only if needed): false when the path ends; survivors are reweighted.
#[inline]
fn roulette(scene: &RenderScene, st: &mut PathState, u: impl FnOnce() -> f32) -> bool {
    let (drawn, q) = roulette_rule(plays_roulette(scene, st.depth), st.beta, st.eta_scale);
    if drawn {
        if u() < q {
            return false;
        }
        st.beta /= 1.0 - q;
    }
    true
}

/// The numbers BSDF sampling reads at a vertex: the direction's two, the lobe's and Russian
/// roulette's (drawn only at depths where roulette is played, else zero).
#[derive(Clone, Copy, Debug, Default)]
pub struct ScatterSamples {
    /// The direction.
    pub dir: Vec2,
    /// The lobe.
    pub lobe: f32,
    /// Russian roulette.
    pub roulette: f32,
}

impl ScatterSamples {
    /// The numbers of the vertex after `depth` bounces ([`Self::draw_lanes`] on one lane).
    #[inline]
    pub fn draw(scene: &RenderScene, sampler: &Sampler, depth: u32) -> Self {
        let all = Reads { dir: true, lobe: true };
        Self::draw_lanes(scene, &SamplerLanes::from(&[*sampler]), &[depth], all)[0]
    }

    /// The numbers of `N` paths' vertices after `depths` bounces, computed across lanes: the
    /// direction's and the lobe's only where some lane's material `reads` them (the others
    /// stay zero, as no lane reads them), roulette's where some lane plays it.
    #[inline(always)]
    pub fn draw_lanes<const N: usize>(
        scene: &RenderScene,
        samplers: &SamplerLanes<N>,
        depths: &[u32; N],
        reads: Reads,
    ) -> [Self; N] {
        let dims = |slot| Dims::vertex_lanes(depths, slot);
        let dir = match reads.dir {
            true => crate::sampler::get_2d_lanes(samplers, &dims(Dims::BSDF)),
            false => [Vec2::ZERO; N],
        };
        let lobe = match reads.lobe {
            true => crate::sampler::get_1d_lanes(samplers, &dims(Dims::LOBE)),
            false => [0.0; N],
        };
        let roulette = match depths.iter().any(|&d| plays_roulette(scene, d + 1)) {
            true => crate::sampler::get_1d_lanes(samplers, &dims(Dims::ROULETTE)),
            false => [0.0; N],
        };
        let mut out = [Self::default(); N];
        for l in 0..N {
            out[l] = Self { dir: dir[l], lobe: lobe[l], roulette: roulette[l] };
        }
        out
    }
}

/// The side of the surface (`sp.n` or `-sp.n`) a ray scattered from `wo` into `wi` leaves
/// from, or `None` when it may not leave.
///
/// The side is the shading normal's: with vertex normals (a smooth-shaded mesh) the two normals
/// disagree about some directions, and the shading normal describes the surface the mesh
/// stands for. A direction on `sp.n`'s side of the shading normal, scattered from a `wo` also
/// there (a reflection on the outside the vertex normals point to), leaves whatever the flat
/// triangle says: it starts at the smooth surface (the hit point is lifted for it, after
/// Hanika 2021: [`pathwave_engine::accel::mesh::terminator_lift`]) and the mesh itself decides what it
/// meets, so the terminator follows the smooth surface instead of the facets. Every other direction the two
/// normals disagree about ends the path as before: a transmission through the shading normal
/// that stays on `wo`'s side of the facet, and a reflection on the inner side, where the point
/// is not lifted. Without vertex normals the two normals are one and every direction not in
/// the tangent plane leaves, with the same operations as before (the second test is not
/// reached), so flat surfaces pay nothing.
///
/// Where a bump or normal map tilted the shading normal, these rules are the base normal's
/// ([`SurfacePoint::ns_base`]), and a direction must also lie on the same side of the tilted
/// normal (as Mitsuba's `bumpmap` and `normalmap` require); elsewhere the two normals are one
/// and that test is implied by the first (`cs` is not zero).
///
/// Light sampling and BSDF sampling call it alike, so both estimate one integral and their
/// MIS weights stay consistent.
#[inline]
pub fn leaving_side(sp: &SurfacePoint, wo: Vec3A, wi: Vec3A) -> Option<Vec3A> {
    let (cg, cs) = (wi.dot(sp.n), wi.dot(sp.ns_base));
    if cg * cs <= 0.0 && !(cs > 0.0 && wo.dot(sp.ns_base) > 0.0) || !(cs * wi.dot(sp.ns) > 0.0) {
        return None;
    }
    Some(if cs > 0.0 { sp.n } else { -sp.n })
}

/// A hit whose shading normal a bump or normal map tilted: it is shaded path by path, the
/// BSDF about the tilted normal (a Lambertian's by [`shade_glossy`], not the lane kernel),
/// and the BSDF's value takes [`terminator_shadowing`]. Only in scenes with
/// [`Features::tilts`].
///
/// [`Features::tilts`]: pathwave_engine::render_scene::Features::tilts
#[inline(always)]
pub fn tilted(sp: &SurfacePoint) -> bool {
    sp.ns != sp.ns_base
}

/// `f` times the BSDF's factor for the direction `wi` leaving `sp`: [`terminator_shadowing`]
/// in scenes with bump or normal maps; elsewhere `f` as it is.
#[inline(always)]
fn shadowed(scene: &RenderScene, sp: &SurfacePoint, wi: Vec3A, f: Vec3) -> Vec3 {
    match scene.features.tilts {
        true => f * terminator_shadowing(sp, wi),
        false => f,
    }
}

/// Samples the BSDF, updates the throughput, applies Russian roulette; returns the next ray, or
/// `None` when the path ends.
#[inline]
pub fn scatter(
    scene: &RenderScene,
    st: &mut PathState,
    sp: &SurfacePoint,
    wo: Vec3A,
    mat: &Material,
    time: f32,
    sampler: &Sampler,
) -> Option<Ray> {
    scatter_with(scene, st, sp, wo, mat, time, &ScatterSamples::draw(scene, sampler, st.depth), false)
}

/// [`scatter`] with the vertex's numbers `u` drawn already; `nee` says whether a light was
/// sampled at the vertex (then an emitter that the new ray meets is weighted by MIS, unless
/// the lobe was a delta). Always inlined: as a call, `st`
/// went through memory, written field by field and read back two fields per load (beta's z with
/// the IOR scale), which no store forwards to (spheres-sky: a quarter of the function's time).
#[expect(clippy::too_many_arguments, reason = "the vertex's pieces, as shade_glossy hands them on")]
#[inline(always)]
pub fn scatter_with(
    scene: &RenderScene,
    st: &mut PathState,
    sp: &SurfacePoint,
    wo: Vec3A,
    mat: &Material,
    time: f32,
    u: &ScatterSamples,
    nee: bool,
) -> Option<Ray> {
    scatter_sampled(scene, st, sp, wo, mat.sample(wo, sp.ns, u.dir, u.lobe)?, time, u, nee)
}

/// [`scatter_with`] once the BSDF has been sampled (`bs`): the side the ray leaves from, the
/// throughput, the MIS state and roulette. The lane kernels sample the BSDF across lanes and
/// call it per path.
#[expect(clippy::too_many_arguments, reason = "the vertex's pieces, as scatter_with")]
#[inline(always)]
pub fn scatter_sampled(
    scene: &RenderScene,
    st: &mut PathState,
    sp: &SurfacePoint,
    wo: Vec3A,
    mut bs: BsdfSample,
    time: f32,
    u: &ScatterSamples,
    nee: bool,
) -> Option<Ray> {
    let side = leaving_side(sp, wo, bs.wi)?;
    bs.weight = shadowed(scene, sp, bs.wi, bs.weight);
    if bs.null {
        // Straight on, as if the surface were not there: the MIS state stays the last
        // scattering's, and no roulette (the throughput is unchanged).
        st.beta *= bs.weight;
        (st.depth, st.crossings) = (st.depth + 1, st.crossings + 1);
        return Some(Ray { origin: offset_ray_origin(sp.p, sp.err, side), dir: bs.wi, time });
    }
    if at_max_depth(scene, st.bounces()) {
        return None;
    }
    st.beta *= bs.weight;
    st.eta_scale *= bs.eta * bs.eta;
    // Where no light was sampled or the lobe is a delta, an emitter the new ray meets counts
    // in full.
    st.delta = bs.delta || !nee;
    st.prev_pdf = bs.pdf;
    (st.prev_p, st.prev_n) = (sp.p, sp.ns);
    let ray = Ray { origin: offset_ray_origin(sp.p, sp.err, side), dir: bs.wi, time };
    st.depth += 1;
    roulette(scene, st, || u.roulette).then_some(ray)
}

/// The numbers a [`Shading::Glossy`](pathwave_engine::material::Shading::Glossy) vertex reads: the light's choice and point, then the
/// BSDF's (see [`ScatterSamples`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct GlossySamples {
    /// Which light.
    pub light_pick: f32,
    /// Where on it.
    pub light: Vec2,
    /// The point on the light sampled apart ([`Dims::apart`]; zero where there is none).
    pub apart: Vec2,
    /// BSDF sampling and roulette.
    pub bsdf: ScatterSamples,
}

impl GlossySamples {
    /// The numbers of the vertex after `depth` bounces ([`Self::draw_lanes`] on one lane).
    #[inline]
    pub fn draw(scene: &RenderScene, sampler: &Sampler, depth: u32) -> Self {
        let all = Reads { dir: true, lobe: true };
        Self::draw_lanes(scene, &SamplerLanes::from(&[*sampler]), &[depth], all)[0]
    }

    /// The numbers of `N` paths' vertices after `depths` bounces, computed across lanes: the
    /// light's choice where there is more than one light, its point where there is one, and
    /// the BSDF's as [`ScatterSamples::draw_lanes`] draws them (those no lane's material
    /// `reads` left at zero).
    #[inline(always)]
    pub fn draw_lanes<const N: usize>(
        scene: &RenderScene,
        samplers: &SamplerLanes<N>,
        depths: &[u32; N],
        reads: Reads,
    ) -> [Self; N] {
        let dims = |slot| Dims::vertex_lanes(depths, slot);
        let light_pick = match scene.lights.len() > 1 {
            true => crate::sampler::get_1d_lanes(samplers, &dims(Dims::LIGHT_PICK)),
            false => [0.0; N],
        };
        let light = match scene.lights.is_empty() {
            false => crate::sampler::get_2d_lanes(samplers, &dims(Dims::LIGHT)),
            true => [Vec2::ZERO; N],
        };
        let apart = match scene.lights.apart_samples() {
            true => crate::sampler::get_2d_lanes(samplers, &Dims::apart_lanes(depths)),
            false => [Vec2::ZERO; N],
        };
        let bsdf = ScatterSamples::draw_lanes(scene, samplers, depths, reads);
        std::array::from_fn(|l| Self {
            light_pick: light_pick[l],
            light: light[l],
            apart: apart[l],
            bsdf: bsdf[l],
        })
    }
}

/// A vertex on a [`Shading::Glossy`](pathwave_engine::material::Shading::Glossy) material: next-event estimation with the BSDF evaluated
/// towards the light sample and weighted against BSDF sampling by MIS (power heuristic; point,
/// spot and directional lights in full), then BSDF sampling and Russian roulette as in
/// [`scatter_with`]. Lambertian hits whose normal a map tilted ([`tilted`]) are shaded here
/// too. A delta lobe alone (a perfect mirror, smooth glass: [`Material::specular`]) reflects
/// no light sample, so none is taken. Returns the shadow rays and the next ray (`None`: the
/// path ends).
#[inline]
pub fn shade_glossy(
    scene: &RenderScene,
    st: &mut PathState,
    sp: &SurfacePoint,
    wo: Vec3A,
    mat: &Material,
    time: f32,
    u: &GlossySamples,
) -> (Shadows, Option<Ray>) {
    if mat.specular() != Specular::No {
        return (Shadows::default(), scatter_with(scene, st, sp, wo, mat, time, &u.bsdf, true));
    }
    let shadow = |lp: LightPick| light_shadow(scene, st, sp, wo, &lp, || mat.eval(wo, lp.wi, sp.ns), time);
    let ours = |lp: &LightPick| !light_traced(scene, st, lp);
    let shadows = Shadows {
        light: glossy_light(scene, sp, time, u).filter(ours).and_then(shadow),
        apart: apart_light(scene, sp.p, u.apart).filter(ours).and_then(shadow),
    };
    (shadows, scatter_with(scene, st, sp, wo, mat, time, &u.bsdf, true))
}

/// The light sample of a [`shade_glossy`] vertex at `sp` (none in a scene without lights).
#[inline(always)]
pub(crate) fn glossy_light(
    scene: &RenderScene,
    sp: &SurfacePoint,
    time: f32,
    u: &GlossySamples,
) -> Option<LightPick> {
    match scene.lights.is_empty() {
        true => None,
        false => pick_light(scene, sp.p, sp.ns, time, u.light_pick, u.light),
    }
}

/// The shadow ray of the light sample `lp` at a vertex whose BSDF towards it is `eval()`
/// (evaluated only where the direction may leave), MIS-weighted against BSDF sampling (point,
/// spot and directional lights in full); `None` where nothing can arrive.
#[inline(always)]
pub(crate) fn light_shadow(
    scene: &RenderScene,
    st: &PathState,
    sp: &SurfacePoint,
    wo: Vec3A,
    lp: &LightPick,
    eval: impl FnOnce() -> BsdfEval,
    time: f32,
) -> Option<ShadowRay> {
    // The same directions leave as in BSDF sampling, from the same side.
    let side = leaving_side(sp, wo, lp.wi)?;
    let e = eval();
    if e.f_cos == Vec3::ZERO {
        return None;
    }
    let w = if lp.delta { 1.0 } else { power_heuristic(lp.pdf, e.pdf) };
    let origin = offset_ray_origin(sp.p, sp.err, side);
    let f_cos = shadowed(scene, sp, lp.wi, e.f_cos);
    let contribution = st.beta * f_cos * lp.le * (w / lp.pdf);
    Some(ShadowRay { ray: Ray { origin, dir: lp.target - origin, time }, contribution })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::Stream;
    use pathwave_engine::math::uniform_sphere;
    use pathwave_engine::world::SceneWorld;

    /// A light sample of the environment map and a ray that escapes in its direction weigh
    /// with one density: the sample's is the light choice's probability (1: sampled apart) times the density
    /// [`escape`] reads there (the map's MIS-compensated one; up to round-off, as the sample's
    /// is read at its (u, v) and the escape's at the direction's), so that the two
    /// techniques' MIS weights sum to 1. Directions dimmer than the map's mean have radiance but no light
    /// density: [`escape`] counts them in full. (Weighing escapes by the map's complete
    /// density while light samples stay compensated fails here; in a render it made
    /// materials-env 1.3% dark, 2-3% on its ground.)
    #[test]
    fn environment_light_samples_and_escapes_weigh_with_one_density() {
        let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/materials-env.ron"));
        let desc = pathwave_engine::scene::load(path).unwrap();
        let scene = SceneWorld::render_scene(&desc);
        // Beside its point light the map is sampled apart, at every vertex: probability 1.
        let (env, pmf) = (scene.lights.environment.unwrap() as usize, scene.lights.environment_pmf());
        assert_eq!((scene.lights.apart(), pmf), (Some(env), 1.0));
        let mut rng = Stream::new(3);
        let p = Vec3A::new(0.3, 0.01, 2.0);
        let (mut sampled, mut other_cell) = (0, 0);
        let agree = |a: f32, b: f32, tol: f32| (a - b).abs() <= tol * a.abs().max(b.abs());
        for _ in 0..10_000 {
            let u = Vec2::new(rng.next_1d(), rng.next_1d());
            let Some(lp) = apart_light(&scene, p, u) else { continue };
            let (le, pdf) = scene.background.radiance_pdf(lp.wi);
            assert!(!lp.delta);
            sampled += 1;
            // The direction's (u, v) found again an ulp into the next cell.
            if !agree(lp.pdf, pmf * pdf, 1e-4) {
                other_cell += 1;
                continue;
            }
            assert!((0..3).all(|c| agree(lp.le[c], le[c], 1e-2)), "{} {} vs {le}", lp.wi, lp.le);
        }
        assert!(sampled > 5_000, "{sampled}");
        assert!(other_cell * 2000 <= sampled, "{other_cell} of {sampled} densities disagree");
        // Directions with radiance and no light density (the sky, dimmer than the map's mean):
        // an escaping ray there takes MIS weight 1.
        let mut dim = 0;
        for _ in 0..20_000 {
            let d = uniform_sphere(Vec2::new(rng.next_1d(), rng.next_1d()));
            let (le, pdf) = scene.background.radiance_pdf(d);
            if le.max_element() > 0.0 && pdf == 0.0 {
                let mut st = PathState { delta: false, prev_pdf: 0.3, ..PathState::new(p) };
                escape(&scene, &mut st, d);
                assert_eq!(st.l, le, "{d}");
                dim += 1;
            }
        }
        assert!(dim > 10_000, "{dim}");
    }
}
