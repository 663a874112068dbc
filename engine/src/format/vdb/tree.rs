//! The tree of an OpenVDB float grid (`tree/RootNode.h`, `InternalNode.h`, `LeafNode.h`): the
//! walk of its topology (root tiles and children, internal nodes of 32^3 and 16^3 slots, leaves
//! of 8^3 voxels), first for the box of its active voxels, then to fill that dense box with its
//! tiles' and leaves' values (`readCompressedValues`).

use super::compress::{chunk, inflate, unblosc};
use super::{ACTIVE_MASK, BLOSC, Cursor, ZIP};
use std::borrow::Cow;

/// What the walk of a tree's topology meets, in the file's order.
pub(super) trait Visit {
    /// Whether only active tiles matter: the walk then passes over the inactive ones by the
    /// words of the node's masks.
    const ACTIVE_ONLY: bool = false;
    /// A tile of `side`^3 voxels from `origin` holding `value`.
    fn tile(&mut self, origin: [i32; 3], side: i32, value: f32, active: bool);
    /// A leaf at `origin` whose active voxels `mask` marks (bit `(x << 6) | (y << 3) | z`).
    fn leaf_topology(&mut self, origin: [i32; 3], mask: [u8; 64]);
}

/// The first walk: the box of the active voxels.
pub(super) struct Bounds {
    pub(super) lo: [i64; 3],
    pub(super) hi: [i64; 3],
}

impl Bounds {
    fn add(&mut self, lo: [i64; 3], hi: [i64; 3]) {
        for a in 0..3 {
            self.lo[a] = self.lo[a].min(lo[a]);
            self.hi[a] = self.hi[a].max(hi[a]);
        }
    }
}

impl Visit for Bounds {
    const ACTIVE_ONLY: bool = true;

    fn tile(&mut self, origin: [i32; 3], side: i32, _: f32, active: bool) {
        if active {
            let lo = origin.map(i64::from);
            self.add(lo, lo.map(|v| v + side as i64 - 1));
        }
    }

    fn leaf_topology(&mut self, origin: [i32; 3], mask: [u8; 64]) {
        for n in (0..512).filter(|&n| bit(&mask, n)) {
            let p = [0, 1, 2].map(|a| origin[a] as i64 + local(n, 3)[a] as i64);
            self.add(p, p);
        }
    }
}

/// The second walk: tiles filled into the dense box, leaves listed for their values.
pub(super) struct Fill {
    pub(super) lo: [i64; 3],
    pub(super) size: [usize; 3],
    pub(super) values: Vec<f32>,
    pub(super) leaves: Vec<([i32; 3], [u8; 64])>,
}

impl Fill {
    /// The part of the box from `origin` of `side` voxels that lies in the dense box, as
    /// ranges of dense indices per axis.
    fn overlap(&self, origin: [i32; 3], side: i64) -> Option<[std::ops::Range<usize>; 3]> {
        let mut r = [0..0, 0..0, 0..0];
        for a in 0..3 {
            let lo = (origin[a] as i64 - self.lo[a]).max(0);
            let hi = (origin[a] as i64 + side - self.lo[a]).min(self.size[a] as i64);
            if lo >= hi {
                return None;
            }
            r[a] = lo as usize..hi as usize;
        }
        Some(r)
    }

    /// The dense index of voxel `(x, y, z)` of the box.
    fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.size[1] + y) * self.size[0] + x
    }

    /// Writes the 512 values of the leaf at `origin` into the box.
    pub(super) fn leaf(&mut self, origin: [i32; 3], leaf: &[f32; 512]) {
        let Some([rx, ry, rz]) = self.overlap(origin, 8) else { return };
        let base = [0, 1, 2].map(|a| (origin[a] as i64 - self.lo[a]) as isize);
        for z in rz {
            for y in ry.clone() {
                for x in rx.clone() {
                    let [lx, ly, lz] = [x as isize - base[0], y as isize - base[1], z as isize - base[2]];
                    let i = self.index(x, y, z);
                    self.values[i] = leaf[((lx << 6) | (ly << 3) | lz) as usize];
                }
            }
        }
    }
}

impl Visit for Fill {
    fn tile(&mut self, origin: [i32; 3], side: i32, value: f32, _: bool) {
        let Some([rx, ry, rz]) = self.overlap(origin, side as i64) else { return };
        for z in rz {
            for y in ry.clone() {
                let row = self.index(rx.start, y, z);
                self.values[row..row + rx.len()].fill(value);
            }
        }
    }

    fn leaf_topology(&mut self, origin: [i32; 3], mask: [u8; 64]) {
        self.leaves.push((origin, mask));
    }
}

/// Bit `n` of a node mask (64-bit little-endian words).
fn bit(mask: &[u8], n: usize) -> bool {
    mask[n >> 3] >> (n & 7) & 1 == 1
}

/// The set bits of a node mask, less those of `minus`, in increasing order, a 64-bit word at
/// a time (a root child's 32,768 slots are 512 words, mostly zero).
fn ones<'a>(mask: &'a [u8], minus: Option<&'a [u8]>) -> impl Iterator<Item = usize> + 'a {
    let word = |m: &[u8], w: usize| u64::from_le_bytes(std::array::from_fn(|k| m[w * 8 + k]));
    (0..mask.len() / 8).flat_map(move |w| {
        let mut bits = word(mask, w) & !minus.map_or(0, |m| word(m, w));
        std::iter::from_fn(move || {
            (bits != 0).then(|| {
                let i = w * 64 + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                i
            })
        })
    })
}

/// The position of slot `n` in a node of `2^log2` slots a side: x slowest, z fastest.
fn local(n: usize, log2: u32) -> [i32; 3] {
    let m = (1 << log2) - 1;
    [(n >> (2 * log2)) as i32, ((n >> log2) & m) as i32, (n & m) as i32]
}

/// How a tree's values are stored.
pub(super) struct Tree {
    pub(super) flags: u32,
    pub(super) half: bool,
    pub(super) background: f32,
}

impl Tree {
    /// The root's tiles and children, their topology to `v`.
    pub(super) fn root(&self, c: &mut Cursor, v: &mut impl Visit) -> Result<(), String> {
        let tiles = c.u32("the root's tile count")? as usize;
        let children = c.u32("the root's child count")? as usize;
        // A tile takes 17 bytes, a child at least its origin and two masks.
        let need = tiles as u128 * 17 + children as u128 * (12 + 2 * 4096);
        if need > c.left() as u128 {
            return Err(c.fail(&format!(
                "{tiles} tiles and {children} children at the root: they need {need} bytes, {} are left",
                c.left()
            )));
        }
        let mut keys: Vec<[i32; 3]> = Vec::with_capacity(tiles);
        for _ in 0..tiles {
            let origin = self.root_origin(c, keys.last())?;
            let value = c.f32("a root tile's value")?;
            let active = match c.u8("a root tile's active flag")? {
                a @ (0 | 1) => a == 1,
                a => return Err(c.fail(&format!("a tile's active flag {a}: 0 or 1"))),
            };
            keys.push(origin);
            v.tile(origin, 4096, value, active);
        }
        let mut last = None;
        for _ in 0..children {
            let origin = self.root_origin(c, last.as_ref())?;
            if keys.binary_search(&origin).is_ok() {
                return Err(c.fail(&format!("a root child at {origin:?} where the root has a tile")));
            }
            last = Some(origin);
            self.internal(c, v, origin, 5, 7)?;
        }
        Ok(())
    }

    /// The origin of a root tile or child: a multiple of 4096, after `last`.
    fn root_origin(&self, c: &mut Cursor, last: Option<&[i32; 3]>) -> Result<[i32; 3], String> {
        let mut o = [0; 3];
        for x in &mut o {
            *x = c.i32("a root entry's origin")?;
        }
        if o.iter().any(|x| x & 4095 != 0) {
            return Err(c.fail(&format!("a root entry at {o:?}: its coordinates must be multiples of 4096")));
        }
        if last.is_some_and(|l| *l >= o) {
            return Err(c.fail(&format!(
                "a root entry at {o:?} after one at {:?}: OpenVDB writes them in increasing order",
                last.unwrap_or(&o)
            )));
        }
        Ok(o)
    }

    /// An internal node of `2^log2` slots a side at `origin`, whose children span `2^child`
    /// voxels a side (leaves when `child` is 3).
    fn internal<V: Visit>(
        &self,
        c: &mut Cursor,
        v: &mut V,
        origin: [i32; 3],
        log2: u32,
        child: u32,
    ) -> Result<(), String> {
        let n = 1usize << (3 * log2);
        let children = c.take(n / 8, "an internal node's child mask")?;
        let active = c.take(n / 8, "an internal node's value mask")?;
        let mut values = vec![0.0f32; n];
        self.values(c, active, &mut values)?;
        let at = |i: usize| {
            let l = local(i, log2);
            [0, 1, 2].map(|a| origin[a] + (l[a] << child))
        };
        match V::ACTIVE_ONLY {
            true => {
                for i in ones(active, Some(children)) {
                    v.tile(at(i), 1 << child, values[i], true);
                }
            }
            false => {
                for (i, &value) in values.iter().enumerate().filter(|(i, _)| !bit(children, *i)) {
                    v.tile(at(i), 1 << child, value, bit(active, i));
                }
            }
        }
        for i in ones(children, None) {
            match child {
                3 => v.leaf_topology(at(i), c.array("a leaf's value mask")?),
                _ => self.internal(c, v, at(i), 4, 3)?,
            }
        }
        Ok(())
    }

    /// A node's values (`readCompressedValues`), `out.len()` of them, of which `mask` marks
    /// the active.
    pub(super) fn values(&self, c: &mut Cursor, mask: &[u8], out: &mut [f32]) -> Result<(), String> {
        let kind = c.u8("a node's value compression")?;
        let bg = self.background;
        let (mut inactive0, mut inactive1) = (if kind == 0 { bg } else { -bg }, bg);
        if kind > 6 {
            return Err(c.fail(&format!(
                "a node's value compression {kind}: OpenVDB's are 0 to 6 (io/Compression.h)"
            )));
        }
        if matches!(kind, 2 | 4 | 5) {
            inactive0 = c.f32("a node's inactive value")?;
            if kind == 5 {
                inactive1 = c.f32("a node's second inactive value")?;
            }
        }
        let select = match kind {
            3..=5 => Some(c.take(out.len() / 8, "a node's inactive value selection")?),
            _ => None,
        };
        let masked = self.flags & ACTIVE_MASK != 0 && kind != 6;
        let count = match masked {
            true => mask[..out.len() / 8].iter().map(|b| b.count_ones() as usize).sum(),
            false => out.len(),
        };
        let read = self.data(c, count)?;
        if count == out.len() {
            out.copy_from_slice(&read);
            return Ok(());
        }
        let mut read = read.into_iter();
        for (i, o) in out.iter_mut().enumerate() {
            *o = match (bit(mask, i), select) {
                (true, _) => read.next().unwrap_or(bg),
                (false, Some(s)) if bit(s, i) => inactive1,
                (false, _) => inactive0,
            };
        }
        Ok(())
    }

    /// `count` values (`readData`, or `HalfReader` for half floats): raw, zlib or Blosc.
    fn data(&self, c: &mut Cursor, count: usize) -> Result<Vec<f32>, String> {
        if self.half && count == 0 {
            // OpenVDB writes nothing, not even a size, for no half values.
            return Ok(Vec::new());
        }
        let width = if self.half { 2 } else { 4 };
        let n = count * width;
        let bytes: Cow<[u8]> = match self.flags & (ZIP | BLOSC) {
            0 => Cow::Borrowed(c.take(n, "a node's values")?),
            ZIP => Cow::Owned(chunk(c, n, "zip", inflate)?),
            _ => Cow::Owned(chunk(c, n, "blosc", unblosc)?),
        };
        Ok(match self.half {
            true => bytes.chunks_exact(2).map(|b| half::f16::from_le_bytes([b[0], b[1]]).to_f32()).collect(),
            false => bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The word-by-word walk gives the bits `bit` reads, in order, less those of the other
    /// mask: on masks of every density, empty and full words among them.
    #[test]
    fn ones_are_the_set_bits_in_order() {
        let mut rnd = crate::testing::uniform(5);
        for density in [0.0, 0.01, 0.5, 0.99, 1.0] {
            let mask: Vec<u8> =
                (0..512).map(|_| (0..8).fold(0, |b, k| b | ((rnd() < density) as u8) << k)).collect();
            let minus: Vec<u8> = (0..512).map(|_| (rnd() * 256.0) as u8).collect();
            let want: Vec<usize> = (0..4096).filter(|&i| bit(&mask, i)).collect();
            assert_eq!(ones(&mask, None).collect::<Vec<_>>(), want);
            let want: Vec<usize> = want.into_iter().filter(|&i| !bit(&minus, i)).collect();
            assert_eq!(ones(&mask, Some(&minus)).collect::<Vec<_>>(), want);
        }
    }
}
