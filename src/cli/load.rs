//! A scene file read with the command line's overrides, checked before any work.

use super::args::Overrides;
use pathwave::engine::render_scene::PixelWindow;
use pathwave::engine::scene;
use std::path::Path;

/// Loads a scene and applies the command line's overrides.
pub fn load(path: &Path, o: &Overrides) -> Result<scene::SceneDesc, String> {
    let _span = tracing::info_span!("load_scene", file = %path.display()).entered();
    let defines = scene::parse_defines(&o.define)?;
    let mut desc = scene::load_with(path, &defines).map_err(|e| e.to_string())?;
    tracing::info!(
        file = %path.display(),
        objects = desc.objects.len(),
        materials = desc.materials.0.len(),
        textures = desc.textures.0.len(),
        "scene parsed"
    );
    let r = &mut desc.render;
    r.spp = o.image.spp.unwrap_or(r.spp);
    r.width = o.image.width.unwrap_or(r.width);
    r.height = o.image.height.unwrap_or(r.height);
    r.seed = o.image.seed.unwrap_or(r.seed);
    r.sampler = o.image.sampler.unwrap_or(r.sampler);
    r.max_depth = o.max_depth.unwrap_or(r.max_depth);
    if let Some(c) = o.clamp {
        if !(c.is_finite() && c > 0.0) {
            return Err(format!("--clamp takes a finite number > 0, not {c}"));
        }
        r.clamp = Some(scene::Positive(c));
    }
    if let Some(c) = &o.crop {
        let c: [f32; 4] = c
            .as_slice()
            .try_into()
            .map_err(|_| format!("--crop takes four numbers x0,x1,y0,y1 (a crop window), not {}", c.len()))?;
        r.crop = Some(scene::CropWindow::new(c).map_err(|e| format!("--crop: {e}"))?);
    }
    pathwave::limits::check_render(r)?;
    if let Some(c) = r.crop
        && PixelWindow::crop(r.width.get(), r.height.get(), c.0).is_none()
    {
        let [x0, x1, y0, y1] = c.0;
        return Err(format!(
            "the crop window ({x0}, {x1}, {y0}, {y1}) holds no pixel of a {}x{} image",
            r.width, r.height
        ));
    }
    Ok(desc)
}

/// Logs what the integrators will see of a scene (info).
pub fn log_scene(scene: &pathwave::engine::render_scene::RenderScene) {
    use pathwave::engine::shape::Primitive;
    let prims = &scene.geometry.prims;
    let triangles = prims.iter().filter(|p| matches!(p, Primitive::Triangle(_))).count();
    let instanced: usize =
        scene.instances.list.iter().map(|i| scene.instances.blas[i.blas as usize].mesh.triangles.len()).sum();
    let s = scene.settings;
    tracing::info!(
        primitives = prims.len(),
        triangles,
        instances = scene.instances.list.len(),
        meshes = scene.instances.blas.len(),
        instanced_triangles = instanced,
        lights = scene.lights.prims.len(),
        features = ?scene.features,
        "scene ready: {}x{} at {} spp, max depth {}",
        s.width,
        s.height,
        s.spp,
        s.max_depth
    );
}
