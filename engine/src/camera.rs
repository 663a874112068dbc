//! Thin-lens perspective camera with a shutter interval.

use crate::math::{Ray, concentric_disk};
use glam::{Vec2, Vec3, Vec3A};

/// A camera ready to generate rays for an image of a given size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    origin: Vec3A,
    /// Image right, up and backward (from the target to the eye) unit axes.
    u: Vec3A,
    v: Vec3A,
    w: Vec3A,
    /// Top-left corner of the image on the focus plane and the pixel steps there.
    corner: Vec3A,
    du: Vec3A,
    dv: Vec3A,
    lens_radius: f32,
    /// Shutter open and close times.
    pub shutter: (f32, f32),
}

impl Camera {
    /// `vfov` is the vertical field of view in degrees; the image is `width` x `height` pixels,
    /// row 0 at the top, right = normalize((look_at - look_from) x vup).
    #[allow(clippy::too_many_arguments)]
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
        let h = 2.0 * (vfov.to_radians() / 2.0).tan() * focus_dist;
        let wd = h * width as f32 / height as f32;
        let origin = Vec3A::from(look_from);
        let du = u * (wd / width as f32);
        let dv = -v * (h / height as f32);
        let corner = origin - focus_dist * w - 0.5 * wd * u + 0.5 * h * v;
        Self { origin, u, v, w, corner, du, dv, lens_radius: aperture_radius, shutter }
    }

    /// The ray through image position `pixel` (in pixels, continuous), lens sample `lens` in
    /// [0,1)^2 and shutter fraction `time_u`. The direction is unit length.
    #[inline]
    pub fn generate_ray(&self, pixel: Vec2, lens: Vec2, time_u: f32) -> Ray {
        let target = self.corner + pixel.x * self.du + pixel.y * self.dv;
        let origin = if self.lens_radius > 0.0 {
            let d = concentric_disk(lens) * self.lens_radius;
            self.origin + d.x * self.u + d.y * self.v
        } else {
            self.origin
        };
        let (t0, t1) = self.shutter;
        Ray { origin, dir: (target - origin).normalize(), time: t0 + (t1 - t0) * time_u }
    }

    /// The direction the camera looks along.
    pub fn forward(&self) -> Vec3A {
        -self.w
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
}
