//! Arbitrary bytes, and mutations of small PNG, JPEG, HDR and EXR files (the seed corpus),
//! into the image decoder of textures and environment maps, with their limits (here at most
//! 64 texels a side, so that each run stays fast). Whatever decodes is looked up as a texture
//! (every wrap mode, at ordinary and extreme uvs) and built into an environment map that is
//! sampled: nothing may panic, and every value must be finite and not negative.
#![no_main]

use glam::{Vec2, Vec3A};
use libfuzzer_sys::fuzz_target;
use pathwave_engine::lighting::environment::{EnvPdf, EnvironmentMap};
use pathwave_engine::scene::files::decode_image_bytes;
use pathwave_engine::texture::{TextureImage, Wrap};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.img");
    let Ok(img) = decode_image_bytes(data.to_vec(), path, 64) else { return };
    let Ok(tex) = TextureImage::from_image(img, path) else { return };
    let ok = |v: glam::Vec3| v.is_finite() && v.min_element() >= 0.0;
    let uvs =
        [(0.0, 0.0), (0.3, 0.9), (1.0, 1.0), (-2.5, 7.25), (1e30, -1e30), (f32::INFINITY, f32::NEG_INFINITY)];
    for (u, v) in uvs {
        for wrap in [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror] {
            let c = tex.bilinear(Vec2::new(u, v), wrap);
            assert!(ok(c), "{c} at ({u}, {v}) {wrap:?}");
        }
    }
    let _ = tex.mean();
    let env = EnvironmentMap::new(tex.width, tex.height, tex.texels(), 1.0, 30.0);
    assert!(env.power_estimate().is_finite() && env.power_estimate() >= 0.0);
    let dirs = [Vec3A::X, Vec3A::NEG_Y, Vec3A::new(-0.48, 0.6, 0.64)];
    for (i, d) in dirs.into_iter().enumerate() {
        for kind in [EnvPdf::Complete, EnvPdf::Compensated] {
            let (c, pdf) = env.radiance_pdf(d, kind);
            assert!(ok(c) && pdf.is_finite() && pdf >= 0.0, "{c} pdf {pdf} towards {d} ({kind:?})");
            let u = Vec2::new(0.37 * i as f32, 0.91 - 0.4 * i as f32);
            if let Some(s) = env.sample(u, kind) {
                assert!(ok(s.radiance) && s.pdf.is_finite() && s.pdf > 0.0, "{s:?} for {u} ({kind:?})");
            }
        }
    }
});
