//! Light that surfaces emit, by material id: one table that the emitter hits of both
//! integrators and light sampling read. A surface emits when its material is an emitter (a
//! `DiffuseLight`, whose BSDF is black) or when its object has an `emit` (Mitsuba 3's `area`
//! emitter on a shape whose BSDF reflects, `src/emitters/area.cpp`): such an object gets a
//! material id of its own, its material's copy, so that the table says per id what is emitted.

use crate::material::{Emission, Material};
use crate::shape::SurfacePoint;
use crate::texture::{MaterialTextures, TextureId, Textures};
use glam::Vec3;

/// What a surface of one material id emits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaEmission {
    /// Emitted radiance; with a texture, the texture's mean (the light's power estimate).
    pub radiance: Vec3,
    /// The texture the radiance comes from, evaluated where the surface is hit or sampled.
    pub texture: Option<TextureId>,
    /// Emits on both sides; otherwise only on the side of the geometric normal.
    pub two_sided: bool,
}

impl AreaEmission {
    /// Radiance towards a direction making cosine `cos_out` with the geometric normal, at the
    /// point whose surface data `at` gives (asked for only where a texture is evaluated).
    #[inline]
    pub fn emitted(&self, textures: &Textures, cos_out: f32, at: impl FnOnce() -> SurfacePoint) -> Vec3 {
        if !(self.two_sided || cos_out > 0.0) {
            return Vec3::ZERO;
        }
        match self.texture {
            None => self.radiance,
            // No mesh attributes: a material that reads one may not emit (checked at load), and
            // emitting meshes are baked into triangles of no mesh.
            Some(t) => textures.at(t, &at(), &[]).max(Vec3::ZERO),
        }
    }
}

/// The emission of every material id: an object's `emit` where it has one (`objects`, indexed
/// like `materials`), else the material's own (an emitter's radiance, textured where its
/// colour slot is).
pub fn emission_table(
    materials: &[Material],
    textures: &[MaterialTextures],
    objects: &[Option<AreaEmission>],
) -> Vec<Option<AreaEmission>> {
    (materials.iter().zip(textures).enumerate())
        .map(|(id, (m, t))| {
            objects.get(id).copied().flatten().or_else(|| {
                m.emission().map(|Emission { emit, two_sided, slot }| AreaEmission {
                    radiance: emit,
                    texture: t.colors[slot],
                    two_sided,
                })
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{diffuse_light::DiffuseLight, lambertian::Lambertian};
    use crate::texture::Texture;
    use glam::{Vec2, Vec3A};

    /// An emitter's radiance and its texture, an object's `emit` over a reflecting material,
    /// nothing for a plain reflector; one-sided emission is dark from behind.
    #[test]
    fn the_table_holds_emitters_and_objects_that_emit() {
        let lamp = Material::from(DiffuseLight { emit: Vec3::splat(0.5), two_sided: false });
        let white = Material::from(Lambertian { albedo: Vec3::ONE, two_sided: true });
        let textured = MaterialTextures { colors: [Some(1), None], ..Default::default() };
        let own = AreaEmission { radiance: Vec3::X, texture: Some(0), two_sided: false };
        let table = emission_table(
            &[lamp, white, white],
            &[textured, MaterialTextures::default(), MaterialTextures::default()],
            &[None, None, Some(own)],
        );
        assert_eq!(
            table[0],
            Some(AreaEmission { radiance: Vec3::splat(0.5), texture: Some(1), two_sided: false })
        );
        assert_eq!((table[1], table[2]), (None, Some(own)));
        let textures = Textures { list: vec![Texture::Solid(Vec3::new(2.0, -1.0, 3.0))] };
        let sp = SurfacePoint::flat(Vec3A::Z, Vec2::ZERO);
        assert_eq!(own.emitted(&textures, 0.5, || sp), Vec3::new(2.0, 0.0, 3.0));
        assert_eq!(own.emitted(&textures, -0.5, || sp), Vec3::ZERO);
        let both = AreaEmission { texture: None, two_sided: true, ..own };
        assert_eq!(both.emitted(&textures, -0.5, || unreachable!("no texture to evaluate")), Vec3::X);
    }
}
