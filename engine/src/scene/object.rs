//! `objects: [..]`: a shape with a material (a surface) or a medium (a volume), its transform,
//! motion and keyframes; checked as placed (`placement::primitives`) at load.
//!
//! The shapes an object may have are in `shape`, the media that fill volumes in `medium`.

mod medium;
mod shape;

pub use medium::{Asymmetry, Density, GridDesc, GridValues, MAX_GRID_EXTINCTION, MediumDesc, PhaseDesc};
pub use shape::{ShapeDesc, ShapeForm, ShapeKind};

use super::assets::open_edge;
use super::material::MaterialRef;
use super::transform::{TransformOp, compose};
use crate::format::{Color, Radiance, V3, context};
use crate::placement::primitives;
use serde::Deserialize;

/// One object: a shape with either a material (a surface) or a medium (a volume), and an
/// optional list of transforms.
#[derive(Deserialize, Debug, Clone)]
#[serde(try_from = "RawObject")]
pub struct ObjectDesc {
    /// The shape, in object space.
    pub shape: ShapeDesc,
    /// What the shape is.
    pub body: Body,
    /// Light the surface emits besides what its material reflects (default none).
    pub emit: Option<EmitDesc>,
    /// Transforms applied in order, first to last (default none).
    pub transform: Vec<TransformOp>,
    /// How it moves (default: it does not).
    pub motion: Option<MotionDesc>,
    /// Keyframed placement, applied after `transform` (default none).
    pub animate: Option<crate::animation::ObjectAnimation>,
}

/// Linear motion: at time `t` the object lies translated by `velocity * t` from where its
/// transform puts it.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields, rename = "Motion")]
pub struct MotionDesc {
    /// World units per unit of time.
    pub velocity: V3,
}

/// `emit: (radiance: (r, g, b), two_sided: false)`: the surface emits `radiance` (or a
/// texture's value at the point, by name) besides what its material reflects, as Mitsuba 3's
/// `area` emitter on a shape with a BSDF: on the side of the geometric normal only, unless
/// `two_sided`. Sampled as a light like an emitter's surface.
#[derive(Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, rename = "Emit")]
pub struct EmitDesc {
    /// Emitted radiance, or the name of a texture.
    pub radiance: Color<Radiance>,
    /// Emit on both sides (default false: only on the side of the normal).
    #[serde(default)]
    pub two_sided: bool,
}

/// What an object's shape bounds.
#[derive(Debug, Clone, PartialEq)]
pub enum Body {
    /// `material: "name"`: a surface with a material from `materials`.
    Surface(MaterialRef),
    /// `medium: (density: .., albedo: ..)`: an invisible, index-matched boundary (a closed
    /// shape: sphere, box or closed mesh) filled with a medium (boxed: it is the larger).
    Volume(Box<MediumDesc>),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Object")]
struct RawObject {
    shape: ShapeDesc,
    #[serde(default)]
    material: Option<MaterialRef>,
    #[serde(default)]
    medium: Option<MediumDesc>,
    #[serde(default)]
    emit: Option<EmitDesc>,
    #[serde(default)]
    transform: Vec<TransformOp>,
    #[serde(default)]
    motion: Option<MotionDesc>,
    #[serde(default)]
    animate: Option<crate::animation::ObjectAnimation>,
}

impl TryFrom<RawObject> for ObjectDesc {
    type Error = String;
    /// The object must survive its transform: no quad flattened to no area, every coordinate
    /// within [`MAX_COORDINATE`]; a medium needs a closed shape.
    fn try_from(r: RawObject) -> Result<Self, String> {
        let body = match (r.material, r.medium) {
            (Some(m), None) => Body::Surface(m),
            (None, Some(_))
                if !matches!(r.shape, ShapeDesc::Mesh(_)) && r.shape.form().closed().is_none() =>
            {
                return Err("a medium needs a closed shape: Sphere, Box or a closed Mesh".into());
            }
            (None, Some(_)) if matches!(&r.shape, ShapeDesc::Mesh(m) if open_edge(&m.mesh).is_some()) => {
                let ShapeDesc::Mesh(m) = &r.shape else { unreachable!() };
                let (a, b, n) = open_edge(&m.mesh).unwrap();
                return Err(format!(
                    "a medium needs a closed mesh, but in {} the edge from {a} to {b} borders {n} triangle(s)",
                    m.path.display()
                ));
            }
            (None, Some(m)) => {
                m.check()?;
                Body::Volume(Box::new(m))
            }
            (Some(_), Some(_)) => return Err("an object has a `material` or a `medium`, not both".into()),
            (None, None) => {
                return Err("an object needs a `material` (a surface) or a `medium` (a volume)".into());
            }
        };
        match (&body, &r.emit) {
            (Body::Volume(_), Some(_)) => {
                return Err("`emit` is for surfaces: a medium glows by its own `emission`".into());
            }
            (Body::Surface(name), Some(_))
                if context::names(|n| n.is_some_and(|n| n.lights.contains(&name.0))) =>
            {
                return Err(format!(
                    "material \"{}\" is a DiffuseLight, which emits already: `emit` is for surfaces whose material reflects",
                    name.0
                ));
            }
            (Body::Surface(name), Some(_))
                if context::names(|n| n.is_some_and(|n| n.wrappers.contains(&name.0))) =>
            {
                return Err(format!(
                    "material \"{}\" is a wrapper ({}): `emit` is for surfaces of plain materials",
                    name.0,
                    crate::material::wrap::NAMES.join(", ")
                ));
            }
            _ => {}
        }
        if let (ShapeDesc::SdfGrid(_), Body::Surface(name)) = (&r.shape, &body) {
            let light = context::names(|n| n.is_some_and(|n| n.lights.contains(&name.0)));
            if light || r.emit.is_some() {
                return Err("an SdfGrid does not emit (nor does Mitsuba's sdfgrid): give it a material that reflects and no `emit`".into());
            }
        }
        if let Body::Surface(m) = &body {
            attributes_found(&r.shape, &m.0)?;
        }
        primitives(&r.shape.form(), &compose(&r.transform), &mut Vec::new()).map_err(|e| e.to_string())?;
        Ok(Self {
            shape: r.shape,
            body,
            emit: r.emit,
            transform: r.transform,
            motion: r.motion,
            animate: r.animate,
        })
    }
}

/// A surface whose material reads mesh attributes (`MeshAttribute` textures) must be a mesh
/// that has them, and must not emit (emitting meshes are baked into world-space triangles,
/// which keep no attributes).
fn attributes_found(shape: &ShapeDesc, material: &str) -> Result<(), String> {
    let (wanted, emits) = crate::format::context::names(|n| match n {
        Some(n) => (
            n.attributes.iter().find(|(m, _)| m == material).map(|(_, a)| a.clone()).unwrap_or_default(),
            n.lights.iter().any(|l| l == material),
        ),
        None => (Vec::new(), false),
    });
    let Some(first) = wanted.first() else { return Ok(()) };
    let ShapeDesc::Mesh(mesh) = shape else {
        return Err(format!("material \"{material}\" reads the mesh attribute {first}: it goes on a Mesh"));
    };
    if emits {
        return Err(format!(
            "material \"{material}\" emits and reads the mesh attribute {first}: pathwave's emitting meshes keep no attributes"
        ));
    }
    let has: Vec<&str> = mesh.mesh.attributes.iter().map(|a| a.name.as_str()).collect();
    match wanted.iter().find(|a| !has.contains(&a.as_str())) {
        None => Ok(()),
        Some(a) => Err(format!(
            "material \"{material}\" reads the mesh attribute {a}, which the mesh {} does not have (it has {})",
            mesh.path.display(),
            if has.is_empty() { "none".to_owned() } else { has.join(", ") }
        )),
    }
}
