//! `pathwave watch SCENE.ron`: renders progressively into the window (or tev) and, whenever the
//! scene file or a file it loads changes, loads it again, updates the ECS world with what
//! changed (so that only what depends on it is rebuilt) and starts the passes again. A scene
//! with an error shows the error (file:line:col) and keeps the last good image.

use crate::engine::render_scene::{PixelWindow, RenderScene};
use crate::engine::scene::{self, BackgroundDesc, SceneDesc, ShapeDesc, TextureDesc};
use crate::engine::world::SceneWorld;
use crate::integrator::{film::Film, wavefront};
use crate::io::{self, LinearImage};
use crate::view::{self, Pass, ViewArgs, Viewers};
use notify_debouncer_full::notify::{EventKind, RecursiveMode};
use notify_debouncer_full::{DebounceEventResult, new_debouncer};
use std::collections::BTreeSet;
use std::num::NonZeroU32;
use std::path::{Component, Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// `pathwave watch`'s arguments.
#[derive(clap::Args, Clone, Debug)]
pub struct WatchArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Also write the image here (.png or .exr) each time the passes finish, and when watch
    /// stops.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Where to show the render (the window when neither is given).
    #[command(flatten)]
    pub view: ViewArgs,
    /// Samples per pixel (overrides the scene).
    #[arg(long)]
    pub spp: Option<NonZeroU32>,
    /// Image width (overrides the scene).
    #[arg(long)]
    pub width: Option<NonZeroU32>,
    /// Image height (overrides the scene).
    #[arg(long)]
    pub height: Option<NonZeroU32>,
    /// Set a parameter the scene declares to VALUE, RON text; repeatable.
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// Worker threads (default: all cores).
    #[arg(short, long, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=crate::MAX_THREADS))]
    pub threads: Option<usize>,
}

/// How long file events are gathered into one reload (an editor's save is several events).
const DEBOUNCE: Duration = Duration::from_millis(100);
/// The longest pass: edits are noticed between passes.
const MAX_PASS: Duration = Duration::from_millis(500);

/// `a/./b/../c` as `a/c`, so that a path a scene names matches the one a file event reports.
fn normalize(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir if out.file_name().is_some() => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out
}

/// The files a loaded scene depends on: the scene file, its meshes and images.
fn files_of(path: &Path, desc: &SceneDesc) -> BTreeSet<PathBuf> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut files = BTreeSet::from([path.to_path_buf()]);
    for o in &desc.objects {
        if let ShapeDesc::Mesh(m) = &o.shape {
            files.insert(dir.join(&m.path));
        }
    }
    for (_, t) in &desc.textures.0 {
        if let TextureDesc::Image { file, .. } = t {
            files.insert(dir.join(&file.path));
        }
    }
    if let BackgroundDesc::Environment { file, .. } = &desc.background {
        files.insert(dir.join(&file.path));
    }
    files.iter().map(|f| normalize(&std::path::absolute(f).unwrap_or_else(|_| f.clone()))).collect()
}

/// Loads the scene with the command line's settings (`defines`: the -D overrides).
fn load(args: &WatchArgs, defines: &[(String, String)]) -> Result<SceneDesc, String> {
    let mut desc = scene::load_with(&args.scene, defines).map_err(|e| e.to_string())?;
    let r = &mut desc.render;
    r.spp = args.spp.unwrap_or(r.spp);
    r.width = args.width.unwrap_or(r.width);
    r.height = args.height.unwrap_or(r.height);
    crate::limits::check_render(r)?;
    Ok(desc)
}

/// How a run of passes ended.
enum Ended {
    /// All the samples are in.
    Done,
    /// A file changed.
    Changed,
    /// The window was closed.
    Closed,
}

/// Whether an event can change a file's contents: not reading it (which the reload itself
/// does) nor its access time.
fn writes(kind: &EventKind) -> bool {
    use notify_debouncer_full::notify::event::{AccessKind, AccessMode, MetadataKind, ModifyKind};
    match kind {
        EventKind::Access(AccessKind::Close(AccessMode::Write)) => true,
        EventKind::Access(_) | EventKind::Modify(ModifyKind::Metadata(MetadataKind::AccessTime)) => false,
        _ => true,
    }
}

/// The file events, kept to those about the scene's files.
struct Events {
    rx: mpsc::Receiver<DebounceEventResult>,
    files: BTreeSet<PathBuf>,
}

impl Events {
    /// Whether one of the files changed (waiting up to `wait`).
    fn changed(&self, wait: Duration) -> bool {
        let deadline = Instant::now() + wait;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(left) {
                Ok(Ok(events)) => {
                    let ours = |p: &PathBuf| self.files.contains(&normalize(p));
                    if events.iter().any(|e| writes(&e.kind) && e.paths.iter().any(ours)) {
                        // What else came with it is the same save.
                        while self.rx.try_recv().is_ok() {}
                        return true;
                    }
                }
                Ok(Err(errors)) => {
                    for e in errors {
                        eprintln!("watch: {e}");
                    }
                }
                Err(_) => return false,
            }
            if left.is_zero() {
                return false;
            }
        }
    }
}

/// Renders `scene` in passes into `film`, showing each, until all its samples are in, a file
/// changes or the window closes.
fn passes(
    scene: &RenderScene,
    film: &mut Film,
    viewers: &mut Viewers,
    events: &Events,
    pool: &rayon::ThreadPool,
) -> Ended {
    let target = scene.settings.spp;
    let (mut pass, mut number) = (1, 0);
    while film.spp < target {
        if events.changed(Duration::ZERO) {
            return Ended::Changed;
        }
        let start = Instant::now();
        let range = film.spp..(film.spp + pass).min(target);
        let k = range.len();
        let opts = wavefront::Options::default();
        let (part, _) = pool.install(|| wavefront::render_samples(scene, opts, range, &|_, _| {}));
        film.absorb(part);
        number += 1;
        let per_sample = start.elapsed().as_secs_f64() / k as f64;
        let left = target - film.spp;
        let eta = Duration::from_secs_f64(per_sample * left as f64);
        if !viewers.show(film, &Pass { number, spp: film.spp, target, eta }) {
            return Ended::Closed;
        }
        pass = view::next_pass(film.spp, left, per_sample, MAX_PASS);
    }
    Ended::Done
}

/// Writes the film to `-o` when given.
fn write(args: &WatchArgs, film: &Film) -> Result<(), String> {
    match &args.output {
        Some(out) => {
            io::write(out, &LinearImage { width: film.width, height: film.height, pixels: film.mean() })
                .map(drop)
        }
        None => Ok(()),
    }
}

/// Runs `pathwave watch` until the window is closed (or the process is stopped).
pub fn run(mut args: WatchArgs) -> Result<(), String> {
    if !args.view.preview && args.view.tev.is_none() {
        args.view.preview = true;
    }
    if let Some(out) = &args.output {
        io::check_output(out, &[&args.scene], false)?;
    }
    // Flags beyond the bounds fail at once; a scene beyond them is reported like any error in
    // it, and the watch waits for the fix.
    let side = args.width.max(args.height).map_or(0, |s| s.get());
    if side > crate::limits::MAX_SIDE || args.spp.is_some_and(|s| s.get() > crate::limits::MAX_SPP) {
        return Err(format!(
            "--width, --height and --spp take at most {} pixels and {} samples per pixel",
            crate::limits::MAX_SIDE,
            crate::limits::MAX_SPP
        ));
    }
    let defines = scene::parse_defines(&args.define)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .map_err(|e| format!("cannot start {:?} threads: {e}", args.threads))?;
    let (tx, rx) = mpsc::channel();
    let mut debouncer = new_debouncer(DEBOUNCE, None, tx).map_err(|e| format!("cannot watch files: {e}"))?;
    let scene_file =
        normalize(&std::path::absolute(&args.scene).map_err(|e| format!("{}: {e}", args.scene.display()))?);
    let mut events = Events { rx, files: BTreeSet::from([scene_file.clone()]) };
    let mut folders = BTreeSet::new();
    let mut world: Option<SceneWorld> = None;
    let mut viewers: Option<(Viewers, PixelWindow, u32, u32)> = None;
    let mut film: Option<Film> = None;
    let name = args.scene.display().to_string();
    loop {
        let start = Instant::now();
        let loaded = load(&args, &defines);
        if let Ok(desc) = &loaded {
            events.files = files_of(&scene_file, desc);
        }
        // Folders, not files: an editor that saves by renaming a new file over the old one
        // replaces the file a watch would follow.
        for folder in events.files.iter().filter_map(|f| f.parent()) {
            if folders.insert(folder.to_path_buf()) {
                debouncer
                    .watch(folder, RecursiveMode::NonRecursive)
                    .map_err(|e| format!("cannot watch {}: {e}", folder.display()))?;
            }
        }
        match loaded {
            Ok(desc) => {
                let (w, reloaded) = match world.take() {
                    Some(mut w) => {
                        let before = w.builds();
                        let r = w.reload(&desc);
                        (w, Some((r, before)))
                    }
                    None => (SceneWorld::new(&desc), None),
                };
                let w = world.insert(w);
                let scene = w.update();
                let s = scene.settings;
                let ms = start.elapsed().as_secs_f64() * 1e3;
                match reloaded {
                    Some((r, before)) => eprintln!(
                        "{name}: reloaded in {ms:.0} ms: {} objects changed, {} added, {} removed, {}; {}",
                        r.changed,
                        r.added,
                        r.removed,
                        match r.resources.is_empty() {
                            true => "no other change".to_string(),
                            false => format!("{} changed", r.resources.join(", ")),
                        },
                        w.builds().since(&before)
                    ),
                    None => eprintln!("{name}: loaded in {ms:.0} ms"),
                }
                // A new size: new viewers (the old window closes first).
                if viewers.as_ref().is_none_or(|v| (v.1, v.2, v.3) != (s.window, s.width, s.height)) {
                    viewers = None;
                }
                let (v, ..) = viewers.get_or_insert_with(|| {
                    (Viewers::open(&args.view, &name, &s), s.window, s.width, s.height)
                });
                let f = film.insert(Film::new(s.window.w, s.window.h));
                match passes(&scene, f, v, &events, &pool) {
                    Ended::Done => {
                        write(&args, f)?;
                        eprintln!("{name}: done, {} spp", s.spp);
                    }
                    Ended::Changed => continue,
                    Ended::Closed => break,
                }
            }
            Err(e) => {
                // The last good image stays on show.
                eprintln!("error: {e}");
                if let Some((v, ..)) = viewers.as_mut() {
                    v.note(&format!("error: {e}"));
                }
            }
        }
        // Until a file changes or the window closes.
        loop {
            if events.changed(Duration::from_millis(100)) {
                break;
            }
            if viewers.as_ref().is_some_and(|v| v.0.closed()) {
                return film.as_ref().map_or(Ok(()), |f| write(&args, f));
            }
        }
    }
    film.as_ref().map_or(Ok(()), |f| write(&args, f))
}
