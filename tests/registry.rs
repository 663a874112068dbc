//! The material registry: a kind registered in one line (the engine's `TestDiffuse`, built with
//! its `test-material` feature) is parsed, gets its own shading queue, stage and statistics row,
//! and renders through the wavefront's generic stage to the image its Lambertian twin gives.

mod common;

use common::inline;
use glam::DVec3;
use pathwave::engine::material::{MaterialKind, Shading};
use pathwave::engine::world::SceneWorld;
use pathwave::integrator::film::Film;
use pathwave::integrator::wavefront::{self, Stage, material_kinds};

/// A sphere on a floor under a square light and a dim sky; `kind` is the floor's and the
/// sphere's material.
fn scene(kind: &str, albedo: f32) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0, 1.5, 5), look_at: (0, 0.6, 0), vfov: 40),
            render: (width: 24, height: 18, spp: 2048),
            background: Constant((0.1, 0.1, 0.1)),
            materials: {{
                "light": DiffuseLight(emit: (6, 6, 6)),
                "m": {kind}(albedo: ({albedo}, {albedo}, 0.5)),
            }},
            objects: [
                (shape: Quad(q: (-1, 3, -1), u: (2, 0, 0), v: (0, 0, 2)), material: "light"),
                (shape: Sphere(center: (0, 0.7, 0), radius: 0.7), material: "m"),
                (shape: Quad(q: (-4, 0, -4), u: (0, 0, 8), v: (8, 0, 0)), material: "m"),
            ],
        )"#
    )
}

/// The image mean and the variance of that mean (pixels are independent).
fn image_mean(film: &Film) -> (DVec3, DVec3) {
    let n = film.mean().len() as f64;
    let m = film.mean().iter().fold(DVec3::ZERO, |a, p| a + p.as_dvec3()) / n;
    let v = film.variance_of_mean().iter().fold(DVec3::ZERO, |a, p| a + p.as_dvec3()) / (n * n);
    (m, v)
}

fn render(text: &str) -> (Film, wavefront::Stats) {
    let scene = SceneWorld::render_scene(&inline(text));
    wavefront::render(&scene, wavefront::Options::default(), &|_, _| {})
}

/// Largest |z| over the channels between two image means.
fn max_z(a: (DVec3, DVec3), b: (DVec3, DVec3)) -> f64 {
    ((a.0 - b.0) / (a.1 + b.1).map(f64::sqrt)).abs().max_element()
}

#[test]
fn a_material_registered_in_one_line_renders_through_the_wavefront() {
    let kind = MaterialKind::TestDiffuse;
    assert_eq!(kind.shading(), Shading::Sampled);
    assert_eq!(kind.stage_name(), "shade_test_diffuse");
    assert!(Stage::ALL.contains(&Stage::Shade(kind)), "the registry gives it a stage");

    let text = scene("TestDiffuse", 0.6);
    let desc = inline(&text);
    assert_eq!(material_kinds(&SceneWorld::render_scene(&desc)), vec![kind]);
    let (test, stats) = render(&text);
    let items = stats.items[Stage::Shade(kind).index()];
    assert!(items > 0, "its queue was shaded");
    assert_eq!(stats.items[Stage::Shade(MaterialKind::Lambertian).index()], 0);

    // The same expectation as the Lambertian kernel (light sampling and MIS), within noise...
    let (lambertian, _) = render(&scene("Lambertian", 0.6));
    let (a, b) = (image_mean(&test), image_mean(&lambertian));
    assert!(max_z(a, b) < 5.0, "means {} vs {} (z {})", a.0, b.0, max_z(a, b));
    // ...and far from it with an albedo 5% off.
    let (darker, _) = render(&scene("TestDiffuse", 0.57));
    let c = image_mean(&darker);
    assert!(max_z(c, b) > 8.0, "5% off: means {} vs {} (z {})", c.0, b.0, max_z(c, b));
}

#[test]
fn unknown_kinds_are_refused_with_the_registered_names() {
    let err = pathwave::engine::scene::parse(&scene("Plastic", 0.5), std::path::Path::new("<test>"))
        .unwrap_err()
        .to_string();
    for k in MaterialKind::ALL {
        assert!(err.contains(k.variant_name()), "{err}");
    }
}
