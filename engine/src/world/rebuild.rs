//! The rebuild systems: primitives and BVH, instances and TLAS, media and the light table,
//! each rebuilt (or refitted) only when what it is made from changed.

use super::components::*;
use crate::accel::geometry::Geometry;
use crate::accel::instances::{Instance, Instances};
use crate::accel::mesh::MeshBlas;
use crate::animation::ShutterMotion;
use crate::lighting::area::emission_table;
use crate::lighting::lights::{LightInputs, LightTable};
use crate::media::{Boundary, Media, Volume, VolumeMotion};
use crate::placement::{Form, primitives};
use crate::shape::MAX_COORDINATE;
use bevy_ecs::prelude::*;
use glam::{Affine3A, Vec3, Vec3A};
use std::sync::Arc;

/// Rebuilds primitives and BVH when a shape, transform, material id or motion changed, an
/// object or its motion was removed, or, in scenes with motion, the camera (its shutter bounds
/// the sweeps).
#[expect(clippy::type_complexity, reason = "ECS queries name their components and filters in their types")]
#[expect(clippy::too_many_arguments, reason = "an ECS system takes each query and resource as a parameter")]
pub fn rebuild_geometry(
    mut out: ResMut<SceneGeometry>,
    objects: Query<
        (Entity, &Transform, &Shape, &MaterialId, Option<&Motion>, Option<&ObjectIndex>),
        Without<Instanced>,
    >,
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
    mut errors: ResMut<FrameErrors>,
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
        errors.0.extend(out.left_out.iter().cloned());
        return;
    }
    out.left_out.clear();
    let _span = tracing::info_span!("rebuild_geometry").entered();
    let start = std::time::Instant::now();
    let mut objs: Vec<_> = objects.iter().collect();
    objs.sort_by_key(|(e, ..)| *e);
    out.entities = objs.iter().map(|(e, ..)| *e).collect();
    let (mut prims, mut mats, mut velocity, mut object) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut file_object = Vec::new();
    let (t0, t1) = camera.0.shutter;
    for (k, (_, transform, shape, material, motion, index)) in objs.into_iter().enumerate() {
        // Scene files are validated at load, but an animation or a shutter may carry an object
        // away, and objects spawned by code may be bad: the object is left out, and the frame
        // reports it.
        let start = prims.len();
        let placed = primitives(&shape.0, &transform.0, &mut prims).map_err(|e| e.to_string()).and_then(|()| {
            let Some(m) = motion else { return Ok(()) };
            let sweep = Vec3A::from(m.velocity).abs().max_element() * t0.abs().max(t1.abs());
            let reach = prims[start..].iter().map(|p| {
                let b = p.aabb();
                b.min.abs().max(b.max.abs()).max_element() + sweep
            });
            match reach.fold(0.0f32, |a, r| if r <= a { a } else { r }) <= MAX_COORDINATE {
                true => Ok(()),
                false => Err(format!(
                    "its motion carries it beyond {MAX_COORDINATE:e} units from the origin within the shutter ({t0}, {t1})"
                )),
            }
        });
        if let Err(e) = placed {
            prims.truncate(start);
            out.left_out.push(named(index, &e));
        }
        mats.resize(prims.len(), material.0);
        velocity.resize(prims.len(), motion.map_or(Vec3A::ZERO, |m| m.velocity.into()));
        object.resize(prims.len(), k as u32);
        file_object.resize(prims.len(), index.map_or(u32::MAX, |i| i.0));
    }
    errors.0.extend(out.left_out.iter().cloned());
    let geometry = Geometry::build_moving(prims, mats, velocity, camera.0.shutter);
    out.objects = geometry.source.iter().map(|&i| object[i as usize]).collect();
    out.file_objects = Arc::new(geometry.source.iter().map(|&i| file_object[i as usize]).collect());
    tracing::info!(
        primitives = geometry.prims.len(),
        moving = geometry.velocity.is_some(),
        "primitives' BVH built in {:.2} ms",
        start.elapsed().as_secs_f64() * 1e3
    );
    out.geometry = Arc::new(geometry);
    out.rebuilds += 1;
}

/// Why the object `index` (of the scene file's `objects`, when it came from there) is left out.
fn named(index: Option<&ObjectIndex>, why: &str) -> String {
    match index {
        Some(i) => format!("objects[{}]: {why}", i.0),
        None => format!("an object: {why}"),
    }
}

/// Keeps the instances: the TLAS is rebuilt when instances come or go or change mesh or
/// material (building the BLAS of a mesh no instance used before), refitted when they only
/// move (or rebuilt when refitting made it much worse), and left alone otherwise. A BLAS is
/// built once per mesh, whatever happens to the instances.
#[expect(clippy::type_complexity, reason = "ECS queries name their components and filters in their types")]
#[expect(clippy::too_many_arguments, reason = "an ECS system takes each query and resource as a parameter")]
pub fn update_instances(
    mut out: ResMut<SceneInstances>,
    mut library: ResMut<MeshLibrary>,
    objects: Query<
        (Entity, &Transform, &Shape, &MaterialId, Option<&Motion>, Option<&Animated>, Option<&ObjectIndex>),
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
    mut errors: ResMut<FrameErrors>,
) {
    let shutter_motion = |anim: Option<&Animated>| shutter_motion(anim?, &time);
    let velocity = |m: Option<&Motion>| m.map_or(Vec3A::ZERO, |m| m.velocity.into());
    // An instance as placed, or why it cannot be: a singular transform, or a placement that
    // carries it beyond the world's bounds while the shutter is open.
    let (t0, t1) = camera.0.shutter;
    let place = |b: &MeshBlas, blas: u32, t: &Transform, m: &MaterialId, v: Option<&Motion>, a| {
        let inst = Instance::new(blas, t.0, m.0, velocity(v))
            .ok_or("its transform is singular or not finite")?
            .with_motion(shutter_motion(a));
        let w = inst.world_bounds(&b.bounds(), camera.0.shutter);
        match w.min.abs().max(w.max.abs()).max_element() <= MAX_COORDINATE {
            true => Ok(inst),
            false => Err(format!(
                "its placement carries it beyond {MAX_COORDINATE:e} units from the origin within the shutter ({t0}, {t1})"
            )),
        }
    };
    let was_built_from = |e: Entity| out.entities.binary_search(&e).is_ok();
    let gone = removed_shape.read().chain(removed_material.read()).chain(removed.read()).any(was_built_from);
    let stopped: Vec<Entity> = stopped.read().filter(|e| was_built_from(*e)).collect();
    let moving = !out.instances.still();
    // An instance moved where it cannot be, or back from where it could not be: the TLAS is
    // built again, leaving out (and reporting) what cannot be placed.
    let misplaced = moved.iter().any(|e| {
        let Ok((_, transform, shape, material, motion, anim, _)) = objects.get(e) else { return false };
        let Form::Mesh(mesh) = &shape.0 else { return false };
        !was_built_from(e) || place(&library.get(mesh), 0, transform, material, motion, anim).is_err()
    });
    if gone || !reshaped.is_empty() || out.builds == 0 || misplaced {
        out.left_out.clear();
        let _span = tracing::info_span!("rebuild_instances").entered();
        let start = std::time::Instant::now();
        let mut objs: Vec<_> = objects.iter().collect();
        objs.sort_by_key(|(e, ..)| *e);
        library.build_all(objs.iter().filter_map(|(_, _, shape, ..)| match &shape.0 {
            Form::Mesh(mesh) => Some(mesh),
            _ => None,
        }));
        let (mut blas, mut list, mut entities) = (Vec::<Arc<MeshBlas>>::new(), Vec::new(), Vec::new());
        for (e, transform, shape, material, motion, anim, object) in objs {
            let Form::Mesh(mesh) = &shape.0 else {
                out.left_out.push(named(object, "only meshes are instanced"));
                continue;
            };
            let b = library.get(mesh);
            let index = blas.iter().position(|x| Arc::ptr_eq(x, &b)).unwrap_or(blas.len());
            match place(&b, index as u32, transform, material, motion, anim) {
                Ok(inst) => {
                    if index == blas.len() {
                        blas.push(b);
                    }
                    list.push(inst);
                    entities.push(e);
                }
                Err(why) => out.left_out.push(named(object, &why)),
            }
        }
        errors.0.extend(out.left_out.iter().cloned());
        // Meshes no instance uses any more are dropped.
        library.blas.retain(|_, b| blas.iter().any(|x| Arc::ptr_eq(x, b)));
        out.instances = Arc::new(Instances::build(blas, list, camera.0.shutter));
        if !out.instances.list.is_empty() {
            tracing::info!(
                instances = out.instances.list.len(),
                meshes = out.instances.blas.len(),
                merged = out.instances.merged(),
                "instances' TLAS and merged BVH built in {:.2} ms (BLAS of new meshes included)",
                start.elapsed().as_secs_f64() * 1e3
            );
        }
        out.entities = entities;
        out.builds += 1;
        return;
    }
    errors.0.extend(out.left_out.iter().cloned());
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
        let Ok((_, transform, _, _, motion, anim, _)) = objects.get(e) else { continue };
        // Checked above: a placement that fails rebuilds instead.
        instances.place(i, transform.0, velocity(motion), shutter_motion(anim));
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

/// The placement over the shutter of a keyframed object that turns or scales while the shutter
/// is open (placed per ray time), or `None` when it does not: then translation alone is the
/// exact linear motion of its [`Motion`].
fn shutter_motion(a: &Animated, time: &FrameTime) -> Option<ShutterMotion> {
    let (t0, t1) = (time.open, time.close);
    let (a0, a1) = (a.keys.at(t0), a.keys.at(t1));
    if !(t1 > t0) || a0.matrix3 == a1.matrix3 {
        return None;
    }
    let v = Vec3A::from(a.velocity);
    let a0 = Affine3A { translation: a0.translation + v * t0, ..a0 };
    let a1 = Affine3A { translation: a1.translation + v * t1, ..a1 };
    ShutterMotion::new(a.base, a0, a1, (t0, t1))
}

/// Rebuilds the media volumes when a medium, or the shape, transform or motion of an entity
/// with one, changed or was removed, or, where media move, the frame's shutter.
#[expect(clippy::type_complexity, reason = "ECS queries name their components and filters in their types")]
#[expect(clippy::too_many_arguments, reason = "an ECS system takes each query and resource as a parameter")]
pub fn rebuild_media(
    mut out: ResMut<SceneMedia>,
    volumes: Query<(
        Entity,
        &Transform,
        &Shape,
        &Filling,
        Option<&Motion>,
        Option<&Animated>,
        Option<&ObjectIndex>,
    )>,
    changed: Query<
        (),
        (With<Filling>, Or<(Changed<Transform>, Changed<Shape>, Changed<Filling>, Changed<Motion>)>),
    >,
    mut removed_shape: RemovedComponents<Shape>,
    mut removed: RemovedComponents<Filling>,
    mut stopped: RemovedComponents<Motion>,
    time: Res<FrameTime>,
    mut errors: ResMut<FrameErrors>,
) {
    let was_built_from = |e: Entity| out.entities.binary_search(&e).is_ok();
    let removed = removed_shape.read().chain(removed.read()).chain(stopped.read()).any(was_built_from);
    // A new shutter changes how moving media are placed per ray time.
    let new_shutter = out.media.moving() && time.is_changed();
    if !(removed || !changed.is_empty() || new_shutter || out.rebuilds == 0) {
        errors.0.extend(out.left_out.iter().cloned());
        return;
    }
    let _span = tracing::info_span!("rebuild_media").entered();
    let mut vols: Vec<_> = volumes.iter().collect();
    vols.sort_by_key(|(e, ..)| *e);
    out.entities = vols.iter().map(|(e, ..)| *e).collect();
    let mut left_out = Vec::new();
    let volumes = vols
        .into_iter()
        .filter_map(|(_, transform, shape, filling, moving, anim, index)| {
            // Scene files are validated at load, but keyframes may scale an object to nothing.
            let det = transform.0.matrix3.determinant();
            if !(det != 0.0 && det.is_finite() && transform.0.translation.is_finite()) {
                left_out.push(named(index, "its transform is singular or not finite"));
                return None;
            }
            let boundary = match &shape.0 {
                Form::Mesh(mesh) => {
                    if let Some((a, b, _)) = crate::scene::open_edge(mesh) {
                        tracing::error!("medium skipped: its mesh is open at the edge {a} - {b}");
                        return None;
                    }
                    Boundary::Mesh(Arc::new(MeshBlas::build(mesh.clone())))
                }
                form => match form.closed() {
                    Some(closed) => Boundary::Closed(closed),
                    None => {
                        tracing::error!("medium skipped: its shape bounds no volume");
                        return None;
                    }
                },
            };
            let motion = match (anim.and_then(|a| shutter_motion(a, &time)), moving) {
                (Some(motion), _) => {
                    VolumeMotion::Keyed { motion: Box::new(motion), world_from_object: transform.0 }
                }
                (None, Some(m)) if m.velocity != Vec3::ZERO => VolumeMotion::Linear(m.velocity.into()),
                (None, _) => VolumeMotion::Still,
            };
            Some(Volume {
                object_from_world: transform.0.inverse(),
                boundary,
                medium: filling.0.clone(),
                motion,
            })
        })
        .collect();
    errors.0.extend(left_out.iter().cloned());
    out.left_out = left_out;
    out.media = Arc::new(Media::new(volumes));
    out.rebuilds += 1;
}

/// Rebuilds the light table when the primitives, the instances (they bound the scene), the
/// materials (which emit), the punctual lights or the background changed.
#[expect(clippy::too_many_arguments, reason = "an ECS system takes each resource it reads as a parameter")]
pub fn rebuild_lights(
    mut out: ResMut<SceneLights>,
    geometry: Res<SceneGeometry>,
    instances: Res<SceneInstances>,
    materials: Res<Materials>,
    textures: Res<SceneTextures>,
    emitting: Res<ObjectEmission>,
    punctual: Res<PunctualLights>,
    background: Res<BackgroundLight>,
    settings: Res<Settings>,
    camera: Res<CameraParams>,
) {
    // A new shutter rebuilds the geometry where something moves (`rebuild_geometry`), and
    // with it this table, whose tree bounds moving lights by their sweep.
    let any = geometry.is_changed()
        || settings.is_changed()
        || instances.is_changed()
        || materials.is_changed()
        || textures.is_changed()
        || emitting.is_changed()
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
    let inputs = LightInputs {
        punctual: &punctual.0,
        environment: background.0.sampling(),
        bounds,
        objects: Some(&geometry.objects),
        sampler: settings.0.light_sampler,
        shutter: camera.0.shutter,
    };
    let emission = emission_table(&materials.0, &textures.per_material, &emitting.0);
    out.lights = Arc::new(LightTable::build(geo, emission, inputs));
    out.rebuilds += 1;
    tracing::info!(lights = out.lights.len(), "light table built");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Ray;
    use crate::media::Medium;
    use crate::render_scene::RenderScene;
    use crate::scene::parse;
    use crate::shape::{BoxShape, SphereShape};
    use crate::world::SceneWorld;
    use glam::Vec3;
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
        match &mut w.world.resource_mut::<CameraParams>().0.view {
            crate::scene::CameraView::LookAt { vfov, .. } => *vfov = 30.0,
            other => panic!("the scene's camera is {other:?}"),
        }
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
            crate::material::lambertian::Lambertian { albedo: Vec3::ONE, two_sided: true }.into();
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
                Shape(Form::Sphere(SphereShape { center: Vec3A::Y, radius: 0.5, poles: Default::default() })),
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
            .find_map(|(e, s)| matches!(s.0, Form::Sphere(_)).then_some(e))
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
                Shape(Form::Box(BoxShape { min: Vec3A::ZERO, max: Vec3A::ONE, uv: Default::default() })),
                Filling(Medium::homogeneous(Vec3::ONE, Vec3::ONE)),
            ))
            .id();
        let with = w.update();
        assert_eq!((with.media.volumes().len(), rebuilds(&w)), (1, 1), "a volume is not geometry");
        assert!(with.features.media);
        w.world.despawn(v);
        assert!(!w.update().features.media);
    }

    /// A medium's motion reaches its volume: rays find it where it is at their time; a new
    /// shutter rebuilds the media only while one moves; stopping rebuilds; keys that scale it
    /// to nothing leave it out, with an error every frame until it is whole again.
    #[test]
    fn moving_media_follow_their_motion_and_rebuild_with_the_shutter() {
        let desc = parse(
            r#"Scene(
                camera: (look_from: (0, 0, 5), look_at: (0, 0, 0), vfov: 40, shutter: (0, 1)),
                materials: { "a": Lambertian(albedo: (0.5, 0.5, 0.5)) },
                objects: [
                    (shape: Box(a: (0, 0, 0), b: (1, 1, 1)), medium: (density: 1, albedo: (1, 1, 1)), motion: (velocity: (2, 0, 0))),
                    (
                        shape: Box(a: (0, 3, 0), b: (1, 4, 1)),
                        medium: (density: 2, albedo: (1, 1, 1)),
                        animate: (scale: Linear([(0, (1, 1, 1)), (10, (0, 0, 0))])),
                    ),
                ],
            )"#,
            Path::new("<test>"),
        )
        .unwrap();
        let mut w = SceneWorld::new(&desc);
        let media_rebuilds = |w: &SceneWorld| w.world.resource::<SceneMedia>().rebuilds;
        let s = w.update();
        assert!(s.media.moving() && s.features.motion);
        // Along z through x = 2.5: the first box covers it from time 0.75 to 1.25.
        let through = |s: &RenderScene, t: f32| {
            let ray = Ray { origin: Vec3A::new(2.5, 0.5, -5.0), dir: Vec3A::Z, time: t };
            s.media.transmittance(&ray, 10.0).x
        };
        assert_eq!((through(&s, 0.0), through(&s, 0.7)), (1.0, 1.0));
        assert!((through(&s, 0.8) - (-1.0f32).exp()).abs() < 1e-6);

        // A new shutter rebuilds them; the same one does not.
        let n = media_rebuilds(&w);
        w.set_time(0.0, 2.0);
        w.update();
        assert_eq!(media_rebuilds(&w), n + 1);
        w.update();
        assert_eq!(media_rebuilds(&w), n + 1);

        // Stopped (the first box's motion removed, the second's keys still over a closed
        // shutter): a rebuild, then none for a new shutter.
        let mut objects = w.world.query::<(Entity, &ObjectIndex)>();
        let first = objects.iter(&w.world).find(|(_, i)| i.0 == 0).unwrap().0;
        w.world.entity_mut(first).remove::<Motion>();
        w.set_time(1.0, 1.0);
        let s = w.update();
        assert!(!s.media.moving() && through(&s, 0.8) == 1.0);
        let n = media_rebuilds(&w);
        w.set_time(1.0, 1.0);
        w.update();
        assert_eq!(media_rebuilds(&w), n);

        // Scaled to nothing at time 10: left out, and said so every frame.
        w.set_time(10.0, 10.0);
        let s = w.update();
        assert_eq!(s.media.volumes().len(), 1);
        let said = |w: &SceneWorld| w.world.resource::<FrameErrors>().0.clone();
        assert_eq!(said(&w), ["objects[1]: its transform is singular or not finite"]);
        w.update();
        assert_eq!(said(&w).len(), 1);
        w.set_time(5.0, 5.0);
        assert_eq!((w.update().media.volumes().len(), said(&w).len()), (2, 0));
    }
}
