//! Path guiding (`--guiding on`): the image is still a function of the scene, the settings and
//! the seed (whatever the threads, a crop is the window of the whole image, both integrators
//! agree), it converges to the unguided image, and where light arrives from one bright spot it
//! is less noisy than without.

mod common;

use common::root;
use pathwave::io::read_exr_channels;
use std::path::Path;
use std::process::Command;

/// `pathwave render SCENE` into `out` with `args`, which must succeed.
fn render(scene: &str, out: &Path, args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .args(["render", scene, "-q", "-o"])
        .arg(out)
        .args(args)
        .current_dir(root())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// The beauty channels of an EXR, and its width.
fn pixels(path: &Path) -> (Vec<[f32; 3]>, u32) {
    let img = read_exr_channels(path).unwrap();
    let ch = |n: &str| &img.channels.iter().find(|(name, _)| name == n).unwrap().1;
    let (r, g, b) = (ch("R"), ch("G"), ch("B"));
    ((0..r.len()).map(|i| [r[i], g[i], b[i]]).collect(), img.width)
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("pathwave-guiding-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn a_guided_image_is_one_render_whatever_renders_it() {
    let dir = temp_dir("bits");
    let base = ["--width", "48", "--height", "40", "--spp", "4", "--guiding", "on"];
    let run = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let args: Vec<&str> = base.iter().chain(extra).copied().collect();
        render("scenes/cornell.ron", &out, &args);
        pixels(&out)
    };
    let (one, w) = run("one.exr", &["-t", "1"]);
    let (two, _) = run("two.exr", &["-t", "2"]);
    assert_eq!(one, two, "one thread and two");
    // The guide learns from the whole image, so a crop keeps its pixels' bits.
    let (part, pw) = run("part.exr", &["-t", "2", "--crop", "0.25,0.75,0.1,0.6"]);
    for (k, p) in part.iter().enumerate() {
        let (x, y) = (k as u32 % pw + 12, k as u32 / pw + 4);
        assert_eq!(*p, one[(y * w + x) as usize], "crop pixel {x},{y}");
    }
    // A farm's shares (each training again over the whole image, and rendering its samples
    // with their stages' guides) merge into the render that kept its training's images.
    for (name, samples) in [("a.exr", "0..1"), ("b.exr", "1..3"), ("c.exr", "3..4")] {
        run(name, &["-t", "2", "--samples", samples]);
    }
    let merged = dir.join("merged.exr");
    let parts = ["a.exr.ckpt", "b.exr.ckpt", "c.exr.ckpt"].map(|p| dir.join(p));
    let m = Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .arg("merge")
        .args(&parts)
        .arg("-o")
        .arg(&merged)
        .output();
    assert!(m.unwrap().status.success());
    assert_eq!(pixels(&merged).0, one, "shares merged");
    // The reference path tracer draws the same guided directions (ties on shared edges
    // aside, as `tests/wavefront.rs` allows).
    let (oracle, _) = run("oracle.exr", &["-t", "2", "--integrator", "oracle"]);
    let differ = oracle.iter().zip(&one).filter(|(a, b)| a != b).count();
    assert!(differ <= 2, "{differ} pixels differ between the integrators");
    // Guiding changes the image (it is not ignored).
    let (off, _) = {
        let out = dir.join("off.exr");
        render("scenes/cornell.ron", &out, &["--width", "48", "--height", "40", "--spp", "4", "-t", "2"]);
        pixels(&out)
    };
    assert_ne!(off, one);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `pathwave render SCENE` into `out` with `args` (not quiet), which must succeed: what it said.
fn render_said(scene: &str, out: &Path, args: &[&str]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .args(["render", scene, "-o"])
        .arg(out)
        .args(args)
        .current_dir(root())
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{said}");
    said
}

#[test]
fn a_guide_file_trains_once_for_every_run_of_the_image() {
    let dir = temp_dir("file");
    let file = dir.join("scene.guides");
    let f = file.to_str().unwrap();
    let base = ["--width", "48", "--height", "40", "--spp", "4", "--guiding", "on", "-t", "2"];
    let run = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let args: Vec<&str> = base.iter().chain(extra).copied().collect();
        let said = render_said("scenes/cornell.ron", &out, &args);
        (pixels(&out).0, said)
    };
    let (plain, _) = run("plain.exr", &[]);
    let (first, said) = run("first.exr", &["--guide-file", f]);
    assert!(file.exists() && !said.contains("guides read"), "{said}");
    assert_eq!(first, plain, "training that writes its guides");
    let (second, said) = run("second.exr", &["--guide-file", f]);
    assert!(said.contains("the guides read (no training)"), "{said}");
    assert_eq!(second, plain, "the guides read");
    // Shares of a farm read them too, and merge into the image.
    for (name, samples) in [("a.exr", "0..1"), ("b.exr", "1..3"), ("c.exr", "3..4")] {
        let (_, said) = run(name, &["--samples", samples, "--guide-file", f]);
        assert!(said.contains("guides read"), "{said}");
    }
    let merged = dir.join("merged.exr");
    let m = Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .arg("merge")
        .args(["a.exr.ckpt", "b.exr.ckpt", "c.exr.ckpt"].map(|p| dir.join(p)))
        .arg("-o")
        .arg(&merged)
        .output();
    assert!(m.unwrap().status.success());
    assert_eq!(pixels(&merged).0, plain, "shares merged");
    // Another seed's render does not take them: it learns its own (and writes them).
    let (seeded, _) = run("seeded.exr", &["--seed", "9"]);
    let (other, said) = run("other.exr", &["--seed", "9", "--guide-file", f]);
    assert!(said.contains("another scene or other settings"), "{said}");
    assert_eq!(other, seeded, "another seed's guides");
    // A damaged file is refused, saying so.
    let mut bytes = std::fs::read(&file).unwrap();
    let at = bytes.len() / 2;
    bytes[at] ^= 0x10;
    std::fs::write(&file, bytes).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .args(["render", "scenes/cornell.ron", "-o"])
        .arg(dir.join("damaged.exr"))
        .args(base)
        .args(["--seed", "9", "--guide-file", f])
        .current_dir(root())
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && said.contains("checksum"), "{said}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Relative variance of a pixel over `renders` (the variance of their values, weighted by
/// `1 / (r^2 + 0.01)` with `r` the reference), averaged over pixels and channels.
fn rel_variance(renders: &[Vec<[f32; 3]>], reference: &[[f32; 3]]) -> f64 {
    let k = renders.len() as f64;
    let mut sum = 0.0;
    for (i, r) in reference.iter().enumerate() {
        for c in 0..3 {
            let m = renders.iter().map(|x| x[i][c] as f64).sum::<f64>() / k;
            let v = renders.iter().map(|x| (x[i][c] as f64 - m).powi(2)).sum::<f64>() / (k - 1.0);
            sum += v / ((r[c] as f64).powi(2) + 0.01);
        }
    }
    sum / (3 * reference.len()) as f64
}

fn mean(img: &[[f32; 3]]) -> f64 {
    img.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / (3 * img.len()) as f64
}

#[test]
fn guiding_converges_to_the_image_and_lowers_the_noise_of_indirect_light() {
    let dir = temp_dir("noise");
    let size = ["--width", "160", "--height", "120", "-t", "2"];
    let run = |name: &str, spp: u32, seed: u32, guiding: &str| {
        let out = dir.join(name);
        let (spp, seed) = (spp.to_string(), seed.to_string());
        let args: Vec<&str> =
            size.iter().copied().chain(["--spp", &spp, "--seed", &seed, "--guiding", guiding]).collect();
        render("scenes/lit-ceiling.ron", &out, &args);
        pixels(&out).0
    };
    let reference = run("ref.exr", 512, 99, "off");
    let off: Vec<_> = (1..=4).map(|k| run(&format!("off{k}.exr"), 32, k, "off")).collect();
    let on: Vec<_> = (1..=4).map(|k| run(&format!("on{k}.exr"), 32, k, "on")).collect();
    // Unbiased: the guided images' mean is the reference's (to within their noise: the
    // unguided ones' means spread by less than 1%).
    let (m_ref, m_on) = (mean(&reference), on.iter().map(|x| mean(x)).sum::<f64>() / 4.0);
    assert!((m_on / m_ref - 1.0).abs() < 0.01, "guided mean {m_on}, reference {m_ref}");
    // Less noise at the same samples (the first seven, training, among them): 0.73x with the
    // guide learning the radiance times the cosine (0.87x learning the radiance alone), so a
    // guide that loses that lowers it past the bound.
    let (v_off, v_on) = (rel_variance(&off, &reference), rel_variance(&on, &reference));
    eprintln!("means: reference {m_ref}, guided {m_on}; relative variance: guided {v_on}, unguided {v_off}");
    assert!(v_on < 0.82 * v_off, "relative variance guided {v_on}, unguided {v_off}");
    std::fs::remove_dir_all(&dir).unwrap();
}
