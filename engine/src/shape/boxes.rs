//! The axis-aligned box as a scene writes it (`Box(a: .., b: .., uv: Around)`) and places it:
//! six quads facing out (it has no primitive of its own), and the volume it closes.

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
    /// How its faces' uv run.
    pub uv: BoxUv,
}

/// How a box's faces are parametrised; each face is the [0, 1]^2 square of uv.
#[derive(serde::Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BoxUv {
    /// The four sides' u runs around the box (counter-clockwise seen from +y: the +z face's u
    /// is +x, the +x face's -z, ...) and their v up (+y); the top's u is +x and v -z, the
    /// bottom's u +x and v +z (default).
    #[default]
    Around,
    /// Each face as Mitsuba 3's `cube` (its `src/shapes/cube.cpp`) maps it, with pathwave's v
    /// (1 - Mitsuba's): u, v along +z, -x on the -y face; -x, +z on +y; +y, +z on +x; +y, -x
    /// on +z; +y, -z on -x; -y, -x on -z. Each face keeps this uv under any transform
    /// (a mirroring one too).
    Mitsuba,
}

/// Axis-aligned box between any two opposite corners: six quads facing out, each face the [0, 1]^2
/// square of uv. `uv: Around` (default): the four sides' u runs around the box counter-clockwise
/// seen from +y (the +z face's u along +x) and their v up; the top's u is +x and v -z, the bottom's
/// u +x and v +z. `uv: Mitsuba`: each face as Mitsuba 3's `cube` maps it (v flipped as pathwave's
/// images), kept under any transform.
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct BoxDesc {
    /// A corner.
    pub a: V3,
    /// The opposite corner.
    pub b: V3,
    /// The faces' uv (default `Around`).
    #[serde(default)]
    pub uv: BoxUv,
}

impl ShapeModel for BoxShape {
    type Desc = BoxDesc;

    fn build(BoxDesc { a, b, uv }: BoxDesc) -> Result<Self, String> {
        let (min, max) = (a.0.min(b.0), a.0.max(b.0));
        if (max - min).min_element() <= 0.0 {
            return Err(format!("Box is flat: corners {} and {} share a coordinate", a.0, b.0));
        }
        Ok(Self { min: min.into(), max: max.into(), uv })
    }

    fn place(&self, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
        let (a, b) = (self.min, self.max);
        let d = b - a;
        let (dx, dy, dz) = (Vec3A::X * d.x, Vec3A::Y * d.y, Vec3A::Z * d.z);
        match self.uv {
            BoxUv::Around => {
                place_quad(m, Vec3A::new(a.x, a.y, b.z), dx, dy, false, out)?; // front (+z)
                place_quad(m, Vec3A::new(b.x, a.y, b.z), -dz, dy, false, out)?; // right (+x)
                place_quad(m, Vec3A::new(b.x, a.y, a.z), -dx, dy, false, out)?; // back (-z)
                place_quad(m, a, dz, dy, false, out)?; // left (-x)
                place_quad(m, Vec3A::new(a.x, b.y, b.z), dx, -dz, false, out)?; // top (+y)
                place_quad(m, a, dx, dz, false, out) // bottom (-y)
            }
            BoxUv::Mitsuba => {
                // Corner (uv 0, 0), u edge, v edge; u x v faces out.
                let faces = [
                    (Vec3A::new(b.x, a.y, a.z), dz, -dx),  // -y
                    (Vec3A::new(b.x, b.y, a.z), -dx, dz),  // +y
                    (Vec3A::new(b.x, a.y, a.z), dy, dz),   // +x
                    (Vec3A::new(b.x, a.y, b.z), dy, -dx),  // +z
                    (Vec3A::new(a.x, a.y, b.z), dy, -dz),  // -x
                    (Vec3A::new(b.x, b.y, a.z), -dy, -dx), // -z
                ];
                // `place_quad` swaps the edges of a mirrored quad: give them swapped, facing
                // the other way, so that the uv survives and the normal still faces out.
                let mirrored = m.matrix3.determinant() < 0.0;
                for (q, u, v) in faces {
                    match mirrored {
                        false => place_quad(m, q, u, v, false, out)?,
                        true => place_quad(m, q, v, u, true, out)?,
                    }
                }
                Ok(())
            }
        }
    }

    fn closed(&self) -> Option<Closed> {
        Some(Closed::Box { min: self.min, max: self.max })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec2, Vec3};

    fn quads(uv: BoxUv, m: Affine3A) -> Vec<crate::shape::Quad> {
        let b = BoxShape::build(BoxDesc { a: V3(Vec3::splat(-1.0)), b: V3(Vec3::ONE), uv }).unwrap();
        let mut out = Vec::new();
        b.place(&m, &mut out).unwrap();
        out.into_iter()
            .map(|p| match p {
                Primitive::Quad(q) => q,
                _ => unreachable!("a box is quads"),
            })
            .collect()
    }

    /// A face's outward normal and, at three of its vertices, the position and Mitsuba's uv.
    type Face = ([f32; 3], [([f32; 3], [f32; 2]); 3]);

    /// Mitsuba's cube (`src/shapes/cube.cpp`), from its vertex table.
    const MITSUBA_CUBE: [Face; 6] = [
        ([0., -1., 0.], [([1., -1., -1.], [0., 1.]), ([1., -1., 1.], [1., 1.]), ([-1., -1., 1.], [1., 0.])]),
        ([0., 1., 0.], [([1., 1., -1.], [0., 1.]), ([-1., 1., -1.], [1., 1.]), ([-1., 1., 1.], [1., 0.])]),
        ([1., 0., 0.], [([1., -1., -1.], [0., 1.]), ([1., 1., -1.], [1., 1.]), ([1., 1., 1.], [1., 0.])]),
        ([0., 0., 1.], [([1., -1., 1.], [0., 1.]), ([1., 1., 1.], [1., 1.]), ([-1., 1., 1.], [1., 0.])]),
        ([-1., 0., 0.], [([-1., -1., 1.], [0., 1.]), ([-1., 1., 1.], [1., 1.]), ([-1., 1., -1.], [1., 0.])]),
        ([0., 0., -1.], [([1., 1., -1.], [0., 1.]), ([1., -1., -1.], [1., 1.]), ([-1., -1., -1.], [1., 0.])]),
    ];

    #[test]
    fn mitsuba_faces_have_mitsubas_uv_and_face_out() {
        // Under the identity and under a mirroring, rotating transform, each of Mitsuba's
        // vertices has Mitsuba's uv (v flipped) on the face with Mitsuba's normal.
        let turn = Affine3A::from_rotation_z(0.3) * Affine3A::from_scale(Vec3::new(-1.0, 2.0, 1.0));
        for m in [Affine3A::IDENTITY, turn] {
            let faces = quads(BoxUv::Mitsuba, m);
            for (n, corners) in MITSUBA_CUBE {
                let n = (m.matrix3.inverse().transpose() * Vec3A::from(n)).normalize();
                let face = faces.iter().find(|q| q.n.dot(n) > 0.999).expect("a face with Mitsuba's normal");
                for (p, uv) in corners {
                    let sp = face.surface(m.transform_point3a(Vec3A::from(p)));
                    let want = Vec2::new(uv[0], 1.0 - uv[1]);
                    assert!((sp.uv - want).length() < 1e-5, "{p:?}: uv {} not {want}", sp.uv);
                }
            }
        }
    }

    #[test]
    fn around_keeps_its_faces() {
        // The default layout's front face: corner (-1, -1, 1), u along +x, v along +y.
        let front = quads(BoxUv::Around, Affine3A::IDENTITY)[0];
        assert_eq!(
            (front.q, front.u, front.v),
            (Vec3A::new(-1.0, -1.0, 1.0), Vec3A::X * 2.0, Vec3A::Y * 2.0)
        );
        assert_eq!(front.n, Vec3A::Z);
    }
}
