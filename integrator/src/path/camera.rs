//! The start of a path: the camera rays of a pixel's samples (the pixel filter's position, the
//! lens and shutter-time numbers) and their random streams.

use crate::sampler::{Dims, Sampler, SamplerLanes};
use glam::Vec2;
use pathwave_engine::camera::RayLanes;
use pathwave_engine::math::Ray;
use pathwave_engine::render_scene::RenderScene;

/// The first ray of sample `index` of pixel (x, y), how far it reaches (the far clip plane;
/// infinite without one) and its random stream ([`camera_rays`] on one lane).
#[inline]
pub fn camera_ray(scene: &RenderScene, x: u32, y: u32, index: u32) -> (Ray, f32, Sampler) {
    let sampler = camera_sampler(scene, x, y, index);
    let (rays, _) = camera_rays(scene, &SamplerLanes::from(&[sampler]), &[(x, y)]);
    (rays.ray(0), rays.tmax[0], sampler)
}

/// Where in its pixel a sample of the stream `sampler` lies, in [0, 1)^2: where the film splats
/// it from (`PixelFilter::splats`; the pixel numbers [`camera_rays`] returns).
#[inline]
pub fn pixel_numbers(sampler: &Sampler) -> [f32; 2] {
    sampler.get_2d(Dims::PIXEL).to_array()
}

/// The camera rays of `N` samples through the pixels `pixel` with the random streams `s`, their
/// numbers and rays computed across lanes: the lens and time numbers are drawn only where the
/// camera has an aperture and something moves while the shutter is open (else zero). With
/// them, the pixel numbers ([`pixel_numbers`]).
#[inline(always)]
pub fn camera_rays<const N: usize>(
    scene: &RenderScene,
    s: &SamplerLanes<N>,
    pixel: &[(u32, u32); N],
) -> (RayLanes<N>, [Vec2; N]) {
    let u = crate::sampler::get_2d_lanes(s, &[Dims::PIXEL; N]);
    let lens = match scene.camera.has_aperture() {
        true => crate::sampler::get_2d_lanes(s, &[Dims::LENS; N]),
        false => [Vec2::ZERO; N],
    };
    let time = match scene.features.motion {
        true => crate::sampler::get_1d_lanes(s, &[Dims::TIME; N]),
        false => [0.0; N],
    };
    let (mut at, mut on_lens) = ([[0.0; 2]; N], [[0.0; 2]; N]);
    // A filter the film does not splat draws the position from the pixel numbers (filter
    // importance sampling: every sample weighs the same); the box and the splatted filters
    // take it uniformly over the pixel, in the loop of before filters.
    match &scene.settings.filter {
        filter if filter.samples_offsets() => {
            for l in 0..N {
                at[l] = filter.position(pixel[l], [u[l].x, u[l].y]);
            }
        }
        _ => {
            for l in 0..N {
                at[l] = [pixel[l].0 as f32 + u[l].x, pixel[l].1 as f32 + u[l].y];
            }
        }
    }
    for l in 0..N {
        on_lens[l] = [lens[l].x, lens[l].y];
    }
    (scene.camera.generate_rays(&at, &on_lens, &time), u)
}

/// The random stream of sample `index` of pixel (x, y).
#[inline]
pub fn camera_sampler(scene: &RenderScene, x: u32, y: u32, index: u32) -> Sampler {
    let s = scene.settings;
    let sampler = Sampler::new(s.sampler, s.seed, y * s.width + x, index, s.spp);
    if scene.camera.has_aperture() { sampler.with_lens() } else { sampler }
}
