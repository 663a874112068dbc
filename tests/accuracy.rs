//! Accuracy against independent ground-truth renders (`tests/references`, linear EXR made
//! with another renderer): block means must agree within the noise estimated from the render itself,
//! and the same test must reject the scene with a deliberate 5% error (an albedo, a density).
//!
//! The noise estimate is the pixels' sample variance over the sample count. For the
//! low-discrepancy default sampler the error of the mean is smaller than that (chi-square per
//! block about 0.4 instead of 1), so the agreement check is conservative, and every scene's
//! deliberate errors show that the test still sees 5%. Independent samples would make the
//! estimate exact on average but not robust: caustics through cornell's glass are rare paths
//! whose block means are heavy-tailed (+-8% over seeds at 128 spp), and the variance of the
//! samples misses what they did not find.

mod common;
use common::*;
use pathwave::engine::material::microfacet::{Roughness, Smith};
use pathwave::engine::scene::{Body, MaterialDesc, Positive, SceneDesc};

/// A deliberate error: what it is, and how to make it.
type Error = (&'static str, fn(&mut SceneDesc));

fn check(scene_file: &str, reference_file: &str, ref_spp: u32, spp: u32, errors: &[Error]) {
    let reference = reference(reference_file);
    let mut desc = scene(scene_file);
    desc.render.spp = spp.try_into().unwrap();
    let stats = block_z(&render(&desc), &reference, 16, ref_spp);
    eprintln!("{scene_file}: {stats:?}");
    assert!(stats.agrees(), "{scene_file} disagrees with its reference: {stats:?}");

    // The same test must be able to fail.
    for (what, make) in errors {
        let mut wrong = desc.clone();
        make(&mut wrong);
        let stats = block_z(&render(&wrong), &reference, 16, ref_spp);
        eprintln!("{scene_file} with {what}: {stats:?}");
        assert!(!stats.agrees(), "{what} went unnoticed: {stats:?}");
    }
}

const WHITE_ALBEDO: Error = ("white albedo +5%", |d| scale_albedo(d, "white", 1.05));

#[test]
fn cornell_matches_reference() {
    // 256 spp, not fewer: the caustics of the mirror box and the glass sphere on the walls are
    // skewed (most renders miss some of their rare bright paths, and the pixels' variance does
    // not count what they missed). At 128 spp three of seeds 0-5 failed, with the sampler of
    // 2026-12-03 morning and with today's alike; at 256 all six pass with both.
    check("cornell.ron", "cornell.exr", 4096, 256, &[WHITE_ALBEDO]);
}

#[test]
fn cornell_diffuse_matches_reference() {
    check("cornell-diffuse.ron", "cornell-diffuse.exr", 4096, 64, &[WHITE_ALBEDO]);
}

#[test]
fn cornell_smoke_matches_reference() {
    // The reference was rendered at 2048 spp (tests/references/README.md); fitted from our renders at 64 to
    // 4096 spp its own relMSE (0.00027) is what we reach at about 1900, close enough.
    let white_smoke_density: Error = ("white smoke density +5%", |d| {
        for o in &mut d.objects {
            if let Body::Volume(m) = &mut o.body
                && m.albedo.0.x == 1.0
            {
                m.density = Positive(m.density.0 * 1.05);
            }
        }
    });
    check("cornell-smoke.ron", "cornell-smoke.exr", 2048, 256, &[WHITE_ALBEDO, white_smoke_density]);
}

#[test]
fn spheres_sky_matches_reference() {
    check(
        "spheres-sky.ron",
        "spheres-sky.exr",
        2048,
        64,
        &[("ground albedo +5%", |d| scale_albedo(d, "ground", 1.05))],
    );
}

#[test]
fn mesh_matches_reference() {
    let knot: Error = ("knot albedo +5%", |d| scale_albedo(d, "knot", 1.05));
    check("mesh.ron", "mesh.exr", 4096, 64, &[WHITE_ALBEDO, knot]);
}

/// Sets every rough material's alpha to `f(alpha)` and its Smith term to `smith`.
fn rough(d: &mut SceneDesc, f: fn(f32) -> f32, smith: Smith) {
    for (_, m) in &mut d.materials.0 {
        match m {
            MaterialDesc::RoughConductor(c) => (c.alpha, c.smith) = (Roughness(f(c.alpha.0)), smith),
            MaterialDesc::RoughDielectric(g) => (g.alpha, g.smith) = (Roughness(f(g.alpha.0)), smith),
            _ => {}
        }
    }
}

#[test]
fn materials_env_matches_reference() {
    let alpha: Error = ("alpha +20%", |d| rough(d, |a| a * 1.2, Smith::Separable));
    let smith: Error = ("height-correlated Smith", |d| rough(d, |a| a, Smith::HeightCorrelated));
    // The two Smith forms differ by a few percent only near grazing angles on the spheres:
    // 512 spp make that many sigma.
    check("materials-env.ron", "materials-env.exr", 4096, 512, &[alpha, smith]);
}
