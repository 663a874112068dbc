//! `<shape>` plugins as pathwave shapes: each gives the shape in its own space and the
//! `to_world` steps that place it.
//!
//! A shape's uv is Mitsuba's with pathwave's v, 1 - Mitsuba's (pathwave's images have row 0 at
//! v = 1, Mitsuba's at v = 0; OBJ files are read so that the two agree), so that any texture,
//! shared by shapes of every kind, reads what Mitsuba reads.

use super::convert::{Converter, num, v3};
use super::props::{Op, Plugin, compose};
use crate::scene::SceneError;
use glam::DVec3;

/// The RON shape and its transform steps, `outer` (the instances around it, innermost first)
/// appended.
pub fn convert(cx: &Converter, p: &Plugin, outer: &[Op]) -> Result<(String, Vec<Op>), SceneError> {
    let mut to_world = p.transform("to_world")?.unwrap_or_default();
    if p.bool("flip_normals")?.unwrap_or(false) {
        return Err(p.at.error(format!("{}: flip_normals is not in pathwave yet", p.label())));
    }
    if to_world.iter().all(|op| *op == Op::Translate(DVec3::ZERO)) {
        to_world.clear();
    }
    to_world.extend_from_slice(outer);
    let shape = match p.kind.as_str() {
        // Mitsuba's rectangle (`src/shapes/rectangle.cpp`): [-1, 1]^2 in z = 0, normal +z,
        // uv ((x + 1) / 2, (y + 1) / 2). pathwave's v, (1 - y) / 2, runs along -y from the corner
        // (-1, 1), so u x v faces -z: the quad faces the other way (`flip_normal`), or, under a
        // mirroring transform (whose quads pathwave gives swapped edges, keeping the side they
        // face), its edges are written swapped.
        "rectangle" => {
            p.finish(&["to_world", "flip_normals"])?;
            match compose(&to_world).determinant() < 0.0 {
                false => "Quad(q: (-1, 1, 0), u: (2, 0, 0), v: (0, -2, 0), flip_normal: true)".to_owned(),
                true => "Quad(q: (-1, 1, 0), u: (0, -2, 0), v: (2, 0, 0))".to_owned(),
            }
        }
        // Mitsuba's cube (`src/shapes/cube.cpp`): a mesh whose faces each map to [0, 1]^2.
        "cube" => {
            p.finish(&["to_world", "flip_normals"])?;
            "Box(a: (-1, -1, -1), b: (1, 1, 1), uv: Mitsuba)".to_owned()
        }
        "sphere" => {
            let center = p.vector("center")?.unwrap_or(DVec3::ZERO);
            let radius = p.float("radius")?.unwrap_or(1.0);
            if !(radius > 0.0) {
                return Err(p.at.error(format!("sphere radius {radius}: expected > 0")));
            }
            p.finish(&["to_world", "flip_normals", "center", "radius"])?;
            // Mitsuba's sphere (`src/shapes/sphere.cpp`) has its uv's poles on z.
            format!("Sphere(center: {}, radius: {}, poles: Z)", v3(center), num(radius))
        }
        "obj" => {
            let (name, at) =
                p.string("filename")?.ok_or_else(|| p.at.error("<shape type=\"obj\"> needs a filename"))?;
            let file = cx.file(&name, &at)?;
            let flat = p.bool("face_normals")?.unwrap_or(false);
            // Mitsuba flips the file's v on load (its default `flip_tex_coords`), and pathwave's
            // v is 1 - Mitsuba's: the file's v as written.
            if let Some(false) = p.bool("flip_tex_coords")? {
                return Err(p.at.error(format!(
                    "{}: flip_tex_coords false is not in pathwave (it reads the file's v as Mitsuba's default flips it)",
                    p.label()
                )));
            }
            p.finish(&["to_world", "flip_normals", "filename", "face_normals", "flip_tex_coords"])?;
            // pathwave reads an OBJ's vertex normals and texture coordinates as Mitsuba does
            // (smooth shading where the file gives normals, unless face_normals).
            match flat {
                true => format!("Mesh(file: {file}, face_normals: true)"),
                false => format!("Mesh(file: {file})"),
            }
        }
        k => {
            return Err(p.at.error(format!(
                "<shape type=\"{k}\">: pathwave reads rectangle, cube, sphere, obj, shapegroup and instance"
            )));
        }
    };
    Ok((shape, to_world))
}
