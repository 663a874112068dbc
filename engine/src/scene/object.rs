//! `objects: [..]`: a shape with a material (a surface) or a medium (a volume), its transform,
//! motion and keyframes; checked as placed (`placement::primitives`) at load.

use super::assets::{GridFrames, GridPath, MeshFile, MeshPath, MeshSource, open_edge};
use super::material::MaterialRef;
use super::transform::{TransformOp, compose};
use crate::format::files::InputFile;
use crate::format::registry::{fields, registry};
use crate::format::{Albedo, Color, Radiance, V3, context};
use crate::media::grid::VoxelGrid;
use crate::placement::{Form, primitives};
use crate::shape::ShapeModel;
use serde::Deserialize;
use serde::de::{Error, VariantAccess};
use std::sync::Arc;

/// One object: a shape with either a material (a surface) or a medium (a volume), and an
/// optional list of transforms.
#[derive(Deserialize, Debug, Clone)]
#[serde(try_from = "RawObject")]
pub struct ObjectDesc {
    /// The shape, in object space.
    pub shape: ShapeDesc,
    /// What the shape is.
    pub body: Body,
    /// Light the surface emits besides what its material reflects (default none).
    pub emit: Option<EmitDesc>,
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

/// `emit: (radiance: (r, g, b), two_sided: false)`: the surface emits `radiance` (or a
/// texture's value at the point, by name) besides what its material reflects, as Mitsuba 3's
/// `area` emitter on a shape with a BSDF: on the side of the geometric normal only, unless
/// `two_sided`. Sampled as a light like an emitter's surface.
#[derive(Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, rename = "Emit")]
pub struct EmitDesc {
    /// Emitted radiance, or the name of a texture.
    pub radiance: Color<Radiance>,
    /// Emit on both sides (default false: only on the side of the normal).
    #[serde(default)]
    pub two_sided: bool,
}

/// What an object's shape bounds.
#[derive(Debug, Clone, PartialEq)]
pub enum Body {
    /// `material: "name"`: a surface with a material from `materials`.
    Surface(MaterialRef),
    /// `medium: (density: .., albedo: ..)`: an invisible, index-matched boundary (a closed
    /// shape: sphere, box or closed mesh) filled with a homogeneous medium.
    Volume(MediumDesc),
}

/// A medium with an isotropic phase function: homogeneous, or scaled by voxel grids.
#[derive(Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, rename = "Medium")]
pub struct MediumDesc {
    /// Extinction coefficient sigma_t per unit length: one number for every channel (> 0), or
    /// `(r, g, b)` per channel (each >= 0, one > 0).
    pub density: Density,
    /// Single-scattering albedo sigma_s / sigma_t, components in [0, 1].
    pub albedo: Albedo,
    /// `grid: (file: "smoke.vol", transform: [..])`: the density is `density` times the grid's
    /// value, inside the grid's cube only (default none: homogeneous). One number for
    /// `density` then.
    #[serde(default)]
    pub grid: Option<GridDesc>,
    /// `albedo_grid: (file: .., transform: [..])`: the albedo is `albedo` times the grid's
    /// colour (its edge values outside its cube), whose values lie in [0, 1] (default none).
    #[serde(default)]
    pub albedo_grid: Option<GridDesc>,
    /// The phase function (default `Isotropic`).
    #[serde(default)]
    pub phase: PhaseDesc,
}

/// A medium's phase function: `Isotropic` or `HenyeyGreenstein(g: 0.7)`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Default)]
#[serde(deny_unknown_fields, rename = "Phase")]
pub enum PhaseDesc {
    /// Every direction alike.
    #[default]
    Isotropic,
    /// Henyey-Greenstein's, of asymmetry `g` in (-1, 1): forwards for `g > 0`.
    HenyeyGreenstein {
        /// The mean cosine of the scattering angle.
        g: Asymmetry,
    },
}

/// A phase function's asymmetry, in (-1, 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Asymmetry(pub f32);

impl<'de> Deserialize<'de> for Asymmetry {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let g = f32::deserialize(d)?;
        match g.abs() < 1.0 {
            true => Ok(Asymmetry(g)),
            false => Err(D::Error::custom(format!("expected an asymmetry g in (-1, 1), found {g}"))),
        }
    }
}

/// The largest extinction a grid medium may reach (`density` times the grid's largest value).
pub const MAX_GRID_EXTINCTION: f32 = 1e7;

/// A voxel grid placed in the object: `(file: "smoke.vol", transform: [..])`. The grid fills
/// the unit cube `[0, 1]^3`, which `transform` (default none) places in the object's space,
/// before the object's own transform.
///
/// An OpenVDB file's grid (`(file: "smoke.vdb", name: "density", transform: [..])`, `name`
/// by default "density") is the dense box over its active voxels, each a cell centred on its
/// index as OpenVDB samples them, placed by the grid's own transform: the grid's world space
/// is the medium's space before `transform`, which places it in the object.
///
/// A `file` with `{frame}` or `{frame:0N}` in it (`smoke_{frame:04}.vdb`, see
/// [`FramePattern`](crate::format::frames::FramePattern)) is a sequence, a file per frame, such
/// as a simulation writes: frame `n` of `pathwave animate` reads the file named for `n`, and
/// `render --time t` the file of the frame that `animate` renders at `t` (frame 0 without
/// `--time`). Within a frame, motion blur included, the grid is that frame's file: there is no
/// interpolation between files. A frame's file is read when the frame is rendered, and only if
/// it is another file than the previous frame's.
#[derive(Debug, Clone, PartialEq)]
pub struct GridDesc {
    /// The file as written (a sequence's pattern).
    pub file: std::path::PathBuf,
    /// The grid's name in an OpenVDB file.
    pub name: Option<String>,
    /// The values.
    pub grid: GridValues,
    /// Transforms applied in order, first to last: for an OpenVDB grid read, where its own
    /// transform puts the unit cube, then those written (a sequence's: those written only,
    /// each frame's file putting its cube first when it is read).
    pub transform: Vec<TransformOp>,
}

/// A grid's values: read with the scene, or a file per frame.
#[derive(Debug, Clone, PartialEq)]
pub enum GridValues {
    /// Read when the scene was loaded.
    Read(Arc<VoxelGrid>),
    /// A file per frame, read by [`GridDesc::at_frame`].
    Frames(Box<GridFrames>),
}

/// A grid as written, before its file's grid is picked.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Grid")]
struct GridFields {
    /// A Mitsuba `.vol` file of 1 or 3 channels or an OpenVDB file, relative to the scene file,
    /// or a pattern of such files numbered by frame.
    file: GridPath,
    /// The grid of an OpenVDB file (default "density").
    #[serde(default)]
    name: Option<String>,
    /// Transforms applied in order, first to last.
    #[serde(default)]
    transform: Vec<TransformOp>,
}

impl<'de> Deserialize<'de> for GridDesc {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let f = GridFields::deserialize(d)?;
        match f.file {
            GridPath::File(file) => {
                let (grid, unit) = file.pick(f.name.as_deref()).map_err(D::Error::custom)?;
                let transform = unit.map(TransformOp).into_iter().chain(f.transform).collect();
                Ok(GridDesc { file: file.path, name: f.name, grid: GridValues::Read(grid), transform })
            }
            GridPath::Frames(frames) => Ok(GridDesc {
                file: frames.written.clone().into(),
                name: f.name,
                grid: GridValues::Frames(Box::new(frames)),
                transform: f.transform,
            }),
        }
    }
}

impl GridDesc {
    /// The grid, placed in the object: `None` for a sequence (see [`Self::at_frame`]).
    pub fn placed(&self) -> Option<crate::media::PlacedGrid> {
        match &self.grid {
            GridValues::Read(grid) => Some(crate::media::PlacedGrid {
                grid: grid.clone(),
                grid_from_object: compose(&self.transform).inverse(),
            }),
            GridValues::Frames(_) => None,
        }
    }

    /// The grid of frame `frame`: a sequence's file for the frame, read (with the hash of its
    /// bytes), as a grid read at load; a grid read at load, as it is.
    pub fn at_frame(&self, frame: u32) -> Result<(GridDesc, Option<InputFile>), String> {
        let GridValues::Frames(frames) = &self.grid else { return Ok((self.clone(), None)) };
        let (file, input) = frames.read(frame)?;
        let (grid, unit) = file
            .pick(self.name.as_deref())
            .map_err(|e| format!("the grid sequence \"{}\": {e}", frames.written))?;
        let transform = unit.map(TransformOp).into_iter().chain(self.transform.iter().cloned()).collect();
        let read =
            GridDesc { file: file.path, name: self.name.clone(), grid: GridValues::Read(grid), transform };
        Ok((read, Some(input)))
    }
}

impl MediumDesc {
    /// The medium it describes: `None` where a grid is a sequence, whose medium is that of a
    /// frame ([`Self::at_frame`]).
    pub fn medium(&self) -> Option<crate::media::Medium> {
        let placed = |g: &Option<GridDesc>| match g {
            None => Some(None),
            Some(g) => g.placed().map(Some),
        };
        Some(self.with_grids(placed(&self.grid)?, placed(&self.albedo_grid)?))
    }

    /// The medium with these grids.
    fn with_grids(
        &self,
        density_grid: Option<crate::media::PlacedGrid>,
        albedo_grid: Option<crate::media::PlacedGrid>,
    ) -> crate::media::Medium {
        crate::media::Medium {
            sigma_t: self.density.0,
            albedo: self.albedo.0,
            density_grid,
            albedo_grid,
            g: match self.phase {
                PhaseDesc::Isotropic => 0.0,
                PhaseDesc::HenyeyGreenstein { g } => g.0,
            },
        }
    }

    /// Its grids that are sequences.
    pub fn sequences(&self) -> impl Iterator<Item = &GridFrames> {
        [&self.grid, &self.albedo_grid].into_iter().flatten().filter_map(|g| match &g.grid {
            GridValues::Frames(f) => Some(&**f),
            GridValues::Read(_) => None,
        })
    }

    /// The medium of frame `frame`, its sequences' files for the frame read and checked as
    /// grids read at load are, and the files read, with their hashes.
    pub fn at_frame(&self, frame: u32) -> Result<(crate::media::Medium, Vec<InputFile>), String> {
        let mut read = Vec::new();
        let mut at = |g: &Option<GridDesc>| -> Result<Option<GridDesc>, String> {
            let Some(g) = g else { return Ok(None) };
            let (g, input) = g.at_frame(frame)?;
            read.extend(input);
            Ok(Some(g))
        };
        let m = MediumDesc { grid: at(&self.grid)?, albedo_grid: at(&self.albedo_grid)?, ..self.clone() };
        m.check()?;
        let placed = |g: &Option<GridDesc>| g.as_ref().and_then(GridDesc::placed);
        Ok((m.with_grids(placed(&m.grid), placed(&m.albedo_grid)), read))
    }

    /// Refuses a grid too dense to track through and an albedo grid with values above 1 (a
    /// sequence's values when a frame is read).
    fn check(&self) -> Result<(), String> {
        let values = |g: &Option<GridDesc>| match g {
            Some(GridDesc { file, grid: GridValues::Read(v), .. }) => Some((file.clone(), v.clone())),
            _ => None,
        };
        if let Some((file, grid)) = values(&self.grid) {
            let peak = self.density.0.max_element() * grid.max();
            if !(peak <= MAX_GRID_EXTINCTION) {
                return Err(format!(
                    "`density` times the grid {}'s largest value is {peak}: at most {MAX_GRID_EXTINCTION} (a medium that dense is opaque, and tracking through it would take that many steps per unit length)",
                    file.display()
                ));
            }
        }
        if let Some((file, grid)) = values(&self.albedo_grid) {
            let max = grid.max();
            if max > 1.0 {
                return Err(format!(
                    "the albedo grid {} holds {max}: an albedo grid's values lie in [0, 1]",
                    file.display()
                ));
            }
        }
        Ok(())
    }
}

/// A medium's extinction: `0.5` (every channel) or `(0.1, 0.9, 0.1)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Density(pub glam::Vec3);

impl<'de> Deserialize<'de> for Density {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = Density;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a density: a number > 0, or (r, g, b) with each >= 0 and one > 0")
            }
            fn visit_f64<E: Error>(self, x: f64) -> Result<Density, E> {
                let x = x as f32;
                match x.is_finite() && x > 0.0 {
                    true => Ok(Density(glam::Vec3::splat(x))),
                    false => Err(E::custom(format!("expected a density > 0, found {x}"))),
                }
            }
            fn visit_i64<E: Error>(self, x: i64) -> Result<Density, E> {
                self.visit_f64(x as f64)
            }
            fn visit_u64<E: Error>(self, x: u64) -> Result<Density, E> {
                self.visit_f64(x as f64)
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Density, A::Error> {
                let mut c = [0.0f32; 3];
                for (i, c) in c.iter_mut().enumerate() {
                    *c = seq.next_element()?.ok_or_else(|| A::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<f32>()?.is_some() {
                    return Err(A::Error::invalid_length(4, &self));
                }
                let v = glam::Vec3::from(c);
                match v.is_finite() && v.min_element() >= 0.0 && v.max_element() > 0.0 {
                    true => Ok(Density(v)),
                    false => Err(A::Error::custom(format!(
                        "expected a density with components >= 0 and one > 0, found {v}"
                    ))),
                }
            }
        }
        d.deserialize_any(Visit)
    }
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
    emit: Option<EmitDesc>,
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
                if !matches!(r.shape, ShapeDesc::Mesh(_)) && r.shape.form().closed().is_none() =>
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
            (None, Some(m)) => {
                m.check()?;
                Body::Volume(m)
            }
            (Some(_), Some(_)) => return Err("an object has a `material` or a `medium`, not both".into()),
            (None, None) => {
                return Err("an object needs a `material` (a surface) or a `medium` (a volume)".into());
            }
        };
        match (&body, &r.emit) {
            (Body::Volume(_), Some(_)) => return Err("a medium does not emit: `emit` is for surfaces".into()),
            (Body::Surface(name), Some(_))
                if context::names(|n| n.is_some_and(|n| n.lights.contains(&name.0))) =>
            {
                return Err(format!(
                    "material \"{}\" is a DiffuseLight, which emits already: `emit` is for surfaces whose material reflects",
                    name.0
                ));
            }
            (Body::Surface(name), Some(_))
                if context::names(|n| n.is_some_and(|n| n.wrappers.contains(&name.0))) =>
            {
                return Err(format!(
                    "material \"{}\" is a wrapper ({}): `emit` is for surfaces of plain materials",
                    name.0,
                    crate::material::wrap::NAMES.join(", ")
                ));
            }
            _ => {}
        }
        if let (ShapeDesc::SdfGrid(_), Body::Surface(name)) = (&r.shape, &body) {
            let light = context::names(|n| n.is_some_and(|n| n.lights.contains(&name.0)));
            if light || r.emit.is_some() {
                return Err("an SdfGrid does not emit (nor does Mitsuba's sdfgrid): give it a material that reflects and no `emit`".into());
            }
        }
        if let Body::Surface(m) = &body {
            attributes_found(&r.shape, &m.0)?;
        }
        primitives(&r.shape.form(), &compose(&r.transform), &mut Vec::new()).map_err(|e| e.to_string())?;
        Ok(Self {
            shape: r.shape,
            body,
            emit: r.emit,
            transform: r.transform,
            motion: r.motion,
            animate: r.animate,
        })
    }
}

/// A surface whose material reads mesh attributes (`MeshAttribute` textures) must be a mesh
/// that has them, and must not emit (emitting meshes are baked into world-space triangles,
/// which keep no attributes).
fn attributes_found(shape: &ShapeDesc, material: &str) -> Result<(), String> {
    let (wanted, emits) = crate::format::context::names(|n| match n {
        Some(n) => (
            n.attributes.iter().find(|(m, _)| m == material).map(|(_, a)| a.clone()).unwrap_or_default(),
            n.lights.iter().any(|l| l == material),
        ),
        None => (Vec::new(), false),
    });
    let Some(first) = wanted.first() else { return Ok(()) };
    let ShapeDesc::Mesh(mesh) = shape else {
        return Err(format!("material \"{material}\" reads the mesh attribute {first}: it goes on a Mesh"));
    };
    if emits {
        return Err(format!(
            "material \"{material}\" emits and reads the mesh attribute {first}: pathwave's emitting meshes keep no attributes"
        ));
    }
    let has: Vec<&str> = mesh.mesh.attributes.iter().map(|a| a.name.as_str()).collect();
    match wanted.iter().find(|a| !has.contains(&a.as_str())) {
        None => Ok(()),
        Some(a) => Err(format!(
            "material \"{material}\" reads the mesh attribute {a}, which the mesh {} does not have (it has {})",
            mesh.path.display(),
            if has.is_empty() { "none".to_owned() } else { has.join(", ") }
        )),
    }
}

/// `ShapeDesc` from the shape registry ([`crate::shape::with_shapes`]), with meshes beside it.
macro_rules! shape_descs {
    ($($(#[$attr:meta])* $variant:ident($ty:ty),)+) => {
        registry! {
            /// Shapes, in their own space: `Kind(field: value, ...)`, each checked as a whole.
            #[derive(Debug, Clone, PartialEq)]
            pub enum ShapeDesc, ShapeKind: dyn ShapeForm, "Shape",
                "a shape such as Sphere(center: (0, 0, 0), radius: 1)", read_shape {
                $($(#[$attr])* $variant($ty),)+
                Mesh(MeshFile) = read_mesh,
            }
        }
    };
}
crate::shape::with_shapes!(shape_descs);

/// Reads a shape kind's fields and builds it, checked once its `)` is read, so that an error
/// points there.
fn read_shape<'de, T: ShapeModel, A: VariantAccess<'de>>(variant: A) -> Result<T, A::Error> {
    T::build(fields::<T::Desc, A>(variant)?).map_err(A::Error::custom)
}

/// `Mesh(file: "assets/knot.obj")`: the triangles of a mesh file (relative to the scene
/// file: OBJ, PLY, glTF 2.0, whose mesh `mesh` it is, by name or index (default: the file's
/// only mesh), all its primitives or only `primitive`, or Mitsuba's `.serialized`, whose mesh
/// `shape_index` it is, default 0), read as the scene is parsed, smooth-shaded where the file gives vertex normals; `face_normals:
/// true` shades it flat all the same (Mitsuba's `face_normals`), `flip_normals: true` turns it
/// inside out (its faces wound the other way, its normals reversed), `flip_tex_coords: true`
/// reads each uv's v as 1 - v. Meshes are not in the shape registry: their runtime form is the
/// shared mesh data the world instances, not a [`ShapeModel`] that places primitives.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshDesc {
    file: MeshPath,
    #[serde(default)]
    shape_index: u32,
    #[serde(default)]
    mesh: Option<super::gltf::MeshRef>,
    #[serde(default)]
    primitive: Option<u32>,
    #[serde(default)]
    face_normals: bool,
    #[serde(default)]
    flip_normals: bool,
    #[serde(default)]
    flip_tex_coords: bool,
}

fn read_mesh<'de, A: VariantAccess<'de>>(variant: A) -> Result<MeshFile, A::Error> {
    let d = fields::<MeshDesc, A>(variant)?;
    let MeshPath { path, full, source } = d.file;
    let gltf_only = match (&d.mesh, d.primitive) {
        (Some(_), _) => Some("mesh"),
        (None, Some(_)) => Some("primitive"),
        (None, None) => None,
    };
    let mesh = match source {
        MeshSource::Unread => return Ok(MeshFile { path, mesh: Default::default() }),
        MeshSource::Mesh(_) | MeshSource::Serialized(_) if gltf_only.is_some() => {
            let message = format!("`{}` picks a mesh of a glTF file", gltf_only.unwrap());
            return Err(A::Error::custom(message));
        }
        MeshSource::Mesh(_) | MeshSource::Gltf(_) if d.shape_index != 0 => {
            let message = format!("shape_index {} picks a mesh of a .serialized file", d.shape_index);
            return Err(A::Error::custom(message));
        }
        MeshSource::Mesh(m) => m,
        MeshSource::Gltf(file) => {
            let key = full.join(format!("#{:?}#{:?}", d.mesh, d.primitive));
            match crate::format::context::read_before(&key) {
                Some(m) => m,
                None => {
                    let m = file.mesh_data(d.mesh.as_ref(), d.primitive, &full).map_err(A::Error::custom)?;
                    let m = Arc::new(m);
                    crate::format::context::keep(key, m.clone());
                    m
                }
            }
        }
        MeshSource::Serialized(file) => {
            let key = full.join(format!("#{}", d.shape_index));
            match crate::format::context::read_before(&key) {
                Some(m) => m,
                None => {
                    let m = Arc::new(file.mesh(d.shape_index as usize, &full).map_err(A::Error::custom)?);
                    crate::format::context::keep(key, m.clone());
                    m
                }
            }
        }
    };
    let face_normals = d.face_normals && mesh.normals.is_some();
    let flip_v = d.flip_tex_coords && mesh.uvs.is_some();
    if !(face_normals || flip_v || d.flip_normals) {
        return Ok(MeshFile { path, mesh });
    }
    // One changed copy per file, mesh and options, shared by the objects that ask for it (one
    // BLAS).
    let key = full.join(format!(
        "#{}#{:?}#{:?}#{face_normals}#{}#{flip_v}",
        d.shape_index, d.mesh, d.primitive, d.flip_normals
    ));
    let cached = crate::format::context::read_before(&key);
    let mesh = cached.unwrap_or_else(|| {
        let mut m = (*mesh).clone();
        if face_normals {
            m.normals = None;
        }
        if flip_v {
            m.uvs.iter_mut().flatten().for_each(|uv| uv.y = 1.0 - uv.y);
        }
        if d.flip_normals {
            m.triangles.iter_mut().for_each(|t| t.swap(1, 2));
            m.normals.iter_mut().flatten().for_each(|n| *n = -*n);
        }
        let m = Arc::new(m);
        crate::format::context::keep(key, m.clone());
        m
    });
    Ok(MeshFile { path, mesh })
}

/// What a shape description becomes in the world.
pub trait ShapeForm {
    /// The shape as the world holds it (a mesh shared, not copied).
    fn form(&self) -> Form;
}

impl<T: ShapeModel> ShapeForm for T
where
    Form: From<T>,
{
    fn form(&self) -> Form {
        self.clone().into()
    }
}

impl ShapeForm for MeshFile {
    fn form(&self) -> Form {
        Form::Mesh(self.mesh.clone())
    }
}

impl ShapeDesc {
    /// The shape as the world holds it (the mesh shared, not copied).
    pub fn form(&self) -> Form {
        self.model().form()
    }
}
