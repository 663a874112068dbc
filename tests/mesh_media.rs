//! A medium bounded by a closed mesh renders like the same medium in the analytic box, and an
//! open mesh is refused as a boundary.

mod common;
use common::*;
use pathwave::metrics::rel_mse;

const CUBE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
f 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\nf 1 7 3\nf 2 4 8\nf 2 8 6\n";

fn scene(shape: &str, density: f32) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0.5, 1.2, 3.5), look_at: (0.5, 0.4, 0.5), vfov: 40),
            render: (width: 48, height: 48, spp: 64, max_depth: 16),
            background: Sky(bottom: (0.2, 0.2, 0.2), top: (1.2, 1.2, 1.2)),
            materials: {{ "floor": Lambertian(albedo: (0.6, 0.6, 0.6)) }},
            objects: [
                (shape: Quad(q: (-5, 0, 5), u: (10, 0, 0), v: (0, 0, -10)), material: "floor"),
                (shape: {shape}, medium: (density: {density}, albedo: (0.8, 0.8, 0.8)),
                 transform: [RotateY(25), Scale((1, 1.3, 1))]),
            ],
        )"#
    )
}

#[test]
fn a_closed_mesh_bounds_a_medium_like_the_box() {
    let dir = std::env::temp_dir().join(format!("pathwave-mesh-media-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("cube.obj"), CUBE).unwrap();
    let load = |text: String| {
        let p = dir.join("s.ron");
        std::fs::write(&p, text).unwrap();
        pathwave::engine::scene::load(&p).unwrap_or_else(|e| panic!("{e}"))
    };
    let boxed = render(&load(scene("Box(a: (0, 0, 0), b: (1, 1, 1))", 2.0))).mean();
    let meshed = render(&load(scene(r#"Mesh(file: "cube.obj")"#, 2.0))).mean();
    let denser = render(&load(scene("Box(a: (0, 0, 0), b: (1, 1, 1))", 2.1))).mean();
    let (same, control) = (rel_mse(&meshed, &boxed), rel_mse(&denser, &boxed));
    eprintln!("mesh vs box relMSE {same:.2e}; density +5% {control:.2e}");
    // Same seed, same paths: only the boundary arithmetic differs.
    assert!(same < 0.01 * control, "mesh {same} vs control {control}");

    // One face missing: refused, naming the file and an open edge.
    let open: String = CUBE.lines().filter(|l| *l != "f 2 8 6").map(|l| format!("{l}\n")).collect();
    std::fs::write(dir.join("open.obj"), open).unwrap();
    let p = dir.join("o.ron");
    std::fs::write(&p, scene(r#"Mesh(file: "open.obj")"#, 2.0)).unwrap();
    let e = pathwave::engine::scene::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("a medium needs a closed mesh") && e.contains("open.obj") && e.contains("borders 1"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
