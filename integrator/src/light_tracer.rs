//! The light tracer: the paths `pathwave_engine::lighting::light_paths` gives it (a punctual
//! light, one or more sharp vertices, a rough vertex seen by the camera), sampled from the
//! light's end and splatted where the camera sees their last vertex.
//!
//! Each sample index of a render traces as many light paths as the whole image has pixels,
//! path `i` of sample `k` from its own random stream (a hash of the seed, `k` and `i`), so that
//! the image is a function of the scene, the settings and the seed: a crop traces every path
//! and keeps what lands in it, and disjoint sample ranges add up to their union. The sums are
//! exact fixed-point integers ([`LIGHT_UNIT`]), added in any order.
//!
//! A path leaves its light with the light's power over the densities of its point and
//! direction ([`LightPaths::emit`]). At a sharp vertex it samples the BSDF from the direction
//! it came along, with the adjoint's two corrections (pbrt-v4's `TransportMode::Importance`;
//! Veach 1997, chapter 5): a refraction's radiance scaling `1 / eta^2` undone, and shading
//! normals' `|wo . ng| |wi . ns| / (|wo . ns| |wi . ng|)`. At the first rough vertex it
//! connects to the pinhole: the BSDF towards the camera, the camera's importance
//! ([`pathwave_engine::camera::Camera::pinhole_view`]) over the squared distance, and the
//! transmittance between; the splat is that over the paths a sample traces, so that a pixel's
//! sum over `spp` is its estimate. The rules a path tracer's vertex follows (which directions
//! leave, the terminator's shadowing under bump maps, one-sided surfaces) are the same
//! functions here, called with the path tracer's directions: the camera's side as `wo`, the
//! light's as `wi`.

use crate::film::LIGHT_UNIT;
use crate::path::{leaving_side, shadow_transmittance};
use crate::sampler::{Stream, mix64};
use glam::{Vec2, Vec3, Vec3A};
use pathwave_engine::camera::PinholeView;
use pathwave_engine::filter::PixelFilter;
use pathwave_engine::lighting::light_paths::{LightPaths, VertexClass};
use pathwave_engine::material::Material;
use pathwave_engine::material::Shading;
use pathwave_engine::material::wrap::{Resolved, terminator_shadowing};
use pathwave_engine::math::{Ray, offset_ray_origin};
use pathwave_engine::render_scene::RenderScene;
use pathwave_engine::shape::SurfacePoint;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicI64, Ordering};

/// Light paths a task traces.
const CHUNK: u64 = 4096;

/// Null crossings and holes a light path may pass before it counts as lost.
const MAX_CROSSINGS: u32 = 64;

/// Traces the light paths of the samples `samples` and returns their sums per pixel of the
/// scene's window (row-major), in units of [`LIGHT_UNIT`]: the film's `light`.
pub fn trace(scene: &RenderScene, plan: &LightPaths, samples: Range<u32>) -> Vec<[i64; 3]> {
    let s = &scene.settings;
    let per_sample = s.width as u64 * s.height as u64;
    let _span = tracing::info_span!("light_paths", paths = per_sample * samples.len() as u64).entered();
    let sums: Vec<[AtomicI64; 3]> = (0..s.window.len()).map(|_| Default::default()).collect();
    let win = s.window;
    let scale = (1.0 / per_sample as f64 * LIGHT_UNIT) as f32;
    let add = |x: f32, y: f32, v: Vec3| {
        let (x, y) = (x as i64 - win.x0 as i64, y as i64 - win.y0 as i64);
        if x < 0 || y < 0 || x >= win.w as i64 || y >= win.h as i64 {
            return;
        }
        // Saturating, as the film's sums: a pixel's light could otherwise wrap around.
        let at = &sums[(y * win.w as i64 + x) as usize];
        for ch in 0..3 {
            let add = |s: i64| Some(s.saturating_add(v[ch].round() as i64));
            let _ = at[ch].fetch_update(Ordering::Relaxed, Ordering::Relaxed, add);
        }
    };
    // A filter other than the box: each pixel whose centre it reaches from the image point
    // takes the splat weighed by the filter there over its integral (pbrt-v4's
    // `RGBFilm::AddSplat`), the expectation the weighted mean of the camera's samples has.
    let filter = s.filter;
    let (radius, norm) = (filter.radius(), filter.integral().powi(2) as f32);
    let splat = |pixel: Vec2, c: Vec3| {
        let v = c * scale;
        if !(v.is_finite() && v.max_element() < (1u64 << 40) as f32) {
            return;
        }
        if filter == PixelFilter::Box {
            return add(pixel.x.floor(), pixel.y.floor(), v);
        }
        let (x0, x1) = ((pixel.x - radius - 0.5).ceil(), (pixel.x + radius - 0.5).floor());
        let (y0, y1) = ((pixel.y - radius - 0.5).ceil(), (pixel.y + radius - 0.5).floor());
        let mut y = y0;
        while y <= y1 {
            let wy = filter.eval(y + 0.5 - pixel.y) / norm;
            let mut x = x0;
            while x <= x1 {
                add(x, y, v * (filter.eval(x + 0.5 - pixel.x) * wy));
                x += 1.0;
            }
            y += 1.0;
        }
    };
    let first = samples.start as u64 * per_sample;
    let total = samples.len() as u64 * per_sample;
    (0..total.div_ceil(CHUNK)).into_par_iter().for_each(|c| {
        for n in first + c * CHUNK..first + ((c + 1) * CHUNK).min(total) {
            let mut rng = Stream::new(mix64(s.seed ^ 0x6c69_6768_7450_6174) ^ n);
            trace_path(scene, plan, &mut rng, &splat);
        }
    });
    sums.into_iter().map(|a| a.map(AtomicI64::into_inner)).collect()
}

/// One light path from the stream `rng`, splatting what the camera sees of it.
fn trace_path(scene: &RenderScene, plan: &LightPaths, rng: &mut Stream, splat: &impl Fn(Vec2, Vec3)) {
    let (light, pmf) = plan.pick(rng.next_1d());
    let (t0, t1) = scene.camera.shutter;
    let time = if scene.features.motion { t0 + (t1 - t0) * rng.next_1d() } else { t0 };
    let u = [rng.next_1d(), rng.next_1d(), rng.next_1d(), rng.next_1d()];
    let Some(e) = plan.emit(light, pmf, u, time, &scene.geometry, &scene.textures) else { return };
    let (mut ray, mut beta) = (e.ray, e.beta);
    let (beta0, max_depth) = (beta.max_element(), scene.settings.max_depth);
    // Vertices the path scattered at so far, and null crossings and holes passed.
    let (mut m, mut crossings) = (0u32, 0u32);
    loop {
        let Some(mut hit) = scene.intersect(&ray, f32::INFINITY) else { return };
        let view = scene.camera.pinhole_view(hit.surface.p);
        if scene.features.wrappers {
            let wo = view.map_or(-ray.dir, |v| v.to_camera);
            let resolved = scene.resolve(hit.material, &mut hit.surface, wo, |_| rng.next_1d());
            match resolved {
                Resolved::Material(id) => hit.material = id,
                Resolved::Pass => {
                    crossings += 1;
                    if crossings > MAX_CROSSINGS {
                        return;
                    }
                    ray = straight_on(&hit.surface, ray);
                    continue;
                }
            }
        }
        let sp = &hit.surface;
        let mat = scene.material_at(hit.material, sp);
        let wi = -ray.dir;
        let (class, tilted) = (plan.class(&mat), crate::path::tilted(sp));
        // The light's neighbour must be sharp, and every vertex rough or sharp.
        if class == VertexClass::Other || m == 0 && (class != VertexClass::Sharp || tilted) {
            return;
        }
        if class == VertexClass::Rough
            && m < max_depth
            && let Some(v) = view
        {
            connect(scene, sp, &mat, wi, v, beta, time, splat);
        }
        // A vertex after it must be within the depth limit; a tilted one ends the path (its
        // tilt may depend on the direction towards the camera's side, known only there).
        if m + 2 > max_depth || tilted {
            return;
        }
        let u = Vec2::new(rng.next_1d(), rng.next_1d());
        let Some(bs) = mat.sample(wi, sp.ns, u, rng.next_1d()) else { return };
        // (Kinds with a null lobe are neither rough nor sharp.)
        if bs.null {
            return;
        }
        // The camera's side is the sampled direction, the light's the one the path came along.
        let wo = bs.wi;
        if leaving_side(sp, wo, wi).is_none() {
            return;
        }
        let mut weight = bs.weight * (bs.eta * bs.eta);
        if scene.features.tilts {
            weight *= terminator_shadowing(sp, wi);
        }
        let corr = (wo.dot(sp.n) * wi.dot(sp.ns)).abs() / (wo.dot(sp.ns) * wi.dot(sp.n)).abs();
        beta *= weight * corr;
        m += 1;
        // Russian roulette from the third vertex on, by the throughput against the light's.
        if m >= 3 {
            let q = (beta.max_element() / beta0).min(1.0);
            if !(rng.next_1d() < q) {
                return;
            }
            beta /= q;
        }
        if !(beta.max_element() > 0.0) || !beta.is_finite() {
            return;
        }
        let side = if wo.dot(sp.n) > 0.0 { sp.n } else { -sp.n };
        ray = Ray { origin: offset_ray_origin(sp.p, sp.err, side), dir: wo, time };
    }
}

/// Splats what the camera sees of a light path's throughput `beta` arriving along `-wi` at the
/// rough vertex `sp` on `mat`, which the pinhole sees as `v`.
#[expect(clippy::too_many_arguments, reason = "the vertex's pieces")]
fn connect(
    scene: &RenderScene,
    sp: &SurfacePoint,
    mat: &Material,
    wi: Vec3A,
    v: PinholeView,
    beta: Vec3,
    time: f32,
    splat: &impl Fn(Vec2, Vec3),
) {
    let wo = v.to_camera;
    if mat.shading() == Shading::Diffuse && crate::path::black_behind(mat, sp, wo) {
        return;
    }
    let Some(side) = leaving_side(sp, wo, wi) else { return };
    let mut f_cos = mat.eval(wo, wi, sp.ns).f_cos;
    if scene.features.tilts {
        f_cos *= terminator_shadowing(sp, wi);
    }
    if f_cos == Vec3::ZERO {
        return;
    }
    // The shading normal's correction: `f_cos` holds |wi . ns|, the path's measure |wo . ng|
    // towards the camera and |wi . ng| on arrival.
    let corr = wo.dot(sp.n).abs() / wi.dot(sp.n).abs();
    let origin = offset_ray_origin(sp.p, sp.err, if wo.dot(side) > 0.0 { side } else { -side });
    let target = sp.p + wo * v.dist;
    let shadow = Ray { origin, dir: target - origin, time };
    let Some(tr) = shadow_transmittance(scene, &shadow) else { return };
    splat(v.pixel, beta * f_cos * tr * (corr * v.importance / (v.dist * v.dist)));
}

/// The ray going on unbent past the surface at `sp`.
#[inline]
fn straight_on(sp: &SurfacePoint, ray: Ray) -> Ray {
    let side = if ray.dir.dot(sp.n) > 0.0 { sp.n } else { -sp.n };
    Ray { origin: offset_ray_origin(sp.p, sp.err, side), ..ray }
}
