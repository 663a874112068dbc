//! The XML reader's conversions and refusals, on small scenes written here.

use super::to_ron;
use std::path::{Path, PathBuf};

fn scene(tag: &str, body: &str) -> PathBuf {
    scene_with(tag, SENSOR, body)
}

/// A scene whose sensor is `sensor`.
fn scene_with(tag: &str, sensor: &str, body: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pathwave-mitsuba-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join("scene.xml");
    std::fs::write(&p, format!("<scene version=\"3.0.0\">\n{sensor}\n{body}\n</scene>\n")).unwrap();
    p
}

const SENSOR: &str = r#"<sensor type="perspective"><float name="fov" value="40"/>
<transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
<film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/><rfilter type="box"/></film></sensor>"#;

fn ron(tag: &str, body: &str) -> String {
    let p = scene(tag, body);
    to_ron(&p, &[], p.parent().unwrap()).unwrap_or_else(|e| panic!("{e}")).ron
}

fn error(tag: &str, body: &str) -> crate::scene::SceneError {
    let p = scene(tag, body);
    match to_ron(&p, &[], p.parent().unwrap()) {
        Ok(c) => panic!("converted:\n{}", c.ron),
        Err(e) => e,
    }
}

#[test]
fn depths_count_scattering_events() {
    let r = ron(
        "depth",
        r#"<integrator type="moment"><integrator type="path"><integer name="max_depth" value="3"/></integrator></integrator>"#,
    );
    assert!(r.contains("max_depth: 2, rr_depth: 5"), "{r}");
    let r = ron("unbounded", r#"<integrator type="volpath"/>"#);
    assert!(r.contains("max_depth: 1024"), "{r}");
    let r = ron("direct", r#"<integrator type="direct"/>"#);
    assert!(r.contains("max_depth: 1,"), "{r}");
}

#[test]
fn plugins_become_pathwave_kinds() {
    let r = ron(
        "kinds",
        r#"<bsdf type="twosided" id="white"><bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.6, 0.5"/></bsdf></bsdf>
        <shape type="rectangle"><ref id="white"/><transform name="to_world"><scale value="2"/><translate z="-1"/></transform></shape>
        <shape type="cube"><bsdf type="dielectric"><string name="int_ior" value="water"/></bsdf></shape>
        <shape type="sphere"><float name="radius" value="0.5"/><emitter type="area"><rgb name="radiance" value="4"/></emitter></shape>
        <emitter type="point"><transform name="to_world"><translate value="1, 2, 3"/></transform><rgb name="intensity" value="10"/></emitter>"#,
    );
    for want in [
        r#""white": Lambertian(albedo: (0.7, 0.6, 0.5))"#,
        r#"(shape: Quad(q: (-1, -1, 0), u: (2, 0, 0), v: (0, 2, 0)), material: "white", transform: [UniformScale(2), Translate((0, 0, -1))])"#,
        "Dielectric(ior: 1.33263",
        "Sphere(center: (0, 0, 0), radius: 0.5)",
        "DiffuseLight(emit: (4, 4, 4), two_sided: false)",
        "Point(position: (1, 2, 3), intensity: (10, 10, 10))",
    ] {
        assert!(r.contains(want), "missing {want} in\n{r}");
    }
}

#[test]
fn instances_place_their_group_members() {
    let r = ron(
        "instance",
        r#"<shape type="shapegroup" id="g"><shape type="sphere"><transform name="to_world"><translate x="1"/></transform></shape></shape>
        <shape type="instance"><ref id="g"/><transform name="to_world"><rotate y="1" angle="90"/></transform></shape>
        <shape type="instance"><ref id="g"/></shape>"#,
    );
    assert!(r.contains("transform: [Translate((1, 0, 0)), Rotate(axis: (0, 1, 0), degrees: 90)]"), "{r}");
    assert_eq!(r.matches("Sphere(").count(), 2, "{r}");
}

#[test]
fn the_envmap_turns_as_mitsuba_turns_it() {
    let d = std::env::temp_dir().join(format!("pathwave-mitsuba-env-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    image::Rgb32FImage::new(4, 2).save(d.join("sky.exr")).unwrap();
    let r = ron(
        "env",
        &format!(
            r#"<emitter type="envmap"><string name="filename" value="{}"/><transform name="to_world"><rotate y="1" angle="30"/></transform></emitter>"#,
            d.join("sky.exr").display()
        ),
    );
    assert!(r.contains("rotate: 30"), "{r}");
}

/// Refusals name the place and what pathwave reads instead.
#[test]
fn what_is_not_supported_is_refused_where_it_is_written() {
    let e = error("plugin", "\n<shape type=\"teapot\"/>");
    assert_eq!((e.line, e.col), (6, 1), "{e}");
    assert!(e.message.contains("teapot") && e.message.contains("rectangle, cube, sphere"), "{e}");
    let e = error("param", "<shape type=\"sphere\"><float name=\"radios\" value=\"1\"/></shape>");
    assert!(e.message.contains("`radios`") && e.message.contains("radius"), "{e}");
    let e = error("bsdf", "<shape type=\"sphere\"><bsdf type=\"plastic\"/></shape>");
    assert!(e.message.contains("plastic"), "{e}");
    let e = error("ref", "<shape type=\"sphere\"><ref id=\"nope\"/></shape>");
    assert!(e.message.contains("nope"), "{e}");
    let e = error("twice", "<bsdf type=\"diffuse\" id=\"a\"/><bsdf type=\"diffuse\" id=\"a\"/>");
    assert!(e.message.contains("twice"), "{e}");
    let e = error(
        "hide",
        "<integrator type=\"path\"><boolean name=\"hide_emitters\" value=\"true\"/></integrator>",
    );
    assert!(e.message.contains("hide"), "{e}");
    let e = error(
        "spectrum",
        "<shape type=\"sphere\"><bsdf type=\"conductor\"><spectrum name=\"eta\" value=\"700:1, 400:2\"/></bsdf></shape>",
    );
    assert!(e.message.contains("increase"), "{e}");
}

#[test]
fn file_names_are_relative_to_the_ron() {
    let d = std::env::temp_dir().join(format!("pathwave-mitsuba-files-{}", std::process::id()));
    std::fs::create_dir_all(d.join("meshes")).unwrap();
    std::fs::write(d.join("meshes/t.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(
        d.join("s.xml"),
        format!("<scene version=\"3.0.0\">{SENSOR}<shape type=\"obj\"><string name=\"filename\" value=\"meshes/t.obj\"/></shape></scene>"),
    )
    .unwrap();
    let r = to_ron(&d.join("s.xml"), &[], &d).unwrap().ron;
    assert!(r.contains(r#"Mesh(file: "meshes/t.obj")"#), "{r}");
    std::fs::create_dir_all(d.join("out")).unwrap();
    let r = to_ron(&d.join("s.xml"), &[], &d.join("out")).unwrap().ron;
    assert!(r.contains(r#"Mesh(file: "../meshes/t.obj")"#), "{r}");
    let _ = Path::new("");
}

#[test]
fn checkerboards_keep_mitsubas_cells() {
    let r = ron(
        "checker",
        r#"<texture type="checkerboard" id="c"><transform name="to_uv"><scale x="5" y="3"/></transform><rgb name="color0" value="0.8"/></texture>
        <shape type="rectangle"><bsdf type="diffuse"><ref name="reflectance" id="c"/></bsdf></shape>
        <shape type="cube"><bsdf type="diffuse"><texture name="reflectance" type="checkerboard"/></bsdf></shape>"#,
    );
    assert!(r.contains(r#""c": UvChecker(u: 10, v: 6, even: (0.8, 0.8, 0.8), odd: (0.2, 0.2, 0.2))"#), "{r}");
    assert!(r.contains(r#"Lambertian(albedo: "c")"#), "{r}");
    assert!(r.contains("UvChecker(u: 2, v: 2, even: (0.4, 0.4, 0.4)"), "{r}");
}

#[test]
fn spectra_become_the_rgb_mitsuba_makes_of_them() {
    let r = ron(
        "spectra",
        r#"<shape type="sphere"><bsdf type="diffuse"><spectrum name="reflectance" value="0.5"/></bsdf></shape>
        <shape type="cube"><emitter type="area"><spectrum name="radiance" value="2"/></emitter></shape>"#,
    );
    assert!(r.contains("Lambertian(albedo: (0.5, 0.5, 0.5))"), "{r}");
    // Emission: 2 times equal-energy white in sRGB, not (2, 2, 2).
    let white = super::spectrum::xyz_to_srgb(glam::DVec3::ONE) * 2.0;
    assert!(r.contains(&format!("DiffuseLight(emit: {}", super::convert::v3(white))), "{r}");
}

/// Mitsuba's sensors always clip: the camera gets near_clip and far_clip, the scene's or
/// Mitsuba's defaults (0.01 and 10000), for perspective, thinlens and orthographic alike.
#[test]
fn sensors_keep_their_clip_planes() {
    let film =
        r#"<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>"#;
    let convert = |tag: &str, sensor: &str| {
        let p = scene_with(tag, sensor, "");
        to_ron(&p, &[], p.parent().unwrap()).unwrap_or_else(|e| panic!("{e}")).ron
    };
    let r = ron("clip-default", "");
    assert!(r.contains("near_clip: 0.01, far_clip: 10000"), "{r}");
    for kind in ["perspective", "thinlens", "orthographic"] {
        let lens = if kind == "thinlens" { r#"<float name="focus_distance" value="2"/>"# } else { "" };
        let sensor = format!(
            r#"<sensor type="{kind}"><float name="near_clip" value="0.5"/><float name="far_clip" value="25"/>{lens}{film}</sensor>"#
        );
        let r = convert(&format!("clip-{kind}"), &sensor);
        assert!(r.contains("near_clip: 0.5, far_clip: 25"), "{kind}: {r}");
        // The RON loader takes what the converter wrote.
        let desc =
            crate::scene::parse(&r, std::path::Path::new("<converted>")).unwrap_or_else(|e| panic!("{e}"));
        let clip = desc.camera.view.clip().expect("clip planes");
        assert_eq!((clip.near, clip.far), (0.5, 25.0), "{kind}");
    }
    let bad = format!(
        r#"<sensor type="perspective"><float name="near_clip" value="3"/><float name="far_clip" value="2"/>{film}</sensor>"#
    );
    let p = scene_with("clip-bad", &bad, "");
    let e = to_ron(&p, &[], p.parent().unwrap()).err().expect("refused").to_string();
    assert!(e.contains("need 0 < near < far"), "{e}");
}

/// Rough BSDFs take Mitsuba's distribution (Beckmann unless told `ggx`) and an isotropic alpha,
/// from `alpha` or from equal `alpha_u` and `alpha_v`; unequal ones are refused where written.
#[test]
fn microfacets_keep_their_distribution() {
    let r = ron(
        "rough",
        r#"<shape type="sphere"><bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf></shape>
        <shape type="cube"><bsdf type="roughdielectric"><string name="distribution" value="GGX"/></bsdf></shape>
        <shape type="rectangle"><bsdf type="roughconductor"><string name="distribution" value="ggx"/>
            <float name="alpha_u" value="0.3"/><float name="alpha_v" value="0.3"/></bsdf></shape>"#,
    );
    for want in [
        "RoughConductor(tint: (1, 1, 1), alpha: 0.2, distribution: Beckmann)",
        "RoughDielectric(ior: 1.504",
        "alpha: 0.1, distribution: Ggx)",
        "RoughConductor(tint: (1, 1, 1), alpha: 0.3, distribution: Ggx)",
    ] {
        assert!(r.contains(want), "missing {want} in\n{r}");
    }
    let e = error(
        "aniso",
        "<shape type=\"sphere\"><bsdf type=\"roughconductor\"><float name=\"alpha_u\" value=\"0.1\"/>\n<float name=\"alpha_v\" value=\"0.3\"/></bsdf></shape>",
    );
    assert_eq!((e.line, e.col), (6, 1), "{e}");
    assert!(e.message.contains("anisotropic") && e.message.contains("isotropic"), "{e}");
    for (tag, body, message) in [
        ("one-axis", r#"<float name="alpha_u" value="0.1"/>"#, "alpha_u and alpha_v go together"),
        (
            "both",
            r#"<float name="alpha" value="0.1"/><float name="alpha_u" value="0.1"/>"#,
            "either alpha or",
        ),
        ("phong", r#"<string name="distribution" value="phong"/>"#, "\"beckmann\" and \"ggx\""),
    ] {
        let e = error(
            tag,
            &format!("<shape type=\"sphere\"><bsdf type=\"roughdielectric\">{body}</bsdf></shape>"),
        );
        assert!(e.message.contains(message), "{tag}: {e}");
    }
}
