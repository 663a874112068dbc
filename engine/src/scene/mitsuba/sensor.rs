//! `<sensor>` with its `<film>`, `<rfilter>` and `<sampler>` as pathwave's `camera` and
//! `render` fields. Mitsuba 3's defaults (its plugin reference, mitsuba.readthedocs.io, and
//! mitsuba3 `src/sensors/perspective.cpp`, `thinlens.cpp`, `orthographic.cpp`): `fov_axis` x,
//! a 50 mm focal length, `near_clip` 0.01 and `far_clip` 10000, hdrfilm 768 x 576 with a
//! gaussian filter.

use super::convert::{Converter, num, num32, ops};
use super::props::Plugin;
use super::xml::{At, Element};
use crate::scene::SceneError;

impl Converter<'_> {
    /// `<sensor>`: the camera, with its `<film>` and `<sampler>`.
    pub(super) fn sensor(&mut self, e: &Element) -> Result<(), SceneError> {
        if self.out.camera.is_some() {
            return Err(e.at.error("a second <sensor>: pathwave renders one camera"));
        }
        let p = Plugin::new(e)?;
        let to_world = p.transform("to_world")?.unwrap_or_default();
        let mut fields = vec![format!("to_world: {}", ops(&to_world))];
        let mut reads =
            vec!["to_world", "near_clip", "far_clip", "shutter_open", "shutter_close", "film", "sampler"];
        match p.kind.as_str() {
            "perspective" | "thinlens" => {
                // Mitsuba's `parse_fov`: a focal length (default 50 mm) is 35 mm film
                // equivalent, and gives the field of view along the 36 x 24 mm diagonal.
                let diagonal = |mm: f64| 2.0 * (36.0f64.hypot(24.0) / (2.0 * mm)).atan().to_degrees();
                let (fov, axis) = match (p.float("fov")?, p.string("focal_length")?) {
                    (Some(f), None) => {
                        let axis = match p.string("fov_axis")? {
                            None => "X",
                            Some((a, at)) => match a.to_ascii_lowercase().as_str() {
                                "x" => "X",
                                "y" => "Y",
                                "diagonal" => "Diagonal",
                                "smaller" => "Smaller",
                                "larger" => "Larger",
                                _ => {
                                    return Err(at.error(format!(
                                        "fov_axis \"{a}\": expected x, y, diagonal, smaller or larger"
                                    )));
                                }
                            },
                        };
                        (f, axis)
                    }
                    (None, Some((f, at))) => {
                        let mm = f
                            .trim()
                            .strip_suffix("mm")
                            .unwrap_or(&f)
                            .trim()
                            .parse::<f64>()
                            .ok()
                            .filter(|v| *v > 0.0);
                        let mm = mm.ok_or_else(|| {
                            at.error(format!("focal_length \"{f}\" is not a length like \"50mm\""))
                        })?;
                        (diagonal(mm), "Diagonal")
                    }
                    (None, None) => (diagonal(50.0), "Diagonal"),
                    (Some(_), Some((_, at))) => return Err(at.error("give fov or focal_length, not both")),
                };
                fields.push(format!("projection: Perspective(fov: {}, fov_axis: {axis})", num32(fov)));
                reads.extend(["fov", "focal_length", "fov_axis"]);
            }
            "orthographic" => fields.push("projection: Orthographic".into()),
            k => {
                return Err(p.at.error(format!(
                    "<sensor type=\"{k}\">: pathwave's cameras are perspective, thinlens and orthographic"
                )));
            }
        }
        // Mitsuba always clips (its defaults 0.01 and 10000), so the camera always gets both.
        let near = p.float("near_clip")?.unwrap_or(0.01);
        let far = p.float("far_clip")?.unwrap_or(10000.0);
        if !(near > 0.0 && far > near) {
            return Err(p.at.error(format!("near_clip {near} and far_clip {far}: need 0 < near < far")));
        }
        if p.kind == "thinlens" {
            // Mitsuba requires the aperture (0 is its pinhole), and focuses at far_clip unless
            // told otherwise (`Sensor`'s constructor in src/render/sensor.cpp; its plugin
            // documentation says 0).
            let r = p
                .float("aperture_radius")?
                .ok_or_else(|| p.at.error("<sensor type=\"thinlens\"> needs an aperture_radius"))?;
            let f = p.float("focus_distance")?.unwrap_or(far);
            fields.push(format!("aperture_radius: {}", num(r)));
            fields.push(format!("focus_dist: {}", num(f)));
            reads.extend(["aperture_radius", "focus_distance"]);
        }
        fields.push(format!("near_clip: {}, far_clip: {}", num(near), num(far)));
        let open = p.float("shutter_open")?.unwrap_or(0.0);
        let close = p.float("shutter_close")?.unwrap_or(0.0);
        if (open, close) != (0.0, 0.0) {
            fields.push(format!("shutter: ({}, {})", num(open), num(close)));
        }
        let mut film = None;
        let mut sampler = None;
        for c in p.unnamed() {
            match c.tag.as_str() {
                "film" => film = Some(c),
                "sampler" => sampler = Some(c),
                t => {
                    return Err(c.at.error(format!(
                        "<{t}> inside a <sensor>: pathwave reads <film> and <sampler> there"
                    )));
                }
            }
        }
        p.finish(&reads)?;
        self.film(film, &p.at)?;
        if let Some(s) = sampler {
            self.sampler(s)?;
        }
        self.out.camera = Some((format!("({})", fields.join(", ")), p.at.clone()));
        Ok(())
    }

    fn film(&mut self, e: Option<&Element>, sensor: &At) -> Result<(), SceneError> {
        let Some(e) = e else {
            return Err(sensor.error("the <sensor> has no <film>: pathwave needs its size"));
        };
        let p = Plugin::new(e)?;
        if p.kind != "hdrfilm" {
            return Err(p.at.error(format!("<film type=\"{}\">: pathwave's film is hdrfilm", p.kind)));
        }
        let w = p.int("width")?.unwrap_or(768);
        let h = p.int("height")?.unwrap_or(576);
        for (n, v) in [("width", w), ("height", h)] {
            if !(1..=65536).contains(&v) {
                return Err(p.at.error(format!("film {n} {v}: expected 1 to 65536")));
            }
        }
        // The output's format is pathwave's choice (the file's extension); these leave the
        // pixels' values alone.
        for n in ["file_format", "component_format"] {
            p.string(n)?;
        }
        if let Some((f, at)) = p.string("pixel_format")?
            && !matches!(f.as_str(), "rgb" | "rgba")
        {
            return Err(at.error(format!("pixel_format \"{f}\": pathwave writes rgb")));
        }
        if p.bool("sample_border")?.unwrap_or(false) {
            return Err(p.at.error(
                "sample_border: pathwave's filters keep each pixel's samples in reach of that pixel",
            ));
        }
        let mut filter = "Gaussian(stddev: 0.5)".to_owned();
        for c in p.unnamed() {
            if c.tag != "rfilter" {
                return Err(c
                    .at
                    .error(format!("<{}> inside a <film>: pathwave reads <rfilter> there", c.tag)));
            }
            filter = rfilter(c)?;
        }
        p.finish(&[
            "width",
            "height",
            "file_format",
            "component_format",
            "pixel_format",
            "sample_border",
            "rfilter",
        ])?;
        self.out.render.push(("width".into(), w.to_string()));
        self.out.render.push(("height".into(), h.to_string()));
        self.out.render.push(("filter".into(), filter));
        Ok(())
    }

    fn sampler(&mut self, e: &Element) -> Result<(), SceneError> {
        let p = Plugin::new(e)?;
        // Every Mitsuba sampler draws unbiased pixel samples; pathwave draws its own (the
        // render's `sampler`), which changes the noise but not the image it converges to.
        if !matches!(
            p.kind.as_str(),
            "independent" | "stratified" | "multijitter" | "orthogonal" | "ldsampler"
        ) {
            return Err(p
                .at
                .error(format!("<sampler type=\"{}\"> is not one of Mitsuba's samplers", p.kind)));
        }
        let spp = p.int("sample_count")?.unwrap_or(4);
        if !(1..=1 << 24).contains(&spp) {
            return Err(p.at.error(format!("sample_count {spp}: expected 1 to {}", 1 << 24)));
        }
        let seed = p.int("seed")?;
        p.int("dimension")?;
        p.bool("jitter")?;
        p.finish(&["sample_count", "seed", "dimension", "jitter"])?;
        self.out.render.push(("spp".into(), spp.to_string()));
        if let Some(s) = seed {
            self.out.render.push(("seed".into(), s.max(0).to_string()));
        }
        Ok(())
    }
}

/// `<rfilter>` as pathwave's pixel filter.
fn rfilter(e: &Element) -> Result<String, SceneError> {
    let p = Plugin::new(e)?;
    let out = match p.kind.as_str() {
        "box" => "Box".to_owned(),
        "tent" => {
            let r = p.float("radius")?.unwrap_or(1.0);
            if !(r > 0.0 && r <= 16.0) {
                return Err(p.at.error(format!("tent radius {r}: expected (0, 16]")));
            }
            format!("Tent(radius: {})", num(r))
        }
        "gaussian" => {
            let s = p.float("stddev")?.unwrap_or(0.5);
            if !(s > 0.0 && s <= 4.0) {
                return Err(p.at.error(format!("gaussian stddev {s}: expected (0, 4]")));
            }
            format!("Gaussian(stddev: {})", num(s))
        }
        k => {
            return Err(p
                .at
                .error(format!("<rfilter type=\"{k}\">: pathwave's filters are box, tent and gaussian")));
        }
    };
    p.finish(&["radius", "stddev"])?;
    Ok(out)
}
