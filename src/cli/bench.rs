//! `pathwave bench`: time against error on the scenes that have a reference.

use pathwave::bench;
use pathwave::denoiser::Denoiser;
use pathwave::io;
use std::path::{Path, PathBuf};

/// Renders each scene at each of `spps` (and denoised with each of `denoise`), measures time
/// and error against its reference, and prints the table (and writes the plot to `svg`).
#[expect(clippy::too_many_arguments, reason = "the bench subcommand's flags, passed through as they are")]
pub fn bench(
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
