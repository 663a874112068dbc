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
        r#"(shape: Quad(q: (-1, 1, 0), u: (2, 0, 0), v: (0, -2, 0), flip_normal: true), material: "white", transform: [UniformScale(2), Translate((0, 0, -1))])"#,
        "Box(a: (-1, -1, -1), b: (1, 1, 1), uv: Mitsuba)",
        "Dielectric(ior: 1.33263",
        "Sphere(center: (0, 0, 0), radius: 0.5, poles: Z)",
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
    let e = error("bsdf", "<shape type=\"sphere\"><bsdf type=\"measured\"/></shape>");
    assert!(e.message.contains("measured") && e.message.contains("roughplastic"), "{e}");
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
    // Mitsuba's default flip of v is pathwave's reading; without it, pathwave flips.
    for (flip, want) in [("true", r#"Mesh(file: "meshes/t.obj")"#), ("false", "flip_tex_coords: true")] {
        let obj = format!(
            r#"<shape type="obj"><string name="filename" value="meshes/t.obj"/><boolean name="flip_tex_coords" value="{flip}"/></shape>"#
        );
        std::fs::write(d.join("f.xml"), format!("<scene version=\"3.0.0\">{SENSOR}{obj}</scene>")).unwrap();
        let r = to_ron(&d.join("f.xml"), &[], &d).unwrap_or_else(|e| panic!("{e}")).ron;
        assert!(r.contains(want), "flip_tex_coords {flip}: {r}");
    }
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
    // Mitsuba's uv (u, 1 - v), then to_uv.
    let c = r#""c": UvChecker(u: 2, v: 2, even: (0.8, 0.8, 0.8), odd: (0.2, 0.2, 0.2), uv_transform: ((5, 0, 0), (0, -3, 3)))"#;
    assert!(r.contains(c), "{r}");
    assert!(r.contains(r#"Lambertian(albedo: "c", two_sided: false)"#), "{r}");
    assert!(r.contains("UvChecker(u: 2, v: 2, even: (0.4, 0.4, 0.4), odd: (0.2, 0.2, 0.2), uv_transform: ((1, 0, 0), (0, -1, 1)))"), "{r}");
}

/// A 4 x 3 PNG whose texels all differ: column i, row j (from the top) is
/// (10 + 60 i, 20 + 70 j, 5 + 15 (i + j)).
fn texels_png(dir: &Path) -> PathBuf {
    let img = image::RgbImage::from_fn(4, 3, |i, j| {
        image::Rgb([10 + 60 * i as u8, 20 + 70 * j as u8, 5 + 15 * (i + j) as u8])
    });
    let path = dir.join("texels.png");
    img.save(&path).unwrap();
    path
}

/// Texel (i, j) of [`texels_png`] as Mitsuba reads it (sRGB-decoded), or `raw`.
fn texel(i: i64, j: i64, raw: bool) -> glam::Vec3 {
    let code = [10 + 60 * i, 20 + 70 * j, 5 + 15 * (i + j)];
    glam::Vec3::from_array(code.map(|c| match raw {
        true => c as f32 / 255.0,
        false => crate::texture::srgb8_table()[c as usize],
    }))
}

#[test]
fn bitmaps_become_images() {
    let d = std::env::temp_dir().join(format!("pathwave-mitsuba-bitmap-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let png = texels_png(&d);
    let r = ron(
        "bitmap",
        &format!(
            r#"<shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="{png}"/></texture></bsdf></shape>
            <shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="{png}"/>
                <string name="filter_type" value="nearest"/><string name="wrap_mode" value="mirror"/><boolean name="raw" value="true"/>
                <transform name="to_uv"><scale x="2" y="3"/><translate x="-0.5" y="0.25"/></transform></texture></bsdf></shape>"#,
            png = png.display()
        ),
    );
    assert!(r.contains(r#"Image(file: "texels.png", wrap: Repeat, filter: Bilinear)"#), "{r}");
    // (u, 1 - v), to_uv (u' = 2 u - 0.5, v' = 3 v + 0.25), (u, 1 - v): u' = 2 u - 0.5,
    // v' = 1 - (3 (1 - v) + 0.25) = 3 v - 2.25.
    let want = r#"Image(file: "texels.png", wrap: Mirror, filter: Nearest, raw: true, uv_transform: ((2, 0, -0.5), (0, 3, -2.25)))"#;
    assert!(r.contains(want), "{r}");
    let refused = |tag: &str, param: &str| {
        error(
            tag,
            &format!(
                r#"<shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="{}"/>
                {param}</texture></bsdf></shape>"#,
                png.display()
            ),
        )
    };
    let e = refused("bitmap-filter", r#"<string name="filter_type" value="cubic"/>"#);
    assert!(e.message.contains(r#""cubic""#) && e.message.contains("bilinear and nearest"), "{e}");
    assert_eq!(e.line, 6, "{e}");
    let e = refused("bitmap-wrap", r#"<string name="wrap_mode" value="border"/>"#);
    assert!(e.message.contains(r#""border""#) && e.message.contains("repeat, mirror and clamp"), "{e}");
    let e = refused("bitmap-format", r#"<string name="format" value="uint8"/>"#);
    assert!(e.message.contains(r#""uint8""#) && e.message.contains("32-bit"), "{e}");
    let e = error(
        "bitmap-ior",
        &format!(
            r#"<shape type="sphere"><bsdf type="conductor"><texture type="bitmap" name="eta"><string name="filename" value="{}"/></texture></bsdf></shape>"#,
            png.display()
        ),
    );
    assert!(e.message.contains("`eta` must be a colour"), "{e}");
    let e = error(
        "bitmap-none",
        r#"<shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"/></bsdf></shape>"#,
    );
    assert!(e.message.contains("needs a filename"), "{e}");
}

/// Renders nothing: loads the converted scene and reads, at Mitsuba's local points of each
/// shape, the reflectance pathwave shades with, against the texel Mitsuba's definitions give
/// there (its shapes' uv, `src/shapes/{rectangle,sphere,cube}.cpp`; the nearest lookup of
/// `src/textures/bitmap.cpp` through Dr.Jit: texel (floor(u w), floor(v h)), row 0 of the file
/// at v = 0; the checkerboard's cells).
#[test]
fn converted_shapes_read_the_texels_mitsuba_reads() {
    use crate::math::Ray;
    use glam::{DMat4, DVec3, Vec3A};
    let d = std::env::temp_dir().join(format!("pathwave-mitsuba-texels-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let png = texels_png(&d);
    let bitmap = format!(
        r#"<texture type="bitmap" id="t"><string name="filename" value="{}"/><string name="filter_type" value="nearest"/></texture>
        <texture type="checkerboard" id="c"><transform name="to_uv"><scale x="3" y="2"/></transform><rgb name="color0" value="0.9"/><rgb name="color1" value="0.1"/></texture>
        <bsdf type="diffuse" id="b"><ref name="reflectance" id="t"/></bsdf>
        <bsdf type="diffuse" id="k"><ref name="reflectance" id="c"/></bsdf>"#,
        png.display()
    );
    // Each shape alone, placed by `to_world` (a mirroring one among them).
    let placements = [
        r#"<rotate x="1" angle="30"/><translate z="-3"/>"#,
        r#"<scale x="-1" y="2"/><rotate y="1" angle="20"/><translate z="-3"/>"#,
    ];
    let mitsuba_texel = |uv: DVec3| texel((uv.x * 4.0).floor() as i64, (uv.y * 3.0).floor() as i64, false);
    let checker = |uv: DVec3| {
        let (a, b) = ((uv.x * 3.0).fract() > 0.5, (uv.y * 2.0).fract() > 0.5);
        glam::Vec3::splat(if a == b { 0.9 } else { 0.1 })
    };
    let mut rnd = crate::testing::signed(5);
    for (kind, shape) in [("rectangle", "rectangle"), ("sphere", "sphere"), ("cube", "cube")] {
        for (pi, place) in placements.iter().enumerate() {
            for (bsdf, expect) in [("b", &mitsuba_texel as &dyn Fn(DVec3) -> glam::Vec3), ("k", &checker)] {
                let tag = format!("texels-{kind}-{pi}-{bsdf}");
                let p = scene(
                    &tag,
                    &format!(
                        r#"{bitmap}<shape type="{shape}"><ref id="{bsdf}"/><transform name="to_world">{place}</transform></shape>"#
                    ),
                );
                let desc = crate::scene::load(&p).unwrap_or_else(|e| panic!("{e}"));
                let scene = crate::world::SceneWorld::render_scene(&desc);
                let to_world = super::props::compose(&mitsuba_to_world(place));
                let normal_to_world =
                    DMat4::from_mat3(glam::DMat3::from_mat4(to_world).inverse().transpose());
                let mut checked = 0;
                for _ in 0..400 {
                    // A local point, its outward normal and Mitsuba's uv there.
                    let (local, n, uv) = match kind {
                        "rectangle" => {
                            let (x, y) = (rnd() as f64, rnd() as f64);
                            (
                                DVec3::new(x, y, 0.0),
                                DVec3::Z,
                                DVec3::new((x + 1.0) / 2.0, (y + 1.0) / 2.0, 0.0),
                            )
                        }
                        "sphere" => {
                            let v = DVec3::new(rnd() as f64, rnd() as f64, rnd() as f64);
                            if !(v.length() > 0.1 && v.length() < 1.0) {
                                continue;
                            }
                            let v = v.normalize();
                            let phi = v.y.atan2(v.x).rem_euclid(std::f64::consts::TAU);
                            (
                                v,
                                v,
                                DVec3::new(
                                    phi / std::f64::consts::TAU,
                                    v.z.acos() / std::f64::consts::PI,
                                    0.0,
                                ),
                            )
                        }
                        _ => {
                            let face = (rnd().abs() * 5.999) as usize;
                            let (s, t) = (rnd() as f64, rnd() as f64);
                            cube_point(face, s, t)
                        }
                    };
                    // Away from texel and cell edges, where f32 rounding may pick either side.
                    let near_edge = |x: f64, k: f64| ((x * k).fract() - 0.5).abs() > 0.49;
                    if near_edge(uv.x, 4.0)
                        || near_edge(uv.y, 3.0)
                        || near_edge(uv.x, 6.0)
                        || near_edge(uv.y, 4.0)
                    {
                        continue;
                    }
                    let wp = to_world.transform_point3(local);
                    let wn = normal_to_world.transform_vector3(n).normalize();
                    let o = wp + wn * 0.01;
                    let ray = Ray::new(Vec3A::from(o.as_vec3()), Vec3A::from((-wn).as_vec3()));
                    let hit =
                        scene.intersect(&ray, 1.0).unwrap_or_else(|| panic!("{tag}: no hit at {local}"));
                    let albedo = scene.albedo_at(hit.material, &hit.surface);
                    let want = expect(uv);
                    assert!(
                        (albedo - want).abs().max_element() < 1e-6,
                        "{tag}: at {local} (Mitsuba's uv {uv}) {albedo}, not {want}"
                    );
                    assert!(
                        hit.surface.n.dot(Vec3A::from(wn.as_vec3())) > 0.99,
                        "{tag}: the normal faces in at {local}"
                    );
                    checked += 1;
                }
                assert!(checked > 100, "{tag}: {checked} points");
            }
        }
    }
}

/// The `<transform>` steps of `xml`.
fn mitsuba_to_world(xml: &str) -> Vec<super::props::Op> {
    use super::props::Op;
    use glam::DVec3;
    let attr = |e: &str, name: &str| -> f64 {
        e.split(&format!("{name}=\""))
            .nth(1)
            .and_then(|r| r.split('"').next())
            .map_or(0.0, |v| v.parse().unwrap())
    };
    xml.split('<')
        .filter(|e| !e.is_empty())
        .map(|e| {
            if e.starts_with("rotate") {
                Op::Rotate(DVec3::new(attr(e, "x"), attr(e, "y"), attr(e, "z")), attr(e, "angle"))
            } else if e.starts_with("translate") {
                Op::Translate(DVec3::new(attr(e, "x"), attr(e, "y"), attr(e, "z")))
            } else {
                let one = |v: f64| if v == 0.0 { 1.0 } else { v };
                Op::Scale(DVec3::new(one(attr(e, "x")), one(attr(e, "y")), one(attr(e, "z"))))
            }
        })
        .collect()
}

/// A point of Mitsuba's cube (`src/shapes/cube.cpp`) on face `face` at (s, t) in [-1, 1]^2,
/// its outward normal and Mitsuba's uv there (each face's two triangles interpolate its
/// vertices' uv, an affine map of the face).
fn cube_point(face: usize, s: f64, t: f64) -> (glam::DVec3, glam::DVec3, glam::DVec3) {
    use glam::DVec3;
    let (a, b) = ((s + 1.0) / 2.0, (t + 1.0) / 2.0);
    // Per face: the point at (s, t), the normal, and uv as read off the vertex table.
    match face {
        // -y: vertices 0-3; u = (z + 1) / 2, v = (x + 1) / 2.
        0 => (DVec3::new(s, -1.0, t), -DVec3::Y, DVec3::new(b, a, 0.0)),
        // +y: u = (1 - x) / 2, v = (1 - z) / 2.
        1 => (DVec3::new(s, 1.0, t), DVec3::Y, DVec3::new(1.0 - a, 1.0 - b, 0.0)),
        // +x: u = (y + 1) / 2, v = (1 - z) / 2.
        2 => (DVec3::new(1.0, s, t), DVec3::X, DVec3::new(a, 1.0 - b, 0.0)),
        // +z: u = (y + 1) / 2, v = (x + 1) / 2.
        3 => (DVec3::new(s, t, 1.0), DVec3::Z, DVec3::new(b, a, 0.0)),
        // -x: u = (y + 1) / 2, v = (z + 1) / 2.
        4 => (DVec3::new(-1.0, s, t), -DVec3::X, DVec3::new(a, b, 0.0)),
        // -z: u = (1 - y) / 2, v = (x + 1) / 2.
        _ => (DVec3::new(s, t, -1.0), -DVec3::Z, DVec3::new(1.0 - b, a, 0.0)),
    }
}

#[test]
fn spectra_become_the_rgb_mitsuba_makes_of_them() {
    let r = ron(
        "spectra",
        r#"<shape type="sphere"><bsdf type="diffuse"><spectrum name="reflectance" value="0.5"/></bsdf></shape>
        <shape type="cube"><emitter type="area"><spectrum name="radiance" value="2"/></emitter></shape>"#,
    );
    assert!(r.contains("Lambertian(albedo: (0.5, 0.5, 0.5), two_sided: false)"), "{r}");
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
        let lens = match kind {
            "thinlens" => {
                r#"<float name="focus_distance" value="2"/><float name="aperture_radius" value="0.1"/>"#
            }
            _ => "",
        };
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

/// An area emitter on a shape whose BSDF reflects is an object's `emit` beside its material;
/// with no BSDF or a black one it stays a `DiffuseLight`. Its radiance may be a texture.
#[test]
fn area_emitters_on_reflecting_shapes_emit_beside_their_material() {
    let r = ron(
        "area-reflects",
        r#"<bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.8"/></bsdf>
        <shape type="rectangle"><ref id="white"/><emitter type="area"><rgb name="radiance" value="0.2, 0.4, 0.6"/></emitter></shape>
        <shape type="sphere"><ref id="white"/><emitter type="area"><texture name="radiance" type="checkerboard"/></emitter></shape>
        <shape type="cube"><emitter type="area"><rgb name="radiance" value="3"/></emitter></shape>"#,
    );
    assert!(r.contains(r#"material: "white", emit: (radiance: (0.2, 0.4, 0.6))"#), "{r}");
    assert!(r.contains(r#"material: "white", emit: (radiance: "checkerboard-0")"#), "{r}");
    assert!(r.contains("DiffuseLight(emit: (3, 3, 3), two_sided: false)"), "{r}");
}

/// Mitsuba's spot and projector: placed by their `to_world` (a rotation, a uniform scale and
/// a translation; a projector's scale multiplies its intensity, as in Mitsuba), the spot with
/// its linear falloff, `beam_width` defaulting to 3/4 of `cutoff_angle`.
#[test]
fn spots_and_projectors_keep_mitsubas_placement_and_falloff() {
    let r = ron(
        "spot-projector",
        r#"<emitter type="spot"><rgb name="intensity" value="5"/><float name="cutoff_angle" value="20"/>
            <transform name="to_world"><lookat origin="0, 3, 0" target="0, 0, 0" up="0, 0, 1"/></transform></emitter>
        <emitter type="spot"><texture name="texture" type="checkerboard"/><float name="cutoff_angle" value="30"/><float name="beam_width" value="15"/>
            <transform name="to_world"><lookat origin="1, 0, 0" target="1, 0, 1" up="0, 1, 0"/></transform></emitter>
        <emitter type="projector"><float name="fov" value="45"/><float name="scale" value="3"/>
            <transform name="to_world"><scale value="2"/><lookat origin="0, 0, 1" target="0, 0, 0" up="0, 1, 0"/></transform></emitter>"#,
    );
    for want in [
        "Spot(position: (0, 3, 0), look_at: (0, 2, 0), intensity: (5, 5, 5), cone_angle: 20, falloff_start: 15, falloff: Linear)",
        r#"Spot(position: (1, 0, 0), look_at: (1, 0, 1), intensity: (1, 1, 1), cone_angle: 30, falloff_start: 15, falloff: Linear, texture: "checkerboard-0", up: (0, 1, 0))"#,
        "Projector(position: (0, 0, 1), look_at: (0, 0, -1), up: (0, 2, 0), fov: 45, fov_axis: X, irradiance: (1, 1, 1), scale: 6)",
    ] {
        assert!(r.contains(want), "{want} not in\n{r}");
    }
    let e = error(
        "spot-sheared",
        r#"<emitter type="spot"><transform name="to_world"><scale x="2"/></transform></emitter>"#,
    );
    assert!(e.to_string().contains("rotation, a uniform scale and a translation"), "{e}");
    let e = error(
        "spot-intensity-texture",
        r#"<emitter type="spot"><texture name="intensity" type="checkerboard"/></emitter>"#,
    );
    assert!(e.to_string().contains("`intensity` is a colour, not a texture"), "{e}");
}

/// A thin lens needs its aperture (Mitsuba has no default) and focuses at far_clip unless told
/// (Mitsuba's `Sensor` constructor; its documentation's 0 is not what it does).
#[test]
fn a_thin_lens_needs_its_aperture_and_focuses_at_far_clip() {
    let film =
        r#"<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>"#;
    let lens = |tag: &str, params: &str| {
        let p = scene_with(tag, &format!(r#"<sensor type="thinlens">{params}{film}</sensor>"#), "");
        to_ron(&p, &[], p.parent().unwrap())
    };
    let e = lens("lens-none", "").err().expect("refused").to_string();
    assert!(e.contains("needs an aperture_radius"), "{e}");
    let r =
        lens("lens-far", r#"<float name="aperture_radius" value="0.1"/><float name="far_clip" value="50"/>"#)
            .unwrap_or_else(|e| panic!("{e}"))
            .ron;
    assert!(r.contains("aperture_radius: 0.1") && r.contains("focus_dist: 50"), "{r}");
    crate::scene::parse(&r, Path::new("<converted>")).unwrap_or_else(|e| panic!("{e}"));
}

/// Anonymous BSDFs that convert to the same material are one material (as an author writes
/// it); a BSDF with an id keeps its own name, and other anonymous ones stay apart.
#[test]
fn identical_anonymous_bsdfs_share_one_material() {
    let r = ron(
        "dedup",
        r#"<shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0.2"/></bsdf></shape>
        <shape type="sphere"><float name="radius" value="0.5"/><bsdf type="diffuse"><rgb name="reflectance" value="0.2"/></bsdf></shape>
        <shape type="cube"><bsdf type="diffuse"><rgb name="reflectance" value="0.3"/></bsdf></shape>
        <bsdf type="diffuse" id="named"><rgb name="reflectance" value="0.2"/></bsdf>
        <shape type="rectangle"><ref id="named"/></shape>"#,
    );
    assert_eq!(r.matches("Lambertian(albedo: (0.2, 0.2, 0.2), two_sided: false)").count(), 2, "{r}");
    assert_eq!(r.matches("material: \"diffuse-0\"").count(), 2, "{r}");
    assert!(
        r.contains("material: \"named\"")
            && r.contains("Lambertian(albedo: (0.3, 0.3, 0.3), two_sided: false)"),
        "{r}"
    );
    crate::scene::parse(&r, Path::new("<converted>")).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn disks_cylinders_and_mesh_files_convert_with_mitsubas_defaults() {
    let p = scene(
        "shapes",
        r#"<shape type="disk"><boolean name="flip_normals" value="true"/></shape>
        <shape type="cylinder"><point name="p0" value="0, 0, 1"/><point name="p1" value="0, 2, 1"/><float name="radius" value="0.5"/></shape>
        <shape type="cylinder"/>
        <shape type="obj"><string name="filename" value="m.obj"/></shape>
        <shape type="obj"><string name="filename" value="m.obj"/><boolean name="flip_tex_coords" value="false"/></shape>
        <shape type="ply"><string name="filename" value="m.ply"/><boolean name="flip_normals" value="true"/>
            <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"><string name="name" value="vertex_color"/></texture></bsdf></shape>
        <shape type="serialized"><string name="filename" value="m.serialized"/><integer name="shape_index" value="2"/></shape>"#,
    );
    let dir = p.parent().unwrap();
    for f in ["m.obj", "m.ply", "m.serialized"] {
        std::fs::write(dir.join(f), "").unwrap();
    }
    let r = to_ron(&p, &[], dir).unwrap_or_else(|e| panic!("{e}")).ron;
    for want in [
        "Disk(center: (0, 0, 0), normal: (0, 0, 1), radius: 1, flip_normals: true)",
        "Cylinder(p0: (0, 0, 1), p1: (0, 2, 1), radius: 0.5)",
        "Cylinder(p0: (0, 0, 0), p1: (0, 0, 1), radius: 1)",
        // Mitsuba flips an OBJ's v unless told not to, and reads the others' as written.
        r#"Mesh(file: "m.obj")"#,
        r#"Mesh(file: "m.obj", flip_tex_coords: true)"#,
        r#"Mesh(file: "m.ply", flip_normals: true, flip_tex_coords: true)"#,
        r#"Mesh(file: "m.serialized", shape_index: 2, flip_tex_coords: true)"#,
        r#"MeshAttribute(name: "vertex_color", scale: 1)"#,
    ] {
        assert!(r.contains(want), "{want} in\n{r}");
    }
    let e = error("flip", r#"<shape type="sphere"><boolean name="flip_normals" value="true"/></shape>"#);
    assert!(e.message.contains("flip_normals"), "{e}");
    let e = error(
        "attr",
        r#"<texture type="mesh_attribute" id="t"><string name="name" value="color"/></texture>
        <shape type="sphere"><bsdf type="diffuse"><ref name="reflectance" id="t"/></bsdf></shape>"#,
    );
    assert!(e.message.contains("vertex_ or face_"), "{e}");
    let e = error("tube", r#"<shape type="cylinder"><float name="radius" value="0"/></shape>"#);
    assert!(e.message.contains("radius > 0"), "{e}");
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
    // Anisotropic and textured: roughconductor's alpha_u and alpha_v, roughdielectric's alpha.
    let r = ron(
        "aniso-ok",
        r#"<shape type="sphere"><bsdf type="roughconductor"><float name="alpha_u" value="0.1"/>
            <texture name="alpha_v" type="checkerboard"><float name="color0" value="0.3"/></texture></bsdf></shape>
        <shape type="cube"><bsdf type="roughdielectric"><texture name="alpha" type="checkerboard"/></bsdf></shape>"#,
    );
    for want in [
        r#"RoughConductor(tint: (1, 1, 1), alpha: 0.1, alpha_v: "checkerboard-0", distribution: Beckmann)"#,
        // Read as a number, Mitsuba's checkerboard has color0 (0.3) where its colour has color1.
        r#""checkerboard-0": UvChecker(u: 2, v: 2, even: (0.2, 0.2, 0.2), odd: (0.3, 0.3, 0.3)"#,
        r#"RoughDielectric(ior: 1.5041833, alpha: "checkerboard-1", distribution: Beckmann)"#,
    ] {
        assert!(r.contains(want), "missing {want} in\n{r}");
    }
    let e = error(
        "plastic-texture",
        "<shape type=\"sphere\"><bsdf type=\"roughplastic\">\n<texture name=\"alpha\" type=\"checkerboard\"/></bsdf></shape>",
    );
    assert_eq!((e.line, e.col), (6, 1), "{e}");
    assert!(e.message.contains("textured alpha"), "{e}");
    let e = error(
        "negative",
        "<shape type=\"sphere\"><bsdf type=\"roughconductor\">\n<float name=\"alpha_u\" value=\"-0.1\"/><float name=\"alpha_v\" value=\"0.1\"/></bsdf></shape>",
    );
    assert_eq!((e.line, e.col), (6, 1), "{e}");
    assert!(e.message.contains("alpha_u -0.1: pathwave takes 0 to 1"), "{e}");
    let e = error(
        "aniso",
        "<shape type=\"sphere\"><bsdf type=\"roughdielectric\"><float name=\"alpha_u\" value=\"0.1\"/>\n<float name=\"alpha_v\" value=\"0.3\"/></bsdf></shape>",
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

/// `plastic` and `roughplastic` become `Plastic` and `RoughPlastic` with Mitsuba's defaults
/// (polypropylene in air, diffuse 0.5, Beckmann alpha 0.1), named indices, textures and
/// `twosided`; indices that Mitsuba or pathwave refuse are refused where written.
#[test]
fn plastics_become_plastic_kinds() {
    let r = ron(
        "plastic",
        r#"<texture type="checkerboard" id="check"/>
        <shape type="sphere"><bsdf type="plastic"/></shape>
        <shape type="cube"><bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.1, 0.27, 0.36"/>
            <float name="int_ior" value="1.9"/><boolean name="nonlinear" value="true"/></bsdf></shape>
        <shape type="rectangle"><bsdf type="roughplastic"><string name="distribution" value="ggx"/>
            <float name="alpha" value="0.4"/><string name="int_ior" value="bk7"/><string name="ext_ior" value="air"/>
            <ref name="diffuse_reflectance" id="check"/><rgb name="specular_reflectance" value="0.5"/></bsdf></shape>
        <shape type="disk"><bsdf type="twosided"><bsdf type="roughplastic"/></bsdf></shape>"#,
    );
    for want in [
        "Plastic(albedo: (0.5, 0.5, 0.5), tint: (1, 1, 1), ior: 1.4895874, nonlinear: false)",
        "Plastic(albedo: (0.1, 0.27, 0.36), tint: (1, 1, 1), ior: 1.8994738, nonlinear: true)",
        r#"RoughPlastic(albedo: "check", alpha: 0.4, distribution: Ggx, tint: (0.5, 0.5, 0.5), ior: 1.5041833, nonlinear: false)"#,
        "RoughPlastic(albedo: (0.5, 0.5, 0.5), alpha: 0.1, distribution: Beckmann, tint: (1, 1, 1), ior: 1.4895874, nonlinear: false, two_sided: true)",
    ] {
        assert!(r.contains(want), "missing {want} in\n{r}");
    }
    for (tag, body, at, message) in [
        (
            "same",
            "<bsdf type=\"roughplastic\">\n<float name=\"int_ior\" value=\"1.2\"/><float name=\"ext_ior\" value=\"1.2\"/></bsdf>",
            (5, 22),
            "wants them to differ",
        ),
        (
            "zero",
            "<bsdf type=\"plastic\">\n<float name=\"int_ior\" value=\"0\"/></bsdf>",
            (6, 1),
            "positive number",
        ),
        (
            "far",
            "<bsdf type=\"plastic\">\n<float name=\"int_ior\" value=\"20\"/></bsdf>",
            (6, 1),
            "from 0.1 to 10",
        ),
        (
            "name",
            "<bsdf type=\"plastic\">\n<string name=\"int_ior\" value=\"jelly\"/></bsdf>",
            (6, 1),
            "named media",
        ),
        (
            "phong",
            "<bsdf type=\"roughplastic\">\n<string name=\"distribution\" value=\"phong\"/></bsdf>",
            (6, 1),
            "\"ggx\"",
        ),
        (
            "banner",
            "<bsdf type=\"plastic\">\n<float name=\"banner\" value=\"1\"/></bsdf>",
            (6, 1),
            "`banner`",
        ),
    ] {
        let e = error(tag, &format!("<shape type=\"sphere\">{body}</shape>"));
        assert!(e.message.contains(message), "{tag}: {e}");
        assert_eq!((e.line, e.col), at, "{tag}: {e}");
    }
}

#[test]
fn media_fill_the_interiors_of_their_shapes() {
    let r = ron(
        "media",
        r#"<medium type="homogeneous" id="fog"><rgb name="sigma_t" value="1, 2, 3"/><rgb name="albedo" value="0.5"/><float name="scale" value="2"/><phase type="isotropic"/></medium>
        <shape type="sphere"><bsdf type="null"/><ref id="fog" name="interior"/></shape>
        <shape type="cube"><bsdf type="dielectric"/><medium type="homogeneous" name="interior"><float name="sigma_t" value="0.5"/></medium></shape>
        <shape type="sphere"><float name="radius" value="3"/><bsdf type="thindielectric"><string name="int_ior" value="water"/></bsdf></shape>
        <shape type="sphere"><float name="radius" value="5"/><bsdf type="null"/></shape>
        <shape type="sphere"><float name="radius" value="7"/><bsdf type="null"/><medium type="homogeneous" name="interior"><phase type="hg"/></medium></shape>
        <shape type="sphere"><float name="radius" value="8"/><bsdf type="null"/><medium type="homogeneous" name="interior"><phase type="hg"><float name="g" value="-0.25"/></phase></medium></shape>"#,
    );
    for want in [
        "(shape: Sphere(center: (0, 0, 0), radius: 1, poles: Z), medium: (density: (2, 4, 6), albedo: (0.5, 0.5, 0.5)))",
        // Mitsuba's defaults: albedo 0.75; the cube's surface beside its volume.
        "(shape: Box(a: (-1, -1, -1), b: (1, 1, 1), uv: Mitsuba), medium: (density: 0.5, albedo: (0.75, 0.75, 0.75)))",
        "(shape: Box(a: (-1, -1, -1), b: (1, 1, 1), uv: Mitsuba), material: \"dielectric-",
        "ThinDielectric(ior: 1.33263",
        // Mitsuba's hg: g by default 0.8.
        "radius: 7, poles: Z), medium: (density: 1, albedo: (0.75, 0.75, 0.75), phase: HenyeyGreenstein(g: 0.8)))",
        "phase: HenyeyGreenstein(g: -0.25)))",
    ] {
        assert!(r.contains(want), "missing {want} in\n{r}");
    }
    // A null BSDF without a medium is nothing at all.
    assert!(!r.contains("radius: 5"), "{r}");
    // The converted scene loads: the volumes' shapes are closed.
    let p = scene(
        "media-load",
        r#"<shape type="sphere"><bsdf type="null"/><medium type="homogeneous" name="interior"/></shape>"#,
    );
    super::load(&p, &[]).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn media_pathwave_cannot_render_are_refused_where_they_are_written() {
    let e = error("unknown-medium", "\n<medium type=\"fluid\" id=\"m\"/>");
    assert_eq!((e.line, e.col), (6, 1), "{e}");
    assert!(e.message.contains("heterogeneous") && e.message.contains("homogeneous"), "{e}");
    // A heterogeneous medium of constant sigma_t lives in Mitsuba's unit cube only.
    let e = error("hetero-constant", "\n<medium type=\"heterogeneous\" id=\"m\"/>");
    assert_eq!((e.line, e.col), (6, 1), "{e}");
    assert!(e.message.contains("gridvolume") && e.message.contains("homogeneous medium"), "{e}");
    let e = error(
        "hg",
        "<medium type=\"homogeneous\" id=\"m\"><phase type=\"hg\"><float name=\"g\" value=\"1\"/></phase></medium>",
    );
    assert!(e.message.contains("\"hg\"") && e.message.contains("(-1, 1)"), "{e}");
    let e = error("rayleigh", "<medium type=\"homogeneous\" id=\"m\"><phase type=\"rayleigh\"/></medium>");
    assert!(e.message.contains("\"rayleigh\"") && e.message.contains("isotropic and hg"), "{e}");
    let e = error(
        "exterior",
        "<medium type=\"homogeneous\" id=\"m\"/><shape type=\"sphere\"><ref id=\"m\" name=\"exterior\"/></shape>",
    );
    assert!(e.message.contains("exterior") && e.message.contains("interior"), "{e}");
    let e =
        error("null-emitter", "<shape type=\"sphere\"><bsdf type=\"null\"/><emitter type=\"area\"/></shape>");
    assert!(e.message.contains("null"), "{e}");
    let e = error(
        "not-a-medium",
        "<bsdf type=\"diffuse\" id=\"b\"/><shape type=\"sphere\"><ref id=\"b\" name=\"interior\"/></shape>",
    );
    assert!(e.message.contains("not a <medium>"), "{e}");
    let e = error(
        "negative",
        "<shape type=\"sphere\"><medium type=\"homogeneous\" name=\"interior\"><float name=\"sigma_t\" value=\"-1\"/></medium></shape>",
    );
    assert!(e.message.contains(">= 0"), "{e}");
    // An open shape cannot hold a medium: the RON loader's refusal, at the XML shape.
    let p = scene(
        "open",
        "\n<shape type=\"rectangle\"><bsdf type=\"null\"/><medium type=\"homogeneous\" name=\"interior\"/></shape>",
    );
    let Err(e) = super::load(&p, &[]) else { panic!("an open boundary is refused") };
    assert_eq!(e.line, 6, "{e}");
    assert!(e.message.contains("closed"), "{e}");
}

/// `mask` and `blendbsdf` become `Mask` and `Blend` around the materials their BSDFs become
/// (named before them), a float or a texture for the opacity (Mitsuba's default 0.5) and the
/// weight; inside `twosided` their BSDFs are two-sided. Opacities outside [0, 1], a missing
/// weight and a wrong number of BSDFs are refused where written.
#[test]
fn masks_and_blends_become_wrappers() {
    let r = ron(
        "wrappers",
        r#"<texture type="checkerboard" id="check"/>
        <shape type="sphere"><bsdf type="mask"><ref name="opacity" id="check"/><bsdf type="diffuse"/></bsdf></shape>
        <shape type="cube"><bsdf type="blendbsdf"><float name="weight" value="0.25"/>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.2"/></bsdf><bsdf type="roughconductor"/></bsdf></shape>
        <shape type="disk"><bsdf type="twosided"><bsdf type="mask"><bsdf type="blendbsdf"><float name="weight" value="1"/>
            <bsdf type="diffuse"/><bsdf type="plastic"/></bsdf></bsdf></bsdf></shape>"#,
    );
    let line =
        |name: &str| r.lines().find(|l| l.trim_start().starts_with(&format!("{name:?}"))).unwrap_or("");
    assert!(line("mask-1").contains(r#"Mask(opacity: "check", material: "diffuse-0")"#), "{r}");
    assert!(
        line("blendbsdf-4").contains(r#"Blend(weight: 0.25, materials: ("diffuse-2", "roughconductor-3"))"#),
        "{r}"
    );
    assert!(line("diffuse-5").contains("Lambertian(albedo: (0.5, 0.5, 0.5))"), "{r}");
    assert!(line("plastic-6").contains("two_sided: true"), "{r}");
    assert!(
        line("blendbsdf-7").contains(r#"Blend(weight: 1, materials: ("diffuse-5", "plastic-6"))"#),
        "{r}"
    );
    assert!(line("twosided-8").contains(r#"Mask(opacity: 0.5, material: "blendbsdf-7")"#), "{r}");
    for (tag, body, at, message) in [
        (
            "opacity",
            "<bsdf type=\"mask\">\n<float name=\"opacity\" value=\"1.5\"/><bsdf type=\"diffuse\"/></bsdf>",
            (6, 1),
            "`opacity` is a number in [0, 1] or a texture",
        ),
        (
            "weight",
            "<bsdf type=\"blendbsdf\"><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf>",
            (5, 22),
            "`weight` is required",
        ),
        (
            "count",
            "<bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"0.5\"/><bsdf type=\"diffuse\"/></bsdf>",
            (5, 22),
            "holds 2 BSDF(s), not 1",
        ),
    ] {
        let e = error(tag, &format!("<shape type=\"sphere\">{body}</shape>"));
        assert!((e.line, e.col) == at && e.message.contains(message), "{tag}: {e}");
    }
}

/// Writes `name` in the folder of the scene `tag`: a `.vol` grid of `size` and `channels`.
fn grid_file(tag: &str, name: &str, size: [i32; 3], channels: i32, bbox: [f32; 6]) {
    let d = std::env::temp_dir().join(format!("pathwave-mitsuba-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let mut b = b"VOL\x03".to_vec();
    for n in [1, size[0], size[1], size[2], channels] {
        b.extend(n.to_le_bytes());
    }
    let n = (size[0] * size[1] * size[2] * channels) as usize;
    for x in bbox.iter().chain(&vec![0.25f32; n]) {
        b.extend(x.to_le_bytes());
    }
    std::fs::write(d.join(name), b).unwrap();
}

/// A heterogeneous medium's grids are placed in the object's space: the shape's `to_world`
/// undone after the grid's, and the file's box with `use_grid_bbox`; the scene loads.
#[test]
fn grid_media_are_placed_in_their_objects() {
    let tag = "grid-media";
    grid_file(tag, "d.vol", [2, 3, 4], 1, [0.0; 6]);
    grid_file(tag, "a.vol", [1, 1, 1], 3, [-1.0, -1.0, -1.0, 1.0, 3.0, 1.0]);
    let body = r#"<shape type="cube"><bsdf type="null"/><transform name="to_world"><scale value="2"/><translate x="1"/></transform>
        <medium type="heterogeneous" name="interior"><float name="scale" value="5"/>
          <volume name="sigma_t" type="gridvolume"><string name="filename" value="d.vol"/><transform name="to_world"><translate x="3"/></transform></volume>
          <volume name="albedo" type="gridvolume"><string name="filename" value="a.vol"/><boolean name="use_grid_bbox" value="true"/></volume>
        </medium></shape>"#;
    let r = ron(tag, body);
    // The density grid: world = translate(3) p, object = (world - (1, 0, 0)) / 2.
    let want = r#"medium: (density: 5, albedo: (1, 1, 1), grid: (file: "d.vol", transform: [Matrix([[0.5, 0, 0, 1], [0, 0.5, 0, 0], [0, 0, 0.5, 0], [0, 0, 0, 1]])]), albedo_grid: (file: "a.vol", transform: [Matrix([[1, 0, 0, -1], [0, 2, 0, -0.5], [0, 0, 1, -0.5], [0, 0, 0, 1]])]))"#;
    assert!(r.contains(want), "missing {want} in\n{r}");
    super::load(&scene(tag, body), &[]).unwrap_or_else(|e| panic!("{e}"));
}

/// A `gridvolume` naming an OpenVDB file (a pathwave extension: Mitsuba reads `.vol` only)
/// becomes a RON grid of that file, placed by `to_world` after the file's own transform, and
/// the scene loads with the file's grid; `use_grid_bbox` (a `.vol` header's box) is refused
/// for it. Checked to fail with the file's first bytes read as a `.vol` header.
#[test]
fn an_openvdb_gridvolume_is_read_and_placed() {
    let tag = "grid-vdb";
    let d = scene(tag, "").parent().unwrap().to_path_buf();
    let vdb = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/assets/smoke-zip.vdb");
    std::fs::copy(vdb, d.join("smoke.data")).unwrap();
    let body = |extra: &str| {
        format!(
            r#"<shape type="cube"><bsdf type="null"/>
        <medium type="heterogeneous" name="interior">
          <volume name="sigma_t" type="gridvolume"><string name="filename" value="smoke.data"/><transform name="to_world"><translate x="3"/></transform>{extra}</volume>
        </medium></shape>"#
        )
    };
    let r = ron(tag, &body(""));
    let want = r#"grid: (file: "smoke.data", transform: [Matrix([[1, 0, 0, 3], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])])"#;
    assert!(r.contains(want), "missing {want} in\n{r}");
    super::load(&scene(tag, &body("")), &[]).unwrap_or_else(|e| panic!("{e}"));
    let e = error(tag, &body(r#"<boolean name="use_grid_bbox" value="true"/>"#));
    assert!(e.message.contains("use_grid_bbox") && e.message.contains("OpenVDB"), "{e}");
}

#[test]
fn grid_media_pathwave_cannot_render_are_refused() {
    let tag = "grid-refused";
    grid_file(tag, "rgb.vol", [2, 2, 2], 3, [0.0; 6]);
    grid_file(tag, "one.vol", [2, 2, 2], 1, [0.0; 6]);
    let medium = |inner: &str| {
        format!(
            "<shape type=\"sphere\"><bsdf type=\"null\"/><medium type=\"heterogeneous\" name=\"interior\">\n{inner}</medium></shape>"
        )
    };
    let e = error(
        tag,
        &medium(
            r#"<volume name="sigma_t" type="gridvolume"><string name="filename" value="rgb.vol"/></volume>"#,
        ),
    );
    assert!(e.message.contains("3 channels") && e.message.contains("one density"), "{e}");
    let e = error(
        tag,
        &medium(
            r#"<volume name="sigma_t" type="gridvolume"><string name="filename" value="one.vol"/><string name="wrap_mode" value="repeat"/></volume>"#,
        ),
    );
    assert!(e.message.contains("wrap_mode \"repeat\"") && e.message.contains("clamp"), "{e}");
    let e = error(
        tag,
        &medium(
            r#"<volume name="sigma_t" type="gridvolume"><string name="filename" value="none.vol"/></volume>"#,
        ),
    );
    assert!(e.message.contains("none.vol"), "{e}");
    let e = error(
        tag,
        &medium(r#"<volume name="sigma_t" type="constvolume"><float name="value" value="1"/></volume>"#),
    );
    assert!(e.message.contains("gridvolume"), "{e}");
}

/// Named conductors take Mitsuba's RGB indices ([`super::conductors`]); unknown names, names
/// beside `eta`, and the names whose RGB eta has a zero channel are refused where written. The
/// table agrees with what [`super::spectrum`] makes of Mitsuba's spectral files (gold and
/// amorphous carbon, copied into tests/mitsuba-data/ior).
#[test]
fn named_conductors_take_mitsubas_rgb_indices() {
    use super::conductors::CONDUCTORS;
    use super::spectrum::{Spectrum, Use};
    let r = ron(
        "named",
        r#"<shape type="sphere"><bsdf type="conductor"><string name="material" value="Au"/></bsdf></shape>
        <shape type="cube"><bsdf type="roughconductor"><string name="material" value="a-C"/></bsdf></shape>"#,
    );
    for want in [
        "RoughConductor(tint: (1, 1, 1), alpha: 0, eta: (0.14303597807884216, 0.3753070831298828, 1.4420453310012817), k: (3.982996940612793, 2.38555645942688, 1.6033592224121094))",
        "alpha: 0.1, distribution: Beckmann, eta: (2.9440457820892334, 2.2271363735198975, 1.968161702156067), k: (0.8874648809432983, ",
    ] {
        assert!(r.contains(want), "missing {want} in\n{r}");
    }
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/mitsuba-data/ior");
    let at = super::xml::At { file: std::sync::Arc::new("t.spd".into()), line: 1, col: 1 };
    for (name, eta, k) in CONDUCTORS.iter().filter(|(n, ..)| ["Au", "a-C"].contains(n)) {
        for (part, want) in [("eta", eta), ("k", k)] {
            let text = std::fs::read_to_string(data.join(format!("{name}.{part}.spd"))).unwrap();
            // Not weighted by D65 (as emission is): `complex_ior_from_file` calls
            // `spectrum_list_to_srgb` with its default, unlike a `<spectrum>` written in a scene.
            // With D65 amorphous carbon's red eta is 2.45, not Mitsuba's 2.94.
            let rgb = Spectrum::parse_file(&text, &at).unwrap().to_rgb(Use::Emission);
            let want = glam::DVec3::from(want.map(f64::from));
            assert!(
                (rgb - want).abs().max_element() < 1e-4 * want.max_element(),
                "{name} {part}: {rgb} vs {want}"
            );
        }
    }
    let bsdf =
        |inner: &str| format!("<shape type=\"sphere\"><bsdf type=\"conductor\">\n{inner}</bsdf></shape>");
    let e = error("unknown", &bsdf(r#"<string name="material" value="Gold"/>"#));
    assert_eq!((e.line, e.col), (6, 1), "{e}");
    assert!(
        e.message.contains("\"Gold\"") && e.message.contains("Au, Be") && e.message.contains("W, or none"),
        "{e}"
    );
    let e = error("both", &bsdf(r#"<string name="material" value="Au"/><float name="eta" value="2"/>"#));
    assert!(e.message.contains("either eta and k or a material"), "{e}");
    let e = error("zero", &bsdf(r#"<string name="material" value="AlSb"/>"#));
    assert!(e.message.contains("eta > 0"), "{e}");
}

/// `principled` becomes `Principled` with its weights as numbers or textures (checkerboards read
/// as numbers), `specular` or `eta`, and the sampling rates; out-of-range weights and both
/// `eta` and `specular` are refused where written.
#[test]
fn principled_becomes_principled() {
    let r = ron(
        "principled",
        r#"<shape type="sphere"><bsdf type="principled"><rgb name="base_color" value="0.2, 0.8, 0.1"/>
            <float name="roughness" value="0.15"/><texture name="metallic" type="checkerboard"/>
            <float name="specular" value="0.7"/><float name="clearcoat_sampling_rate" value="0.5"/></bsdf></shape>"#,
    );
    let want = r#"Principled(base_color: (0.2, 0.8, 0.1), roughness: 0.15, metallic: "checkerboard-0", specular: 0.7, sampling_rates: (1, 0.5, 1))"#;
    assert!(r.contains(want), "missing {want} in\n{r}");
    for (tag, body, message) in [
        ("sheen", r#"<float name="sheen" value="1.5"/>"#, "sheen 1.5: expected 0 to 1"),
        (
            "both",
            r#"<float name="eta" value="1.5"/><float name="specular" value="0.5"/>"#,
            "either eta or specular",
        ),
        ("eta", r#"<float name="eta" value="0"/>"#, "eta 0: expected > 0"),
    ] {
        let e =
            error(tag, &format!("<shape type=\"sphere\"><bsdf type=\"principled\">\n{body}</bsdf></shape>"));
        assert_eq!(e.line, 6, "{e}");
        assert!(e.message.contains(message), "{tag}: {e}");
    }
}

/// `principledthin` becomes `PrincipledThin`, `diff_trans` up to 2.
#[test]
fn principledthin_becomes_principled_thin() {
    let r = ron(
        "thin",
        r#"<shape type="rectangle"><bsdf type="principledthin"><float name="eta" value="1.33"/>
            <texture name="diff_trans" type="checkerboard"><float name="color1" value="1.4"/></texture>
            <float name="spec_trans" value="0.5"/></bsdf></shape>"#,
    );
    let want = r#"PrincipledThin(base_color: (0.5, 0.5, 0.5), spec_trans: 0.5, diff_trans: "checkerboard-0", eta: 1.33)"#;
    assert!(r.contains(want), "missing {want} in\n{r}");
    let e = error(
        "thin-bad",
        "<shape type=\"rectangle\"><bsdf type=\"principledthin\">\n<float name=\"diff_trans\" value=\"2.5\"/></bsdf></shape>",
    );
    assert_eq!(e.line, 6, "{e}");
    assert!(e.message.contains("diff_trans 2.5: expected 0 to 2"), "{e}");
}

/// `bumpmap` and `normalmap` become `Bump` and `NormalMap` around the material their BSDF
/// becomes: the bump map's one texture under whatever name, its scale (default 1), the
/// normal map's `normalmap` (here a `rawconstant`), and `flip_invalid_normals`. A bump map
/// with two textures and `use_shadowing_function` off are refused where written.
#[test]
fn bump_and_normal_maps_become_maps() {
    let dir = scene("maps", "").parent().unwrap().to_owned();
    let png = texels_png(&dir);
    let png = png.file_name().unwrap().to_str().unwrap();
    let r = ron(
        "maps",
        &format!(
            r#"<shape type="sphere"><bsdf type="bumpmap"><float name="scale" value="0.02"/>
                <texture name="tiles" type="bitmap"><string name="filename" value="{png}"/><boolean name="raw" value="true"/></texture>
                <bsdf type="diffuse"/></bsdf></shape>
            <shape type="cube"><bsdf type="normalmap"><boolean name="flip_invalid_normals" value="false"/>
                <texture name="normalmap" type="rawconstant"><vector name="value" value="0.5, 0.5, 1"/></texture>
                <bsdf type="roughconductor"/></bsdf></shape>"#
        ),
    );
    let line =
        |name: &str| r.lines().find(|l| l.trim_start().starts_with(&format!("{name:?}"))).unwrap_or("");
    assert!(line("bitmap-0").contains("raw: true"), "{r}");
    assert!(
        line("bumpmap-1").contains(
            r#"Bump(texture: "bitmap-0", scale: 0.02, material: "diffuse-0", flip_invalid_normals: true)"#
        ),
        "{r}"
    );
    assert!(line("rawconstant-1").contains("Solid((0.5, 0.5, 1))"), "{r}");
    assert!(
        line("normalmap-3").contains(
            r#"NormalMap(texture: "rawconstant-1", material: "roughconductor-2", flip_invalid_normals: false)"#
        ),
        "{r}"
    );
    let t = r#"<texture name="a" type="rawconstant"><float name="value" value="0.5"/></texture>"#;
    for (tag, body, at, message) in [
        (
            "two",
            format!(
                "<bsdf type=\"bumpmap\">{t}\n{}<bsdf type=\"diffuse\"/></bsdf>",
                t.replace("\"a\"", "\"b\"")
            ),
            (5, 22),
            "takes one texture, not 2",
        ),
        (
            "shadowing",
            format!(
                "<bsdf type=\"normalmap\">\n<boolean name=\"use_shadowing_function\" value=\"false\"/>{}<bsdf type=\"diffuse\"/></bsdf>",
                t.replace("\"a\"", "\"normalmap\"")
            ),
            (6, 1),
            "use_shadowing_function false: pathwave's maps always shadow the terminator",
        ),
    ] {
        let e = error(tag, &format!("<shape type=\"sphere\">{body}</shape>"));
        assert!((e.line, e.col) == at && e.message.contains(message), "{tag}: {e}");
    }
}
