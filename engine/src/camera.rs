//! Thin-lens perspective and orthographic cameras with a shutter interval.

use crate::math::{Ray, disk_branch_free};
use glam::{Affine3A, Vec2, Vec3, Vec3A};

/// Where the camera is and where its image lies: origin, the lens's axes `u` and `v` (image
/// right and up for [`Camera::new`]; a `to_world` camera's camera-space x and y, scaled as it
/// scales them), the backward unit axis `w`, and the top-left corner of the image on the focus
/// plane with the pixel steps there (an orthographic camera: on the plane its rays start from).
/// For the clip planes: `ahead`, camera space's unit +z in the world (`-w` for
/// [`Camera::new`], `to_world`'s z axis, scaled as it scales it), and `focus`, the camera-space
/// depth of the focus plane (the image's plane for a perspective camera).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Pose {
    origin: Vec3A,
    u: Vec3A,
    v: Vec3A,
    w: Vec3A,
    corner: Vec3A,
    du: Vec3A,
    dv: Vec3A,
    ahead: Vec3A,
    focus: f32,
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
            ahead: self.ahead.lerp(b.ahead, s),
            focus: self.focus + (b.focus - self.focus) * s,
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
    /// How far each ray reaches (along its unit direction, from its origin): the far clip
    /// plane's distance ([`Camera::with_clip`]), infinite without one.
    pub tmax: [f32; N],
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

/// Near and far clip planes, camera-space depths as Mitsuba 3's `near_clip` and `far_clip`
/// (mitsuba3 `src/sensors/perspective.cpp`, `thinlens.cpp`, `orthographic.cpp`): a
/// perspective ray starts where it crosses the plane z = `near` and reaches to the plane
/// z = `far` (Mitsuba's near_t = near_clip / d.z, far_t = far_clip / d.z for the normalised
/// camera-space direction d from the lens point, on the lens plane z = 0); an orthographic ray
/// starts on z = `near` and reaches `far - near` further along its unit direction (Mitsuba's
/// `maxt`, in world units: with a scale along z that is not the plane z = `far`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clip {
    /// Camera-space depth where rays start (0: at the lens or the image plane).
    pub near: f32,
    /// Camera-space depth beyond which nothing is seen (may be infinite), more than `near`.
    pub far: f32,
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
    /// Orthographic: each ray starts at its image point and runs along `-w`.
    orthographic: bool,
    /// Clip planes (none: rays start at the lens and reach infinitely far).
    clip: Option<Clip>,
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
        let pose = Pose { origin, u, v, w, corner, du, dv, ahead: -w, focus: focus_dist };
        Self { pose, close: None, lens_radius: aperture_radius, shutter, orthographic: false, clip: None }
    }

    /// A perspective (thin-lens) camera placed by `to_world` in Mitsuba 3's camera space (it
    /// looks along +z, +y is up, +x points to the image's left), whose horizontal field of
    /// view has half-angle tangent `tan_half_x`; `aperture_radius` and `focus_dist` are in
    /// camera space. A ray is the line Mitsuba 3's `perspective` and `thinlens` sensors
    /// trace for the same image point and lens point (mitsuba3 `src/sensors/perspective.cpp`,
    /// `thinlens.cpp`: the lens point `to_world(r x, r y, 0)`, aimed at `to_world` of the
    /// image point on the camera-space plane z = focus_dist), with the direction normalised
    /// after `to_world` (so a scale does not change what a pixel sees in camera space).
    pub fn perspective(
        to_world: Affine3A,
        tan_half_x: f32,
        aperture_radius: f32,
        focus_dist: f32,
        shutter: (f32, f32),
        width: u32,
        height: u32,
    ) -> Self {
        // Camera space: the image's top-left corner at (tx, ty, 1) f, with x decreasing to
        // the right and y downwards.
        let (tx, ty) = (tan_half_x, tan_half_x * height as f32 / width as f32);
        let f = focus_dist;
        let corner = Vec3A::new(tx * f, ty * f, f);
        let du = Vec3A::new(-2.0 * tx * f / width as f32, 0.0, 0.0);
        let dv = Vec3A::new(0.0, -2.0 * ty * f / height as f32, 0.0);
        Self::placed(to_world, corner, du, dv, aperture_radius, f, shutter, false)
    }

    /// An orthographic camera placed by `to_world` in Mitsuba 3's camera space: the image
    /// spans camera-space x from 1 (left) to -1 (right) and y from 1/aspect (top) to
    /// -1/aspect, aspect = width / height; rays start there on the plane z = 0 (z = near with
    /// [`Self::with_clip`]) and run along `to_world`'s +z (mitsuba3
    /// `src/sensors/orthographic.cpp`).
    pub fn orthographic(to_world: Affine3A, shutter: (f32, f32), width: u32, height: u32) -> Self {
        let inv_aspect = height as f32 / width as f32;
        let corner = Vec3A::new(1.0, inv_aspect, 0.0);
        let du = Vec3A::new(-2.0 / width as f32, 0.0, 0.0);
        let dv = Vec3A::new(0.0, -2.0 * inv_aspect / height as f32, 0.0);
        Self::placed(to_world, corner, du, dv, 0.0, 1.0, shutter, true)
    }

    /// The camera whose image's camera-space corner and pixel steps are `corner`, `du`, `dv`
    /// (on the plane z = `focus`), taken to the world by `to_world`.
    #[expect(clippy::too_many_arguments, reason = "the pose's parts and the lens")]
    fn placed(
        to_world: Affine3A,
        corner: Vec3A,
        du: Vec3A,
        dv: Vec3A,
        aperture_radius: f32,
        focus: f32,
        shutter: (f32, f32),
        orthographic: bool,
    ) -> Self {
        let m = to_world.matrix3;
        let pose = Pose {
            origin: to_world.translation,
            u: m.x_axis,
            v: m.y_axis,
            w: -m.z_axis.normalize(),
            corner: to_world.transform_point3a(corner),
            du: m * du,
            dv: m * dv,
            ahead: m.z_axis,
            focus,
        };
        Self { pose, close: None, lens_radius: aperture_radius, shutter, orthographic, clip: None }
    }

    /// This camera with the clip planes `clip` (none: rays start at the lens and reach
    /// infinitely far, with the bits of a camera that never had clip planes).
    pub fn with_clip(self, clip: Option<Clip>) -> Self {
        Self { clip, ..self }
    }

    /// True when camera rays reach only a finite distance (a far clip plane).
    #[inline]
    pub fn has_far_clip(&self) -> bool {
        self.clip.is_some_and(|c| c.far.is_finite())
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
        self.generate_clipped_ray(pixel, lens, time_u).0
    }

    /// [`Self::generate_ray`] and how far the ray reaches (infinite without a far clip plane).
    #[inline]
    pub fn generate_clipped_ray(&self, pixel: Vec2, lens: Vec2, time_u: f32) -> (Ray, f32) {
        let pose = match &self.close {
            Some(close) => self.pose.lerp(close, time_u),
            None => self.pose,
        };
        if self.orthographic {
            let mut origin = pose.corner + pixel.x * pose.du + pixel.y * pose.dv;
            let (t0, t1) = self.shutter;
            let mut tmax = f32::INFINITY;
            if let Some(c) = self.clip {
                // mitsuba3 `src/sensors/orthographic.cpp`: the sample on the plane z = near,
                // `maxt = far_clip - near_clip`.
                origin += pose.ahead * c.near;
                tmax = c.far - c.near;
            }
            return (Ray { origin, dir: -pose.w, time: t0 + (t1 - t0) * time_u }, tmax);
        }
        let (o, d, time, tmax) =
            self.ray_from(&pose, self.has_aperture(), self.clip, pixel.to_array(), lens.to_array(), time_u);
        (Ray { origin: o.into(), dir: d.into(), time }, tmax)
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
        let mut out =
            RayLanes { o: [[0.0; N]; 3], d: [[0.0; N]; 3], time: [0.0; N], tmax: [f32::INFINITY; N] };
        let mut set = |l: usize, (o, d, t, tmax): ([f32; 3], [f32; 3], f32, f32)| {
            for a in 0..3 {
                (out.o[a][l], out.d[a][l]) = (o[a], d[a]);
            }
            (out.time[l], out.tmax[l]) = (t, tmax);
        };
        if self.close.is_some() || self.orthographic {
            for l in 0..N {
                let (r, tmax) =
                    self.generate_clipped_ray(Vec2::from(pixel[l]), Vec2::from(lens[l]), time_u[l]);
                set(l, (r.origin.to_array(), r.dir.to_array(), r.time, tmax));
            }
        } else if self.clip.is_some() {
            let lensed = self.has_aperture();
            for l in 0..N {
                set(l, self.ray_from(&self.pose, lensed, self.clip, pixel[l], lens[l], time_u[l]));
            }
        } else if self.has_aperture() {
            // One loop per case, so that a pinhole camera's lanes compute no lens point.
            for l in 0..N {
                set(l, self.ray_from(&self.pose, true, None, pixel[l], lens[l], time_u[l]));
            }
        } else {
            for l in 0..N {
                set(l, self.ray_from(&self.pose, false, None, pixel[l], lens[l], time_u[l]));
            }
        }
        out
    }

    /// The ray of [`Self::generate_clipped_ray`] from `pose` on plain numbers (origin, unit
    /// direction, time, reach), the operations in glam's order (`Vec3A::normalize` sums
    /// `(x^2 + y^2) + z^2` and divides by the length), so scalar and lane calls agree bit for
    /// bit. The lens point comes from [`disk_branch_free`] (a polynomial sine and cosine);
    /// `lensed` is [`Self::has_aperture`] and `clip` the camera's clip planes (parameters, so
    /// that callers can specialise on them).
    #[inline(always)]
    fn ray_from(
        &self,
        pose: &Pose,
        lensed: bool,
        clip: Option<Clip>,
        pixel: [f32; 2],
        lens: [f32; 2],
        time_u: f32,
    ) -> ([f32; 3], [f32; 3], f32, f32) {
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
        let (origin, tmax) = match clip {
            None => (origin, f32::INFINITY),
            // `e` runs from the lens (camera-space z = 0) to the focus plane (z = focus), so the
            // point at camera-space depth z is origin + e z / focus: Mitsuba's
            // origin + d near_clip / d.z (mitsuba3 `src/sensors/thinlens.cpp`), and the far
            // plane lies (far - near) / focus |e| further along the unit direction.
            Some(c) => {
                let s = c.near / pose.focus;
                let from = |a: usize| origin[a] + e[a] * s;
                ([from(0), from(1), from(2)], len * ((c.far - c.near) / pose.focus))
            }
        };
        (origin, [e[0] / len, e[1] / len, e[2] / len], t0 + (t1 - t0) * time_u, tmax)
    }

    /// The direction the camera looks along (at shutter open).
    pub fn forward(&self) -> Vec3A {
        -self.pose.w
    }

    /// True for a pinhole that light tracing can connect to ([`Self::pinhole_view`]): a
    /// perspective camera without aperture, at rest.
    pub fn is_pinhole(&self) -> bool {
        !self.orthographic && !self.has_aperture() && !self.moves()
    }

    /// Where a pinhole camera ([`Self::is_pinhole`]) sees the world point `p`: the image
    /// position in pixels (as [`Self::generate_ray`] takes it), the unit direction from `p` to
    /// the pinhole, the distance, and the camera's importance along that ray per unit of image
    /// area in pixels: `1 / (d omega / dA)`, the solid angle a pixel spans there being
    /// `|du x dv| cos^3 theta / F^2` (pixel steps `du`, `dv` on the image plane at distance
    /// `F`, `theta` the ray's angle from the plane's normal; pbrt-v4's
    /// `PerspectiveCamera::We` per pixel). `None` where `p` is behind the camera, outside the
    /// image, or outside the clip planes' depths.
    pub fn pinhole_view(&self, p: Vec3A) -> Option<PinholeView> {
        let pose = &self.pose;
        let n = pose.du.cross(pose.dv);
        let area = n.length();
        let to_plane = pose.corner - pose.origin;
        let n = if n.dot(to_plane) < 0.0 { -n / area } else { n / area };
        let f = to_plane.dot(n);
        let q = p - pose.origin;
        let depth = q.dot(n);
        if !(depth > 0.0) || !(f > 0.0) {
            return None;
        }
        // Camera-space depth: the image plane lies at `focus` (see `ray_from`).
        if let Some(c) = self.clip
            && !(c.near..=c.far).contains(&(depth / f * pose.focus))
        {
            return None;
        }
        let r = q * (f / depth) - to_plane;
        let (uu, uv, vv) = (pose.du.dot(pose.du), pose.du.dot(pose.dv), pose.dv.dot(pose.dv));
        let (ru, rv) = (r.dot(pose.du), r.dot(pose.dv));
        let det = uu * vv - uv * uv;
        let pixel = Vec2::new((ru * vv - rv * uv) / det, (rv * uu - ru * uv) / det);
        let dist = q.length();
        let cos = depth / dist;
        let importance = f * f / (area * cos * cos * cos);
        (importance.is_finite() && pixel.is_finite()).then_some(PinholeView {
            pixel,
            to_camera: -q / dist,
            dist,
            importance,
        })
    }
}

/// A world point as a pinhole camera sees it ([`Camera::pinhole_view`]).
#[derive(Clone, Copy, Debug)]
pub struct PinholeView {
    /// Image position in pixels.
    pub pixel: Vec2,
    /// Unit direction from the point to the pinhole.
    pub to_camera: Vec3A,
    /// Distance from the point to the pinhole.
    pub dist: f32,
    /// Importance per unit of image area (pixels): `1 / (d omega / dA)`.
    pub importance: f32,
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

    /// Mitsuba 3's `look_at` matrix: columns left = normalize(up x dir), up, dir, origin.
    fn mitsuba_look_at(origin: Vec3, target: Vec3, up: Vec3) -> Affine3A {
        let dir = (target - origin).normalize();
        let left = up.normalize().cross(dir).normalize();
        let new_up = dir.cross(left);
        Affine3A::from_cols(left.into(), new_up.into(), dir.into(), origin.into())
    }

    /// A look_from/look_at camera and the same view given by Mitsuba's look_at matrix (its
    /// vertical field of view as `fov_axis: Y`) trace the same rays: the image is not mirrored
    /// and row 0 is the top.
    #[test]
    fn to_world_look_at_matches_look_from_look_at() {
        let (from, at, up) = (Vec3::new(3.0, 2.0, 7.0), Vec3::new(-1.0, 0.5, 0.0), Vec3::new(0.1, 1.0, 0.0));
        let (w, h) = (320, 200);
        let a = Camera::new(from, at, up, 35.0, 0.0, 4.0, (0.0, 0.0), w, h);
        let tan_x = crate::scene::FovAxis::Y.tan_half_x_fov(35.0, w as f64 / h as f64) as f32;
        let b = Camera::perspective(mitsuba_look_at(from, at, up), tan_x, 0.0, 4.0, (0.0, 0.0), w, h);
        for p in [[0.0, 0.0], [320.0, 0.0], [0.0, 200.0], [160.0, 100.0], [17.5, 181.25]] {
            let (ra, rb) = (
                a.generate_ray(Vec2::from(p), Vec2::ZERO, 0.0),
                b.generate_ray(Vec2::from(p), Vec2::ZERO, 0.0),
            );
            assert!((ra.origin - rb.origin).length() < 1e-6, "{p:?}");
            assert!((ra.dir - rb.dir).length() < 1e-6, "{p:?}: {} against {}", ra.dir, rb.dir);
        }
        // Image right is (look_at - look_from) x vup: for a camera on +z looking at the
        // origin, the right edge looks towards +x and the top row towards +y.
        let c = Camera::perspective(
            mitsuba_look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y),
            0.5,
            0.0,
            1.0,
            (0.0, 0.0),
            64,
            64,
        );
        assert!(c.generate_ray(Vec2::new(64.0, 32.0), Vec2::ZERO, 0.0).dir.x > 0.0);
        assert!(c.generate_ray(Vec2::new(32.0, 0.0), Vec2::ZERO, 0.0).dir.y > 0.0);
    }

    /// `fov_axis` as Mitsuba 3's `parse_fov`: the half-angle tangents across x, y and the
    /// diagonal of a 2:1 image, and Smaller / Larger choosing between x and y.
    #[test]
    fn fov_axes_as_mitsuba() {
        use crate::scene::FovAxis;
        let (w, h) = (200, 100);
        let tan = |axis: FovAxis| axis.tan_half_x_fov(60.0, 2.0) as f32;
        let t = (30f32).to_radians().tan();
        let ray = |tx: f32, p: [f32; 2]| {
            Camera::perspective(Affine3A::IDENTITY, tx, 0.0, 1.0, (0.0, 0.0), w, h)
                .generate_ray(Vec2::from(p), Vec2::ZERO, 0.0)
                .dir
        };
        // Camera space: +x is the image's left.
        let left = ray(tan(FovAxis::X), [0.0, 50.0]);
        assert!((left.x / left.z - t).abs() < 1e-6, "{left}");
        let top = ray(tan(FovAxis::Y), [100.0, 0.0]);
        assert!((top.y / top.z - t).abs() < 1e-6, "{top}");
        let corner = ray(tan(FovAxis::Diagonal), [0.0, 0.0]);
        assert!(((corner.x * corner.x + corner.y * corner.y).sqrt() / corner.z - t).abs() < 1e-6, "{corner}");
        assert_eq!(tan(FovAxis::Smaller), tan(FovAxis::Y));
        assert_eq!(tan(FovAxis::Larger), tan(FovAxis::X));
        assert_eq!(FovAxis::Smaller.tan_half_x_fov(60.0, 0.5), FovAxis::X.tan_half_x_fov(60.0, 0.5));
    }

    /// A uniform scale in `to_world` changes no direction (Mitsuba normalises after it); the
    /// thin lens still focuses on the plane at focus_dist (camera space, so scaled).
    #[test]
    fn to_world_scale_keeps_the_view() {
        let m = mitsuba_look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y);
        let scaled = m * Affine3A::from_scale(Vec3::splat(3.0));
        let a = Camera::perspective(m, 0.4, 0.0, 2.0, (0.0, 0.0), 50, 40);
        let b = Camera::perspective(scaled, 0.4, 0.0, 2.0, (0.0, 0.0), 50, 40);
        let p = Vec2::new(7.0, 31.0);
        let (ra, rb) = (a.generate_ray(p, Vec2::ZERO, 0.0), b.generate_ray(p, Vec2::ZERO, 0.0));
        assert!((ra.dir - rb.dir).length() < 1e-6 && (ra.origin - rb.origin).length() < 1e-6);
        let lens = Camera::perspective(scaled, 0.4, 0.25, 2.0, (0.0, 0.0), 50, 40);
        let (r1, r2) =
            (lens.generate_ray(p, Vec2::new(0.1, 0.8), 0.0), lens.generate_ray(p, Vec2::new(0.7, 0.3), 0.0));
        // Both pass through the image point at camera-space depth 2, world depth 6.
        let focus = b.generate_ray(p, Vec2::ZERO, 0.0);
        let target = focus.at(6.0 / focus.dir.dot(-b.pose.w));
        for r in [r1, r2] {
            let to = target - r.origin;
            assert!((to.normalize() - r.dir).length() < 1e-5, "{} against {}", to.normalize(), r.dir);
        }
    }

    /// Orthographic: rays parallel to `to_world`'s +z, starting on the camera-space square
    /// x in [-1, 1], y in [-1/aspect, 1/aspect], +x to the left, sized by a scale.
    #[test]
    fn orthographic_as_mitsuba() {
        let m =
            Affine3A::from_translation(Vec3::new(0.0, 0.0, -4.0)) * Affine3A::from_scale(Vec3::splat(2.0));
        let c = Camera::orthographic(m, (0.0, 0.0), 40, 20);
        let top_left = c.generate_ray(Vec2::ZERO, Vec2::ZERO, 0.0);
        assert_eq!(top_left.dir, Vec3A::Z);
        assert!((top_left.origin - Vec3A::new(2.0, 1.0, -4.0)).length() < 1e-6, "{}", top_left.origin);
        let bottom_right = c.generate_ray(Vec2::new(40.0, 20.0), Vec2::ZERO, 0.0);
        assert!((bottom_right.origin - Vec3A::new(-2.0, -1.0, -4.0)).length() < 1e-6);
    }

    /// Clip planes as Mitsuba 3's (mitsuba3 `src/sensors/thinlens.cpp`, `orthographic.cpp`):
    /// a perspective ray, through a lens or not, at the image's corner or centre, starts on the
    /// camera-space plane z = near and reaches the plane z = far; an orthographic one starts on
    /// z = near and reaches far - near further.
    #[test]
    fn clip_planes_are_camera_space_depths() {
        let m = mitsuba_look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::new(-2.0, 0.5, -1.0), Vec3::Y);
        let to_camera = m.inverse();
        let z = |p: Vec3A| to_camera.transform_point3a(p).z;
        let clip = Some(Clip { near: 0.25, far: 7.0 });
        let (w, h) = (40, 30);
        for lens_radius in [0.0, 0.3] {
            let c = Camera::perspective(m, 1.0, lens_radius, 2.0, (0.0, 0.0), w, h).with_clip(clip);
            for p in [[0.0, 0.0], [40.0, 30.0], [20.0, 15.0], [3.5, 27.0]] {
                let (r, tmax) = c.generate_clipped_ray(Vec2::from(p), Vec2::new(0.9, 0.3), 0.0);
                assert!((z(r.origin) - 0.25).abs() < 1e-5, "{p:?}: starts at z = {}", z(r.origin));
                assert!((z(r.at(tmax)) - 7.0).abs() < 1e-4, "{p:?}: reaches z = {}", z(r.at(tmax)));
                // The same line as without clip planes.
                let (plain, inf) =
                    c.with_clip(None).generate_clipped_ray(Vec2::from(p), Vec2::new(0.9, 0.3), 0.0);
                assert_eq!(inf, f32::INFINITY);
                assert!((plain.dir - r.dir).length() < 1e-6);
                assert!((plain.dir.cross(r.origin - plain.origin)).length() < 1e-5);
            }
        }
        let o = Camera::orthographic(m, (0.0, 0.0), w, h).with_clip(clip);
        let (r, tmax) = o.generate_clipped_ray(Vec2::new(3.0, 29.0), Vec2::ZERO, 0.0);
        assert!((z(r.origin) - 0.25).abs() < 1e-5 && (z(r.at(tmax)) - 7.0).abs() < 1e-4);
    }

    /// The lane version gives the bits of the scalar one, with and without AVX-512, for a
    /// pinhole, a thin lens and a moving camera.
    #[test]
    fn lanes_give_the_scalar_bits() {
        let from = Vec3::new(13.0, 2.0, 3.0);
        let lens = Camera::new(from, Vec3::ZERO, Vec3::Y, 20.0, 0.05, 10.0, (0.0, 1.0), 384, 216);
        let close = Camera::new(from + Vec3::X, Vec3::ZERO, Vec3::Y, 20.0, 0.05, 10.0, (0.0, 1.0), 384, 216);
        let placed =
            mitsuba_look_at(from, Vec3::ZERO, Vec3::Y) * Affine3A::from_scale(Vec3::new(1.0, 2.0, 0.5));
        let to_world = Camera::perspective(placed, 0.7, 0.05, 10.0, (0.0, 1.0), 384, 216);
        let ortho = Camera::orthographic(placed, (0.0, 1.0), 384, 216);
        let clip = Some(Clip { near: 0.5, far: 40.0 });
        let clipped =
            [to_world.with_clip(clip), ortho.with_clip(clip), lens.moving_to(&close).with_clip(clip)];
        for cam in [cornell(), lens, lens.moving_to(&close), to_world, ortho].into_iter().chain(clipped) {
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
                let (r, tmax) =
                    cam.generate_clipped_ray(Vec2::from(pixel[k]), Vec2::from(on_lens[k]), time[k]);
                for (got, got_tmax) in [(wide.ray(k), wide.tmax[k]), (base.ray(k), base.tmax[k])] {
                    let bits =
                        |r: &Ray| (r.origin.to_array().map(f32::to_bits), r.dir.to_array().map(f32::to_bits));
                    assert_eq!(bits(&got), bits(&r), "lane {k}");
                    assert_eq!(got.time.to_bits(), r.time.to_bits());
                    assert_eq!(got_tmax.to_bits(), tmax.to_bits());
                }
            }
        }
    }
}
