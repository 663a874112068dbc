//! A material that exists to test the registry (cargo feature `test-material`): a Lambertian
//! reflector shaded by BSDF sampling alone, through the generic sampled-material stage. It
//! converges to the same image as `Lambertian`, with more noise.

use super::lambertian::LambertianDesc;
use super::{BsdfSample, Colors, MaterialModel, Shading};
use glam::{Vec2, Vec3, Vec3A};

/// Diffuse reflector without light sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TestDiffuse {
    /// Reflectance in [0, 1].
    pub albedo: Vec3,
}

/// Written as `TestDiffuse(albedo: (r, g, b))`, the fields of a Lambertian.
impl MaterialModel for TestDiffuse {
    type Desc = LambertianDesc;
    const SHADING: Shading = Shading::Sampled;

    fn build(desc: &LambertianDesc, colors: &mut Colors) -> Self {
        Self { albedo: colors.get(&desc.albedo).min(Vec3::ONE) }
    }

    fn set_color(&mut self, _slot: usize, value: Vec3) {
        self.albedo = value.clamp(Vec3::ZERO, Vec3::ONE);
    }

    fn sample(&self, wo: Vec3A, n: Vec3A, u: Vec2, _uc: f32) -> Option<BsdfSample> {
        super::lambertian::sample(self.albedo, wo, n, u)
    }

    fn albedo(&self) -> Vec3 {
        self.albedo
    }
}
