//! Spawning: the entities and resources of a scene description.

use super::components::*;
use crate::accel::mesh::MeshData;
use crate::lighting::area::AreaEmission;
use crate::lighting::environment::EnvironmentMap;
use crate::lighting::punctual::LightTextures;
use crate::material::Material;
use crate::placement::{Form, primitives};
use crate::render_scene::{Background, PixelWindow, RenderSettings};
use crate::scene::{BackgroundDesc, Body, Color, MaterialDesc, Rgb, SceneDesc, compose};
use crate::shape::Primitive;
use crate::texture::{MaterialTextures, Texture, TextureId, Textures};
use bevy_ecs::prelude::*;
use glam::{Affine3A, Vec3};
use std::sync::Arc;

/// Spawns the entities and inserts the resources of `desc` into an empty world.
pub(super) fn spawn(world: &mut World, desc: &SceneDesc) {
    let names: Vec<&str> = desc.materials.iter().map(|(n, _)| n.as_str()).collect();
    let textures = build_textures(desc);
    let (mut mats, mut per_material, mut wrappers): (Vec<Material>, Vec<MaterialTextures>, Vec<_>) =
        (Vec::new(), Vec::new(), Vec::new());
    for (_, m) in desc.materials.iter() {
        match m {
            // A wrapper's entry holds a material it names (one before it), or their mix.
            MaterialDesc::Wrap(w) => {
                let id =
                    |name: &str| names.iter().position(|n| *n == name).expect("validated at load") as u32;
                let textured = |id: u32| per_material[id as usize].any();
                let (m, w) = w.lower(id, |t| texture_id(desc, t)).settle(&mats, &wrappers, textured);
                mats.push(m);
                per_material.push(MaterialTextures::default());
                wrappers.push(w);
            }
            m => {
                let (m, t) = material(desc, m, &textures);
                mats.push(m);
                per_material.push(t);
                wrappers.push(None);
            }
        }
    }
    // Each object with an `emit` gets a material id of its own: its material's copy, with
    // the emission beside it (the ids of the named materials emit only if they are emitters).
    let mut emission = vec![None; mats.len()];
    let ids: Vec<Option<u32>> = desc
        .objects
        .iter()
        .map(|o| {
            let Body::Surface(name) = &o.body else { return None };
            let id = names.iter().position(|n| *n == name.0).expect("material names are validated at load");
            let Some(emit) = &o.emit else { return Some(id as u32) };
            let (radiance, texture) = match &emit.radiance {
                Color::Value(v) => (v.0, None),
                Color::Texture(t) => {
                    let t = texture_id(desc, t);
                    (textures.mean(t), Some(t))
                }
            };
            mats.push(mats[id]);
            per_material.push(per_material[id]);
            wrappers.push(wrappers[id]);
            emission.push(Some(AreaEmission { radiance, texture, two_sided: emit.two_sided }));
            Some(mats.len() as u32 - 1)
        })
        .collect();
    let emits = |id: u32| mats[id as usize].is_emissive() || emission[id as usize].is_some();
    // Boxes and quads whose keyframes turn or scale them become meshes, so that they blur
    // by their motion over the shutter as instances do (not at their mid-shutter pose).
    let shapes: Vec<Form> = desc
        .objects
        .iter()
        .zip(&ids)
        .map(|(o, id)| {
            let turns = o.animate.as_ref().is_some_and(|a| a.rotate.is_some() || a.scale.is_some());
            let surface = id.is_some_and(|id| !emits(id));
            match (turns && surface).then(|| flat_mesh(&o.shape.form())).flatten() {
                Some(mesh) => Form::Mesh(Arc::new(mesh)),
                None => o.shape.form(),
            }
        })
        .collect();
    // Emitting meshes stay primitives, so that light sampling finds their triangles.
    let instanced: Vec<bool> = shapes
        .iter()
        .zip(&ids)
        .map(|(shape, id)| matches!(shape, Form::Mesh(_)) && id.is_some_and(|id| !emits(id)))
        .collect();
    let id = |name: &str| texture_id(desc, name);
    let lights =
        desc.lights.iter().map(|l| l.to_light(&LightTextures { textures: &textures, id: &id })).collect();
    world.insert_resource(Materials(mats));
    let wrappers = crate::material::wrap::Wrappers(wrappers);
    world.insert_resource(MaterialWrappers(Arc::new(wrappers)));
    world.insert_resource(SceneTextures { textures: Arc::new(textures), per_material });
    world.insert_resource(ObjectEmission(emission));
    for (i, (((obj, instanced), shape), id)) in
        desc.objects.iter().zip(instanced).zip(shapes).zip(ids).enumerate()
    {
        let placed = (Transform(compose(&obj.transform)), Shape(shape), ObjectIndex(i as u32));
        let mut e = match id {
            Some(id) => world.spawn((placed, MaterialId(id))),
            // Objects without a material id are volumes.
            None => {
                let Body::Volume(m) = &obj.body else { continue };
                match m.medium() {
                    Some(medium) => world.spawn((placed, Filling(medium))),
                    None => world.spawn((placed, GridSequence((**m).clone()), GridInputs::default())),
                }
            }
        };
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
        filter: r.filter.into(),
        light_sampler: r.light_sampler,
        guiding: r.guiding,
        light_tracing: r.light_tracing,
    }));
    world.insert_resource(CameraParams(desc.camera, None));
    world.insert_resource(FrameTime { open: desc.camera.shutter.0, close: desc.camera.shutter.1 });
    world.insert_resource(CameraKeys { base: desc.camera, keys: desc.animation.camera.clone() });
    let emit_keys = desc
        .animation
        .emit
        .iter()
        .map(|(name, track)| {
            let id = names.iter().position(|n| *n == name.0).expect("material names are validated at load");
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
            let texels = img.texels();
            Background::Environment(Arc::new(EnvironmentMap::new(
                img.width, img.height, texels, scale.0, rotate.0,
            )))
        }
    }));
    world.insert_resource(PunctualLights(lights));
    world.init_resource::<SceneLights>();
    world.init_resource::<SceneGeometry>();
    world.init_resource::<SceneInstances>();
    world.init_resource::<MeshLibrary>();
    world.init_resource::<SceneMedia>();
    world.init_resource::<Extracted>();
    world.init_resource::<FrameErrors>();
    world.init_resource::<FrameNumber>();
    world.init_resource::<GridReads>();
}

/// A shape made of quads (a box, a quad) as a triangle mesh in its own space (two triangles
/// per quad, uvs as the quads'); `None` for meshes and shapes with other primitives.
fn flat_mesh(shape: &Form) -> Option<MeshData> {
    if let Form::Mesh(_) = shape {
        return None;
    }
    let mut quads = Vec::new();
    primitives(shape, &Affine3A::IDENTITY, &mut quads).ok()?;
    let mut mesh = MeshData { uvs: Some(Vec::new()), ..Default::default() };
    for p in quads {
        let Primitive::Quad(q) = p else { return None };
        let base = mesh.positions.len() as u32;
        mesh.positions.extend([q.q, q.q + q.u, q.q + q.u + q.v, q.q + q.v]);
        mesh.uvs.as_mut()?.extend([glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::ONE, glam::Vec2::Y]);
        // The triangles turn as the quad faces: about u x v, or the other way if it is flipped.
        match q.n.dot(q.u.cross(q.v)) < 0.0 {
            false => mesh.triangles.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]),
            true => mesh.triangles.extend([[base, base + 2, base + 1], [base, base + 3, base + 2]]),
        }
    }
    Some(mesh)
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
    let mut list: Vec<Texture> = desc.textures.0.iter().map(|(_, t)| t.model().build(&mut sub)).collect();
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
