//! Parallelogram `Q + a u + b v`, a, b in [0, 1] (SEED.md section 2.3.2).

use super::{LightSample, SurfacePoint, area_to_solid_angle};
use crate::math::gamma;
use glam::{Vec2, Vec3A};
use obvhs::aabb::Aabb;

/// A parallelogram. Its normal is `normalize(u x v)`; `uv` = (a, b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad {
    /// Corner.
    pub q: Vec3A,
    /// First edge.
    pub u: Vec3A,
    /// Second edge.
    pub v: Vec3A,
    /// Unit normal `normalize(u x v)`.
    pub n: Vec3A,
    /// `(u x v) / |u x v|^2`, which turns cross products into the coordinates (a, b).
    w: Vec3A,
    /// Area `|u x v|`.
    pub area: f32,
}

impl Quad {
    /// Builds a quad; `None` when `u` and `v` are parallel or zero (no area), or the area is
    /// too small for `f32` (below about 1e-38).
    pub fn new(q: Vec3A, u: Vec3A, v: Vec3A) -> Option<Self> {
        let c = u.cross(v);
        // |c|^2 overflows for edges near 1e10: work with c scaled to a largest component of 1.
        let k = c.abs().max_element();
        let cs = c / k;
        let len = cs.length();
        let (n, w, area) = (cs / len, cs / (k * len * len), k * len);
        (k > 0.0 && w.is_finite() && area.is_finite()).then_some(Self { q, u, v, n, w, area })
    }

    /// Error bound of points computed as `q + a u + b v`, scaled by the conditioning
    /// `|u| |v| / |u x v|` of the edges: the intersection test's plane (through `q`, normal
    /// `n`) tilts from the true one by the error of `n`, which grows as the edges near
    /// parallel (a quad with edges 5 degrees apart re-hit itself at t = 4e-5 in the property
    /// tests). For perpendicular edges the factor is 1.
    #[inline]
    pub fn point_error(&self) -> f32 {
        let cond = (self.u.length() * self.v.length() / self.area).max(1.0);
        gamma(4) * (self.q.abs() + self.u.abs() + self.v.abs()).max_element() * cond
    }

    /// Bounding box.
    pub fn aabb(&self) -> Aabb {
        let mut b = Aabb::empty();
        for p in [self.q, self.q + self.u, self.q + self.v, self.q + self.u + self.v] {
            b.extend(p);
        }
        b
    }

    /// Smallest `t` in `(0, tmax)` where `o + t d` meets the quad, or `f32::INFINITY`.
    #[inline]
    pub fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        quad_t(self.kernel(), o.to_array(), d.to_array(), tmax)
    }

    /// The data of the intersection kernel: q, u, v, n, w.
    #[inline]
    pub fn kernel(&self) -> [[f32; 3]; 5] {
        [self.q, self.u, self.v, self.n, self.w].map(|x| x.to_array())
    }

    /// Surface data at the point `p`, re-projected onto the plane as `Q + a u + b v`.
    #[inline]
    pub fn surface(&self, p: Vec3A) -> SurfacePoint {
        let ph = p - self.q;
        let a = self.w.dot(ph.cross(self.v)).clamp(0.0, 1.0);
        let b = self.w.dot(self.u.cross(ph)).clamp(0.0, 1.0);
        SurfacePoint {
            p: self.q + a * self.u + b * self.v,
            n: self.n,
            ns: self.n,
            uv: Vec2::new(a, b),
            err: self.point_error(),
        }
    }

    /// Samples a point uniformly by area; the density is returned in solid angle at `from`.
    pub fn sample_solid_angle(&self, from: Vec3A, u: Vec2) -> LightSample {
        let p = self.q + u.x * self.u + u.y * self.v;
        LightSample {
            p,
            n: self.n,
            pdf: area_to_solid_angle(1.0 / self.area, from, p, self.n),
            err: self.point_error(),
        }
    }

    /// Solid-angle density of [`Self::sample_solid_angle`] for the point `p` seen from `from`.
    pub fn pdf_solid_angle(&self, from: Vec3A, p: Vec3A) -> f32 {
        area_to_solid_angle(1.0 / self.area, from, p, self.n)
    }
}

#[inline(always)]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline(always)]
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// The quad test on plain numbers (`k` = q, u, v, n, w), branch-free so that a loop over many
/// rays vectorises; the single-ray and the stream tests both use it, so they agree to the bit.
#[inline(always)]
pub fn quad_t(k: [[f32; 3]; 5], o: [f32; 3], d: [f32; 3], tmax: f32) -> f32 {
    let [q, u, v, n, w] = k;
    let denom = dot(n, d);
    let t = dot(n, [q[0] - o[0], q[1] - o[1], q[2] - o[2]]) / denom;
    let ph = [o[0] + t * d[0] - q[0], o[1] + t * d[1] - q[1], o[2] + t * d[2] - q[2]];
    let a = dot(w, cross(ph, v));
    let b = dot(w, cross(u, ph));
    let hit = denom != 0.0 && t > 0.0 && t < tmax && a >= 0.0 && a <= 1.0 && b >= 0.0 && b <= 1.0;
    if hit { t } else { f32::INFINITY }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Quad {
        Quad::new(Vec3A::ZERO, Vec3A::X, Vec3A::Y).unwrap()
    }

    #[test]
    fn hit_inside_and_uv() {
        let q = unit();
        let o = Vec3A::new(0.25, 0.75, -2.0);
        let t = q.intersect(o, Vec3A::Z, f32::INFINITY);
        assert!((t - 2.0).abs() < 1e-6);
        let sp = q.surface(o + t * Vec3A::Z);
        assert!((sp.uv - Vec2::new(0.25, 0.75)).length() < 1e-6);
        assert_eq!(sp.n, Vec3A::Z);
        // From the back side as well: geometry is two-sided.
        assert!(q.intersect(Vec3A::new(0.5, 0.5, 1.0), -Vec3A::Z, f32::INFINITY).is_finite());
    }

    #[test]
    fn miss_outside_parallel_behind() {
        let q = unit();
        assert_eq!(q.intersect(Vec3A::new(1.5, 0.5, -1.0), Vec3A::Z, f32::INFINITY), f32::INFINITY);
        assert_eq!(q.intersect(Vec3A::new(0.5, 0.5, -1.0), Vec3A::X, f32::INFINITY), f32::INFINITY);
        assert_eq!(q.intersect(Vec3A::new(0.5, 0.5, 1.0), Vec3A::Z, f32::INFINITY), f32::INFINITY);
        assert_eq!(q.intersect(Vec3A::new(0.5, 0.5, -1.0), Vec3A::Z, 0.5), f32::INFINITY);
    }

    #[test]
    fn grazing_rays_hit_edges_consistently() {
        let q = unit();
        // A ray almost parallel to the plane still finds the right point.
        let d = Vec3A::new(1.0, 0.0, 1e-4).normalize();
        let o = Vec3A::new(-1000.0, 0.5, -0.1);
        let t = q.intersect(o, d, f32::INFINITY);
        assert!(t.is_finite());
        let p = o + t * d;
        assert!(p.z.abs() < 1e-3 && (0.0..=1.0).contains(&p.x), "{p}");
    }

    #[test]
    fn degenerate_quads_are_rejected() {
        assert!(Quad::new(Vec3A::ZERO, Vec3A::X, Vec3A::X * 2.0).is_none());
        assert!(Quad::new(Vec3A::ZERO, Vec3A::ZERO, Vec3A::Y).is_none());
    }

    #[test]
    fn area_pdf_matches_geometry() {
        let q = Quad::new(Vec3A::new(-1.0, -1.0, 2.0), Vec3A::X * 2.0, Vec3A::Y * 2.0).unwrap();
        let ls = q.sample_solid_angle(Vec3A::ZERO, Vec2::splat(0.5));
        assert!((ls.p - Vec3A::new(0.0, 0.0, 2.0)).length() < 1e-6);
        assert!((ls.pdf - 4.0 / 4.0).abs() < 1e-6, "dist^2 / (A cos) = 4 / 4");
    }
}
