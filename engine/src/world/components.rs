//! The components of scene entities and the resources of the scene world.

use crate::accel::geometry::Geometry;
use crate::accel::instances::Instances;
use crate::accel::mesh::{MeshBlas, MeshData};
use crate::lighting::area::AreaEmission;
use crate::lighting::lights::{LightTable, PunctualLight};
use crate::material::Material;
use crate::media::{Media, Medium};
use crate::placement::Form;
use crate::render_scene::{Background, RenderScene, RenderSettings};
use crate::scene::CameraDesc;
use crate::texture::{MaterialTextures, Textures};
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;
use glam::{Affine3A, Vec3};
use std::sync::Arc;

/// Object to world.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Transform(pub Affine3A);

/// The object-space shape of an entity.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct Shape(pub Form);

/// A medium filling the entity's (closed) shape; such entities have no [`MaterialId`] and are
/// not surfaces.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct Filling(pub Medium);

/// A medium whose grids are sequences (a file per frame): the system
/// [`read_grid_frames`](super::read_grid_frames) reads the files of the [`FrameNumber`] and
/// sets the entity's [`Filling`] from them.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct GridSequence(pub crate::scene::MediumDesc);

/// The files the [`Filling`] of a [`GridSequence`] entity was read from, with their hashes
/// (empty until a frame's are read).
#[derive(Component, Clone, Debug, Default, PartialEq)]
pub struct GridInputs(pub Vec<crate::format::files::InputFile>);

/// The frame whose files [`GridSequence`]s read (0 for a still).
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameNumber(pub u32);

/// How many grid files the [`GridSequence`]s have read.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GridReads(pub u64);

/// Linear motion: at time `t` the entity lies translated by `velocity * t`.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    /// World units per unit time.
    pub velocity: Vec3,
}

/// Marks a mesh entity drawn as an instance: its mesh's BLAS (one per mesh, shared by every
/// entity naming the same mesh) placed through the TLAS, instead of its triangles baked into
/// the primitive BVH. Scenes mark every mesh whose material does not emit; emitting meshes
/// stay primitives, so that light sampling finds their triangles. An instanced entity whose
/// shape is not a mesh is skipped (with an error).
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
pub struct Instanced;

/// Keyframed placement: the system [`animate_objects`](super::animate_objects) sets the entity's [`Transform`] and
/// [`Motion`] from it for the current [`FrameTime`].
#[derive(Component, Clone, Debug, PartialEq)]
pub struct Animated {
    /// The static transform the keyframed one is applied after.
    pub base: Affine3A,
    /// The keys.
    pub keys: crate::animation::ObjectAnimation,
    /// The object's own linear motion, added to the keyframed one.
    pub velocity: Vec3,
}

/// The shutter interval of the frame being rendered, in absolute seconds: rays sample times in
/// it and keyframes are evaluated in it. A still has the camera's shutter (frame time 0).
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct FrameTime {
    /// Shutter opens.
    pub open: f32,
    /// Shutter closes.
    pub close: f32,
}

/// Why this frame's scene is not the one the scene file asks for (an object moved or animated
/// beyond [`MAX_COORDINATE`](crate::shape::MAX_COORDINATE), an animated camera that the loader
/// would refuse): written by the systems of one update, read by the commands, which fail rather
/// than render it.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct FrameErrors(pub Vec<String>);

/// The camera as the scene file places it, and its keyframes.
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct CameraKeys {
    /// The camera without keyframes.
    pub base: CameraDesc,
    /// Its keyframes.
    pub keys: crate::animation::CameraAnimation,
}

/// Emitted radiance keyframes: (material id, keys).
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct EmitKeys(pub Vec<(u32, crate::animation::Track<Vec3>)>);

/// The entity's place in the scene file's `objects` (what [`SceneWorld::reload`](super::SceneWorld::reload) pairs).
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct ObjectIndex(pub u32);

/// Index into the [`Materials`] resource (a material's, or an emitting object's copy of it:
/// see [`ObjectEmission`]).
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialId(pub u32);

/// All materials.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct Materials(pub Vec<Material>);

/// The wrappers among the materials (indexed like [`Materials`]: see
/// [`crate::material::wrap`]).
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct MaterialWrappers(pub Arc<crate::material::wrap::Wrappers>);

/// The `emit` of objects, by the material id each was given (indexed like [`Materials`]; `None`
/// for the ids of the named materials).
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct ObjectEmission(pub Vec<Option<AreaEmission>>);

/// The camera as described (turned into a [`Camera`](crate::camera::Camera) for the image size at extraction), and,
/// when keyframes move it while the shutter is open, as it is at shutter close (the first is
/// then the camera at shutter open).
#[derive(Resource, Clone, Copy, Debug)]
pub struct CameraParams(pub CameraDesc, pub Option<CameraDesc>);

/// Image and sampling settings.
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct Settings(pub RenderSettings);

/// Light from outside.
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct BackgroundLight(pub Background);

/// The point, spot and directional lights.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct PunctualLights(pub Vec<PunctualLight>);

/// The light table, rebuilt by [`rebuild_lights`](super::rebuild_lights).
#[derive(Resource, Default)]
pub struct SceneLights {
    /// What next-event estimation samples.
    pub lights: Arc<LightTable>,
    /// How many times it was rebuilt.
    pub rebuilds: u64,
}

/// World-space primitives and BVH, rebuilt by [`rebuild_geometry`](super::rebuild_geometry).
#[derive(Resource, Default)]
pub struct SceneGeometry {
    /// Primitives and BVH.
    pub geometry: Arc<Geometry>,
    /// How many times the geometry was rebuilt (for tests and statistics).
    pub rebuilds: u64,
    /// The entities it was built from, sorted.
    pub entities: Vec<Entity>,
    /// For each primitive (in the geometry's order), the rank in `entities` of the object it
    /// belongs to.
    pub objects: Vec<u32>,
    /// For each primitive, its object's place in the scene file's `objects` ([`ObjectIndex`];
    /// `u32::MAX` for an object spawned without one).
    pub file_objects: Arc<Vec<u32>>,
    /// Why objects were left out of the last build: reported in [`FrameErrors`] by every
    /// update until a build has them back, not only by the one that left them out.
    pub left_out: Vec<String>,
}

/// The world-space media volumes, rebuilt by [`rebuild_media`](super::rebuild_media).
#[derive(Resource, Default)]
pub struct SceneMedia {
    /// The volumes.
    pub media: Arc<Media>,
    /// How many times they were rebuilt.
    pub rebuilds: u64,
    /// The entities they were built from, sorted.
    pub entities: Vec<Entity>,
    /// Why media were left out when last rebuilt (a transform that an animation made
    /// singular), reported again with every frame until they are rebuilt.
    pub left_out: Vec<String>,
}

/// The BLAS of every mesh that some instance uses, keyed by the mesh's address (each BLAS
/// holds its mesh, so the address stays taken while the entry lives).
#[derive(Resource, Default)]
pub struct MeshLibrary {
    pub(super) blas: std::collections::HashMap<usize, Arc<MeshBlas>>,
    /// How many BLAS were built.
    pub builds: u64,
}

impl MeshLibrary {
    /// Number of meshes held.
    pub fn len(&self) -> usize {
        self.blas.len()
    }

    /// True when no mesh is held.
    pub fn is_empty(&self) -> bool {
        self.blas.is_empty()
    }

    /// The BLAS of `mesh`, built the first time it is asked for.
    pub(super) fn get(&mut self, mesh: &Arc<MeshData>) -> Arc<MeshBlas> {
        let key = Arc::as_ptr(mesh) as usize;
        if let Some(b) = self.blas.get(&key) {
            return b.clone();
        }
        self.builds += 1;
        let b = Arc::new(MeshBlas::build(mesh.clone()));
        self.blas.insert(key, b.clone());
        b
    }

    /// Builds the BLAS of those of `meshes` not held yet, one mesh per rayon task (each as
    /// [`Self::get`] builds it), so that [`Self::get`] finds them: a scene's many small
    /// meshes are built side by side, where one at a time each build's own parallel steps
    /// left the cores waiting (200 meshes of 16k triangles: 1.04 s).
    pub(super) fn build_all<'a>(&mut self, meshes: impl IntoIterator<Item = &'a Arc<MeshData>>) {
        use rayon::prelude::*;
        let mut seen = std::collections::HashSet::new();
        let new: Vec<&Arc<MeshData>> = meshes
            .into_iter()
            .filter(|m| {
                let key = Arc::as_ptr(m) as usize;
                !self.blas.contains_key(&key) && seen.insert(key)
            })
            .collect();
        let built: Vec<MeshBlas> = new.par_iter().map(|&m| MeshBlas::build(m.clone())).collect();
        for (m, b) in new.into_iter().zip(built) {
            self.builds += 1;
            self.blas.insert(Arc::as_ptr(m) as usize, Arc::new(b));
        }
    }
}

/// Instances and their TLAS, kept by [`update_instances`](super::update_instances).
#[derive(Resource, Default)]
pub struct SceneInstances {
    /// The instances (index `i` is `entities[i]`).
    pub instances: Arc<Instances>,
    /// The instanced entities, sorted.
    pub entities: Vec<Entity>,
    /// How many times the TLAS was built.
    pub builds: u64,
    /// How many times it was refitted instead.
    pub refits: u64,
    /// Why instanced objects were left out of the last build (as [`SceneGeometry::left_out`]).
    pub left_out: Vec<String>,
}

/// The latest extracted scene.
#[derive(Resource, Default)]
pub struct Extracted(pub Option<Arc<RenderScene>>);

/// The per-frame update schedule.
#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
pub struct Update;

/// The scene's textures, and which material colours use them.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct SceneTextures {
    /// All textures.
    pub textures: Arc<Textures>,
    /// Per material (indexed like [`Materials`]): its textured colours.
    pub per_material: Vec<MaterialTextures>,
}
