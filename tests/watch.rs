//! `pathwave watch`: an edited material colour is shown after a reload that rebuilds only the
//! light table; a syntax error is reported with file:line:col and the last image stays; the
//! fix brings back the first image, bit for bit. It takes `render`'s flags and honours them.

mod common;
use common::root;
use common::tev::{Packet, Received, fake_tev};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// A running `pathwave watch` and its stderr lines; killed when dropped.
struct Watch {
    child: Child,
    lines: mpsc::Receiver<String>,
    log: Vec<String>,
}

impl Watch {
    fn start(scene: &Path, out: &Path, tev: &str, flags: &[&str]) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_pathwave"))
            .arg("watch")
            .args(flags)
            .args(["--tev", tev, "-o"])
            .arg(out)
            .arg(scene)
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let (tx, lines) = mpsc::channel();
        let stderr = BufReader::new(child.stderr.take().unwrap());
        std::thread::spawn(move || {
            for line in stderr.lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    return;
                }
            }
        });
        Watch { child, lines, log: Vec::new() }
    }

    /// The next line that contains every one of `words` (within a minute).
    fn wait_for(&mut self, words: &[&str]) -> String {
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    self.log.push(line.clone());
                    if words.iter().all(|w| line.contains(w)) {
                        return line;
                    }
                }
                Err(_) => panic!("no line with {words:?}; stderr:\n{}", self.log.join("\n")),
            }
        }
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Replaces the file as an editor saving it does: a new file renamed over the old one.
fn save(path: &Path, text: &str) {
    let tmp = path.with_extension("ron.swp");
    std::fs::write(&tmp, text).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

/// The R, G, B planes of the last image update tev got, and how many packets came, once they
/// stopped coming: `watch` hands its images to a thread that sends them, so the last pass may
/// still be on its way when "done" is printed (for at most tev's 3 s deadline a packet).
fn shown(received: &Received) -> (Vec<Vec<f32>>, usize) {
    let count = || received.lock().unwrap().len();
    let (start, mut last, mut since) = (Instant::now(), count(), Instant::now());
    while since.elapsed() < Duration::from_millis(300) && start.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(20));
        if count() != last {
            (last, since) = (count(), Instant::now());
        }
    }
    let packets = received.lock().unwrap();
    let last = packets.iter().rev().find_map(|p| match p {
        Packet::Update { planes, .. } => Some(planes[..3].to_vec()),
        Packet::Create { .. } => None,
    });
    (last.expect("an image update"), packets.len())
}

fn bits(planes: &[Vec<f32>]) -> Vec<u32> {
    planes.iter().flatten().map(|f| f.to_bits()).collect()
}

#[test]
fn watch_shows_edits_keeps_the_last_image_on_an_error_and_rebuilds_only_what_changed() {
    let dir: PathBuf = std::env::temp_dir().join(format!("pathwave-watch-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.ron");
    let original = std::fs::read_to_string(root().join("scenes/cornell.ron")).unwrap();
    std::fs::write(&scene, &original).unwrap();
    let out = dir.join("out.exr");
    let (addr, received, _server) = fake_tev(None);
    let mut watch = Watch::start(&scene, &out, &addr, &["--width", "32", "--height", "32", "--spp", "4"]);

    watch.wait_for(&["loaded in"]);
    watch.wait_for(&["done, 4 spp"]);
    let (first, _) = shown(&received);
    // What tev shows is the film, which -o wrote.
    let written = pathwave::io::read_linear(&out).unwrap();
    let film: Vec<Vec<f32>> = (0..3).map(|k| written.pixels.iter().map(|p| p[k]).collect()).collect();
    assert_eq!(bits(&first), bits(&film));

    // The red wall turns blue: the materials change, the light table follows, nothing else.
    let red = r#""red": Lambertian(albedo: (0.65, 0.05, 0.05)),"#;
    assert!(original.contains(red));
    save(&scene, &original.replace(red, r#""red": Lambertian(albedo: (0.05, 0.05, 0.65)),"#));
    let line = watch.wait_for(&["reloaded", "materials changed"]);
    assert!(
        line.contains("0 objects changed, 0 added, 0 removed, materials changed; light table rebuilt; BVH, TLAS, BLAS, media kept"),
        "{line}"
    );
    watch.wait_for(&["done, 4 spp"]);
    let (blue, _) = shown(&received);
    let mean = |p: &Vec<f32>| p.iter().sum::<f32>() / p.len() as f32;
    assert!(mean(&blue[2]) > mean(&first[2]) && mean(&blue[0]) < mean(&first[0]), "the wall is not bluer");

    // A typo: its place in the file is reported, the last image stays on show.
    let typo = original.replace("vfov: 40,", "vfov: 40 oops,");
    let at = typo.lines().position(|l| l.contains("oops")).unwrap() + 1;
    save(&scene, &typo);
    let error = watch.wait_for(&["error:"]);
    assert!(error.contains(&format!("scene.ron:{at}:")), "{error}");
    let (_, count) = shown(&received);
    std::thread::sleep(Duration::from_millis(500));
    let (still, later) = shown(&received);
    assert_eq!((bits(&still), later), (bits(&blue), count), "the image changed after the error");
    assert!(watch.child.try_wait().unwrap().is_none(), "watch ended on the error");

    // Fixed: back to the first scene, and to the first image's bits.
    save(&scene, &original);
    let line = watch.wait_for(&["reloaded", "materials changed"]);
    assert!(line.contains("light table rebuilt; BVH, TLAS, BLAS, media kept"), "{line}");
    watch.wait_for(&["done, 4 spp"]);
    assert_eq!(bits(&shown(&received).0), bits(&first), "the reloaded world renders another image");
    // Reading the files to reload them is no change: nothing more happens.
    std::thread::sleep(Duration::from_millis(400));
    let more: Vec<String> = watch.lines.try_iter().collect();
    assert!(more.is_empty(), "reloads with no edit: {more:?}");
    drop(watch);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The pixels of an image file, as bits.
fn image_bits(path: &Path) -> Vec<u32> {
    let img = pathwave::io::read_linear(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    img.pixels.iter().flat_map(|p| p.to_array()).map(f32::to_bits).collect()
}

/// `watch` takes the flags of `render` that change an image (through the same argument structs)
/// and honours them: with `--seed`, `--max-depth`, `--sampler`, `--clamp` and `--crop` its image
/// has the bits of `render`'s with the same flags, and leaving out any one of them changes
/// `render`'s image (so a flag that `watch` accepted and ignored would be seen).
#[test]
fn watch_takes_and_honours_the_flags_of_render() {
    let dir: PathBuf = std::env::temp_dir().join(format!("pathwave-watch-flags-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.ron");
    std::fs::copy(root().join("scenes/cornell.ron"), &scene).unwrap();
    let size: &[&str] = &["--width", "24", "--height", "24", "--spp", "4"];
    let flags: [&[&str]; 5] = [
        &["--seed", "7"],
        &["--max-depth", "2"],
        &["--sampler", "independent"],
        &["--clamp", "0.5"],
        &["--crop", "0.25,0.75,0,0.5"],
    ];
    let render = |flags: &[&[&str]], name: &str| {
        let out = dir.join(format!("{name}.exr"));
        let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
            .arg("render")
            .arg(&scene)
            .arg("-o")
            .arg(&out)
            .args(size)
            .args(flags.concat())
            .output()
            .unwrap();
        assert!(o.status.success(), "render {flags:?}: {}", String::from_utf8_lossy(&o.stderr));
        image_bits(&out)
    };
    let want = render(&flags, "all");
    for (i, f) in flags.iter().enumerate() {
        let others: Vec<&[&str]> =
            flags.iter().enumerate().filter(|(j, _)| *j != i).map(|(_, f)| *f).collect();
        assert_ne!(render(&others, &format!("without-{i}")), want, "{f:?} does not change render's image");
    }

    let (addr, _received, _server) = fake_tev(None);
    let out = dir.join("watch.exr");
    let mut watch = Watch::start(&scene, &out, &addr, &[size, &flags.concat()].concat());
    watch.wait_for(&["done, 4 spp"]);
    assert!(image_bits(&out) == want, "watch's image is not render's with the same flags");
    drop(watch);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `watch -o` naming a file the scene reads (its texture) would render, write, reload and render
/// for ever: it is an error in the scene, shown and waited out like any other, and the texture
/// is left as it was. Pointed elsewhere by an edit of the scene, the watch renders.
#[test]
fn watch_refuses_an_output_that_the_scene_reads() {
    let dir: PathBuf = std::env::temp_dir().join(format!("pathwave-watch-input-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let texture = dir.join("tex.exr");
    image::Rgb32FImage::from_pixel(2, 2, image::Rgb([0.8, 0.4, 0.2])).save(&texture).unwrap();
    let before = std::fs::read(&texture).unwrap();
    let original = std::fs::read_to_string(root().join("scenes/cornell.ron")).unwrap();
    let with = |file: &str| {
        let t = format!("textures: {{ \"t\": Image(file: \"{file}\") }},\n    materials:");
        original.replacen("materials:", &t, 1)
    };
    let scene = dir.join("scene.ron");
    std::fs::write(&scene, with("tex.exr")).unwrap();
    let (addr, _received, _server) = fake_tev(None);
    let mut watch = Watch::start(&scene, &texture, &addr, &["--width", "8", "--height", "8", "--spp", "1"]);
    watch.wait_for(&["error", "would write over this file, which the scene reads"]);
    assert_eq!(std::fs::read(&texture).unwrap(), before);
    std::fs::copy(&texture, dir.join("other.exr")).unwrap();
    save(&scene, &with("other.exr"));
    watch.wait_for(&["done, 1 spp"]);
    drop(watch);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A scene's folder removed and made again (a checkout, a sync tool) takes the folder's watch
/// with it: `watch` says so, looks for the folder until it is back, and then reloads from it.
#[test]
fn watch_follows_a_folder_removed_and_made_again() {
    let dir: PathBuf = std::env::temp_dir().join(format!("pathwave-watch-gone-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let folder = dir.join("scene");
    std::fs::create_dir_all(&folder).unwrap();
    let scene = folder.join("scene.ron");
    std::fs::copy(root().join("scenes/cornell.ron"), &scene).unwrap();
    let (addr, _received, _server) = fake_tev(None);
    let out = dir.join("out.exr");
    let mut watch = Watch::start(&scene, &out, &addr, &["--width", "8", "--height", "8", "--spp", "1"]);
    watch.wait_for(&["done, 1 spp"]);
    std::fs::remove_dir_all(&folder).unwrap();
    watch.wait_for(&["was removed: waiting for it to come back"]);
    std::fs::create_dir_all(&folder).unwrap();
    std::fs::copy(root().join("scenes/cornell.ron"), &scene).unwrap();
    watch.wait_for(&["is back"]);
    watch.wait_for(&["reloaded"]);
    watch.wait_for(&["done, 1 spp"]);
    drop(watch);
    std::fs::remove_dir_all(&dir).unwrap();
}
