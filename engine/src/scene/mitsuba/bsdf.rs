//! `<bsdf>` plugins as pathwave materials.
//!
//! Mitsuba's BSDFs other than `twosided` are one-sided (black seen from behind): `diffuse`
//! becomes a Lambertian with `two_sided: false`, and `twosided` around it the two-sided
//! Lambertian. Its conductors and plastics are one-sided as pathwave's, and its dielectrics the
//! same on both sides in both renderers.

use super::convert::{Converter, num, num32, v3};
use super::props::{Plugin, Value};
use super::spectrum::Use;
use super::xml::Element;
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
        k => Err(one.at.error(format!(
            "twosided around \"{k}\": pathwave reads twosided around diffuse, conductor, roughconductor, plastic, roughplastic, mask and blendbsdf"
        ))),
    }
}

/// The microfacet parameters of roughconductor and roughdielectric as RON fields,
/// `alpha: A, distribution: D`, read as Mitsuba's `MicrofacetDistribution` reads them: the
/// distribution `beckmann` (its default) or `ggx`, and `alpha` (default 0.1) or both `alpha_u`
/// and `alpha_v`, which pathwave's isotropic distributions take only when they are equal.
fn microfacet(p: &Plugin) -> Result<String, SceneError> {
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
    let (alpha_u, alpha_v) = (p.float("alpha_u")?, p.float("alpha_v")?);
    let a = match (p.float("alpha")?, alpha_u, alpha_v) {
        (a, None, None) => a.unwrap_or(0.1),
        (Some(_), _, _) => {
            return Err(p.at.error(format!("{}: give either alpha or alpha_u and alpha_v", p.label())));
        }
        (None, Some(u), Some(v)) if u == v => u,
        (None, Some(u), Some(v)) => {
            let at = p.param("alpha_v").map_or(&p.at, |param| &param.at);
            return Err(at.error(format!(
                "{}: anisotropic roughness (alpha_u {u}, alpha_v {v}): pathwave's microfacets are isotropic; give one alpha",
                p.label()
            )));
        }
        (None, _, _) => {
            return Err(p.at.error(format!("{}: alpha_u and alpha_v go together", p.label())));
        }
    };
    if !(0.0..=1.0).contains(&a) {
        return Err(p.at.error(format!("alpha {a}: pathwave takes 0 to 1")));
    }
    Ok(format!("alpha: {}, distribution: {distribution}", num(a)))
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
        true => Some(microfacet(p)?),
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
            let rough = if p.kind == "roughconductor" { microfacet(&p)? } else { "alpha: 0".to_owned() };
            if let Some((m, at)) = p.string("material")?
                && m != "none"
            {
                return Err(at.error(format!(
                    "material \"{m}\": pathwave's named metals come in a later version; give eta and k"
                )));
            }
            let eta = p.rgb_as("eta", Use::Unbounded)?;
            let k = p.rgb_as("k", Use::Unbounded)?;
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
        "dielectric" | "roughdielectric" => {
            let rough = if p.kind == "roughdielectric" { Some(microfacet(&p)?) } else { None };
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
        "null" => {
            return Err(p.at.error(
                "<bsdf type=\"null\"> is a shape's invisible boundary: pathwave reads it directly inside a <shape>",
            ));
        }
        k => {
            return Err(p.at.error(format!(
                "<bsdf type=\"{k}\">: pathwave reads diffuse, twosided, conductor, roughconductor, dielectric, roughdielectric, thindielectric, plastic, roughplastic, mask, blendbsdf and null"
            )));
        }
    };
    Ok(out)
}
