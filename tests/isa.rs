//! The lane loops give the same bits with AVX-512 as with the AVX2 baseline: whole renders
//! through the binary, once held to AVX2 by `PATHWAVE_ISA`, once free to use AVX-512. That test
//! needs a CPU with AVX-512, so it is ignored (listed as such, not passed, where `cargo test`
//! runs); `.ci/run` runs it where the CPU has AVX-512 and says it skipped it where not.

mod common;
use common::*;

fn render(scene: &str, isa: &str, out: &std::path::Path) -> Vec<u8> {
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .args(["render", scene, "--spp", "6", "--width", "64", "--height", "48", "-q", "-o"])
        .arg(out)
        .env(pathwave::engine::simd::ISA_VAR, isa)
        .current_dir(root())
        .status()
        .unwrap();
    assert!(status.success(), "{scene} with {isa}");
    std::fs::read(out).unwrap()
}

#[test]
#[ignore = "needs a CPU with AVX-512 (.ci/run runs it where there is one)"]
fn avx512_and_avx2_render_the_same_bits() {
    assert!(
        pathwave::engine::simd::cpu_has_avx512(),
        "this CPU has no AVX-512: both runs would take the AVX2 baseline, nothing to compare"
    );
    let dir = std::env::temp_dir().join(format!("pathwave-isa-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Quads (closest hits and shadow rays), a glass sphere, media, the lens with spheres, and
    // the kinds shaded across lanes (GGX and Beckmann conductors, plastics smooth and rough,
    // principled, a fuzzy metal, among others).
    for scene in [
        "scenes/cornell-diffuse.ron",
        "scenes/cornell.ron",
        "scenes/cornell-smoke.ron",
        "scenes/spheres-sky.ron",
        "scenes/materials-env.ron",
        "scenes/rough-spheres.ron",
        "scenes/plastics.ron",
        "scenes/textures.ron",
        "tests/mitsuba-data/tests/scenes/bsdf_spheres/test_arealight_path.xml",
    ] {
        let a = render(scene, "avx2", &dir.join("a.exr"));
        let b = render(scene, "avx512", &dir.join("b.exr"));
        assert!(a == b, "{scene}: the AVX-512 image differs from the AVX2 one");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_unknown_instruction_set_is_reported_and_the_render_goes_on() {
    let dir = std::env::temp_dir().join(format!("pathwave-isa-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .args(["render", "scenes/cornell.ron", "--spp", "1", "--width", "16", "--height", "16", "-q", "-o"])
        .arg(dir.join("c.png"))
        .env(pathwave::engine::simd::ISA_VAR, "sse9")
        .env_remove("RUST_LOG")
        .current_dir(root())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("PATHWAVE_ISA=\"sse9\" names no instruction set"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}
