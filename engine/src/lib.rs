//! pathwave's scene model.
//!
//! Data flows one way: a RON file is parsed into a validated [`scene::SceneDesc`], spawned into a
//! bevy_ecs [`world::SceneWorld`] (entities with `Transform`, `Shape` and `MaterialId`), and a
//! change-detected schedule rebuilds the BVH and the emitter table and extracts a flat, read-only
//! [`render_scene::RenderScene`] that integrators read without touching the ECS.
#![warn(missing_docs)]

pub mod accel;
pub mod animation;
pub mod camera;
pub mod filter;
pub mod format;
pub mod guiding;
pub mod lighting;
pub mod material;
pub mod math;
pub mod media;
pub mod placement;
pub mod render_scene;
pub mod scene;
pub mod shape;
pub mod simd;
pub mod texture;
pub mod world;

/// Helpers shared by the unit tests.
#[cfg(test)]
mod testing {
    /// Deterministic numbers in [0, 1) (xorshift32 from `s`, which must not be 0).
    pub fn uniform(mut s: u32) -> impl FnMut() -> f32 {
        move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s as f32 / u32::MAX as f32
        }
    }

    /// Deterministic numbers in [-1, 1).
    pub fn signed(s: u32) -> impl FnMut() -> f32 {
        let mut u = uniform(s);
        move || u() * 2.0 - 1.0
    }

    /// A material description written as a scene writes it (RON, implicit `Some`).
    pub fn material_desc(text: &str) -> Result<crate::material::MaterialDesc, String> {
        ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
            .from_str::<crate::material::MaterialDesc>(text)
            .map_err(|e| e.to_string())
    }

    /// The material of a description that names no texture.
    pub fn material(text: &str) -> crate::material::Material {
        let desc = material_desc(text).unwrap();
        crate::material::Material::build(&desc, &mut |_| unreachable!("no textures")).0
    }

    /// Points about the plane z = 0 for light samplers of shapes in it, the `k`-th of a series:
    /// from 1e-5 to 1e3 across and away, a quarter exactly on the plane and a quarter within
    /// 1e-6 of it; the height is also returned (to place points above a vertex).
    pub fn near_plane(k: i32, rng: &mut impl FnMut() -> f32) -> (glam::Vec3A, f32) {
        let scale = 10f32.powi(k % 9 - 5);
        let z = match k % 4 {
            0 => 0.0,
            1 => rng() * 1e-6,
            _ => rng() * scale,
        };
        (glam::Vec3A::new(rng() * 2.0 * scale, rng() * 2.0 * scale, z), z)
    }
}
