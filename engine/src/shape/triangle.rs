//! Triangle `p0 p1 p2` with the watertight intersection of Woop, Benthin and Wald (JCGT 2013),
//! as pbrt-v4 writes it: the ray is made the +z axis by a permutation and a shear, the edge
//! functions are evaluated in that frame (in f64 when one is exactly zero), and a hit must lie
//! beyond a conservative bound on the error of `t`. Rays through a shared edge or vertex hit at
//! least one of the triangles sharing it. As a light, a triangle seen from close by is sampled
//! uniformly in its solid angle (Arvo, "Stratified Sampling of Spherical Triangles", SIGGRAPH
//! 1995, in the form of pbrt-v4's `SampleSphericalTriangle`), from afar by area.

use super::quad::SPHERICAL_SOLID_ANGLE;
use super::{
    LightSample, MeshPoint, Primitive, PrimitiveShape, ShapeError, ShapeModel, SurfacePoint,
    area_to_solid_angle,
};
use crate::format::V3;
use crate::math::gamma;
use glam::{Affine3A, DVec3, Vec2, Vec3A};
use obvhs::aabb::Aabb;

/// A triangle. Its normal is `normalize((p1 - p0) x (p2 - p0))`; its surface's uv is (b1, b2),
/// the barycentric weights of `p1` and `p2`, or the vertices' texture coordinates interpolated
/// by them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// Vertices.
    pub p: [Vec3A; 3],
    /// Texture coordinates of the vertices (a mesh's, where its file gives them).
    pub uv: Option<[Vec2; 3]>,
}

/// Triangles estimated to subtend less than this (steradians) are sampled by area. Measured at
/// 64 spp (mean relMSE of seeds 1-3 against 4096 spp, 2 threads, 2026-12-03) on a Cornell box
/// lit by a 300 x 300 square of two emitting triangles 120 units above the tall box: area
/// sampling relMSE 0.004641 in 1.32 s; spherical above 1 sr 0.004407 in 1.37 s, above 0.3
/// 0.003699 in 1.54 s, above 0.1 0.003357 in 1.94 s, above 0.03 0.003269 in 2.11 s. Time x
/// error is least at 0.3 (7% below area sampling); with cornell-smoke's light split into two
/// triangles 0.3 and area sampling are equal (0.00552 both). Quads keep their own bound,
/// measured on their scenes.
const SPHERICAL_MIN_ESTIMATE: f32 = 0.3;

impl Triangle {
    /// The cross product of the edges (twice the area, along the normal).
    #[inline]
    fn cross(&self) -> Vec3A {
        (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0])
    }

    /// The unit normal (zero for a triangle without area, which [`Self::new`] never makes).
    #[inline]
    pub(crate) fn normal(&self) -> Vec3A {
        crate::math::unit(self.cross()).unwrap_or(Vec3A::ZERO)
    }

    /// `None` when the vertices are collinear (no area) or the area is not finite.
    pub fn new(p0: Vec3A, p1: Vec3A, p2: Vec3A) -> Option<Self> {
        let t = Self { p: [p0, p1, p2], uv: None };
        let a = t.area();
        (a > 0.0 && a.is_finite()).then_some(t)
    }

    /// Barycentric weights of `p1` and `p2` at a point in the triangle's plane.
    #[inline]
    fn barycentric(&self, p: Vec3A) -> (f32, f32) {
        // v = b1 e1 + b2 e2, so v x e2 = b1 n and e1 x v = b2 n: one cross product each, which
        // stays accurate for thin triangles (the normal equations square their conditioning).
        let (e1, e2, v) = (self.p[1] - self.p[0], self.p[2] - self.p[0], p - self.p[0]);
        let n = e1.cross(e2);
        // A triangle 1e10 across squares its normal beyond `f32::MAX`: measure it in units of
        // its largest component there (elsewhere the scale is 1, and the bits are kept).
        let s = match n.length_squared() <= f32::MAX {
            true => 1.0,
            false => 1.0 / n.abs().max_element(),
        };
        let n = n * s;
        let inv = 1.0 / n.length_squared();
        let b1 = ((v.cross(e2) * s).dot(n) * inv).clamp(0.0, 1.0);
        let b2 = ((e1.cross(v) * s).dot(n) * inv).clamp(0.0, 1.0 - b1);
        (b1, b2)
    }

    /// Surface data at a point found by [`Self::intersect`]: the point is rebuilt from its
    /// barycentric weights, with pbrt's error bound gamma(7) sum |b_i p_i|.
    #[inline]
    pub fn surface(&self, p: Vec3A) -> SurfacePoint {
        let (b1, b2) = self.barycentric(p);
        self.surface_at(b1, b2)
    }

    /// The spherical triangle seen from `o`, when the triangle is estimated to subtend at least
    /// [`SPHERICAL_MIN_ESTIMATE`] (A cos / d^2 at the centroid, as quads estimate) and its exact
    /// solid angle is in [`SPHERICAL_SOLID_ANGLE`]; else the triangle is sampled by area.
    fn spherical(&self, o: Vec3A) -> Option<SphericalTriangle> {
        let c = (self.p[0] + self.p[1] + self.p[2]) * (1.0 / 3.0) - o;
        let d2 = c.length_squared();
        if 0.5 * self.cross().dot(c).abs() < SPHERICAL_MIN_ESTIMATE * d2 * d2.sqrt() {
            return None;
        }
        self.spherical_triangle(o)
    }

    /// The spherical triangle seen from `o` whatever its estimated solid angle, when the exact
    /// one is in [`SPHERICAL_SOLID_ANGLE`]. In f64: the vertices' directions, the angle at the
    /// first through its cosine and sine, and the solid angle by the formula of Van Oosterom and
    /// Strackee ("The Solid Angle of a Plane Triangle", IEEE Trans. Biomed. Eng. 1983), one
    /// `atan2` without the cancellation of the angle sum minus pi.
    fn spherical_triangle(&self, o: Vec3A) -> Option<SphericalTriangle> {
        let o = v64(o);
        let [a, b, c] = self.p.map(|p| (v64(p) - o).normalize_or_zero());
        let (n_ab, n_ca) = (a.cross(b).normalize_or_zero(), c.cross(a).normalize_or_zero());
        if n_ab == DVec3::ZERO || n_ca == DVec3::ZERO {
            return None;
        }
        // The angle at a is the one between the planes (o, a, b) and (o, a, c).
        let (cos_alpha, sin_alpha) = (-n_ab.dot(n_ca), n_ab.cross(n_ca).length());
        let triple = a.dot(b.cross(c)).abs();
        let s = 2.0 * libm::atan2(triple, 1.0 + a.dot(b) + b.dot(c) + c.dot(a));
        (SPHERICAL_SOLID_ANGLE.contains(&s) && sin_alpha > 0.0).then_some(SphericalTriangle {
            a,
            b,
            c,
            alpha: (cos_alpha, sin_alpha),
            s,
        })
    }

    fn surface_at(&self, b1: f32, b2: f32) -> SurfacePoint {
        let b0 = 1.0 - b1 - b2;
        let [p0, p1, p2] = self.p;
        let p = b0 * p0 + b1 * p1 + b2 * p2;
        let err = gamma(7) * (b0 * p0.abs() + b1 * p1.abs() + b2 * p2.abs()).max_element();
        let n = self.normal();
        // A mesh's interpolation (`accel::mesh`), so that its baked triangles read its uvs.
        let uv = match self.uv {
            None => Vec2::new(b1, b2),
            Some([t0, t1, t2]) => b0 * t0 + b1 * t1 + b2 * t2,
        };
        SurfacePoint { p, n, ns: n, ns_base: n, uv, err, on: MeshPoint::NONE }
    }
}

/// The end of [`Triangle::intersect`] for a triangle so large and so far from the ray's origin
/// that its scaled distance (edge functions times depths, about size^2 x distance) overflows
/// `f32` (a triangle 1e13 across seen from 3e13 away): the same distance and error bound, from
/// the same `f32` edge functions and sheared corners `q`, in `f64`.
#[cold]
fn far_intersect(e: [f32; 3], q: &[Vec3A; 3], tmax: f32) -> f32 {
    let e = e.map(f64::from);
    let z = q.map(|v| v.z as f64);
    let t = (e[0] * z[0] + e[1] * z[1] + e[2] * z[2]) / (e[0] + e[1] + e[2]);
    let max = |c: usize| q.iter().fold(0.0f64, |m, v| m.max(v[c].abs() as f64));
    let (max_x, max_y, max_z) = (max(0), max(1), max(2));
    let g = |n| gamma(n) as f64;
    let delta_z = g(3) * max_z;
    let delta_x = g(5) * (max_x + max_z);
    let delta_y = g(5) * (max_y + max_z);
    let delta_e = 2.0 * (g(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    let max_e = e.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    let det = e[0] + e[1] + e[2];
    let delta_t = 3.0 * (g(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) / det.abs();
    let hit = t > delta_t && (t as f32) < tmax;
    if hit { t as f32 } else { f32::INFINITY }
}

fn v64(v: Vec3A) -> DVec3 {
    DVec3::new(v.x as f64, v.y as f64, v.z as f64)
}

/// `v` less its component along the unit vector `w`, normalised (zero if nothing is left).
fn orthogonal(v: DVec3, w: DVec3) -> DVec3 {
    (v - v.dot(w) * w).normalize_or_zero()
}

/// A triangle as seen from a point: unit directions to its vertices, the cosine and sine of
/// the angle at `a`, and the solid angle `s`.
struct SphericalTriangle {
    a: DVec3,
    b: DVec3,
    c: DVec3,
    alpha: (f64, f64),
    s: f64,
}

impl SphericalTriangle {
    /// A direction uniform in the spherical triangle for the uniform numbers `u` (Arvo 1995):
    /// `u.x` chooses the sub-triangle (a, b, c') of area `u.x s`, `u.y` the point along the arc
    /// from b to c'.
    fn sample(&self, u: Vec2) -> DVec3 {
        let (a, b, c) = (self.a, self.b, self.c);
        let (cos_alpha, sin_alpha) = self.alpha;
        // The angle phi = A' - alpha, A' = u.x s + pi (the sub-triangle's angle sum).
        let (sin_p, cos_p) = libm::sincos(u.x as f64 * self.s + std::f64::consts::PI);
        let sin_phi = sin_p * cos_alpha - cos_p * sin_alpha;
        let cos_phi = cos_p * cos_alpha + sin_p * sin_alpha;
        let k1 = cos_phi + cos_alpha;
        let k2 = sin_phi - sin_alpha * a.dot(b);
        let cos_bp =
            (k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha) / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha);
        // NaN (a triangle that fills nearly the hemisphere) goes to an end of the arc.
        let cos_bp = if cos_bp.is_nan() { 1.0 } else { cos_bp.clamp(-1.0, 1.0) };
        let sin_bp = (1.0 - cos_bp * cos_bp).max(0.0).sqrt();
        let cp = cos_bp * a + sin_bp * orthogonal(c, a);
        let cos_t = 1.0 - u.y as f64 * (1.0 - cp.dot(b));
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        cos_t * b + sin_t * orthogonal(cp, b)
    }
}

/// A triangle in its own space, as a scene places it: normal (b - a) x (c - a).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleShape {
    /// First vertex.
    pub a: Vec3A,
    /// Second vertex.
    pub b: Vec3A,
    /// Third vertex.
    pub c: Vec3A,
}

/// Normal = normalize((b - a) x (c - a)); uv = barycentric weights of b and c; watertight
/// intersection (Woop et al. 2013).
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct TriangleDesc {
    /// First vertex.
    pub a: V3,
    /// Second vertex.
    pub b: V3,
    /// Third vertex (not on the line through the first two).
    pub c: V3,
}

impl ShapeModel for TriangleShape {
    type Desc = TriangleDesc;

    fn build(TriangleDesc { a, b, c }: TriangleDesc) -> Result<Self, String> {
        if !((b.0 - a.0).cross(c.0 - a.0).length_squared() > 0.0) {
            return Err(format!("Triangle has no area: {}, {} and {} are collinear", a.0, b.0, c.0));
        }
        Ok(Self { a: a.0.into(), b: b.0.into(), c: c.0.into() })
    }

    fn place(&self, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
        let [a, b, c] = [self.a, self.b, self.c].map(|p| m.transform_point3a(p));
        // A mirroring transform flips the winding; keep the normal facing the same side.
        let (b, c) = if m.matrix3.determinant() < 0.0 { (c, b) } else { (b, c) };
        let t = Triangle::new(a, b, c).ok_or(ShapeError::FlatTriangle(a, b, c))?;
        out.push(Primitive::Triangle(t));
        Ok(())
    }
}

impl PrimitiveShape for Triangle {
    /// Bounding box.
    fn aabb(&self) -> Aabb {
        let mut b = Aabb::empty();
        for p in self.p {
            b.extend(p);
        }
        b
    }

    /// Smallest `t` in `(0, tmax)` where `o + t d` meets the triangle, or `f32::INFINITY`.
    #[inline]
    fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        const MISS: f32 = f32::INFINITY;
        // Translate to the ray origin, permute so that z is d's largest axis, shear d to +z.
        let kz = d.abs().max_position();
        let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
        let perm = |v: Vec3A| Vec3A::new(v[kx], v[ky], v[kz]);
        let dp = perm(d);
        let (sx, sy, sz) = (-dp.x / dp.z, -dp.y / dp.z, 1.0 / dp.z);
        let mut q = self.p.map(|p| perm(p - o));
        for v in &mut q {
            v.x += sx * v.z;
            v.y += sy * v.z;
        }
        let edge = |a: Vec3A, b: Vec3A| a.x * b.y - a.y * b.x;
        let (mut e0, mut e1, mut e2) = (edge(q[1], q[2]), edge(q[2], q[0]), edge(q[0], q[1]));
        if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
            // On an edge in f32: decide in f64, which is exact for products of f32 values.
            let edge64 = |a: Vec3A, b: Vec3A| (a.x as f64 * b.y as f64 - a.y as f64 * b.x as f64) as f32;
            (e0, e1, e2) = (edge64(q[1], q[2]), edge64(q[2], q[0]), edge64(q[0], q[1]));
        }
        if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
            return MISS;
        }
        if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
            // The ray passes exactly through an edge or a vertex. Of the triangles sharing it,
            // only the one for which the edge is a "top-left" edge (in the ray's frame, with
            // the winding made positive) takes the hit: exactly one, which keeps the parity of
            // hits through closed meshes (media boundaries) right.
            let s = (e0 + e1 + e2).signum();
            let top_left = |a: Vec3A, b: Vec3A| {
                let (dx, dy) = (s * (b.x - a.x), s * (b.y - a.y));
                dy > 0.0 || (dy == 0.0 && dx < 0.0)
            };
            if (e0 == 0.0 && !top_left(q[1], q[2]))
                || (e1 == 0.0 && !top_left(q[2], q[0]))
                || (e2 == 0.0 && !top_left(q[0], q[1]))
            {
                return MISS;
            }
        }
        let det = e0 + e1 + e2;
        if det == 0.0 {
            return MISS;
        }
        for v in &mut q {
            v.z *= sz;
        }
        let t_scaled = e0 * q[0].z + e1 * q[1].z + e2 * q[2].z;
        if !t_scaled.is_finite() {
            return far_intersect([e0, e1, e2], &q, tmax);
        }
        if det < 0.0 && (t_scaled >= 0.0 || t_scaled < tmax * det) {
            return MISS;
        }
        if det > 0.0 && (t_scaled <= 0.0 || t_scaled > tmax * det) {
            return MISS;
        }
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        // t must exceed the bound on its own rounding error (pbrt-v4 6.8.5).
        let max_z = q[0].z.abs().max(q[1].z.abs()).max(q[2].z.abs());
        let max_x = q[0].x.abs().max(q[1].x.abs()).max(q[2].x.abs());
        let max_y = q[0].y.abs().max(q[1].y.abs()).max(q[2].y.abs());
        let delta_z = gamma(3) * max_z;
        let delta_x = gamma(5) * (max_x + max_z);
        let delta_y = gamma(5) * (max_y + max_z);
        let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
        let max_e = e0.abs().max(e1.abs()).max(e2.abs());
        let delta_t = 3.0 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) * inv_det.abs();
        if t <= delta_t || t >= tmax { MISS } else { t }
    }

    #[inline(always)]
    fn surface(&self, p: Vec3A, _uv: bool) -> SurfacePoint {
        Triangle::surface(self, p)
    }

    /// Area.
    fn area(&self) -> f32 {
        0.5 * crate::math::length(self.cross())
    }

    fn sample_area(&self, u: Vec2) -> Option<LightSample> {
        let su = u.x.sqrt();
        let sp = self.surface_at(su * (1.0 - u.y), su * u.y);
        Some(LightSample { p: sp.p, n: sp.n, pdf: 1.0 / self.area(), err: sp.err })
    }

    /// Samples a point of the triangle as seen from `from`: uniformly in its solid angle where
    /// it is estimated to subtend at least 0.3 sr, else uniformly by area (the square-root
    /// parameterisation); the density is returned in solid angle.
    fn sample_solid_angle(&self, from: Vec3A, u: Vec2) -> LightSample {
        if let Some(t) = self.spherical(from) {
            // The sampled direction meets the plane at barycentrics found as Moller and
            // Trumbore do, in f64 (clamped: the direction may graze an edge; one parallel to
            // the plane, which rounding alone could give, takes the centroid).
            let w = t.sample(u);
            let [p0, p1, p2] = self.p.map(v64);
            let (e1, e2, o) = (p1 - p0, p2 - p0, v64(from) - p0);
            let s1 = w.cross(e2);
            let inv = 1.0 / s1.dot(e1);
            let (b1, b2) = if inv.is_finite() {
                ((o.dot(s1) * inv).clamp(0.0, 1.0), (w.dot(o.cross(e1)) * inv).clamp(0.0, 1.0))
            } else {
                (1.0 / 3.0, 1.0 / 3.0)
            };
            let sum = (b1 + b2).max(1.0);
            let sp = self.surface_at((b1 / sum) as f32, (b2 / sum) as f32);
            return LightSample { p: sp.p, n: sp.n, pdf: (1.0 / t.s) as f32, err: sp.err };
        }
        let su = u.x.sqrt();
        let sp = self.surface_at(su * (1.0 - u.y), su * u.y);
        LightSample {
            p: sp.p,
            n: sp.n,
            pdf: area_to_solid_angle(1.0 / self.area(), from, sp.p, sp.n),
            err: sp.err,
        }
    }

    /// Solid-angle density of [`Self::sample_solid_angle`] for the point `p` seen from `from`.
    fn pdf_solid_angle(&self, from: Vec3A, p: Vec3A, _n: Vec3A) -> f32 {
        match self.spherical(from) {
            Some(t) => (1.0 / t.s) as f32,
            None => area_to_solid_angle(1.0 / self.area(), from, p, self.normal()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Triangle {
        Triangle::new(Vec3A::new(0.0, 0.0, 0.0), Vec3A::new(2.0, 0.0, 0.0), Vec3A::new(0.0, 2.0, 0.0))
            .unwrap()
    }

    #[test]
    fn hits_inside_misses_outside_and_respects_tmax() {
        let t = tri();
        assert_eq!(t.intersect(Vec3A::new(0.5, 0.5, 3.0), -Vec3A::Z, f32::INFINITY), 3.0);
        assert_eq!(t.intersect(Vec3A::new(0.5, 0.5, -3.0), Vec3A::new(0.0, 0.0, 2.0), f32::INFINITY), 1.5);
        assert_eq!(t.intersect(Vec3A::new(1.5, 1.5, 3.0), -Vec3A::Z, f32::INFINITY), f32::INFINITY);
        assert_eq!(t.intersect(Vec3A::new(0.5, 0.5, 3.0), -Vec3A::Z, 2.9), f32::INFINITY);
        assert_eq!(t.intersect(Vec3A::new(0.5, 0.5, 3.0), Vec3A::Z, f32::INFINITY), f32::INFINITY);
        // Parallel to the plane.
        assert_eq!(t.intersect(Vec3A::new(0.5, 0.5, 0.0), Vec3A::X, f32::INFINITY), f32::INFINITY);
        let sp = t.surface(Vec3A::new(0.5, 0.5, 0.0));
        assert_eq!((sp.n, sp.uv), (Vec3A::Z, Vec2::new(0.25, 0.25)));
    }

    #[test]
    fn watertight_across_shared_edges_and_vertices() {
        // A fan of triangles around the origin sharing edges and the centre vertex: every ray
        // aimed at the fan, exactly at edges and at the shared vertex included, hits one.
        let n = 7;
        let ring: Vec<Vec3A> = (0..n)
            .map(|i| {
                let a = i as f32 / n as f32 * std::f32::consts::TAU;
                Vec3A::new(a.cos(), a.sin(), 0.1 * (3.0 * a).sin())
            })
            .collect();
        let fan: Vec<Triangle> =
            (0..n).map(|i| Triangle::new(Vec3A::ZERO, ring[i], ring[(i + 1) % n]).unwrap()).collect();
        let origin = Vec3A::new(0.013, -0.021, 5.0);
        let mut targets = vec![Vec3A::ZERO];
        for (i, r) in ring.iter().enumerate() {
            for k in 1..64 {
                targets.push(*r * (k as f32 / 64.0)); // along the shared edge
                targets.push(r.lerp(ring[(i + 1) % n], k as f32 / 64.0) * 0.999); // inside, near the rim
            }
        }
        for target in targets {
            let d = target - origin;
            let hits = fan.iter().filter(|t| t.intersect(origin, d, f32::INFINITY).is_finite()).count();
            assert!(hits >= 1, "a ray at {target} went through the fan");
            assert!(hits <= 1, "a ray at {target} hit {hits} triangles of the fan");
        }
        // Exactly through the shared (diagonal) edge, axis-aligned. (The square's outer corners
        // are not shared: the fill rule may leave them to a neighbour that is not there.)
        let square = [
            Triangle::new(Vec3A::ZERO, Vec3A::X, Vec3A::new(1.0, 1.0, 0.0)).unwrap(),
            Triangle::new(Vec3A::ZERO, Vec3A::new(1.0, 1.0, 0.0), Vec3A::Y).unwrap(),
        ];
        for (x, y) in [(0.5, 0.5), (0.25, 0.25), (0.75, 0.75)] {
            for dir in [-Vec3A::Z, Vec3A::Z] {
                let o = Vec3A::new(x, y, 0.0) - 3.0 * dir;
                let hits = square.iter().filter(|t| t.intersect(o, dir, f32::INFINITY).is_finite()).count();
                assert_eq!(hits, 1, "({x}, {y}) along {dir}");
            }
        }
    }

    #[test]
    fn uniform_area_sampling_density() {
        let t = tri();
        let from = Vec3A::new(0.3, 0.4, 2.0);
        for i in 0..100 {
            let u = Vec2::new((i as f32 + 0.5) / 100.0, ((i * 37) % 100) as f32 / 100.0);
            let ls = t.sample_solid_angle(from, u);
            // Points on the boundary belong to the triangle only on its "top-left" edges.
            let (b1, b2) = t.barycentric(ls.p);
            let boundary = b1 == 0.0 || b2 == 0.0 || b1 + b2 >= 1.0;
            assert!(t.intersect(from, ls.p - from, 2.0).is_finite() || boundary);
            assert!((ls.pdf / t.pdf_solid_angle(from, ls.p, ls.n) - 1.0).abs() < 1e-5);
        }
    }

    /// A triangle that points near it see as a large solid angle, and such points on its two
    /// sides (the estimate A cos / d^2 at the centroid is 5 to 9 sr).
    fn big() -> (Triangle, [Vec3A; 2]) {
        let t = Triangle::new(
            Vec3A::new(-1.0, -1.0, 1.0),
            Vec3A::new(1.5, -1.0, 1.0),
            Vec3A::new(-1.0, 1.5, 1.2),
        )
        .unwrap();
        (t, [Vec3A::new(0.1, -0.2, 0.4), Vec3A::new(-0.3, 0.2, 1.6)])
    }

    /// The point of barycentrics (b1, b2), in f32.
    fn at(t: &Triangle, b1: f32, b2: f32) -> Vec3A {
        t.p[0] + b1 * (t.p[1] - t.p[0]) + b2 * (t.p[2] - t.p[0])
    }

    /// Solid angle of `t` seen from `o` by brute force: the sum of A cos / d^2 over a fine
    /// subdivision into similar triangles.
    fn solid_angle_by_area(t: &Triangle, o: Vec3A) -> f64 {
        let g = 300;
        let n = t.cross().normalize();
        let mut sum = 0.0f64;
        let mut add = |p: Vec3A| {
            let d = p - o;
            let r2 = d.length_squared() as f64;
            sum += (n.dot(d).abs() as f64 / r2.sqrt()) / r2;
        };
        let gf = g as f32;
        for i in 0..g {
            for j in 0..g - i {
                let (x, y) = (i as f32, j as f32);
                add(at(t, (x + 1.0 / 3.0) / gf, (y + 1.0 / 3.0) / gf));
                if i + j < g - 1 {
                    add(at(t, (x + 2.0 / 3.0) / gf, (y + 2.0 / 3.0) / gf));
                }
            }
        }
        sum * t.area() as f64 / (g * g) as f64
    }

    #[test]
    fn spherical_triangles_have_the_solid_angle_of_the_triangle() {
        let (t, near) = big();
        for o in near.into_iter().chain([Vec3A::new(2.0, 2.0, 0.5), Vec3A::new(0.0, 0.0, -3.0)]) {
            let exact = solid_angle_by_area(&t, o);
            let s = t.spherical_triangle(o).expect("in range").s;
            assert!((s / exact - 1.0).abs() < 1e-4, "{o}: {s} vs {exact}");
        }
        // Points near the triangle take the spherical triangle, far ones area sampling.
        for o in near {
            assert!(t.spherical(o).is_some(), "{o}");
        }
        let far = Vec3A::new(0.0, 0.0, -30.0);
        assert!(t.spherical(far).is_none());
        let ls = t.sample_solid_angle(far, Vec2::new(0.3, 0.6));
        assert_eq!(ls.pdf, area_to_solid_angle(1.0 / t.area(), far, ls.p, ls.n));
    }

    #[test]
    fn spherical_samples_are_uniform_in_solid_angle() {
        // Chi-square test of the sampled points against uniform density in solid angle, from
        // both sides: the bins are the g^2 similar triangles of a subdivision, each expecting
        // its own solid angle over the whole.
        let (t, near) = big();
        let g = 8;
        let cell = |i: usize, j: usize, upper: bool| {
            let (x, y, gf) = (i as f32, j as f32, g as f32);
            let c = |dx: f32, dy: f32| at(&t, (x + dx) / gf, (y + dy) / gf);
            let v = if upper {
                [c(1.0, 0.0), c(1.0, 1.0), c(0.0, 1.0)]
            } else {
                [c(0.0, 0.0), c(1.0, 0.0), c(0.0, 1.0)]
            };
            Triangle::new(v[0], v[1], v[2]).unwrap()
        };
        for o in near {
            let total = t.spherical(o).unwrap().s;
            let n = 200_000;
            let mut observed = vec![0usize; 2 * g * g];
            let mut rng = crate::testing::uniform(17);
            for _ in 0..n {
                let ls = t.sample_solid_angle(o, Vec2::new(rng(), rng()));
                assert!((ls.pdf as f64 * total - 1.0).abs() < 1e-6);
                assert_eq!(t.pdf_solid_angle(o, ls.p, ls.n), ls.pdf);
                let (b1, b2) = t.barycentric(ls.p);
                let (x, y) = (b1 * g as f32, b2 * g as f32);
                let i = (x as usize).min(g - 1);
                let j = (y as usize).min(g - 1 - i);
                let upper = x - i as f32 + y - j as f32 > 1.0 && i + j < g - 1;
                observed[i * g + j + if upper { g * g } else { 0 }] += 1;
            }
            let mut chi2 = 0.0;
            for i in 0..g {
                for j in 0..g - i {
                    for upper in [false, true] {
                        if upper && i + j == g - 1 {
                            continue;
                        }
                        let expected = cell(i, j, upper).spherical_triangle(o).unwrap().s / total * n as f64;
                        let seen = observed[i * g + j + if upper { g * g } else { 0 }] as f64;
                        chi2 += (seen - expected).powi(2) / expected;
                    }
                }
            }
            let critical = crate::material::chi2::chi2_critical(g * g - 1);
            assert!(chi2 < critical, "{o}: chi2 {chi2} >= {critical}");
        }
    }

    #[test]
    fn light_samples_are_finite_points_of_the_triangle_from_anywhere() {
        // Points near the plane, on it, at the vertices, far and very close: every sample lies
        // on the triangle with a finite positive density (or none, exactly on the plane) and
        // the density evaluated at it agrees with the one sampled.
        let t = Triangle::new(
            Vec3A::new(-1.0, -1.0, 0.0),
            Vec3A::new(2.0, -1.0, 0.0),
            Vec3A::new(-1.0, 3.0, 0.0),
        )
        .unwrap();
        let mut rng = crate::testing::signed(5);
        let mut u = crate::testing::uniform(9);
        let mut spherical = 0;
        for k in 0..20_000 {
            let (o, z) = crate::testing::near_plane(k, &mut rng);
            // Every seventh point above a vertex.
            let o = if k % 7 == 0 { t.p[k as usize % 3] + Vec3A::new(0.0, 0.0, z) } else { o };
            spherical += t.spherical(o).is_some() as usize;
            let ls = t.sample_solid_angle(o, Vec2::new(u().min(0.999_999), u().min(0.999_999)));
            assert!(ls.p.is_finite(), "{o}: {}", ls.p);
            let (b1, b2) = t.barycentric(ls.p);
            assert!((at(&t, b1, b2) - ls.p).length() < 1e-5, "{o}: {} off the triangle", ls.p);
            assert!(ls.pdf >= 0.0 && !ls.pdf.is_nan(), "{o}: pdf {}", ls.pdf);
            if ls.pdf.is_finite() && ls.pdf > 0.0 {
                assert_eq!(t.pdf_solid_angle(o, ls.p, ls.n), ls.pdf, "{o}");
            }
        }
        assert!(spherical > 1000, "only {spherical} points sampled the spherical triangle");
    }
}
