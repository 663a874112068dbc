//! The `pathwave` command line.

use clap::{Parser, Subcommand};
use pathwave::engine::{scene, world::SceneWorld};
use pathwave::integrator::oracle;
use pathwave::io::{self, LinearImage};
use pathwave::metrics;
use std::io::Write;
use std::num::NonZeroU32;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Mutex;
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
        #[arg(short, long)]
        output: PathBuf,
        /// Samples per pixel (overrides the scene).
        #[arg(long)]
        spp: Option<NonZeroU32>,
        /// Image width (overrides the scene).
        #[arg(long)]
        width: Option<NonZeroU32>,
        /// Image height (overrides the scene).
        #[arg(long)]
        height: Option<NonZeroU32>,
        /// Random seed (overrides the scene).
        #[arg(long)]
        seed: Option<u64>,
        /// Maximum bounces (overrides the scene).
        #[arg(long)]
        max_depth: Option<u32>,
        /// Worker threads (default: all cores).
        #[arg(short, long)]
        threads: Option<usize>,
        /// No progress bar.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Print RMSE and relMSE of image A against reference B (and both means).
    Compare {
        /// The image to judge.
        a: PathBuf,
        /// The reference.
        b: PathBuf,
    },
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_writer(std::io::stderr)
        .init();
    let result = match Cli::parse().command {
        Command::Render { scene, output, spp, width, height, seed, max_depth, threads, quiet } => {
            let overrides = Overrides { spp, width, height, seed, max_depth };
            render(&scene, &output, overrides, threads, quiet)
        }
        Command::Compare { a, b } => compare(&a, &b),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

struct Overrides {
    spp: Option<NonZeroU32>,
    width: Option<NonZeroU32>,
    height: Option<NonZeroU32>,
    seed: Option<u64>,
    max_depth: Option<u32>,
}

fn render(
    path: &PathBuf,
    output: &PathBuf,
    o: Overrides,
    threads: Option<usize>,
    quiet: bool,
) -> Result<(), String> {
    let mut desc = scene::load(path).map_err(|e| e.to_string())?;
    let r = &mut desc.render;
    r.spp = o.spp.unwrap_or(r.spp);
    r.width = o.width.unwrap_or(r.width);
    r.height = o.height.unwrap_or(r.height);
    r.seed = o.seed.unwrap_or(r.seed);
    r.max_depth = o.max_depth.unwrap_or(r.max_depth);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| format!("cannot start {threads:?} threads: {e}"))?;
    let start = Instant::now();
    let scene = SceneWorld::render_scene(&desc);
    let s = scene.settings;
    let bar = Progress::new(quiet);
    let film = pool.install(|| oracle::render(&scene, &|done, total| bar.update(done, total)));
    let secs = start.elapsed().as_secs_f64();
    bar.finish();
    let img = LinearImage { width: film.width, height: film.height, pixels: film.mean() };
    let clamped = io::write(output, &img)?;
    let samples = s.width as f64 * s.height as f64 * s.spp as f64;
    eprintln!(
        "{}: {}x{} {} spp in {secs:.2} s, {:.3} M samples/s, {} threads, {} NaN/Inf samples discarded{}",
        output.display(),
        s.width,
        s.height,
        s.spp,
        samples / secs / 1e6,
        pool.current_num_threads(),
        film.non_finite,
        if clamped > 0 { format!(", {clamped} pixels clamped to 1 in the PNG") } else { String::new() },
    );
    Ok(())
}

fn compare(a: &PathBuf, b: &PathBuf) -> Result<(), String> {
    let (x, r) = (io::read_linear(a)?, io::read_linear(b)?);
    if (x.width, x.height) != (r.width, r.height) {
        return Err(format!("sizes differ: {}x{} vs {}x{}", x.width, x.height, r.width, r.height));
    }
    println!(
        "relMSE {:.6}  RMSE {:.6}  mean {:.6} vs {:.6} ({:+.3}%)",
        metrics::rel_mse(&x.pixels, &r.pixels),
        metrics::rmse(&x.pixels, &r.pixels),
        metrics::mean(&x.pixels),
        metrics::mean(&r.pixels),
        100.0 * (metrics::mean(&x.pixels) / metrics::mean(&r.pixels) - 1.0),
    );
    Ok(())
}

/// A progress bar with ETA on stderr, redrawn at most ten times a second.
struct Progress {
    quiet: bool,
    start: Instant,
    last: Mutex<Option<Instant>>,
}

impl Progress {
    fn new(quiet: bool) -> Self {
        Self { quiet, start: Instant::now(), last: Mutex::new(None) }
    }

    fn update(&self, done: usize, total: usize) {
        if self.quiet {
            return;
        }
        let mut last = self.last.lock().unwrap();
        let now = Instant::now();
        if done < total && last.is_some_and(|t| now.duration_since(t).as_millis() < 100) {
            return;
        }
        *last = Some(now);
        let f = done as f64 / total as f64;
        let elapsed = self.start.elapsed().as_secs_f64();
        let eta = if f > 0.0 { elapsed * (1.0 - f) / f } else { 0.0 };
        let width = 40;
        let filled = (f * width as f64) as usize;
        eprint!(
            "\rRendering: [{}{}] {:5.1}% {:.1}s elapsed, ETA {:.1}s ",
            "+".repeat(filled),
            " ".repeat(width - filled),
            100.0 * f,
            elapsed,
            eta
        );
        let _ = std::io::stderr().flush();
    }

    fn finish(&self) {
        if !self.quiet {
            eprintln!();
        }
    }
}
