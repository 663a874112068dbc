//! `camera: (..)` and `render: (..)`: the camera as placed and the image and sampling settings.

use super::transform::{TransformOp, compose};
use crate::format::{Direction, Finite, Fov, FovAxis, NonNegative, Positive, UnitInterval, V3};
use crate::placement::MAX_COORDINATE;
use glam::{Affine3A, Vec3};
use serde::{Deserialize, Deserializer, de::Error};
use std::num::NonZeroU32;

pub use crate::lighting::tree::LightSamplerKind;

/// Thin-lens camera: where it stands and how it projects ([`CameraView`]), its lens and its
/// shutter.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(try_from = "RawCamera")]
pub struct CameraDesc {
    /// Placement and projection.
    pub view: CameraView,
    /// Lens radius (default 0: pinhole). For a `to_world` camera it is in camera space, as
    /// Mitsuba 3's `thinlens` `aperture_radius` (a scale in `to_world` scales it).
    pub aperture_radius: f32,
    /// Distance to the plane in focus (default: |look_at - look_from|; a `to_world` camera
    /// with a lens needs it, and it is in camera space, as Mitsuba 3's `focus_distance`).
    pub focus_dist: f32,
    /// Shutter open and close times (default (0, 0): no motion blur).
    pub shutter: (f32, f32),
}

/// The camera's two forms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CameraView {
    /// `look_from`, `look_at`, `vup`, `vfov`: a perspective camera whose image has
    /// right = normalize((look_at - look_from) x vup).
    LookAt {
        /// Eye position.
        look_from: Vec3,
        /// Point looked at.
        look_at: Vec3,
        /// Up vector (default (0, 1, 0)); not parallel to the view direction.
        vup: Vec3,
        /// Vertical field of view in degrees, in (0, 180).
        vfov: f32,
    },
    /// `to_world` and `projection`: camera space as Mitsuba 3's sensors have it (the camera
    /// looks along +z, +y is up, +x points to the image's left; `to_world` takes it to the
    /// world, as the `to_world` of Mitsuba's `perspective`, `orthographic` and `thinlens`).
    ToWorld {
        /// Camera to world (invertible; may scale).
        to_world: Affine3A,
        /// How camera space maps to the image.
        projection: Projection,
        /// Camera-space depth where rays start, as Mitsuba 3's `near_clip` (default: none,
        /// rays start at the lens or, orthographic, on the plane z = 0).
        near_clip: Option<f32>,
        /// Camera-space depth beyond which the camera sees nothing (its rays miss, seeing the
        /// background), as Mitsuba 3's `far_clip` (default: none, unbounded).
        far_clip: Option<f32>,
    },
}

impl CameraView {
    /// The clip planes the camera's rays get ([`crate::camera::Clip`]; none when the scene
    /// gives neither).
    pub fn clip(&self) -> Option<crate::camera::Clip> {
        match *self {
            CameraView::ToWorld { near_clip, far_clip, .. } if near_clip.is_some() || far_clip.is_some() => {
                Some(crate::camera::Clip {
                    near: near_clip.unwrap_or(0.0),
                    far: far_clip.unwrap_or(f32::INFINITY),
                })
            }
            _ => None,
        }
    }
}

/// How a `to_world` camera projects (`projection: Perspective(fov: 39.3, fov_axis: X)` or
/// `projection: Orthographic`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// Mitsuba 3's `perspective` (`thinlens` with an aperture): `fov` degrees across
    /// `fov_axis`.
    Perspective {
        /// Field of view in degrees, in (0, 180).
        fov: f32,
        /// The image extent `fov` spans (default `X`).
        fov_axis: FovAxis,
    },
    /// Mitsuba 3's `orthographic`: the view spans camera-space x in [-1, 1] and y in
    /// [-1/aspect, 1/aspect] (aspect = width / height), then `to_world` applies (its scale
    /// sizes the view); rays start on the plane z = 0 and run along +z.
    Orthographic,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Projection")]
enum RawProjection {
    Perspective {
        fov: Fov,
        #[serde(default)]
        fov_axis: FovAxis,
    },
    Orthographic,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Camera")]
struct RawCamera {
    #[serde(default)]
    look_from: Option<V3>,
    #[serde(default)]
    look_at: Option<V3>,
    #[serde(default)]
    vup: Option<Direction>,
    #[serde(default)]
    vfov: Option<Fov>,
    #[serde(default)]
    to_world: Option<Vec<TransformOp>>,
    #[serde(default)]
    projection: Option<RawProjection>,
    #[serde(default)]
    near_clip: Option<Positive>,
    #[serde(default)]
    far_clip: Option<Positive>,
    #[serde(default)]
    aperture_radius: NonNegative,
    #[serde(default)]
    focus_dist: Option<Positive>,
    #[serde(default)]
    shutter: (Finite, Finite),
}

/// The two forms' fields, for messages.
const FORMS: &str =
    "a camera is either (look_from, look_at, vfov[, vup]) or (to_world, projection[, near_clip, far_clip])";

impl TryFrom<RawCamera> for CameraDesc {
    type Error = String;
    fn try_from(r: RawCamera) -> Result<Self, String> {
        if r.shutter.1.0 < r.shutter.0.0 {
            return Err(format!(
                "camera: shutter closes ({}) before it opens ({})",
                r.shutter.1.0, r.shutter.0.0
            ));
        }
        let far = |x: f32| !(x <= MAX_COORDINATE);
        if far(r.aperture_radius.0) || r.focus_dist.is_some_and(|f| far(f.0)) {
            return Err(format!("camera: positions and distances must lie within {MAX_COORDINATE:e} units"));
        }
        let shutter = (r.shutter.0.0, r.shutter.1.0);
        let look_at_form = [r.look_from.is_some(), r.look_at.is_some(), r.vup.is_some(), r.vfov.is_some()];
        let clip = [r.near_clip.is_some(), r.far_clip.is_some()];
        let to_world_form = [r.to_world.is_some(), r.projection.is_some(), clip[0], clip[1]];
        if look_at_form.contains(&true) && to_world_form.contains(&true) {
            return Err(format!(
                "camera: look_from, look_at, vup and vfov do not go with to_world, projection, near_clip and far_clip: {FORMS}"
            ));
        }
        let (near_clip, far_clip) = (r.near_clip.map(|n| n.0), r.far_clip.map(|f| f.0));
        if near_clip.is_some_and(far) || far_clip.is_some_and(far) {
            return Err(format!("camera: near_clip and far_clip must lie within {MAX_COORDINATE:e} units"));
        }
        if let (Some(n), Some(f)) = (near_clip, far_clip)
            && !(n < f)
        {
            return Err(format!("camera: near_clip ({n}) must be less than far_clip ({f})"));
        }
        if let Some(ops) = r.to_world.as_deref() {
            let Some(projection) = r.projection else {
                return Err(format!("camera: missing field `projection`: {FORMS}"));
            };
            let projection = match projection {
                RawProjection::Perspective { fov, fov_axis } => {
                    Projection::Perspective { fov: fov.0, fov_axis }
                }
                RawProjection::Orthographic => Projection::Orthographic,
            };
            let to_world = to_world_checked(ops)?;
            if projection == Projection::Orthographic && r.aperture_radius.0 > 0.0 {
                return Err(
                    "camera: an Orthographic projection has no lens (aperture_radius must be 0)".into()
                );
            }
            let focus_dist = match r.focus_dist {
                Some(f) => f.0,
                None if r.aperture_radius.0 > 0.0 => {
                    return Err(
                        "camera: a to_world camera with a lens (aperture_radius > 0) needs focus_dist".into(),
                    );
                }
                // A pinhole's rays do not depend on it.
                None => 1.0,
            };
            let view = CameraView::ToWorld { to_world, projection, near_clip, far_clip };
            return Ok(Self { view, aperture_radius: r.aperture_radius.0, focus_dist, shutter });
        }
        if r.to_world.is_none() && (r.projection.is_some() || clip.contains(&true)) {
            return Err(format!("camera: missing field `to_world`: {FORMS}"));
        }
        let missing = |name: &str| format!("camera: missing field `{name}`: {FORMS}");
        let look_from = r.look_from.ok_or_else(|| missing("look_from"))?.0;
        let look_at = r.look_at.ok_or_else(|| missing("look_at"))?.0;
        let vfov = r.vfov.ok_or_else(|| missing("vfov"))?.0;
        let vup = r.vup.map_or(Vec3::Y, |v| v.0);
        let camera = Self {
            view: CameraView::LookAt { look_from, look_at, vup, vfov },
            aperture_radius: r.aperture_radius.0,
            focus_dist: r.focus_dist.map_or((look_at - look_from).length(), |f| f.0),
            shutter,
        };
        camera.check()?;
        Ok(camera)
    }
}

impl CameraDesc {
    /// What a camera's pose must be, checked at load and at each frame of an animated camera:
    /// look_from and look_at apart, vup not along the view, positions and distances within
    /// [`MAX_COORDINATE`], vfov in (0, 180) degrees, focus_dist > 0.
    pub fn check(&self) -> Result<(), String> {
        let far = |x: f32| !(x <= MAX_COORDINATE);
        if let CameraView::LookAt { look_from, look_at, vup, vfov } = self.view {
            look_at_checked(look_from, look_at, vup, vfov)?;
        }
        if !(self.focus_dist > 0.0) || far(self.focus_dist) {
            return Err(format!(
                "camera: focus_dist must be > 0 and within {MAX_COORDINATE:e} units, not {}",
                self.focus_dist
            ));
        }
        Ok(())
    }
}

/// The checks of a look_from/look_at camera's pose (see [`CameraDesc::check`]).
fn look_at_checked(look_from: Vec3, look_at: Vec3, vup: Vec3, vfov: f32) -> Result<(), String> {
    let far = |x: f32| !(x <= MAX_COORDINATE);
    let view = look_at - look_from;
    if view.length_squared() == 0.0 {
        return Err("camera: look_from and look_at are the same point".into());
    }
    let far_point = far(look_from.abs().max_element()) || far(look_at.abs().max_element());
    if far_point || far(view.length()) {
        return Err(format!("camera: positions and distances must lie within {MAX_COORDINATE:e} units"));
    }
    if view.normalize().cross(vup.normalize()).length_squared() < 1e-12 {
        return Err("camera: vup is parallel to the view direction".into());
    }
    if !(vfov > 0.0 && vfov < 180.0) {
        return Err(format!("camera: vfov must lie in (0, 180) degrees, not {vfov}"));
    }
    Ok(())
}

/// The product of a camera's `to_world` list, checked: invertible (relative to its own
/// scale, as each step), its origin within [`MAX_COORDINATE`] and its axes no longer than it.
fn to_world_checked(ops: &[TransformOp]) -> Result<Affine3A, String> {
    let m = compose(ops);
    let axes = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
    let size = axes.iter().map(|a| a.length()).fold(0.0f32, f32::max);
    if !(size <= MAX_COORDINATE) || !(m.translation.abs().max_element() <= MAX_COORDINATE) {
        return Err(format!(
            "camera: to_world must keep the camera within {MAX_COORDINATE:e} units (origin {}, largest axis {size})",
            m.translation
        ));
    }
    if !((m.matrix3 * size.recip()).determinant().abs() > f32::EPSILON) {
        return Err("camera: to_world is singular (it flattens camera space)".into());
    }
    Ok(m)
}

/// Image size and sampling.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields, default, rename = "Render")]
pub struct RenderDesc {
    /// Width in pixels (default 512).
    pub width: NonZeroU32,
    /// Height in pixels (default 512).
    pub height: NonZeroU32,
    /// Samples per pixel (default 64).
    pub spp: NonZeroU32,
    /// Maximum number of bounces (default 64).
    pub max_depth: u32,
    /// Bounces before Russian roulette may end a path (default 3; Mitsuba scenes: theirs, 5 by
    /// default).
    pub rr_depth: u32,
    /// Seed of every random number of the image (default 0).
    pub seed: u64,
    /// Scale samples down so that no component exceeds this (default: none, which is unbiased).
    pub clamp: Option<Positive>,
    /// How the samples' random numbers are made: `Sobol` (default), `Stratified`, `Independent`.
    pub sampler: SamplerKind,
    /// Render only this window `(x0, x1, y0, y1)`, fractions of the image in [0, 1] as
    /// pbrt-v4's crop window (default: the whole image).
    pub crop: Option<CropWindow>,
    /// The pixel filter: `Box` (default), `Tent(radius: 1)` or `Gaussian(stddev: 0.5)`.
    pub filter: FilterDesc,
    /// How next-event estimation chooses a light: `Power`, `Tree` or `Auto` (default).
    pub light_sampler: LightSamplerKind,
    /// Path guiding: `Off` (default) or `On` (see [`crate::guiding`]).
    pub guiding: crate::guiding::Guiding,
    /// Light tracing of punctual lights' caustics: `Off` (default) or `On` (see
    /// [`crate::lighting::light_paths`]).
    pub light_tracing: crate::lighting::light_paths::LightTracing,
}

/// A pixel filter as Mitsuba 3 defines it (mitsuba3 `src/rfilters/`), in pixels: `Box`
/// (radius 0.5), `Tent(radius)` (default 1, at most 64), `Gaussian(stddev)` (default 0.5, at
/// most 16; radius 4 stddev). See [`crate::filter`].
#[derive(Deserialize, Debug, Clone, Copy, Default, PartialEq)]
#[serde(try_from = "RawFilter")]
pub enum FilterDesc {
    /// Uniform over the pixel.
    #[default]
    Box,
    /// max(0, 1 - |x| / radius) per axis.
    Tent {
        /// In (0, 64] pixels.
        radius: f32,
    },
    /// Mitsuba's windowed Gaussian per axis.
    Gaussian {
        /// In (0, 16] pixels.
        stddev: f32,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Filter")]
enum RawFilter {
    Box,
    Tent {
        #[serde(default = "one")]
        radius: Positive,
    },
    Gaussian {
        #[serde(default = "half")]
        stddev: Positive,
    },
}

fn one() -> Positive {
    Positive(1.0)
}

fn half() -> Positive {
    Positive(0.5)
}

impl FilterDesc {
    /// The largest tent radius (pixels).
    pub const MAX_RADIUS: f32 = 64.0;
    /// The largest Gaussian standard deviation (pixels).
    pub const MAX_STDDEV: f32 = 16.0;

    /// Checks the bounds.
    pub fn checked(self) -> Result<Self, String> {
        match self {
            FilterDesc::Tent { radius } if !(radius > 0.0 && radius <= Self::MAX_RADIUS) => {
                Err(format!("filter: a Tent's radius is in (0, {}] pixels, not {radius}", Self::MAX_RADIUS))
            }
            FilterDesc::Gaussian { stddev } if !(stddev > 0.0 && stddev <= Self::MAX_STDDEV) => Err(format!(
                "filter: a Gaussian's stddev is in (0, {}] pixels, not {stddev}",
                Self::MAX_STDDEV
            )),
            ok => Ok(ok),
        }
    }
}

impl TryFrom<RawFilter> for FilterDesc {
    type Error = String;
    fn try_from(r: RawFilter) -> Result<Self, String> {
        match r {
            RawFilter::Box => Ok(FilterDesc::Box),
            RawFilter::Tent { radius } => FilterDesc::Tent { radius: radius.0 }.checked(),
            RawFilter::Gaussian { stddev } => FilterDesc::Gaussian { stddev: stddev.0 }.checked(),
        }
    }
}

/// The command line's spelling: `box`, `tent`, `tent:RADIUS`, `gaussian`, `gaussian:STDDEV`.
impl std::str::FromStr for FilterDesc {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (name, value) = s.split_once(':').map_or((s, None), |(n, v)| (n, Some(v)));
        let number = |default: f32| -> Result<f32, String> {
            value.map_or(Ok(default), |v| {
                v.parse::<f32>().map_err(|_| format!("filter: '{v}' is not a number"))
            })
        };
        let f = match (name, value) {
            ("box", None) => FilterDesc::Box,
            ("tent", _) => FilterDesc::Tent { radius: number(1.0)? },
            ("gaussian", _) => FilterDesc::Gaussian { stddev: number(0.5)? },
            _ => {
                return Err(format!(
                    "no filter '{s}': there are box, tent, tent:RADIUS, gaussian and gaussian:STDDEV"
                ));
            }
        };
        f.checked()
    }
}

/// `(x0, x1, y0, y1)` in [0, 1], x0 < x1 and y0 < y1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CropWindow(pub [f32; 4]);

impl<'de> Deserialize<'de> for CropWindow {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let (x0, x1, y0, y1) = <(UnitInterval, UnitInterval, UnitInterval, UnitInterval)>::deserialize(d)?;
        let w = [x0.0, x1.0, y0.0, y1.0];
        CropWindow::new(w).map_err(D::Error::custom)
    }
}

impl CropWindow {
    /// Checks `(x0, x1, y0, y1)`.
    pub fn new(w: [f32; 4]) -> Result<Self, String> {
        let [x0, x1, y0, y1] = w;
        if !w.iter().all(|v| (0.0..=1.0).contains(v)) || !(x0 < x1 && y0 < y1) {
            return Err(format!(
                "a crop window is (x0, x1, y0, y1) with 0 <= x0 < x1 <= 1 and 0 <= y0 < y1 <= 1, not ({x0}, {x1}, {y0}, {y1})"
            ));
        }
        Ok(Self(w))
    }
}

impl Default for RenderDesc {
    fn default() -> Self {
        let n = |x| NonZeroU32::new(x).unwrap();
        Self {
            width: n(512),
            height: n(512),
            spp: n(64),
            max_depth: 64,
            rr_depth: 3,
            seed: 0,
            clamp: None,
            sampler: SamplerKind::default(),
            crop: None,
            filter: FilterDesc::Box,
            light_sampler: LightSamplerKind::Auto,
            guiding: crate::guiding::Guiding::Off,
            light_tracing: crate::lighting::light_paths::LightTracing::Off,
        }
    }
}

/// How the samples' random numbers are made (see the integrator's `sampler` module).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize)]
pub enum SamplerKind {
    /// Owen-scrambled Sobol in every 1D and 2D dimension (extensible: the first N samples of a
    /// pixel are those of an N-spp render).
    #[default]
    Sobol,
    /// Correlated multi-jittered in every 2D dimension, jittered strata in every 1D one (the
    /// pattern depends on the sample count).
    Stratified,
    /// Independent uniform numbers.
    Independent,
}

impl SamplerKind {
    /// The names, as the command line and scene files spell them.
    pub const NAMES: [(&'static str, SamplerKind); 3] = [
        ("sobol", SamplerKind::Sobol),
        ("stratified", SamplerKind::Stratified),
        ("independent", SamplerKind::Independent),
    ];
}
