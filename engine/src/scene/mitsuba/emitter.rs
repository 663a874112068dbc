//! `<emitter>` plugins as pathwave lights, backgrounds and emitting surfaces.

use super::convert::{Converter, num, num32, placed, v3};
use super::props::{Op, Plugin, Value, compose};
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
        Some(param) if matches!(param.value, Value::Object(_)) => {
            return Err(param.at.error(format!("{}: `{name}` is a colour here, not a texture", p.label())));
        }
        Some(_) => p.rgb_as(name, Use::Emission)?.unwrap_or(DVec3::ONE),
        None => DVec3::ONE,
    };
    if !(c.min_element() >= 0.0) {
        return Err(p.at.error(format!("{}: `{name}` has a negative component", p.label())));
    }
    Ok(c)
}

/// An emitted colour that may be a texture, as RON: `(r, g, b)` (a spectrum taken as
/// emission, default white) or a texture's name.
fn emission<'d>(cx: &mut Converter<'d>, p: &Plugin<'d>, name: &str) -> Result<String, SceneError> {
    match p.param(name).map(|param| &param.value) {
        Some(Value::Object(e)) => Ok(format!("{:?}", cx.texture(e)?)),
        _ => Ok(v3(rgb(p, name)?)),
    }
}

/// A light's origin, axis (+z) and up (+y) from its `to_world`, which must be a rotation and a
/// uniform scale (returned) before a translation: a spot or projector in pathwave is placed
/// by a point, a direction and an up.
fn rigid(p: &Plugin, to_world: &[Op]) -> Result<(DVec3, DVec3, DVec3, f64), SceneError> {
    let m = compose(to_world);
    let [x, y, z] = [DVec3::X, DVec3::Y, DVec3::Z].map(|a| m.transform_vector3(a));
    let s = x.length();
    let tol = 1e-6 * s * s;
    let rigid = s > 0.0
        && (y.length_squared() - s * s).abs() <= tol
        && (z.length_squared() - s * s).abs() <= tol
        && x.dot(y).abs() <= tol
        && y.dot(z).abs() <= tol
        && z.dot(x).abs() <= tol
        && x.cross(y).dot(z) > 0.0
        && m.row(3) == glam::DVec4::W;
    if !rigid {
        return Err(p.at.error(format!(
            "{}: pathwave places this light by a rotation, a uniform scale and a translation (its to_world has a shear, an uneven scale or a mirror)",
            p.label()
        )));
    }
    Ok((m.transform_point3(DVec3::ZERO), z, y, s))
}

/// A top-level `<emitter>`.
pub fn convert<'d>(cx: &mut Converter<'d>, e: &'d Element) -> Result<Emitter, SceneError> {
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
        // Mitsuba's spot (`src/emitters/spot.cpp`): intensity linear in the angle from
        // beam_width to cutoff_angle, an optional texture over the cone.
        "spot" => {
            let to_world = p.transform("to_world")?.unwrap_or_default();
            let (position, axis, up, _) = rigid(&p, &to_world)?;
            if let Some(param) = p.param("intensity")
                && matches!(param.value, Value::Object(_))
            {
                return Err(param.at.error(format!("{}: `intensity` is a colour, not a texture", p.label())));
            }
            let intensity = rgb(&p, "intensity")?;
            let cutoff = p.float("cutoff_angle")?.unwrap_or(20.0);
            let beam = p.float("beam_width")?.unwrap_or(0.75 * cutoff);
            let texture = match p.param("texture") {
                None => None,
                Some(param) => match &param.value {
                    Value::Object(t) => Some(cx.texture(t)?),
                    _ => {
                        return Err(param.at.error(format!(
                            "{}: `texture` is a <texture> (Mitsuba requires one that varies)",
                            p.label()
                        )));
                    }
                },
            };
            p.finish(&["to_world", "intensity", "cutoff_angle", "beam_width", "texture"])?;
            let mut s = format!(
                "Spot(position: {}, look_at: {}, intensity: {}, cone_angle: {}, falloff_start: {}, falloff: Linear",
                v3(position),
                v3(position + axis),
                v3(intensity),
                num(cutoff),
                num(beam)
            );
            if let Some(t) = texture {
                s += &format!(", texture: {t:?}, up: {}", v3(up));
            }
            Emitter::Light(s + ")")
        }
        // Mitsuba's projector (`src/emitters/projector.cpp`). Its intensity grows with a
        // uniform scale in `to_world` (it divides by the local depth squared and the length
        // of the scaled axis): the scale goes into `scale`.
        "projector" => {
            let to_world = p.transform("to_world")?.unwrap_or_default();
            let (position, axis, up, size) = rigid(&p, &to_world)?;
            let irradiance = emission(cx, &p, "irradiance")?;
            let scale = p.float("scale")?.unwrap_or(1.0);
            if !(scale >= 0.0) {
                return Err(p.at.error(format!("{}: scale {scale}: expected >= 0", p.label())));
            }
            let (fov, axis_name) = super::sensor::perspective_fov(&p)?;
            p.finish(&["to_world", "irradiance", "scale", "fov", "focal_length", "fov_axis"])?;
            Emitter::Light(format!(
                "Projector(position: {}, look_at: {}, up: {}, fov: {}, fov_axis: {axis_name}, irradiance: {irradiance}, scale: {})",
                v3(position),
                v3(position + axis),
                v3(up),
                num32(fov),
                num(scale * size)
            ))
        }
        "area" => return Err(p.at.error("an area emitter belongs inside a <shape>")),
        k => {
            return Err(p.at.error(format!(
                "<emitter type=\"{k}\">: pathwave reads point, spot, projector, directional, constant and envmap here, and area inside shapes"
            )));
        }
    };
    Ok(out)
}

/// The radiance of a shape's `<emitter type="area">` (`src/emitters/area.cpp`; one-sided), as
/// RON: a colour or a texture's name.
pub fn area<'d>(cx: &mut Converter<'d>, e: &'d Element) -> Result<String, SceneError> {
    let p = Plugin::new(e)?;
    if p.kind != "area" {
        return Err(p
            .at
            .error(format!("<emitter type=\"{}\"> inside a shape: only area emitters go there", p.kind)));
    }
    let radiance = emission(cx, &p, "radiance")?;
    p.finish(&["radiance"])?;
    Ok(radiance)
}
