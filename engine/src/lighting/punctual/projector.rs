//! `Projector(position: (0, 4, 0), look_at: (0, 0, 0), up: (0, 0, 1), fov: 45, irradiance:
//! "slide", scale: 1)`: Mitsuba 3's `projector` (`src/emitters/projector.cpp`), a pinhole that
//! projects an image through a perspective frustum, the reciprocal of a perspective camera. Its
//! runtime form is [`PunctualLight::Projector`].

use super::{LightModel, LightPosition, LightTextures, PunctualLight, look_frame};
use crate::format::{Color, Fov, FovAxis, NonNegative, Radiance, V3};
use glam::Vec3;

/// Mitsuba 3's `projector`: a pinhole at `position` projecting the image `irradiance` (a texture's
/// name, or a colour; default (1, 1, 1)) along `look_at - position`, with its top towards `up`
/// (default (0, 1, 0), not along the axis), as a perspective camera would see it: `fov` degrees (in
/// (0, 180)) across `fov_axis` (`X` default, `Y`, `Diagonal`, `Smaller`, `Larger`) of an image
/// whose width over height is the texture's image's (1 for a colour or a texture that is not an
/// image). A point at (x, y, z) in the frame (x = `normalize(up x axis)`, y = `axis x x`, z along
/// the axis) with z > 0 reads uv = (0.5 - x / (2 z tan_x), 0.5 + y / (2 z tan_y)) (tan_x, tan_y:
/// tan of the half fields of view; nothing outside [0, 1]^2); a plane at unit distance facing the
/// projector receives pi `scale` (default 1, >= 0) times the image's value there (the intensity
/// towards theta from the axis is pi `scale` E / cos^3 theta).
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Projector {
    /// Where the pinhole is.
    pub position: LightPosition,
    /// A point on the axis it shines along.
    pub look_at: V3,
    /// The direction towards the image's top (default (0, 1, 0); not along the axis).
    #[serde(default = "default_up")]
    pub up: V3,
    /// Field of view in degrees, in (0, 180).
    pub fov: Fov,
    /// Which extent of the image `fov` spans: `X` (default), `Y`, `Diagonal`, `Smaller`,
    /// `Larger`.
    #[serde(default)]
    pub fov_axis: FovAxis,
    /// The image: a plane at unit distance facing the projector receives pi times its value
    /// (times `scale`); a colour or a texture's name (default (1, 1, 1)).
    #[serde(default = "white")]
    pub irradiance: Color<Radiance>,
    /// Factor on the irradiance (default 1).
    #[serde(default = "unit")]
    pub scale: NonNegative,
}

fn default_up() -> V3 {
    V3(Vec3::Y)
}

fn white() -> Color<Radiance> {
    Color::Value(Radiance(Vec3::ONE))
}

fn unit() -> NonNegative {
    NonNegative(1.0)
}

impl Projector {
    fn frame(&self) -> Option<[Vec3; 3]> {
        look_frame(self.look_at.0 - self.position.0, self.up.0)
    }
}

impl LightModel for Projector {
    fn check(&self) -> Result<(), String> {
        if (self.look_at.0 - self.position.0).length_squared() == 0.0 {
            return Err("projector: look_at is the light's position".into());
        }
        if self.frame().is_none() {
            return Err("projector: up is along the axis; give an up that orients the image".into());
        }
        Ok(())
    }

    fn to_light(&self, textures: &LightTextures) -> PunctualLight {
        let (color, texture) = textures.color(&self.irradiance);
        let aspect = textures.aspect(texture);
        let tan_x = self.fov_axis.tan_half_x_fov(self.fov.0, aspect);
        // `check` has made sure of the frame.
        let [x, y, z] = self.frame().unwrap_or([Vec3::X, Vec3::Y, Vec3::Z]);
        PunctualLight::Projector {
            position: self.position.0.into(),
            frame: [x.into(), y.into(), z.into()],
            tan_x: tan_x as f32,
            tan_y: (tan_x / aspect) as f32,
            irradiance: color * self.scale.0,
            texture,
        }
    }
}
