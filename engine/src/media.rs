//! Homogeneous participating media inside closed boundaries: boxes and spheres under any affine
//! transform, and closed triangle meshes (convex or not).
//!
//! Boundaries are not surfaces: they are index-matched and invisible, so they are kept out of
//! the BVH. Along a ray, each volume covers one interval of `t`, found analytically in object
//! space (a mesh covers the stretches between its hits, odd hits behind the origin meaning the
//! origin is inside); free-flight distances and transmittance follow from these intervals. Because no ray
//! ever "enters" or "leaves" a medium through a surface hit, there is no medium stack to get
//! wrong: a boundary face coplanar with an opaque surface (the smoke boxes standing on the
//! Cornell floor) cannot switch the medium off.
//!
//! Extinction is the same in every channel (`sigma_t = density`), scattering is
//! `sigma_s = albedo * density` and the phase function is isotropic. Where volumes overlap their
//! coefficients add. Cost: every query visits every volume (scenes hold a handful).

use crate::accel::mesh::MeshBlas;
use crate::shape::Closed;
use glam::{Affine3A, Vec3, Vec3A};
use std::cell::RefCell;
use std::sync::Arc;

/// A homogeneous medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Medium {
    /// Extinction coefficient (per unit length, all channels).
    pub sigma_t: f32,
    /// Single-scattering albedo `sigma_s / sigma_t`.
    pub albedo: Vec3,
}

/// The object-space shape that bounds a volume.
#[derive(Clone, Debug)]
pub enum Boundary {
    /// A box or a ball, entered and left once along a ray.
    Closed(Closed),
    /// A closed triangle mesh (checked closed at load).
    Mesh(Arc<MeshBlas>),
}

/// A medium filling a transformed boundary.
#[derive(Clone, Debug)]
pub struct Volume {
    /// World to object space (the inverse of the object's transform).
    pub object_from_world: Affine3A,
    /// The boundary in object space.
    pub boundary: Boundary,
    /// What fills it.
    pub medium: Medium,
}

impl Volume {
    /// Calls `out(t0, t1)` for each `t` interval of `o + t d` inside the volume, clipped to
    /// `[0, tmax]`, in increasing order. Affine maps preserve `t`, so intervals are computed in
    /// object space.
    #[inline]
    pub fn intervals(&self, o: Vec3A, d: Vec3A, tmax: f32, mut out: impl FnMut(f32, f32)) {
        let Boundary::Mesh(blas) = &self.boundary else {
            if let Some((t0, t1)) = self.interval(o, d, tmax) {
                out(t0, t1);
            }
            return;
        };
        let (o, d) =
            (self.object_from_world.transform_point3a(o), self.object_from_world.transform_vector3a(d));
        HITS.with_borrow_mut(|hits| {
            hits.clear();
            blas.all_hits(o, d, hits);
            hits.sort_unstable_by(f32::total_cmp);
            // An odd number of hits ahead: the origin is inside.
            let mut start = (hits.len() % 2 == 1).then_some(0.0f32);
            for &t in hits.iter() {
                match start.take() {
                    Some(t0) => {
                        let t1 = t.min(tmax);
                        if t0 < t1 {
                            out(t0, t1);
                        }
                    }
                    None => start = Some(t),
                }
                if t >= tmax {
                    break;
                }
            }
        });
    }

    /// The one `t` interval of `o + t d` inside a box or sphere volume, clipped to `[0, tmax]`,
    /// or `None` (always `None` for a mesh: see [`Self::intervals`]).
    #[inline]
    pub fn interval(&self, o: Vec3A, d: Vec3A, tmax: f32) -> Option<(f32, f32)> {
        let o = self.object_from_world.transform_point3a(o);
        let d = self.object_from_world.transform_vector3a(d);
        let (t0, t1) = match self.boundary {
            Boundary::Mesh(_) => return None,
            Boundary::Closed(Closed::Box { min, max }) => {
                let inv = d.recip();
                let (a, b) = ((min - o) * inv, (max - o) * inv);
                // 0 * inf = NaN: a ray parallel to a slab and in one of its planes, which
                // counts as inside the (closed) box: that slab does not limit it.
                let nan = a.cmpne(a) | b.cmpne(b);
                let lo = Vec3A::select(nan, Vec3A::NEG_INFINITY, a.min(b));
                let hi = Vec3A::select(nan, Vec3A::INFINITY, a.max(b));
                (lo.max_element(), hi.min_element())
            }
            Boundary::Closed(Closed::Sphere { center, radius }) => {
                // Ray Tracing Gems ch. 7: the discriminant from the closest-approach vector.
                let len = d.length();
                let dn = d / len;
                let f = o - center;
                let b = -f.dot(dn);
                let perp = f + b * dn;
                let disc = radius * radius - perp.length_squared();
                if !(disc >= 0.0) {
                    return None;
                }
                let h = disc.sqrt();
                ((b - h) / len, (b + h) / len)
            }
        };
        let (t0, t1) = (t0.max(0.0), t1.min(tmax));
        (t0 < t1).then_some((t0, t1))
    }
}

thread_local! {
    /// Scratch for the hits of a mesh boundary.
    static HITS: RefCell<Vec<f32>> = const { RefCell::new(Vec::new()) };
    /// Scratch for the intervals of all volumes along a ray: (t0, t1, volume).
    static SEGMENTS: RefCell<Vec<(f32, f32, u32)>> = const { RefCell::new(Vec::new()) };
}

/// All volumes of a scene.
#[derive(Clone, Debug, Default)]
pub struct Media {
    /// The volumes.
    pub volumes: Vec<Volume>,
}

/// A sampled scattering point along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumEvent {
    /// Ray parameter of the point.
    pub t: f32,
    /// Throughput factor: `sigma_s / sigma_t` there (the albedo, blended where volumes overlap).
    pub albedo: Vec3,
}

impl Media {
    /// No volumes.
    pub fn is_empty(&self) -> bool {
        self.volumes.is_empty()
    }

    /// Transmittance `exp(-integral of sigma_t)` along `o + t d`, `t` in `[0, tmax]`.
    #[inline]
    pub fn transmittance(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        let mut depth = 0.0;
        for v in &self.volumes {
            v.intervals(o, d, tmax, |t0, t1| depth += v.medium.sigma_t * (t1 - t0));
        }
        crate::math::exp(-depth * d.length())
    }

    /// Free-flight sampling along `o + t d` up to `tmax` (the closest surface, or infinity):
    /// the distance has density `sigma_t(t) T(t)`, from the uniform number `u` by inverting
    /// the optical depth. `None` (probability `T(tmax)`) when the ray gets through; then the
    /// throughput is unchanged, as transmittance over its probability is one.
    #[inline]
    pub fn sample(&self, o: Vec3A, d: Vec3A, tmax: f32, u: f32) -> Option<MediumEvent> {
        let len = d.length();
        // Optical depth to travel, in units of t.
        let mut left = -crate::math::ln(1.0 - u) / len;
        let mut t = 0.0f32;
        SEGMENTS.with_borrow_mut(|segs| {
            segs.clear();
            for (i, v) in self.volumes.iter().enumerate() {
                v.intervals(o, d, tmax, |t0, t1| segs.push((t0, t1, i as u32)));
            }
            // Sweep the piecewise-constant extinction: at `t`, the summed sigma_t of the
            // intervals covering [t, next) and the next interval end or start.
            loop {
                let (mut sigma, mut next) = (0.0f32, tmax);
                for &(t0, t1, i) in segs.iter() {
                    if t0 <= t && t < t1 {
                        sigma += self.volumes[i as usize].medium.sigma_t;
                        next = next.min(t1);
                    } else if t0 > t {
                        next = next.min(t0);
                    }
                }
                if sigma > 0.0 && sigma * (next - t) > left {
                    let ts = t + left / sigma;
                    return Some(MediumEvent { t: ts, albedo: self.albedo_at(segs, ts) });
                }
                left -= sigma * (next - t);
                if !(next > t) || next >= tmax {
                    return None;
                }
                t = next;
            }
        })
    }

    /// `sum sigma_s / sum sigma_t` over the intervals covering ray parameter `t`.
    fn albedo_at(&self, segs: &[(f32, f32, u32)], t: f32) -> Vec3 {
        let (mut s, mut e) = (Vec3::ZERO, 0.0);
        for &(t0, t1, i) in segs {
            if t0 <= t && t <= t1 {
                let m = &self.volumes[i as usize].medium;
                s += m.albedo * m.sigma_t;
                e += m.sigma_t;
            }
        }
        if e > 0.0 { s / e } else { Vec3::ZERO }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box(sigma_t: f32, m: Affine3A) -> Volume {
        Volume {
            object_from_world: m.inverse(),
            boundary: Boundary::Closed(Closed::Box { min: Vec3A::ZERO, max: Vec3A::ONE }),
            medium: Medium { sigma_t, albedo: Vec3::splat(0.5) },
        }
    }

    #[test]
    fn box_interval_under_rotation_and_scale() {
        // The unit box scaled by 2 along x, rotated 90 degrees about y: it covers x in [0, 1],
        // z in [-2, 0].
        let m = Affine3A::from_rotation_y(std::f32::consts::FRAC_PI_2)
            * Affine3A::from_scale(Vec3::new(2.0, 1.0, 1.0));
        let v = unit_box(1.0, m);
        let (t0, t1) = v.interval(Vec3A::new(0.5, 0.5, 5.0), Vec3A::new(0.0, 0.0, -2.0), 100.0).unwrap();
        assert!((t0 - 2.5).abs() < 1e-5 && (t1 - 3.5).abs() < 1e-5, "{t0} {t1}");
        // Starting inside: the interval starts at 0. Missing: none.
        assert_eq!(v.interval(Vec3A::new(0.5, 0.5, -1.0), Vec3A::Z, 100.0), Some((0.0, 1.0)));
        assert_eq!(v.interval(Vec3A::new(5.0, 0.5, -1.0), Vec3A::Z, 100.0), None);
    }

    #[test]
    fn ray_in_a_face_plane_is_inside() {
        // A ray along the bottom face (y = 0) of the box: inside the closed box.
        let v = unit_box(1.0, Affine3A::IDENTITY);
        let (t0, t1) = v.interval(Vec3A::new(-1.0, 0.0, 0.5), Vec3A::X, 100.0).unwrap();
        assert_eq!((t0, t1), (1.0, 2.0));
    }

    #[test]
    fn sphere_interval() {
        let v = Volume {
            object_from_world: Affine3A::IDENTITY,
            boundary: Boundary::Closed(Closed::Sphere { center: Vec3A::ZERO, radius: 2.0 }),
            medium: Medium { sigma_t: 1.0, albedo: Vec3::ONE },
        };
        let (t0, t1) = v.interval(Vec3A::new(0.0, 0.0, -10.0), Vec3A::new(0.0, 0.0, 4.0), 100.0).unwrap();
        assert!((t0 - 2.0).abs() < 1e-6 && (t1 - 3.0).abs() < 1e-6);
    }

    #[test]
    fn transmittance_is_beer_lambert_over_overlaps() {
        // Two overlapping boxes: x in [0, 1] (sigma 1) and [0.5, 1.5] (sigma 2).
        let a = unit_box(1.0, Affine3A::IDENTITY);
        let b = unit_box(2.0, Affine3A::from_translation(Vec3::new(0.5, 0.0, 0.0)));
        let media = Media { volumes: vec![a, b] };
        let (o, d) = (Vec3A::new(-1.0, 0.5, 0.5), Vec3A::new(0.5, 0.0, 0.0));
        let tr = media.transmittance(o, d, 100.0);
        assert!((tr - (-3.0f32).exp()).abs() < 1e-6, "{tr}");
    }

    #[test]
    fn sampled_distances_follow_the_optical_depth() {
        // Overlapping boxes again: the probability of scattering before x reaches the point
        // is 1 - exp(-0.5) and of passing exp(-3); the albedo is blended where they overlap.
        let mut a = unit_box(1.0, Affine3A::IDENTITY);
        let mut b = unit_box(2.0, Affine3A::from_translation(Vec3::new(0.5, 0.0, 0.0)));
        (a.medium.albedo, b.medium.albedo) = (Vec3::splat(0.2), Vec3::splat(0.8));
        let media = Media { volumes: vec![a, b] };
        let (o, d) = (Vec3A::new(-1.0, 0.5, 0.5), Vec3A::X);
        let n = 100_000;
        let (mut before_overlap, mut passed) = (0, 0);
        for k in 0..n {
            let u = (k as f32 + 0.5) / n as f32;
            match media.sample(o, d, 10.0, u) {
                None => passed += 1,
                Some(e) => {
                    let x = o.x + e.t;
                    assert!((0.0..=1.5).contains(&x), "scattered outside the media at x = {x}");
                    // Where both cover x, sigma_s / sigma_t = (0.2 * 1 + 0.8 * 2) / 3.
                    let expected = if x < 0.5 {
                        0.2
                    } else if x <= 1.0 {
                        0.6
                    } else {
                        0.8
                    };
                    assert!((e.albedo.x - expected).abs() < 1e-6);
                    before_overlap += (x < 0.5) as u32;
                }
            }
        }
        let p_before = before_overlap as f64 / n as f64;
        let p_pass = passed as f64 / n as f64;
        assert!((p_before - (1.0 - (-0.5f64).exp())).abs() < 1e-3, "{p_before}");
        assert!((p_pass - (-3.0f64).exp()).abs() < 1e-3, "{p_pass}");
    }

    /// The 12 triangles of the box [lo, hi], wound outwards.
    fn cube(lo: Vec3A, hi: Vec3A, mesh: &mut crate::accel::mesh::MeshData) {
        let base = mesh.positions.len() as u32;
        for i in 0..8 {
            let pick = |bit: u32, a: f32, b: f32| if i & bit == 0 { a } else { b };
            mesh.positions.push(Vec3A::new(pick(1, lo.x, hi.x), pick(2, lo.y, hi.y), pick(4, lo.z, hi.z)));
        }
        for q in [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]] {
            mesh.triangles.push([base + q[0], base + q[1], base + q[2]]);
            mesh.triangles.push([base + q[0], base + q[2], base + q[3]]);
        }
    }

    fn mesh_volume(mesh: crate::accel::mesh::MeshData, m: Affine3A) -> Volume {
        assert_eq!(crate::scene::open_edge(&mesh), None, "the test mesh is closed");
        Volume {
            object_from_world: m.inverse(),
            boundary: Boundary::Mesh(Arc::new(MeshBlas::build(Arc::new(mesh)))),
            medium: Medium { sigma_t: 1.0, albedo: Vec3::splat(0.5) },
        }
    }

    #[test]
    fn a_cube_mesh_covers_what_the_box_covers() {
        let m = Affine3A::from_rotation_y(0.4) * Affine3A::from_scale(Vec3::new(2.0, 1.0, 1.0));
        let mut mesh = crate::accel::mesh::MeshData::default();
        cube(Vec3A::ZERO, Vec3A::ONE, &mut mesh);
        let (mv, bv) = (mesh_volume(mesh, m), unit_box(1.0, m));
        let mut rnd = crate::testing::uniform(5);
        let mut inside = 0;
        for _ in 0..2000 {
            let o = Vec3A::new(rnd(), rnd(), rnd()) * 4.0 - Vec3A::new(1.0, 1.5, 1.5);
            let d = Vec3A::new(rnd(), rnd(), rnd()) - 0.5;
            let tmax = 10.0 * rnd();
            let mut got = Vec::new();
            mv.intervals(o, d, tmax, |a, b| got.push((a, b)));
            let want: Vec<_> = bv.interval(o, d, tmax).into_iter().collect();
            assert_eq!(got.len(), want.len(), "ray {o} {d} tmax {tmax}: {got:?} vs {want:?}");
            for (g, w) in got.iter().zip(&want) {
                let tol = 1e-4 * (1.0 + w.1);
                assert!((g.0 - w.0).abs() < tol && (g.1 - w.1).abs() < tol, "{got:?} vs {want:?}");
                inside += (g.0 == 0.0) as u32;
            }
        }
        assert!(inside > 20, "rays starting inside: {inside}");
    }

    #[test]
    fn a_non_convex_mesh_covers_each_of_its_parts() {
        // Two unit cubes 1 apart along x, in one mesh: a ray along x crosses both.
        let mut mesh = crate::accel::mesh::MeshData::default();
        cube(Vec3A::ZERO, Vec3A::ONE, &mut mesh);
        cube(Vec3A::new(2.0, 0.0, 0.0), Vec3A::new(3.0, 1.0, 1.0), &mut mesh);
        let media = Media { volumes: vec![mesh_volume(mesh, Affine3A::IDENTITY)] };
        let (o, d) = (Vec3A::new(-1.0, 0.5, 0.5), Vec3A::X);
        let mut got = Vec::new();
        media.volumes[0].intervals(o, d, 100.0, |a, b| got.push((a, b)));
        assert_eq!(got, vec![(1.0, 2.0), (3.0, 4.0)]);
        assert!((media.transmittance(o, d, 100.0) - (-2.0f32).exp()).abs() < 1e-6);
        // From inside the first cube, the first interval starts at 0.
        got.clear();
        media.volumes[0].intervals(Vec3A::new(0.5, 0.5, 0.5), d, 100.0, |a, b| got.push((a, b)));
        assert_eq!(got, vec![(0.0, 0.5), (1.5, 2.5)]);
        // Sampling never scatters in the gap.
        for k in 0..1000 {
            if let Some(e) = media.sample(o, d, 100.0, (k as f32 + 0.5) / 1000.0) {
                let x = o.x + e.t;
                assert!(!(x > 1.0 && x < 2.0), "scattered in the gap at x = {x}");
            }
        }
    }
}
