//! Extraction: the flat, read-only [`RenderScene`] the integrators read, made from the world's
//! resources when any of them changed.

use super::components::*;
use crate::camera::Camera;
use crate::lighting::light_paths::{LightPaths, LightTracing, SHARP_ALPHA};
use crate::material::Material;
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
    let mut scene = RenderScene {
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
        light_paths: None,
    };
    scene.light_paths = match plan_light_paths(&scene) {
        Ok(plan) => plan.map(Arc::new),
        Err(why) => {
            // Once a process: an animation makes its scene again each frame.
            static WARNED: std::sync::Once = std::sync::Once::new();
            WARNED.call_once(|| tracing::warn!("{why}"));
            None
        }
    };
    out.0 = Some(Arc::new(scene));
}

/// Light tracing for `scene` ([`LightPaths`]): `None` where it is off or has nothing to take
/// (no light it emits from, no sharp material); an error saying why where it is on but the
/// scene has what it does not follow: participating media, a camera other than a pinhole at
/// rest, or a pixel filter wider than the film splats.
fn plan_light_paths(scene: &RenderScene) -> Result<Option<LightPaths>, String> {
    if scene.settings.light_tracing == LightTracing::Off {
        return Ok(None);
    }
    let sharp = |m: &Material| m.sharpest_alpha().is_some_and(|a| a < SHARP_ALPHA);
    if !scene.materials.iter().any(sharp) {
        return Ok(None);
    }
    let refuse = |what: &str| Err(format!("light tracing is off: {what}"));
    if scene.features.media {
        return refuse("the scene has participating media");
    }
    if !scene.camera.is_pinhole() {
        return refuse("the camera is not a pinhole at rest (it has a lens or moves, or is orthographic)");
    }
    if scene.settings.filter.samples_offsets() {
        return refuse("the pixel filter reaches further than the film splats (4 pixels)");
    }
    Ok(LightPaths::new(&scene.lights, &scene.geometry))
}
