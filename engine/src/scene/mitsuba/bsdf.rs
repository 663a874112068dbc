//! `<bsdf>` plugins as pathwave materials.
//!
//! Mitsuba's BSDFs other than `twosided` are one-sided (black seen from behind): `diffuse`
//! becomes a Lambertian with `two_sided: false`, and `twosided` around it the two-sided
//! Lambertian. Its conductors and plastics are one-sided as pathwave's, and its dielectrics the
//! same on both sides in both renderers.

use super::conductors::CONDUCTORS;
use super::convert::{Converter, num, num32, v3};
use super::props::{Plugin, Value};
use super::spectrum::Use;
use super::xml::{At, Element};
use crate::scene::SceneError;
use glam::DVec3;

/// A colour parameter as RON: `(r, g, b)` or a texture's name.
fn color<'d>(
    cx: &mut Converter<'d>,
    p: &Plugin<'d>,
    name: &str,
    default: DVec3,
) -> Result<String, SceneError> {
    match p.param(name) {
        None => Ok(v3(default)),
        Some(param) => match &param.value {
            Value::Rgb(_) | Value::Spectrum(_) | Value::Float(_) => Ok(v3(p.rgb(name)?.unwrap_or(default))),
            Value::Object(e) => Ok(format!("{:?}", cx.texture(e)?)),
            _ => Err(param.at.error(format!("{}: `{name}` is a colour or a texture", p.label()))),
        },
    }
}

/// A wrapper's opacity or weight as RON: a number in [0, 1] (`default` when absent, or an
/// error naming the parameter when `None`) or a texture's name.
fn amount<'d>(
    cx: &mut Converter<'d>,
    p: &Plugin<'d>,
    name: &str,
    default: Option<f64>,
) -> Result<String, SceneError> {
    let Some(param) = p.param(name) else {
        return match default {
            Some(d) => Ok(num(d)),
            None => Err(p.at.error(format!("{}: `{name}` is required", p.label()))),
        };
    };
    match &param.value {
        Value::Object(e) => Ok(format!("{:?}", cx.texture(e)?)),
        _ => match p.float(name)? {
            Some(v) if (0.0..=1.0).contains(&v) => Ok(num(v)),
            _ => Err(param.at.error(format!("{}: `{name}` is a number in [0, 1] or a texture", p.label()))),
        },
    }
}

/// The names of the materials that the BSDFs nested in a wrapper become (`count` of them),
/// each made two-sided where `two_sided` (the wrapper is inside a `twosided`).
fn nested<'d>(
    cx: &mut Converter<'d>,
    p: &Plugin<'d>,
    count: usize,
    two_sided: bool,
) -> Result<Vec<String>, SceneError> {
    let inner: Vec<&Element> = p.unnamed().collect();
    if inner.len() != count {
        return Err(p.at.error(format!("{} holds {count} BSDF(s), not {}", p.label(), inner.len())));
    }
    inner.into_iter().map(|e| if two_sided { cx.two_sided_material(e) } else { cx.material(e) }).collect()
}

/// Mitsuba's `mask` (`src/bsdfs/mask.cpp`): an opacity (default 0.5) around one BSDF, as
/// `Mask`; its BSDF two-sided where `two_sided`.
fn mask<'d>(cx: &mut Converter<'d>, p: &Plugin<'d>, two_sided: bool) -> Result<String, SceneError> {
    let opacity = amount(cx, p, "opacity", Some(0.5))?;
    let [inner] = nested(cx, p, 1, two_sided)?.try_into().expect("one");
    p.finish(&["opacity"])?;
    Ok(format!("Mask(opacity: {opacity}, material: {inner:?})"))
}

/// Mitsuba's `blendbsdf` (`src/bsdfs/blendbsdf.cpp`): `(1 - weight) first + weight second`, as
/// `Blend`; its BSDFs two-sided where `two_sided`.
fn blend<'d>(cx: &mut Converter<'d>, p: &Plugin<'d>, two_sided: bool) -> Result<String, SceneError> {
    let weight = amount(cx, p, "weight", None)?;
    let [a, b] = nested(cx, p, 2, two_sided)?.try_into().expect("two");
    p.finish(&["weight"])?;
    Ok(format!("Blend(weight: {weight}, materials: ({a:?}, {b:?}))"))
}

/// Mitsuba's `bumpmap` (`src/bsdfs/bumpmap.cpp`): the one texture it is given, under
/// whatever name, read as heights times `scale` (default 1), around one BSDF, as `Bump`.
fn bump<'d>(cx: &mut Converter<'d>, p: &Plugin<'d>, two_sided: bool) -> Result<String, SceneError> {
    let textures: Vec<String> =
        p.params.iter().filter(|q| matches!(q.value, Value::Object(_))).map(|q| q.name.clone()).collect();
    let [name] = textures.as_slice() else {
        return Err(p.at.error(format!("{} takes one texture, not {}", p.label(), textures.len())));
    };
    let Some(Value::Object(e)) = p.param(name).map(|q| &q.value) else { unreachable!("found above") };
    let heights = cx.texture(e)?;
    let scale = p.float("scale")?.unwrap_or(1.0);
    if !scale.is_finite() {
        let at = p.param("scale").map_or(&p.at, |q| &q.at);
        return Err(at.error(format!("{}: scale {scale}: expected a finite number", p.label())));
    }
    let flip = map_options(p)?;
    let [inner] = nested(cx, p, 1, two_sided)?.try_into().expect("one");
    p.finish(&[name, "scale", "flip_invalid_normals", "use_shadowing_function"])?;
    Ok(format!(
        "Bump(texture: {heights:?}, scale: {}, material: {inner:?}, flip_invalid_normals: {flip})",
        num(scale)
    ))
}

/// Mitsuba's `normalmap` (`src/bsdfs/normalmap.cpp`): the texture `normalmap` around one
/// BSDF, as `NormalMap`.
fn normal_map<'d>(cx: &mut Converter<'d>, p: &Plugin<'d>, two_sided: bool) -> Result<String, SceneError> {
    let Some(Value::Object(e)) = p.param("normalmap").map(|q| &q.value) else {
        return Err(p.at.error(format!("{} needs a texture named normalmap", p.label())));
    };
    let normals = cx.texture(e)?;
    let flip = map_options(p)?;
    let [inner] = nested(cx, p, 1, two_sided)?.try_into().expect("one");
    p.finish(&["normalmap", "flip_invalid_normals", "use_shadowing_function"])?;
    Ok(format!("NormalMap(texture: {normals:?}, material: {inner:?}, flip_invalid_normals: {flip})"))
}

/// A map's `flip_invalid_normals` (default true); its `use_shadowing_function` must be true
/// (pathwave always shadows the terminator).
fn map_options(p: &Plugin) -> Result<bool, SceneError> {
    if p.bool("use_shadowing_function")? == Some(false) {
        let at = p.param("use_shadowing_function").map_or(&p.at, |q| &q.at);
        return Err(at.error(format!(
            "{}: use_shadowing_function false: pathwave's maps always shadow the terminator",
            p.label()
        )));
    }
    Ok(p.bool("flip_invalid_normals")?.unwrap_or(true))
}

/// The material that the BSDF `one` becomes inside Mitsuba's `twosided` (the same on both
/// sides): a two-sided Lambertian, plastic or conductor, and a mask or blend of such.
pub fn two_sided<'d>(cx: &mut Converter<'d>, one: &'d Element) -> Result<String, SceneError> {
    let one = cx.by_id(one)?;
    let inner = Plugin::new(one)?;
    match inner.kind.as_str() {
        "diffuse" => diffuse(cx, &inner, true),
        "plastic" | "roughplastic" => plastic(cx, &inner, true),
        // pathwave's conductors are one-sided as Mitsuba's; `two_sided` makes them what
        // `twosided` makes Mitsuba's.
        "conductor" | "roughconductor" => {
            let inner = convert(cx, one)?;
            match inner.strip_suffix(')') {
                Some(head) => Ok(format!("{head}, two_sided: true)")),
                None => Err(one.at.error(format!("twosided: cannot extend {inner}"))),
            }
        }
        // A wrapper the same on both sides wraps materials the same on both sides.
        "mask" => mask(cx, &inner, true),
        "blendbsdf" => blend(cx, &inner, true),
        "bumpmap" => bump(cx, &inner, true),
        "normalmap" => normal_map(cx, &inner, true),
        k => Err(one.at.error(format!(
            "twosided around \"{k}\": pathwave reads twosided around diffuse, conductor, roughconductor, plastic, roughplastic, mask, blendbsdf, bumpmap and normalmap"
        ))),
    }
}

/// A roughness parameter as RON: a number in [0, 1] or a texture's name (Mitsuba's float
/// textures). `None` when not written.
fn roughness<'d>(cx: &mut Converter<'d>, p: &Plugin<'d>, name: &str) -> Result<Option<String>, SceneError> {
    let Some(param) = p.param(name) else { return Ok(None) };
    match &param.value {
        Value::Object(e) => Ok(Some(format!("{:?}", cx.float_texture(e)?))),
        _ => {
            let a = p.float(name)?.unwrap_or_default();
            if !(0.0..=1.0).contains(&a) {
                return Err(param.at.error(format!("{}: {name} {a}: pathwave takes 0 to 1", p.label())));
            }
            Ok(Some(num(a)))
        }
    }
}

/// What a kind's RON takes of the microfacet parameters.
#[derive(Clone, Copy, PartialEq)]
enum Takes {
    /// One number.
    Number,
    /// A number or a texture.
    Textured,
    /// A number or a texture, and `alpha_v` beside `alpha` (anisotropic).
    Anisotropic,
}

/// The microfacet parameters of the rough BSDFs as RON fields, `alpha: A, distribution: D`
/// or `alpha: U, alpha_v: V, distribution: D`, read as Mitsuba's `MicrofacetDistribution`
/// reads them: the distribution `beckmann` (its default) or `ggx`, and `alpha` (default 0.1)
/// or both `alpha_u` and `alpha_v`. A kind that `takes` only a number refuses textures and
/// unequal `alpha_u` and `alpha_v`.
fn microfacet<'d>(cx: &mut Converter<'d>, p: &Plugin<'d>, takes: Takes) -> Result<String, SceneError> {
    let distribution = match p.string("distribution")? {
        None => "Beckmann",
        Some((d, at)) => match d.to_lowercase().as_str() {
            "beckmann" => "Beckmann",
            "ggx" => "Ggx",
            _ => {
                return Err(at.error(format!(
                    "distribution \"{d}\": Mitsuba and pathwave read \"beckmann\" and \"ggx\""
                )));
            }
        },
    };
    // Visible-normal sampling is how pathwave samples both; Mitsuba's switch changes only noise.
    p.bool("sample_visible")?;
    if takes == Takes::Number {
        for name in ["alpha", "alpha_u", "alpha_v"] {
            if let Some(param) = p.param(name)
                && matches!(param.value, Value::Object(_))
            {
                return Err(param.at.error(format!(
                    "{}: a textured {name}: pathwave's {} takes a number",
                    p.label(),
                    p.kind
                )));
            }
        }
    }
    let (alpha_u, alpha_v) = (roughness(cx, p, "alpha_u")?, roughness(cx, p, "alpha_v")?);
    let fields = match (roughness(cx, p, "alpha")?, alpha_u, alpha_v) {
        (a, None, None) => format!("alpha: {}", a.unwrap_or_else(|| num(0.1))),
        (Some(_), _, _) => {
            return Err(p.at.error(format!("{}: give either alpha or alpha_u and alpha_v", p.label())));
        }
        (None, Some(u), Some(v)) if u == v => format!("alpha: {u}"),
        (None, Some(u), Some(v)) if takes == Takes::Anisotropic => format!("alpha: {u}, alpha_v: {v}"),
        (None, Some(u), Some(v)) => {
            let at = p.param("alpha_v").map_or(&p.at, |param| &param.at);
            return Err(at.error(format!(
                "{}: anisotropic roughness (alpha_u {u}, alpha_v {v}): pathwave's {} is isotropic; give one alpha",
                p.label(),
                p.kind
            )));
        }
        (None, _, _) => {
            return Err(p.at.error(format!("{}: alpha_u and alpha_v go together", p.label())));
        }
    };
    Ok(format!("{fields}, distribution: {distribution}"))
}

/// The RGB `eta` and `k` of one of Mitsuba's named conductors ([`CONDUCTORS`]).
fn named_conductor(name: &str, at: &At) -> Result<(Option<DVec3>, Option<DVec3>), SceneError> {
    let Some((_, eta, k)) = CONDUCTORS.iter().find(|(n, ..)| *n == name) else {
        let known: Vec<&str> = CONDUCTORS.iter().map(|(n, ..)| *n).collect();
        return Err(at.error(format!(
            "material \"{name}\" is not one of Mitsuba's named conductors ({}, or none)",
            known.join(", ")
        )));
    };
    let (eta, k) = (DVec3::from(eta.map(f64::from)), DVec3::from(k.map(f64::from)));
    if eta.min_element() <= 0.0 {
        return Err(at.error(format!(
            "material \"{name}\": Mitsuba's RGB for its eta is ({}, {}, {}), and pathwave takes an eta > 0 in each channel",
            eta.x, eta.y, eta.z
        )));
    }
    Ok((Some(eta), Some(k)))
}

fn unit_scale(p: &Plugin, name: &str) -> Result<(), SceneError> {
    match p.rgb(name)? {
        None => Ok(()),
        Some(c) if c == DVec3::ONE => Ok(()),
        Some(_) => Err(p.at.error(format!("{}: `{name}` other than 1 is not in pathwave yet", p.label()))),
    }
}

/// Mitsuba's `diffuse` (`src/bsdfs/diffuse.cpp`) as a Lambertian: one-sided, or both sides
/// alike inside `twosided` (the RON default).
fn diffuse<'d>(cx: &mut Converter<'d>, p: &Plugin<'d>, two_sided: bool) -> Result<String, SceneError> {
    let albedo = color(cx, p, "reflectance", DVec3::splat(0.5))?;
    p.finish(&["reflectance"])?;
    Ok(match two_sided {
        true => format!("Lambertian(albedo: {albedo})"),
        false => format!("Lambertian(albedo: {albedo}, two_sided: false)"),
    })
}

/// Mitsuba's `plastic` and `roughplastic` (`src/bsdfs/plastic.cpp`, `roughplastic.cpp`) as
/// `Plastic` and `RoughPlastic`: `diffuse_reflectance` (default 0.5) and
/// `specular_reflectance` (default 1) as colours or textures, `int_ior` (default
/// polypropylene) over `ext_ior` (default air) as `ior`, `nonlinear`, and the rough one's
/// microfacet parameters (default Beckmann, alpha 0.1). As Mitsuba, the indices must be
/// positive and, for `roughplastic`, differ; pathwave also wants their ratio in [0.1, 10].
fn plastic<'d>(cx: &mut Converter<'d>, p: &Plugin<'d>, two_sided: bool) -> Result<String, SceneError> {
    let rough = match p.kind == "roughplastic" {
        true => Some(microfacet(cx, p, Takes::Number)?),
        false => None,
    };
    let int = Converter::ior(p, "int_ior", 1.49)?;
    let ext = Converter::ior(p, "ext_ior", 1.000277)?;
    let ior = int / ext;
    if rough.is_some() && int == ext {
        return Err(p.at.error(format!(
            "{}: int_ior and ext_ior are both {int}: Mitsuba's roughplastic wants them to differ",
            p.label()
        )));
    }
    if !(0.1..=10.0).contains(&ior) {
        let at = p.param("int_ior").or(p.param("ext_ior")).map_or(&p.at, |param| &param.at);
        return Err(at.error(format!(
            "{}: int_ior / ext_ior = {ior}: pathwave takes coating indices from 0.1 to 10",
            p.label()
        )));
    }
    let albedo = color(cx, p, "diffuse_reflectance", DVec3::splat(0.5))?;
    let tint = color(cx, p, "specular_reflectance", DVec3::ONE)?;
    let nonlinear = p.bool("nonlinear")?.unwrap_or(false);
    p.finish(&[
        "diffuse_reflectance",
        "specular_reflectance",
        "int_ior",
        "ext_ior",
        "nonlinear",
        "alpha",
        "alpha_u",
        "alpha_v",
        "distribution",
        "sample_visible",
    ])?;
    let kind = if rough.is_some() { "RoughPlastic" } else { "Plastic" };
    let mut s = format!("{kind}(albedo: {albedo}, ");
    if let Some(rough) = rough {
        s += &format!("{rough}, ");
    }
    s += &format!("tint: {tint}, ior: {}, nonlinear: {nonlinear}", num32(ior));
    if two_sided {
        s += ", two_sided: true";
    }
    Ok(s + ")")
}

/// A weight of `principled` in [0, 1] as RON (a number or a texture read as a number), or
/// nothing when not written.
fn weight<'d>(cx: &mut Converter<'d>, p: &Plugin<'d>, name: &str) -> Result<Option<String>, SceneError> {
    let Some(param) = p.param(name) else { return Ok(None) };
    match &param.value {
        Value::Object(e) => Ok(Some(format!("{name}: {:?}", cx.float_texture(e)?))),
        _ => {
            let v = p.float(name)?.unwrap_or_default();
            if !(0.0..=1.0).contains(&v) {
                return Err(param.at.error(format!("{}: {name} {v}: expected 0 to 1", p.label())));
            }
            Ok(Some(format!("{name}: {}", num(v))))
        }
    }
}

/// Mitsuba's `principled` (`src/bsdfs/principled.cpp`) as `Principled`: `base_color` a colour
/// or texture, every weight a number or texture, `eta` or `specular`, and the sampling rates.
fn principled<'d>(cx: &mut Converter<'d>, p: &Plugin<'d>) -> Result<String, SceneError> {
    const WEIGHTS: [&str; 10] = [
        "roughness",
        "anisotropic",
        "metallic",
        "spec_trans",
        "spec_tint",
        "sheen",
        "sheen_tint",
        "flatness",
        "clearcoat",
        "clearcoat_gloss",
    ];
    let mut fields = vec![format!("base_color: {}", color(cx, p, "base_color", DVec3::splat(0.5))?)];
    for name in WEIGHTS {
        fields.extend(weight(cx, p, name)?);
    }
    match (p.param("eta"), p.param("specular")) {
        (Some(_), Some(param)) => {
            return Err(param.at.error(format!("{}: give either eta or specular, as Mitsuba", p.label())));
        }
        (Some(param), None) => {
            let eta = p.float("eta")?.unwrap_or_default();
            if !(eta > 0.0) {
                return Err(param.at.error(format!("{}: eta {eta}: expected > 0", p.label())));
            }
            fields.push(format!("eta: {}", num(eta)));
        }
        (None, Some(param)) => {
            let s = p.float("specular")?.unwrap_or_default();
            if !(0.0..=1.0).contains(&s) {
                return Err(param.at.error(format!("{}: specular {s}: expected 0 to 1", p.label())));
            }
            fields.push(format!("specular: {}", num(s)));
        }
        (None, None) => {}
    }
    let rates =
        ["main_specular_sampling_rate", "clearcoat_sampling_rate", "diffuse_reflectance_sampling_rate"];
    sampling_rates(p, rates, &mut fields)?;
    let mut known = vec!["base_color", "eta", "specular"];
    known.extend(WEIGHTS);
    known.extend(rates);
    p.finish(&known)?;
    Ok(format!("Principled({})", fields.join(", ")))
}

/// Mitsuba's `principledthin` (`src/bsdfs/principledthin.cpp`) as `PrincipledThin`:
/// `base_color` a colour or texture, the weights numbers or textures (`diff_trans` 0 to 2),
/// `eta` a number, and the four sampling rates.
fn principled_thin<'d>(cx: &mut Converter<'d>, p: &Plugin<'d>) -> Result<String, SceneError> {
    const WEIGHTS: [&str; 7] =
        ["roughness", "anisotropic", "spec_trans", "spec_tint", "sheen", "sheen_tint", "flatness"];
    let mut fields = vec![format!("base_color: {}", color(cx, p, "base_color", DVec3::splat(0.5))?)];
    for name in WEIGHTS {
        fields.extend(weight(cx, p, name)?);
    }
    if let Some(param) = p.param("diff_trans") {
        match &param.value {
            Value::Object(e) => fields.push(format!("diff_trans: {:?}", cx.float_texture(e)?)),
            _ => {
                let v = p.float("diff_trans")?.unwrap_or_default();
                if !(0.0..=2.0).contains(&v) {
                    return Err(param.at.error(format!("{}: diff_trans {v}: expected 0 to 2", p.label())));
                }
                fields.push(format!("diff_trans: {}", num(v)));
            }
        }
    }
    if let Some(param) = p.param("eta") {
        let eta = p.float("eta")?.unwrap_or_default();
        if !(eta > 0.0) {
            return Err(param.at.error(format!("{}: eta {eta}: expected a number > 0", p.label())));
        }
        fields.push(format!("eta: {}", num(eta)));
    }
    let rates = [
        "specular_reflectance_sampling_rate",
        "specular_transmittance_sampling_rate",
        "diffuse_reflectance_sampling_rate",
        "diffuse_transmittance_sampling_rate",
    ];
    sampling_rates(p, rates, &mut fields)?;
    let mut known = vec!["base_color", "eta", "diff_trans"];
    known.extend(WEIGHTS);
    known.extend(rates);
    p.finish(&known)?;
    Ok(format!("PrincipledThin({})", fields.join(", ")))
}

/// The material a `<bsdf>` element becomes.
pub fn convert<'d>(cx: &mut Converter<'d>, e: &'d Element) -> Result<String, SceneError> {
    let p = Plugin::new(e)?;
    let out = match p.kind.as_str() {
        "diffuse" => diffuse(cx, &p, false)?,
        "twosided" => {
            let inner: Vec<&Element> = p.unnamed().collect();
            p.finish(&[])?;
            let [one] = inner.as_slice() else {
                return Err(p.at.error(
                    "<bsdf type=\"twosided\"> with two BSDFs: pathwave reads one, the same on both sides",
                ));
            };
            two_sided(cx, one)?
        }
        "conductor" | "roughconductor" => {
            let rough = match p.kind == "roughconductor" {
                true => microfacet(cx, &p, Takes::Anisotropic)?,
                false => "alpha: 0".to_owned(),
            };
            let (mut eta, mut k) = (p.rgb_as("eta", Use::Unbounded)?, p.rgb_as("k", Use::Unbounded)?);
            if let Some((m, at)) = p.string("material")?
                && m != "none"
            {
                (eta, k) = named_conductor(&m, &at)?;
                if let Some(param) = p.param("eta").or(p.param("k")) {
                    return Err(param.at.error(format!(
                        "{}: give either eta and k or a material (\"{m}\"), as Mitsuba",
                        p.label()
                    )));
                }
            }
            let tint = color(cx, &p, "specular_reflectance", DVec3::ONE)?;
            p.finish(&[
                "alpha",
                "alpha_u",
                "alpha_v",
                "distribution",
                "sample_visible",
                "material",
                "eta",
                "k",
                "specular_reflectance",
            ])?;
            let mut s = format!("RoughConductor(tint: {tint}, {rough}");
            match (eta, k) {
                (None, None) => {}
                (eta, k) => {
                    s += &format!(
                        ", eta: {}, k: {}",
                        v3(eta.unwrap_or(DVec3::ONE)),
                        v3(k.unwrap_or(DVec3::ZERO))
                    );
                }
            }
            s + ")"
        }
        "plastic" | "roughplastic" => plastic(cx, &p, false)?,
        "principled" => principled(cx, &p)?,
        "principledthin" => principled_thin(cx, &p)?,
        "dielectric" | "roughdielectric" => {
            let rough = match p.kind == "roughdielectric" {
                true => Some(microfacet(cx, &p, Takes::Textured)?),
                false => None,
            };
            let int = Converter::ior(&p, "int_ior", 1.5046)?;
            let ext = Converter::ior(&p, "ext_ior", 1.000277)?;
            unit_scale(&p, "specular_reflectance")?;
            unit_scale(&p, "specular_transmittance")?;
            p.finish(&[
                "alpha",
                "alpha_u",
                "alpha_v",
                "distribution",
                "sample_visible",
                "int_ior",
                "ext_ior",
            ])?;
            let ior = num32(int / ext);
            match rough {
                None => format!("Dielectric(ior: {ior})"),
                Some(rough) => format!("RoughDielectric(ior: {ior}, {rough})"),
            }
        }
        // Mitsuba's thindielectric (`src/bsdfs/thindielectric.cpp`): a pane whose reflectance
        // sums the inter-reflections inside it, and which lets the rest straight through.
        "thindielectric" => {
            let int = Converter::ior(&p, "int_ior", 1.5046)?;
            let ext = Converter::ior(&p, "ext_ior", 1.000277)?;
            unit_scale(&p, "specular_reflectance")?;
            unit_scale(&p, "specular_transmittance")?;
            p.finish(&["int_ior", "ext_ior"])?;
            format!("ThinDielectric(ior: {})", num32(int / ext))
        }
        "mask" => mask(cx, &p, false)?,
        "blendbsdf" => blend(cx, &p, false)?,
        "bumpmap" => bump(cx, &p, false)?,
        "normalmap" => normal_map(cx, &p, false)?,
        "null" => {
            return Err(p.at.error(
                "<bsdf type=\"null\"> is a shape's invisible boundary: pathwave reads it directly inside a <shape>",
            ));
        }
        k => {
            return Err(p.at.error(format!(
                "<bsdf type=\"{k}\">: pathwave reads diffuse, twosided, conductor, roughconductor, dielectric, roughdielectric, thindielectric, plastic, roughplastic, principled, principledthin, mask, blendbsdf, bumpmap, normalmap and null"
            )));
        }
    };
    Ok(out)
}

/// The principled BSDFs' sampling rates `names` (each >= 0, by default 1) as the RON field
/// `sampling_rates: (..)` in `fields`, left out where all are 1.
fn sampling_rates<const N: usize>(
    p: &Plugin,
    names: [&str; N],
    fields: &mut Vec<String>,
) -> Result<(), SceneError> {
    let mut r = [1.0; N];
    for (i, name) in names.iter().enumerate() {
        if let Some(v) = p.float(name)? {
            if !(v >= 0.0 && v.is_finite()) {
                let at = p.param(name).map_or(&p.at, |param| &param.at);
                return Err(at.error(format!("{}: {name} {v}: expected >= 0", p.label())));
            }
            r[i] = v;
        }
    }
    if r != [1.0; N] {
        fields.push(format!("sampling_rates: ({})", r.map(num).join(", ")));
    }
    Ok(())
}
