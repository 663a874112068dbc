//! Diffuse area emitter: constant radiance over the hemisphere of its normal (or both), with a
//! black BSDF. Light sampling picks emitters by power (see [`crate::lighting::lights`]).

use super::{Colors, Emission, MaterialModel, Shading};
use crate::format::{Color, Radiance};
use glam::Vec3;

/// Area emitter of radiance `emit` (a colour or a texture) with a black BSDF; emits only on the
/// normal's side unless `two_sided: true` (default false).
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct DiffuseLightDesc {
    /// Emitted radiance, or a texture.
    pub emit: Color<Radiance>,
    /// Emit on both sides (default false: only on the side of the normal).
    #[serde(default)]
    pub two_sided: bool,
}

/// Diffuse area emitter with a black BSDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseLight {
    /// Emitted radiance.
    pub emit: Vec3,
    /// Emit from both sides; otherwise only on the side of the geometric normal.
    pub two_sided: bool,
}

impl MaterialModel for DiffuseLight {
    type Desc = DiffuseLightDesc;
    const SHADING: Shading = Shading::Emitter;

    fn build(desc: &DiffuseLightDesc, colors: &mut Colors) -> Self {
        Self { emit: colors.get(&desc.emit), two_sided: desc.two_sided }
    }

    #[inline]
    fn set_color(&mut self, _slot: usize, value: Vec3) {
        self.emit = value.max(Vec3::ZERO);
    }

    /// The albedo guide shows the radiance, clamped.
    #[inline]
    fn albedo(&self) -> Vec3 {
        self.emit.clamp(Vec3::ZERO, Vec3::ONE)
    }

    #[inline]
    fn emission(&self) -> Option<Emission> {
        Some(Emission { emit: self.emit, two_sided: self.two_sided, slot: 0 })
    }

    fn set_emission(&mut self, emit: Vec3) {
        self.emit = emit;
    }
}
