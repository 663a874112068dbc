//! The Lambertian vertex as one branch-free kernel over plain numbers: BSDF evaluation and MIS
//! weight of the light sample (drawn when the inputs are gathered), the shadow ray,
//! cosine-weighted sampling of the next direction (with a polynomial sine/cosine) and Russian
//! roulette. The reference path tracer
//! runs it one path at a time; the wavefront runs it over arrays, where it vectorises across
//! paths. Inputs are gathered and outputs applied by shared code, so both compute the same bits.

use crate::path::{self, PathState, ShadowRay, power_heuristic};
use crate::plain::{dot, offset, sel3};
use crate::sampler::{Dims, Sampler, SamplerLanes};
use glam::{Vec2, Vec3, Vec3A};
use pathwave_engine::math::Ray;
use pathwave_engine::math::disk_branch_free;
use pathwave_engine::render_scene::RenderScene;
use pathwave_engine::shape::SurfacePoint;
use std::f32::consts::FRAC_1_PI;

/// Everything the kernel reads for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct LambertIn {
    /// Hit point.
    pub p: Vec3,
    /// Unit shading normal (the BSDF's).
    pub n: Vec3,
    /// Unit geometric normal (rays leave along it).
    pub ng: Vec3,
    /// Error bound of `p`.
    pub err: f32,
    /// Direction to the previous vertex.
    pub wo: Vec3,
    /// Reflectance.
    pub albedo: Vec3,
    /// Throughput before this vertex.
    pub beta: Vec3,
    /// Squared IOR ratios crossed.
    pub eta_scale: f32,
    /// Bounces after this vertex scatters.
    pub depth_after: u32,
    /// Unit direction to the light sample.
    pub wi: Vec3,
    /// Radiance it sends towards the point.
    pub le: Vec3,
    /// Its solid-angle density, light choice included (0: no light sample).
    pub pdf_light: f32,
    /// The light is a point, spot or directional light: no MIS weight.
    pub delta_light: bool,
    /// The light point offset off the light, for the shadow ray to aim at.
    pub target: Vec3,
    /// Random numbers: direction.
    pub u_dir: [f32; 2],
    /// Russian roulette.
    pub u_rr: f32,
    /// Russian roulette applies at this depth.
    pub rr_on: bool,
}

/// Everything the kernel writes for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct LambertOut {
    /// A shadow ray was made.
    pub shadow: bool,
    /// Shadow ray origin.
    pub so: Vec3,
    /// Shadow ray direction (t = 1 at the light).
    pub sd: Vec3,
    /// Contribution if unoccluded.
    pub contribution: Vec3,
    /// The path goes on.
    pub alive: bool,
    /// Next ray origin.
    pub o: Vec3,
    /// Next ray direction.
    pub d: Vec3,
    /// New throughput.
    pub beta: Vec3,
    /// Density of the sampled direction.
    pub pdf: f32,
    /// The density that MIS weighs the direction with where it meets a light: the BSDF's own
    /// (cosine-weighted), which is `pdf` but at a guided vertex ([`crate::guided`]). Any
    /// densities give weights that sum to one over the two strategies; the guide learns no
    /// light that light sampling finds, so its share there is small.
    pub mis_pdf: f32,
}

/// The light sample's part of the kernel: whether it makes a shadow ray, the ray's origin
/// and its contribution if unoccluded. Its MIS weight reads the BSDF's cosine-weighted
/// density, at a guided vertex too ([`LambertOut::mis_pdf`]).
#[inline(always)]
pub(crate) fn light_part(i: &LambertIn) -> (bool, Vec3, Vec3) {
    let (p, n, ng) = (i.p, i.n, i.ng);
    let wi = i.wi;
    let (co, ci) = (dot(i.wo, n), dot(wi, n));
    let c = ci.abs() * FRAC_1_PI;
    let f = i.albedo * c;
    let w = power_heuristic(i.pdf_light, if i.delta_light { 0.0 } else { c });
    let contribution = i.beta * (f * i.le * (w / i.pdf_light));
    // The light must lie on wo's side of the shading normal, and leaves from that side: on
    // the outer side (ci > 0: ng is on the shading normal's side) whatever the facet says, on
    // the inner side only where the facet agrees (`path::leaving_side`).
    let cig = dot(wi, ng);
    let shadow = i.pdf_light > 0.0 && co * ci > 0.0 && (ci > 0.0 || cig < 0.0);
    let so = offset(p, i.err, sel3(ci > 0.0, ng, -ng));
    (shadow, so, contribution)
}

/// The shadow ray towards the light sampled apart from the choice among the others
/// (`LightTable::apart`) at the vertex of inputs `i` (its light sample replaced),
/// with the numbers `u`: the kernel's light part, one path at a time, in both integrators.
#[inline]
pub fn apart_shadow(scene: &RenderScene, i: &LambertIn, time: f32, u: Vec2) -> Option<ShadowRay> {
    let lp = path::apart_light(scene, i.p.into(), u)?;
    let i = LambertIn {
        wi: lp.wi.into(),
        le: lp.le,
        pdf_light: lp.pdf,
        delta_light: lp.delta,
        target: lp.target.into(),
        ..*i
    };
    let (shadow, so, contribution) = light_part(&i);
    shadow.then(|| ShadowRay {
        ray: Ray { origin: so.into(), dir: (i.target - so).into(), time },
        contribution,
    })
}

/// The kernel.
#[inline(always)]
pub fn lambert(i: &LambertIn) -> LambertOut {
    let (n, ng) = (i.n, i.ng);
    // Light sample.
    let (shadow, so, contribution) = light_part(i);
    let co = dot(i.wo, n);
    // Cosine-weighted direction about the normal on the side of wo.
    let nf = sel3(co < 0.0, -n, n);
    let (d, z) = cosine_about(nf, i.u_dir);
    let pdf = z * FRAC_1_PI;
    // The same rule for the sampled direction (on wo's side of the shading normal but for
    // rounding).
    let (dg, ds) = (dot(d, ng), dot(d, n));
    let leaves = (ds > 0.0 && co > 0.0) || dg * ds > 0.0;
    scatter_out(i, (shadow, so, contribution), (d, ds, pdf, pdf, leaves), i.beta * i.albedo)
}

/// The kernel's last steps, shared with the guided kernel ([`crate::guided`]): the next ray's
/// origin on the side of `d` (`ds`: its cosine with the shading normal), drawn with density
/// `pdf`, weighed in MIS with `mis_pdf` and leaving (`leaves`) or not, Russian roulette on the
/// throughput `beta` after the BSDF's weight, and the outputs with the light sample's
/// `(shadow, origin, contribution)`.
#[inline(always)]
pub(crate) fn scatter_out(
    i: &LambertIn,
    (shadow, so, contribution): (bool, Vec3, Vec3),
    (d, ds, pdf, mis_pdf, leaves): (Vec3, f32, f32, f32, bool),
    beta: Vec3,
) -> LambertOut {
    let o = offset(i.p, i.err, sel3(ds > 0.0, i.ng, -i.ng));
    let (rr_drawn, q) = path::roulette_rule(i.rr_on, beta, i.eta_scale);
    let survive = !(rr_drawn && i.u_rr < q);
    let beta = if rr_drawn { beta / (1.0 - q) } else { beta };
    LambertOut {
        shadow,
        so,
        sd: i.target - so,
        contribution,
        alive: pdf > 0.0 && survive && leaves,
        o,
        d,
        beta,
        pdf,
        mis_pdf,
    }
}

/// A cosine-weighted direction about the unit normal `nf` for the numbers `u`, and its cosine.
#[inline(always)]
pub(crate) fn cosine_about(nf: Vec3, u: [f32; 2]) -> (Vec3, f32) {
    let (dx, dy) = disk_branch_free(u);
    let z = (1.0 - (dx * dx + dy * dy)).max(0.0).sqrt();
    let sign = 1f32.copysign(nf.z);
    let a = -1.0 / (sign + nf.z);
    let b = nf.x * nf.y * a;
    let t = Vec3::new(1.0 + sign * nf.x * nf.x * a, sign * b, -sign * nf.x);
    let bt = Vec3::new(b, sign + nf.y * nf.y * a, -nf.y);
    (t * dx + bt * dy + nf * z, z)
}

/// The numbers a Lambertian vertex reads (those it does not need are left at zero).
#[derive(Clone, Copy, Debug, Default)]
pub struct VertexSamples {
    /// Which light.
    pub light_pick: f32,
    /// Where on it.
    pub light: Vec2,
    /// The point on the light sampled apart (zero where there is none).
    pub apart: Vec2,
    /// The next direction.
    pub dir: Vec2,
    /// Russian roulette.
    pub roulette: f32,
}

impl VertexSamples {
    /// The numbers of the vertex after `depth` bounces, one path at a time
    /// ([`Self::draw_lanes`]' numbers on one lane).
    #[inline]
    pub fn draw(scene: &RenderScene, sampler: &Sampler, depth: u32) -> Self {
        Self::draw_lanes_with::<1>(scene, &SamplerLanes::from(&[*sampler]), &[depth]).get(0)
    }

    /// The same numbers for `LANES` paths at once (the same bits, computed across lanes, with
    /// AVX-512 where the CPU has it).
    #[inline]
    pub fn draw_lanes(
        scene: &RenderScene,
        samplers: &SamplerLanes<LANES>,
        depths: &[u32; LANES],
    ) -> VertexSamplesLanes {
        pathwave_engine::simd::lanes(
            #[inline(always)]
            || Self::draw_lanes_with(scene, samplers, depths),
        )
    }

    /// The numbers of `N` paths' vertices after `depths` bounces, computed across lanes: the
    /// light's choice where there are lights to choose from, its point where there are
    /// lights, the direction, and roulette's where the lane plays it.
    #[inline(always)]
    fn draw_lanes_with<const N: usize>(
        scene: &RenderScene,
        samplers: &SamplerLanes<N>,
        depths: &[u32; N],
    ) -> VertexSamplesLanes<N> {
        let dims = |slot| Dims::vertex_lanes(depths, slot);
        let pick = if scene.lights.len() > 1 {
            crate::sampler::get_1d_lanes(samplers, &dims(Dims::LIGHT_PICK))
        } else {
            [0.0; N]
        };
        let light = if scene.lights.is_empty() {
            [Vec2::ZERO; N]
        } else {
            crate::sampler::get_2d_lanes(samplers, &dims(Dims::LIGHT))
        };
        let apart = match scene.lights.apart_samples() {
            true => crate::sampler::get_2d_lanes(samplers, &Dims::apart_lanes(depths)),
            false => [Vec2::ZERO; N],
        };
        let dir = crate::sampler::get_2d_lanes(samplers, &dims(Dims::BSDF));
        // Roulette's number only where some lane plays it.
        let plays = depths.map(|d| path::plays_roulette(scene, d + 1));
        let rr = if plays.contains(&true) {
            crate::sampler::get_1d_lanes(samplers, &dims(Dims::ROULETTE))
        } else {
            [0.0; N]
        };
        let mut out = VertexSamplesLanes { light_pick: pick, ..Default::default() };
        for l in 0..N {
            (out.light[0][l], out.light[1][l]) = (light[l].x, light[l].y);
            (out.apart[0][l], out.apart[1][l]) = (apart[l].x, apart[l].y);
            (out.dir[0][l], out.dir[1][l]) = (dir[l].x, dir[l].y);
            out.roulette[l] = if plays[l] { rr[l] } else { 0.0 };
        }
        out
    }
}

/// [`VertexSamples`] for `N` paths ([`LANES`] unless said), one array per number: the light
/// sampler reads its numbers as whole vectors.
#[derive(Clone, Copy, Debug)]
pub struct VertexSamplesLanes<const N: usize = LANES> {
    /// Which light, per lane.
    pub light_pick: [f32; N],
    /// Where on it: the two coordinates, per lane.
    pub light: [[f32; N]; 2],
    /// The point on the light sampled apart, per lane.
    pub apart: [[f32; N]; 2],
    /// The next direction: the two coordinates, per lane.
    pub dir: [[f32; N]; 2],
    /// Russian roulette, per lane.
    pub roulette: [f32; N],
}

impl<const N: usize> Default for VertexSamplesLanes<N> {
    fn default() -> Self {
        Self {
            light_pick: [0.0; N],
            light: [[0.0; N]; 2],
            apart: [[0.0; N]; 2],
            dir: [[0.0; N]; 2],
            roulette: [0.0; N],
        }
    }
}

impl<const N: usize> VertexSamplesLanes<N> {
    /// Lane `l`.
    #[inline(always)]
    pub fn get(&self, l: usize) -> VertexSamples {
        VertexSamples {
            light_pick: self.light_pick[l],
            light: Vec2::new(self.light[0][l], self.light[1][l]),
            apart: Vec2::new(self.apart[0][l], self.apart[1][l]),
            dir: Vec2::new(self.dir[0][l], self.dir[1][l]),
            roulette: self.roulette[l],
        }
    }
}

/// What the kernel reads of the path's state.
#[derive(Clone, Copy, Debug)]
pub struct PathIn {
    /// Throughput.
    pub beta: Vec3,
    /// Squared IOR ratios crossed.
    pub eta_scale: f32,
    /// Bounces so far.
    pub depth: u32,
}

impl From<&PathState> for PathIn {
    fn from(st: &PathState) -> Self {
        Self { beta: st.beta, eta_scale: st.eta_scale, depth: st.depth }
    }
}

/// Gathers the kernel's inputs for a Lambertian hit, with the vertex's numbers `u`.
#[inline]
pub fn gather(
    scene: &RenderScene,
    st: PathIn,
    sp: &SurfacePoint,
    wo: Vec3A,
    albedo: Vec3,
    time: f32,
    u: &VertexSamples,
) -> LambertIn {
    let mut i = gather_surface(scene, st, sp, wo, albedo, u);
    if !scene.lights.is_empty()
        && let Some(lp) = path::pick_light(scene, sp.p, i.n.into(), time, u.light_pick, u.light)
    {
        (i.wi, i.le, i.pdf_light, i.target, i.delta_light) =
            (lp.wi.into(), lp.le, lp.pdf, lp.target.into(), lp.delta);
    }
    i
}

/// [`gather`] without the light sample (left at zero).
#[inline]
pub fn gather_surface(
    scene: &RenderScene,
    st: PathIn,
    sp: &SurfacePoint,
    wo: Vec3A,
    albedo: Vec3,
    u: &VertexSamples,
) -> LambertIn {
    let mut i = surface_inputs(st, sp, wo, albedo);
    i.u_dir = [u.dir.x, u.dir.y];
    i.rr_on = path::plays_roulette(scene, i.depth_after);
    i.u_rr = u.roulette;
    i
}

/// The kernel's inputs that come from the surface and the path (the light sample and the
/// numbers left at zero).
#[inline(always)]
fn surface_inputs(st: PathIn, sp: &SurfacePoint, wo: Vec3A, albedo: Vec3) -> LambertIn {
    LambertIn {
        p: sp.p.into(),
        n: sp.ns.into(),
        ng: sp.n.into(),
        err: sp.err,
        wo: wo.into(),
        albedo,
        beta: st.beta,
        eta_scale: st.eta_scale,
        depth_after: st.depth + 1,
        ..Default::default()
    }
}

impl LambertInLanes {
    /// Sets lane `l`'s inputs from the surface and the path, as [`gather_surface`] does; the
    /// numbers are set for all lanes at once ([`Self::set_numbers`]), the light sample by
    /// [`crate::light_lanes::LightSampler`].
    #[inline(always)]
    pub fn set_surface(&mut self, l: usize, st: PathIn, sp: &SurfacePoint, wo: Vec3A, albedo: Vec3) {
        let i = surface_inputs(st, sp, wo, albedo);
        for a in 0..3 {
            (self.p[a][l], self.n[a][l], self.ng[a][l]) = (i.p[a], i.n[a], i.ng[a]);
            (self.wo[a][l], self.albedo[a][l], self.beta[a][l]) = (i.wo[a], i.albedo[a], i.beta[a]);
        }
        (self.err[l], self.eta_scale[l], self.depth_after[l]) = (i.err, i.eta_scale, i.depth_after);
    }

    /// Sets every lane's numbers from `u`, as [`gather_surface`] does (after
    /// [`Self::set_surface`], which sets the depths that decide roulette).
    #[inline(always)]
    pub fn set_numbers(&mut self, scene: &RenderScene, u: &VertexSamplesLanes) {
        (self.u_dir, self.u_rr) = (u.dir, u.roulette);
        for l in 0..LANES {
            self.rr_on[l] = path::plays_roulette(scene, self.depth_after[l]);
        }
    }
}

/// Applies the kernel's outputs to the path: returns the shadow ray (if any) and the next ray
/// (`None` when the path ends).
#[inline]
pub fn apply(
    i: &LambertIn,
    o: &LambertOut,
    st: &mut PathState,
    time: f32,
) -> (Option<ShadowRay>, Option<Ray>) {
    let shadow = o.shadow.then(|| ShadowRay {
        ray: Ray { origin: o.so.into(), dir: o.sd.into(), time },
        contribution: o.contribution,
    });
    let PathState { beta, delta, prev_pdf, prev_p, prev_n, depth, .. } = st;
    if !scattered(i.p, i.n, i.depth_after, o, Bounce { beta, delta, prev_pdf, prev_p, prev_n, depth }) {
        return (shadow, None);
    }
    let next = o.alive.then(|| Ray { origin: o.o.into(), dir: o.d.into(), time });
    (shadow, next)
}

/// The parts of a path's state that a vertex which scatters sets, wherever the path is kept (a
/// [`PathState`], or the wavefront's arrays: only these are written back there).
pub struct Bounce<'a> {
    /// Throughput.
    pub beta: &'a mut Vec3,
    /// The last scattering was a delta lobe.
    pub delta: &'a mut bool,
    /// The density MIS weighs the last scattering with ([`LambertOut::mis_pdf`]).
    pub prev_pdf: &'a mut f32,
    /// Last scattering point.
    pub prev_p: &'a mut Vec3A,
    /// Its shading normal.
    pub prev_n: &'a mut Vec3A,
    /// Bounces so far.
    pub depth: &'a mut u32,
}

/// The path's state after a vertex at `p` that makes its bounce number `depth_after`: where
/// the kernel sampled a direction (then true), `st` takes its throughput and density; else
/// (false) the path ends as it was. [`apply`] and the wavefront's Lambertian loop both call it;
/// each sends the next ray (`o.alive`) its own way.
#[inline(always)]
pub fn scattered(p: Vec3, n: Vec3, depth_after: u32, o: &LambertOut, st: Bounce) -> bool {
    if !(o.pdf > 0.0) {
        return false;
    }
    *st.beta = o.beta;
    *st.delta = false;
    *st.prev_pdf = o.mis_pdf;
    *st.prev_p = p.into();
    *st.prev_n = n.into();
    *st.depth = depth_after;
    true
}

/// Lanes processed together by [`lambert_lanes`], the light samples and the sample numbers:
/// one AVX-512 register of `f32` (two of AVX2). With AVX-512 chosen at run time
/// ([`pathwave_engine::simd`]) 16 lanes render cornell-diffuse 9% faster than 8 (which gained
/// nothing from it); with AVX2 the two take the same time.
pub const LANES: usize = 16;

/// A structure of `[_; LANES]` arrays mirroring a struct, with per-lane get and set: kernel
/// loops over such locals vectorise (contiguous, and no aliasing to prove). Field kinds: `v3`
/// (a `Vec3`), `f2` and `f3` (`[f32; 2]`, `[f32; 3]`), `[f3; N]` (`[[f32; 3]; N]`), `(lanes L)` (a
/// struct that has the lanes struct `L`), or a plain type.
macro_rules! lanes {
    ($vis:vis $lanes:ident for $t:ident { $($f:ident : $kind:tt),* $(,)? }) => {
        #[doc = concat!("`", stringify!($t), "` for [`LANES`] lanes, one array per component.")]
        #[derive(Clone, Copy, Default)]
        $vis struct $lanes { $(#[doc = concat!("`", stringify!($f), "` of every lane.")] $vis $f: lanes!(@ty $kind),)* }
        impl $lanes {
            /// Lane `l`.
            #[inline(always)]
            #[allow(dead_code, reason = "per invocation: some lane structs are only written, some only read")]
            $vis fn get(&self, l: usize) -> $t { $t { $($f: lanes!(@get self.$f, l, $kind),)* } }
            /// Sets lane `l`.
            #[inline(always)]
            #[allow(dead_code, reason = "per invocation: some lane structs are only written, some only read")]
            $vis fn set(&mut self, l: usize, v: &$t) { $(lanes!(@set self.$f, l, v.$f, $kind);)* }
        }
    };
    (@ty v3) => { [[f32; LANES]; 3] };
    (@ty f2) => { [[f32; LANES]; 2] };
    (@ty f3) => { [[f32; LANES]; 3] };
    (@ty [f3; $n:literal]) => { [[[f32; LANES]; 3]; $n] };
    (@ty (lanes $l:ident)) => { $l };
    (@ty $k:ty) => { [$k; LANES] };
    (@get $a:expr, $l:expr, v3) => { Vec3::new($a[0][$l], $a[1][$l], $a[2][$l]) };
    (@get $a:expr, $l:expr, f2) => { [$a[0][$l], $a[1][$l]] };
    (@get $a:expr, $l:expr, f3) => { [$a[0][$l], $a[1][$l], $a[2][$l]] };
    (@get $a:expr, $l:expr, [f3; $n:literal]) => {{
        let mut m = [[0.0; 3]; $n];
        for c in 0..$n {
            m[c] = [$a[c][0][$l], $a[c][1][$l], $a[c][2][$l]];
        }
        m
    }};
    (@get $a:expr, $l:expr, (lanes $k:ident)) => { $a.get($l) };
    (@get $a:expr, $l:expr, $k:ty) => { $a[$l] };
    (@set $a:expr, $l:expr, $v:expr, v3) => { $a[0][$l] = $v.x; $a[1][$l] = $v.y; $a[2][$l] = $v.z; };
    (@set $a:expr, $l:expr, $v:expr, f2) => { $a[0][$l] = $v[0]; $a[1][$l] = $v[1]; };
    (@set $a:expr, $l:expr, $v:expr, f3) => { $a[0][$l] = $v[0]; $a[1][$l] = $v[1]; $a[2][$l] = $v[2]; };
    (@set $a:expr, $l:expr, $v:expr, [f3; $n:literal]) => {
        for c in 0..$n {
            $a[c][0][$l] = $v[c][0];
            $a[c][1][$l] = $v[c][1];
            $a[c][2][$l] = $v[c][2];
        }
    };
    (@set $a:expr, $l:expr, $v:expr, (lanes $k:ident)) => { $a.set($l, &$v) };
    (@set $a:expr, $l:expr, $v:expr, $k:ty) => { $a[$l] = $v; };
}

pub(crate) use lanes;

lanes!(pub LambertInLanes for LambertIn {
    p: v3, n: v3, ng: v3, err: f32, wo: v3, albedo: v3, beta: v3, eta_scale: f32, depth_after: u32,
    wi: v3, le: v3, pdf_light: f32, delta_light: bool, target: v3, u_dir: f2, u_rr: f32, rr_on: bool,
});

lanes!(pub LambertOutLanes for LambertOut {
    shadow: bool, so: v3, sd: v3, contribution: v3, alive: bool, o: v3, d: v3, beta: v3, pdf: f32,
    mis_pdf: f32,
});

/// Runs the kernel on all lanes.
#[inline(never)]
pub fn lambert_lanes(i: &LambertInLanes, o: &mut LambertOutLanes) {
    pathwave_engine::simd::lanes(
        #[inline(always)]
        || {
            for l in 0..LANES {
                o.set(l, &lambert(&i.get(l)));
            }
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use pathwave_engine::material::chi2::{chi2, chi2_critical};

    #[test]
    fn offset_equals_the_engine_offset() {
        let mut s = crate::sampler::Stream::new(4);
        for _ in 0..10_000 {
            let p = Vec3::new(s.next_1d() - 0.5, s.next_1d() - 0.5, s.next_1d() - 0.5)
                * 10f32.powi((s.next_1d() * 12.0) as i32 - 6);
            let n = Vec3::new(s.next_1d() - 0.5, s.next_1d() - 0.5, s.next_1d() - 0.5).normalize();
            let err = s.next_1d() * 1e-4;
            let a = offset(p, err, n);
            let b = pathwave_engine::math::offset_ray_origin(p.into(), err, n.into());
            assert_eq!(a, Vec3::from(b));
        }
    }

    /// The kernel against the textbook Lambertian vertex, written plainly with the engine's
    /// own functions (concentric disk, `sin`/`cos`, the orthonormal frame, the error-bounded
    /// offset): the light sample's contribution `beta f |cos| Le w / p` with `f = albedo / pi`
    /// and the power heuristic `w = p^2 / (p^2 + (|cos| / pi)^2)`, the cosine-distributed
    /// direction about the normal on `wo`'s side and its density, the throughput and Russian
    /// roulette. Random vertices (normals, albedos, light samples, roulette on and off): the
    /// same decisions, and numbers equal to float rounding.
    #[test]
    fn the_kernel_is_the_textbook_lambertian_vertex() {
        use pathwave_engine::math::{Frame, concentric_disk, offset_ray_origin};
        let mut s = crate::sampler::Stream::new(21);
        let mut unit = || {
            let v = Vec3::new(s.next_1d() - 0.5, s.next_1d() - 0.5, s.next_1d() - 0.5);
            if v.length() > 1e-3 { v.normalize() } else { Vec3::Y }
        };
        let close =
            |a: Vec3, b: Vec3, tol: f32| (a - b).abs().max_element() <= tol * (1.0 + b.abs().max_element());
        let mut s = crate::sampler::Stream::new(22);
        let (mut shadows, mut alive) = (0, 0);
        for k in 0..20_000 {
            let n = unit();
            let i = LambertIn {
                p: Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10.0,
                n,
                ng: n,
                err: 1e-5,
                wo: unit(),
                albedo: Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()),
                beta: Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 0.4 + 0.02,
                eta_scale: 1.0,
                depth_after: 1 + (k % 8),
                wi: unit(),
                le: Vec3::splat(1.0 + 10.0 * s.next_1d()),
                pdf_light: 0.1 + 5.0 * s.next_1d(),
                target: Vec3::ONE,
                u_dir: [s.next_1d(), s.next_1d()],
                u_rr: s.next_1d(),
                rr_on: k % 2 == 0,
                ..Default::default()
            };
            let o = lambert(&i);
            // Next-event estimation.
            let (co, ci) = (i.wo.dot(n), i.wi.dot(n));
            let f_cos = i.albedo / std::f32::consts::PI * ci.abs();
            let pdf_bsdf = ci.abs() / std::f32::consts::PI;
            let w = i.pdf_light * i.pdf_light / (i.pdf_light * i.pdf_light + pdf_bsdf * pdf_bsdf);
            assert_eq!(o.shadow, co * ci > 0.0, "{k}: a light on wo's side only");
            if o.shadow {
                shadows += 1;
                assert!(close(o.contribution, i.beta * f_cos * i.le * w / i.pdf_light, 1e-5), "{k}");
                let side = if ci > 0.0 { n } else { -n };
                assert_eq!(o.so, Vec3::from(offset_ray_origin(i.p.into(), i.err, side.into())), "{k}");
            }
            // The next direction: the concentric disk lifted to the hemisphere on wo's side.
            let nf = if co < 0.0 { -n } else { n };
            let d = concentric_disk(glam::Vec2::from(i.u_dir));
            let z = (1.0 - d.length_squared()).max(0.0).sqrt();
            let want = Frame::from_normal(nf.into()).to_world(Vec3A::new(d.x, d.y, z));
            assert!(close(o.d, want.into(), 2e-5), "{k}: {} vs {want}", o.d);
            // cos = sqrt(1 - r^2) amplifies the disk's rounding near the rim: compare its square.
            let cos = o.pdf * std::f32::consts::PI;
            assert!((cos * cos - z * z).abs() <= 1e-6, "{k}: pdf {} vs {}", o.pdf, z / std::f32::consts::PI);
            // Throughput and roulette: survive with the largest channel of the new throughput
            // over the survivors' weight.
            let beta = i.beta * i.albedo;
            let q = if i.rr_on { (1.0 - beta.max_element() / path::ROULETTE_WEIGHT).max(0.0) } else { 0.0 };
            let survives = !(i.u_rr < q);
            assert_eq!(o.alive, survives && o.pdf > 0.0, "{k}");
            if survives {
                alive += 1;
                assert!(close(o.beta, beta / (1.0 - q), 1e-6), "{k}: {} vs {}", o.beta, beta / (1.0 - q));
            }
        }
        assert!(shadows > 5_000 && alive > 5_000 && alive < 19_000, "{shadows} {alive}");
    }

    #[test]
    fn sampled_directions_follow_the_cosine_density_chi2() {
        let n = Vec3::new(0.2, -0.9, 0.3).normalize();
        let wo = Vec3::new(0.5, -0.5, 0.7).normalize();
        let (stat, dof) = chi2(
            |u, _| {
                let i = LambertIn {
                    n,
                    ng: n,
                    wo,
                    u_dir: [u.x, u.y],
                    albedo: Vec3::ONE,
                    beta: Vec3::ONE,
                    ..Default::default()
                };
                let o = lambert(&i);
                (o.pdf > 0.0).then(|| Vec3A::from(o.d.normalize()))
            },
            |w| {
                let c = w.dot(Vec3A::from(n));
                if c * wo.dot(n) > 0.0 { c.abs() * FRAC_1_PI } else { 0.0 }
            },
            n.into(),
            -1.0,
            1_000_000,
        );
        assert!(stat < chi2_critical(dof), "chi2 {stat} dof {dof}");
    }
}
