//! What a scene's media are made of: a [`Medium`] (homogeneous, or scaled by grids) filling a
//! [`Volume`], the closed [`Boundary`] placed by an affine transform, and how the volume moves
//! while the shutter is open ([`VolumeMotion`]). Along a ray a volume covers the stretches of
//! `t` between its boundary's hits, found in object space (affine maps preserve `t`).

use super::grid;
use crate::accel::mesh::MeshBlas;
use crate::animation::ShutterMotion;
use crate::shape::Closed;
use glam::{Affine3A, Vec3, Vec3A};
use std::cell::RefCell;
use std::sync::Arc;

/// A medium: homogeneous, or scaled by grids.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// Extinction coefficient per unit length, per channel.
    pub sigma_t: Vec3,
    /// Single-scattering albedo `sigma_s / sigma_t`.
    pub albedo: Vec3,
    /// The density's grid: `sigma_t` times its value where its cube is, no medium outside
    /// (Mitsuba's `heterogeneous` medium, which exists only in its `sigma_t` volume's bounding
    /// box). Only with grey `sigma_t`.
    pub density_grid: Option<PlacedGrid>,
    /// The albedo's grid: `albedo` times its colour (taken from its edges outside its cube).
    pub albedo_grid: Option<PlacedGrid>,
    /// The Henyey-Greenstein phase function's asymmetry `g`, in (-1, 1) ([`super::phase`]; 0:
    /// isotropic).
    pub g: f32,
    /// The radiance the medium emits, `Le`: a point emits `sigma_a Le` per unit length
    /// (absorption times the radiance, pbrt-v4's convention: an opaque, absorbing medium
    /// shows `Le`). Zero for media that do not glow.
    pub emission: Vec3,
    /// The emission's grid: `emission` times its colour (taken from its edges outside its
    /// cube), as a flame's temperature makes it glow.
    pub emission_grid: Option<PlacedGrid>,
}

/// A grid in an object's space: it fills the unit cube of `grid_from_object`'s image.
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedGrid {
    /// The values.
    pub grid: Arc<grid::VoxelGrid>,
    /// Object space to grid space.
    pub grid_from_object: Affine3A,
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
    /// How it moves while the shutter is open.
    pub motion: VolumeMotion,
}

/// How a volume moves while the shutter is open (as instances do, [`crate::accel::instances`]).
#[derive(Clone, Debug, Default)]
pub enum VolumeMotion {
    /// It stays where `object_from_world` places it.
    #[default]
    Still,
    /// At time `t` it lies translated by this velocity times `t` from where
    /// `object_from_world` places it.
    Linear(Vec3A),
    /// It turns or scales while the shutter is open.
    Keyed {
        /// Places it per ray time.
        motion: Box<ShutterMotion>,
        /// The inverse of the volume's `object_from_world`: takes rays from its object space
        /// back to its rest frame.
        world_from_object: Affine3A,
    },
}

impl Medium {
    /// A homogeneous medium.
    pub fn homogeneous(sigma_t: Vec3, albedo: Vec3) -> Self {
        Self {
            sigma_t,
            albedo,
            density_grid: None,
            albedo_grid: None,
            g: 0.0,
            emission: Vec3::ZERO,
            emission_grid: None,
        }
    }

    /// The same extinction in every channel.
    #[inline]
    pub fn grey(&self) -> bool {
        self.sigma_t.x == self.sigma_t.y && self.sigma_t.y == self.sigma_t.z
    }
}

impl Volume {
    /// The ray `o + t d` at `time` in the volume's rest frame, the space in which
    /// `object_from_world` places it (`t` unchanged).
    #[inline]
    pub(super) fn rest_ray(&self, o: Vec3A, d: Vec3A, time: f32) -> (Vec3A, Vec3A) {
        match &self.motion {
            VolumeMotion::Still => (o, d),
            VolumeMotion::Linear(v) => (o - *v * time, d),
            VolumeMotion::Keyed { motion, world_from_object } => {
                let (o, d) = motion.object_ray(time, o, d);
                (world_from_object.transform_point3a(o), world_from_object.transform_vector3a(d))
            }
        }
    }

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
}
