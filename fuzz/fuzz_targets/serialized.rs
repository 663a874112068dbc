//! Arbitrary bytes, and mutations of small Mitsuba `.serialized` meshes (the seed corpus), into
//! the `.serialized` reader. The first byte says what the rest is: even, a whole file, read as
//! is; odd, the inflated data of one mesh, which the target wraps in a zlib stream and frames (header of
//! version 4 when bit 1 is set, else 3, and the table of meshes at the end), so that mutations
//! reach the reader behind the zlib stream. Every mesh of the file is read; one it accepts is
//! checked as the `obj` target checks one (`pathwave_fuzz::check_mesh`). Nothing may panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pathwave_engine::scene::SerializedFile;
use std::path::Path;

/// A file of one mesh whose inflated data is `data`, as a zlib stream of stored (uncompressed)
/// deflate blocks (RFC 1950 and 1951): a compressor's state costs more than the rest of an
/// execution.
fn framed(data: &[u8], version: u16) -> Vec<u8> {
    let mut file = [0x041Cu16.to_le_bytes(), version.to_le_bytes()].concat();
    file.extend_from_slice(&[0x78, 0x01]);
    let mut blocks = data.chunks(0xFFFF).peekable();
    if blocks.peek().is_none() {
        file.extend_from_slice(&[1, 0, 0, 0xFF, 0xFF]);
    }
    while let Some(block) = blocks.next() {
        let len = block.len() as u16;
        file.push(blocks.peek().is_none() as u8);
        file.extend_from_slice(&len.to_le_bytes());
        file.extend_from_slice(&(!len).to_le_bytes());
        file.extend_from_slice(block);
    }
    let (a, b) = data.iter().fold((1u32, 0u32), |(a, b), &x| {
        let a = (a + x as u32) % 65521;
        (a, (b + a) % 65521)
    });
    file.extend_from_slice(&(b << 16 | a).to_be_bytes());
    file.extend_from_slice(if version == 4 { &[0u8; 8] } else { &[0u8; 4] });
    file.extend_from_slice(&1u32.to_le_bytes());
    file
}

fuzz_target!(|data: &[u8]| {
    let Some((&first, rest)) = data.split_first() else { return };
    let bytes = match first & 1 {
        0 => rest.to_vec(),
        _ => framed(rest, if first & 2 != 0 { 4 } else { 3 }),
    };
    let path = Path::new("fuzz.serialized");
    let Ok(file) = SerializedFile::new(bytes, path) else { return };
    // Beyond the table too: an index past the last is refused.
    for index in 0..=file.count().min(8) {
        if let Ok(mesh) = file.mesh(index, path) {
            pathwave_fuzz::check_mesh(mesh);
        }
    }
});
