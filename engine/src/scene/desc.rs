//! The scene description as written in RON. Every struct denies unknown fields; defaults are
//! the ones documented on each field.

use super::values::*;
pub use crate::material::MaterialDesc;
use crate::placement::{Form, MAX_COORDINATE, primitives};
use crate::render_scene::SamplerKind;
use crate::texture::{TextureImage, Wrap};
use glam::{Affine3A, Mat4, Vec3, Vec4};
use serde::{Deserialize, Deserializer, de::Error};
use std::cell::{Cell, RefCell};
use std::num::NonZeroU32;

/// A whole scene file: `Scene(camera: .., render: .., background: .., materials: {..}, objects: [..])`.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields, rename = "Scene")]
pub struct SceneDesc {
    /// Declared parameters and their defaults, as RON text: `$name` elsewhere in the file
    /// stands for the value (substituted before parsing; `-D name=value` overrides).
    #[serde(default)]
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

/// Thin-lens camera.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(try_from = "RawCamera")]
pub struct CameraDesc {
    /// Eye position.
    pub look_from: Vec3,
    /// Point looked at.
    pub look_at: Vec3,
    /// Up vector (default (0, 1, 0)); must not be parallel to the view direction.
    pub vup: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub vfov: f32,
    /// Lens radius (default 0: pinhole).
    pub aperture_radius: f32,
    /// Distance to the plane in focus (default: |look_at - look_from|).
    pub focus_dist: f32,
    /// Shutter open and close times (default (0, 0): no motion blur).
    pub shutter: (f32, f32),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Camera")]
struct RawCamera {
    look_from: V3,
    look_at: V3,
    #[serde(default = "default_vup")]
    vup: Direction,
    vfov: Fov,
    #[serde(default)]
    aperture_radius: NonNegative,
    #[serde(default)]
    focus_dist: Option<Positive>,
    #[serde(default)]
    shutter: (Finite, Finite),
}

fn default_vup() -> Direction {
    Direction(Vec3::Y)
}

impl TryFrom<RawCamera> for CameraDesc {
    type Error = String;
    fn try_from(r: RawCamera) -> Result<Self, String> {
        let view = r.look_at.0 - r.look_from.0;
        if view.length_squared() == 0.0 {
            return Err("camera: look_from and look_at are the same point".into());
        }
        if view.normalize().cross(r.vup.0.normalize()).length_squared() < 1e-12 {
            return Err("camera: vup is parallel to the view direction".into());
        }
        let far = [r.look_from.0.abs().max_element(), r.look_at.0.abs().max_element(), r.aperture_radius.0]
            .into_iter()
            .chain(r.focus_dist.map(|f| f.0))
            .any(|x| x > MAX_COORDINATE);
        if far || view.length() > MAX_COORDINATE {
            return Err(format!("camera: positions and distances must lie within {MAX_COORDINATE:e} units"));
        }
        if r.shutter.1.0 < r.shutter.0.0 {
            return Err(format!(
                "camera: shutter closes ({}) before it opens ({})",
                r.shutter.1.0, r.shutter.0.0
            ));
        }
        Ok(Self {
            look_from: r.look_from.0,
            look_at: r.look_at.0,
            vup: r.vup.0,
            vfov: r.vfov.0,
            aperture_radius: r.aperture_radius.0,
            focus_dist: r.focus_dist.map_or(view.length(), |f| f.0),
            shutter: (r.shutter.0.0, r.shutter.1.0),
        })
    }
}

/// Image size and sampling.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields, default, rename = "Render")]
pub struct RenderDesc {
    /// Width in pixels (default 512).
    pub width: NonZeroU32,
    /// Height in pixels (default 512).
    pub height: NonZeroU32,
    /// Samples per pixel (default 64).
    pub spp: NonZeroU32,
    /// Maximum number of bounces (default 64).
    pub max_depth: u32,
    /// Bounces before Russian roulette may end a path (default 5).
    pub rr_depth: u32,
    /// Seed of every random number of the image (default 0).
    pub seed: u64,
    /// Scale samples down so that no component exceeds this (default: none, which is unbiased).
    pub clamp: Option<Positive>,
    /// How the samples' random numbers are made: `Sobol` (default), `Stratified`, `Independent`.
    pub sampler: SamplerKind,
    /// Render only this window `(x0, x1, y0, y1)`, fractions of the image in [0, 1] as
    /// pbrt-v4's crop window (default: the whole image).
    pub crop: Option<CropWindow>,
}

/// `(x0, x1, y0, y1)` in [0, 1], x0 < x1 and y0 < y1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CropWindow(pub [f32; 4]);

impl<'de> Deserialize<'de> for CropWindow {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let (x0, x1, y0, y1) = <(UnitInterval, UnitInterval, UnitInterval, UnitInterval)>::deserialize(d)?;
        let w = [x0.0, x1.0, y0.0, y1.0];
        CropWindow::new(w).map_err(D::Error::custom)
    }
}

impl CropWindow {
    /// Checks `(x0, x1, y0, y1)`.
    pub fn new(w: [f32; 4]) -> Result<Self, String> {
        let [x0, x1, y0, y1] = w;
        if !w.iter().all(|v| (0.0..=1.0).contains(v)) || !(x0 < x1 && y0 < y1) {
            return Err(format!(
                "a crop window is (x0, x1, y0, y1) with 0 <= x0 < x1 <= 1 and 0 <= y0 < y1 <= 1, not ({x0}, {x1}, {y0}, {y1})"
            ));
        }
        Ok(Self(w))
    }
}

impl Default for RenderDesc {
    fn default() -> Self {
        let n = |x| NonZeroU32::new(x).unwrap();
        Self {
            width: n(512),
            height: n(512),
            spp: n(64),
            max_depth: 64,
            rr_depth: 5,
            seed: 0,
            clamp: None,
            sampler: SamplerKind::default(),
            crop: None,
        }
    }
}

/// Radiance seen by rays that leave the scene.
#[derive(Deserialize, Debug, Clone, Default)]
#[serde(deny_unknown_fields, rename = "Background")]
pub enum BackgroundDesc {
    /// No light from outside (default).
    #[default]
    Black,
    /// The same radiance in every direction.
    Constant(Rgb),
    /// `(1 - a) * bottom + a * top` with `a = 0.5 * (dir.y + 1)`.
    Sky {
        /// Radiance straight down (default (1, 1, 1)).
        #[serde(default = "white")]
        bottom: Rgb,
        /// Radiance straight up (default (0.5, 0.7, 1.0)).
        #[serde(default = "sky_blue")]
        top: Rgb,
    },
    /// `Environment(file: "sky.exr", scale: 1, rotate: 0)`: a lat-long HDR map (EXR or HDR,
    /// linear; relative to the scene file), sampled as a light by its luminance. A direction
    /// `d` looks up `u = atan2(d.x, -d.z) / 2 pi`, `v = acos(d.y) / pi` (the top row is +y, the
    /// left edge -z), bilinearly between texel centres.
    Environment {
        /// The map.
        file: ImageFile,
        /// Factor on its radiance (default 1).
        #[serde(default = "unit_scale")]
        scale: NonNegative,
        /// Rotation of the map about +y in degrees, counter-clockwise seen from above (default 0).
        #[serde(default)]
        rotate: Finite,
    },
}

fn unit_scale() -> NonNegative {
    NonNegative(1.0)
}

/// A light that is not an object: `Point(..)`, `Spot(..)` or `Directional(..)`.
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields, rename = "Light")]
pub enum LightDesc {
    /// `Point(position: (2, 3, 2), intensity: (10, 10, 10))`: radiant intensity in W/sr, the
    /// same in every direction.
    Point {
        /// Where it is.
        position: LightPosition,
        /// Radiant intensity (W/sr).
        intensity: Rgb,
    },
    /// `Spot(position: (0, 4, 0), look_at: (0, 0, 0), intensity: (50, 50, 50), cone_angle: 30,
    /// falloff_start: 25)`: a point light shining into a cone about `look_at - position`.
    Spot {
        /// Where it is.
        position: LightPosition,
        /// A point on the cone's axis.
        look_at: V3,
        /// Radiant intensity on the axis (W/sr).
        intensity: Rgb,
        /// Half angle of the cone in degrees, in (0, 180) (default 30).
        #[serde(default = "default_cone")]
        cone_angle: Finite,
        /// Angle from the axis where the falloff to the cone's edge starts, in degrees, in
        /// [0, cone_angle] (default 25).
        #[serde(default = "default_falloff")]
        falloff_start: Finite,
    },
    /// `Directional(direction: (0, -1, 0), irradiance: (3, 3, 3))`: parallel light travelling
    /// along `direction`, of irradiance (W/m^2) on a surface facing it.
    Directional {
        /// The direction the light travels in.
        direction: Direction,
        /// Irradiance on a surface facing the light.
        irradiance: Rgb,
    },
}

fn default_cone() -> Finite {
    Finite(30.0)
}

fn default_falloff() -> Finite {
    Finite(25.0)
}

/// A light's position: three finite numbers within [`MAX_COORDINATE`] of the origin.
#[derive(Debug, Clone, Copy)]
pub struct LightPosition(pub Vec3);

impl<'de> Deserialize<'de> for LightPosition {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let p = V3::deserialize(d)?.0;
        match p.abs().max_element() <= MAX_COORDINATE {
            true => Ok(LightPosition(p)),
            false => {
                Err(D::Error::custom(format!("the light is beyond {MAX_COORDINATE:e} units from the origin")))
            }
        }
    }
}

impl LightDesc {
    /// Checks the cone of a spot light.
    fn check(&self) -> Result<(), String> {
        if let LightDesc::Spot { position, look_at, cone_angle, falloff_start, .. } = *self {
            if !(cone_angle.0 > 0.0 && cone_angle.0 < 180.0) {
                return Err(format!(
                    "spot light: cone_angle must be in (0, 180) degrees, found {}",
                    cone_angle.0
                ));
            }
            if !(falloff_start.0 >= 0.0 && falloff_start.0 <= cone_angle.0) {
                return Err(format!(
                    "spot light: falloff_start must be in [0, cone_angle = {}] degrees, found {}",
                    cone_angle.0, falloff_start.0
                ));
            }
            if (look_at.0 - position.0).length_squared() == 0.0 {
                return Err("spot light: look_at is the light's position".into());
            }
        }
        Ok(())
    }

    /// The light in world space.
    pub fn to_light(&self) -> crate::lights::PunctualLight {
        use crate::lights::PunctualLight;
        match *self {
            LightDesc::Point { position, intensity } => {
                PunctualLight::Point { position: position.0.into(), intensity: intensity.0 }
            }
            LightDesc::Spot { position, look_at, intensity, cone_angle, falloff_start } => {
                PunctualLight::Spot {
                    position: position.0.into(),
                    axis: (look_at.0 - position.0).normalize().into(),
                    intensity: intensity.0,
                    cos_falloff: falloff_start.0.to_radians().cos(),
                    cos_total: cone_angle.0.to_radians().cos(),
                }
            }
            LightDesc::Directional { direction, irradiance } => PunctualLight::Directional {
                to_light: (-direction.0.normalize()).into(),
                irradiance: irradiance.0,
            },
        }
    }
}

fn white() -> Rgb {
    Rgb(Vec3::ONE)
}

fn sky_blue() -> Rgb {
    Rgb(Vec3::new(0.5, 0.7, 1.0))
}

/// A colour written out, or the name of a texture from `textures`.
#[derive(Debug, Clone, PartialEq)]
pub enum Color<T> {
    /// `(r, g, b)`.
    Value(T),
    /// `"name"`.
    Texture(String),
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Color<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for V<T> {
            type Value = Color<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a colour (r, g, b) or the name of a texture")
            }
            fn visit_str<E: Error>(self, name: &str) -> Result<Self::Value, E> {
                check_texture_name(name).map_err(E::custom)?;
                Ok(Color::Texture(name.to_owned()))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
                T::deserialize(serde::de::value::SeqAccessDeserializer::new(seq)).map(Color::Value)
            }
        }
        d.deserialize_any(V(std::marker::PhantomData))
    }
}

/// A texture as written in the scene; colours inside may name textures defined before it.
#[derive(Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, rename = "Texture")]
pub enum TextureDesc {
    /// `Solid((r, g, b))`.
    Solid(Rgb),
    /// `Checker(scale: s, even: .., odd: ..)`: 3-D cells of side s in world space.
    Checker {
        /// Cell size.
        scale: Positive,
        /// Even cells.
        even: Color<Rgb>,
        /// Odd cells.
        odd: Color<Rgb>,
    },
    /// `UvChecker(u: 8, v: 4, even: .., odd: ..)`: u by v cells over the uv square.
    UvChecker {
        /// Cells along u.
        u: Positive,
        /// Cells along v.
        v: Positive,
        /// Even cells.
        even: Color<Rgb>,
        /// Odd cells.
        odd: Color<Rgb>,
    },
    /// `Image(file: "earth.png", wrap: Repeat)`: PNG, JPEG, HDR or EXR, relative to the scene
    /// file; 8-bit images are sRGB, float ones linear.
    Image {
        /// The file.
        file: ImageFile,
        /// `Repeat` (default), `Clamp` or `Mirror`.
        #[serde(default)]
        wrap: Wrap,
    },
    /// `Noise(scale: 4)`: smooth Perlin gradient noise of `scale * p`, in [0, 1].
    Noise {
        /// Frequency.
        scale: Positive,
        /// Colour the noise multiplies (default white).
        #[serde(default = "white")]
        color: Rgb,
    },
    /// `BlockyNoise(scale: 4)`: one random value per lattice cell, in [0, 1).
    BlockyNoise {
        /// Frequency.
        scale: Positive,
        /// Colour the noise multiplies (default white).
        #[serde(default = "white")]
        color: Rgb,
    },
    /// `Turbulence(scale: 4, depth: 7)`: sum of octaves of |noise|, in [0, 2).
    Turbulence {
        /// Frequency.
        scale: Positive,
        /// Octaves, 1 to [`MAX_OCTAVES`] (default 7).
        #[serde(default = "seven", deserialize_with = "octaves")]
        depth: u32,
        /// Colour the turbulence multiplies (default white).
        #[serde(default = "white")]
        color: Rgb,
    },
    /// `Marble(scale: 4, depth: 7)`: 0.5 (1 + sin(scale z + 10 turbulence)), in [0, 1].
    Marble {
        /// Frequency.
        scale: Positive,
        /// Octaves of the turbulence, 1 to [`MAX_OCTAVES`] (default 7).
        #[serde(default = "seven", deserialize_with = "octaves")]
        depth: u32,
        /// Colour of the veins' bright parts (default white).
        #[serde(default = "white")]
        color: Rgb,
    },
}

fn seven() -> u32 {
    7
}

/// The most octaves of turbulence: the 25th would weigh 2^-24 of the first, below what an f32
/// sum keeps (and a depth of billions made one texture lookup run for minutes).
pub const MAX_OCTAVES: u32 = 24;

fn octaves<'de, D: Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
    let n = u32::deserialize(d)?;
    match (1..=MAX_OCTAVES).contains(&n) {
        true => Ok(n),
        false => Err(D::Error::custom(format!("expected 1 to {MAX_OCTAVES} octaves, found {n}"))),
    }
}

/// An image file, read when the scene is loaded.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageFile {
    /// The path as written.
    pub path: std::path::PathBuf,
    /// The decoded image.
    pub image: std::sync::Arc<TextureImage>,
}

impl<'de> Deserialize<'de> for ImageFile {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let path = std::path::PathBuf::from(String::deserialize(d)?);
        let image = match SCENE_DIR.with(|s| s.borrow().clone()) {
            Some(dir) => TextureImage::load(&dir.join(&path)).map_err(D::Error::custom)?,
            None => TextureImage::default(),
        };
        Ok(ImageFile { path, image: std::sync::Arc::new(image) })
    }
}

/// The triangles of an OBJ file, read when the scene is loaded. Objects naming the same file
/// share one mesh (and, as instances, one BLAS).
#[derive(Debug, Clone, PartialEq)]
pub struct MeshFile {
    /// The path as written.
    pub path: std::path::PathBuf,
    /// Positions and triangles.
    pub mesh: std::sync::Arc<crate::mesh::MeshData>,
}

impl<'de> Deserialize<'de> for MeshFile {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let path = std::path::PathBuf::from(String::deserialize(d)?);
        let Some(dir) = SCENE_DIR.with(|s| s.borrow().clone()) else {
            return Ok(MeshFile { path, mesh: Default::default() });
        };
        let full = dir.join(&path);
        if let Some(mesh) = MESHES.with(|m| m.borrow().get(&full).cloned()) {
            return Ok(MeshFile { path, mesh });
        }
        let mesh = std::sync::Arc::new(read_obj(&full).map_err(D::Error::custom)?);
        MESHES.with(|m| m.borrow_mut().insert(full, mesh.clone()));
        Ok(MeshFile { path, mesh })
    }
}

/// An edge (by vertex position) that borders an odd number of triangles, and that number: a
/// mesh without one is closed, so a ray's hits alternate between entering and leaving it.
pub fn open_edge(mesh: &crate::mesh::MeshData) -> Option<(glam::Vec3A, glam::Vec3A, u32)> {
    use std::collections::HashMap;
    let key = |p: glam::Vec3A| p.to_array().map(f32::to_bits);
    let mut count: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (key(mesh.positions[t[k] as usize]), key(mesh.positions[t[(k + 1) % 3] as usize]));
            *count.entry(if a < b { (a, b) } else { (b, a) }).or_default() += 1;
        }
    }
    let pos = |k: [u32; 3]| glam::Vec3A::from_array(k.map(f32::from_bits));
    let mut odd: Vec<_> = count.into_iter().filter(|(_, n)| n % 2 == 1).collect();
    odd.sort_unstable();
    odd.first().map(|&((a, b), n)| (pos(a), pos(b), n))
}

/// Positions and triangles of every model in an OBJ file (faces triangulated as fans).
fn read_obj(path: &std::path::Path) -> Result<crate::mesh::MeshData, String> {
    parse_obj(&super::files::read_bounded(path, super::files::MAX_ASSET_BYTES, "mesh")?, path)
}

/// Positions and triangles of every model in the OBJ text `bytes` (faces triangulated as
/// fans); `path` names the file in errors.
pub fn parse_obj(bytes: &[u8], path: &std::path::Path) -> Result<crate::mesh::MeshData, String> {
    check_obj_indices(bytes, path)?;
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    // `mtllib` lines are ignored: materials come from the scene, and a line naming any file
    // (a device, a folder elsewhere) is never opened.
    let no_materials = |_: &std::path::Path| Ok((Vec::new(), Default::default()));
    let (models, _) = tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &options, no_materials)
        .map_err(|e| format!("cannot read the mesh {}: {e}", path.display()))?;
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    // Vertex normals and uvs count only if every model has them.
    let (mut normals, mut uvs) = (Some(Vec::new()), Some(Vec::new()));
    for m in models {
        let m = m.mesh;
        let base = positions.len() as u32;
        let n = m.positions.len() / 3;
        positions.extend(m.positions.chunks_exact(3).map(|p| glam::Vec3A::new(p[0], p[1], p[2])));
        triangles.extend(m.indices.chunks_exact(3).map(|t| [base + t[0], base + t[1], base + t[2]]));
        match (&mut normals, m.normals.len() == 3 * n) {
            (Some(v), true) => {
                v.extend(m.normals.chunks_exact(3).map(|p| glam::Vec3A::new(p[0], p[1], p[2])))
            }
            _ => normals = None,
        }
        match (&mut uvs, m.texcoords.len() == 2 * n) {
            (Some(v), true) => v.extend(m.texcoords.chunks_exact(2).map(|t| glam::Vec2::new(t[0], t[1]))),
            _ => uvs = None,
        }
    }
    // Vertex normals of unit length, as written when they are (within 1e-4), else normalised
    // (scaled down first: the square of a component of 1e38 overflowed when they were
    // interpolated, found by the obj fuzzer), or zero.
    let unit = |n: glam::Vec3A| match (n.length_squared() - 1.0).abs() < 1e-4 {
        true => n,
        false => (n / n.abs().max_element()).normalize_or_zero(),
    };
    let normals =
        normals.filter(|n| n.iter().all(|v| v.is_finite())).map(|n| n.into_iter().map(unit).collect());
    let uvs = uvs.filter(|u| u.iter().all(|v| v.is_finite()));
    if !positions.iter().all(|p| p.is_finite()) {
        return Err(format!("the mesh {} has a vertex that is not a finite number", path.display()));
    }
    if triangles.is_empty() {
        return Err(format!("the mesh {} has no faces", path.display()));
    }
    if triangles.iter().flatten().any(|&i| i as usize >= positions.len()) {
        return Err(format!("the mesh {} has a face with a vertex index out of range", path.display()));
    }
    Ok(crate::mesh::MeshData { positions, triangles, normals, uvs })
}

/// Refuses face indices that refer to no vertex, texture coordinate or normal: a relative
/// (negative) one before the first, or one beyond the file's last. tobj (4.0.5) multiplies
/// texture and normal indices unchecked, so such an index overflowed inside it (found by the
/// `obj` fuzzer).
fn check_obj_indices(bytes: &[u8], path: &std::path::Path) -> Result<(), String> {
    const KINDS: [&str; 3] = ["v", "vt", "vn"];
    // Lines as tobj reads them (one that is not UTF-8 is its error).
    let lines = || bytes.split(|&b| b == b'\n').filter_map(|l| std::str::from_utf8(l).ok());
    let kind = |l: &str| l.split_whitespace().next().and_then(|w| KINDS.iter().position(|k| *k == w));
    let mut total = [0u64; 3];
    lines().filter_map(kind).for_each(|k| total[k] += 1);
    let mut seen = [0u64; 3];
    for (n, line) in lines().enumerate() {
        if let Some(k) = kind(line) {
            seen[k] += 1;
        }
        let mut words = line.split_whitespace();
        if !matches!(words.next(), Some("f" | "l")) {
            continue;
        }
        for (k, index) in words.flat_map(|w| w.split('/').take(3).enumerate()) {
            let Ok(i) = index.parse::<i64>() else { continue };
            let refers = if i < 0 { i.unsigned_abs() <= seen[k] } else { i as u64 <= total[k] };
            if !refers {
                let what = ["vertex", "texture coordinate", "normal"][k];
                return Err(format!(
                    "the mesh {}: line {}: index {i} refers to no {what}",
                    path.display(),
                    n + 1
                ));
            }
        }
    }
    Ok(())
}

/// The `textures: { "name": Texture(..), .. }` map, in file order; names are unique.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NamedTextures(pub Vec<(String, TextureDesc)>);

impl<'de> Deserialize<'de> for NamedTextures {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = NamedTextures;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a map from texture names to textures")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut out: Vec<(String, TextureDesc)> = Vec::new();
                while let Some(name) = map.next_key::<String>()? {
                    if out.iter().any(|(n, _)| *n == name) {
                        return Err(A::Error::custom(format!("texture \"{name}\" is defined twice")));
                    }
                    // Inside a texture, only the textures before it may be named (no cycles).
                    TEXTURES_BEFORE.set(Some(out.len()));
                    let t = map.next_value();
                    TEXTURES_BEFORE.set(None);
                    out.push((name, t?));
                }
                Ok(NamedTextures(out))
            }
        }
        d.deserialize_map(V)
    }
}

/// Checks a texture name against the scene's textures (in the second parsing pass).
fn check_texture_name(name: &str) -> Result<(), String> {
    TEXTURE_NAMES.with(|t| match &*t.borrow() {
        None => Ok(()),
        Some(names) => {
            let before = TEXTURES_BEFORE.get();
            let visible = &names[..before.unwrap_or(names.len()).min(names.len())];
            if visible.iter().any(|n| n == name) {
                Ok(())
            } else if before.is_some() && names.iter().any(|n| n == name) {
                Err(format!("texture \"{name}\" must be defined before the texture that uses it"))
            } else if visible.is_empty() {
                Err(format!("unknown texture \"{name}\"; no textures are defined before this point"))
            } else {
                let list: Vec<String> = visible.iter().map(|n| format!("\"{n}\"")).collect();
                Err(format!("unknown texture \"{name}\"; defined: {}", list.join(", ")))
            }
        }
    })
}

/// The `materials: { "name": Material(..), .. }` map, in file order; names are unique.
#[derive(Debug, Clone, Default)]
pub struct NamedMaterials(pub Vec<(String, MaterialDesc)>);

impl NamedMaterials {
    /// (name, material) pairs in file order.
    pub fn iter(&self) -> impl Iterator<Item = &(String, MaterialDesc)> {
        self.0.iter()
    }
}

impl<'de> Deserialize<'de> for NamedMaterials {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = NamedMaterials;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a map from material names to materials")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut out: Vec<(String, MaterialDesc)> = Vec::new();
                while let Some(name) = map.next_key::<String>()? {
                    if out.iter().any(|(n, _)| *n == name) {
                        return Err(A::Error::custom(format!("material \"{name}\" is defined twice")));
                    }
                    let m = map.next_value()?;
                    out.push((name, m));
                }
                Ok(NamedMaterials(out))
            }
        }
        d.deserialize_map(V)
    }
}

thread_local! {
    /// The scene's texture names, in the second pass.
    static TEXTURE_NAMES: RefCell<Option<Vec<String>>> = const { RefCell::new(None) };
    /// While a texture is parsed: how many textures precede it.
    static TEXTURES_BEFORE: Cell<Option<usize>> = const { Cell::new(None) };
    /// The directory image paths are relative to, in the second pass (images load then).
    static SCENE_DIR: RefCell<Option<std::path::PathBuf>> = const { RefCell::new(None) };
    /// The index of the object being parsed, while inside `objects`.
    static OBJECT_INDEX: Cell<Option<usize>> = const { Cell::new(None) };
    static MATERIAL_NAMES: RefCell<Option<Vec<String>>> = const { RefCell::new(None) };
    /// The names of the `DiffuseLight` materials, in the second pass.
    static LIGHT_NAMES: RefCell<Option<Vec<String>>> = const { RefCell::new(None) };
    /// Meshes read so far in this load, by path: each file is read once and shared.
    static MESHES: RefCell<std::collections::HashMap<std::path::PathBuf, std::sync::Arc<crate::mesh::MeshData>>> =
        RefCell::new(Default::default());
}

/// The index in `objects` of the object the parser stopped in, if it stopped in one: errors
/// name it. Taking it resets it for the next parse.
pub(crate) fn take_current_object() -> Option<usize> {
    OBJECT_INDEX.take()
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
                OBJECT_INDEX.set(Some(out.len()));
                match seq.next_element()? {
                    Some(o) => out.push(o),
                    None => break,
                }
            }
            OBJECT_INDEX.set(None);
            Ok(out)
        }
    }
    d.deserialize_seq(V)
}

/// While alive, [`MaterialRef`]s parsed on this thread must name one of the given materials.
///
/// Likewise texture names, and images load relative to `dir`.
pub(crate) struct MaterialNameScope;

impl MaterialNameScope {
    pub(crate) fn enter(
        materials: Vec<String>,
        lights: Vec<String>,
        textures: Vec<String>,
        dir: std::path::PathBuf,
    ) -> Self {
        MATERIAL_NAMES.with(|m| *m.borrow_mut() = Some(materials));
        LIGHT_NAMES.with(|m| *m.borrow_mut() = Some(lights));
        TEXTURE_NAMES.with(|m| *m.borrow_mut() = Some(textures));
        SCENE_DIR.with(|m| *m.borrow_mut() = Some(dir));
        MaterialNameScope
    }
}

impl Drop for MaterialNameScope {
    fn drop(&mut self) {
        MATERIAL_NAMES.with(|m| *m.borrow_mut() = None);
        LIGHT_NAMES.with(|m| *m.borrow_mut() = None);
        TEXTURE_NAMES.with(|m| *m.borrow_mut() = None);
        SCENE_DIR.with(|m| *m.borrow_mut() = None);
        MESHES.with(|m| m.borrow_mut().clear());
        TEXTURES_BEFORE.set(None);
    }
}

/// The name of a material defined in `materials`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MaterialRef(pub String);

impl<'de> Deserialize<'de> for MaterialRef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        MATERIAL_NAMES.with(|m| match &*m.borrow() {
            Some(names) if names.is_empty() => {
                Err(D::Error::custom(format!("unknown material \"{name}\"; no materials are defined")))
            }
            Some(names) if !names.contains(&name) => {
                let list: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
                Err(D::Error::custom(format!("unknown material \"{name}\"; defined: {}", list.join(", "))))
            }
            _ => Ok(MaterialRef(name.clone())),
        })
    }
}

/// The name of a `DiffuseLight` material.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LightRef(pub String);

impl<'de> Deserialize<'de> for LightRef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let MaterialRef(name) = MaterialRef::deserialize(d)?;
        LIGHT_NAMES.with(|l| match &*l.borrow() {
            Some(lights) if !lights.contains(&name) => Err(D::Error::custom(format!(
                "material \"{name}\" is not a DiffuseLight: only emitters have `emit` keys"
            ))),
            _ => Ok(LightRef(name.clone())),
        })
    }
}

/// One object: a shape with either a material (a surface) or a medium (a volume), and an
/// optional list of transforms.
#[derive(Deserialize, Debug, Clone)]
#[serde(try_from = "RawObject")]
pub struct ObjectDesc {
    /// The shape, in object space.
    pub shape: ShapeDesc,
    /// What the shape is.
    pub body: Body,
    /// Transforms applied in order, first to last (default none).
    pub transform: Vec<TransformOp>,
    /// How it moves (default: it does not).
    pub motion: Option<MotionDesc>,
    /// Keyframed placement, applied after `transform` (default none).
    pub animate: Option<crate::animation::ObjectAnimation>,
}

/// Linear motion: at time `t` the object lies translated by `velocity * t` from where its
/// transform puts it.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields, rename = "Motion")]
pub struct MotionDesc {
    /// World units per unit of time.
    pub velocity: V3,
}

/// What an object's shape bounds.
#[derive(Debug, Clone, PartialEq)]
pub enum Body {
    /// `material: "name"`: a surface with a material from `materials`.
    Surface(MaterialRef),
    /// `medium: (density: .., albedo: ..)`: an invisible, index-matched boundary (a closed
    /// shape: sphere or box) filled with a homogeneous medium.
    Volume(MediumDesc),
}

/// A homogeneous medium with an isotropic phase function.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields, rename = "Medium")]
pub struct MediumDesc {
    /// Extinction coefficient sigma_t per unit length, the same in every channel (> 0).
    pub density: Positive,
    /// Single-scattering albedo sigma_s / sigma_t, components in [0, 1].
    pub albedo: Albedo,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Object")]
struct RawObject {
    shape: ShapeDesc,
    #[serde(default)]
    material: Option<MaterialRef>,
    #[serde(default)]
    medium: Option<MediumDesc>,
    #[serde(default)]
    transform: Vec<TransformOp>,
    #[serde(default)]
    motion: Option<MotionDesc>,
    #[serde(default)]
    animate: Option<crate::animation::ObjectAnimation>,
}

impl TryFrom<RawObject> for ObjectDesc {
    type Error = String;
    /// The object must survive its transform: no quad flattened to no area, every coordinate
    /// within [`MAX_COORDINATE`]; a medium needs a closed shape.
    fn try_from(r: RawObject) -> Result<Self, String> {
        let body = match (r.material, r.medium) {
            (Some(m), None) => Body::Surface(m),
            (None, Some(_))
                if !matches!(
                    r.shape,
                    ShapeDesc::Sphere { .. } | ShapeDesc::Box { .. } | ShapeDesc::Mesh(_)
                ) =>
            {
                return Err("a medium needs a closed shape: Sphere, Box or a closed Mesh".into());
            }
            (None, Some(_)) if matches!(&r.shape, ShapeDesc::Mesh(m) if open_edge(&m.mesh).is_some()) => {
                let ShapeDesc::Mesh(m) = &r.shape else { unreachable!() };
                let (a, b, n) = open_edge(&m.mesh).unwrap();
                return Err(format!(
                    "a medium needs a closed mesh, but in {} the edge from {a} to {b} borders {n} triangle(s)",
                    m.path.display()
                ));
            }
            (None, Some(m)) => Body::Volume(m),
            (Some(_), Some(_)) => return Err("an object has a `material` or a `medium`, not both".into()),
            (None, None) => {
                return Err("an object needs a `material` (a surface) or a `medium` (a volume)".into());
            }
        };
        if r.motion.is_some() && matches!(body, Body::Volume(_)) {
            return Err("media do not move: `motion` is for surfaces".into());
        }
        if r.animate.is_some() && matches!(body, Body::Volume(_)) {
            return Err("media do not move: `animate` is for surfaces".into());
        }
        primitives(&r.shape.form(), &compose(&r.transform), &mut Vec::new()).map_err(|e| e.to_string())?;
        Ok(Self { shape: r.shape, body, transform: r.transform, motion: r.motion, animate: r.animate })
    }
}

/// Shapes.
#[derive(Deserialize, Debug, Clone, PartialEq)]
#[serde(try_from = "RawShape")]
pub enum ShapeDesc {
    /// `Sphere(center: (x, y, z), radius: r)`.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius (> 0).
        radius: f32,
    },
    /// `Quad(q: .., u: .., v: ..)`: the points q + a u + b v, a, b in [0, 1]; normal u x v.
    Quad {
        /// Corner.
        q: Vec3,
        /// First edge.
        u: Vec3,
        /// Second edge (not parallel to u).
        v: Vec3,
    },
    /// `Triangle(a: .., b: .., c: ..)`: normal (b - a) x (c - a); uv = barycentric weights of
    /// b and c.
    Triangle {
        /// First vertex.
        a: Vec3,
        /// Second vertex.
        b: Vec3,
        /// Third vertex.
        c: Vec3,
    },
    /// `Mesh(file: "assets/knot.obj")`: the triangles of an OBJ file (relative to the scene
    /// file), flat shaded; triangles without area are dropped.
    Mesh(MeshFile),
    /// `Box(a: .., b: ..)`: the axis-aligned box between two opposite corners, six quads facing out.
    Box {
        /// Minimum corner.
        min: Vec3,
        /// Maximum corner.
        max: Vec3,
    },
}

impl ShapeDesc {
    /// The shape as the world holds it (the mesh shared, not copied).
    pub fn form(&self) -> Form {
        match *self {
            ShapeDesc::Sphere { center, radius } => Form::Sphere { center: center.into(), radius },
            ShapeDesc::Quad { q, u, v } => Form::Quad { q: q.into(), u: u.into(), v: v.into() },
            ShapeDesc::Triangle { a, b, c } => Form::Triangle { a: a.into(), b: b.into(), c: c.into() },
            ShapeDesc::Mesh(ref file) => Form::Mesh(file.mesh.clone()),
            ShapeDesc::Box { min, max } => Form::Box { min: min.into(), max: max.into() },
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Shape")]
enum RawShape {
    Sphere { center: V3, radius: Positive },
    Quad { q: V3, u: V3, v: V3 },
    Triangle { a: V3, b: V3, c: V3 },
    Mesh { file: MeshFile },
    Box { a: V3, b: V3 },
}

impl TryFrom<RawShape> for ShapeDesc {
    type Error = String;
    fn try_from(r: RawShape) -> Result<Self, String> {
        Ok(match r {
            RawShape::Sphere { center, radius } => ShapeDesc::Sphere { center: center.0, radius: radius.0 },
            RawShape::Quad { q, u, v } => {
                let c = u.0.cross(v.0);
                if !(c.length_squared() > 0.0) {
                    return Err(format!("Quad has no area: u {} and v {} are parallel or zero", u.0, v.0));
                }
                ShapeDesc::Quad { q: q.0, u: u.0, v: v.0 }
            }
            RawShape::Triangle { a, b, c } => {
                if !((b.0 - a.0).cross(c.0 - a.0).length_squared() > 0.0) {
                    return Err(format!("Triangle has no area: {}, {} and {} are collinear", a.0, b.0, c.0));
                }
                ShapeDesc::Triangle { a: a.0, b: b.0, c: c.0 }
            }
            RawShape::Mesh { file } => ShapeDesc::Mesh(file),
            RawShape::Box { a, b } => {
                let (min, max) = (a.0.min(b.0), a.0.max(b.0));
                if (max - min).min_element() <= 0.0 {
                    return Err(format!("Box is flat: corners {} and {} share a coordinate", a.0, b.0));
                }
                ShapeDesc::Box { min, max }
            }
        })
    }
}

/// One step of an object's transform.
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(try_from = "RawTransform")]
pub struct TransformOp(pub Affine3A);

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Transform")]
enum RawTransform {
    Translate(V3),
    RotateX(Finite),
    RotateY(Finite),
    RotateZ(Finite),
    Rotate {
        axis: Direction,
        degrees: Finite,
    },
    Scale(V3),
    UniformScale(Finite),
    Shear {
        #[serde(default)]
        xy: Finite,
        #[serde(default)]
        xz: Finite,
        #[serde(default)]
        yx: Finite,
        #[serde(default)]
        yz: Finite,
        #[serde(default)]
        zx: Finite,
        #[serde(default)]
        zy: Finite,
    },
    Matrix(Vec<Vec<Finite>>),
}

impl TryFrom<RawTransform> for TransformOp {
    type Error = String;
    fn try_from(r: RawTransform) -> Result<Self, String> {
        let a = match r {
            RawTransform::Translate(t) => Affine3A::from_translation(t.0),
            RawTransform::RotateX(d) => Affine3A::from_rotation_x(d.0.to_radians()),
            RawTransform::RotateY(d) => Affine3A::from_rotation_y(d.0.to_radians()),
            RawTransform::RotateZ(d) => Affine3A::from_rotation_z(d.0.to_radians()),
            RawTransform::Rotate { axis, degrees } => {
                Affine3A::from_axis_angle(axis.0.normalize(), degrees.0.to_radians())
            }
            RawTransform::Scale(s) => Affine3A::from_scale(s.0),
            RawTransform::UniformScale(s) => Affine3A::from_scale(Vec3::splat(s.0)),
            // x' = x + xy y + xz z, and likewise for y' and z'.
            RawTransform::Shear { xy, xz, yx, yz, zx, zy } => Affine3A::from_mat3(glam::Mat3::from_cols(
                Vec3::new(1.0, yx.0, zx.0),
                Vec3::new(xy.0, 1.0, zy.0),
                Vec3::new(xz.0, yz.0, 1.0),
            )),
            RawTransform::Matrix(rows) => {
                if rows.len() != 4 || rows.iter().any(|r| r.len() != 4) {
                    return Err("Matrix: expected 4 rows of 4 numbers".into());
                }
                let r: Vec<Vec4> = rows.iter().map(|r| Vec4::new(r[0].0, r[1].0, r[2].0, r[3].0)).collect();
                if r[3] != Vec4::W {
                    return Err(format!("Matrix: the last row must be (0, 0, 0, 1), found {}", r[3]));
                }
                Affine3A::from_mat4(Mat4::from_cols(r[0], r[1], r[2], r[3]).transpose())
            }
        };
        // Singular relative to the matrix's own scale: a tiny uniform scale is fine.
        let size = (a.matrix3.x_axis.abs() + a.matrix3.y_axis.abs() + a.matrix3.z_axis.abs()).max_element();
        if !((a.matrix3 * size.recip()).determinant().abs() > f32::EPSILON) {
            return Err("transform is singular (it flattens the object)".into());
        }
        Ok(TransformOp(a))
    }
}

/// The product of a transform list: the first element is applied first.
pub fn compose(ops: &[TransformOp]) -> Affine3A {
    ops.iter().fold(Affine3A::IDENTITY, |acc, op| op.0 * acc)
}
