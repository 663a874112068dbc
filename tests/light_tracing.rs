//! Light tracing (`--light-tracing on`): the caustics of punctual lights through sharp
//! surfaces, traced from the lights. Checked against closed forms of the scene (a mirror's image
//! of a light), against the path tracer where both can sample the same paths, and for the
//! guarantees every render keeps (threads, sample ranges, crops, both integrators).

mod common;

use common::inline;
use glam::Vec3;
use pathwave::engine::render_scene::RenderScene;
use pathwave::engine::world::SceneWorld;
use pathwave::integrator::film::Film;
use pathwave::integrator::{oracle, wavefront};
use std::sync::Arc;

/// A floor (up to z = 4) and a clay ball, and a spot light behind the camera that shines away
/// from them: into a mirror (`MIRROR`), or in its place the light's image in that mirror
/// (`IMAGE`).
const ROOM: &str = r#"
#![enable(implicit_some)]
Scene(
    camera: (look_from: (0, 5, 3), look_at: (0, 0, -0.5), vfov: 50),
    render: (width: 40, height: 40, spp: 1024, max_depth: 64, light_tracing: LT),
    background: Constant((0, 0, 0)),
    materials: {
        "floor": Lambertian(albedo: (0.6, 0.6, 0.6)),
        "clay": Lambertian(albedo: (0.7, 0.3, 0.2)),
        MATERIAL
    },
    objects: [
        (shape: Quad(q: (-20, 0, -20), u: (0, 0, 24), v: (40, 0, 0)), material: "floor"),
        (shape: Sphere(center: (0, 0.5, -1), radius: 0.5), material: "clay"),
        OBJECT
    ],
    lights: [LIGHT],
)
"#;

/// The spot light, shining towards +z and a little down, and the mirror at z = 6.
const MIRROR: [&str; 3] = [
    r#""mirror": Metal(albedo: (0.8, 0.7, 0.6), fuzz: 0),"#,
    r#"(shape: Quad(q: (-20, 0, 6), u: (40, 0, 0), v: (0, 20, 0)), material: "mirror"),"#,
    "Spot(position: (0, 2, 4), look_at: (0, 1, 10), intensity: (20, 20, 20), cone_angle: 35, falloff_start: 30)",
];

/// The spot's image in that mirror: mirrored in z = 6, its intensity times the mirror's
/// albedo.
const IMAGE: [&str; 3] = [
    "",
    "",
    "Spot(position: (0, 2, 8), look_at: (0, 1, 2), intensity: (16, 14, 12), cone_angle: 35, falloff_start: 30)",
];

fn room(mirror: bool, light_tracing: &str) -> String {
    let [m, o, l] = if mirror { MIRROR } else { IMAGE };
    ROOM.replace("LT", light_tracing).replace("MATERIAL", m).replace("OBJECT", o).replace("LIGHT", l)
}

/// The room lit by a panel facing the mirror (one-sided, behind the camera and above what
/// the mirror shows the room of it), or by its image.
fn panel_room(mirror: bool, light_tracing: &str) -> String {
    let panel = |emit: &str, q: &str, v: &str| {
        format!(r#""panel": DiffuseLight(emit: {emit}), MATERIAL"#,)
            .replace("MATERIAL", if mirror { MIRROR[0] } else { "" })
            + &format!("@(shape: Quad(q: {q}, u: (1, 0, 0), v: {v}), material: \"panel\"),")
    };
    let text = match mirror {
        true => panel("(60, 60, 60)", "(-0.5, 3.5, 4)", "(0, 0.5, 0)"),
        false => panel("(48, 42, 36)", "(-0.5, 4, 8)", "(0, -0.5, 0)"),
    };
    let (materials, panel) = text.split_once('@').unwrap();
    let objects = if mirror { format!("{panel}{}", MIRROR[1]) } else { panel.to_string() };
    let room = ROOM.replace("spp: 1024", "spp: 4096");
    room.replace("LT", light_tracing)
        .replace("MATERIAL", materials)
        .replace("OBJECT", &objects)
        .replace("LIGHT", "")
}

/// Means of `b` x `b` blocks of the image, per channel.
fn blocks(film: &Film, b: u32) -> Vec<Vec3> {
    let mean = film.mean();
    let (bw, bh) = (film.width / b, film.height / b);
    let mut out = vec![Vec3::ZERO; (bw * bh) as usize];
    for y in 0..bh * b {
        for x in 0..bw * b {
            out[(y / b * bw + x / b) as usize] += mean[(y * film.width + x) as usize] / (b * b) as f32;
        }
    }
    out
}

/// The largest relative difference of `a`'s block means from `b`'s, over blocks and channels
/// (relative to the block's mean over the channels, so that dark channels do not dominate).
fn worst_block(a: &Film, b: &Film, size: u32) -> f32 {
    let (a, b) = (blocks(a, size), blocks(b, size));
    a.iter()
        .zip(&b)
        .map(|(a, b)| ((*a - *b).abs() / b.element_sum().max(1e-3) * 3.0).max_element())
        .fold(0.0, f32::max)
}

fn scene(text: &str) -> Arc<RenderScene> {
    SceneWorld::render_scene(&inline(text))
}

fn render(scene: &RenderScene) -> Film {
    oracle::render(scene, &|_, _| {})
}

#[test]
fn a_mirror_shows_the_lights_image() {
    // The path tracer cannot sample a spot light's light off a perfect mirror; light tracing
    // must give the image the mirror's closed form gives: the scene lit by the light's image.
    let image = render(&scene(&room(false, "Off")));
    let traced = scene(&room(true, "On"));
    assert!(traced.light_paths.is_some(), "light tracing takes the scene");
    let mirrored = render(&traced);
    let worst = worst_block(&mirrored, &image, 10);
    assert!(worst < 0.03, "light-traced mirror against the light's image: block means {worst} apart");
    // Without light tracing the image is black.
    let dark = render(&scene(&room(true, "Off")));
    assert!(dark.mean().iter().all(|p| *p == Vec3::ZERO), "the path tracer's share of the mirror's light");
}

#[test]
fn light_paths_splat_through_the_pixel_filter() {
    // With a filter the film splats (Mitsuba's tent, Gaussian), each light path's splat goes to
    // the pixels the filter reaches, weighed as the camera's samples are.
    for filter in ["Tent(radius: 1.5)", "Gaussian(stddev: 0.5)"] {
        let with =
            |text: String| text.replace("light_tracing:", &format!("filter: {filter}, light_tracing:"));
        let image = render(&scene(&with(room(false, "Off"))));
        let mirrored = render(&scene(&with(room(true, "On"))));
        let worst = worst_block(&mirrored, &image, 10);
        assert!(
            worst < 0.03,
            "{filter}: light-traced mirror against the light's image: block means {worst} apart"
        );
    }
}

#[test]
fn a_mirror_shows_a_panels_image() {
    // The path tracer finds a panel's light off a perfect mirror only by its BSDF samples;
    // light tracing takes those paths and must give the panel's image's light.
    let image = render(&scene(&panel_room(false, "Off")));
    let traced = scene(&panel_room(true, "On"));
    assert_eq!(
        traced.light_paths.as_deref().map(|l| l.traced.clone()),
        Some(vec![true]),
        "the panel is traced"
    );
    let mirrored = render(&traced);
    let worst = worst_block(&mirrored, &image, 10);
    assert!(worst < 0.03, "light-traced mirror against the panel's image: block means {worst} apart");
    // The path tracer's own estimate of the same (its BSDF samples off the mirror) agrees too.
    let plain = render(&scene(&panel_room(true, "Off")));
    let worst = worst_block(&plain, &image, 10);
    assert!(worst < 0.1, "the path tracer's mirror against the panel's image: block means {worst} apart");
}

/// A floor, a rough glass ball and a rough gold ball under a point light.
const BALLS: &str = r#"
#![enable(implicit_some)]
Scene(
    camera: (look_from: (0, 4, 4), look_at: (0, 0.3, 0), vfov: 40),
    render: (width: 32, height: 32, spp: 1024, max_depth: 64, light_tracing: LT),
    background: Constant((0, 0, 0)),
    materials: {
        "floor": Lambertian(albedo: (0.6, 0.6, 0.6)),
        "glass": RoughDielectric(ior: 1.5, alpha: 0.2),
        "gold": RoughConductor(tint: (1, 0.8, 0.5), alpha: 0.04, eta: (0.27, 0.68, 1.22), k: (3.61, 2.63, 2.29)),
    },
    objects: [
        (shape: Quad(q: (-20, 0, -20), u: (0, 0, 40), v: (40, 0, 0)), material: "floor"),
        (shape: Sphere(center: (-0.7, 0.6, 0), radius: 0.6), material: "glass"),
        (shape: Sphere(center: (0.8, 0.5, 0.3), radius: 0.5), material: "gold"),
    ],
    lights: [Point(position: (0.5, 3, -2), intensity: (10, 10, 10))],
)
"#;

#[test]
fn rough_lobes_give_the_path_tracers_image_from_the_lights_end() {
    // The glass's lobe is the path tracer's by default (the gold's is sharp); counted as
    // sharp, the light tracer takes both balls' caustics (and the floor seen in them), and
    // both estimate the same image.
    let plain = render(&scene(&BALLS.replace("LT", "Off")));
    let mut traced = (*scene(&BALLS.replace("LT", "On"))).clone();
    let mut plan = traced.light_paths.as_deref().expect("light tracing takes the scene").clone();
    plan.sharp = 0.3;
    traced.light_paths = Some(Arc::new(plan));
    let both = render(&traced);
    let worst = worst_block(&both, &plain, 8);
    assert!(worst < 0.04, "light-traced rough lobes against the path tracer's: block means {worst} apart");
    // The light tracer's share alone is a large part of the image: the comparison sees it.
    let alone = Film { pixels: vec![Default::default(); both.pixels.len()], ..both.clone() };
    let worst = worst_block(&Film { spp: both.spp, ..alone }, &plain, 8);
    assert!(worst > 0.2, "the light tracer's share is only {worst} of a block");
}

#[test]
fn light_paths_keep_the_bits_of_one_render() {
    let text = room(true, "On");
    let scene = scene(&text);
    // Threads.
    let one = common::render_threads(&inline(&text), 1);
    let two = common::render_threads(&inline(&text), 2);
    assert_eq!(one, two, "one thread and two");
    // Sample ranges merged.
    let mut parts = oracle::render_samples(&scene, 0..300, &|_, _| {});
    parts.merge(&oracle::render_samples(&scene, 300..1024, &|_, _| {}));
    assert_eq!(parts, one, "two sample ranges merged and one render");
    // The wavefront and the reference path tracer.
    let (wave, _) = wavefront::render(&scene, wavefront::Options::default(), &|_, _| {});
    assert_eq!(wave.light, one.light, "the light tracer's sums in both integrators");
    let differing = (wave.mean().iter().zip(one.mean()))
        .filter(|(a, b)| (**a - *b).abs().max_element() > 1e-6 * b.max_element().max(1e-3))
        .count();
    assert!(differing <= 2, "{differing} pixels differ between the integrators");
    // A crop: the window's pixels of the whole image, every light path traced for it.
    let cropped = SceneWorld::render_scene(&{
        let mut d = inline(&text);
        d.render.crop = Some(pathwave::engine::scene::CropWindow([0.25, 0.75, 0.5, 1.0]));
        d
    });
    let part = render(&cropped);
    let w = cropped.settings.window;
    let (whole, crop) = (one.mean(), part.mean());
    for y in 0..w.h {
        for x in 0..w.w {
            let at = ((y + w.y0) * one.width + x + w.x0) as usize;
            assert_eq!(crop[(y * w.w + x) as usize], whole[at], "pixel {x},{y} of the crop");
        }
    }
}

#[test]
fn scenes_without_its_paths_render_as_before() {
    // No sharp surface, or the camera has a lens: no light tracing, the same bits.
    let text = room(false, "On");
    assert!(scene(&text).light_paths.is_none(), "nothing sharp");
    assert_eq!(render(&scene(&text)), render(&scene(&room(false, "Off"))));
    let lens = room(true, "On").replace("vfov: 50)", "vfov: 50, aperture_radius: 0.05, focus_dist: 5)");
    assert!(scene(&lens).light_paths.is_none(), "a camera with a lens");
}

#[test]
fn shares_of_a_light_traced_render_merge_into_it_and_resume() {
    // Through the command line: machines' sample ranges (checkpoints of format 5, the light
    // tracer's sums beside the pixels') merge into the bits of one render, and --resume
    // completes a partial one.
    let dir = common::temp("light", "shares");
    std::fs::write(dir.join("room.ron"), room(true, "On").replace("spp: 1024", "spp: 8")).unwrap();
    let out = |name: &str| dir.join(name);
    let render = |name: &str, extra: &[&str]| {
        common::run(
            common::pathwave().arg("render").arg(dir.join("room.ron")).arg("-o").arg(out(name)).args(extra),
        )
    };
    render("whole.exr", &["-q"]);
    render("a.exr", &["-q", "--samples", "0..3"]);
    render("b.exr", &["-q", "--samples", "3..8"]);
    common::run(
        common::pathwave()
            .arg("merge")
            .arg(out("b.exr.ckpt"))
            .arg(out("a.exr.ckpt"))
            .arg("-o")
            .arg(out("ab.exr")),
    );
    let whole = std::fs::read(out("whole.exr")).unwrap();
    assert!(std::fs::read(out("ab.exr")).unwrap() == whole, "two shares merged");
    render("c.exr", &["-q", "--samples", "0..3"]);
    std::fs::rename(out("c.exr.ckpt"), out("d.exr.ckpt")).unwrap();
    render("d.exr", &["-q", "--resume"]);
    assert!(std::fs::read(out("d.exr")).unwrap() == whole, "a share resumed to the whole");
    std::fs::remove_dir_all(&dir).unwrap();
}
