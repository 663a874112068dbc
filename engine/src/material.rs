//! Material parameters (plain data). How each one scatters light lives in the integrator crate.

use glam::Vec3;

/// How a dielectric computes its reflectance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Deserialize)]
pub enum Fresnel {
    /// The exact Fresnel equations for unpolarised light (default).
    #[default]
    Exact,
    /// Schlick's approximation (what SEED.md's original renderer used).
    Schlick,
}

/// A material. Colours are linear RGB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Ideal diffuse reflector, two-sided.
    Lambertian {
        /// Reflectance in [0, 1].
        albedo: Vec3,
    },
    /// Mirror reflection scaled by `albedo`, blurred by `fuzz` in [0, 1].
    Metal {
        /// Reflectance.
        albedo: Vec3,
        /// Radius of the ball added to the mirror direction; 0 is a perfect mirror.
        fuzz: f32,
    },
    /// Smooth clear dielectric (glass), with reflection and refraction weighted by Fresnel.
    Dielectric {
        /// Index of refraction inside (outside is 1).
        ior: f32,
        /// Exact or Schlick reflectance.
        fresnel: Fresnel,
    },
    /// Diffuse area emitter with a black BSDF.
    DiffuseLight {
        /// Emitted radiance.
        emit: Vec3,
        /// Emit from both sides; otherwise only on the side of the geometric normal.
        two_sided: bool,
    },
}

impl Material {
    /// Radiance emitted towards a direction making cosine `cos_out` with the normal.
    #[inline]
    pub fn emitted(&self, cos_out: f32) -> Vec3 {
        match *self {
            Material::DiffuseLight { emit, two_sided } if two_sided || cos_out > 0.0 => emit,
            _ => Vec3::ZERO,
        }
    }

    /// True for emitters.
    pub fn is_emissive(&self) -> bool {
        matches!(self, Material::DiffuseLight { .. })
    }
}
