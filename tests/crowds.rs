//! Crowded geometry (issue 45, item 1): thousands of coincident quads, identical spheres,
//! triangles or mesh instances, concentric spheres, and an OBJ that repeats its faces. Each
//! crowd floats over a floor under the sky and renders, in both integrators, the image of the
//! same scene with one copy (for the concentric spheres, the outermost alone): the copies meet
//! every ray at the same distance with the same surface, and the outermost sphere hides the
//! others. PLOC chained such crowds as deep as they were many, and the traversal stacks
//! overflowed (`index out of bounds: the len is 512 but the index is 512`).

use pathwave::engine::scene::load;
use pathwave::engine::world::SceneWorld;
use pathwave::integrator::film::Film;
use pathwave::integrator::{oracle, wavefront};
use std::path::Path;

const SQUARE: &str = "v -0.5 -0.5 0\nv 0.5 -0.5 0.2\nv 0.5 0.5 0\nv -0.5 0.5 -0.2\n";

/// Writes the scene of `objects` (RON object entries) into `dir` and renders it with both
/// integrators.
fn render_both(dir: &Path, name: &str, objects: &str) -> [Film; 2] {
    let text = format!(
        r#"Scene(
            camera: (look_from: (0.3, 1.5, 4), look_at: (0, 0.8, 0), vfov: 35),
            render: (width: 24, height: 24, spp: 4, max_depth: 3),
            background: Sky(bottom: (1, 1, 1), top: (0.5, 0.7, 1)),
            materials: {{
                "floor": Lambertian(albedo: (0.5, 0.5, 0.5)),
                "crowd": Lambertian(albedo: (0.7, 0.4, 0.2)),
            }},
            objects: [
                (shape: Quad(q: (-5, 0, -5), u: (0, 0, 10), v: (10, 0, 0)), material: "floor"),
                {objects}
            ],
        )"#
    );
    let path = dir.join(format!("{name}.ron"));
    std::fs::write(&path, text).unwrap();
    let desc = load(&path).unwrap_or_else(|e| panic!("{e}"));
    let scene = SceneWorld::render_scene(&desc);
    let wave = wavefront::render(&scene, wavefront::Options::default(), &|_, _| {}).0;
    [oracle::render(&scene, &|_, _| {}), wave]
}

fn repeat(entry: &str, n: usize) -> String {
    vec![entry; n].join(",\n")
}

/// The crowd's images against the one copy's: the oracle's bits exactly, the wavefront's but
/// for a pixel or two where a ray meets two primitives at one distance (the one-copy scene is
/// small enough for flat primitive lists, which break such ties differently;
/// `tests/wavefront.rs`), and never a non-finite pixel.
fn check(dir: &Path, name: &str, crowd: &str, one: &str) {
    let [crowd_oracle, crowd_wave] = render_both(dir, name, crowd);
    let [one_oracle, one_wave] = render_both(dir, &format!("{name}-one"), one);
    for film in [&crowd_oracle, &crowd_wave, &one_oracle, &one_wave] {
        assert_eq!(film.non_finite(), 0, "{name}");
    }
    assert!(crowd_oracle.mean().iter().any(|p| p[0] > p[2] * 1.2), "{name}: the crowd is in view");
    let differing = |a: &Film, b: &Film| a.pixels.iter().zip(&b.pixels).filter(|(a, b)| a != b).count();
    assert_eq!(differing(&crowd_oracle, &one_oracle), 0, "{name}: oracle");
    assert!(
        differing(&crowd_wave, &one_wave) <= 2,
        "{name}: wavefront, {}",
        differing(&crowd_wave, &one_wave)
    );
    assert!(differing(&crowd_wave, &crowd_oracle) <= 2, "{name}: wavefront against the oracle");
}

#[test]
fn coincident_quads_render_as_one() {
    let dir = tempfile::tempdir().unwrap();
    let quad = r#"(shape: Quad(q: (-0.5, 0.4, 0.2), u: (1, 0, 0), v: (0, 1, -0.3)), material: "crowd")"#;
    check(dir.path(), "quads", &repeat(quad, 4000), quad);
}

#[test]
fn identical_spheres_render_as_one() {
    let dir = tempfile::tempdir().unwrap();
    let sphere = r#"(shape: Sphere(center: (0, 0.8, 0), radius: 0.5), material: "crowd")"#;
    check(dir.path(), "spheres", &repeat(sphere, 10_000), sphere);
}

#[test]
fn identical_triangles_render_as_one() {
    let dir = tempfile::tempdir().unwrap();
    let tri =
        r#"(shape: Triangle(a: (-0.6, 0.3, 0), b: (0.6, 0.3, 0.2), c: (0, 1.4, -0.1)), material: "crowd")"#;
    check(dir.path(), "triangles", &repeat(tri, 10_000), tri);
}

#[test]
fn coincident_mesh_instances_render_as_one() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("square.obj"), format!("{SQUARE}f 1 2 3\nf 1 3 4\n")).unwrap();
    let instance =
        r#"(shape: Mesh(file: "square.obj"), material: "crowd", transform: [Translate((0, 0.8, 0))])"#;
    check(dir.path(), "instances", &repeat(instance, 10_000), instance);
}

#[test]
fn concentric_spheres_render_as_the_outermost() {
    let dir = tempfile::tempdir().unwrap();
    let sphere = |r: f32| format!(r#"(shape: Sphere(center: (0, 0.8, 0), radius: {r}), material: "crowd")"#);
    let nested: Vec<String> = (1..=5000).map(|k| sphere(0.6 * k as f32 / 5000.0)).collect();
    check(dir.path(), "concentric", &nested.join(",\n"), &sphere(0.6));
}

#[test]
fn an_obj_of_duplicate_faces_renders_as_its_faces_once() {
    let dir = tempfile::tempdir().unwrap();
    let faces = "f 1 2 3\nf 1 3 4\n";
    std::fs::write(dir.path().join("repeated.obj"), format!("{SQUARE}{}", faces.repeat(2500))).unwrap();
    std::fs::write(dir.path().join("once.obj"), format!("{SQUARE}{faces}")).unwrap();
    let mesh = |file: &str| {
        format!(r#"(shape: Mesh(file: "{file}"), material: "crowd", transform: [Translate((0, 0.8, 0))])"#)
    };
    check(dir.path(), "faces", &mesh("repeated.obj"), &mesh("once.obj"));
}
