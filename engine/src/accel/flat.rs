//! Small scenes without a BVH: quads, spheres and ellipsoids in flat arrays, tested by brute
//! force. A single ray scans every primitive; a stream of rays is tested primitive by primitive,
//! each test running over all rays so that it vectorises across rays (8 or 16 lanes, see
//! [`crate::simd`]). Other kinds follow, tested ray by ray with their own test; scenes with
//! triangles take the BVH. Both scan quads, then spheres, then ellipsoids, then the rest, in
//! order, keeping the first of equal distances: the stream finds exactly the hits of the
//! single-ray scan, and both the BVH's (the same operations in the same order).

use crate::shape::{
    Primitive, TransformedSphere,
    quad::quad_t,
    sphere::{sphere_t, sphere_t_single},
};
use glam::Vec3A;

/// Rays as parallel arrays of coordinates.
#[derive(Default, Debug, Clone)]
pub struct RayStream {
    /// Origins.
    pub o: [Vec<f32>; 3],
    /// Directions.
    pub d: [Vec<f32>; 3],
}

impl RayStream {
    /// Empties the stream, keeping its storage.
    pub fn clear(&mut self) {
        self.o.iter_mut().chain(self.d.iter_mut()).for_each(Vec::clear);
    }

    /// Appends a ray.
    #[inline]
    pub fn push(&mut self, o: [f32; 3], d: [f32; 3]) {
        for k in 0..3 {
            self.o[k].push(o[k]);
            self.d[k].push(d[k]);
        }
    }

    /// Makes the stream `n` rays long, ray `k` being `ray(k)` (origin, direction): one pass
    /// of plain stores where pushing would check capacity six times per ray.
    #[inline]
    pub fn fill_with(&mut self, n: usize, mut ray: impl FnMut(usize) -> ([f32; 3], [f32; 3])) {
        self.o.iter_mut().chain(self.d.iter_mut()).for_each(|a| a.resize(n, 0.0));
        let [ox, oy, oz] = &mut self.o;
        let [dx, dy, dz] = &mut self.d;
        let (ox, oy, oz) = (&mut ox[..n], &mut oy[..n], &mut oz[..n]);
        let (dx, dy, dz) = (&mut dx[..n], &mut dy[..n], &mut dz[..n]);
        for k in 0..n {
            let (o, d) = ray(k);
            (ox[k], oy[k], oz[k]) = (o[0], o[1], o[2]);
            (dx[k], dy[k], dz[k]) = (d[0], d[1], d[2]);
        }
    }

    /// Number of rays.
    pub fn len(&self) -> usize {
        self.o[0].len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.o[0].is_empty()
    }
}

/// An ellipsoid (a [`TransformedSphere`]) as its test reads it: the columns and translation
/// of the world-to-object transform, and the sphere in object space.
#[derive(Clone, Copy, Debug)]
struct Ellipsoid {
    m: [[f32; 3]; 4],
    c: [f32; 3],
    r: f32,
}

impl Ellipsoid {
    fn new(e: &TransformedSphere) -> Self {
        let a = e.object_from_world;
        let col = |v: glam::Vec3A| v.to_array();
        Self {
            m: [col(a.matrix3.x_axis), col(a.matrix3.y_axis), col(a.matrix3.z_axis), col(a.translation)],
            c: e.sphere.center.to_array(),
            r: e.sphere.radius,
        }
    }

    /// The ray in object space, by the operations of glam's `Affine3A::transform_point3a` and
    /// `transform_vector3a` in their order (`x o.x + y o.y + z o.z + t`, no fused multiply-add),
    /// so that the bits are those of [`TransformedSphere`]'s own test, which the BVH runs.
    #[inline(always)]
    fn object_ray(&self, o: [f32; 3], d: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        let [x, y, z, t] = self.m;
        let (mut lo, mut ld) = ([0.0; 3], [0.0; 3]);
        for k in 0..3 {
            lo[k] = x[k] * o[0] + y[k] * o[1] + z[k] * o[2] + t[k];
            ld[k] = x[k] * d[0] + y[k] * d[1] + z[k] * d[2];
        }
        (lo, ld)
    }

    /// Smallest `t` in `(0, tmax)` (or infinity), branch-free for the stream.
    #[inline(always)]
    fn t(&self, o: [f32; 3], d: [f32; 3], tmax: f32) -> f32 {
        let (lo, ld) = self.object_ray(o, d);
        sphere_t(self.c, self.r, lo, ld, tmax)
    }

    /// [`Self::t`] for one ray, which returns early on a miss (the same bits).
    #[inline(always)]
    fn t_single(&self, o: [f32; 3], d: [f32; 3], tmax: f32) -> f32 {
        let (lo, ld) = self.object_ray(o, d);
        sphere_t_single(self.c, self.r, lo, ld, tmax)
    }
}

/// A quad whose normal is a coordinate axis `k` and whose edge vectors `ea`, `eb` (see
/// [`quad_t`]) each have one non-zero coordinate, `i` and `j`: the walls, floors and lights of
/// box-like rooms. Its test reads three coordinates where [`quad_t`] forms three dot products,
/// with the same bits: the terms dropped are products with exact zeros, which leave a finite
/// sum unchanged, and where they would not (a zero sum, whose sign they may flip, or an
/// infinite `t`) `quad_t` misses either way. cornell-diffuse (6 of its 18 quads): closest hits
/// 3.5% and shadow rays 10% faster.
#[derive(Clone, Copy, Debug)]
struct AxisQuad {
    /// The normal's axis and the axes `ea` and `eb` read.
    k: usize,
    i: usize,
    j: usize,
    /// The corner's coordinates along `k`, `i` and `j`.
    q: [f32; 3],
    /// The normal's, `ea`'s and `eb`'s non-zero coordinates.
    n: f32,
    ea: f32,
    eb: f32,
}

impl AxisQuad {
    /// The axis form of the quad kernel `[q, n, ea, eb]` of [`quad_t`], if it has one.
    fn new([q, n, ea, eb]: [[f32; 3]; 4]) -> Option<Self> {
        let only = |v: [f32; 3]| match v.map(|x| x != 0.0) {
            [true, false, false] => Some(0),
            [false, true, false] => Some(1),
            [false, false, true] => Some(2),
            _ => None,
        };
        let (k, i, j) = (only(n)?, only(ea)?, only(eb)?);
        let q = [q[k], q[i], q[j]];
        (k != i && k != j && i != j).then_some(Self { k, i, j, q, n: n[k], ea: ea[i], eb: eb[j] })
    }

    /// The first `n` entries of the coordinate arrays `c` along `k`, `i` and `j`.
    #[inline(always)]
    fn pick<'a>(&self, c: &'a [Vec<f32>; 3], n: usize) -> [&'a [f32]; 3] {
        [&c[self.k][..n], &c[self.i][..n], &c[self.j][..n]]
    }

    /// [`quad_t`] of the quad, from the ray's coordinates along `k`, `i` and `j`.
    #[inline(always)]
    fn t(&self, [ok, oi, oj]: [f32; 3], [dk, di, dj]: [f32; 3], tmax: f32) -> f32 {
        let oq = [ok - self.q[0], oi - self.q[1], oj - self.q[2]];
        let denom = self.n * dk;
        let t = -(self.n * oq[0]) / denom;
        let a = self.ea * (oq[1] + t * di);
        let b = self.eb * (oq[2] + t * dj);
        let hit = denom != 0.0 && t > 0.0 && t < tmax && a >= 0.0 && a <= 1.0 && b >= 0.0 && b <= 1.0;
        if hit { t } else { f32::INFINITY }
    }
}

/// Quads, spheres and ellipsoids as flat arrays, other kinds without a stream test as they
/// are, with their primitive indices.
#[derive(Default, Debug)]
pub struct FlatPrims {
    quads: Vec<[[f32; 3]; 4]>,
    /// Per quad, its [`AxisQuad`] form when it has one.
    axis: Vec<Option<AxisQuad>>,
    quad_id: Vec<u32>,
    spheres: Vec<([f32; 3], f32)>,
    sphere_id: Vec<u32>,
    ellipsoids: Vec<Ellipsoid>,
    ellipsoid_id: Vec<u32>,
    others: Vec<Primitive>,
    other_id: Vec<u32>,
}

impl FlatPrims {
    /// The lists of `prims`, or `None` when there are triangles: their test, ray by ray, costs
    /// more than the BVH that passes them by (benches/scenes/triangle-lamp.ron, two triangles
    /// among 17 quads: closest hits 14.4 -> 12.1 M rays/s on one thread when they were listed).
    pub fn new(prims: &[Primitive]) -> Option<Self> {
        let mut f = FlatPrims::default();
        for (i, p) in prims.iter().enumerate() {
            match p {
                Primitive::Quad(q) => {
                    f.quads.push(q.kernel());
                    f.axis.push(AxisQuad::new(q.kernel()));
                    f.quad_id.push(i as u32);
                }
                Primitive::Sphere(s) => {
                    f.spheres.push((s.center.to_array(), s.radius));
                    f.sphere_id.push(i as u32);
                }
                Primitive::TransformedSphere(e) => {
                    f.ellipsoids.push(Ellipsoid::new(e));
                    f.ellipsoid_id.push(i as u32);
                }
                Primitive::Triangle(_) => return None,
                // Kinds without a stream test (disks, cylinders) are tested ray by ray.
                other => {
                    f.others.push(*other);
                    f.other_id.push(i as u32);
                }
            }
        }
        Some(f)
    }

    /// Closest hit `(t, primitive)` with t in (0, tmax), or `None`.
    #[inline]
    pub fn intersect(&self, o: [f32; 3], d: [f32; 3], tmax: f32) -> Option<(f32, u32)> {
        let (mut best, mut id) = (tmax, u32::MAX);
        for (k, q) in self.quads.iter().enumerate() {
            let t = quad_t(*q, o, d, best);
            if t < best {
                best = t;
                id = self.quad_id[k];
            }
        }
        for (k, (c, r)) in self.spheres.iter().enumerate() {
            let t = sphere_t(*c, *r, o, d, best);
            if t < best {
                best = t;
                id = self.sphere_id[k];
            }
        }
        for (k, e) in self.ellipsoids.iter().enumerate() {
            let t = e.t_single(o, d, best);
            if t < best {
                best = t;
                id = self.ellipsoid_id[k];
            }
        }
        for (k, p) in self.others.iter().enumerate() {
            let t = p.intersect(o.into(), d.into(), best);
            if t < best {
                best = t;
                id = self.other_id[k];
            }
        }
        (id != u32::MAX).then_some((best, id))
    }

    /// True when something lies on the ray with t in (0, tmax).
    #[inline]
    pub fn occluded(&self, o: [f32; 3], d: [f32; 3], tmax: f32) -> bool {
        self.quads.iter().any(|q| quad_t(*q, o, d, tmax) < tmax)
            || self.spheres.iter().any(|(c, r)| sphere_t(*c, *r, o, d, tmax) < tmax)
            || self.ellipsoids.iter().any(|e| e.t_single(o, d, tmax) < tmax)
            || self.others.iter().any(|p| p.intersect(o.into(), d.into(), tmax) < tmax)
    }

    /// Closest hits of a stream: on return `t[i]` and `id[i]` hold ray i's hit (`u32::MAX`
    /// and the initial `t[i]` on a miss). `t` must hold each ray's tmax on entry.
    pub fn intersect_stream(&self, rays: &RayStream, t: &mut [f32], id: &mut [u32]) {
        crate::simd::lanes(
            #[inline(always)]
            || self.intersect_stream_lanes(rays, t, id),
        )
    }

    #[inline(always)]
    fn intersect_stream_lanes(&self, rays: &RayStream, t: &mut [f32], id: &mut [u32]) {
        let n = rays.len();
        let (t, id) = (&mut t[..n], &mut id[..n]);
        id.fill(u32::MAX);
        let [ox, oy, oz] = &rays.o;
        let [dx, dy, dz] = &rays.d;
        let (ox, oy, oz, dx, dy, dz) = (&ox[..n], &oy[..n], &oz[..n], &dx[..n], &dy[..n], &dz[..n]);
        for (k, q) in self.quads.iter().enumerate() {
            let pid = self.quad_id[k];
            if let Some(a) = self.axis[k] {
                let ([ok, oi, oj], [dk, di, dj]) = (a.pick(&rays.o, n), a.pick(&rays.d, n));
                for i in 0..n {
                    let h = a.t([ok[i], oi[i], oj[i]], [dk[i], di[i], dj[i]], t[i]);
                    let better = h < t[i];
                    t[i] = if better { h } else { t[i] };
                    id[i] = if better { pid } else { id[i] };
                }
                continue;
            }
            for i in 0..n {
                let h = quad_t(*q, [ox[i], oy[i], oz[i]], [dx[i], dy[i], dz[i]], t[i]);
                let better = h < t[i];
                t[i] = if better { h } else { t[i] };
                id[i] = if better { pid } else { id[i] };
            }
        }
        for (k, (c, r)) in self.spheres.iter().enumerate() {
            let pid = self.sphere_id[k];
            for i in 0..n {
                let h = sphere_t(*c, *r, [ox[i], oy[i], oz[i]], [dx[i], dy[i], dz[i]], t[i]);
                let better = h < t[i];
                t[i] = if better { h } else { t[i] };
                id[i] = if better { pid } else { id[i] };
            }
        }
        for (k, e) in self.ellipsoids.iter().enumerate() {
            let pid = self.ellipsoid_id[k];
            for i in 0..n {
                let h = e.t([ox[i], oy[i], oz[i]], [dx[i], dy[i], dz[i]], t[i]);
                let better = h < t[i];
                t[i] = if better { h } else { t[i] };
                id[i] = if better { pid } else { id[i] };
            }
        }
        for (k, p) in self.others.iter().enumerate() {
            for i in 0..n {
                let h = p.intersect(Vec3A::new(ox[i], oy[i], oz[i]), Vec3A::new(dx[i], dy[i], dz[i]), t[i]);
                if h < t[i] {
                    (t[i], id[i]) = (h, self.other_id[k]);
                }
            }
        }
    }

    /// Occlusion of a stream with tmax = 1 for every ray (shadow rays aimed at a light point):
    /// `hit[i]` becomes true when something lies on ray i with t in (0, 1).
    pub fn occluded_stream(&self, rays: &RayStream, hit: &mut [bool]) {
        crate::simd::lanes(
            #[inline(always)]
            || self.occluded_stream_lanes(rays, hit),
        )
    }

    #[inline(always)]
    fn occluded_stream_lanes(&self, rays: &RayStream, hit: &mut [bool]) {
        let n = rays.len();
        let hit = &mut hit[..n];
        hit.fill(false);
        let [ox, oy, oz] = &rays.o;
        let [dx, dy, dz] = &rays.d;
        let (ox, oy, oz, dx, dy, dz) = (&ox[..n], &oy[..n], &oz[..n], &dx[..n], &dy[..n], &dz[..n]);
        for (k, q) in self.quads.iter().enumerate() {
            if let Some(a) = self.axis[k] {
                let ([ok, oi, oj], [dk, di, dj]) = (a.pick(&rays.o, n), a.pick(&rays.d, n));
                for i in 0..n {
                    hit[i] |= a.t([ok[i], oi[i], oj[i]], [dk[i], di[i], dj[i]], 1.0) < 1.0;
                }
                continue;
            }
            for i in 0..n {
                hit[i] |= quad_t(*q, [ox[i], oy[i], oz[i]], [dx[i], dy[i], dz[i]], 1.0) < 1.0;
            }
        }
        for (c, r) in &self.spheres {
            for i in 0..n {
                hit[i] |= sphere_t(*c, *r, [ox[i], oy[i], oz[i]], [dx[i], dy[i], dz[i]], 1.0) < 1.0;
            }
        }
        for e in &self.ellipsoids {
            for i in 0..n {
                hit[i] |= e.t([ox[i], oy[i], oz[i]], [dx[i], dy[i], dz[i]], 1.0) < 1.0;
            }
        }
        for p in &self.others {
            for i in 0..n {
                if !hit[i] {
                    hit[i] =
                        p.intersect(Vec3A::new(ox[i], oy[i], oz[i]), Vec3A::new(dx[i], dy[i], dz[i]), 1.0)
                            < 1.0;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::{PrimitiveShape, Sphere};
    use crate::testing::signed;
    use glam::{Affine3A, Mat3, Quat, Vec3, Vec3A};

    #[test]
    fn ellipsoid_tests_give_the_bits_of_the_transformed_sphere() {
        let mut rnd = signed(11);
        let (mut hits, mut rays) = (0, 0);
        for _ in 0..200 {
            let m = Affine3A::from_scale_rotation_translation(
                Vec3::new(1.0 + rnd().abs() * 80.0, 1.0 + rnd().abs() * 80.0, 1.0 + rnd().abs() * 80.0),
                Quat::from_euler(glam::EulerRot::XYZ, rnd() * 3.0, rnd() * 3.0, rnd() * 3.0),
                Vec3::new(rnd(), rnd(), rnd()) * 300.0,
            ) * Affine3A::from_mat3(Mat3::from_cols(
                Vec3::new(1.0, rnd() * 0.5, 0.0),
                Vec3::new(0.0, 1.0, rnd() * 0.5),
                Vec3::Z,
            ));
            let sphere = Sphere::new(Vec3A::new(rnd(), rnd(), rnd()), 0.5 + rnd().abs());
            let e = TransformedSphere::new(sphere, m).expect("invertible");
            let flat = Ellipsoid::new(&e);
            let c = m.transform_point3a(sphere.center);
            for _ in 0..100 {
                let o = Vec3A::new(rnd(), rnd(), rnd()) * 600.0;
                let d = c + Vec3A::new(rnd(), rnd(), rnd()) * 60.0 - o;
                let tmax = if rnd() > 0.0 { f32::INFINITY } else { rnd().abs() * 2.0 };
                let want = e.intersect(o, d, tmax);
                let (oa, da) = (o.to_array(), d.to_array());
                assert_eq!(flat.t_single(oa, da, tmax).to_bits(), want.to_bits(), "{o} {d}");
                assert_eq!(flat.t(oa, da, tmax).to_bits(), want.to_bits(), "{o} {d}");
                hits += want.is_finite() as u32;
                rays += 1;
            }
        }
        assert!(hits > rays / 4, "{hits} hits of {rays}");
    }

    /// Quads along the axes take the axis test, with the bits of `quad_t`, also for rays
    /// parallel to the plane or starting on it; a tilted quad keeps the general test.
    #[test]
    fn axis_quads_give_the_bits_of_the_quad_test() {
        use crate::shape::quad::Quad;
        let mut rnd = signed(5);
        let (mut hits, mut rays) = (0, 0);
        for case in 0..300 {
            let k = case % 3;
            let (i, j) = ((k + 1 + case / 3 % 2) % 3, (k + 2 - case / 3 % 2) % 3);
            let axis =
                |a: usize, len: f32| Vec3A::from(std::array::from_fn(|c| if c == a { len } else { 0.0 }));
            let (u, v) = (axis(i, rnd() * 600.0), axis(j, rnd() * 600.0));
            let corner = Vec3A::new(rnd(), rnd(), rnd()) * 300.0;
            let Some(quad) = Quad::new(corner, u, v) else { continue };
            let kernel = quad.kernel();
            let a = AxisQuad::new(kernel).expect("an axis quad");
            for r in 0..100 {
                let mut o = Vec3A::new(rnd(), rnd(), rnd()) * 600.0;
                let aim = corner + u * (0.5 + rnd() * 0.7) + v * (0.5 + rnd() * 0.7);
                let mut d = aim - o;
                match r % 10 {
                    0 => d[k] = 0.0,
                    1 => o[k] = corner[k],
                    2 => d = -d,
                    _ => {}
                }
                let tmax = if r % 3 == 0 { rnd().abs() * 2.0 } else { f32::INFINITY };
                let want = quad_t(kernel, o.to_array(), d.to_array(), tmax);
                let pick = |x: Vec3A| [x[a.k], x[a.i], x[a.j]];
                assert_eq!(a.t(pick(o), pick(d), tmax).to_bits(), want.to_bits(), "{o} {d} {tmax}");
                hits += want.is_finite() as u32;
                rays += 1;
            }
        }
        assert!(hits > rays / 4, "{hits} hits of {rays}");
        let tilted = Quad::new(Vec3A::ZERO, Vec3A::new(1.0, 0.0, 0.1), Vec3A::Y).expect("a quad");
        assert!(AxisQuad::new(tilted.kernel()).is_none());
    }
}
