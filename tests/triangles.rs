//! Triangles through the whole renderer: cornell-diffuse with the floor and the light each
//! split into two triangles renders like the original quads (the light is then sampled as two
//! triangle emitters by area), and a 5% dimmer light is detected.

mod common;
use common::*;
use pathwave::io::LinearImage;

const FLOOR: &str = r#"(shape: Quad(q: (0, 0, 0), u: (555, 0, 0), v: (0, 0, 555)), material: "white"),"#;
const LIGHT: &str =
    r#"(shape: Quad(q: (343, 554, 332), u: (-130, 0, 0), v: (0, 0, -105)), material: "light"),"#;

fn small(text: &str, seed: u64) -> pathwave::engine::scene::SceneDesc {
    let mut desc = inline(text);
    (desc.render.width, desc.render.height, desc.render.spp) =
        (48.try_into().unwrap(), 48.try_into().unwrap(), 64.try_into().unwrap());
    desc.render.seed = seed;
    desc
}

#[test]
fn quads_split_into_triangles_render_alike() {
    let text = std::fs::read_to_string(root().join("scenes/cornell-diffuse.ron")).unwrap();
    assert!(text.contains(FLOOR) && text.contains(LIGHT));
    let reference = render(&small(&text, 0));
    let reference = LinearImage { width: 48, height: 48, pixels: reference.mean() };
    // q, q + u, q + v and q + u, q + u + v, q + v: the same winding, so the same normal.
    let floor = r#"(shape: Triangle(a: (0, 0, 0), b: (555, 0, 0), c: (0, 0, 555)), material: "white"),
        (shape: Triangle(a: (555, 0, 0), b: (555, 0, 555), c: (0, 0, 555)), material: "white"),"#;
    let light = r#"(shape: Triangle(a: (343, 554, 332), b: (213, 554, 332), c: (343, 554, 227)), material: "light"),
        (shape: Triangle(a: (213, 554, 332), b: (213, 554, 227), c: (343, 554, 227)), material: "light"),"#;
    let split = text.replace(FLOOR, floor).replace(LIGHT, light);
    let stats = block_z(&render(&small(&split, 7)), &reference, 8, 64);
    assert!(stats.agrees(), "{stats:?}");
    let dim = split.replace("DiffuseLight(emit: (15, 15, 15))", "DiffuseLight(emit: (14.25, 14.25, 14.25))");
    let stats = block_z(&render(&small(&dim, 7)), &reference, 8, 64);
    assert!(!stats.agrees(), "5% less light went unnoticed: {stats:?}");
}

/// `face_normals: true` shades a mesh whose file has vertex normals flat (its own copy, shared
/// by the objects that ask for it); without it the normals are kept.
#[test]
fn face_normals_drop_the_files_normals() {
    use pathwave::engine::scene::{ShapeDesc, load};
    let dir = std::env::temp_dir().join(format!("pathwave-face-normals-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("ball.obj"), sphere_obj(8, 16, true)).unwrap();
    let scene = dir.join("s.ron");
    std::fs::write(
        &scene,
        r#"Scene(camera: (look_from: (0, 0, -5), look_at: (0, 0, 0), vfov: 40),
        materials: {"m": Lambertian(albedo: (0.5, 0.5, 0.5))},
        objects: [(shape: Mesh(file: "ball.obj"), material: "m"),
                  (shape: Mesh(file: "ball.obj", face_normals: true), material: "m"),
                  (shape: Mesh(file: "ball.obj", face_normals: true), material: "m")])"#,
    )
    .unwrap();
    let desc = load(&scene).unwrap_or_else(|e| panic!("{e}"));
    let mesh = |i: usize| match &desc.objects[i].shape {
        ShapeDesc::Mesh(m) => m.mesh.clone(),
        other => panic!("{other:?}"),
    };
    assert!(mesh(0).normals.is_some());
    assert!(mesh(1).normals.is_none() && mesh(1).positions == mesh(0).positions);
    assert!(std::sync::Arc::ptr_eq(&mesh(1), &mesh(2)), "the flat copy is shared");
}
