//! Ray queries over a queue of rays, as the wavefront's stages ask them: the closest hits of
//! the active paths' rays, and the occlusion of a queue of shadow rays. How the rays are
//! traced is decided here, from what the scene holds, after pbrt-v4's aggregate
//! (`IntersectClosest`/`IntersectShadow` over a queue): small scenes without triangles as one
//! flat stream, primitive by primitive across the rays ([`crate::accel::flat`]); still
//! geometry with a BVH in packets of [`PACKET`] rays, the last few one by one; moving geometry
//! ray by ray; instances after the primitives, the first vertices' shadow rays through still
//! instances in packets. Every way gives each ray the hit [`Aggregate::intersect`] gives it
//! alone (and [`Aggregate::occluded`] the same answers).

use super::bvh8::PACKET;
use super::flat::RayStream;
use super::geometry::{Geometry, Hit};
use super::instances::Instances;
use crate::math::Ray;
use glam::Vec3A;

/// What ray queries see of a scene: its primitives and, where it has any, its instances.
#[derive(Clone, Copy)]
pub struct Aggregate<'a> {
    /// The primitives (flat lists or a BVH).
    pub geometry: &'a Geometry,
    /// The instances, `None` in scenes without any.
    pub instances: Option<&'a Instances>,
    /// Whether hits carry texture coordinates (scenes with textures).
    pub uv: bool,
}

/// Storage of a closest-hit query over a queue (kept between queries so that none allocates):
/// the rays as a stream and the closest distance and primitive found for each.
#[derive(Clone, Debug, Default)]
pub struct ClosestQuery {
    rays: RayStream,
    t: Vec<f32>,
    prim: Vec<u32>,
    /// The rays were not traced together ([`Aggregate::closest_hit`] traces each alone).
    alone: bool,
}

impl ClosestQuery {
    /// Room for `n` rays.
    pub fn reserve(&mut self, n: usize) {
        let floats = self.rays.o.iter_mut().chain(self.rays.d.iter_mut()).chain([&mut self.t]);
        floats.for_each(|v| v.reserve(n.saturating_sub(v.len())));
        self.prim.reserve(n.saturating_sub(self.prim.len()));
    }
}

impl Aggregate<'_> {
    /// The closest hit on the ray with `t` in `(0, tmax)`, primitives and instances alike.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmax: f32) -> Option<Hit> {
        let hit = self.geometry.intersect_uv(ray, tmax, self.uv);
        match self.instances {
            Some(instances) => instances.intersect(ray, hit.map_or(tmax, |h| h.t)).or(hit),
            None => hit,
        }
    }

    /// True when a primitive or an instance lies on the ray with `t` in `(0, tmax)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, tmax: f32) -> bool {
        self.geometry.occluded(ray, tmax) || self.instances.is_some_and(|i| i.occluded(ray, tmax))
    }

    /// Traces the `n` rays whose origin and direction are `ray(k)` (each to `t` = infinity)
    /// together where the geometry allows it (still geometry: the rays' times do not matter);
    /// [`Self::closest_hit`] then gives ray `k`'s hit. Two steps, so that the caller may
    /// change what `ray` reads while it takes the hits.
    pub fn trace_closest(&self, query: &mut ClosestQuery, n: usize, ray: impl Fn(usize) -> (Vec3A, Vec3A)) {
        let geo = self.geometry;
        query.alone = !(geo.flat().is_some() || geo.is_static_bvh());
        if query.alone {
            return;
        }
        query.t.clear();
        query.t.resize(n, f32::INFINITY);
        query.prim.resize(n, 0);
        match geo.flat() {
            Some(flat) => {
                query.rays.fill_with(n, |k| {
                    let (o, d) = ray(k);
                    (o.to_array(), d.to_array())
                });
                flat.intersect_stream(&query.rays, &mut query.t, &mut query.prim);
            }
            None => closest_in_packets(geo, n, &ray, &mut query.t, &mut query.prim),
        }
    }

    /// The closest hit of ray `k` of the last [`Self::trace_closest`] (`ray` is that ray):
    /// the primitive it found, or the instances' hit before it.
    #[inline(always)]
    pub fn closest_hit(&self, query: &ClosestQuery, k: usize, ray: &Ray) -> Option<Hit> {
        if query.alone {
            return self.intersect(ray, f32::INFINITY);
        }
        let (t, prim) = (query.t[k], query.prim[k]);
        let hit = (prim != u32::MAX).then(|| self.geometry.static_hit(ray, t, prim, self.uv));
        // Instances behind the primitives' hit are not looked at.
        match self.instances {
            Some(instances) => instances.intersect(ray, t).or(hit),
            None => hit,
        }
    }

    /// Occlusion of the shadow rays `rays` (at times `time`, each reaching its light at
    /// `t` = 1) into `occluded`. Runs of [`PACKET`] rays for which `coherent` holds (they
    /// leave one spot for one light: the shadow rays of one pixel's first vertices) go
    /// through still instances together.
    pub fn trace_occluded(
        &self,
        rays: &RayStream,
        time: &[f32],
        coherent: impl Fn(usize) -> bool,
        occluded: &mut Vec<bool>,
    ) {
        let n = rays.len();
        occluded.clear();
        occluded.resize(n, false);
        let ray = |k: usize| Ray { time: time[k], ..ray_of(rays, k) };
        let geo = self.geometry;
        match geo.flat() {
            Some(flat) => flat.occluded_stream(rays, occluded),
            None if geo.is_static_bvh() => occluded_in_packets(geo, rays, occluded),
            None => {
                for (k, o) in occluded.iter_mut().enumerate() {
                    *o = self.occluded(&ray(k), 1.0);
                }
                return;
            }
        }
        let Some(instances) = self.instances else { return };
        let packets = instances.still();
        let mut k = 0;
        while k < n {
            if packets && k + PACKET <= n && (k..k + PACKET).all(&coherent) {
                shadow_packet_in_instances(instances, rays, k, &mut occluded[k..k + PACKET]);
                k += PACKET;
                continue;
            }
            if !occluded[k] {
                occluded[k] = instances.occluded(&ray(k), 1.0);
            }
            k += 1;
        }
    }
}

/// Ray `k` of a stream, at time 0.
#[inline(always)]
fn ray_of(rays: &RayStream, k: usize) -> Ray {
    let ([ox, oy, oz], [dx, dy, dz]) = (&rays.o, &rays.d);
    Ray::new(Vec3A::new(ox[k], oy[k], oz[k]), Vec3A::new(dx[k], dy[k], dz[k]))
}

/// Closest hits `(t, prim)` of the rays `ray(0..n)` in still geometry with a BVH, in packets
/// of [`PACKET`] consecutive rays traced together (the last few one by one): the same hits as
/// one at a time. Camera rays come in runs of one pixel's samples, whose packets stay
/// together; bounce rays gain less but still gain: spheres-sky's closest hits ran 11.8 M rays/s
/// per thread without packets and 14.4 with every ray in one (benches/results/). A mesh's
/// rays stay single: in its deep tree they part ways at once, and packets were slower.
fn closest_in_packets(
    geo: &Geometry,
    n: usize,
    ray: &impl Fn(usize) -> (Vec3A, Vec3A),
    t: &mut [f32],
    prim: &mut [u32],
) {
    let groups = n / PACKET;
    for g in 0..groups {
        let (mut o, mut d) = ([[0.0; PACKET]; 3], [[0.0; PACKET]; 3]);
        for l in 0..PACKET {
            let (origin, dir) = ray(g * PACKET + l);
            for a in 0..3 {
                (o[a][l], d[a][l]) = (origin[a], dir[a]);
            }
        }
        let ts = &mut t[g * PACKET..(g + 1) * PACKET];
        let mut best = [0.0; PACKET];
        best.copy_from_slice(ts);
        let hit = crate::simd::lanes(
            #[inline(always)]
            || geo.closest_packet(&o, &d, &mut best),
        );
        ts.copy_from_slice(&best);
        prim[g * PACKET..(g + 1) * PACKET].copy_from_slice(&hit);
    }
    for k in groups * PACKET..n {
        let (o, d) = ray(k);
        (t[k], prim[k]) = geo.closest_static(&Ray::new(o, d), t[k]);
    }
}

/// The rays `k..k + PACKET` of a stream as lane arrays.
#[inline(always)]
fn packet_of(rays: &RayStream, k: usize) -> ([[f32; PACKET]; 3], [[f32; PACKET]; 3]) {
    let (mut o, mut d) = ([[0.0; PACKET]; 3], [[0.0; PACKET]; 3]);
    for a in 0..3 {
        o[a].copy_from_slice(&rays.o[a][k..k + PACKET]);
        d[a].copy_from_slice(&rays.d[a][k..k + PACKET]);
    }
    (o, d)
}

/// Occlusion of shadow rays (tmax 1) by still primitives with a BVH, in packets of [`PACKET`]
/// consecutive rays traced together (the last few one by one).
fn occluded_in_packets(geo: &Geometry, rays: &RayStream, occluded: &mut [bool]) {
    let n = rays.len();
    let groups = n / PACKET;
    for g in 0..groups {
        let (o, d) = packet_of(rays, g * PACKET);
        let hit = crate::simd::lanes(
            #[inline(always)]
            || geo.occluded_packet(&o, &d, &[1.0; PACKET]),
        );
        for l in 0..PACKET {
            occluded[g * PACKET + l] = hit >> l & 1 != 0;
        }
    }
    for k in groups * PACKET..n {
        occluded[k] = geo.occluded(&ray_of(rays, k), 1.0);
    }
}

/// The shadow rays `k..k + PACKET` not yet occluded, through still instances together: rays
/// that leave one spot for one light, so the TLAS and BLAS nodes are read once for all of them
/// ([`Instances::occluded_packet`]), with the answers of [`Instances::occluded`].
fn shadow_packet_in_instances(instances: &Instances, rays: &RayStream, k: usize, occluded: &mut [bool]) {
    let (o, d) = packet_of(rays, k);
    let tmax: [f32; PACKET] = std::array::from_fn(|l| if occluded[l] { -1.0 } else { 1.0 });
    let hit = crate::simd::lanes(
        #[inline(always)]
        || instances.occluded_packet(&o, &d, &tmax),
    );
    for l in 0..PACKET {
        occluded[l] |= hit >> l & 1 != 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::geometry::FLAT_MAX;
    use crate::accel::instances::Instance;
    use crate::accel::mesh::{MeshBlas, MeshData};
    use crate::shape::{Primitive, Quad, Sphere};
    use glam::{Affine3A, Quat, Vec3};
    use std::sync::Arc;

    /// `n` spheres and quads about the origin.
    fn prims(n: usize) -> Vec<Primitive> {
        let mut rnd = crate::testing::signed(17);
        (0..n)
            .filter_map(|i| {
                let c = Vec3A::new(rnd(), rnd(), rnd()) * 8.0;
                match i % 2 {
                    0 => Some(Primitive::Sphere(Sphere::new(c, 0.3 + rnd().abs()))),
                    _ => Quad::new(
                        c,
                        Vec3A::new(rnd(), rnd(), rnd()) * 3.0,
                        Vec3A::new(rnd(), rnd(), rnd()) * 3.0,
                    )
                    .map(Primitive::Quad),
                }
            })
            .collect()
    }

    fn instances(moving: bool) -> Instances {
        let blas = Arc::new(MeshBlas::build(Arc::new(MeshData::knot(30, 12))));
        let place = |a: f32, t: Vec3| {
            Affine3A::from_scale_rotation_translation(Vec3::splat(0.8), Quat::from_rotation_y(a), t)
        };
        let v = if moving { Vec3A::X } else { Vec3A::ZERO };
        let list = vec![
            Instance::new(0, place(0.3, Vec3::new(2.0, 0.0, 0.0)), 0, v).unwrap(),
            Instance::new(0, place(-1.1, Vec3::new(-3.0, 1.0, 0.5)), 1, Vec3A::ZERO).unwrap(),
        ];
        Instances::build(vec![blas], list, (0.0, 1.0))
    }

    /// Every way of tracing a queue (flat streams, packets, one by one; with and without
    /// still or moving instances; rays in runs from one point, as a pixel's, and scattered)
    /// gives each ray what it gets alone.
    #[test]
    fn a_queue_gets_the_answers_of_its_rays_alone() {
        let ids = |p: &[Primitive]| (0..p.len() as u32).collect::<Vec<_>>();
        let (few, many) = (prims(FLAT_MAX - 4), prims(300));
        let flat = Geometry::build(few.clone(), ids(&few));
        let bvh = Geometry::build(many.clone(), ids(&many));
        let velocity = (0..many.len()).map(|i| Vec3A::new(0.0, (i % 3) as f32, 0.0)).collect();
        let moving = Geometry::build_moving(many.clone(), ids(&many), velocity, (0.0, 1.0));
        assert!(flat.flat().is_some() && bvh.is_static_bvh() && !moving.is_static_bvh());
        let (still, moved) = (instances(false), instances(true));
        let mut rnd = crate::testing::signed(3);
        let n = 16 * 20 + 5;
        let rays: Vec<Ray> = (0..n)
            .map(|k| {
                let o = match k / 16 % 2 {
                    0 => Vec3A::new(1.0, 2.0, 14.0) + Vec3A::new(rnd(), rnd(), rnd()) * 0.01,
                    _ => Vec3A::new(rnd(), rnd(), rnd()) * 15.0,
                };
                let d = Vec3A::new(rnd(), rnd(), rnd()) * 6.0 - o;
                Ray { origin: o, dir: d, time: rnd().abs() }
            })
            .collect();
        let time: Vec<f32> = rays.iter().map(|r| r.time).collect();
        // Shadow rays most of the way to the points aimed at.
        let short: Vec<Ray> = rays.iter().map(|r| Ray { dir: r.dir * 0.8, ..*r }).collect();
        let mut stream = RayStream::default();
        short.iter().for_each(|r| stream.push(r.origin.to_array(), r.dir.to_array()));
        let mut query = ClosestQuery::default();
        let (mut hits, mut blocked, mut occluded) = (0, 0, Vec::new());
        for geometry in [&flat, &bvh, &moving] {
            for instances in [None, Some(&still), Some(&moved)] {
                let a = Aggregate { geometry, instances, uv: true };
                a.trace_closest(&mut query, n, |k| (rays[k].origin, rays[k].dir));
                for (k, ray) in rays.iter().enumerate() {
                    let (got, alone) = (a.closest_hit(&query, k, ray), a.intersect(ray, f32::INFINITY));
                    let key = |h: Option<Hit>| h.map(|h| (h.t, h.prim, h.material));
                    assert_eq!(key(got), key(alone), "ray {k}");
                    hits += alone.is_some() as u32;
                }
                a.trace_occluded(&stream, &time, |k| k / 16 % 2 == 0, &mut occluded);
                for (k, ray) in short.iter().enumerate() {
                    assert_eq!(occluded[k], a.occluded(ray, 1.0), "shadow ray {k}");
                    blocked += occluded[k] as u32;
                }
            }
        }
        assert!(hits > n as u32 * 3 && blocked > n as u32, "{hits} hits, {blocked} blocked");
    }
}
