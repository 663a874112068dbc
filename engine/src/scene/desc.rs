//! The scene description as written in RON: the top-level `Scene(..)` and its animation
//! block. Every struct of the format denies unknown fields; defaults are the ones documented on
//! each field. The parts live beside it: `camera` (camera and render settings), `light`
//! (background and punctual lights), `material`, `texture`, `object` (shapes and bodies),
//! `transform` and `assets` (image and OBJ files).

use super::camera::{CameraDesc, RenderDesc};
use super::light::{BackgroundDesc, LightDesc};
use super::material::{LightRef, NamedMaterials};
use super::object::{Body, ObjectDesc};
use super::texture::NamedTextures;
use crate::format::{Positive, UnitInterval, context};
use serde::{Deserialize, Deserializer, de::Error};
use std::num::NonZeroU32;

/// A whole scene file: `Scene(camera: .., render: .., background: .., materials: {..}, objects: [..])`.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields, rename = "Scene")]
pub struct SceneDesc {
    /// Declared parameters and their defaults, as RON text: `$name` elsewhere in the file
    /// stands for the value (substituted before parsing; `-D name=value` overrides).
    #[serde(default, deserialize_with = "super::params::declarations")]
    pub parameters: std::collections::BTreeMap<String, String>,
    /// The camera.
    pub camera: CameraDesc,
    /// Image size and sampling (all fields have defaults).
    #[serde(default)]
    pub render: RenderDesc,
    /// What rays that leave the scene see (default black).
    #[serde(default)]
    pub background: BackgroundDesc,
    /// Textures by name (default none); a colour of a material may name one.
    #[serde(default)]
    pub textures: NamedTextures,
    /// Materials by name.
    pub materials: NamedMaterials,
    /// The objects.
    #[serde(deserialize_with = "objects")]
    pub objects: Vec<ObjectDesc>,
    /// Point, spot and directional lights (default none).
    #[serde(default, deserialize_with = "lights")]
    pub lights: Vec<LightDesc>,
    /// Frames, frame rate and shutter of `pathwave animate`, and the camera's and emitters'
    /// keyframes (default: a still).
    #[serde(default)]
    pub animation: AnimationDesc,
    /// Every file the load read, with a hash of what it read: the scene file, its includes,
    /// meshes, images and spectra. Not written in a scene: [`super::load_with`] fills it; a
    /// command checks each file it will write against it before any work, and the hashes
    /// identify the render in its checkpoints.
    #[serde(skip)]
    pub inputs: Vec<crate::format::files::InputFile>,
}

impl SceneDesc {
    /// The grid sequences of its media (a file per frame: see [`super::GridDesc`]), with the
    /// index of their object.
    pub fn grid_sequences(&self) -> impl Iterator<Item = (usize, &super::GridFrames)> {
        self.objects.iter().enumerate().flat_map(|(i, o)| {
            let sequences = match &o.body {
                Body::Volume(m) => Some(m.sequences().map(move |s| (i, s))),
                Body::Surface(_) => None,
            };
            sequences.into_iter().flatten()
        })
    }

    /// The files that frame `frame` reads besides the scene's [`inputs`](Self::inputs): those
    /// its grid sequences name for it.
    pub fn frame_files(&self, frame: u32) -> Vec<std::path::PathBuf> {
        self.grid_sequences().map(|(_, s)| s.path(frame)).collect()
    }

    /// Checks that every file frame `frame` reads is there and starts as a grid file does
    /// (without reading it all), naming the frame, the object and the path looked for.
    pub fn check_frame(&self, frame: u32) -> Result<(), String> {
        for (i, s) in self.grid_sequences() {
            s.check(frame).map_err(|e| format!("frame {frame}: objects[{i}]: {e}"))?;
        }
        Ok(())
    }
}

/// `animation: (frames: 48, fps: 24, shutter: 0.5, camera: (..), emit: [("light", ..)])`.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields, default, rename = "Animation")]
pub struct AnimationDesc {
    /// Frames that `pathwave animate` renders by default (default 1).
    pub frames: NonZeroU32,
    /// Frames per second (default 24): frame `i` is at time `i / fps`.
    pub fps: Positive,
    /// Shutter as a fraction of the frame interval, in [0, 1] (default 0: no motion blur).
    pub shutter: UnitInterval,
    /// Camera keyframes.
    pub camera: crate::animation::CameraAnimation,
    /// Emitted radiance keyframes of `DiffuseLight` materials, by material name.
    pub emit: Vec<(LightRef, crate::animation::RgbTrack)>,
}

impl Default for AnimationDesc {
    fn default() -> Self {
        Self {
            frames: NonZeroU32::MIN,
            fps: Positive(24.0),
            shutter: UnitInterval(0.0),
            camera: Default::default(),
            emit: Vec::new(),
        }
    }
}

/// `lights: [..]`, each light checked as it is read (the error points at its end).
fn lights<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<LightDesc>, D::Error> {
    struct V;
    impl<'de> serde::de::Visitor<'de> for V {
        type Value = Vec<LightDesc>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a list of lights")
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
            let mut out = Vec::new();
            while let Some(l) = seq.next_element::<LightDesc>()? {
                l.check().map_err(A::Error::custom)?;
                out.push(l);
            }
            Ok(out)
        }
    }
    d.deserialize_seq(V)
}

/// `objects: [..]`, noting the index of each element while it is parsed.
fn objects<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<ObjectDesc>, D::Error> {
    struct V;
    impl<'de> serde::de::Visitor<'de> for V {
        type Value = Vec<ObjectDesc>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a list of objects")
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
            let mut out = Vec::new();
            loop {
                context::set_current_object(Some(out.len()));
                match seq.next_element::<ObjectDesc>()? {
                    Some(o) => out.push(o),
                    None => break,
                }
            }
            context::set_current_object(None);
            Ok(out)
        }
    }
    d.deserialize_seq(V)
}
