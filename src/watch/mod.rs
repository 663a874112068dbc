//! `pathwave watch SCENE.ron`: renders progressively into the window (or tev) and, whenever the
//! scene file or a file it loads changes, loads it again, updates the ECS world with what
//! changed (so that only what depends on it is rebuilt) and starts the passes again. A scene
//! with an error shows the error (file:line:col) and keeps the last good image. It takes the
//! flags of `render` that apply to it ([`WatchArgs`]) and loads scenes as `render` does.

pub mod events;

use crate::engine::guiding::Guiding;
use crate::engine::render_scene::{PixelWindow, RenderScene};
use crate::engine::world::SceneWorld;
use crate::integrator::{film::Film, guide_training, oracle, wavefront};
use crate::io::{self, LinearImage};
use crate::look::LookArgs;
use crate::render::args::{EngineArgs, Integrator, LogArgs, SceneArgs, TimeArgs};
use crate::render::load::load;
use crate::terminal::safe;
use crate::view::{self, Pass, ViewArgs, Viewers};
use events::{Events, normalize};
use notify_debouncer_full::new_debouncer;
use notify_debouncer_full::notify::RecursiveMode;
use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// `pathwave watch`'s arguments: those of `render` that apply to a watch (not its output's
/// denoising, AOVs, checkpoints or sample ranges, nor its profiling).
#[derive(clap::Args, Clone, Debug)]
pub struct WatchArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Also write the image here (.png or .exr) each time the passes finish, and when watch
    /// stops.
    #[arg(short, long, visible_alias = "outfile")]
    pub output: Option<PathBuf>,
    /// Where to show the render (the window when neither is given).
    #[command(flatten)]
    pub view: ViewArgs,
    /// The scene's settings the flags override, as `render`'s.
    #[command(flatten)]
    pub settings: SceneArgs,
    /// How samples are computed, as `render`'s.
    #[command(flatten)]
    pub engine: EngineArgs,
    /// The moment shown, as `render --time`.
    #[command(flatten)]
    pub time: TimeArgs,
    /// How the window and a PNG output show the image, as `render`'s.
    #[command(flatten)]
    pub look: LookArgs,
    /// What is logged, as `render`'s.
    #[command(flatten)]
    pub log: LogArgs,
}

/// How long file events are gathered into one reload (an editor's save is several events).
const DEBOUNCE: Duration = Duration::from_millis(100);
/// The longest pass: edits are noticed between passes.
const MAX_PASS: Duration = Duration::from_millis(500);

/// How a run of passes ended.
enum Ended {
    /// All the samples are in.
    Done,
    /// A file changed.
    Changed,
    /// The window was closed.
    Closed,
}

/// Renders `scene` in passes into `film`, showing each, until all its samples are in, a file
/// changes or the window closes.
fn passes(
    scene: &RenderScene,
    film: &mut Film,
    viewers: &mut Viewers,
    events: &Events,
    engine: EngineArgs,
    pool: &rayon::ThreadPool,
) -> Ended {
    // Path guiding learns its guide first, once for each version of the scene; the preview's
    // samples all render with the last stage's guide (training's images are set aside: the
    // passes are the viewer's).
    let trained;
    let scene = match scene.settings.guiding {
        Guiding::On => {
            let opts = wavefront::Options { batch: engine.batch as usize, ..Default::default() };
            let last = guide_training::stage_of(scene.settings.spp.max(1) - 1);
            let mut training = pool.install(|| guide_training::train(scene, opts, last, &|_| {}));
            trained = RenderScene { guide: training.guides.pop().flatten(), ..scene.clone() };
            &trained
        }
        Guiding::Off => scene,
    };
    let target = scene.settings.spp;
    let (mut pass, mut number) = (1, 0);
    while film.spp < target {
        if events.changed(Duration::ZERO) {
            return Ended::Changed;
        }
        let start = Instant::now();
        let range = film.spp..(film.spp + pass).min(target);
        let k = range.len();
        let part = pool.install(|| match engine.integrator {
            Integrator::Oracle => oracle::render_samples(scene, range, &|_, _| {}),
            Integrator::Wavefront => {
                let opts = wavefront::Options { batch: engine.batch as usize, ..Default::default() };
                wavefront::render_samples(scene, opts, range, &|_, _| {}).0
            }
        });
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
            let img = LinearImage { width: film.width, height: film.height, pixels: film.mean() };
            io::write(out, &img, &args.look.look()).map(drop)
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
    // Flags no scene makes right fail at once; a scene beyond the bounds is reported like any
    // error in it, and the watch waits for the fix.
    args.settings.check()?;
    let time = args.time.checked()?;
    let pool = crate::pool(args.engine.threads)?;
    let (tx, rx) = mpsc::channel();
    let mut debouncer = new_debouncer(DEBOUNCE, None, tx).map_err(|e| format!("cannot watch files: {e}"))?;
    let scene_file =
        normalize(&std::path::absolute(&args.scene).map_err(|e| format!("{}: {e}", args.scene.display()))?);
    let mut events = Events { rx, files: BTreeSet::from([scene_file.clone()]) };
    let mut folders = BTreeSet::new();
    // Watched folders that were removed: their watch went with them, so they are looked for
    // until they are back (a checkout, a sync tool, `rm -r` and a copy).
    let mut missing = BTreeSet::new();
    let mut world: Option<SceneWorld> = None;
    let mut viewers: Option<(Viewers, PixelWindow, u32, u32)> = None;
    let mut film: Option<Film> = None;
    let name = args.scene.display().to_string();
    loop {
        let start = Instant::now();
        let loaded = load(&args.scene, &args.settings);
        // The files of the frame at --time (grid sequences') are watched too.
        let frame_files = |desc: &crate::engine::scene::SceneDesc| {
            let frame = crate::render::args::frame_at(desc, time).unwrap_or(0);
            desc.frame_files(frame)
        };
        if let Ok(desc) = &loaded {
            let frame = frame_files(desc).into_iter().filter_map(|f| std::path::absolute(f).ok());
            events.files =
                desc.inputs.iter().map(|f| normalize(&f.path)).chain(frame.map(|f| normalize(&f))).collect();
        }
        // `-o` must not name a file the scene reads (it would reload for ever): an error in the
        // scene like any other, until either changes.
        let loaded = loaded.and_then(|desc| match &args.output {
            Some(out) => io::Inputs::of(&desc).and(frame_files(&desc)).check(out).map(|()| desc),
            None => Ok(desc),
        });
        // Folders, not files: an editor that saves by renaming a new file over the old one
        // replaces the file a watch would follow.
        for folder in events.files.iter().filter_map(|f| f.parent()) {
            if !folders.contains(folder) && !missing.contains(folder) {
                match folder.is_dir() {
                    true => debouncer
                        .watch(folder, RecursiveMode::NonRecursive)
                        .map_err(|e| format!("cannot watch {}: {e}", folder.display()))?,
                    false => {
                        missing.insert(folder.to_path_buf());
                        continue;
                    }
                }
                folders.insert(folder.to_path_buf());
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
                    None => (crate::render::load::world(&desc, &args.scene, &args.settings), None),
                };
                let w = world.insert(w);
                // As `render --time` (the shutter may have changed).
                let shutter = crate::render::args::shutter_at(&desc, time);
                w.set_time(shutter.0, shutter.1);
                let frame = crate::render::args::frame_at(&desc, time);
                if let Ok(frame) = frame {
                    w.set_frame(frame);
                }
                match frame.and_then(|_| w.update_checked()) {
                    Err(e) => show_error(&mut viewers, &e),
                    Ok(scene) => {
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
                            (
                                Viewers::open(&args.view, &name, &s, args.look.look()),
                                s.window,
                                s.width,
                                s.height,
                            )
                        });
                        let f = film.insert(Film::new(s.window.w, s.window.h));
                        match passes(&scene, f, v, &events, args.engine, &pool) {
                            Ended::Done => {
                                write(&args, f)?;
                                eprintln!("{name}: done, {} spp", s.spp);
                            }
                            Ended::Changed => continue,
                            Ended::Closed => break,
                        }
                    }
                }
            }
            Err(e) => show_error(&mut viewers, &e),
        }
        // Until a file changes, a removed folder is back, or the window closes.
        loop {
            if events.changed(Duration::from_millis(100)) {
                break;
            }
            let gone: Vec<PathBuf> = folders.iter().filter(|f| !f.is_dir()).cloned().collect();
            for folder in gone {
                folders.remove(&folder);
                let _ = debouncer.unwatch(&folder);
                let shown = safe(&folder.display().to_string());
                eprintln!("watch: the folder {shown} was removed: waiting for it to come back");
                missing.insert(folder);
            }
            if let Some(back) = missing.iter().find(|f| f.is_dir()).cloned() {
                missing.remove(&back);
                debouncer
                    .watch(&back, RecursiveMode::NonRecursive)
                    .map_err(|e| format!("cannot watch {}: {e}", back.display()))?;
                eprintln!("watch: the folder {} is back", safe(&back.display().to_string()));
                folders.insert(back);
                break;
            }
            if viewers.as_ref().is_some_and(|v| v.0.closed()) {
                return film.as_ref().map_or(Ok(()), |f| write(&args, f));
            }
        }
    }
    film.as_ref().map_or(Ok(()), |f| write(&args, f))
}

/// Reports an error in the scene (or in the frame it makes) on the terminal and in the window,
/// where the last good image stays on show.
fn show_error(viewers: &mut Option<(Viewers, PixelWindow, u32, u32)>, e: &str) {
    eprintln!("error: {}", crate::terminal::safe(e));
    if let Some((v, ..)) = viewers.as_mut() {
        v.note(&format!("error: {e}"));
    }
}
