//! Cylinder: Mitsuba 3's `cylinder` shape (`src/shapes/cylinder.cpp`), the open tube (no caps)
//! of `radius` around the segment from `p0` to `p1`. In object space it is Mitsuba's unit
//! cylinder `x^2 + y^2 = 1`, `0 <= z <= 1`, placed by `to_world translate(p0) to_frame(axis)
//! scale(radius, radius, length)`; rays are intersected there (as `TransformedSphere` does), by
//! the quadratic of the sphere's robust form in two dimensions.
//!
//! Texture coordinates are Mitsuba's with pathwave's v: u = phi / 2pi, phi the angle about the
//! axis from the frame's first tangent in [0, 2pi), and v = 1 - z (Mitsuba's v is z; pathwave's
//! image rows run the other way). The normal points away from the axis, or towards it with
//! `flip_normals` (Mitsuba flips it back under a mirroring `to_world`, so a mirror changes
//! nothing). As a light it is sampled uniformly by area: uniform in phi and z, which is
//! uniform on a circular cylinder; [`CylinderShape::place`] refuses placements that make the
//! cross-section an ellipse or shear the axis (Mitsuba warns of them and renders them with the
//! circular cylinder's area).

use super::{
    LightSample, MeshPoint, Primitive, PrimitiveShape, ShapeError, ShapeModel, SurfacePoint,
    area_to_solid_angle,
};
use crate::format::{Positive, V3};
use crate::math::{Frame, cos_sin_turn, gamma};
use glam::{Affine3A, Mat3A, Vec2, Vec3A};
use obvhs::aabb::Aabb;
use std::f32::consts::PI;

/// A cylinder in world space: the unit cylinder of object space placed by `world_from_object`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylinder {
    /// Object to world.
    pub world_from_object: Affine3A,
    /// World to object.
    pub object_from_world: Affine3A,
    /// Inverse transpose of the linear part: object normals to world normals.
    normal_to_world: Mat3A,
    /// -1 when the normal points towards the axis, else 1.
    side: f32,
    /// Area `2 pi radius length`.
    area: f32,
    /// Largest column sum of `|M|`, how much the map scales errors.
    scale: f32,
    /// Largest `|translation|` component.
    shift: f32,
}

/// The relative tolerance of [`CylinderShape::place`]'s check that the placed cross-section is
/// a circle at right angles to the axis.
const CIRCULAR: f32 = 1e-4;

impl Cylinder {
    /// The unit cylinder placed by `m` (whose first two columns are the radii, the third the
    /// axis), facing away from the axis unless `inward`; `None` when `m` is singular.
    pub fn new(m: Affine3A, inward: bool) -> Option<Self> {
        let det = m.matrix3.determinant();
        if !(det.abs() > 0.0) || !det.is_finite() || !m.translation.is_finite() {
            return None;
        }
        let inv = m.inverse();
        let cols = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
        let area = 2.0 * PI * cols[0].length() * cols[2].length();
        Some(Self {
            world_from_object: m,
            object_from_world: inv,
            normal_to_world: inv.matrix3.transpose(),
            side: if inward { -1.0 } else { 1.0 },
            area,
            scale: (cols[0].abs() + cols[1].abs() + cols[2].abs()).max_element(),
            shift: m.translation.abs().max_element(),
        })
        .filter(|c| c.area.is_finite() && c.area > 0.0)
    }

    /// The world point and unit normal of the object point `(cos, sin, z)`.
    #[inline]
    fn placed(&self, cos: f32, sin: f32, z: f32) -> (Vec3A, Vec3A) {
        let p = self.world_from_object.transform_point3a(Vec3A::new(cos, sin, z));
        let n = (self.normal_to_world * Vec3A::new(cos, sin, 0.0)).normalize() * self.side;
        (p, n)
    }

    /// Error bound of a world point placed from the object point `(x, y, z)` with a radial error
    /// of a few ulps: the object error scaled by the map, plus the rounding of `M p + t`.
    #[inline]
    fn error(&self, z: f32) -> f32 {
        let object = gamma(5) * (1.0 + z.abs());
        let magnitude = self.scale * 1f32.max(z.abs()) + self.shift;
        self.scale * object + gamma(4) * magnitude
    }
}

/// The roots of `|f + t d|^2 = 1` for the two-dimensional `f` and `d`, nearest first, with the
/// discriminant computed as the sphere's (`a (1 - |f - (b / a) d|^2)`, free of the
/// cancellation of `b^2 - a c`); `None` when the line misses.
#[inline]
fn circle_roots(f: Vec2, d: Vec2) -> Option<(f32, f32)> {
    let a = d.length_squared();
    let b = f.dot(d);
    let l = f - (b / a) * d;
    let disc = a * (1.0 - l.length_squared());
    if !(disc >= 0.0) || !(a > 0.0) {
        return None;
    }
    let q = -(b + disc.sqrt().copysign(b));
    let (t0, t1) = ((f.length_squared() - 1.0) / q, q / a);
    Some((t0.min(t1), t0.max(t1)))
}

impl PrimitiveShape for Cylinder {
    /// Mitsuba's bound: the boxes of the two end circles (each axis reaches
    /// `sqrt(x_i^2 + y_i^2)` of the radii's components), and the points' error.
    fn aabb(&self) -> Aabb {
        let m = self.world_from_object;
        let (x, y) = (m.matrix3.x_axis, m.matrix3.y_axis);
        let reach = (x * x + y * y).powf(0.5) + self.error(1.0);
        let (p0, p1) = (m.translation, m.transform_point3a(Vec3A::Z));
        Aabb { min: p0.min(p1) - reach, max: p0.max(p1) + reach }
    }

    /// Smallest `t` in `(0, tmax)`: the nearer root whose point lies between the ends, else the
    /// farther one (seen from inside, or through the open end).
    #[inline]
    fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        let lo = self.object_from_world.transform_point3a(o);
        let ld = self.object_from_world.transform_vector3a(d);
        let Some((t0, t1)) = circle_roots(Vec2::new(lo.x, lo.y), Vec2::new(ld.x, ld.y)) else {
            return f32::INFINITY;
        };
        let along = |t: f32| lo.z + t * ld.z;
        let within = |t: f32| t > 0.0 && t < tmax && (0.0..=1.0).contains(&along(t));
        if within(t0) {
            t0
        } else if within(t1) {
            t1
        } else {
            f32::INFINITY
        }
    }

    /// Surface data at `p`, re-projected onto the cylinder in object space (the radial part
    /// scaled to 1, `z` clamped to the ends); uv only if `uv`.
    #[inline]
    fn surface(&self, p: Vec3A, uv: bool) -> SurfacePoint {
        let local = self.object_from_world.transform_point3a(p);
        let r = Vec2::new(local.x, local.y).length();
        let (cos, sin) = if r > 0.0 { (local.x / r, local.y / r) } else { (1.0, 0.0) };
        let z = local.z.clamp(0.0, 1.0);
        let (p, n) = self.placed(cos, sin, z);
        let uv = match uv {
            true => {
                let turn = crate::math::atan2(sin, cos) / (2.0 * PI);
                Vec2::new(if turn < 0.0 { turn + 1.0 } else { turn }, 1.0 - z)
            }
            false => Vec2::ZERO,
        };
        SurfacePoint { p, n, ns: n, ns_base: n, uv, err: self.error(z), on: MeshPoint::NONE }
    }

    fn area(&self) -> f32 {
        self.area
    }

    /// A point uniform by area: phi and z uniform (Mitsuba's `sample_position`).
    fn sample_solid_angle(&self, from: Vec3A, u: Vec2) -> LightSample {
        let (cos, sin) = cos_sin_turn(u.y);
        let (p, n) = self.placed(cos, sin, u.x);
        let pdf = area_to_solid_angle(1.0 / self.area, from, p, n);
        LightSample { p, n, pdf, err: self.error(u.x) }
    }

    fn pdf_solid_angle(&self, from: Vec3A, p: Vec3A, n: Vec3A) -> f32 {
        area_to_solid_angle(1.0 / self.area, from, p, n)
    }
}

/// A cylinder in its own space, as a scene places it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CylinderShape {
    /// Centre of the first end.
    pub p0: Vec3A,
    /// Centre of the second end.
    pub p1: Vec3A,
    /// Radius (> 0).
    pub radius: f32,
    /// The normal points towards the axis.
    pub flip_normals: bool,
}

/// The open tube (no caps) of `radius` about the segment from `p0` to `p1`, normal away from the
/// axis (towards it with `flip_normals: true`, default false; a mirroring transform changes
/// nothing, as in Mitsuba): Mitsuba's `cylinder`. uv: u = phi / 2pi about the axis from the first
/// tangent of its frame, v = 1 at `p0` to 0 at `p1`. Transforms that make the cross-section an
/// ellipse or shear the axis are refused. As a light, sampled uniformly by area.
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct CylinderDesc {
    /// Centre of the first end (v = 1).
    pub p0: V3,
    /// Centre of the second end (v = 0), not `p0`.
    pub p1: V3,
    /// Radius (> 0).
    pub radius: Positive,
    /// The normal points towards the axis (default false: away from it; Mitsuba's
    /// `flip_normals`).
    #[serde(default)]
    pub flip_normals: bool,
}

impl ShapeModel for CylinderShape {
    type Desc = CylinderDesc;

    fn build(d: CylinderDesc) -> Result<Self, String> {
        let axis = d.p1.0 - d.p0.0;
        if !(axis.length() > 0.0) || !axis.length().is_finite() {
            return Err(format!("Cylinder has no length: p0 {} and p1 {} must differ", d.p0.0, d.p1.0));
        }
        Ok(Self { p0: d.p0.0.into(), p1: d.p1.0.into(), radius: d.radius.0, flip_normals: d.flip_normals })
    }

    /// Any map that keeps the cross-section a circle at right angles to the axis (rotations,
    /// translations, mirrors, scales; a non-uniform scale only along the axis).
    fn place(&self, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
        let axis = self.p1 - self.p0;
        let length = axis.length();
        let f = Frame::from_normal(axis / length);
        let local = Affine3A::from_cols(f.t * self.radius, f.b * self.radius, f.n * length, self.p0);
        let w = *m * local;
        let [x, y, z] = [w.matrix3.x_axis, w.matrix3.y_axis, w.matrix3.z_axis];
        let (lx, ly, lz) = (x.length(), y.length(), z.length());
        let circular = (lx - ly).abs() <= CIRCULAR * lx
            && x.dot(y).abs() <= CIRCULAR * lx * ly
            && x.dot(z).abs() <= CIRCULAR * lx * lz
            && y.dot(z).abs() <= CIRCULAR * ly * lz;
        if !circular {
            return Err(ShapeError::OvalCylinder);
        }
        let cylinder = Cylinder::new(w, self.flip_normals).ok_or(ShapeError::Flattened)?;
        out.push(Primitive::Cylinder(cylinder));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn place(shape: CylinderShape, m: Affine3A) -> Result<Cylinder, ShapeError> {
        let mut out = Vec::new();
        shape.place(&m, &mut out)?;
        match out[0] {
            Primitive::Cylinder(c) => Ok(c),
            _ => unreachable!(),
        }
    }

    fn unit() -> CylinderShape {
        CylinderShape { p0: Vec3A::ZERO, p1: Vec3A::Z, radius: 1.0, flip_normals: false }
    }

    #[test]
    fn hits_the_outside_then_the_inside_through_the_open_end() {
        let c = place(unit(), Affine3A::IDENTITY).unwrap();
        let t = c.intersect(Vec3A::new(-3.0, 0.0, 0.5), Vec3A::X, f32::INFINITY);
        assert!((t - 2.0).abs() < 1e-6);
        let sp = c.surface(Vec3A::new(-1.0, 0.0, 0.5), true);
        assert!((sp.n - -Vec3A::X).length() < 1e-6);
        // phi = pi: Mitsuba's uv (0.5, 0.5), pathwave's v = 1 - 0.5.
        assert!((sp.uv - Vec2::new(0.5, 0.5)).length() < 1e-6, "{}", sp.uv);
        let sp = c.surface(Vec3A::new(0.0, 1.0, 0.25), true);
        assert!((sp.uv - Vec2::new(0.25, 0.75)).length() < 1e-6, "{}", sp.uv);
        // Above the top end the outside is missed; the inside is hit through the opening.
        assert_eq!(c.intersect(Vec3A::new(-3.0, 0.0, 1.5), Vec3A::X, f32::INFINITY), f32::INFINITY);
        let d = Vec3A::new(1.0, 0.0, -1.0);
        let t = c.intersect(Vec3A::new(-0.5, 0.0, 1.5), d, f32::INFINITY);
        assert!((t - 1.5).abs() < 1e-5, "the far wall at x = 1: {t}");
        // From inside, the wall ahead; parallel to the axis, nothing.
        assert!((c.intersect(Vec3A::new(0.0, 0.0, 0.5), Vec3A::Y, f32::INFINITY) - 1.0).abs() < 1e-6);
        assert_eq!(c.intersect(Vec3A::new(0.0, 0.0, -1.0), Vec3A::Z, f32::INFINITY), f32::INFINITY);
        assert_eq!(c.intersect(Vec3A::new(-3.0, 0.0, 0.5), Vec3A::X, 1.5), f32::INFINITY);
    }

    #[test]
    fn flip_normals_turns_the_normal_inwards_and_a_mirror_changes_nothing() {
        let p = Vec3A::new(0.6, 0.8, 0.3);
        let out = place(unit(), Affine3A::IDENTITY).unwrap().surface(p, true);
        let inward = place(CylinderShape { flip_normals: true, ..unit() }, Affine3A::IDENTITY).unwrap();
        assert!((inward.surface(p, true).n + out.n).length() < 1e-6);
        assert_eq!(inward.surface(p, true).uv, out.uv);
        let mirror = Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let m = place(unit(), mirror).unwrap().surface(Vec3A::new(-0.6, 0.8, 0.3), true);
        assert!((m.n - Vec3A::new(-0.6, 0.8, 0.0)).length() < 1e-6, "{}", m.n);
    }

    #[test]
    fn ends_and_radius_from_p0_p1_and_oval_placements_refused() {
        let s = CylinderShape {
            p0: Vec3A::new(1.0, 2.0, 3.0),
            p1: Vec3A::new(1.0, 5.0, 3.0),
            radius: 0.5,
            flip_normals: false,
        };
        let c = place(s, Affine3A::IDENTITY).unwrap();
        assert!((c.area() - 2.0 * PI * 0.5 * 3.0).abs() < 1e-5);
        let t = c.intersect(Vec3A::new(1.0, 4.0, 0.0), Vec3A::Z, f32::INFINITY);
        assert!((t - 2.5).abs() < 1e-5, "{t}");
        let b = c.aabb();
        assert!(b.min.cmple(Vec3A::new(0.5, 2.0, 2.5)).all() && b.max.cmpge(Vec3A::new(1.5, 5.0, 3.5)).all());
        // A scale along the axis is fine; across it, an ellipse: refused.
        assert!(place(s, Affine3A::from_scale(Vec3::new(2.0, 5.0, 2.0))).is_ok());
        let oval = place(s, Affine3A::from_scale(Vec3::new(2.0, 1.0, 1.0)));
        assert_eq!(oval.err(), Some(ShapeError::OvalCylinder));
    }

    #[test]
    fn hit_points_lie_on_the_cylinder_within_their_error_bound() {
        let m = Affine3A::from_translation(Vec3::new(-40.0, 7.0, 120.0))
            * Affine3A::from_axis_angle(Vec3::new(0.3, 1.0, -0.2).normalize(), 1.1);
        let s = CylinderShape {
            p0: Vec3A::new(1.0, 0.0, 0.0),
            p1: Vec3A::new(1.0, 3.0, 1.0),
            radius: 1.5,
            flip_normals: false,
        };
        let c = place(s, m).unwrap();
        let (p0, p1) = (m.transform_point3a(s.p0).as_dvec3(), m.transform_point3a(s.p1).as_dvec3());
        let axis = (p1 - p0).normalize();
        let mut rnd = crate::testing::signed(13);
        let mut hits = 0;
        for _ in 0..20_000 {
            let o = p0.as_vec3a() + 10.0 * Vec3A::new(rnd(), rnd(), rnd());
            let target = p0.as_vec3a()
                + (rnd() + 1.0) * 0.5 * (p1 - p0).as_vec3a()
                + 1.6 * Vec3A::new(rnd(), rnd(), rnd());
            let d = target - o;
            let t = c.intersect(o, d, f32::INFINITY);
            if !t.is_finite() {
                continue;
            }
            hits += 1;
            let sp = c.surface(o + t * d, true);
            let q = sp.p.as_dvec3() - p0;
            let radial = (q - q.dot(axis) * axis).length();
            assert!((radial - 1.5).abs() <= sp.err as f64 * 3f64.sqrt(), "{radial} {}", sp.err);
            for side in [sp.n, -sp.n] {
                let start = crate::math::offset_ray_origin(sp.p, sp.err, side);
                let away = side + 0.3 * Vec3A::new(rnd(), rnd(), rnd());
                // Leaving outwards never meets the tube again; inwards it may meet the far wall,
                // but not this point.
                let t2 = c.intersect(start, away, f32::INFINITY);
                assert!(!(t2 * away.length() < 1e-3), "re-hit at {t2}");
            }
        }
        assert!(hits > 5_000, "{hits}");
    }

    #[test]
    fn area_samples_integrate_the_visible_solid_angle() {
        // From outside, each direction meets the tube at most twice; the estimate of the
        // integral of |cos| / d^2 over the area with light samples is the count of crossings
        // over the sphere of directions, which direction sampling estimates too.
        let s = CylinderShape {
            p0: Vec3A::new(0.0, 0.0, 2.0),
            p1: Vec3A::new(0.5, 1.0, 3.0),
            radius: 0.7,
            flip_normals: false,
        };
        let c = place(s, Affine3A::IDENTITY).unwrap();
        let from = Vec3A::new(0.1, -0.2, 0.0);
        let n = 400_000;
        let mut u = crate::testing::uniform(5);
        let mut by_light = 0.0f64;
        for _ in 0..n {
            let ls = c.sample_solid_angle(from, Vec2::new(u(), u()));
            assert_eq!(c.pdf_solid_angle(from, ls.p, ls.n), ls.pdf);
            by_light += 1.0 / ls.pdf as f64;
        }
        let mut by_dir = 0.0f64;
        for _ in 0..n {
            let d = crate::math::uniform_sphere(Vec2::new(u(), u()));
            let t = c.intersect(from, d, f32::INFINITY);
            if t.is_finite() {
                let again = c.intersect(from + t * d + 1e-4 * d, d, f32::INFINITY);
                by_dir += if again.is_finite() { 2.0 } else { 1.0 };
            }
        }
        let (a, b) = (by_light / n as f64, by_dir / n as f64 * 4.0 * std::f64::consts::PI);
        assert!((a / b - 1.0).abs() < 0.01, "light samples {a}, directions {b}");
    }
}
