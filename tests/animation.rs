//! Animation: a frame of `animate` equals `render` at that time, a keyframed instance blurs
//! like the same motion without instancing, a static scene rebuilds no BVH after the first
//! frame, and a killed sequence resumes without redoing finished frames.

mod common;
use common::*;
use pathwave::animate::sequence;
use pathwave::engine::world::{SceneGeometry, SceneInstances, SceneLights, SceneWorld};
use pathwave::integrator::wavefront;
use pathwave::io::read_linear;
use std::path::{Path, PathBuf};
use std::process::Command;

fn temp(name: &str) -> PathBuf {
    common::temp("anim", name)
}

#[test]
fn a_frame_of_animate_equals_render_at_its_time() {
    let dir = temp("frame");
    let scene = root().join("scenes/animation-bounce.ron");
    let pattern = dir.join("f_{frame:03}.exr");
    let small = ["--spp", "4", "--width", "64", "--height", "48"];
    run(pathwave()
        .arg("animate")
        .arg(&scene)
        .args(["-o", pattern.to_str().unwrap(), "--frames", "17..19", "-q"])
        .args(small));
    // Frame 18 opens at 18/24 s for the scene's half-frame shutter, and so does render --time
    // 0.75 (it rendered the instant, without the blur, before).
    let still = dir.join("still.exr");
    run(pathwave()
        .arg("render")
        .arg(&scene)
        .args(["-o", still.to_str().unwrap(), "--time", "0.75", "-q"])
        .args(small));
    let frame = read_linear(&dir.join("f_018.exr")).unwrap();
    assert_eq!(frame, read_linear(&still).unwrap(), "frame 18 differs from render --time 0.75");
    // And the previous frame is a different picture (the ball moved).
    assert_ne!(read_linear(&dir.join("f_017.exr")).unwrap(), frame);
    std::fs::remove_dir_all(&dir).unwrap();
}

const INSTANCE_SCENE: &str = r#"Scene(
    camera: (look_from: (0, 0, 6), look_at: (0, 0, 0), vfov: 40),
    render: (width: 48, height: 48, spp: 64),
    background: Constant((1, 1, 1)),
    materials: { "m": Lambertian(albedo: (0.5, 0.5, 0.5)) },
    objects: [
        (
            shape: Mesh(file: "assets/knot-2k.obj"),
            material: "m",
            transform: [UniformScale(0.6)],
            animate: (translate: Linear([(0, (-1.5, 0, 0)), (1, (1.5, 0, 0))])),
        ),
    ],
    animation: (fps: 4, shutter: 1),
)"#;

#[test]
fn a_keyframed_instance_blurs_like_the_same_motion_without_instancing() {
    let desc = pathwave::engine::scene::parse(INSTANCE_SCENE, &root().join("scenes/inline.ron")).unwrap();
    let render_frame = |instanced: bool, shutter: f32| {
        let mut w = SceneWorld::new(&desc);
        if !instanced {
            use bevy_ecs::prelude::*;
            use pathwave::engine::world::Instanced;
            let es: Vec<Entity> =
                w.world.query_filtered::<Entity, With<Instanced>>().iter(&w.world).collect();
            for e in es {
                w.world.entity_mut(e).remove::<Instanced>();
            }
        }
        // Frame 1 of 4 per second with a full shutter: the knot sweeps 0.75 units.
        let scene = sequence::scene_at(&mut w, 1, 4.0, shutter).unwrap();
        assert_eq!(scene.features.instances, instanced);
        assert_eq!(scene.features.motion, shutter > 0.0);
        wavefront::render(&scene, wavefront::Options::default(), &|_, _| {}).0.mean()
    };
    let (inst, baked, still) = (render_frame(true, 1.0), render_frame(false, 1.0), render_frame(true, 0.0));
    let rel = |a: &[glam::Vec3], b: &[glam::Vec3]| pathwave::metrics::rel_mse(a, b);
    let same = rel(&inst, &baked);
    let blur = rel(&inst, &still);
    // The same samples see the same (moving) triangles up to rounding in two spaces.
    assert!(same < 1e-4, "instanced vs baked blur: relMSE {same}");
    assert!(blur > 100.0 * same.max(1e-6), "the blur must show: relMSE against the still {blur}");
}

#[test]
fn a_static_scene_rebuilds_no_bvh_after_the_first_frame() {
    let desc = scene("mesh.ron");
    let mut w = SceneWorld::new(&desc);
    for frame in 0..8 {
        sequence::scene_at(&mut w, frame, 24.0, 0.5).unwrap();
    }
    assert_eq!(w.world.resource::<SceneGeometry>().rebuilds, 1);
    let i = w.world.resource::<SceneInstances>();
    assert_eq!((i.builds, i.refits), (1, 0));
    // Whereas a scene whose ball moves rebuilds its primitives each frame.
    let mut w = SceneWorld::new(&scene("animation-bounce.ron"));
    for frame in 0..8 {
        sequence::scene_at(&mut w, frame, 24.0, 0.5).unwrap();
    }
    assert_eq!(w.world.resource::<SceneGeometry>().rebuilds, 8);
}

fn mtime(p: &Path) -> std::time::SystemTime {
    std::fs::metadata(p).unwrap().modified().unwrap()
}

#[test]
fn a_killed_sequence_resumes_without_redoing_frames() {
    let dir = temp("resume");
    let pattern = dir.join("f_{frame:04}.png");
    let args = |c: &mut Command| {
        c.arg("animate").arg(root().join("scenes/animation-orbit.ron")).args([
            "-o",
            pattern.to_str().unwrap(),
            "--frames",
            "0..12",
            "-t",
            "1",
            "--spp",
            "64",
        ]);
    };
    let frame = |i: u32| sequence::frame_path(pattern.to_str().unwrap(), i).unwrap();
    let mut child = {
        let mut c = pathwave();
        args(&mut c);
        c.stderr(std::process::Stdio::null()).spawn().unwrap()
    };
    // Kill it once two frames are on disk.
    let start = std::time::Instant::now();
    while !frame(1).exists() {
        assert!(start.elapsed().as_secs() < 120, "no frame after 2 minutes");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let done: Vec<u32> = (0..12).filter(|&i| frame(i).exists()).collect();
    assert!(done.len() < 12, "the run finished before it was killed");
    // No temporary file is left looking like a frame.
    for e in std::fs::read_dir(&dir).unwrap() {
        let name = e.unwrap().file_name().into_string().unwrap();
        assert!(name.starts_with("f_") || name.starts_with('.'), "{name}");
    }
    let before: Vec<_> = done.iter().map(|&i| mtime(&frame(i))).collect();
    let mut c = pathwave();
    args(&mut c);
    let log = run(&mut c);
    for (k, &i) in done.iter().enumerate() {
        assert_eq!(mtime(&frame(i)), before[k], "frame {i} was rendered again");
    }
    assert!((0..12).all(|i| frame(i).exists()));
    assert!(log.contains(&format!("{} skipped", done.len())), "{log}");
    // An empty frame (what versions before atomic writes left on a full disk) is not skipped.
    std::fs::write(frame(0), b"").unwrap();
    let mut c = pathwave();
    args(&mut c);
    let log = run(&mut c);
    assert!(log.contains("1 frames rendered, 11 skipped"), "{log}");
    assert!(read_linear(&frame(0)).is_ok(), "frame 0 was written again");
    // --overwrite renders them all.
    let mut c = pathwave();
    args(&mut c);
    let log = run(c.arg("--overwrite"));
    assert!(log.contains("12 frames rendered, 0 skipped"), "{log}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn animate_writes_an_animated_gif() {
    let dir = temp("gif");
    let gif = dir.join("a.gif");
    run(pathwave().arg("animate").arg(root().join("scenes/animation-bounce.ron")).args([
        "-o",
        gif.to_str().unwrap(),
        "--frames",
        "0..3",
        "--spp",
        "2",
        "--width",
        "32",
        "--height",
        "24",
        "--fps",
        "24",
    ]));
    use image::AnimationDecoder;
    let dec =
        image::codecs::gif::GifDecoder::new(std::io::BufReader::new(std::fs::File::open(&gif).unwrap()))
            .unwrap();
    let frames = dec.into_frames().collect_frames().unwrap();
    assert_eq!(frames.len(), 3);
    assert_eq!(frames[0].buffer().dimensions(), (32, 24));
    // GIF delays are hundredths of a second: 24 fps alternates 4 and 5 (at 1/24 s each, the
    // frames end at 4.2, 8.3 and 12.5 hundredths), where one delay of 4 would play at 25.
    let delays: Vec<(u32, u32)> = frames.iter().map(|f| f.delay().numer_denom_ms()).collect();
    assert_eq!(delays, [(40, 1), (40, 1), (50, 1)]);
    std::fs::remove_dir_all(&dir).unwrap();
}

const SPIN_SCENE: &str = r#"Scene(
    camera: (look_from: (0, 0, 7), look_at: (0, 0, 0), vfov: 40),
    render: (width: 48, height: 48, spp: 1024, max_depth: 4),
    background: Constant((1, 1, 1)),
    materials: { "m": Lambertian(albedo: (0.5, 0.5, 0.5)) },
    objects: [
        (
            shape: Mesh(file: "assets/knot-2k.obj"),
            material: "m",
            transform: [Translate((0.5, 0, 0))],
            animate: (rotate: Linear([(0, Euler((0, 0, 0))), (1, Euler((0, 0, 90)))])),
        ),
    ],
)"#;

/// The mean of `steps` renders at evenly spaced times in [0, 1] with the shutter closed.
fn still_average(desc: &pathwave::engine::scene::SceneDesc, steps: u32) -> pathwave::io::LinearImage {
    let mut sum = vec![glam::Vec3::ZERO; 48 * 48];
    for k in 0..steps {
        let t = (k as f32 + 0.5) / steps as f32;
        let mut d = desc.clone();
        d.render.spp = (desc.render.spp.get() / steps).try_into().unwrap();
        d.render.seed = 1000 + k as u64;
        let mut w = SceneWorld::new(&d);
        w.set_time(t, t);
        let film = pathwave::integrator::oracle::render(&w.update(), &|_, _| {});
        for (s, p) in sum.iter_mut().zip(film.mean()) {
            *s += p / steps as f32;
        }
    }
    pathwave::io::LinearImage { width: 48, height: 48, pixels: sum }
}

/// The scene `text` rendered with the shutter open over [0, 1] must agree (block means) with
/// the mean of 32 stills across it, and with a shutter 10% short must not; `moves` checks that
/// what should move while the shutter is open does.
fn blurs_like_its_stills(
    text: &str,
    what: &str,
    moves: impl Fn(&pathwave::engine::render_scene::RenderScene) -> bool,
) {
    let desc = pathwave::engine::scene::parse(text, &root().join("scenes/inline.ron")).unwrap();
    let reference = still_average(&desc, 32);
    let blurred = |close: f32| {
        let mut w = SceneWorld::new(&desc);
        w.set_time(0.0, close);
        let scene = w.update();
        assert!(moves(&scene), "{what}: nothing moves while the shutter is open");
        pathwave::integrator::oracle::render(&scene, &|_, _| {})
    };
    let stats = block_z(&blurred(1.0), &reference, 8, 1024);
    eprintln!("{what}: {stats:?}");
    assert!(stats.agrees(), "{what}: {stats:?}");
    let stats = block_z(&blurred(0.9), &reference, 8, 1024);
    eprintln!("{what}, shutter 10% short: {stats:?}");
    assert!(!stats.agrees(), "{what}: a shutter 10% short went unnoticed: {stats:?}");
}

#[test]
fn a_spinning_instance_averages_its_still_images() {
    blurs_like_its_stills(SPIN_SCENE, "spinning instance", |s| s.instances.list[0].motion.is_some());
}

/// A slab of grey smoke sliding across a white background (its stills are placed by the
/// keys alone, so that they check the linear motion that rays see while the shutter is open).
const SLIDING_SMOKE: &str = r#"Scene(
    camera: (look_from: (0, 0, 7), look_at: (0, 0, 0), vfov: 40),
    render: (width: 48, height: 48, spp: 1024, max_depth: 4),
    background: Constant((1, 1, 1)),
    materials: { "m": Lambertian(albedo: (0.5, 0.5, 0.5)) },
    objects: [
        (
            shape: Box(a: (-1.2, -0.8, -0.5), b: (-0.2, 0.8, 0.5)),
            medium: (density: 2, albedo: (0.5, 0.5, 0.5)),
            animate: (translate: Linear([(0, (0, 0, 0)), (1, (1.5, 0.3, 0))])),
        ),
    ],
)"#;

/// A plume of smoke from a voxel grid turning a quarter turn about the view axis.
const SPINNING_PLUME: &str = r#"Scene(
    camera: (look_from: (0, 0, 7), look_at: (0, 0, 0), vfov: 40),
    render: (width: 48, height: 48, spp: 1024, max_depth: 4),
    background: Constant((1, 1, 1)),
    materials: { "m": Lambertian(albedo: (0.5, 0.5, 0.5)) },
    objects: [
        (
            shape: Box(a: (-0.6, 0, -0.6), b: (0.6, 2, 0.6)),
            medium: (
                density: 40,
                albedo: (0.8, 0.8, 0.8),
                grid: (file: "assets/plume.vol", transform: [Scale((1.2, 2, 1.2)), Translate((-0.6, 0, -0.6))]),
            ),
            transform: [Translate((0.3, -1, 0))],
            animate: (rotate: Linear([(0, Euler((0, 0, 0))), (1, Euler((0, 0, 90)))])),
        ),
    ],
)"#;

#[test]
fn a_sliding_medium_averages_its_still_images() {
    blurs_like_its_stills(SLIDING_SMOKE, "sliding medium", |s| s.media.moving());
}

#[test]
fn a_spinning_grid_medium_averages_its_still_images() {
    blurs_like_its_stills(SPINNING_PLUME, "spinning grid medium", |s| s.media.moving());
}

#[test]
fn camera_and_emission_keys_reach_the_scene_and_only_changes_rebuild() {
    use pathwave::engine::material::Material;
    let desc = pathwave::engine::scene::parse(
        r#"Scene(
            camera: (look_from: (0, 0, 5), look_at: (0, 0, 0), vfov: 40),
            materials: { "l": DiffuseLight(emit: (1, 1, 1)), "m": Lambertian(albedo: (0.5, 0.5, 0.5)) },
            objects: [
                (shape: Quad(q: (-1, 2, -1), u: (2, 0, 0), v: (0, 0, 2)), material: "l"),
                (shape: Sphere(center: (0, 0, 0), radius: 1), material: "m"),
            ],
            animation: (
                camera: (look_from: Linear([(0, (0, 0, 5)), (2, (0, 0, 9))]), vfov: Smooth([(0, 40), (1, 30)])),
                emit: [("l", Linear([(0, (1, 1, 1)), (1, (3, 3, 3)), (2, (3, 3, 3))]))],
            ),
        )"#,
        std::path::Path::new("<test>"),
    )
    .unwrap();
    let mut w = SceneWorld::new(&desc);
    let emit = |s: &pathwave::engine::render_scene::RenderScene| match s.materials[0] {
        Material::DiffuseLight(l) => l.emit.x,
        other => panic!("the light is {other:?}"),
    };
    let at = |w: &mut SceneWorld, t: f32| {
        w.set_time(t, t);
        w.update()
    };
    let s = at(&mut w, 0.5);
    assert_eq!(emit(&s), 2.0);
    assert_eq!(
        s.camera,
        pathwave::engine::camera::Camera::new(
            glam::Vec3::new(0.0, 0.0, 6.0),
            glam::Vec3::ZERO,
            glam::Vec3::Y,
            35.0,
            0.0,
            6.0,
            (0.5, 0.5),
            512,
            512,
        )
    );
    let tables = |w: &SceneWorld| w.world.resource::<SceneLights>().rebuilds;
    let geometry = |w: &SceneWorld| w.world.resource::<SceneGeometry>().rebuilds;
    let (before, shapes) = (tables(&w), geometry(&w));
    // Between 1 and 2 s the radiance holds: the light table is not rebuilt.
    at(&mut w, 1.2);
    let b = tables(&w);
    at(&mut w, 1.6);
    assert_eq!(tables(&w), b, "a frame where nothing the light table depends on changed rebuilt it");
    assert!(b > before, "the radiance change from 2 to 3 reached the light table");
    assert_eq!(geometry(&w), shapes, "a change of radiance rebuilt the geometry");
}

#[test]
fn shards_split_a_sequence_into_the_frames_of_one_run() {
    let dir = temp("shard");
    let small = ["--spp", "2", "--width", "32", "--height", "24", "--frames", "0..7", "-t", "1"];
    let scene = root().join("scenes/animation-bounce.ron");
    let (whole, split) = (dir.join("whole_{frame:02}.exr"), dir.join("split_{frame:02}.exr"));
    run(pathwave().arg("animate").arg(&scene).arg("-o").arg(&whole).args(small));
    // Two processes at once on one directory, as on two machines sharing it.
    let shard = |i: u32| {
        let mut c = pathwave();
        c.arg("animate").arg(&scene).arg("-o").arg(&split).args(small).args(["--shard", &format!("{i}/2")]);
        c.stderr(std::process::Stdio::piped()).spawn().unwrap()
    };
    let (a, b) = (shard(0), shard(1));
    let logs: Vec<String> = [a, b]
        .into_iter()
        .map(|c| {
            let out = c.wait_with_output().unwrap();
            assert!(out.status.success());
            String::from_utf8_lossy(&out.stderr).to_string()
        })
        .collect();
    assert!(logs[0].contains("4 frames rendered") && logs[1].contains("3 frames rendered"), "{logs:?}");
    for f in 0..7 {
        let path = |p: &PathBuf| sequence::frame_path(p.to_str().unwrap(), f).unwrap();
        assert_eq!(std::fs::read(path(&split)).unwrap(), std::fs::read(path(&whole)).unwrap(), "frame {f}");
    }
    let gif = pathwave()
        .arg("animate")
        .arg(&scene)
        .arg("-o")
        .arg(dir.join("a.gif"))
        .args(small)
        .args(["--shard", "0/2"])
        .output()
        .unwrap();
    assert!(!gif.status.success());
    assert!(String::from_utf8_lossy(&gif.stderr).contains("a GIF needs every frame in one process"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A camera sliding sideways past a sphere and turning a little: the blurred frame must agree
/// with the mean of stills across the shutter.
const PAN_SCENE: &str = r#"Scene(
    camera: (look_from: (0, 0, 7), look_at: (0, 0, 0), vfov: 40),
    render: (width: 48, height: 48, spp: 1024, max_depth: 4),
    background: Constant((1, 1, 1)),
    materials: { "m": Lambertian(albedo: (0.5, 0.5, 0.5)), "r": Lambertian(albedo: (0.7, 0.1, 0.1)) },
    objects: [
        (shape: Sphere(center: (0, 0, 0), radius: 1), material: "m"),
        (shape: Sphere(center: (1.2, 0.8, -1), radius: 0.4), material: "r"),
        // A wall behind them, so that no block is background alone (noise-free).
        (shape: Quad(q: (-20, -20, -3), u: (40, 0, 0), v: (0, 40, 0)), material: "m"),
    ],
    animation: (camera: (
        look_from: Linear([(0, (-1, 0, 7)), (1, (1, 0, 7))]),
        look_at: Linear([(0, (-0.8, 0, 0)), (1, (0.8, 0, 0))]),
    )),
)"#;

#[test]
fn a_moving_camera_averages_its_still_images() {
    blurs_like_its_stills(PAN_SCENE, "panning camera", |s| s.camera.moves() && s.features.motion);
    // With the shutter closed the camera is still: no time is drawn.
    let desc = pathwave::engine::scene::parse(PAN_SCENE, &root().join("scenes/inline.ron")).unwrap();
    let mut w = SceneWorld::new(&desc);
    w.set_time(0.5, 0.5);
    let still = w.update();
    assert!(!still.camera.moves() && !still.features.motion);
}

/// A box spun by keyframes: as an analytic box it would take its mid-shutter pose; it must
/// blur like the mean of its stills.
const SPIN_BOX_SCENE: &str = r#"Scene(
    camera: (look_from: (0, 0, 7), look_at: (0, 0, 0), vfov: 40),
    render: (width: 48, height: 48, spp: 1024, max_depth: 4),
    background: Constant((1, 1, 1)),
    materials: { "m": Lambertian(albedo: (0.5, 0.5, 0.5)), "w": Lambertian(albedo: (0.8, 0.8, 0.8)) },
    objects: [
        (
            shape: Box(a: (-1, -1, -1), b: (1, 1, 1)),
            material: "m",
            animate: (rotate: Linear([(0, Euler((0, 0, 0))), (1, Euler((0, 0, 60)))])),
        ),
        (shape: Quad(q: (-20, -20, -3), u: (40, 0, 0), v: (0, 40, 0)), material: "w"),
    ],
)"#;

#[test]
fn a_spinning_box_averages_its_still_images() {
    blurs_like_its_stills(SPIN_BOX_SCENE, "spinning box", |s| s.instances.list[0].motion.is_some());
}

/// Rotation keys turn by the angles written: a 0 to 720 degree track turns the object twice,
/// and a track to -90 degrees turns it the negative way (read from the instance's transform).
#[test]
fn rotation_keys_turn_by_the_angles_written() {
    let text = |keys: &str| {
        format!(
            r#"Scene(
                camera: (look_from: (0, 0, 7), look_at: (0, 0, 0), vfov: 40),
                materials: {{ "m": Lambertian(albedo: (0.5, 0.5, 0.5)) }},
                objects: [(shape: Mesh(file: "assets/knot-2k.obj"), material: "m",
                           animate: (rotate: Linear({keys})))],
            )"#
        )
    };
    // The angle about +y by which the object's +x axis has turned, in (-180, 180].
    let angle_at = |desc: &pathwave::engine::scene::SceneDesc, t: f32| {
        let mut w = SceneWorld::new(desc);
        w.set_time(t, t);
        let x = w.update().instances.list[0].world_from_object.transform_vector3(glam::Vec3::X);
        (-x.z).atan2(x.x).to_degrees()
    };
    let wrap = |d: f32| (d + 540.0).rem_euclid(360.0) - 180.0;
    let path = root().join("scenes/inline.ron");
    let twice = pathwave::engine::scene::parse(
        &text("[(0, AxisAngle(axis: (0, 1, 0), degrees: 0)), (2, AxisAngle(axis: (0, 1, 0), degrees: 720))]"),
        &path,
    )
    .unwrap();
    for k in 0..=16 {
        let t = k as f32 / 8.0;
        let got = angle_at(&twice, t);
        assert!(wrap(got - 360.0 * t).abs() < 0.01, "at {t} s: {got} degrees, expected {}", 360.0 * t);
    }
    let back =
        pathwave::engine::scene::parse(&text("[(0, Euler((0, 0, 0))), (1, Euler((0, -90, 0)))]"), &path)
            .unwrap();
    for k in 1..=4 {
        let t = k as f32 / 4.0;
        let got = angle_at(&back, t);
        assert!((got + 90.0 * t).abs() < 0.01, "at {t} s: {got} degrees, expected {}", -90.0 * t);
    }
}

/// `animate --stats --trace -v` reports each frame's stages and scene update, the sequence's
/// table, the BVH updates in the log, and a trace with frames, updates and tiles.
#[test]
fn animate_reports_stages_and_bvh_updates_per_frame() {
    let dir = temp("profile");
    let scene = root().join("scenes/animation-bounce.ron");
    let trace = dir.join("t.json");
    let err = run(pathwave()
        .env_remove("RUST_LOG")
        .arg("animate")
        .arg(&scene)
        .args(["-o", dir.join("f_{frame:02}.png").to_str().unwrap(), "--frames", "0..3"])
        .args(["--spp", "2", "--width", "32", "--height", "24", "-v", "--stats", "--trace"])
        .arg(&trace));
    for frame in 0..3 {
        let line = err.lines().find(|l| l.starts_with(&format!("frame {frame}: scene update")));
        let line = line.unwrap_or_else(|| panic!("no stats line for frame {frame}:\n{err}"));
        assert!(line.contains("intersect_closest") && line.contains("shade_lambertian"), "{line}");
    }
    assert!(err.contains("the sequence's frames together:"), "{err}");
    assert!(err.contains("primitives' BVH built in"), "the log names the BVH build:\n{err}");
    assert!(err.contains("instances' TLAS"), "the log names the instances' updates:\n{err}");
    assert_eq!(err.matches("frame rendered in").count(), 3, "{err}");
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&trace).unwrap()).unwrap();
    let events = json["traceEvents"].as_array().unwrap();
    let count = |name: &str| events.iter().filter(|e| e["name"] == name).count();
    assert_eq!((count("frame"), count("scene_update")), (3, 3));
    assert!(count("tile") >= 3 * 4 && count("intersect_closest") == count("tile"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `render -q` prints only the summary when nothing goes wrong; `-v` logs the scene, the
/// build and the pass.
#[test]
fn log_levels_follow_quiet_and_verbose() {
    let dir = temp("log");
    let scene = root().join("scenes/cornell.ron");
    let args = ["--spp", "1", "--width", "16", "--height", "16", "-o"];
    let out = dir.join("c.png");
    let quiet =
        run(pathwave().env_remove("RUST_LOG").arg("render").arg(&scene).args(args).arg(&out).arg("-q"));
    assert_eq!(quiet.lines().count(), 1, "only the summary:\n{quiet}");
    let loud =
        run(pathwave().env_remove("RUST_LOG").arg("render").arg(&scene).args(args).arg(&out).arg("-v"));
    for what in ["scene parsed", "scene ready", "primitives' BVH built in", "pass: samples 0..1 of 1"] {
        assert!(loud.contains(what), "-v lacks {what:?}:\n{loud}");
    }
    assert!(!loud.contains("\u{1b}["), "no colour codes when stderr is not a terminal");
    // The scene's count of lights is the light table's (it once counted emitting primitives
    // only, and said lights=0 after "light table built lights=2").
    let lights = root().join("scenes/lights.ron");
    let log =
        run(pathwave().env_remove("RUST_LOG").arg("render").arg(&lights).args(args).arg(&out).arg("-v"));
    let count = |line: &str| {
        let line = log.lines().find(|l| l.contains(line)).unwrap_or_else(|| panic!("no {line:?}:\n{log}"));
        let at = line.find(" lights=").unwrap_or_else(|| panic!("{line}")) + 8;
        line[at..].split(|c: char| !c.is_ascii_digit()).next().unwrap().parse::<usize>().unwrap()
    };
    assert_eq!(count("scene ready"), count("light table built"), "{log}");
    assert!(count("scene ready") > 1, "{log}");
    // Into a file, progress is a line per pass (three passes of one sample), no bar.
    let passes = ["--spp", "3", "--width", "16", "--height", "16", "--checkpoint-every", "0", "-o"];
    let log = run(pathwave().env_remove("RUST_LOG").arg("render").arg(&scene).args(passes).arg(&out));
    assert!(!log.contains('\r'), "no bar redraws in a file:\n{log}");
    for k in 0..3 {
        assert!(log.contains(&format!("pass: samples {k}..{} of 3", k + 1)), "no line for pass {k}:\n{log}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `render --help` and `animate --help` list the same sample and output flags.
#[test]
fn render_and_animate_share_their_flags() {
    let help = |cmd: &str| {
        let out = pathwave().args([cmd, "--help"]).output().unwrap();
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let (render, animate) = (help("render"), help("animate"));
    for flag in [
        "--spp",
        "--width",
        "--height",
        "--seed",
        "--sampler",
        "--max-depth",
        "--clamp",
        "--integrator",
        "--batch",
        "--denoise",
        "--aov",
        "--checkpoint-every",
        "--threads",
        "--verbose",
        "--quiet",
        "--stats",
        "--trace",
        "--outfile",
        "--nthreads",
    ] {
        assert!(
            render.contains(flag) && animate.contains(flag),
            "{flag} is not in both:\n{render}\n{animate}"
        );
    }
}

/// `animate` with the render flags: per-frame checkpoints, denoised frames with their noisy
/// twins, a depth override; a GIF refuses the flags that write beside frames.
#[test]
fn animate_takes_the_render_flags() {
    let dir = temp("flags");
    let scene = root().join("scenes/animation-bounce.ron");
    let pattern = dir.join("f_{frame:02}.png");
    run(pathwave()
        .arg("animate")
        .arg(&scene)
        .args(["-o", pattern.to_str().unwrap(), "--frames", "0..2", "-q"])
        .args(["--spp", "2", "--width", "32", "--height", "24", "--max-depth", "3"])
        .args(["--checkpoint-every", "0", "--denoise", "--integrator", "oracle"]));
    for f in ["f_00.png", "f_00.noisy.png", "f_00.png.ckpt", "f_01.png", "f_01.noisy.png", "f_01.png.ckpt"] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    let gif = pathwave()
        .arg("animate")
        .arg(&scene)
        .args(["-o", dir.join("a.gif").to_str().unwrap(), "--frames", "0..2", "--denoise"])
        .output()
        .unwrap();
    assert!(!gif.status.success());
    assert!(String::from_utf8_lossy(&gif.stderr).contains("rather than a GIF"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A frame's checkpoint records its shutter interval: rendering the frame again with another
/// shutter (`--overwrite --shutter 1` after `--shutter 0`) is refused with the difference,
/// rather than resumed from the other shutter's samples.
#[test]
fn a_frame_checkpoint_of_another_shutter_is_refused() {
    let dir = temp("shutter-key");
    let scene = root().join("scenes/animation-bounce.ron");
    let pattern = dir.join("f_{frame:02}.exr");
    let animate = |extra: &[&str]| {
        pathwave()
            .arg("animate")
            .arg(&scene)
            .args(["-o", pattern.to_str().unwrap(), "--frames", "0..1", "-q", "--spp", "1"])
            .args(["--width", "8", "--height", "8", "--checkpoint-every", "60"])
            .args(extra)
            .output()
            .unwrap()
    };
    assert!(animate(&["--shutter", "0"]).status.success());
    let o = animate(&["--shutter", "1", "--overwrite"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("shutter"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A frame that is not the scene the file asks for fails, naming why, instead of rendering
/// something else with exit code 0: an animated camera the loader would refuse (look_from
/// reaching look_at, a Smooth vfov overshooting below zero between keys), an object animated
/// beyond 1e15 (an instanced mesh too), a shutter that carries a moving object to infinity.
/// Each rendered black or clamped in silence before.
#[test]
fn frames_the_scene_does_not_describe_fail() {
    let dir = temp("bad-frames");
    let scene = |camera: &str, object: &str, animation: &str| {
        format!(
            r#"Scene(
    camera: ({camera}),
    render: (width: 16, height: 12, spp: 1),
    materials: {{ "m": Lambertian(albedo: (0.5, 0.5, 0.5)) }},
    objects: [(shape: Sphere(center: (0, 0, 0), radius: 1), material: "m"{object})],
    animation: ({animation}),
)"#
        )
    };
    let still = "look_from: (0, 0, 5), look_at: (0, 0, 0), vfov: 40";
    std::fs::write(dir.join("t.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let cases = [
        (
            "look_from reaches look_at",
            scene(still, "", "camera: (look_from: Linear([(0, (0, 0, 5)), (1, (0, 0, 0))]))"),
            "1",
            "look_from and look_at are the same point",
        ),
        (
            // Catmull-Rom through 1, 1, 1, 170: about -11.5 degrees at t = 2/3.
            "vfov overshoots",
            scene(still, "", "camera: (vfov: Smooth([(0, 1), (1, 1), (2, 170), (3, 1)]))"),
            "0.6667",
            "vfov must lie in (0, 180)",
        ),
        (
            "object animated away",
            scene(still, ", animate: (translate: Linear([(0, (0, 0, 0)), (1, (1e16, 0, 0))]))", ""),
            "1",
            "objects[0]",
        ),
        (
            "instanced mesh animated away",
            scene(still, ", animate: (translate: Linear([(0, (0, 0, 0)), (1, (1e16, 0, 0))]))", "")
                .replace("Sphere(center: (0, 0, 0), radius: 1)", r#"Mesh(file: "t.obj")"#),
            "1",
            "objects[0]: its placement carries it beyond 1e15 units",
        ),
        (
            "moving object, endless shutter",
            scene(&format!("{still}, shutter: (-2e38, 2e38)"), ", motion: (velocity: (1, 0, 0))", ""),
            "0",
            "beyond 1e15 units",
        ),
    ];
    for (what, text, time, words) in &cases {
        let path = dir.join("s.ron");
        std::fs::write(&path, text).unwrap();
        let out = pathwave()
            .args(["render", "--time", time, "-o"])
            .arg(dir.join("s.png"))
            .arg(&path)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(words), "{what}: {err}");
        assert!(!dir.join("s.png").exists(), "{what}: an image was written");
    }
    // Frame 1 of the first, through `animate`, is refused too; frame 0 is fine alone.
    std::fs::write(dir.join("s.ron"), &cases[0].1).unwrap();
    let pattern = dir.join("f_{frame}.png");
    let out = pathwave()
        .args(["animate", "--fps", "1", "--frames", "0..2", "-o"])
        .arg(&pattern)
        .arg(dir.join("s.ron"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("frame 1:"), "{err}");
}
