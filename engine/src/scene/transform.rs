//! Object transforms: lists of translate, rotate, scale and matrix steps, composed in order.

use crate::format::{Direction, Finite, V3};
use glam::{Affine3A, Mat4, Vec3, Vec4};
use serde::Deserialize;

/// One step of an object's transform.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(try_from = "RawTransform")]
pub struct TransformOp(pub Affine3A);

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Transform")]
enum RawTransform {
    Translate(V3),
    RotateX(Finite),
    RotateY(Finite),
    RotateZ(Finite),
    Rotate {
        axis: Direction,
        degrees: Finite,
    },
    Scale(V3),
    UniformScale(Finite),
    Shear {
        #[serde(default)]
        xy: Finite,
        #[serde(default)]
        xz: Finite,
        #[serde(default)]
        yx: Finite,
        #[serde(default)]
        yz: Finite,
        #[serde(default)]
        zx: Finite,
        #[serde(default)]
        zy: Finite,
    },
    Matrix(Vec<Vec<Finite>>),
}

impl TryFrom<RawTransform> for TransformOp {
    type Error = String;
    fn try_from(r: RawTransform) -> Result<Self, String> {
        let a = match r {
            RawTransform::Translate(t) => Affine3A::from_translation(t.0),
            RawTransform::RotateX(d) => Affine3A::from_rotation_x(d.0.to_radians()),
            RawTransform::RotateY(d) => Affine3A::from_rotation_y(d.0.to_radians()),
            RawTransform::RotateZ(d) => Affine3A::from_rotation_z(d.0.to_radians()),
            RawTransform::Rotate { axis, degrees } => {
                Affine3A::from_axis_angle(axis.0.normalize(), degrees.0.to_radians())
            }
            RawTransform::Scale(s) => Affine3A::from_scale(s.0),
            RawTransform::UniformScale(s) => Affine3A::from_scale(Vec3::splat(s.0)),
            // x' = x + xy y + xz z, and likewise for y' and z'.
            RawTransform::Shear { xy, xz, yx, yz, zx, zy } => Affine3A::from_mat3(glam::Mat3::from_cols(
                Vec3::new(1.0, yx.0, zx.0),
                Vec3::new(xy.0, 1.0, zy.0),
                Vec3::new(xz.0, yz.0, 1.0),
            )),
            RawTransform::Matrix(rows) => {
                if rows.len() != 4 || rows.iter().any(|r| r.len() != 4) {
                    return Err("Matrix: expected 4 rows of 4 numbers".into());
                }
                let r: Vec<Vec4> = rows.iter().map(|r| Vec4::new(r[0].0, r[1].0, r[2].0, r[3].0)).collect();
                if r[3] != Vec4::W {
                    return Err(format!("Matrix: the last row must be (0, 0, 0, 1), found {}", r[3]));
                }
                Affine3A::from_mat4(Mat4::from_cols(r[0], r[1], r[2], r[3]).transpose())
            }
        };
        // Singular relative to the matrix's own scale: a tiny uniform scale is fine.
        let size = (a.matrix3.x_axis.abs() + a.matrix3.y_axis.abs() + a.matrix3.z_axis.abs()).max_element();
        if !((a.matrix3 * size.recip()).determinant().abs() > f32::EPSILON) {
            return Err("transform is singular (it flattens the object)".into());
        }
        Ok(TransformOp(a))
    }
}

/// The product of a transform list: the first element is applied first.
pub fn compose(ops: &[TransformOp]) -> Affine3A {
    ops.iter().fold(Affine3A::IDENTITY, |acc, op| op.0 * acc)
}
