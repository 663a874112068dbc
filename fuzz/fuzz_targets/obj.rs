//! Arbitrary bytes, and mutations of the example meshes (the seed corpus), into the OBJ loader.
//! Whatever it accepts is placed as a scene object would be (refused beyond the scene's
//! coordinate bound), its BVH is built and rays from around it meet its surface: nothing may
//! panic, and every surface point met must be finite with unit normals.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pathwave_engine::scene::parse_obj;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(mesh) = parse_obj(data, Path::new("fuzz.obj")) else { return };
    pathwave_fuzz::check_mesh(mesh);
});
