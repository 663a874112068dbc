//! Arbitrary bytes, and mutations of small glTF files (the seed corpus), into the glTF reader.
//! The first byte says what the rest is: even, a whole file (`.gltf` JSON or `.glb`); odd, a
//! JSON document and, after its first NUL byte, a binary chunk, which the target frames as a
//! `.glb` so that mutations of the JSON reach the accessors behind it. The file is read
//! (`GltfFile::new`), every mesh (at most 8, and one past the last) read whole and by primitive
//! and checked as the `obj` target checks a mesh (`pathwave_fuzz::check_mesh`), every image's
//! bytes fetched (not decoded: the `image` target fuzzes the decoders); then the file, written
//! into a folder of this process, is loaded as a whole scene (`scene::gltf::load`: converted
//! to RON and read by the RON loader). Every file read is confined to that folder. Nothing may
//! panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pathwave_engine::format::files::confined;
use pathwave_engine::format::gltf::GltfFile;
use pathwave_engine::scene::gltf::{self, MeshRef};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The folder of this process's glTF file (in `/dev/shm` where there is one, as the `xml`
/// target's), with a `.bin` a file may name.
fn folder() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let shm = Path::new("/dev/shm");
        let base = if shm.is_dir() { shm.to_path_buf() } else { std::env::temp_dir() };
        let dir = base.join(format!("pathwave-fuzz-gltf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let quad: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .chain([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()))
            .collect();
        std::fs::write(dir.join("b.bin"), quad).unwrap();
        dir
    })
}

/// A `.glb` of the JSON chunk `json` and the binary chunk `bin` (each padded to 4 bytes).
fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |b: &[u8], with: u8| {
        let mut v = b.to_vec();
        v.resize(b.len().div_ceil(4) * 4, with);
        v
    };
    let (json, bin) = (pad(json, b' '), pad(bin, 0));
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((28 + json.len() + bin.len()) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

fuzz_target!(|data: &[u8]| {
    let Some((&first, rest)) = data.split_first() else { return };
    let bytes = match first & 1 {
        0 => rest.to_vec(),
        _ => match rest.iter().position(|&b| b == 0) {
            Some(i) => glb(&rest[..i], &rest[i + 1..]),
            None => glb(rest, &[]),
        },
    };
    let dir = folder();
    let path = dir.join(if bytes.starts_with(b"glTF") { "f.glb" } else { "f.gltf" });
    let _ = confined(dir, &path, || {
        let Ok(file) = GltfFile::new(&bytes, &path) else { return };
        for m in 0..=file.doc.meshes().len().min(8) {
            let which = Some(MeshRef::Index(m as u32));
            if let Ok(mesh) = file.mesh_data(which.as_ref(), None, &path) {
                pathwave_fuzz::check_mesh(mesh);
            }
            for p in 0..2 {
                if let Ok(mesh) = file.mesh_data(which.as_ref(), Some(p), &path) {
                    pathwave_fuzz::check_mesh(mesh);
                }
            }
        }
        for i in 0..=file.doc.images().len().min(8) {
            let _ = file.image_bytes(i, &path);
        }
        std::fs::write(&path, &bytes).unwrap();
        let _ = gltf::load(&path);
    });
});
