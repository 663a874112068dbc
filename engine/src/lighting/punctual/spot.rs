//! `Spot(position: (0, 4, 0), look_at: (0, 0, 0), intensity: (50, 50, 50), cone_angle: 30,
//! falloff_start: 25)`: a point light shining into a cone about `look_at - position`.

use super::{LightModel, LightPosition, PunctualLight};
use crate::format::{Finite, Rgb, V3};

/// A spot light (pbrt-v4's `SpotLight`: see [`PunctualLight::Spot`]).
#[derive(serde::Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct Spot {
    /// Where it is.
    pub position: LightPosition,
    /// A point on the cone's axis.
    pub look_at: V3,
    /// Radiant intensity on the axis (W/sr).
    pub intensity: Rgb,
    /// Half angle of the cone in degrees, in (0, 180) (default 30).
    #[serde(default = "default_cone")]
    pub cone_angle: Finite,
    /// Angle from the axis where the falloff to the cone's edge starts, in degrees, in
    /// [0, cone_angle] (default 25).
    #[serde(default = "default_falloff")]
    pub falloff_start: Finite,
}

fn default_cone() -> Finite {
    Finite(30.0)
}

fn default_falloff() -> Finite {
    Finite(25.0)
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
        Ok(())
    }

    fn to_light(&self) -> PunctualLight {
        let Spot { position, look_at, intensity, cone_angle, falloff_start } = *self;
        PunctualLight::Spot {
            position: position.0.into(),
            axis: (look_at.0 - position.0).normalize().into(),
            intensity: intensity.0,
            // In f64, rounded: a C library's last bits reach the f32 only at a rounding tie.
            cos_falloff: (falloff_start.0 as f64).to_radians().cos() as f32,
            cos_total: (cone_angle.0 as f64).to_radians().cos() as f32,
        }
    }
}
