//! The command line's schema (clap derive): subcommands, their flags, and the settings the
//! render commands derive from them (`Overrides` of the scene, `How` to render).

use clap::{Parser, Subcommand};
use pathwave::denoiser::Denoiser;
use pathwave::engine::render_scene::SamplerKind;
use pathwave::view::ViewArgs;
use pathwave::{MAX_THREADS, farm};
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(name = "pathwave", version, about = "A physically based path tracer")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Render a RON scene to PNG (sRGB, clamped) or EXR (linear float).
    Render {
        /// The scene file.
        scene: PathBuf,
        /// Output image; the extension picks the format (.png or .exr).
        #[arg(short, long, visible_alias = "outfile")]
        output: PathBuf,
        #[command(flatten)]
        args: RenderArgs,
        /// Evaluate keyframes at this time (seconds); the camera's shutter opens and closes
        /// relative to it.
        #[arg(long, default_value_t = 0.0)]
        time: f32,
        /// Continue from OUT.ckpt if it exists (same scene and settings; the result has the
        /// bits of an uninterrupted render); checkpoints every 60 s unless --checkpoint-every.
        #[arg(long)]
        resume: bool,
        /// Render only sample indices A..B of each pixel (of --spp) and keep them in OUT.ckpt,
        /// for `pathwave merge` to add to the other parts; `auto`: this task's share, from a
        /// Slurm job array's or a Kubernetes Indexed Job's environment.
        #[arg(long, value_name = "A..B|auto")]
        samples: Option<String>,
        /// With `--samples auto`: the number of tasks (else SLURM_ARRAY_TASK_COUNT or
        /// PATHWAVE_SHARD_COUNT).
        #[arg(long, value_name = "N")]
        shard_count: Option<u32>,
        #[command(flatten)]
        view: ViewArgs,
    },
    /// Render a scene in passes into a window (or tev) and render it again whenever it or a
    /// file it loads changes; a scene with an error shows the error and keeps the last image.
    Watch(pathwave::watch::WatchArgs),
    /// Merge checkpoints holding disjoint sample ranges of one render (from `render
    /// --samples` on several machines) into its image, and OUT.ckpt when they are contiguous.
    Merge {
        /// Checkpoints (OUT.ckpt files) to merge.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        /// The image; the extension picks the format.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Render an animation sequence: one image per frame (`{frame:04}` in the output name), or
    /// an animated GIF when the output ends in .gif. Existing frames are skipped (empty files are rendered again).
    Animate {
        /// The scene file.
        scene: PathBuf,
        /// Output pattern, e.g. out/frame_{frame:04}.png (or .exr), or anim.gif.
        #[arg(short, long, visible_alias = "outfile")]
        output: String,
        /// Frames A..B (B excluded) or A..=B (default: 0..the scene's `animation.frames`).
        #[arg(long)]
        frames: Option<String>,
        /// Frames per second (default: the scene's, 24 if it has none).
        #[arg(long)]
        fps: Option<f32>,
        /// Shutter as a fraction of the frame interval, 0 = no motion blur (default: the
        /// scene's `animation.shutter`).
        #[arg(long)]
        shutter: Option<f32>,
        /// Render frames whose file already exists.
        #[arg(long)]
        overwrite: bool,
        /// Render only every N-th frame from the I-th (I/N, 0-based), so that N processes split
        /// the sequence (frame files only, not a GIF); `auto`: this task's, from a Slurm job
        /// array's or a Kubernetes Indexed Job's environment.
        #[arg(long, value_name = "I/N|auto")]
        shard: Option<String>,
        /// With `--shard auto`: the number of tasks (else SLURM_ARRAY_TASK_COUNT or
        /// PATHWAVE_SHARD_COUNT).
        #[arg(long, value_name = "N")]
        shard_count: Option<u32>,
        #[command(flatten)]
        args: RenderArgs,
    },
    /// Render on a cluster: shares of the work as tasks of a Slurm job array, then a job that
    /// checks and merges them.
    Farm {
        #[command(subcommand)]
        farm: FarmCommand,
    },
    /// Run time against error: render the scenes that have references at several sample
    /// counts with both integrators; print a markdown table, optionally write an SVG plot.
    Bench {
        /// Sample counts.
        #[arg(long, value_delimiter = ',', default_value = "4,16,64,256,1024")]
        spp: Vec<u32>,
        /// Folder of the reference EXRs.
        #[arg(long, default_value = "tests/references")]
        refs: PathBuf,
        /// Only these scenes (file stems, e.g. cornell).
        #[arg(long, value_delimiter = ',')]
        only: Vec<String>,
        /// Paths in flight per worker (wavefront).
        #[arg(long, default_value_t = 256)]
        batch: usize,
        /// Write a log-log plot of relMSE against seconds.
        #[arg(long, value_name = "FILE.svg")]
        svg: Option<PathBuf>,
        /// Also the wavefront's images denoised by each of these (oidn, atrous; a bare --denoise:
        /// every one this build has). Seconds include the render recording the guides and the
        /// filter.
        #[arg(long, value_name = "oidn,atrous", num_args = 0..=1, value_delimiter = ',',
              value_parser = Denoiser::parse)]
        denoise: Option<Vec<Denoiser>>,
        /// Worker threads, 1 to 1024 (default: all cores).
        #[arg(short, long, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=MAX_THREADS))]
        threads: Option<usize>,
        /// Add Mitsuba's rows and curve from the JSON lines a side-by-side run printed (e.g.
        /// `side_by_side.py ... > anchor.jsonl`), for the scenes benchmarked.
        #[arg(long, value_name = "FILE.jsonl")]
        anchor: Option<PathBuf>,
    },
    /// BVH build time and traversal rates (Mrays/s) on the Embree anchor's torus knot and on a
    /// scene's geometry: primary, diffuse-bounce and shadow rays on 1 and 2 threads.
    BenchRays {
        /// Knot rings (2 x rings x segments triangles).
        #[arg(long, default_value_t = 2000)]
        rings: u32,
        /// Knot ring vertices.
        #[arg(long, default_value_t = 250)]
        segments: u32,
        /// A scene whose geometry and first light also get primary, bounce and shadow rays.
        #[arg(long, default_value = "scenes/cornell-diffuse.ron")]
        scene: PathBuf,
        /// Also time per-frame updates of this scene of instances (one instance moving).
        #[arg(long, value_name = "SCENE.ron")]
        instances: Option<PathBuf>,
        /// Also build and trace knots of 10^3 up to 10^N triangles.
        #[arg(long, value_name = "N")]
        scaling: Option<u32>,
    },
    /// Print RMSE and relMSE of image A against reference B (and both means). EXR and HDR
    /// files are linear (an EXR's beauty: R, G, B); an 8-bit file (PNG, JPEG) is sRGB-encoded,
    /// so comparing one with a linear file needs `--encoded` to say how to read it.
    Compare {
        /// The image to judge.
        a: PathBuf,
        /// The reference.
        b: PathBuf,
        /// How to read an 8-bit file compared with a linear one: `decode` its sRGB values to
        /// linear, or compare them `as-stored` (in [0, 1]).
        #[arg(long, value_enum)]
        encoded: Option<Encoded>,
    },
}

#[derive(Subcommand)]
pub enum FarmCommand {
    /// Write an sbatch job array whose tasks render every N-th frame (`animate --shard auto`)
    /// or, with --split-samples, a share of one image's samples (`render --samples auto`), and
    /// a merge job that runs after all of them have succeeded; submit both.
    Slurm {
        #[command(flatten)]
        job: farm::SlurmArgs,
        #[command(flatten)]
        args: Box<RenderArgs>,
    },
    /// Check that every task's share is there and whole, and merge sample shares into the
    /// image; name what is missing (task, samples or frames) and write nothing if anything is.
    Merge(farm::MergeArgs),
}

/// How `compare` reads an sRGB-encoded file beside a linear one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Encoded {
    /// Decode sRGB to linear.
    Decode,
    /// Compare the stored values.
    AsStored,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Integrator {
    /// Stages over structure-of-arrays queues (default).
    Wavefront,
    /// The reference path tracer, one path at a time.
    Oracle,
}

/// What `render` and `animate` share: every setting that changes a sample or an output.
#[derive(clap::Args, Clone, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub image: ImageArgs,
    /// Maximum bounces (overrides the scene).
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Scale samples down so that no component exceeds MAX (biased; off by default).
    #[arg(long, value_name = "MAX")]
    pub clamp: Option<f32>,
    /// Render only the window x0..x1, y0..y1 (fractions of the image, as pbrt-v4's crop
    /// window): the output has the window's size and the bits of those pixels in the whole
    /// image.
    #[arg(long, value_name = "X0,X1,Y0,Y1", value_delimiter = ',')]
    pub crop: Option<Vec<f32>>,
    /// Which integrator renders.
    #[arg(long, value_enum, default_value_t = Integrator::Wavefront)]
    pub integrator: Integrator,
    /// Paths in flight per worker (wavefront), 1 to 65536.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub batch: u32,
    /// Denoise with `oidn` (Intel Open Image Denoise, guided by albedo and normals; a build with
    /// `--features oidn`, where a bare --denoise means it) or `atrous` (pathwave's à-trous filter,
    /// guided by albedo, normals and the per-pixel variance; a bare --denoise in other builds):
    /// the output gets the denoised image, NAME.noisy.EXT the render as it came.
    #[arg(long, value_name = "oidn|atrous", num_args = 0..=1,
          default_missing_value = Denoiser::DEFAULT_NAME, value_parser = Denoiser::parse)]
    pub denoise: Option<Denoiser>,
    /// Also write AOVs, a comma-separated list of albedo, normal, depth, variance, noisy (a bare
    /// `--aov`: albedo,normal). An EXR output holds them as layers of the same file (`albedo.R`,
    /// `normal.X`, `depth.Z`, `variance.R`, `noisy.R`, ...); beside a PNG, albedo and normal go
    /// to NAME.albedo.png and NAME.normal.png (normals mapped to 0.5 + 0.5 n), and depth and
    /// variance need an EXR. `noisy` (the render before denoising) needs --denoise.
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
    /// Set a parameter the scene declares (`parameters: { "NAME": "default" }`, used as
    /// `$NAME`) to VALUE, RON text; repeatable.
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// Worker threads, 1 to 1024 (default: all cores).
    #[arg(short, long, visible_alias = "nthreads",
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=MAX_THREADS))]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub log: LogArgs,
    #[command(flatten)]
    pub profile: ProfileArgs,
}

impl RenderArgs {
    /// The scene overrides.
    pub fn overrides(&self) -> Overrides {
        Overrides {
            image: self.image,
            max_depth: self.max_depth,
            clamp: self.clamp,
            crop: self.crop.clone(),
            define: self.define.clone(),
        }
    }

    /// How to render.
    pub fn how(&self) -> How {
        How {
            defines: self.define.clone(),
            integrator: self.integrator,
            batch: self.batch as usize,
            stats: self.profile.stats,
            threads: self.threads,
            quiet: self.log.quiet,
            verbose: self.log.verbose > 0,
            denoise: self.denoise,
            aov: self.aov.clone().unwrap_or_default(),
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

/// How much `render` and `animate` say on stderr.
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

/// What `render` and `animate` may both override of a scene's `render` settings.
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
}

pub struct Overrides {
    pub image: ImageArgs,
    pub max_depth: Option<u32>,
    pub clamp: Option<f32>,
    pub crop: Option<Vec<f32>>,
    pub define: Vec<String>,
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
}

impl How {
    /// Whether the denoiser's guides are needed.
    pub fn guides(&self) -> bool {
        self.denoise.is_some() || self.aov.iter().any(|a| matches!(a, Aov::Albedo | Aov::Normal))
    }

    /// Refuses, before any work, AOVs that `output` cannot hold or that need `--denoise`.
    pub fn check_aovs(&self, output: &Path) -> Result<(), String> {
        let exr = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        for a in &self.aov {
            match a {
                Aov::Depth | Aov::Variance if !exr => {
                    return Err(
                        format!("{}: --aov {a:?} needs an .exr output", output.display()).to_lowercase()
                    );
                }
                Aov::Noisy if self.denoise.is_none() => return Err("--aov noisy needs --denoise".into()),
                _ => {}
            }
        }
        Ok(())
    }
}

pub struct How {
    /// The -D parameter overrides (they change the scene, so they are in checkpoint keys).
    pub defines: Vec<String>,
    pub verbose: bool,
    pub denoise: Option<Denoiser>,
    pub aov: Vec<Aov>,
    pub integrator: Integrator,
    pub batch: usize,
    pub stats: bool,
    pub threads: Option<usize>,
    pub quiet: bool,
}
