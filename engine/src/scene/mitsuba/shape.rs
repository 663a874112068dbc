//! `<shape>` plugins as pathwave shapes: each gives the shape in its own space and the
//! `to_world` steps that place it.

use super::convert::{Converter, num, v3};
use super::props::{Op, Plugin};
use crate::scene::SceneError;
use glam::DVec3;

/// The RON shape and its transform steps.
pub fn convert(cx: &Converter, p: &Plugin) -> Result<(String, Vec<Op>), SceneError> {
    let mut to_world = p.transform("to_world")?.unwrap_or_default();
    if p.bool("flip_normals")?.unwrap_or(false) {
        return Err(p.at.error(format!("{}: flip_normals is not in pathwave yet", p.label())));
    }
    let shape = match p.kind.as_str() {
        // Mitsuba's rectangle: [-1, 1]^2 in z = 0, normal +z, uv (x, y) mapped to [0, 1]^2.
        "rectangle" => {
            p.finish(&["to_world", "flip_normals"])?;
            "Quad(q: (-1, -1, 0), u: (2, 0, 0), v: (0, 2, 0))".to_owned()
        }
        "cube" => {
            p.finish(&["to_world", "flip_normals"])?;
            "Box(a: (-1, -1, -1), b: (1, 1, 1))".to_owned()
        }
        "sphere" => {
            let center = p.vector("center")?.unwrap_or(DVec3::ZERO);
            let radius = p.float("radius")?.unwrap_or(1.0);
            if !(radius > 0.0) {
                return Err(p.at.error(format!("sphere radius {radius}: expected > 0")));
            }
            p.finish(&["to_world", "flip_normals", "center", "radius"])?;
            format!("Sphere(center: {}, radius: {})", v3(center), num(radius))
        }
        "obj" => {
            let (name, at) =
                p.string("filename")?.ok_or_else(|| p.at.error("<shape type=\"obj\"> needs a filename"))?;
            let file = cx.file(&name, &at)?;
            let flat = p.bool("face_normals")?.unwrap_or(false);
            p.finish(&["to_world", "flip_normals", "filename", "face_normals"])?;
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
    if to_world.iter().all(|op| *op == Op::Translate(DVec3::ZERO)) {
        to_world.clear();
    }
    Ok((shape, to_world))
}
