//! `camera: (..)` and `render: (..)`: the camera as placed and the image and sampling settings.

use crate::format::{Direction, Finite, Fov, NonNegative, Positive, UnitInterval, V3};
use crate::placement::MAX_COORDINATE;
use glam::Vec3;
use serde::{Deserialize, Deserializer, de::Error};
use std::num::NonZeroU32;

/// Thin-lens camera.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(try_from = "RawCamera")]
pub struct CameraDesc {
    /// Eye position.
    pub look_from: Vec3,
    /// Point looked at.
    pub look_at: Vec3,
    /// Up vector (default (0, 1, 0)); must not be parallel to the view direction.
    pub vup: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub vfov: f32,
    /// Lens radius (default 0: pinhole).
    pub aperture_radius: f32,
    /// Distance to the plane in focus (default: |look_at - look_from|).
    pub focus_dist: f32,
    /// Shutter open and close times (default (0, 0): no motion blur).
    pub shutter: (f32, f32),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Camera")]
struct RawCamera {
    look_from: V3,
    look_at: V3,
    #[serde(default = "default_vup")]
    vup: Direction,
    vfov: Fov,
    #[serde(default)]
    aperture_radius: NonNegative,
    #[serde(default)]
    focus_dist: Option<Positive>,
    #[serde(default)]
    shutter: (Finite, Finite),
}

fn default_vup() -> Direction {
    Direction(Vec3::Y)
}

impl TryFrom<RawCamera> for CameraDesc {
    type Error = String;
    fn try_from(r: RawCamera) -> Result<Self, String> {
        let view = r.look_at.0 - r.look_from.0;
        if view.length_squared() == 0.0 {
            return Err("camera: look_from and look_at are the same point".into());
        }
        if view.normalize().cross(r.vup.0.normalize()).length_squared() < 1e-12 {
            return Err("camera: vup is parallel to the view direction".into());
        }
        let far = [r.look_from.0.abs().max_element(), r.look_at.0.abs().max_element(), r.aperture_radius.0]
            .into_iter()
            .chain(r.focus_dist.map(|f| f.0))
            .any(|x| x > MAX_COORDINATE);
        if far || view.length() > MAX_COORDINATE {
            return Err(format!("camera: positions and distances must lie within {MAX_COORDINATE:e} units"));
        }
        if r.shutter.1.0 < r.shutter.0.0 {
            return Err(format!(
                "camera: shutter closes ({}) before it opens ({})",
                r.shutter.1.0, r.shutter.0.0
            ));
        }
        Ok(Self {
            look_from: r.look_from.0,
            look_at: r.look_at.0,
            vup: r.vup.0,
            vfov: r.vfov.0,
            aperture_radius: r.aperture_radius.0,
            focus_dist: r.focus_dist.map_or(view.length(), |f| f.0),
            shutter: (r.shutter.0.0, r.shutter.1.0),
        })
    }
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
    /// Bounces before Russian roulette may end a path (default 5).
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
            rr_depth: 5,
            seed: 0,
            clamp: None,
            sampler: SamplerKind::default(),
            crop: None,
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
