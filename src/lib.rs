//! pathwave: a physically based path tracer. This crate is the command-line tool and a facade
//! over the `engine` (scene model) and `integrator` crates, plus image I/O and error metrics.
#![warn(missing_docs)]

pub mod animate;
pub mod bench;
pub mod checkpoint;
pub mod denoiser;
pub mod farm;
pub mod io;
pub mod limits;
pub mod metrics;
pub mod raybench;
pub mod shard;
pub mod trace;
pub mod view;
pub mod watch;

/// The most worker threads `--threads` takes.
pub const MAX_THREADS: u64 = 1024;

pub use pathwave_engine as engine;
pub use pathwave_integrator as integrator;
