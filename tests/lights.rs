//! Point, spot and directional lights and projectors against their closed forms: a white Lambertian floor
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
    floor_scene_with("", light)
}

/// [`floor_scene`] with the `textures` map's entries.
fn floor_scene_with(textures: &str, light: &str) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0, 6, 0), look_at: (0, 0, 0), vup: (0, 0, -1), vfov: 40),
            render: (width: {W}, height: {W}, spp: 256),
            textures: {{ {textures} }},
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
    check_with("", light, expected)
}

/// [`check`] with the `textures` map's entries.
fn check_with(textures: &str, light: &str, expected: impl Fn(Vec3) -> f32) {
    check_scene(&floor_scene_with(textures, light), expected)
}

/// [`check`] on the scene `text` (whose camera and floor are [`floor_scene`]'s).
fn check_scene(text: &str, expected: impl Fn(Vec3) -> f32) {
    let desc = inline(text);
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

/// A black veil under a `Mask` of opacity 0.3 between the camera, the point light and the floor:
/// camera rays cross it with probability 0.7 (else they meet its black), and shadow rays get 0.7
/// of the light through, so the floor shows 0.49 of its light. Shadow rays stopped by the veil
/// (its opacity not let through, a deliberate error) fail it.
#[test]
fn a_mask_lets_through_one_minus_its_opacity() {
    let text = floor_scene("Point(position: (0.5, 2, -0.3), intensity: (10, 10, 10))").replace(
        r#"materials: { "white": Lambertian(albedo: (1, 1, 1)) },"#,
        r#"materials: {
                "white": Lambertian(albedo: (1, 1, 1)),
                "black": Lambertian(albedo: (0, 0, 0)),
                "veil": Mask(opacity: 0.3, material: "black"),
            },"#,
    );
    let text = text.replace(
        "objects: [",
        r#"objects: [
                (shape: Quad(q: (-5, 1, -5), u: (10, 0, 0), v: (0, 0, 10)), material: "veil"),"#,
    );
    let light = Vec3::new(0.5, 2.0, -0.3);
    check_scene(&text, |p| {
        let d = light - p;
        0.49 * 10.0 * (d.y / d.length()) / d.length_squared() / PI
    });
}

/// A fuzzy `Metal` floor (fuzz 0.5) under the point light shows the highlight the fuzzed
/// lobe gives: `I / d^2` times the ball's density towards the light about the mirror
/// direction of the view. Found by trying pathwave as a new user: when Metal was only
/// sampled, no path ever met the point and the floor was black.
#[test]
fn fuzzy_metal_shows_a_point_lights_highlight() {
    use pathwave::engine::material::metal::fuzz_pdf;
    let text = floor_scene("Point(position: (0.5, 2, -0.3), intensity: (10, 10, 10))").replace(
        r#""white": Lambertian(albedo: (1, 1, 1))"#,
        r#""white": Metal(albedo: (1, 1, 1), fuzz: 0.5)"#,
    );
    let (light, eye) = (Vec3::new(0.5, 2.0, -0.3), Vec3::new(0.0, 6.0, 0.0));
    check_scene(&text, |p| {
        let (d, wo) = (light - p, (eye - p).normalize());
        let r = 2.0 * wo.y * Vec3::Y - wo;
        10.0 * fuzz_pdf(r, 0.5, d.normalize()) / d.length_squared()
    });
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

/// Mitsuba's spot falloff: linear in the angle from `falloff_start` to `cone_angle`.
#[test]
fn linear_spot_light_falls_off_linearly_in_the_angle() {
    let light = Vec3::new(0.0, 2.0, 0.0);
    check(
        "Spot(position: (0, 2, 0), look_at: (0, 0, 0), intensity: (10, 10, 10), cone_angle: 30, falloff_start: 20, falloff: Linear)",
        |p| {
            let d = light - p;
            let cos = d.y / d.length();
            let theta = cos.clamp(-1.0, 1.0).acos().to_degrees();
            let f = ((30.0 - theta) / 10.0).clamp(0.0, 1.0);
            10.0 * f * cos / d.length_squared() / PI
        },
    );
}

/// A frame as Mitsuba's `look_at` makes it (x = up x dir, y = dir x x, z = dir), and the
/// coordinates of `v` in it.
fn local(dir: Vec3, up: Vec3, v: Vec3) -> Vec3 {
    let z = dir.normalize();
    let x = up.cross(z).normalize();
    Vec3::new(v.dot(x), v.dot(z.cross(x)), v.dot(z))
}

/// A 4 x 4 checker of 1 and 0.25 in uv.
const CHECKER: &str = r#""c": UvChecker(u: 4, v: 4, even: (1, 1, 1), odd: (0.25, 0.25, 0.25))"#;

fn checker(u: f32, v: f32) -> f32 {
    if ((4.0 * u).floor() + (4.0 * v).floor()).rem_euclid(2.0) < 1.0 { 1.0 } else { 0.25 }
}

/// A spot's texture, read at Mitsuba's uv of each direction: (0.5 + x / (2 z tan), 0.5 - y / (2
/// z tan)) in the frame of the axis and `up`.
#[test]
fn textured_spot_light_projects_its_texture() {
    let light = Vec3::new(0.0, 2.0, 0.0);
    let tan = 30f32.to_radians().tan();
    check_with(
        CHECKER,
        "Spot(position: (0, 2, 0), look_at: (0, 0, 0), up: (0, 0, -1), intensity: (10, 10, 10), cone_angle: 30, falloff_start: 30, falloff: Linear, texture: \"c\")",
        |p| {
            let d = light - p;
            let l = local(-Vec3::Y, -Vec3::Z, p - light);
            let (u, v) = (0.5 + l.x / (2.0 * l.z * tan), 0.5 - l.y / (2.0 * l.z * tan));
            let inside = (d.y / d.length()) > 30f32.to_radians().cos();
            let cos = d.y / d.length();
            if inside { 10.0 * checker(u, v) * cos / d.length_squared() / PI } else { 0.0 }
        },
    );
}

/// A projector two units above the floor, facing it: the floor receives pi `scale` times the
/// image's value over the square the 60-degree frustum cuts, at uv (0.5 - x / (2 z tan), 0.5 +
/// y / (2 z tan)), so it shows `scale / 4` times the value; nothing outside.
#[test]
fn projector_lights_its_frustum_with_its_image() {
    let light = Vec3::new(0.0, 2.0, 0.0);
    let tan = 30f32.to_radians().tan();
    let at = |p: Vec3| {
        let l = local(-Vec3::Y, -Vec3::Z, p - light);
        Some((0.5 - l.x / (2.0 * l.z * tan), 0.5 + l.y / (2.0 * l.z * tan)))
            .filter(|(u, v)| (0.0..=1.0).contains(u) && (0.0..=1.0).contains(v))
    };
    let projector = "Projector(position: (0, 2, 0), look_at: (0, 0, 0), up: (0, 0, -1), fov: 60, scale: 0.5";
    check(&format!("{projector})"), |p| at(p).map_or(0.0, |_| 0.125));
    check_with(CHECKER, &format!("{projector}, irradiance: \"c\")"), |p| {
        at(p).map_or(0.0, |(u, v)| 0.125 * checker(u, v))
    });
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

#[test]
fn spot_textures_and_projectors_that_cannot_be_oriented_are_refused() {
    let spot = "Spot(position: (0, 2, 0), look_at: (0, 0, 0), intensity: (1, 1, 1)";
    for (light, what) in [
        (format!("{spot}, up: (0, 0, 1))"), "up orients a texture; this spot has none"),
        (format!("{spot}, texture: \"c\")"), "up is along the axis"),
        (
            format!("{spot}, up: (0, 0, 1), cone_angle: 100, falloff_start: 10, texture: \"c\")"),
            "less than 90",
        ),
        ("Projector(position: (0, 2, 0), look_at: (0, 0, 0), fov: 40)".into(), "up is along the axis"),
        ("Projector(position: (0, 2, 0), look_at: (0, 0, 0), up: (0, 0, 1), fov: 180)".into(), "(0, 180)"),
    ] {
        let text = floor_scene_with(CHECKER, &light);
        let err =
            pathwave::engine::scene::parse(&text, std::path::Path::new("<test>")).unwrap_err().to_string();
        assert!(err.contains(what) && err.contains("<test>:"), "{light}: {err}");
    }
}

/// Lights of every kind the light tree holds, many of them: 48 sphere lights and 24 one-sided
/// quads facing down over a floor, some two-sided, with point and spot lights, a directional
/// light at infinity, a box that shadows some, and a rough metal ball that reflects them
/// (where the emitter hits that BSDF sampling finds weigh most in MIS).
fn many_lights_scene() -> String {
    let mut objects = String::new();
    for k in 0..48 {
        let (x, z) = ((k % 8) as f32 - 3.5, (k / 8) as f32 - 2.5);
        let y = 0.3 + 0.2 * ((k * 7 % 5) as f32);
        let colour = ["red", "green", "blue"][k % 3];
        objects += &format!(
            r#"(shape: Sphere(center: ({x}, {y}, {z}), radius: 0.15), material: "{colour}"),"#,
            x = 0.9 * x,
            z = 0.9 * z
        );
    }
    for k in 0..24 {
        let (x, z) = ((k % 6) as f32 - 2.5, (k / 6) as f32 - 1.5);
        let material = if k % 4 == 0 { "both" } else { "lamp" };
        objects += &format!(
            r#"(shape: Quad(q: ({x}, 2.2, {z}), u: (0.25, 0, 0), v: (0, 0, 0.25)), material: "{material}"),"#,
            x = 1.3 * x,
            z = 1.3 * z
        );
    }
    format!(
        r#"Scene(
            camera: (look_from: (0, 5, 6), look_at: (0, 0, 0), vfov: 45),
            render: (width: 48, height: 32, spp: 64),
            materials: {{
                "white": Lambertian(albedo: (0.8, 0.8, 0.8)),
                "metal": RoughConductor(tint: (1, 1, 1), alpha: 0.05, eta: (0.2, 0.9, 1.1), k: (3.9, 2.4, 2.2)),
                "red": DiffuseLight(emit: (8, 1, 1)),
                "green": DiffuseLight(emit: (1, 8, 1)),
                "blue": DiffuseLight(emit: (1, 1, 8)),
                "lamp": DiffuseLight(emit: (3, 3, 2)),
                "both": DiffuseLight(emit: (2, 3, 3), two_sided: true),
            }},
            objects: [
                (shape: Quad(q: (-5, 0, 5), u: (10, 0, 0), v: (0, 0, -10)), material: "white"),
                (shape: Box(a: (-1.8, 0, -0.4), b: (-1.0, 0.9, 0.4)), material: "white"),
                (shape: Sphere(center: (1.0, 0.7, 0.3), radius: 0.7), material: "metal"),
                {objects}
            ],
            lights: [
                Point(position: (-2, 1.2, 1.5), intensity: (2, 2, 2)),
                Point(position: (2.5, 0.4, -1.5), intensity: (1, 2, 1)),
                Spot(position: (0, 2, 2), look_at: (0, 0, 0), intensity: (20, 15, 10), cone_angle: 25, falloff_start: 20),
                Directional(direction: (1, -0.4, -0.3), irradiance: (0.2, 0.25, 0.3)),
            ],
        )"#
    )
}

/// The light tree changes which lights are sampled, not the image: the wavefront's render of
/// many lights choosing by the tree agrees block by block (4 x 4 pixels) with the oracle's
/// render of the same scene choosing by power. The power image is the one whose variance
/// is read (it has the more): chi-square per block 0.34. MIS weights of emitter hits taken
/// with the power table's probability in `LightTable::pdf` (the tree's ignored there) fail it
/// (4.2, a block 6.7 sigma off), as does the other child's probability in `LightTree::pmf`
/// (16.5). (Densities read without the previous vertex's normal, where the choice had it,
/// give 0.55: too small a bias for this test; the tree's own tests check that choice and
/// density agree.)
#[test]
fn the_light_tree_converges_to_the_power_tables_image() {
    use pathwave::engine::scene::LightSamplerKind;
    use pathwave::io::LinearImage;
    let mut desc = inline(&many_lights_scene());
    desc.render.light_sampler = LightSamplerKind::Tree;
    desc.render.spp = 256.try_into().unwrap();
    let scene = SceneWorld::render_scene(&desc);
    assert!(scene.lights.tree.is_some());
    let tree = wavefront::render(&scene, Default::default(), &|_, _| {}).0;
    let reference = LinearImage { width: tree.width, height: tree.height, pixels: tree.mean() };
    desc.render.light_sampler = LightSamplerKind::Power;
    desc.render.spp = 64.try_into().unwrap();
    desc.render.seed = 3;
    let power = render(&desc);
    let stats = block_z(&power, &reference, 4, 256);
    assert!(stats.agrees(), "{stats:?}");
}

/// Lamps that rise through the floor while the shutter is open: at rest (time 0) each is under
/// the floor, facing down, so that the floor lies behind it; at time 1 it hangs 2.5 above.
/// The light tree bounds a moving light by its box swept over the shutter, so it picks the
/// lamps for the floor where they are near it: the variance of its image is 0.38x the power
/// table's, and the two images agree. Bounded at rest instead, every lamp has importance 0 at
/// the floor: the tree never samples them there and only BSDF sampling finds them (still
/// unbiased, MIS weighing by the same zero), with 6.6x the table's variance.
#[test]
fn the_light_tree_bounds_moving_lights_by_their_sweep() {
    use pathwave::engine::scene::LightSamplerKind;
    let lamps: String = (0..12)
        .map(|k| {
            let (x, z) = (-2.5 + (k % 4) as f32 * 1.6, -1.5 + (k / 4) as f32 * 1.5);
            format!(
                "(shape: Quad(q: ({x}, -0.5, {z}), u: (0.3, 0, 0), v: (0, 0, 0.3)), material: \"lamp\", \
                 motion: (velocity: (0, 3, 0))),\n"
            )
        })
        .collect();
    let text = format!(
        r#"Scene(
            camera: (look_from: (0, 6, 7), look_at: (0, 0, 0), vfov: 50, shutter: (0, 1)),
            render: (width: 40, height: 30, spp: 64),
            materials: {{
                "white": Lambertian(albedo: (0.8, 0.8, 0.8)),
                "lamp": DiffuseLight(emit: (20, 18, 15)),
            }},
            objects: [
                (shape: Quad(q: (-5, 0, 5), u: (10, 0, 0), v: (0, 0, -10)), material: "white"),
                {lamps}
            ],
        )"#
    );
    let desc = inline(&text);
    let run = |desc: &pathwave::engine::scene::SceneDesc, sampler| {
        let mut desc = desc.clone();
        desc.render.light_sampler = sampler;
        let scene = SceneWorld::render_scene(&desc);
        assert_eq!(scene.lights.tree.is_some(), sampler == LightSamplerKind::Tree);
        let film = wavefront::render(&scene, Default::default(), &|_, _| {}).0;
        let var: f64 = film.variance_of_mean().iter().map(|v| v.element_sum() as f64).sum();
        let mean: f64 = film.mean().iter().map(|v| v.element_sum() as f64).sum();
        (var, mean)
    };
    let (var_tree, mean_tree) = run(&desc, LightSamplerKind::Tree);
    let (var_power, mean_power) = run(&desc, LightSamplerKind::Power);
    assert!(var_tree < 2.0 * var_power, "tree {var_tree} against the table's {var_power}");
    // Both unbiased: the image sums agree within their noise.
    let sigma = (var_tree + var_power).sqrt();
    assert!((mean_tree - mean_power).abs() < 5.0 * sigma, "{mean_tree} vs {mean_power} (sigma {sigma})");
}
