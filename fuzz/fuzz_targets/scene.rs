//! Arbitrary bytes, and mutations of the example scenes (the seed corpus), into the scene
//! loader. Whatever it accepts is spawned into the ECS world, the BVH is built and a 4x4
//! image is rendered at 2 spp: nothing may panic and no pixel may be NaN or infinite.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pathwave_engine::scene::parse;
use pathwave_engine::world::SceneWorld;
use pathwave_integrator::wavefront;
use std::num::NonZeroU32;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(mut desc) = parse(text, Path::new("fuzz.ron")) else { return };
    let r = &mut desc.render;
    (r.width, r.height, r.spp) = (NonZeroU32::new(4).unwrap(), NonZeroU32::new(4).unwrap(), NonZeroU32::new(2).unwrap());
    r.max_depth = r.max_depth.min(4);
    let scene = SceneWorld::render_scene(&desc);
    let (film, _) = wavefront::render(&scene, wavefront::Options::default(), &|_, _| {});
    for p in film.mean() {
        assert!(p.is_finite(), "pixel {p} in a film of {:?}", desc.objects);
    }
});
