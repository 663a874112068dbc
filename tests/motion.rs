//! Motion blur: the image of a moving sphere is the average over the shutter of the images of
//! the sphere standing still, so the blurred render must agree (block means, within the noise)
//! with the mean of static renders at evenly spaced times; a shutter 5% too short must not.

mod common;
use common::*;
use pathwave::engine::scene::{MotionDesc, SceneDesc, TransformOp, V3};
use pathwave::io::LinearImage;

const SCENE: &str = r#"
Scene(
    camera: (look_from: (0, 1, 6), look_at: (0, 0.5, 0), vfov: 30, shutter: (0, 1)),
    render: (width: 64, height: 48, spp: 1024, max_depth: 8),
    background: Sky(),
    materials: {
        "ground": Lambertian(albedo: (0.5, 0.5, 0.5)),
        "red": Lambertian(albedo: (0.7, 0.2, 0.1)),
    },
    objects: [
        (shape: Sphere(center: (0, -1000, 0), radius: 1000), material: "ground"),
        (shape: Sphere(center: (-0.5, 0.5, 0), radius: 0.5), material: "red", motion: (velocity: (1, 0.4, 0))),
    ],
)"#;

/// The mean of `steps` renders with the sphere standing where it is at times (k + 0.5) / steps.
fn static_average(desc: &SceneDesc, steps: u32) -> LinearImage {
    let velocity = desc.objects[1].motion.expect("the sphere moves").velocity.0;
    let mut sum = vec![glam::Vec3::ZERO; 64 * 48];
    for k in 0..steps {
        let t = (k as f32 + 0.5) / steps as f32;
        let mut still = desc.clone();
        still.camera.shutter = (0.0, 0.0);
        still.render.spp = (desc.render.spp.get() / steps).try_into().unwrap();
        still.render.seed = 1000 + k as u64;
        let sphere = &mut still.objects[1];
        sphere.motion = None;
        sphere.transform.push(TransformOp(glam::Affine3A::from_translation(velocity * t)));
        for (s, p) in sum.iter_mut().zip(render(&still).mean()) {
            *s += p / steps as f32;
        }
    }
    LinearImage { width: 64, height: 48, pixels: sum }
}

#[test]
fn a_moving_sphere_averages_its_static_images() {
    let desc = inline(SCENE);
    let reference = static_average(&desc, 64);
    let stats = block_z(&render(&desc), &reference, 8, 1024);
    eprintln!("moving: {stats:?}");
    assert!(stats.agrees(), "{stats:?}");

    let mut short = desc.clone();
    short.camera.shutter = (0.0, 0.95);
    let stats = block_z(&render(&short), &reference, 8, 1024);
    eprintln!("shutter 5% short: {stats:?}");
    assert!(!stats.agrees(), "a shutter 5% too short went unnoticed: {stats:?}");
}

#[test]
fn motion_in_the_scene_file() {
    let desc = inline(SCENE);
    assert_eq!(desc.objects[1].motion, Some(MotionDesc { velocity: V3(glam::Vec3::new(1.0, 0.4, 0.0)) }));
    assert_eq!(desc.objects[0].motion, None);
}
