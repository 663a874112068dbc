//! OpenVDB files (`.vdb`): the scalar float grids that smoke, cloud and fire simulations write,
//! read into a dense box of values over their active voxels.
//!
//! What is read, as OpenVDB's `io/Archive.cc`, `io/Compression.h`, `tree/RootNode.h`,
//! `InternalNode.h`, `LeafNode.h` and `math/Maps.h` define it (little-endian throughout):
//! - the header: the magic `0x56444220` (8 bytes), the file format version (222 to 225: older
//!   files store compression per file and are refused by number), the library version, whether
//!   the file has grid offsets (files that `io::File` writes do), a 36-byte UUID and the file's
//!   metadata; then the grid descriptors (name, type, instance parent, the grid's offsets);
//! - a grid: its compression flags (`COMPRESS_ZIP` 1, `COMPRESS_ACTIVE_MASK` 2, `COMPRESS_BLOSC`
//!   4), its metadata (a level set's `class` is refused), its transform (`UniformScaleMap`,
//!   `ScaleMap`, `UniformScaleTranslateMap`, `ScaleTranslateMap`, `TranslationMap`,
//!   `AffineMap`; others are refused by name), then the tree of type `Tree_float_5_4_3`, with or
//!   without `_HalfFloat` storage: the root (background, tiles of 4096^3 voxels, children), the
//!   internal nodes of 32^3 and 16^3 slots (child and value masks, the slots' values) and the
//!   leaves of 8^3 voxels (value mask; the values after the whole topology);
//! - values: each node's are preceded by a byte telling how its inactive values were dropped
//!   (`readCompressedValues`: none, all `-background`, one value, a mask selecting between two,
//!   or all kept), then written raw, zlib-compressed (`flate2`) or as a Blosc chunk: Blosc's
//!   16-byte header, its block offsets and, per block, one LZ4 stream per byte of the type
//!   (`lz4_flex`), byte-unshuffled (c-blosc's `README_CHUNK_FORMAT` and `blosc_d`). Half
//!   floats are IEEE binary16 (`half`).
//!
//! A voxel's value stands at its integer index (OpenVDB's cell-centred sampling); the dense
//! box spans the active voxels (active tiles fill their whole region), and every voxel of it
//! takes the tree's value there, active or not (leaf values, tile values, else the
//! background), as OpenVDB's `getValue` and its dense copy give. Every count and size is
//! bounded before anything is allocated: strings, metadata and tiles by the bytes left,
//! decompressed sizes by the node's value count, the dense box by [`super::vol::MAX_VALUES`].
//! The topology is walked twice (first for the active box, then to fill tiles into the box),
//! so that nothing proportional to the tree's slots is kept.
//!
//! Why not the `vdb-rs` crate (Traverse Research): every release builds C-Blosc and LZ4 from C
//! (through `blosc-src`), pulls glam 0.24 beside the workspace's 0.33, panics in about 22
//! places and allocates up to 7e16 bytes on one-byte corruptions of a 28 KB file, and reads
//! grids of other value types as floats without a word.
//!
//! The walk of a tree's topology and values, and the dense box it fills, are in `tree`; the
//! zlib and Blosc decoding of compressed values in `compress`.

mod compress;
mod tree;

use glam::{DAffine3, DMat3, DVec3};
use std::path::{Path, PathBuf};
use tree::{Bounds, Fill, Tree};

/// The first 8 bytes of every OpenVDB file (`OPENVDB_MAGIC`, an `int64`).
pub const MAGIC: [u8; 8] = [0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0];

/// The bytes of the magic and the file format version.
pub const HEADER_BYTES: usize = 12;

/// The oldest file format version read (`OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION`).
pub const OLDEST_VERSION: u32 = 222;

/// The newest file format version read (`OPENVDB_FILE_VERSION_HALF_GRID`, OpenVDB 12).
pub const NEWEST_VERSION: u32 = 225;

/// The one tree type read.
const FLOAT_TREE: &str = "Tree_float_5_4_3";

/// The suffix of a grid type whose values are stored as half floats.
const HALF_SUFFIX: &str = "_HalfFloat";

/// The compression flags (`io/Compression.h`).
const ZIP: u32 = 0x1;
const ACTIVE_MASK: u32 = 0x2;
const BLOSC: u32 = 0x4;

/// Whether `bytes` start as an OpenVDB file.
pub fn is_vdb(bytes: &[u8]) -> bool {
    bytes.starts_with(&MAGIC)
}

/// An OpenVDB file: its bytes and the grids it lists.
#[derive(Debug)]
pub struct VdbFile {
    bytes: Vec<u8>,
    path: PathBuf,
    grids: Vec<Descriptor>,
}

/// A grid as the file lists it.
#[derive(Debug)]
struct Descriptor {
    /// The name (OpenVDB's unique name less its `\x1e` suffix).
    name: String,
    /// The unique name, which instances name as their parent.
    unique: String,
    /// The tree type less `_HalfFloat`.
    tree: String,
    /// Values stored as half floats.
    half: bool,
    /// The unique name of the grid whose tree this one shares (empty if none).
    parent: String,
    /// Where the grid's data start.
    at: usize,
}

/// A grid read into a dense box.
#[derive(Clone, Debug, PartialEq)]
pub struct VdbGrid {
    /// Voxels along x, y and z.
    pub size: [usize; 3],
    /// The values, x fastest, then y, then z.
    pub values: Vec<f32>,
    /// The index of the box's first voxel.
    pub index_min: [i32; 3],
    /// The grid's transform: index space to world space.
    pub world_from_index: DAffine3,
}

impl VdbGrid {
    /// The map from the unit cube that the box fills (voxel `i` centred at `(i + 1/2) / size`)
    /// to the grid's world space, where voxel `i` stands at index `index_min + i`.
    pub fn world_from_unit(&self) -> DAffine3 {
        let size = DVec3::new(self.size[0] as f64, self.size[1] as f64, self.size[2] as f64);
        let min = DVec3::new(self.index_min[0] as f64, self.index_min[1] as f64, self.index_min[2] as f64);
        self.world_from_index * DAffine3::from_translation(min - 0.5) * DAffine3::from_scale(size)
    }
}

impl VdbFile {
    /// Reads the header and grid list of the file `bytes` read from `path` (named in errors).
    pub fn parse(bytes: Vec<u8>, path: &Path) -> Result<Self, String> {
        let mut c = Cursor { bytes: &bytes, at: 0, path, mark: 0, flags: 0 };
        c.header()?;
        c.take(8, "the library version")?;
        let offsets = c.u8("the grid offsets flag")?;
        if offsets != 1 {
            return Err(c.fail(&format!(
                "grid offsets flag {offsets}: pathwave reads files with grid offsets (1, as io::File writes them)"
            )));
        }
        c.take(36, "the UUID")?;
        c.metadata("the file's metadata")?;
        let count = c.i32("the grid count")?;
        // A descriptor takes at least 3 empty strings and 3 offsets.
        let most = c.left() / 36;
        if count < 0 || count as usize > most {
            return Err(c.fail(&format!("{count} grids: between 0 and {most} fit in the bytes left")));
        }
        let mut grids = Vec::with_capacity(count as usize);
        for _ in 0..count {
            let unique = c.string("a grid's name")?;
            let kind = c.string("a grid's type")?;
            let parent = c.string("a grid's instance parent")?;
            let grid_at = c.offset("a grid's offset")?;
            c.offset("a grid's block offset")?;
            let end = c.offset("a grid's end offset")?;
            if grid_at < c.at || end < grid_at {
                return Err(c.fail(&format!(
                    "a grid from byte {grid_at} to {end}: it must start after its descriptor (byte {}) and end after it starts",
                    c.at
                )));
            }
            let name = unique.split('\x1e').next().unwrap_or_default().to_string();
            let (tree, half) = match kind.strip_suffix(HALF_SUFFIX) {
                Some(t) => (t.to_string(), true),
                None => (kind, false),
            };
            grids.push(Descriptor { name, unique, tree, half, parent, at: grid_at });
            c.at = end;
        }
        let path = path.to_path_buf();
        Ok(VdbFile { bytes, path, grids })
    }

    /// Checks the start of a file, its first [`HEADER_BYTES`] bytes (or all of a shorter
    /// file): OpenVDB's magic and a file format version pathwave reads. What a sequence's
    /// frames are checked for before they are rendered.
    pub fn check_header(head: &[u8], path: &Path) -> Result<(), String> {
        Cursor { bytes: head, at: 0, path, mark: 0, flags: 0 }.header()
    }

    /// The names of its grids and their tree types, as an error lists them.
    fn listing(&self) -> String {
        let names: Vec<String> = self.grids.iter().map(|g| format!("\"{}\" ({})", g.name, g.tree)).collect();
        match names.is_empty() {
            true => "it has no grids".into(),
            false => format!("its grids: {}", names.join(", ")),
        }
    }

    /// The float grid named `name`, dense over its active voxels.
    pub fn grid(&self, name: &str) -> Result<VdbGrid, String> {
        let fail = |why: String| format!("the OpenVDB file {}: {why}", self.path.display());
        let Some(g) = self.grids.iter().find(|g| g.name == name) else {
            return Err(fail(format!("no grid named \"{name}\"; {}", self.listing())));
        };
        let float = |g: &Descriptor| match g.tree == FLOAT_TREE {
            true => Ok(()),
            false => Err(fail(format!(
                "the grid \"{}\" is a {}: pathwave reads scalar float grids ({FLOAT_TREE})",
                g.name, g.tree
            ))),
        };
        float(g)?;
        let mut c = Cursor { bytes: &self.bytes, at: g.at, path: &self.path, mark: g.at, flags: 0 };
        let world_from_index = c.grid_header(&g.name)?;
        // An instance shares the tree of its parent, read with the parent's compression.
        let (tree_grid, mut t) = match g.parent.is_empty() {
            true => (g, c),
            false => {
                let Some(p) = self.grids.iter().find(|p| p.unique == g.parent) else {
                    return Err(fail(format!(
                        "the grid \"{}\" shares the tree of \"{}\", which the file does not hold",
                        g.name, g.parent
                    )));
                };
                float(p)?;
                let mut c = Cursor { bytes: &self.bytes, at: p.at, path: &self.path, mark: p.at, flags: 0 };
                c.grid_header(&p.name)?;
                (p, c)
            }
        };
        let flags = t.flags;
        t.tree(&tree_grid.name, flags, tree_grid.half, world_from_index)
    }
}

/// A reading position in a file.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
    path: &'a Path,
    /// Where the last field read starts (errors name it).
    mark: usize,
    /// The compression flags of the grid being read.
    flags: u32,
}

impl<'a> Cursor<'a> {
    /// An error at the start of the last field read.
    /// Reads and checks the magic and the file format version.
    fn header(&mut self) -> Result<(), String> {
        if !is_vdb(self.bytes) {
            return Err(
                self.fail("not an OpenVDB file (its first 8 bytes are not OpenVDB's magic 0x56444220)")
            );
        }
        self.at = 8;
        let version = self.u32("the file format version")?;
        if version < OLDEST_VERSION {
            return Err(self.fail(&format!(
                "file format version {version}: pathwave reads versions {OLDEST_VERSION} to {NEWEST_VERSION}"
            )));
        }
        if version > NEWEST_VERSION {
            return Err(self.fail(&format!(
                "file format version {version}: newer than {NEWEST_VERSION}, the latest pathwave reads"
            )));
        }
        Ok(())
    }

    fn fail(&self, why: &str) -> String {
        format!("the OpenVDB file {}: at byte {}: {why}", self.path.display(), self.mark)
    }

    fn left(&self) -> usize {
        self.bytes.len().saturating_sub(self.at)
    }

    /// The next `n` bytes, which hold `what`.
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        self.mark = self.at;
        if n > self.left() {
            return Err(self.fail(&format!("{what} is cut short ({n} bytes, {} left)", self.left())));
        }
        self.at += n;
        Ok(&self.bytes[self.at - n..self.at])
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], String> {
        let b = self.take(N, what)?;
        let mut a = [0; N];
        a.copy_from_slice(b);
        Ok(a)
    }

    fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.array::<1>(what)?[0])
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }

    fn i32(&mut self, what: &str) -> Result<i32, String> {
        Ok(i32::from_le_bytes(self.array(what)?))
    }

    fn i64(&mut self, what: &str) -> Result<i64, String> {
        Ok(i64::from_le_bytes(self.array(what)?))
    }

    fn f32(&mut self, what: &str) -> Result<f32, String> {
        Ok(f32::from_le_bytes(self.array(what)?))
    }

    fn vec3d(&mut self, what: &str) -> Result<DVec3, String> {
        let mut v = [0.0; 3];
        for x in &mut v {
            *x = f64::from_le_bytes(self.array(what)?);
        }
        Ok(DVec3::from_array(v))
    }

    /// A byte offset into the file, within it.
    fn offset(&mut self, what: &str) -> Result<usize, String> {
        let o = self.i64(what)?;
        match usize::try_from(o).ok().filter(|&o| o <= self.bytes.len()) {
            Some(o) => Ok(o),
            None => Err(self.fail(&format!("{what} {o}: not within the file's {} bytes", self.bytes.len()))),
        }
    }

    /// A string: its length (a `uint32`) and its bytes.
    fn string(&mut self, what: &str) -> Result<String, String> {
        let n = self.u32(what)? as usize;
        Ok(String::from_utf8_lossy(self.take(n, what)?).into_owned())
    }

    /// A metadata map (`MetaMap::readMeta`): a count, then name, type name and sized value;
    /// returns the value of the `class` entry if it is a string.
    fn metadata(&mut self, what: &str) -> Result<Option<String>, String> {
        let count = self.u32(what)? as usize;
        // An entry takes at least two empty strings and a size.
        let most = self.left() / 12;
        if count > most {
            return Err(self.fail(&format!("{what}: {count} entries, at most {most} fit in the bytes left")));
        }
        let mut class = None;
        for _ in 0..count {
            let name = self.string(what)?;
            let kind = self.string(what)?;
            let size = self.u32(what)? as usize;
            let value = self.take(size, what)?;
            if name == "class" && kind == "string" {
                class = Some(String::from_utf8_lossy(value).into_owned());
            }
        }
        Ok(class)
    }

    /// A grid's compression flags, metadata and transform (index to world space); the flags
    /// are kept for its tree. Returns the transform.
    fn grid_header(&mut self, name: &str) -> Result<DAffine3, String> {
        let flags = self.u32("the grid's compression flags")?;
        if flags & !(ZIP | ACTIVE_MASK | BLOSC) != 0 || flags & (ZIP | BLOSC) == ZIP | BLOSC {
            return Err(self.fail(&format!(
                "compression flags {flags:#x} of the grid \"{name}\": OpenVDB's are zip (0x1), active mask (0x2) and blosc (0x4), zip and blosc not both"
            )));
        }
        self.flags = flags;
        let class = self.metadata("the grid's metadata")?;
        if class.as_deref() == Some("level set") {
            return Err(self.fail(&format!(
                "the grid \"{name}\" is a level set (signed distances): pathwave reads densities (fog volumes)"
            )));
        }
        let map = self.string("the grid's transform")?;
        let (scale, translation) = match map.as_str() {
            "UniformScaleMap" | "ScaleMap" => (self.scale()?, DVec3::ZERO),
            "UniformScaleTranslateMap" | "ScaleTranslateMap" => {
                let t = self.vec3d("the transform's translation")?;
                (self.scale()?, t)
            }
            "TranslationMap" => (DVec3::ONE, self.vec3d("the transform's translation")?),
            "AffineMap" => return self.affine(),
            _ => {
                return Err(self.fail(&format!(
                    "the grid \"{name}\" has a {map}: pathwave reads UniformScaleMap, ScaleMap, UniformScaleTranslateMap, ScaleTranslateMap, TranslationMap and AffineMap"
                )));
            }
        };
        let m = DAffine3::from_mat3_translation(DMat3::from_diagonal(scale), translation);
        self.checked_map(m)
    }

    /// A scale map's values: the scale, then four vectors derived from it.
    fn scale(&mut self) -> Result<DVec3, String> {
        let s = self.vec3d("the transform's scale")?;
        self.take(4 * 24, "the transform's derived values")?;
        Ok(s)
    }

    /// An affine map's 4 x 4 matrix (OpenVDB's row vectors: the translation in the last row).
    fn affine(&mut self) -> Result<DAffine3, String> {
        let mut rows = [DVec3::ZERO; 4];
        let mut last = [0.0; 4];
        for (r, w) in rows.iter_mut().zip(&mut last) {
            *r = self.vec3d("the transform's matrix")?;
            *w = f64::from_le_bytes(self.array("the transform's matrix")?);
        }
        if last != [0.0, 0.0, 0.0, 1.0] {
            return Err(
                self.fail(&format!("an affine map's last column is {last:?}: it must be (0, 0, 0, 1)"))
            );
        }
        self.checked_map(DAffine3::from_mat3_translation(
            DMat3::from_cols(rows[0], rows[1], rows[2]),
            rows[3],
        ))
    }

    /// `m` if it is finite and invertible.
    fn checked_map(&self, m: DAffine3) -> Result<DAffine3, String> {
        let det = m.matrix3.determinant();
        match m.is_finite() && det.is_normal() {
            true => Ok(m),
            false => Err(self.fail(&format!("the transform {m:?} is not finite and invertible"))),
        }
    }

    /// The tree of the grid `name`, whose compression is `flags` and values half floats if
    /// `half`, dense over its active voxels.
    fn tree(
        &mut self,
        name: &str,
        flags: u32,
        half: bool,
        world_from_index: DAffine3,
    ) -> Result<VdbGrid, String> {
        let buffers = self.i32("the tree's buffer count")?;
        if buffers != 1 {
            return Err(self.fail(&format!("{buffers} buffers in the tree: OpenVDB writes 1")));
        }
        let background = self.f32("the background value")?;
        let tree = Tree { flags, half, background };
        let start = self.at;
        let mut bounds = Bounds { lo: [i64::MAX; 3], hi: [i64::MIN; 3] };
        tree.root(self, &mut bounds)?;
        let values_at = self.at;
        if bounds.lo[0] > bounds.hi[0] {
            return Err(self.fail(&format!("the grid \"{name}\" has no active voxels")));
        }
        let size = [0, 1, 2].map(|a| (bounds.hi[a] - bounds.lo[a] + 1) as u64);
        let count = size
            .iter()
            .try_fold(1u64, |n, &s| n.checked_mul(s))
            .filter(|&n| n <= super::vol::MAX_VALUES as u64);
        let Some(count) = count else {
            return Err(self.fail(&format!(
                "the grid \"{name}\"'s active voxels span {} x {} x {}: more than {} values",
                size[0],
                size[1],
                size[2],
                super::vol::MAX_VALUES
            )));
        };
        let size = size.map(|s| s as usize);
        let mut fill =
            Fill { lo: bounds.lo, size, values: vec![background; count as usize], leaves: Vec::new() };
        // The second walk meets the same bytes.
        self.at = start;
        tree.root(self, &mut fill)?;
        debug_assert_eq!(self.at, values_at);
        let mut leaf = [0.0f32; 512];
        for (origin, mask) in std::mem::take(&mut fill.leaves) {
            self.take(64, "a leaf's value mask")?;
            tree.values(self, &mask, &mut leaf)?;
            fill.leaf(origin, &leaf);
        }
        if let Some(i) = fill.values.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            let at = [i % size[0], i / size[0] % size[1], i / (size[0] * size[1])];
            let index = [0, 1, 2].map(|a| bounds.lo[a] + at[a] as i64);
            return Err(format!(
                "the OpenVDB file {}: the grid \"{name}\" holds {} at index {index:?}: a density must be finite and >= 0",
                self.path.display(),
                fill.values[i]
            ));
        }
        let index_min = bounds.lo.map(|v| v as i32);
        Ok(VdbGrid { size, values: fill.values, index_min, world_from_index })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::vol::VolHeader;

    /// The test grids of `scenes/vdb-make.py` (written by OpenVDB 12).
    const FILES: [&str; 5] =
        ["smoke-blosc.vdb", "smoke-zip.vdb", "smoke-zip-nomask.vdb", "smoke-none.vdb", "smoke-half.vdb"];

    fn asset(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/assets").join(name)
    }

    fn open(name: &str) -> VdbFile {
        let path = asset(name);
        VdbFile::parse(std::fs::read(&path).unwrap(), &path).unwrap()
    }

    /// The bytes of `name` changed by `edit`, read as the grid "density".
    fn read_edited(name: &str, edit: impl FnOnce(&mut Vec<u8>, &VdbFile)) -> Result<VdbGrid, String> {
        let file = open(name);
        let mut bytes = file.bytes.clone();
        edit(&mut bytes, &file);
        VdbFile::parse(bytes, Path::new(name))?.grid("density")
    }

    #[test]
    fn every_compression_gives_the_values_of_the_vol() {
        let path = asset("smoke-vdb.vol");
        let bytes = std::fs::read(&path).unwrap();
        let vol = VolHeader::parse(&bytes, &path, "grid").unwrap();
        let want = vol.values(&bytes, &path, "grid").unwrap();
        for name in FILES {
            let g = open(name).grid("density").unwrap();
            assert_eq!(g.size, vol.size, "{name}");
            assert_eq!(g.index_min, [-10, 0, 1], "{name}");
            let wrong = g.values.iter().zip(&want).filter(|(a, b)| a != b).count();
            assert_eq!(wrong, 0, "{name}: {wrong} values differ from the .vol's");
            // Voxels of 0.05, index 0 at (0.1, 0, -0.2): the first voxel's centre, in the unit
            // cube half a voxel in from the corner, stands at index (-10, 0, 1).
            let first = g.world_from_unit().transform_point3(0.5 / DVec3::new(19.0, 24.0, 19.0));
            assert!((first - DVec3::new(-0.4, 0.0, -0.15)).abs().max_element() < 1e-12, "{name}: {first}");
        }
    }

    #[test]
    fn grids_are_picked_by_name_and_other_types_refused() {
        let file = open("smoke-blosc.vdb");
        let t = file.grid("temperature").unwrap();
        assert_eq!((t.size, t.index_min, t.values), ([1, 1, 1], [0, 4, 0], vec![2.0]));
        // An instance: the density's tree (its parent's) under its own transform.
        let i = file.grids.iter().find(|g| g.name == "instance").unwrap();
        assert_eq!(i.parent, "density");
        let (instance, density) = (file.grid("instance").unwrap(), file.grid("density").unwrap());
        assert!(instance.values == density.values && instance.size == density.size);
        assert_eq!(instance.world_from_index, DAffine3::from_scale(DVec3::splat(0.1)));
        let e = file.grid("dens").unwrap_err();
        assert!(e.contains("smoke-blosc.vdb") && e.contains("no grid named \"dens\""), "{e}");
        assert!(
            e.contains("\"velocity\" (Tree_vec3s_5_4_3)") && e.contains("\"density\" (Tree_float_5_4_3)"),
            "{e}"
        );
        let e = file.grid("velocity").unwrap_err();
        assert!(e.contains("\"velocity\" is a Tree_vec3s_5_4_3: pathwave reads scalar float grids"), "{e}");
        let e = file.grid("id").unwrap_err();
        assert!(e.contains("\"id\" is a Tree_int32_5_4_3"), "{e}");
    }

    #[test]
    fn damaged_files_are_refused_with_what_was_expected() {
        // Cut short anywhere: an error naming the file, never a panic.
        let whole = open("smoke-zip.vdb").bytes;
        for n in (0..whole.len()).step_by(97).chain([whole.len() - 1]) {
            let e = VdbFile::parse(whole[..n].to_vec(), Path::new("cut.vdb")).and_then(|f| f.grid("density"));
            let e = e.unwrap_err();
            assert!(e.starts_with("the OpenVDB file cut.vdb: "), "{e}");
        }
        let e = read_edited("smoke-zip.vdb", |b, _| b.truncate(b.len() - 100)).unwrap_err();
        let n = whole.len();
        assert!(e.contains(&format!("end offset {n}: not within the file's {} bytes", n - 100)), "{e}");
        let e = read_edited("smoke-zip.vdb", |b, _| b.truncate(40)).unwrap_err();
        assert!(e.contains("at byte 21: the UUID is cut short (36 bytes, 19 left)"), "{e}");
        let e = read_edited("smoke-zip.vdb", |b, _| b.truncate(100)).unwrap_err();
        assert!(e.contains("1 grids: between 0 and 0 fit in the bytes left"), "{e}");
        // An unknown compression flag (0x8) of the grid.
        let e = read_edited("smoke-zip.vdb", |b, f| b[f.grids[0].at] |= 0x8).unwrap_err();
        assert!(
            e.contains("at byte 124: compression flags 0xb")
                && e.contains("zip (0x1), active mask (0x2) and blosc (0x4)"),
            "{e}"
        );
        // A huge grid count (after the header: magic, version, library, flag, UUID, metadata).
        let e = read_edited("smoke-zip.vdb", |b, _| {
            let meta = 8 + 4 + 8 + 1 + 36;
            assert_eq!(b[meta..meta + 4], [0; 4], "the test files have no file metadata");
            b[meta + 4..meta + 8].copy_from_slice(&i32::MAX.to_le_bytes());
        })
        .unwrap_err();
        assert!(e.contains("2147483647 grids: between 0 and"), "{e}");
        // A huge tile count at the root.
        let e = read_edited("smoke-zip.vdb", |b, f| {
            let mut c = Cursor { bytes: &f.bytes, at: f.grids[0].at, path: Path::new(""), mark: 0, flags: 0 };
            c.grid_header("density").unwrap();
            let tiles = c.at + 8;
            b[tiles..tiles + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        })
        .unwrap_err();
        assert!(e.contains("4294967295 tiles and 2 children at the root: they need"), "{e}");
        // An older file format version, and not an OpenVDB file at all.
        let e = read_edited("smoke-zip.vdb", |b, _| b[8] = 221).unwrap_err();
        assert!(e.contains("file format version 221: pathwave reads versions 222 to 225"), "{e}");
        let e = read_edited("smoke-zip.vdb", |b, _| b[0] = b'V').unwrap_err();
        assert!(e.contains("not an OpenVDB file"), "{e}");
    }
}
