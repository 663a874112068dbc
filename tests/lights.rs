//! Point, spot and directional lights against their closed forms: a white Lambertian floor
//! (albedo 1, nothing else in the scene, black background) lit by one light shows
//! `E / pi` at each point, `E` the irradiance there. Each pixel's mean is compared with the
//! closed form averaged over the pixel's box filter (16 x 16 points of the pixel).

mod common;
use common::*;
use glam::{Vec2, Vec3};
use pathwave::engine::world::SceneWorld;
use pathwave::integrator::{oracle, wavefront};
use std::f32::consts::PI;

const W: u32 = 32;

/// The scene: a floor quad at y = 0 seen from straight above, lit by `light`.
fn floor_scene(light: &str) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0, 6, 0), look_at: (0, 0, 0), vup: (0, 0, -1), vfov: 40),
            render: (width: {W}, height: {W}, spp: 256),
            materials: {{ "white": Lambertian(albedo: (1, 1, 1)) }},
            objects: [
                (shape: Quad(q: (-5, 0, -5), u: (10, 0, 0), v: (0, 0, 10)), material: "white"),
            ],
            lights: [{light}],
        )"#
    )
}

/// Checks every pixel against `expected(point on the floor)`, averaged over the pixel, within
/// 0.5% plus five standard errors of the pixel's mean (the pixel position is sampled: pixels
/// where the light changes fast vary), for both integrators.
fn check(light: &str, expected: impl Fn(Vec3) -> f32) {
    let desc = inline(&floor_scene(light));
    let scene = SceneWorld::render_scene(&desc);
    let films =
        [oracle::render(&scene, &|_, _| {}), wavefront::render(&scene, Default::default(), &|_, _| {}).0];
    let floor = |x: f32, y: f32| {
        let ray = scene.camera.generate_ray(Vec2::new(x, y), Vec2::ZERO, 0.0);
        let t = -ray.origin.y / ray.dir.y;
        Vec3::from(ray.at(t))
    };
    for film in films {
        let (mean, var) = (film.mean(), film.variance_of_mean());
        for y in 0..W {
            for x in 0..W {
                let sub = |k: u32| (k as f32 + 0.5) / 16.0;
                let e = (0..256)
                    .map(|k| expected(floor(x as f32 + sub(k % 16), y as f32 + sub(k / 16))))
                    .sum::<f32>()
                    / 256.0;
                let (got, v) = (mean[(y * W + x) as usize], var[(y * W + x) as usize]);
                for c in 0..3 {
                    let err = (got[c] - e).abs();
                    let tol = 0.005 * e + 5.0 * v[c].sqrt() + 1e-6;
                    assert!(err <= tol, "pixel ({x}, {y}): {} against {e}", got[c]);
                }
            }
        }
    }
}

#[test]
fn point_light_gives_intensity_cos_over_distance_squared() {
    let light = Vec3::new(0.5, 2.0, -0.3);
    check("Point(position: (0.5, 2, -0.3), intensity: (10, 10, 10))", |p| {
        let d = light - p;
        10.0 * (d.y / d.length()) / d.length_squared() / PI
    });
}

#[test]
fn spot_light_is_full_inside_its_falloff_and_dark_outside_its_cone() {
    let light = Vec3::new(0.0, 2.0, 0.0);
    let (cos_total, cos_falloff) = (30f32.to_radians().cos(), 20f32.to_radians().cos());
    check(
        "Spot(position: (0, 2, 0), look_at: (0, 0, 0), intensity: (10, 10, 10), cone_angle: 30, falloff_start: 20)",
        |p| {
            let d = light - p;
            let cos = d.y / d.length();
            let t = ((cos - cos_total) / (cos_falloff - cos_total)).clamp(0.0, 1.0);
            10.0 * t * t * (3.0 - 2.0 * t) * cos / d.length_squared() / PI
        },
    );
}

#[test]
fn directional_light_gives_irradiance_times_cosine() {
    let dir = Vec3::new(1.0, -2.0, 0.5).normalize();
    check("Directional(direction: (1, -2, 0.5), irradiance: (3, 3, 3))", |_| 3.0 * -dir.y / PI);
}

/// The check above sees an intensity 2% off.
#[test]
fn light_check_catches_a_wrong_intensity() {
    let light = Vec3::new(0.5, 2.0, -0.3);
    let r = std::panic::catch_unwind(|| {
        check("Point(position: (0.5, 2, -0.3), intensity: (10.2, 10.2, 10.2))", |p| {
            let d = light - p;
            10.0 * (d.y / d.length()) / d.length_squared() / PI
        })
    });
    assert!(r.is_err());
}

/// A point light and an area light together: each light is chosen by its power, and the sum is
/// what each gives alone.
#[test]
fn a_point_light_beside_an_emitter_adds_up() {
    // The lamp stays in the scene (it hides part of the floor), emitting or not.
    let with = |lights: &str, emit: f32| {
        let lamp = r#"(shape: Quad(q: (-0.5, 3, -0.5), u: (1, 0, 0), v: (0, 0, 1)), material: "lamp"),"#;
        let text = floor_scene(lights)
            .replace(
                r#""white": Lambertian"#,
                &format!(r#""lamp": DiffuseLight(emit: ({emit}, {emit}, {emit})), "white": Lambertian"#),
            )
            .replace("objects: [", &format!("objects: [{lamp}"));
        let desc = inline(&text);
        render(&desc).mean().iter().map(|p| p.x as f64).sum::<f64>()
    };
    let point = "Point(position: (1, 2, 0), intensity: (5, 5, 5))";
    let (both, lamp, alone) = (with(point, 4.0), with("", 4.0), with(point, 0.0));
    let rel = (both - lamp - alone).abs() / both;
    assert!(rel < 0.01, "both {both}, lamp {lamp}, point {alone}");
}

#[test]
fn bad_spot_cones_are_refused_with_their_place() {
    for (bad, what) in [
        ("cone_angle: 190", "cone_angle must be in (0, 180)"),
        ("cone_angle: 20, falloff_start: 25", "falloff_start must be in [0, cone_angle = 20]"),
    ] {
        let text = floor_scene(&format!(
            "Spot(position: (0, 2, 0), look_at: (0, 0, 0), intensity: (1, 1, 1), {bad})"
        ));
        let err =
            pathwave::engine::scene::parse(&text, std::path::Path::new("<test>")).unwrap_err().to_string();
        assert!(err.contains(what) && err.contains("<test>:"), "{err}");
    }
}
