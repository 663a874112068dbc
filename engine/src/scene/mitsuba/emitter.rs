//! `<emitter>` plugins as pathwave lights, backgrounds and emitting materials.

use super::convert::{Converter, num, num32, placed, v3};
use super::props::{Plugin, compose};
use super::spectrum::Use;
use super::xml::Element;
use crate::scene::SceneError;
use glam::DVec3;

/// What a top-level emitter becomes.
pub enum Emitter {
    /// An entry of `lights: [..]`.
    Light(String),
    /// The `background`.
    Background(String),
}

fn rgb(p: &Plugin, name: &str) -> Result<DVec3, SceneError> {
    let c = match p.param(name) {
        Some(param) if matches!(param.value, super::props::Value::Object(_)) => {
            return Err(param.at.error(format!(
                "{}: a texture for `{name}`: pathwave reads textured emitters from XML in a later version",
                p.label()
            )));
        }
        Some(_) => p.rgb_as(name, Use::Emission)?.unwrap_or(DVec3::ONE),
        None => DVec3::ONE,
    };
    if !(c.min_element() >= 0.0) {
        return Err(p.at.error(format!("{}: `{name}` has a negative component", p.label())));
    }
    Ok(c)
}

/// A top-level `<emitter>`.
pub fn convert(cx: &Converter, e: &Element) -> Result<Emitter, SceneError> {
    let p = Plugin::new(e)?;
    let out = match p.kind.as_str() {
        "point" => {
            let to_world = p.transform("to_world")?.unwrap_or_default();
            let position = match p.vector("position")? {
                Some(pos) if !to_world.is_empty() => {
                    return Err(p.at.error(format!("point light at {pos} with a to_world too: give one")));
                }
                Some(pos) => pos,
                None => placed(&to_world).0,
            };
            let intensity = rgb(&p, "intensity")?;
            p.finish(&["to_world", "position", "intensity"])?;
            Emitter::Light(format!("Point(position: {}, intensity: {})", v3(position), v3(intensity)))
        }
        "directional" => {
            let to_world = p.transform("to_world")?.unwrap_or_default();
            let direction = match p.vector("direction")? {
                Some(d) if !to_world.is_empty() => {
                    return Err(p
                        .at
                        .error(format!("directional light along {d} with a to_world too: give one")));
                }
                Some(d) => d,
                None => compose(&to_world).transform_vector3(DVec3::Z),
            };
            if !(direction.length_squared() > 0.0) {
                return Err(p.at.error("directional light: the direction is zero"));
            }
            let irradiance = rgb(&p, "irradiance")?;
            p.finish(&["to_world", "direction", "irradiance"])?;
            Emitter::Light(format!(
                "Directional(direction: {}, irradiance: {})",
                v3(direction),
                v3(irradiance)
            ))
        }
        "constant" => {
            let radiance = rgb(&p, "radiance")?;
            p.finish(&["radiance"])?;
            Emitter::Background(format!("Constant({})", v3(radiance)))
        }
        "envmap" => {
            let (name, at) = p
                .string("filename")?
                .ok_or_else(|| p.at.error("<emitter type=\"envmap\"> needs a filename"))?;
            let file = cx.file(&name, &at)?;
            let scale = p.float("scale")?.unwrap_or(1.0);
            if !(scale >= 0.0) {
                return Err(p.at.error(format!("envmap scale {scale}: expected >= 0")));
            }
            let to_world = p.transform("to_world")?.unwrap_or_default();
            let m = compose(&to_world);
            // pathwave's environment turns about +y only: the map's own axes (Mitsuba's
            // latitude-longitude convention, +y up) may turn about y and nothing else.
            let x = m.transform_vector3(DVec3::X);
            let y = m.transform_vector3(DVec3::Y);
            let z = m.transform_vector3(DVec3::Z);
            let about_y = (y - DVec3::Y).length() < 1e-6
                && x.y.abs() < 1e-6
                && (x.length() - 1.0).abs() < 1e-6
                && (z - x.cross(y)).length() < 1e-6
                && m.w_axis.truncate() == DVec3::ZERO;
            if !about_y {
                return Err(p.at.error("envmap to_world: pathwave turns environments about +y only"));
            }
            // R_y(t) takes +x to (cos t, 0, -sin t).
            let degrees = (-x.z).atan2(x.x).to_degrees();
            p.finish(&["filename", "scale", "to_world"])?;
            let mut s = format!("Environment(file: {file}, scale: {}", num(scale));
            if degrees != 0.0 {
                s += &format!(", rotate: {}", num32(degrees));
            }
            Emitter::Background(s + ")")
        }
        "area" => return Err(p.at.error("an area emitter belongs inside a <shape>")),
        k => {
            return Err(p.at.error(format!(
                "<emitter type=\"{k}\">: pathwave reads point, directional, constant and envmap here, and area inside shapes"
            )));
        }
    };
    Ok(out)
}

/// The material of a shape's `<emitter type="area">`: one-sided, as Mitsuba's.
pub fn area(e: &Element) -> Result<String, SceneError> {
    let p = Plugin::new(e)?;
    if p.kind != "area" {
        return Err(p
            .at
            .error(format!("<emitter type=\"{}\"> inside a shape: only area emitters go there", p.kind)));
    }
    let radiance = rgb(&p, "radiance")?;
    p.finish(&["radiance"])?;
    Ok(format!("DiffuseLight(emit: {}, two_sided: false)", v3(radiance)))
}
