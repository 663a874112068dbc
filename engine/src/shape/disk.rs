//! Disk: the unit disk of Mitsuba 3's `disk` shape (`src/shapes/disk.cpp`) in its own frame,
//! placed by any affine map (an ellipse under a non-uniform scale). The intersection is the
//! quad's ([`super::quad`]): the plane through the centre, and the point's coordinates along
//! the two placed radii from vectors dual to them, inside when `a^2 + b^2 <= 1`.
//!
//! Texture coordinates are Mitsuba's polar ones with pathwave's v: u = r, the distance from
//! the centre in radii, and v = 1 - phi / 2pi, phi the angle from the first radius towards the
//! second in [0, 2pi) (Mitsuba's v is phi / 2pi; pathwave's image rows run the other way). As
//! a light it is sampled uniformly by area (Shirley and Chiu's concentric map of the unit
//! square, carried by the affine map, whose area scale is constant).

use super::{
    LightSample, MeshPoint, Primitive, PrimitiveShape, ShapeError, ShapeModel, SurfacePoint,
    area_to_solid_angle,
};
use crate::format::{Direction, Positive, V3};
use crate::math::{Frame, concentric_disk, gamma};
use glam::{Affine3A, Vec2, Vec3A};
use obvhs::aabb::Aabb;
use std::f32::consts::PI;

/// A disk (or ellipse) in world space: the points `c + a u + b v` with `a^2 + b^2 <= 1`, facing
/// along `n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    /// Centre.
    pub c: Vec3A,
    /// First radius (where phi = 0).
    pub u: Vec3A,
    /// Second radius (phi = pi / 2).
    pub v: Vec3A,
    /// Unit normal on the side it faces: `normalize(u x v)`, or its opposite for a mirroring
    /// placement or `flip_normals`.
    pub n: Vec3A,
    /// Vectors dual to `u` and `v` in the plane: a point `c + ph` of the plane has the
    /// coordinates `(ea . ph, eb . ph)` (as [`super::Quad`]'s).
    ea: Vec3A,
    eb: Vec3A,
    /// Area `pi |u x v|`.
    area: f32,
    /// Error bound of its points.
    err: f32,
}

impl Disk {
    /// The disk `c + a u + b v`, facing `normalize(u x v)` (the other way if `flip`); `None`
    /// when `u` and `v` are parallel or zero, or the area is too small for `f32`.
    pub fn new(c: Vec3A, u: Vec3A, v: Vec3A, flip: bool) -> Option<Self> {
        let x = u.cross(v);
        // As `Quad::new`: |x|^2 overflows for radii near 1e10, so x is scaled first.
        let k = x.abs().max_element();
        let xs = x / k;
        let len = xs.length();
        let (n, w, area) = (xs / len, xs / (k * len * len), PI * k * len);
        let (ea, eb) = (v.cross(w), w.cross(u));
        let cond = (u.length() * v.length() / (k * len)).max(1.0);
        let err = gamma(4) * (c.abs() + u.abs() + v.abs()).max_element() * cond;
        let finite = w.is_finite() && ea.is_finite() && eb.is_finite() && area.is_finite() && area > 0.0;
        let n = if flip { -n } else { n };
        (k > 0.0 && finite).then_some(Self { c, u, v, n, ea, eb, area, err })
    }

    /// The disk's coordinates `(a, b)` of a point of its plane.
    #[inline]
    fn coords(&self, p: Vec3A) -> (f32, f32) {
        let ph = p - self.c;
        (self.ea.dot(ph), self.eb.dot(ph))
    }
}

impl PrimitiveShape for Disk {
    /// Mitsuba's bound: per axis, the centre plus or minus `sqrt(u_i^2 + v_i^2)`, the reach of
    /// the ellipse along that axis.
    fn aabb(&self) -> Aabb {
        let reach = (self.u * self.u + self.v * self.v).powf(0.5) + self.err;
        Aabb { min: self.c - reach, max: self.c + reach }
    }

    /// Smallest `t` in `(0, tmax)`: the plane hit relative to the centre, `(o - c) + t d`, then
    /// its coordinates.
    #[inline]
    fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        let oc = o - self.c;
        let denom = self.n.dot(d);
        let t = -self.n.dot(oc) / denom;
        let ph = oc + t * d;
        let (a, b) = (self.ea.dot(ph), self.eb.dot(ph));
        let hit = denom != 0.0 && t > 0.0 && t < tmax && a * a + b * b <= 1.0;
        if hit { t } else { f32::INFINITY }
    }

    /// Surface data at `p`, re-projected onto the plane as `c + a u + b v` (and onto the rim
    /// when rounding put it just outside); the polar uv only if `uv`.
    #[inline]
    fn surface(&self, p: Vec3A, uv: bool) -> SurfacePoint {
        let (mut a, mut b) = self.coords(p);
        let r2 = a * a + b * b;
        if r2 > 1.0 {
            let r = r2.sqrt();
            (a, b) = (a / r, b / r);
        }
        let uv = match uv {
            true => {
                let phi = crate::math::atan2(b, a);
                let turn = phi / (2.0 * PI);
                let turn = if turn < 0.0 { turn + 1.0 } else { turn };
                Vec2::new(r2.min(1.0).sqrt(), 1.0 - turn)
            }
            false => Vec2::ZERO,
        };
        let p = self.c + a * self.u + b * self.v;
        SurfacePoint { p, n: self.n, ns: self.n, ns_base: self.n, uv, err: self.err, on: MeshPoint::NONE }
    }

    fn area(&self) -> f32 {
        self.area
    }

    /// A point uniform by area: the concentric map's point of the unit disk, placed.
    fn sample_solid_angle(&self, from: Vec3A, u: Vec2) -> LightSample {
        let q = concentric_disk(u);
        let p = self.c + q.x * self.u + q.y * self.v;
        let pdf = area_to_solid_angle(1.0 / self.area, from, p, self.n);
        LightSample { p, n: self.n, pdf, err: self.err }
    }

    fn pdf_solid_angle(&self, from: Vec3A, p: Vec3A, _n: Vec3A) -> f32 {
        area_to_solid_angle(1.0 / self.area, from, p, self.n)
    }
}

/// A disk in its own space, as a scene places it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiskShape {
    /// Centre.
    pub center: Vec3A,
    /// Normal (largest component of magnitude 1).
    pub normal: Vec3A,
    /// Radius (> 0).
    pub radius: f32,
    /// Faces against `normal`.
    pub flip_normals: bool,
}

/// The points within `radius` of `center` in the plane normal to `normal`, facing along it (against
/// it with `flip_normals: true`, default false): Mitsuba's `disk`. uv: u = r / radius, v = 1 - phi
/// / 2pi, phi measured from the first tangent of `normal`'s frame (+x for +z) towards the second
/// (+y); any transform (an ellipse under a non-uniform scale). As a light, sampled uniformly by
/// area.
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct DiskDesc {
    /// Centre.
    pub center: V3,
    /// The side it faces (any length but zero); its frame (`math::Frame::from_normal`) gives
    /// the radii where phi = 0 and pi / 2: +x and +y for +z.
    pub normal: Direction,
    /// Radius (> 0).
    pub radius: Positive,
    /// Faces against `normal`, the uv unchanged (default false; Mitsuba's `flip_normals`).
    #[serde(default)]
    pub flip_normals: bool,
}

impl ShapeModel for DiskShape {
    type Desc = DiskDesc;

    fn build(d: DiskDesc) -> Result<Self, String> {
        Ok(Self {
            center: d.center.0.into(),
            normal: d.normal.0.into(),
            radius: d.radius.0,
            flip_normals: d.flip_normals,
        })
    }

    /// Any affine map: the radii are mapped as vectors (an ellipse under a non-uniform scale),
    /// and the disk faces along the mapped normal (`M^-T normal`, Mitsuba's), which a mirroring
    /// map turns to the other side of `u x v`.
    fn place(&self, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
        let f = Frame::from_normal(self.normal.normalize());
        let (u, v) = (m.transform_vector3a(self.radius * f.t), m.transform_vector3a(self.radius * f.b));
        let mirrored = m.matrix3.determinant() < 0.0;
        let disk = Disk::new(m.transform_point3a(self.center), u, v, mirrored != self.flip_normals)
            .ok_or(ShapeError::Flattened)?;
        out.push(Primitive::Disk(disk));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn placed(shape: DiskShape, m: Affine3A) -> Disk {
        let mut out = Vec::new();
        shape.place(&m, &mut out).unwrap();
        match out[0] {
            Primitive::Disk(d) => d,
            _ => unreachable!(),
        }
    }

    fn unit() -> DiskShape {
        DiskShape { center: Vec3A::ZERO, normal: Vec3A::Z, radius: 1.0, flip_normals: false }
    }

    #[test]
    fn hits_inside_the_rim_with_mitsubas_polar_uv() {
        let d = placed(unit(), Affine3A::IDENTITY);
        let o = Vec3A::new(0.0, 0.5, -2.0);
        let t = d.intersect(o, Vec3A::Z, f32::INFINITY);
        assert!((t - 2.0).abs() < 1e-6);
        let sp = d.surface(o + t * Vec3A::Z, true);
        // r = 0.5 at phi = pi / 2: Mitsuba's v = 0.25, pathwave's 0.75.
        assert!((sp.uv - Vec2::new(0.5, 0.75)).length() < 1e-6, "{}", sp.uv);
        assert_eq!(sp.n, Vec3A::Z);
        let sp = d.surface(Vec3A::new(0.0, -0.25, 0.0), true);
        assert!((sp.uv - Vec2::new(0.25, 0.25)).length() < 1e-6, "{}", sp.uv);
        // Just outside the rim, behind, beyond tmax, parallel: misses.
        let miss = |o: Vec3A, dir: Vec3A, tmax: f32| d.intersect(o, dir, tmax);
        assert_eq!(miss(Vec3A::new(0.72, 0.72, -1.0), Vec3A::Z, f32::INFINITY), f32::INFINITY);
        assert_eq!(miss(Vec3A::new(0.0, 0.0, 1.0), Vec3A::Z, f32::INFINITY), f32::INFINITY);
        assert_eq!(miss(Vec3A::new(0.0, 0.0, -1.0), Vec3A::Z, 0.5), f32::INFINITY);
        assert_eq!(miss(Vec3A::new(0.0, 0.0, -1.0), Vec3A::X, f32::INFINITY), f32::INFINITY);
        assert!(miss(Vec3A::new(0.7, 0.7, 1.0), -Vec3A::Z, f32::INFINITY).is_finite(), "two-sided");
    }

    #[test]
    fn an_ellipse_under_a_scale_with_flipped_and_mirrored_normals() {
        let m = Affine3A::from_scale(Vec3::new(1.5, 2.5, 1.0));
        let d = placed(unit(), m);
        assert!((d.area() - PI * 1.5 * 2.5).abs() < 1e-5);
        assert!(d.intersect(Vec3A::new(0.0, 2.4, -1.0), Vec3A::Z, f32::INFINITY).is_finite());
        assert_eq!(d.intersect(Vec3A::new(1.45, 0.8, -1.0), Vec3A::Z, f32::INFINITY), f32::INFINITY);
        let b = d.aabb();
        assert!((b.max - Vec3A::new(1.5, 2.5, 0.0)).abs().max_element() < 1e-5, "{b:?}");
        // flip_normals turns the normal and keeps the uv; so does a mirror in z, both undo it.
        let flipped = placed(DiskShape { flip_normals: true, ..unit() }, m);
        let mirror = Affine3A::from_scale(Vec3::new(1.0, 1.0, -1.0));
        let p = Vec3A::new(0.3, -0.9, 0.0);
        assert_eq!(flipped.n, -Vec3A::Z);
        assert_eq!(flipped.surface(p, true).uv, d.surface(p, true).uv);
        assert_eq!(placed(unit(), mirror).n, -Vec3A::Z);
        assert_eq!(placed(DiskShape { flip_normals: true, ..unit() }, mirror).n, Vec3A::Z);
    }

    #[test]
    fn hit_points_lie_on_the_disk_within_their_error_bound() {
        // A tilted, offset ellipse far from the origin; rays from all around.
        let m = Affine3A::from_translation(Vec3::new(300.0, -20.0, 45.0))
            * Affine3A::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7)
            * Affine3A::from_scale(Vec3::new(3.0, 0.5, 1.0));
        let d = placed(unit(), m);
        let mut rnd = crate::testing::signed(7);
        let mut hits = 0;
        for _ in 0..20_000 {
            let o = d.c + 20.0 * Vec3A::new(rnd(), rnd(), rnd());
            let target = d.c + rnd() * d.u + rnd() * d.v;
            let dir = target - o;
            let t = d.intersect(o, dir, f32::INFINITY);
            if !t.is_finite() {
                continue;
            }
            hits += 1;
            let sp = d.surface(o + t * dir, true);
            // Exact distance to the plane in f64.
            let (c, n) = (d.c.as_dvec3(), d.u.as_dvec3().cross(d.v.as_dvec3()).normalize());
            let dist = (sp.p.as_dvec3() - c).dot(n).abs();
            assert!(dist <= sp.err as f64 * 3f64.sqrt(), "{dist} > {}", sp.err);
            assert!((0.0..=1.0).contains(&sp.uv.x) && (0.0..=1.0).contains(&sp.uv.y));
            // A ray leaving on either side does not hit the disk again.
            for side in [sp.n, -sp.n] {
                let start = crate::math::offset_ray_origin(sp.p, sp.err, side);
                let away = side + 0.3 * Vec3A::new(rnd(), rnd(), rnd());
                if away.dot(side) > 0.0 {
                    assert_eq!(d.intersect(start, away, f32::INFINITY), f32::INFINITY);
                }
            }
        }
        assert!(hits > 5_000, "{hits}");
    }

    #[test]
    fn area_samples_integrate_the_solid_angle() {
        // The pdf integrates to one: the mean of 1 / pdf over samples is the solid angle, which a
        // brute-force sum over a fine polar grid of the ellipse also gives.
        let m = Affine3A::from_translation(Vec3::new(0.2, 0.1, 1.5))
            * Affine3A::from_axis_angle(Vec3::X, 0.4)
            * Affine3A::from_scale(Vec3::new(1.0, 2.0, 1.0));
        let d = placed(unit(), m);
        let from = Vec3A::ZERO;
        let mut u = crate::testing::uniform(3);
        let n = 400_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let ls = d.sample_solid_angle(from, Vec2::new(u(), u()));
            assert!(ls.pdf > 0.0 && ls.pdf.is_finite());
            assert_eq!(d.pdf_solid_angle(from, ls.p, ls.n), ls.pdf);
            sum += 1.0 / ls.pdf as f64;
        }
        let (rings, sectors) = (400, 800);
        let mut exact = 0.0f64;
        for i in 0..rings {
            for j in 0..sectors {
                let r = (i as f64 + 0.5) / rings as f64;
                let phi = (j as f64 + 0.5) / sectors as f64 * std::f64::consts::TAU;
                let p = d.c.as_dvec3() + r * (phi.cos() * d.u.as_dvec3() + phi.sin() * d.v.as_dvec3());
                let dir = p - from.as_dvec3();
                let cos = dir.normalize().dot(d.n.as_dvec3()).abs();
                let da = d.area as f64 / std::f64::consts::PI * r / rings as f64 * std::f64::consts::TAU
                    / sectors as f64;
                exact += cos * da / dir.length_squared();
            }
        }
        let estimate = sum / n as f64;
        assert!((estimate / exact - 1.0).abs() < 5e-3, "{estimate} vs {exact}");
    }
}
