//! Small scenes without a BVH: quads and spheres in structure-of-arrays form, tested by brute
//! force. A single ray scans every primitive; a stream of rays is tested primitive by primitive,
//! each test running over all rays so that it vectorises across rays (8 lanes with AVX2).
//! Ellipsoids follow, tested ray by ray with their own test; scenes with triangles take the
//! BVH. Both scan quads, then spheres, then ellipsoids, in order, keeping the first of equal
//! distances: the stream finds exactly the hits of the single-ray scan.

use crate::shape::{Primitive, quad::quad_t, sphere::sphere_t};
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

/// Quads and spheres as parallel arrays, ellipsoids (and other kinds without a stream test)
/// as they are, with their primitive indices.
#[derive(Default, Debug)]
pub struct FlatPrims {
    quads: Vec<[[f32; 3]; 4]>,
    quad_id: Vec<u32>,
    spheres: Vec<([f32; 3], f32)>,
    sphere_id: Vec<u32>,
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
                    f.quad_id.push(i as u32);
                }
                Primitive::Sphere(s) => {
                    f.spheres.push((s.center.to_array(), s.radius));
                    f.sphere_id.push(i as u32);
                }
                Primitive::Triangle(_) => return None,
                // Kinds without a stream test are tested ray by ray: transforms.ron (three
                // ellipsoids among twelve quads) traced every ray through the BVH before, its
                // closest hits at 12.7 M rays/s on one thread against 18.2 now.
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
        for q in &self.quads {
            for i in 0..n {
                hit[i] |= quad_t(*q, [ox[i], oy[i], oz[i]], [dx[i], dy[i], dz[i]], 1.0) < 1.0;
            }
        }
        for (c, r) in &self.spheres {
            for i in 0..n {
                hit[i] |= sphere_t(*c, *r, [ox[i], oy[i], oz[i]], [dx[i], dy[i], dz[i]], 1.0) < 1.0;
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
