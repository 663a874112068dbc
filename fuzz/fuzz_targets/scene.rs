//! Arbitrary bytes, and mutations of the example scenes (the seed corpus), into the scene
//! loader. Whatever it accepts is spawned into the ECS world, the BVH is built and a 4x4
//! image is rendered at 2 spp: nothing may panic and no pixel may be NaN or infinite.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pathwave_engine::scene::parse;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(desc) = parse(text, Path::new("fuzz.ron")) else { return };
    pathwave_fuzz::render_and_check(desc);
});
