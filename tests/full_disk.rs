//! A write that fails (here: a full disk) keeps the previous file and exits non-zero with a
//! message naming the user's path, and a read-only folder is refused before any work. The two
//! tests that mount small tmpfs need root, so they are ignored unless asked for (`cargo test
//! --release --test full_disk -- --ignored`, as `.ci/run` does); asked for where they cannot
//! run, they fail saying so.

mod common;

use common::root;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A mounted tmpfs, unmounted when dropped.
struct Tmpfs(PathBuf);

impl Tmpfs {
    /// A tmpfs with mount options `options` (e.g. `size=1m`) at a folder named after `name`;
    /// fails saying so where it cannot be mounted (not root).
    fn mount(name: &str, options: &str) -> Tmpfs {
        let dir = std::env::temp_dir().join(format!("pathwave-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let status = Command::new("mount").args(["-t", "tmpfs", "-o", options, "tmpfs"]).arg(&dir).status();
        match status {
            Ok(s) if s.success() => Tmpfs(dir),
            other => {
                let _ = std::fs::remove_dir(&dir);
                let why = other.map_or_else(|e| e.to_string(), |s| s.to_string());
                panic!("cannot run: mounting a tmpfs needs root (mount: {why})");
            }
        }
    }

    /// Fills the disk.
    fn fill(&self) {
        let mut f = std::fs::File::create(self.0.join("fill")).unwrap();
        let block = vec![0u8; 4096];
        while std::io::Write::write_all(&mut f, &block).is_ok() {}
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
        let _ = std::fs::remove_dir(&self.0);
    }
}

fn render(out: &Path, extra: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .args(["render", "scenes/cornell.ron", "--width", "32", "--height", "32", "-q", "-o"])
        .arg(out)
        .args(extra)
        .current_dir(root())
        .output()
        .unwrap()
}

#[test]
#[ignore = "needs root (mount): cargo test --release --test full_disk -- --ignored"]
fn a_full_disk_keeps_the_previous_image_trace_and_checkpoint() {
    let fs = Tmpfs::mount("full", "size=1m");
    let (image, trace) = (fs.0.join("c.png"), fs.0.join("t.json"));
    let first =
        render(&image, &["--spp", "1", "--checkpoint-every", "1000", "--trace", trace.to_str().unwrap()]);
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    let ckpt = fs.0.join("c.png.ckpt");
    let before: Vec<Vec<u8>> = [&image, &trace, &ckpt].iter().map(|p| std::fs::read(p).unwrap()).collect();
    fs.fill();
    let second =
        render(&image, &["--spp", "2", "--checkpoint-every", "1000", "--trace", trace.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert!(!second.status.success(), "a write to a full disk succeeded:\n{stderr}");
    assert!(stderr.contains(fs.0.to_str().unwrap()), "the error names no path of the user's:\n{stderr}");
    assert!(!stderr.contains(".tmp"), "the error names a temporary file:\n{stderr}");
    for (p, old) in [&image, &trace, &ckpt].iter().zip(&before) {
        assert_eq!(&std::fs::read(p).unwrap(), old, "{} changed", p.display());
    }
    let leftovers: Vec<_> = std::fs::read_dir(&fs.0)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left behind: {leftovers:?}");
}

/// A read-only folder (a read-only mount: root may write to any folder whatever its mode) is
/// refused before any rendering, for the image, the trace and the checkpoint alike.
#[test]
#[ignore = "needs root (mount): cargo test --release --test full_disk -- --ignored"]
fn a_read_only_folder_is_refused_before_the_work() {
    let fs = Tmpfs::mount("ro", "size=64k,ro");
    let here = std::env::temp_dir().join(format!("pathwave-ro-ok-{}", std::process::id()));
    std::fs::create_dir_all(&here).unwrap();
    for (out, trace) in [(fs.0.join("c.png"), here.join("t.json")), (here.join("c.png"), fs.0.join("t.json"))]
    {
        let o =
            render(&out, &["--spp", "1", "--checkpoint-every", "1000", "--trace", trace.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{err}");
        // The check made before rendering ("cannot write there", "cannot write the trace"),
        // not a failed write after it.
        assert!(err.contains("cannot write") && err.to_lowercase().contains("read-only"), "{err}");
        assert!(err.contains(fs.0.to_str().unwrap()), "the error names the folder's path: {err}");
        assert!(!here.join("c.png").exists(), "nothing is written beside a refused output");
    }
    let _ = std::fs::remove_dir_all(&here);
}

/// Outputs are checked before any rendering: an unknown format, a missing folder, and the
/// scene itself are refused at once, and the scene is left intact.
#[test]
fn outputs_are_checked_before_the_work() {
    let dir = std::env::temp_dir().join(format!("pathwave-outputs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("s.ron");
    std::fs::copy(root().join("scenes/cornell.ron"), &scene).unwrap();
    let before = std::fs::read(&scene).unwrap();
    for (out, says) in [
        (dir.join("late.tiff"), "unknown output format"),
        (dir.join("missing/c.png"), "cannot write there: no such folder"),
        (scene.clone(), "unknown output format"),
        (dir.join("s.ron.png"), ""),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
            .arg("render")
            .arg(&scene)
            .args(["--spp", "1", "--width", "8", "--height", "8", "-q", "-o"])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.success(), says.is_empty(), "{}: {err}", out.display());
        assert!(err.contains(says), "{}: {err}", out.display());
    }
    // A time that is no time.
    let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .arg("render")
        .arg(&scene)
        .args(["--spp", "1", "-q", "--time", "NaN", "-o"])
        .arg(dir.join("t.png"))
        .output()
        .unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("--time takes seconds"));
    // The scene named as the output of a PNG-named scene file.
    let png_scene = dir.join("scene.png");
    std::fs::copy(&scene, &png_scene).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .arg("render")
        .arg(&png_scene)
        .args(["--spp", "1", "-q", "-o"])
        .arg(&png_scene)
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("would replace an input"));
    assert_eq!(std::fs::read(&png_scene).unwrap(), before);
    // A trace into a missing folder, before any work (it panicked in tracing-chrome once).
    let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .arg("render")
        .arg(&scene)
        .args(["--spp", "1", "-q", "--trace"])
        .arg(dir.join("missing/t.json"))
        .arg("-o")
        .arg(dir.join("t.png"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("missing/t.json: cannot write the trace: no such folder"),
        "{err}"
    );
    assert!(!dir.join("t.png").exists(), "rendered before the trace was refused");
    // merge's output over one of its parts, and its checkpoint over another.
    let part = dir.join("p.png.ckpt");
    let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .arg("render")
        .arg(&scene)
        .args(["--spp", "2", "--width", "8", "--height", "8", "--samples", "0..1", "-q", "-o"])
        .arg(dir.join("p.png"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let part_bytes = std::fs::read(&part).unwrap();
    for (out, says) in
        [(part.clone(), "unknown output format"), (dir.join("p.png"), "would replace the part")]
    {
        let o = Command::new(env!("CARGO_BIN_EXE_pathwave"))
            .arg("merge")
            .arg(&part)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(says), "{}: {err}", out.display());
        assert_eq!(std::fs::read(&part).unwrap(), part_bytes);
    }
    assert_eq!(std::fs::read(&scene).unwrap(), before);
    std::fs::remove_dir_all(&dir).unwrap();
}
