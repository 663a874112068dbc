//! Mitsuba's `.serialized` meshes (the format of Mitsuba 3's `src/shapes/serialized.cpp`, whose
//! header comment describes it): one or more meshes, each a little-endian `u16` format code
//! `0x041C` and version (3 or 4) followed by a zlib stream of flags, the name (version 4),
//! vertex and triangle counts (`u64`), positions, then as the flags say normals, uv and
//! colours (`f32`, or `f64` with flag `0x2000`), then `u32` vertex indices; the file ends with
//! the offset of each mesh (`u64`, `u32` in version 3) and their count (`u32`). A scene picks one
//! mesh by its index (`shape_index`). Colours become the attribute `vertex_color` (Mitsuba reads
//! past them); the face-normals flag is ignored, as Mitsuba 3 ignores it (`face_normals` asks).
//! As Mitsuba, uv are read as written: pathwave's v runs the other way, so its XML reader flips
//! them (`flip_tex_coords`).
//!
//! The streams are inflated by `flate2` (with `miniz_oxide`, already among the image crates'
//! dependencies). Counts are checked before anything is read for them and arrays grow only as
//! the stream delivers data, within [`MAX_INFLATED`] bytes in all, so that a small file cannot
//! claim or inflate to more.

use crate::accel::mesh::{MeshAttribute, MeshData};
use std::io::Read;
use std::path::Path;

/// The format code every mesh starts with.
const FORMAT: u16 = 0x041C;
/// The most bytes one mesh may inflate to (as much as an uncompressed mesh file may have).
pub const MAX_INFLATED: u64 = crate::format::files::MAX_ASSET_BYTES;

/// A `.serialized` file: its bytes and where each mesh starts.
#[derive(Debug)]
pub struct SerializedFile {
    bytes: Vec<u8>,
    /// Offsets of the meshes (the first is 0); only the first when the table at the end is
    /// missing or broken.
    offsets: Vec<usize>,
    /// The table at the end is missing or broken.
    no_table: bool,
}

impl SerializedFile {
    /// The file `bytes` (`path` names it in errors): its first header and its table of meshes.
    pub fn new(bytes: Vec<u8>, path: &Path) -> Result<Self, String> {
        let fail = |m: &str| format!("cannot read the mesh {}: {m}", path.display());
        let version = header(&bytes, 0).map_err(|m| fail(&m))?;
        let (offsets, no_table) = match table(&bytes, version) {
            Some(o) => (o, false),
            None => (vec![0], true),
        };
        Ok(Self { bytes, offsets, no_table })
    }

    /// How many meshes the file holds (1 when its table is missing).
    pub fn count(&self) -> usize {
        self.offsets.len()
    }

    /// Mesh `index` (`path` names the file in errors).
    pub fn mesh(&self, index: usize, path: &Path) -> Result<MeshData, String> {
        let fail = |m: String| format!("cannot read mesh {index} of {}: {m}", path.display());
        let Some(&start) = self.offsets.get(index) else {
            let why = match self.no_table {
                true => {
                    "its table of meshes at the end is missing or broken, so only mesh 0 can be read".into()
                }
                false => format!("it holds {} meshes (shape_index 0 to {})", self.count(), self.count() - 1),
            };
            return Err(format!("cannot read mesh {index} of {}: {why}", path.display()));
        };
        let version = header(&self.bytes, start).map_err(fail)?;
        let mut z =
            Inflated { z: flate2::read::ZlibDecoder::new(&self.bytes[start + 4..]), budget: MAX_INFLATED };
        let flags = u32::from_le_bytes(z.array().map_err(fail)?);
        if version == 4 {
            // The name, NUL-terminated.
            while z.array::<1>().map_err(fail)?[0] != 0 {}
        }
        let vertices = u64::from_le_bytes(z.array().map_err(fail)?);
        let faces = u64::from_le_bytes(z.array().map_err(fail)?);
        if vertices > u32::MAX as u64 {
            return Err(fail(format!("{vertices} vertices, more than pathwave indexes")));
        }
        let double = flags & 0x2000 != 0;
        let mut floats = |per: u64| z.floats(vertices, per, double).map_err(fail);
        let positions: Vec<glam::Vec3A> =
            floats(3)?.chunks_exact(3).map(|p| glam::Vec3A::new(p[0], p[1], p[2])).collect();
        let normals = match flags & 0x1 != 0 {
            true => Some(floats(3)?.chunks_exact(3).map(|n| glam::Vec3A::new(n[0], n[1], n[2])).collect()),
            false => None,
        };
        let uvs = match flags & 0x2 != 0 {
            true => Some(floats(2)?.chunks_exact(2).map(|t| glam::Vec2::new(t[0], t[1])).collect()),
            false => None,
        };
        let mut attributes = Vec::new();
        if flags & 0x8 != 0 {
            attributes.push(MeshAttribute { name: "vertex_color".into(), channels: 3, values: floats(3)? });
        }
        let indices = z.bytes(faces, 12).map_err(fail)?;
        let triangles = indices
            .chunks_exact(12)
            .map(|t| {
                std::array::from_fn(|k| {
                    u32::from_le_bytes([t[4 * k], t[4 * k + 1], t[4 * k + 2], t[4 * k + 3]])
                })
            })
            .collect();
        super::assets::finish_mesh(positions, triangles, normals, uvs, attributes, path)
    }
}

/// The version of the mesh header at `at`.
fn header(bytes: &[u8], at: usize) -> Result<u16, String> {
    let word = |k: usize| bytes.get(at + k..at + k + 2).map(|b| u16::from_le_bytes([b[0], b[1]]));
    match (word(0), word(2)) {
        (Some(FORMAT), Some(v @ (3 | 4))) => Ok(v),
        (Some(FORMAT), Some(v)) => Err(format!("version {v}, not 3 or 4")),
        _ => Err("it is not a Mitsuba .serialized mesh (no format code 0x041C)".into()),
    }
}

/// The offsets of the table at the end of the file, when it is whole: a count of at least one,
/// offsets from 0 rising within the file, each at a mesh header.
fn table(bytes: &[u8], version: u16) -> Option<Vec<usize>> {
    let len = bytes.len();
    let count = u32::from_le_bytes(bytes.get(len.checked_sub(4)?..)?.try_into().ok()?) as usize;
    let width = if version == 4 { 8 } else { 4 };
    let start = len.checked_sub(4)?.checked_sub(count.checked_mul(width)?)?;
    let offsets: Vec<usize> = bytes[start..len - 4]
        .chunks_exact(width)
        .map(|o| o.iter().rev().fold(0u64, |acc, &b| acc << 8 | b as u64))
        .map(|o| usize::try_from(o).unwrap_or(usize::MAX))
        .collect();
    let ok = offsets.first() == Some(&0)
        && offsets.windows(2).all(|w| w[0] < w[1])
        && offsets.iter().all(|&o| o < start && start - o >= 4 && header(bytes, o).is_ok());
    ok.then_some(offsets)
}

/// An inflating reader that gives at most `budget` bytes in all.
struct Inflated<'a> {
    z: flate2::read::ZlibDecoder<&'a [u8]>,
    budget: u64,
}

impl Inflated<'_> {
    /// The next `N` bytes.
    fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let b = self.bytes(1, N as u64)?;
        Ok(std::array::from_fn(|i| b[i]))
    }

    /// The next `count * size` bytes, refused beyond the budget; read as they come (nothing is
    /// reserved for a count the stream does not back with data).
    fn bytes(&mut self, count: u64, size: u64) -> Result<Vec<u8>, String> {
        let n = count.checked_mul(size).filter(|&n| n <= self.budget).ok_or_else(|| {
            format!("{count} records of {size} bytes are more than the {MAX_INFLATED} bytes a mesh may hold")
        })?;
        self.budget -= n;
        let mut out = Vec::new();
        (&mut self.z)
            .take(n)
            .read_to_end(&mut out)
            .map_err(|e| format!("the compressed data is broken: {e}"))?;
        if (out.len() as u64) < n {
            return Err("the compressed data ends early".into());
        }
        Ok(out)
    }

    /// `count * per` numbers, `f64` or `f32` in the file, as `f32`.
    fn floats(&mut self, count: u64, per: u64, double: bool) -> Result<Vec<f32>, String> {
        let size = if double { 8 } else { 4 };
        let b = self.bytes(count.saturating_mul(per), size)?;
        Ok(match double {
            true => {
                b.chunks_exact(8).map(|x| f64::from_le_bytes(x.try_into().unwrap_or([0; 8])) as f32).collect()
            }
            false => b.chunks_exact(4).map(|x| f32::from_le_bytes([x[0], x[1], x[2], x[3]])).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// A mesh as a version 4 stream: flags, name, counts, data.
    fn stream(flags: u32, double: bool, vertices: &[[f64; 3]], uv: bool, faces: &[[u32; 3]]) -> Vec<u8> {
        let mut raw = Vec::new();
        raw.extend(flags.to_le_bytes());
        raw.extend(b"mesh\0");
        raw.extend((vertices.len() as u64).to_le_bytes());
        raw.extend((faces.len() as u64).to_le_bytes());
        let num = |raw: &mut Vec<u8>, x: f64| match double {
            true => raw.extend(x.to_le_bytes()),
            false => raw.extend((x as f32).to_le_bytes()),
        };
        for v in vertices {
            v.iter().for_each(|&x| num(&mut raw, x));
        }
        if flags & 1 != 0 {
            (0..vertices.len() * 3).for_each(|i| num(&mut raw, if i % 3 == 2 { 1.0 } else { 0.0 }));
        }
        if uv {
            vertices.iter().for_each(|v| [v[0], v[1]].iter().for_each(|&x| num(&mut raw, x)));
        }
        if flags & 8 != 0 {
            (0..vertices.len() * 3).for_each(|i| num(&mut raw, i as f64 / 10.0));
        }
        faces.iter().flatten().for_each(|i| raw.extend(i.to_le_bytes()));
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&raw).unwrap();
        let mut out = FORMAT.to_le_bytes().to_vec();
        out.extend(4u16.to_le_bytes());
        out.extend(z.finish().unwrap());
        out
    }

    /// Meshes concatenated, with the table.
    fn file(meshes: &[Vec<u8>]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut offsets = Vec::new();
        for m in meshes {
            offsets.push(out.len() as u64);
            out.extend(m);
        }
        offsets.iter().for_each(|o| out.extend(o.to_le_bytes()));
        out.extend((meshes.len() as u32).to_le_bytes());
        out
    }

    const SQUARE: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];

    #[test]
    fn meshes_are_picked_by_index_with_normals_uv_and_colours() {
        let a = stream(0x1003 | 8, false, &SQUARE, true, &[[0, 1, 2], [0, 2, 3]]);
        let b = stream(0x2000, true, &SQUARE[..3], false, &[[0, 1, 2]]);
        let f = SerializedFile::new(file(&[a, b]), Path::new("t.serialized")).unwrap();
        assert_eq!(f.count(), 2);
        let m = f.mesh(0, Path::new("t.serialized")).unwrap();
        assert_eq!(m.triangles, [[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.normals.as_ref().unwrap()[3], glam::Vec3A::Z);
        assert_eq!(m.uvs.as_ref().unwrap()[2], glam::Vec2::ONE);
        assert_eq!((m.attributes[0].name.as_str(), m.attributes[0].values[4]), ("vertex_color", 0.4));
        let m = f.mesh(1, Path::new("t.serialized")).unwrap();
        assert_eq!(m.positions[1], glam::Vec3A::X);
        assert!(m.normals.is_none() && m.uvs.is_none() && m.attributes.is_empty());
        let err = f.mesh(2, Path::new("t.serialized")).unwrap_err();
        assert!(err.contains("holds 2 meshes"), "{err}");
    }

    #[test]
    fn malformed_files_are_refused_without_panicking() {
        let p = Path::new("t.serialized");
        let good = file(&[stream(3, false, &SQUARE, true, &[[0, 1, 2]])]);
        let read = |b: &[u8]| SerializedFile::new(b.to_vec(), p).and_then(|f| f.mesh(0, p));
        assert!(read(&good).is_ok());
        // Every truncation, and every single flipped byte, fails cleanly or reads a mesh.
        for cut in 0..good.len() {
            let _ = read(&good[..cut]);
        }
        for i in 0..good.len() {
            let mut b = good.clone();
            b[i] ^= 0x5a;
            let _ = read(&b);
        }
        let says = |b: &[u8], what: &str| {
            let err = read(b).expect_err(what);
            assert!(err.contains("t.serialized") && err.contains(what), "{what}: {err}");
        };
        says(b"\x1c\x04", "format code");
        says(b"\x1c\x04\x05\x00", "version 5");
        says(&good[..good.len() - 30], "compressed data");
        // A count far beyond what the stream backs: refused before anything is reserved.
        let mut raw = 0u32.to_le_bytes().to_vec();
        raw.extend(b"\0");
        raw.extend((u32::MAX as u64).to_le_bytes());
        raw.extend(u64::MAX.to_le_bytes());
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&raw).unwrap();
        let huge = [&[0x1c, 0x04, 0x04, 0x00][..], &z.finish().unwrap()].concat();
        says(&huge, "more than");
        let out_of_range = file(&[stream(0, false, &SQUARE, false, &[[0, 1, 7]])]);
        says(&out_of_range, "out of range");
    }

    /// A table offset near `u64::MAX` overflowed `offset + 4` where overflow is checked (debug
    /// builds, the `serialized` fuzzer, which found it): the table is broken, and mesh 0 is
    /// still read.
    #[test]
    fn a_table_offset_near_the_largest_u64_is_a_broken_table() {
        let p = Path::new("t.serialized");
        let mesh = stream(3, false, &SQUARE, true, &[[0, 1, 2]]);
        let mut b = mesh.clone();
        b.extend(0u64.to_le_bytes());
        b.extend(u64::MAX.to_le_bytes());
        b.extend(2u32.to_le_bytes());
        let f = SerializedFile::new(b, p).unwrap();
        assert_eq!(f.count(), 1);
        assert!(f.mesh(0, p).is_ok());
        assert!(f.mesh(1, p).unwrap_err().contains("table of meshes"));
    }
}
