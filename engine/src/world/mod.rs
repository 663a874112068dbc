//! The ECS scene: entities with `Transform`, `Shape` and `MaterialId`; systems that rebuild the
//! geometry (BVH and emitter table) only when what it depends on changed, and extract the
//! [`RenderScene`].
//!
//! Data flows one way through the submodules: `spawn` turns a scene description into entities
//! and resources (`components`); each frame the schedule runs the animation systems (`animate`:
//! keyframes, and the grid files of the frame),
//! the rebuilds (`rebuild`) and the extraction (`extract`), in that order; `reload` writes an
//! edited description into a live world.

mod animate;
mod components;
mod extract;
mod rebuild;
mod reload;
mod spawn;

pub use animate::{animate_camera, animate_emission, animate_objects, read_grid_frames};
pub use components::*;
pub use extract::extract_render_scene;
pub use rebuild::{rebuild_geometry, rebuild_lights, rebuild_media, update_instances};
pub use reload::{Builds, Reload};

use crate::format::files;
use crate::render_scene::RenderScene;
use crate::scene::SceneDesc;
use bevy_ecs::prelude::*;
use std::sync::Arc;

/// A bevy_ecs world holding a scene, with its update schedule.
pub struct SceneWorld {
    /// The ECS world (entities and resources); edit it between calls to [`Self::update`].
    pub world: World,
    schedule: Schedule,
    /// The folder the files an update reads must lie in, and the file exempt (see
    /// [`Self::confine`]).
    confined: Option<(std::path::PathBuf, std::path::PathBuf)>,
}

impl SceneWorld {
    /// Spawns the entities and resources of a scene description.
    pub fn new(desc: &SceneDesc) -> Self {
        let mut world = World::new();
        spawn::spawn(&mut world, desc);
        let mut schedule = Schedule::new(Update);
        schedule.add_systems(
            (
                (animate_objects, animate_camera, animate_emission, read_grid_frames),
                (rebuild_geometry, update_instances, rebuild_media),
                rebuild_lights,
                extract_render_scene,
            )
                .chain(),
        );
        Self { world, schedule, confined: None }
    }

    /// Makes every file an update reads (a grid sequence's frame) lie in the folder `root`,
    /// but `exempt`, as the scene's load did ([`files::confined`], `--assets-under`).
    pub fn confine(&mut self, root: &std::path::Path, exempt: &std::path::Path) {
        self.confined = Some((root.to_owned(), exempt.to_owned()));
    }

    /// Sets the frame whose files grid sequences read (see [`crate::scene::GridDesc`]) for the
    /// next [`Self::update`]; a world starts at frame 0.
    pub fn set_frame(&mut self, frame: u32) {
        if self.world.resource::<FrameNumber>().0 != frame {
            self.world.resource_mut::<FrameNumber>().0 = frame;
        }
    }

    /// The files the current media were read from besides the scene's inputs (grid
    /// sequences' frames), with their hashes, sorted by path: with the scene's
    /// [`inputs`](crate::scene::SceneDesc::inputs), what the last [`Self::update`]'s scene was
    /// made from.
    pub fn frame_inputs(&mut self) -> Vec<files::InputFile> {
        let mut list: Vec<files::InputFile> =
            self.world.query::<&GridInputs>().iter(&self.world).flat_map(|g| g.0.iter().cloned()).collect();
        list.sort_by(|a, b| a.path.cmp(&b.path));
        list.dedup();
        list
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
        let (schedule, world) = (&mut self.schedule, &mut self.world);
        match &self.confined {
            Some((root, exempt)) => {
                if let Err(e) = files::confined(root, exempt, || schedule.run(world)) {
                    world.resource_mut::<FrameErrors>().0.push(e);
                }
            }
            None => schedule.run(world),
        }
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
