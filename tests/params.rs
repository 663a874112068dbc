//! Scene parameters: `$name` takes the declared default or `-D name=value`, and errors point
//! into the file as written.

mod common;

use pathwave::engine::scene::{parse, parse_with};
use std::path::Path;

const SCENE: &str = r#"Scene(
    parameters: { "wall": "(0.7, 0.7, 0.7)", "spp": "16" },
    camera: (look_from: (0, 0, 5), look_at: (0, 0, 0), vfov: 40),
    render: (width: 8, height: 8, spp: $spp),
    background: Constant((1, 1, 1)),
    materials: { "white": Lambertian(albedo: $wall) },
    objects: [(shape: Sphere(center: (0, 0, 0), radius: 1), material: "white")],
)"#;

fn albedo(desc: &pathwave::engine::scene::SceneDesc) -> glam::Vec3 {
    use pathwave::engine::scene::{Color, MaterialDesc};
    match &desc.materials.0[0].1 {
        MaterialDesc::Lambertian(d) => match &d.albedo {
            Color::Value(a) => a.0,
            Color::Texture(_) => panic!("a texture"),
        },
        other => panic!("{other:?}"),
    }
}

#[test]
fn parameters_take_their_defaults_or_the_overrides() {
    let t = Path::new("t.ron");
    let d = parse(SCENE, t).unwrap();
    assert_eq!((d.render.spp.get(), albedo(&d)), (16, glam::Vec3::splat(0.7)));
    let o = [("wall".to_owned(), "(0.1, 0.2, 0.3)".to_owned()), ("spp".to_owned(), "4".to_owned())];
    let d = parse_with(SCENE, t, &o).unwrap();
    assert_eq!((d.render.spp.get(), albedo(&d)), (4, glam::Vec3::new(0.1, 0.2, 0.3)));
}

#[test]
fn parameter_errors_point_into_the_file_as_written() {
    let t = Path::new("t.ron");
    // A bad value: the error stands at the `$wall` that brought it.
    let wall = SCENE.lines().nth(5).unwrap().find("$wall").unwrap() + 1;
    let e = parse_with(SCENE, t, &[("wall".into(), "(2, 0, 0)".into())]).unwrap_err();
    assert_eq!((e.line, e.col), (6, wall), "{e}");
    assert!(e.message.contains("albedo"), "{e}");
    // An undeclared reference.
    let e = parse(&SCENE.replace("albedo: $wall", "albedo: $floor"), t).unwrap_err();
    assert_eq!((e.line, e.col), (6, wall), "{e}");
    assert!(e.message.contains("$floor is not a declared parameter"), "{e}");
    // An error after the substitutions has the position it has in the same scene written
    // without parameters.
    let bad = SCENE.replace("radius: 1)", "radius: -1)");
    let e = parse(&bad, t).unwrap_err();
    let literal = bad.replace("$spp", "16").replace("$wall", "(0.7, 0.7, 0.7)");
    let expected = parse(&literal, t).unwrap_err();
    assert_eq!((e.line, e.col, &e.message), (expected.line, expected.col, &expected.message));
    assert_eq!(e.line, 7, "{e}");
    // An override of nothing.
    let e = parse_with(SCENE, t, &[("walls".into(), "1".into())]).unwrap_err();
    assert!(e.message.contains("-D walls: the scene declares no such parameter"), "{e}");
}

#[test]
fn render_takes_d_overrides() {
    let dir = std::env::temp_dir().join(format!("pathwave-params-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("s.ron");
    std::fs::write(&scene, SCENE).unwrap();
    let render = |out: &str, extra: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_pathwave"))
            .arg("render")
            .arg(&scene)
            .args(["-q", "-o"])
            .arg(dir.join(out))
            .args(extra)
            .output()
            .unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    assert!(render("a.exr", &[]).0);
    assert!(render("b.exr", &["-D", "wall=(0.2, 0.2, 0.2)"]).0);
    let (a, b) = (
        pathwave::io::read_linear(&dir.join("a.exr")).unwrap(),
        pathwave::io::read_linear(&dir.join("b.exr")).unwrap(),
    );
    let mean = |i: &pathwave::io::LinearImage| i.pixels.iter().map(|p| p.x).sum::<f32>();
    assert!(mean(&b) < mean(&a), "a darker wall renders darker");
    let (ok, err) = render("c.exr", &["-D", "nothing"]);
    assert!(!ok && err.contains("-D takes NAME=VALUE"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
