//! The lights that are not primitives, in world space as the light table samples them: point,
//! spot, directional and projector lights (what each kind of `lights: [..]` in a scene becomes,
//! `lighting::punctual`), with their falloffs and projected textures.

use crate::lighting::tree::LightBounds;
use crate::math::luminance;
use crate::texture::{TextureId, Textures};
use glam::{Vec2, Vec3, Vec3A};

/// Lights that are not primitives, as a scene writes them (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PunctualLight {
    /// An isotropic point light of radiant intensity `intensity` (W/sr): irradiance
    /// `intensity * cos / d^2` at distance `d`.
    Point {
        /// Where it is.
        position: Vec3A,
        /// Radiant intensity.
        intensity: Vec3,
    },
    /// A point light shining into a cone: the intensity towards a direction at angle `theta` from
    /// `axis` is `intensity` times the falloff (full inside `falloff_start`, none outside
    /// `cone_angle`) and times the texture's value there, if it has one.
    Spot {
        /// Where it is.
        position: Vec3A,
        /// Unit direction of the cone's axis.
        axis: Vec3A,
        /// Radiant intensity on the axis.
        intensity: Vec3,
        /// Cosine of the angle where the falloff starts.
        cos_falloff: f32,
        /// Cosine of the cone's half angle.
        cos_total: f32,
        /// How the intensity falls off between the two.
        falloff: SpotFalloff,
        /// A texture over the cone.
        texture: Option<SpotTexture>,
    },
    /// Parallel light from one direction, of irradiance `irradiance` (W/m^2) on a surface
    /// facing it.
    Directional {
        /// Unit direction towards the light.
        to_light: Vec3A,
        /// Irradiance.
        irradiance: Vec3,
    },
    /// A projector (Mitsuba 3's `projector`, `src/emitters/projector.cpp`): a pinhole at
    /// `position` projecting an image through a perspective frustum along `z`. A point at
    /// `(x, y, z)` in its frame (`z > 0`) is lit through the image's `uv = (0.5 - x / (2 z
    /// tan_x), 0.5 + y / (2 z tan_y))` (outside [0, 1]^2, not at all), with intensity `pi
    /// irradiance E(uv) / cos^3 theta`: a plane at unit distance facing it receives `pi
    /// irradiance E(uv)`, the texture's value `E` (1 without one).
    Projector {
        /// Where the pinhole is.
        position: Vec3A,
        /// Unit axes of its frame: `x` to the image's left (seen from behind the projector),
        /// `y` to its top, `z` the direction it shines in.
        frame: [Vec3A; 3],
        /// Half the image's width on the plane `z = 1`: tan of half the horizontal field of view.
        tan_x: f32,
        /// Half its height there.
        tan_y: f32,
        /// The irradiance factor (the colour, or 1 under a texture, times the scale).
        irradiance: Vec3,
        /// The projected image.
        texture: Option<LightTexture>,
    },
}

/// How a spot light's intensity falls off between its falloff angle and its cone's edge.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum SpotFalloff {
    /// `smoothstep(cos_total, cos_falloff, cos theta)`, pbrt-v4's `SpotLight` (`smoothstep(a, b,
    /// x)` = 3t^2 - 2t^3, t = (x - a) / (b - a) clamped to [0, 1]).
    #[default]
    Smoothstep,
    /// Linear in the angle, Mitsuba 3's `spot` (`src/emitters/spot.cpp`): `(total - theta) /
    /// (total - falloff)`.
    Linear {
        /// The cone's half angle, radians.
        total: f32,
        /// `1 / (total - falloff)`, the falloff angle in radians (infinite when they are equal).
        inv_width: f32,
    },
}

/// A texture a punctual light projects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightTexture {
    /// The texture.
    pub id: TextureId,
    /// Its mean (the light's power estimate).
    pub mean: Vec3,
}

/// A texture over a spot light's cone, as Mitsuba 3's `spot` maps it: a direction `(x, y, z)`
/// in the frame (`x`, `y`, the axis) reads `uv = (0.5 + x / (2 z tan), 0.5 - y / (2 z tan))`,
/// `tan` that of the cone's half angle (Mitsuba's uv with pathwave's v, 1 - Mitsuba's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotTexture {
    /// The texture.
    pub texture: LightTexture,
    /// Unit x axis of the frame (Mitsuba's `look_at` frame: `normalize(up x axis)`).
    pub x: Vec3A,
    /// Unit y axis (`axis x x`).
    pub y: Vec3A,
    /// `1 / tan(cone angle)`.
    pub inv_tan: f32,
}

impl PunctualLight {
    /// Its power divided by pi (the unit the table compares finite lights in); for a
    /// directional light, which takes a share of its own, the luminance of its irradiance.
    pub(super) fn power_over_pi(&self) -> f32 {
        match *self {
            PunctualLight::Point { intensity, .. } => 4.0 * luminance(intensity),
            PunctualLight::Spot { intensity, cos_falloff, cos_total, falloff, texture, .. } => {
                let mean = texture.map_or(Vec3::ONE, |t| t.texture.mean);
                // The integral of the falloff over the sphere, over 2 pi.
                let cone = match falloff {
                    SpotFalloff::Smoothstep => (1.0 - cos_falloff) + 0.5 * (cos_falloff - cos_total),
                    SpotFalloff::Linear { total, inv_width } if inv_width.is_finite() => {
                        let (sin_total, sin_falloff) =
                            ((total as f64).sin(), (1.0 - (cos_falloff as f64).powi(2)).sqrt());
                        (1.0 - (sin_total - sin_falloff) * inv_width as f64) as f32
                    }
                    SpotFalloff::Linear { .. } => 1.0 - cos_total,
                };
                2.0 * luminance(intensity * mean) * cone
            }
            PunctualLight::Directional { irradiance, .. } => luminance(irradiance),
            // The image's irradiance over the plane z = 1 (2 tan_x by 2 tan_y), times pi.
            PunctualLight::Projector { tan_x, tan_y, irradiance, texture, .. } => {
                let mean = texture.map_or(Vec3::ONE, |t| t.mean);
                luminance(irradiance * mean) * 4.0 * tan_x * tan_y
            }
        }
    }

    /// Its bounds for the light tree (pbrt-v4's `PointLight::Bounds`, `SpotLight::Bounds`,
    /// `ProjectionLight::Bounds`); `None` at infinity. Their power is that of a point light of
    /// the same intensity along the axis (4 times it, over pi), not the light's own: the
    /// importance's cone factor accounts for the directions it does not reach, as pbrt-v4
    /// notes. (With a spot's own power, a spot of 25 degrees weighed 20 times too little
    /// beside a point light: `scenes/lights.ron`, benches/results/sampling.md.)
    pub(super) fn bounds(&self) -> Option<LightBounds> {
        let phi = match *self {
            PunctualLight::Point { intensity, .. } => luminance(intensity),
            PunctualLight::Spot { intensity, texture, .. } => {
                luminance(intensity * texture.map_or(Vec3::ONE, |t| t.texture.mean))
            }
            // The irradiance on the plane at distance 1 is the intensity along the axis.
            PunctualLight::Projector { irradiance, texture, .. } => {
                luminance(irradiance * texture.map_or(Vec3::ONE, |t| t.mean))
            }
            PunctualLight::Directional { .. } => return None,
        } * 4.0;
        let at = |p: Vec3A, w: Vec3A, cos_theta_o: f32, cos_theta_e: f32| LightBounds {
            lo: p,
            hi: p,
            phi,
            w,
            cos_theta_o,
            cos_theta_e,
            two_sided: false,
        };
        match *self {
            // Every direction: theta_o = pi, theta_e = pi / 2.
            PunctualLight::Point { position, .. } => Some(at(position, Vec3A::Z, -1.0, 0.0)),
            // Full within the falloff angle, spreading to the cone's edge.
            PunctualLight::Spot { position, axis, cos_falloff, cos_total, .. } => {
                let spread = crate::math::acos(cos_total) - crate::math::acos(cos_falloff);
                Some(at(position, axis, cos_falloff, cos_sin_of(spread)))
            }
            PunctualLight::Projector { position, frame, tan_x, tan_y, .. } => {
                let corner = 1.0 / (1.0 + tan_x * tan_x + tan_y * tan_y).sqrt();
                Some(at(position, frame[2], 1.0, corner))
            }
            PunctualLight::Directional { .. } => None,
        }
    }

    /// At infinity: takes its own share of the light choices.
    pub(super) fn infinite(&self) -> bool {
        matches!(self, PunctualLight::Directional { .. })
    }

    /// The light seen from `from`: the unit direction towards it, the distance (infinite for a
    /// directional light) and the radiance-like factor that, divided by the choice's
    /// probability, is the light's estimate (`intensity / d^2` or the irradiance); `textures`
    /// are the scene's.
    #[inline]
    pub fn illuminate(&self, from: Vec3A, textures: &Textures) -> (Vec3A, f32, Vec3) {
        match *self {
            PunctualLight::Point { position, intensity } => {
                let (wi, d, d2, _) = toward(position.into(), from.into(), [0.0; 3]);
                (wi.into(), d, intensity / d2)
            }
            PunctualLight::Spot { position, axis, intensity, cos_falloff, cos_total, falloff, texture } => {
                let (wi, d, d2, cos) = toward(position.into(), from.into(), axis.into());
                let wi = Vec3A::from(wi);
                let f = match falloff {
                    SpotFalloff::Smoothstep => smoothstep(cos_total, cos_falloff, cos),
                    SpotFalloff::Linear { total, inv_width } => {
                        linear_falloff(cos, cos_total, cos_falloff, total, inv_width)
                    }
                };
                let le = intensity * (f / d2);
                match texture {
                    Some(t) if f > 0.0 => {
                        let (x, y) = (-wi.dot(t.x), -wi.dot(t.y));
                        let s = 0.5 * t.inv_tan / cos;
                        let uv = Vec2::new(0.5 + x * s, 0.5 - y * s);
                        (wi, d, le * textures.eval(t.texture.id, uv, position))
                    }
                    _ => (wi, d, le),
                }
            }
            PunctualLight::Directional { to_light, irradiance } => (to_light, f32::INFINITY, irradiance),
            PunctualLight::Projector { position, frame: [x, y, z], tan_x, tan_y, irradiance, texture } => {
                let to = position - from;
                let d = to.length();
                let wi = to / d;
                let (lx, ly, lz) = (-to.dot(x), -to.dot(y), -to.dot(z));
                let uv = Vec2::new(0.5 - 0.5 * lx / (lz * tan_x), 0.5 + 0.5 * ly / (lz * tan_y));
                let inside = lz > 0.0 && (0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y);
                if !inside {
                    return (wi, d, Vec3::ZERO);
                }
                let e = texture.map_or(Vec3::ONE, |t| textures.eval(t.id, uv, position));
                // Mitsuba's pi E / (z^2 cos theta), cos theta = z / d.
                (wi, d, irradiance * e * (std::f32::consts::PI * d / (lz * lz * lz)))
            }
        }
    }
}

/// Mitsuba 3's spot falloff: 1 from the axis to the falloff angle (cosine `cos_falloff`), then
/// linear in the angle down to 0 at the cone's edge (`total`, cosine `cos_total`), 0 beyond.
#[inline]
fn linear_falloff(cos: f32, cos_total: f32, cos_falloff: f32, total: f32, inv_width: f32) -> f32 {
    if !(cos > cos_total) {
        0.0
    } else if cos >= cos_falloff {
        1.0
    } else {
        ((total - crate::math::acos(cos)) * inv_width).clamp(0.0, 1.0)
    }
}

/// `cos(x)` for `x` in [0, pi], with the same bits on every machine.
fn cos_sin_of(x: f32) -> f32 {
    crate::math::cos_sin_turn((x / std::f32::consts::TAU).clamp(0.0, 0.5)).0
}

/// Hermite smoothstep of `x` between `a` and `b` (0 below `a`, 1 above `b`), its branch a
/// select (a loop of it over lanes vectorises).
#[inline(always)]
pub fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    let step = if x < a { 0.0 } else { 1.0 };
    if a == b { step } else { t * t * (3.0 - 2.0 * t) }
}

/// From `from` towards a point light at `position`: the unit direction, the distance, its
/// square and the cosine between the direction back from the light and `axis` (a spot's). On
/// plain numbers, glam's operations in glam's order (a dot product adds x and y, then z), so
/// that a loop of it over lanes vectorises and gives each lane [`PunctualLight::illuminate`]'s
/// bits.
#[inline(always)]
pub fn toward(position: [f32; 3], from: [f32; 3], axis: [f32; 3]) -> ([f32; 3], f32, f32, f32) {
    let to = [0, 1, 2].map(|c| position[c] - from[c]);
    let d2 = (to[0] * to[0] + to[1] * to[1]) + to[2] * to[2];
    let d = d2.sqrt();
    let wi = to.map(|t| t / d);
    let cos = -((wi[0] * axis[0] + wi[1] * axis[1]) + wi[2] * axis[2]);
    (wi, d, d2, cos)
}
