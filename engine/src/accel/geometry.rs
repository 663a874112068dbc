//! The primitive list and its BVH (our 8-wide [`Bvh8`], built from obvhs's binary BVH):
//! closest-hit and occlusion queries.

use crate::accel::bvh8::{Bvh8, PACKET};
use crate::accel::flat::FlatPrims;
use crate::math::Ray;
use crate::shape::sphere::{sphere_t, sphere_t_single};
use crate::shape::{Primitive, SurfacePoint};
use glam::Vec3A;
use obvhs::aabb::Aabb;

/// A closest hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter.
    pub t: f32,
    /// Index into [`Geometry::prims`], or [`crate::accel::instances::INSTANCE_PRIM`].
    pub prim: u32,
    /// Material id.
    pub material: u32,
    /// Surface data.
    pub surface: SurfacePoint,
}

/// Primitives per BVH leaf at most: spheres-sky (488 primitives) renders 64 spp in 1.12-1.14 s
/// with leaves of 1 or 2, 1.39 s with 4, 1.68 s with 8 (obvhs's CWBVH: 1.60 s).
const LEAF: u32 = 2;

/// Scenes with at most this many primitives and no triangles also keep flat primitive lists
/// (quads and spheres as arrays, ellipsoids ray by ray): a stream of rays tests them primitive
/// by primitive, SIMD across rays, which beats traversing the BVH once per ray. Single rays
/// still traverse the BVH (a scalar scan of even 13 quads was slower than obvhs's CWBVH, which
/// our BVH8 has since replaced: cornell rendered in 2.53 s against 1.72 s).
pub const FLAT_MAX: usize = 32;

/// Primitives with per-primitive material ids and the structures that find ray hits among them.
#[derive(Default)]
pub struct Geometry {
    /// Primitives, in BVH leaf order.
    pub prims: Vec<Primitive>,
    /// Material id of each primitive.
    pub material: Vec<u32>,
    /// Velocity of each primitive (world units per unit time) when some primitive moves: at
    /// time `t` a primitive lies translated by `velocity * t`.
    pub velocity: Option<Vec<Vec3A>>,
    /// The index each primitive had in the list it was built from (before the BVH's reorder).
    pub source: Vec<u32>,
    bvh: Option<Bvh8>,
    flat: Option<FlatPrims>,
    /// Per slot, a sphere's centre and radius, or a NaN radius for the other primitives: the
    /// BVH's leaves test spheres from these 16 bytes instead of the 224 of a [`Primitive`]
    /// (a transformed sphere's matrices set its size), so the 488 spheres of spheres-sky take
    /// 8 KB of cache instead of 109 KB (spheres-sky 11% faster with the early exit of
    /// [`sphere_t_single`], benches/RESULTS.md).
    spheres: Vec<[f32; 4]>,
}

impl Geometry {
    /// Builds the BVH and reorders the primitives (and their materials) to its leaf order.
    pub fn build(prims: Vec<Primitive>, material: Vec<u32>) -> Self {
        let mut g = Self::build_bvh(prims, material);
        if g.prims.len() <= FLAT_MAX {
            g.flat = FlatPrims::new(&g.prims);
        }
        g
    }

    /// Builds the geometry of primitives moving with `velocity` (one per primitive) during the
    /// shutter interval: BVH bounds cover each primitive's whole sweep. Without motion this is
    /// [`Self::build`].
    pub fn build_moving(
        prims: Vec<Primitive>,
        material: Vec<u32>,
        velocity: Vec<Vec3A>,
        shutter: (f32, f32),
    ) -> Self {
        assert_eq!(prims.len(), velocity.len());
        if velocity.iter().all(|v| *v == Vec3A::ZERO) {
            return Self::build(prims, material);
        }
        let aabbs = prims
            .iter()
            .zip(&velocity)
            .map(|(p, &v)| {
                let b = p.aabb();
                let (a, c) = (v * shutter.0, v * shutter.1);
                Aabb { min: b.min + a.min(c), max: b.max + a.max(c) }
            })
            .collect();
        Self::from_aabbs(prims, material, Some(velocity), aabbs)
    }

    /// Builds the BVH only, whatever the primitive count.
    pub fn build_bvh(prims: Vec<Primitive>, material: Vec<u32>) -> Self {
        let aabbs = prims.iter().map(Primitive::aabb).collect();
        Self::from_aabbs(prims, material, None, aabbs)
    }

    fn from_aabbs(
        prims: Vec<Primitive>,
        material: Vec<u32>,
        velocity: Option<Vec<Vec3A>>,
        aabbs: Vec<Aabb>,
    ) -> Self {
        assert_eq!(prims.len(), material.len());
        if prims.is_empty() {
            return Self::default();
        }
        // Leaves of up to LEAF primitives, stored in leaf order.
        let mut order = Vec::with_capacity(prims.len());
        let bvh = Bvh8::build(&aabbs, LEAF, |leaf| {
            order.extend_from_slice(leaf);
            ((order.len() - leaf.len()) as u32, leaf.len() as u32)
        });
        let order = &order;
        let prims: Vec<Primitive> = order.iter().map(|&i| prims[i as usize]).collect();
        let material = order.iter().map(|&i| material[i as usize]).collect();
        let velocity = velocity.map(|v| order.iter().map(|&i| v[i as usize]).collect());
        let source = order.clone();
        let spheres = prims
            .iter()
            .map(|p| match p {
                Primitive::Sphere(s) => [s.center.x, s.center.y, s.center.z, s.radius],
                _ => [0.0, 0.0, 0.0, f32::NAN],
            })
            .collect();
        Self { prims, material, velocity, source, bvh: Some(bvh), flat: None, spheres }
    }

    /// Checks the BVH's invariants ([`Bvh8::validate`]); for still primitives also that each
    /// leaf's box holds its primitives (moving ones are checked for the tree's shape only).
    pub fn validate(&self) -> Result<(), String> {
        let Some(bvh) = &self.bvh else { return Ok(()) };
        bvh.validate(|first, count| match self.velocity {
            Some(_) => Aabb::empty(),
            None => {
                let prims = &self.prims[first as usize..(first + count) as usize];
                prims.iter().fold(Aabb::empty(), |b, p| b.union(&p.aabb()))
            }
        })
    }

    /// How far primitive `prim` has moved at `time` (zero for static scenes).
    #[inline]
    pub fn offset(&self, prim: u32, time: f32) -> Vec3A {
        match &self.velocity {
            Some(v) => v[prim as usize] * time,
            None => Vec3A::ZERO,
        }
    }

    /// Closest hit with `t` in `(0, tmax)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmax: f32) -> Option<Hit> {
        self.intersect_uv(ray, tmax, true)
    }

    /// [`Self::intersect`], with texture coordinates in the hit only if `uv` (see
    /// [`Primitive::surface`]).
    #[inline]
    pub fn intersect_uv(&self, ray: &Ray, tmax: f32, uv: bool) -> Option<Hit> {
        // One traversal loop each for still and moving geometry: the still one does no motion
        // arithmetic per primitive.
        match &self.velocity {
            None => self.intersect_with(ray, tmax, uv, |_| ray.origin),
            Some(v) => self.intersect_with(ray, tmax, uv, |slot| ray.origin - v[slot] * ray.time),
        }
    }

    /// [`Self::intersect`], with `origin(slot)` the ray origin relative to primitive `slot`
    /// at rest.
    #[inline(always)]
    fn intersect_with(&self, ray: &Ray, tmax: f32, uv: bool, origin: impl Fn(usize) -> Vec3A) -> Option<Hit> {
        let (best, prim) = self.closest_with(ray, tmax, origin);
        (prim != u32::MAX).then(|| self.hit(ray, best, prim, uv))
    }

    /// The closest hit's distance and primitive (`u32::MAX` and `tmax` for none).
    #[inline(always)]
    fn closest_with(&self, ray: &Ray, tmax: f32, origin: impl Fn(usize) -> Vec3A) -> (f32, u32) {
        let Some(bvh) = self.bvh.as_ref() else { return (tmax, u32::MAX) };
        let mut prim = u32::MAX;
        let best = bvh.closest(ray.origin, ray.dir, tmax, |first, count, mut best| {
            for slot in first as usize..(first + count) as usize {
                let t = self.test(slot, origin(slot), ray.dir, best);
                if t < best {
                    (best, prim) = (t, slot as u32);
                }
            }
            best
        });
        (best, prim)
    }

    /// True for geometry without motion in a BVH: what [`Self::closest_static`] and
    /// [`Self::closest_packet`] take.
    pub fn is_static_bvh(&self) -> bool {
        self.bvh.is_some() && self.velocity.is_none()
    }

    /// The closest hit's distance and primitive (`u32::MAX` and `tmax` for none) in geometry
    /// without motion ([`Self::static_hit`] makes the hit record).
    #[inline]
    pub fn closest_static(&self, ray: &Ray, tmax: f32) -> (f32, u32) {
        debug_assert!(self.velocity.is_none());
        self.closest_with(ray, tmax, |_| ray.origin)
    }

    /// Which of [`PACKET`] rays traced together meet something with `t` in `(0, tmax[l])` in
    /// geometry without motion ([`Bvh8::any_packet`]): a bit mask, each ray's bit the answer of
    /// [`Self::occluded`]. Spheres are tested across the packet's lanes by `sphere_t` (the bits
    /// of `sphere_t_single`), other kinds ray by ray; call it in a [`crate::simd::lanes`] region.
    #[inline(always)]
    pub fn occluded_packet(
        &self,
        o: &[[f32; PACKET]; 3],
        d: &[[f32; PACKET]; 3],
        tmax: &[f32; PACKET],
    ) -> u32 {
        debug_assert!(self.velocity.is_none());
        let Some(bvh) = self.bvh.as_ref() else { return 0 };
        bvh.any_packet(o, d, tmax, |first, count, active| {
            let mut hit = [false; PACKET];
            for slot in first as usize..(first + count) as usize {
                let t = self.packet_test(slot, o, d, tmax, active);
                for l in 0..PACKET {
                    hit[l] |= t[l] < tmax[l];
                }
            }
            crate::simd::mask16(&hit) & active
        })
    }

    /// The distances at which the packet's rays meet primitive `slot` (of the BVH's leaves)
    /// before their `tmax`: a sphere across the lanes by [`sphere_t`] (the bits of
    /// [`sphere_t_single`], every lane computed), other kinds lane by lane for the `active`
    /// rays (infinity for the others).
    #[inline(always)]
    fn packet_test(
        &self,
        slot: usize,
        o: &[[f32; PACKET]; 3],
        d: &[[f32; PACKET]; 3],
        tmax: &[f32; PACKET],
        active: u32,
    ) -> [f32; PACKET] {
        let mut t = [f32::INFINITY; PACKET];
        let [x, y, z, r] = self.spheres[slot];
        if r.is_nan() {
            for l in (0..PACKET).filter(|l| active >> l & 1 != 0) {
                let (ol, dl) = (Vec3A::new(o[0][l], o[1][l], o[2][l]), Vec3A::new(d[0][l], d[1][l], d[2][l]));
                t[l] = self.prims[slot].intersect(ol, dl, tmax[l]);
            }
            return t;
        }
        for l in 0..PACKET {
            t[l] = sphere_t([x, y, z], r, [o[0][l], o[1][l], o[2][l]], [d[0][l], d[1][l], d[2][l]], tmax[l]);
        }
        t
    }

    /// [`Self::closest_static`] for [`PACKET`] rays traced together ([`Bvh8::closest_packet`]):
    /// `t[l]` holds ray `l`'s `tmax` on entry and its closest distance on return, and the
    /// primitives are returned (`u32::MAX` for none). Spheres are tested across the packet's
    /// lanes by `sphere_t`, other kinds ray by ray. Call it in a [`crate::simd::lanes`] region.
    #[inline(always)]
    pub fn closest_packet(
        &self,
        o: &[[f32; PACKET]; 3],
        d: &[[f32; PACKET]; 3],
        t: &mut [f32; PACKET],
    ) -> [u32; PACKET] {
        debug_assert!(self.velocity.is_none());
        let mut prim = [u32::MAX; PACKET];
        let Some(bvh) = self.bvh.as_ref() else { return prim };
        bvh.closest_packet(o, d, t, |first, count, active, best| {
            for slot in first as usize..(first + count) as usize {
                let h = self.packet_test(slot, o, d, best, active);
                for l in 0..PACKET {
                    let take = (active >> l & 1 != 0) & (h[l] < best[l]);
                    best[l] = if take { h[l] } else { best[l] };
                    prim[l] = if take { slot as u32 } else { prim[l] };
                }
            }
        });
        prim
    }

    /// [`Primitive::intersect`] of the primitive in `slot` (of the BVH's leaves), a sphere
    /// tested from [`Self::spheres`].
    #[inline(always)]
    fn test(&self, slot: usize, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        let [x, y, z, r] = self.spheres[slot];
        if r.is_nan() {
            return self.prims[slot].intersect(o, d, tmax);
        }
        sphere_t_single([x, y, z], r, o.to_array(), d.to_array(), tmax)
    }

    /// The hit record of primitive `prim` at distance `t` (texture coordinates if `uv`).
    #[inline]
    pub fn hit(&self, ray: &Ray, t: f32, prim: u32, uv: bool) -> Hit {
        if self.velocity.is_none() {
            return self.static_hit(ray, t, prim, uv);
        }
        let mut surface = self.moving_surface(prim, ray.at(t), ray.time, uv);
        surface.on.triangle = prim;
        Hit { t, prim, material: self.material[prim as usize], surface }
    }

    /// [`Self::hit`] for geometry without motion (flat lists exist only then).
    #[inline(always)]
    pub fn static_hit(&self, ray: &Ray, t: f32, prim: u32, uv: bool) -> Hit {
        debug_assert!(self.velocity.is_none());
        let mut surface = self.prims[prim as usize].surface(ray.at(t), uv);
        surface.on.triangle = prim;
        Hit { t, prim, material: self.material[prim as usize], surface }
    }

    /// Surface data of primitive `prim` at the point `p` at `time`, with texture coordinates.
    #[inline]
    pub fn surface(&self, prim: u32, p: Vec3A, time: f32) -> SurfacePoint {
        if self.velocity.is_none() {
            return self.prims[prim as usize].surface(p, true);
        }
        self.moving_surface(prim, p, time, true)
    }

    /// [`Self::surface`] in scenes with motion (kept out of line).
    #[inline(never)]
    fn moving_surface(&self, prim: u32, p: Vec3A, time: f32, uv: bool) -> SurfacePoint {
        // The primitive where it is at `time`: found at rest, moved back.
        let off = self.offset(prim, time);
        let mut surface = self.prims[prim as usize].surface(p - off, uv);
        surface.err += crate::math::gamma(2) * (surface.p.abs() + off.abs()).max_element();
        surface.p += off;
        surface
    }

    /// The flat primitive lists, for scenes small enough to trace as streams.
    pub fn flat(&self) -> Option<&FlatPrims> {
        self.flat.as_ref()
    }

    /// True when something lies on the ray with `t` in `(0, tmax)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, tmax: f32) -> bool {
        match &self.velocity {
            None => self.occluded_with(ray, tmax, |_| ray.origin),
            Some(v) => self.occluded_with(ray, tmax, |slot| ray.origin - v[slot] * ray.time),
        }
    }

    #[inline(always)]
    fn occluded_with(&self, ray: &Ray, tmax: f32, origin: impl Fn(usize) -> Vec3A) -> bool {
        let Some(bvh) = self.bvh.as_ref() else { return false };
        bvh.any(ray.origin, ray.dir, tmax, |first, count| {
            (first as usize..(first + count) as usize)
                .any(|slot| self.test(slot, origin(slot), ray.dir, tmax) < tmax)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::{Quad, Sphere, TransformedSphere, Triangle};
    use glam::Affine3A;

    use crate::testing::signed as xorshift;

    /// A deterministic scatter of spheres and quads, including huge, tiny and overlapping ones.
    fn scene() -> Vec<Primitive> {
        let mut r = xorshift(12345);
        let mut rnd = move || 0.5 * (r() + 1.0);
        let mut v = Vec::new();
        for i in 0..300 {
            let c = Vec3A::new(rnd(), rnd(), rnd()) * 20.0 - 10.0;
            if i % 2 == 0 {
                let r = [0.001, 0.3, 2.0, 50.0][i % 4 / 2 + (i % 7 == 0) as usize * 2];
                v.push(Primitive::Sphere(Sphere::new(c, r)));
            } else {
                let u = Vec3A::new(rnd(), rnd(), rnd()) * 3.0;
                let w = Vec3A::new(rnd(), rnd(), rnd()) * 3.0;
                if let Some(q) = Quad::new(c, u, w) {
                    v.push(Primitive::Quad(q));
                }
            }
        }
        v
    }

    #[test]
    fn bvh_closest_hit_equals_brute_force() {
        let prims = scene();
        let n = prims.len();
        let geo = Geometry::build_bvh(prims.clone(), (0..n as u32).collect());
        geo.validate().unwrap();
        let mut rnd = xorshift(99);
        let (mut hits, mut sum_t) = (0, 0.0f64);
        for _ in 0..5000 {
            let o = Vec3A::new(rnd(), rnd(), rnd()) * 30.0;
            let d = Vec3A::new(rnd(), rnd(), rnd());
            let ray = Ray::new(o, d);
            let brute = prims.iter().map(|p| p.intersect(o, d, f32::INFINITY)).fold(f32::INFINITY, f32::min);
            let got = geo.intersect(&ray, f32::INFINITY).map_or(f32::INFINITY, |h| h.t);
            assert_eq!(brute, got, "ray {o} {d}");
            assert_eq!(geo.occluded(&ray, f32::INFINITY), brute.is_finite());
            if got.is_finite() {
                hits += 1;
                sum_t += got as f64;
            }
        }
        assert!(hits > 500, "the test must exercise hits: {hits}, sum {sum_t}");
    }

    #[test]
    fn flat_scan_and_stream_equal_the_bvh() {
        use crate::accel::flat::RayStream;
        // Quads and spheres, and ellipsoids (tested ray by ray); a triangle sends the scene to
        // the BVH.
        let triangle = Triangle::new(Vec3A::ZERO, Vec3A::X, Vec3A::Y).unwrap();
        let with_triangle: Vec<Primitive> =
            scene().into_iter().take(3).chain([Primitive::Triangle(triangle)]).collect();
        assert!(Geometry::build(with_triangle, (0..4).collect()).flat().is_none());
        let mut prims: Vec<Primitive> = scene().into_iter().take(FLAT_MAX - 2).collect();
        let centers = [Vec3A::new(2.0, 3.0, 4.0), Vec3A::new(-5.0, 6.0, 1.0)];
        for (i, c) in centers.into_iter().enumerate() {
            let m = Affine3A::from_scale_rotation_translation(
                glam::Vec3::new(1.0, 2.5, 0.5 + i as f32),
                glam::Quat::from_rotation_y(0.7),
                c.into(),
            );
            prims.push(Primitive::TransformedSphere(
                TransformedSphere::new(Sphere::new(Vec3A::ZERO, 1.5), m).unwrap(),
            ));
        }
        let n = prims.len() as u32;
        let geo = Geometry::build(prims.clone(), (0..n).collect());
        let f = geo.flat().expect("small scenes have flat lists");
        assert!(Geometry::build_bvh(prims.clone(), (0..n).collect()).flat().is_none());
        let mut rnd = xorshift(7);
        let mut stream = RayStream::default();
        let mut rays = Vec::new();
        for k in 0..3000 {
            let o = Vec3A::new(rnd(), rnd(), rnd()) * 15.0;
            let mut d = Vec3A::new(rnd(), rnd(), rnd());
            if k % 3 == 0 {
                // Aimed at an ellipsoid.
                d = centers[k % 2] + Vec3A::new(rnd(), rnd(), rnd()) * 2.0 - o;
            }
            let ray = Ray::new(o, d);
            stream.push(ray.origin.to_array(), ray.dir.to_array());
            rays.push(ray);
        }
        let (mut t, mut id) = (vec![f32::INFINITY; rays.len()], vec![0; rays.len()]);
        f.intersect_stream(&stream, &mut t, &mut id);
        let mut occ = vec![false; rays.len()];
        f.occluded_stream(&stream, &mut occ);
        let (mut hits, mut others) = (0, 0);
        for (i, ray) in rays.iter().enumerate() {
            let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
            let a = f.intersect(o, d, f32::INFINITY);
            let b = geo.intersect(ray, f32::INFINITY).map(|h| (h.t, h.prim));
            assert_eq!(a, b, "flat scan vs BVH");
            assert_eq!(a, (id[i] != u32::MAX).then_some((t[i], id[i])), "stream vs scan");
            assert_eq!(occ[i], f.occluded(o, d, 1.0));
            assert_eq!(occ[i], geo.occluded(ray, 1.0));
            hits += a.is_some() as u32;
            let other = |p: u32| {
                matches!(geo.prims[p as usize], Primitive::TransformedSphere(_) | Primitive::Triangle(_))
            };
            others += a.is_some_and(|(_, p)| other(p)) as u32;
        }
        assert!(hits > 300 && others > 20, "{hits} hits, {others} on ellipsoids");
    }

    #[test]
    fn empty_geometry_has_no_hits() {
        let geo = Geometry::build(vec![], vec![]);
        let ray = Ray::new(Vec3A::ZERO, Vec3A::X);
        assert!(geo.intersect(&ray, f32::INFINITY).is_none());
        assert!(!geo.occluded(&ray, f32::INFINITY));
    }

    #[test]
    fn axis_aligned_rays_with_negative_zero_components_hit() {
        // -Z is (-0, -0, -1): obvhs used to miss every node with such a ray.
        let s = Primitive::Sphere(Sphere::new(Vec3A::ZERO, 1.0));
        let geo = Geometry::build_bvh(vec![s, s], vec![0, 0]);
        for dir in [-Vec3A::X, -Vec3A::Y, -Vec3A::Z, Vec3A::X, Vec3A::Y, Vec3A::Z] {
            let ray = Ray::new(-4.0 * dir, dir);
            let hit = geo.intersect(&ray, f32::INFINITY).map(|h| h.t);
            assert_eq!(hit, Some(3.0), "{dir}");
            assert!(geo.occluded(&ray, 10.0), "{dir}");
        }
    }
}
