//! Extraction: the flat, read-only [`RenderScene`] the integrators read, made from the world's
//! resources when any of them changed.

use super::components::*;
use crate::camera::Camera;
use crate::render_scene::{Features, RenderScene};
use crate::scene::{CameraDesc, CameraView, Projection};
use bevy_ecs::prelude::*;
use std::sync::Arc;

/// Builds a new [`RenderScene`] when anything it holds changed.
#[expect(clippy::too_many_arguments, reason = "an ECS system takes each resource it reads as a parameter")]
pub fn extract_render_scene(
    geometry: Res<SceneGeometry>,
    instances: Res<SceneInstances>,
    lights: Res<SceneLights>,
    media: Res<SceneMedia>,
    textures: Res<SceneTextures>,
    materials: Res<Materials>,
    wrappers: Res<MaterialWrappers>,
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
        || wrappers.is_changed()
        || camera.is_changed()
        || settings.is_changed()
        || background.is_changed();
    if !any && out.0.is_some() {
        return;
    }
    let s = settings.0;
    let make = |c: &CameraDesc| {
        let (r, f, shutter, w, h) = (c.aperture_radius, c.focus_dist, c.shutter, s.width, s.height);
        let camera = match c.view {
            CameraView::LookAt { look_from, look_at, vup, vfov } => {
                Camera::new(look_from, look_at, vup, vfov, r, f, shutter, w, h)
            }
            CameraView::ToWorld {
                to_world, projection: Projection::Perspective { fov, fov_axis }, ..
            } => {
                let tan_half_x = fov_axis.tan_half_x_fov(fov, w as f64 / h as f64) as f32;
                Camera::perspective(to_world, tan_half_x, r, f, shutter, w, h)
            }
            CameraView::ToWorld { to_world, projection: Projection::Orthographic, .. } => {
                Camera::orthographic(to_world, shutter, w, h)
            }
        };
        camera.with_clip(c.view.clip())
    };
    let camera = match &camera.1 {
        Some(close) => make(&camera.0).moving_to(&make(close)),
        None => make(&camera.0),
    };
    out.0 = Some(Arc::new(RenderScene {
        features: Features::detect(&geometry.geometry, &instances.instances, &media.media, &camera)
            .with_materials(
                &geometry.geometry,
                &instances.instances,
                &materials.0,
                &textures.per_material,
                &lights.lights.emission,
                &wrappers.0,
            ),
        camera,
        settings: s,
        background: background.0.clone(),
        materials: materials.0.clone(),
        geometry: geometry.geometry.clone(),
        objects: geometry.file_objects.clone(),
        instances: instances.instances.clone(),
        lights: lights.lights.clone(),
        media: media.media.clone(),
        textures: textures.textures.clone(),
        material_textures: textures.per_material.clone(),
        varies: RenderScene::varying_materials(&textures.per_material, &wrappers.0),
        wrappers: wrappers.0.clone(),
        guide: None,
    }));
}
