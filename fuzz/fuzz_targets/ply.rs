//! Arbitrary bytes, and mutations of small PLY files (ASCII and binary, with normals, uv,
//! polygons and face colours: the seed corpus), into the PLY reader. A mesh it accepts is
//! checked as the `obj` target checks one (`pathwave_fuzz::check_mesh`): nothing may panic,
//! its arrays agree in length, and surface points met by rays are finite with unit normals.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pathwave_engine::scene::parse_ply;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(mesh) = parse_ply(data, Path::new("fuzz.ply")) else { return };
    pathwave_fuzz::check_mesh(mesh);
});
