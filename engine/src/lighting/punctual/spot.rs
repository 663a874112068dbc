//! `Spot(position: (0, 4, 0), look_at: (0, 0, 0), intensity: (50, 50, 50), cone_angle: 30,
//! falloff_start: 25)`: a point light shining into a cone about `look_at - position`, its
//! intensity falling off as pbrt-v4's `SpotLight` (`falloff: Smoothstep`, the default) or as
//! Mitsuba 3's `spot` (`falloff: Linear`), optionally through a texture over the cone. Its
//! runtime form is [`PunctualLight::Spot`].

use super::{LightModel, LightPosition, LightTextures, PunctualLight, look_frame};
use crate::format::{Color, Finite, Radiance, V3};
use crate::lighting::lights::{SpotFalloff, SpotTexture};
use glam::Vec3;

/// A point light into a cone about `look_at - position`: intensity towards a direction at angle
/// theta from the axis is `intensity` times the falloff: full within `falloff_start`, none beyond
/// `cone_angle` (degrees; cone in (0, 180), default 30; falloff in [0, cone], default 25), between
/// them `smoothstep(cos(cone_angle), cos(falloff_start), cos theta)` with `falloff: Smoothstep`
/// (the default; pbrt-v4's `SpotLight`; `smoothstep(a, b, x)` = 3t^2 - 2t^3 with t = (x - a) / (b -
/// a) clamped to [0, 1]) or `(cone_angle - theta) / (cone_angle - falloff_start)` with `falloff:
/// Linear` (Mitsuba 3's `spot`, whose `cutoff_angle` and `beam_width` are `cone_angle` and
/// `falloff_start`). `texture` (a texture's name; a colour tints the intensity) multiplies it by
/// the texture's value at Mitsuba's uv of the direction: for the direction (x, y, z) in the frame
/// whose z is the axis, x is `normalize(up x axis)` and y `axis x x` (`up` default (0, 1, 0), not
/// along the axis), uv = (0.5 + x / (2 z tan(cone_angle)), 0.5 - y / (2 z tan(cone_angle))) (a cone
/// under 90 degrees).
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Spot {
    /// Where it is.
    pub position: LightPosition,
    /// A point on the cone's axis.
    pub look_at: V3,
    /// Radiant intensity on the axis (W/sr).
    pub intensity: Radiance,
    /// Half angle of the cone in degrees, in (0, 180) (default 30).
    #[serde(default = "default_cone")]
    pub cone_angle: Finite,
    /// Angle from the axis where the falloff to the cone's edge starts, in degrees, in
    /// [0, cone_angle] (default 25).
    #[serde(default = "default_falloff")]
    pub falloff_start: Finite,
    /// How the intensity falls from `falloff_start` to `cone_angle` (default `Smoothstep`).
    #[serde(default)]
    pub falloff: Falloff,
    /// A texture over the cone (default none): the intensity is times its value at the
    /// direction's uv (see [`SpotTexture`]); a colour written out tints it.
    #[serde(default)]
    pub texture: Option<Color<Radiance>>,
    /// Orients a texture: its frame's y axis is `up` made orthogonal to the cone's axis
    /// (default (0, 1, 0); it may not lie along the axis).
    #[serde(default)]
    pub up: Option<V3>,
}

/// How a spot's intensity falls off between `falloff_start` and `cone_angle`.
#[derive(serde::Deserialize, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Falloff {
    /// A smoothstep of the cosine (pbrt-v4's `SpotLight`).
    #[default]
    Smoothstep,
    /// Linear in the angle (Mitsuba 3's `spot`).
    Linear,
}

fn default_cone() -> Finite {
    Finite(30.0)
}

fn default_falloff() -> Finite {
    Finite(25.0)
}

impl Spot {
    /// The axis and the texture's frame.
    fn frame(&self) -> Option<[Vec3; 3]> {
        look_frame(self.look_at.0 - self.position.0, self.up.map_or(Vec3::Y, |u| u.0))
    }
}

impl LightModel for Spot {
    fn check(&self) -> Result<(), String> {
        let Spot { position, look_at, cone_angle, falloff_start, .. } = *self;
        if !(cone_angle.0 > 0.0 && cone_angle.0 < 180.0) {
            return Err(format!(
                "spot light: cone_angle must be in (0, 180) degrees, found {}",
                cone_angle.0
            ));
        }
        if !(falloff_start.0 >= 0.0 && falloff_start.0 <= cone_angle.0) {
            return Err(format!(
                "spot light: falloff_start must be in [0, cone_angle = {}] degrees, found {}",
                cone_angle.0, falloff_start.0
            ));
        }
        if (look_at.0 - position.0).length_squared() == 0.0 {
            return Err("spot light: look_at is the light's position".into());
        }
        let textured = matches!(self.texture, Some(Color::Texture(_)));
        match (textured, self.up) {
            (false, Some(_)) => Err("spot light: up orients a texture; this spot has none".into()),
            (true, _) if self.frame().is_none() => {
                Err("spot light: up is along the axis; give an up that orients the texture".into())
            }
            (true, _) if cone_angle.0 >= 90.0 => {
                Err("spot light: a texture covers a cone of less than 90 degrees".into())
            }
            _ => Ok(()),
        }
    }

    fn to_light(&self, textures: &LightTextures) -> PunctualLight {
        let Spot { position, look_at, intensity, cone_angle, falloff_start, falloff, .. } = *self;
        // In f64, rounded: a C library's last bits reach the f32 only at a rounding tie.
        let (total, start) = ((cone_angle.0 as f64).to_radians(), (falloff_start.0 as f64).to_radians());
        let (tint, texture) = self.texture.as_ref().map_or((Vec3::ONE, None), |c| textures.color(c));
        let texture = texture.zip(self.frame()).map(|(texture, [x, y, _])| SpotTexture {
            texture,
            x: x.into(),
            y: y.into(),
            inv_tan: (1.0 / total.tan()) as f32,
        });
        PunctualLight::Spot {
            position: position.0.into(),
            axis: (look_at.0 - position.0).normalize().into(),
            intensity: intensity.0 * tint,
            cos_falloff: start.cos() as f32,
            cos_total: total.cos() as f32,
            falloff: match falloff {
                Falloff::Smoothstep => SpotFalloff::Smoothstep,
                Falloff::Linear => {
                    SpotFalloff::Linear { total: total as f32, inv_width: (1.0 / (total - start)) as f32 }
                }
            },
            texture,
        }
    }
}
