//! Auxiliary images for the denoiser: the albedo, the shading normal and the emitted radiance
//! seen directly through each pixel, averaged over the same camera rays (lens, pixel area,
//! shutter time) as the render's samples. Perfect mirrors and glass pass the albedo and normal
//! guides on to the first other surface they show (media are not followed).
//!
//! With every sample of the render traced, `emission` is exactly the part of each pixel's mean
//! that camera rays found on emitters and the background (times the media's transmittance,
//! its expectation, in scenes with media): the denoiser filters the rest and adds it back, so
//! lights and their antialiased edges stay as sharp as rendered.

use crate::path;
use glam::Vec3;
use pathwave_engine::material::dielectric::refract;
use pathwave_engine::material::{Material, Specular};
use pathwave_engine::math::{Ray, offset_ray_origin, reflect};
use pathwave_engine::render_scene::RenderScene;
use rayon::prelude::*;
use std::ops::Range;

/// Per-pixel albedo, normal and directly seen emission, row-major, row 0 on top.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Aovs {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Mean albedo in [0, 1]: the material's reflectance, 1 for glass, the clamped radiance of
    /// an emitter or of the background where a ray leaves the scene.
    pub albedo: Vec<Vec3>,
    /// Mean world-space shading normal turned towards the camera (not renormalised: its length
    /// falls where a pixel sees several orientations); zero where rays leave the scene.
    pub normal: Vec<Vec3>,
    /// Mean radiance of emitters and background met by the camera rays themselves.
    pub emission: Vec<Vec3>,
}

/// Traces the camera rays of samples `samples` of every pixel (the render's own: give its
/// sample range, and `emission` is exactly what its camera rays met).
pub fn render(scene: &RenderScene, samples: Range<u32>) -> Aovs {
    let _span = tracing::info_span!("render_aovs", samples = samples.len()).entered();
    let win = scene.settings.window;
    let (w, h) = (win.w, win.h);
    let n = samples.len().max(1) as f32;
    let rows: Vec<Vec<[Vec3; 3]>> = (win.y0..win.y0 + h)
        .into_par_iter()
        .map(|y| {
            (win.x0..win.x0 + w)
                .map(|x| {
                    let mut sum = [Vec3::ZERO; 3];
                    for index in samples.clone() {
                        let (ray, tmax, _) = path::camera_ray(scene, x, y, index);
                        let one = first_surface(scene, &ray, tmax);
                        (0..3).for_each(|k| sum[k] += one[k]);
                    }
                    sum.map(|v| v / n)
                })
                .collect()
        })
        .collect();
    let mut out = Aovs { width: w, height: h, ..Default::default() };
    for [a, n, e] in rows.into_iter().flatten() {
        out.albedo.push(a);
        out.normal.push(n);
        out.emission.push(e);
    }
    out
}

/// Per pixel, the mean distance along the camera rays of samples `samples` to the first
/// surface they meet (mirrors and glass included), over the rays that meet one; infinity where
/// none does. Distances are in world units from the ray's origin (on the lens, or on the near
/// clip plane).
pub fn depth(scene: &RenderScene, samples: Range<u32>) -> Vec<f32> {
    let _span = tracing::info_span!("render_depth", samples = samples.len()).entered();
    let win = scene.settings.window;
    (win.y0..win.y0 + win.h)
        .into_par_iter()
        .flat_map_iter(|y| {
            let samples = samples.clone();
            (win.x0..win.x0 + win.w).map(move |x| {
                let (mut sum, mut n) = (0.0f64, 0u32);
                for index in samples.clone() {
                    let (ray, tmax, _) = path::camera_ray(scene, x, y, index);
                    if let Some(h) = scene.intersect(&ray, tmax) {
                        sum += (h.t * ray.dir.length()) as f64;
                        n += 1;
                    }
                }
                if n == 0 { f32::INFINITY } else { (sum / n as f64) as f32 }
            })
        })
        .collect()
}

/// The sky's albedo guide: its radiance, clamped.
#[inline]
pub fn sky_albedo(radiance: Vec3) -> Vec3 {
    radiance.clamp(Vec3::ZERO, Vec3::ONE)
}

/// What a camera ray has shown so far, as it follows perfect mirrors and glass: the one rule
/// for the albedo and normal guides, applied by the separate pass ([`render`]) and by the
/// wavefront's `record_guides` stage to its paths.
#[derive(Clone, Copy, Debug)]
pub struct Guide {
    /// Still following perfect mirrors and glass from the camera: albedo and normal to come.
    pub open: bool,
    /// The last surface followed was glass (its normal, facing the ray that came, is `normal`).
    pub glass: bool,
    /// Product of the mirrors' albedos so far.
    pub tint: Vec3,
    /// Albedo of the first surface that is not a perfect mirror or glass.
    pub albedo: Vec3,
    /// Its camera-facing shading normal (or the last mirror's or glass's).
    pub normal: Vec3,
    /// Radiance the camera ray itself met on an emitter or the background.
    pub emission: Vec3,
}

impl Guide {
    /// A fresh camera ray's.
    pub const NEW: Guide = Guide {
        open: true,
        glass: false,
        tint: Vec3::ONE,
        albedo: Vec3::ZERO,
        normal: Vec3::ZERO,
        emission: Vec3::ZERO,
    };

    /// Records the surface that ends the chain of mirrors and glass.
    #[inline]
    pub fn close(&mut self, albedo: Vec3, normal: Vec3) {
        (self.open, self.albedo, self.normal) = (false, self.tint * albedo, normal);
    }

    /// The ray met a surface of material `m` whose shading normal, turned towards the ray, is
    /// `ns`: a perfect mirror tints what follows, glass hands on to what it shows, anything
    /// else (emitters included) closes the chain.
    #[inline]
    pub fn surface(&mut self, m: &Material, ns: Vec3) {
        match m.specular() {
            Specular::Mirror => (self.tint, self.normal, self.glass) = (self.tint * m.albedo(), ns, false),
            Specular::Glass { .. } => (self.normal, self.glass) = (ns, true),
            Specular::No => self.close(m.albedo(), ns),
        }
    }

    /// The ray left the scene where the background's radiance is `sky`: the sky's albedo, and
    /// the last mirror's or glass's normal (zero if none, as the sky's own pixels).
    #[inline]
    pub fn sky(&mut self, sky: Vec3) {
        let normal = self.normal;
        self.close(sky_albedo(sky), normal);
    }
}

/// Perfect mirrors and glass hand the guides on to what they show, up to this many times.
const MAX_SPECULAR: u32 = 4;

/// Albedo, camera-facing shading normal and emitted radiance of what a camera ray sees. The
/// emission is the first surface's or the background's, as [`path::emit`] and [`path::escape`]
/// add it at the first vertex. Albedo and normal are those of the first surface that is not a
/// perfect mirror or glass (tinted by the mirrors on the way; glass refracts unless the light
/// cannot get out), so that what those show keeps its edges. The camera ray sees surfaces
/// closer than `tmax` (the far clip plane).
fn first_surface(scene: &RenderScene, camera: &Ray, tmax: f32) -> [Vec3; 3] {
    let first = scene.intersect(camera, tmax);
    let transmittance = if scene.features.media {
        scene.media.transmittance(camera, first.map_or(f32::INFINITY, |h| h.t))
    } else {
        Vec3::ONE
    };
    let emission = match &first {
        None => scene.background.radiance(camera.dir),
        Some(h) => scene.emitted(h.material, &h.surface, h.surface.n.dot(-camera.dir)),
    } * transmittance;
    // The last mirror's or glass's normal: a reflection of the sky keeps it, so that it does
    // not pass for the sky itself (whose pixels hold only emission).
    let (mut ray, mut hit, mut g) = (*camera, first, Guide::NEW);
    for bounce in 0..=MAX_SPECULAR {
        let Some(h) = hit else {
            g.sky(scene.background.radiance(ray.dir));
            return [g.albedo, g.normal, emission];
        };
        let sp = &h.surface;
        let wo = -ray.dir.normalize();
        let ns = if sp.ns.dot(wo) < 0.0 { -sp.ns } else { sp.ns };
        let m = scene.material_at(h.material, sp);
        match bounce {
            // The last bounce shows what it meets, mirror and glass alike.
            MAX_SPECULAR => g.close(m.albedo(), ns.into()),
            _ => g.surface(&m, ns.into()),
        }
        if !g.open {
            return [g.albedo, g.normal, emission];
        }
        let dir = match m.specular() {
            Specular::Glass { ior } => {
                let eta = if sp.ns.dot(wo) >= 0.0 { ior } else { 1.0 / ior };
                refract(wo, ns, eta).unwrap_or_else(|| reflect(wo, ns))
            }
            _ => reflect(wo, ns),
        };
        let side = if dir.dot(sp.n) > 0.0 { sp.n } else { -sp.n };
        ray = Ray { origin: offset_ray_origin(sp.p, sp.err, side), dir, time: ray.time };
        hit = scene.intersect(&ray, f32::INFINITY);
    }
    unreachable!("the last bounce returns")
}
