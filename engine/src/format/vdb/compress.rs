//! Compressed values of an OpenVDB file (`io/Compression.h`): zlib streams (`flate2`) and Blosc
//! chunks: Blosc's 16-byte header, its block offsets and, per block, one LZ4 stream per byte of
//! the type (`lz4_flex`), byte-unshuffled (c-blosc's `README_CHUNK_FORMAT` and `blosc_d`).

use super::Cursor;

/// A compressed chunk of `n` bytes once decoded (`unzipFromStream`, `bloscFromStream`): its
/// size (an `int64`; minus the size for bytes stored as they are), then the bytes, decoded by
/// `decode` into exactly `n` bytes.
pub(super) fn chunk(
    c: &mut Cursor,
    n: usize,
    what: &str,
    decode: fn(&[u8], &mut [u8]) -> Result<(), String>,
) -> Result<Vec<u8>, String> {
    let size = c.i64(&format!("the size of a {what} chunk"))?;
    if size <= 0 {
        if size.unsigned_abs() != n as u64 {
            return Err(
                c.fail(&format!("a stored {what} chunk of {} bytes: expected {n}", size.unsigned_abs()))
            );
        }
        return Ok(c.take(n, &format!("a stored {what} chunk"))?.to_vec());
    }
    let packed = c.take(usize::try_from(size).unwrap_or(usize::MAX), &format!("a {what} chunk"))?;
    let mut out = vec![0; n];
    match decode(packed, &mut out) {
        Ok(()) => Ok(out),
        Err(why) => Err(c.fail(&format!("a {what} chunk of {size} bytes that should hold {n}: {why}"))),
    }
}

/// Inflates the zlib stream `z` into exactly `out`.
pub(super) fn inflate(z: &[u8], out: &mut [u8]) -> Result<(), String> {
    let mut d = flate2::Decompress::new(true);
    match d.decompress(z, out, flate2::FlushDecompress::Finish) {
        Ok(flate2::Status::StreamEnd) if d.total_out() == out.len() as u64 => Ok(()),
        Ok(_) => Err(format!("the stream does not end after {} bytes", out.len())),
        Err(e) => Err(format!("not a zlib stream ({e})")),
    }
}

/// Decodes the Blosc chunk `b` (c-blosc 1's format, LZ4 codec) into exactly `out`.
pub(super) fn unblosc(b: &[u8], out: &mut [u8]) -> Result<(), String> {
    let Some(h) = b.get(..16) else {
        return Err(format!("{} bytes: shorter than Blosc's 16-byte header", b.len()));
    };
    let word = |at: usize| u32::from_le_bytes([h[at], h[at + 1], h[at + 2], h[at + 3]]) as usize;
    let (version, flags, typesize) = (h[0], h[2], h[3] as usize);
    let (nbytes, blocksize, cbytes) = (word(4), word(8), word(12));
    if !(1..=2).contains(&version) {
        return Err(format!("Blosc format version {version}: pathwave reads 1 and 2 (c-blosc 1)"));
    }
    if nbytes != out.len() || cbytes > b.len() || cbytes < 16 || typesize == 0 {
        return Err(format!(
            "its header says {nbytes} bytes, {cbytes} compressed, type size {typesize}: expected {} bytes in at most {} (type size > 0)",
            out.len(),
            b.len()
        ));
    }
    let b = &b[..cbytes];
    if flags & 0x2 != 0 {
        // Stored as they are.
        return match b.get(16..16 + nbytes) {
            Some(raw) => {
                out.copy_from_slice(raw);
                Ok(())
            }
            None => Err(format!("{nbytes} bytes stored in a chunk of {cbytes}")),
        };
    }
    if flags >> 5 != 1 || flags & 0x4 != 0 {
        return Err(format!(
            "flags {flags:#04x}: OpenVDB's chunks are LZ4 (codec 1) with byte shuffle, pathwave reads those (codec {}{})",
            flags >> 5,
            if flags & 0x4 != 0 { ", bit shuffle" } else { "" }
        ));
    }
    if blocksize == 0 {
        return Err("a block size of 0".into());
    }
    let blocks = nbytes.div_ceil(blocksize);
    if blocks > (cbytes - 16) / 4 {
        return Err(format!(
            "{blocks} blocks of {blocksize} bytes: their offsets do not fit in {cbytes} bytes"
        ));
    }
    let mut tmp = vec![0u8; blocksize.min(nbytes)];
    for (j, block) in out.chunks_mut(blocksize).enumerate() {
        let at = u32::from_le_bytes([b[16 + 4 * j], b[17 + 4 * j], b[18 + 4 * j], b[19 + 4 * j]]) as usize;
        let bsize = block.len();
        let leftover = bsize < blocksize;
        let split = flags & 0x10 == 0 && typesize <= 16 && bsize / typesize >= 128 && !leftover;
        let splits = if split { typesize } else { 1 };
        if bsize % splits != 0 {
            return Err(format!("block {j} of {bsize} bytes does not split into {splits} streams"));
        }
        let each = bsize / splits;
        let mut at = at;
        for s in 0..splits {
            let Some(size) = b.get(at..at + 4) else {
                return Err(format!(
                    "block {j}'s stream {s} starts at {at}, beyond the chunk's {cbytes} bytes"
                ));
            };
            let size = i32::from_le_bytes([size[0], size[1], size[2], size[3]]);
            at += 4;
            let src = usize::try_from(size).ok().and_then(|n| b.get(at..at.checked_add(n)?));
            let Some(src) = src else {
                return Err(format!("block {j}'s stream {s} of {size} bytes does not fit in the chunk"));
            };
            at += src.len();
            let dst = &mut tmp[s * each..(s + 1) * each];
            if src.len() == each {
                dst.copy_from_slice(src);
            } else {
                match lz4_flex::block::decompress_into(src, dst) {
                    Ok(k) if k == each => {}
                    Ok(k) => return Err(format!("block {j}'s stream {s} gives {k} bytes, not {each}")),
                    Err(e) => return Err(format!("block {j}'s stream {s}: {e}")),
                }
            }
        }
        match flags & 0x1 != 0 && typesize > 1 {
            true => unshuffle(typesize, &tmp[..bsize], block),
            false => block.copy_from_slice(&tmp[..bsize]),
        }
    }
    Ok(())
}

/// Undoes Blosc's byte shuffle of `src` (byte `j` of every element together, then the bytes
/// past the last whole element as they are) into `dst`.
fn unshuffle(typesize: usize, src: &[u8], dst: &mut [u8]) {
    let n = src.len() / typesize;
    for i in 0..n {
        for j in 0..typesize {
            dst[i * typesize + j] = src[j * n + i];
        }
    }
    dst[n * typesize..].copy_from_slice(&src[n * typesize..]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Blosc's byte shuffle, which [`unshuffle`] undoes.
    fn shuffle(typesize: usize, src: &[u8]) -> Vec<u8> {
        let n = src.len() / typesize;
        let mut dst = src.to_vec();
        for i in 0..n {
            for j in 0..typesize {
                dst[j * n + i] = src[i * typesize + j];
            }
        }
        dst
    }

    /// A Blosc chunk of `data` in blocks of `blocksize` as c-blosc 1 lays it out: whole blocks
    /// of 128 or more elements split into one LZ4 stream per byte of the type, the last block
    /// (shorter) in one stream, each block byte-shuffled.
    fn blosc(data: &[u8], typesize: usize, blocksize: usize) -> Vec<u8> {
        let blocks: Vec<&[u8]> = data.chunks(blocksize).collect();
        let mut body = Vec::new();
        let mut starts = Vec::new();
        let first = 16 + 4 * blocks.len();
        for b in &blocks {
            starts.push((first + body.len()) as u32);
            let shuffled = shuffle(typesize, b);
            let whole = b.len() == blocksize && b.len() / typesize >= 128;
            for stream in shuffled.chunks(if whole { b.len() / typesize } else { b.len() }) {
                let packed = lz4_flex::block::compress(stream);
                body.extend((packed.len() as i32).to_le_bytes());
                body.extend(packed);
            }
        }
        let mut chunk = vec![2, 1, 0x01 | 1 << 5, typesize as u8];
        for n in [data.len(), blocksize, first + body.len()] {
            chunk.extend((n as u32).to_le_bytes());
        }
        chunk.extend(starts.iter().flat_map(|s| s.to_le_bytes()));
        chunk.extend(body);
        chunk
    }

    #[test]
    fn blosc_chunks_of_several_blocks_split_and_not() {
        // Two blocks: 1024 bytes in four streams, then the last 601 in one (though long
        // enough to split), with a tail of one byte past the last whole element.
        let data: Vec<u8> = (0..1625u32).map(|i| (i * 7 % 251) as u8 ^ (i / 13) as u8).collect();
        let chunk = blosc(&data, 4, 1024);
        let mut out = vec![0; data.len()];
        unblosc(&chunk, &mut out).unwrap();
        assert!(out == data);
        // The same bytes stored as they are (the flag 0x2).
        let mut stored = vec![2, 1, 0x03 | 1 << 5, 4];
        for n in [data.len(), data.len(), 16 + data.len()] {
            stored.extend((n as u32).to_le_bytes());
        }
        stored.extend(&data);
        unblosc(&stored, &mut out).unwrap();
        assert!(out == data);
        // A chunk that is not what it should be.
        let e = |c: &[u8], n: usize| unblosc(c, &mut vec![0; n]).unwrap_err();
        assert!(e(&chunk, 1000).contains("says 1625 bytes"), "{}", e(&chunk, 1000));
        let mut zstd = chunk.clone();
        zstd[2] = 0x01 | 4 << 5;
        assert!(e(&zstd, 1625).contains("codec 4"), "{}", e(&zstd, 1625));
        assert!(
            e(&chunk[..chunk.len() - 1], 1625).contains("in at most"),
            "{}",
            e(&chunk[..chunk.len() - 1], 1625)
        );
        let mut lost = chunk.clone();
        lost[16] = 0xff;
        assert!(e(&lost, 1625).contains("block 0's stream 0"), "{}", e(&lost, 1625));
    }
}
