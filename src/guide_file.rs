//! Path guiding's learned guides in a file (`--guide-file`, and beside a checkpoint), so that
//! a resumed render, or every share of a farm's image, renders with the guides one training
//! learned instead of training again (the same bits either way: training is a function of
//! the scene, the settings and the seed).
//!
//! The file is binary, little-endian: the magic `PWGUIDE1`, the 64-bit key of the render it
//! was learned for (the checkpoint key of the whole image: [`super::render::image::RenderId`]),
//! the number of training stages it holds, then per stage after the first (which renders
//! without a guide) a byte saying whether a guide was learned and, if one was, its box (six
//! `f32`), its cell count (`u64`), its nodes (a `u64` count, then `u32`s) and its grids (a
//! `u64` count of bins, then their `f32` densities and their `u32` alias words), and last the
//! XXH3-64 checksum of everything before it. A file that fails a check (version, checksum,
//! sizes, a guide's own checks) is refused with what is wrong.

use crate::engine::guiding::{Guide, GuideParts};
use std::path::Path;
use std::sync::Arc;

const MAGIC: &[u8; 8] = b"PWGUIDE1";

/// The guides of a render's training stages: `guides[k]` renders stage `k` (the first
/// `None`), as `integrator::guide_training::Training::guides` holds them.
pub type Guides = Vec<Option<Arc<Guide>>>;

/// The largest guide file read (a guide of a few thousand cells takes a few MB).
pub const MAX_BYTES: u64 = 1 << 30;

/// The guides of the training stages (`guides[k]` renders stage `k`; the first `None`) for
/// the render whose key is `key`, as the file's bytes.
pub fn to_bytes(key: u64, guides: &[Option<Arc<Guide>>]) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&key.to_le_bytes());
    out.extend_from_slice(&(guides.len() as u32).to_le_bytes());
    for g in guides.iter().skip(1) {
        out.push(g.is_some() as u8);
        let Some(g) = g else { continue };
        let p = g.to_parts();
        for x in p.lo.iter().chain(&p.inv_size) {
            out.extend_from_slice(&x.to_le_bytes());
        }
        out.extend_from_slice(&p.cells.to_le_bytes());
        out.extend_from_slice(&(p.nodes.len() as u64).to_le_bytes());
        out.extend(p.nodes.iter().flat_map(|n| n.to_le_bytes()));
        out.extend_from_slice(&(p.grids.0.len() as u64).to_le_bytes());
        out.extend(p.grids.0.iter().flat_map(|x| x.to_le_bytes()));
        out.extend(p.grids.1.iter().flat_map(|x| x.to_le_bytes()));
    }
    let checksum = xxhash_rust::xxh3::xxh3_64(&out);
    out.extend_from_slice(&checksum.to_le_bytes());
    out
}

/// Writes the file at `path` (whole or not at all).
pub fn save(path: &Path, key: u64, guides: &[Option<Arc<Guide>>]) -> Result<(), String> {
    crate::io::atomically(path, &to_bytes(key, guides))
}

/// Reads the file at `path`: its key and guides ([`to_bytes`]).
pub fn load(path: &Path) -> Result<(u64, Guides), String> {
    let size = std::fs::metadata(path).map_err(|e| format!("{}: {e}", path.display()))?.len();
    if size > MAX_BYTES {
        return Err(format!("{}: {size} bytes, more than a guide file's {MAX_BYTES}", path.display()));
    }
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    from_bytes(&bytes).map_err(|e| format!("{}: not a guide file pathwave can read: {e}", path.display()))
}

/// The key and guides of a file's `bytes`.
pub fn from_bytes(bytes: &[u8]) -> Result<(u64, Guides), String> {
    if bytes.len() < MAGIC.len() + 8 + 4 + 8 || &bytes[..8] != MAGIC {
        return Err("no PWGUIDE1 header".into());
    }
    let (body, tail) = bytes.split_at(bytes.len() - 8);
    if xxhash_rust::xxh3::xxh3_64(body) != u64::from_le_bytes(tail.try_into().expect("8 bytes")) {
        return Err("its checksum does not match (a damaged or cut file)".into());
    }
    let mut r = Reader { bytes: body, at: MAGIC.len() };
    let key = r.u64()?;
    let stages = r.u32()? as usize;
    if stages == 0 || stages > 32 {
        return Err(format!("{stages} stages: 1 to 32 expected"));
    }
    let mut guides = vec![None];
    for k in 1..stages {
        let guide = match r.bytes(1)?[0] {
            0 => None,
            1 => {
                let mut v = [0.0f32; 6];
                for x in &mut v {
                    *x = r.f32()?;
                }
                let cells = r.u64()?;
                let n = r.count(4)?;
                let nodes = (0..n).map(|_| r.u32()).collect::<Result<_, _>>()?;
                let bins = r.count(8)?;
                let pdf = (0..bins).map(|_| r.f32()).collect::<Result<_, _>>()?;
                let alias = (0..bins).map(|_| r.u32()).collect::<Result<_, _>>()?;
                let parts = GuideParts {
                    lo: [v[0], v[1], v[2]],
                    inv_size: [v[3], v[4], v[5]],
                    cells,
                    nodes,
                    grids: (pdf, alias),
                };
                Some(Arc::new(Guide::from_parts(parts).map_err(|e| format!("stage {k}: {e}"))?))
            }
            b => return Err(format!("stage {k}: {b} where 0 or 1 (a guide or none) was expected")),
        };
        guides.push(guide);
    }
    if r.at != body.len() {
        return Err(format!("{} bytes after the last guide", body.len() - r.at));
    }
    Ok((key, guides))
}

/// Reads a file's fields in order, each bounded by what is left.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn bytes(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| format!("cut short at byte {} ({n} more expected)", self.at))?;
        let b = &self.bytes[self.at..end];
        self.at = end;
        Ok(b)
    }

    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.bytes(4)?.try_into().expect("4 bytes")))
    }

    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.bytes(8)?.try_into().expect("8 bytes")))
    }

    fn f32(&mut self) -> Result<f32, String> {
        Ok(f32::from_le_bytes(self.bytes(4)?.try_into().expect("4 bytes")))
    }

    /// A count of items of `size` bytes each, no more than the bytes left hold.
    fn count(&mut self, size: usize) -> Result<usize, String> {
        let n = self.u64()?;
        let left = (self.bytes.len() - self.at) / size;
        match usize::try_from(n) {
            Ok(n) if n <= left => Ok(n),
            _ => Err(format!("{n} items of {size} bytes at byte {}, where {left} fit", self.at)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::guiding::{Record, Refine, SpatialRefine, to_square};
    use glam::Vec3A;

    fn guide() -> Guide {
        let records: Vec<Record> = (0..5000)
            .map(|k| {
                let t = k as f32 / 5000.0;
                let d = Vec3A::new(t - 0.5, 0.3, 1.0).normalize();
                Record {
                    p: [t, (t * 7.0).fract(), (t * 13.0).fract()],
                    square: to_square(d),
                    energy: 1.0 + t,
                }
            })
            .collect();
        let spatial = SpatialRefine { max_records: 500, max_depth: 30 };
        Guide::build(&records, Vec3A::ZERO, Vec3A::ONE, spatial, Refine::DEFAULT)
    }

    #[test]
    fn guides_come_back_as_written_and_damaged_files_are_refused() {
        let g = Some(Arc::new(guide()));
        let guides = vec![None, g.clone(), None, g];
        let bytes = to_bytes(42, &guides);
        let (key, back) = from_bytes(&bytes).expect("read back");
        assert_eq!(key, 42);
        assert_eq!(back, guides);
        // A flipped bit anywhere fails the checksum; a cut file too.
        let mut bad = bytes.clone();
        bad[40] ^= 1;
        assert!(from_bytes(&bad).unwrap_err().contains("checksum"));
        assert!(from_bytes(&bytes[..bytes.len() - 9]).is_err());
        assert!(from_bytes(b"PWCKPT04........").unwrap_err().contains("header"));
        // A count larger than the file, with a right checksum, is refused before allocating.
        let mut big = to_bytes(42, &[None, guides[1].clone()]);
        big.truncate(big.len() - 8);
        let count_at = 8 + 8 + 4 + 1 + 24 + 8;
        big[count_at..count_at + 8].copy_from_slice(&u64::MAX.to_le_bytes());
        let sum = xxhash_rust::xxh3::xxh3_64(&big);
        big.extend_from_slice(&sum.to_le_bytes());
        assert!(from_bytes(&big).unwrap_err().contains("items of 4 bytes"));
    }
}
