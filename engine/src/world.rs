//! The ECS scene: entities with `Transform`, `Shape` and `MaterialId`; systems that rebuild the
//! geometry (BVH and emitter table) only when what it depends on changed, and extract the
//! [`RenderScene`].

use crate::camera::Camera;
use crate::environment::EnvironmentMap;
use crate::geometry::{Geometry, Primitive};
use crate::instances::{Instance, Instances, ShutterMotion};
use crate::lights::{LightInputs, LightTable, PunctualLight};
use crate::material::Material;
use crate::media::{Boundary, Media, Medium, Volume};
use crate::mesh::{MeshBlas, MeshData};
use crate::render_scene::{Background, Features, PixelWindow, RenderScene, RenderSettings};
use crate::scene::{
    BackgroundDesc, Body, CameraDesc, Color, MaterialDesc, Positive, Rgb, SceneDesc, ShapeDesc, TextureDesc,
    compose,
};
use crate::shape::{Quad, Sphere, TransformedSphere, Triangle};
use crate::texture::{MaterialTextures, NoiseKind, Texture, TextureId, Textures};
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;
use glam::{Affine3A, Vec3, Vec3A};
use std::sync::Arc;

/// Object to world.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Transform(pub Affine3A);

/// The object-space shape of an entity.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct Shape(pub ShapeDesc);

/// A homogeneous medium filling the entity's (closed) shape; such entities have no
/// [`MaterialId`] and are not surfaces.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Filling(pub Medium);

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

/// Keyframed placement: the system [`animate_objects`] sets the entity's [`Transform`] and
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

/// Places keyframed objects for the frame's shutter: rotation and scale as at mid-shutter,
/// translation moving linearly from its position at shutter open to the one at shutter close
/// (as a [`Motion`], so rays see it at their own time). Components are written only when they
/// change, so a frame that moves nothing rebuilds nothing.
pub fn animate_objects(
    time: Res<FrameTime>,
    mut objects: Query<(Ref<Animated>, &mut Transform, &mut Motion)>,
) {
    for (anim, mut transform, mut motion) in &mut objects {
        if !(time.is_changed() || anim.is_changed()) {
            continue;
        }
        let at = |t: f32| anim.keys.at(t) * anim.base;
        let (t0, t1) = (time.open, time.close);
        let mid = at(0.5 * (t0 + t1));
        let (p0, p1) = (at(t0).translation, at(t1).translation);
        let v = if t1 > t0 { (p1 - p0) / (t1 - t0) } else { Vec3A::ZERO };
        // At time t the object is at p0 + v (t - t0) (plus its own motion, v_own t).
        let placed = Affine3A { matrix3: mid.matrix3, translation: p0 - v * t0 };
        let velocity = Vec3::from(v) + anim.velocity;
        transform.set_if_neq(Transform(placed));
        motion.set_if_neq(Motion { velocity });
    }
}

/// Sets the camera for the frame: keyframes at mid-shutter, shutter = the frame's.
pub fn animate_camera(time: Res<FrameTime>, keys: Res<CameraKeys>, mut camera: ResMut<CameraParams>) {
    if !(time.is_changed() || keys.is_changed()) {
        return;
    }
    let at = |t: f32| {
        let mut c = keys.base;
        let k = &keys.keys;
        if let Some(k) = &k.look_from {
            c.look_from = k.at(t);
        }
        if let Some(k) = &k.look_at {
            c.look_at = k.at(t);
        }
        if let Some(k) = &k.vfov {
            c.vfov = k.at(t).clamp(1e-3, 179.0);
        }
        if let Some(k) = &k.focus_dist {
            c.focus_dist = k.at(t).max(1e-6);
        } else if k.look_from.is_some() || k.look_at.is_some() {
            // The default focus distance follows the target.
            c.focus_dist = (c.look_at - c.look_from).length();
        }
        c.shutter = (time.open, time.close);
        c
    };
    // A camera that moves while the shutter is open: its poses at open and close, between
    // which camera rays interpolate.
    let (open, close) = (at(time.open), at(time.close));
    let next = if same_camera(&open, &close) {
        (at(0.5 * (time.open + time.close)), None)
    } else {
        (open, Some(close))
    };
    let same = same_camera(&camera.0, &next.0)
        && match (&camera.1, &next.1) {
            (Some(a), Some(b)) => same_camera(a, b),
            (a, b) => a.is_none() && b.is_none(),
        };
    if !same {
        (camera.0, camera.1) = next;
    }
}

fn same_camera(a: &CameraDesc, b: &CameraDesc) -> bool {
    (a.look_from, a.look_at, a.vup, a.vfov, a.aperture_radius, a.focus_dist, a.shutter)
        == (b.look_from, b.look_at, b.vup, b.vfov, b.aperture_radius, b.focus_dist, b.shutter)
}

/// Sets keyframed emitted radiance for the frame (at mid-shutter).
pub fn animate_emission(time: Res<FrameTime>, keys: Res<EmitKeys>, mut materials: ResMut<Materials>) {
    if !time.is_changed() || keys.0.is_empty() {
        return;
    }
    let t = 0.5 * (time.open + time.close);
    let mut changed = false;
    for (id, track) in &keys.0 {
        let new = track.at(t).max(Vec3::ZERO);
        let m = &mut materials.bypass_change_detection().0[*id as usize];
        if m.emission().is_some_and(|e| e.emit != new) {
            m.set_emission(new);
            changed = true;
        }
    }
    if changed {
        materials.set_changed();
    }
}

/// The entity's place in the scene file's `objects` (what [`SceneWorld::reload`] pairs).
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct ObjectIndex(pub u32);

/// Index into the [`Materials`] resource.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialId(pub u32);

/// All materials.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct Materials(pub Vec<Material>);

/// The camera as described (turned into a [`Camera`] for the image size at extraction), and,
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

/// The light table, rebuilt by [`rebuild_lights`].
#[derive(Resource, Default)]
pub struct SceneLights {
    /// What next-event estimation samples.
    pub lights: Arc<LightTable>,
    /// How many times it was rebuilt.
    pub rebuilds: u64,
}

/// World-space primitives and BVH, rebuilt by [`rebuild_geometry`].
#[derive(Resource, Default)]
pub struct SceneGeometry {
    /// Primitives and BVH.
    pub geometry: Arc<Geometry>,
    /// How many times the geometry was rebuilt (for tests and statistics).
    pub rebuilds: u64,
    /// The entities it was built from, sorted.
    pub entities: Vec<Entity>,
}

/// The world-space media volumes, rebuilt by [`rebuild_media`].
#[derive(Resource, Default)]
pub struct SceneMedia {
    /// The volumes.
    pub media: Arc<Media>,
    /// How many times they were rebuilt.
    pub rebuilds: u64,
    /// The entities they were built from, sorted.
    pub entities: Vec<Entity>,
}

/// The BLAS of every mesh that some instance uses, keyed by the mesh's address (each BLAS
/// holds its mesh, so the address stays taken while the entry lives).
#[derive(Resource, Default)]
pub struct MeshLibrary {
    blas: std::collections::HashMap<usize, Arc<MeshBlas>>,
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
    fn get(&mut self, mesh: &Arc<MeshData>) -> Arc<MeshBlas> {
        let key = Arc::as_ptr(mesh) as usize;
        if let Some(b) = self.blas.get(&key) {
            return b.clone();
        }
        self.builds += 1;
        let b = Arc::new(MeshBlas::build(mesh.clone()));
        self.blas.insert(key, b.clone());
        b
    }
}

/// Instances and their TLAS, kept by [`update_instances`].
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
}

/// The latest extracted scene.
#[derive(Resource, Default)]
pub struct Extracted(pub Option<Arc<RenderScene>>);

/// The per-frame update schedule.
#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
pub struct Update;

/// Rebuilds primitives and BVH when a shape, transform, material id or motion changed, an
/// object or its motion was removed, or, in scenes with motion, the camera (its shutter bounds
/// the sweeps).
#[allow(clippy::type_complexity)]
#[allow(clippy::too_many_arguments)]
pub fn rebuild_geometry(
    mut out: ResMut<SceneGeometry>,
    objects: Query<(Entity, &Transform, &Shape, &MaterialId, Option<&Motion>), Without<Instanced>>,
    changed: Query<
        (),
        (
            With<MaterialId>,
            Without<Instanced>,
            Or<(Changed<Transform>, Changed<Shape>, Changed<MaterialId>, Changed<Motion>)>,
        ),
    >,
    now_instanced: Query<Entity, Added<Instanced>>,
    mut removed_shape: RemovedComponents<Shape>,
    mut removed_material: RemovedComponents<MaterialId>,
    mut stopped: RemovedComponents<Motion>,
    mut not_instanced: RemovedComponents<Instanced>,
    camera: Res<CameraParams>,
) {
    // Only removals from entities the geometry was built from matter (not from volumes or
    // instances); an entity that stops being an instance joins.
    let was_built_from = |e: Entity| out.entities.binary_search(&e).is_ok();
    let removed = removed_shape
        .read()
        .chain(removed_material.read())
        .chain(stopped.read())
        .chain(now_instanced.iter())
        .any(was_built_from)
        | not_instanced.read().any(|e| objects.contains(e));
    // The shutter bounds the sweep of moving objects.
    let moving = out.geometry.velocity.is_some();
    if !(removed || !changed.is_empty() || (moving && camera.is_changed()) || out.rebuilds == 0) {
        return;
    }
    let _span = tracing::info_span!("rebuild_geometry").entered();
    let start = std::time::Instant::now();
    let mut objs: Vec<_> = objects.iter().collect();
    objs.sort_by_key(|(e, ..)| *e);
    out.entities = objs.iter().map(|(e, ..)| *e).collect();
    let (mut prims, mut mats, mut velocity) = (Vec::new(), Vec::new(), Vec::new());
    for (_, transform, shape, material, motion) in objs {
        // Scene files are validated at load; objects spawned by code may still be bad.
        if let Err(e) = world_primitives(&shape.0, &transform.0, &mut prims) {
            tracing::error!("object skipped: {e}");
        }
        mats.resize(prims.len(), material.0);
        velocity.resize(prims.len(), motion.map_or(Vec3A::ZERO, |m| m.velocity.into()));
    }
    let geometry = Geometry::build_moving(prims, mats, velocity, camera.0.shutter);
    tracing::info!(
        primitives = geometry.prims.len(),
        moving = geometry.velocity.is_some(),
        "primitives' BVH built in {:.2} ms",
        start.elapsed().as_secs_f64() * 1e3
    );
    out.geometry = Arc::new(geometry);
    out.rebuilds += 1;
}

/// Keeps the instances: the TLAS is rebuilt when instances come or go or change mesh or
/// material (building the BLAS of a mesh no instance used before), refitted when they only
/// move (or rebuilt when refitting made it much worse), and left alone otherwise. A BLAS is
/// built once per mesh, whatever happens to the instances.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
pub fn update_instances(
    mut out: ResMut<SceneInstances>,
    mut library: ResMut<MeshLibrary>,
    objects: Query<
        (Entity, &Transform, &Shape, &MaterialId, Option<&Motion>, Option<&Animated>),
        With<Instanced>,
    >,
    reshaped: Query<(), (With<Instanced>, Or<(Added<Instanced>, Changed<Shape>, Changed<MaterialId>)>)>,
    moved: Query<Entity, (With<Instanced>, Or<(Changed<Transform>, Changed<Motion>)>)>,
    mut removed_shape: RemovedComponents<Shape>,
    mut removed_material: RemovedComponents<MaterialId>,
    mut removed: RemovedComponents<Instanced>,
    mut stopped: RemovedComponents<Motion>,
    camera: Res<CameraParams>,
    time: Res<FrameTime>,
) {
    // Keyframed instances that turn or scale while the shutter is open are placed per ray
    // time; translation alone is the exact linear motion of `Motion`.
    let shutter_motion = |anim: Option<&Animated>| -> Option<ShutterMotion> {
        let a = anim?;
        let (t0, t1) = (time.open, time.close);
        let (a0, a1) = (a.keys.at(t0), a.keys.at(t1));
        if !(t1 > t0) || a0.matrix3 == a1.matrix3 {
            return None;
        }
        let v = Vec3A::from(a.velocity);
        let a0 = Affine3A { translation: a0.translation + v * t0, ..a0 };
        let a1 = Affine3A { translation: a1.translation + v * t1, ..a1 };
        ShutterMotion::new(a.base, a0, a1, (t0, t1))
    };
    let was_built_from = |e: Entity| out.entities.binary_search(&e).is_ok();
    let gone = removed_shape.read().chain(removed_material.read()).chain(removed.read()).any(was_built_from);
    let stopped: Vec<Entity> = stopped.read().filter(|e| was_built_from(*e)).collect();
    let moving = out.instances.list.iter().any(|i| i.velocity != Vec3A::ZERO || i.motion.is_some());
    let velocity = |m: Option<&Motion>| m.map_or(Vec3A::ZERO, |m| m.velocity.into());
    if gone || !reshaped.is_empty() || out.builds == 0 {
        let _span = tracing::info_span!("rebuild_instances").entered();
        let start = std::time::Instant::now();
        let mut objs: Vec<_> = objects.iter().collect();
        objs.sort_by_key(|(e, ..)| *e);
        let (mut blas, mut list, mut entities) = (Vec::<Arc<MeshBlas>>::new(), Vec::new(), Vec::new());
        for (e, transform, shape, material, motion, anim) in objs {
            let ShapeDesc::Mesh(file) = &shape.0 else {
                tracing::error!("instance skipped: only meshes are instanced");
                continue;
            };
            let b = library.get(&file.mesh);
            let index = match blas.iter().position(|x| Arc::ptr_eq(x, &b)) {
                Some(i) => i,
                None => {
                    blas.push(b);
                    blas.len() - 1
                }
            };
            match Instance::new(index as u32, transform.0, material.0, velocity(motion)) {
                Some(inst) => {
                    list.push(inst.with_motion(shutter_motion(anim)));
                    entities.push(e);
                }
                None => tracing::error!("instance skipped: its transform is singular"),
            }
        }
        // Meshes no instance uses any more are dropped.
        library.blas.retain(|_, b| blas.iter().any(|x| Arc::ptr_eq(x, b)));
        out.instances = Arc::new(Instances::build(blas, list, camera.0.shutter));
        if !out.instances.list.is_empty() {
            tracing::info!(
                instances = out.instances.list.len(),
                meshes = out.instances.blas.len(),
                "instances' TLAS built in {:.2} ms (BLAS of new meshes included)",
                start.elapsed().as_secs_f64() * 1e3
            );
        }
        out.entities = entities;
        out.builds += 1;
        return;
    }
    // A new shutter changes the sweep of whatever moves: a refit covers it.
    let new_shutter = moving && camera.is_changed();
    if moved.is_empty() && stopped.is_empty() && !new_shutter {
        return;
    }
    let _span = tracing::info_span!("move_instances").entered();
    let start = std::time::Instant::now();
    let out = &mut *out;
    let instances = Arc::make_mut(&mut out.instances);
    instances.shutter = camera.0.shutter;
    for e in moved.iter().chain(stopped) {
        let Ok(i) = out.entities.binary_search(&e) else { continue };
        let Ok((_, transform, _, _, motion, anim)) = objects.get(e) else { continue };
        if !instances.place(i, transform.0, velocity(motion), shutter_motion(anim)) {
            tracing::error!("instance not moved: its new transform is singular");
        }
    }
    let how = if instances.refit() {
        out.refits += 1;
        "refitted"
    } else {
        *instances = Instances::build(instances.blas.clone(), instances.list.clone(), camera.0.shutter);
        out.builds += 1;
        "rebuilt (a refit would have loosened it too much)"
    };
    tracing::info!(
        instances = instances.list.len(),
        "instances' TLAS {how} in {:.2} ms",
        start.elapsed().as_secs_f64() * 1e3
    );
}

/// Rebuilds the media volumes when a medium, or the shape or transform of an entity with one,
/// changed or was removed.
#[allow(clippy::type_complexity)]
pub fn rebuild_media(
    mut out: ResMut<SceneMedia>,
    volumes: Query<(Entity, &Transform, &Shape, &Filling)>,
    changed: Query<(), (With<Filling>, Or<(Changed<Transform>, Changed<Shape>, Changed<Filling>)>)>,
    mut removed_shape: RemovedComponents<Shape>,
    mut removed: RemovedComponents<Filling>,
) {
    let was_built_from = |e: Entity| out.entities.binary_search(&e).is_ok();
    let removed = removed_shape.read().chain(removed.read()).any(was_built_from);
    if !(removed || !changed.is_empty() || out.rebuilds == 0) {
        return;
    }
    let _span = tracing::info_span!("rebuild_media").entered();
    let mut vols: Vec<_> = volumes.iter().collect();
    vols.sort_by_key(|(e, ..)| *e);
    out.entities = vols.iter().map(|(e, ..)| *e).collect();
    let volumes = vols
        .into_iter()
        .filter_map(|(_, transform, shape, filling)| {
            let boundary = match &shape.0 {
                ShapeDesc::Mesh(file) => {
                    if let Some((a, b, _)) = crate::scene::open_edge(&file.mesh) {
                        tracing::error!("medium skipped: its mesh is open at the edge {a} - {b}");
                        return None;
                    }
                    Boundary::Mesh(Arc::new(MeshBlas::build(file.mesh.clone())))
                }
                &ShapeDesc::Sphere { center, radius } => Boundary::Sphere { center: center.into(), radius },
                &ShapeDesc::Box { min, max } => Boundary::Box { min: min.into(), max: max.into() },
                ShapeDesc::Quad { .. } | ShapeDesc::Triangle { .. } => {
                    tracing::error!("medium skipped: a quad or triangle bounds no volume");
                    return None;
                }
            };
            Some(Volume { object_from_world: transform.0.inverse(), boundary, medium: filling.0 })
        })
        .collect();
    out.media = Arc::new(Media { volumes });
    out.rebuilds += 1;
}

/// Rebuilds the light table when the primitives, the instances (they bound the scene), the
/// materials (which emit), the punctual lights or the background changed.
pub fn rebuild_lights(
    mut out: ResMut<SceneLights>,
    geometry: Res<SceneGeometry>,
    instances: Res<SceneInstances>,
    materials: Res<Materials>,
    punctual: Res<PunctualLights>,
    background: Res<BackgroundLight>,
) {
    let any = geometry.is_changed()
        || instances.is_changed()
        || materials.is_changed()
        || punctual.is_changed()
        || background.is_changed();
    if !any && out.rebuilds > 0 {
        return;
    }
    let geo = &geometry.geometry;
    let inst = &instances.instances;
    let boxes =
        (geo.prims.iter().map(|p| p.aabb())).chain((0..inst.list.len()).map(|i| inst.world_bounds(i)));
    let bounds = boxes.fold(None, |acc: Option<(Vec3A, Vec3A)>, b| {
        let (lo, hi) = (b.min, b.max);
        Some(acc.map_or((lo, hi), |(a, c)| (a.min(lo), c.max(hi))))
    });
    let inputs = LightInputs { punctual: &punctual.0, environment: background.0.is_sampled(), bounds };
    out.lights = Arc::new(LightTable::build(geo, &materials.0, inputs));
    out.rebuilds += 1;
    tracing::info!(lights = out.lights.len(), "light table built");
}

/// Builds a new [`RenderScene`] when anything it holds changed.
#[allow(clippy::too_many_arguments)]
pub fn extract_render_scene(
    geometry: Res<SceneGeometry>,
    instances: Res<SceneInstances>,
    lights: Res<SceneLights>,
    media: Res<SceneMedia>,
    textures: Res<SceneTextures>,
    materials: Res<Materials>,
    camera: Res<CameraParams>,
    settings: Res<Settings>,
    background: Res<BackgroundLight>,
    mut out: ResMut<Extracted>,
) {
    let any = geometry.is_changed()
        || instances.is_changed()
        || lights.is_changed()
        || media.is_changed()
        || textures.is_changed()
        || materials.is_changed()
        || camera.is_changed()
        || settings.is_changed()
        || background.is_changed();
    if !any && out.0.is_some() {
        return;
    }
    let s = settings.0;
    let make = |c: &CameraDesc| {
        let (from, at, up) = (c.look_from, c.look_at, c.vup);
        Camera::new(from, at, up, c.vfov, c.aperture_radius, c.focus_dist, c.shutter, s.width, s.height)
    };
    let camera = match &camera.1 {
        Some(close) => make(&camera.0).moving_to(&make(close)),
        None => make(&camera.0),
    };
    out.0 = Some(Arc::new(RenderScene {
        features: Features::detect(&geometry.geometry, &instances.instances, &media.media, &camera)
            .with_textures(&geometry.geometry, &instances.instances, &textures.per_material),
        camera,
        settings: s,
        background: background.0.clone(),
        materials: materials.0.clone(),
        geometry: geometry.geometry.clone(),
        instances: instances.instances.clone(),
        lights: lights.lights.clone(),
        media: media.media.clone(),
        textures: textures.textures.clone(),
        material_textures: textures.per_material.clone(),
    }));
}

/// How far from the origin anything may lie, in world units. Beyond it the BVH's surface-area
/// arithmetic (extent squared times primitive count) overflows `f32`.
pub const MAX_COORDINATE: f32 = 1e15;

/// Why a placed shape cannot be rendered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ShapeError {
    /// A triangle whose corners are collinear.
    #[error("a triangle {0}, {1}, {2} has no area")]
    FlatTriangle(Vec3A, Vec3A, Vec3A),
    /// A quad whose edges are parallel (or tiny).
    #[error("a quad with edges {0} and {1} has no area (or less than 1e-38)")]
    FlatQuad(Vec3A, Vec3A),
    /// A sphere under a singular transform.
    #[error("the transform flattens the sphere")]
    FlatSphere,
    /// Coordinates beyond [`MAX_COORDINATE`].
    #[error("the object reaches beyond {MAX_COORDINATE:e} units from the origin")]
    TooFar,
}

/// Appends the world-space primitives of `shape` placed by `m`; an error says why the placed
/// shape cannot be rendered (a quad or ellipsoid flattened to nothing, or coordinates beyond
/// [`MAX_COORDINATE`]). Scene files are checked with it at load.
pub fn world_primitives(shape: &ShapeDesc, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
    let start = out.len();
    match *shape {
        ShapeDesc::Mesh(ref mesh) => {
            let world: Vec<Vec3A> = mesh.mesh.positions.iter().map(|&p| m.transform_point3a(p)).collect();
            let mirrored = m.matrix3.determinant() < 0.0;
            for &[a, b, c] in mesh.mesh.triangles.iter() {
                let [a, b, c] = [a, b, c].map(|i| world[i as usize]);
                let (b, c) = if mirrored { (c, b) } else { (b, c) };
                // Triangles without area cannot be hit: meshes often hold a few; drop them.
                if let Some(t) = Triangle::new(a, b, c) {
                    out.push(Primitive::Triangle(t));
                }
            }
        }
        ShapeDesc::Sphere { center, radius } => {
            let sphere = Sphere { center: center.into(), radius };
            // Translation and uniform scale keep a sphere a sphere (and its uv frame); anything
            // else is intersected in object space.
            let lin = m.matrix3;
            let s = lin.x_axis.x;
            let diagonal_uniform = s > 0.0 && lin == glam::Mat3A::from_diagonal(Vec3::splat(s));
            if diagonal_uniform {
                let center = m.transform_point3a(sphere.center);
                out.push(Primitive::Sphere(Sphere { center, radius: radius * s }));
            } else {
                let ts = TransformedSphere::new(sphere, *m).ok_or(ShapeError::FlatSphere)?;
                out.push(Primitive::TransformedSphere(ts));
            }
        }
        ShapeDesc::Quad { q, u, v } => push_quad(m, q.into(), u.into(), v.into(), out)?,
        ShapeDesc::Triangle { a, b, c } => {
            let [a, b, c] = [a, b, c].map(|p| m.transform_point3a(p.into()));
            // A mirroring transform flips the winding; keep the normal facing the same side.
            let (b, c) = if m.matrix3.determinant() < 0.0 { (c, b) } else { (b, c) };
            let t = Triangle::new(a, b, c).ok_or(ShapeError::FlatTriangle(a, b, c))?;
            out.push(Primitive::Triangle(t));
        }
        ShapeDesc::Box { min, max } => {
            let (a, b) = (Vec3A::from(min), Vec3A::from(max));
            let d = b - a;
            let (dx, dy, dz) = (Vec3A::X * d.x, Vec3A::Y * d.y, Vec3A::Z * d.z);
            push_quad(m, Vec3A::new(a.x, a.y, b.z), dx, dy, out)?; // front (+z)
            push_quad(m, Vec3A::new(b.x, a.y, b.z), -dz, dy, out)?; // right (+x)
            push_quad(m, Vec3A::new(b.x, a.y, a.z), -dx, dy, out)?; // back (-z)
            push_quad(m, a, dz, dy, out)?; // left (-x)
            push_quad(m, Vec3A::new(a.x, b.y, b.z), dx, -dz, out)?; // top (+y)
            push_quad(m, a, dx, dz, out)?; // bottom (-y)
        }
    }
    let far = out[start..].iter().map(Primitive::aabb).any(|b| {
        let m = b.min.abs().max(b.max.abs()).max_element();
        !(m <= MAX_COORDINATE)
    });
    if far {
        out.truncate(start);
        return Err(ShapeError::TooFar);
    }
    Ok(())
}

/// A box or a quad as a triangle mesh in its own space (two triangles per face, uvs as the
/// quads'); `None` for other shapes.
fn flat_mesh(shape: &ShapeDesc) -> Option<MeshData> {
    if !matches!(shape, ShapeDesc::Box { .. } | ShapeDesc::Quad { .. }) {
        return None;
    }
    let mut quads = Vec::new();
    world_primitives(shape, &Affine3A::IDENTITY, &mut quads).ok()?;
    let mut mesh = MeshData { uvs: Some(Vec::new()), ..Default::default() };
    for p in quads {
        let Primitive::Quad(q) = p else { return None };
        let base = mesh.positions.len() as u32;
        mesh.positions.extend([q.q, q.q + q.u, q.q + q.u + q.v, q.q + q.v]);
        mesh.uvs.as_mut()?.extend([glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::ONE, glam::Vec2::Y]);
        mesh.triangles.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
    }
    Some(mesh)
}

fn push_quad(m: &Affine3A, q: Vec3A, u: Vec3A, v: Vec3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
    let (q, mut u, mut v) = (m.transform_point3a(q), m.transform_vector3a(u), m.transform_vector3a(v));
    // A mirroring transform flips u x v; swap the edges so the normal keeps facing out.
    if m.matrix3.determinant() < 0.0 {
        std::mem::swap(&mut u, &mut v);
    }
    let quad = Quad::new(q, u, v).ok_or(ShapeError::FlatQuad(u, v))?;
    out.push(Primitive::Quad(quad));
    Ok(())
}

/// The scene's textures, and which material colours use them.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct SceneTextures {
    /// All textures.
    pub textures: Arc<Textures>,
    /// Per material (indexed like [`Materials`]): its textured colours.
    pub per_material: Vec<MaterialTextures>,
}

/// Builds the runtime textures: the named ones keep their indices in file order; colours
/// written inline inside them (checker squares) become solid textures after them.
fn build_textures(desc: &SceneDesc) -> Textures {
    let n = desc.textures.0.len() as TextureId;
    let mut inline = Vec::new();
    let mut sub = |c: &Color<Rgb>| match c {
        Color::Texture(name) => texture_id(desc, name),
        Color::Value(v) => {
            inline.push(Texture::Solid(v.0));
            n + inline.len() as TextureId - 1
        }
    };
    let noise = |kind, scale: &Positive, depth, color: &Rgb| Texture::Noise {
        kind,
        scale: scale.0,
        depth,
        color: color.0,
    };
    let mut list: Vec<Texture> = desc
        .textures
        .0
        .iter()
        .map(|(_, t)| match t {
            TextureDesc::Solid(c) => Texture::Solid(c.0),
            TextureDesc::Checker { scale, even, odd } => {
                Texture::Checker { scale: scale.0, even: sub(even), odd: sub(odd) }
            }
            TextureDesc::UvChecker { u, v, even, odd } => {
                Texture::UvChecker { u: u.0, v: v.0, even: sub(even), odd: sub(odd) }
            }
            TextureDesc::Image { file, wrap } => Texture::Image { image: file.image.clone(), wrap: *wrap },
            TextureDesc::Noise { scale, color } => noise(NoiseKind::Smooth, scale, 0, color),
            TextureDesc::BlockyNoise { scale, color } => noise(NoiseKind::Blocky, scale, 0, color),
            TextureDesc::Turbulence { scale, depth, color } => {
                noise(NoiseKind::Turbulence, scale, *depth, color)
            }
            TextureDesc::Marble { scale, depth, color } => noise(NoiseKind::Marble, scale, *depth, color),
        })
        .collect();
    list.extend(inline);
    Textures { list }
}

/// The index of a named texture.
fn texture_id(desc: &SceneDesc, name: &str) -> TextureId {
    desc.textures.0.iter().position(|(n, _)| n == name).expect("texture names are validated at load")
        as TextureId
}

/// A material's parameters (textured colours hold the texture's mean) and its textures.
fn material(desc: &SceneDesc, m: &MaterialDesc, textures: &Textures) -> (Material, MaterialTextures) {
    Material::build(m, &mut |name| {
        let id = texture_id(desc, name);
        (id, textures.mean(id))
    })
}

/// A bevy_ecs world holding a scene, with its update schedule.
pub struct SceneWorld {
    /// The ECS world (entities and resources); edit it between calls to [`Self::update`].
    pub world: World,
    schedule: Schedule,
}

impl SceneWorld {
    /// Spawns the entities and resources of a scene description.
    pub fn new(desc: &SceneDesc) -> Self {
        let mut world = World::new();
        let names: Vec<&str> = desc.materials.iter().map(|(n, _)| n.as_str()).collect();
        let textures = build_textures(desc);
        let (mats, per_material): (Vec<Material>, _) =
            desc.materials.iter().map(|(_, m)| material(desc, m, &textures)).unzip();
        let emits = |id: usize| mats[id].is_emissive();
        // Boxes and quads whose keyframes turn or scale them become meshes, so that they blur
        // by their motion over the shutter as instances do (not at their mid-shutter pose).
        let shapes: Vec<ShapeDesc> = desc
            .objects
            .iter()
            .map(|o| {
                let turns = o.animate.as_ref().is_some_and(|a| a.rotate.is_some() || a.scale.is_some());
                let surface = matches!(&o.body, Body::Surface(name)
                    if !emits(names.iter().position(|n| *n == name.0).expect("validated")));
                match (turns && surface).then(|| flat_mesh(&o.shape)).flatten() {
                    Some(mesh) => ShapeDesc::Mesh(crate::scene::MeshFile {
                        path: "<keyframed shape>".into(),
                        mesh: Arc::new(mesh),
                    }),
                    None => o.shape.clone(),
                }
            })
            .collect();
        let instanced: Vec<bool> = desc
            .objects
            .iter()
            .zip(&shapes)
            .map(|(o, shape)| match (shape, &o.body) {
                (ShapeDesc::Mesh(_), Body::Surface(name)) => {
                    !emits(names.iter().position(|n| *n == name.0).expect("validated"))
                }
                _ => false,
            })
            .collect();
        world.insert_resource(Materials(mats));
        world.insert_resource(SceneTextures { textures: Arc::new(textures), per_material });
        for (i, ((obj, instanced), shape)) in desc.objects.iter().zip(instanced).zip(shapes).enumerate() {
            let placed = (Transform(compose(&obj.transform)), Shape(shape), ObjectIndex(i as u32));
            match &obj.body {
                Body::Surface(name) => {
                    let id = names
                        .iter()
                        .position(|n| *n == name.0)
                        .expect("material names are validated at load");
                    let mut e = world.spawn((placed, MaterialId(id as u32)));
                    let velocity = obj.motion.map_or(Vec3::ZERO, |m| m.velocity.0);
                    if obj.motion.is_some() || obj.animate.is_some() {
                        e.insert(Motion { velocity });
                    }
                    if let Some(keys) = &obj.animate {
                        e.insert(Animated { base: compose(&obj.transform), keys: keys.clone(), velocity });
                    }
                    if instanced {
                        e.insert(Instanced);
                    }
                }
                Body::Volume(m) => {
                    world.spawn((placed, Filling(Medium { sigma_t: m.density.0, albedo: m.albedo.0 })));
                }
            }
        }
        let r = desc.render;
        let (width, height) = (r.width.get(), r.height.get());
        let whole = PixelWindow { x0: 0, y0: 0, w: width, h: height };
        // A window too small to hold a pixel at this size (the CLI refuses it first) falls
        // back to the whole image.
        let window = r.crop.and_then(|c| PixelWindow::crop(width, height, c.0)).unwrap_or(whole);
        world.insert_resource(Settings(RenderSettings {
            width,
            height,
            window,
            spp: r.spp.get(),
            max_depth: r.max_depth,
            rr_depth: r.rr_depth,
            seed: r.seed,
            clamp: r.clamp.map(|c| c.0),
            sampler: r.sampler,
        }));
        world.insert_resource(CameraParams(desc.camera, None));
        world.insert_resource(FrameTime { open: desc.camera.shutter.0, close: desc.camera.shutter.1 });
        world.insert_resource(CameraKeys { base: desc.camera, keys: desc.animation.camera.clone() });
        let emit_keys = desc
            .animation
            .emit
            .iter()
            .map(|(name, track)| {
                let id =
                    names.iter().position(|n| *n == name.0).expect("material names are validated at load");
                (id as u32, track.0.clone())
            })
            .collect();
        world.insert_resource(EmitKeys(emit_keys));
        world.insert_resource(BackgroundLight(match &desc.background {
            BackgroundDesc::Black => Background::Constant(Vec3::ZERO),
            BackgroundDesc::Constant(c) => Background::Constant(c.0),
            BackgroundDesc::Sky { bottom, top } => Background::Sky { bottom: bottom.0, top: top.0 },
            BackgroundDesc::Environment { file, scale, rotate } => {
                let img = &file.image;
                let texels = img.texels.clone();
                Background::Environment(Arc::new(EnvironmentMap::new(
                    img.width, img.height, texels, scale.0, rotate.0,
                )))
            }
        }));
        world.insert_resource(PunctualLights(desc.lights.iter().map(|l| l.to_light()).collect()));
        world.init_resource::<SceneLights>();
        world.init_resource::<SceneGeometry>();
        world.init_resource::<SceneInstances>();
        world.init_resource::<MeshLibrary>();
        world.init_resource::<SceneMedia>();
        world.init_resource::<Extracted>();
        let mut schedule = Schedule::new(Update);
        schedule.add_systems(
            (
                (animate_objects, animate_camera, animate_emission),
                (rebuild_geometry, update_instances, rebuild_media),
                rebuild_lights,
                extract_render_scene,
            )
                .chain(),
        );
        Self { world, schedule }
    }

    /// Sets the frame's shutter interval (absolute seconds) for the next [`Self::update`].
    pub fn set_time(&mut self, open: f32, close: f32) {
        let t = FrameTime { open, close };
        if *self.world.resource::<FrameTime>() != t {
            *self.world.resource_mut::<FrameTime>() = t;
        }
    }

    /// Runs the systems and returns the current render scene.
    pub fn update(&mut self) -> Arc<RenderScene> {
        self.schedule.run(&mut self.world);
        self.world.clear_trackers();
        self.world.resource::<Extracted>().0.clone().expect("extract_render_scene always runs")
    }

    /// Convenience: spawn and extract in one step.
    pub fn render_scene(desc: &SceneDesc) -> Arc<RenderScene> {
        Self::new(desc).update()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Ray;
    use crate::scene::parse;
    use std::path::Path;

    fn world() -> SceneWorld {
        let desc = parse(
            r#"Scene(
                camera: (look_from: (0, 0, 5), look_at: (0, 0, 0), vfov: 40),
                materials: { "a": Lambertian(albedo: (0.5, 0.5, 0.5)), "l": DiffuseLight(emit: (1, 1, 1)) },
                objects: [
                    (shape: Sphere(center: (0, 0, 0), radius: 1), material: "a"),
                    (shape: Quad(q: (0, 2, 0), u: (1, 0, 0), v: (0, 0, 1)), material: "l"),
                ],
            )"#,
            Path::new("<test>"),
        )
        .unwrap();
        SceneWorld::new(&desc)
    }

    fn rebuilds(w: &SceneWorld) -> u64 {
        w.world.resource::<SceneGeometry>().rebuilds
    }

    #[test]
    fn geometry_is_rebuilt_only_when_its_inputs_change() {
        let mut w = world();
        let first = w.update();
        assert_eq!(rebuilds(&w), 1);
        assert_eq!(first.geometry.prims.len(), 2);
        assert_eq!(first.lights.prims.len(), 1);

        // Nothing changed: no rebuild, and the same extracted scene.
        let again = w.update();
        assert_eq!(rebuilds(&w), 1);
        assert!(Arc::ptr_eq(&first, &again));

        // A camera edit re-extracts without touching the geometry.
        w.world.resource_mut::<CameraParams>().0.vfov = 30.0;
        let cam = w.update();
        assert_eq!(rebuilds(&w), 1);
        assert!(!Arc::ptr_eq(&first, &cam) && Arc::ptr_eq(&first.geometry, &cam.geometry));

        // Moving an object rebuilds.
        let e = w.world.query_filtered::<Entity, With<Shape>>().iter(&w.world).next().unwrap();
        w.world.entity_mut(e).insert(Transform(Affine3A::from_translation(Vec3::X)));
        let moved = w.update();
        assert_eq!(rebuilds(&w), 2);

        // A material edit rebuilds the light table, not the geometry: the light goes dark.
        let tables = w.world.resource::<SceneLights>().rebuilds;
        w.world.resource_mut::<Materials>().0[1] =
            crate::material::lambertian::Lambertian { albedo: Vec3::ONE }.into();
        let dark = w.update();
        assert_eq!(rebuilds(&w), 2);
        assert_eq!(w.world.resource::<SceneLights>().rebuilds, tables + 1);
        assert!(dark.lights.is_empty());
        assert!(Arc::ptr_eq(&dark.geometry, &moved.geometry));

        // Spawning and despawning rebuild; the removal is seen after clear_trackers.
        let s = w
            .world
            .spawn((
                Transform(Affine3A::IDENTITY),
                Shape(ShapeDesc::Sphere { center: Vec3::Y, radius: 0.5 }),
                MaterialId(0),
            ))
            .id();
        assert_eq!(w.update().geometry.prims.len(), 3);
        assert_eq!(rebuilds(&w), 3);
        w.world.despawn(s);
        assert_eq!(w.update().geometry.prims.len(), 2);
        assert_eq!(rebuilds(&w), 4);
        w.update();
        assert_eq!(rebuilds(&w), 4);
    }

    #[test]
    fn motion_rebuilds_with_swept_bounds_and_follows_the_shutter() {
        let mut w = world();
        w.update();
        // A still scene ignores the shutter.
        w.world.resource_mut::<CameraParams>().0.shutter = (0.0, 1.0);
        let still = w.update();
        assert_eq!(rebuilds(&w), 1);
        assert!(!still.features.motion);

        // Setting the sphere moving rebuilds; the BVH covers its sweep, time is sampled.
        let e = w
            .world
            .query::<(Entity, &Shape)>()
            .iter(&w.world)
            .find_map(|(e, s)| matches!(s.0, ShapeDesc::Sphere { .. }).then_some(e))
            .unwrap();
        w.world.entity_mut(e).insert(Motion { velocity: Vec3::new(3.0, 0.0, 0.0) });
        let moving = w.update();
        assert_eq!(rebuilds(&w), 2);
        assert!(moving.features.motion);
        let at = |s: &RenderScene, t: f32| {
            s.geometry
                .intersect(&Ray { origin: Vec3A::new(3.0, 0.0, 5.0), dir: -Vec3A::Z, time: t }, f32::INFINITY)
        };
        assert!(at(&moving, 0.0).is_none() && at(&moving, 1.0).is_some());

        // Now the shutter bounds the sweep: changing it rebuilds.
        w.world.resource_mut::<CameraParams>().0.shutter = (0.0, 2.0);
        w.update();
        assert_eq!(rebuilds(&w), 3);

        // Stopping (removing the motion) rebuilds, seen after clear_trackers.
        w.world.entity_mut(e).remove::<Motion>();
        let stopped = w.update();
        assert_eq!(rebuilds(&w), 4);
        assert!(!stopped.features.motion && at(&stopped, 1.0).is_none());
    }

    #[test]
    fn media_rebuild_only_when_a_volume_changes() {
        let mut w = world();
        w.update();
        assert!(w.update().media.is_empty());
        let v = w
            .world
            .spawn((
                Transform(Affine3A::IDENTITY),
                Shape(ShapeDesc::Box { min: Vec3::ZERO, max: Vec3::ONE }),
                Filling(Medium { sigma_t: 1.0, albedo: Vec3::ONE }),
            ))
            .id();
        let with = w.update();
        assert_eq!((with.media.volumes.len(), rebuilds(&w)), (1, 1), "a volume is not geometry");
        assert!(with.features.media);
        w.world.despawn(v);
        assert!(!w.update().features.media);
    }
}
