//! One image from samples to its pixels, for `render` and for each frame of `animate`
//! (checkpoints and resuming, passes, previews, progress).

use super::args::{Checkpointing, How, Integrator};
use super::post_process::post_process;
use crate::checkpoint::{self, Checkpoint};
use crate::engine::filter::PixelFilter;
use crate::engine::guiding::Guiding;
use crate::engine::lighting::light_paths::{self, LightTracing};
use crate::engine::render_scene::{PixelWindow, RenderScene, SamplerKind};
use crate::engine::scene::LightSamplerKind;
use crate::engine::scene::files::InputFile;
use crate::integrator::{costs::PixelCosts, film::Film, guide_training, oracle, wavefront};
use crate::io::{self, LinearImage};
use crate::view::{self, Viewers};
use std::path::Path;
use std::time::Instant;

/// What identifies a render's samples: the checkpoint key (a hash of the bytes of every file the
/// scene's load read, as it read them, and of every setting that changes a sample) and those
/// settings as text, so that a checkpoint of other settings is refused with the ones that
/// differ.
pub struct RenderId {
    /// The checkpoint key.
    pub key: u64,
    /// The settings as text (`checkpoint::settings_text`).
    pub settings: String,
    /// The key of the whole image's render (the same but for the window, and with the samples
    /// per pixel): what path guiding's training learns from, whichever part of the image a run
    /// renders ([`crate::guide_file`]).
    pub whole_key: u64,
}

/// The [`RenderId`] of a render of the scene made from `inputs` (the files its load read, then
/// those its frame read: grid sequences') at `time`, its shutter open over `shutter` (seconds).
pub fn render_id(
    inputs: &[InputFile],
    scene: &RenderScene,
    how: &How,
    time: f32,
    shutter: (f32, f32),
) -> Result<RenderId, String> {
    let s = scene.settings;
    let w = &s.window;
    // The filter only where it is not the box, and the light sampler where it is not `Auto`,
    // so that earlier checkpoints keep their key; a splatted filter says so (the samples of
    // earlier checkpoints sampled its offsets).
    let filter = (s.filter != PixelFilter::Box).then(|| match s.filter.splats() {
        true => ("filter", format!("{}, splatted", s.filter.describe())),
        false => ("filter", s.filter.describe()),
    });
    let lights = (s.light_sampler != LightSamplerKind::Auto)
        .then(|| ("light_sampler", format!("{:?}", s.light_sampler)));
    // Guiding says how many of its samples train (the checkpoints of versions whose training
    // was apart from the samples hold other samples).
    let guiding = (s.guiding != Guiding::Off)
        .then(|| ("guiding", format!("{:?}, {} training stages", s.guiding, guide_training::PASSES)));
    // Light tracing says where sharp lobes start (the paths it takes).
    let light_tracing = (s.light_tracing != LightTracing::Off).then(|| {
        ("light_tracing", format!("{:?}, sharp below alpha {}", s.light_tracing, light_paths::SHARP_ALPHA))
    });
    let settings_of = |w: &PixelWindow| {
        checkpoint::settings_text(
            &[
                ("size", format!("{}x{}", s.width, s.height)),
                ("window", format!("{}x{} at {},{}", w.w, w.h, w.x0, w.y0)),
                ("seed", s.seed.to_string()),
                ("max_depth", s.max_depth.to_string()),
                ("rr_depth", s.rr_depth.to_string()),
                ("clamp", format!("{:?}", s.clamp)),
                ("time", time.to_string()),
                ("shutter", format!("{} to {}", shutter.0, shutter.1)),
                ("integrator", format!("{:?}", how.integrator)),
                ("sampler", format!("{:?}", s.sampler)),
                ("defines", format!("{:?}", how.defines)),
            ]
            .into_iter()
            .chain(filter.clone())
            .chain(lights.clone())
            .chain(guiding.clone())
            .chain(light_tracing.clone())
            .collect::<Vec<_>>(),
        )
    };
    let settings = settings_of(w);
    if settings.len() > checkpoint::MAX_SETTINGS_BYTES {
        return Err(format!(
            "the -D values take {} bytes; at most {} fit in a checkpoint",
            settings.len(),
            checkpoint::MAX_SETTINGS_BYTES
        ));
    }
    // The files in path order, by content only: a scene moved with its files keeps its key.
    let loaded: Vec<u8> = inputs.iter().flat_map(|f| f.hash.to_le_bytes()).collect();
    // The whole image's, and its samples per pixel (which the sample pattern is stratified
    // for: training's samples depend on it).
    let whole =
        settings_of(&PixelWindow { x0: 0, y0: 0, w: s.width, h: s.height }) + &format!("spp: {}\n", s.spp);
    Ok(RenderId {
        key: checkpoint::key(&loaded, &settings),
        settings,
        whole_key: checkpoint::key(&loaded, &whole),
    })
}

/// What a layered EXR's header records of a render: pathwave's version, the checkpoint key (a
/// hash of the scene file and the settings that change the image), samples per pixel and seed.
/// Not the render time: the same render gives the same bytes.
pub fn metadata(key: u64, scene: &RenderScene, r: &Rendered) -> Vec<(&'static str, String)> {
    vec![
        ("pathwave:version", env!("CARGO_PKG_VERSION").to_string()),
        ("pathwave:scene_key", format!("{key:016x}")),
        ("pathwave:spp", r.spp.to_string()),
        ("pathwave:seed", scene.settings.seed.to_string()),
    ]
}

/// Path guiding's training for `scene` (whose [`RenderId`] is `id`) up to stage `last`: read
/// from the guide `file` where it holds them (no films then, and no statistics), else learned
/// (with a progress bar unless quiet) and written there.
pub fn learn_guides(
    scene: &RenderScene,
    id: &RenderId,
    how: &How,
    last: u32,
    file: Option<&Path>,
    pool: &rayon::ThreadPool,
) -> Result<guide_training::Training, String> {
    if let Some(f) = file.filter(|f| f.exists())
        && let Some(guides) = stored_guides(f, id.whole_key, last, how.quiet)?
    {
        return Ok(guide_training::Training { guides, films: Vec::new(), stats: Default::default() });
    }
    let s = scene.settings;
    let started = Instant::now();
    let opts = wavefront::Options { batch: how.batch, timing: how.stats, ..Default::default() };
    let full = PixelWindow { x0: 0, y0: 0, w: s.width, h: s.height };
    let (tiles_x, tiles_y) = crate::integrator::tile::Tile::grid_of(&full);
    let total = guide_training::stage_start(last) as usize * (tiles_x * tiles_y) as usize;
    let bar = Progress::new(how.quiet, total, "Training");
    let training = pool.install(|| guide_training::train(scene, opts, last, &|done| bar.update(done)));
    bar.finish();
    if !how.quiet {
        let size = training.guides.last().and_then(|g| g.as_ref()).map_or((0, 0), |g| g.size());
        eprintln!(
            "guide learned in {:.2} s: {} cells, {} with directions",
            started.elapsed().as_secs_f64(),
            size.0,
            size.1
        );
    }
    if let Some(f) = file {
        crate::guide_file::save(f, id.whole_key, &training.guides)?;
    }
    Ok(training)
}

/// Where a checkpointed render keeps its guides when not told: beside the checkpoint.
pub fn guides_beside(ckpt: &Path) -> std::path::PathBuf {
    let mut name = ckpt.as_os_str().to_owned();
    name.push(".guides");
    name.into()
}

/// The guides of the training stages up to `last` in the guide file `path`, where it holds
/// those of the render whose whole image's key is `key`; `None` (said unless `quiet`) where
/// it holds another render's or fewer stages, which training then writes over.
fn stored_guides(
    path: &Path,
    key: u64,
    last: u32,
    quiet: bool,
) -> Result<Option<crate::guide_file::Guides>, String> {
    let (stored, mut guides) = crate::guide_file::load(path)?;
    let note = |why: &str| {
        if !quiet {
            eprintln!("{}: {why}; learning them again", path.display());
        }
    };
    if stored != key {
        note("the guides of another scene or other settings");
        return Ok(None);
    }
    if guides.len() <= last as usize {
        note(&format!("guides of {} training stages, where {} are needed", guides.len(), last + 1));
        return Ok(None);
    }
    guides.truncate(last as usize + 1);
    if !quiet {
        eprintln!("{}: the guides read (no training)", path.display());
    }
    Ok(Some(guides))
}

/// One rendered image, before it is written.
pub struct Rendered {
    /// The image (denoised when asked for).
    pub img: LinearImage,
    /// The AOVs an EXR output holds as layers.
    pub layers: Vec<io::ExrLayer<'static>>,
    /// Samples per pixel in it.
    pub spp: u32,
    /// Samples rendered by this run (not those resumed).
    pub new_samples: f64,
    /// Per-stage statistics (wavefront).
    pub stats: Option<wavefront::Stats>,
    /// What each pixel cost (wavefront, with `--stats` or the cost AOVs), over the samples
    /// this run rendered.
    pub costs: Option<PixelCosts>,
    /// Seconds, from the start of rendering to the image.
    pub secs: f64,
    /// NaN/Inf samples discarded.
    pub non_finite: u64,
    /// With `--stats`, each pixel's mean luminance as rendered (before denoising).
    pub luminance: Vec<f32>,
}

/// Renders `scene` into the image meant for `output`, as `render` and each frame of `animate`
/// do: from its checkpoint when resuming, in passes that save checkpoints (and, with
/// `partial`, the image so far) when asked, or show the image to `viewers` (passes of 1, 2, 4,
/// ... spp, until a viewer stops the render), then denoised or with guides when asked.
#[expect(
    clippy::too_many_arguments,
    reason = "one image's scene, identity, output, settings and viewers, as `render` and `animate` give them"
)]
pub fn render_image(
    scene: &RenderScene,
    id: &RenderId,
    output: &Path,
    how: &How,
    checkpointing: Option<&Checkpointing>,
    samples: Option<(u32, u32)>,
    pool: &rayon::ThreadPool,
    partial: bool,
    viewers: &mut Viewers,
) -> Result<Rendered, String> {
    let start = Instant::now();
    let s = scene.settings;
    let ckpt_path = checkpoint::path_for(output);
    // The sample indices this run owns: all of them, or a range with --samples (one machine's
    // share of a frame, added to the others by `pathwave merge`).
    let (lo, hi) = samples.unwrap_or((0, s.spp));
    if hi > s.spp {
        return Err(format!("--samples {lo}..{hi} goes beyond the {} samples per pixel", s.spp));
    }
    let part = (lo, hi) != (0, s.spp);
    let mut film = Film::new(s.window.w, s.window.h);
    if checkpointing.is_some_and(|c| c.resume) {
        if ckpt_path.exists() {
            let ckpt = Checkpoint::load(&ckpt_path)?;
            if ckpt.key != id.key {
                return Err(format!(
                    "{}: the checkpoint is of another scene or other settings ({}); remove it or \
                     render without --resume",
                    ckpt_path.display(),
                    checkpoint::mismatch("the checkpoint", &ckpt.settings, "this render", &id.settings)
                ));
            }
            if (ckpt.film.width, ckpt.film.height) != (s.window.w, s.window.h) {
                return Err(format!(
                    "{}: the checkpoint holds a {}x{} image, this render makes {}x{}",
                    ckpt_path.display(),
                    ckpt.film.width,
                    ckpt.film.height,
                    s.window.w,
                    s.window.h
                ));
            }
            if ckpt.first_sample != lo {
                return Err(format!(
                    "{}: the checkpoint holds samples from {}, this run renders {lo}..{hi}",
                    ckpt_path.display(),
                    ckpt.first_sample
                ));
            }
            // Sobol and independent samples do not depend on the count: a render extended to
            // more samples is the bits of a fresh one. Stratified patterns do.
            if ckpt.target_spp != s.spp && lo + ckpt.film.spp < hi && s.sampler == SamplerKind::Stratified {
                eprintln!(
                    "note: the checkpoint was started for {} spp: samples {}..{hi} are stratified for {} \
                     (unbiased, but not the bits of a fresh {}-spp render)",
                    ckpt.target_spp,
                    lo + ckpt.film.spp,
                    s.spp,
                    s.spp
                );
            }
            let (have, want) = (ckpt.film.spp, hi - lo);
            if have > want {
                return Err(format!(
                    "{}: the checkpoint holds {have} samples per pixel, more than the {want} asked for; \
                     ask for at least {have} with --spp (or render without --resume)",
                    ckpt_path.display()
                ));
            }
            if have == want {
                eprintln!("{}: complete ({have} spp); writing its image", ckpt_path.display());
            } else if part {
                eprintln!("{}: resuming samples {lo}..{hi} at {}", ckpt_path.display(), lo + have);
            } else {
                eprintln!("{}: resuming at {have} of {} spp", ckpt_path.display(), s.spp);
            }
            film = ckpt.film;
        } else if !how.quiet {
            eprintln!("{}: no checkpoint yet, starting at sample {lo}", ckpt_path.display());
        }
    }
    // Path guiding trains first: the stages over the whole image that learn the guides of the
    // samples asked for (the same for every share and pass of the image), unless a guide file
    // holds them.
    let guided = s.guiding == Guiding::On && lo + film.spp < hi;
    // Training's passes count in `--stats` with the render's.
    let mut trained_stats = None;
    let stages: Vec<RenderScene> = match guided {
        true => {
            let last = guide_training::stage_of(hi - 1);
            let file = how.guide_file.clone().or_else(|| checkpointing.map(|_| guides_beside(&ckpt_path)));
            let training = learn_guides(scene, id, how, last, file.as_deref(), pool)?;
            // A plain render of the whole image keeps the stages' images: they are its
            // samples (not the oracle's: it may differ from the wavefront in the last bit).
            let whole = s.window == PixelWindow { x0: 0, y0: 0, w: s.width, h: s.height };
            let plain = !how.guides() && !how.costs() && checkpointing.is_none() && !viewers.progressive();
            if whole && plain && how.integrator == Integrator::Wavefront {
                for (k, part) in (0..).zip(training.films) {
                    if lo + film.spp == guide_training::stage_start(k)
                        && guide_training::stage_start(k + 1) <= hi
                    {
                        film.absorb(part);
                    }
                }
            }
            trained_stats = (last > 0).then_some(training.stats);
            training.guides.into_iter().map(|guide| RenderScene { guide, ..scene.clone() }).collect()
        }
        false => Vec::new(),
    };
    // The scene a pass starting at sample `first` renders, and where its stage ends.
    let stage = |first: u32| match guided {
        true => {
            let k = guide_training::stage_of(first);
            let end = if k < guide_training::PASSES { guide_training::stage_start(k + 1) } else { u32::MAX };
            (&stages[k as usize], end)
        }
        false => (scene, u32::MAX),
    };
    let first_spp = film.spp;
    let (tiles_x, tiles_y) = crate::integrator::tile::Tile::grid_of(&s.window);
    let tiles = (tiles_x * tiles_y) as usize;
    let bar = Progress::new(how.quiet, (hi - lo - film.spp) as usize * tiles, "Rendering");
    let mut stats: Option<wavefront::Stats> = trained_stats;
    let mut last_save = Instant::now();
    // Without checkpoints or viewers, one pass; with checkpoints, passes sized to take about
    // half the interval (measured on the pass before), starting with one sample per pixel; with
    // viewers, no longer than doubling the samples (and at most `view::MAX_PASS`).
    let mut pass = if checkpointing.is_some() || viewers.progressive() { 1 } else { hi - lo };
    let mut passes = 0;
    while lo + film.spp < hi {
        let next = lo + film.spp;
        let (scene, stage_end) = stage(next);
        let range = next..(next + pass).min(hi).min(stage_end);
        let k = range.len();
        let before = (film.spp - first_spp) as usize * tiles;
        let progress = |done: usize, _| bar.update(before + done * k);
        let pass_start = Instant::now();
        let span = tracing::info_span!("pass", first = range.start, samples = k).entered();
        let (part, st) = pool.install(|| match how.integrator {
            Integrator::Oracle => (oracle::render_samples(scene, range.clone(), &progress), None),
            Integrator::Wavefront => {
                let opts = wavefront::Options {
                    batch: how.batch,
                    guides: how.guides(),
                    timing: how.stats,
                    costs: how.costs(),
                    train: None,
                };
                let (film, stats) = wavefront::render_samples(scene, opts, range.clone(), &progress);
                (film, Some(stats))
            }
        });
        drop(span);
        let secs = pass_start.elapsed().as_secs_f64();
        let msps = s.window.len() as f64 * k as f64 / secs.max(1e-9) / 1e6;
        tracing::info!(
            "pass: samples {}..{} of {} in {secs:.2} s, {msps:.3} M samples/s",
            range.start,
            range.end,
            s.spp
        );
        bar.pass_done(range.start, range.end, s.spp, secs, msps);
        film.absorb(part);
        stats = match (stats, st) {
            (Some(a), Some(b)) => Some(a.merge(b)),
            (a, b) => a.or(b),
        };
        passes += 1;
        let per_sample = pass_start.elapsed().as_secs_f64() / k as f64;
        let left = hi - lo - film.spp;
        let go_on = !viewers.progressive() || {
            let eta = std::time::Duration::from_secs_f64(per_sample * left as f64);
            viewers.show(&film, &view::Pass { number: passes, spp: film.spp, target: hi - lo, eta })
        };
        if let Some(c) = checkpointing {
            let finished = lo + film.spp == hi;
            if last_save.elapsed().as_secs_f64() >= c.every || finished || !go_on {
                // The image so far first: once a checkpoint exists, so does an image.
                if !finished && partial && go_on {
                    io::write(
                        output,
                        &LinearImage { width: film.width, height: film.height, pixels: film.mean() },
                        &how.look,
                    )?;
                }
                let settings = id.settings.clone();
                Checkpoint { key: id.key, settings, target_spp: s.spp, first_sample: lo, film: film.clone() }
                    .save(&ckpt_path)?;
                last_save = Instant::now();
            }
            pass = ((c.every / 2.0 / per_sample.max(1e-9)) as u32).clamp(1, s.spp);
        }
        if viewers.progressive() {
            let doubling = view::next_pass(film.spp, left, per_sample, view::MAX_PASS);
            pass = if checkpointing.is_some() { pass.min(doubling) } else { doubling };
        }
        if !go_on {
            eprintln!("stopped at {} of {} spp: the preview window was closed", film.spp, hi - lo);
            break;
        }
    }
    let secs = start.elapsed().as_secs_f64();
    bar.finish();
    if how.verbose {
        for &(i, n) in &film.non_finite_pixels() {
            eprintln!("NaN/Inf: {n} samples discarded at pixel {},{}", i % film.width, i / film.width);
        }
    }
    let img = LinearImage { width: film.width, height: film.height, pixels: film.mean() };
    let luminance = match how.stats {
        true => img.pixels.iter().map(|&c| crate::engine::math::luminance(c)).collect(),
        false => Vec::new(),
    };
    let (img, layers) = match how.guides() || !how.aov.is_empty() {
        true => post_process(scene, &film, lo..lo + film.spp, img, output, how, pool)?,
        false => (img, Vec::new()),
    };
    Ok(Rendered {
        img,
        layers,
        spp: film.spp,
        new_samples: s.window.len() as f64 * (film.spp - first_spp) as f64,
        stats,
        non_finite: film.non_finite(),
        costs: film.costs,
        secs,
        luminance,
    })
}

/// Render progress: an `indicatif` bar with ETA on a terminal. When stderr is not a terminal
/// the bar hides itself and each pass prints one line instead (`pass_done`), so that
/// `2> log.txt` stays readable.
struct Progress {
    bar: indicatif::ProgressBar,
    lines: bool,
}

impl Progress {
    /// A bar of `total` steps, saying `what` it counts (`Rendering`, `Training`).
    fn new(quiet: bool, total: usize, what: &str) -> Self {
        use std::io::IsTerminal;
        let bar = match quiet {
            true => indicatif::ProgressBar::hidden(),
            false => indicatif::ProgressBar::new(total as u64),
        };
        bar.set_style(
            indicatif::ProgressStyle::with_template(&format!(
                "{what} [{{bar:40}}] {{percent:>3}}% {{elapsed}} elapsed, ETA {{eta}}"
            ))
            .expect("a valid template")
            .progress_chars("=> "),
        );
        Self { bar, lines: !quiet && !std::io::stderr().is_terminal() }
    }

    /// `done` of the whole render's tile passes are done.
    fn update(&self, done: usize) {
        self.bar.set_position(done as u64);
    }

    /// One pass finished (a line when there is no bar, unless the info log just said it).
    fn pass_done(&self, first: u32, end: u32, spp: u32, secs: f64, msps: f64) {
        if self.lines && !tracing::enabled!(tracing::Level::INFO) {
            eprintln!("pass: samples {first}..{end} of {spp} in {secs:.2} s, {msps:.3} M samples/s");
        }
    }

    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
