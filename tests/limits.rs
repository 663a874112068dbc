//! Whatever a scene, an asset or a flag says, work and memory stay bounded: only regular
//! files are read, within a size; `mtllib` is never opened; images that decode too large are
//! refused; image sizes and batches from flags are bounded up front.

mod common;

use common::root;
use pathwave::engine::scene::parse;
use std::path::Path;
use std::process::Command;

fn scene_with(textures: &str, material: &str, shape: &str) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0, 0, 5), look_at: (0, 0, 0), vfov: 40),
            textures: {{ {textures} }},
            materials: {{ "m": {material} }},
            objects: [(shape: {shape}, material: "m")],
        )"#
    )
}

const LAMBERT: &str = "Lambertian(albedo: (0.5, 0.5, 0.5))";
const SPHERE: &str = "Sphere(center: (0, 0, 0), radius: 1)";

#[test]
fn assets_are_read_within_bounds() {
    let dir = std::env::temp_dir().join(format!("pathwave-limits-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let at = dir.join("s.ron");
    // A device is not a mesh (it would read forever).
    let e = parse(&scene_with("", LAMBERT, r#"Mesh(file: "/dev/zero")"#), &at).unwrap_err();
    assert!(e.message.contains("is not a regular file"), "{e}");
    // `mtllib` naming a device is ignored; the mesh loads.
    std::fs::write(dir.join("m.obj"), "mtllib /dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    parse(&scene_with("", LAMBERT, r#"Mesh(file: "m.obj")"#), &at).unwrap();
    // A small file that decodes to an image wider than 32768 pixels.
    image::GrayImage::new(40_000, 1).save(dir.join("wide.png")).unwrap();
    let textured = scene_with(r#""w": Image(file: "wide.png")"#, r#"Lambertian(albedo: "w")"#, SPHERE);
    let e = parse(&textured, &at).unwrap_err();
    assert!(e.message.contains("cannot read the image") && e.message.contains("wide.png"), "{e}");
    // A folder is not an image.
    std::fs::create_dir_all(dir.join("folder.png")).unwrap();
    let folder = scene_with(r#""f": Image(file: "folder.png")"#, r#"Lambertian(albedo: "f")"#, SPHERE);
    assert!(parse(&folder, &at).unwrap_err().message.contains("not a regular file"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn turbulence_octaves_are_bounded() {
    let at = Path::new("t.ron");
    let ok = scene_with(r#""n": Turbulence(scale: 4, depth: 24)"#, r#"Lambertian(albedo: "n")"#, SPHERE);
    parse(&ok, at).unwrap();
    for depth in ["0", "25", "4000000000"] {
        let t = format!(r#""n": Marble(scale: 4, depth: {depth})"#);
        let e = parse(&scene_with(&t, r#"Lambertian(albedo: "n")"#, SPHERE), at).unwrap_err();
        assert!(e.message.contains("expected 1 to 24 octaves"), "{depth}: {e}");
    }
}

#[test]
fn sizes_and_batches_from_flags_are_bounded_up_front() {
    let run = |extra: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
            .args(["render", "scenes/cornell.ron", "-q", "-o"])
            .arg(std::env::temp_dir().join(format!("pathwave-limits-{}.png", std::process::id())))
            .args(extra)
            .current_dir(root())
            .output()
            .unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (ok, err) = run(&["--width", "100000", "--height", "100000"]);
    assert!(!ok && err.contains("each side is at most 65536"), "{err}");
    // 60000 x 60000 pixels need hundreds of GiB: refused before any allocation.
    if Path::new("/proc/meminfo").exists() {
        let (ok, err) = run(&["--width", "60000", "--height", "60000"]);
        assert!(!ok && err.contains("more than the") && err.contains("MiB available"), "{err}");
    }
    let (ok, err) = run(&["--batch", "1000000000000"]);
    assert!(!ok && err.contains("--batch"), "{err}");
    for (flags, says) in [
        (&["--spp", "20000000"][..], "at most 16777216 samples per pixel"),
        (&["--max-depth", "4294967295"], "1024 bounces"),
        (&["--threads", "100000"], "not in 1..=1024"),
    ] {
        let (ok, err) = run(flags);
        assert!(!ok && err.contains(says), "{flags:?}: {err}");
    }
}

#[test]
fn watch_takes_the_bounds_of_render() {
    // Flags beyond them fail at once (the watch would otherwise wait for a fix of the scene).
    for (flags, says) in [
        (&["--width", "100000"][..], "at most 65536 pixels"),
        (&["--spp", "20000000"], "16777216 samples per pixel"),
        (&["-t", "0"], "not in 1..=1024"),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
            .args(["watch", "scenes/cornell.ron"])
            .args(flags)
            .current_dir(root())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(says), "{flags:?}: {err}");
    }
}

/// Paths on the command line that are not files (a device, a pipe) are refused, not read
/// until memory runs out; a frame pattern cannot ask for a gigantic name.
#[test]
fn hostile_paths_on_the_command_line_are_refused() {
    let dir = std::env::temp_dir().join(format!("pathwave-paths-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_pathwave")).args(args).current_dir(root()).output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let out = dir.join("m.png");
    let out = out.to_str().unwrap();
    let (ok, err) = run(&["merge", "/dev/zero", "-o", out]);
    assert!(!ok && err.contains("/dev/zero is not a regular file"), "{err}");
    let (ok, err) = run(&["compare", "--encoded", "decode", "/dev/zero", "tests/references/cornell.exr"]);
    assert!(!ok && err.contains("/dev/zero is not a regular file"), "{err}");
    let pattern = dir.join("{frame:099999999999}.png");
    let (ok, err) = run(&["animate", "scenes/animation-bounce.ron", "-o", pattern.to_str().unwrap()]);
    assert!(!ok && err.contains("N at most 10"), "{err}");
    // Frame times stay within --time's bound.
    let pattern = dir.join("{frame}.png");
    let (ok, err) = run(&["animate", "scenes/motion.ron", "--fps", "1e-30", "-o", pattern.to_str().unwrap()]);
    assert!(!ok && err.contains("beyond 1e7 seconds"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Face indices that refer to no vertex, texture coordinate or normal are refused with the
/// line (the `obj` fuzzer found a relative normal index before the first normal overflowing
/// inside tobj).
#[test]
fn obj_indices_beyond_the_lists_are_refused() {
    let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
    for (face, says) in [
        ("f 1//-16 2//1 3//1", "line 6: index -16 refers to no normal"),
        ("f 1/9223372036854775807 2/1 3/1", "index 9223372036854775807 refers to no texture coordinate"),
        ("f -9223372036854775808 2 3", "refers to no vertex"),
        ("f 1 2 4", "index 4 refers to no vertex"),
    ] {
        let err =
            pathwave::engine::scene::parse_obj(format!("{head}{face}\n").as_bytes(), Path::new("m.obj"))
                .unwrap_err();
        assert!(err.contains("the mesh m.obj") && err.contains(says), "{face}: {err}");
    }
    let ok = pathwave::engine::scene::parse_obj(
        format!("{head}f -3/-1/-1 -2/1/1 3/1/1\n").as_bytes(),
        Path::new("m.obj"),
    );
    assert_eq!(ok.unwrap().triangles.len(), 1);
    // A vertex normal of 1e38 is normalised at load (its square overflowed when interpolated).
    let m = pathwave::engine::scene::parse_obj(
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 1e38 0 -1\nf 1//1 2//1 3//1\n",
        Path::new("m.obj"),
    )
    .unwrap();
    let n = m.normals.unwrap()[0];
    assert!(n.abs_diff_eq(glam::Vec3A::X, 1e-6), "{n}");
}
