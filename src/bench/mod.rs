//! `pathwave bench`: time against error on the scenes that have a reference. Its flags
//! ([`BenchCommand`]) and the measurements ([`measure`]).

pub mod measure;

use crate::MAX_THREADS;
use crate::denoiser::Denoiser;
use crate::io;
use std::path::PathBuf;

/// `pathwave bench`'s flags.
#[derive(clap::Args, Debug)]
pub struct BenchCommand {
    /// Sample counts.
    #[arg(long, value_delimiter = ',', default_value = "4,16,64,256,1024")]
    pub spp: Vec<u32>,
    /// Folder of the reference EXRs.
    #[arg(long, default_value = "tests/references")]
    pub refs: PathBuf,
    /// Only these scenes (file stems, e.g. cornell).
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
    /// Paths in flight per worker (wavefront).
    #[arg(long, default_value_t = 256)]
    pub batch: usize,
    /// Write a log-log plot of relMSE against seconds.
    #[arg(long, value_name = "FILE.svg")]
    pub svg: Option<PathBuf>,
    /// Also the wavefront's images denoised by each of these (oidn, atrous; a bare --denoise:
    /// every one this build has). Seconds include the render recording the guides and the
    /// filter.
    #[arg(long, value_name = "oidn,atrous", num_args = 0..=1, value_delimiter = ',',
          value_parser = Denoiser::parse)]
    pub denoise: Option<Vec<Denoiser>>,
    /// Worker threads, 1 to 1024 (default: all cores).
    #[arg(short, long, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=MAX_THREADS))]
    pub threads: Option<usize>,
    /// Add Mitsuba's rows and curve from the JSON lines a side-by-side run printed (e.g.
    /// `side_by_side.py ... > anchor.jsonl`), for the scenes benchmarked.
    #[arg(long, value_name = "FILE.jsonl")]
    pub anchor: Option<PathBuf>,
}

/// Renders each scene at each of `--spp` (and denoised with each of `--denoise`), measures
/// time and error against its reference, and prints the table (and writes the plot to `--svg`).
pub fn run(c: &BenchCommand) -> Result<(), String> {
    let (spps, refs, only, batch) = (&c.spp, c.refs.as_path(), &c.only, c.batch);
    let denoise = match &c.denoise {
        Some(d) if d.is_empty() => Denoiser::AVAILABLE.to_vec(),
        d => d.clone().unwrap_or_default(),
    };
    let pool = crate::pool(c.threads)?;
    let stem = |p: &PathBuf| p.file_stem().and_then(|s| s.to_str()).unwrap_or_default().to_string();
    let scenes = measure::default_scenes(refs);
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
    let anchor = match &c.anchor {
        Some(path) => {
            let mut pixels = Vec::new();
            for (scene, reference) in &scenes {
                let r = io::read_linear(reference)?;
                pixels.push((stem(scene), r.width as u64 * r.height as u64));
            }
            measure::anchor_rows(path, &pixels)?
        }
        None => Vec::new(),
    };
    let mut rows = Vec::new();
    for (scene, reference) in scenes {
        rows.extend(pool.install(|| measure::run(&scene, &reference, spps, batch, &denoise))?);
    }
    rows.extend(anchor);
    println!(
        "{}, {} threads, {}, batch {batch}\n",
        measure::today(),
        pool.current_num_threads(),
        measure::machine()
    );
    println!("{}", measure::table_header());
    for r in &rows {
        println!("{}", measure::table_row(r));
    }
    if let Some(path) = &c.svg {
        io::atomically(path, measure::svg(&rows)?.as_bytes())?;
    }
    Ok(())
}
