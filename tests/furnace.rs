//! Scenes with a known answer: energy conservation (white furnace) and direct lighting with
//! light sampling, BSDF sampling and MIS agreeing on analytic values.

mod common;
use common::*;
use pathwave::engine::world::SceneWorld;

/// Mean of the pixels of a film with per-pixel values within `tolerance` sigma of `expected`.
fn assert_all_pixels_near(film: &pathwave::integrator::film::Film, expected: impl Fn(usize) -> Option<f32>) {
    let (mean, var) = (film.mean(), film.variance_of_mean());
    let (mut chi2, mut n) = (0.0f64, 0);
    for (i, (m, v)) in mean.iter().zip(&var).enumerate() {
        let Some(e) = expected(i) else { continue };
        for c in 0..3 {
            let sigma2 = v[c] as f64 + 1e-10;
            chi2 += (m[c] as f64 - e as f64).powi(2) / sigma2;
            n += 1;
        }
    }
    let dof = chi2 / n as f64;
    assert!(n > 100, "too few pixels checked: {n}");
    assert!(dof < 1.0 + 5.0 * (2.0 / n as f64).sqrt(), "chi2/dof {dof} over {n} pixel channels");
}

/// Albedo-1 surfaces of every kind (diffuse, mirror, glass, a thin pane around a diffuse ball)
/// under a uniform sky of radiance 1: nothing is absorbed, so every pixel is 1 whatever the
/// paths do (Russian roulette, glass radiance scaling by 1/eta^2 and back, concave crevices that
/// need many bounces, shadow rays through the pane and the MIS of paths that cross it).
/// Albedo-1 diffuse, fuzzed-mirror, glass and thin-glass objects on a ground sphere under
/// `BACKGROUND`.
const FURNACE: &str = r#"Scene(
    camera: (look_from: (0, 3, 8), look_at: (0, 0.6, 0), vfov: 40),
    render: (width: 40, height: 32, spp: 64, max_depth: 200, rr_depth: 3),
    background: BACKGROUND,
    materials: {
        "white": Lambertian(albedo: (1, 1, 1)),
        "mirror": Metal(albedo: (1, 1, 1), fuzz: 0.3),
        "glass": Dielectric(ior: 1.5),
        "pane": ThinDielectric(ior: 1.5),
    },
    objects: [
        (shape: Sphere(center: (0, -100, 0), radius: 100), material: "white"),
        (shape: Sphere(center: (0, 1, 0), radius: 1), material: "glass"),
        (shape: Sphere(center: (-1.3, 0.75, 1.8), radius: 0.7), material: "pane"),
        (shape: Sphere(center: (-1.3, 0.75, 1.8), radius: 0.45), material: "white"),
        (shape: Sphere(center: (-1.6, 0.7, 0.3), radius: 0.7), material: "white"),
        (shape: Sphere(center: (1.6, 0.7, 0.3), radius: 0.7), material: "mirror"),
        (shape: Box(a: (-0.5, 0, 1.2), b: (0.5, 0.6, 2)), material: "white", transform: [RotateY(30)]),
    ],
)"#;

#[test]
fn white_furnace_is_one_everywhere() {
    let desc = inline(&FURNACE.replace("BACKGROUND", "Constant((1, 1, 1))"));
    let film = render(&desc);
    let mean = film.mean();
    let avg: f32 = mean.iter().map(|p| p.x + p.y + p.z).sum::<f32>() / (3 * mean.len()) as f32;
    assert!((avg - 1.0).abs() < 0.01, "image mean {avg}");
    assert_all_pixels_near(&film, |_| Some(1.0));
}

/// A white ball inside a thin pane in the white furnace, close up: light sampling reaches the
/// ball through the pane, attenuated by 1 - R', and BSDF sampling crosses it without changing
/// the MIS state; nothing is absorbed, so every pixel is 1. Shadow rays that crossed the pane
/// unattenuated (an injected error) make the ball 3% to 8% too bright, which fails here.
#[test]
fn a_ball_inside_a_thin_pane_in_the_furnace_is_one_everywhere() {
    let desc = inline(
        r#"Scene(
            camera: (look_from: (0, 1.2, 2.4), look_at: (0, 0.7, 0), vfov: 40),
            render: (width: 32, height: 32, spp: 256, max_depth: 200, rr_depth: 3),
            background: Constant((1, 1, 1)),
            materials: { "white": Lambertian(albedo: (1, 1, 1)), "pane": ThinDielectric(ior: 1.5) },
            objects: [
                (shape: Sphere(center: (0, -100, 0), radius: 100), material: "white"),
                (shape: Sphere(center: (0, 0.75, 0), radius: 0.7), material: "pane"),
                (shape: Sphere(center: (0, 0.75, 0), radius: 0.45), material: "white"),
            ],
        )"#,
    );
    let oracle = render(&desc);
    assert_all_pixels_near(&oracle, |_| Some(1.0));
    let scene = pathwave::engine::world::SceneWorld::render_scene(&desc);
    let (film, _) = pathwave::integrator::wavefront::render(&scene, Default::default(), &|_, _| {});
    assert_eq!(film.pixels, oracle.pixels, "the wavefront gives the oracle's bits");
}

/// The same scene with albedo 0.95 must fail the test above: it can see energy loss.
#[test]
fn white_furnace_detects_absorption() {
    let desc = inline(
        r#"Scene(
            camera: (look_from: (0, 3, 8), look_at: (0, 0.6, 0), vfov: 40),
            render: (width: 40, height: 32, spp: 64),
            background: Constant((1, 1, 1)),
            materials: { "white": Lambertian(albedo: (0.95, 0.95, 0.95)) },
            objects: [
                (shape: Sphere(center: (0, -100, 0), radius: 100), material: "white"),
                (shape: Sphere(center: (-1.6, 0.7, 0.3), radius: 0.7), material: "white"),
            ],
        )"#,
    );
    let film = render(&desc);
    let result = std::panic::catch_unwind(|| assert_all_pixels_near(&film, |_| Some(1.0)));
    assert!(result.is_err());
}

/// A lamp seen through three thin panes at normal incidence (an orthographic camera) with
/// `max_depth: 0`: each pane lets 1 - R' through, R' = 2R / (1 + R) with R = ((n - 1) /
/// (n + 1))^2, and crossing one is no bounce, so every pixel is the lamp times (1 - R')^3. A
/// pane that ended paths at the depth limit like a bounce would leave the image black.
#[test]
fn thin_panes_pass_one_minus_their_reflectance_without_a_bounce() {
    let desc = inline(
        r#"Scene(
            camera: (to_world: [], projection: Orthographic),
            render: (width: 16, height: 16, spp: 64, max_depth: 0),
            materials: { "pane": ThinDielectric(ior: 1.5), "lamp": DiffuseLight(emit: (2, 2, 2)) },
            objects: [
                (shape: Quad(q: (-5, -5, 1), u: (10, 0, 0), v: (0, 10, 0)), material: "pane"),
                (shape: Quad(q: (-5, -5, 2), u: (0, 10, 0), v: (10, 0, 0)), material: "pane"),
                (shape: Quad(q: (-5, -5, 3), u: (10, 0, 0), v: (0, 10, 0)), material: "pane"),
                (shape: Quad(q: (-5, -5, 5), u: (0, 10, 0), v: (10, 0, 0)), material: "lamp"),
            ],
        )"#,
    );
    let r = (0.5f32 / 2.5).powi(2);
    let t = 1.0 - 2.0 * r / (1.0 + r);
    let oracle = render(&desc);
    assert_all_pixels_near(&oracle, |_| Some(2.0 * t * t * t));
    let scene = pathwave::engine::world::SceneWorld::render_scene(&desc);
    assert!(scene.features.null_surfaces);
    let (film, _) = pathwave::integrator::wavefront::render(&scene, Default::default(), &|_, _| {});
    assert_eq!(film.pixels, oracle.pixels, "the wavefront gives the oracle's bits");
}

/// A box of albedo-1 medium whose extinction differs by channel, (0.5, 4, 0.05), over a
/// white ground under a uniform sky: nothing is absorbed, so every pixel is 1 in each channel.
/// Spectral MIS must weigh each channel right whichever channel chose the distance; a weight
/// off in one channel (an injected error: ignoring the weight of rays that get through, which
/// is 1 only in grey media) makes that channel's pixels differ from 1 and fails here.
#[test]
fn a_coloured_medium_loses_nothing_in_any_channel() {
    let desc = inline(
        r#"Scene(
            camera: (look_from: (0, 2, 6), look_at: (0, 0.6, 0), vfov: 40),
            render: (width: 32, height: 24, spp: 64, max_depth: 200, rr_depth: 3),
            background: Constant((1, 1, 1)),
            materials: { "white": Lambertian(albedo: (1, 1, 1)) },
            objects: [
                (shape: Sphere(center: (0, -100, 0), radius: 100), material: "white"),
                (shape: Box(a: (-1, 0, -1), b: (1, 1.5, 1)), medium: (density: (0.5, 4, 0.05), albedo: (1, 1, 1))),
            ],
        )"#,
    );
    assert!(SceneWorld::render_scene(&desc).media.chromatic());
    assert_one_everywhere_in_both_integrators(&desc);
}

/// As [`a_coloured_medium_loses_nothing_in_any_channel`], with the coloured extinction on a
/// grid (the plume of `scenes/smoke-plume.ron`: delta tracking against the largest channel's
/// majorant, null collisions weighted per channel) overlapped by a homogeneous sphere of
/// another colour. An injected error that fails here: null collisions weighted as in grey
/// media (unchanged; chi2/dof 8.6). Extinction ten times as strong in one channel as in
/// another, (2, 20, 0.5), also converges to 1 (2e-4 at 300 000 spp) but is skewed at 64 spp:
/// rare samples of one hero carry much of another channel, so the pixels' sample variances
/// underestimate their error (chi2/dof 1.3).
#[test]
fn a_coloured_grid_medium_loses_nothing_in_any_channel() {
    let desc =
        plume_furnace("density: (2, 8, 0.5), albedo: (1, 1, 1)", "density: (3, 0.2, 1), albedo: (1, 1, 1)");
    assert!(SceneWorld::render_scene(&desc).media.chromatic());
    assert_one_everywhere_in_both_integrators(&desc);
}

/// Albedo-1 media under a uniform sky over a white ground: a grid medium (the plume of
/// `scenes/smoke-plume.ron`, delta and ratio tracking) scattering forwards (Henyey-Greenstein,
/// g = 0.7), overlapped by a sphere of homogeneous medium scattering backwards (g = -0.5).
/// Nothing is absorbed, so every pixel is 1, whichever phase function each scattering uses and
/// however light sampling and phase sampling share the work (MIS with the phase function's
/// density). An injected error that fails here: the overlap's pick of a phase function
/// without dividing by its probability. (Under uniform light any phase function integrates to
/// the same: `tests/mitsuba.rs` checks the phase function's shape against Mitsuba.)
#[test]
fn media_scattering_forwards_and_backwards_lose_nothing() {
    let desc = plume_furnace(
        "density: 20, albedo: (1, 1, 1), phase: HenyeyGreenstein(g: 0.7)",
        "density: 3, albedo: (1, 1, 1), phase: HenyeyGreenstein(g: -0.5)",
    );
    assert_one_everywhere_in_both_integrators(&desc);
}

/// Media that absorb and glow with radiance 1 under a uniform sky of 1, over a white ground:
/// what a point absorbs of the radiance 1 around it, `sigma_a`, it emits again (`sigma_a Le`),
/// so every pixel is 1 however dense, coloured or uneven the media (the radiative transfer
/// equation's source balances its absorption where `L = Le`). The plume's grid (delta
/// tracking) and a sphere over it, each with an albedo below 1: both grey (free flights in
/// grey media), then the sphere coloured (spectral MIS). Injected errors that fail here: the
/// emission weighted by `sigma_t` instead of `sigma_a` (chi2/dof 17 on the coloured scene),
/// and gathered after the throughput took the albedo, in grey media (104) or in coloured ones
/// (19). Gathering in coloured media without the spectral MIS's mean passes: each hero alone
/// is unbiased where every channel has extinction (it only adds variance).
#[test]
fn glowing_media_give_back_what_they_absorb() {
    let plume = "density: 20, albedo: (0.3, 0.6, 0.9), emission: (1, 1, 1)";
    for (sphere, chromatic) in [
        ("density: 3, albedo: (0.5, 0.2, 0.7), emission: (1, 1, 1)", false),
        ("density: (3, 0.2, 1), albedo: (0.5, 0.5, 0.5), emission: (1, 1, 1)", true),
    ] {
        let desc = plume_furnace(plume, sphere);
        let scene = SceneWorld::render_scene(&desc);
        assert_eq!(scene.media.chromatic(), chromatic);
        assert!(scene.media.volumes().iter().all(|v| v.medium.emission == glam::Vec3::ONE));
        assert_one_everywhere_in_both_integrators(&desc);
    }
}

/// On a white ground under a uniform sky of 1, the plume of `scenes/smoke-plume.ron` in a box
/// (its medium `plume`: a density, an albedo and what else it takes) overlapped by a sphere of
/// medium `sphere`.
fn plume_furnace(plume: &str, sphere: &str) -> pathwave::engine::scene::SceneDesc {
    inline(&format!(
        r#"Scene(
            camera: (look_from: (0, 1.5, 4), look_at: (0, 1.1, 0), vfov: 30),
            render: (width: 32, height: 24, spp: 64, max_depth: 200, rr_depth: 3),
            background: Constant((1, 1, 1)),
            materials: {{ "white": Lambertian(albedo: (1, 1, 1)) }},
            objects: [
                (shape: Sphere(center: (0, -100, 0), radius: 100), material: "white"),
                (
                    shape: Box(a: (-1, 0, -1), b: (1, 2, 1)),
                    medium: (
                        {plume},
                        grid: (file: "scenes/assets/plume.vol", transform: [Scale((2, 2, 2)), Translate((-1, 0, -1))]),
                    ),
                ),
                (shape: Sphere(center: (0, 1.2, 0), radius: 0.5), medium: ({sphere})),
            ],
        )"#
    ))
}

/// Every pixel of the reference integrator's image is 1 within its noise, and the wavefront
/// gives its bits.
fn assert_one_everywhere_in_both_integrators(desc: &pathwave::engine::scene::SceneDesc) {
    let oracle = render(desc);
    assert_all_pixels_near(&oracle, |_| Some(1.0));
    let scene = SceneWorld::render_scene(desc);
    let (film, _) = pathwave::integrator::wavefront::render(&scene, Default::default(), &|_, _| {});
    assert_eq!(film.pixels, oracle.pixels, "the wavefront gives the oracle's bits");
}

/// The camera inside a two-sided spherical emitter of radiance 1 looking at a convex diffuse
/// sphere of albedo 0.5: the sphere receives radiance 1 from every direction, so it shows
/// exactly 0.5 and the emitter 1. Exercises light sampling of a sphere from inside it (area
/// sampling), emitter hits by BSDF sampling, and their MIS weights, which must sum to one.
#[test]
fn diffuse_sphere_inside_an_emitter_shows_its_albedo() {
    let desc = inline(
        r#"Scene(
            camera: (look_from: (0, 0, 4), look_at: (0, 0, 0), vfov: 50),
            render: (width: 32, height: 32, spp: 64),
            materials: {
                "sky": DiffuseLight(emit: (1, 1, 1), two_sided: true),
                "grey": Lambertian(albedo: (0.5, 0.5, 0.5)),
            },
            objects: [
                (shape: Sphere(center: (0, 0, 0), radius: 10), material: "sky"),
                (shape: Sphere(center: (0, 0, 0), radius: 1), material: "grey"),
            ],
        )"#,
    );
    let film = render(&desc);
    let mean = film.mean();
    // Pixels fully on the small sphere (well inside its silhouette) are 0.5; the background 1.
    let on_sphere = |i: usize| {
        let (x, y) = ((i % 32) as f32 + 0.5 - 16.0, (i / 32) as f32 + 0.5 - 16.0);
        let r = (x * x + y * y).sqrt();
        // Silhouette radius in pixels: tan(asin(1/4)) = 1/sqrt(15) against tan(25 degrees) for 16 px.
        let edge = 16.0 * (1.0 / 15f32.sqrt()) / 25f32.to_radians().tan();
        if r < edge - 1.5 {
            Some(0.5)
        } else if r > edge + 1.5 {
            Some(1.0)
        } else {
            None
        }
    };
    let inside = (0..mean.len()).filter(|&i| on_sphere(i) == Some(0.5)).count();
    assert!(inside > 50, "{inside} pixels on the sphere");
    assert_all_pixels_near(&film, on_sphere);
}

/// Surfaces that emit and reflect (objects with an `emit`): a closed room whose walls are
/// albedo-0.5 Lambertian and emit radiance 1 on their inner side (one-sided, two walls through
/// a texture of value 1), holding an albedo-1 box, a perfect mirror and glass, which lose
/// nothing. Every wall sees radiance L from every direction, so L = 1 + 0.5 L: every pixel is 2.
/// Exercises emission added on hit with its MIS weight and the wall's BSDF scattering after
/// it (Lambertian kernel, delta lobes), textured emitters sampled as lights, and the wavefront
/// against the oracle.
#[test]
fn emitting_walls_that_reflect_give_emission_over_one_minus_albedo() {
    let desc = inline(
        r#"Scene(
            camera: (look_from: (0, 0.2, 0.8), look_at: (0, -0.3, 0), vfov: 70),
            render: (width: 32, height: 32, spp: 64, max_depth: 200),
            textures: { "one": Solid((1, 1, 1)) },
            materials: {
                "wall": Lambertian(albedo: (0.5, 0.5, 0.5)),
                "white": Lambertian(albedo: (1, 1, 1)),
                "mirror": Metal(albedo: (1, 1, 1), fuzz: 0),
                "glass": Dielectric(ior: 1.5),
            },
            objects: [
                (shape: Quad(q: (-1, -1, -1), u: (0, 0, 2), v: (2, 0, 0)), material: "wall", emit: (radiance: (1, 1, 1))),
                (shape: Quad(q: (-1, 1, -1), u: (2, 0, 0), v: (0, 0, 2)), material: "wall", emit: (radiance: (1, 1, 1))),
                (shape: Quad(q: (-1, -1, -1), u: (0, 2, 0), v: (0, 0, 2)), material: "wall", emit: (radiance: "one")),
                (shape: Quad(q: (1, -1, -1), u: (0, 0, 2), v: (0, 2, 0)), material: "wall", emit: (radiance: (1, 1, 1))),
                (shape: Quad(q: (-1, -1, -1), u: (2, 0, 0), v: (0, 2, 0)), material: "wall", emit: (radiance: "one")),
                (shape: Quad(q: (-1, -1, 1), u: (0, 2, 0), v: (2, 0, 0)), material: "wall", emit: (radiance: (1, 1, 1))),
                (shape: Box(a: (-0.2, -1, -0.6), b: (0.2, -0.5, -0.2)), material: "white"),
                (shape: Sphere(center: (-0.5, -0.6, 0), radius: 0.3), material: "mirror"),
                (shape: Sphere(center: (0.5, -0.6, 0), radius: 0.3), material: "glass"),
            ],
        )"#,
    );
    let scene = pathwave::engine::world::SceneWorld::render_scene(&desc);
    assert_eq!(scene.lights.prims.len(), 6, "the walls are lights");
    assert!(scene.features.emitting_surfaces && scene.features.textures);
    let oracle = render(&desc);
    assert_all_pixels_near(&oracle, |_| Some(2.0));
    let (film, _) = pathwave::integrator::wavefront::render(&scene, Default::default(), &|_, _| {});
    let differing = film.pixels.iter().zip(&oracle.pixels).filter(|(a, b)| a != b).count();
    assert!(differing <= 2, "{differing} pixels differ from the oracle");
    // Walls that emit but do not reflect (the emission alone) are a different room: 1 + the
    // objects' reflections of it, so the test sees a lost bounce.
    let mut black = desc.clone();
    scale_albedo(&mut black, "wall", 0.0);
    let result = std::panic::catch_unwind(|| assert_all_pixels_near(&render(&black), |_| Some(2.0)));
    assert!(result.is_err());
}

/// A diffuse plane lit by a spherical emitter seen from outside: where the whole sphere is above
/// the horizon, the plane's radiance is exactly rho L (r^2 / D^2) (h / D), with D the distance to
/// the centre and h its height. Exercises cone sampling of spheres and its MIS with BSDF sampling.
#[test]
fn plane_under_a_sphere_light_matches_the_closed_form() {
    use glam::{Vec2, Vec3A};
    let desc = inline(
        r#"Scene(
            camera: (look_from: (0, 6, 9), look_at: (0, 0, 0), vfov: 45),
            render: (width: 48, height: 36, spp: 64),
            materials: {
                "lamp": DiffuseLight(emit: (4, 4, 4)),
                "floor": Lambertian(albedo: (0.6, 0.6, 0.6)),
            },
            objects: [
                (shape: Sphere(center: (0, 3, 0), radius: 1), material: "lamp"),
                (shape: Quad(q: (-50, 0, -50), u: (0, 0, 100), v: (100, 0, 0)), material: "floor"),
            ],
        )"#,
    );
    let scene = pathwave::engine::world::SceneWorld::render_scene(&desc);
    let film = render(&desc);
    let (c, r, l, rho) = (Vec3A::new(0.0, 3.0, 0.0), 1.0f32, 4.0f32, 0.6f32);
    let expected = |i: usize| {
        let (x, y) = ((i % 48) as f32 + 0.5, (i / 48) as f32 + 0.5);
        let ray = scene.camera.generate_ray(Vec2::new(x, y), Vec2::ZERO, 0.0);
        // Skip pixels that see (or nearly see) the lamp.
        let oc = c - ray.origin;
        let miss = (oc - oc.dot(ray.dir) * ray.dir).length();
        if miss < r + 0.3 || ray.dir.y >= 0.0 {
            return None;
        }
        let p = ray.at(-ray.origin.y / ray.dir.y);
        let d = (c - p).length();
        (c.y / d > r / d + 0.01).then(|| rho * l * (r * r) / (d * d) * (c.y / d))
    };
    assert_all_pixels_near(&film, expected);
}

/// Writes a `w` x `h` lat-long EXR of radiance `texel(column, row)` and returns its path.
fn env_map(name: &str, w: u32, h: u32, texel: impl Fn(u32, u32) -> f32) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("pathwave-furnace-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    let img = image::Rgb32FImage::from_fn(w, h, |x, y| image::Rgb([texel(x, y); 3]));
    img.save(&path).unwrap();
    path
}

/// The white furnace under an environment map of radiance 1: the map is sampled as a light
/// (by its luminance, here uniform) and combined with BSDF sampling by MIS, so the weights of
/// both strategies must sum to one on every kind of surface; every pixel is 1, in both
/// integrators.
#[test]
fn white_furnace_under_an_environment_map_is_one_everywhere() {
    let map = env_map("white.exr", 16, 8, |_, _| 1.0);
    let desc = inline(
        &FURNACE.replace("BACKGROUND", &format!("Environment(file: {:?})", map.display().to_string())),
    );
    let scene = pathwave::engine::world::SceneWorld::render_scene(&desc);
    assert_eq!(scene.lights.len(), 1, "the map is a light");
    assert_all_pixels_near(&render(&desc), |_| Some(1.0));
    let (film, _) = pathwave::integrator::wavefront::render(&scene, Default::default(), &|_, _| {});
    assert_all_pixels_near(&film, |_| Some(1.0));
}

/// A diffuse floor under a map that is dim but for a bright band of rows near the zenith shows
/// `rho E / pi`, E the map's irradiance on the floor computed here by quadrature.
#[test]
fn a_floor_under_a_bright_band_matches_quadrature() {
    let (w, h) = (64u32, 32u32);
    // Rows 2..5 (theta from 2/32 to 5/32 of pi) shine 50; the rest 0.1.
    let band = |y: u32| if (2..5).contains(&y) { 50.0 } else { 0.1 };
    let map = env_map("band.exr", w, h, |_, y| band(y));
    let desc = inline(&format!(
        r#"Scene(
            camera: (look_from: (0, 6, 0), look_at: (0, 0, 0), vup: (0, 0, -1), vfov: 30),
            render: (width: 24, height: 24, spp: 64),
            background: Environment(file: "{}"),
            materials: {{ "floor": Lambertian(albedo: (0.5, 0.5, 0.5)) }},
            objects: [ (shape: Quad(q: (-1000, 0, -1000), u: (0, 0, 2000), v: (2000, 0, 0)), material: "floor") ],
        )"#,
        map.display()
    ));
    // Irradiance on an upward floor: integral of L(theta) cos(theta) sin(theta) dtheta dphi over
    // the upper hemisphere, L bilinear between row centres (clamped above the first).
    let n = 200_000;
    let mut e = 0.0f64;
    for k in 0..n {
        let theta = (k as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
        let y = theta / std::f64::consts::PI * h as f64 - 0.5;
        let (y0, f) = (y.floor(), y - y.floor());
        let row = |r: f64| band(r.clamp(0.0, (h - 1) as f64) as u32) as f64;
        let l = row(y0) * (1.0 - f) + row(y0 + 1.0) * f;
        e += l * theta.cos() * theta.sin() * (std::f64::consts::FRAC_PI_2 / n as f64) * std::f64::consts::TAU;
    }
    let expected = (0.5 * e / std::f64::consts::PI) as f32;
    assert_all_pixels_near(&render(&desc), |_| Some(expected));
}
