//! Renders against the independent references (`tests/references`, linear EXR made with another
//! renderer). Each scene is checked two ways, from one sequence of renders:
//!
//! - **Accuracy.** Block means must agree within the noise estimated from the render itself, and
//!   the same test must reject the scene with a deliberate 5% error (an albedo, a density). The
//!   noise estimate is the pixels' sample variance over the sample count. For the low-discrepancy
//!   default sampler the error of the mean is smaller than that (chi-square per block about 0.4
//!   instead of 1), so the agreement check is conservative, and every scene's deliberate errors
//!   show that the test still sees 5%. Independent samples would make the estimate exact on
//!   average but not robust: caustics through cornell's glass are rare paths whose block means
//!   are heavy-tailed (+-8% over seeds at 128 spp), and the variance of the samples misses what
//!   they did not find.
//! - **Convergence.** relMSE at 16, 64, 256 and 1024 spp must fall at least as fast as
//!   1/spp^0.9 (fitted log-log slope, after subtracting the reference's own relMSE, which no
//!   render can get below, over the errors at least twice that; low-discrepancy samples may fall
//!   faster than 1/spp), and the image mean must be within 0.5% at 1024 spp. A biased renderer
//!   flattens at high spp and fails.
//!
//! Renders with the wavefront (the default integrator) and the default sampler, Owen-scrambled
//! Sobol, whose first N samples of a pixel are those of an N-spp render: the renders at each
//! sample count are one 1024-spp render made in sample ranges and merged as it goes. The
//! reference path tracer (the oracle) is held to the same references through the wavefront:
//! `tests/wavefront.rs` shows that both draw the same samples on each of these scenes.

mod common;
use common::*;
use pathwave::engine::format::Scalar;
use pathwave::engine::material::microfacet::{Roughness, Smith};
use pathwave::engine::scene::{Body, Density, MaterialDesc, SceneDesc};
use pathwave::engine::world::SceneWorld;
use pathwave::integrator::film::Film;
use pathwave::integrator::wavefront;
use pathwave::metrics::{mean, rel_mse};

/// A deliberate error: what it is, and how to make it.
type Error = (&'static str, fn(&mut SceneDesc));

/// The sample counts whose relMSE the convergence check fits.
const LADDER: [u32; 4] = [16, 64, 256, 1024];

/// One scene's checks.
struct Case {
    /// The scene (`scenes/NAME.ron`) and its reference (`tests/references/NAME.exr`).
    name: &'static str,
    /// The samples per pixel the reference was rendered with.
    reference_spp: u32,
    /// The relMSE the reference carries of its own.
    own: f64,
    /// The samples per pixel of the accuracy check: enough for its deliberate errors to show.
    accuracy_spp: u32,
    /// The deliberate errors the accuracy check must see.
    errors: &'static [Error],
}

fn render(desc: &SceneDesc, samples: std::ops::Range<u32>) -> Film {
    let scene = SceneWorld::render_scene(desc);
    wavefront::render_samples(&scene, wavefront::Options::default(), samples, &|_, _| {}).0
}

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

/// Half the relMSE between two independent references of a scene: each one's own.
fn reference_pair_noise(name: &str) -> f64 {
    let (a, b) = (reference(&format!("{name}.exr")), reference(&format!("{name}-B.exr")));
    rel_mse(&a.pixels, &b.pixels) / 2.0
}

fn check(case: Case) {
    let name = case.name;
    let reference = reference(&format!("{name}.exr"));
    let mut desc = scene(&format!("{name}.ron"));
    let last = *LADDER.last().unwrap();
    desc.render.spp = last.try_into().unwrap();
    assert!(case.accuracy_spp <= last);
    let mut stops: Vec<u32> = LADDER.into_iter().chain([case.accuracy_spp]).collect();
    stops.sort_unstable();
    stops.dedup();

    let mut film: Option<Film> = None;
    let mut points = Vec::new();
    let mut last_mean = 0.0;
    for spp in stops {
        let done = film.as_ref().map_or(0, |f| f.spp);
        let part = render(&desc, done..spp);
        film = Some(match film {
            Some(mut f) => {
                f.merge(&part);
                f
            }
            None => part,
        });
        let film = film.as_ref().unwrap();
        if spp == case.accuracy_spp {
            let stats = block_z(film, &reference, 16, case.reference_spp);
            eprintln!("{name} {spp} spp: {stats:?}");
            assert!(stats.agrees(), "{name} disagrees with its reference: {stats:?}");
        }
        if LADDER.contains(&spp) {
            let img = film.mean();
            let e = rel_mse(&img, &reference.pixels);
            eprintln!("{name} {spp} spp: relMSE {e:.6} (reference's own {:.6})", case.own);
            // Errors close to the reference's own noise say little about ours: fit those at
            // least twice as large.
            if e > 2.0 * case.own {
                points.push((spp as f64, e - case.own));
            }
            last_mean = mean(&img) / mean(&reference.pixels) - 1.0;
        }
    }
    assert!(points.len() >= 3, "{name}: fewer than three errors well above the reference's own noise");
    let slope = log_log_slope(&points);
    eprintln!("{name}: slope {slope:.3}, mean at {last} spp {:+.3}%", 100.0 * last_mean);
    assert!(slope <= -0.9, "{name}: relMSE slope {slope:.3} (a biased renderer flattens)");
    assert!(last_mean.abs() < 0.005, "{name}: mean off by {:+.3}% at {last} spp", 100.0 * last_mean);

    // The accuracy check must be able to fail.
    for (what, make) in case.errors {
        let mut wrong = desc.clone();
        make(&mut wrong);
        let stats = block_z(&render(&wrong, 0..case.accuracy_spp), &reference, 16, case.reference_spp);
        eprintln!("{name} with {what}: {stats:?}");
        assert!(!stats.agrees(), "{what} went unnoticed: {stats:?}");
    }
}

const WHITE_ALBEDO: Error = ("white albedo +5%", |d| scale_albedo(d, "white", 1.05));

#[test]
fn cornell() {
    // cornell.exr and cornell-B.exr are independent renders. Accuracy at 256 spp, not fewer: the
    // caustics of the mirror box and the glass sphere on the walls are skewed (most renders miss
    // some of their rare bright paths, and the pixels' variance does not count what they
    // missed). At 128 spp three of seeds 0-5 failed, with the sampler of 2026-12-03 morning and
    // with today's alike; at 256 all six pass with both.
    check(Case {
        name: "cornell",
        reference_spp: 4096,
        own: reference_pair_noise("cornell"),
        accuracy_spp: 256,
        errors: &[WHITE_ALBEDO],
    });
}

// The other references (Mitsuba 3, independent samples): their own relMSE is that of 64-spp
// renders with independent samples, Mitsuba's where recorded (cornell-smoke: 0.00895), else
// pathwave's (`--sampler independent`), scaled to the references' sample counts.

#[test]
fn cornell_diffuse() {
    check(Case {
        name: "cornell-diffuse",
        reference_spp: 4096,
        own: reference_noise(0.00385, 64, 4096),
        accuracy_spp: 64,
        errors: &[WHITE_ALBEDO],
    });
}

#[test]
fn cornell_smoke() {
    // The reference was rendered at 2048 spp (tests/references/README.md); fitted from our
    // renders at 64 to 4096 spp its own relMSE (0.00027) is what we reach at about 1900, close
    // enough.
    const WHITE_SMOKE_DENSITY: Error = ("white smoke density +5%", |d| {
        for o in &mut d.objects {
            if let Body::Volume(m) = &mut o.body
                && m.albedo.0.x == 1.0
            {
                m.density = Density(m.density.0 * 1.05);
            }
        }
    });
    check(Case {
        name: "cornell-smoke",
        reference_spp: 2048,
        own: reference_noise(0.00895, 64, 2048),
        accuracy_spp: 256,
        errors: &[WHITE_ALBEDO, WHITE_SMOKE_DENSITY],
    });
}

#[test]
fn spheres_sky() {
    check(Case {
        name: "spheres-sky",
        reference_spp: 2048,
        own: reference_noise(0.00302, 64, 2048),
        accuracy_spp: 64,
        errors: &[("ground albedo +5%", |d| scale_albedo(d, "ground", 1.05))],
    });
}

#[test]
fn mesh() {
    check(Case {
        name: "mesh",
        reference_spp: 4096,
        own: reference_noise(0.00234, 64, 4096),
        accuracy_spp: 64,
        errors: &[WHITE_ALBEDO, ("knot albedo +5%", |d| scale_albedo(d, "knot", 1.05))],
    });
}

/// Sets every rough material's alpha (a number) to `f(alpha)` and its Smith term to `smith`.
fn rough(d: &mut SceneDesc, f: fn(f32) -> f32, smith: Smith) {
    let map = |a: &mut Scalar<Roughness>| {
        if let Scalar::Value(r) = a {
            *r = Roughness(f(r.0));
        }
    };
    for (_, m) in &mut d.materials.0 {
        match m {
            MaterialDesc::RoughConductor(c) => {
                map(&mut c.alpha);
                c.smith = smith;
            }
            MaterialDesc::RoughDielectric(g) => {
                map(&mut g.alpha);
                g.smith = smith;
            }
            _ => {}
        }
    }
}

#[test]
fn materials_env() {
    // materials-env.exr and materials-env-B.exr are independent renders. The two Smith forms
    // differ by a few percent only near grazing angles on the spheres: 512 spp make that many
    // sigma.
    check(Case {
        name: "materials-env",
        reference_spp: 4096,
        own: reference_pair_noise("materials-env"),
        accuracy_spp: 512,
        errors: &[
            ("alpha +20%", |d| rough(d, |a| a * 1.2, Smith::Separable)),
            ("height-correlated Smith", |d| rough(d, |a| a, Smith::HeightCorrelated)),
        ],
    });
}
