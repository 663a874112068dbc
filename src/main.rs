//! The `pathwave` command line.

use clap::{Parser, Subcommand};
use pathwave::checkpoint::{self, Checkpoint};
use pathwave::denoiser::{self, Denoiser};
use pathwave::engine::render_scene::{PixelWindow, SamplerKind};
use pathwave::engine::{scene, world::SceneWorld};
use pathwave::integrator::{aov, film::Film, oracle, wavefront};
use pathwave::io::{self, LinearImage};
use pathwave::view::{self, ViewArgs, Viewers};
use pathwave::{MAX_THREADS, animate, bench, farm, metrics, shard, trace};
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser)]
#[command(name = "pathwave", version, about = "A physically based path tracer")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
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
    /// BVH build time and traversal rates (Mrays/s) on the knot of ANCHORS.md and on a scene's
    /// geometry: primary, diffuse-bounce and shadow rays on 1 and 2 threads.
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
enum FarmCommand {
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
enum Encoded {
    /// Decode sRGB to linear.
    Decode,
    /// Compare the stored values.
    AsStored,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum Integrator {
    /// Stages over structure-of-arrays queues (default).
    Wavefront,
    /// The reference path tracer, one path at a time.
    Oracle,
}

/// What `render` and `animate` share: every setting that changes a sample or an output.
#[derive(clap::Args, Clone, Debug)]
struct RenderArgs {
    #[command(flatten)]
    image: ImageArgs,
    /// Maximum bounces (overrides the scene).
    #[arg(long)]
    max_depth: Option<u32>,
    /// Scale samples down so that no component exceeds MAX (biased; off by default).
    #[arg(long, value_name = "MAX")]
    clamp: Option<f32>,
    /// Render only the window x0..x1, y0..y1 (fractions of the image, as pbrt-v4's crop
    /// window): the output has the window's size and the bits of those pixels in the whole
    /// image.
    #[arg(long, value_name = "X0,X1,Y0,Y1", value_delimiter = ',')]
    crop: Option<Vec<f32>>,
    /// Which integrator renders.
    #[arg(long, value_enum, default_value_t = Integrator::Wavefront)]
    integrator: Integrator,
    /// Paths in flight per worker (wavefront), 1 to 65536.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    batch: u32,
    /// Denoise with `oidn` (Intel Open Image Denoise, guided by albedo and normals; a build with
    /// `--features oidn`, where a bare --denoise means it) or `atrous` (pathwave's à-trous filter,
    /// guided by albedo, normals and the per-pixel variance; a bare --denoise in other builds):
    /// the output gets the denoised image, NAME.noisy.EXT the render as it came.
    #[arg(long, value_name = "oidn|atrous", num_args = 0..=1,
          default_missing_value = Denoiser::DEFAULT_NAME, value_parser = Denoiser::parse)]
    denoise: Option<Denoiser>,
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
    aov: Option<Vec<Aov>>,
    /// Render in passes and, every SECS seconds, save the samples so far to OUT.ckpt (render:
    /// and the image so far to OUT; animate: a killed frame resumes from its checkpoint). The
    /// checkpoint is kept at the end, to add samples later.
    #[arg(long, value_name = "SECS")]
    checkpoint_every: Option<f64>,
    /// Set a parameter the scene declares (`parameters: { "NAME": "default" }`, used as
    /// `$NAME`) to VALUE, RON text; repeatable.
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    define: Vec<String>,
    /// Worker threads, 1 to 1024 (default: all cores).
    #[arg(short, long, visible_alias = "nthreads",
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=MAX_THREADS))]
    threads: Option<usize>,
    #[command(flatten)]
    log: LogArgs,
    #[command(flatten)]
    profile: ProfileArgs,
}

impl RenderArgs {
    /// The scene overrides.
    fn overrides(&self) -> Overrides {
        Overrides {
            image: self.image,
            max_depth: self.max_depth,
            clamp: self.clamp,
            crop: self.crop.clone(),
            define: self.define.clone(),
        }
    }

    /// How to render.
    fn how(&self) -> How {
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
    fn checkpoint_every(&self) -> Result<Option<f64>, String> {
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
struct LogArgs {
    /// More on stderr: -v logs the scene, BVH builds, passes and frames (info) and lists the
    /// pixels that discarded NaN/Inf samples; -vv adds debug logs and every span's duration.
    /// RUST_LOG, when set, chooses the log levels instead.
    #[arg(short, long, action = clap::ArgAction::Count)]
    verbose: u8,
    /// Less on stderr: no progress or per-frame lines, only warnings, errors and the summary.
    #[arg(short, long, conflicts_with = "verbose")]
    quiet: bool,
}

/// Where `render` and `animate` say where the time goes.
#[derive(clap::Args, Clone, Debug)]
struct ProfileArgs {
    /// Print per-stage statistics (wavefront): time share, items, rate and calls, and queue
    /// occupancy (`animate`: a line per frame with its scene update and stage shares, then
    /// the table for the sequence).
    #[arg(long)]
    stats: bool,
    /// Write a Chrome trace (open it in ui.perfetto.dev): scene load, ECS systems, frames,
    /// passes and tiles as spans, each tile's stages with their items, and counter tracks.
    #[arg(long, value_name = "FILE.json")]
    trace: Option<PathBuf>,
}

/// One subscriber for every subcommand. Log lines go to stderr at the level `log` asks for
/// (warnings by default and with -q, info with -v, debug with -vv, which also logs each
/// span's duration when it closes) unless RUST_LOG sets the levels; colours only on a
/// terminal. With a trace file, the Chrome layer takes every span and stage report of
/// pathwave's crates; the returned file is finished by the caller.
fn init_tracing(log: LogArgs, trace: Option<&Path>) -> Result<Option<trace::TraceFile>, String> {
    use std::io::IsTerminal;
    use tracing::level_filters::LevelFilter;
    use tracing_subscriber::prelude::*;
    // Quiet silences progress and per-frame lines, never warnings.
    let level = match log.verbose {
        0 => LevelFilter::WARN,
        1 => LevelFilter::INFO,
        _ => LevelFilter::DEBUG,
    };
    let filter = match std::env::var("RUST_LOG") {
        Ok(v) if !v.trim().is_empty() => tracing_subscriber::EnvFilter::builder().parse_lossy(v),
        _ => tracing_subscriber::EnvFilter::default().add_directive(level.into()),
    };
    let spans = match filter.max_level_hint().is_some_and(|l| l >= LevelFilter::DEBUG) {
        true => tracing_subscriber::fmt::format::FmtSpan::CLOSE,
        false => tracing_subscriber::fmt::format::FmtSpan::NONE,
    };
    let fmt = tracing_subscriber::fmt::layer()
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .with_span_events(spans)
        .with_filter(filter);
    let ours = || {
        tracing_subscriber::filter::Targets::new()
            .with_target("pathwave", tracing::Level::TRACE)
            .with_target("pathwave_engine", tracing::Level::TRACE)
            .with_target("pathwave_integrator", tracing::Level::TRACE)
    };
    let (chrome, file) = match trace {
        Some(path) => {
            let (layer, file) = trace::create(path)?;
            (Some(layer.with_filter(ours())), Some(file))
        }
        None => (None, None),
    };
    // Built with `--features tracy`: the Tracy profiler can connect while pathwave runs.
    #[cfg(feature = "tracy")]
    let tracy = Some(tracing_tracy::TracyLayer::default().with_filter(ours()));
    #[cfg(not(feature = "tracy"))]
    let tracy: Option<tracing_subscriber::layer::Identity> = None;
    tracing_subscriber::registry().with(fmt).with(chrome).with(tracy).init();
    Ok(file)
}

/// The binary is built for x86-64-v3 (`.cargo/config.toml`: the same instructions, so the same
/// bits, on every machine); on a CPU without the instructions it was built with it would die of
/// an illegal instruction somewhere. Say so instead, first thing.
#[cfg(target_arch = "x86_64")]
fn check_cpu() -> Result<(), String> {
    let have = [
        ("AVX", !cfg!(target_feature = "avx") || std::arch::is_x86_feature_detected!("avx")),
        ("AVX2", !cfg!(target_feature = "avx2") || std::arch::is_x86_feature_detected!("avx2")),
        ("FMA", !cfg!(target_feature = "fma") || std::arch::is_x86_feature_detected!("fma")),
        ("BMI1", !cfg!(target_feature = "bmi1") || std::arch::is_x86_feature_detected!("bmi1")),
        ("BMI2", !cfg!(target_feature = "bmi2") || std::arch::is_x86_feature_detected!("bmi2")),
        ("F16C", !cfg!(target_feature = "f16c") || std::arch::is_x86_feature_detected!("f16c")),
        ("LZCNT", !cfg!(target_feature = "lzcnt") || std::arch::is_x86_feature_detected!("lzcnt")),
        ("MOVBE", !cfg!(target_feature = "movbe") || std::arch::is_x86_feature_detected!("movbe")),
    ];
    let missing: Vec<&str> = have.iter().filter(|(_, ok)| !ok).map(|(name, _)| *name).collect();
    match missing.is_empty() {
        true => Ok(()),
        false => Err(format!(
            "this CPU lacks {}: pathwave is built for x86-64-v3 CPUs (Intel Haswell, AMD Excavator \
             or later); see the README for building for older ones",
            missing.join(", ")
        )),
    }
}

#[cfg(not(target_arch = "x86_64"))]
fn check_cpu() -> Result<(), String> {
    Ok(())
}

fn main() -> ExitCode {
    if let Err(e) = check_cpu() {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    // The matches too: a farm passes the render flags given to it on to its tasks.
    let matches = <Cli as clap::CommandFactory>::command().get_matches();
    let cli = match <Cli as clap::FromArgMatches>::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.format(&mut <Cli as clap::CommandFactory>::command()).exit(),
    };
    let (log, trace) = match &cli.command {
        Command::Render { args, .. } | Command::Animate { args, .. } => {
            (args.log, args.profile.trace.clone())
        }
        _ => (LogArgs { verbose: 0, quiet: false }, None),
    };
    let trace_file = match init_tracing(log, trace.as_deref()) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let result = match cli.command {
        Command::Render { scene, output, args, time, resume, samples, shard_count, view } => (|| {
            let every = args.checkpoint_every()?;
            let samples = samples.as_deref().map(|r| shard::Samples::parse(r, shard_count)).transpose()?;
            // A part is kept in its checkpoint for `merge`.
            let checkpoint = (every.is_some() || resume || samples.is_some())
                .then(|| Checkpointing { every: every.unwrap_or(60.0), resume });
            render(&scene, &output, args.overrides(), &args.how(), time, checkpoint, samples, &view)
        })(),
        Command::Merge { parts, output } => merge(&parts, &output),
        Command::Watch(args) => pathwave::watch::run(args),
        Command::Animate { scene, output, frames, fps, shutter, overwrite, shard, shard_count, args } => {
            let seq = SequenceArgs { frames, fps, shutter, overwrite, shard, shard_count };
            animate(&scene, &output, seq, &args)
        }
        Command::Farm { farm: FarmCommand::Slurm { job, args } } => {
            match matches.subcommand_matches("farm").and_then(|m| m.subcommand_matches("slurm")) {
                Some(m) => farm_slurm(&job, &args, m),
                None => Err("farm slurm: its flags are not where clap puts them".into()),
            }
        }
        Command::Farm { farm: FarmCommand::Merge(m) } => match (m.spp, &m.parts, &m.frames) {
            (Some(spp), Some(parts), _) => {
                farm::check_samples(parts, m.tasks, spp).and_then(|p| merge(&p, Path::new(&m.output)))
            }
            (_, _, Some(f)) => animate::parse_range(f, "--frames")
                .and_then(|f| farm::check_frames(&m.output, f, m.tasks))
                .map(|()| eprintln!("{}: every frame is there", m.output)),
            _ => Err("farm merge takes --spp with --parts, or --frames".into()),
        },
        Command::Compare { a, b, encoded } => compare(&a, &b, encoded),
        Command::BenchRays { rings, segments, scene, instances, scaling } => {
            pathwave::raybench::run((rings, segments), Some(&scene))
                .and_then(|_| instances.map_or(Ok(()), |p| pathwave::raybench::instance_update(&p, 100)))
                .and_then(|_| scaling.map_or(Ok(()), pathwave::raybench::scaling))
        }
        Command::Bench { spp, refs, only, batch, svg, denoise, threads, anchor } => {
            let denoise = match denoise {
                Some(d) if d.is_empty() => Denoiser::AVAILABLE.to_vec(),
                d => d.unwrap_or_default(),
            };
            bench(&spp, &refs, &only, batch, svg, &denoise, threads, anchor.as_deref())
        }
    };
    let result = match (trace_file, result) {
        (Some(file), Ok(())) => file.finish().map(|()| {
            let t = trace.expect("a trace file has a path");
            eprintln!("trace written to {} (open it in ui.perfetto.dev)", t.display());
        }),
        (_, result) => result,
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// What `render` and `animate` may both override of a scene's `render` settings.
#[derive(clap::Args, Clone, Copy, Debug)]
struct ImageArgs {
    /// Samples per pixel (overrides the scene).
    #[arg(long)]
    spp: Option<NonZeroU32>,
    /// Image width (overrides the scene).
    #[arg(long)]
    width: Option<NonZeroU32>,
    /// Image height (overrides the scene).
    #[arg(long)]
    height: Option<NonZeroU32>,
    /// Random seed (overrides the scene; every frame of a sequence uses it).
    #[arg(long)]
    seed: Option<u64>,
    /// How samples are made: sobol (default), stratified or independent (overrides the scene).
    #[arg(long)]
    sampler: Option<SamplerKind>,
}

struct Overrides {
    image: ImageArgs,
    max_depth: Option<u32>,
    clamp: Option<f32>,
    crop: Option<Vec<f32>>,
    define: Vec<String>,
}

/// `--checkpoint-every` and `--resume`.
struct Checkpointing {
    /// Seconds between checkpoints.
    every: f64,
    /// Start from the checkpoint file if there is one.
    resume: bool,
}

/// An image beside the render (`--aov`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum Aov {
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
    fn guides(&self) -> bool {
        self.denoise.is_some() || self.aov.iter().any(|a| matches!(a, Aov::Albedo | Aov::Normal))
    }

    /// Refuses, before any work, AOVs that `output` cannot hold or that need `--denoise`.
    fn check_aovs(&self, output: &Path) -> Result<(), String> {
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

struct How {
    /// The -D parameter overrides (they change the scene, so they are in checkpoint keys).
    defines: Vec<String>,
    verbose: bool,
    denoise: Option<Denoiser>,
    aov: Vec<Aov>,
    integrator: Integrator,
    batch: usize,
    stats: bool,
    threads: Option<usize>,
    quiet: bool,
}

/// Loads a scene and applies the command line's overrides.
fn load(path: &Path, o: &Overrides) -> Result<scene::SceneDesc, String> {
    let _span = tracing::info_span!("load_scene", file = %path.display()).entered();
    let defines = scene::parse_defines(&o.define)?;
    let mut desc = scene::load_with(path, &defines).map_err(|e| e.to_string())?;
    tracing::info!(
        file = %path.display(),
        objects = desc.objects.len(),
        materials = desc.materials.0.len(),
        textures = desc.textures.0.len(),
        "scene parsed"
    );
    let r = &mut desc.render;
    r.spp = o.image.spp.unwrap_or(r.spp);
    r.width = o.image.width.unwrap_or(r.width);
    r.height = o.image.height.unwrap_or(r.height);
    r.seed = o.image.seed.unwrap_or(r.seed);
    r.sampler = o.image.sampler.unwrap_or(r.sampler);
    r.max_depth = o.max_depth.unwrap_or(r.max_depth);
    if let Some(c) = o.clamp {
        if !(c.is_finite() && c > 0.0) {
            return Err(format!("--clamp takes a finite number > 0, not {c}"));
        }
        r.clamp = Some(scene::Positive(c));
    }
    if let Some(c) = &o.crop {
        let c: [f32; 4] = c
            .as_slice()
            .try_into()
            .map_err(|_| format!("--crop takes four numbers x0,x1,y0,y1 (a crop window), not {}", c.len()))?;
        r.crop = Some(scene::CropWindow::new(c).map_err(|e| format!("--crop: {e}"))?);
    }
    pathwave::limits::check_render(r)?;
    if let Some(c) = r.crop
        && PixelWindow::crop(r.width.get(), r.height.get(), c.0).is_none()
    {
        let [x0, x1, y0, y1] = c.0;
        return Err(format!(
            "the crop window ({x0}, {x1}, {y0}, {y1}) holds no pixel of a {}x{} image",
            r.width, r.height
        ));
    }
    Ok(desc)
}

/// Logs what the integrators will see of a scene (info).
fn log_scene(scene: &pathwave::engine::render_scene::RenderScene) {
    use pathwave::engine::geometry::Primitive;
    let prims = &scene.geometry.prims;
    let triangles = prims.iter().filter(|p| matches!(p, Primitive::Triangle(_))).count();
    let instanced: usize =
        scene.instances.list.iter().map(|i| scene.instances.blas[i.blas as usize].mesh.triangles.len()).sum();
    let s = scene.settings;
    tracing::info!(
        primitives = prims.len(),
        triangles,
        instances = scene.instances.list.len(),
        meshes = scene.instances.blas.len(),
        instanced_triangles = instanced,
        lights = scene.lights.prims.len(),
        features = ?scene.features,
        "scene ready: {}x{} at {} spp, max depth {}",
        s.width,
        s.height,
        s.spp,
        s.max_depth
    );
}

fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool, String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| format!("cannot start {threads:?} threads: {e}"))
}

/// `animate`'s options about which frames to render.
struct SequenceArgs {
    frames: Option<String>,
    fps: Option<f32>,
    shutter: Option<f32>,
    overwrite: bool,
    shard: Option<String>,
    shard_count: Option<u32>,
}

fn animate(path: &Path, output: &str, seq_args: SequenceArgs, args: &RenderArgs) -> Result<(), String> {
    // Frame folders are created as frames come; the format and the scene are checked now.
    let first = match Path::new(output).extension().is_some_and(|e| e.eq_ignore_ascii_case("gif")) {
        true => PathBuf::from(output),
        false => animate::frame_path(output, 0)?,
    };
    if io::same_file(path, &first) {
        return Err(format!("{output}: the output would replace the scene {}", path.display()));
    }
    let ext = first.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    if !["png", "exr", "gif"].contains(&ext.as_str()) {
        return Err(format!("{output}: unknown output format (use .png, .exr or .gif)"));
    }
    let desc = load(path, &args.overrides())?;
    let a = &desc.animation;
    let frames = match &seq_args.frames {
        Some(f) => animate::parse_range(f, "--frames")?,
        None => (0, a.frames.get()),
    };
    let fps = seq_args.fps.unwrap_or(a.fps.0);
    if !(fps.is_finite() && fps > 0.0) {
        return Err(format!("--fps takes a number > 0, not {fps}"));
    }
    // The times of the frames stay where --time may go.
    if frames.1 as f32 / fps > 1e7 {
        return Err(format!("frames up to {} at {fps} fps reach beyond 1e7 seconds", frames.1));
    }
    let shutter = seq_args.shutter.unwrap_or(a.shutter.0);
    if !(0.0..=1.0).contains(&shutter) {
        return Err(format!("--shutter takes a fraction of the frame interval in [0, 1], not {shutter}"));
    }
    let shard = match seq_args.shard.as_deref() {
        Some(s) => shard::parse_shard(s, seq_args.shard_count).map(|t| (t.index, t.count))?,
        None => (0, 1),
    };
    let every = args.checkpoint_every()?;
    args.how().check_aovs(&first)?;
    let gif = Path::new(output).extension().is_some_and(|e| e.eq_ignore_ascii_case("gif"));
    if gif && (args.denoise.is_some() || args.aov.is_some() || every.is_some()) {
        return Err(format!(
            "{output}: --denoise, --aov and --checkpoint-every write files beside each frame; \
             render frame files (e.g. frame_{{frame:04}}.png) rather than a GIF"
        ));
    }
    // A frame killed half way resumes from its checkpoint.
    let checkpointing = every.map(|every| Checkpointing { every, resume: true });
    let pool = pool(args.threads)?;
    if let Some(d) = args.denoise {
        denoiser::prepare(d, pool.current_num_threads())?;
    }
    let mut world = SceneWorld::new(&desc);
    let quiet = args.log.quiet;
    let seq = animate::Sequence { output, frames, shard, fps, shutter, overwrite: seq_args.overwrite, quiet };
    // Frames report one line each (from `animate::run`), not a bar or a line per pass.
    let how = How { quiet: true, ..args.how() };
    let mut total: Option<(wavefront::Stats, f64, u64)> = None;
    let mut logged = false;
    // Frames are not shown while they render.
    let nv = &mut Viewers::default();
    animate::run(&mut world, &seq, |scene, info| {
        if !logged {
            log_scene(scene);
            logged = true;
        }
        let r = match &info.path {
            Some(out) => {
                let id = render_id(path, scene, &how, info.open)?;
                let r = render_image(scene, &id, out, &how, checkpointing.as_ref(), None, &pool, false, nv)?;
                let metadata = metadata(id.key, scene, &r);
                (r, metadata)
            }
            // A GIF's frames: no checkpoints, no files beside them (refused above).
            None => {
                {
                    // No checkpoint, so nothing identifies it.
                    let id = RenderId { key: 0, settings: String::new() };
                    (
                        render_image(scene, &id, Path::new(output), &how, None, None, &pool, false, nv)?,
                        Vec::new(),
                    )
                }
            }
        };
        let (r, metadata) = r;
        if args.profile.stats {
            match &r.stats {
                Some(st) => eprintln!(
                    "frame {}: scene update {:.2} ms, render {:.2} s, {}",
                    info.frame,
                    info.update.as_secs_f64() * 1e3,
                    r.secs,
                    stage_shares(st)
                ),
                None => eprintln!("--stats: per-stage statistics exist for the wavefront integrator only"),
            }
            if let Some(st) = r.stats.clone() {
                total = Some(match total.take() {
                    Some((t, s, n)) => (t.merge(st), s + r.secs, n + r.non_finite),
                    None => (st, r.secs, r.non_finite),
                });
            }
        }
        Ok(io::Output { img: r.img, layers: r.layers, metadata })
    })?;
    if let Some((st, secs, non_finite)) = &total {
        eprintln!("the sequence's frames together:");
        print_stats(st, *secs, *non_finite);
    }
    Ok(())
}

/// `pathwave farm slurm`: checks the scene and the options, then writes and submits the jobs.
fn farm_slurm(job: &farm::SlurmArgs, args: &RenderArgs, matches: &clap::ArgMatches) -> Result<(), String> {
    if args.profile.trace.is_some() {
        return Err("--trace: every task would write the same file; trace one share by hand".into());
    }
    if job.split_samples && (args.denoise.is_some() || args.aov.is_some()) {
        return Err("--split-samples: the merge adds samples; it does not denoise or write AOVs".into());
    }
    let desc = load(&job.scene, &args.overrides())?;
    let flags = <RenderArgs as clap::Args>::augment_args(clap::Command::new("render"));
    let forwarded = farm::forwarded(&flags, matches)?;
    let plan = farm::Job::plan(job, desc.render.spp.get(), (0, desc.animation.frames.get()), forwarded)?;
    if let farm::Work::Frames { first, .. } = plan.work {
        args.how().check_aovs(&animate::frame_path(&plan.output, first)?)?;
    }
    plan.submit(job.dry_run)
}

/// Each stage's share of the time, `name 12.3%`, largest first.
fn stage_shares(st: &wavefront::Stats) -> String {
    let total: f64 = st.time.iter().map(|t| t.as_secs_f64()).sum();
    let mut shares: Vec<(f64, &str)> = wavefront::Stage::ALL
        .iter()
        .filter(|s| st.calls[s.index()] > 0)
        .map(|s| (st.time[s.index()].as_secs_f64() / total.max(1e-12), s.name()))
        .collect();
    shares.sort_by(|a, b| b.0.total_cmp(&a.0));
    let list: Vec<String> = shares.iter().map(|(f, n)| format!("{n} {:.1}%", 100.0 * f)).collect();
    list.join(", ")
}

#[allow(clippy::too_many_arguments)]
fn render(
    path: &Path,
    output: &Path,
    o: Overrides,
    how: &How,
    time: f32,
    checkpointing: Option<Checkpointing>,
    samples: Option<shard::Samples>,
    view: &ViewArgs,
) -> Result<(), String> {
    io::check_output(output, &[path], false)?;
    how.check_aovs(output)?;
    if !(time.is_finite() && time.abs() <= 1e7) {
        return Err(format!("--time takes seconds in [-1e7, 1e7], not {time}"));
    }
    let desc = load(path, &o)?;
    let samples = samples.map(|s| s.range(desc.render.spp.get())).transpose()?;
    let pool = pool(how.threads)?;
    if let Some(d) = how.denoise {
        denoiser::prepare(d, pool.current_num_threads())?;
    }
    let mut world = SceneWorld::new(&desc);
    let shutter = desc.camera.shutter;
    world.set_time(time + shutter.0, time + shutter.1);
    let scene = world.update();
    log_scene(&scene);
    let s = scene.settings;
    let id = render_id(path, &scene, how, time)?;
    let mut viewers = Viewers::open(view, &output.display().to_string(), &s);
    let r =
        render_image(&scene, &id, output, how, checkpointing.as_ref(), samples, &pool, true, &mut viewers)?;
    if how.stats {
        match &r.stats {
            Some(st) => print_stats(st, r.secs, r.non_finite),
            None => eprintln!("--stats: per-stage statistics exist for the wavefront integrator only"),
        }
    }
    let metadata = metadata(id.key, &scene, &r);
    let clamped = io::write_output(output, &io::Output { img: r.img, layers: r.layers, metadata })?;
    eprintln!(
        "{}: {}x{}{} {} spp in {:.2} s, {:.3} M samples/s, {} threads, {} NaN/Inf samples discarded{}{}",
        output.display(),
        s.window.w,
        s.window.h,
        match s.window == (PixelWindow { x0: 0, y0: 0, w: s.width, h: s.height }) {
            true => String::new(),
            false => format!(" (crop at {},{} of {}x{})", s.window.x0, s.window.y0, s.width, s.height),
        },
        r.spp,
        r.secs,
        r.new_samples / r.secs.max(1e-9) / 1e6,
        pool.current_num_threads(),
        r.non_finite,
        if clamped > 0 { format!(", {clamped} pixels clamped to 1 in the PNG") } else { String::new() },
        match checkpointing {
            Some(_) => format!("; checkpoint {}", checkpoint::path_for(output).display()),
            None => String::new(),
        },
    );
    Ok(())
}

/// What identifies a render's samples: the checkpoint key (a hash of the scene file's bytes and
/// of every setting that changes a sample) and those settings as text, so that a checkpoint of
/// other settings is refused with the ones that differ.
struct RenderId {
    key: u64,
    settings: String,
}

/// The [`RenderId`] of a render of the scene file `path` at `time`.
fn render_id(
    path: &Path,
    scene: &pathwave::engine::render_scene::RenderScene,
    how: &How,
    time: f32,
) -> Result<RenderId, String> {
    let s = scene.settings;
    use pathwave::engine::scene::files;
    let w = &s.window;
    let settings = checkpoint::settings_text(&[
        ("size", format!("{}x{}", s.width, s.height)),
        ("window", format!("{}x{} at {},{}", w.w, w.h, w.x0, w.y0)),
        ("seed", s.seed.to_string()),
        ("max_depth", s.max_depth.to_string()),
        ("rr_depth", s.rr_depth.to_string()),
        ("clamp", format!("{:?}", s.clamp)),
        ("time", time.to_string()),
        ("integrator", format!("{:?}", how.integrator)),
        ("sampler", format!("{:?}", s.sampler)),
        ("defines", format!("{:?}", how.defines)),
    ]);
    if settings.len() > checkpoint::MAX_SETTINGS_BYTES {
        return Err(format!(
            "the -D values take {} bytes; at most {} fit in a checkpoint",
            settings.len(),
            checkpoint::MAX_SETTINGS_BYTES
        ));
    }
    let scene_file = files::read_bounded(path, files::MAX_SCENE_BYTES, "scene")?;
    Ok(RenderId { key: checkpoint::key(&scene_file, &settings), settings })
}

/// What a layered EXR's header records of a render: pathwave's version, the checkpoint key (a
/// hash of the scene file and the settings that change the image), samples per pixel and seed.
/// Not the render time: the same render gives the same bytes.
fn metadata(
    key: u64,
    scene: &pathwave::engine::render_scene::RenderScene,
    r: &Rendered,
) -> Vec<(&'static str, String)> {
    vec![
        ("pathwave:version", env!("CARGO_PKG_VERSION").to_string()),
        ("pathwave:scene_key", format!("{key:016x}")),
        ("pathwave:spp", r.spp.to_string()),
        ("pathwave:seed", scene.settings.seed.to_string()),
    ]
}

/// One rendered image, before it is written.
struct Rendered {
    /// The image (denoised when asked for).
    img: LinearImage,
    /// The AOVs an EXR output holds as layers.
    layers: Vec<io::ExrLayer<'static>>,
    /// Samples per pixel in it.
    spp: u32,
    /// Samples rendered by this run (not those resumed).
    new_samples: f64,
    /// Per-stage statistics (wavefront).
    stats: Option<wavefront::Stats>,
    /// Seconds, from the start of rendering to the image.
    secs: f64,
    /// NaN/Inf samples discarded.
    non_finite: u64,
}

/// Renders `scene` into the image meant for `output`, as `render` and each frame of `animate`
/// do: from its checkpoint when resuming, in passes that save checkpoints (and, with
/// `partial`, the image so far) when asked, or show the image to `viewers` (passes of 1, 2, 4,
/// ... spp, until a viewer stops the render), then denoised or with guides when asked.
#[allow(clippy::too_many_arguments)]
fn render_image(
    scene: &pathwave::engine::render_scene::RenderScene,
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
    let first_spp = film.spp;
    let (tiles_x, tiles_y) = pathwave::integrator::tile::Tile::grid_of(&s.window);
    let tiles = (tiles_x * tiles_y) as usize;
    let bar = Progress::new(how.quiet, (hi - lo - film.spp) as usize * tiles);
    let mut stats: Option<wavefront::Stats> = None;
    let mut last_save = Instant::now();
    // Without checkpoints or viewers, one pass; with checkpoints, passes sized to take about
    // half the interval (measured on the pass before), starting with one sample per pixel; with
    // viewers, no longer than doubling the samples (and at most `view::MAX_PASS`).
    let mut pass = if checkpointing.is_some() || viewers.progressive() { 1 } else { hi - lo };
    let mut passes = 0;
    while lo + film.spp < hi {
        let next = lo + film.spp;
        let range = next..(next + pass).min(hi);
        let k = range.len();
        let before = (film.spp - first_spp) as usize * tiles;
        let progress = |done: usize, _| bar.update(before + done * k);
        let pass_start = Instant::now();
        let span = tracing::info_span!("pass", first = range.start, samples = k).entered();
        let (part, st) = pool.install(|| match how.integrator {
            Integrator::Oracle => (oracle::render_samples(scene, range.clone(), &progress), None),
            Integrator::Wavefront => {
                let opts = wavefront::Options { batch: how.batch, guides: how.guides(), timing: how.stats };
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
        film.merge(&part);
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
        secs,
        non_finite: film.non_finite(),
    })
}

fn merge(parts: &[PathBuf], output: &Path) -> Result<(), String> {
    let inputs: Vec<&Path> = parts.iter().map(PathBuf::as_path).collect();
    io::check_output(output, &inputs, false)?;
    let ckpt = checkpoint::path_for(output);
    if let Some(p) = parts.iter().find(|p| io::same_file(p, &ckpt)) {
        return Err(format!(
            "{}: the merged checkpoint would replace the part {}",
            ckpt.display(),
            p.display()
        ));
    }
    let loaded = parts.iter().map(|p| Checkpoint::load(p)).collect::<Result<Vec<_>, _>>()?;
    let (merged, hi) = checkpoint::merge(&loaded)?;
    let f = &merged.film;
    io::write(output, &LinearImage { width: f.width, height: f.height, pixels: f.mean() })?;
    let lo = merged.first_sample;
    if lo + f.spp == hi {
        merged.save(&ckpt)?;
        eprintln!(
            "{}: samples {lo}..{hi} of {} from {} parts{}; checkpoint {}",
            output.display(),
            merged.target_spp,
            parts.len(),
            if (lo, hi) == (0, merged.target_spp) { " (all of them)" } else { "" },
            ckpt.display()
        );
    } else {
        eprintln!(
            "{}: {} samples between {lo} and {hi} of {}, with gaps (no checkpoint written: \
             a checkpoint holds one run of samples)",
            output.display(),
            f.spp,
            merged.target_spp
        );
    }
    Ok(())
}

/// Renders the guides and the AOVs asked for, writes those a PNG cannot hold beside it, and
/// returns the image, denoised with `--denoise` (which also keeps the image as rendered: a
/// `noisy` layer, or a file beside the output), with the layers of an EXR output.
fn post_process(
    scene: &pathwave::engine::render_scene::RenderScene,
    film: &Film,
    samples: std::ops::Range<u32>,
    img: LinearImage,
    output: &Path,
    how: &How,
    pool: &rayon::ThreadPool,
) -> Result<(LinearImage, Vec<io::ExrLayer<'static>>), String> {
    let start = Instant::now();
    // Recorded by the wavefront on the way, or traced now from the render's own camera rays
    // (the oracle, a resumed render), so that the emission they met comes out exactly.
    let aovs = match (&film.guides, how.guides()) {
        (Some(g), _) => g.clone(),
        (None, true) => pool.install(|| aov::render(scene, samples.clone())),
        (None, false) => aov::Aovs::default(),
    };
    let aov_secs = start.elapsed().as_secs_f64();
    let sibling = |tag: &str| {
        let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let ext = output.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default();
        output.with_file_name(format!("{stem}.{tag}.{ext}"))
    };
    let image = |pixels| LinearImage { width: img.width, height: img.height, pixels };
    let exr = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    let flat = |v: &[glam::Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
    let rgb: &'static [&'static str] = &["R", "G", "B"];
    let mut layers = Vec::new();
    for a in &how.aov {
        match (a, exr) {
            (Aov::Albedo, true) => {
                layers.push(io::ExrLayer { name: "albedo", channels: rgb, data: flat(&aovs.albedo) })
            }
            (Aov::Normal, true) => layers.push(io::ExrLayer {
                name: "normal",
                channels: &["X", "Y", "Z"],
                data: flat(&aovs.normal),
            }),
            (Aov::Albedo, false) => io::write(&sibling("albedo"), &image(aovs.albedo.clone())).map(drop)?,
            (Aov::Normal, false) => {
                let normal = aovs.normal.iter().map(|n| 0.5 + 0.5 * *n).collect();
                io::write(&sibling("normal"), &image(normal)).map(drop)?
            }
            (Aov::Depth, _) => {
                let depth = pool.install(|| aov::depth(scene, samples.clone()));
                layers.push(io::ExrLayer { name: "depth", channels: &["Z"], data: depth })
            }
            (Aov::Variance, _) => layers.push(io::ExrLayer {
                name: "variance",
                channels: rgb,
                data: flat(&film.variance_of_mean()),
            }),
            (Aov::Noisy, _) => {}
        }
    }
    if how.guides() {
        match film.guides {
            Some(_) => tracing::info!("guides recorded during the render"),
            None => tracing::info!("guides ({} rays per pixel) in {aov_secs:.2} s", samples.len()),
        }
    }
    let Some(which) = how.denoise else {
        return Ok((img, layers));
    };
    match exr && how.aov.contains(&Aov::Noisy) {
        true => layers.push(io::ExrLayer { name: "noisy", channels: rgb, data: flat(&img.pixels) }),
        false => io::write(&sibling("noisy"), &img).map(drop)?,
    }
    let start = Instant::now();
    let variance = film.variance_of_mean();
    let threads = pool.current_num_threads();
    let out = pool.install(|| denoiser::denoise(which, &img.pixels, &variance, &aovs, threads))?;
    let guides = if film.guides.is_some() { String::new() } else { format!(" (guides {aov_secs:.2} s)") };
    if !how.quiet {
        eprintln!("denoised ({}) in {:.2} s{guides}", which.name(), start.elapsed().as_secs_f64());
    }
    Ok((image(out), layers))
}

fn bench(
    spps: &[u32],
    refs: &std::path::Path,
    only: &[String],
    batch: usize,
    svg: Option<PathBuf>,
    denoise: &[Denoiser],
    threads: Option<usize>,
    anchor: Option<&Path>,
) -> Result<(), String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| e.to_string())?;
    let stem = |p: &PathBuf| p.file_stem().and_then(|s| s.to_str()).unwrap_or_default().to_string();
    let scenes = bench::default_scenes(refs);
    if let Some(missing) = only.iter().find(|o| !scenes.iter().any(|(s, _)| stem(s) == **o)) {
        let names: Vec<String> = scenes.iter().map(|(s, _)| stem(s)).collect();
        return Err(format!(
            "--only {missing}: no such scene with a reference in {}; there are: {}",
            refs.display(),
            names.join(", ")
        ));
    }
    let scenes: Vec<_> =
        scenes.into_iter().filter(|(s, _)| only.is_empty() || only.contains(&stem(s))).collect();
    // The anchor's file is read before the work, so that a bad one fails at once.
    let anchor = match anchor {
        Some(path) => {
            let mut pixels = Vec::new();
            for (scene, reference) in &scenes {
                let r = io::read_linear(reference)?;
                pixels.push((stem(scene), r.width as u64 * r.height as u64));
            }
            bench::anchor_rows(path, &pixels)?
        }
        None => Vec::new(),
    };
    let mut rows = Vec::new();
    for (scene, reference) in scenes {
        rows.extend(pool.install(|| bench::run(&scene, &reference, spps, batch, denoise))?);
    }
    rows.extend(anchor);
    println!(
        "{}, {} threads, {}, batch {batch}\n",
        bench::today(),
        pool.current_num_threads(),
        bench::machine()
    );
    println!("{}", bench::table_header());
    for r in &rows {
        println!("{}", bench::table_row(r));
    }
    if let Some(path) = svg {
        io::atomically(&path, bench::svg(&rows)?.as_bytes())?;
    }
    Ok(())
}

/// The `--stats` table on stderr.
fn print_stats(st: &wavefront::Stats, wall: f64, non_finite: u64) {
    let total: f64 = st.time.iter().map(|t| t.as_secs_f64()).sum();
    eprintln!("{:<22} {:>7} {:>12} {:>10} {:>9}", "stage", "time %", "items", "M items/s", "calls");
    for stage in wavefront::Stage::ALL {
        let k = stage.index();
        if st.calls[k] == 0 {
            continue;
        }
        let t = st.time[k].as_secs_f64();
        eprintln!(
            "{:<22} {:>6.1}% {:>12} {:>10.2} {:>9}",
            stage.name(),
            100.0 * t / total,
            st.items[k],
            st.items[k] as f64 / t / 1e6,
            st.calls[k]
        );
    }
    let ix = wavefront::Stage::IntersectClosest.index();
    let sh = wavefront::Stage::TraceShadowRays.index();
    let rays = st.items[ix] + st.items[sh];
    eprintln!(
        "{} iterations, mean queue occupancy {:.1}%; {} rays ({} closest, {} shadow): {:.2} Mrays/s; {:.3} M samples/s; {} NaN/Inf discarded; lanes {}",
        st.iterations,
        100.0 * st.occupancy_sum / st.iterations.max(1) as f64,
        rays,
        st.items[ix],
        st.items[sh],
        rays as f64 / wall / 1e6,
        st.paths as f64 / wall / 1e6,
        non_finite,
        pathwave::engine::simd::isa_name()
    );
}

fn compare(a: &Path, b: &Path, encoded: Option<Encoded>) -> Result<(), String> {
    let linear = |p: &Path| {
        let e = p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
        e == "exr" || e == "hdr"
    };
    let read = |p: &Path| -> Result<LinearImage, String> {
        let mut img = io::read_linear(p)?;
        if !linear(p) && encoded == Some(Encoded::Decode) {
            img.pixels.iter_mut().for_each(|c| *c = c.map(pathwave::engine::texture::srgb_to_linear));
        }
        Ok(img)
    };
    if linear(a) != linear(b) && encoded.is_none() {
        let (enc, lin) = if linear(a) { (b, a) } else { (a, b) };
        return Err(format!(
            "{} is sRGB-encoded and {} linear: pass --encoded decode to decode the first to linear, \
             or --encoded as-stored to compare the stored values",
            enc.display(),
            lin.display()
        ));
    }
    let (x, r) = (read(a)?, read(b)?);
    if (x.width, x.height) != (r.width, r.height) {
        return Err(format!("sizes differ: {}x{} vs {}x{}", x.width, x.height, r.width, r.height));
    }
    let (mx, mr) = (metrics::mean(&x.pixels), metrics::mean(&r.pixels));
    // Against a black reference a relative difference of means says nothing.
    let relative = match mr > 0.0 {
        true => format!(" ({:+.3}%)", 100.0 * (mx / mr - 1.0)),
        false => String::new(),
    };
    println!(
        "relMSE {:.6}  RMSE {:.6}  mean {mx:.6} vs {mr:.6}{relative}",
        metrics::rel_mse(&x.pixels, &r.pixels),
        metrics::rmse(&x.pixels, &r.pixels),
    );
    Ok(())
}

/// Render progress: an `indicatif` bar with ETA on a terminal. When stderr is not a terminal
/// the bar hides itself and each pass prints one line instead (`pass_done`), so that
/// `2> log.txt` stays readable.
struct Progress {
    bar: indicatif::ProgressBar,
    lines: bool,
}

impl Progress {
    fn new(quiet: bool, total: usize) -> Self {
        use std::io::IsTerminal;
        let bar = match quiet {
            true => indicatif::ProgressBar::hidden(),
            false => indicatif::ProgressBar::new(total as u64),
        };
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "Rendering [{bar:40}] {percent:>3}% {elapsed} elapsed, ETA {eta}",
            )
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
