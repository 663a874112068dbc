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
use std::fmt::Write;

/// The RON shape and its transform steps, `outer` (the instances around it, innermost first)
/// appended.
pub fn convert(cx: &Converter, p: &Plugin, outer: &[Op]) -> Result<(String, Vec<Op>), SceneError> {
    let mut to_world = p.transform("to_world")?.unwrap_or_default();
    if to_world.iter().all(|op| *op == Op::Translate(DVec3::ZERO)) {
        to_world.clear();
    }
    to_world.extend_from_slice(outer);
    let flip = p.bool("flip_normals")?.unwrap_or(false);
    let flip_here = |what: &str| match flip {
        true => Err(p.at.error(format!("{}: flip_normals is not in pathwave's {what} yet", p.label()))),
        false => Ok(()),
    };
    let shape = match p.kind.as_str() {
        // Mitsuba's rectangle (`src/shapes/rectangle.cpp`): [-1, 1]^2 in z = 0, normal +z,
        // uv ((x + 1) / 2, (y + 1) / 2). pathwave's v, (1 - y) / 2, runs along -y from the corner
        // (-1, 1), so u x v faces -z: the quad faces the other way (`flip_normal`), or, under a
        // mirroring transform (whose quads pathwave gives swapped edges, keeping the side they
        // face), its edges are written swapped.
        "rectangle" => {
            flip_here("rectangles")?;
            p.finish(&["to_world"])?;
            match compose(&to_world).determinant() < 0.0 {
                false => "Quad(q: (-1, 1, 0), u: (2, 0, 0), v: (0, -2, 0), flip_normal: true)".to_owned(),
                true => "Quad(q: (-1, 1, 0), u: (0, -2, 0), v: (2, 0, 0))".to_owned(),
            }
        }
        // Mitsuba's cube (`src/shapes/cube.cpp`): a mesh whose faces each map to [0, 1]^2.
        "cube" => {
            flip_here("cubes")?;
            p.finish(&["to_world"])?;
            "Box(a: (-1, -1, -1), b: (1, 1, 1), uv: Mitsuba)".to_owned()
        }
        "sphere" => {
            flip_here("spheres")?;
            let center = p.vector("center")?.unwrap_or(DVec3::ZERO);
            let radius = p.float("radius")?.unwrap_or(1.0);
            if !(radius > 0.0) {
                return Err(p.at.error(format!("sphere radius {radius}: expected > 0")));
            }
            p.finish(&["to_world", "center", "radius"])?;
            // Mitsuba's sphere (`src/shapes/sphere.cpp`) has its uv's poles on z.
            format!("Sphere(center: {}, radius: {}, poles: Z)", v3(center), num(radius))
        }
        // Mitsuba's disk: the unit disk in z = 0 facing +z, its frame's x and y the radii.
        "disk" => {
            p.finish(&["to_world", "flip_normals"])?;
            format!("Disk(center: (0, 0, 0), normal: (0, 0, 1), radius: 1{})", flag("flip_normals", flip))
        }
        "cylinder" => {
            let p0 = p.vector("p0")?.unwrap_or(DVec3::ZERO);
            let p1 = p.vector("p1")?.unwrap_or(DVec3::Z);
            let radius = p.float("radius")?.unwrap_or(1.0);
            if !(radius > 0.0) || !(p0.distance(p1) > 0.0) {
                return Err(p.at.error(format!(
                    "cylinder radius {radius}, p0 {p0}, p1 {p1}: expected a radius > 0 and p0 apart from p1"
                )));
            }
            p.finish(&["to_world", "flip_normals", "p0", "p1", "radius"])?;
            format!(
                "Cylinder(p0: {}, p1: {}, radius: {}{})",
                v3(p0),
                v3(p1),
                num(radius),
                flag("flip_normals", flip)
            )
        }
        // Mitsuba's sdfgrid (`src/shapes/sdfgrid.cpp`): the grid from a file (its `grid`
        // tensor is for Python and C++ only), shaded with `normals` smooth (its default) or
        // analytic.
        "sdfgrid" => {
            flip_here("SDF grids")?;
            let (name, at) = p.string("filename")?.ok_or_else(|| {
                p.at.error("<shape type=\"sdfgrid\"> needs a filename (pathwave reads grids from files)")
            })?;
            let file = cx.file(&name, &at)?;
            let normals = match p.string("normals")? {
                None => "Smooth",
                Some((n, at)) => match n.as_str() {
                    "smooth" => "Smooth",
                    "analytic" => "Analytic",
                    _ => {
                        return Err(at.error(format!(
                            "normals \"{n}\": Mitsuba and pathwave read \"smooth\" and \"analytic\""
                        )));
                    }
                },
            };
            p.finish(&["to_world", "filename", "normals"])?;
            format!("SdfGrid(file: {file}, normals: {normals})")
        }
        "obj" | "ply" | "serialized" => {
            let kind = p.kind.as_str();
            let (name, at) = p
                .string("filename")?
                .ok_or_else(|| p.at.error(format!("<shape type=\"{kind}\"> needs a filename")))?;
            let file = cx.file(&name, &at)?;
            let flat = p.bool("face_normals")?.unwrap_or(false);
            // Mitsuba flips an OBJ's v by default and reads the others' as written; pathwave's v
            // already runs the way Mitsuba's flipped one does.
            let mitsuba_flips = match kind {
                "serialized" => false,
                _ => p.bool("flip_tex_coords")?.unwrap_or(kind == "obj"),
            };
            let index = match kind {
                "serialized" => p.int("shape_index")?.unwrap_or(0),
                _ => 0,
            };
            if !(0..=u32::MAX as i64).contains(&index) {
                return Err(p.at.error(format!("shape_index {index}: expected 0 or more")));
            }
            let reads =
                ["to_world", "flip_normals", "filename", "face_normals", "flip_tex_coords", "shape_index"];
            p.finish(&reads)?;
            // pathwave reads vertex normals and texture coordinates as Mitsuba does (smooth
            // shading where the file gives normals, unless face_normals); PLY properties
            // become the same mesh attributes.
            let mut text = format!("Mesh(file: {file}");
            if index > 0 {
                write!(text, ", shape_index: {index}").unwrap();
            }
            text += &flag("face_normals", flat);
            text += &flag("flip_normals", flip);
            text += &flag("flip_tex_coords", !mitsuba_flips);
            text + ")"
        }
        k => {
            return Err(p.at.error(format!(
                "<shape type=\"{k}\">: pathwave reads rectangle, cube, sphere, disk, cylinder, obj, ply, serialized, sdfgrid, shapegroup and instance"
            )));
        }
    };
    Ok((shape, to_world))
}

/// `, name: true` when `on`, else nothing (the RON default).
fn flag(name: &str, on: bool) -> String {
    match on {
        true => format!(", {name}: true"),
        false => String::new(),
    }
}
