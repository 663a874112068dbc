//! Parallelogram `Q + a u + b v`, a, b in [0, 1] (Shirley, "Ray Tracing: The Next Week",
//! "Quadrilaterals").

use super::{
    LightSample, MeshPoint, Primitive, PrimitiveShape, ShapeError, ShapeModel, SurfacePoint,
    area_to_solid_angle,
};
use crate::format::V3;
use crate::math::{dot3 as dot, gamma};
use glam::{Affine3A, Vec2, Vec3A};
use obvhs::aabb::Aabb;

/// A parallelogram. Its normal is `normalize(u x v)`, or its opposite ([`Self::flipped`]);
/// `uv` = (a, b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad {
    /// Corner.
    pub q: Vec3A,
    /// First edge.
    pub u: Vec3A,
    /// Second edge.
    pub v: Vec3A,
    /// Unit normal `normalize(u x v)` (or its opposite).
    pub n: Vec3A,
    /// `v x w` and `w x u` for `w = (u x v) / |u x v|^2`: the coordinates (a, b) of a point
    /// `q + ph` of the plane are `ea . ph` and `eb . ph` (the triple products `w . (ph x v)`
    /// and `w . (u x ph)`), with nothing to compute per ray.
    ea: Vec3A,
    eb: Vec3A,
    /// Area `|u x v|`.
    pub area: f32,
    /// [`Self::point_error`].
    err: f32,
    /// The edges are perpendicular: lights are sampled by solid angle.
    rect: bool,
}

/// A quad light as plain numbers, for sampling many points at once: what
/// [`Quad::sample_solid_angle`] reads when it samples by area, and the
/// light's emission (without textures). Computed with the same operations as the quad's own
/// methods, so that a lane-wise sampler reproduces their bits.
#[derive(Clone, Copy, Debug)]
pub struct QuadLight {
    /// Corner.
    pub q: [f32; 3],
    /// Edges.
    pub u: [f32; 3],
    /// Second edge.
    pub v: [f32; 3],
    /// Unit normal.
    pub n: [f32; 3],
    /// `q + 0.5 (u + v)`, where the spherical-rectangle bound measures from.
    pub center: [f32; 3],
    /// Area.
    pub area: f32,
    /// `1 / area`.
    pub inv_area: f32,
    /// Error bound of its points.
    pub err: f32,
    /// The edges are perpendicular: points close to the light take the spherical rectangle.
    pub rect: bool,
    /// Emitted radiance.
    pub emit: [f32; 3],
    /// Emits on both sides.
    pub two_sided: bool,
}

/// Solid angles outside this range are sampled by area: below it the two densities agree
/// closely and the spherical mapping loses precision, above it the point is almost on the
/// plane inside the rectangle (the bounds of pbrt-v4's `DiffuseAreaLight`).
pub(super) const SPHERICAL_SOLID_ANGLE: std::ops::Range<f64> = 3e-4..6.22;

/// Rectangles estimated to subtend less than this (steradians) are sampled by area. Spherical
/// sampling costs about 400 cycles (f64 square roots and divisions, `atan2`, `sincos`) against
/// 20 for area sampling, and the light's pdf pays the set-up again for every BSDF-sampled hit
/// on it. Measured at 64 spp (mean relMSE of seeds 1-3, one thread, 2026-12-02) at a bound of
/// 0.1 against 1: cornell-diffuse relMSE 0.001769 vs 0.001826 but 7% more time; cornell-smoke
/// 0.002554 vs 0.003173 for 39% more time: at equal error 1 is 4% and 11% faster (and 0.3
/// is worse than both on cornell-smoke). What remains spherical are points within about a
/// light's size of it, where area sampling's density falls off as cos / d^2.
pub const SPHERICAL_MIN_ESTIMATE: f32 = 1.0;

/// A rectangle as seen from a point: the spherical rectangle of Urena, Fajardo and King, "An
/// Area-Preserving Parametrization for Spherical Rectangles" (EGSR 2013), in the rectangle's
/// frame (x along `u`, y along `v`, z so that the point lies at z0 < 0 below the corner), in
/// f64. The interior angles g_i enter only through cos and sin, which are algebraic in the
/// corner coordinates, so the solid angle needs one `atan2` (of a product of unit complex
/// numbers: no cancellation in the sum of angles minus 2 pi) and a sample one `sincos`. The
/// transcendental functions are the `libm` crate's, the same bits on every x86-64 CPU.
struct SphericalRect {
    x0: f64,
    y0: f64,
    z0: f64,
    x1: f64,
    y1: f64,
    /// z components of the edge-plane normals n0 and n2.
    b0: f64,
    b1: f64,
    /// cos and sin of k = 2 pi - g2 - g3.
    k: (f64, f64),
    /// Solid angle.
    s: f64,
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
        let rect = u.normalize().dot(v.normalize()).abs() < 1e-5;
        let (ea, eb) = (v.cross(w), w.cross(u));
        // Conditioning of the edges, for `point_error`.
        let cond = (u.length() * v.length() / area).max(1.0);
        let err = gamma(4) * (q.abs() + u.abs() + v.abs()).max_element() * cond;
        let finite = w.is_finite() && ea.is_finite() && eb.is_finite() && area.is_finite();
        (k > 0.0 && finite).then_some(Self { q, u, v, n, ea, eb, area, err, rect })
    }

    /// The same quad facing the other way: normal `-normalize(u x v)`, the same points, uv
    /// and intersections (the plane test's `t` is a ratio of two dot products with the normal,
    /// so its sign cancels to the bit).
    pub fn flipped(self) -> Self {
        Self { n: -self.n, ..self }
    }

    /// Error bound of points computed as `q + a u + b v`, scaled by the conditioning
    /// `|u| |v| / |u x v|` of the edges: the intersection test's plane (through `q`, normal
    /// `n`) tilts from the true one by the error of `n`, which grows as the edges near
    /// parallel (a quad with edges 5 degrees apart re-hit itself at t = 4e-5 in the property
    /// tests). For perpendicular edges the factor is 1.
    #[inline]
    pub fn point_error(&self) -> f32 {
        self.err
    }

    /// The data of the intersection kernel: q, n, ea, eb.
    #[inline]
    pub fn kernel(&self) -> [[f32; 3]; 4] {
        [self.q, self.n, self.ea, self.eb].map(|x| x.to_array())
    }

    /// Surface data at the point `p`, re-projected onto the plane as `Q + a u + b v`.
    #[inline]
    pub fn surface(&self, p: Vec3A) -> SurfacePoint {
        let ph = p - self.q;
        let a = self.ea.dot(ph).clamp(0.0, 1.0);
        let b = self.eb.dot(ph).clamp(0.0, 1.0);
        SurfacePoint {
            p: self.q + a * self.u + b * self.v,
            n: self.n,
            ns: self.n,
            ns_base: self.n,
            uv: Vec2::new(a, b),
            err: self.point_error(),
            on: MeshPoint::NONE,
        }
    }

    /// The quad as a light for lanes of points, emitting `emit` (on both sides if
    /// `two_sided`): see [`QuadLight`].
    pub fn light(&self, emit: [f32; 3], two_sided: bool) -> QuadLight {
        QuadLight {
            q: self.q.to_array(),
            u: self.u.to_array(),
            v: self.v.to_array(),
            n: self.n.to_array(),
            // The same expression as in `spherical`, so the same bits.
            center: (self.q + 0.5 * (self.u + self.v)).to_array(),
            area: self.area,
            inv_area: 1.0 / self.area,
            err: self.point_error(),
            rect: self.rect,
            emit,
            two_sided,
        }
    }

    /// The spherical rectangle seen from `o`, when the quad is a rectangle whose solid angle is
    /// in [`SPHERICAL_SOLID_ANGLE`].
    fn spherical(&self, o: Vec3A) -> Option<SphericalRect> {
        if !self.rect {
            return None;
        }
        // Where the rectangle subtends little, area sampling is about as good and much cheaper:
        // a first estimate of the solid angle, A cos / d^2 at the centre, decides.
        // `QuadLight::center` and the lanes' bound repeat these operations.
        let c = self.q + 0.5 * (self.u + self.v) - o;
        let d2 = c.length_squared();
        if self.area * self.n.dot(c).abs() < SPHERICAL_MIN_ESTIMATE * d2 * d2.sqrt() {
            return None;
        }
        self.spherical_rect(o)
    }

    /// The spherical rectangle seen from `o` whatever its estimated solid angle (the quad must
    /// be a rectangle), when the exact one is in [`SPHERICAL_SOLID_ANGLE`].
    fn spherical_rect(&self, o: Vec3A) -> Option<SphericalRect> {
        let v3 = |v: Vec3A| glam::DVec3::new(v.x as f64, v.y as f64, v.z as f64);
        let (eu, ev) = (v3(self.u), v3(self.v));
        let (exl, eyl) = (eu.length(), ev.length());
        let (x, y) = (eu / exl, ev / eyl);
        let d = v3(self.q) - v3(o);
        let (x0, y0) = (d.dot(x), d.dot(y));
        let z0 = -d.dot(x.cross(y)).abs();
        let (x1, y1) = (x0 + exl, y0 + eyl);
        // Lengths of the edge planes' normals (0, z0, -y0), (-z0, 0, x1), (0, -z0, y1),
        // (z0, 0, -x0), and distances to the corners (x1, y0), (x1, y1), (x0, y1), (x0, y0).
        let z2 = z0 * z0;
        let r = [(z2 + y0 * y0).sqrt(), (z2 + x1 * x1).sqrt(), (z2 + y1 * y1).sqrt(), (z2 + x0 * x0).sqrt()];
        let c = [
            (x1 * x1 + y0 * y0 + z2).sqrt(),
            (x1 * x1 + y1 * y1 + z2).sqrt(),
            (x0 * x0 + y1 * y1 + z2).sqrt(),
            (x0 * x0 + y0 * y0 + z2).sqrt(),
        ];
        if !(r.iter().all(|&r| r > 0.0)) {
            return None;
        }
        // Interior angle g_i between planes i and i+1: cos g = -n_i . n_(i+1), sin g =
        // |n_i x n_(i+1)| = |z0| * (distance to their shared corner) / (r_i r_(i+1)).
        let g = |cos_num: f64, i: usize, j: usize| {
            let rr = r[i] * r[j];
            (cos_num / rr, -z0 * c[i] / rr)
        };
        let g0 = g(x1 * y0, 0, 1);
        let g1 = g(-x1 * y1, 1, 2);
        let g2 = g(x0 * y1, 2, 3);
        let g3 = g(-x0 * y0, 3, 0);
        let mul = |a: (f64, f64), b: (f64, f64)| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
        // e^(i (g0 + g1 + g2 + g3)) = e^(i (S + 2 pi)); e^(i k) = conj(e^(i (g2 + g3))).
        let g23 = mul(g2, g3);
        let e = mul(mul(g0, g1), g23);
        let mut s = libm::atan2(e.1, e.0);
        if s < 0.0 {
            s += std::f64::consts::TAU;
        }
        SPHERICAL_SOLID_ANGLE.contains(&s).then_some(SphericalRect {
            x0,
            y0,
            z0,
            x1,
            y1,
            b0: -y0 / r[0],
            b1: y1 / r[2],
            k: (g23.0, -g23.1),
            s,
        })
    }
}

impl SphericalRect {
    /// The point of uniform numbers `u` as the quad's (a, b), uniform in solid angle.
    fn sample(&self, u: Vec2) -> (f32, f32) {
        let (x0, y0, z0, x1, y1) = (self.x0, self.y0, self.z0, self.x1, self.y1);
        // au = u.x S + k.
        let (su, cu) = libm::sincos(u.x as f64 * self.s);
        let (ca, sa) = (cu * self.k.0 - su * self.k.1, su * self.k.0 + cu * self.k.1);
        let fu = (ca * self.b0 - self.b1) / sa;
        let cu = (1.0 / (fu * fu + self.b0 * self.b0).sqrt()).copysign(fu).clamp(-1.0, 1.0);
        let xu = (-(cu * z0) / (1.0 - cu * cu).max(0.0).sqrt()).clamp(x0, x1);
        let d2 = xu * xu + z0 * z0;
        let h0 = y0 / (d2 + y0 * y0).sqrt();
        let h1 = y1 / (d2 + y1 * y1).sqrt();
        let hv = h0 + u.y as f64 * (h1 - h0);
        let yv = if hv * hv < 1.0 - 1e-12 { hv * d2.sqrt() / (1.0 - hv * hv).sqrt() } else { y1 };
        let a = ((xu - x0) / (x1 - x0)).clamp(0.0, 1.0);
        let b = ((yv.clamp(y0, y1) - y0) / (y1 - y0)).clamp(0.0, 1.0);
        (a as f32, b as f32)
    }
}

/// The quad test on plain numbers (`k` = q, n, ea, eb), branch-free so that a loop over many
/// rays vectorises; the single-ray and the stream tests both use it, so they agree to the bit.
/// The hit point is formed relative to the corner, `(o - q) + t d`, which stays accurate far
/// from the origin.
#[inline(always)]
pub fn quad_t(k: [[f32; 3]; 4], o: [f32; 3], d: [f32; 3], tmax: f32) -> f32 {
    let [q, n, ea, eb] = k;
    let oq = [o[0] - q[0], o[1] - q[1], o[2] - q[2]];
    let denom = dot(n, d);
    let t = -dot(n, oq) / denom;
    let ph = [oq[0] + t * d[0], oq[1] + t * d[1], oq[2] + t * d[2]];
    let a = dot(ea, ph);
    let b = dot(eb, ph);
    let hit = denom != 0.0 && t > 0.0 && t < tmax && a >= 0.0 && a <= 1.0 && b >= 0.0 && b <= 1.0;
    if hit { t } else { f32::INFINITY }
}

/// A parallelogram in its own space, as a scene places it: the points q + a u + b v, a, b in
/// [0, 1]; normal u x v, or -(u x v) if `flip_normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadShape {
    /// Corner.
    pub q: Vec3A,
    /// First edge.
    pub u: Vec3A,
    /// Second edge.
    pub v: Vec3A,
    /// The normal is -(u x v).
    pub flip_normal: bool,
}

/// Points q + a u + b v, a, b in [0, 1]; normal = normalize(u x v), or its opposite with
/// `flip_normal: true` (default false); uv = (a, b). Under a mirroring transform the edges are
/// swapped (the normal keeps facing its side; uv becomes (b, a)).
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct QuadDesc {
    /// Corner.
    pub q: V3,
    /// First edge.
    pub u: V3,
    /// Second edge (not parallel to u).
    pub v: V3,
    /// Face the side of -(u x v) (default false): a quad whose uv runs the other way round
    /// its normal, as Mitsuba's `rectangle` with pathwave's v.
    #[serde(default)]
    pub flip_normal: bool,
}

impl ShapeModel for QuadShape {
    type Desc = QuadDesc;

    fn build(QuadDesc { q, u, v, flip_normal }: QuadDesc) -> Result<Self, String> {
        if !(u.0.cross(v.0).length_squared() > 0.0) {
            return Err(format!("Quad has no area: u {} and v {} are parallel or zero", u.0, v.0));
        }
        Ok(Self { q: q.0.into(), u: u.0.into(), v: v.0.into(), flip_normal })
    }

    fn place(&self, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
        place_quad(m, self.q, self.u, self.v, self.flip_normal, out)
    }
}

/// Appends the quad `q`, `u`, `v` placed by `m` (also the faces of a box), facing the side of
/// u x v, or of -(u x v) if `flip`, in its own space.
pub(crate) fn place_quad(
    m: &Affine3A,
    q: Vec3A,
    u: Vec3A,
    v: Vec3A,
    flip: bool,
    out: &mut Vec<Primitive>,
) -> Result<(), ShapeError> {
    let (q, mut u, mut v) = (m.transform_point3a(q), m.transform_vector3a(u), m.transform_vector3a(v));
    // A mirroring transform flips u x v; swap the edges so the normal keeps facing its side
    // (the uv becomes (b, a)).
    if m.matrix3.determinant() < 0.0 {
        std::mem::swap(&mut u, &mut v);
    }
    let quad = Quad::new(q, u, v).ok_or(ShapeError::FlatQuad(u, v))?;
    out.push(Primitive::Quad(if flip { quad.flipped() } else { quad }));
    Ok(())
}

impl PrimitiveShape for Quad {
    /// Bounding box.
    fn aabb(&self) -> Aabb {
        let mut b = Aabb::empty();
        for p in [self.q, self.q + self.u, self.q + self.v, self.q + self.u + self.v] {
            b.extend(p);
        }
        b
    }

    /// Smallest `t` in `(0, tmax)` where `o + t d` meets the quad, or `f32::INFINITY`.
    #[inline]
    fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        quad_t(self.kernel(), o.to_array(), d.to_array(), tmax)
    }

    #[inline(always)]
    fn surface(&self, p: Vec3A, _uv: bool) -> SurfacePoint {
        Quad::surface(self, p)
    }

    /// The edges: u runs along the first from 0 to 1, v along the second.
    fn derivatives(&self, _sp: &SurfacePoint) -> Option<(Vec3A, Vec3A)> {
        Some((self.u, self.v))
    }

    fn area(&self) -> f32 {
        self.area
    }

    fn sample_area(&self, u: Vec2) -> Option<LightSample> {
        let p = self.q + u.x * self.u + u.y * self.v;
        Some(LightSample { p, n: self.n, pdf: 1.0 / self.area, err: self.point_error() })
    }

    /// Samples a point of the quad as seen from `from`: uniformly in the solid angle of a
    /// rectangle (unless it subtends very little or almost everything), else uniformly by area;
    /// the density is returned in solid angle.
    fn sample_solid_angle(&self, from: Vec3A, u: Vec2) -> LightSample {
        let (a, b, pdf) = match self.spherical(from) {
            Some(r) => {
                let (a, b) = r.sample(u);
                (a, b, (1.0 / r.s) as f32)
            }
            None => (u.x, u.y, 0.0),
        };
        let p = self.q + a * self.u + b * self.v;
        let pdf = if pdf > 0.0 { pdf } else { area_to_solid_angle(1.0 / self.area, from, p, self.n) };
        LightSample { p, n: self.n, pdf, err: self.point_error() }
    }

    /// Solid-angle density of [`Self::sample_solid_angle`] for the point `p` seen from `from`.
    fn pdf_solid_angle(&self, from: Vec3A, p: Vec3A, _n: Vec3A) -> f32 {
        match self.spherical(from) {
            Some(r) => (1.0 / r.s) as f32,
            None => area_to_solid_angle(1.0 / self.area, from, p, self.n),
        }
    }
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
        // A parallelogram (not a rectangle) is sampled by area.
        let q = Quad::new(Vec3A::new(-1.5, -1.0, 2.0), Vec3A::X * 2.0, Vec3A::new(1.0, 2.0, 0.0)).unwrap();
        let ls = q.sample_solid_angle(Vec3A::ZERO, Vec2::splat(0.5));
        assert!((ls.p - Vec3A::new(0.0, 0.0, 2.0)).length() < 1e-6);
        assert!((ls.pdf - 4.0 / 4.0).abs() < 1e-6, "dist^2 / (A cos) = 4 / 4");
        assert_eq!(q.pdf_solid_angle(Vec3A::ZERO, ls.p, ls.n), ls.pdf);
    }

    /// Solid angle of `q` seen from `o` by brute force: a fine grid of area elements.
    fn solid_angle_by_area(q: &Quad, o: Vec3A) -> f64 {
        let m = 1000;
        let mut sum = 0.0f64;
        for i in 0..m {
            for j in 0..m {
                let p = q.q + (i as f32 + 0.5) / m as f32 * q.u + (j as f32 + 0.5) / m as f32 * q.v;
                let d = p - o;
                let r2 = d.length_squared() as f64;
                sum += (q.n.dot(d).abs() as f64 / r2.sqrt()) / r2;
            }
        }
        sum * q.area as f64 / (m * m) as f64
    }

    #[test]
    fn spherical_rectangles_have_the_solid_angle_of_the_quad() {
        let q = Quad::new(Vec3A::new(-1.0, 0.5, 2.0), Vec3A::X * 3.0, Vec3A::new(0.0, 1.0, 1.0)).unwrap();
        for o in
            [Vec3A::ZERO, Vec3A::new(0.3, 1.2, 2.4), Vec3A::new(2.0, -1.0, 1.5), Vec3A::new(0.0, 1.0, 1.4)]
        {
            let exact = solid_angle_by_area(&q, o);
            let r = q.spherical_rect(o).expect("in range");
            assert!((r.s / exact - 1.0).abs() < 1e-4, "{o}: {} vs {exact}", r.s);
        }
        // Tiny solid angles fall back to area sampling, with its density.
        let far = Vec3A::new(0.0, 0.0, -200.0);
        assert!(q.spherical(far).is_none());
        let ls = q.sample_solid_angle(far, Vec2::new(0.3, 0.6));
        assert_eq!(ls.pdf, area_to_solid_angle(1.0 / q.area, far, ls.p, q.n));
    }

    #[test]
    fn light_samples_are_finite_points_of_the_quad_from_anywhere() {
        // Points near the plane, on it, at the corners, far and very close: every sample lies
        // on the quad with a finite positive density (or none, exactly on the plane) and the
        // density evaluated at it agrees with the one sampled.
        let q = Quad::new(Vec3A::new(-1.0, -1.0, 0.0), Vec3A::X * 2.0, Vec3A::Y * 3.0).unwrap();
        let mut rng = crate::testing::signed(5);
        let mut u = crate::testing::uniform(9);
        for k in 0..20_000 {
            let (o, _) = crate::testing::near_plane(k, &mut rng);
            let ls = q.sample_solid_angle(o, Vec2::new(u().min(0.999_999), u().min(0.999_999)));
            assert!(ls.p.is_finite(), "{o}: {}", ls.p);
            let ph = ls.p - q.q;
            assert!(
                ph.z.abs() <= 1e-6
                    && (-1e-5..=2.0 + 1e-5).contains(&ph.x)
                    && (-1e-5..=3.0 + 1e-5).contains(&ph.y)
            );
            assert!(ls.pdf >= 0.0 && !ls.pdf.is_nan(), "{o}: pdf {}", ls.pdf);
            if ls.pdf.is_finite() && ls.pdf > 0.0 {
                assert_eq!(q.pdf_solid_angle(o, ls.p, ls.n), ls.pdf, "{o}");
            }
        }
    }

    #[test]
    fn spherical_samples_are_uniform_in_solid_angle() {
        // Chi-square test of the sampled directions against uniform density in solid angle:
        // bins are a grid on the quad, each expecting its own solid angle over the total.
        let q = Quad::new(Vec3A::new(-1.0, -1.0, 1.0), Vec3A::X * 2.5, Vec3A::Y * 2.0).unwrap();
        let o = Vec3A::new(0.2, 0.1, 0.4);
        let total = q.spherical(o).unwrap().s;
        let g = 8;
        let mut observed = vec![0usize; g * g];
        let n = 200_000;
        let mut rng = crate::testing::uniform(11);
        for _ in 0..n {
            let ls = q.sample_solid_angle(o, Vec2::new(rng(), rng()));
            assert!((ls.pdf as f64 * total - 1.0).abs() < 1e-5);
            let ph = ls.p - q.q;
            let (a, b) = (ph.dot(q.u) / q.u.length_squared(), ph.dot(q.v) / q.v.length_squared());
            observed[((a * g as f32) as usize).min(g - 1) * g + ((b * g as f32) as usize).min(g - 1)] += 1;
        }
        let mut chi2 = 0.0;
        for i in 0..g {
            for j in 0..g {
                let (fu, fv) = (1.0 / g as f32, 1.0 / g as f32);
                let cell =
                    Quad::new(q.q + i as f32 * fu * q.u + j as f32 * fv * q.v, q.u * fu, q.v * fv).unwrap();
                let expected = solid_angle_by_area(&cell, o) / total * n as f64;
                chi2 += (observed[i * g + j] as f64 - expected).powi(2) / expected;
            }
        }
        // 63 degrees of freedom: the 99.9% quantile is about 103.
        assert!(chi2 < 103.0, "chi2 {chi2}");
    }
}
