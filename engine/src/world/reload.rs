//! Reloading an edited scene into a live [`SceneWorld`]: only the components and resources that
//! differ from the new description are written, so that the world's change detection rebuilds
//! only what depends on them (a new material colour rebuilds the light table, not the BVH; a
//! moved instance refits the TLAS).

use crate::scene::SceneDesc;
use crate::world::{
    Animated, BackgroundLight, CameraKeys, EmitKeys, Filling, FrameTime, GridInputs, GridReads, GridSequence,
    Instanced, MaterialId, MaterialWrappers, Materials, MeshLibrary, Motion, ObjectEmission, ObjectIndex,
    PunctualLights, SceneGeometry, SceneInstances, SceneLights, SceneMedia, SceneTextures, SceneWorld,
    Settings, Shape, Transform,
};
use bevy_ecs::component::Mutable;
use bevy_ecs::prelude::*;

/// What a reload wrote into the world.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Reload {
    /// Objects with a component changed.
    pub changed: usize,
    /// Objects added.
    pub added: usize,
    /// Objects removed.
    pub removed: usize,
    /// The resources written (materials, textures, settings, camera, lights, background, ...).
    pub resources: Vec<&'static str>,
}

impl Reload {
    /// Whether nothing was written.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// How many times each derived structure was built, to tell what an update rebuilt.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Builds {
    /// The primitives' BVH.
    pub geometry: u64,
    /// The instances' TLAS, built.
    pub tlas: u64,
    /// The instances' TLAS, refitted.
    pub refits: u64,
    /// Meshes' BLAS.
    pub blas: u64,
    /// Media volumes.
    pub media: u64,
    /// The light table.
    pub lights: u64,
    /// Grid files read for a frame (grid sequences').
    pub grids: u64,
}

impl Builds {
    /// What was built between `before` and `self`, e.g. `light table rebuilt; BVH, TLAS, BLAS
    /// and media kept`.
    pub fn since(&self, before: &Builds) -> String {
        let parts = [
            ("BVH", self.geometry - before.geometry, "rebuilt"),
            ("TLAS", self.tlas - before.tlas, "rebuilt"),
            ("TLAS", self.refits - before.refits, "refitted"),
            ("BLAS", self.blas - before.blas, "built"),
            ("media", self.media - before.media, "rebuilt"),
            ("light table", self.lights - before.lights, "rebuilt"),
            ("grid files", self.grids - before.grids, "read"),
        ];
        let done: Vec<String> =
            parts.iter().filter(|p| p.1 > 0).map(|(name, _, how)| format!("{name} {how}")).collect();
        let mut kept: Vec<&str> = Vec::new();
        for (name, n, _) in parts {
            let touched = parts.iter().any(|p| p.0 == name && p.1 > 0);
            // Files are read, not kept.
            if n == 0 && !touched && !kept.contains(&name) && name != "grid files" {
                kept.push(name);
            }
        }
        match (done.is_empty(), kept.is_empty()) {
            (true, _) => "nothing rebuilt".into(),
            (false, true) => done.join(", "),
            (false, false) => format!("{}; {} kept", done.join(", "), kept.join(", ")),
        }
    }
}

/// Writes `C` of `from` into `to` when it differs (inserting or removing it); true when written.
fn sync<C: Component + Clone + PartialEq>(to: &mut World, e: Entity, from: Option<&C>) -> bool {
    let current = to.get::<C>(e);
    match (current, from) {
        (Some(a), Some(b)) if a == b => false,
        (None, None) => false,
        (_, Some(b)) => {
            to.entity_mut(e).insert(b.clone());
            true
        }
        (Some(_), None) => {
            to.entity_mut(e).remove::<C>();
            true
        }
    }
}

/// Writes resource `R` of `from` into `to` when it differs; true when written.
fn sync_resource<R: Resource + Component<Mutability = Mutable> + Clone + PartialEq>(
    to: &mut World,
    from: &World,
) -> bool {
    let new = from.resource::<R>();
    if to.resource::<R>() == new {
        return false;
    }
    *to.resource_mut::<R>() = new.clone();
    true
}

/// The entities of the scene file's objects, in the file's order.
fn objects(world: &mut World) -> Vec<Entity> {
    let mut list: Vec<(ObjectIndex, Entity)> =
        world.query::<(&ObjectIndex, Entity)>().iter(world).map(|(i, e)| (*i, e)).collect();
    list.sort();
    list.into_iter().map(|(_, e)| e).collect()
}

impl SceneWorld {
    /// Makes the world hold `desc`, writing only what differs from what it holds: the n-th
    /// object of the file is the n-th entity, objects past the end are spawned or despawned,
    /// and the next [`Self::update`] rebuilds only what the written components and resources
    /// feed. The frame's files of grid sequences are read again by that update (a reload
    /// follows an edit, maybe to them), and rebuild the media only if their values changed.
    pub fn reload(&mut self, desc: &SceneDesc) -> Reload {
        let mut fresh = SceneWorld::new(desc).world;
        let world = &mut self.world;
        let mut report = Reload::default();
        let named = [
            ("materials", sync_resource::<Materials>(world, &fresh)),
            ("wrappers", sync_resource::<MaterialWrappers>(world, &fresh)),
            ("emission", sync_resource::<ObjectEmission>(world, &fresh)),
            ("textures", sync_resource::<SceneTextures>(world, &fresh)),
            ("settings", sync_resource::<Settings>(world, &fresh)),
            ("camera", sync_resource::<CameraKeys>(world, &fresh)),
            ("emission keys", sync_resource::<EmitKeys>(world, &fresh)),
            ("background", sync_resource::<BackgroundLight>(world, &fresh)),
            ("lights", sync_resource::<PunctualLights>(world, &fresh)),
            ("shutter", sync_resource::<FrameTime>(world, &fresh)),
        ];
        report.resources = named.iter().filter(|r| r.1).map(|r| r.0).collect();
        let (old, new) = (objects(world), objects(&mut fresh));
        for (i, &n) in new.iter().enumerate() {
            let e = match old.get(i) {
                Some(&e) => e,
                None => {
                    report.added += 1;
                    world.spawn_empty().id()
                }
            };
            let f = fresh.entity(n);
            sync(world, e, f.get::<ObjectIndex>());
            let mut changed = sync(world, e, f.get::<Shape>());
            changed |= sync(world, e, f.get::<MaterialId>());
            // A sequence's medium is read by `read_grid_frames`: again after a reload, which
            // follows an edit that may be to the frame's files (the same values rebuild nothing).
            let sequence = sync(world, e, f.get::<GridSequence>());
            sync(world, e, f.get::<GridInputs>());
            changed |= sequence;
            if f.get::<GridSequence>().is_none() || sequence {
                changed |= sync(world, e, f.get::<Filling>());
            }
            changed |= sync(world, e, f.get::<Instanced>());
            changed |= sync(world, e, f.get::<Animated>());
            // Keyframed objects are placed by `animate_objects` from their `Animated`.
            if f.get::<Animated>().is_none() {
                changed |= sync(world, e, f.get::<Transform>());
                changed |= sync(world, e, f.get::<Motion>());
            }
            if changed && i < old.len() {
                report.changed += 1;
            }
        }
        for &e in old.iter().skip(new.len()) {
            world.despawn(e);
            report.removed += 1;
        }
        // The keyframed placements, camera and emission are evaluated again over what changed.
        if !report.is_empty() {
            world.resource_mut::<FrameTime>().set_changed();
        }
        report
    }

    /// How many times each derived structure has been built so far.
    pub fn builds(&self) -> Builds {
        let w = &self.world;
        let instances = w.resource::<SceneInstances>();
        Builds {
            geometry: w.resource::<SceneGeometry>().rebuilds,
            tlas: instances.builds,
            refits: instances.refits,
            blas: w.resource::<MeshLibrary>().builds,
            media: w.resource::<SceneMedia>().rebuilds,
            lights: w.resource::<SceneLights>().rebuilds,
            grids: w.resource::<GridReads>().0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::parse;
    use std::path::Path;

    fn scene(albedo: &str, sphere_x: &str, extra: &str) -> SceneDesc {
        let text = format!(
            r#"Scene(
                camera: (look_from: (0, 0, 5), look_at: (0, 0, 0), vfov: 40),
                materials: {{ "a": Lambertian(albedo: {albedo}), "l": DiffuseLight(emit: (1, 1, 1)) }},
                objects: [
                    (shape: Sphere(center: ({sphere_x}, 0, 0), radius: 1), material: "a"),
                    (shape: Quad(q: (0, 2, 0), u: (1, 0, 0), v: (0, 0, 1)), material: "l"),
                    {extra}
                ],
            )"#
        );
        parse(&text, Path::new("<test>")).unwrap()
    }

    #[test]
    fn a_reload_rebuilds_only_what_changed() {
        let mut w = SceneWorld::new(&scene("(0.5, 0.5, 0.5)", "0", ""));
        let first = w.update();
        let b0 = w.builds();
        // The same scene: nothing written, nothing rebuilt, the same extracted scene.
        assert!(w.reload(&scene("(0.5, 0.5, 0.5)", "0", "")).is_empty());
        assert!(std::sync::Arc::ptr_eq(&first, &w.update()));
        assert_eq!(w.builds(), b0);
        // A new colour: the materials; the light table follows them, the BVH stays.
        let r = w.reload(&scene("(0.9, 0.1, 0.1)", "0", ""));
        assert_eq!((r.changed, r.resources.as_slice()), (0, ["materials"].as_slice()));
        let s = w.update();
        assert_eq!(w.builds().since(&b0), "light table rebuilt; BVH, TLAS, BLAS, media kept");
        assert!(std::sync::Arc::ptr_eq(&first.geometry, &s.geometry));
        // A moved sphere: one object, the BVH.
        let b1 = w.builds();
        let r = w.reload(&scene("(0.9, 0.1, 0.1)", "0.5", ""));
        assert_eq!((r.changed, r.added, r.removed), (1, 0, 0));
        w.update();
        assert_eq!(w.builds().geometry, b1.geometry + 1);
        // An object more, then none.
        let more = r#"(shape: Sphere(center: (3, 0, 0), radius: 1), material: "a"),"#;
        let r = w.reload(&scene("(0.9, 0.1, 0.1)", "0.5", more));
        assert_eq!((r.changed, r.added), (0, 1));
        assert_eq!(w.update().geometry.prims.len(), 3);
        let r = w.reload(&scene("(0.9, 0.1, 0.1)", "0.5", ""));
        assert_eq!(r.removed, 1);
        assert_eq!(w.update().geometry.prims.len(), 2);
        // The reloaded world renders what a fresh one does.
        let fresh = SceneWorld::new(&scene("(0.9, 0.1, 0.1)", "0.5", "")).update();
        assert_eq!(w.update().materials, fresh.materials);
        assert_eq!(w.update().geometry.prims, fresh.geometry.prims);
    }
}
