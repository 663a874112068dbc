//! Smooth shading: a coarse mesh sphere with the sphere's normals at its vertices shades like
//! the analytic sphere much more closely than the same mesh shaded flat.

mod common;
use common::*;
use pathwave::metrics::rel_mse;

/// A UV sphere of radius 1 with `rings` x `segments` quads as triangles, with or without
/// vertex normals (`vn`).
fn sphere_obj(rings: u32, segments: u32, normals: bool) -> String {
    let mut s = String::new();
    let mut verts = Vec::new();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            verts.push([theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()]);
        }
    }
    for v in &verts {
        s += &format!("v {} {} {}\n", v[0], v[1], v[2]);
        if normals {
            s += &format!("vn {} {} {}\n", v[0], v[1], v[2]);
        }
    }
    let at = |i: u32, j: u32| i * segments + j % segments + 1;
    let face = |a: u32, b: u32, c: u32| {
        if normals { format!("f {a}//{a} {b}//{b} {c}//{c}\n") } else { format!("f {a} {b} {c}\n") }
    };
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            // Outward winding: (b - a) x (c - a) points away from the centre.
            s += &face(a, c, b);
            s += &face(a, d, c);
        }
    }
    s
}

fn scene(shape: &str) -> String {
    format!(
        r#"Scene(
            camera: (look_from: (0, 0.8, 4), look_at: (0, 0, 0), vfov: 35),
            render: (width: 64, height: 64, spp: 256, max_depth: 4),
            background: Sky(bottom: (0.1, 0.1, 0.1), top: (1.5, 1.4, 1.2)),
            materials: {{ "m": Lambertian(albedo: (0.8, 0.8, 0.8)) }},
            objects: [ (shape: {shape}, material: "m") ],
        )"#
    )
}

#[test]
fn vertex_normals_shade_a_coarse_sphere_like_the_sphere() {
    let dir = std::env::temp_dir().join(format!("pathwave-smooth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("smooth.obj"), sphere_obj(10, 20, true)).unwrap();
    std::fs::write(dir.join("flat.obj"), sphere_obj(10, 20, false)).unwrap();
    let load = |shape: &str| {
        let path = dir.join("s.ron");
        std::fs::write(&path, scene(shape)).unwrap();
        pathwave::engine::scene::load(&path).unwrap()
    };
    let exact = render(&load("Sphere(center: (0, 0, 0), radius: 1)")).mean();
    let smooth = render(&load(r#"Mesh(file: "smooth.obj")"#)).mean();
    let flat = render(&load(r#"Mesh(file: "flat.obj")"#)).mean();
    let (e_smooth, e_flat) = (rel_mse(&smooth, &exact), rel_mse(&flat, &exact));
    eprintln!("relMSE against the analytic sphere: smooth {e_smooth:.5}, flat {e_flat:.5}");
    // Silhouettes differ alike (the mesh is polygonal either way); the shading is what differs.
    assert!(e_smooth < 0.5 * e_flat, "smooth {e_smooth} vs flat {e_flat}");
    std::fs::remove_dir_all(&dir).unwrap();
}
