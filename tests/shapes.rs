//! Disks and cylinders as lights against closed forms, and meshes with attributes: the light's
//! samples and density and the MIS weight of BSDF-sampled rays that hit it must all be right
//! for the floor under a lamp to have its exact radiance, and both integrators give the same
//! bits on every shape.

mod common;
use common::*;
use glam::DVec3;
use pathwave::engine::world::SceneWorld;
use pathwave::integrator::film::Film;
use pathwave::integrator::{oracle, wavefront};

/// The mean of the image and the variance of that mean.
fn image_mean(film: &Film) -> (DVec3, DVec3) {
    let n = film.mean().len() as f64;
    let m = film.mean().iter().fold(DVec3::ZERO, |a, p| a + p.as_dvec3()) / n;
    let v = film.variance_of_mean().iter().fold(DVec3::ZERO, |a, p| a + p.as_dvec3()) / (n * n);
    (m, v)
}

/// The wavefront's image of `text`, checked to be the oracle's bits.
fn render_both(text: &str) -> Film {
    let scene = SceneWorld::render_scene(&inline(text));
    let film = wavefront::render(&scene, wavefront::Options::default(), &|_, _| {}).0;
    assert!(oracle::render(&scene, &|_, _| {}) == film, "the oracle's bits");
    film
}

/// A floor of albedo 0.5 seen straight down through a narrow camera at height `cam`, lit by
/// `lamp` (a shape with the material "lamp", radiance 5) alone.
fn floor_under(lamp: &str, cam: f32) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0, {cam}, 0), look_at: (0, 0, 0), vup: (0, 0, -1), vfov: 2),
            render: (width: 8, height: 8, spp: 4096),
            materials: {{
                "lamp": DiffuseLight(emit: (5, 5, 5)),
                "floor": Lambertian(albedo: (0.5, 0.5, 0.5)),
            }},
            objects: [
                (shape: {lamp}, material: "lamp"),
                (shape: Quad(q: (-50, 0, -50), u: (0, 0, 100), v: (100, 0, 0)), material: "floor"),
            ],
        )"#
    )
}

/// Asserts that `film`'s mean is `want` (within 1% and 5 standard deviations).
#[track_caller]
fn assert_mean(film: &Film, want: f64) {
    let (mean, var) = image_mean(film);
    let z = ((mean - DVec3::splat(want)) / var.map(f64::sqrt)).abs().max_element();
    assert!(z < 5.0 && (mean.x / want - 1.0).abs() < 0.01, "mean {mean}, want {want} (z {z})");
}

/// Under a disk lamp of radiance L, radius r, at height h, facing down, the floor straight below
/// has radiance `albedo L r^2 / (h^2 + r^2)`. The disk is given facing up and flipped, and
/// stretched from a smaller one: its normal, flip and transform all count. A 5% darker floor is
/// told apart.
#[test]
fn a_disk_lamp_lights_the_floor_below_exactly() {
    let (h, r) = (2.0, 1.0);
    let want = 0.5 * 5.0 * r * r / (h * h + r * r);
    let disk = "Disk(center: (0, 4, 0), normal: (0, 1, 0), radius: 0.5, flip_normals: true), \
                transform: [UniformScale(2), Translate((0, -6, 0))]";
    let text = floor_under(disk, 1.0);
    assert_mean(&render_both(&text), want);
    let darker = render_both(&text.replace("(0.5, 0.5, 0.5)", "(0.475, 0.475, 0.475)"));
    let (m, v) = image_mean(&darker);
    assert!(((m - DVec3::splat(want)) / v.map(f64::sqrt)).abs().min_element() > 8.0, "5% off: {m}");
}

/// Inside a tube of radius r and height h that emits inwards (`flip_normals`), standing on the
/// floor, the floor's centre sees the wall between the polar angles atan(r / h) and pi / 2: its
/// irradiance is `pi L h^2 / (h^2 + r^2)`, its radiance `albedo L h^2 / (h^2 + r^2)`. The camera
/// looks down through the open top.
#[test]
fn an_inward_cylinder_lamp_lights_the_floor_inside_exactly() {
    let (h, r) = (1.5, 0.8);
    let want = 0.5 * 5.0 * h * h / (h * h + r * r);
    let tube = format!("Cylinder(p0: (0, 0, 0), p1: (0, {h}, 0), radius: {r}, flip_normals: true)");
    assert_mean(&render_both(&floor_under(&tube, 3.0)), want);
    // Facing out it does not light the floor inside.
    let outward = render_both(&floor_under(&tube.replace(", flip_normals: true", ""), 3.0));
    assert_eq!(image_mean(&outward).0, DVec3::ZERO);
}

/// A binary PLY square of two triangles in z = 0 (corners (-1, -1) to (1, 1), facing +z) with
/// one colour per vertex (`red green blue` as bytes) and per face (`c_0 c_1 c_2` as floats).
fn attribute_square() -> Vec<u8> {
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n\
        property float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
        element face 2\nproperty list uchar int vertex_indices\nproperty float c_0\nproperty float c_1\n\
        property float c_2\nend_header\n"
        .to_vec();
    let corners = [
        (-1.0f32, -1.0f32, [255u8, 0, 0]),
        (1.0, -1.0, [0, 255, 0]),
        (1.0, 1.0, [0, 0, 255]),
        (-1.0, 1.0, [255, 255, 255]),
    ];
    for (x, y, rgb) in corners {
        for v in [x, y, 0.0] {
            b.extend(v.to_le_bytes());
        }
        b.extend(rgb);
    }
    for (tri, colour) in [([0i32, 1, 2], [0.2f32, 0.4, 0.6]), ([0, 2, 3], [0.9, 0.8, 0.1])] {
        b.push(3);
        tri.iter().for_each(|i| b.extend(i.to_le_bytes()));
        colour.iter().for_each(|c| b.extend(c.to_le_bytes()));
    }
    b
}

/// The square under a white sky, seen from +z through a narrow view that it fills: a
/// Lambertian surface of albedo `a` under a uniform sky of radiance 1 has radiance `a`, so each
/// pixel shows the attribute over its footprint (the default box filter's one pixel).
fn attribute_scene(dir: &std::path::Path, attribute: &str) -> String {
    std::fs::write(dir.join("square.ply"), attribute_square()).unwrap();
    let text = format!(
        r#"Scene(
            camera: (look_from: (0, 0, 10), look_at: (0, 0, 0), vfov: 10),
            render: (width: 4, height: 4, spp: 1024),
            background: Constant((1, 1, 1)),
            textures: {{ "a": MeshAttribute(name: "{attribute}") }},
            materials: {{ "m": Lambertian(albedo: "a") }},
            objects: [(shape: Mesh(file: "square.ply"), material: "m")],
        )"#
    );
    let path = dir.join("attr.ron");
    std::fs::write(&path, &text).unwrap();
    text
}

/// Face colours are constant over each triangle; vertex colours (bytes, read as sRGB like
/// Mitsuba) are interpolated. Both integrators agree.
#[test]
fn mesh_attributes_colour_the_faces_and_blend_the_vertices() {
    let dir = tempfile::tempdir().unwrap();
    attribute_scene(dir.path(), "face_c");
    let desc = pathwave::engine::scene::load(&dir.path().join("attr.ron")).unwrap_or_else(|e| panic!("{e}"));
    let scene = SceneWorld::render_scene(&desc);
    let film = wavefront::render(&scene, wavefront::Options::default(), &|_, _| {}).0;
    assert!(oracle::render(&scene, &|_, _| {}) == film, "the oracle's bits");
    let px = |film: &Film, x: usize, y: usize| film.mean()[y * 4 + x];
    // Pixel (3, 3) (bottom right, x > 0 > y) lies in the first triangle, (0, 0) in the second.
    assert!(
        (px(&film, 3, 3) - glam::Vec3::new(0.2, 0.4, 0.6)).abs().max_element() < 0.02,
        "{}",
        px(&film, 3, 3)
    );
    assert!(
        (px(&film, 0, 0) - glam::Vec3::new(0.9, 0.8, 0.1)).abs().max_element() < 0.02,
        "{}",
        px(&film, 0, 0)
    );
    attribute_scene(dir.path(), "vertex_color");
    let desc = pathwave::engine::scene::load(&dir.path().join("attr.ron")).unwrap_or_else(|e| panic!("{e}"));
    let film =
        wavefront::render(&SceneWorld::render_scene(&desc), wavefront::Options::default(), &|_, _| {}).0;
    // The pixel nearest the red corner (-1, -1) is mostly red; the image's mean is the blend.
    let c = px(&film, 0, 3);
    assert!(c.x > 0.5 && c.y < 0.3 && c.z < 0.3, "{c}");
    assert!(film.mean().iter().all(|p| p.is_finite() && p.min_element() >= 0.0));
}

/// A material reading an attribute is refused on a shape that is not a mesh, and on a mesh
/// without it (naming the ones it has).
#[test]
fn mesh_attributes_the_mesh_lacks_are_refused_with_their_place() {
    let dir = tempfile::tempdir().unwrap();
    let text = attribute_scene(dir.path(), "vertex_weight");
    let err = pathwave::engine::scene::load(&dir.path().join("attr.ron")).unwrap_err().to_string();
    assert!(
        err.contains("vertex_weight") && err.contains("vertex_color, face_c") && err.contains(":7:"),
        "{err}"
    );
    let sphere = text.replace(r#"Mesh(file: "square.ply")"#, "Sphere(center: (0, 0, 0), radius: 1)");
    let err = pathwave::engine::scene::parse(&sphere, &dir.path().join("s.ron")).unwrap_err().to_string();
    assert!(err.contains("goes on a Mesh"), "{err}");
    let bad = text.replace("vertex_weight", "weight");
    let err = pathwave::engine::scene::parse(&bad, &dir.path().join("s.ron")).unwrap_err().to_string();
    assert!(err.contains("starts with vertex_ or face_") && err.contains(":5:"), "{err}");
}
