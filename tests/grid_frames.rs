//! Grid sequences (`grid: (file: "d_{frame}.vol")`): each frame of `animate` reads its own
//! file, `render --time` reads the file of `animate`'s frame at that time, a file is read again
//! only when the frame names another, a missing frame is named before any frame renders (by
//! `animate` and by `farm slurm`), bad braces are refused, and a frame's grid file is part of
//! its checkpoint key and of the inputs no output may replace.

mod common;
use common::{pathwave, run};
use pathwave::engine::format::files::recording;
use pathwave::engine::world::{Filling, SceneWorld};
use pathwave::io::read_linear;
use std::path::{Path, PathBuf};
use std::process::Command;

fn temp(name: &str) -> PathBuf {
    common::temp("grid-frames", name)
}

fn fails(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!out.status.success(), "succeeded: {err}");
    err
}

/// A `.vol` grid of 4 x 1 x 1 voxels along x.
fn write_vol(path: &Path, values: [f32; 4]) {
    let mut b = b"VOL\x03".to_vec();
    for i in [1i32, 4, 1, 1, 1] {
        b.extend(i.to_le_bytes());
    }
    for f in [0f32, 0.0, 0.0, 1.0, 1.0, 1.0].into_iter().chain(values) {
        b.extend(f.to_le_bytes());
    }
    std::fs::write(path, b).unwrap();
}

/// Dense on the left (-x, the image's left) or on the right.
const LEFT: [f32; 4] = [1.0, 1.0, 0.0, 0.0];
const RIGHT: [f32; 4] = [0.0, 0.0, 1.0, 1.0];

/// An absorbing slab filling the view of a white background, its density from the grid `grid`
/// (fps 4).
fn scene(dir: &Path, grid: &str, extra: &str) -> PathBuf {
    let text = format!(
        r#"Scene(
            camera: (look_from: (0, 0, 3), look_at: (0, 0, 0), vfov: 20),
            render: (width: 24, height: 12, spp: 4),
            background: Constant((1, 1, 1)),
            materials: {{}},
            objects: [
                (
                    shape: Box(a: (-1, -0.5, -0.5), b: (1, 0.5, 0.5)),
                    medium: (density: 4, albedo: (0, 0, 0), grid: (file: "{grid}", transform: [Scale((2, 1, 1)), Translate((-1, -0.5, -0.5))])),
                ),
                {extra}
            ],
            animation: (frames: 3, fps: 4),
        )"#
    );
    let path = dir.join("s.ron");
    std::fs::write(&path, text).unwrap();
    path
}

/// The mean of the left and of the right half of an image.
fn halves(path: &Path) -> (f32, f32) {
    let img = read_linear(path).unwrap();
    let (w, h) = (img.width as usize, img.height as usize);
    let (mut l, mut r) = (0.0, 0.0);
    for y in 0..h {
        for x in 0..w {
            let v = img.pixels[y * w + x].x;
            if x < w / 2 { l += v } else { r += v }
        }
    }
    let n = (w * h / 2) as f32;
    (l / n, r / n)
}

/// Frame 0 reads a grid dense on the left, frame 1 one dense on the right, frame 2 the left
/// again: the dark side of the image follows. Checked to fail with the frame number left out of
/// the file name (`FramePattern::at` giving frame 0's name for every frame: frame 1 was dark on
/// the left).
#[test]
fn each_frame_renders_its_own_grid_file() {
    let dir = temp("sides");
    for (n, v) in [LEFT, RIGHT, LEFT].into_iter().enumerate() {
        write_vol(&dir.join(format!("d_{n:02}.vol")), v);
    }
    let s = scene(&dir, "d_{frame:02}.vol", "");
    let out = dir.join("f_{frame}.exr");
    let log = run(pathwave().arg("animate").arg(&s).arg("-o").arg(&out).args(["-q", "--stats"]));
    for (n, left_dark) in [(0, true), (1, false), (2, true)] {
        let (l, r) = halves(&dir.join(format!("f_{n}.exr")));
        eprintln!("frame {n}: left {l:.3}, right {r:.3}");
        assert!((l < 0.5 * r) == left_dark && (r < 0.5 * l) == !left_dark, "frame {n}: left {l}, right {r}");
    }
    // Each frame read its file, and said so.
    assert!(log.contains("grid files read"), "{log}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `render --time t` reads the file of the frame `animate` renders at `t` (0.25 s at 4 fps:
/// frame 1; 0.45 s too), and gives that frame's bits; without `--time`, frame 0's.
#[test]
fn render_at_a_time_reads_the_frame_animate_renders_then() {
    let dir = temp("time");
    for (n, v) in [LEFT, RIGHT, LEFT].into_iter().enumerate() {
        write_vol(&dir.join(format!("d{n}.vol")), v);
    }
    let s = scene(&dir, "d{frame}.vol", "");
    run(pathwave()
        .arg("animate")
        .arg(&s)
        .arg("-o")
        .arg(dir.join("f_{frame}.exr"))
        .args(["-q", "--frames", "0..2"]));
    let render = |name: &str, time: &[&str]| {
        let out = dir.join(name);
        run(pathwave().arg("render").arg(&s).arg("-o").arg(&out).arg("-q").args(time));
        read_linear(&out).unwrap()
    };
    let frame1 = read_linear(&dir.join("f_1.exr")).unwrap();
    assert_eq!(render("t.exr", &["--time", "0.25"]), frame1, "render --time 0.25 is not frame 1");
    let (l, r) = halves(&dir.join("t.exr"));
    assert!(r < 0.5 * l, "left {l}, right {r}");
    let (l, r) = halves(&{
        render("later.exr", &["--time", "0.45"]);
        dir.join("later.exr")
    });
    assert!(r < 0.5 * l, "--time 0.45 (frame 1): left {l}, right {r}");
    assert_eq!(render("still.exr", &[]), read_linear(&dir.join("f_0.exr")).unwrap(), "a still is frame 0");
    let e = fails(pathwave().arg("render").arg(&s).arg("-o").arg(dir.join("x.exr")).args(["--time=-1"]));
    assert!(e.contains("before frame 0") && e.contains("d{frame}.vol"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A grid file is read when a frame names a file other than the one its medium holds: a grid
/// that is one file for every frame is read once, with the scene; a frame rendered again reads
/// nothing; a reload reads the frame's file again, and rebuilds the media only if it changed.
/// Read through the engine's record of the files it reads.
#[test]
fn a_file_is_read_only_when_the_frame_names_another() {
    let dir = temp("reads");
    for (n, v) in [LEFT, RIGHT].into_iter().enumerate() {
        write_vol(&dir.join(format!("d{n}.vol")), v);
    }
    write_vol(&dir.join("still.vol"), RIGHT);
    let still = r#"(
        shape: Box(a: (-1, 1, -0.5), b: (1, 2, 0.5)),
        medium: (density: 1, albedo: (0.5, 0.5, 0.5), grid: (file: "still.vol")),
    ),"#;
    let (desc, read) =
        recording(|| pathwave::engine::scene::load(&scene(&dir, "d{frame}.vol", still)).unwrap());
    let names = |files: &[pathwave::engine::format::files::InputFile]| -> Vec<String> {
        files.iter().map(|f| f.path.file_name().unwrap().to_string_lossy().into_owned()).collect()
    };
    assert_eq!(names(&read), ["s.ron", "still.vol"], "the load reads no frame's file");
    let mut w = SceneWorld::new(&desc);
    let update = |w: &mut SceneWorld, frame: u32| {
        w.set_frame(frame);
        let (scene, read) = recording(|| w.update_checked().unwrap());
        (scene, names(&read))
    };
    let (first, read) = update(&mut w, 0);
    assert_eq!(read, ["d0.vol"]);
    // The still medium (density 1) keeps the grid the load read.
    let still_grid = |w: &mut SceneWorld| {
        let mut q = w.world.query::<&Filling>();
        let f = q.iter(&w.world).find(|f| f.0.sigma_t == glam::Vec3::ONE).unwrap();
        f.0.density_grid.as_ref().unwrap().grid.clone()
    };
    let held = still_grid(&mut w);
    let before = w.builds();
    let (again, read) = update(&mut w, 0);
    assert!(read.is_empty() && std::sync::Arc::ptr_eq(&first, &again), "frame 0 again read {read:?}");
    assert_eq!(w.builds(), before, "frame 0 again rebuilt something");
    let (next, read) = update(&mut w, 1);
    assert_eq!(read, ["d1.vol"], "frame 1 reads its file only");
    assert!(!std::sync::Arc::ptr_eq(&first.media, &next.media));
    let built = w.builds().since(&before);
    assert_eq!(
        (w.builds().grids, built.as_str()),
        (2, "media rebuilt, grid files read; BVH, TLAS, BLAS, light table kept")
    );
    assert!(std::sync::Arc::ptr_eq(&held, &still_grid(&mut w)));
    let inputs = w.frame_inputs();
    assert!(inputs.len() == 1 && inputs[0].path.ends_with("d1.vol"), "{inputs:?}");
    // A reload (as `watch` makes after an edit) reads the frame's file again: the same values
    // rebuild nothing, new ones the media.
    w.reload(&desc);
    let before = w.builds();
    let (same, read) = update(&mut w, 1);
    assert!(read == ["d1.vol"] && std::sync::Arc::ptr_eq(&same.media, &next.media));
    assert_eq!(w.builds().media, before.media);
    write_vol(&dir.join("d1.vol"), LEFT);
    w.reload(&desc);
    let (edited, read) = update(&mut w, 1);
    assert!(read == ["d1.vol"] && w.builds().media == before.media + 1);
    assert!(!std::sync::Arc::ptr_eq(&edited.media, &next.media));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A frame whose file is missing is named, with the path looked for, before any frame renders
/// (by `animate`, and by `farm slurm` before it submits); a file that is not a grid is named
/// too, and braces other than `{frame}` and `{frame:0N}` are refused where the file is named.
#[test]
fn missing_frames_and_bad_braces_are_named_before_any_work() {
    let dir = temp("missing");
    write_vol(&dir.join("d0.vol"), LEFT);
    write_vol(&dir.join("d1.vol"), RIGHT);
    let s = scene(&dir, "d{frame}.vol", "");
    let out = dir.join("f_{frame}.exr");
    let e = fails(pathwave().arg("animate").arg(&s).arg("-o").arg(&out));
    let looked = dir.join("d2.vol");
    assert!(e.contains("frame 2") && e.contains(&looked.display().to_string()), "{e}");
    assert!(!dir.join("f_0.exr").exists(), "frame 0 was rendered before the check");
    // The frames before it are all there.
    run(pathwave().arg("animate").arg(&s).arg("-o").arg(&out).args(["-q", "--frames", "0..2"]));
    let farm = |frames: &str| {
        let mut c = pathwave();
        c.args(["farm", "slurm"]).arg(&s).arg("-o").arg(dir.join("farm/f_{frame}.exr"));
        c.args(["--tasks", "2", "--frames", frames, "--dry-run"]);
        c
    };
    let e = fails(&mut farm("0..3"));
    assert!(e.contains("frame 2") && e.contains(&looked.display().to_string()), "{e}");
    run(&mut farm("0..2"));
    // Not a grid: named by its frame before any work too.
    std::fs::write(&looked, b"not a grid").unwrap();
    let e = fails(pathwave().arg("animate").arg(&s).arg("-o").arg(dir.join("g_{frame}.exr")));
    assert!(e.contains("frame 2") && e.contains("not a grid volume"), "{e}");
    assert!(!dir.join("g_0.exr").exists());
    for bad in ["d{frame:2}.vol", "d{frame.vol", "d{n}.vol", "d}.vol"] {
        let e = fails(pathwave().arg("render").arg(scene(&dir, bad, "")).arg("-o").arg(dir.join("x.exr")));
        assert!(e.contains("`file`") && e.contains(bad) && e.contains("{frame:0N}"), "{bad}: {e}");
        assert!(e.contains("s.ron:"), "no line and column: {e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A frame's grid file is one of its render's inputs: a checkpoint of frame 0 is refused once
/// frame 0's file has changed (checked to fail with the frame's files left out of the key:
/// the resume went on, mixing two grids), and no output may write over a frame's file.
#[test]
fn a_frames_grid_file_keys_its_checkpoint_and_is_never_written_over() {
    let dir = temp("key");
    // Grid files named as a trace is (a grid is told by its bytes), so that one may be asked
    // to be written over.
    write_vol(&dir.join("d0.json"), LEFT);
    write_vol(&dir.join("d1.json"), RIGHT);
    write_vol(&dir.join("d2.json"), RIGHT);
    let s = scene(&dir, "d{frame}.json", "");
    let out = dir.join("o.exr");
    let render = |spp: &str| {
        pathwave()
            .arg("render")
            .arg(&s)
            .args(["-q", "--resume", "--spp", spp, "-o"])
            .arg(&out)
            .output()
            .unwrap()
    };
    assert!(render("2").status.success());
    let o = {
        write_vol(&dir.join("d0.json"), RIGHT);
        render("4")
    };
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("the scene file or a file it reads has changed"), "{err}");
    // The key an EXR with layers records: the same frame with another file has another.
    let key = |file: [f32; 4]| {
        write_vol(&dir.join("d0.json"), file);
        let o = dir.join("k.exr");
        run(pathwave().arg("render").arg(&s).args(["-q", "--aov", "albedo", "-o"]).arg(&o));
        let l = pathwave::io::read_exr_channels(&o).unwrap();
        l.metadata.into_iter().find(|(n, _)| n == "pathwave:scene_key").unwrap().1
    };
    assert_ne!(key(LEFT), key(RIGHT));
    assert_eq!(key(LEFT), key(LEFT));
    // No file written over a frame's file: this frame's (render at frame 0), or any frame's of
    // the sequence (animate's frame 0 and frame 2's file).
    let e = fails(
        pathwave()
            .arg("render")
            .arg(&s)
            .arg("-o")
            .arg(dir.join("x.exr"))
            .arg("--trace")
            .arg(dir.join("d0.json")),
    );
    assert!(e.contains("d0.json: the render would write over this file, which the scene reads"), "{e}");
    let animate = || {
        let mut c = pathwave();
        c.arg("animate")
            .arg(&s)
            .arg("-o")
            .arg(dir.join("a_{frame}.exr"))
            .args(["--frames", "0..1", "--trace"]);
        c
    };
    let e = fails(animate().arg(dir.join("d2.json")));
    assert!(e.contains("d2.json: the render would write over this file, which the scene reads"), "{e}");
    assert!(!dir.join("a_0.exr").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An OpenVDB sequence: each frame's grid is placed by its own file's transform, as the same
/// file named alone places it (frames 0 and 1 are two compressions of one grid). Checked to
/// fail with the file's transform left out of a frame's placement.
#[test]
fn an_openvdb_frame_is_the_grid_its_file_names_alone() {
    let dir = temp("vdb");
    let assets = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/assets");
    std::fs::copy(assets.join("smoke-blosc.vdb"), dir.join("v0.vdb")).unwrap();
    std::fs::copy(assets.join("smoke-zip.vdb"), dir.join("v1.vdb")).unwrap();
    let filling = |grid: &str, frame: u32| {
        let text = format!(
            r#"Scene(
                camera: (look_from: (0, 0.5, -3), look_at: (0, 0.5, 0), vfov: 40),
                materials: {{}},
                objects: [(
                    shape: Box(a: (-0.45, -0.05, -0.2), b: (0.55, 1.2, 0.8)),
                    medium: (density: 20, albedo: (0.8, 0.8, 0.8), grid: (file: "{grid}", transform: [RotateY(20)])),
                )],
            )"#
        );
        let path = dir.join("v.ron");
        std::fs::write(&path, text).unwrap();
        let mut w = SceneWorld::new(&pathwave::engine::scene::load(&path).unwrap());
        w.set_frame(frame);
        w.update_checked().unwrap();
        let mut q = w.world.query::<&Filling>();
        q.single(&w.world).unwrap().0.clone()
    };
    let alone = filling("v0.vdb", 0);
    assert!(alone.density_grid.is_some());
    let placed = |m: &pathwave::engine::media::Medium| m.density_grid.as_ref().unwrap().grid_from_object;
    for frame in [0, 1] {
        let m = filling("v{frame}.vdb", frame);
        // (A short message: the grids' values are long.)
        assert!(m == alone, "frame {frame}: placed by {:?}, alone by {:?}", placed(&m), placed(&alone));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A frame's files are confined as the scene's load is (`--assets-under`; `farm slurm`'s
/// default, the scene's folder): a sequence outside the folder is refused by `render` (the
/// world's read), `animate` and `farm slurm` (their checks before any work), naming the frame.
#[test]
fn a_sequence_outside_the_assets_folder_is_refused() {
    let dir = temp("confined");
    let (scenes, grids) = (dir.join("scenes"), dir.join("grids"));
    std::fs::create_dir_all(&scenes).unwrap();
    std::fs::create_dir_all(&grids).unwrap();
    for n in 0..3 {
        write_vol(&grids.join(format!("d{n}.vol")), LEFT);
    }
    let s = scene(&scenes, "../grids/d{frame}.vol", "");
    let under = ["--assets-under", scenes.to_str().unwrap()];
    let outside = "lies outside";
    let e = fails(pathwave().arg("render").arg(&s).arg("-o").arg(dir.join("x.exr")).args(under));
    assert!(e.contains("frame 0") && e.contains(outside), "{e}");
    let e = fails(pathwave().arg("animate").arg(&s).arg("-o").arg(dir.join("f{frame}.exr")).args(under));
    assert!(e.contains("frame 0") && e.contains(outside), "{e}");
    let farm = pathwave()
        .args(["farm", "slurm"])
        .arg(&s)
        .arg("-o")
        .arg(dir.join("o/f{frame}.exr"))
        .args(["--tasks", "2", "--dry-run"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&farm.stderr);
    assert!(!farm.status.success() && e.contains("frame 0") && e.contains(outside), "{e}");
    // Under the folder that holds both, all render.
    let whole = ["--assets-under", dir.to_str().unwrap()];
    run(pathwave().arg("animate").arg(&s).arg("-o").arg(dir.join("f{frame}.exr")).args(whole).arg("-q"));
    std::fs::remove_dir_all(&dir).unwrap();
}
