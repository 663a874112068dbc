//! The flags the render commands share (clap derive), and the settings derived from them:
//! [`SceneArgs`] override a scene's `render` settings (`render`, `animate`, `watch`, and `farm
//! slurm`'s tasks), [`EngineArgs`] choose how samples are computed, [`RenderArgs`] are every flag
//! of `render` that `animate` and `farm slurm` take too, and [`How`] is what a render reads of
//! them.

use crate::MAX_THREADS;
use crate::denoiser::Denoiser;
use crate::engine::guiding::Guiding;
use crate::engine::lighting::light_paths::LightTracing;
use crate::engine::render_scene::SamplerKind;
use crate::engine::scene::{FilterDesc, LightSamplerKind, SceneDesc};
use crate::look::{Look, LookArgs};
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};

/// Which integrator renders (`--integrator`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Integrator {
    /// Stages over structure-of-arrays queues (default).
    Wavefront,
    /// The reference path tracer, one path at a time.
    Oracle,
}

/// What `render`, `animate` and `watch` override of a scene's `render` settings (and its
/// parameters).
#[derive(clap::Args, Clone, Debug)]
pub struct SceneArgs {
    /// Size, samples and their seed and sampler.
    #[command(flatten)]
    pub image: ImageArgs,
    /// Maximum bounces (overrides the scene).
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// How a light is chosen: power (a table fixed for the scene), tree (the light tree: by
    /// each point's view of the lights) or auto (the tree with two lights or more; default)
    /// (overrides the scene).
    #[arg(long, value_name = "power|tree|auto")]
    pub light_sampler: Option<LightSamplerKind>,
    /// Path guiding: on (the render's first samples, in stages of 1, 2 and 4 per pixel over the
    /// whole image, learn where light comes from, and Lambertian surfaces draw half their
    /// directions from what was learned) or off (default) (overrides the scene).
    #[arg(long, value_name = "on|off")]
    pub guiding: Option<Guiding>,
    /// Light tracing: on (the caustics that point, spot, directional and projector lights
    /// throw onto rough surfaces through mirrors, glass and sharp lobes are traced from the
    /// lights and connected to the camera) or off (default) (overrides the scene).
    #[arg(long, value_name = "on|off")]
    pub light_tracing: Option<LightTracing>,
    /// Scale samples down so that no component exceeds MAX (biased; off by default).
    #[arg(long, value_name = "MAX")]
    pub clamp: Option<f32>,
    /// Render only the window x0..x1, y0..y1 (fractions of the image, as pbrt-v4's crop
    /// window): the output has the window's size and the bits of those pixels in the whole
    /// image.
    #[arg(long, value_name = "X0,X1,Y0,Y1", value_delimiter = ',')]
    pub crop: Option<Vec<f32>>,
    /// Set a parameter the scene declares (`parameters: { "NAME": "default" }`, used as
    /// `$NAME`) to VALUE, RON text; repeatable.
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// Every file the scene reads (includes, meshes, images, spectra) must lie in DIR once links
    /// are resolved, for a scene from elsewhere (`farm slurm`: the scene's folder by default).
    #[arg(long, value_name = "DIR")]
    pub assets_under: Option<PathBuf>,
}

/// How `render`, `animate` and `watch` compute samples (not what the samples are: every choice
/// gives the same image, or the oracle's).
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct EngineArgs {
    /// Which integrator renders.
    #[arg(long, value_enum, default_value_t = Integrator::Wavefront)]
    pub integrator: Integrator,
    /// Paths in flight per worker (wavefront), 1 to 65536.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub batch: u32,
    /// Worker threads, 1 to 1024 (default: all cores).
    #[arg(short, long, visible_alias = "nthreads",
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=MAX_THREADS))]
    pub threads: Option<usize>,
}

/// What `render` and `animate` share: every setting that changes a sample or an output.
#[derive(clap::Args, Clone, Debug)]
pub struct RenderArgs {
    /// The scene's settings they override.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// How samples are computed.
    #[command(flatten)]
    pub engine: EngineArgs,
    /// Denoise with `oidn` (Intel Open Image Denoise, guided by albedo and normals; a build with
    /// `--features oidn`, where a bare --denoise means it) or `atrous` (pathwave's à-trous filter,
    /// guided by albedo, normals and the per-pixel variance; a bare --denoise in other builds):
    /// the output gets the denoised image, NAME.noisy.EXT the render as it came.
    #[arg(long, value_name = "oidn|atrous", num_args = 0..=1,
          default_missing_value = Denoiser::DEFAULT_NAME, value_parser = Denoiser::parse)]
    pub denoise: Option<Denoiser>,
    /// Also write AOVs, a comma-separated list of albedo, normal, depth, variance, noisy, and
    /// what each pixel cost: time, paths, bounces, rays (a bare `--aov`: albedo,normal). An EXR
    /// output holds them as layers of the same file (`albedo.R`, `normal.X`, `depth.Z`,
    /// `variance.R`, `noisy.R`, `time.Y`, ...); beside a PNG, albedo and normal go to
    /// NAME.albedo.png and NAME.normal.png (normals mapped to 0.5 + 0.5 n), and the others need
    /// an EXR. `noisy` (the render before denoising) needs --denoise; the costs, the wavefront.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        num_args = 0..,
        default_missing_values = ["albedo", "normal"],
        value_name = "AOV,.."
    )]
    pub aov: Option<Vec<Aov>>,
    /// Render in passes and, every SECS seconds, save the samples so far to OUT.ckpt (render:
    /// and the image so far to OUT; animate: a killed frame resumes from its checkpoint). The
    /// checkpoint is kept at the end, to add samples later.
    #[arg(long, value_name = "SECS")]
    pub checkpoint_every: Option<f64>,
    /// With path guiding, read the learned guides from FILE when it holds those of this scene
    /// and these settings (the whole image's, whatever --crop or --samples), else learn them
    /// and write them there: a farm's shares and a resumed render then train once. A render
    /// with --checkpoint-every keeps them beside its checkpoint (OUT.ckpt.guides) unless told.
    #[arg(long, value_name = "FILE")]
    pub guide_file: Option<std::path::PathBuf>,
    /// How 8-bit outputs show the image.
    #[command(flatten)]
    pub look: LookArgs,
    /// What is logged.
    #[command(flatten)]
    pub log: LogArgs,
    /// Where the time goes.
    #[command(flatten)]
    pub profile: ProfileArgs,
}

impl RenderArgs {
    /// How to render.
    pub fn how(&self) -> How {
        How {
            defines: self.scene.define.clone(),
            integrator: self.engine.integrator,
            batch: self.engine.batch as usize,
            stats: self.profile.stats,
            threads: self.engine.threads,
            quiet: self.log.quiet,
            verbose: self.log.verbose > 0,
            denoise: self.denoise,
            aov: self.aov.clone().unwrap_or_default(),
            look: self.look.look(),
            guide_file: self.guide_file.clone(),
        }
    }

    /// `--checkpoint-every`, a number of seconds >= 0.
    pub fn checkpoint_every(&self) -> Result<Option<f64>, String> {
        match self.checkpoint_every {
            Some(s) if !(s >= 0.0 && s.is_finite()) => {
                Err(format!("--checkpoint-every takes a number of seconds >= 0, not {s}"))
            }
            other => Ok(other),
        }
    }
}

/// `--time`: the moment `render` and `watch` show.
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct TimeArgs {
    /// Evaluate keyframes at this time (seconds). A scene whose `animation` sets a shutter
    /// opens it here for that fraction of a frame, as `animate`'s frame at this time; else the
    /// camera's shutter opens and closes relative to it. Grid sequences read the files of
    /// `animate`'s frame at this time (frame 0 at time 0).
    #[arg(long, default_value_t = 0.0)]
    pub time: f32,
}

/// The shutter interval `render --time` and `watch` show at `time`: a scene whose `animation`
/// sets a shutter opens it at `time` for that fraction of a frame, as `animate`'s frame at
/// `time` does (so the two give the same image); else the camera's shutter, relative to `time`.
pub fn shutter_at(desc: &SceneDesc, time: f32) -> (f32, f32) {
    let a = &desc.animation;
    match a.shutter.0 > 0.0 {
        true => (time, time + a.shutter.0 / a.fps.0),
        false => (time + desc.camera.shutter.0, time + desc.camera.shutter.1),
    }
}

/// The frame whose files (grid sequences') `render --time` and `watch` read at `time`: the one
/// `animate` renders at `time` at the scene's `animation.fps` (24 by default), the last whose
/// shutter opened at or before it; frame 0 at the default time 0, so a still reads frame 0. A
/// scene without grid sequences reads no frame's files: 0.
pub fn frame_at(desc: &SceneDesc, time: f32) -> Result<u32, String> {
    match desc.grid_sequences().next() {
        None => Ok(0),
        Some((_, s)) => crate::engine::format::frames::frame_at(time, desc.animation.fps.0).map_err(|e| {
            format!(
                "--time {time}: {e}, and the grid sequence \"{}\" has a file per frame from frame 0",
                s.written
            )
        }),
    }
}

impl TimeArgs {
    /// `--time`, seconds in [-1e7, 1e7].
    pub fn checked(self) -> Result<f32, String> {
        match self.time.is_finite() && self.time.abs() <= 1e7 {
            true => Ok(self.time),
            false => Err(format!("--time takes seconds in [-1e7, 1e7], not {}", self.time)),
        }
    }
}

/// How much `render`, `animate` and `watch` say on stderr.
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct LogArgs {
    /// More on stderr: -v logs the scene, BVH builds, passes and frames (info) and lists the
    /// pixels that discarded NaN/Inf samples; -vv adds debug logs and every span's duration.
    /// RUST_LOG, when set, chooses the log levels instead.
    #[arg(short, long, action = clap::ArgAction::Count)]
    pub verbose: u8,
    /// Less on stderr: no progress or per-frame lines, only warnings, errors and the summary.
    #[arg(short, long, conflicts_with = "verbose")]
    pub quiet: bool,
}

/// Where `render` and `animate` say where the time goes.
#[derive(clap::Args, Clone, Debug)]
pub struct ProfileArgs {
    /// Print per-stage statistics (wavefront): time share, items, rate and calls, and queue
    /// occupancy (`animate`: a line per frame with its scene update and stage shares, then
    /// the table for the sequence).
    #[arg(long)]
    pub stats: bool,
    /// Write a Chrome trace (open it in ui.perfetto.dev): scene load, ECS systems, frames,
    /// passes and tiles as spans, each tile's stages with their items, and counter tracks.
    #[arg(long, value_name = "FILE.json")]
    pub trace: Option<PathBuf>,
}

/// The image's size and samples, which `render`, `animate` and `watch` may override of a
/// scene's `render` settings.
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct ImageArgs {
    /// Samples per pixel (overrides the scene).
    #[arg(long)]
    pub spp: Option<NonZeroU32>,
    /// Image width (overrides the scene).
    #[arg(long)]
    pub width: Option<NonZeroU32>,
    /// Image height (overrides the scene).
    #[arg(long)]
    pub height: Option<NonZeroU32>,
    /// Random seed (overrides the scene; every frame of a sequence uses it).
    #[arg(long)]
    pub seed: Option<u64>,
    /// How samples are made: sobol (default), stratified or independent (overrides the scene).
    #[arg(long)]
    pub sampler: Option<SamplerKind>,
    /// Pixel filter: box (default), tent, tent:RADIUS, gaussian or gaussian:STDDEV, in pixels,
    /// as Mitsuba 3's (overrides the scene's `render: (filter: ..)`).
    #[arg(long)]
    pub filter: Option<FilterDesc>,
}

/// `--checkpoint-every` and `--resume`.
pub struct Checkpointing {
    /// Seconds between checkpoints.
    pub every: f64,
    /// Start from the checkpoint file if there is one.
    pub resume: bool,
}

/// An image beside the render (`--aov`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Aov {
    /// Mean albedo of the first surface that is not a perfect mirror or glass (the denoiser's
    /// guide).
    Albedo,
    /// Its camera-facing shading normal, averaged (the denoiser's guide).
    Normal,
    /// Mean distance along the camera rays to the first surface (infinity where none).
    Depth,
    /// Variance of each pixel's mean, per channel.
    Variance,
    /// The render before denoising.
    Noisy,
    /// Seconds the pixel's samples cost: each stage's time shared out evenly among the rays or
    /// paths it took (as pbrt-v4's `--pixelstats` time).
    Time,
    /// Samples (paths) the pixel's costs cover: those this run rendered.
    Paths,
    /// Mean bounces of the pixel's paths.
    Bounces,
    /// Rays cast for the pixel: closest-hit and shadow rays.
    Rays,
}

impl Aov {
    /// Its name on the command line.
    pub fn name(self) -> String {
        use clap::ValueEnum;
        self.to_possible_value().map(|v| v.get_name().to_owned()).unwrap_or_default()
    }

    /// Whether the AOV is a cost the wavefront measures (`time`, `paths`, `bounces`, `rays`).
    pub fn is_cost(self) -> bool {
        matches!(self, Aov::Time | Aov::Paths | Aov::Bounces | Aov::Rays)
    }
}

impl How {
    /// Every file a render to `output` writes: the image; beside a PNG, NAME.albedo.png and
    /// NAME.normal.png for those AOVs; with `--denoise`, NAME.noisy.EXT unless the noisy image
    /// is a layer of the EXR; with `--stats`, the heat map of time per pixel NAME.time.png.
    /// (The checkpoint and the trace are the caller's to add.)
    pub fn files(&self, output: &Path) -> Vec<PathBuf> {
        let exr = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        let mut files = vec![output.to_owned()];
        if !exr {
            for (aov, tag) in [(Aov::Albedo, "albedo"), (Aov::Normal, "normal")] {
                if self.aov.contains(&aov) {
                    files.push(sibling(output, tag));
                }
            }
        }
        if self.denoise.is_some() && !(exr && self.aov.contains(&Aov::Noisy)) {
            files.push(sibling(output, "noisy"));
        }
        if self.stats {
            files.push(heat_map(output));
        }
        files
    }

    /// Whether the wavefront measures what each pixel costs: for `--stats` and the cost AOVs.
    pub fn costs(&self) -> bool {
        self.stats || self.aov.iter().any(|a| a.is_cost())
    }

    /// Whether the denoiser's guides are needed.
    pub fn guides(&self) -> bool {
        self.denoise.is_some() || self.aov.iter().any(|a| matches!(a, Aov::Albedo | Aov::Normal))
    }

    /// Refuses, before any work, AOVs that `output` cannot hold, that need `--denoise` or the
    /// wavefront, or that come twice.
    pub fn check_aovs(&self, output: &Path) -> Result<(), String> {
        let exr = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        for (i, &a) in self.aov.iter().enumerate() {
            let name = a.name();
            if self.aov[..i].contains(&a) {
                return Err(format!("--aov {name} is named twice"));
            }
            match a {
                Aov::Albedo | Aov::Normal | Aov::Noisy => {}
                _ if !exr => return Err(format!("{}: --aov {name} needs an .exr output", output.display())),
                _ => {}
            }
            if a == Aov::Noisy && self.denoise.is_none() {
                return Err("--aov noisy needs --denoise".into());
            }
            if a.is_cost() && self.integrator != Integrator::Wavefront {
                return Err(format!("--aov {name}: the wavefront integrator measures costs, not the oracle"));
            }
        }
        Ok(())
    }
}

/// What a render reads of [`RenderArgs`] besides the scene.
pub struct How {
    /// The -D parameter overrides (they change the scene, so they are in checkpoint keys).
    pub defines: Vec<String>,
    /// `-v`: list the pixels that discarded NaN/Inf samples.
    pub verbose: bool,
    /// `--denoise`.
    pub denoise: Option<Denoiser>,
    /// `--aov`.
    pub aov: Vec<Aov>,
    /// `--integrator`.
    pub integrator: Integrator,
    /// `--batch`.
    pub batch: usize,
    /// `--stats`: time the wavefront's stages, measure what each pixel costs and find the
    /// causes of the noise.
    pub stats: bool,
    /// `--threads`.
    pub threads: Option<usize>,
    /// `-q`: no progress bar or lines.
    pub quiet: bool,
    /// `--exposure` and `--view-transform`: how 8-bit outputs show the image.
    pub look: Look,
    /// `--guide-file`.
    pub guide_file: Option<std::path::PathBuf>,
}

/// The heat map of time per pixel that `--stats` writes beside the output NAME.EXT:
/// NAME.time.png.
pub fn heat_map(output: &Path) -> PathBuf {
    sibling(output, "time").with_extension("png")
}

/// The side file NAME.TAG.EXT beside the output NAME.EXT.
pub fn sibling(output: &Path, tag: &str) -> PathBuf {
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let ext = output.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default();
    output.with_file_name(format!("{stem}.{tag}.{ext}"))
}
