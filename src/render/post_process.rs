//! After the samples: AOVs, the denoiser's guides and the denoised image.

use super::args::{Aov, How};
use crate::denoiser;
use crate::integrator::{aov, costs::PixelCosts, film::Film};
use crate::io::{self, LinearImage};
use crate::look::Look;
use std::path::Path;
use std::time::Instant;

/// Renders the guides and the AOVs asked for, writes those a PNG cannot hold beside it, and
/// returns the image, denoised with `--denoise` (which also keeps the image as rendered: a
/// `noisy` layer, or a file beside the output), with the layers of an EXR output.
pub fn post_process(
    scene: &crate::engine::render_scene::RenderScene,
    film: &Film,
    samples: std::ops::Range<u32>,
    img: LinearImage,
    output: &Path,
    how: &How,
    pool: &rayon::ThreadPool,
) -> Result<(LinearImage, Vec<io::ExrLayer<'static>>), String> {
    let start = Instant::now();
    // Recorded by the wavefront on the way, or traced now from the render's own camera rays
    // (the oracle, a resumed render), so that the emission they met comes out exactly.
    let aovs = match (&film.guides, how.guides()) {
        (Some(g), _) => g.clone(),
        (None, true) => pool.install(|| aov::render(scene, samples.clone())),
        (None, false) => aov::Aovs::default(),
    };
    let aov_secs = start.elapsed().as_secs_f64();
    let sibling = |tag: &str| super::args::sibling(output, tag);
    let image = |pixels| LinearImage { width: img.width, height: img.height, pixels };
    let exr = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    let flat = |v: &[glam::Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
    let rgb: &'static [&'static str] = &["R", "G", "B"];
    let mut layers = Vec::new();
    for a in &how.aov {
        match (a, exr) {
            (Aov::Albedo, true) => {
                layers.push(io::ExrLayer { name: "albedo", channels: rgb, data: flat(&aovs.albedo) })
            }
            (Aov::Normal, true) => layers.push(io::ExrLayer {
                name: "normal",
                channels: &["X", "Y", "Z"],
                data: flat(&aovs.normal),
            }),
            // Albedo and normals are data in [0, 1], shown as they are.
            (Aov::Albedo, false) => {
                io::write(&sibling("albedo"), &image(aovs.albedo.clone()), &Look::default()).map(drop)?
            }
            (Aov::Normal, false) => {
                let normal = aovs.normal.iter().map(|n| 0.5 + 0.5 * *n).collect();
                io::write(&sibling("normal"), &image(normal), &Look::default()).map(drop)?
            }
            (Aov::Depth, _) => {
                let depth = pool.install(|| aov::depth(scene, samples.clone()));
                layers.push(io::ExrLayer { name: "depth", channels: &["Z"], data: depth })
            }
            (Aov::Variance, _) => layers.push(io::ExrLayer {
                name: "variance",
                channels: rgb,
                data: flat(&film.variance_of_mean()),
            }),
            (Aov::Noisy, _) => {}
            (cost @ (Aov::Time | Aov::Paths | Aov::Bounces | Aov::Rays), _) => {
                let costs = film.costs.clone().unwrap_or_else(|| {
                    tracing::warn!("--aov {}: this run rendered no samples to measure", cost.name());
                    PixelCosts::new(film.pixels.len())
                });
                let (name, data) = match cost {
                    Aov::Time => ("time", costs.time.iter().map(|&t| t as f32).collect()),
                    Aov::Paths => ("paths", costs.paths.iter().map(|&n| n as f32).collect()),
                    Aov::Bounces => ("bounces", costs.mean_bounces()),
                    Aov::Rays => ("rays", costs.rays.iter().map(|&n| n as f32).collect()),
                    other => unreachable!("{other:?} is not a cost"),
                };
                layers.push(io::ExrLayer { name, channels: &["Y"], data })
            }
        }
    }
    if how.guides() {
        match film.guides {
            Some(_) => tracing::info!("guides recorded during the render"),
            None => tracing::info!("guides ({} rays per pixel) in {aov_secs:.2} s", samples.len()),
        }
    }
    let Some(which) = how.denoise else {
        return Ok((img, layers));
    };
    match exr && how.aov.contains(&Aov::Noisy) {
        true => layers.push(io::ExrLayer { name: "noisy", channels: rgb, data: flat(&img.pixels) }),
        false => io::write(&sibling("noisy"), &img, &how.look).map(drop)?,
    }
    let start = Instant::now();
    let variance = film.variance_of_mean();
    let threads = pool.current_num_threads();
    let out = pool.install(|| denoiser::denoise(which, &img.pixels, &variance, &aovs, threads))?;
    let guides = if film.guides.is_some() { String::new() } else { format!(" (guides {aov_secs:.2} s)") };
    if !how.quiet {
        eprintln!("denoised ({}) in {:.2} s{guides}", which.name(), start.elapsed().as_secs_f64());
    }
    Ok((image(out), layers))
}
