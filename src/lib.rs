//! pathwave: a physically based path tracer. This crate is the command-line tool, one module
//! per subcommand (`render`, `animate`, `watch`, `farm`, `merge`, `compare`, `bench`,
//! `bench_rays`, each with its flags and its work; [`cli`] puts them together), and a facade over
//! the `engine` (scene model) and `integrator` crates, plus image I/O and error metrics.
#![warn(missing_docs)]

pub mod animate;
pub mod bench;
pub mod bench_rays;
pub mod checkpoint;
pub mod cli;
pub mod compare;
pub mod convert;
pub mod denoiser;
pub mod farm;
pub mod guide_file;
pub mod io;
pub mod limits;
pub mod look;
pub mod merge;
pub mod metrics;
pub mod render;
pub mod shard;
pub mod terminal;
pub mod trace;
pub mod view;
pub mod watch;

/// The most worker threads `--threads` takes.
pub const MAX_THREADS: u64 = 1024;

/// A rayon pool of `threads` workers (all cores when `None`).
pub fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool, String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| format!("cannot start {threads:?} threads: {e}"))
}

pub use pathwave_engine as engine;
pub use pathwave_integrator as integrator;
