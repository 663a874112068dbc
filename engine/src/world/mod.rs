//! The ECS scene: entities with `Transform`, `Shape` and `MaterialId`; systems that rebuild the
//! geometry (BVH and emitter table) only when what it depends on changed, and extract the
//! [`RenderScene`].
//!
//! Data flows one way through the submodules: `spawn` turns a scene description into entities
//! and resources (`components`); each frame the schedule runs the animation systems (`animate`),
//! the rebuilds (`rebuild`) and the extraction (`extract`), in that order; `reload` writes an
//! edited description into a live world.

mod animate;
mod components;
mod extract;
mod rebuild;
mod reload;
mod spawn;

pub use animate::{animate_camera, animate_emission, animate_objects};
pub use components::*;
pub use extract::extract_render_scene;
pub use rebuild::{rebuild_geometry, rebuild_lights, rebuild_media, update_instances};
pub use reload::{Builds, Reload};

use crate::render_scene::RenderScene;
use crate::scene::SceneDesc;
use bevy_ecs::prelude::*;
use std::sync::Arc;

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
        spawn::spawn(&mut world, desc);
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

    /// Runs the systems and returns the current render scene; [`Self::errors`] says whether it
    /// is the scene the file asks for.
    pub fn update(&mut self) -> Arc<RenderScene> {
        self.world.resource_mut::<FrameErrors>().0.clear();
        self.schedule.run(&mut self.world);
        self.world.clear_trackers();
        self.world.resource::<Extracted>().0.clone().expect("extract_render_scene always runs")
    }

    /// Why the last [`Self::update`]'s scene is not the one the scene file asks for (empty when
    /// it is): an object its motion or animation carried beyond the world's bounds (left out),
    /// an animated camera that the loader would refuse (kept as it was).
    pub fn errors(&self) -> &[String] {
        &self.world.resource::<FrameErrors>().0
    }

    /// [`Self::update`], failing with [`Self::errors`] where there are any: what a command that
    /// renders the scene calls.
    pub fn update_checked(&mut self) -> Result<Arc<RenderScene>, String> {
        let scene = self.update();
        match self.errors() {
            [] => Ok(scene),
            e => Err(e.join("; ")),
        }
    }

    /// Convenience: spawn and extract in one step.
    pub fn render_scene(desc: &SceneDesc) -> Arc<RenderScene> {
        Self::new(desc).update()
    }
}
