//! The axis-aligned box as a scene writes it (`Box(a: .., b: ..)`) and places it: six quads
//! facing out (it has no primitive of its own), and the volume it closes.

use super::quad::place_quad;
use super::{Closed, Primitive, ShapeError, ShapeModel};
use crate::format::V3;
use glam::{Affine3A, Vec3A};

/// The axis-aligned box between two opposite corners, in its own space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxShape {
    /// Minimum corner.
    pub min: Vec3A,
    /// Maximum corner.
    pub max: Vec3A,
}

/// `Box(a: .., b: ..)`: any two opposite corners.
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct BoxDesc {
    /// A corner.
    pub a: V3,
    /// The opposite corner.
    pub b: V3,
}

impl ShapeModel for BoxShape {
    type Desc = BoxDesc;

    fn build(BoxDesc { a, b }: BoxDesc) -> Result<Self, String> {
        let (min, max) = (a.0.min(b.0), a.0.max(b.0));
        if (max - min).min_element() <= 0.0 {
            return Err(format!("Box is flat: corners {} and {} share a coordinate", a.0, b.0));
        }
        Ok(Self { min: min.into(), max: max.into() })
    }

    fn place(&self, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
        let (a, b) = (self.min, self.max);
        let d = b - a;
        let (dx, dy, dz) = (Vec3A::X * d.x, Vec3A::Y * d.y, Vec3A::Z * d.z);
        place_quad(m, Vec3A::new(a.x, a.y, b.z), dx, dy, out)?; // front (+z)
        place_quad(m, Vec3A::new(b.x, a.y, b.z), -dz, dy, out)?; // right (+x)
        place_quad(m, Vec3A::new(b.x, a.y, a.z), -dx, dy, out)?; // back (-z)
        place_quad(m, a, dz, dy, out)?; // left (-x)
        place_quad(m, Vec3A::new(a.x, b.y, b.z), dx, -dz, out)?; // top (+y)
        place_quad(m, a, dx, dz, out) // bottom (-y)
    }

    fn closed(&self) -> Option<Closed> {
        Some(Closed::Box { min: self.min, max: self.max })
    }
}
