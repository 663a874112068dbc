//! Thin-lens perspective camera with a shutter interval.

use crate::math::{Ray, disk_branch_free};
use glam::{Vec2, Vec3, Vec3A};

/// Where the camera is and where its image lies: origin, image right / up / backward unit axes,
/// and the top-left corner of the image on the focus plane with the pixel steps there.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Pose {
    origin: Vec3A,
    u: Vec3A,
    v: Vec3A,
    w: Vec3A,
    corner: Vec3A,
    du: Vec3A,
    dv: Vec3A,
}

impl Pose {
    /// The pose a fraction `s` of the way to `b` (component-wise: for the small steps of one
    /// shutter interval, a chord of a turning camera's path).
    fn lerp(&self, b: &Pose, s: f32) -> Pose {
        Pose {
            origin: self.origin.lerp(b.origin, s),
            u: self.u.lerp(b.u, s),
            v: self.v.lerp(b.v, s),
            w: self.w.lerp(b.w, s),
            corner: self.corner.lerp(b.corner, s),
            du: self.du.lerp(b.du, s),
            dv: self.dv.lerp(b.dv, s),
        }
    }
}

/// `N` rays, one array per coordinate ([`Camera::generate_rays`]).
#[derive(Clone, Copy, Debug)]
pub struct RayLanes<const N: usize> {
    /// Origins.
    pub o: [[f32; N]; 3],
    /// Unit directions.
    pub d: [[f32; N]; 3],
    /// Times.
    pub time: [f32; N],
}

impl<const N: usize> RayLanes<N> {
    /// Ray `l`.
    #[inline(always)]
    pub fn ray(&self, l: usize) -> Ray {
        let (o, d) = (&self.o, &self.d);
        Ray {
            origin: Vec3A::new(o[0][l], o[1][l], o[2][l]),
            dir: Vec3A::new(d[0][l], d[1][l], d[2][l]),
            time: self.time[l],
        }
    }
}

/// A camera ready to generate rays for an image of a given size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// The pose at shutter open (the only one for a camera that does not move).
    pose: Pose,
    /// The pose at shutter close, for a camera that moves while the shutter is open.
    close: Option<Pose>,
    lens_radius: f32,
    /// Shutter open and close times.
    pub shutter: (f32, f32),
}

impl Camera {
    /// `vfov` is the vertical field of view in degrees; the image is `width` x `height` pixels,
    /// row 0 at the top, right = normalize((look_at - look_from) x vup).
    #[expect(clippy::too_many_arguments, reason = "the camera's fields as the scene file gives them")]
    pub fn new(
        look_from: Vec3,
        look_at: Vec3,
        vup: Vec3,
        vfov: f32,
        aperture_radius: f32,
        focus_dist: f32,
        shutter: (f32, f32),
        width: u32,
        height: u32,
    ) -> Self {
        let w = Vec3A::from(look_from - look_at).normalize();
        let u = Vec3A::from(vup).cross(w).normalize();
        let v = w.cross(u);
        // The tangent in f64, rounded: a C library's last bits reach the f32 only at a rounding
        // tie (about one value in 2^29).
        let h = 2.0 * ((vfov as f64).to_radians() / 2.0).tan() as f32 * focus_dist;
        let wd = h * width as f32 / height as f32;
        let origin = Vec3A::from(look_from);
        let du = u * (wd / width as f32);
        let dv = -v * (h / height as f32);
        let corner = origin - focus_dist * w - 0.5 * wd * u + 0.5 * h * v;
        let pose = Pose { origin, u, v, w, corner, du, dv };
        Self { pose, close: None, lens_radius: aperture_radius, shutter }
    }

    /// This camera at shutter open, moving to `close`'s pose at shutter close (its aperture
    /// and shutter are this one's).
    pub fn moving_to(self, close: &Camera) -> Self {
        Self { close: (close.pose != self.pose).then_some(close.pose), ..self }
    }

    /// True when the camera moves while the shutter is open.
    pub fn moves(&self) -> bool {
        self.close.is_some() && self.shutter.0 != self.shutter.1
    }

    /// True when the lens has an aperture (rays then need a lens sample).
    #[inline]
    pub fn has_aperture(&self) -> bool {
        self.lens_radius > 0.0
    }

    /// The ray through image position `pixel` (in pixels, continuous), lens sample `lens` in
    /// [0,1)^2 and shutter fraction `time_u`. The direction is unit length.
    #[inline]
    pub fn generate_ray(&self, pixel: Vec2, lens: Vec2, time_u: f32) -> Ray {
        let pose = match &self.close {
            Some(close) => self.pose.lerp(close, time_u),
            None => self.pose,
        };
        let (o, d, time) =
            self.ray_from(&pose, self.has_aperture(), pixel.to_array(), lens.to_array(), time_u);
        Ray { origin: o.into(), dir: d.into(), time }
    }

    /// [`Self::generate_ray`] for `N` samples at once (`pixel`, `lens` and `time_u` per lane),
    /// with the same bits: a camera at rest computes every lane with the same operations on
    /// plain numbers, which vectorise inside [`crate::simd::lanes`]; a moving camera takes
    /// [`Self::generate_ray`] lane by lane. The rays come as one array per coordinate: written
    /// as `Ray` values, each lane's coordinates were stored one by one and read back as 16 bytes,
    /// which no store forwards to.
    #[inline(always)]
    pub fn generate_rays<const N: usize>(
        &self,
        pixel: &[[f32; 2]; N],
        lens: &[[f32; 2]; N],
        time_u: &[f32; N],
    ) -> RayLanes<N> {
        let mut out = RayLanes { o: [[0.0; N]; 3], d: [[0.0; N]; 3], time: [0.0; N] };
        let mut set = |l: usize, (o, d, t): ([f32; 3], [f32; 3], f32)| {
            for a in 0..3 {
                (out.o[a][l], out.d[a][l]) = (o[a], d[a]);
            }
            out.time[l] = t;
        };
        if self.close.is_some() {
            for l in 0..N {
                let r = self.generate_ray(Vec2::from(pixel[l]), Vec2::from(lens[l]), time_u[l]);
                set(l, (r.origin.to_array(), r.dir.to_array(), r.time));
            }
        } else if self.has_aperture() {
            // One loop per case, so that a pinhole camera's lanes compute no lens point.
            for l in 0..N {
                set(l, self.ray_from(&self.pose, true, pixel[l], lens[l], time_u[l]));
            }
        } else {
            for l in 0..N {
                set(l, self.ray_from(&self.pose, false, pixel[l], lens[l], time_u[l]));
            }
        }
        out
    }

    /// The ray of [`Self::generate_ray`] from `pose` on plain numbers (origin, unit direction,
    /// time), the operations in glam's order (`Vec3A::normalize` sums `(x^2 + y^2) + z^2` and
    /// divides by the length), so scalar and lane calls agree bit for bit.
    /// The lens point comes from [`disk_branch_free`] (a polynomial sine and cosine); `lensed`
    /// is [`Self::has_aperture`] (a parameter, so that callers can specialise on it).
    #[inline(always)]
    fn ray_from(
        &self,
        pose: &Pose,
        lensed: bool,
        pixel: [f32; 2],
        lens: [f32; 2],
        time_u: f32,
    ) -> ([f32; 3], [f32; 3], f32) {
        let (c, du, dv) = (pose.corner.to_array(), pose.du.to_array(), pose.dv.to_array());
        let at = |a: usize| c[a] + pixel[0] * du[a] + pixel[1] * dv[a];
        let target = [at(0), at(1), at(2)];
        let (po, u, v) = (pose.origin.to_array(), pose.u.to_array(), pose.v.to_array());
        // Without an aperture the point on the lens is the centre (`po + 0 * u` could differ
        // from `po` in the sign of a zero).
        let origin = match lensed {
            true => {
                let (x, y) = disk_branch_free(lens);
                let (x, y) = (x * self.lens_radius, y * self.lens_radius);
                let from = |a: usize| po[a] + x * u[a] + y * v[a];
                [from(0), from(1), from(2)]
            }
            false => po,
        };
        let e = [target[0] - origin[0], target[1] - origin[1], target[2] - origin[2]];
        let len = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
        let (t0, t1) = self.shutter;
        (origin, [e[0] / len, e[1] / len, e[2] / len], t0 + (t1 - t0) * time_u)
    }

    /// The direction the camera looks along (at shutter open).
    pub fn forward(&self) -> Vec3A {
        -self.pose.w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cornell() -> Camera {
        let from = Vec3::new(278.0, 278.0, -800.0);
        let at = Vec3::new(278.0, 278.0, 0.0);
        Camera::new(from, at, Vec3::Y, 40.0, 0.0, 800.0, (0.0, 0.0), 256, 256)
    }

    #[test]
    fn centre_pixel_looks_at_target_and_right_is_minus_x() {
        let c = cornell();
        let r = c.generate_ray(Vec2::new(128.0, 128.0), Vec2::ZERO, 0.0);
        assert!((r.dir - Vec3A::Z).length() < 1e-6);
        // Image right = cross(at - from, up) = -x for cornell: the right edge looks towards -x.
        let right = c.generate_ray(Vec2::new(256.0, 128.0), Vec2::ZERO, 0.0);
        assert!(right.dir.x < 0.0);
        let top = c.generate_ray(Vec2::new(128.0, 0.0), Vec2::ZERO, 0.0);
        assert!(top.dir.y > 0.0, "row 0 is the top row");
        let half = (20f32).to_radians();
        assert!((top.dir.y.atan2(top.dir.z) - half).abs() < 1e-5, "vertical fov");
    }

    #[test]
    fn thin_lens_rays_converge_on_the_focus_plane() {
        let from = Vec3::new(13.0, 2.0, 3.0);
        let c = Camera::new(from, Vec3::ZERO, Vec3::Y, 20.0, 0.5, 10.0, (0.0, 0.0), 384, 216);
        let a = c.generate_ray(Vec2::new(100.0, 50.0), Vec2::new(0.1, 0.9), 0.0);
        let b = c.generate_ray(Vec2::new(100.0, 50.0), Vec2::new(0.8, 0.2), 0.0);
        assert!(a.origin != b.origin);
        // Both pass through the same point of the focus plane (distance 10 along the view axis).
        let fwd = c.forward();
        let pa = a.at((10.0 - (a.origin - Vec3A::from(from)).dot(fwd)) / a.dir.dot(fwd));
        let pb = b.at((10.0 - (b.origin - Vec3A::from(from)).dot(fwd)) / b.dir.dot(fwd));
        assert!((pa - pb).length() < 1e-4, "{pa} {pb}");
    }

    /// The lane version gives the bits of the scalar one, with and without AVX-512, for a
    /// pinhole, a thin lens and a moving camera.
    #[test]
    fn lanes_give_the_scalar_bits() {
        let from = Vec3::new(13.0, 2.0, 3.0);
        let lens = Camera::new(from, Vec3::ZERO, Vec3::Y, 20.0, 0.05, 10.0, (0.0, 1.0), 384, 216);
        let close = Camera::new(from + Vec3::X, Vec3::ZERO, Vec3::Y, 20.0, 0.05, 10.0, (0.0, 1.0), 384, 216);
        for cam in [cornell(), lens, lens.moving_to(&close)] {
            let u = |k: usize, m: u32| ((k as u32 * m) % 1009) as f32 / 1009.0;
            let pixel: [[f32; 2]; 16] = std::array::from_fn(|k| [383.0 * u(k, 7), 215.0 * u(k, 13)]);
            let on_lens: [[f32; 2]; 16] = std::array::from_fn(|k| [u(k, 31), u(k, 101)]);
            let time: [f32; 16] = std::array::from_fn(|k| u(k, 211));
            let wide = crate::simd::lanes(
                #[inline(always)]
                || cam.generate_rays(&pixel, &on_lens, &time),
            );
            let base = cam.generate_rays(&pixel, &on_lens, &time);
            for k in 0..16 {
                let r = cam.generate_ray(Vec2::from(pixel[k]), Vec2::from(on_lens[k]), time[k]);
                for got in [wide.ray(k), base.ray(k)] {
                    let bits =
                        |r: &Ray| (r.origin.to_array().map(f32::to_bits), r.dir.to_array().map(f32::to_bits));
                    assert_eq!(bits(&got), bits(&r), "lane {k}");
                    assert_eq!(got.time.to_bits(), r.time.to_bits());
                }
            }
        }
    }
}
