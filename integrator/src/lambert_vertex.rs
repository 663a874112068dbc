//! The Lambertian vertex under quad lights as one branch-free kernel over plain numbers: light
//! sample, BSDF evaluation and MIS weight, the shadow ray, cosine-weighted sampling of the next
//! direction (with a polynomial sine/cosine) and Russian roulette. The reference path tracer
//! runs it one path at a time; the wavefront runs it over arrays, where it vectorises across
//! paths. Inputs are gathered and outputs applied by shared code, so both compute the same bits.

use crate::material::power_heuristic;
use crate::path::{PathState, ShadowRay};
use crate::sampler::Sampler;
use glam::{Vec3, Vec3A};
use pathwave_engine::geometry::{Geometry, Primitive};
use pathwave_engine::math::Ray;
use pathwave_engine::render_scene::RenderScene;
use pathwave_engine::shape::SurfacePoint;
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};

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
    /// The picked quad light: corner, edges, unit normal, point error bound.
    pub lq: Vec3,
    /// First edge.
    pub lu: Vec3,
    /// Second edge.
    pub lv: Vec3,
    /// Unit normal.
    pub ln: Vec3,
    /// Error bound of light points.
    pub lerr: f32,
    /// 1 / area.
    pub inv_area: f32,
    /// Emitted radiance (zero when the scene has no lights).
    pub emit: Vec3,
    /// Emits on both sides.
    pub two_sided: bool,
    /// Probability of having picked this light (0: no light sampling).
    pub pmf: f32,
    /// Random numbers: light point, direction, roulette.
    pub u_light: [f32; 2],
    /// Direction.
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
    /// The roulette number was used.
    pub rr_drawn: bool,
}

#[inline(always)]
fn sel3(c: bool, a: Vec3, b: Vec3) -> Vec3 {
    Vec3::new(if c { a.x } else { b.x }, if c { a.y } else { b.y }, if c { a.z } else { b.z })
}

#[inline(always)]
fn dot(a: Vec3, b: Vec3) -> f32 {
    a.x * b.x + a.y * b.y + a.z * b.z
}

/// `offset_ray_origin` on plain numbers: error bound along the normal, then one ulp further.
#[inline(always)]
fn offset(p: Vec3, err: f32, n: Vec3) -> Vec3 {
    let d = err * (n.x.abs() + n.y.abs() + n.z.abs());
    let o = Vec3::new(d * n.x, d * n.y, d * n.z);
    let po = Vec3::new(p.x + o.x, p.y + o.y, p.z + o.z);
    let away = |x: f32, o: f32| {
        // next_up / next_down on the bits, branch-free for finite non-zero x.
        let bits = x.to_bits() as i32;
        let up = if x >= 0.0 { 1 } else { -1 };
        let step = if o > 0.0 {
            up
        } else if o < 0.0 {
            -up
        } else {
            0
        };
        let moved = f32::from_bits(bits.wrapping_add(step) as u32);
        if x == 0.0 {
            if o > 0.0 {
                f32::from_bits(1)
            } else if o < 0.0 {
                -f32::from_bits(1)
            } else {
                x
            }
        } else {
            moved
        }
    };
    Vec3::new(away(po.x, o.x), away(po.y, o.y), away(po.z, o.z))
}

/// sin and cos on [-pi/4, pi/4] (Taylor to degree 7 and 8: errors below 3.2e-7 and 2.5e-8).
#[inline(always)]
fn sin_cos_quarter(x: f32) -> (f32, f32) {
    let x2 = x * x;
    let s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0)));
    let c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
    (s, c)
}

/// Concentric map of [0,1)^2 to the unit disk, branch-free.
#[inline(always)]
fn disk(u: [f32; 2]) -> (f32, f32) {
    let (ox, oy) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    let wide = ox.abs() > oy.abs();
    let (r, ratio) = if wide { (ox, oy / ox) } else { (oy, ox / oy) };
    let (s, c) = sin_cos_quarter(FRAC_PI_4 * ratio);
    let (x, y) = if wide { (r * c, r * s) } else { (r * s, r * c) };
    let zero = ox == 0.0 && oy == 0.0;
    (if zero { 0.0 } else { x }, if zero { 0.0 } else { y })
}

/// The kernel.
#[inline(always)]
pub fn lambert(i: &LambertIn) -> LambertOut {
    let (p, n, ng) = (i.p, i.n, i.ng);
    // Light sample.
    let pl = i.lq + i.lu * i.u_light[0] + i.lv * i.u_light[1];
    let to = pl - p;
    let dist2 = dot(to, to);
    let dist = dist2.sqrt();
    let wi = to / dist;
    let cos_l = (dot(i.ln, to) / dist).abs();
    let pdf_area = if cos_l > 0.0 { i.inv_area * dist2 / cos_l } else { 0.0 };
    let pdf_light = pdf_area * i.pmf;
    let faces = i.two_sided || dot(i.ln, -wi) > 0.0;
    let (co, ci) = (dot(i.wo, n), dot(wi, n));
    let c = ci.abs() * FRAC_1_PI;
    let f = i.albedo * c;
    let w = power_heuristic(pdf_light, c);
    let contribution = i.beta * (f * i.emit * (w / pdf_light));
    // Directions must leave on the same side of the surface and of the shading normal.
    let cig = dot(wi, ng);
    let shadow =
        dist > 0.0 && pdf_light > 0.0 && faces && i.emit != Vec3::ZERO && co * ci > 0.0 && cig * ci > 0.0;
    let so = offset(p, i.err, sel3(cig > 0.0, ng, -ng));
    let st = offset(pl, i.lerr, sel3(dot(i.ln, wi) < 0.0, i.ln, -i.ln));
    // Cosine-weighted direction about the normal on the side of wo.
    let nf = sel3(co < 0.0, -n, n);
    let (dx, dy) = disk(i.u_dir);
    let z = (1.0 - (dx * dx + dy * dy)).max(0.0).sqrt();
    let pdf = z * FRAC_1_PI;
    let sign = 1f32.copysign(nf.z);
    let a = -1.0 / (sign + nf.z);
    let b = nf.x * nf.y * a;
    let t = Vec3::new(1.0 + sign * nf.x * nf.x * a, sign * b, -sign * nf.x);
    let bt = Vec3::new(b, sign + nf.y * nf.y * a, -nf.y);
    let d = t * dx + bt * dy + nf * z;
    let dg = dot(d, ng);
    let o = offset(p, i.err, sel3(dg > 0.0, ng, -ng));
    // Russian roulette.
    let beta = i.beta * i.albedo;
    let rr = (beta * i.eta_scale).max_element();
    let rr_drawn = i.rr_on && rr < 1.0;
    let q = (1.0 - rr).max(0.0);
    let survive = !(rr_drawn && i.u_rr < q);
    let beta = if rr_drawn { beta / (1.0 - q) } else { beta };
    LambertOut {
        shadow,
        so,
        sd: st - so,
        contribution,
        alive: pdf > 0.0 && survive && dg * dot(d, n) > 0.0,
        o,
        d,
        beta,
        pdf,
        rr_drawn: rr_drawn && pdf > 0.0,
    }
}

/// Gathers the kernel's inputs for a Lambertian hit, drawing the random numbers in a fixed order
/// (light pick, light point, direction, one spare, then the roulette number, which is consumed
/// by [`apply`] only if used).
#[inline]
pub fn gather(
    scene: &RenderScene,
    st: &PathState,
    sp: &SurfacePoint,
    wo: Vec3A,
    albedo: Vec3,
    sampler: &mut Sampler,
) -> LambertIn {
    let geo: &Geometry = &scene.geometry;
    let lights = &*scene.lights;
    let mut i = LambertIn {
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
    };
    if !lights.is_empty() {
        let (light, pmf) = lights.pick(sampler.next_1d());
        let prim = lights.prims[light] as usize;
        let Primitive::Quad(q) = &geo.prims[prim] else { unreachable!("call only when lights_are_quads") };
        let pathwave_engine::material::Material::DiffuseLight { emit, two_sided } =
            scene.materials[geo.material[prim] as usize]
        else {
            unreachable!("lights are emissive")
        };
        (i.lq, i.lu, i.lv, i.ln) = (q.q.into(), q.u.into(), q.v.into(), q.n.into());
        (i.lerr, i.inv_area, i.emit, i.two_sided, i.pmf) =
            (q.point_error(), 1.0 / q.area, emit, two_sided, pmf);
        let u = sampler.next_2d();
        i.u_light = [u.x, u.y];
    }
    let u = sampler.next_2d();
    i.u_dir = [u.x, u.y];
    sampler.next_1d();
    i.rr_on = i.depth_after >= scene.settings.rr_depth;
    i.u_rr = sampler.peek_1d();
    i
}

/// Applies the kernel's outputs to the path: returns the shadow ray (if any) and the next ray
/// (`None` when the path ends).
#[inline]
pub fn apply(
    i: &LambertIn,
    o: &LambertOut,
    st: &mut PathState,
    time: f32,
    sampler: &mut Sampler,
) -> (Option<ShadowRay>, Option<Ray>) {
    let shadow = o.shadow.then(|| ShadowRay {
        ray: Ray { origin: o.so.into(), dir: o.sd.into(), time },
        contribution: o.contribution,
    });
    if o.pdf <= 0.0 {
        return (shadow, None);
    }
    st.beta = o.beta;
    st.delta = false;
    st.prev_pdf = o.pdf;
    st.prev_p = i.p.into();
    st.depth = i.depth_after;
    if o.rr_drawn {
        sampler.next_1d();
    }
    let next = o.alive.then(|| Ray { origin: o.o.into(), dir: o.d.into(), time });
    (shadow, next)
}

/// Lanes processed together by [`lambert_lanes`].
pub const LANES: usize = 8;

/// A structure of `[_; LANES]` arrays mirroring a struct, with per-lane get and set: kernel
/// loops over such locals vectorise (contiguous, and no aliasing to prove).
macro_rules! lanes {
    ($lanes:ident for $t:ident { $($f:ident : $kind:tt),* $(,)? }) => {
        #[doc = concat!("`", stringify!($t), "` for ", "8 lanes, one array per component.")]
        #[derive(Clone, Copy, Default)]
        pub struct $lanes { $($f: lanes!(@ty $kind),)* }
        impl $lanes {
            /// Lane `l`.
            #[inline(always)]
            pub fn get(&self, l: usize) -> $t { $t { $($f: lanes!(@get self.$f, l, $kind),)* } }
            /// Sets lane `l`.
            #[inline(always)]
            pub fn set(&mut self, l: usize, v: &$t) { $(lanes!(@set self.$f, l, v.$f, $kind);)* }
        }
    };
    (@ty v3) => { [[f32; LANES]; 3] };
    (@ty f2) => { [[f32; LANES]; 2] };
    (@ty $k:ty) => { [$k; LANES] };
    (@get $a:expr, $l:expr, v3) => { Vec3::new($a[0][$l], $a[1][$l], $a[2][$l]) };
    (@get $a:expr, $l:expr, f2) => { [$a[0][$l], $a[1][$l]] };
    (@get $a:expr, $l:expr, $k:ty) => { $a[$l] };
    (@set $a:expr, $l:expr, $v:expr, v3) => { $a[0][$l] = $v.x; $a[1][$l] = $v.y; $a[2][$l] = $v.z; };
    (@set $a:expr, $l:expr, $v:expr, f2) => { $a[0][$l] = $v[0]; $a[1][$l] = $v[1]; };
    (@set $a:expr, $l:expr, $v:expr, $k:ty) => { $a[$l] = $v; };
}

lanes!(LambertInLanes for LambertIn {
    p: v3, n: v3, ng: v3, err: f32, wo: v3, albedo: v3, beta: v3, eta_scale: f32, depth_after: u32,
    lq: v3, lu: v3, lv: v3, ln: v3, lerr: f32, inv_area: f32, emit: v3, two_sided: bool, pmf: f32,
    u_light: f2, u_dir: f2, u_rr: f32, rr_on: bool,
});

lanes!(LambertOutLanes for LambertOut {
    shadow: bool, so: v3, sd: v3, contribution: v3, alive: bool, o: v3, d: v3, beta: v3, pdf: f32,
    rr_drawn: bool,
});

/// Runs the kernel on all lanes.
#[inline(never)]
pub fn lambert_lanes(i: &LambertInLanes, o: &mut LambertOutLanes) {
    for l in 0..LANES {
        o.set(l, &lambert(&i.get(l)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::testing::{chi2, chi2_critical};
    use glam::Vec2;

    #[test]
    fn polynomial_sine_and_cosine_are_accurate_on_the_quarter() {
        for k in 0..=2000 {
            let x = -FRAC_PI_4 + FRAC_PI_4 * 2.0 * k as f32 / 2000.0;
            let (s, c) = sin_cos_quarter(x);
            assert!((s - x.sin()).abs() < 4e-7 && (c - x.cos()).abs() < 2e-7, "{x}");
        }
    }

    #[test]
    fn disk_matches_the_concentric_map() {
        for k in 0..10_000 {
            let u = [(k % 100) as f32 / 100.0 + 0.003, (k / 100) as f32 / 100.0 + 0.007];
            let (x, y) = disk(u);
            let r = pathwave_engine::math::concentric_disk(Vec2::new(u[0], u[1]));
            assert!((x - r.x).abs() < 1e-6 && (y - r.y).abs() < 1e-6, "{u:?}");
        }
        assert_eq!(disk([0.5, 0.5]), (0.0, 0.0));
    }

    #[test]
    fn offset_equals_the_engine_offset() {
        let mut s = Sampler::new(4, 0, 0);
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
