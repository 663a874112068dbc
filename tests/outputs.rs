//! No file a command writes may replace a file the scene reads: not the image, nor the side
//! files its flags add (NAME.albedo.png, NAME.noisy.EXT, OUT.ckpt), nor the trace, nor a
//! frame of an animation; RON and Mitsuba XML scenes alike. Each is refused before any work,
//! and the input is left as it was. So are outputs that name a folder or the same AOV twice.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pathwave-outputs-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A small RON scene with an image texture `texture` (a 2x2 PNG written beside it).
fn textured_scene(dir: &Path, scene: &str, texture: &str) -> PathBuf {
    image::RgbImage::from_pixel(2, 2, image::Rgb([200, 100, 50]))
        .save_with_format(dir.join(texture), image::ImageFormat::Png)
        .unwrap();
    let path = dir.join(scene);
    std::fs::write(
        &path,
        format!(
            r#"Scene(
                camera: (look_from: (0, 0, 5), look_at: (0, 0, 0), vfov: 40),
                render: (width: 8, height: 8, spp: 2),
                textures: {{ "t": Image(file: "{texture}") }},
                materials: {{ "m": Lambertian(albedo: "t"), "l": DiffuseLight(emit: (4, 4, 4)) }},
                objects: [
                    (shape: Sphere(center: (0, 0, 0), radius: 1), material: "m"),
                    (shape: Sphere(center: (0, 3, 3), radius: 0.5), material: "l"),
                ],
            )"#
        ),
    )
    .unwrap();
    path
}

fn pathwave(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pathwave")).args(args).current_dir(dir).output().unwrap()
}

/// Runs `args`, which must fail with a message containing `words` and leave `kept` unchanged.
fn refused(dir: &Path, args: &[&str], words: &str, kept: &Path) {
    let before = std::fs::read(kept).unwrap();
    let o = pathwave(args, dir);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{args:?} succeeded: {err}");
    assert!(err.contains(words), "{args:?}: {err}");
    assert!(!err.contains("spp in"), "{args:?} rendered before refusing: {err}");
    assert_eq!(std::fs::read(kept).unwrap(), before, "{args:?} changed {}", kept.display());
}

#[test]
fn render_outputs_and_side_files_never_replace_a_scene_input() {
    let dir = folder("render");
    let over = "the render would write over this file, which the scene reads";
    textured_scene(&dir, "s.ron", "tex.png");
    refused(&dir, &["render", "s.ron", "-o", "tex.png"], over, &dir.join("tex.png"));
    // Through another spelling of the path, or a link.
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    refused(&dir, &["render", "s.ron", "-o", "./sub/../tex.png"], over, &dir.join("tex.png"));
    std::os::unix::fs::symlink(dir.join("tex.png"), dir.join("link.png")).unwrap();
    refused(&dir, &["render", "s.ron", "-o", "link.png"], over, &dir.join("tex.png"));
    textured_scene(&dir, "a.ron", "out.albedo.png");
    refused(
        &dir,
        &["render", "a.ron", "-o", "out.png", "--aov", "albedo"],
        over,
        &dir.join("out.albedo.png"),
    );
    textured_scene(&dir, "n.ron", "out.noisy.png");
    refused(
        &dir,
        &["render", "n.ron", "-o", "out.png", "--denoise", "atrous"],
        over,
        &dir.join("out.noisy.png"),
    );
    // A scene whose name is the checkpoint's, or the trace's.
    textured_scene(&dir, "x.png.ckpt", "t.png");
    refused(
        &dir,
        &["render", "x.png.ckpt", "-o", "x.png", "--checkpoint-every", "60"],
        over,
        &dir.join("x.png.ckpt"),
    );
    textured_scene(&dir, "scene.json", "t.png");
    refused(
        &dir,
        &["render", "scene.json", "-o", "y.png", "--trace", "scene.json"],
        over,
        &dir.join("scene.json"),
    );
    // Without the clash, the same commands render.
    let o = pathwave(&["render", "s.ron", "-o", "fine.png", "--aov", "albedo", "--trace", "t.json"], &dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_mitsuba_scene_s_includes_and_images_are_inputs_too() {
    let dir = folder("xml");
    image::Rgb32FImage::from_pixel(4, 2, image::Rgb([1.0, 1.0, 1.0])).save(dir.join("sky.exr")).unwrap();
    // An include may have any name, a trace's among them.
    std::fs::write(dir.join("inc.json"), r#"<scene version="3.0.0"><bsdf type="diffuse" id="d"/></scene>"#)
        .unwrap();
    std::fs::write(
        dir.join("s.xml"),
        r#"<scene version="3.0.0">
            <include filename="inc.json"/>
            <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
            <emitter type="envmap"><string name="filename" value="sky.exr"/></emitter>
            <shape type="sphere"><ref id="d"/></shape>
        </scene>"#,
    )
    .unwrap();
    let over = "the render would write over this file, which the scene reads";
    refused(&dir, &["render", "s.xml", "-o", "sky.exr"], over, &dir.join("sky.exr"));
    refused(&dir, &["render", "s.xml", "-o", "y.png", "--trace", "inc.json"], over, &dir.join("inc.json"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn no_frame_of_an_animation_replaces_a_scene_input() {
    let dir = folder("animate");
    textured_scene(&dir, "s.ron", "f0002.png");
    let args = ["animate", "s.ron", "-o", "f{frame:04}.png", "--frames", "0..4"];
    refused(&dir, &args, "the render would write over this file", &dir.join("f0002.png"));
    // A shard that does not render frame 2 has nothing to refuse.
    let o = pathwave(&[&args[..], &["--shard", "1/2"]].concat(), &dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("f0001.png").exists() && dir.join("f0003.png").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn outputs_that_cannot_be_written_are_refused_before_the_render() {
    let dir = folder("late");
    let scene = textured_scene(&dir, "s.ron", "tex.png");
    std::fs::create_dir_all(dir.join("folder.png")).unwrap();
    refused(&dir, &["render", "s.ron", "-o", "folder.png"], "is a folder", &scene);
    refused(&dir, &["render", "s.ron", "-o", "o.png", "--aov", "albedo,albedo"], "named twice", &scene);
    // A side file whose name is too long for the file system, though the image's is not.
    let long = format!("{}.png", "a".repeat(240));
    refused(&dir, &["render", "s.ron", "-o", &long, "--aov", "albedo"], "cannot write there", &scene);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_farm_refuses_frames_that_would_replace_a_scene_input_before_submitting() {
    let dir = folder("farm");
    textured_scene(&dir, "s.ron", "f002.png");
    let args =
        ["farm", "slurm", "s.ron", "-o", "f{frame:03}.png", "--tasks", "2", "--frames", "0..4", "--dry-run"];
    refused(&dir, &args, "the render would write over this file", &dir.join("f002.png"));
    textured_scene(&dir, "t.ron", "one.png");
    let args = ["farm", "slurm", "t.ron", "-o", "one.png", "--tasks", "2", "--split-samples", "--dry-run"];
    refused(&dir, &args, "the render would write over this file", &dir.join("one.png"));
    std::fs::remove_dir_all(&dir).unwrap();
}
