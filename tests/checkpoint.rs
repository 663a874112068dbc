//! Checkpoints: a render killed mid-way and resumed ends with the bits of an uninterrupted
//! render; a checkpoint of other settings is refused.

mod common;
use pathwave::checkpoint::Checkpoint;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pathwave-ckpt-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn pathwave(out: &Path, spp: u32, extra: &[&str]) -> Command {
    let mut c = common::render_cornell(out, (96, 96), spp, extra);
    c.arg("-q");
    c
}

#[test]
fn a_killed_render_resumes_to_the_same_bits() {
    let dir = temp("resume");
    let (plain, out) = (dir.join("plain.exr"), dir.join("out.exr"));
    assert!(pathwave(&plain, 384, &[]).status().unwrap().success());
    let ckpt = dir.join("out.exr.ckpt");
    // Checkpoints after every pass; killed as soon as the first one is on disk.
    let mut child = pathwave(&out, 384, &["--checkpoint-every", "0"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !ckpt.exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no checkpoint appeared");
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let partial = Checkpoint::load(&ckpt).unwrap();
    assert!(partial.film.spp < 384, "the render finished before it could be killed: {}", partial.film.spp);
    // The image so far is there to look at.
    assert!(out.exists());

    let resumed = pathwave(&out, 384, &["--resume"]).output().unwrap();
    let log = String::from_utf8_lossy(&resumed.stderr);
    assert!(resumed.status.success(), "{log}");
    assert!(log.contains(&format!("resuming at {} of 384 spp", partial.film.spp)), "{log}");
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&plain).unwrap(), "the resumed image differs");
    // The finished checkpoint is kept, complete.
    assert_eq!(Checkpoint::load(&ckpt).unwrap().film.spp, 384);

    // Another seed: refused, and nothing is overwritten.
    let before = std::fs::read(&out).unwrap();
    let other = pathwave(&out, 384, &["--resume", "--seed", "7"]).output().unwrap();
    assert!(!other.status.success());
    let log = String::from_utf8_lossy(&other.stderr);
    assert!(log.contains("the checkpoint is of another scene or other settings"), "{log}");
    // It names the setting that differs, and only that one.
    assert!(log.contains("(seed 0 in the checkpoint, 7 in this render)"), "{log}");
    assert_eq!(std::fs::read(&out).unwrap(), before);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn resume_without_a_checkpoint_starts_from_the_first_sample() {
    let dir = temp("fresh");
    let (plain, out) = (dir.join("plain.exr"), dir.join("out.exr"));
    assert!(pathwave(&plain, 4, &[]).status().unwrap().success());
    let run = pathwave(&out, 4, &["--resume"]).output().unwrap();
    assert!(run.status.success());
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&plain).unwrap());
    assert_eq!(Checkpoint::load(&dir.join("out.exr.ckpt")).unwrap().film.spp, 4);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn more_samples_on_a_finished_render_give_the_bits_of_a_fresh_one() {
    // Sobol samples do not depend on the sample count: 4 spp resumed to 16 is the 16-spp render.
    // Stratified patterns do, and the run says so.
    let dir = temp("extend");
    for (sampler, same) in [("sobol", true), ("stratified", false)] {
        let (plain, out) = (dir.join(format!("plain-{sampler}.exr")), dir.join(format!("out-{sampler}.exr")));
        assert!(pathwave(&plain, 16, &["--sampler", sampler]).status().unwrap().success());
        assert!(pathwave(&out, 4, &["--resume", "--sampler", sampler]).status().unwrap().success());
        let more = pathwave(&out, 16, &["--resume", "--sampler", sampler]).output().unwrap();
        let log = String::from_utf8_lossy(&more.stderr);
        assert!(more.status.success(), "{log}");
        assert_eq!(log.contains("not the bits of a fresh 16-spp render"), !same, "{sampler}: {log}");
        let equal = std::fs::read(&out).unwrap() == std::fs::read(&plain).unwrap();
        assert_eq!(equal, same, "{sampler}: extended render equal to a fresh one: {equal}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn parts_rendered_apart_merge_into_the_whole_render() {
    let dir = temp("merge");
    let out = |name: &str| dir.join(name);
    let render = |name: &str, extra: &[&str]| {
        let r = pathwave(&out(name), 7, extra).output().unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    };
    let merge = |parts: &[&str], to: &str| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_pathwave"));
        c.arg("merge").args(parts.iter().map(|p| out(p))).arg("-o").arg(out(to));
        c.output().unwrap()
    };
    // With samples in their own pixels, and splatted over their neighbours' (the Gaussian).
    for filter in ["box", "gaussian"] {
        let render = |name: &str, extra: &[&str]| render(name, &[extra, &["--filter", filter]].concat());
        render("plain.exr", &[]);
        // Three machines' shares, merged in any order.
        render("a.exr", &["--samples", "0..2"]);
        render("b.exr", &["--samples", "2..3"]);
        render("c.exr", &["--samples", "3..7"]);
        assert!(merge(&["c.exr.ckpt", "a.exr.ckpt", "b.exr.ckpt"], "all.exr").status.success());
        let plain = std::fs::read(out("plain.exr")).unwrap();
        assert_eq!(std::fs::read(out("all.exr")).unwrap(), plain, "{filter}");
        // Two of three: an image of their samples and a checkpoint that --resume completes.
        std::fs::remove_file(out("ab.exr.ckpt")).ok();
        assert!(merge(&["a.exr.ckpt", "b.exr.ckpt"], "ab.exr").status.success());
        assert_eq!(Checkpoint::load(&out("ab.exr.ckpt")).unwrap().film.spp, 3);
        render("ab.exr", &["--resume"]);
        assert_eq!(std::fs::read(out("ab.exr")).unwrap(), plain, "{filter}");
    }
    // A sample twice, or parts of other settings, are refused.
    let twice = merge(&["a.exr.ckpt", "a.exr.ckpt"], "x.exr");
    assert!(!twice.status.success() && String::from_utf8_lossy(&twice.stderr).contains("overlap"));
    render("s.exr", &["--samples", "3..7", "--seed", "9"]);
    let other = merge(&["a.exr.ckpt", "b.exr.ckpt", "s.exr.ckpt"], "x.exr");
    let log = String::from_utf8_lossy(&other.stderr);
    assert!(!other.status.success(), "{log}");
    assert!(
        log.contains(
            "samples 3..7 are of another render than samples 0..2: seed 9 in samples 3..7, 0 in samples 0..2"
        ),
        "{log}"
    );
    assert!(!out("x.exr").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A damaged checkpoint is refused, never resumed into a wrong image: every one of 3000
/// random single-bit flips (and a truncation) fails to load, and `--resume` on a flipped file
/// exits non-zero leaving the image as it was.
#[test]
fn damaged_checkpoints_are_refused() {
    let dir = temp("damaged");
    let out = dir.join("c.exr");
    assert!(pathwave(&out, 2, &["--checkpoint-every", "0"]).status().unwrap().success());
    let ckpt = dir.join("c.exr.ckpt");
    let good = std::fs::read(&ckpt).unwrap();
    assert!(Checkpoint::load(&ckpt).is_ok());
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    for _ in 0..3000 {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        let bit = (s % (good.len() as u64 * 8)) as usize;
        let mut bad = good.clone();
        bad[bit / 8] ^= 1 << (bit % 8);
        assert!(Checkpoint::from_bytes(&bad, &ckpt).is_err(), "a flip of bit {bit} went unnoticed");
    }
    assert!(Checkpoint::from_bytes(&good[..good.len() - 1], &ckpt).is_err());
    // Through the command line: the spp field (bytes 32..36) flipped.
    let image = std::fs::read(&out).unwrap();
    let mut bad = good.clone();
    bad[32] ^= 0x80;
    std::fs::write(&ckpt, &bad).unwrap();
    let o = pathwave(&out, 8, &["--resume"]).output().unwrap();
    assert!(!o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("checksum"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(std::fs::read(&out).unwrap(), image);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A checkpoint whose checksum holds but whose image has the render's key and pixel count in
/// another shape (96 x 96 resealed as 48 x 192) is refused with what is wrong; it made the
/// film merge panic.
#[test]
fn a_resealed_checkpoint_of_another_size_is_refused() {
    let dir = temp("reshaped");
    let out = dir.join("c.exr");
    assert!(pathwave(&out, 2, &["--checkpoint-every", "0"]).status().unwrap().success());
    let ckpt = dir.join("c.exr.ckpt");
    let mut c = Checkpoint::load(&ckpt).unwrap();
    (c.film.width, c.film.height) = (48, 192);
    c.save(&ckpt).unwrap();
    let image = std::fs::read(&out).unwrap();
    let o = pathwave(&out, 4, &["--resume"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("holds a 48x192 image, this render makes 96x96"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(std::fs::read(&out).unwrap(), image);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A checkpoint is keyed by every file the scene read, as the load read it: a changed texture
/// refuses the resume (it would mix two images), and a scene saved after the load does not
/// change the key of the render that loaded it.
#[test]
fn a_checkpoint_is_keyed_by_every_file_the_scene_read_as_loaded() {
    let dir = temp("inputs");
    let texture = dir.join("t.png");
    image::RgbImage::from_pixel(2, 2, image::Rgb([200, 100, 50])).save(&texture).unwrap();
    let scene = dir.join("s.ron");
    let text = r#"Scene(
        camera: (look_from: (0, 0, 5), look_at: (0, 0, 0), vfov: 40),
        render: (width: 8, height: 8),
        background: Constant((1, 1, 1)),
        textures: { "t": Image(file: "t.png") },
        materials: { "m": Lambertian(albedo: "t") },
        objects: [(shape: Sphere(center: (0, 0, 0), radius: 1), material: "m")],
    )"#;
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("o.exr");
    let render = |spp: &str| {
        Command::new(env!("CARGO_BIN_EXE_pathwave"))
            .arg("render")
            .arg(&scene)
            .args(["-q", "--resume", "--spp", spp, "-o"])
            .arg(&out)
            .output()
            .unwrap()
    };
    assert!(render("2").status.success());
    image::RgbImage::from_pixel(2, 2, image::Rgb([10, 100, 50])).save(&texture).unwrap();
    let o = render("4");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("the scene file or a file it reads has changed"), "{err}");

    // What identifies a load is what it read, whatever the file holds afterwards.
    let desc = pathwave::engine::scene::load(&scene).unwrap();
    std::fs::write(&scene, text.replace("(1, 1, 1)", "(0.5, 0.5, 0.5)")).unwrap();
    let again = pathwave::engine::scene::load(&scene).unwrap();
    let hash = |d: &pathwave::engine::scene::SceneDesc| {
        d.inputs.iter().find(|f| f.path.ends_with("s.ron")).expect("the scene is an input").hash
    };
    assert_eq!(hash(&desc), xxhash_rust::xxh3::xxh3_64(text.as_bytes()));
    assert_ne!(hash(&desc), hash(&again));
    assert_eq!(desc.inputs.len(), 2, "{:?}", desc.inputs);
    std::fs::remove_dir_all(&dir).unwrap();
}
