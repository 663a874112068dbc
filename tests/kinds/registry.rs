//! The material registry: a kind registered in one line (the engine's `TestDiffuse`, built with
//! its `test-material` feature) is parsed, gets its own shading queue, stage and statistics row,
//! and renders through the wavefront's generic stage to the image its Lambertian twin gives;
//! the shape registry likewise with the engine's `TestDisk` (its `test-shape` feature), the light
//! registry with `TestPoint` (`test-light`) and the texture registry with `TestStripes`
//! (`test-texture`).
//!
//! A package of its own (`tests/kinds/Cargo.toml`), outside the workspace, so that the features
//! that add those kinds never reach the user's binary.

use glam::DVec3;
use pathwave_engine::material::{MaterialKind, Shading};
use pathwave_engine::scene::{LightKind, ShapeKind, TextureKind};
use pathwave_engine::scene::{SceneDesc, parse};
use pathwave_engine::world::SceneWorld;
use pathwave_integrator::film::Film;
use pathwave_integrator::oracle;
use pathwave_integrator::wavefront::{self, Stage, material_kinds};
use std::path::Path;

/// A scene given as text.
fn inline(text: &str) -> SceneDesc {
    parse(text, Path::new("<test>")).unwrap_or_else(|e| panic!("{e}"))
}

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
    let err = parse(&scene("Velvet", 0.5), Path::new("<test>")).unwrap_err().to_string();
    for k in MaterialKind::ALL {
        assert!(err.contains(k.variant_name()), "{err}");
    }
    // The other registries, the test-only kinds among their names.
    let lambertian = scene("Lambertian", 0.5);
    for (text, names, kind) in [
        (
            lambertian.replace("Sphere(center: (0, 0.7, 0), radius: 0.7)", "Cone(h: 1)"),
            ShapeKind::NAMES,
            "TestDisk",
        ),
        (
            lambertian.replace("objects: [", "lights: [Area(size: 1)], objects: ["),
            LightKind::NAMES,
            "TestPoint",
        ),
        (
            lambertian.replace("materials: {", r#"textures: { "t": Wood(scale: 1) }, materials: {"#),
            TextureKind::NAMES,
            "TestStripes",
        ),
    ] {
        let err = parse(&text, Path::new("<test>")).unwrap_err().to_string();
        assert!(names.contains(&kind), "{kind} is registered");
        for name in names {
            assert!(err.contains(name), "{err}");
        }
    }
}

/// A one-sided disk lamp of radius `r` at height `h`, facing down onto a floor of albedo
/// `albedo`, seen straight down from under it through a narrow camera.
fn disk_over_floor(h: f32, r: f32, albedo: f32) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0, {cam}, 0), look_at: (0, 0, 0), vup: (0, 0, -1), vfov: 2),
            render: (width: 8, height: 8, spp: 4096),
            background: Constant((0, 0, 0)),
            materials: {{
                "lamp": DiffuseLight(emit: (5, 5, 5)),
                "floor": Lambertian(albedo: ({albedo}, {albedo}, {albedo})),
            }},
            objects: [
                (shape: TestDisk(center: (0, {h}, 0), normal: (0, -1, 0), radius: {r}), material: "lamp"),
                (shape: Quad(q: (-50, 0, -50), u: (0, 0, 100), v: (100, 0, 0)), material: "floor"),
            ],
        )"#,
        cam = h / 2.0
    )
}

/// The shape registry: a kind registered by a line in each list (the engine's `TestDisk`,
/// built with its `test-shape` feature, one file for its primitive and its placement) is
/// parsed, placed, intersected and sampled as a light. Under a disk lamp of radiance L the
/// floor straight below has radiance `albedo L r^2 / (h^2 + r^2)` (the disk's irradiance on
/// its axis is `pi L r^2 / (h^2 + r^2)`); light sampling (its points and density) and the MIS
/// weight of BSDF-sampled rays that hit the disk must both be right to get it. Both
/// integrators give the same bits.
#[test]
fn a_shape_registered_in_one_line_renders_and_lights_exactly() {
    let (h, r, albedo) = (2.0, 1.0, 0.5);
    let want = (albedo * 5.0 * r * r / (h * h + r * r)) as f64;
    let text = disk_over_floor(h, r, albedo);
    let (film, _) = render(&text);
    let (mean, var) = image_mean(&film);
    let z = ((mean - DVec3::splat(want)) / var.map(f64::sqrt)).abs().max_element();
    assert!(z < 5.0 && (mean.x / want - 1.0).abs() < 0.01, "mean {mean}, want {want} (z {z})");
    let oracle = oracle::render(&SceneWorld::render_scene(&inline(&text)), &|_, _| {});
    assert!(oracle == film, "the oracle's bits");
    // A 5% darker floor is told apart.
    let (darker, _) = render(&disk_over_floor(h, r, albedo * 0.95));
    let (m, v) = image_mean(&darker);
    let z = ((m - DVec3::splat(want)) / v.map(f64::sqrt)).abs().min_element();
    assert!(z > 8.0, "5% off: mean {m}, want {want} (z {z})");
}

/// A Lambertian floor of albedo `albedo` lit only by `light` (no background), seen straight down
/// through a narrow camera from under the light.
fn floor_under(light: &str, albedo: f32) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0, 1, 0), look_at: (0, 0, 0), vup: (0, 0, -1), vfov: 2),
            render: (width: 8, height: 8, spp: 16),
            background: Constant((0, 0, 0)),
            materials: {{ "floor": Lambertian(albedo: ({albedo}, {albedo}, {albedo})) }},
            objects: [(shape: Quad(q: (-50, 0, -50), u: (0, 0, 100), v: (100, 0, 0)), material: "floor")],
            lights: [{light}],
        )"#
    )
}

/// The light registry: a kind registered in one line (the engine's `TestPoint`, built with its
/// `test-light` feature, a point light given by its power) is parsed and becomes the point light
/// of intensity `power / 4 pi`: the floor straight below it at height h has radiance
/// `albedo power / (4 pi^2 h^2)`, and the image is, bit for bit and with both integrators, the
/// one of the `Point` of that intensity.
#[test]
fn a_light_registered_in_one_line_is_the_point_light_of_its_power() {
    let (h, power, albedo) = (2.0f32, 100.0f32, 0.5f32);
    let test_point = format!("TestPoint(position: (0, {h}, 0), power: ({power}, {power}, {power}))");
    let desc = inline(&floor_under(&test_point, albedo));
    assert_eq!(desc.lights[0].kind(), LightKind::TestPoint);
    let (film, _) = render(&floor_under(&test_point, albedo));
    let want = (albedo * power / (4.0 * std::f32::consts::PI.powi(2) * h * h)) as f64;
    let (mean, _) = image_mean(&film);
    assert!((mean / want - 1.0).abs().max_element() < 1e-3, "mean {mean}, want {want}");
    let oracle = oracle::render(&SceneWorld::render_scene(&desc), &|_, _| {});
    assert!(oracle == film, "the oracle's bits");
    // The point light of the intensity it stands for: the same bits.
    let i = power / (4.0 * std::f32::consts::PI);
    let point = format!("Point(position: (0, {h}, 0), intensity: ({i}, {i}, {i}))");
    let (same, _) = render(&floor_under(&point, albedo));
    assert!(same == film, "TestPoint differs from the Point of intensity {i}");
}

/// A floor of texture `texture` lit by a square lamp, seen from above at an angle.
fn textured_floor(texture: &str) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0, 3, 3), look_at: (0, 0, 0), vfov: 50),
            render: (width: 24, height: 16, spp: 16),
            background: Constant((0.2, 0.2, 0.2)),
            textures: {{ "t": {texture} }},
            materials: {{
                "light": DiffuseLight(emit: (4, 4, 4)),
                "floor": Lambertian(albedo: "t"),
            }},
            objects: [
                (shape: Quad(q: (-1, 3, -1), u: (2, 0, 0), v: (0, 0, 2)), material: "light"),
                (shape: Quad(q: (-2, 0, -2), u: (4, 0, 0), v: (0, 0, 4)), material: "floor"),
            ],
        )"#
    )
}

/// The texture registry: a kind registered in one line (the engine's `TestStripes`, built with
/// its `test-texture` feature) is parsed and evaluated at every hit as the `UvChecker` of
/// `stripes` by 1 cells it stands for: the same bits with both integrators, and other bits with
/// a stripe more or its colours swapped.
#[test]
fn a_texture_registered_in_one_line_renders_as_its_stripes() {
    let stripes = "TestStripes(stripes: 5, even: (0.8, 0.8, 0.8), odd: (0.1, 0.3, 0.1))";
    let desc = inline(&textured_floor(stripes));
    assert_eq!(desc.textures.0[0].1.kind(), TextureKind::TestStripes);
    let (film, _) = render(&textured_floor(stripes));
    let oracle = oracle::render(&SceneWorld::render_scene(&desc), &|_, _| {});
    assert!(oracle == film, "the oracle's bits");
    let checker = |u: u32, even: &str, odd: &str| {
        render(&textured_floor(&format!("UvChecker(u: {u}, v: 1, even: {even}, odd: {odd})"))).0
    };
    let (light, dark) = ("(0.8, 0.8, 0.8)", "(0.1, 0.3, 0.1)");
    assert!(checker(5, light, dark) == film, "TestStripes differs from its UvChecker");
    assert!(checker(6, light, dark) != film, "the stripe count goes unseen");
    assert!(checker(5, dark, light) != film, "the stripes' colours go unseen");
}
