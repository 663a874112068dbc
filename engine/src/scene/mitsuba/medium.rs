//! `<medium>` plugins as pathwave media, and what a shape's `interior` and `exterior` can mean
//! in pathwave.
//!
//! pathwave's media fill the inside of closed shapes, found along each ray by intervals (see
//! `crate::media`): a shape's `interior` medium becomes a volume of the same boundary, beside
//! the shape's surface (or alone, for Mitsuba's `null` BSDF, an invisible boundary). What lies
//! outside a shape is whatever volumes cover that space, so a shape cannot have an `exterior`
//! medium of its own: Mitsuba's `exterior` is refused. Where it names the medium that
//! surrounds the shape anyway (an object inside a volume), leaving it out renders the same.
//!
//! Mitsuba's `homogeneous` medium (`src/media/homogeneous.cpp`): extinction `sigma_t` (by
//! default 1) times `scale` (by default 1), single-scattering `albedo` (by default 0.75), and
//! an `isotropic` phase function (the default).

use super::convert::{num, v3};
use super::props::Plugin;
use super::spectrum::Use;
use super::xml::Element;
use crate::scene::SceneError;
use glam::DVec3;

/// A `<medium>` as the RON of an object's `medium: (density: .., albedo: ..)`.
pub fn convert(e: &Element) -> Result<String, SceneError> {
    let p = Plugin::new(e)?;
    if p.kind != "homogeneous" {
        return Err(p.at.error(format!(
            "<medium type=\"{}\">: pathwave reads homogeneous media (grid and other heterogeneous media come in a later version)",
            p.kind
        )));
    }
    let sigma_t = p.rgb_as("sigma_t", Use::Unbounded)?.unwrap_or(DVec3::ONE);
    let albedo = p.rgb("albedo")?.unwrap_or(DVec3::splat(0.75));
    let scale = p.float("scale")?.unwrap_or(1.0);
    // Both only change how Mitsuba samples, not what it renders: pathwave always samples
    // lights from media, and samples coloured extinction by spectral MIS.
    p.bool("sample_emitters")?;
    p.bool("has_spectral_extinction")?;
    for c in p.unnamed() {
        let phase = Plugin::new(c)?;
        match (c.tag.as_str(), phase.kind.as_str()) {
            ("phase", "isotropic") => phase.finish(&[])?,
            ("phase", k) => {
                return Err(phase.at.error(format!(
                    "<phase type=\"{k}\">: pathwave's media scatter isotropically (it reads the isotropic phase function)"
                )));
            }
            (t, _) => return Err(c.at.error(format!("<{t}> inside a <medium>: it holds a <phase>"))),
        }
    }
    if let Some(param) = p.param("phase") {
        return Err(param.at.error("the phase function is an unnamed <phase> inside the <medium>"));
    }
    p.finish(&["sigma_t", "albedo", "scale", "sample_emitters", "has_spectral_extinction"])?;
    let density = sigma_t * scale;
    if !(density.min_element() >= 0.0 && density.max_element() > 0.0) {
        return Err(p.at.error(format!(
            "{}: sigma_t times scale is {density}: pathwave needs every channel >= 0 and one > 0",
            p.label()
        )));
    }
    if !(albedo.min_element() >= 0.0 && albedo.max_element() <= 1.0) {
        return Err(p.at.error(format!("{}: albedo {albedo}: expected components in [0, 1]", p.label())));
    }
    let density = match density.x == density.y && density.y == density.z {
        true => num(density.x),
        false => v3(density),
    };
    Ok(format!("(density: {density}, albedo: {})", v3(albedo)))
}
