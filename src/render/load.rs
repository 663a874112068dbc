//! A scene file read with the command line's overrides ([`SceneArgs`]), checked before any
//! work: `render`, `animate`, `watch` and `farm slurm` load scenes here.

use super::args::SceneArgs;
use crate::engine::render_scene::PixelWindow;
use crate::engine::scene;
use crate::engine::world::SceneWorld;
use crate::limits::{self, MAX_DEPTH, MAX_SPP};
use std::path::Path;

impl SceneArgs {
    /// `--clamp`, a finite number > 0.
    fn clamp(&self) -> Result<Option<scene::Positive>, String> {
        match self.clamp {
            Some(c) if !(c.is_finite() && c > 0.0) => {
                Err(format!("--clamp takes a finite number > 0, not {c}"))
            }
            c => Ok(c.map(scene::Positive)),
        }
    }

    /// `--crop`, four fractions x0,x1,y0,y1.
    fn crop(&self) -> Result<Option<scene::CropWindow>, String> {
        let Some(c) = &self.crop else { return Ok(None) };
        let c: [f32; 4] = c
            .as_slice()
            .try_into()
            .map_err(|_| format!("--crop takes four numbers x0,x1,y0,y1 (a crop window), not {}", c.len()))?;
        scene::CropWindow::new(c).map(Some).map_err(|e| format!("--crop: {e}"))
    }

    /// Refuses flags that no scene makes right (beyond the bounds of [`limits`], a bad clamp,
    /// crop window or -D), before a scene is read.
    pub fn check(&self) -> Result<(), String> {
        let i = &self.image;
        limits::check_size(i.width.map_or(1, |w| w.get()), i.height.map_or(1, |h| h.get()))?;
        if let Some(spp) = i.spp.filter(|s| s.get() > MAX_SPP) {
            return Err(format!("--spp {spp}: at most {MAX_SPP} samples per pixel"));
        }
        if let Some(d) = self.max_depth.filter(|&d| d > MAX_DEPTH) {
            return Err(format!("--max-depth {d}: at most {MAX_DEPTH} bounces"));
        }
        self.clamp()?;
        self.crop()?;
        scene::parse_defines(&self.define).map(drop)
    }
}

/// Loads a scene and applies the command line's overrides.
pub fn load(path: &Path, o: &SceneArgs) -> Result<scene::SceneDesc, String> {
    let _span = tracing::info_span!("load_scene", file = %path.display()).entered();
    o.check()?;
    let defines = scene::parse_defines(&o.define)?;
    let load = || scene::load_with(path, &defines).map_err(|e| e.to_string());
    let mut desc = match &o.assets_under {
        Some(root) => crate::engine::format::files::confined(root, path, load)??,
        None => load()?,
    };
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
    r.filter = o.image.filter.unwrap_or(r.filter);
    r.max_depth = o.max_depth.unwrap_or(r.max_depth);
    r.light_sampler = o.light_sampler.unwrap_or(r.light_sampler);
    r.guiding = o.guiding.unwrap_or(r.guiding);
    r.light_tracing = o.light_tracing.unwrap_or(r.light_tracing);
    r.clamp = o.clamp()?.or(r.clamp);
    r.crop = o.crop()?.or(r.crop);
    limits::check_render(r)?;
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

/// Runs `f` with the files it reads confined as the scene's load was (`--assets-under`).
pub fn confined<R>(path: &Path, o: &SceneArgs, f: impl FnOnce() -> R) -> Result<R, String> {
    match &o.assets_under {
        Some(root) => crate::engine::format::files::confined(root, path, f),
        None => Ok(f()),
    }
}

/// The world of the scene loaded from `path`, reading the files of frames (grid sequences')
/// confined as its load was (`--assets-under`).
pub fn world(desc: &scene::SceneDesc, path: &Path, o: &SceneArgs) -> SceneWorld {
    let mut world = SceneWorld::new(desc);
    if let Some(root) = &o.assets_under {
        world.confine(root, path);
    }
    world
}

/// Logs what the integrators will see of a scene (info).
pub fn log_scene(scene: &crate::engine::render_scene::RenderScene) {
    use crate::engine::shape::Primitive;
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
        lights = scene.lights.len(),
        emitting_primitives = scene.lights.prims.len(),
        features = ?scene.features,
        "scene ready: {}x{} at {} spp, max depth {}",
        s.width,
        s.height,
        s.spp,
        s.max_depth
    );
    if tracing::enabled!(tracing::Level::DEBUG) {
        let geo = &scene.geometry;
        let traversal = match (geo.flat().is_some(), geo.is_static_bvh()) {
            (true, _) => "flat streams (few primitives: every ray tests every one)",
            (false, true) => "BVH, camera and shadow rays in packets",
            (false, false) => "BVH over moving primitives, one ray at a time",
        };
        let instances = match (scene.instances.list.is_empty(), scene.instances.still()) {
            (true, _) => "none",
            (false, true) => "still (shadow rays in packets)",
            (false, false) => "moving (one ray at a time)",
        };
        let f = scene.features;
        let on = |b: bool| if b { "on" } else { "skipped" };
        tracing::debug!(
            traversal,
            instances,
            instance_bytes = scene.instances.bytes(),
            media = on(f.media),
            motion = on(f.motion),
            textures = on(f.textures),
            texel_bytes = scene.textures.texel_bytes(),
            wrappers = on(f.wrappers),
            normal_maps = on(f.tilts),
            shading_loops = ?crate::integrator::wavefront::material_kinds(scene),
            "code paths"
        );
    }
}
