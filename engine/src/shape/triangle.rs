//! Triangle `p0 p1 p2` with the watertight intersection of Woop, Benthin and Wald (JCGT 2013),
//! as pbrt-v4 writes it: the ray is made the +z axis by a permutation and a shear, the edge
//! functions are evaluated in that frame (in f64 when one is exactly zero), and a hit must lie
//! beyond a conservative bound on the error of `t`. Rays through a shared edge or vertex hit at
//! least one of the triangles sharing it.

use super::{
    LightSample, Primitive, PrimitiveShape, ShapeError, ShapeModel, SurfacePoint, area_to_solid_angle,
};
use crate::math::gamma;
use glam::{Affine3A, Vec2, Vec3A};
use obvhs::aabb::Aabb;

/// A triangle. Its normal is `normalize((p1 - p0) x (p2 - p0))`; `uv` = (b1, b2), the
/// barycentric weights of `p1` and `p2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// Vertices.
    pub p: [Vec3A; 3],
}

impl Triangle {
    /// The cross product of the edges (twice the area, along the normal).
    #[inline]
    fn cross(&self) -> Vec3A {
        (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0])
    }

    /// `None` when the vertices are collinear (no area) or the area is not finite.
    pub fn new(p0: Vec3A, p1: Vec3A, p2: Vec3A) -> Option<Self> {
        let t = Self { p: [p0, p1, p2] };
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
        let inv = 1.0 / n.length_squared();
        let b1 = (v.cross(e2).dot(n) * inv).clamp(0.0, 1.0);
        let b2 = (e1.cross(v).dot(n) * inv).clamp(0.0, 1.0 - b1);
        (b1, b2)
    }

    /// Surface data at a point found by [`Self::intersect`]: the point is rebuilt from its
    /// barycentric weights, with pbrt's error bound gamma(7) sum |b_i p_i|.
    #[inline]
    pub fn surface(&self, p: Vec3A) -> SurfacePoint {
        let (b1, b2) = self.barycentric(p);
        self.surface_at(b1, b2)
    }

    fn surface_at(&self, b1: f32, b2: f32) -> SurfacePoint {
        let b0 = 1.0 - b1 - b2;
        let [p0, p1, p2] = self.p;
        let p = b0 * p0 + b1 * p1 + b2 * p2;
        let err = gamma(7) * (b0 * p0.abs() + b1 * p1.abs() + b2 * p2.abs()).max_element();
        let n = self.cross().normalize();
        SurfacePoint { p, n, ns: n, uv: Vec2::new(b1, b2), err }
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

impl ShapeModel for TriangleShape {
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
        0.5 * self.cross().length()
    }

    /// Samples a point uniformly by area (the square-root parameterisation).
    fn sample_solid_angle(&self, from: Vec3A, u: Vec2) -> LightSample {
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
        area_to_solid_angle(1.0 / self.area(), from, p, self.cross().normalize())
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
}
