//! Scene loader errors: every bad scene is rejected with the line and column of the offending
//! token and a message that says what was expected; the CLI reports them as `file:line:col:`.

use pathwave::engine::scene::{SceneError, load, parse};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The camera, the second material and the object of the template, each alone on its line.
const CAMERA: &str = "look_from: (0, 0, -5), look_at: (0, 0, 0), vfov: 40";
const MATERIAL: &str = r#""light": DiffuseLight(emit: (4, 4, 4)),"#;
const OBJECT: &str = r#"(shape: Sphere(center: (0, 0, 0), radius: 1), material: "white"),"#;
/// `OBJECT` with `radius` misspelled.
const MISSPELLED: &str = r#"(shape: Sphere(center: (0, 0, 0), radious: 1), material: "white"),"#;

/// A minimal valid scene. The camera fields start at line 2, column 14; the second material
/// and the object start at column 9 of lines 5 and 8.
fn scene(camera: &str, material: &str, object: &str) -> String {
    format!(
        r#"Scene(
    camera: ({camera}),
    materials: {{
        "white": Lambertian(albedo: (0.7, 0.7, 0.7)),
        {material}
    }},
    objects: [
        {object}
    ],
)
"#
    )
}

fn with_camera(camera: &str) -> String {
    scene(camera, MATERIAL, OBJECT)
}

fn with_material(material: &str) -> String {
    scene(CAMERA, material, OBJECT)
}

fn with_object(object: &str) -> String {
    scene(CAMERA, MATERIAL, object)
}

/// The error `text` must give.
fn err(text: &str) -> SceneError {
    parse(text, Path::new("test.ron")).expect_err("the scene should be rejected")
}

/// Asserts that `text` fails at `line:col` with a message containing every one of `words`.
#[track_caller]
fn assert_err(text: &str, line: usize, col: usize, words: &[&str]) {
    let e = err(text);
    let src = text.lines().nth(e.line.wrapping_sub(1)).unwrap_or("");
    let caret = format!("{}^", " ".repeat(e.col.saturating_sub(1)));
    assert!(
        (e.line, e.col) == (line, col) && words.iter().all(|w| e.message.contains(w)),
        "expected {line}:{col} and a message with {words:?}, got\n{e}\n{src}\n{caret}"
    );
}

#[test]
fn template_is_valid() {
    parse(&scene(CAMERA, MATERIAL, OBJECT), Path::new("test.ron")).unwrap();
}

// 1. Misspelled field.

#[test]
fn misspelled_field_lists_valid_fields() {
    // 8:43 is the `r` of `radious`.
    assert_err(&with_object(MISSPELLED), 8, 43, &["`radious`", "`Sphere`", "`center`", "`radius`"]);
}

// 2. Wrong type.

#[test]
fn string_where_number_expected() {
    let text = with_object(r#"(shape: Sphere(center: (0, 0, 0), radius: "big"), material: "white"),"#);
    // ron points at the blank before `"big"` (8:51), one column early.
    assert_err(&text, 8, 50, &["Expected float"]);
}

// 3. Unknown material.

#[test]
fn unknown_material_names_it_and_lists_defined_ones() {
    let text = with_object(r#"(shape: Sphere(center: (0, 0, 0), radius: 1), material: "whyte"),"#);
    // 8:66 is the `w` of `"whyte"`, just inside the opening quote.
    assert_err(&text, 8, 66, &[r#"unknown material "whyte""#, r#""white""#, r#""light""#]);
}

// 4. Material defined twice.

#[test]
fn material_defined_twice() {
    let text = with_material(r#""white": Metal(albedo: (1, 1, 1)),"#);
    // 5:10 is the `w` of the second `"white"` key.
    assert_err(&text, 5, 10, &[r#"material "white" is defined twice"#]);
}

// 5. Bad values.

#[test]
fn negative_radius() {
    let text = with_object(r#"(shape: Sphere(center: (0, 0, 0), radius: -1), material: "white"),"#);
    assert_err(&text, 8, 51, &["> 0", "found -1"]);
}

#[test]
fn zero_radius() {
    let text = with_object(r#"(shape: Sphere(center: (0, 0, 0), radius: 0), material: "white"),"#);
    assert_err(&text, 8, 51, &["> 0", "found 0"]);
}

#[test]
fn nan_in_vector() {
    let text = with_object(r#"(shape: Sphere(center: (0, NaN, 0), radius: 1), material: "white"),"#);
    // Vectors are checked whole: 8:42 is the `)` that closes `(0, NaN, 0)`.
    assert_err(&text, 8, 42, &["three finite numbers", "(0, NaN, 0)"]);
}

#[test]
fn inf_in_vector() {
    let text = with_camera("look_from: (0, 0, inf), look_at: (0, 0, 0), vfov: 40");
    // 2:35 is the `)` that closes `(0, 0, inf)`.
    assert_err(&text, 2, 35, &["three finite numbers", "(0, 0, inf)"]);
}

#[test]
fn vfov_zero() {
    let text = with_camera("look_from: (0, 0, -5), look_at: (0, 0, 0), vfov: 0");
    assert_err(&text, 2, 63, &["field of view in (0, 180)", "found 0"]);
}

#[test]
fn vfov_180() {
    let text = with_camera("look_from: (0, 0, -5), look_at: (0, 0, 0), vfov: 180");
    assert_err(&text, 2, 63, &["field of view in (0, 180)", "found 180"]);
}

#[test]
fn albedo_above_one() {
    let text = with_material(r#""dull": Lambertian(albedo: (0.5, 1.5, 0.5)),"#);
    // 5:50 is the `)` that closes `(0.5, 1.5, 0.5)`.
    assert_err(&text, 5, 50, &["albedo with components in [0, 1]", "[0.5, 1.5, 0.5]"]);
}

/// Emitted colours above what the film records (it discards samples above 1e12): a light of
/// 1e20 rendered its room black, a 3e38 point light added nothing, and both exited 0.
#[test]
fn emission_beyond_the_films_range() {
    let light = r#""light": DiffuseLight(emit: (1e20, 1, 1)),"#;
    let col = 8 + light.find("))").unwrap() + 1;
    assert_err(&with_material(light), 5, col, &["emitted colour with components in [0, 1e10]"]);
    for lights in [
        "Point(position: (0, 5, 0), intensity: (3e38, 3e38, 3e38))",
        "Directional(direction: (0, -1, 0), irradiance: (1, 2e10, 1))",
    ] {
        let text = with_camera(CAMERA)
            .replace("    objects: [", &format!("    lights: [{lights}],\n    objects: ["));
        let e = err(&text);
        assert!(e.line == 7 && e.message.contains("components in [0, 1e10]"), "{lights}: {e}");
    }
    // At the bound, a light is read.
    let text = with_material(r#""light": DiffuseLight(emit: (1e10, 1e10, 1e10)),"#);
    parse(&text, Path::new("test.ron")).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn zero_area_quad() {
    let text = with_object(r#"(shape: Quad(q: (0, 0, 0), u: (1, 0, 0), v: (2, 0, 0)), material: "white"),"#);
    // Shapes are checked whole: 8:62 is the `)` that closes `Quad(..)`.
    assert_err(&text, 8, 62, &["Quad has no area", "parallel"]);
}

#[test]
fn errors_in_objects_name_the_object() {
    let degenerate = r#"(shape: Quad(q: (0, 0, 0), u: (1, 0, 0), v: (0, 0, 0)), material: "white"),"#;
    let text = with_object(&format!("{OBJECT}\n        {OBJECT}\n        {degenerate}"));
    // The third object, on line 10; 10:62 is the `)` that closes `Quad(..)`.
    assert_err(&text, 10, 62, &["in objects[2]: Quad has no area"]);
    // The index does not leak into the next scene's errors.
    let e = err(&with_camera("look_from: (0, 0, -5), look_at: (0, 0, 0), vfov: 180"));
    assert!(!e.message.contains("objects["), "{e}");
}

#[test]
fn object_beyond_max_coordinate() {
    // Found by the fuzzer: the BVH builder's area arithmetic overflowed.
    let text =
        with_object(r#"(shape: Quad(q: (0, 0, 0), u: (0, 1, 0), v: (0, 1e38, 1)), material: "white"),"#);
    // Objects are checked whole, with their transform: 8:85 is the `)` that closes the object.
    assert_err(&text, 8, 85, &["in objects[0]", "reaches beyond 1e15 units"]);
    let scaled = r#"(shape: Sphere(center: (0, 0, 0), radius: 1), material: "white", transform: [UniformScale(1e16)]),"#;
    assert_err(&with_object(scaled), 8, 105, &["reaches beyond 1e15 units"]);
}

#[test]
fn camera_beyond_max_coordinate() {
    let text = with_camera("look_from: (0, 0, -2e15), look_at: (0, 0, 0), vfov: 40");
    assert_err(&text, 2, 68, &["camera", "within 1e15 units"]);
}

#[test]
fn object_with_neither_or_both_material_and_medium() {
    let neither = r#"(shape: Sphere(center: (0, 0, 0), radius: 1)),"#;
    assert_err(&with_object(neither), 8, 53, &["needs a `material`", "or a `medium`"]);
    let both = r#"(shape: Sphere(center: (0, 0, 0), radius: 1), material: "white", medium: (density: 1, albedo: (1, 1, 1))),"#;
    assert_err(&with_object(both), 8, 113, &["not both"]);
}

/// An object's `emit` goes with a material that reflects: not an emitter, not a medium; its
/// radiance is a colour with no negative component or a defined texture.
#[test]
fn emit_is_for_surfaces_whose_material_reflects() {
    let end = |object: &str| 9 + object.rfind(')').unwrap();
    let on_light =
        r#"(shape: Sphere(center: (0, 0, 0), radius: 1), material: "light", emit: (radiance: (1, 1, 1))),"#;
    assert_err(
        &with_object(on_light),
        8,
        end(on_light),
        &["\"light\" is a DiffuseLight", "whose material reflects"],
    );
    let on_medium = r#"(shape: Sphere(center: (0, 0, 0), radius: 1), medium: (density: 1, albedo: (1, 1, 1)), emit: (radiance: (1, 1, 1))),"#;
    assert_err(&with_object(on_medium), 8, end(on_medium), &["a medium glows by its own `emission`"]);
    let negative =
        r#"(shape: Sphere(center: (0, 0, 0), radius: 1), material: "white", emit: (radiance: (1, -1, 1))),"#;
    assert_err(
        &with_object(negative),
        8,
        9 + negative.find("(1, -1").unwrap() + 9,
        &["components in [0, 1e10]"],
    );
    let unknown =
        r#"(shape: Sphere(center: (0, 0, 0), radius: 1), material: "white", emit: (radiance: "sky")),"#;
    let e = err(&with_object(unknown));
    assert!(e.line == 8 && e.message.contains("\"sky\""), "{e}");
}

#[test]
fn medium_needs_a_closed_shape_and_valid_numbers() {
    let quad = r#"(shape: Quad(q: (0, 0, 0), u: (1, 0, 0), v: (0, 1, 0)), medium: (density: 1, albedo: (1, 1, 1))),"#;
    assert_err(&with_object(quad), 8, 104, &["closed shape", "Sphere, Box or a closed Mesh"]);
    let zero = r#"(shape: Sphere(center: (0, 0, 0), radius: 1), medium: (density: 0, albedo: (1, 1, 1))),"#;
    assert_err(&with_object(zero), 8, 73, &["density > 0", "found 0"]);
    // Per channel: each >= 0 and one > 0.
    for bad in ["(1, -1, 1)", "(0, 0, 0)"] {
        let coloured = zero.replace("density: 0", &format!("density: {bad}"));
        let e = err(&with_object(&coloured));
        assert!(e.line == 8 && e.message.contains("components >= 0 and one > 0"), "{e}");
    }
    let short = zero.replace("density: 0", "density: (1, 1)");
    assert!(err(&with_object(&short)).message.contains("density"), "(1, 1)");
    let bright = r#"(shape: Sphere(center: (0, 0, 0), radius: 1), medium: (density: 1, albedo: (1, 2, 1))),"#;
    assert_err(&with_object(bright), 8, 92, &["albedo with components in [0, 1]"]);
}

/// A `.vol` grid file of one value per point, `size` points, `channels` channels.
fn vol(size: [i32; 3], channels: i32, data: &[f32]) -> Vec<u8> {
    let mut b = b"VOL\x03".to_vec();
    for n in [1, size[0], size[1], size[2], channels] {
        b.extend(n.to_le_bytes());
    }
    for x in [0.0f32; 6].iter().chain(data) {
        b.extend(x.to_le_bytes());
    }
    b
}

/// Grid media: a grid takes one density, an albedo grid values in [0, 1], an emission grid an
/// `emission` it keeps below the brightest radiance, and a bad file is named; each at the
/// object.
#[test]
fn grid_media_refuse_what_they_cannot_render() {
    let dir = std::env::temp_dir().join(format!("pathwave-grid-errors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("d.vol"), vol([2, 1, 1], 1, &[0.0, 1.0])).unwrap();
    std::fs::write(dir.join("bright.vol"), vol([1, 1, 1], 3, &[0.5, 1.5, 0.5])).unwrap();
    std::fs::write(dir.join("cut.vol"), &vol([2, 2, 2], 1, &[1.0; 8])[..60]).unwrap();
    let load_object = |objects: &str| {
        let path = dir.join("scene.ron");
        std::fs::write(&path, scene(CAMERA, MATERIAL, objects)).unwrap();
        load(&path)
    };
    let grid = r#"(shape: Box(a: (0, 0, 0), b: (1, 1, 1)), medium: (density: 2, albedo: (0.5, 0.5, 0.5), grid: (file: "d.vol"))),"#;
    let ok = load_object(grid).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(ok.objects.len(), 1);
    // Coloured extinction on a grid, beside a coloured homogeneous medium.
    let coloured = format!(
        "{}\n        (shape: Sphere(center: (3, 0, 0), radius: 1), medium: (density: (1, 2, 3), albedo: (1, 1, 1))),",
        grid.replace("density: 2", "density: (1, 2, 0)")
    );
    assert_eq!(load_object(&coloured).unwrap_or_else(|e| panic!("{e}")).objects.len(), 2);
    let glowing = grid.replace(
        "albedo: (0.5, 0.5, 0.5)",
        "albedo: (0.5, 0.5, 0.5), emission: (2, 1, 0.5), emission_grid: (file: \"bright.vol\")",
    );
    assert_eq!(load_object(&glowing).unwrap_or_else(|e| panic!("{e}")).objects.len(), 1);
    for (object, words) in [
        (
            grid.replace("grid: (file: \"d.vol\")", "albedo_grid: (file: \"bright.vol\")"),
            &["bright.vol holds 1.5", "values lie in [0, 1]"][..],
        ),
        (grid.replace("d.vol", "cut.vol"), &["cut.vol", "bytes of values for 2 x 2 x 2 points"][..]),
        (
            grid.replace("density: 2", "density: 1e30"),
            &["largest value is 1000000000000000000000000000000", "at most 10000000"][..],
        ),
        // The bound holds for the densest channel.
        (grid.replace("density: 2", "density: (1, 1e30, 1)"), &["at most 10000000"][..]),
        (
            grid.replace("grid: (file: \"d.vol\")", "emission_grid: (file: \"bright.vol\")"),
            &["an `emission_grid` scales the medium's `emission`"][..],
        ),
        (
            grid.replace(
                "grid: (file: \"d.vol\")",
                "emission: (1, 1e10, 1), emission_grid: (file: \"bright.vol\")",
            ),
            &["bright.vol's largest value is 15000000000", "at most 1e10"][..],
        ),
        (grid.replace("grid: (file", "emission: (1, -1, 1), grid: (file"), &["emitted colour"][..]),
    ] {
        let e = load_object(&object).expect_err(&object);
        assert!(e.line >= 8 && words.iter().all(|w| e.message.contains(w)), "{object}: {e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A scene with a `textures` map before the materials.
fn with_textures(textures: &str, material: &str) -> String {
    scene(CAMERA, material, OBJECT).replacen(
        "    materials: {",
        &format!("    textures: {{ {textures} }},\n    materials: {{"),
        1,
    )
}

#[test]
fn unknown_texture_names_list_the_defined_ones() {
    let text = with_textures(r#""a": Noise(scale: 2)"#, r#""t": Lambertian(albedo: "b"),"#);
    // Line 6 (the textures map is line 3): 6:34 is the end of the name.
    assert_err(&text, 6, 34, &["unknown texture \"b\"", "defined: \"a\""]);
}

#[test]
fn a_texture_may_only_name_textures_before_it() {
    let text = with_textures(
        r#""a": Checker(scale: 1, even: "b", odd: (1, 1, 1)), "b": Noise(scale: 2)"#,
        r#""t": Lambertian(albedo: "a"),"#,
    );
    // 3:47 is the end of `"b"`.
    assert_err(&text, 3, 47, &["texture \"b\" must be defined before the texture that uses it"]);
}

#[test]
fn missing_image_file_is_named() {
    let text = with_textures(r#""a": Image(file: "no-such.png")"#, r#""t": Lambertian(albedo: "a"),"#);
    // 3:35 is the end of the file name (files are relative to the scene's directory).
    assert_err(&text, 3, 35, &["cannot read the image", "no-such.png"]);
}

#[test]
fn collinear_triangle() {
    let text =
        with_object(r#"(shape: Triangle(a: (0, 0, 0), b: (1, 1, 1), c: (2, 2, 2)), material: "white"),"#);
    // 8:66 is the `)` that closes `Triangle(..)`.
    assert_err(&text, 8, 66, &["Triangle has no area", "collinear"]);
}

/// A number where a colour belongs says what was expected, not that a parenthesis is missing.
#[test]
fn a_number_for_a_colour_says_a_colour_was_expected() {
    let text = scene(CAMERA, MATERIAL, OBJECT).replacen(
        "objects: [",
        "lights: [Point(position: (0, 5, 0), intensity: 30)],\n    objects: [",
        1,
    );
    let e = err(&text);
    assert!(
        e.message.contains("Expected an emitted colour (r, g, b) but found the unsigned integer `30`"),
        "{e}"
    );
}

#[test]
fn missing_mesh_file_is_named() {
    let text = with_object(r#"(shape: Mesh(file: "scenes/none.obj"), material: "white"),"#);
    // 8:29 is the file name (relative to the scene's directory), and where it was looked for
    // is said as an absolute path.
    let folder = std::path::absolute("scenes").unwrap();
    let there = format!("cannot read the mesh scenes/none.obj: there is no none.obj in {}", folder.display());
    assert_err(&text, 8, 29, &["in objects[0]", &there]);
    let text = with_object(r#"(shape: Mesh(file: "elsewhere/none.obj"), material: "white"),"#);
    let folder = std::path::absolute("elsewhere").unwrap();
    assert_err(&text, 8, 29, &[&format!("there is no folder {}", folder.display())]);
}

#[test]
fn flat_box() {
    let text = with_object(r#"(shape: Box(a: (0, 0, 0), b: (1, 0, 1)), material: "white"),"#);
    // 8:47 is the `)` that closes `Box(..)`.
    assert_err(&text, 8, 47, &["Box is flat", "share a coordinate"]);
}

#[test]
fn singular_transform() {
    let text = with_object(
        r#"(shape: Sphere(center: (0, 0, 0), radius: 1), material: "white", transform: [Scale((1, 0, 1))]),"#,
    );
    // 8:101 is the `)` that closes `Scale(..)`.
    assert_err(&text, 8, 101, &["transform is singular"]);
}

#[test]
fn zero_vup() {
    let text = with_camera("look_from: (0, 0, -5), look_at: (0, 0, 0), vup: (0, 0, 0), vfov: 40");
    // 2:70 is the `)` that closes the `vup` vector.
    assert_err(&text, 2, 70, &["expected a non-zero direction"]);
}

#[test]
fn look_from_equals_look_at() {
    let text = with_camera("look_from: (1, 2, 3), look_at: (1, 2, 3), vfov: 40");
    // The camera is checked whole: 2:64 is the `)` that closes `camera: (..)`, not either point.
    assert_err(&text, 2, 64, &["look_from and look_at are the same point"]);
}

// 6. Unknown enum variant.

#[test]
fn unknown_material_variant() {
    let text = with_material(r#""velvet": Velvet(albedo: (0.5, 0.5, 0.5)),"#);
    assert_err(
        &text,
        5,
        19,
        &["`Velvet`", "`Lambertian`", "`Metal`", "`Dielectric`", "`Plastic`", "`DiffuseLight`"],
    );
}

#[test]
fn unknown_shape_variant() {
    let text = with_object(r#"(shape: Cone(center: (0, 0, 0), radius: 1), material: "white"),"#);
    assert_err(&text, 8, 17, &["`Cone`", "`Sphere`", "`Quad`", "`Box`", "`Disk`", "`Cylinder`"]);
}

// 7. Missing field and syntax errors.

#[test]
fn missing_camera() {
    let text = r#"Scene(
    materials: {"white": Lambertian(albedo: (0.7, 0.7, 0.7))},
    objects: [],
)
"#;
    // Missing fields are only noticed at the `)` that closes the struct (4:1).
    assert_err(text, 4, 1, &["missing field named `camera`", "`Scene`"]);
}

#[test]
fn missing_closing_paren() {
    // `(0, 0, 0` is not closed; 8:42 is the `radius` where `)` was expected.
    let text = with_object(r#"(shape: Sphere(center: (0, 0, 0, radius: 1), material: "white"),"#);
    assert_err(&text, 8, 42, &["Expected closing `)`"]);
}

#[test]
fn trailing_garbage() {
    // `oops` is at 11:1, but ron reports the end of the scene (10:2, just after its `)`).
    let text = format!("{}oops\n", with_object(OBJECT));
    assert_err(&text, 10, 2, &["trailing characters"]);
}

// 8. Unreadable file.

#[test]
fn load_nonexistent_file() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/no-such-scene.ron");
    let e = load(&path).expect_err("a missing file should be an error");
    assert_eq!((e.line, e.col), (0, 0));
    assert_eq!(e.path, path);
    assert!(e.message.contains("cannot read the scene"), "{e}");
    assert!(e.to_string().starts_with(&format!("{}: cannot read", path.display())), "{e}");
}

// 9. The command line.

#[test]
fn cli_reports_position_without_panicking() {
    let dir = std::env::temp_dir().join(format!("pathwave-scene-errors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene_path = dir.join("bad.ron");
    std::fs::write(&scene_path, with_object(MISSPELLED)).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .arg("render")
        .arg(&scene_path)
        .arg("-o")
        .arg(dir.join("bad.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(!out.status.success(), "exit status {}; stderr:\n{stderr}", out.status);
    assert!(stderr.contains(&format!("{}:8:43:", scene_path.display())), "stderr:\n{stderr}");
    assert!(!stderr.contains("panicked"), "stderr:\n{stderr}");
}

/// Names from a scene reach the terminal inside errors; their control characters (a colour, a
/// screen clear, a carriage return) are written as escapes, not sent to it.
#[test]
fn cli_errors_do_not_pass_control_characters_to_the_terminal() {
    let dir = std::env::temp_dir().join(format!("pathwave-scene-escapes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene_path = dir.join("bad.ron");
    let name = "\u{1b}[2J\u{1b}]0;title\u{7}\rwhite\u{9b}31m";
    std::fs::write(&scene_path, with_object(&OBJECT.replace("\"white\"", &format!("\"{name}\"")))).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .arg("render")
        .arg(&scene_path)
        .arg("-o")
        .arg(dir.join("bad.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(!out.status.success() && stderr.contains("unknown material"), "stderr:\n{stderr}");
    assert!(!stderr.contains(|c: char| c.is_control() && c != '\n'), "stderr: {stderr:?}");
    assert!(stderr.contains("\\u{1b}[2J"), "stderr: {stderr:?}");
}

/// With `--assets-under DIR`, a scene may read only files in DIR (links resolved): not through
/// `../`, an absolute path or a link out of it; `farm slurm` confines a scene to its folder by
/// default. Without the flag the same scene loads.
#[test]
fn assets_under_keeps_a_scene_in_its_folder() {
    let dir = std::env::temp_dir().join(format!("pathwave-assets-under-{}", std::process::id()));
    let inside = dir.join("scene");
    std::fs::create_dir_all(&inside).unwrap();
    let png = |p: &Path| {
        image::RgbImage::from_pixel(2, 2, image::Rgb([200, 100, 50]))
            .save_with_format(p, image::ImageFormat::Png)
            .unwrap()
    };
    png(&dir.join("private.png"));
    png(&inside.join("own.png"));
    std::os::unix::fs::symlink(dir.join("private.png"), inside.join("link.png")).unwrap();
    let private = dir.join("private.png").display().to_string();
    let scene = inside.join("s.ron");
    let write_scene = |texture: &str| {
        let text = with_material(r#""t": Lambertian(albedo: "tex"),"#).replace(
            "    materials:",
            &format!("    textures: {{ \"tex\": Image(file: \"{texture}\") }},\n    materials:"),
        );
        std::fs::write(&scene, text).unwrap();
    };
    let render = |texture: &str, flags: &[&str]| {
        write_scene(texture);
        Command::new(env!("CARGO_BIN_EXE_pathwave"))
            .args(["render", "--spp", "1", "--width", "4", "--height", "4"])
            .args(flags)
            .arg(&scene)
            .arg("-o")
            .arg(inside.join("o.png"))
            .output()
            .unwrap()
    };
    let under = inside.display().to_string();
    for texture in ["../private.png", private.as_str(), "link.png"] {
        let o = render(texture, &["--assets-under", &under]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains("lies outside"), "{texture}: {err}");
        let o = render(texture, &[]);
        assert!(o.status.success(), "{texture} without the flag: {}", String::from_utf8_lossy(&o.stderr));
    }
    let o = render("own.png", &["--assets-under", &under]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // farm slurm: the scene's folder by default.
    write_scene("../private.png");
    let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .args(["farm", "slurm", "--tasks", "2", "--dry-run", "-o"])
        .arg(dir.join("f_{frame}.png"))
        .arg(&scene)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("lies outside"), "farm: {err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A scene's meshes and images are read ahead of the parse that places them, side by side on
/// rayon's threads, under the loading thread's rules: each file is an input of the load
/// (recorded, as read on the loading thread), and `--assets-under` holds for them as for a file
/// read in the parse (a read-ahead that escaped it would leave the file read for the parse,
/// and the scene would load). Several files, so that the read-ahead runs.
#[test]
fn files_read_ahead_keep_the_loads_rules() {
    use pathwave::engine::format::files::{confined, recording};
    let dir = std::env::temp_dir().join(format!("pathwave-read-ahead-{}", std::process::id()));
    let inside = dir.join("scene");
    std::fs::create_dir_all(&inside).unwrap();
    let obj =
        |p: &Path, k: usize| std::fs::write(p, format!("v 0 0 0\nv 1 0 {k}\nv 0 1 0\nf 1 2 3\n")).unwrap();
    let png = |p: &Path| image::RgbImage::new(2, 2).save_with_format(p, image::ImageFormat::Png).unwrap();
    for k in 0..3 {
        obj(&inside.join(format!("m{k}.obj")), k);
    }
    obj(&dir.join("private.obj"), 9);
    png(&inside.join("a.png"));
    png(&inside.join("b.png"));
    let file = inside.join("s.ron");
    let write = |last_mesh: &str| {
        let meshes: String = ["m0.obj", "m1.obj", "m2.obj", last_mesh]
            .iter()
            .map(|m| format!(r#"        (shape: Mesh(file: "{m}"), material: "a"),"#))
            .collect::<Vec<_>>()
            .join("\n");
        let text = scene(CAMERA, r#""a": Lambertian(albedo: "ta"), "b": Lambertian(albedo: "tb"),"#, &meshes)
            .replace(
                "    materials:",
                "    textures: { \"ta\": Image(file: \"a.png\"), \"tb\": Image(file: \"b.png\") },\n    materials:",
            );
        std::fs::write(&file, text).unwrap();
    };
    write("m0.obj");
    let (desc, read) = recording(|| load(&file).unwrap());
    let mut names: Vec<String> =
        read.iter().map(|f| f.path.file_name().unwrap().to_string_lossy().into_owned()).collect();
    names.sort();
    assert_eq!(names, ["a.png", "b.png", "m0.obj", "m1.obj", "m2.obj", "s.ron"]);
    assert_eq!(desc.inputs.len(), 6, "{:?}", desc.inputs);
    // A mesh outside the folder, among files that are inside: refused where the scene names it.
    write("../private.obj");
    let Err(e) = confined(&inside, &file, || load(&file)).unwrap() else {
        panic!("the scene loaded with a mesh outside the folder");
    };
    assert!(e.message.contains("lies outside") && e.line == 12, "{e}");
    assert!(load(&file).is_ok(), "the same scene without the confinement");
    std::fs::remove_dir_all(&dir).unwrap();
}

// 10. Positive control.

#[test]
fn shipped_scenes_parse() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "ron") {
            load(&path).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
    }
    assert!(n > 0, "no scenes in {}", dir.display());
}

// 11. Messages name the user's words, and valid unusual input is accepted.

#[test]
fn messages_name_user_facing_types() {
    let e = err(&with_object(r#"(shape: Cone(radius: 1), material: "white"),"#));
    assert!(e.message.contains("`Shape`") && !e.message.contains("Raw"), "{e}");
    let e = err(&with_camera("look_from: (0, 0, -5), look_at: (0, 0, 0), vfvo: 40"));
    assert!(e.message.contains("`Camera`") && !e.message.contains("Raw"), "{e}");
}

#[test]
fn no_materials_defined() {
    let text = with_object(OBJECT)
        .replace(r#""white": Lambertian(albedo: (0.7, 0.7, 0.7)),"#, "")
        .replace(MATERIAL, "");
    let e = err(&text);
    assert!(e.message.contains("no materials are defined"), "{e}");
}

#[test]
fn matrix_rows_tiny_scales_and_a_byte_order_mark_are_accepted() {
    let object = r#"(shape: Sphere(center: (0, 0, 0), radius: 1), material: "white", transform: [UniformScale(1e-5), Matrix([[1, 0, 0, 2], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])]),"#;
    let text = format!("\u{feff}{}", with_object(object));
    parse(&text, Path::new("test.ron")).unwrap_or_else(|e| panic!("{e}"));
    let bad_row = object.replace("[0, 0, 0, 1]]", "[0, 0, 0]]");
    assert!(err(&with_object(&bad_row)).message.contains("4 rows of 4 numbers"));
}

/// A scene with an `animation` block on line 10 (after the template's closing `],`).
fn with_animation(animation: &str) -> String {
    scene(CAMERA, MATERIAL, OBJECT).replacen(
        "    ],\n)",
        &format!("    ],\n    animation: ({animation}),\n)"),
        1,
    )
}

#[test]
fn animation_errors_name_the_key() {
    let text = with_animation(r#"emit: [("light", Linear([(0, (1, 1, 1)), (0, (2, 2, 2))]))]"#);
    let e = err(&text);
    assert!(e.line == 10 && e.message.contains("key times must increase: 0 comes after 0"), "{e}");
    let e = err(&with_animation(r#"emit: [("white", Linear([(0, (1, 1, 1))]))]"#));
    assert!(e.line == 10 && e.message.contains("\"white\" is not a DiffuseLight"), "{e}");
    let e = err(&with_animation("shutter: 1.5"));
    assert!(e.line == 10 && e.message.contains("expected a number in [0, 1], found 1.5"), "{e}");
    let e = err(&with_animation("camera: (vfov: Cubic([(0, 40)]))"));
    assert!(e.line == 10 && e.message.contains("Linear") && e.message.contains("Smooth"), "{e}");
    let e = err(&with_object(
        r#"(shape: Sphere(center: (0, 0, 0), radius: 1), material: "white", animate: (rotate: Linear([(0, Euler(1, 2))]))),"#,
    ));
    assert!(e.line == 8 && e.message.contains("in objects[0]"), "{e}");
}

/// Values the README bounds are refused, not clamped: a fuzz of 2 (README: [0, 1]).
#[test]
fn metal_fuzz_beyond_one_is_refused() {
    let text = with_material(r#""blurry": Metal(albedo: (0.5, 0.5, 0.5), fuzz: 2),"#);
    let e = err(&text);
    assert_eq!(e.line, 5, "{e}");
    assert!(e.message.contains("expected a number in [0, 1], found 2"), "{e}");
}

/// Wrappers (`Mask`, `Blend`) refuse an opacity or weight outside [0, 1], a texture or
/// material that is not defined, a material defined after them (so no cycle) or an emitter
/// inside, each at the value (a quoted name at its first letter), and an `emit` on an object
/// that uses one.
#[test]
fn wrappers_name_what_is_wrong_where() {
    // The material line starts at column 9; `at` is where `token` begins in it.
    let at = |m: &str, token: &str| 9 + m.find(token).unwrap();
    for (m, token, words) in [
        (
            r#""m": Mask(opacity: 1.5, material: "white"),"#,
            "1.5",
            &["a number in [0, 1] or a texture", "1.5"][..],
        ),
        (r#""m": Blend(weight: -0.5, materials: ("white", "white")),"#, "-0.5", &["[0, 1]", "-0.5"]),
        (r#""m": Mask(opacity: "nope", material: "white"),"#, "\"nope\"", &["unknown texture \"nope\""]),
        (r#""m": Mask(opacity: 0.5, material: "nope"),"#, "\"nope\"", &["unknown material \"nope\""]),
        (
            r#""m": Blend(weight: 0.5, materials: ("white", "later")), "later": Lambertian(albedo: (1, 1, 1)),"#,
            "\"later\"",
            &["\"later\" must be defined before the wrapper"],
        ),
        (
            r#""m": Blend(weight: 0.5, materials: ("white", "m")),"#,
            "\"m\")",
            &["\"m\" must be defined before"],
        ),
        (
            r#""l": DiffuseLight(emit: (1, 1, 1)), "m": Mask(opacity: 0.5, material: "l"),"#,
            "\"l\")",
            &["\"l\" is a DiffuseLight: wrappers go around materials that reflect"],
        ),
    ] {
        let col = at(m, token) + token.starts_with('"') as usize;
        assert_err(&with_material(m), 5, col, words);
    }
    let masked = r#""m": Mask(opacity: 0.5, material: "white"),"#;
    let glowing =
        r#"(shape: Sphere(center: (0, 0, 0), radius: 1), material: "m", emit: (radiance: (1, 1, 1))),"#;
    let e = err(&scene(CAMERA, masked, glowing));
    assert!(
        e.line == 8 && e.message.contains("\"m\" is a wrapper (Mask, Blend, Bump, NormalMap): `emit`"),
        "{e}"
    );
    let misspelt = err(&with_material(r#""m": Masc(opacity: 0.5, material: "white"),"#));
    assert!(misspelt.message.contains("`Mask`, `Blend`, `Bump`, or `NormalMap`"), "{misspelt}");
}

/// Bump and normal maps refuse heights that are not an image (a bump map takes the image's
/// slopes), a scale that is not finite, a texture or material that is not defined, and a map
/// inside another (directly or through a mask), each at the value.
#[test]
fn maps_name_what_is_wrong_where() {
    let dir = std::env::temp_dir().join(format!("pathwave-maps-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    image::GrayImage::from_pixel(2, 2, image::Luma([100])).save(dir.join("h.png")).unwrap();
    let path = dir.join("s.ron");
    let textures = r#""h": Image(file: "h.png", raw: true), "n": Noise(scale: 2)"#;
    // The material line starts at column 9 of line 6; `at` is where `token` begins in it.
    let at = |m: &str, token: &str| 9 + m.find(token).unwrap() + token.starts_with('"') as usize;
    for (m, token, words) in [
        (
            r#""m": Bump(texture: "n", material: "white"),"#,
            "\"n\"",
            &["texture \"n\" is not an Image: a bump map reads the heights of an image"][..],
        ),
        (r#""m": Bump(texture: "h", scale: inf, material: "white"),"#, "inf", &["finite", "inf"]),
        (r#""m": NormalMap(texture: "x", material: "white"),"#, "\"x\"", &["unknown texture \"x\""]),
        (r#""m": NormalMap(texture: "h", material: "y"),"#, "\"y\"", &["unknown material \"y\""]),
        (
            r#""b": Bump(texture: "h", material: "white"), "m": NormalMap(texture: "h", material: "b"),"#,
            "\"b\")",
            &["material \"b\" is or holds a bump or normal map: maps do not nest"],
        ),
        (
            r#""b": Bump(texture: "h", material: "white"), "k": Mask(opacity: 0.5, material: "b"), "m": Bump(texture: "h", material: "k"),"#,
            "\"k\")",
            &["material \"k\" is or holds a bump or normal map"],
        ),
    ] {
        let text = with_textures(textures, m);
        let e = parse(&text, &path).expect_err(m);
        let want = (6, at(m, token));
        assert!(
            (e.line, e.col) == want && words.iter().all(|w| e.message.contains(w)),
            "{m}: expected {want:?} and {words:?}, got {e}"
        );
    }
    // Both parse where all is well, and a mask may go inside a map.
    let fine = r#""k": Mask(opacity: 0.5, material: "white"), "b": Bump(texture: "h", scale: 0.1, material: "k"), "m": NormalMap(texture: "h", material: "white", flip_invalid_normals: false),"#;
    parse(&with_textures(textures, fine), &path).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}
