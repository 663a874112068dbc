//! The camera given by a `to_world` transform (Mitsuba 3's camera space) and the pixel
//! filters: the two camera forms render the same image, orthographic views have the size
//! Mitsuba gives them, clip planes hide what lies outside them, bad cameras are refused with
//! clear errors.

mod common;
use common::*;
use pathwave::engine::scene::{SceneDesc, parse};
use pathwave::engine::world::SceneWorld;
use pathwave::integrator::film::Film;
use pathwave::integrator::wavefront;
use std::path::Path;

/// A blue sphere at -x and a red one at +x under a white sky, seen from +z; `camera` and
/// `render` are spliced in.
fn two_spheres(camera: &str, render: &str) -> String {
    format!(
        r#"Scene(
    camera: ({camera}),
    render: ({render}),
    background: Constant((1, 1, 1)),
    materials: {{ "red": Lambertian(albedo: (0.8, 0.1, 0.1)), "blue": Lambertian(albedo: (0.1, 0.1, 0.8)) }},
    objects: [
        (shape: Sphere(center: (1.2, 0, 0), radius: 1), material: "red"),
        (shape: Sphere(center: (-1.2, 0, 0), radius: 1), material: "blue"),
    ],
)"#
    )
}

fn both(desc: &SceneDesc) -> [Film; 2] {
    let scene = SceneWorld::render_scene(desc);
    [render(desc), wavefront::render(&scene, wavefront::Options::default(), &|_, _| {}).0]
}

/// Mean red minus blue over the left and the right half of the image.
fn red_minus_blue(film: &Film) -> (f32, f32) {
    let mean = film.mean();
    let (mut l, mut r) = (0.0, 0.0);
    for (i, p) in mean.iter().enumerate() {
        let x = i as u32 % film.width;
        if x < film.width / 2 { l += p.x - p.z } else { r += p.x - p.z }
    }
    let n = (film.width * film.height / 2) as f32;
    (l / n, r / n)
}

/// Mitsuba's look_at(origin (0, 0, 6), target 0, up +y) has columns left = up x dir =
/// (-1, 0, 0), up, dir = (0, 0, -1), origin: the same view as look_from/look_at, so the same
/// image (to float rounding), with the red sphere (+x) on the right.
#[test]
fn to_world_renders_the_look_at_image_unmirrored() {
    let size = "width: 48, height: 32, spp: 4";
    let look_at = inline(&two_spheres("look_from: (0, 0, 6), look_at: (0, 0, 0), vfov: 40", size));
    let to_world = inline(&two_spheres(
        "to_world: [Matrix([[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 6], [0, 0, 0, 1]])], \
         projection: Perspective(fov: 40, fov_axis: Y)",
        size,
    ));
    for (a, b) in both(&look_at).iter().zip(&both(&to_world)) {
        let (ma, mb) = (a.mean(), b.mean());
        let differ = ma.iter().zip(&mb).filter(|(p, q)| (**p - **q).abs().max_element() > 1e-3).count();
        assert!(differ <= 2, "{differ} pixels differ between the two camera forms");
        let (left, right) = red_minus_blue(b);
        assert!(left < -0.1 && right > 0.1, "the image is mirrored: left {left}, right {right}");
    }
    // The same matrix without the flip of x (x = +1: camera-space x to world +x) mirrors it.
    let mirrored = inline(&two_spheres(
        "to_world: [Matrix([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 6], [0, 0, 0, 1]])], \
         projection: Perspective(fov: 40, fov_axis: Y)",
        size,
    ));
    let (left, right) = red_minus_blue(&render(&mirrored));
    assert!(left > 0.1 && right < -0.1, "left {left}, right {right}");
}

/// An orthographic view spans camera-space x in [-1, 1] and y in [-1/aspect, 1/aspect], then
/// to_world's scale (2) applies: the unit sphere covers pi / (4 * 2) of a 2:1 image (x in
/// [-2, 2], y in [-1, 1]), and, centred at x = 0.5, lies mostly in the right half.
#[test]
fn orthographic_view_is_sized_by_to_world() {
    let text = two_spheres(
        "to_world: [Scale((2, 2, 1)), RotateY(180), Translate((0, 0, 6))], projection: Orthographic",
        "width: 128, height: 64, spp: 4",
    )
    .replace(r#"(shape: Sphere(center: (-1.2, 0, 0), radius: 1), material: "blue"),"#, "")
    .replace("center: (1.2, 0, 0)", "center: (0.5, 0, 0)");
    for film in both(&inline(&text)) {
        let mean = film.mean();
        let hit = mean.iter().filter(|p| p.y < 0.5).count() as f32 / mean.len() as f32;
        let expected = std::f32::consts::PI / (4.0 * 2.0);
        assert!((hit - expected).abs() < 0.01, "sphere covers {hit}, expected {expected}");
        let (left, right) = red_minus_blue(&film);
        assert!(right > left + 0.1, "left {left}, right {right}");
    }
}

fn error(camera: &str, extra: &str) -> String {
    let text = two_spheres(camera, "width: 8, height: 8").replace("\n)", &format!("\n    {extra}\n)"));
    match parse(&text, Path::new("<test>")) {
        Ok(_) => panic!("accepted: {camera}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_cameras_are_refused_clearly() {
    let eye = "Matrix([[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 6], [0, 0, 0, 1]])";
    for (camera, extra, expected) in [
        ("to_world: [Scale((1, 0, 1))], projection: Orthographic".to_string(), "", "singular"),
        (format!("to_world: [{eye}, Scale((1, 1e-9, 1))], projection: Orthographic"), "", "singular"),
        (format!("to_world: [{eye}], projection: Perspective(fov: 180)"), "", "field of view in (0, 180)"),
        (format!("to_world: [{eye}], projection: Perspective(fov: 0)"), "", "field of view in (0, 180)"),
        (format!("to_world: [{eye}], projection: Perspective(fov: 30, fov_axis: Z)"), "", "Diagonal"),
        (format!("to_world: [{eye}]"), "", "missing field `projection`"),
        ("projection: Orthographic".to_string(), "", "missing field `to_world`"),
        (format!("to_world: [{eye}], projection: Orthographic, vfov: 40"), "", "do not go with"),
        (format!("to_world: [{eye}], projection: Orthographic, aperture_radius: 0.1"), "", "has no lens"),
        (
            format!("to_world: [{eye}], projection: Perspective(fov: 30), aperture_radius: 0.1"),
            "",
            "needs focus_dist",
        ),
        ("to_world: [Translate((0, 0, 2e15))], projection: Orthographic".to_string(), "", "within 1e15"),
        ("look_from: (0, 0, 6), look_at: (0, 0, 0)".to_string(), "", "missing field `vfov`"),
        (
            format!("to_world: [{eye}], projection: Orthographic, near_clip: 2, far_clip: 2"),
            "",
            "less than far_clip",
        ),
        (
            format!("to_world: [{eye}], projection: Orthographic, near_clip: 3, far_clip: 2"),
            "",
            "less than far_clip",
        ),
        (format!("to_world: [{eye}], projection: Orthographic, near_clip: 0"), "", "finite number > 0"),
        (format!("to_world: [{eye}], projection: Orthographic, far_clip: -1"), "", "finite number > 0"),
        (format!("to_world: [{eye}], projection: Orthographic, far_clip: inf"), "", "finite number > 0"),
        (format!("to_world: [{eye}], projection: Orthographic, far_clip: 1e16"), "", "within 1e15"),
        (
            "look_from: (0, 0, 6), look_at: (0, 0, 0), vfov: 40, near_clip: 1".to_string(),
            "",
            "do not go with",
        ),
        ("near_clip: 1, far_clip: 2".to_string(), "", "missing field `to_world`"),
        (
            format!("to_world: [{eye}], projection: Perspective(fov: 30)"),
            "animation: (camera: (look_from: Linear([(0, (0, 0, 5))]))),",
            "need a look_from/look_at camera",
        ),
    ] {
        let e = error(&camera, extra);
        assert!(e.contains(expected), "{camera}: {e}");
    }
}

/// A sharp vertical edge (an emitter of radiance 1 over world x > 0, black elsewhere) seen by
/// an orthographic camera whose pixel boundary lies on it: pixel column c's mean is the
/// filter's normalised CDF at its centre's distance from the edge, c + 0.5 - 8 pixels (the
/// box: 0 or 1; the tent of radius 1: 0.125 and 0.875 beside the edge), with both integrators.
#[test]
fn filters_blur_a_sharp_edge_by_their_cdf() {
    use pathwave::engine::filter::PixelFilter;
    use pathwave::engine::scene::FilterDesc;
    for (filter, desc) in [
        ("Box", FilterDesc::Box),
        ("Tent(radius: 1)", FilterDesc::Tent { radius: 1.0 }),
        ("Tent(radius: 2.5)", FilterDesc::Tent { radius: 2.5 }),
        ("Gaussian(stddev: 0.5)", FilterDesc::Gaussian { stddev: 0.5 }),
        ("Gaussian(stddev: 0.8)", FilterDesc::Gaussian { stddev: 0.8 }),
    ] {
        let text = format!(
            r#"Scene(
    camera: (to_world: [RotateY(180), Translate((0, 0, 5))], projection: Orthographic),
    render: (width: 16, height: 2, spp: 1024, filter: {filter}),
    materials: {{ "lamp": DiffuseLight(emit: (1, 1, 1)) }},
    objects: [(shape: Quad(q: (0, -5, 0), u: (5, 0, 0), v: (0, 10, 0)), material: "lamp")],
)"#
        );
        let f = PixelFilter::from(desc);
        // The normalised CDF by the midpoint rule.
        let cdf = |d: f32| {
            let r = f.radius();
            let at = |x: f32| f.eval(x) as f64;
            let n = 20_000;
            let step = 2.0 * r / n as f32;
            let (mut below, mut all) = (0.0, 0.0);
            for k in 0..n {
                let x = -r + (k as f32 + 0.5) * step;
                all += at(x);
                if x < d {
                    below += at(x);
                }
            }
            below / all
        };
        for film in both(&inline(&text)) {
            let mean = film.mean();
            for c in 0..16u32 {
                let expected = cdf(c as f32 + 0.5 - 8.0) as f32;
                for row in 0..2 {
                    let got = mean[(row * 16 + c) as usize].x;
                    assert!(
                        (got - expected).abs() < 0.02,
                        "{filter}: column {c}: {got}, expected {expected}"
                    );
                }
            }
        }
    }
}

/// A camera at the origin looking along +z (`camera`: its projection and lens) with clip
/// planes at camera-space depths 1 and 2, a red lamp square at depth `z` filling the view and
/// a blue background; `extra` objects are spliced in.
fn clipped(camera: &str, z: f32, extra: &str) -> SceneDesc {
    let (q, s) = (-3.0 * z, 6.0 * z);
    inline(&format!(
        r#"Scene(
    camera: (to_world: [Translate((0, 0, 0))], {camera}, near_clip: 1, far_clip: 2),
    render: (width: 8, height: 8, spp: 16),
    background: Constant((0, 0, 1)),
    materials: {{ "lamp": DiffuseLight(emit: (1, 0, 0), two_sided: true), "mirror": Metal(albedo: (1, 1, 1)) }},
    objects: [(shape: Quad(q: ({q}, {q}, {z}), u: ({s}, 0, 0), v: (0, {s}, 0)), material: "lamp"), {extra}],
)"#
    ))
}

/// Every pixel of both integrators' images is red (the lamp is seen) or blue (the background).
fn assert_sees(desc: &SceneDesc, lamp: bool, what: &str) {
    for (film, name) in both(desc).iter().zip(["oracle", "wavefront"]) {
        for (i, p) in film.mean().iter().enumerate() {
            let (x, y) = (i as u32 % film.width, i as u32 / film.width);
            let seen = if lamp { p.x } else { p.z };
            assert!(seen > 0.999 && p.x + p.z < 1.001, "{what}, {name}: pixel ({x}, {y}) is {p}");
        }
    }
}

/// Mitsuba 3's clip planes (mitsuba3 `src/sensors/perspective.cpp`, `thinlens.cpp`,
/// `orthographic.cpp`): a lamp nearer than near_clip or farther than far_clip is not seen (the
/// background is), one between them is, in every pixel. The planes are camera-space depths,
/// not distances along the ray: at the image's corners (90 degrees across, so the corner rays
/// are at 55 degrees to the axis) a distance of 1 along the ray reaches only depth 0.58, so the
/// lamp at depth 0.8 would show there, and a distance of 2 only depth 1.15, hiding the one at
/// 1.8.
#[test]
fn clip_planes_hide_what_lies_outside_them() {
    for camera in [
        "projection: Perspective(fov: 90)",
        "projection: Perspective(fov: 90), aperture_radius: 0.2, focus_dist: 1.5",
        "projection: Orthographic",
    ] {
        for (z, lamp) in [(0.8, false), (1.2, true), (1.8, true), (2.2, false)] {
            assert_sees(&clipped(camera, z, ""), lamp, &format!("{camera}, lamp at depth {z}"));
        }
    }
}

/// The far plane limits the camera rays only: a mirror between the planes shows a lamp 10
/// behind the camera (a path 11.5 long).
#[test]
fn far_clip_limits_only_camera_rays() {
    let mirror = "(shape: Quad(q: (-5, -5, 1.5), u: (10, 0, 0), v: (0, 10, 0)), material: \"mirror\")";
    for camera in ["projection: Perspective(fov: 90)", "projection: Orthographic"] {
        assert_sees(&clipped(camera, -10.0, mirror), true, &format!("{camera}, lamp seen in a mirror"));
    }
}

/// A splatted pixel's variance ([`Film::variance_of_mean`], from its weighted sums) is the
/// variance its value has over seeds, and the image mean's variance is about the sum of the
/// pixels' times the filter's gain (`PixelFilter::splat_gain`: splatted pixels share their
/// noise), for the tent and the Gaussian, on a grey floor shadowed by a sphere under a white
/// sky. Taken as the plain sum (the gain left out), the image mean's variance is 2.8 and 3.9
/// times the prediction, and the test says so; with the effective sample count taken as the
/// sum of the weights, the pixels' prediction is a third of what it should be, and
/// the test says so too. 200 seeds of an independent sampler, so that the renders are
/// independent draws; the green channel. (The gain is about 1.25 times short here: the image's
/// edge rows, whose pixels have no neighbours beyond them, are a fifth of a 24x16 image.)
#[test]
fn splatted_pixels_know_their_variance_and_share_it() {
    use pathwave::engine::filter::PixelFilter;
    use pathwave::engine::scene::FilterDesc;
    let seeds = 200;
    for desc_filter in [FilterDesc::Tent { radius: 1.0 }, FilterDesc::Gaussian { stddev: 0.5 }] {
        let filter = PixelFilter::from(desc_filter);
        assert!(filter.splats());
        let mut desc = inline(
            r#"Scene(
    camera: (look_from: (0, 6, 0.01), look_at: (0, 0, 0), vfov: 50),
    render: (width: 24, height: 16, spp: 4),
    background: Constant((1, 1, 1)),
    materials: { "grey": Lambertian(albedo: (0.5, 0.5, 0.5)) },
    objects: [
        (shape: Quad(q: (-20, 0, -20), u: (40, 0, 0), v: (0, 0, 40)), material: "grey"),
        (shape: Sphere(center: (0, 1.5, 0), radius: 1), material: "grey"),
    ],
)"#,
        );
        desc.render.filter = desc_filter;
        desc.render.sampler = "independent".parse().unwrap();
        let n = 24 * 16;
        let (mut sum, mut sum_sq, mut predicted) = (vec![0.0f64; n], vec![0.0f64; n], vec![0.0f64; n]);
        let mut means = Vec::new();
        for seed in 0..seeds {
            desc.render.seed = seed;
            let scene = SceneWorld::render_scene(&desc);
            let film = wavefront::render(&scene, wavefront::Options::default(), &|_, _| {}).0;
            let (mean, var) = (film.mean(), film.variance_of_mean());
            for p in 0..n {
                let v = mean[p].y as f64;
                (sum[p], sum_sq[p]) = (sum[p] + v, sum_sq[p] + v * v);
                predicted[p] += var[p].y as f64 / seeds as f64;
            }
            means.push(mean.iter().map(|c| c.y as f64).sum::<f64>() / n as f64);
        }
        let k = seeds as f64;
        let observed: f64 = (0..n).map(|p| (sum_sq[p] - sum[p] * sum[p] / k) / (k - 1.0)).sum();
        let pixels = observed / predicted.iter().sum::<f64>();
        let m = means.iter().sum::<f64>() / k;
        let observed_mean = means.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (k - 1.0);
        let predicted_mean = predicted.iter().sum::<f64>() / (n * n) as f64;
        let image = observed_mean / (predicted_mean * filter.splat_gain());
        eprintln!(
            "{desc_filter:?}: observed / predicted variance: pixels {pixels:.3}, image mean {image:.3} \
             (without the gain {:.3})",
            observed_mean / predicted_mean
        );
        assert!(
            (0.9..1.1).contains(&pixels),
            "{desc_filter:?}: pixels' variance {pixels} times the prediction"
        );
        assert!(
            (0.8..1.6).contains(&image),
            "{desc_filter:?}: the image mean's {image} times the prediction"
        );
    }
}
