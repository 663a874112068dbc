//! Files a scene names: meshes (OBJ, PLY, glTF 2.0 and Mitsuba's `.serialized`) and images
//! (textures, environment maps; [`ImageFile`] lives with the image texture kind,
//! `texture/image.rs`), read in the second parsing pass relative to the scene file.

use super::serialized::SerializedFile;
use crate::accel::mesh::{MeshAttribute, MeshData};
use crate::format::context;
use crate::format::files::{InputFile, ReadRules};
use crate::format::frames::FramePattern;
use crate::format::vdb::{VdbFile, is_vdb};
use crate::media::grid::VoxelGrid;
use crate::texture::TextureImage;
pub use crate::texture::image::ImageFile;
use glam::Affine3A;
use serde::{Deserialize, Deserializer, de::Error};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// The triangles of a mesh file, read when the scene is loaded. Objects naming the same file
/// (and the same mesh and options of it) share one mesh (and, as instances, one BLAS).
#[derive(Debug, Clone, PartialEq)]
pub struct MeshFile {
    /// The path as written.
    pub path: std::path::PathBuf,
    /// Positions and triangles.
    pub mesh: Arc<MeshData>,
}

/// A mesh file as `Mesh(file: ..)` names it, read when the name is (its format told by
/// [`mesh_format`]): an OBJ or PLY file decoded whole, a `.serialized` or glTF file kept whole
/// until the shape says which of its meshes it is.
#[derive(Debug, Clone)]
pub struct MeshPath {
    /// The path as written.
    pub path: std::path::PathBuf,
    /// The path from the scene's folder (the key of the parse's file cache).
    pub full: std::path::PathBuf,
    /// What the file holds.
    pub source: MeshSource,
}

/// What a mesh file holds.
#[derive(Debug, Clone)]
pub enum MeshSource {
    /// Not read: the first parsing pass reads no files.
    Unread,
    /// One mesh (OBJ, PLY).
    Mesh(Arc<MeshData>),
    /// Meshes to pick from, by index.
    Serialized(Arc<SerializedFile>),
    /// Meshes to pick from, by name or index.
    Gltf(Arc<super::gltf::GltfFile>),
}

impl<'de> Deserialize<'de> for MeshPath {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let path = std::path::PathBuf::from(String::deserialize(d)?);
        let Some(dir) = context::scene_dir() else {
            context::want(&path, context::Wanted::Mesh);
            return Ok(MeshPath { full: path.clone(), path, source: MeshSource::Unread });
        };
        let full = dir.join(&path);
        if let Some(source) = context::read_before::<MeshSource>(&full) {
            return Ok(MeshPath { path, full, source: (*source).clone() });
        }
        let source = read_mesh_file(&full).map_err(D::Error::custom)?;
        context::keep(full.clone(), Arc::new(source.clone()));
        Ok(MeshPath { path, full, source })
    }
}

/// A voxel grid file, read when the scene is loaded: Mitsuba's `.vol`, or an OpenVDB file
/// (told by its first bytes, or by the extension `.vdb` for a damaged one) whose grid the
/// medium picks by name ([`GridFile::pick`]). Objects naming the same `.vol`, or the same
/// grid of an OpenVDB file, share one grid.
#[derive(Debug, Clone)]
pub struct GridFile {
    /// The path as written.
    pub path: std::path::PathBuf,
    /// What the file holds.
    source: GridSource,
}

/// What a grid file holds.
#[derive(Debug, Clone)]
enum GridSource {
    /// Not read: the first parsing pass reads no files.
    Unread,
    /// A `.vol` file's grid.
    Vol(Arc<VoxelGrid>),
    /// An OpenVDB file's grids, to pick from by name.
    Vdb(Arc<VdbGrids>),
}

/// An OpenVDB file and the dense boxes made of its grids, each made once however many media
/// pick it (a box may hold 2^28 voxels, 1 GiB).
#[derive(Debug)]
pub struct VdbGrids {
    file: VdbFile,
    /// The boxes made so far by grid name.
    dense: Mutex<HashMap<String, DenseBox>>,
}

/// A grid made a dense box, with where its unit cube lies, or why it cannot be one.
type DenseBox = Result<(Arc<VoxelGrid>, Affine3A), String>;

impl VdbGrids {
    fn new(file: VdbFile) -> Self {
        Self { file, dense: Mutex::new(HashMap::new()) }
    }

    /// The grid `name` as a dense box and where its unit cube lies in the medium's space (its
    /// transform: the grid's world is the medium's space), made on the first pick.
    fn pick(&self, name: &str, path: &std::path::Path) -> Result<(Arc<VoxelGrid>, Affine3A), String> {
        // A poisoned lock only means another thread panicked while building a box: build again.
        let mut dense = self.dense.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        dense
            .entry(name.to_owned())
            .or_insert_with(|| {
                let g = self.file.grid(name)?;
                let unit = g.world_from_unit().as_affine3a();
                let det = unit.matrix3.determinant();
                if !(unit.is_finite() && det.is_normal()) {
                    return Err(format!(
                        "the OpenVDB file {}: the grid's box maps to {unit:?} in single precision, which is not finite and invertible",
                        path.display()
                    ));
                }
                Ok((Arc::new(VoxelGrid::new(g.size, 1, g.values)), unit))
            })
            .clone()
    }
}

/// The grid a medium's `name` picks of the file's: OpenVDB's default.
pub const DEFAULT_VDB_GRID: &str = "density";

impl GridFile {
    /// The grid that `name` picks (an OpenVDB file's grid of that name, by default
    /// [`DEFAULT_VDB_GRID`]; a `.vol` file takes no name) and where its unit cube lies in the
    /// medium's space: `None` for a `.vol` (the unit cube itself), an OpenVDB grid's transform
    /// (its world space is the medium's space) for its dense box over the active voxels.
    pub fn pick(&self, name: Option<&str>) -> Result<(Arc<VoxelGrid>, Option<Affine3A>), String> {
        match &self.source {
            GridSource::Unread => Ok((Arc::new(VoxelGrid::new([1, 1, 1], 1, vec![0.0])), None)),
            GridSource::Vol(grid) => match name {
                None => Ok((grid.clone(), None)),
                Some(n) => Err(format!(
                    "`name: \"{n}\"` picks a grid of an OpenVDB file: the .vol file {} holds one grid",
                    self.path.display()
                )),
            },
            GridSource::Vdb(grids) => {
                let (grid, unit) = grids.pick(name.unwrap_or(DEFAULT_VDB_GRID), &self.path)?;
                Ok((grid, Some(unit)))
            }
        }
    }
}

/// A grid file as a medium's `file` names it: one file, read when the scene is loaded, or a
/// frame-numbered sequence (`smoke_{frame:04}.vdb`: [`FramePattern`]), whose files are read
/// frame by frame as the frames are rendered.
#[derive(Debug, Clone)]
pub enum GridPath {
    /// One file for every frame.
    File(GridFile),
    /// A file per frame.
    Frames(GridFrames),
}

/// A grid file per frame: frame `n` reads the file its pattern names for `n`.
#[derive(Debug, Clone, PartialEq)]
pub struct GridFrames {
    /// The pattern as written.
    pub written: String,
    /// The pattern.
    pub pattern: FramePattern,
    /// The folder the names are relative to (the scene file's).
    pub dir: std::path::PathBuf,
}

impl GridFrames {
    /// The file frame `frame` reads.
    pub fn path(&self, frame: u32) -> std::path::PathBuf {
        self.dir.join(self.pattern.at(frame))
    }

    /// Reads frame `frame`'s file, and the hash of its bytes (an input of the frame's render).
    pub fn read(&self, frame: u32) -> Result<(GridFile, InputFile), String> {
        let full = self.path(frame);
        let fail = |e: String| format!("the grid sequence \"{}\": {e}", self.written);
        let bytes = super::files::read_bounded(&full, super::files::MAX_ASSET_BYTES, "grid").map_err(fail)?;
        let hash = xxhash_rust::xxh3::xxh3_64(&bytes);
        let source = grid_source(bytes, &full).map_err(fail)?;
        let path = std::path::absolute(&full).unwrap_or_else(|_| full.clone());
        Ok((GridFile { path: self.pattern.at(frame).into(), source }, InputFile { path, hash }))
    }

    /// Checks that frame `frame`'s file is there and starts as a grid file does (a `.vol`'s
    /// header and length, an OpenVDB file's magic and version), without reading the rest: what
    /// a command checks of every frame before it renders the first.
    pub fn check(&self, frame: u32) -> Result<(), String> {
        let full = self.path(frame);
        let fail = |e: String| format!("the grid sequence \"{}\": {e}", self.written);
        let max = super::files::MAX_ASSET_BYTES;
        let head = crate::format::vol::HEADER_BYTES.max(crate::format::vdb::HEADER_BYTES);
        let (bytes, len) = super::files::read_head(&full, head, max, "grid").map_err(fail)?;
        if is_vdb(&bytes) || is_vdb_name(&full) {
            return VdbFile::check_header(&bytes, &full).map_err(fail);
        }
        let h = crate::format::vol::VolHeader::parse(&bytes, &full, "grid").map_err(fail)?;
        let want = (crate::format::vol::HEADER_BYTES + 4 * h.count()) as u64;
        match len == want {
            true => Ok(()),
            false => Err(fail(format!(
                "the grid {} has {len} bytes, where its header asks for {want}",
                full.display()
            ))),
        }
    }
}

impl<'de> Deserialize<'de> for GridPath {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let written = String::deserialize(d)?;
        let pattern = FramePattern::parse(&written).map_err(|e| D::Error::custom(format!("`file`: {e}")))?;
        let dir = context::scene_dir();
        if let Some(pattern) = pattern {
            return Ok(GridPath::Frames(GridFrames { written, pattern, dir: dir.unwrap_or_default() }));
        }
        let path = std::path::PathBuf::from(written);
        let Some(dir) = dir else {
            return Ok(GridPath::File(GridFile { path, source: GridSource::Unread }));
        };
        let full = dir.join(&path);
        if let Some(grid) = context::read_before::<VoxelGrid>(&full) {
            return Ok(GridPath::File(GridFile { path, source: GridSource::Vol(grid) }));
        }
        if let Some(grids) = context::read_before::<VdbGrids>(&full) {
            return Ok(GridPath::File(GridFile { path, source: GridSource::Vdb(grids) }));
        }
        let bytes = super::files::read_bounded(&full, super::files::MAX_ASSET_BYTES, "grid")
            .map_err(D::Error::custom)?;
        let source = grid_source(bytes, &full).map_err(D::Error::custom)?;
        match &source {
            GridSource::Vdb(grids) => context::keep(full, grids.clone()),
            GridSource::Vol(grid) => context::keep(full, grid.clone()),
            GridSource::Unread => {}
        }
        Ok(GridPath::File(GridFile { path, source }))
    }
}

/// Whether `path` is named as an OpenVDB file (`.vdb`), which a damaged one is read as.
fn is_vdb_name(path: &std::path::Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("vdb"))
}

/// What the grid file `bytes` read from `path` holds: an OpenVDB file (told by its first
/// bytes, or its name) or a `.vol`.
fn grid_source(bytes: Vec<u8>, path: &std::path::Path) -> Result<GridSource, String> {
    Ok(match is_vdb(&bytes) || is_vdb_name(path) {
        true => GridSource::Vdb(Arc::new(VdbGrids::new(VdbFile::parse(bytes, path)?))),
        false => GridSource::Vol(Arc::new(VoxelGrid::parse_vol(&bytes, path)?)),
    })
}

/// The mesh formats `Mesh(file: ..)` reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ (`.obj`).
    Obj,
    /// PLY, ASCII or binary (`.ply`).
    Ply,
    /// glTF 2.0 (`.gltf` JSON or `.glb`).
    Gltf,
    /// Mitsuba's `.serialized`.
    Serialized,
}

/// The formats, as an error lists them.
const FORMATS: &str = "OBJ (.obj), PLY (.ply), glTF 2.0 (.gltf, .glb) and Mitsuba's .serialized";

/// The format of the mesh file `bytes` read from `path`: by its first bytes where they say
/// (`ply`, the `.glb` magic `glTF` or a JSON `{`, the `.serialized` format code 0x041C), else by
/// its extension; a file that is neither is refused, naming the formats there are.
pub fn mesh_format(bytes: &[u8], path: &std::path::Path) -> Result<MeshFormat, String> {
    let ply = bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n");
    if ply {
        return Ok(MeshFormat::Ply);
    }
    if super::gltf::is_gltf(bytes) {
        return Ok(MeshFormat::Gltf);
    }
    if bytes.starts_with(&[0x1C, 0x04]) {
        return Ok(MeshFormat::Serialized);
    }
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("obj") => Ok(MeshFormat::Obj),
        Some("ply") => Ok(MeshFormat::Ply),
        Some("gltf" | "glb") => Ok(MeshFormat::Gltf),
        Some("serialized") => Ok(MeshFormat::Serialized),
        _ => Err(format!(
            "the mesh {} is in no format pathwave reads: neither its extension nor its first bytes are those of {FORMATS}",
            path.display()
        )),
    }
}

/// Reads the mesh file at `path` in its format ([`mesh_format`]); a glTF file read before in
/// this parse (by a texture or another mesh) is not parsed again.
fn read_mesh_file(path: &std::path::Path) -> Result<MeshSource, String> {
    let bytes = super::files::read_bounded(path, super::files::MAX_ASSET_BYTES, "mesh")?;
    let format = mesh_format(&bytes, path)?;
    if format == MeshFormat::Gltf
        && let Some(file) = context::read_before::<super::gltf::GltfFile>(path)
    {
        return Ok(MeshSource::Gltf(file));
    }
    let source = parse_mesh_file(bytes, path, format)?;
    if let MeshSource::Gltf(file) = &source {
        context::keep(path.to_owned(), file.clone());
    }
    Ok(source)
}

/// The mesh file `path` of these `bytes`, in `format` ([`mesh_format`]); the parse context
/// is not touched, so that it runs on any thread.
fn parse_mesh_file(bytes: Vec<u8>, path: &std::path::Path, format: MeshFormat) -> Result<MeshSource, String> {
    Ok(match format {
        MeshFormat::Ply => MeshSource::Mesh(Arc::new(super::ply::parse_ply(&bytes, path)?)),
        MeshFormat::Serialized => MeshSource::Serialized(Arc::new(SerializedFile::new(bytes, path)?)),
        MeshFormat::Gltf => MeshSource::Gltf(Arc::new(super::gltf::GltfFile::new(&bytes, path)?)),
        MeshFormat::Obj => MeshSource::Mesh(Arc::new(parse_obj(&bytes, path)?)),
    })
}

/// Reads the mesh and image files that the first parsing pass met ([`context::take_wanted`];
/// paths relative to `dir`) across rayon's threads, each under the calling thread's rules
/// ([`ReadRules`]: `--assets-under`, the recording of inputs), and keeps what they hold for
/// the second pass, which then finds them read. A file that cannot be read is left to the
/// second pass: it reads it again and reports the error where the scene names the file.
/// Without this, a scene's files were read one after the other, each as the parser reached it.
pub(crate) fn read_ahead(dir: &std::path::Path) {
    use rayon::prelude::*;
    let wanted = context::take_wanted();
    if wanted.len() < 2 {
        return;
    }
    let rules = ReadRules::here();
    let read: Vec<_> = wanted
        .par_iter()
        .map(|(path, what)| {
            let full = dir.join(path);
            let (ahead, files) = rules.apply(|| match what {
                context::Wanted::Mesh => {
                    let read = || {
                        let bytes = super::files::read_bounded(&full, super::files::MAX_ASSET_BYTES, "mesh")?;
                        let format = mesh_format(&bytes, &full)?;
                        parse_mesh_file(bytes, &full, format)
                    };
                    read().ok().map(Ahead::Mesh)
                }
                context::Wanted::Image => TextureImage::load(&full).ok().map(|i| Ahead::Image(Arc::new(i))),
            });
            (full, ahead, files)
        })
        .collect();
    for (full, ahead, files) in read {
        files.keep();
        match ahead {
            Some(Ahead::Mesh(source)) => {
                if let MeshSource::Gltf(file) = &source {
                    context::keep(full.clone(), file.clone());
                }
                context::keep(full, Arc::new(source));
            }
            Some(Ahead::Image(image)) => context::keep(full, image),
            None => {}
        }
    }
}

/// What [`read_ahead`] read of a file.
enum Ahead {
    Mesh(MeshSource),
    Image(Arc<TextureImage>),
}

/// An edge (by vertex position) that borders an odd number of triangles, and that number: a
/// mesh without one is closed, so a ray's hits alternate between entering and leaving it.
pub fn open_edge(mesh: &crate::accel::mesh::MeshData) -> Option<(glam::Vec3A, glam::Vec3A, u32)> {
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

/// Positions and triangles of every model in the OBJ text `bytes` (faces triangulated as
/// fans); `path` names the file in errors.
pub fn parse_obj(bytes: &[u8], path: &std::path::Path) -> Result<MeshData, String> {
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
    finish_mesh(positions, triangles, normals, uvs, Vec::new(), path)
}

/// A mesh file's data checked (finite positions, at least one face, indices in range) and
/// cleaned: vertex normals of unit length, as written when they are (within 1e-4), else
/// normalised (scaled down first: the square of a component of 1e38 overflowed when they were
/// interpolated, found by the obj fuzzer), or zero; normals or uvs with a value that is not
/// finite are dropped, as are attributes with a value that is not (with a warning).
pub(super) fn finish_mesh(
    positions: Vec<glam::Vec3A>,
    triangles: Vec<[u32; 3]>,
    normals: Option<Vec<glam::Vec3A>>,
    uvs: Option<Vec<glam::Vec2>>,
    mut attributes: Vec<MeshAttribute>,
    path: &std::path::Path,
) -> Result<MeshData, String> {
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
    attributes.retain(|a| {
        let finite = a.values.iter().all(|v| v.is_finite());
        if !finite {
            tracing::warn!(
                "the mesh {}: the attribute {} has a value that is not finite: dropped",
                path.display(),
                a.name
            );
        }
        finite
    });
    Ok(MeshData { positions, triangles, normals, uvs, attributes })
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
