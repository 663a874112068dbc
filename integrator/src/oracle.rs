//! The reference path tracer: one path at a time, recursion unrolled into a loop. It defines
//! the estimator every other integrator must match in expectation: next-event estimation on
//! quad and sphere emitters combined with BSDF sampling by MIS (power heuristic), Russian
//! roulette, box-filtered stratified pixel samples, rayon over tiles.

use crate::film::{Film, PixelAccumulator};
use crate::material::{self, power_heuristic};
use crate::sampler::{Sampler, pixel_sample};
use glam::{Vec2, Vec3, Vec3A};
use pathwave_engine::math::{Ray, offset_ray_origin};
use pathwave_engine::render_scene::RenderScene;
use pathwave_engine::shape::SurfacePoint;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Edge of the square tiles handed to rayon.
const TILE: u32 = 16;

/// Renders the whole image. `progress(done, total)` is called after each tile, from any thread.
pub fn render(scene: &RenderScene, progress: &(dyn Fn(usize, usize) + Sync)) -> Film {
    let s = scene.settings;
    let _span =
        tracing::info_span!("oracle_render", width = s.width, height = s.height, spp = s.spp).entered();
    let (tx, ty) = (s.width.div_ceil(TILE), s.height.div_ceil(TILE));
    let total = (tx * ty) as usize;
    let done = AtomicUsize::new(0);
    let tiles: Vec<Vec<PixelAccumulator>> = (0..tx * ty)
        .into_par_iter()
        .map(|t| {
            let (x0, y0) = ((t % tx) * TILE, (t / tx) * TILE);
            let mut out = Vec::with_capacity((TILE * TILE) as usize);
            for y in y0..(y0 + TILE).min(s.height) {
                for x in x0..(x0 + TILE).min(s.width) {
                    out.push(render_pixel(scene, x, y));
                }
            }
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            out
        })
        .collect();
    let mut film = Film::new(s.width, s.height);
    film.spp = s.spp;
    for (t, tile) in tiles.into_iter().enumerate() {
        let t = t as u32;
        let (x0, y0) = ((t % tx) * TILE, (t / tx) * TILE);
        let w = (x0 + TILE).min(s.width) - x0;
        for (i, acc) in tile.into_iter().enumerate() {
            let (x, y) = (x0 + i as u32 % w, y0 + i as u32 / w);
            let p = (y * s.width + x) as usize;
            film.sum[p] = acc.sum;
            film.sum_sq[p] = acc.sum_sq;
            film.non_finite += acc.non_finite;
        }
    }
    film
}

/// All samples of one pixel.
pub fn render_pixel(scene: &RenderScene, x: u32, y: u32) -> PixelAccumulator {
    let s = scene.settings;
    let pixel = y * s.width + x;
    let has_shutter = scene.camera.shutter.0 != scene.camera.shutter.1;
    let mut acc = PixelAccumulator::default();
    for i in 0..s.spp {
        let offset = pixel_sample(s.seed, pixel, i, s.spp);
        let mut sampler = Sampler::new(s.seed, pixel, i);
        let lens = sampler.next_2d();
        let time = if has_shutter { sampler.next_1d() } else { 0.0 };
        let ray = scene.camera.generate_ray(Vec2::new(x as f32, y as f32) + offset, lens, time);
        acc.add(radiance(scene, ray, &mut sampler));
    }
    acc
}

/// Radiance arriving at the ray origin along the ray (unit direction).
pub fn radiance(scene: &RenderScene, mut ray: Ray, sampler: &mut Sampler) -> Vec3 {
    let geo = &*scene.geometry;
    let lights = &*scene.lights;
    let s = scene.settings;
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    let mut eta_scale = 1.0f32;
    // State of the previous vertex for MIS on emitters hit by BSDF sampling.
    let mut delta = true;
    let mut prev_p = ray.origin;
    let mut prev_pdf = 0.0f32;
    let mut depth = 0;
    loop {
        let Some(hit) = geo.intersect(&ray, f32::INFINITY) else {
            l += beta * scene.background.radiance(ray.dir);
            break;
        };
        let sp = hit.surface;
        let mat = &scene.materials[geo.material[hit.prim as usize] as usize];
        let wo = -ray.dir;
        if mat.is_emissive() {
            let le = mat.emitted(sp.n.dot(wo));
            if le != Vec3::ZERO {
                let w = if delta {
                    1.0
                } else {
                    power_heuristic(prev_pdf, lights.pdf(geo, hit.prim, prev_p, sp.p, sp.n))
                };
                l += beta * le * w;
            }
            break; // emitters have a black BSDF
        }
        if depth == s.max_depth {
            break;
        }
        if material::has_smooth_part(mat) && !lights.is_empty() {
            l += beta * direct_light(scene, &sp, wo, mat, ray.time, sampler);
        }
        let Some(bs) = material::sample(mat, wo, sp.n, sampler.next_2d(), sampler.next_1d()) else {
            break;
        };
        beta *= bs.weight;
        eta_scale *= bs.eta * bs.eta;
        delta = bs.delta;
        prev_pdf = bs.pdf;
        prev_p = sp.p;
        let side = if bs.wi.dot(sp.n) > 0.0 { sp.n } else { -sp.n };
        ray = Ray { origin: offset_ray_origin(sp.p, sp.err, side), dir: bs.wi, time: ray.time };
        depth += 1;
        if depth >= s.rr_depth {
            let rr = (beta * eta_scale).max_element();
            if rr < 1.0 {
                let q = (1.0 - rr).max(0.0);
                if sampler.next_1d() < q {
                    break;
                }
                beta /= 1.0 - q;
            }
        }
    }
    l
}

/// One light sample at a surface point, MIS-weighted against BSDF sampling.
fn direct_light(
    scene: &RenderScene,
    sp: &SurfacePoint,
    wo: Vec3A,
    mat: &pathwave_engine::material::Material,
    time: f32,
    sampler: &mut Sampler,
) -> Vec3 {
    let (p, n) = (sp.p, sp.n);
    let geo = &*scene.geometry;
    let lights = &*scene.lights;
    let (light, pmf) = lights.pick(sampler.next_1d());
    let ls = lights.sample(geo, light, p, sampler.next_2d());
    let to = ls.p - p;
    let dist = to.length();
    if !(dist > 0.0) {
        return Vec3::ZERO;
    }
    let wi = to / dist;
    let light_mat = &scene.materials[geo.material[lights.prims[light] as usize] as usize];
    let le = light_mat.emitted(ls.n.dot(-wi));
    let pdf_light = ls.pdf * pmf;
    if le == Vec3::ZERO || !(pdf_light > 0.0) {
        return Vec3::ZERO;
    }
    let (f, pdf_bsdf) = material::eval(mat, wo, wi, n);
    if f == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let origin = offset_ray_origin(p, sp.err, if wi.dot(n) > 0.0 { n } else { -n });
    let target = offset_ray_origin(ls.p, ls.err, if ls.n.dot(wi) < 0.0 { ls.n } else { -ls.n });
    let shadow = Ray { origin, dir: target - origin, time };
    if geo.occluded(&shadow, 1.0) {
        return Vec3::ZERO;
    }
    f * le * (power_heuristic(pdf_light, pdf_bsdf) / pdf_light)
}
