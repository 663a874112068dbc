//! Convergence against the independent references: relMSE at 16, 64, 256 and 1024 spp must fall
//! at least as fast as 1/spp^0.9 (fitted log-log slope, after subtracting the reference's own
//! relMSE, which no render can get below, over the errors at least twice that; low-discrepancy
//! samples may fall faster than 1/spp),
//! and the image mean must be within 0.5% at 1024 spp. A biased renderer flattens at high spp
//! and fails. Renders with the wavefront (the default integrator) and the default sampler.

mod common;
use common::*;
use pathwave::engine::world::SceneWorld;
use pathwave::integrator::wavefront;
use pathwave::metrics::{mean, rel_mse};

/// Least-squares slope of log(y) against log(x).
fn log_log_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let cov: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let var: f64 = lx.iter().map(|x| (x - mx).powi(2)).sum();
    cov / var
}

/// The relMSE a reference carries of its own, estimated as that of an `spp`-sample render
/// with independent samples (as the reference's renderer used) times `spp / reference_spp`: the
/// error of independent samples falls as 1/spp.
fn reference_noise(independent_relmse: f64, spp: u32, reference_spp: u32) -> f64 {
    independent_relmse * spp as f64 / reference_spp as f64
}

fn check(name: &str, own: f64) {
    let reference = reference(&format!("{name}.exr"));
    let mut points = Vec::new();
    let mut last_mean = 0.0;
    for spp in [16u32, 64, 256, 1024] {
        let mut desc = scene(&format!("{name}.ron"));
        desc.render.spp = spp.try_into().unwrap();
        let scene = SceneWorld::render_scene(&desc);
        let film = wavefront::render(&scene, wavefront::Options::default(), &|_, _| {}).0;
        let img = film.mean();
        let e = rel_mse(&img, &reference.pixels);
        eprintln!("{name} {spp} spp: relMSE {e:.6} (reference's own {own:.6})");
        // Errors close to the reference's own noise say little about ours: fit those at least
        // twice as large.
        if e > 2.0 * own {
            points.push((spp as f64, e - own));
        }
        last_mean = mean(&img) / mean(&reference.pixels) - 1.0;
    }
    assert!(points.len() >= 3, "{name}: fewer than three errors well above the reference's own noise");
    let slope = log_log_slope(&points);
    eprintln!("{name}: slope {slope:.3}, mean at 1024 spp {:+.3}%", 100.0 * last_mean);
    assert!(slope <= -0.9, "{name}: relMSE slope {slope:.3} (a biased renderer flattens)");
    assert!(last_mean.abs() < 0.005, "{name}: mean off by {:+.3}% at 1024 spp", 100.0 * last_mean);
}

#[test]
fn cornell_converges() {
    // cornell.exr and cornell-B.exr are independent renders: half their relMSE is each one's own.
    let (a, b) = (reference("cornell.exr"), reference("cornell-B.exr"));
    check("cornell", rel_mse(&a.pixels, &b.pixels) / 2.0);
}

// The other references (Mitsuba 3, independent samples): the relMSE of 64-spp renders with
// independent samples, Mitsuba's where recorded (cornell-smoke: 0.00895), else pathwave's
// (`--sampler independent`), and the references' sample counts.

#[test]
fn cornell_diffuse_converges() {
    check("cornell-diffuse", reference_noise(0.00385, 64, 4096));
}

#[test]
fn spheres_sky_converges() {
    check("spheres-sky", reference_noise(0.00302, 64, 2048));
}

#[test]
fn cornell_smoke_converges() {
    check("cornell-smoke", reference_noise(0.00895, 64, 2048));
}

#[test]
fn mesh_converges() {
    check("mesh", reference_noise(0.00234, 64, 4096));
}

#[test]
fn materials_env_converges() {
    // materials-env.exr and materials-env-B.exr are independent renders.
    let (a, b) = (reference("materials-env.exr"), reference("materials-env-B.exr"));
    check("materials-env", rel_mse(&a.pixels, &b.pixels) / 2.0);
}
