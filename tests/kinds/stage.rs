//! The stage table: a stage registered by one row of `stages!` (the integrator's
//! `TestExposure`, built with its `test-stage` feature, one file) is in the pipeline in its
//! place, takes its queue's items, is counted under its name, and does its work on the paths:
//! it scales each finished path's radiance by a factor, so an image rendered with the factor
//! 1/2 is half the image rendered with 1, pixel by pixel.
//!
//! A test binary of its own: the factor is a global that every render in the process reads.

use pathwave_engine::scene::parse;
use pathwave_engine::world::SceneWorld;
use pathwave_integrator::wavefront::{self, Stage, test_stage};
use std::path::Path;
use std::sync::atomic::Ordering::Relaxed;

const SCENE: &str = r#"Scene(
    camera: (look_from: (0, 1.5, 5), look_at: (0, 0.6, 0), vfov: 40),
    render: (width: 12, height: 9, spp: 16),
    background: Constant((0.2, 0.2, 0.2)),
    materials: {
        "light": DiffuseLight(emit: (6, 6, 6)),
        "white": Lambertian(albedo: (0.6, 0.6, 0.5)),
        "glass": Dielectric(ior: 1.5),
    },
    objects: [
        (shape: Quad(q: (-1, 3, -1), u: (2, 0, 0), v: (0, 0, 2)), material: "light"),
        (shape: Sphere(center: (0, 0.7, 0), radius: 0.7), material: "glass"),
        (shape: Quad(q: (-4, 0, -4), u: (0, 0, 8), v: (8, 0, 0)), material: "white"),
    ],
)"#;

#[test]
fn a_stage_registered_in_one_row_runs_in_its_place_on_its_queue() {
    let stage = Stage::TestExposure;
    assert_eq!(stage.name(), "test_exposure");
    let at = Stage::ALL.iter().position(|&s| s == stage).expect("the table lists it");
    assert_eq!(Stage::ALL[at + 1], Stage::AccumulateFilm, "its row is just before the film's");

    let scene = SceneWorld::render_scene(&parse(SCENE, Path::new("<test>")).unwrap());
    let samples = 12 * 9 * 16;
    let render = |factor: f32| {
        test_stage::EXPOSURE.store(factor.to_bits(), Relaxed);
        let seen = test_stage::SEEN.load(Relaxed);
        let (film, stats) = wavefront::render(&scene, wavefront::Options::default(), &|_, _| {});
        // Every path ends once: the stage took each, and its statistics slot counted them.
        assert_eq!(stats.items[stage.index()], samples);
        assert_eq!(test_stage::SEEN.load(Relaxed) - seen, samples);
        film.mean()
    };
    let one = render(1.0);
    let half = render(0.5);
    assert!(one.iter().any(|p| p.max_element() > 0.1), "the scene is lit");
    for (k, (a, b)) in one.iter().zip(&half).enumerate() {
        assert!(
            (*a * 0.5 - *b).abs().max_element() <= 1e-6 * a.max_element().max(1.0),
            "pixel {k}: {a} vs {b}"
        );
    }
}
