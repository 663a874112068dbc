//! Mesh instances and the top-level BVH over them. An instance places a shared [`MeshBlas`]
//! with an affine transform, a material and a velocity; rays move into the instance's object
//! space, so a thousand instances of a mesh cost a thousand instance records and one BLAS.

use crate::accel::bvh8::{Bvh8, PACKET};
use crate::accel::geometry::Hit;
use crate::accel::mesh::{MeshBlas, MeshHit};
use crate::animation::ShutterMotion;
use crate::math::{Ray, gamma, transform_box};
use crate::shape::{MeshPoint, SurfacePoint, adapt_shading_normal};
use glam::{Affine3A, Mat3A, Vec3A};
use obvhs::aabb::Aabb;
use std::sync::Arc;

/// The `prim` of a [`Hit`] on an instance (there is no primitive index: the triangle is an
/// instance's business, and emitters are never instanced).
pub const INSTANCE_PRIM: u32 = u32::MAX;

/// One placed mesh.
#[derive(Clone, Debug)]
pub struct Instance {
    /// Index into [`Instances::blas`].
    pub blas: u32,
    /// Object to world (at time 0).
    pub world_from_object: Affine3A,
    /// World to object.
    pub object_from_world: Affine3A,
    /// Inverse transpose of the linear part (object normals to world normals).
    pub normal_to_world: Mat3A,
    /// Material id.
    pub material: u32,
    /// World units per unit time.
    pub velocity: Vec3A,
    /// A placement that turns or scales while the shutter is open: then it, not the fields
    /// above, places the instance (per ray time).
    pub motion: Option<Box<ShutterMotion>>,
}

impl Instance {
    /// World bounds over the `shutter` interval of the instance of a mesh whose object-space
    /// bounds are `object`.
    pub fn world_bounds(&self, object: &Aabb, shutter: (f32, f32)) -> Aabb {
        if let Some(m) = &self.motion {
            return m.bounds(object);
        }
        let b = transform_box(object, &self.world_from_object);
        let (a, c) = (self.velocity * shutter.0, self.velocity * shutter.1);
        Aabb { min: b.min + a.min(c), max: b.max + a.max(c) }
    }

    /// True when the instance does not move while the shutter is open.
    fn is_still(&self) -> bool {
        self.motion.is_none() && self.velocity == Vec3A::ZERO
    }

    /// An instance, or `None` when the transform is singular or not finite.
    pub fn new(blas: u32, world_from_object: Affine3A, material: u32, velocity: Vec3A) -> Option<Self> {
        let det = world_from_object.matrix3.determinant();
        if !(det.abs() > 0.0 && det.is_finite() && world_from_object.translation.is_finite()) {
            return None;
        }
        let object_from_world = world_from_object.inverse();
        Some(Self {
            blas,
            world_from_object,
            object_from_world,
            normal_to_world: object_from_world.matrix3.transpose(),
            material,
            velocity,
            motion: None,
        })
    }

    /// This instance turning or scaling over the shutter as `motion` says (its fixed fields
    /// then hold the mid-shutter placement, for anything that wants one).
    pub fn with_motion(mut self, motion: Option<ShutterMotion>) -> Self {
        self.motion = motion.map(Box::new);
        self
    }
}

/// Instances, the BLAS they share and the TLAS over them.
#[derive(Clone, Debug, Default)]
pub struct Instances {
    /// Bottom-level BVHs.
    pub blas: Vec<Arc<MeshBlas>>,
    /// The instances.
    pub list: Vec<Instance>,
    /// Shutter interval the TLAS bounds cover (moving instances are swept over it).
    pub shutter: (f32, f32),
    /// The instances traced together in world space ([`Merged`]); the TLAS holds the others.
    merged: Option<Merged>,
    tlas: Bvh8,
    /// Instance indices in TLAS leaf order (the instances [`Self::merged`] does not hold).
    order: Vec<u32>,
    /// Sum of child-box areas when the TLAS was built (see [`Bvh8::sah_cost`]).
    built_cost: f32,
    /// Some instance moves while the shutter is open (at the last build or refit); false for
    /// none, so that a default (empty) set is still.
    moving: bool,
    /// An instance of the merged BVH was placed anew: a refit cannot follow it.
    stale: bool,
}

/// Still instances of meshes that no other instance shares, their triangles placed in world
/// space under one BVH: what a single-level BVH over every mesh does for them (Embree's, in
/// Mitsuba 3). Under the TLAS a ray enters, one after another, each mesh whose box it crosses,
/// and the meshes of a room (its walls, a lamp, a table) all overlap: on Bitterli's veach-bidir
/// (12 meshes) closest hits ran at 4.3 M rays/s a thread under the TLAS and 6.0 merged
/// (`benches/results/bvh-and-traversal.md`). A hit is handed back as the instance's own.
#[derive(Clone, Debug, Default)]
struct Merged {
    /// The BVH of the triangles in world space.
    bvh: Arc<MeshBlas>,
    /// Each of its triangles' instance, and the triangle's index in the instance's mesh.
    of: Vec<(u32, u32)>,
    /// The instances it holds.
    holds: Vec<bool>,
}

/// The most triangles [`Merged`] takes: each costs its world-space copy in the BVH's blocks
/// and nodes (about 55 bytes) beside its mesh's own BLAS.
const MERGED_TRIANGLES: usize = 1 << 20;

impl Merged {
    /// The merged BVH of `list`'s still instances of meshes no other instance shares, when
    /// there are at least two (and [`MERGED_TRIANGLES`] triangles at most).
    fn build(blas: &[Arc<MeshBlas>], list: &[Instance]) -> Option<Self> {
        let mut users = vec![0u32; blas.len()];
        list.iter().for_each(|inst| users[inst.blas as usize] += 1);
        let holds: Vec<bool> =
            list.iter().map(|inst| inst.is_still() && users[inst.blas as usize] == 1).collect();
        let held = || list.iter().enumerate().filter(|&(i, _)| holds[i]);
        let count: usize = held().map(|(_, inst)| blas[inst.blas as usize].mesh.triangles.len()).sum();
        if held().count() < 2 || count > MERGED_TRIANGLES {
            return None;
        }
        let (mut triangles, mut of) = (Vec::with_capacity(count), Vec::with_capacity(count));
        for (i, inst) in held() {
            let mesh = &blas[inst.blas as usize].mesh;
            for t in 0..mesh.triangles.len() as u32 {
                triangles.push(mesh.triangle(t).map(|p| inst.world_from_object.transform_point3a(p)));
                of.push((i as u32, t));
            }
        }
        Some(Self { bvh: Arc::new(MeshBlas::over_triangles(&triangles)), of, holds })
    }
}

impl Instances {
    /// Builds the TLAS over `list` (BLAS indices into `blas`); bounds cover each instance's
    /// motion over `shutter`.
    pub fn build(blas: Vec<Arc<MeshBlas>>, list: Vec<Instance>, shutter: (f32, f32)) -> Self {
        Self::build_merging(blas, list, shutter, true)
    }

    /// [`Self::build`], with a [`Merged`] BVH where `merge` allows.
    fn build_merging(
        blas: Vec<Arc<MeshBlas>>,
        list: Vec<Instance>,
        shutter: (f32, f32),
        merge: bool,
    ) -> Self {
        let _span = tracing::info_span!("build_tlas", instances = list.len()).entered();
        let merged = merge.then(|| Merged::build(&blas, &list)).flatten();
        let mut me = Self { blas, list, shutter, merged, ..Default::default() };
        let traced: Vec<u32> = (0..me.list.len() as u32).filter(|&i| !me.is_merged(i as usize)).collect();
        let aabbs: Vec<Aabb> = traced.iter().map(|&i| me.world_bounds(i as usize)).collect();
        let mut order = Vec::with_capacity(aabbs.len());
        me.tlas = Bvh8::build(&aabbs, 4, |prims| {
            order.extend(prims.iter().map(|&p| traced[p as usize]));
            ((order.len() - prims.len()) as u32, prims.len() as u32)
        });
        me.order = order;
        me.built_cost = me.tlas.sah_cost();
        me.moving = !me.list.iter().all(Instance::is_still);
        me
    }

    /// How many instances the merged BVH holds (still instances of meshes no other instance
    /// uses, traced together in world space).
    pub fn merged(&self) -> usize {
        self.merged.as_ref().map_or(0, |m| m.holds.iter().filter(|&&h| h).count())
    }

    /// Whether instance `i` is traced in the merged BVH, not under the TLAS.
    #[inline]
    fn is_merged(&self, i: usize) -> bool {
        self.merged.as_ref().is_some_and(|m| m.holds[i])
    }

    /// True when no instance moves while the shutter is open (as placed at the last build or
    /// [`Self::refit`]).
    pub fn still(&self) -> bool {
        !self.moving
    }

    /// True when there are no instances.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// World bounds of instance `i` over the shutter interval.
    pub fn world_bounds(&self, i: usize) -> Aabb {
        let inst = &self.list[i];
        inst.world_bounds(&self.blas[inst.blas as usize].bounds(), self.shutter)
    }

    /// Replaces the placement of instance `i` (call [`Self::refit`] after the last one; an
    /// instance of the merged BVH moved makes it ask for a build).
    pub fn place(
        &mut self,
        i: usize,
        world_from_object: Affine3A,
        velocity: Vec3A,
        motion: Option<ShutterMotion>,
    ) -> bool {
        let old = &self.list[i];
        match Instance::new(old.blas, world_from_object, old.material, velocity) {
            Some(new) => {
                self.list[i] = new.with_motion(motion);
                self.stale |= self.is_merged(i);
                true
            }
            None => false,
        }
    }

    /// Refits the TLAS to the instances' current placements. Returns false, leaving the TLAS
    /// as it was fitted, when the refitted tree has become much worse than a fresh build would
    /// be (its node areas doubled): then the caller rebuilds.
    pub fn refit(&mut self) -> bool {
        let _span = tracing::info_span!("refit_tlas", instances = self.list.len()).entered();
        self.moving = !self.list.iter().all(Instance::is_still);
        let aabbs: Vec<Aabb> = (0..self.list.len()).map(|i| self.world_bounds(i)).collect();
        let order = &self.order;
        self.tlas.refit(|first, count| {
            order[first as usize..(first + count) as usize]
                .iter()
                .fold(Aabb::empty(), |b, &i| b.union(&aabbs[i as usize]))
        });
        !self.stale && self.tlas.sah_cost() <= 2.0 * self.built_cost.max(1.0)
    }

    /// Checks the TLAS's invariants ([`Bvh8::validate`], each leaf's box around its instances'
    /// bounds over the shutter).
    pub fn validate(&self) -> Result<(), String> {
        if let Some(m) = &self.merged {
            m.bvh.validate()?;
        }
        self.tlas.validate(|first, count| {
            self.order[first as usize..(first + count) as usize]
                .iter()
                .fold(Aabb::empty(), |b, &i| b.union(&self.world_bounds(i as usize)))
        })
    }

    /// Bytes held by the instance records and the TLAS (not the BLAS).
    pub fn bytes(&self) -> usize {
        let merged = self.merged.as_ref().map_or(0, |m| m.bvh.bytes() + m.of.len() * 8 + m.holds.len());
        self.list.len() * size_of::<Instance>() + self.tlas.node_bytes() + self.order.len() * 4 + merged
    }

    /// The ray in instance `i`'s object space (the direction is not renormalised, so `t` is
    /// the same in both spaces).
    #[inline(always)]
    fn object_ray(&self, inst: &Instance, ray: &Ray) -> (Vec3A, Vec3A) {
        if let Some(m) = &inst.motion {
            return m.object_ray(ray.time, ray.origin, ray.dir);
        }
        let o = ray.origin - inst.velocity * ray.time;
        (inst.object_from_world.transform_point3a(o), inst.object_from_world.transform_vector3a(ray.dir))
    }

    /// Closest hit with `t` in `(0, tmax)`. Always inlined: as a call per ray (LLVM's choice
    /// for `#[inline]`) the mesh's closest hits ran 4-5% slower, and a profile-guided build,
    /// which inlines it, showed the way (benches/RESULTS.md).
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, tmax: f32) -> Option<Hit> {
        let mut found: Option<(u32, MeshHit)> = None;
        let mut tmax = tmax;
        if let Some(m) = &self.merged
            && let Some(h) = m.bvh.intersect(ray.origin, ray.dir, tmax)
        {
            // The instance's own triangle, its corners in object space.
            let (i, id) = m.of[h.id as usize];
            let mesh = &self.blas[self.list[i as usize].blas as usize].mesh;
            (tmax, found) = (h.t, Some((i, MeshHit { t: h.t, id, p: mesh.triangle(id) })));
        }
        let t = self.tlas.closest(ray.origin, ray.dir, tmax, |first, count, mut best| {
            for &i in &self.order[first as usize..(first + count) as usize] {
                let inst = &self.list[i as usize];
                let (o, d) = self.object_ray(inst, ray);
                if let Some(h) = self.blas[inst.blas as usize].intersect(o, d, best) {
                    (best, found) = (h.t, Some((i, h)));
                }
            }
            best
        });
        found.map(|(i, tri)| {
            let inst = &self.list[i as usize];
            Hit { t, prim: INSTANCE_PRIM, material: inst.material, surface: self.surface(i, &tri, ray, t) }
        })
    }

    /// Which of [`PACKET`] rays (world space, instances [`Self::still`]) meet an instance with
    /// `t` in `(0, tmax[l])`, traced together, as a bit mask: [`Self::occluded`]'s answers. A
    /// negative `tmax` leaves the ray out.
    #[inline(always)]
    pub fn occluded_packet(
        &self,
        o: &[[f32; PACKET]; 3],
        d: &[[f32; PACKET]; 3],
        tmax: &[f32; PACKET],
    ) -> u32 {
        debug_assert!(self.still());
        let merged = self.merged.as_ref().map_or(0, |m| m.bvh.occluded_packet(o, d, tmax));
        let tmax: [f32; PACKET] = std::array::from_fn(|l| if merged >> l & 1 != 0 { -1.0 } else { tmax[l] });
        merged
            | self.tlas.any_packet(o, d, &tmax, |first, count, active| {
                let mut hits = 0;
                for &i in &self.order[first as usize..(first + count) as usize] {
                    let inst = &self.list[i as usize];
                    let (oo, od) = self.object_packet(inst, o, d);
                    let t: [f32; PACKET] =
                        std::array::from_fn(|l| if (active & !hits) >> l & 1 != 0 { tmax[l] } else { -1.0 });
                    hits |= self.blas[inst.blas as usize].occluded_packet(&oo, &od, &t);
                }
                hits
            })
    }

    /// The rays of a packet in a still instance's object space, lane by lane as
    /// [`Self::object_ray`] moves one ray.
    #[inline(always)]
    fn object_packet(
        &self,
        inst: &Instance,
        o: &[[f32; PACKET]; 3],
        d: &[[f32; PACKET]; 3],
    ) -> ([[f32; PACKET]; 3], [[f32; PACKET]; 3]) {
        let (mut oo, mut od) = ([[0.0; PACKET]; 3], [[0.0; PACKET]; 3]);
        for l in 0..PACKET {
            let ray = Ray {
                origin: Vec3A::new(o[0][l], o[1][l], o[2][l]),
                dir: Vec3A::new(d[0][l], d[1][l], d[2][l]),
                time: 0.0,
            };
            let (a, b) = self.object_ray(inst, &ray);
            for k in 0..3 {
                (oo[k][l], od[k][l]) = (a[k], b[k]);
            }
        }
        (oo, od)
    }

    /// True when some instance lies on the ray with `t` in `(0, tmax)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, tmax: f32) -> bool {
        if self.merged.as_ref().is_some_and(|m| m.bvh.occluded(ray.origin, ray.dir, tmax)) {
            return true;
        }
        self.tlas.any(ray.origin, ray.dir, tmax, |first, count| {
            self.order[first as usize..(first + count) as usize].iter().any(|&i| {
                let inst = &self.list[i as usize];
                let (o, d) = self.object_ray(inst, ray);
                self.blas[inst.blas as usize].occluded(o, d, tmax)
            })
        })
    }

    /// World-space surface data of triangle `tri` of `inst` hit by `ray` at `t`: found in
    /// object space (re-projected onto the triangle, so the ray's rounding does not enter) and
    /// moved back, with the error bound of [`crate::shape::TransformedSphere`] plus the motion
    /// offset's rounding. Without vertex normals the shading normal is the geometric one.
    ///
    /// With vertex normals the shading normal is adapted to the ray ([`adapt_shading_normal`]),
    /// and the point moves along `n` by half the height `h` of the smooth surface over the
    /// triangle ([`crate::accel::mesh::terminator_lift`], Hanika 2021) while `err` grows by
    /// `h / (2 |n|_1)`: [`crate::math::offset_ray_origin`] then puts a ray that leaves on `n`'s
    /// side (the side the normals point to) `h` higher than it would have, at the smooth
    /// surface, and a ray on the other side exactly where it would have. This is done in world
    /// space, where the offset is applied (a transform that is not a similarity would break
    /// the cancellation in object space).
    fn surface(&self, index: u32, tri: &MeshHit, ray: &Ray, t: f32) -> SurfacePoint {
        let inst = &self.list[index as usize];
        let (o, d) = self.object_ray(inst, ray);
        let (local, lift) = self.blas[inst.blas as usize].surface(tri, o + t * d);
        let (m, normal_to_world, off) = match &inst.motion {
            Some(motion) => {
                let m = motion.world_from_object(ray.time);
                (m, m.matrix3.inverse().transpose(), Vec3A::ZERO)
            }
            None => (inst.world_from_object, inst.normal_to_world, inst.velocity * ray.time),
        };
        let norm = |a: &Mat3A| (a.x_axis.abs() + a.y_axis.abs() + a.z_axis.abs()).max_element();
        let scale = norm(&m.matrix3);
        let mut p = m.transform_point3a(local.p) + off;
        let magnitude = scale * local.p.abs().max_element() + m.translation.abs().max_element();
        let mut err = scale * local.err
            + gamma(4) * magnitude
            + gamma(2) * (p.abs().max_element() + off.abs().max_element());
        let n_world = normal_to_world * local.n;
        let mut n = n_world.normalize();
        let mut ns = n;
        if local.ns != local.n {
            // Smooth shading. The shading normal's side decides (the file's normals say where
            // outside is); then it is adapted to the ray that arrives.
            ns = (normal_to_world * local.ns).normalize();
            if n.dot(ns) < 0.0 {
                n = -n;
            }
            ns = adapt_shading_normal(n, ns, -ray.dir.normalize());
            if lift > 0.0 {
                // The object-space height along the unit object normal is lift / |M^-T n|
                // along the world normal.
                let h = lift / n_world.length();
                p += (0.5 * h) * n;
                err += 0.5 * h * (1.0 + gamma(4)) / n.abs().element_sum() + gamma(2) * p.abs().max_element();
            }
        }
        SurfacePoint {
            p,
            n,
            ns,
            ns_base: ns,
            uv: local.uv,
            err,
            on: MeshPoint { mesh: inst.blas, instance: index, ..local.on },
        }
    }

    /// `(dp/du, dp/dv)` in world space at a point of a placed mesh (`sp.on` names the instance
    /// and the triangle), from the triangle's corners and texture coordinates as Mitsuba's
    /// meshes compute them (with barycentric coordinates where the mesh has none); `None` off
    /// meshes and where the uvs are degenerate. A moving instance's are taken at its pose at
    /// rest.
    pub fn derivatives(&self, sp: &SurfacePoint) -> Option<(Vec3A, Vec3A)> {
        let inst = self.list.get(sp.on.instance as usize)?;
        let mesh = &self.blas[inst.blas as usize].mesh;
        let [p0, p1, p2] = mesh.triangle(sp.on.triangle);
        let (dp0, dp1) = (p1 - p0, p2 - p0);
        let (du, dv) = match &mesh.uvs {
            None => (dp0, dp1),
            Some(uvs) => {
                let [a, b, c] = mesh.triangles[sp.on.triangle as usize].map(|v| uvs[v as usize]);
                let (d0, d1) = (b - a, c - a);
                let det = d0.x * d1.y - d0.y * d1.x;
                if det == 0.0 || !det.is_finite() {
                    return None;
                }
                ((d1.y * dp0 - d0.y * dp1) / det, (d0.x * dp1 - d1.x * dp0) / det)
            }
        };
        let m = inst.world_from_object.matrix3;
        Some((m * du, m * dv))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::mesh::MeshData;
    use glam::{Quat, Vec3};

    #[test]
    fn packets_find_what_each_ray_finds_alone_among_still_instances() {
        let blas = Arc::new(MeshBlas::build(Arc::new(MeshData::knot(60, 24))));
        let place = |angle: f32, at: Vec3| {
            Affine3A::from_scale_rotation_translation(
                Vec3::new(1.0, 1.5, 0.8),
                Quat::from_rotation_y(angle),
                at,
            )
        };
        let list = vec![
            Instance::new(0, place(0.3, Vec3::new(2.0, 0.0, 0.0)), 4, Vec3A::ZERO).unwrap(),
            Instance::new(0, place(-1.1, Vec3::new(-2.0, 1.0, 0.5)), 7, Vec3A::ZERO).unwrap(),
        ];
        let mut inst = Instances::build(vec![blas], list, (0.0, 1.0));
        inst.validate().unwrap();
        assert!(inst.still());
        let mut rnd = crate::testing::signed(21);
        let (mut occluded, mut rays) = (0, 0);
        for i in 0..300 {
            let (o, d, tmax) =
                crate::accel::mesh::tests::packet(&mut rnd, if i % 2 == 0 { 0.02 } else { 2.0 }, 2.0);
            let occ = crate::simd::lanes(|| inst.occluded_packet(&o, &d, &tmax));
            for l in 0..PACKET {
                let ray = Ray {
                    origin: Vec3A::new(o[0][l], o[1][l], o[2][l]),
                    dir: Vec3A::new(d[0][l], d[1][l], d[2][l]),
                    time: rnd().abs(),
                };
                let alone = tmax[l] >= 0.0 && inst.occluded(&ray, tmax[l]);
                assert_eq!(occ >> l & 1 != 0, alone, "lane {l} of packet {i}");
                (occluded, rays) = (occluded + alone as u32, rays + (tmax[l] >= 0.0) as u32);
            }
        }
        assert!(occluded > 500 && rays - occluded > 500, "{occluded} of {rays} occluded");
        // A moving instance makes the instances unfit for packets.
        assert!(inst.place(1, place(0.0, Vec3::ZERO), Vec3A::X, None));
        inst.refit();
        inst.validate().unwrap();
        assert!(!inst.still());
    }

    /// Still instances of three meshes, one of them shared by two instances (so under the
    /// TLAS), traced with and without the merged BVH: the same hits, each the instance's own
    /// triangle. With `turned`, the instances are scaled and turned (their triangles and rays
    /// then round differently in world and object space: rays near edges may disagree).
    fn merged_against_tlas(turned: bool) -> (u32, u32) {
        let knot = |r, s| Arc::new(MeshBlas::build(Arc::new(MeshData::knot(r, s))));
        let blas = vec![knot(60, 24), knot(40, 16), knot(30, 12)];
        let place = |scale: f32, angle: f32, at: Vec3| match turned {
            true => Affine3A::from_scale_rotation_translation(
                Vec3::splat(scale),
                Quat::from_rotation_y(angle),
                at,
            ),
            false => Affine3A::IDENTITY,
        };
        let list = vec![
            Instance::new(0, place(1.0, 0.3, Vec3::new(2.0, 0.0, 0.0)), 4, Vec3A::ZERO).unwrap(),
            Instance::new(1, place(0.7, -1.1, Vec3::new(-2.0, 1.0, 0.5)), 7, Vec3A::ZERO).unwrap(),
            Instance::new(2, place(1.3, 2.0, Vec3::new(0.0, -1.0, -1.0)), 2, Vec3A::ZERO).unwrap(),
            Instance::new(2, place(0.9, 0.5, Vec3::new(0.5, 2.0, 1.0)), 3, Vec3A::ZERO).unwrap(),
        ];
        let merged = Instances::build(blas.clone(), list.clone(), (0.0, 1.0));
        merged.validate().unwrap();
        assert_eq!(merged.merged.as_ref().map(|m| m.holds.clone()), Some(vec![true, true, false, false]));
        assert_eq!((merged.order.len(), merged.merged()), (2, 2));
        let tlas = Instances::build_merging(blas, list, (0.0, 1.0), false);
        assert!(tlas.merged.is_none());
        let mut rnd = crate::testing::signed(5);
        let (mut hits, mut differ) = (0, 0);
        for i in 0..400 {
            let (o, d, tmax) =
                crate::accel::mesh::tests::packet(&mut rnd, if i % 2 == 0 { 0.02 } else { 2.0 }, 2.0);
            let occluded = [&merged, &tlas].map(|x| crate::simd::lanes(|| x.occluded_packet(&o, &d, &tmax)));
            for l in 0..PACKET {
                let ray = Ray {
                    origin: Vec3A::new(o[0][l], o[1][l], o[2][l]),
                    dir: Vec3A::new(d[0][l], d[1][l], d[2][l]),
                    time: 0.0,
                };
                let (a, b) = (merged.intersect(&ray, f32::INFINITY), tlas.intersect(&ray, f32::INFINITY));
                let key = |h: &Option<Hit>| {
                    h.as_ref().map(|h| (h.material, h.surface.on.instance, h.surface.on.triangle))
                };
                let same = key(&a) == key(&b)
                    && a.zip(b).is_none_or(|(a, b)| (a.t - b.t).abs() <= 1e-5 * a.t.max(1.0))
                    && (tmax[l] < 0.0
                        || (merged.occluded(&ray, tmax[l]) == tlas.occluded(&ray, tmax[l])
                            && (occluded[0] >> l & 1) == (occluded[1] >> l & 1)));
                assert!(same || turned, "ray {l} of packet {i}: {a:?} against {b:?}");
                (hits, differ) = (hits + a.is_some() as u32, differ + !same as u32);
            }
        }
        (hits, differ)
    }

    #[test]
    fn the_merged_bvh_finds_what_the_tlas_finds() {
        let (hits, differ) = merged_against_tlas(false);
        assert!(hits > 1000 && differ == 0, "{hits} hits, {differ} differ");
        let (hits, differ) = merged_against_tlas(true);
        assert!(hits > 1000 && differ <= hits / 500, "{hits} hits, {differ} differ");
    }

    #[test]
    fn moving_a_merged_instance_asks_for_a_build() {
        let knot = |r, s| Arc::new(MeshBlas::build(Arc::new(MeshData::knot(r, s))));
        let at = |x: f32| Affine3A::from_translation(Vec3::new(x, 0.0, 0.0));
        let list = vec![
            Instance::new(0, at(-2.0), 0, Vec3A::ZERO).unwrap(),
            Instance::new(1, at(2.0), 1, Vec3A::ZERO).unwrap(),
        ];
        let mut inst = Instances::build(vec![knot(30, 12), knot(20, 8)], list, (0.0, 1.0));
        assert!(inst.merged.is_some() && inst.refit());
        assert!(inst.place(1, at(3.0), Vec3A::X, None));
        assert!(!inst.refit(), "a refit cannot move the merged BVH's triangles");
        let rebuilt = Instances::build(inst.blas.clone(), inst.list.clone(), (0.0, 1.0));
        // Only one still instance is left: nothing to merge.
        assert!(rebuilt.merged.is_none() && !rebuilt.still());
    }
}
