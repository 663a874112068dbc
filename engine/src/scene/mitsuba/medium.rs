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
//! an `isotropic` phase function (the default) or `hg` (Henyey-Greenstein's).
//!
//! Its `heterogeneous` medium (`src/media/heterogeneous.cpp`) takes `sigma_t` from a
//! `gridvolume` (`src/volumes/grid.cpp`: a `.vol` file filling the unit cube of its `to_world`,
//! or with `use_grid_bbox` the box the file gives) and exists only in that volume's bounding
//! box; `albedo` is a constant or a grid too. They become a medium's `grid` and `albedo_grid`,
//! placed in the object's space (the shape's `to_world` undone). Mitsuba bounds the medium by
//! the world-axis box around a rotated grid, pathwave by the grid's own cube: the two agree
//! for grids that are only scaled and moved. A `gridvolume` may also name an OpenVDB file
//! (told by its first bytes or `.vdb`; Mitsuba reads only `.vol`): its float grid "density",
//! placed by the file's own transform and then by `to_world`, as a RON medium's VDB grid.

use super::convert::{Converter, num, ops, v3};
use super::props::{Op, Plugin, Value, compose};
use super::spectrum::Use;
use super::xml::Element;
use crate::scene::SceneError;
use glam::{DMat4, DVec3};

/// A `<medium>` as the RON of an object's `medium: (density: .., albedo: ..)`, inside a shape
/// placed by `to_world`.
pub fn convert(cx: &Converter, e: &Element, to_world: &[Op]) -> Result<String, SceneError> {
    let p = Plugin::new(e)?;
    let (sigma_t, albedo, grids) = match p.kind.as_str() {
        "homogeneous" => {
            let sigma_t = p.rgb_as("sigma_t", Use::Unbounded)?.unwrap_or(DVec3::ONE);
            (sigma_t, p.rgb("albedo")?.unwrap_or(DVec3::splat(0.75)), String::new())
        }
        "heterogeneous" => heterogeneous(cx, &p, to_world)?,
        k => {
            return Err(p.at.error(format!(
                "<medium type=\"{k}\">: pathwave reads homogeneous and heterogeneous media"
            )));
        }
    };
    let scale = p.float("scale")?.unwrap_or(1.0);
    // Both only change how Mitsuba samples, not what it renders: pathwave always samples
    // lights from media, and samples coloured extinction by spectral MIS.
    p.bool("sample_emitters")?;
    p.bool("has_spectral_extinction")?;
    let mut phase_ron = String::new();
    for c in p.unnamed() {
        let phase = Plugin::new(c)?;
        match (c.tag.as_str(), phase.kind.as_str()) {
            ("phase", "isotropic") => phase.finish(&[])?,
            // Mitsuba's `hg` (`src/phase/hg.cpp`): g by default 0.8.
            ("phase", "hg") => {
                let g = phase.float("g")?.unwrap_or(0.8);
                if !(g.abs() < 1.0) {
                    return Err(phase
                        .at
                        .error(format!("<phase type=\"hg\">: g {g}: expected a number in (-1, 1)")));
                }
                phase.finish(&["g"])?;
                phase_ron = format!(", phase: HenyeyGreenstein(g: {})", num(g));
            }
            ("phase", k) => {
                return Err(phase.at.error(format!(
                    "<phase type=\"{k}\">: pathwave reads the isotropic and hg phase functions"
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
    Ok(format!("(density: {density}, albedo: {}{grids}{phase_ron})", v3(albedo)))
}

/// A heterogeneous medium's `sigma_t` (one, scaled by the grid), `albedo` and the RON of its
/// grids (`, grid: (..)` and `, albedo_grid: (..)`).
fn heterogeneous(cx: &Converter, p: &Plugin, to_world: &[Op]) -> Result<(DVec3, DVec3, String), SceneError> {
    let object_from_world = compose(to_world).inverse();
    let volume = |name: &str| match p.param(name) {
        Some(param) => match &param.value {
            Value::Object(e) => cx.by_id(e).map(Some),
            _ => Ok(None),
        },
        None => Ok(None),
    };
    let Some(sigma_t) = volume("sigma_t")? else {
        return Err(p.at.error(format!(
            "{}: pathwave reads a heterogeneous medium's sigma_t from a <volume type=\"gridvolume\"> (Mitsuba bounds one of constant sigma_t by the unit cube; write a homogeneous medium for a constant one)",
            p.label()
        )));
    };
    let (density, channels) = grid(cx, sigma_t, object_from_world)?;
    if channels != 1 {
        return Err(sigma_t.at.error(format!(
            "a sigma_t grid of {channels} channels: pathwave's grid media have one density in every channel"
        )));
    }
    let mut ron = format!(", grid: {density}");
    let albedo = match volume("albedo")? {
        Some(e) => {
            ron += &format!(", albedo_grid: {}", grid(cx, e, object_from_world)?.0);
            DVec3::ONE
        }
        None => p.rgb("albedo")?.unwrap_or(DVec3::splat(0.75)),
    };
    Ok((DVec3::ONE, albedo, ron))
}

/// A `<volume type="gridvolume">` as the RON of a medium's grid in the object's space
/// (`object_from_world`), and its channel count.
fn grid(cx: &Converter, e: &Element, object_from_world: DMat4) -> Result<(String, usize), SceneError> {
    let g = Plugin::new(e)?;
    if e.tag != "volume" || !matches!(g.kind.as_str(), "gridvolume" | "grid") {
        return Err(e.at.error(format!("{}: a medium's grid is a <volume type=\"gridvolume\">", g.label())));
    }
    let (name, at) =
        g.string("filename")?.ok_or_else(|| g.at.error(format!("{} needs a filename", g.label())))?;
    for (param, only) in [("filter_type", "trilinear"), ("wrap_mode", "clamp")] {
        if let Some((v, at)) = g.string(param)?
            && v != only
        {
            return Err(at.error(format!("{param} \"{v}\": pathwave's grids are read with \"{only}\"")));
        }
    }
    // Spectral upsampling and GPU texture units: neither changes an RGB render.
    g.bool("raw")?;
    g.bool("accel")?;
    let path = cx.resolve(&name, &at)?;
    let header = read_header(&path).map_err(|why| at.error(why))?;
    let mut grid_to_world = compose(&g.transform("to_world")?.unwrap_or_default());
    if g.bool("use_grid_bbox")?.unwrap_or(false) {
        let Some(header) = header else {
            return Err(g.at.error(format!(
                "{}: use_grid_bbox with the OpenVDB file {name}: its grid is placed by the file's own transform",
                g.label()
            )));
        };
        let (lo, hi) = header.bbox;
        let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
        grid_to_world *= DMat4::from_translation(lo) * DMat4::from_scale(hi - lo);
    }
    g.finish(&["filename", "to_world", "use_grid_bbox", "filter_type", "wrap_mode", "raw", "accel"])?;
    let m = object_from_world * grid_to_world;
    let rows = m.transpose().to_cols_array_2d();
    let file = cx.file(&name, &at)?;
    // An OpenVDB file's grid is one float channel.
    let channels = header.map_or(1, |h| h.channels);
    Ok((format!("(file: {file}, transform: {})", ops(&[Op::Matrix(rows)])), channels))
}

/// The header of the `.vol` file at `path`, or `None` for an OpenVDB file (whose header is
/// checked).
fn read_header(path: &std::path::Path) -> Result<Option<crate::format::vol::VolHeader>, String> {
    use crate::format::{files, vdb, vol};
    let n = vol::HEADER_BYTES.max(vdb::HEADER_BYTES);
    let (bytes, _) = files::read_head(path, n, files::MAX_ASSET_BYTES, "grid")?;
    let named_vdb = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("vdb"));
    if vdb::is_vdb(&bytes) || named_vdb {
        return vdb::VdbFile::check_header(&bytes, path).map(|()| None);
    }
    vol::VolHeader::parse(&bytes, path, "grid").map(Some)
}
