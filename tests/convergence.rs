//! Convergence against the independent references: relMSE at 64, 256 and 1024 spp must fall as
//! 1/spp (fitted log-log slope in [-1.1, -0.9], after subtracting the reference's own relMSE,
//! which no render can get below), and the image mean must be within 0.5% at 1024 spp. A biased
//! renderer flattens at high spp and fails. Renders with the wavefront (the default integrator).

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

fn check(name: &str, reference_noise: impl Fn(f64) -> f64) {
    let reference = reference(&format!("{name}.exr"));
    let mut points = Vec::new();
    let mut last_mean = 0.0;
    let mut e64 = 0.0;
    for spp in [64u32, 256, 1024] {
        let mut desc = scene(&format!("{name}.ron"));
        desc.render.spp = spp.try_into().unwrap();
        let scene = SceneWorld::render_scene(&desc);
        let film = wavefront::render(&scene, wavefront::Options::default(), &|_, _| {}).0;
        let img = film.mean();
        let e = rel_mse(&img, &reference.pixels);
        if spp == 64 {
            e64 = e;
        }
        let own = reference_noise(e64);
        eprintln!("{name} {spp} spp: relMSE {e:.6} (reference's own {own:.6})");
        assert!(
            e > own * 1.5,
            "{name}: at {spp} spp the error is too close to the reference's own noise to fit"
        );
        points.push((spp as f64, e - own));
        last_mean = mean(&img) / mean(&reference.pixels) - 1.0;
    }
    let slope = log_log_slope(&points);
    eprintln!("{name}: slope {slope:.3}, mean at 1024 spp {:+.3}%", 100.0 * last_mean);
    assert!((-1.1..=-0.9).contains(&slope), "{name}: relMSE slope {slope:.3} (a biased renderer flattens)");
    assert!(last_mean.abs() < 0.005, "{name}: mean off by {:+.3}% at 1024 spp", 100.0 * last_mean);
}

#[test]
fn cornell_converges() {
    // cornell.exr and cornell-B.exr are independent renders: half their relMSE is each one's own.
    let (a, b) = (reference("cornell.exr"), reference("cornell-B.exr"));
    let own = rel_mse(&a.pixels, &b.pixels) / 2.0;
    check("cornell", |_| own);
}

#[test]
fn cornell_diffuse_converges() {
    // The reference used 4096 spp: its own relMSE is about relMSE(64) * 64 / 4096.
    check("cornell-diffuse", |e64| e64 * 64.0 / 4096.0);
}

#[test]
fn spheres_sky_converges() {
    check("spheres-sky", |e64| e64 * 64.0 / 2048.0);
}

#[test]
fn cornell_smoke_converges() {
    // The reference used 2048 spp (ANCHORS.md).
    check("cornell-smoke", |e64| e64 * 64.0 / 2048.0);
}

#[test]
fn mesh_converges() {
    // The reference used 4096 spp (ANCHORS.md).
    check("mesh", |e64| e64 * 64.0 / 4096.0);
}
