//! Intel Open Image Denoise (`--features oidn`) against the independent references: at 16 spp
//! its output must be at least as close to each reference as OIDN 2.5.1's own command-line tool
//! got from pathwave's noisy image and guides (issue 17), keep each image's mean within 1%, and
//! depend on the albedo guide; the command line keeps the render beside the denoised image, in
//! `render`, `animate` and `bench`.
#![cfg(feature = "oidn")]

mod common;
use common::*;
use glam::Vec3;
use pathwave::denoiser::{self, Denoiser, oidn};
use pathwave::engine::world::SceneWorld;
use pathwave::integrator::{aov::Aovs, wavefront};
use pathwave::io::read_linear;
use pathwave::metrics::{mean, rel_mse};
use std::process::Command;

/// The wavefront's render of `scenes/NAME.ron` at 16 spp: per-pixel means, their variance and
/// the guides it recorded.
fn render16(name: &str) -> (Vec<Vec3>, Vec<Vec3>, Aovs) {
    let mut desc = scene(&format!("{name}.ron"));
    desc.render.spp = 16.try_into().unwrap();
    let scene = SceneWorld::render_scene(&desc);
    let opts = wavefront::Options { guides: true, ..Default::default() };
    let (film, _) = wavefront::render(&scene, opts, &|_, _| {});
    (film.mean(), film.variance_of_mean(), film.guides.expect("recorded"))
}

/// relMSE at 16 spp of `oidnDenoise --hdr --alb --nrm` on pathwave's noisy image and guides
/// (issue 17; pathwave's à-trous filter: 0.0011, 0.0133, 0.0063, 0.0013), and how far the
/// denoised mean may be from the reference's: 1%, but 1.5% on cornell, whose caustics through
/// the glass OIDN partly takes for noise (its mean -0.77% with the directions from the Sobol
/// net, -1.02% from the lattice, at seed 0, where the noisy image is -0.12% off). A wrong
/// scale or guide moves a mean by several percent.
const OIDN_TOOL: [(&str, f64, f64); 4] = [
    ("cornell-diffuse", 0.00054, 0.01),
    ("cornell", 0.0044, 0.015),
    ("spheres-sky", 0.0027, 0.01),
    ("mesh", 0.00055, 0.01),
];

#[test]
fn oidn_reaches_the_figures_of_its_own_tool_and_keeps_the_means() {
    let mut failures = Vec::new();
    for (name, bound, mean_bound) in OIDN_TOOL {
        let r = reference(&format!("{name}.exr"));
        let (noisy, variance, aovs) = render16(name);
        let out = denoiser::denoise(Denoiser::Oidn, &noisy, &variance, &aovs, 0).unwrap();
        let atrous = denoiser::denoise(Denoiser::Atrous, &noisy, &variance, &aovs, 0).unwrap();
        let e = |x: &[Vec3]| rel_mse(x, &r.pixels);
        let drift = mean(&out) / mean(&r.pixels) - 1.0;
        eprintln!(
            "{name}: relMSE noisy {:.6}, à-trous {:.6}, OIDN {:.6} (bound {bound}); OIDN mean {:+.3}% (noisy {:+.3}%)",
            e(&noisy),
            e(&atrous),
            e(&out),
            100.0 * drift,
            100.0 * (mean(&noisy) / mean(&r.pixels) - 1.0)
        );
        if e(&out) > bound {
            failures.push(format!("{name}: relMSE {:.6} > {bound}", e(&out)));
        }
        if drift.abs() > mean_bound {
            failures.push(format!("{name}: the mean is {:+.2}% off", 100.0 * drift));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

#[test]
fn the_albedo_guide_matters() {
    // OIDN takes a normal only beside an albedo: without the albedo it has the colour alone.
    // On cornell-diffuse the guides measured relMSE 0.00025 against 0.00035 without.
    let r = reference("cornell-diffuse.exr");
    let (noisy, _, aovs) = render16("cornell-diffuse");
    let guided = oidn::denoise(&noisy, &aovs, &oidn::Options::default()).unwrap();
    let opts = oidn::Options { albedo: false, ..Default::default() };
    let blind = oidn::denoise(&noisy, &aovs, &opts).unwrap();
    let (e_guided, e_blind) = (rel_mse(&guided, &r.pixels), rel_mse(&blind, &r.pixels));
    let apart = rel_mse(&blind, &guided);
    eprintln!("relMSE with the guides {e_guided:.6}, without {e_blind:.6}; between the two {apart:.6}");
    assert!(e_blind > 1.2 * e_guided, "the guides gain too little: {e_guided} against {e_blind}");
    assert!(apart > 0.1 * e_guided, "the albedo changes too little: {apart}");
}

fn pathwave() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pathwave"));
    c.current_dir(root());
    c
}

fn temp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("pathwave-oidn-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{err}");
    String::from_utf8_lossy(&out.stdout).into_owned() + &err
}

#[test]
fn the_command_line_denoises_with_oidn_by_default() {
    let dir = temp("render");
    let render = |out: &str, extra: &[&str]| {
        run(pathwave()
            .args(["render", "scenes/cornell-diffuse.ron", "--spp", "4", "--width", "64", "--height", "64"])
            .arg("-o")
            .arg(dir.join(out))
            .args(extra));
    };
    render("plain.exr", &["-q"]);
    render("bare.exr", &["--denoise", "-q"]);
    render("oidn.exr", &["--denoise", "oidn", "-q"]);
    render("atrous.exr", &["--denoise=atrous", "-q"]);
    let read = |name: &str| read_linear(&dir.join(name)).unwrap();
    for d in ["bare", "oidn", "atrous"] {
        assert_eq!(read(&format!("{d}.noisy.exr")), read("plain.exr"), "{d}: the render as it came");
    }
    assert_eq!(read("bare.exr"), read("oidn.exr"), "a bare --denoise is OIDN");
    assert_ne!(read("oidn.exr"), read("plain.exr"));
    assert_ne!(read("oidn.exr"), read("atrous.exr"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn animate_denoises_each_frame_with_its_own_guides() {
    let dir = temp("animate");
    let pattern = dir.join("f_{frame:02}.exr");
    run(pathwave()
        .args(["animate", "scenes/animation-bounce.ron", "-o", pattern.to_str().unwrap()])
        .args(["--frames", "10..12", "--spp", "4", "--width", "64", "--height", "48", "-q"])
        .args(["--denoise", "oidn", "--aov"]));
    let read = |name: &str| read_linear(&dir.join(name)).unwrap();
    for f in ["f_10", "f_11"] {
        let (out, noisy) = (read(&format!("{f}.exr")), read(&format!("{f}.noisy.exr")));
        assert_ne!(out, noisy, "{f} is denoised");
        assert!(rel_mse(&out.pixels, &noisy.pixels) < 0.5, "{f}: the denoised frame is another picture");
    }
    // The ball moved: each frame has its own guides (layers of the frame's EXR).
    let albedo = |f: &str| {
        let l = pathwave::io::read_exr_channels(&dir.join(format!("{f}.exr"))).unwrap();
        l.channels.into_iter().find(|(n, _)| n == "albedo.R").expect("an albedo layer").1
    };
    assert_ne!(albedo("f_10"), albedo("f_11"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bench_compares_both_denoisers() {
    let out = run(pathwave().args(["bench", "--only", "cornell-diffuse", "--spp", "1", "--denoise"]));
    for row in ["| cornell-diffuse | wavefront | 1 |", "| wavefront + OIDN |", "| wavefront + à-trous |"] {
        assert!(out.contains(row), "no {row} in\n{out}");
    }
}

/// Mean absolute difference over pixels and channels.
fn mad(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(a, b)| (*a - *b).abs().element_sum() as f64).sum::<f64>() / (3 * a.len()) as f64
}

/// Frame-to-frame flicker of a static camera (benches/results/denoiser.md): `animate` gives every frame
/// the same seed, so a still shot renders the same noise, and the same denoised image, in every
/// frame (checked here: OIDN's output is a function of its input). With a seed per frame
/// (`render --seed K`, the frames of a still shot differing only in their noise), the mean
/// absolute difference of consecutive frames, noisy and denoised. Run with `--ignored`.
#[test]
#[ignore = "a measurement (about a minute); prints its figures"]
fn flicker_of_a_static_camera() {
    const FRAMES: u64 = 8;
    for name in ["cornell-diffuse", "cornell", "spheres-sky", "mesh"] {
        let mut frames: [Vec<Vec<Vec3>>; 3] = Default::default();
        for seed in 0..FRAMES {
            let mut desc = scene(&format!("{name}.ron"));
            desc.render.spp = 16.try_into().unwrap();
            desc.render.seed = seed;
            let scene = SceneWorld::render_scene(&desc);
            let opts = wavefront::Options { guides: true, ..Default::default() };
            let (film, _) = wavefront::render(&scene, opts, &|_, _| {});
            let (noisy, variance, aovs) = (film.mean(), film.variance_of_mean(), film.guides.unwrap());
            let oidn = denoiser::denoise(Denoiser::Oidn, &noisy, &variance, &aovs, 0).unwrap();
            if seed == 0 {
                let again = denoiser::denoise(Denoiser::Oidn, &noisy, &variance, &aovs, 0).unwrap();
                assert_eq!(oidn, again, "OIDN is deterministic");
            }
            frames[1].push(denoiser::denoise(Denoiser::Atrous, &noisy, &variance, &aovs, 0).unwrap());
            frames[2].push(oidn);
            frames[0].push(noisy);
        }
        let m = mean(&reference(&format!("{name}.exr")).pixels);
        let flicker: Vec<f64> = frames
            .iter()
            .map(|f| f.windows(2).map(|w| mad(&w[0], &w[1])).sum::<f64>() / (FRAMES - 1) as f64)
            .collect();
        eprintln!(
            "| {name} | {:.5} ({:.2}%) | {:.5} ({:.2}%, {:.2}x) | {:.5} ({:.2}%, {:.2}x) |",
            flicker[0],
            100.0 * flicker[0] / m,
            flicker[1],
            100.0 * flicker[1] / m,
            flicker[1] / flicker[0],
            flicker[2],
            100.0 * flicker[2] / m,
            flicker[2] / flicker[0],
        );
    }
}
